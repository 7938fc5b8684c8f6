#pragma once
// Look-at paths for the perception-only thread: viewpoints from which each entity of interest
// projects into the payload camera's image with a clear line of sight, joined by safe UAV
// flights; the guarantee is re-checked on the final timed path, not assumed.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "hameritt/planning/uav_planner.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::planning {

// Pinhole projection with the payload camera model: the UAV flies level, so the camera pose is
// the UAV pose (position, yaw) composed with the mount (xyz in FLU body, roll-pitch-yaw in
// degrees, positive pitch looks down). Returns the pixel (u right, v down) when the point is in
// front of the camera and inside the image shrunk by `margin_px`, else nullopt.
std::optional<geometry::Vec2> projectToImage(const scenario::CameraSpec& cam,
                                             const geometry::Vec3& uav_position, double uav_yaw,
                                             const geometry::Vec3& point, double margin_px = 0.0);
// The camera's optical centre in the world for a UAV pose.
geometry::Vec3 cameraPosition(const scenario::CameraSpec& cam, const geometry::Vec3& uav_position,
                              double uav_yaw);

// Something to look at: a point (usually its box centre) and the occluder boxes that belong to
// it (World::occludersOf for a world entity; empty for a scenario mover), which do not block.
struct LookAtTarget {
  std::string id;
  geometry::Vec3 point;
  std::vector<int> own_occluders;
};

struct LookAtSettings {
  int candidates = 200;       // viewpoint candidates sampled per target
  double range_min = 10.0;    // horizontal stand-off bounds for non-nadir cameras, metres
  double range_max = 80.0;
  double margin_px = 8.0;     // the target must project this far inside the image
  double dwell = 1.0;         // seconds hovering at each viewpoint
  double yaw_rate_deg = 90.0; // turning in place to the viewing yaw
  void validate() const;      // ConfigError naming "look_at.<field>"
};

struct Viewpoint {
  std::string target_id;
  geometry::Vec3 position;
  double yaw = 0.0;
  double t = 0.0;              // time of the dwell sample that looks at the target
  geometry::Vec2 pixel{0, 0};  // where the target projects at that sample
};

struct LookAtResult {
  PlanStatus status = PlanStatus::kNoSolution;
  std::string message;
  std::vector<Viewpoint> viewpoints;  // in visiting order, verified on the final path
  std::vector<std::string> unseen;    // targets without a valid viewpoint
  PlanResult flight;                  // the whole timed path
};

// Chooses for each target a viewpoint (seeded candidates: altitude in the band, stand-off from
// the camera pitch, yaw facing the target) that is valid for all time after t0 (so hovering
// there is safe), projects the target inside the image and has clear line of sight
// (OccluderIndex::clear); orders them greedily by distance, flies planUavPath legs between them
// and turns in place to the viewing yaw at each. Then verifies, on the final timed path's
// dwell samples, the projection and line of sight again. kExact only when every target is
// verified; a target without a viewpoint gives kNoSolution (the others are still planned and
// reported in `unseen`).
LookAtResult planLookAtPath(const WorldValidity& validity, const scenario::CameraSpec& camera,
                            const geometry::Vec3& start, double t0,
                            const std::vector<LookAtTarget>& targets,
                            const UavPlannerSettings& settings, std::uint64_t seed,
                            const LookAtSettings& look = {});

}  // namespace hameritt::planning
