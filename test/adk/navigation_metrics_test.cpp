#include "hameritt/adk/navigation_metrics.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {
namespace {

using geometry::Vec3;

TEST(Spl, AndersonEquation) {
  // Success along a path twice the shortest: 0.5; shorter than the "shortest" (a shortcut
  // through a tolerance): 1; failure: 0 whatever the path.
  EXPECT_DOUBLE_EQ(splOf({true, 100.0, 200.0}), 0.5);
  EXPECT_DOUBLE_EQ(splOf({true, 100.0, 90.0}), 1.0);
  EXPECT_DOUBLE_EQ(splOf({false, 100.0, 100.0}), 0.0);
  EXPECT_DOUBLE_EQ(
      spl({{true, 100.0, 200.0}, {true, 50.0, 50.0}, {false, 10.0, 1.0}, {true, 30.0, 40.0}}),
      (0.5 + 1.0 + 0.0 + 0.75) / 4);
  EXPECT_THROW(spl({}), InputError);
  EXPECT_THROW(splOf({true, 0.0, 10.0}), InputError);
  EXPECT_THROW(splOf({true, 10.0, NAN}), InputError);
  EXPECT_DOUBLE_EQ(pathLength({Vec3(0, 0, 0), Vec3(3, 4, 0), Vec3(3, 4, 12)}), 17.0);
  EXPECT_DOUBLE_EQ(pathLength({}), 0.0);
}

TEST(TimeToCollision, HeadOnCrossingAndParting) {
  // Head-on at 10 m/s closing from 21 m with radius 1: 2 s.
  EXPECT_DOUBLE_EQ(timeToCollision(Vec3(21, 0, 0), Vec3(-10, 0, 0), 1.0), 2.0);
  EXPECT_DOUBLE_EQ(timeToCollision(Vec3(0.5, 0, 0), Vec3(10, 0, 0), 1.0), 0.0);  // inside
  EXPECT_EQ(timeToCollision(Vec3(21, 0, 0), Vec3(10, 0, 0), 1.0), kNever);       // parting
  EXPECT_EQ(timeToCollision(Vec3(21, 0, 0), Vec3(0, 0, 0), 1.0), kNever);        // still
  EXPECT_EQ(timeToCollision(Vec3(20, 2, 0), Vec3(-10, 0, 0), 1.0), kNever);      // misses by 2
  // Against stepping the extrapolation forward in 1e-4 s steps, on random encounters.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-20, 20);
  int hits = 0, misses = 0;
  for (int k = 0; k < 200; ++k) {
    const Vec3 p(u(rng), u(rng), u(rng) / 4), v(u(rng) / 2, u(rng) / 2, u(rng) / 8);
    const double r = 3.0;
    double stepped = kNever;
    for (double t = 0; t < 20; t += 1e-4) {
      if ((p + v * t).norm() <= r) {
        stepped = t;
        break;
      }
    }
    const double ttc = timeToCollision(p, v, r);
    if (stepped == kNever) {
      // Either never or later than the stepping horizon.
      EXPECT_TRUE(ttc == kNever || ttc > 19.999) << k;
      ++misses;
    } else {
      EXPECT_NEAR(ttc, stepped, 1.5e-4) << k;
      ++hits;
    }
  }
  EXPECT_GE(hits, 10);
  EXPECT_GE(misses, 10);
}

// The vehicle flies east at 5 m/s along y = 0, z = 10; one aircraft crosses at x = 50.
std::vector<TrafficSample> crossing(double aircraft_z) {
  std::vector<TrafficSample> s;
  for (int i = 0; i <= 200; ++i) {
    TrafficSample x;
    x.t = 0.1 * i;
    x.position = Vec3(0.5 * i, 0, 10);
    x.velocity = Vec3(5, 0, 0);
    // Southbound over (50, 0) at t = 10 s, 4 m/s.
    x.aircraft.push_back({"ac1", Vec3(50, 40 - 4 * x.t, aircraft_z), Vec3(0, -4, 0)});
    s.push_back(x);
  }
  return s;
}

TEST(Separation, CrossingTrafficHandWorked) {
  // Both reach (50, 0) at t = 10: contact; 2 m apart vertically is inside the 3 m minimum.
  const auto s = scoreSeparation(crossing(12.0));
  EXPECT_NEAR(s.min_distance_m, 2.0, 1e-9);
  EXPECT_NEAR(s.min_distance_t, 10.0, 1e-9);
  EXPECT_EQ(s.closest_aircraft, "ac1");
  EXPECT_FALSE(s.contact);  // 2 m > 1 m radius
  EXPECT_EQ(s.losses, 1u);
  // Horizontal distance sqrt(25 + 16) (t - 10) < 5 for |t - 10| < 5 / sqrt(41) = 0.781 s:
  // samples 9.3 .. 10.7 (15 samples of 0.1 s).
  EXPECT_NEAR(s.seconds_below_minimum, 1.5, 1e-9);
  // 2 m vertical offset, 1 m radius: the extrapolation never comes within 1 m.
  EXPECT_EQ(s.min_time_to_collision_s, kNever);
  // Same altitude: contact, and at t = 0 the time to collision is 10 s minus the time to
  // cover 1 m at sqrt(41) m/s.
  const auto c = scoreSeparation(crossing(10.0));
  EXPECT_TRUE(c.contact);
  EXPECT_NEAR(c.min_distance_m, 0.0, 1e-9);
  EXPECT_DOUBLE_EQ(c.min_time_to_collision_s, 0.0);  // reached at t = 10
  const auto first = timeToCollision(Vec3(50, 40, 0), Vec3(-5, -4, 0), 1.0);
  EXPECT_NEAR(first, 10.0 - 1.0 / std::sqrt(41.0), 1e-9);
  // Negative control: 3.5 m above is outside the vertical minimum: no loss of separation.
  const auto far = scoreSeparation(crossing(13.5));
  EXPECT_EQ(far.losses, 0u);
  EXPECT_DOUBLE_EQ(far.seconds_below_minimum, 0.0);
  // A stricter minimum counts it.
  SeparationMinimum strict;
  strict.vertical = 4.0;
  EXPECT_EQ(scoreSeparation(crossing(13.5), strict).losses, 1u);
}

TEST(Separation, RejectsMalformedInput) {
  auto s = crossing(12.0);
  s[5].t = s[4].t;
  EXPECT_THROW(scoreSeparation(s), InputError);
  s = crossing(12.0);
  s[3].aircraft[0].position.x() = NAN;
  EXPECT_THROW(scoreSeparation(s), InputError);
  s = crossing(12.0);
  s[3].aircraft.push_back(s[3].aircraft[0]);
  EXPECT_THROW(scoreSeparation(s), InputError);
  SeparationMinimum bad;
  bad.horizontal = -1;
  EXPECT_THROW(scoreSeparation(crossing(12.0), bad), scenario::ConfigError);
  EXPECT_EQ(scoreSeparation({}).losses, 0u);
}

// The tracker that the ADK updates live gives, after every sample, what a batch score of the
// samples so far gives; a rejected sample leaves it as it was.
TEST(Separation, TrackerMatchesTheBatchScoreAfterEverySample) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  std::vector<TrafficSample> samples;
  SeparationTracker tracker;
  for (int i = 0; i < 200; ++i) {
    TrafficSample x;
    x.t = 0.1 * (i + 1);
    x.position = Vec3(u(rng), u(rng), 10 + 0.2 * u(rng));
    x.velocity = Vec3(u(rng), u(rng), 0);
    for (int k = 0; k < 3; ++k) {
      AircraftState a;
      a.id = "aircraft_" + std::to_string(k);
      a.position = Vec3(u(rng), u(rng), 10 + 0.3 * u(rng));
      a.velocity = Vec3(u(rng), u(rng), 0);
      x.aircraft.push_back(a);
    }
    samples.push_back(x);
    tracker.add(x);
    const SeparationScore b = scoreSeparation(samples);
    const SeparationScore& t = tracker.score();
    ASSERT_EQ(t.min_distance_m, b.min_distance_m) << i;
    ASSERT_EQ(t.closest_aircraft, b.closest_aircraft) << i;
    ASSERT_EQ(t.seconds_below_minimum, b.seconds_below_minimum) << i;
    ASSERT_EQ(t.losses, b.losses) << i;
    ASSERT_EQ(t.min_time_to_collision_s, b.min_time_to_collision_s) << i;
    ASSERT_EQ(t.contact, b.contact) << i;
  }
  EXPECT_GT(tracker.score().losses, 0u);  // the random traffic does lose separation
  TrafficSample late = samples.back();    // same stamp: rejected, nothing changes
  late.position = late.aircraft[0].position;
  const SeparationScore before = tracker.score();
  EXPECT_THROW(tracker.add(late), InputError);
  EXPECT_EQ(tracker.samples(), 200u);
  EXPECT_EQ(tracker.score().min_distance_m, before.min_distance_m);
  EXPECT_EQ(tracker.score().contact, before.contact);
}

