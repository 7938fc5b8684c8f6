// TrackScorer: the track phase from the find to its duration, frame by frame. Success needs the
// tracked fraction and every loss reacquired in time; the negative controls (a loss 1 s too
// long, too small a fraction, an early end, no find) fail, and malformed reports are counted.
#include "hameritt/adk/track_score.h"

#include <gtest/gtest.h>

#include <cmath>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {
namespace {

scenario::MissionPhase trackPhase(double duration, std::vector<std::string> targets = {"car_1"}) {
  scenario::MissionPhase p;
  p.id = "track_1";
  p.type = scenario::PhaseType::kTrack;
  p.targets = std::move(targets);
  p.duration = duration;
  return p;  // criteria: the defaults 0.5, 400 px, 70 %, 10 s
}

TargetTruth seen(const std::string& id) { return {id, PixelBox{100, 100, 40, 30}, 0.9, 0.1}; }
TargetTruth hidden(const std::string& id) { return {id, PixelBox{100, 100, 40, 30}, 0.2, 0.8}; }

// Frames at 10 Hz from `from` to `to` (inclusive), the target lost in [lost_from, lost_to).
void feed(TrackScorer& s, double from, double to, double lost_from = -1, double lost_to = -1) {
  for (int k = 0; from + 0.1 * k <= to + 1e-9; ++k) {
    const double t = std::round((from + 0.1 * k) * 10.0) / 10.0;
    const bool lost = t >= lost_from - 1e-9 && t < lost_to - 1e-9;
    s.addFrame(t, {lost ? hidden("car_1") : seen("car_1")});
  }
}

TEST(TrackScorer, TrackedThroughoutSucceeds) {
  TrackScorer s(trackPhase(20.0));
  EXPECT_FALSE(s.addFrame(1.0, {seen("car_1")}));  // before the find: ignored
  EXPECT_EQ(s.score(false).state, PhaseState::kPending);
  s.start(5.0);
  feed(s, 5.0, 24.9);
  EXPECT_FALSE(s.complete());
  EXPECT_EQ(s.score(false).state, PhaseState::kActive);
  feed(s, 25.0, 26.0);  // the frame at 25 s completes it; later ones are ignored
  EXPECT_TRUE(s.complete());
  const TrackPhaseScore r = s.score(true);
  EXPECT_TRUE(r.success) << r.failure;
  EXPECT_EQ(r.state, PhaseState::kSucceeded);
  EXPECT_EQ(r.frames, 201u);
  EXPECT_DOUBLE_EQ(r.tracked_fraction, 1.0);
  EXPECT_DOUBLE_EQ(r.elapsed, 20.0);
  ASSERT_EQ(r.tracking.targets.size(), 1u);
  EXPECT_EQ(r.tracking.targets[0].breaks, 0u);
}

TEST(TrackScorer, ALossLongerThanTheReacquireLimitFails) {
  // 9 s lost: reacquired in time, tracked 31 of 40 s: success.
  TrackScorer ok(trackPhase(40.0));
  ok.start(0.0);
  feed(ok, 0.0, 40.0, 10.0, 19.0);
  const TrackPhaseScore a = ok.score(true);
  EXPECT_TRUE(a.success) << a.failure;
  EXPECT_EQ(a.tracking.targets[0].breaks, 1u);
  EXPECT_NEAR(a.tracking.targets[0].reacquire_max_s, 9.0, 1e-9);
  // Negative control: 11 s lost fails as soon as the loss passes 10 s, and stays failed.
  TrackScorer bad(trackPhase(40.0));
  bad.start(0.0);
  feed(bad, 0.0, 20.0, 10.0, 21.1);
  EXPECT_FALSE(bad.failedEarly());  // lost exactly 10 s at t = 20 s: not yet too long
  feed(bad, 20.1, 20.1, 10.0, 21.1);
  EXPECT_TRUE(bad.failedEarly());
  feed(bad, 20.2, 40.0, 10.0, 21.1);
  const TrackPhaseScore b = bad.score(true);
  EXPECT_FALSE(b.success);
  EXPECT_EQ(b.state, PhaseState::kFailed);
  EXPECT_NE(b.failure.find("lost for more than 10.0 s"), std::string::npos) << b.failure;
}

TEST(TrackScorer, TooSmallATrackedFractionFails) {
  // Lost 2 s in every 5 s: 60 % tracked, every loss reacquired in 2 s.
  TrackScorer s(trackPhase(30.0));
  s.start(0.0);
  for (int k = 0; k < 6; ++k) feed(s, 5.0 * k, 5.0 * k + 4.9, 5.0 * k + 3.0, 5.0 * k + 5.0);
  feed(s, 30.0, 30.0);
  const TrackPhaseScore r = s.score(true);
  EXPECT_FALSE(r.success);
  EXPECT_FALSE(s.failedEarly());
  EXPECT_NEAR(r.tracked_fraction, 0.6, 0.01);
  EXPECT_NE(r.failure.find("expected at least 70.0 %"), std::string::npos) << r.failure;
  EXPECT_EQ(r.tracking.targets[0].breaks, 6u);
}

TEST(TrackScorer, EarlyEndNoFindAndTheLowestTargetDecide) {
  TrackScorer early(trackPhase(20.0));
  early.start(0.0);
  feed(early, 0.0, 10.0);
  EXPECT_EQ(early.score(false).state, PhaseState::kActive);
  EXPECT_EQ(early.score(true).state, PhaseState::kFailed);
  EXPECT_NE(early.score(true).failure.find("before the track phase's duration"), std::string::npos);
  TrackScorer never(trackPhase(20.0));
  EXPECT_EQ(never.score(true).failure, "the search phase did not succeed");
  // Two targets: the second never in view fails the phase (its loss runs from the find).
  TrackScorer two(trackPhase(20.0, {"car_1", "car_2"}));
  two.start(0.0);
  feed(two, 0.0, 20.0);
  const TrackPhaseScore r = two.score(true);
  EXPECT_FALSE(r.success);
  EXPECT_TRUE(two.failedEarly());
  EXPECT_DOUBLE_EQ(r.tracked_fraction, 0.0);
  EXPECT_EQ(r.tracking.targets.size(), 2u);
}

// The live status (published at the ADK's status rate) keeps counters instead of re-scoring
// every frame so far: at every frame of a two-target phase with losses, boxes under the minimum
// area, reports and a failure, it equals score(false) in every field but the TrackEval scores it
// leaves out.
TEST(TrackScorer, LiveStatusEqualsTheFullScore) {
  TrackScorer s(trackPhase(30.0, {"car_1", "car_2"}));
  EXPECT_EQ(s.status().state, PhaseState::kPending);
  s.start(2.0);
  int frames = 0, differing_fractions = 0;
  for (int k = 0; k <= 330; ++k) {
    const double t = 2.0 + 0.1 * k;
    std::vector<TargetTruth> in_view;
    if (k % 7 != 3) in_view.push_back(k % 11 == 0 ? hidden("car_1") : seen("car_1"));
    if (k > 40 && k % 5 != 0) {
      TargetTruth small = seen("car_2");
      small.box.w = k % 3 == 0 ? 10.0 : 40.0;  // 300 px: under the 400 px minimum
      in_view.push_back(small);
    }
    s.addFrame(t, in_view);
    if (k % 4 == 0) s.addReport(t, {{"car_1", PixelBox{100, 100, 40, 30}}});
    const TrackPhaseScore full = s.score(false), live = s.status();
    SCOPED_TRACE("frame " + std::to_string(k));
    EXPECT_EQ(live.state, full.state);
    EXPECT_EQ(live.failure, full.failure);
    EXPECT_EQ(live.tracked_fraction, full.tracked_fraction);
    EXPECT_EQ(live.current_break_s, full.current_break_s);
    EXPECT_EQ(live.frames, full.frames);
    EXPECT_EQ(live.reports, full.reports);
    EXPECT_EQ(live.elapsed, full.elapsed);
    EXPECT_EQ(live.errors.total(), full.errors.total());
    EXPECT_EQ(live.start_time, full.start_time);
    EXPECT_TRUE(live.tracking.targets.empty());
    ASSERT_EQ(full.tracking.targets.size(), 2u);
    if (full.tracking.targets[0].tracked_fraction != full.tracking.targets[1].tracked_fraction) {
      ++differing_fractions;
    }
    ++frames;
  }
  EXPECT_GT(differing_fractions, 100);  // the minimum over the targets was exercised
  EXPECT_EQ(s.status().state, PhaseState::kFailed);  // car_2 lost for the first 4 s, and more
  EXPECT_GT(frames, 300);
}

TEST(TrackScorer, MalformedReportsAreCountedAndBadInputRejected) {
  TrackScorer s(trackPhase(20.0));
  EXPECT_FALSE(s.addReport(0.5, {{"car_1", PixelBox{100, 100, 40, 30}}}));  // before the find
  s.start(0.0);
  feed(s, 0.0, 1.0);
  EXPECT_TRUE(s.addReport(0.5, {{"car_1", PixelBox{100, 100, 40, 30}},
                                {"car_7", PixelBox{0, 0, 5, 5}},
                                {"car_1", PixelBox{NAN, 0, 5, 5}}}));
  s.addReport(0.55, {});  // no such frame
  s.addReport(0.4, {});   // out of order
  s.addReport(5.0, {});   // ahead of every frame: waits, unmatched only at the end
  EXPECT_EQ(s.score(false).errors.unmatched_stamp, 1u);
  const TrackPhaseScore r = s.score(true);
  EXPECT_EQ(r.reports, 4u);
  EXPECT_EQ(r.errors.unknown_id, 1u);
  EXPECT_EQ(r.errors.bad_box, 1u);
  EXPECT_EQ(r.errors.unmatched_stamp, 2u);
  EXPECT_EQ(r.errors.out_of_order, 1u);
  EXPECT_EQ(r.errors.total(), 5u);
  EXPECT_THROW(s.addFrame(NAN, {}), InputError);
  EXPECT_THROW(s.addFrame(2.0, {{"car_1", PixelBox{0, 0, -1, 5}, 0.9, 0.1}}), InputError);
  EXPECT_THROW(TrackScorer(trackPhase(0.0)), scenario::ConfigError);
  scenario::MissionPhase p = trackPhase(20.0);
  p.track.min_tracked_fraction = 1.5;
  EXPECT_THROW(TrackScorer{p}, scenario::ConfigError);
  p = trackPhase(20.0, {});
  EXPECT_THROW(TrackScorer{p}, scenario::ConfigError);
}

}  // namespace
}  // namespace hameritt::adk
