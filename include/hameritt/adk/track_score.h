#pragma once
// The track phase's score, kept up frame by frame: from the phase's start (the find that ends
// the search phase) to its duration, one camera's frames (the targets' ground truth) and the
// client's reports go into a TrackingRecorder, which counts malformed reports. Success: every
// target tracked at least min_tracked_fraction of the phase's frames, every break reacquired
// within max_reacquire_s (a break still open at the end too), and the whole phase flown.
// ROS-free.

#include <optional>
#include <string>
#include <vector>

#include "hameritt/adk/follow_score.h"  // PhaseState
#include "hameritt/adk/tracking_metrics.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::adk {

struct TrackPhaseScore {
  std::string phase;                 // the phase's id
  std::vector<std::string> targets;  // the tracked targets' ids
  PhaseState state = PhaseState::kPending;
  std::optional<double> start_time;  // the find
  double duration = 0.0;             // the phase's, from mission.json
  double elapsed = 0.0;              // of the phase, up to the last frame recorded
  std::size_t frames = 0;            // camera frames of the phase
  std::size_t reports = 0;           // client reports received during the phase
  // The lowest tracked fraction over the targets, and the longest break still open now.
  double tracked_fraction = 0.0;
  double current_break_s = 0.0;
  TrackingScore tracking;    // every score, per target and over all targets
  TrackReportErrors errors;  // malformed reports, counted
  bool success = false;
  std::string failure;  // why not, "" on success (and while the phase is pending or active)
};

class TrackScorer {
 public:
  // `phase` must be a track phase with targets and a duration. Throws scenario::ConfigError
  // naming "track.<field>" for bad criteria or duration.
  explicit TrackScorer(const scenario::MissionPhase& phase);

  // The search phase succeeded at t: the track phase begins. Later calls are ignored.
  void start(double t);
  bool started() const { return start_.has_value(); }
  // A camera frame's ground truth of the targets at sim time t (targets not in the image are
  // absent). Before the start, after the phase's end or not after the previous frame: ignored
  // (false). InputError for a non-finite t or truth outside its ranges.
  bool addFrame(double t, const std::vector<TargetTruth>& targets);
  // A client report for the frame stamped `stamp` (see TrackingRecorder::addReport); before
  // the start it is ignored (false).
  bool addReport(double stamp, const std::vector<ReportedTrack>& tracks);
  // The phase's duration has been recorded (a frame at or after start + duration).
  bool complete() const;
  // The phase can no longer succeed: a target has been lost longer than max_reacquire_s.
  bool failedEarly() const { return exceeded_; }

  // The score so far. `ended`: the mission is over, so a phase not complete has failed.
  TrackPhaseScore score(bool ended) const;
  // The live status while the phase runs: score(false) without `tracking` (the TrackEval
  // scores, which walk every frame so far), from counters kept frame by frame; every other
  // field is the same. The ADK publishes it at its status rate.
  TrackPhaseScore status() const;

  const scenario::MissionPhase& phase() const { return phase_; }

 private:
  scenario::MissionPhase phase_;
  TrackingSettings settings_;
  TrackingRecorder recorder_;
  std::optional<double> start_;
  double last_t_ = 0.0;
  std::vector<std::optional<double>> lost_since_;  // per target: the first untracked frame
  bool exceeded_ = false;
  // Per target: the frames in which it was tracked (as the recorder counts them: a frame lists
  // each target once).
  std::vector<std::size_t> tracked_frames_;
  TrackPhaseScore judged(bool ended, bool full) const;
};

}  // namespace hameritt::adk
