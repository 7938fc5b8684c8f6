#include "hameritt/adk/detection_scoring.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {

using geometry::Vec3;

GroundTruthHistory::GroundTruthHistory(double horizon) : horizon_(horizon) {
  if (!(horizon > 0.0) || !std::isfinite(horizon)) {
    throw InputError("ground truth horizon: expected seconds > 0, got " +
                     scenario::formatNumber(horizon));
  }
}

double GroundTruthHistory::newestTime() const {
  return snapshots_.empty() ? 0.0 : snapshots_.back().t;
}

void GroundTruthHistory::add(double t, std::vector<EntityTruth> entities) {
  if (!std::isfinite(t)) {
    throw InputError("ground truth: time: expected a finite number, got " +
                     scenario::formatNumber(t));
  }
  // A whole snapshot is refused for one bad entity: interpolating across it would be wrong.
  for (std::size_t i = 0; i < entities.size(); ++i) {
    const EntityTruth& e = entities[i];
    if (!e.position.allFinite() || !std::isfinite(e.yaw)) {
      throw InputError("ground truth: entities[" + std::to_string(i) + "] '" + e.id +
                       "': expected a finite position and yaw");
    }
  }
  if (!snapshots_.empty() && !(t > snapshots_.back().t)) snapshots_.clear();
  snapshots_.push_back(Snapshot{t, std::move(entities)});
  std::size_t drop = 0;
  while (drop + 1 < snapshots_.size() && snapshots_[drop].t < t - horizon_) ++drop;
  snapshots_.erase(snapshots_.begin(), snapshots_.begin() + static_cast<std::ptrdiff_t>(drop));
}

std::vector<EntityTruth> GroundTruthHistory::at(double t) const {
  if (snapshots_.empty()) return {};
  if (t <= snapshots_.front().t) return snapshots_.front().entities;
  if (t >= snapshots_.back().t) return snapshots_.back().entities;
  const auto hi = std::lower_bound(snapshots_.begin(), snapshots_.end(), t,
                                   [](const Snapshot& s, double v) { return s.t < v; });
  if (hi->t == t) return hi->entities;
  const auto lo = hi - 1;
  const double w = (t - lo->t) / (hi->t - lo->t);
  std::unordered_map<std::string, const EntityTruth*> later;
  for (const auto& e : hi->entities) later.emplace(e.id, &e);
  std::vector<EntityTruth> out;
  out.reserve(std::max(lo->entities.size(), hi->entities.size()));
  for (const auto& e : lo->entities) {
    EntityTruth r = e;
    const auto it = later.find(e.id);
    if (it != later.end()) {
      const EntityTruth& b = *it->second;
      r.position = e.position + (b.position - e.position) * w;
      r.yaw = geometry::wrapPi(e.yaw + geometry::wrapPi(b.yaw - e.yaw) * w);
      later.erase(it);
    }
    out.push_back(std::move(r));
  }
  for (const auto& e : hi->entities) {
    if (later.count(e.id)) out.push_back(e);
  }
  return out;
}

EntityTruth scenarioEntityAt(const scenario::ScenarioEntity& e, double t) {
  EntityTruth r;
  r.id = e.entity.id;
  r.cls = scenario::toString(e.entity.cls);
  r.role = e.role;
  if (e.trajectory.empty()) {
    r.position = e.entity.position();
    r.yaw = e.entity.yaw();
  } else {
    const scenario::TrajectoryPoint p = scenario::sampleTrajectory(e.trajectory, t);
    r.position = Vec3(p.x, p.y, p.z);
    r.yaw = p.yaw;
  }
  return r;
}

void ScoringSettings::validate() const {
  auto check = [](double v, const char* name) {
    if (!(v > 0.0 && v <= 100.0)) {
      throw scenario::ConfigError(std::string("scoring.") + name +
                                  ": expected metres in (0, 100], got " +
                                  scenario::formatNumber(v));
    }
  };
  check(car_gate, "car_gate");
  check(pedestrian_gate, "pedestrian_gate");
}

const char* toString(Verdict v) {
  switch (v) {
    case Verdict::kTarget:
      return "target";
    case Verdict::kConfuser:
      return "confuser";
    case Verdict::kOther:
      return "other";
    case Verdict::kNone:
      return "none";
  }
  return "?";
}

DetectionScorer::DetectionScorer(const scenario::Mission& mission,
                                 const std::vector<scenario::ScenarioEntity>& entities,
                                 const ScoringSettings& settings)
    : settings_(settings) {
  settings_.validate();
  for (const auto& e : entities) roles_[e.entity.id] = e.role;
  for (const auto& t : mission.objective.targets) {
    if (!roles_.count(t.id)) {
      throw scenario::ConfigError("objective target " + t.id +
                                  ": not among the sim_config entities (mission and sim_config "
                                  "of different scenarios?)");
    }
    targets_.push_back(t.id);
    found_[t.id] = false;
  }
}

DetectionVerdict DetectionScorer::score(const DetectionClaim& claim,
                                        const std::vector<EntityTruth>& truth) {
  if (!claim.position.allFinite() || !std::isfinite(claim.stamp)) {
    throw InputError("detection: expected a finite stamp and position");
  }
  const EntityTruth* best = nullptr;
  double best_d = std::numeric_limits<double>::infinity();
  for (const auto& e : truth) {
    if (!claim.entity_class.empty() && e.cls != claim.entity_class) continue;
    double gate = 0.0;
    if (e.cls == "car") {
      gate = settings_.car_gate;
    } else if (e.cls == "pedestrian") {
      gate = settings_.pedestrian_gate;
    } else {
      continue;
    }
    const double d = (e.position.head<2>() - claim.position.head<2>()).norm();
    // Nearest; ties go to the entity listed first (deterministic).
    if (d <= gate && d < best_d) {
      best = &e;
      best_d = d;
    }
  }
  DetectionVerdict v;
  if (!best) return v;
  v.entity_id = best->id;
  const auto role = roles_.find(best->id);
  v.role = role != roles_.end() ? role->second : best->role;
  v.position_error = best_d;
  const auto target = found_.find(best->id);
  if (target != found_.end()) {
    v.verdict = Verdict::kTarget;
    v.first_correct = !target->second;
    target->second = true;
  } else if (v.role == "confuser") {
    v.verdict = Verdict::kConfuser;
  } else {
    v.verdict = Verdict::kOther;
  }
  return v;
}

}  // namespace hameritt::adk
