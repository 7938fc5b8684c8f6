#include "hameritt/sim/setpoint_guard.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "hameritt/scenario/error.h"

namespace hameritt::sim {

namespace {

const char* const kAxis[3] = {"x", "y", "z"};

std::string fmt(double v) { return scenario::formatNumber(v); }

void addField(std::string* list, const std::string& field) {
  *list += (list->empty() ? "" : ", ") + field;
}

}  // namespace

SetpointGuard::SetpointGuard(const Geofence& fence, const QuadrotorParams& params)
    : fence_(fence), params_(params) {
  for (int i = 0; i < 3; ++i) {
    if (!(std::isfinite(fence.min[i]) && std::isfinite(fence.max[i]) &&
          fence.min[i] < fence.max[i])) {
      throw scenario::ConfigError(std::string("geofence: ") + kAxis[i] +
                                  ": expected finite min < max, got [" + fmt(fence.min[i]) + ", " +
                                  fmt(fence.max[i]) + "]");
    }
  }
  if (!(fence.brake_distance >= 0 && std::isfinite(fence.brake_distance))) {
    throw scenario::ConfigError("geofence: brake_distance: expected metres >= 0, got " +
                                fmt(fence.brake_distance));
  }
}

SetpointCheck SetpointGuard::checkVelocity(Vec3* velocity, double* yaw_rate) const {
  SetpointCheck out;
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite((*velocity)[i])) {
      out.error = std::string("linear.") + kAxis[i] + ": expected a finite velocity (m/s), got " +
                  fmt((*velocity)[i]);
      return out;
    }
  }
  if (!std::isfinite(*yaw_rate)) {
    out.error = "angular.z: expected a finite yaw rate (rad/s), got " + fmt(*yaw_rate);
    return out;
  }
  const double h = std::hypot(velocity->x(), velocity->y());
  if (h > params_.max_horizontal_speed) {
    velocity->x() *= params_.max_horizontal_speed / h;
    velocity->y() *= params_.max_horizontal_speed / h;
    addField(&out.clamped, "linear.x/y to " + fmt(params_.max_horizontal_speed) + " m/s");
  }
  const double z = std::clamp(velocity->z(), -params_.max_descent, params_.max_climb);
  if (z != velocity->z()) {
    velocity->z() = z;
    addField(&out.clamped,
             "linear.z to [-" + fmt(params_.max_descent) + ", " + fmt(params_.max_climb) + "] m/s");
  }
  const double w = std::clamp(*yaw_rate, -params_.max_yaw_rate, params_.max_yaw_rate);
  if (w != *yaw_rate) {
    *yaw_rate = w;
    addField(&out.clamped, "angular.z to +-" + fmt(params_.max_yaw_rate) + " rad/s");
  }
  return out;
}

SetpointCheck SetpointGuard::checkPosition(Vec3* position, double* yaw) const {
  SetpointCheck out;
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite((*position)[i])) {
      out.error = std::string("pose.position.") + kAxis[i] +
                  ": expected a finite coordinate (m), got " + fmt((*position)[i]);
      return out;
    }
  }
  if (!std::isfinite(*yaw)) {
    *yaw = 0.0;
    addField(&out.clamped, "pose.orientation (not a rotation) to yaw 0");
  }
  // Into the fence with brake_distance to spare (the floor is the ground: no margin there), so
  // that the position loop's overshoot stays inside.
  for (int i = 0; i < 3; ++i) {
    const double lo = i < 2 ? fence_.min[i] + fence_.brake_distance : fence_.min[i];
    const double hi = fence_.max[i] - fence_.brake_distance;
    const double c = std::clamp((*position)[i], std::min(lo, hi), std::max(lo, hi));
    if (c != (*position)[i]) {
      addField(&out.clamped, std::string("pose.position.") + kAxis[i] + " " + fmt((*position)[i]) +
                                 " to the geofence's " + fmt(c));
      (*position)[i] = c;
    }
  }
  return out;
}

Vec3 SetpointGuard::fenceVelocity(const Vec3& position, const Vec3& velocity) const {
  // The floor is the ground, where descending ends in a landing (or a crash): no braking there.
  Vec3 v = velocity;
  for (int i = 0; i < 3; ++i) {
    const double to_min = position[i] - fence_.min[i];
    const double to_max = fence_.max[i] - position[i];
    if (to_min < 0) {
      v[i] = std::max(v[i], 1.0);
    } else if (to_max < 0) {
      v[i] = std::min(v[i], -1.0);
    } else if (i < 2 && to_min < fence_.brake_distance && v[i] < 0) {
      v[i] = 0.0;
    } else if (to_max < fence_.brake_distance && v[i] > 0) {
      v[i] = 0.0;
    }
  }
  return v;
}

}  // namespace hameritt::sim
