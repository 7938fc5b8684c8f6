#include "hameritt/adk/track_score.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {

namespace {
TrackingSettings settingsOf(const scenario::TrackPhaseSpec& t) {
  TrackingSettings s;
  s.min_visible_fraction = t.min_visible_fraction;
  s.min_box_area = t.min_box_area;
  return s;
}
}  // namespace

TrackScorer::TrackScorer(const scenario::MissionPhase& phase)
    : phase_(phase),
      settings_(settingsOf(phase.track)),
      recorder_(phase.targets, settingsOf(phase.track)) {
  const std::string where = "track phase '" + phase.id + "': ";
  if (phase.type != scenario::PhaseType::kTrack || phase.targets.empty()) {
    throw scenario::ConfigError(where + "expected a track phase with targets");
  }
  if (!phase.duration || !(*phase.duration > 0.0) || !std::isfinite(*phase.duration)) {
    throw scenario::ConfigError(where + "track.duration: expected a finite number > 0");
  }
  const auto& c = phase.track;
  if (!(c.min_tracked_fraction >= 0.0 && c.min_tracked_fraction <= 1.0)) {
    throw scenario::ConfigError(where + "track.min_tracked_fraction: expected [0, 1], got " +
                                scenario::formatNumber(c.min_tracked_fraction));
  }
  if (!(c.max_reacquire_s >= 0.0 && std::isfinite(c.max_reacquire_s))) {
    throw scenario::ConfigError(where +
                                "track.max_reacquire_s: expected a finite number >= 0, got " +
                                scenario::formatNumber(c.max_reacquire_s));
  }
  lost_since_.resize(phase.targets.size());
  tracked_frames_.assign(phase.targets.size(), 0);
}

void TrackScorer::start(double t) {
  if (start_) return;
  start_ = t;
  // The find: every target counts as lost from here until its first tracked frame.
  for (auto& l : lost_since_) l = t;
}

bool TrackScorer::complete() const {
  return start_ && recorder_.frames() > 0 && last_t_ >= *start_ + *phase_.duration;
}

bool TrackScorer::addFrame(double t, const std::vector<TargetTruth>& targets) {
  if (!std::isfinite(t)) throw InputError("tracking frame: t is not finite");
  if (!start_ || t < *start_ || complete()) return false;
  if (recorder_.frames() > 0 && !(t > last_t_)) return false;
  for (const auto& g : targets) {
    const PixelBox& b = g.box;
    if (!std::isfinite(b.x) || !std::isfinite(b.y) || !(b.w >= 0.0) || !(b.h >= 0.0) ||
        !std::isfinite(b.w) || !std::isfinite(b.h) ||
        !(g.visible_fraction >= 0.0 && g.visible_fraction <= 1.0) ||
        !(g.occlusion >= 0.0 && g.occlusion <= 1.0)) {
      throw InputError("tracking frame at t = " + scenario::formatNumber(t) + ": target '" + g.id +
                       "': expected a finite box and fractions in [0, 1]");
    }
  }
  recorder_.addFrame(t, targets);
  last_t_ = t;
  for (std::size_t i = 0; i < phase_.targets.size(); ++i) {
    bool tracked = false;
    for (const auto& g : targets) {
      tracked |= g.id == phase_.targets[i] &&
                 g.visible_fraction >= settings_.min_visible_fraction &&
                 g.box.area() >= settings_.min_box_area;
    }
    if (tracked) {
      ++tracked_frames_[i];
      lost_since_[i].reset();
    } else if (!lost_since_[i]) {
      lost_since_[i] = t;
    } else if (t - *lost_since_[i] > phase_.track.max_reacquire_s) {
      exceeded_ = true;
    }
  }
  return true;
}

bool TrackScorer::addReport(double stamp, const std::vector<ReportedTrack>& tracks) {
  if (!start_) return false;
  recorder_.addReport(stamp, tracks);
  return true;
}

TrackPhaseScore TrackScorer::score(bool ended) const { return judged(ended, true); }

TrackPhaseScore TrackScorer::status() const { return judged(false, false); }

TrackPhaseScore TrackScorer::judged(bool ended, bool full) const {
  TrackPhaseScore s;
  s.phase = phase_.id;
  s.targets = phase_.targets;
  s.start_time = start_;
  s.duration = *phase_.duration;
  s.frames = recorder_.frames();
  s.reports = recorder_.reports();
  s.errors = recorder_.errors();
  // At the end, a report still waiting for its frame never got one.
  if (ended) s.errors.unmatched_stamp += recorder_.pendingReports();
  if (!start_) {
    s.state = ended ? PhaseState::kFailed : PhaseState::kPending;
    if (ended) s.failure = "the search phase did not succeed";
    return s;
  }
  s.elapsed = s.frames > 0 ? std::min(last_t_ - *start_, s.duration) : 0.0;
  if (full) {
    s.tracking = recorder_.score();
    s.tracked_fraction = s.tracking.targets.empty() ? 0.0 : 1.0;
    for (const auto& t : s.tracking.targets) {
      s.tracked_fraction = std::min(s.tracked_fraction, t.tracked_fraction);
    }
  } else {
    // The same fractions as the recorder's (tracked frames over all frames, per target).
    s.tracked_fraction = 1.0;
    for (const std::size_t n : tracked_frames_) {
      s.tracked_fraction = std::min(
          s.tracked_fraction, s.frames == 0 ? 0.0 : static_cast<double>(n) / s.frames);
    }
  }
  for (const auto& l : lost_since_) {
    if (l) s.current_break_s = std::max(s.current_break_s, last_t_ - *l);
  }
  const auto& c = phase_.track;
  char buf[200];
  if (exceeded_ || s.current_break_s > c.max_reacquire_s) {
    std::snprintf(buf, sizeof(buf), "a target was lost for more than %.1f s", c.max_reacquire_s);
    s.failure = buf;
  } else if (!complete()) {
    if (ended) s.failure = "the mission ended before the track phase's duration";
  } else if (s.tracked_fraction < c.min_tracked_fraction) {
    std::snprintf(buf, sizeof(buf), "tracked %.1f %% of the phase (expected at least %.1f %%)",
                  100.0 * s.tracked_fraction, 100.0 * c.min_tracked_fraction);
    s.failure = buf;
  }
  s.success = s.failure.empty() && complete();
  if (s.success) {
    s.state = PhaseState::kSucceeded;
  } else if (!s.failure.empty()) {
    s.state = PhaseState::kFailed;
  } else {
    s.state = PhaseState::kActive;
  }
  return s;
}

}  // namespace hameritt::adk
