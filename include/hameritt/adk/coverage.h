#pragma once
// Search coverage: which parts of the mission's areas of interest a payload camera has looked
// at while each area's window was active, and how much of the prior probability mass that
// covers. ROS-free.

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "hameritt/geometry/polygon.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::adk {

// Pinhole intrinsics in the ROS / OpenCV convention (pixel centres at integer u, v; u right,
// v down; no distortion): sensor_msgs/CameraInfo K = [fx 0 cx; 0 fy cy; 0 0 1].
struct CameraIntrinsics {
  int width = 640;
  int height = 480;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  // Throws InputError for a size < 1 or non-positive or non-finite focal lengths.
  void validate() const;
};

// Square pixels, principal point at the image centre: fx = fy = (width / 2) / tan(hfov / 2),
// cx = (width - 1) / 2, cy = (height - 1) / 2 (the renderer's convention). InputError for
// sizes < 1 or a field of view outside (0, 180) degrees.
CameraIntrinsics intrinsicsFromHfov(int width, int height, double hfov_deg);

// The optical frame (z forward, x right, y down) of a payload camera in the world, given
// world_T_base (base_link, FLU) and the camera's mount (xyz in metres, rpy_deg roll-pitch-yaw
// in degrees applied as Rz(yaw) Ry(pitch) Rx(roll), positive pitch looks down), as the
// simulator publishes uav/base_link -> uav/<camera>_camera_link.
Eigen::Isometry3d opticalPose(const Eigen::Isometry3d& world_T_base,
                              const scenario::CameraSpec& camera);

// The ground (z = 0) the camera sees: the image's frustum (the four planes through the
// camera centre and the image borders, in front of the camera) cut by the ground, clipped to
// `max_range` metres horizontally from the camera (a regular 64-gon inscribed in that circle).
// Rays near or above the horizon therefore end at max_range. Counter-clockwise convex polygon;
// empty when the camera is at or below the ground or sees no ground within range.
geometry::Polygon groundFootprint(const CameraIntrinsics& intrinsics,
                                  const Eigen::Isometry3d& world_T_optical,
                                  double max_range = 150.0);

// Coverage of one area of interest.
struct AoiCoverage {
  std::string aoi_id;
  int cells = 0;                // grid cells whose centre lies in the area
  int covered = 0;              // of those, seen while the area's window was active
  double fraction = 0.0;        // covered / cells
  bool has_prior = false;       // the mission gives this area a prior
  double prior_weighted = 0.0;  // sum over prior cells of probability x covered fraction
};

// A grid over each area of interest; a grid cell belongs to the area when its centre lies in
// the polygon, and to the first prior cell of that area whose polygon holds its centre.
class CoverageGrid {
 public:
  // cell_size in metres (> 0; InputError otherwise).
  explicit CoverageGrid(const scenario::Mission& mission, double cell_size = 2.0);

  // Marks the cells whose centre lies in `footprint`, in every area whose window is active at
  // mission time t. Returns how many cells were newly covered.
  int addFootprint(const geometry::Polygon& footprint, double t);

  double cellSize() const { return cell_; }
  std::vector<AoiCoverage> coverage() const;
  // Mean of prior_weighted over the areas with a prior (each prior sums to 1 over its area);
  // 0 when the mission has no prior.
  double priorWeightedCoverage() const;

 private:
  struct AreaGrid {
    std::string id;
    geometry::TimeWindow window;
    geometry::Vec2 origin;  // centre of cell (0, 0)
    int nx = 0, ny = 0;
    std::vector<std::int8_t> member;  // cell centre in the area
    std::vector<std::int32_t> prior;  // prior cell index, or -1
    std::vector<std::int8_t> covered;
    std::vector<double> prior_probability;
    std::vector<int> prior_cells;  // grid cells per prior cell
    int cells = 0;
    bool has_prior = false;
  };
  double cell_;
  std::vector<AreaGrid> areas_;
};

}  // namespace hameritt::adk
