#include "hameritt/adk/follow_score.h"

#include <cmath>
#include <cstdio>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {

const char* toString(PhaseState s) {
  switch (s) {
    case PhaseState::kPending:
      return "pending";
    case PhaseState::kActive:
      return "active";
    case PhaseState::kSucceeded:
      return "succeeded";
    case PhaseState::kFailed:
      return "failed";
  }
  return "unknown";
}

namespace {
FollowEnvelope envelopeOf(const scenario::FollowPhaseSpec& f) {
  FollowEnvelope e;
  e.distance = f.distance;
  e.distance_tolerance = f.distance_tolerance;
  e.height = f.height;
  e.height_tolerance = f.height_tolerance;
  return e;
}
}  // namespace

FollowScorer::FollowScorer(const scenario::MissionPhase& phase)
    : phase_(phase), envelope_(envelopeOf(phase.follow)), accumulator_(FollowEnvelope()) {
  const std::string where = "follow phase '" + phase.id + "': ";
  if (phase.type != scenario::PhaseType::kFollow || phase.targets.size() != 1) {
    throw scenario::ConfigError(where + "expected a follow phase with one target");
  }
  if (!phase.duration || !(*phase.duration > 0.0) || !std::isfinite(*phase.duration)) {
    throw scenario::ConfigError(where + "follow.duration: expected a finite number > 0");
  }
  try {
    envelope_.validate();
    accumulator_ = FollowAccumulator(envelope_);
  } catch (const scenario::ConfigError& e) {
    throw scenario::ConfigError(where + "follow." + e.what());
  }
  criteria_.min_inside_fraction = phase.follow.min_inside_fraction;
  criteria_.max_outside_s = phase.follow.max_outside_s;
  if (!(phase.follow.approach_s >= 0.0 && std::isfinite(phase.follow.approach_s))) {
    throw scenario::ConfigError(where + "follow.approach_s: expected a finite number >= 0, got " +
                                scenario::formatNumber(phase.follow.approach_s));
  }
  if (!(criteria_.min_inside_fraction >= 0.0 && criteria_.min_inside_fraction <= 1.0)) {
    throw scenario::ConfigError(where + "follow.min_inside_fraction: expected [0, 1], got " +
                                scenario::formatNumber(criteria_.min_inside_fraction));
  }
  if (!(criteria_.max_outside_s >= 0.0 && std::isfinite(criteria_.max_outside_s))) {
    throw scenario::ConfigError(where +
                                "follow.max_outside_s: expected a finite number >= 0, got " +
                                scenario::formatNumber(criteria_.max_outside_s));
  }
}

void FollowScorer::start(double t) {
  if (!start_) start_ = t;
}

bool FollowScorer::complete() const {
  return scored_from_ && *last_t_ >= *scored_from_ + *phase_.duration;
}

bool FollowScorer::add(const FollowSample& s) {
  if (!start_ || s.t < *start_ || complete()) return false;
  if (!std::isfinite(s.t) || (last_t_ && !(s.t > *last_t_))) {
    throw InputError("follow sample: t = " + scenario::formatNumber(s.t) +
                     " does not come after the previous sample");
  }
  if (!s.vehicle.allFinite() || !s.target.allFinite() || !std::isfinite(s.target_yaw)) {
    throw InputError("follow sample at t = " + scenario::formatNumber(s.t) +
                     ": expected finite positions and yaw");
  }
  last_t_ = s.t;
  const bool inside = insideEnvelope(s, envelope_);
  if (!scored_from_) {
    // The approach: nothing is scored until the first entry or the end of the allowance.
    if (!inside && s.t < *start_ + phase_.follow.approach_s) return true;
    scored_from_ = s.t;
  }
  accumulator_.add(s);
  if (inside) {
    outside_since_.reset();
  } else if (!outside_since_) {
    outside_since_ = s.t;
  }
  if (outside_since_ && s.t - *outside_since_ > criteria_.max_outside_s) exceeded_ = true;
  return true;
}

bool FollowScorer::failedEarly() const { return exceeded_; }

FollowPhaseScore FollowScorer::score(double koz_seconds, bool collision, bool ended) const {
  FollowPhaseScore r;
  r.phase = phase_.id;
  r.target = phase_.targets.front();
  r.duration = *phase_.duration;
  r.start_time = start_;
  r.koz_seconds = koz_seconds;
  r.collision = collision;
  r.envelope = accumulator_.result();
  if (scored_from_) {
    r.approach_time = *scored_from_ - *start_;
    r.elapsed = *last_t_ - *scored_from_;
  } else if (start_ && last_t_) {
    r.approach_time = *last_t_ - *start_;
  }
  r.outside = outside_since_.has_value();
  if (outside_since_) r.current_outside_s = *last_t_ - *outside_since_;
  char buf[160];
  if (!start_) {
    r.failure = "the search phase did not find the target";
  } else if (collision) {
    r.failure = "collision";
  } else if (koz_seconds > 0.0) {
    std::snprintf(buf, sizeof(buf), "%.2f s inside keep-out zones during the phase", koz_seconds);
    r.failure = buf;
  } else if (r.envelope.longest_outside_s > criteria_.max_outside_s) {
    std::snprintf(buf, sizeof(buf), "outside the envelope for %.2f s at a stretch (at most %g s)",
                  r.envelope.longest_outside_s, criteria_.max_outside_s);
    r.failure = buf;
  } else if (!scored_from_) {
    std::snprintf(buf, sizeof(buf), "the mission ended %.2f s into the approach (%g s allowed)",
                  r.approach_time, phase_.follow.approach_s);
    r.failure = buf;
  } else if (!complete()) {
    std::snprintf(buf, sizeof(buf), "the mission ended %.2f s into the %g s phase", r.elapsed,
                  r.duration);
    r.failure = buf;
  } else if (r.envelope.inside_fraction < criteria_.min_inside_fraction) {
    std::snprintf(buf, sizeof(buf), "inside the envelope %.1f %% of the phase (at least %g %%)",
                  100.0 * r.envelope.inside_fraction, 100.0 * criteria_.min_inside_fraction);
    r.failure = buf;
  }
  const bool decided = ended || complete() || failedEarly() || collision || koz_seconds > 0.0;
  if (!start_) {
    r.state = ended ? PhaseState::kFailed : PhaseState::kPending;
  } else if (!decided) {
    r.state = PhaseState::kActive;
    r.failure.clear();
  } else {
    r.success = r.failure.empty();
    r.state = r.success ? PhaseState::kSucceeded : PhaseState::kFailed;
  }
  if (r.state == PhaseState::kPending) r.failure.clear();
  return r;
}

}  // namespace hameritt::adk
