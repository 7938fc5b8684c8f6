#pragma once
// Where a scenario's target may stand: the parking-slot rules that the random generator and the
// spec compiler share.

#include <vector>

#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

// Metres along the street that a pursuit target drives to pull out of its kerb slot into its lane.
constexpr double kPullOut = 10.0;
// A car's lane centre lies this far inside the kerb: half the street width less this, right of
// the centreline.
constexpr double kLaneOffsetFromKerb = 3.45;

// True for points at least 20 m inside the neighborhood, where an AOI around them fits.
bool insideBy20(const World& world, const geometry::Vec2& p);

// A pursuit target's kerb slot: in a block, well inside, with room ahead to pull out into the
// lane before the corner.
bool pursuitSlotFits(const World& world, const ParkingSlot& s);

// True when parking slot `slot` can hold the target of a `cls` scenario (free, well inside the
// neighborhood; for a pursuit, a kerb slot with room to pull out into the lane).
bool targetSlotAllowed(const World& world, int slot, ScenarioClass cls);

// A straight drive in a lane: from street node position `from` in direction `dir`, the lane
// centre `lane_offset` right of the centreline, from `begin` to `end` metres along (where the
// lane ends before the next intersection). Route-search starts and a pursuit target's drive
// after it pulls out; the spec compiler measures relations along it.
struct LaneDrive {
  geometry::Vec2 from = geometry::Vec2(0, 0);
  geometry::Vec2 dir = geometry::Vec2(1, 0);
  double lane_offset = 0;
  double begin = 0;
  double end = 0;
  // The rounded pose `s` metres along, at time `t`.
  TrajectoryPoint pose(double s, double t = 0.0) const;
};

// A route-search target's start that the spec compiler offers: `s` metres from node `from`
// towards node `to`, in the lane (whole metres, 20 m to a fifth of the street on, and room
// before the corner, as the random generator draws them).
struct RouteStart {
  int from = -1;
  int to = -1;
  double s = 0;
};
// Every route start of the world, street by street in both directions.
std::vector<RouteStart> routeStarts(const World& world);
// The drive from a route start to the end of its first street.
LaneDrive routeStartDrive(const World& world, const RouteStart& start);
// A pursuit target's drive in its lane after pulling out of kerb slot `slot`.
LaneDrive pursuitDrive(const World& world, int slot);

}  // namespace hameritt::scenario
