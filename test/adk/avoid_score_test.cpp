// The avoid phase's score: a clean flight succeeds with SPL = shortest / flown; each way of
// failing (no reach, late, lost separation, contact) fails it with SPL 0 (the controls).
#include "hameritt/adk/avoid_score.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {
namespace {

using geometry::Vec3;

scenario::AvoidPhaseSpec spec() {
  scenario::AvoidPhaseSpec s;
  s.goal = Vec3(100, 0, 30);
  s.goal_radius = 5.0;
  s.shortest_path_m = 100.0;
  return s;
}

// The vehicle flies from (0, 0, 30) east at 10 m/s; one aircraft sits at `aircraft` (moving
// with `v`), sampled every 0.5 s until `until`.
AvoidScore fly(const Vec3& aircraft, const Vec3& v, double until = 20.0, double limit = 60.0) {
  AvoidScorer scorer(spec(), limit);
  for (double t = 0.0; t <= until; t += 0.5) {
    TrafficSample s;
    s.t = t;
    s.position = Vec3(std::min(10.0 * t, 100.0), 0, 30);
    s.velocity = Vec3(10, 0, 0);
    s.aircraft.push_back({"aircraft_1", aircraft + v * t, v});
    scorer.add(s);
  }
  return scorer.score(2.5);
}

TEST(AvoidScore, CleanFlightSucceedsWithFullSpl) {
  const AvoidScore s = fly(Vec3(50, 40, 30), Vec3(0, 0, 0));
  EXPECT_TRUE(s.success) << s.failure;
  ASSERT_TRUE(s.reach_time.has_value());
  EXPECT_DOUBLE_EQ(*s.reach_time, 9.5);      // x = 95 m, 5 m from the goal
  EXPECT_NEAR(s.path_length_m, 95.0, 1e-9);  // samples after the reach are ignored
  EXPECT_DOUBLE_EQ(s.spl, 1.0);              // flew less than the shortest path: capped at 1
  EXPECT_NEAR(s.separation.min_distance_m, 40.0, 1e-9);
  EXPECT_EQ(s.separation.losses, 0u);
  EXPECT_DOUBLE_EQ(s.koz_seconds, 2.5);
}

TEST(AvoidScore, LostSeparationFails) {
  // 2 m to the side at the same height when the vehicle passes x = 50 (t = 5).
  const AvoidScore s = fly(Vec3(50, 2, 30), Vec3(0, 0, 0));
  EXPECT_FALSE(s.success);
  EXPECT_EQ(s.separation.losses, 1u);
  // Lost within 4.58 m of x = 50: only the sample at t = 5 (x = 45 and 55 are 5.39 m away),
  // which stands for [5, 5.5).
  EXPECT_NEAR(s.separation.seconds_below_minimum, 0.5, 1e-9);
  EXPECT_NE(s.failure.find("lost separation"), std::string::npos);
  EXPECT_EQ(s.spl, 0.0);
  // 2 m to the side but 4 m higher: separated vertically.
  EXPECT_TRUE(fly(Vec3(50, 2, 34), Vec3(0, 0, 0)).success);
}

TEST(AvoidScore, ContactLateAndNoReachFail) {
  const AvoidScore hit = fly(Vec3(50, 0, 30), Vec3(0, 0, 0));
  EXPECT_NE(hit.failure.find("contact with aircraft_1"), std::string::npos) << hit.failure;
  EXPECT_TRUE(std::isfinite(hit.separation.min_time_to_collision_s));
  const AvoidScore late = fly(Vec3(50, 40, 30), Vec3(0, 0, 0), 20.0, 8.0);
  EXPECT_NE(late.failure.find("after the time limit"), std::string::npos) << late.failure;
  const AvoidScore short_of = fly(Vec3(50, 40, 30), Vec3(0, 0, 0), 8.0);
  EXPECT_FALSE(short_of.reach_time.has_value());
  EXPECT_NE(short_of.failure.find("did not come within 5 m"), std::string::npos);
  EXPECT_NEAR(short_of.goal_distance_m, 20.0, 1e-9);
}

TEST(AvoidScore, BadInputIsAnErrorNotAScore) {
  AvoidScorer scorer(spec(), 60.0);
  TrafficSample s;
  s.t = 1.0;
  scorer.add(s);
  TrafficSample back = s;
  back.t = 0.5;
  EXPECT_THROW(scorer.add(back), InputError);
  TrafficSample nan = s;
  nan.t = 2.0;
  nan.position.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(scorer.add(nan), InputError);
  EXPECT_EQ(scorer.score().path_length_m, 0.0);  // neither was kept
  scenario::AvoidPhaseSpec bad = spec();
  bad.shortest_path_m = 0.0;
  EXPECT_THROW(AvoidScorer(bad, 60.0), scenario::ConfigError);
}

}  // namespace
}  // namespace hameritt::adk
