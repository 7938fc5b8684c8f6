#pragma once
// The avoid phase's score from the vehicle's states and the other aircraft's ground truth
// (navigation_metrics.h): success (within the goal radius before the time limit, no contact,
// separation never lost), SPL against the generator's shortest path (Anderson et al. 2018),
// the minimum separation, the seconds below it and the minimum time to collision. The phase
// ends when the vehicle first comes within the goal radius; samples after that are ignored.
// ROS-free.

#include <optional>
#include <string>
#include <vector>

#include "hameritt/adk/navigation_metrics.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::adk {

struct AvoidScore {
  bool success = false;
  std::string failure;               // why not, "" on success
  std::optional<double> reach_time;  // first sample within the goal radius
  double goal_distance_m = 0.0;      // 3D, at the last sample scored
  double path_length_m = 0.0;        // flown up to the reach (or the last sample)
  double shortest_path_m = 0.0;      // the generator's
  double spl = 0.0;
  SeparationScore separation;
  double koz_seconds = 0.0;  // the constraint monitor's violation seconds (reported only)
};

class AvoidScorer {
 public:
  // Throws scenario::ConfigError for a non-positive goal radius, shortest path or separation
  // minimum, or a non-positive time limit.
  AvoidScorer(const scenario::AvoidPhaseSpec& spec, double time_limit,
              double collision_radius = 1.0);

  // One sample: the vehicle and the aircraft at t. InputError as scoreSeparation (stamps that
  // do not increase, non-finite values, an aircraft twice), before anything is kept.
  void add(const TrafficSample& sample);
  bool reached() const { return reach_time_.has_value(); }
  // Whether the last sample added had lost separation.
  bool separationLost() const { return separation_.lost(); }

  // The score so far (constant work: the ADK publishes it live); `koz_seconds` from the
  // constraint monitor.
  AvoidScore score(double koz_seconds = 0.0) const;

 private:
  scenario::AvoidPhaseSpec spec_;
  double time_limit_;
  SeparationTracker separation_;
  double path_length_ = 0.0;
  std::optional<geometry::Vec3> last_position_;
  std::optional<double> reach_time_;
};

}  // namespace hameritt::adk
