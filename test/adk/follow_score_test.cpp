// The follow phase's score: a vehicle that stays in the envelope behind a driving target
// succeeds; the same flight with an 11 s excursion (the negative control) fails on the
// 10 s rule, and one that hovers where the target was found fails on both rules. The scored
// part starts at the first entry within the approach allowance; an approach 11 s longer than
// the allowance fails on the 10 s rule.
#include "hameritt/adk/follow_score.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {
namespace {

using geometry::Vec3;

scenario::MissionPhase followPhase() {
  scenario::MissionPhase p;
  p.id = "follow_1";
  p.type = scenario::PhaseType::kFollow;
  p.targets = {"car_7"};
  p.duration = 60.0;
  p.follow.distance = 15.0;
  p.follow.distance_tolerance = 5.0;
  p.follow.height = 25.0;
  p.follow.height_tolerance = 5.0;
  return p;
}

// The target drives east at 8 m/s from x = 0 at t = 20 (the find); the vehicle keeps 15 m
// behind and 25 m above, except between `away_from` and `away_to` when it climbs 20 m.
// Sampled every 0.1 s from t = 10 to t = 90.
FollowScorer flight(double away_from, double away_to, bool hover = false) {
  FollowScorer s(followPhase());
  for (int i = 100; i <= 900; ++i) {
    const double t = i / 10.0;
    if (i == 200) s.start(t);
    FollowSample f;
    f.t = t;
    f.target = Vec3(std::max(0.0, 8.0 * (t - 20.0)), 0.0, 0.0);
    f.target_yaw = 0.0;
    f.vehicle = hover ? Vec3(-15.0, 0.0, 25.0) : f.target + Vec3(-15.0, 1.0, 24.0);
    if (t >= away_from && t < away_to) f.vehicle.z() += 20.0;
    f.line_of_sight = t < 50.0;
    s.add(f);
  }
  return s;
}

TEST(FollowScore, InsideTheEnvelopeSucceeds) {
  const FollowScorer s = flight(-1, -1);
  EXPECT_TRUE(s.complete());
  EXPECT_FALSE(s.failedEarly());
  const FollowPhaseScore r = s.score(0.0, false, true);
  EXPECT_TRUE(r.success) << r.failure;
  EXPECT_EQ(r.state, PhaseState::kSucceeded);
  ASSERT_TRUE(r.start_time.has_value());
  EXPECT_NEAR(*r.start_time, 20.0, 1e-9);
  // Samples from the find to the phase's end only (t = 20.0 ... 80.0).
  EXPECT_EQ(r.envelope.samples, 601u);
  EXPECT_NEAR(r.envelope.duration_s, 60.0, 1e-6);
  EXPECT_NEAR(r.envelope.inside_fraction, 1.0, 1e-9);
  EXPECT_NEAR(r.envelope.rms_distance_error_m, 1.0, 1e-9);
  EXPECT_NEAR(r.envelope.p95_distance_error_m, 1.0, 1e-9);
  EXPECT_NEAR(r.envelope.rms_height_error_m, 1.0, 1e-9);
  EXPECT_NEAR(r.envelope.line_of_sight_fraction, 0.5, 1e-6);  // [20, 50) of [20, 80]
  EXPECT_DOUBLE_EQ(r.envelope.longest_outside_s, 0.0);
}

TEST(FollowScore, ElevenSecondsOutsideFails) {
  // Negative control: 11 s above the envelope, 49 s of 60 (81.7 %) inside: the fraction
  // passes, the longest stretch does not.
  const FollowScorer s = flight(30.0, 41.0);
  EXPECT_TRUE(s.failedEarly());
  const FollowPhaseScore r = s.score(0.0, false, true);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.state, PhaseState::kFailed);
  EXPECT_NEAR(r.envelope.longest_outside_s, 11.0, 1e-6);
  EXPECT_NEAR(r.envelope.inside_fraction, 49.0 / 60.0, 1e-6);
  EXPECT_NE(r.failure.find("outside the envelope for 11.00 s"), std::string::npos) << r.failure;
  // Nine seconds outside passes the same rule.
  const FollowPhaseScore nine = flight(30.0, 39.0).score(0.0, false, true);
  EXPECT_TRUE(nine.success) << nine.failure;
}

