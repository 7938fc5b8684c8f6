#pragma once
// The follower's setpoint (the planner node's "carrot"): a point ahead on the planned path that
// the UAV's position controller flies straight at. Ahead by a fixed time, it cuts each corner of
// the path, and beside a building the cut can be deeper than the planner's margin (a UAV at
// 12 m/s with a 1.5 s lookahead aims 18 m ahead). The carrot is therefore pulled back along the
// path until the straight line to it keeps a clearance from the obstacles.

#include "hameritt/geometry/types.h"
#include "hameritt/planning/validity.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::planning {

// The plan time of the carrot on the timed `path` (linear interpolation between samples), the
// UAV at `here` and projected on the path at plan time `plan_t`: the latest of
// plan_t + lookahead * (1, 3/4, 1/2, 1/4) whose straight segment from `here` stays `clearance`
// metres clear of every static obstacle box of `validity` (its margin replaced by `clearance`,
// which must lie in (0, margin]; the altitude band is not checked: the UAV may still be taking
// off); plan_t + lookahead / 8 when none does, so that the UAV keeps moving along the path.
double clearCarrotTime(const WorldValidity& validity, const scenario::Trajectory& path,
                       const geometry::Vec3& here, double plan_t, double lookahead,
                       double clearance);

}  // namespace hameritt::planning
