#include "hameritt/adk/metrics.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/scenario_io.h"

namespace hameritt::adk {

using geometry::Vec3;

void EnergyModel::validate() const {
  auto positive = [](double v, const char* name) {
    if (!(v > 0.0) || !std::isfinite(v)) {
      throw scenario::ConfigError(std::string("energy.") + name +
                                  ": expected a finite number > 0, got " +
                                  scenario::formatNumber(v));
    }
  };
  positive(mass, "mass");
  positive(gravity, "gravity");
  positive(air_density, "air_density");
  positive(rotor_radius, "rotor_radius");
  if (rotors < 1) {
    throw scenario::ConfigError("energy.rotors: expected at least 1, got " +
                                std::to_string(rotors));
  }
  if (!(figure_of_merit > 0.0 && figure_of_merit <= 1.0)) {
    throw scenario::ConfigError("energy.figure_of_merit: expected a number in (0, 1], got " +
                                scenario::formatNumber(figure_of_merit));
  }
  if (!(drag_area >= 0.0) || !std::isfinite(drag_area)) {
    throw scenario::ConfigError("energy.drag_area: expected a finite number >= 0, got " +
                                scenario::formatNumber(drag_area));
  }
  if (!(max_thrust_to_weight >= 1.0) || !std::isfinite(max_thrust_to_weight)) {
    throw scenario::ConfigError("energy.max_thrust_to_weight: expected a finite number >= 1, got " +
                                scenario::formatNumber(max_thrust_to_weight));
  }
  if (!(airborne_altitude >= 0.0) || !(moving_speed >= 0.0)) {
    throw scenario::ConfigError("energy.airborne_altitude, energy.moving_speed: expected >= 0");
  }
}

double EnergyModel::power(const Vec3& v, const Vec3& a) const {
  const double thrust =
      std::min(mass * (a + Vec3(0, 0, gravity)).norm(), max_thrust_to_weight * mass * gravity);
  const double disk = rotors * geometry::kPi * rotor_radius * rotor_radius;
  const double induced = std::pow(thrust, 1.5) / std::sqrt(2.0 * air_density * disk);
  const double speed = v.norm();
  return induced / figure_of_merit + 0.5 * air_density * drag_area * speed * speed * speed;
}

double EnergyModel::hoverPower() const { return power(Vec3::Zero(), Vec3::Zero()); }

bool EnergyModel::airborne(const Vec3& p, const Vec3& v) const {
  return p.z() > airborne_altitude || v.norm() > moving_speed;
}

const char* toString(Outcome o) {
  switch (o) {
    case Outcome::kSuccess:
      return "success";
    case Outcome::kTimeout:
      return "timeout";
    case Outcome::kCrashed:
      return "crashed";
    case Outcome::kAborted:
      return "aborted";
    case Outcome::kEnded:
      return "ended";
    case Outcome::kFailed:
      return "failed";
  }
  return "?";
}

void ObjectiveSettings::validate() const {
  if (!(track_fraction > 0.0 && track_fraction <= 1.0)) {
    throw scenario::ConfigError("objective.track_fraction: expected a number in (0, 1], got " +
                                scenario::formatNumber(track_fraction));
  }
}

MetricsAccumulator::MetricsAccumulator(const scenario::Mission& mission,
                                       const ObjectiveSettings& objective,
                                       const EnergyModel& energy)
    : scenario_id_(mission.scenario_id),
      scenario_class_(scenario::toString(mission.cls)),
      objective_type_(mission.objective.type),
      objective_(objective),
      energy_(energy),
      track_(mission.objective.type == "track") {
  objective_.validate();
  energy_.validate();
  for (const auto& t : mission.objective.targets) {
    TargetMetrics m;
    m.id = t.id;
    targets_.push_back(m);
  }
  in_view_.resize(targets_.size());
}

TargetMetrics* MetricsAccumulator::target(const std::string& id) {
  for (auto& t : targets_) {
    if (t.id == id) return &t;
  }
  return nullptr;
}

bool MetricsAccumulator::addState(double t, const Vec3& p, const Vec3& v) {
  if (!std::isfinite(t) || !p.allFinite() || !v.allFinite()) {
    throw InputError("state at t = " + scenario::formatNumber(t) +
                     ": expected finite time, position and velocity");
  }
  if (have_state_ && !(t > last_t_)) return false;
  if (have_state_) {
    const double dt = t - last_t_;
    flight_.path_length += (p - last_p_).norm();
    const bool airborne = last_airborne_ || energy_.airborne(p, v);
    if (airborne) {
      flight_.flight_time += dt;
      flight_.energy += energy_.power(0.5 * (v + last_v_), (v - last_v_) / dt) * dt;
    }
  }
  flight_.max_speed = std::max(flight_.max_speed, v.norm());
  have_state_ = true;
  last_t_ = t;
  last_p_ = p;
  last_v_ = v;
  last_airborne_ = energy_.airborne(p, v);
  return true;
}

void MetricsAccumulator::addVerdict(double stamp, const DetectionVerdict& verdict) {
  ++counts_.total;
  switch (verdict.verdict) {
    case Verdict::kTarget: {
      ++counts_.correct;
      TargetMetrics* m = target(verdict.entity_id);
      if (m && (!m->first_correct_time || stamp < *m->first_correct_time)) {
        m->first_correct_time = stamp;
      }
      if (m && !objective_.found_by_sighting) m->found = true;
      break;
    }
    case Verdict::kConfuser:
      ++counts_.false_on_confusers;
      break;
    case Verdict::kOther:
      ++counts_.false_on_other_entities;
      break;
    case Verdict::kNone:
      ++counts_.false_on_nothing;
      break;
  }
}

void MetricsAccumulator::addSighting(const std::string& entity_id, double stamp,
                                     double frame_period) {
  for (std::size_t i = 0; i < targets_.size(); ++i) {
    TargetMetrics& m = targets_[i];
    if (m.id != entity_id) continue;
    if (!m.first_seen_time || stamp < *m.first_seen_time) m.first_seen_time = stamp;
    if (objective_.found_by_sighting) m.found = true;
    in_view_[i].add(stamp, stamp + std::max(0.0, frame_period));
    m.in_view_time = in_view_[i].measure();
  }
}

bool MetricsAccumulator::objectiveMet(double t) const {
  if (targets_.empty()) return false;
  for (const auto& m : targets_) {
    if (track_) {
      if (!(t > 0.0) || m.in_view_time < objective_.track_fraction * t) return false;
    } else if (!m.found) {
      return false;
    }
  }
  return true;
}

MissionMetrics MetricsAccumulator::finish(Outcome outcome, const std::string& reason,
                                          double start_time, double end_time, double time_limit,
                                          const std::string& mode, const ConstraintMonitor& monitor,
                                          const CoverageGrid& coverage) const {
  MissionMetrics m;
  m.scenario_id = scenario_id_;
  m.scenario_class = scenario_class_;
  m.objective_type = objective_type_;
  m.mode = mode;
  m.outcome = outcome;
  m.reason = reason;
  m.start_time = start_time;
  m.end_time = end_time;
  m.time_limit = time_limit;
  m.targets = targets_;
  bool all = !targets_.empty();
  double last_found = 0.0;
  for (const auto& t : targets_) {
    if (t.first_correct_time &&
        (!m.time_to_first_correct || *t.first_correct_time < *m.time_to_first_correct)) {
      m.time_to_first_correct = *t.first_correct_time;
    }
    const std::optional<double> found_at =
        objective_.found_by_sighting ? t.first_seen_time : t.first_correct_time;
    if (!t.found || !found_at) {
      all = false;
    } else {
      last_found = std::max(last_found, *found_at);
    }
  }
  if (all && !track_) m.time_to_all_found = last_found;
  m.detections = counts_;
  m.violations = monitor.violations();
  m.violation_duration = monitor.violationDuration();
  m.flight = flight_;
  m.energy_model = energy_;
  m.coverage_cell_size = coverage.cellSize();
  m.coverage = coverage.coverage();
  m.aoi_time = monitor.areas();
  m.prior_weighted_coverage = coverage.priorWeightedCoverage();
  return m;
}

namespace {

// The "track" block: the phase, its state and every tracking score.
nlohmann::ordered_json trackJson(const TrackPhaseScore& t) {
  using nlohmann::ordered_json;
  ordered_json o;
  o["phase"] = t.phase;
  o["targets"] = t.targets;
  o["state"] = toString(t.state);
  o["success"] = t.success;
  o["failure"] = t.failure;
  o["start_time"] = t.start_time ? ordered_json(*t.start_time) : ordered_json(nullptr);
  o["duration"] = t.duration;
  o["elapsed"] = t.elapsed;
  o["frames"] = t.frames;
  o["reports"] = t.reports;
  o["tracked_fraction"] = t.tracked_fraction;
  ordered_json errors;
  errors["unknown_id"] = t.errors.unknown_id;
  errors["bad_box"] = t.errors.bad_box;
  errors["duplicate_id"] = t.errors.duplicate_id;
  errors["out_of_order"] = t.errors.out_of_order;
  errors["unmatched_stamp"] = t.errors.unmatched_stamp;
  errors["total"] = t.errors.total();
  o["report_errors"] = errors;
  ordered_json targets = ordered_json::array();
  for (const auto& s : t.tracking.targets) {
    ordered_json g;
    g["id"] = s.id;
    g["frames"] = s.frames;
    g["in_view_frames"] = s.in_view_frames;
    g["tracked_frames"] = s.tracked_frames;
    g["tracked_fraction"] = s.tracked_fraction;
    ordered_json levels;
    for (std::size_t l = 0; l < kOcclusionLevels; ++l) {
      const auto& lv = s.by_occlusion[l];
      levels[occlusionLevelName(static_cast<OcclusionLevel>(l))] = {
          {"frames", lv.frames},
          {"tracked_fraction", lv.tracked_fraction},
          {"held_fraction", lv.held_fraction}};
    }
    g["by_occlusion"] = levels;
    g["scored_frames"] = s.scored_frames;
    g["precision"] = s.precision;
    g["success"] = s.success;
    g["breaks"] = s.breaks;
    g["reacquired"] = s.reacquired;
    g["reacquire_median"] = s.reacquire_median_s;
    g["reacquire_max"] = s.reacquire_max_s;
    g["open_break"] = s.open_break_s;
    g["id_switches"] = s.id_switches;
    targets.push_back(g);
  }
  o["per_target"] = targets;
  // The multi-object scores, meaningful with several targets (computed for one too).
  const auto& c = t.tracking.clear;
  o["clear_mot"] = {{"mota", c.mota},
                    {"motp", c.motp},
                    {"tp", c.tp},
                    {"fn", c.fn},
                    {"fp", c.fp},
                    {"id_switches", c.id_switches},
                    {"mostly_tracked", c.mostly_tracked},
                    {"partly_tracked", c.partly_tracked},
                    {"mostly_lost", c.mostly_lost},
                    {"fragmentations", c.fragmentations}};
  const auto& id = t.tracking.identity;
  o["identity"] = {{"idf1", id.idf1}, {"idr", id.idr},   {"idp", id.idp},
                   {"idtp", id.idtp}, {"idfn", id.idfn}, {"idfp", id.idfp}};
  const auto& h = t.tracking.hota;
  o["hota"] = {{"hota", h.mean_hota},     {"det_a", h.mean_det_a},   {"ass_a", h.mean_ass_a},
               {"det_re", h.mean_det_re}, {"det_pr", h.mean_det_pr}, {"ass_re", h.mean_ass_re},
               {"ass_pr", h.mean_ass_pr}, {"loc_a", h.mean_loc_a}};
  return o;
}

}  // namespace

std::string metricsJson(const MissionMetrics& m) {
  using nlohmann::ordered_json;
  auto opt = [](const std::optional<double>& v) -> ordered_json {
    return v ? ordered_json(*v) : ordered_json(nullptr);
  };
  ordered_json j;
  j["schema"] = "hameritt/metrics";
  j["schema_version"] = 1;
  j["scenario_id"] = m.scenario_id;
  j["class"] = m.scenario_class;
  j["objective_type"] = m.objective_type;
  j["mode"] = m.mode;
  j["outcome"] = toString(m.outcome);
  j["reason"] = m.reason;
  j["start_time"] = m.start_time;
  j["end_time"] = m.end_time;
  j["time_limit"] = m.time_limit;
  ordered_json targets = ordered_json::array();
  for (const auto& t : m.targets) {
    ordered_json o;
    o["id"] = t.id;
    o["found"] = t.found;
    o["first_correct_time"] = opt(t.first_correct_time);
    o["first_seen_time"] = opt(t.first_seen_time);
    o["in_view_time"] = t.in_view_time;
    targets.push_back(o);
  }
  j["targets"] = targets;
  j["time_to_first_correct_detection"] = opt(m.time_to_first_correct);
  j["time_to_all_targets_found"] = opt(m.time_to_all_found);
  ordered_json d;
  d["total"] = m.detections.total;
  d["correct"] = m.detections.correct;
  d["false_on_confusers"] = m.detections.false_on_confusers;
  d["false_on_other_entities"] = m.detections.false_on_other_entities;
  d["false_on_nothing"] = m.detections.false_on_nothing;
  j["detections"] = d;
  ordered_json k;
  k["violation_count"] = m.violations.size();
  k["violation_duration"] = m.violation_duration;
  ordered_json list = ordered_json::array();
  for (const auto& v : m.violations) {
    ordered_json o;
    o["zone"] = v.zone_id;
    o["purpose"] = v.purpose;
    o["t_enter"] = v.t_enter;
    o["t_exit"] = v.t_exit;
    o["duration"] = v.duration();
    o["ongoing"] = v.ongoing;
    list.push_back(o);
  }
  k["violations"] = list;
  j["keep_out_zones"] = k;
  ordered_json f;
  f["path_length"] = m.flight.path_length;
  f["flight_time"] = m.flight.flight_time;
  f["max_speed"] = m.flight.max_speed;
  f["energy"] = m.flight.energy;
  f["mean_power"] = m.flight.flight_time > 0 ? m.flight.energy / m.flight.flight_time : 0.0;
  ordered_json em;
  em["model"] = "momentum_theory";
  em["mass"] = m.energy_model.mass;
  em["rotors"] = m.energy_model.rotors;
  em["rotor_radius"] = m.energy_model.rotor_radius;
  em["figure_of_merit"] = m.energy_model.figure_of_merit;
  em["drag_area"] = m.energy_model.drag_area;
  em["max_thrust_to_weight"] = m.energy_model.max_thrust_to_weight;
  em["air_density"] = m.energy_model.air_density;
  em["hover_power"] = m.energy_model.hoverPower();
  f["energy_model"] = em;
  j["flight"] = f;
  ordered_json c;
  c["cell_size"] = m.coverage_cell_size;
  c["prior_weighted"] = m.prior_weighted_coverage;
  ordered_json areas = ordered_json::array();
  for (std::size_t i = 0; i < m.coverage.size(); ++i) {
    const AoiCoverage& a = m.coverage[i];
    ordered_json o;
    o["id"] = a.aoi_id;
    o["cells"] = a.cells;
    o["covered"] = a.covered;
    o["fraction"] = a.fraction;
    o["prior_weighted"] = a.has_prior ? ordered_json(a.prior_weighted) : ordered_json(nullptr);
    if (i < m.aoi_time.size()) {
      o["time_inside"] = m.aoi_time[i].time_inside;
      o["time_inside_active"] = m.aoi_time[i].time_inside_active;
      o["entries"] = m.aoi_time[i].entries;
    }
    areas.push_back(o);
  }
  c["areas_of_interest"] = areas;
  j["coverage"] = c;
  if (m.avoid) {
    const AvoidScore& a = *m.avoid;
    auto finiteOrNull = [](double v) -> ordered_json {
      return std::isfinite(v) ? ordered_json(v) : ordered_json(nullptr);
    };
    ordered_json o;
    o["success"] = a.success;
    o["failure"] = a.failure;
    o["reach_time"] = opt(a.reach_time);
    o["goal_distance"] = a.goal_distance_m;
    o["path_length"] = a.path_length_m;
    o["shortest_path"] = a.shortest_path_m;
    o["spl"] = a.spl;
    o["min_separation"] = finiteOrNull(a.separation.min_distance_m);
    o["closest_aircraft"] = a.separation.closest_aircraft;
    o["min_separation_time"] = a.separation.min_distance_t;
    o["seconds_below_minimum"] = a.separation.seconds_below_minimum;
    o["separation_losses"] = a.separation.losses;
    o["min_time_to_collision"] = finiteOrNull(a.separation.min_time_to_collision_s);
    o["time_to_collision_aircraft"] = a.separation.time_to_collision_aircraft;
    o["contact"] = a.separation.contact;
    o["koz_seconds"] = a.koz_seconds;
    j["avoid"] = o;
  }
  if (m.follow) {
    const FollowPhaseScore& f = *m.follow;
    ordered_json o;
    o["phase"] = f.phase;
    o["target"] = f.target;
    o["state"] = toString(f.state);
    o["success"] = f.success;
    o["failure"] = f.failure;
    o["start_time"] = opt(f.start_time);
    o["approach_time"] = f.approach_time;
    o["duration"] = f.duration;
    o["elapsed"] = f.elapsed;
    o["samples"] = f.envelope.samples;
    o["inside_fraction"] = f.envelope.inside_fraction;
    o["longest_outside"] = f.envelope.longest_outside_s;
    o["rms_distance_error"] = f.envelope.rms_distance_error_m;
    o["p95_distance_error"] = f.envelope.p95_distance_error_m;
    o["rms_height_error"] = f.envelope.rms_height_error_m;
    o["line_of_sight_fraction"] = f.envelope.line_of_sight_fraction;
    o["koz_seconds"] = f.koz_seconds;
    o["collision"] = f.collision;
    j["follow"] = o;
  }
  if (m.track) j["track"] = trackJson(*m.track);
  return j.dump(2) + "\n";
}

void writeMetricsJson(const MissionMetrics& m, const std::string& path) {
  scenario::writeFileAtomic(path, metricsJson(m));
}

const char* toString(MissionState s) {
  switch (s) {
    case MissionState::kWaiting:
      return "waiting";
    case MissionState::kRunning:
      return "running";
    case MissionState::kSucceeded:
      return "succeeded";
    case MissionState::kTimeout:
      return "timeout";
    case MissionState::kCrashed:
      return "crashed";
    case MissionState::kAborted:
      return "aborted";
    case MissionState::kEnded:
      return "ended";
    case MissionState::kFailed:
      return "failed";
  }
  return "?";
}

Outcome outcomeOf(MissionState s) {
  switch (s) {
    case MissionState::kSucceeded:
      return Outcome::kSuccess;
    case MissionState::kTimeout:
      return Outcome::kTimeout;
    case MissionState::kCrashed:
      return Outcome::kCrashed;
    case MissionState::kEnded:
      return Outcome::kEnded;
    case MissionState::kFailed:
      return Outcome::kFailed;
    default:
      return Outcome::kAborted;
  }
}

MissionLifecycle::MissionLifecycle(double time_limit) : time_limit_(time_limit) {
  if (!(time_limit > 0.0) || !std::isfinite(time_limit)) {
    throw InputError("time_limit: expected seconds > 0, got " + scenario::formatNumber(time_limit));
  }
}

bool MissionLifecycle::ended() const {
  return state_ != MissionState::kWaiting && state_ != MissionState::kRunning;
}

bool MissionLifecycle::end(MissionState s, double t, const std::string& reason) {
  if (ended()) return false;
  state_ = s;
  end_ = t;
  reason_ = reason;
  return true;
}

bool MissionLifecycle::update(double t, bool have_odometry) {
  if (ended()) return false;
  bool changed = false;
  if (state_ == MissionState::kWaiting && t > 0.0 && have_odometry) {
    state_ = MissionState::kRunning;
    start_ = t;
    reason_ = "running";
    changed = true;
  }
  if (t >= time_limit_) {
    end(MissionState::kTimeout, t,
        "time limit " + scenario::formatNumber(time_limit_) + " s reached" +
            (have_odometry ? "" : " without odometry"));
    changed = true;
  }
  return changed;
}

bool MissionLifecycle::succeed(double t, const std::string& reason) {
  return end(MissionState::kSucceeded, t, reason);
}

bool MissionLifecycle::crash(double t, const std::string& reason) {
  return end(MissionState::kCrashed, t, reason);
}

bool MissionLifecycle::fail(double t, const std::string& reason) {
  return end(MissionState::kFailed, t, reason);
}

bool MissionLifecycle::abort(double t, const std::string& reason) {
  return end(MissionState::kAborted, t, reason);
}

bool MissionLifecycle::simulationEnded(double t, const std::string& reason) {
  return end(MissionState::kEnded, t, reason);
}

}  // namespace hameritt::adk
