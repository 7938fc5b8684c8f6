#include "hameritt/clients/context_filter.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "hameritt/scenario/catalog.h"
#include "hameritt/scenario/error.h"

namespace hameritt::clients {

using geometry::Vec2;
using geometry::Vec3;
using scenario::RelationOp;

namespace {

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.2f", v);
  return buf;
}

geometry::OrientedBox boxOf(const CandidatePose& c, double yaw) {
  geometry::OrientedBox b;
  b.center = c.position + Vec3(0, 0, 0.5 * c.size.z());
  b.size = c.size;
  b.yaw = yaw;
  return b;
}

}  // namespace

bool matchesDescription(const Observation& seen, const scenario::TargetDescription& target) {
  auto value = [&](const std::string& key) -> std::string {
    for (const auto& [k, v] : seen.attributes) {
      if (k == key) return lower(v);
    }
    return "";
  };
  if (!target.cls.empty() && lower(seen.entity_class) != lower(target.cls)) return false;
  const std::pair<const char*, const std::string*> fields[] = {
      {"vehicle_class", &target.vehicle_class},
      {"make", &target.make},
      {"model", &target.model},
      {"color", &target.color}};
  for (const auto& [key, want] : fields) {
    if (!want->empty() && value(key) != lower(*want)) return false;
  }
  return true;
}

std::string describe(const scenario::TargetDescription& t) {
  std::string s;
  for (const std::string* p : {&t.color, &t.make, &t.model}) {
    if (p->empty()) continue;
    if (!s.empty()) s += " ";
    s += *p;
  }
  if (s.empty()) s = t.cls;
  if (!t.vehicle_class.empty()) s += " (" + t.vehicle_class + ")";
  return s;
}

Vec3 nominalSize(const scenario::TargetDescription& t) {
  if (const auto* m = scenario::catalog::findCarModel(t.make, t.model)) {
    return {m->length, m->width, m->height};
  }
  // Mean of the catalog's models of the class.
  Vec3 sum(0, 0, 0);
  int n = 0;
  for (const auto& m : scenario::catalog::carModels()) {
    if (lower(m.vehicle_class) == lower(t.vehicle_class)) {
      sum += Vec3(m.length, m.width, m.height);
      ++n;
    }
  }
  if (n > 0) return sum / n;
  if (lower(t.cls) == "pedestrian") return {0.5, 0.5, 1.75};
  return {4.8, 1.85, 1.6};
}

void ContextSettings::validate() const {
  auto need = [](bool ok, const char* field, const std::string& what, double v) {
    if (!ok) {
      throw scenario::ConfigError(std::string("context.") + field + ": expected " + what +
                                  ", got " + scenario::formatNumber(v));
    }
  };
  need(region_tolerance >= 0, "region_tolerance", "metres >= 0", region_tolerance);
  need(distance_tolerance >= 0, "distance_tolerance", "metres >= 0", distance_tolerance);
  need(over_tolerance >= 0, "over_tolerance", "metres >= 0", over_tolerance);
  need(drive_off_speed >= 0, "drive_off_speed", "m/s >= 0", drive_off_speed);
  need(bearing_tolerance_deg >= 0 && bearing_tolerance_deg <= 180, "bearing_tolerance_deg",
       "degrees in [0, 180]", bearing_tolerance_deg);
  thresholds.validate();
}

ContextFilter::ContextFilter(const scenario::Mission& mission, const scenario::World* world,
                             const ContextSettings& settings)
    : mission_(mission), world_(world), settings_(settings) {
  settings_.validate();
}

std::vector<const scenario::TargetDescription*> ContextFilter::targetsMatching(
    const Observation& seen) const {
  std::vector<const scenario::TargetDescription*> out;
  for (const auto& t : mission_.objective.targets) {
    if (matchesDescription(seen, t)) out.push_back(&t);
  }
  return out;
}

std::string ContextFilter::regionOf(const Vec2& p, double t, bool* driven_off) const {
  *driven_off = false;
  for (const auto& a : mission_.aois) {
    if (a.window.active(t) && a.polygon.distance(p) <= settings_.region_tolerance) return a.id;
  }
  for (const auto& r : mission_.routes) {
    if (r.band.distance(p) <= settings_.region_tolerance) return r.id;
  }
  const bool moving = mission_.cls == scenario::ScenarioClass::kPursuit ||
                      mission_.cls == scenario::ScenarioClass::kFollow ||
                      mission_.cls == scenario::ScenarioClass::kTrack;
  if (!moving || settings_.drive_off_speed <= 0) return "";
  for (const auto& a : mission_.aois) {
    if (!a.window.nlt || t <= *a.window.nlt) continue;
    const double reach = settings_.drive_off_speed * (t - *a.window.nlt);
    if (a.polygon.distance(p) <= settings_.region_tolerance + reach) {
      *driven_off = true;
      return a.id;
    }
  }
  return "";
}