// A target driving north (yaw pi/2) at 10 m/s from the origin; the vehicle 15 m behind and
// 20 m above, except where `off` says how far it lags further behind.
std::vector<FollowSample> follow(const std::vector<double>& off) {
  std::vector<FollowSample> s;
  for (std::size_t i = 0; i < off.size(); ++i) {
    FollowSample x;
    x.t = static_cast<double>(i);
    x.target = Vec3(0, 10.0 * i, 0);
    x.target_yaw = geometry::kPi / 2;
    x.vehicle = Vec3(0, 10.0 * i - 15.0 - off[i], 20.0);
    x.line_of_sight = i % 2 == 0;
    s.push_back(x);
  }
  return s;
}

TEST(Follow, EnvelopeHandWorked) {
  const FollowEnvelope e;  // 15 +- 5 behind, 20 +- 5 above
  // Lags 0, 0, 8 (outside), 8, 8, 2, 0, 9 (outside), 0, 0, 0 m: 11 samples over 10 s.
  const auto s = scoreFollow(follow({0, 0, 8, 8, 8, 2, 0, 9, 0, 0, 0}), e);
  EXPECT_EQ(s.samples, 11u);
  EXPECT_DOUBLE_EQ(s.duration_s, 10.0);
  // Outside during [2, 5) and [7, 8): 4 of 10 s.
  EXPECT_DOUBLE_EQ(s.inside_fraction, 0.6);
  EXPECT_DOUBLE_EQ(s.longest_outside_s, 3.0);
  EXPECT_DOUBLE_EQ(s.line_of_sight_fraction, 0.5);  // even samples, each 1 s
  EXPECT_NEAR(s.rms_distance_error_m, std::sqrt((64.0 * 3 + 4 + 81) / 11), 1e-12);
  EXPECT_DOUBLE_EQ(s.p95_distance_error_m, 9.0);  // the 11th smallest of 11
  EXPECT_NEAR(s.rms_height_error_m, 0.0, 1e-12);
  EXPECT_FALSE(FollowCriteria{}.passed(s));  // 60 % < 80 %
  // The envelope follows the target's heading: the same positions with the target facing
  // south put the vehicle 15 m in front of it, 30 m from where it should be.
  auto turned = follow({0, 0, 0});
  for (auto& x : turned) x.target_yaw = -geometry::kPi / 2;
  const auto t = scoreFollow(turned, e);
  EXPECT_DOUBLE_EQ(t.inside_fraction, 0.0);
  EXPECT_NEAR(t.rms_distance_error_m, 30.0, 1e-9);
  // Negative control: all inside passes.
  const auto good = scoreFollow(follow(std::vector<double>(11, 1.0)), e);
  EXPECT_DOUBLE_EQ(good.inside_fraction, 1.0);
  EXPECT_DOUBLE_EQ(good.longest_outside_s, 0.0);
  EXPECT_TRUE(FollowCriteria{}.passed(good));
  // Too high is outside too.
  auto high = follow({0, 0});
  high[0].vehicle.z() += 6;
  EXPECT_FALSE(insideEnvelope(high[0], e));
  EXPECT_TRUE(insideEnvelope(high[1], e));
  // Open at the end: outside from t = 3 to the last sample at 5.
  EXPECT_DOUBLE_EQ(scoreFollow(follow({0, 0, 0, 9, 9, 9}), e).longest_outside_s, 2.0);
}

