#pragma once
// Scores of the follow and avoid missions: SPL (Anderson et al., "On Evaluation of Embodied
// Navigation Agents", arXiv:1807.06757, 2018), separation from other aircraft with the
// time to collision of a constant-velocity extrapolation, and how well the vehicle keeps a
// follow envelope behind a moving target. ROS-free; samples come from the ADK node at its
// state rate. Times are sample-and-hold: sample i stands for [t_i, t_{i+1}).

#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "hameritt/adk/intervals.h"  // InputError
#include "hameritt/geometry/types.h"

namespace hameritt::adk {

// ---------------------------------------------------------------- SPL
// One episode: whether it succeeded, the shortest path from start to goal (the generator's)
// and the length of the path flown.
struct NavigationEpisode {
  bool success = false;
  double shortest_path_m = 0.0;
  double path_length_m = 0.0;
};

// S * l / max(p, l) of one episode. Throws InputError for a shortest path <= 0 or a
// negative or non-finite length.
double splOf(const NavigationEpisode& e);
// SPL of a set of episodes: the mean of splOf (Anderson et al., eq. 1). Empty: InputError.
double spl(const std::vector<NavigationEpisode>& episodes);
// Length of a polyline.
double pathLength(const std::vector<geometry::Vec3>& points);

// ---------------------------------------------------------------- avoid
// The separation the vehicle must keep from every other aircraft: a loss of separation is
// less than `horizontal` metres apart horizontally while less than `vertical` apart
// vertically (the cylinder of air traffic separation standards). Contact is closer than
// `collision_radius` (the sum of the two bodies' radii); the time to collision is the time
// until the constant-velocity extrapolation comes that close.
struct SeparationMinimum {
  double horizontal = 5.0;        // m
  double vertical = 3.0;          // m
  double collision_radius = 1.0;  // m
  // Throws scenario::ConfigError naming "separation.<field>" and the bad value.
  void validate() const;
};

// Another aircraft's ground truth at a sample.
struct AircraftState {
  std::string id;
  geometry::Vec3 position{0, 0, 0};
  geometry::Vec3 velocity{0, 0, 0};
};

// The vehicle and the other aircraft at sim time t.
struct TrafficSample {
  double t = 0.0;
  geometry::Vec3 position{0, 0, 0};
  geometry::Vec3 velocity{0, 0, 0};
  std::vector<AircraftState> aircraft;
};

constexpr double kNever = std::numeric_limits<double>::infinity();

// Seconds until |p + v t| first falls to `radius` for t >= 0: 0 when already within it,
// kNever when it never does.
double timeToCollision(const geometry::Vec3& relative_position,
                       const geometry::Vec3& relative_velocity, double radius);

struct SeparationScore {
  double min_distance_m = kNever;  // 3D, over samples and aircraft (kNever: no aircraft)
  std::string closest_aircraft;
  double min_distance_t = 0.0;
  double seconds_below_minimum = 0.0;  // time with a loss of separation to any aircraft
  std::size_t losses = 0;              // separate stretches of lost separation
  double min_time_to_collision_s = kNever;
  std::string time_to_collision_aircraft;
  bool contact = false;  // closer than collision_radius at a sample
};

// The separation score kept up to date sample by sample (constant work per sample): what
// scoreSeparation() gives for the samples added so far.
class SeparationTracker {
 public:
  explicit SeparationTracker(const SeparationMinimum& minimum = {});
  // Throws InputError for a stamp that does not increase, a non-finite value, or an aircraft
  // id twice in the sample, before anything is kept.
  void add(const TrafficSample& sample);
  const SeparationScore& score() const { return score_; }
  // Whether the last sample added had lost separation.
  bool lost() const { return last_lost_; }
  std::size_t samples() const { return count_; }

 private:
  SeparationMinimum minimum_;
  SeparationScore score_;
  std::size_t count_ = 0;
  double last_t_ = 0.0;
  bool last_lost_ = false;
};

// Throws InputError for stamps that do not increase, a non-finite value, or an aircraft id
// twice in one sample.
SeparationScore scoreSeparation(const std::vector<TrafficSample>& samples,
                                const SeparationMinimum& minimum = {});

// ---------------------------------------------------------------- follow
// The envelope behind a moving target, in the target's frame (x forward along its yaw, z
// up): the vehicle is inside when its horizontal distance from the point `distance` behind
// the target is at most `distance_tolerance` and its height above the target is within
// `height` +- `height_tolerance`.
struct FollowEnvelope {
  double distance = 15.0;           // d*, m behind
  double distance_tolerance = 5.0;  // D, m
  double height = 20.0;             // h*, m above
  double height_tolerance = 5.0;    // H, m
  // Throws scenario::ConfigError naming "envelope.<field>" and the bad value.
  void validate() const;
};

// The vehicle and the target at sim time t; line_of_sight from the renderer or a ray cast.
struct FollowSample {
  double t = 0.0;
  geometry::Vec3 vehicle{0, 0, 0};
  geometry::Vec3 target{0, 0, 0};
  double target_yaw = 0.0;  // rad, ENU
  bool line_of_sight = true;
};

struct FollowScore {
  double duration_s = 0.0;       // last sample's t minus the first's
  double inside_fraction = 0.0;  // time inside the envelope / duration
  double line_of_sight_fraction = 0.0;
  double longest_outside_s = 0.0;  // longest stretch outside (to the next inside sample)
  // Per sample: horizontal distance from the point d* behind the target, and height error.
  double rms_distance_error_m = 0.0;
  double p95_distance_error_m = 0.0;  // nearest rank: the ceil(0.95 n)-th smallest
  double rms_height_error_m = 0.0;
  std::size_t samples = 0;
};

// Whether one sample lies inside the envelope.
bool insideEnvelope(const FollowSample& s, const FollowEnvelope& envelope);

// Throws InputError for stamps that do not increase or a non-finite value.
FollowScore scoreFollow(const std::vector<FollowSample>& samples, const FollowEnvelope& envelope);

// scoreFollow one sample at a time (scoreFollow is this over the whole vector): a live score
// costs O(1) per sample plus one O(n) selection for the p95, not a pass over every sample.
class FollowAccumulator {
 public:
  explicit FollowAccumulator(const FollowEnvelope& envelope);  // ConfigError from validate()
  // InputError (naming the sample's index) for a stamp that does not increase or a non-finite
  // value; the sample is then not kept.
  void add(const FollowSample& sample);
  FollowScore result() const;

 private:
  FollowEnvelope e_;
  std::size_t n_ = 0;
  double first_t_ = 0.0, last_t_ = 0.0;
  bool last_in_ = false, last_los_ = false;
  std::vector<double> dist_;
  double sum_d2_ = 0.0, sum_h2_ = 0.0, inside_s_ = 0.0, los_s_ = 0.0, longest_outside_ = 0.0;
  bool outside_ = false;
  double outside_since_ = 0.0;
};

// The follow phase's success test (besides no collision and no KOZ violation, which the
// constraint monitor judges): inside at least `min_inside_fraction` of the phase and never
// outside for longer than `max_outside_s`.
struct FollowCriteria {
  double min_inside_fraction = 0.8;
  double max_outside_s = 10.0;
  bool passed(const FollowScore& s) const {
    return s.inside_fraction >= min_inside_fraction && s.longest_outside_s <= max_outside_s;
  }
};

}  // namespace hameritt::adk