TEST(FollowScore, HoveringAtTheFindFails) {
  const FollowScorer s = flight(-1, -1, /*hover=*/true);
  const FollowPhaseScore r = s.score(0.0, false, true);
  EXPECT_FALSE(r.success);
  EXPECT_LT(r.envelope.inside_fraction, 0.8);
  EXPECT_GT(r.envelope.longest_outside_s, 10.0);
}

TEST(FollowScore, SearchCollisionKozAndEarlyEndFail) {
  // Never started: the search phase failed.
  FollowScorer never(followPhase());
  FollowSample f;
  f.t = 1.0;
  EXPECT_FALSE(never.add(f));
  FollowPhaseScore r = never.score(0.0, false, false);
  EXPECT_EQ(r.state, PhaseState::kPending);
  r = never.score(0.0, false, true);
  EXPECT_EQ(r.state, PhaseState::kFailed);
  EXPECT_NE(r.failure.find("search phase"), std::string::npos);

  const FollowScorer good = flight(-1, -1);
  r = good.score(0.0, true, true);
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.failure, "collision");
  r = good.score(1.5, false, true);
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.failure.find("keep-out"), std::string::npos);

  // The mission ends 30 s into the phase: active while it runs, failed at the end.
  FollowScorer part(followPhase());
  part.start(0.0);
  for (int i = 0; i <= 300; ++i) {
    FollowSample g;
    g.t = i / 10.0;
    g.target = Vec3(8.0 * g.t, 0, 0);
    g.vehicle = g.target + Vec3(-15.0, 0.0, 25.0);
    part.add(g);
  }
  EXPECT_FALSE(part.complete());
  EXPECT_EQ(part.score(0.0, false, false).state, PhaseState::kActive);
  EXPECT_TRUE(part.score(0.0, false, false).failure.empty());
  r = part.score(0.0, false, true);
  EXPECT_EQ(r.state, PhaseState::kFailed);
  EXPECT_NE(r.failure.find("ended 30.00 s into the 60 s phase"), std::string::npos) << r.failure;
}

// The target drives east at 8 m/s from x = 0 at t = 20 (the find) with a 30 s approach
// allowance; the vehicle hovers 100 m behind it until `enter` and then keeps inside the
// envelope (or at 20 m too high between `away_from` and `away_to`). Sampled every 0.1 s from
// t = 10 to t = 150; `last` ends the mission early.
FollowScorer approach(double enter, double last = 150.0) {
  scenario::MissionPhase p = followPhase();
  p.follow.approach_s = 30.0;
  FollowScorer s(p);
  for (int i = 100; i <= static_cast<int>(last * 10.0 + 0.5); ++i) {
    const double t = i / 10.0;
    if (i == 200) s.start(t);
    FollowSample f;
    f.t = t;
    f.target = Vec3(std::max(0.0, 8.0 * (t - 20.0)), 0.0, 0.0);
    f.vehicle = t < enter ? Vec3(-100.0, 0.0, 25.0) : f.target + Vec3(-15.0, 1.0, 24.0);
    s.add(f);
  }
  return s;
}