ContextVerdict ContextFilter::check(const CandidatePose& c, double t,
                                    const scenario::TargetDescription& target) const {
  ContextVerdict v;
  const Vec2 p = c.position.head<2>();
  bool driven_off = false;
  if (!mission_.aois.empty() || !mission_.routes.empty()) {
    v.region_id = regionOf(p, t, &driven_off);
    if (v.region_id.empty()) {
      v.reason = "outside every active area of interest and route band at t=" + fmt(t);
      return v;
    }
  }
  // Relations describe the scene at t = 0 (EVENTUALLY_* at their time): they say nothing about a
  // moving target's later position.
  bool static_target = mission_.cls == scenario::ScenarioClass::kAreaSearch;
  if (mission_.cls == scenario::ScenarioClass::kPursuit ||
      mission_.cls == scenario::ScenarioClass::kFollow ||
      mission_.cls == scenario::ScenarioClass::kTrack) {
    for (const auto& a : mission_.aois) static_target |= a.id == v.region_id && !driven_off;
  }
  // The mission's targets with this description: the candidate may be any of them.
  std::vector<const scenario::TargetDescription*> candidates;
  for (const auto& tg : mission_.objective.targets) {
    if (tg.id == target.id ||
        (tg.cls == target.cls && tg.vehicle_class == target.vehicle_class &&
         tg.make == target.make && tg.model == target.model && tg.color == target.color)) {
      candidates.push_back(&tg);
    }
  }
  if (candidates.empty()) candidates.push_back(&target);
  std::string first_failure;
  for (const auto* tg : candidates) {
    int checked = 0, skipped = 0;
    std::string failure;
    for (const auto& rel : mission_.relations) {
      if (rel.target_id != tg->id) continue;
      bool skip = !world_ || !settings_.check_relations || !static_target || rel.eventually;
      std::string why;
      if (!skip) why = checkRelation(rel, c, &skip);
      if (skip) {
        ++skipped;
      } else if (!why.empty()) {
        failure = why;
        break;
      } else {
        ++checked;
      }
    }
    if (failure.empty()) {
      v.accepted = true;
      v.target_id = tg->id;
      v.relations_checked = checked;
      v.relations_skipped = skipped;
      v.reason = "in " + (v.region_id.empty() ? std::string("the mission area") : v.region_id) +
                 (driven_off ? " (within reach past its window)" : "") + ", " +
                 std::to_string(checked) + " relations hold, " + std::to_string(skipped) +
                 " not checkable";
      return v;
    }
    if (first_failure.empty()) first_failure = tg->id + ": " + failure;
  }
  v.reason = first_failure;
  return v;
}

std::string ContextFilter::checkRelation(const scenario::SceneRelation& rel, const CandidatePose& c,
                                         bool* skipped) const {
  *skipped = false;
  const std::string name = "[" + rel.related_id + "] [" + scenario::toString(rel.op) + "]";
  if (rel.op == RelationOp::kPartOf) {
    for (const auto& b : world_->blocks()) {
      if (b.name != rel.related_id) continue;
      const int at = world_->blockAt(c.position.head<2>());
      if (at >= 0 && world_->blocks()[static_cast<std::size_t>(at)].name == b.name) return "";
      return name + ": not in that block";
    }
    *skipped = true;  // convoy or vignette: membership is not visible on the map
    return "";
  }
  const int idx = world_->find(rel.related_id);
  if (idx < 0) {
    *skipped = true;  // a scenario entity (car, pedestrian): not in the public map
    return "";
  }
  const scenario::Entity& e = world_->entities()[static_cast<std::size_t>(idx)];
  const auto& th = settings_.thresholds;
  const double dtol = settings_.distance_tolerance;
  const double d = geometry::footprintDistance(boxOf(c, c.yaw), e.box);
  auto distance_matches = [&](std::string* why) {
    if (std::abs(d - rel.distance) <= dtol) return true;
    *why = name + ": footprint distance " + fmt(d) + " m, evidence " + fmt(rel.distance) + " m";
    return false;
  };
  std::string why;
  switch (rel.op) {
    case RelationOp::kNextTo:
      if (!distance_matches(&why)) return why;
      if (d >= th.next_to_distance + dtol) return name + ": " + fmt(d) + " m away";
      return "";
    case RelationOp::kNotNextTo:
      if (!distance_matches(&why)) return why;
      return "";
    case RelationOp::kOnTopOf:
    case RelationOp::kNotOnTopOf: {
      const geometry::Polygon fp = e.box.footprint();
      const Vec2 p = c.position.head<2>();
      const bool inside = fp.contains(p);
      const double depth = inside ? fp.boundaryDistance(p) : -fp.boundaryDistance(p);
      if (rel.op == RelationOp::kOnTopOf) {
        if (depth >= -settings_.over_tolerance) return "";
        return name + ": centre " + fmt(-depth) + " m outside " + rel.related_id;
      }
      if (depth <= settings_.over_tolerance) return "";
      return name + ": centre " + fmt(depth) + " m inside " + rel.related_id;
    }
    case RelationOp::kLeftOf:
    case RelationOp::kRightOf:
    case RelationOp::kInFrontOf:
    case RelationOp::kOrthogonalTo: {
      if (!distance_matches(&why)) return why;
      const Vec2 dv = e.box.center2() - c.position.head<2>();
      const double world_deg = geometry::radToDeg(std::atan2(dv.y(), dv.x()));
      std::vector<double> expected{rel.bearing_deg};
      if (rel.op == RelationOp::kOrthogonalTo) expected.push_back(rel.bearing_deg + 180.0);
      std::vector<double> yaws{c.yaw};
      if (c.yaw_ambiguous) yaws.push_back(c.yaw + geometry::kPi);
      double best = 180.0;
      for (double y : yaws) {
        const double bearing = geometry::wrapDeg360(world_deg - geometry::radToDeg(y));
        for (double want : expected) {
          best = std::min(best, geometry::angleDiffDeg(bearing, want));
        }
      }
      if (best <= settings_.bearing_tolerance_deg) return "";
      return name + ": bearing off the evidence by " + fmt(best) + " deg";
    }
    case RelationOp::kPartOf:
      break;
  }
  *skipped = true;
  return "";
}

}  // namespace hameritt::clients
