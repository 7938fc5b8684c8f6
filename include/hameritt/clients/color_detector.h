#pragma once
// A colour-and-shape car detector, the perception half of the baseline clients: pixels of the
// target's colour that stand at car height above the ground are grouped into blobs, each blob is
// back-projected with the depth image and the camera's intrinsics and pose into a metric
// footprint, and blobs whose length and width match the target's vehicle are candidates.
// Classical OpenCV, no learning; ROS-free (cv::Mat in, map-frame candidates out).

#include <Eigen/Geometry>
#include <map>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "hameritt/geometry/types.h"

namespace hameritt::clients {

// Pinhole intrinsics, ROS / OpenCV convention (pixel centres at integer u, v; no distortion),
// as in sensor_msgs/CameraInfo K.
struct PinholeCamera {
  int width = 640;
  int height = 480;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};
// Square pixels, principal point at the image centre: fx = fy = (width / 2) / tan(hfov / 2),
// cx = (width - 1) / 2, cy = (height - 1) / 2 (the renderer's convention).
PinholeCamera pinholeFromHfov(int width, int height, double hfov_deg);

// The optical frame (z forward, x right, y down) of a camera mounted on base_link (FLU) at
// mount_xyz (m) with mount_rpy_deg (roll, pitch, yaw in degrees; positive pitch looks down).
Eigen::Isometry3d opticalPose(const Eigen::Isometry3d& world_T_base,
                              const geometry::Vec3& mount_xyz, const geometry::Vec3& mount_rpy_deg);

// One HSV box in OpenCV's scale (H 0..179, S and V 0..255). h_min > h_max wraps around red.
struct HsvRange {
  int h_min = 0, h_max = 179;
  int s_min = 0, s_max = 255;
  int v_min = 0, v_max = 255;
};

// Detector settings. validate() throws scenario::ConfigError naming "detector.<field>".
struct DetectorSettings {
  // Colour name -> HSV boxes (a pixel of the colour lies in at least one).
  std::map<std::string, std::vector<HsvRange>> colors;
  int min_blob_pixels = 25;     // fewer pixels of colour: noise
  int open_kernel = 3;          // px, morphological opening (speckle removal); 0 or 1: none
  int close_kernel = 5;         // px, closing (fills seams); 0 or 1: none
  double ground_z = 0.0;        // m, the ground plane (streets are at 0)
  double height_min = 0.25;     // m above the ground: car pixels lie in [height_min, height_max]
  double height_max = 2.6;      //   (rejects the street, lawns, roofs and canopies)
  double merge_gap = 0.8;       // m, blobs whose footprints come closer are one vehicle (windows
                                //   split a car's body into hood, roof and trunk)
  double size_tolerance = 0.3;  // relative, on length and width
  double max_range = 150.0;     // m, farther blobs are too coarse to measure
  bool reject_border = true;    // blobs touching the image border are cut: not measurable
  // The scene's snow (sim_config environment.snow, public weather, [0, 1]) and how strongly the
  // chromatic colours are tested after taking the snow's white out of each pixel (colorMask):
  // snow cover whitens a car's roof, the surface a down camera sees.
  double snow = 0.0;
  double snow_whitening = 3.0;
  void validate() const;
};

// Defaults: min/max boxes for the catalog colours (red, blue, white, black, silver, grey,
// green, yellow); achromatic colours by saturation and value bands. To be tuned on renders.
DetectorSettings defaultDetectorSettings();

// A colour blob measured on the ground.
struct CarCandidate {
  geometry::Vec3 position{0, 0, 0};  // map frame: centre of the footprint at ground_z
  double yaw = 0.0;                  // direction of the long axis, [0, pi): heading or reverse
  double length = 0.0, width = 0.0;  // m, minimum-area rectangle of the blob's ground points
  double top = 0.0;                  // m, highest point of the blob
  double range = 0.0;                // m, median depth
  int pixels = 0;                    // pixels of colour at car height
  cv::Rect box;                      // image bounding box
  double size_score = 0.0;           // 1: exact size, 0: at the tolerance
  bool cut = false;                  // touches the image border (part of the vehicle may be out)
  std::string reject;                // "" for a candidate; else why not
};

class ColorShapeDetector {
 public:
  explicit ColorShapeDetector(DetectorSettings settings = defaultDetectorSettings());

  // Whether blob `c` (of detect() with `expected`) can stand for a vehicle's box in a track:
  // a candidate, or a blob cut by the image border (a vehicle partly out of the image, whose
  // size is not measurable) no larger than `expected` within the tolerance and in range.
  bool trackable(const CarCandidate& c, const geometry::Vec3& expected) const;

  // Pixels of `color` (CV_8U, 255 where set) in an RGB image (CV_8UC3, R first). Throws
  // scenario::ConfigError for a colour without HSV ranges. With snow, a chromatic range (one
  // that asks for saturation of at least 60) is tested on the image less k times each pixel's
  // least channel, k = min(0.9, snow_whitening * snow): snow cover blends white into a surface
  // (more of every channel alike), which lowers its saturation but keeps its hue and chroma.
  cv::Mat colorMask(const cv::Mat& rgb, const std::string& color) const;

  // Blobs of `color` at car height in one frame. rgb: CV_8UC3 (R first); depth: CV_32FC1,
  // metres along the optical axis (non-finite or <= 0: nothing). `expected` is the target's
  // length, width, height. Every blob of at least min_blob_pixels is returned, accepted ones
  // (reject empty) first, by size score.
  std::vector<CarCandidate> detect(const cv::Mat& rgb, const cv::Mat& depth,
                                   const PinholeCamera& camera,
                                   const Eigen::Isometry3d& world_T_optical,
                                   const std::string& color, const geometry::Vec3& expected) const;

  const DetectorSettings& settings() const { return settings_; }

 private:
  DetectorSettings settings_;
};

// Confidence of a claim: the blob's size score and how much of the symbolic context could be
// verified (relations checked out of those listed), in [0, 1].
double claimConfidence(double size_score, int relations_checked, int relations_skipped);

}  // namespace hameritt::clients