// The batch score written out plainly (sort for the p95, dt to the next sample): the reference
// for the accumulator's live score after every sample.
FollowScore referenceFollow(const std::vector<FollowSample>& s, const FollowEnvelope& e) {
  FollowScore r;
  r.samples = s.size();
  std::vector<double> dist;
  double d2 = 0, h2 = 0, in_s = 0, los_s = 0, since = 0;
  bool out = false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const Vec3 want =
        s[i].target - e.distance * Vec3(std::cos(s[i].target_yaw), std::sin(s[i].target_yaw), 0);
    const double d = (s[i].vehicle - want).head<2>().norm();
    const double h = s[i].vehicle.z() - s[i].target.z() - e.height;
    const bool in = d <= e.distance_tolerance && std::fabs(h) <= e.height_tolerance;
    const double dt = i + 1 < s.size() ? s[i + 1].t - s[i].t : 0.0;
    in_s += in ? dt : 0.0;
    los_s += s[i].line_of_sight ? dt : 0.0;
    if (!in && !out) since = s[i].t;
    if (in && out) r.longest_outside_s = std::max(r.longest_outside_s, s[i].t - since);
    out = !in;
    dist.push_back(d);
    d2 += d * d;
    h2 += h * h;
  }
  if (out) r.longest_outside_s = std::max(r.longest_outside_s, s.back().t - since);
  r.duration_s = s.back().t - s.front().t;
  r.inside_fraction = r.duration_s > 0 ? in_s / r.duration_s : 0.0;
  r.line_of_sight_fraction = r.duration_s > 0 ? los_s / r.duration_s : 0.0;
  r.rms_distance_error_m = std::sqrt(d2 / s.size());
  r.rms_height_error_m = std::sqrt(h2 / s.size());
  std::sort(dist.begin(), dist.end());
  r.p95_distance_error_m = dist[static_cast<std::size_t>(std::ceil(0.95 * s.size())) - 1];
  return r;
}

