#pragma once
// Throttled logging on wall time. ROS_*_THROTTLE keys on ros::Time::now(), which is sim time in
// these nodes: a message never prints while sim time is below the period (the first seconds of
// a mission, a simulator paused at t = 0) and prints once only while sim time stands still.
// These print the first occurrence at once, then at most once per `period` wall seconds per
// call site.

#include <ros/console.h>
#include <ros/time.h>

namespace hameritt::ros_wrappers {

// One call site's throttle: due() is true on the first call and then once per period.
class WallThrottle {
 public:
  bool due(double period) {
    const double now = ros::WallTime::now().toSec();
    if (hit_ && now - last_ < period && now >= last_) return false;
    hit_ = true;
    last_ = now;
    return true;
  }

 private:
  bool hit_ = false;
  double last_ = 0.0;
};

}  // namespace hameritt::ros_wrappers

// ROS_ERROR at most once per `period` wall seconds from this call site (the first at once).
#define HAMERITT_ERROR_THROTTLE(period, ...)                          \
  do {                                                                \
    static ::hameritt::ros_wrappers::WallThrottle hameritt_throttle_; \
    if (hameritt_throttle_.due(period)) ROS_ERROR(__VA_ARGS__);       \
  } while (false)

// ROS_INFO at most once per `period` wall seconds from this call site (the first at once).
#define HAMERITT_INFO_THROTTLE(period, ...)                           \
  do {                                                                \
    static ::hameritt::ros_wrappers::WallThrottle hameritt_throttle_; \
    if (hameritt_throttle_.due(period)) ROS_INFO(__VA_ARGS__);        \
  } while (false)
