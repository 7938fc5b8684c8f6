#pragma once

#include <string>

#include "hameritt/sim/quadrotor.h"

namespace hameritt::sim {

// The box the UAV must stay in (map/ENU metres): the neighborhood bounds grown by a margin, from
// the ground up to a ceiling above the UAV's flight band.
struct Geofence {
  Vec3 min{0, 0, 0};
  Vec3 max{0, 0, 0};
  // Within this distance of a face, a velocity setpoint's outward component is dropped (the
  // braking distance from full speed at full tilt, with room for the controller's lag).
  double brake_distance = 20.0;
};

// What a setpoint check decided: `error` is empty when the setpoint was accepted as it is or
// clamped (then `clamped` names the fields changed); a non-empty `error` means rejected.
struct SetpointCheck {
  std::string error;
  std::string clamped;
};

// Hostile setpoints: rejects non-finite fields, clamps finite ones into the controller's limits
// and the geofence. Every message names the field and what was expected.
class SetpointGuard {
 public:
  SetpointGuard(const Geofence& fence, const QuadrotorParams& params);

  // A velocity setpoint (map frame) and yaw rate: non-finite -> rejected; speeds clamped to
  // the horizontal, climb, descent and yaw-rate limits.
  SetpointCheck checkVelocity(Vec3* velocity, double* yaw_rate) const;
  // A position setpoint and yaw: a non-finite position -> rejected; a non-finite yaw -> 0; a
  // position is clamped into the geofence with brake_distance to spare at its sides and ceiling.
  SetpointCheck checkPosition(Vec3* position, double* yaw) const;
  // The velocity the UAV at `position` may be commanded now: components pointing out of the
  // fence are dropped within brake_distance of a side or the ceiling (beyond one, a return at
  // 1 m/s is commanded instead).
  Vec3 fenceVelocity(const Vec3& position, const Vec3& velocity) const;

  // The fence this guard keeps.
  const Geofence& fence() const { return fence_; }

 private:
  Geofence fence_;
  QuadrotorParams params_;
};

}  // namespace hameritt::sim