TEST(FollowScore, ScoringStartsAtTheFirstEntryWithinTheAllowance) {
  // In at t = 32.5, 12.5 s after the find: the 60 s are scored from there, all inside.
  const FollowScorer s = approach(32.5);
  ASSERT_TRUE(s.scoredFrom().has_value());
  EXPECT_NEAR(*s.scoredFrom(), 32.5, 1e-9);
  EXPECT_TRUE(s.complete());
  const FollowPhaseScore r = s.score(0.0, false, true);
  EXPECT_TRUE(r.success) << r.failure;
  EXPECT_NEAR(*r.start_time, 20.0, 1e-9);
  EXPECT_NEAR(r.approach_time, 12.5, 1e-9);
  EXPECT_NEAR(r.elapsed, 60.0, 1e-6);
  EXPECT_EQ(r.envelope.samples, 601u);  // t = 32.5 ... 92.5
  EXPECT_NEAR(r.envelope.inside_fraction, 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(r.envelope.longest_outside_s, 0.0);
  // Control: with no allowance the same flight is scored from the find and fails on the
  // 12.5 s outside at its start.
  scenario::MissionPhase p = followPhase();
  FollowScorer none(p);
  for (int i = 200; i <= 1500; ++i) {
    const double t = i / 10.0;
    if (i == 200) none.start(t);
    FollowSample f;
    f.t = t;
    f.target = Vec3(8.0 * (t - 20.0), 0.0, 0.0);
    f.vehicle = t < 32.5 ? Vec3(-100.0, 0.0, 25.0) : f.target + Vec3(-15.0, 1.0, 24.0);
    none.add(f);
  }
  const FollowPhaseScore n = none.score(0.0, false, true);
  EXPECT_FALSE(n.success);
  EXPECT_DOUBLE_EQ(n.approach_time, 0.0);
  EXPECT_NEAR(n.envelope.longest_outside_s, 12.5, 1e-6);
}

TEST(FollowScore, AnApproachLongerThanTheAllowanceCountsAsOutside) {
  // Negative control: in at t = 61, 41 s after the find: the allowance ends at t = 50 and the
  // 11 s after it are outside, past the 10 s rule.
  const FollowScorer late = approach(61.0);
  EXPECT_TRUE(late.failedEarly());
  FollowPhaseScore r = late.score(0.0, false, true);
  EXPECT_FALSE(r.success);
  EXPECT_NEAR(r.approach_time, 30.0, 1e-9);
  EXPECT_NEAR(r.envelope.longest_outside_s, 11.0, 1e-6);
  EXPECT_NE(r.failure.find("outside the envelope for 11.00 s"), std::string::npos) << r.failure;
  // In at t = 56, 6 s after the allowance: within the 10 s rule, and the 6 s count as outside
  // in the fraction (54 of 60 s inside).
  r = approach(56.0).score(0.0, false, true);
  EXPECT_TRUE(r.success) << r.failure;
  EXPECT_NEAR(r.approach_time, 30.0, 1e-9);
  EXPECT_NEAR(r.envelope.longest_outside_s, 6.0, 1e-6);
  EXPECT_NEAR(r.envelope.inside_fraction, 54.0 / 60.0, 1e-6);
  // The mission ends during the approach: active until then, failed at the end.
  const FollowScorer cut = approach(1000.0, 40.0);
  EXPECT_FALSE(cut.scoredFrom().has_value());
  EXPECT_EQ(cut.score(0.0, false, false).state, PhaseState::kActive);
  r = cut.score(0.0, false, true);
  EXPECT_EQ(r.state, PhaseState::kFailed);
  EXPECT_NEAR(r.approach_time, 20.0, 1e-9);
  EXPECT_EQ(r.envelope.samples, 0u);
  EXPECT_NE(r.failure.find("ended 20.00 s into the approach (30 s allowed)"), std::string::npos)
      << r.failure;
}

TEST(FollowScore, BadInputIsRefused) {
  scenario::MissionPhase p = followPhase();
  p.follow.distance_tolerance = 0.0;
  EXPECT_THROW(FollowScorer{p}, scenario::ConfigError);
  p = followPhase();
  p.duration.reset();
  EXPECT_THROW(FollowScorer{p}, scenario::ConfigError);
  p = followPhase();
  p.type = scenario::PhaseType::kTrack;
  EXPECT_THROW(FollowScorer{p}, scenario::ConfigError);
  for (double bad : {-1.0, std::numeric_limits<double>::quiet_NaN()}) {
    p = followPhase();
    p.follow.approach_s = bad;
    std::string what;
    try {
      FollowScorer{p};
    } catch (const scenario::ConfigError& e) {
      what = e.what();
    }
    EXPECT_NE(what.find("follow.approach_s"), std::string::npos) << what;
  }

  FollowScorer s(followPhase());
  s.start(0.0);
  FollowSample a;
  a.t = 1.0;
  EXPECT_TRUE(s.add(a));
  EXPECT_THROW(s.add(a), InputError);  // the same stamp again
  FollowSample b;
  b.t = 2.0;
  b.vehicle.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(s.add(b), InputError);
  b.vehicle.x() = 0.0;
  EXPECT_TRUE(s.add(b));  // nothing was kept from the refused samples
  EXPECT_EQ(s.score(0, false, false).envelope.samples, 2u);
}

}  // namespace
}  // namespace hameritt::adk
