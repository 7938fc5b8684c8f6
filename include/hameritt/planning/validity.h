#pragma once
// Validity of UAV states and motions over the static neighborhood and a mission's keep-out
// zones. ROS-free and OMPL-free: the OMPL planners wrap it, and tests and clients can check any
// path with it. Frame: ENU metres; times in seconds from mission start.

#include <memory>
#include <string>
#include <vector>

#include "hameritt/geometry/line_of_sight.h"
#include "hameritt/geometry/polygon.h"
#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::planning {

// How conservative the checker is. Validated by validate() (ConfigError naming the field).
struct ValiditySettings {
  double margin = 1.0;         // obstacles and keep-out zones inflated by this, metres
  double altitude_min = 20.0;  // flight band, metres above ground (z)
  double altitude_max = 60.0;
  // Throws scenario::ConfigError naming "planning.<field>" and the bad value.
  void validate() const;
};

// Settings of a UAV flight from the sim_config's UavSpec (altitude band) and a margin.
ValiditySettings validitySettingsFor(const scenario::UavSpec& uav, double margin = 1.0);

// The world as a validity checker. Hard constraints: every static obstacle box (houses,
// garages, fences, tree trunks and canopies, parked cars: World::occluders()) inflated by the
// margin in all directions, the altitude band, the neighborhood bounds, and the keep-out zones
// (polygon inflated by the margin, altitude band +- margin) while their time window is active.
// Areas of interest are soft constraints and play no part in validity.
// Segment checks are exact (continuous), not sampled: boxes by slab tests through the
// occluder grid, keep-out zones by clipping the segment to the zone's altitude band and active
// time and measuring its plane distance to the polygon.
// Immutable after construction; safe to share between threads.
class WorldValidity {
 public:
  // The obstacles inflated by the margin, with a point grid over them (validity.cpp).
  struct Obstacles;

  WorldValidity(const scenario::World& world, std::vector<scenario::KeepOutZone> kozs,
                const ValiditySettings& settings);
  WorldValidity(const scenario::World& world, const scenario::Mission& mission,
                const ValiditySettings& settings);

  const scenario::World& world() const { return world_; }
  const ValiditySettings& settings() const { return settings_; }
  const std::vector<scenario::KeepOutZone>& kozs() const { return kozs_; }
  // Planar bounds of flight (the neighborhood bounds).
  const geometry::Aabb2& bounds() const { return bounds_; }
  // True when some keep-out zone has a bounded time window.
  bool hasTimedKozs() const;

  // Obstacles, band and bounds only (time-independent). `slack` shrinks the margin (used to
  // validate rounded output paths).
  bool staticValid(const geometry::Vec3& p, double slack = 0.0) const;
  bool staticSegmentValid(const geometry::Vec3& a, const geometry::Vec3& b,
                          double slack = 0.0) const;
  // The obstacles alone (no band, no bounds): the segment meets no obstacle box inflated by the
  // margin less `slack` (a negative slack inflates them more). Exact.
  bool obstacleSegmentClear(const geometry::Vec3& a, const geometry::Vec3& b,
                            double slack = 0.0) const;
  // p is clear of every keep-out zone active at some instant of [t0, t1].
  bool kozClear(const geometry::Vec3& p, double t0, double t1, double slack = 0.0) const;
  // The segment, traversed with time linear from ta (at a) to tb (at b), never meets an
  // active keep-out zone. Exact.
  bool kozSegmentClear(const geometry::Vec3& a, const geometry::Vec3& b, double ta, double tb,
                       double slack = 0.0) const;
  // Conservative: the segment is clear of every zone active at any instant of [t0, t1]
  // (the time along it is only known to lie in that interval).
  bool kozSegmentClearDuring(const geometry::Vec3& a, const geometry::Vec3& b, double t0,
                             double t1, double slack = 0.0) const;
  // Point at time t: static and keep-out zones.
  bool valid(const geometry::Vec3& p, double t) const {
    return staticValid(p) && kozClear(p, t, t);
  }
  // Why p at time t is invalid ("inside the inflated box of house_12"), "" when valid.
  std::string explain(const geometry::Vec3& p, double t) const;
  // Checks a timed path as the simulator reads it (linear interpolation in position and time
  // between samples), continuously, in pieces of at most `max_step` metres, with the margin
  // reduced by `slack`. Returns "" when valid, else what failed and where.
  std::string checkTrajectory(const scenario::Trajectory& traj, double max_step = 0.25,
                              double slack = 0.0) const;

 private:
  bool kozSegmentHit(const scenario::KeepOutZone& k, std::size_t i, const geometry::Vec3& a,
                     const geometry::Vec3& b, double u0, double u1, double slack) const;

  const scenario::World& world_;
  std::vector<scenario::KeepOutZone> kozs_;
  std::vector<geometry::Aabb2> koz_bounds_;  // inflated by the margin
  ValiditySettings settings_;
  geometry::Aabb2 bounds_;
  // Shared by every checker of the same world and margin (the generator builds one per
  // scenario).
  std::shared_ptr<const Obstacles> obstacles_;
};

}  // namespace hameritt::planning