TEST(Follow, AccumulatorMatchesTheReferenceAfterEverySample) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> lag(-3.0, 9.0);
  std::vector<double> off;
  for (int i = 0; i < 400; ++i) off.push_back(lag(rng));
  const auto samples = follow(off);
  const FollowEnvelope e;
  FollowAccumulator a(e);
  for (std::size_t i = 0; i < samples.size(); ++i) {
    a.add(samples[i]);
    const std::vector<FollowSample> prefix(samples.begin(), samples.begin() + i + 1);
    const FollowScore x = a.result(), r = referenceFollow(prefix, e);
    ASSERT_EQ(x.samples, r.samples) << i;
    ASSERT_NEAR(x.inside_fraction, r.inside_fraction, 1e-12) << i;
    ASSERT_NEAR(x.line_of_sight_fraction, r.line_of_sight_fraction, 1e-12) << i;
    ASSERT_DOUBLE_EQ(x.longest_outside_s, r.longest_outside_s) << i;
    ASSERT_NEAR(x.rms_distance_error_m, r.rms_distance_error_m, 1e-9) << i;
    ASSERT_NEAR(x.rms_height_error_m, r.rms_height_error_m, 1e-9) << i;
    ASSERT_DOUBLE_EQ(x.p95_distance_error_m, r.p95_distance_error_m) << i;
  }
  // The random lags leave the envelope and come back (the figures above are not all trivial).
  EXPECT_GT(a.result().longest_outside_s, 0.0);
  EXPECT_GT(a.result().inside_fraction, 0.2);
  EXPECT_LT(a.result().inside_fraction, 0.9);
  // A sample out of order is refused and changes nothing.
  const FollowScore before = a.result();
  EXPECT_THROW(a.add(samples.front()), InputError);
  EXPECT_EQ(a.result().samples, before.samples);
}

TEST(Follow, RejectsMalformedInput) {
  auto s = follow({0, 0, 0});
  s[1].target_yaw = NAN;
  EXPECT_THROW(scoreFollow(s, {}), InputError);
  s = follow({0, 0, 0});
  s[2].t = 0.5;
  EXPECT_THROW(scoreFollow(s, {}), InputError);
  FollowEnvelope bad;
  bad.distance_tolerance = 0;
  try {
    scoreFollow(follow({0}), bad);
    ADD_FAILURE() << "no error";
  } catch (const scenario::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("envelope.distance_tolerance"), std::string::npos);
  }
  EXPECT_EQ(scoreFollow({}, {}).samples, 0u);
}

}  // namespace
}  // namespace hameritt::adk
