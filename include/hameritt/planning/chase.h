#pragma once
// Chase paths for the perception-only thread of follow and track missions: the UAV pursues a
// moving target's scripted trajectory and then keeps a chase point (a distance behind the target
// along its own path, a height above it) with the target in a payload camera's view. Unlike a
// look-at path (look_at.h), which waits for the targets to stop, a chase path keeps up with the
// target while it drives.

#include <optional>
#include <string>

#include "hameritt/planning/uav_planner.h"
#include "hameritt/planning/validity.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::planning {

struct ChaseSettings {
  double behind = 0.0;         // metres behind the target, measured along the target's own path
  double height = 30.0;        // metres above the target's ground point (then kept in the band)
  double step = 0.5;           // seconds between keyframes
  double time_constant = 2.0;  // seconds: the pursuit closes the gap at 1/time_constant
  double caught_radius = 2.0;  // metres: the chase point is held within this
  double yaw_offset = 0.0;     // radians added to the heading that faces the target
  void validate() const;       // ConfigError naming "chase.<field>"
};

struct ChaseResult {
  PlanStatus status = PlanStatus::kNoSolution;
  std::string message;             // why a path was cut short
  scenario::Trajectory path;       // {t, x, y, z, yaw} from t0, every `step` seconds
  std::optional<double> caught_t;  // first keyframe within caught_radius of the chase point
  int seen = 0;                    // keyframes from caught_t on that see the target ...
  int frames = 0;                  // ... of these many (projection + clear line of sight)
};

// Pursues `target` (its scripted trajectory; `target_size` its box: length, width, height) from
// `start` at t0 up to t_end with the speed limits of `settings.speed` (top horizontal speed,
// climb and descent rates, acceleration). The chase point at time t lies `behind` metres back
// along the target's path (before it, along its first heading) and `height` metres above the
// target's ground point, kept within [zmin, zmax]; the UAV faces the target (the target's
// heading when it is within 3 m horizontally), turned by `yaw_offset`. It stays 2 m inside the
// area's bounds (waiting at the edge for a target that drives out). Every step is checked
// against `validity` (static obstacles, band, bounds, keep-out zones at their times); a step
// that is not valid is replaced by holding in place, and when holding is not valid either, the
// path ends there: kNoSolution with the path up to the last valid keyframe and the reason. Else
// kExact. `camera` judges what is seen (its projection of the box centre inside the image shrunk by
// 8 px, and a clear line of sight through the world's occluders).
ChaseResult planChasePath(const WorldValidity& validity, const scenario::CameraSpec& camera,
                          const geometry::Vec3& start, double t0, double t_end,
                          const scenario::Trajectory& target, const geometry::Vec3& target_size,
                          double zmin, double zmax, const UavPlannerSettings& settings,
                          const ChaseSettings& chase);

}  // namespace hameritt::planning
