#pragma once
// Where a scenario's target may stand: the parking-slot rules that the random generator and the
// spec compiler share.

#include "hameritt/scenario/scenario.h"
#include "hameritt/scenario/world.h"

namespace hameritt::scenario {

// Metres along the street that a pursuit target drives to pull out of its kerb slot into its lane.
constexpr double kPullOut = 10.0;

// True for points at least 20 m inside the neighborhood, where an AOI around them fits.
bool insideBy20(const World& world, const geometry::Vec2& p);

// A pursuit target's kerb slot: in a block, well inside, with room ahead to pull out into the
// lane before the corner.
bool pursuitSlotFits(const World& world, const ParkingSlot& s);

// True when parking slot `slot` can hold the target of a `cls` scenario (free, well inside the
// neighborhood; for a pursuit, a kerb slot with room to pull out into the lane).
bool targetSlotAllowed(const World& world, int slot, ScenarioClass cls);

}  // namespace hameritt::scenario
