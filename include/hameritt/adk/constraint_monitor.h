#pragma once
// Continuous monitoring of a UAV path against a mission's keep-out zones (hard constraints)
// and areas of interest (soft constraints). The path between two consecutive samples is the
// straight segment with time linear along it, exactly as the simulator's and the planner's
// timed paths are read; every entry, exit and violation time is computed from the exact
// intersection of that segment with the zone, not from the samples. ROS-free.

#include <cstddef>
#include <string>
#include <vector>

#include "hameritt/adk/intervals.h"
#include "hameritt/geometry/polygon.h"
#include "hameritt/geometry/types.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::adk {

// Parameter intervals [u0, u1] within [0, 1] during which a + u (b - a) lies in the polygon
// region (boundary counts as inside; a segment that only touches a vertex gives a zero-length
// interval). Exact up to rounding: the breakpoints are the segment's intersections with the
// polygon's edges, and every piece between two breakpoints is classified by its midpoint.
std::vector<Interval> segmentInsidePolygon(const geometry::Polygon& polygon,
                                           const geometry::Vec2& a, const geometry::Vec2& b);

// Time intervals within [ta, tb] during which the path from a (at ta) to b (at tb), linear in
// time, is inside the keep-out zone's prism (polygon x altitude band; a missing bound is open;
// boundary inside), ignoring the zone's time window. ta <= tb. A moving zone is taken where
// it stands at (ta + tb) / 2.
std::vector<Interval> prismIntervals(const scenario::KeepOutZone& zone, const geometry::Vec3& a,
                                     const geometry::Vec3& b, double ta, double tb);

// The same intersected with the zone's time window: when the path violates the zone.
std::vector<Interval> violationIntervals(const scenario::KeepOutZone& zone, const geometry::Vec3& a,
                                         const geometry::Vec3& b, double ta, double tb);

// One time interval during which the UAV was inside an active keep-out zone. Intervals of the
// same zone that touch (across samples, or where a window opens as the UAV enters) are merged.
struct Violation {
  std::string zone_id;
  std::string purpose;
  double t_enter = 0.0;
  double t_exit = 0.0;   // the latest sample's time while ongoing
  bool ongoing = false;  // the UAV is still inside the active zone at the latest sample
  double duration() const { return t_exit - t_enter; }
};

// An entry or exit as it happens, at its exact interpolated time and position.
struct ConstraintEvent {
  enum class Kind { kEnter, kExit, kViolationStart, kViolationEnd };
  Kind kind = Kind::kEnter;
  bool keep_out_zone = true;  // false: an area of interest
  std::string id;
  std::string purpose;  // keep-out zones only
  double t = 0.0;
  geometry::Vec3 position{0, 0, 0};
  bool active = false;  // the zone's (or area's) time window is active at t
};
// "enter", "exit", "violation_start", "violation_end".
const char* toString(ConstraintEvent::Kind k);

// A keep-out zone now (at the latest sample).
struct ZoneStatus {
  std::string id;
  std::string purpose;
  bool inside = false;     // inside the prism, whether the zone is active or not
  bool active = false;     // its window is active now
  bool violating = false;  // inside and active
};

// Time spent in an area of interest (its polygon, any altitude).
struct AoiStatus {
  std::string id;
  bool inside = false;
  bool active = false;              // its window is active now
  double time_inside = 0.0;         // total
  double time_inside_active = 0.0;  // while its window was active
  int entries = 0;                  // times the UAV entered (the first sample inside counts)
};

// Feeds timed positions and keeps violations, events and area times up to the latest sample.
class ConstraintMonitor {
 public:
  explicit ConstraintMonitor(const scenario::Mission& mission);

  // Adds a sample at mission time t (strictly after the previous one; t and p finite:
  // InputError otherwise, and the monitor is unchanged). Returns the events of the segment from
  // the previous sample (or of the first sample), in time order.
  std::vector<ConstraintEvent> add(double t, const geometry::Vec3& p);

  std::size_t sampleCount() const { return samples_; }
  // Time and position of the latest sample (sampleCount() > 0).
  double lastTime() const { return last_t_; }
  const geometry::Vec3& lastPosition() const { return last_p_; }

  // Every violation so far (completed ones and an ongoing one per zone), by entry time.
  std::vector<Violation> violations() const;
  // Sum of violation durations and their number.
  double violationDuration() const;
  std::size_t violationCount() const;
  std::vector<ZoneStatus> zones() const;
  std::vector<AoiStatus> areas() const;

 private:
  struct ZoneTrack {
    scenario::KeepOutZone zone;
    bool in_prism = false;
    bool violating = false;
    std::vector<Violation> violations;
  };
  struct AreaTrack {
    scenario::AreaOfInterest area;
    AoiStatus status;
  };
  void segment(const geometry::Vec3& a, const geometry::Vec3& b, double ta, double tb,
               std::vector<ConstraintEvent>* events);

  std::vector<ZoneTrack> zones_;
  std::vector<AreaTrack> areas_;
  std::size_t samples_ = 0;
  double last_t_ = 0.0;
  geometry::Vec3 last_p_{0, 0, 0};
};

}  // namespace hameritt::adk
