// The spec compiler, its constructive sampler (random or Halton) and the independent checker.

#include "hameritt/generation/spec_sampler.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <optional>
#include <variant>

#include "hameritt/generation/target_slots.h"
#include "hameritt/scenario/catalog.h"
#include "hameritt/scenario/relations.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/scenario/trajectory.h"

namespace hameritt::generation {

using geometry::OrientedBox;
using geometry::Vec2;
using geometry::Vec3;
using scenario::EntityClass;
using scenario::ScenarioClass;

namespace {

std::string values(const AttributeSet& a) {
  if (a.values.empty()) return "any";
  std::string s;
  for (const auto& v : a.values) s += (s.empty() ? "" : "|") + v;
  return s;
}

std::string where(const SourcePos& p) {
  return p.file + ":" + std::to_string(p.line) + ":" + std::to_string(p.column) + ": error: ";
}

std::string history(const std::vector<NarrowingStep>& steps) {
  std::string s;
  for (const auto& st : steps) {
    s += (s.empty() ? "" : " -> ") + st.label + ": " + std::to_string(st.count);
  }
  return "(" + s + ")";
}

// The target's box parked at a slot, rounded as the generator rounds it.
OrientedBox parkedBox(const scenario::ParkingSlot& sl, const scenario::catalog::CarModel& m) {
  return scenario::boxFromPose(
      Vec3(scenario::roundMilli(sl.position.x()), scenario::roundMilli(sl.position.y()),
           scenario::roundMilli(sl.ground_z)),
      scenario::roundMilli(geometry::wrapPi(sl.yaw)), Vec3(m.length, m.width, m.height));
}

// The world entities within `reach` of a place that could be the requirement's related entity
// (its class, look and an operator that applies): computed once per parking place, for every
// car model parked there.
std::vector<int> relatedNear(const scenario::World& world, const Requirement& r, const Vec2& centre,
                             double reach) {
  std::vector<int> out;
  for (int i : world.footprints().near(centre, reach)) {
    const scenario::Entity& e = world.entities()[static_cast<std::size_t>(i)];
    if (scenario::operatorApplies(r.op, e.cls) && r.matchesRelated(e.cls, e.attributes))
      out.push_back(i);
  }
  return out;
}

// True when one of `candidates` (a superset of the related entities near the box) stands in the
// requirement's relation to a target with this box (the negation is applied by the caller). The
// same answer as holds(measure()) over nearbyWorldDistances(), but line of sight (the costly
// part) is traced only where the distance and bearing leave the relation possible.
bool holdsAmong(const scenario::RelationEvaluator& eval, const scenario::World& world,
                const Requirement& r, const OrientedBox& box, const std::vector<int>& candidates) {
  static const scenario::Attributes kNone;
  const scenario::RelationConfig& cfg = eval.config();
  scenario::Subject target;
  target.id = "__spec_target__";
  target.cls = EntityClass::kCar;
  target.attributes = &kNone;
  target.box = box;
  double nominal = -1;  // the directional operators' bearing; ORTHOGONAL_TO: 90 or 270
  if (r.op == scenario::RelationOp::kLeftOf || r.op == scenario::RelationOp::kOrthogonalTo)
    nominal = 90.0;
  if (r.op == scenario::RelationOp::kRightOf) nominal = 270.0;
  if (r.op == scenario::RelationOp::kInFrontOf) nominal = 180.0;
  for (int i : candidates) {
    const scenario::Entity& e = world.entities()[static_cast<std::size_t>(i)];
    const auto& [c, s] = world.footprints().trig(i);
    const double d = geometry::footprintDistance(box, e.box, c, s);
    if (d > cfg.radius) continue;  // not nearby: never considered
    // Margins of 1 mm and 1e-6 deg over the thresholds keep the pruning on the safe side of
    // measure()'s own rounding.
    if (r.op == scenario::RelationOp::kNextTo && d >= cfg.next_to_distance + 1e-3) continue;
    if (nominal >= 0) {
      const Vec2 dv = e.box.center2() - box.center2();
      const double bearing =
          geometry::wrapDeg360(geometry::radToDeg(std::atan2(dv.y(), dv.x()) - box.yaw));
      const double tol = cfg.bearing_tolerance_deg + 1e-6;
      const bool could = geometry::angleDiffDeg(bearing, nominal) <= tol ||
                         (r.op == scenario::RelationOp::kOrthogonalTo &&
                          geometry::angleDiffDeg(bearing, 270.0) <= tol);
      if (!could) continue;
    }
    const scenario::RelationFacts f = eval.measure(target, scenario::worldSubject(world, i));
    if (eval.holds(r.op, f, e.cls)) return true;
  }
  return false;
}

bool worldRelationHoldsPruned(const scenario::RelationEvaluator& eval, const scenario::World& world,
                              const Requirement& r, const OrientedBox& box) {
  const double reach = eval.config().radius + 0.5 * box.size.head<2>().norm();
  return holdsAmong(eval, world, r, box, relatedNear(world, r, box.center2(), reach));
}

// The checker's reference: holds(measure()) on every nearby entity of the related class and
// look, with no pruning. The compiler's worldRelationHolds() must agree with it (the spec tests
// validate every generated scene with this one).
bool worldRelationHoldsReference(const scenario::RelationEvaluator& eval,
                                 const scenario::World& world, const Requirement& r,
                                 const OrientedBox& box) {
  static const scenario::Attributes kNone;
  scenario::Subject target;
  target.id = "__spec_target__";
  target.cls = EntityClass::kCar;
  target.attributes = &kNone;
  target.box = box;
  for (const auto& [i, d] : eval.nearbyWorldDistances(box)) {
    const scenario::Entity& e = world.entities()[static_cast<std::size_t>(i)];
    if (!r.matchesRelated(e.cls, e.attributes)) continue;
    const scenario::RelationFacts f = eval.measure(target, scenario::worldSubject(world, i));
    if (eval.holds(r.op, f, e.cls)) return true;
  }
  return false;
}

double radicalInverse(int base, std::uint64_t i) {
  double inv = 1.0 / base, f = inv, r = 0;
  while (i > 0) {
    r += f * static_cast<double>(i % static_cast<std::uint64_t>(base));
    i /= static_cast<std::uint64_t>(base);
    f *= inv;
  }
  return r;
}

int prime(int n) {
  static const int kPrimes[] = {2,   3,   5,   7,   11,  13,  17,  19,  23,  29,  31, 37, 41,
                                43,  47,  53,  59,  61,  67,  71,  73,  79,  83,  89, 97, 101,
                                103, 107, 109, 113, 127, 131, 137, 139, 149, 151, 157};
  constexpr int kCount = sizeof(kPrimes) / sizeof(kPrimes[0]);
  return kPrimes[n % kCount];
}

scenario::Range fixed(double v) { return {v, v}; }

void applySetting(const std::string& key, double v, ScenarioClass cls, scenario::GeneratorConfig* c,
                  scenario::ScenarioPlan* plan) {
  const int n = static_cast<int>(std::lround(v));
  if (key == "mission.time_limit") {
    (cls == ScenarioClass::kAreaSearch    ? c->time_limit_area_search
     : cls == ScenarioClass::kRouteSearch ? c->time_limit_route_search
                                          : c->time_limit_pursuit) = fixed(v);
  } else if (key == "aois.count") {
    c->aoi_count_min = c->aoi_count_max = n;
  } else if (key == "aois.length") {
    c->aoi_length = fixed(v);
  } else if (key == "aois.width") {
    c->aoi_width = fixed(v);
  } else if (key == "aois.window_probability") {
    c->aoi_window_probability = v;
  } else if (key == "prior.depth") {
    c->prior_depth_min = c->prior_depth_max = n;
  } else if (key == "kozs.count") {
    c->koz_count_min = c->koz_count_max = n;
  } else if (key == "kozs.window_probability") {
    plan->koz_window_probability = v;
  } else if (key == "route.edges") {
    c->route_edges_min = c->route_edges_max = n;
  } else if (key == "route.band") {
    c->band_width = fixed(v);
  } else if (key == "confusers.count") {
    c->confuser_count_min = c->confuser_count_max = n;
  } else if (key == "traffic.cars") {
    c->traffic_count_min = c->traffic_count_max = n;
  } else if (key == "traffic.pedestrians") {
    c->pedestrian_count_min = c->pedestrian_count_max = n;
  } else if (key == "environment.time") {
    c->time_of_day = fixed(v);
  } else if (key == "environment.snow") {
    plan->snow = v;
  } else if (key == "environment.rain") {
    plan->rain = v;
  } else if (key == "environment.dust") {
    plan->dust = v;
  } else if (key == "environment.fog") {
    plan->fog = v;
  } else if (key == "environment.foliage") {
    c->foliage = fixed(v);
  } else if (key == "environment.wind") {
    c->wind_speed = fixed(v);
  } else if (key == "environment.gusts") {
    c->gust_intensity = fixed(v);
  } else if (key == "camera.front_pitch") {
    c->front_pitch = fixed(v);
  } else if (key == "camera.front_fov") {
    c->front_hfov = fixed(v);
  } else if (key == "camera.down_fov") {
    c->down_hfov = fixed(v);
  } else if (key == "camera.noise") {
    c->noise_std = fixed(v);
  } else if (key == "camera.salt_pepper") {
    c->salt_pepper = fixed(v);
  } else if (key == "camera.motion_blur") {
    c->motion_blur_px = fixed(v);
  } else if (key == "uav.altitude_min") {
    c->uav_altitude_min = fixed(v);
  } else if (key == "uav.altitude_max") {
    c->uav_altitude_max = fixed(v);
  } else if (key == "uav.start_within") {
    plan->uav_start_within = v;
  } else if (key == "aois.target_offset") {
    plan->aoi_target_offset = v;
  }
}

}  // namespace

bool worldRelationHolds(const scenario::RelationEvaluator& eval, const scenario::World& world,
                        const Requirement& r, const geometry::OrientedBox& box, bool pruned) {
  return pruned ? worldRelationHoldsPruned(eval, world, r, box)
                : worldRelationHoldsReference(eval, world, r, box);
}

bool parseSampler(const std::string& s, SamplerKind* out) {
  if (s == "random")
    *out = SamplerKind::kRandom;
  else if (s == "halton")
    *out = SamplerKind::kHalton;
  else
    return false;
  return true;
}

CompiledSpec::CompiledSpec(Spec spec, const scenario::World& world,
                           const scenario::GeneratorConfig& base)
    : spec_(std::move(spec)), world_(world), base_(base) {
  const auto& models = scenario::catalog::carModels();
  const auto& colors = scenario::catalog::carColors();
  placed_ = spec_.cls != ScenarioClass::kRouteSearch;
  models_.resize(models.size());
  std::iota(models_.begin(), models_.end(), 0);
  colors_ = colors;
  std::vector<int> slots;
  if (placed_) {
    for (int i = 0; i < static_cast<int>(world.slots().size()); ++i) {
      if (scenario::targetSlotAllowed(world, i, spec_.cls)) slots.push_back(i);
    }
  }
  auto count = [&](std::size_t pairs) {
    return static_cast<long long>(pairs) * static_cast<long long>(colors_.size());
  };
  const std::size_t places = placed_ ? slots.size() : 1;
  steps_.push_back({placed_ ? "parking places x looks" : "looks", count(places * models_.size())});
  auto refuse = [&](const SourcePos& pos, const std::string& what, long long before) {
    throw SpecError(where(pos) + "unsatisfiable in this world: " + what + ": 0 of " +
                    std::to_string(before) + " candidates " + history(steps_));
  };
  // The target's look: catalog models and colours.
  for (const auto& a : spec_.target.attributes) {
    const long long before = steps_.back().count;
    if (a.key == "color") {
      if (!a.values.empty()) colors_ = a.values;
    } else {
      std::vector<int> kept;
      for (int m : models_) {
        const auto& cm = models[static_cast<std::size_t>(m)];
        const std::string v = a.key == "vehicle_class" ? cm.vehicle_class
                              : a.key == "make"        ? cm.make
                                                       : cm.model;
        if (a.values.empty() || std::find(a.values.begin(), a.values.end(), v) != a.values.end()) {
          kept.push_back(m);
        }
      }
      models_ = kept;
    }
    const long long now = count(places * models_.size());
    if (now == 0) refuse(a.pos, "target car {" + a.key + ": " + values(a) + "}", before);
    steps_.push_back({a.key + " " + values(a), now});
  }
  if (const Distribution* off = spec_.setting("aois.target_offset")) {
    // The target must stay inside its AOI, 5 m from the edge, whatever sides are drawn.
    const Distribution* len = spec_.setting("aois.length");
    const Distribution* wid = spec_.setting("aois.width");
    const double side = std::min(len ? len->minValue() : base_.aoi_length.min,
                                 wid ? wid->minValue() : base_.aoi_width.min);
    if (off->maxValue() > 0.5 * side - 5.0) {
      char buf[200];
      std::snprintf(buf, sizeof(buf),
                    "%s: error: aois.target_offset: up to %.3g m, but the target must lie 5 m "
                    "inside an AOI whose shortest side may be %.3g m (at most %.3g m)",
                    spec_.file.c_str(), off->maxValue(), side, 0.5 * side - 5.0);
      throw SpecError(buf);
    }
  }
  if (!placed_) return;
  // Where: a block or a street.
  if (!spec_.target.block.empty() || !spec_.target.street.empty()) {
    const long long before = steps_.back().count;
    std::vector<int> kept;
    for (int i : slots) {
      const auto& sl = world.slots()[static_cast<std::size_t>(i)];
      bool ok;
      if (!spec_.target.block.empty()) {
        ok = sl.block >= 0 &&
             world.blocks()[static_cast<std::size_t>(sl.block)].name == spec_.target.block;
      } else {
        ok = sl.edge >= 0 &&
             world.edges()[static_cast<std::size_t>(sl.edge)].name == spec_.target.street;
      }
      if (ok) kept.push_back(i);
    }
    slots = kept;
    const std::string label = spec_.target.block.empty() ? "on \"" + spec_.target.street + "\""
                                                         : "in " + spec_.target.block;
    if (slots.empty()) refuse(spec_.target.pos, "target " + label, before);
    steps_.push_back({label, count(slots.size() * models_.size())});
  }
  std::vector<std::pair<int, int>> pairs;
  for (int s : slots) {
    for (int m : models_) pairs.emplace_back(s, m);
  }
  // The longest footprint diagonal of the models left: one neighbourhood query per place
  // serves them all.
  double max_diagonal = 0;
  for (int m : models_) {
    const auto& cm = models[static_cast<std::size_t>(m)];
    max_diagonal = std::max(max_diagonal, std::hypot(cm.length, cm.width));
  }
  // Requirements, hard ones first narrowing the set, soft ones split it.
  const scenario::RelationEvaluator eval(world, base.relations);
  std::vector<std::vector<char>> soft_masks;
  for (std::size_t ri = 0; ri < spec_.requirements.size(); ++ri) {
    const Requirement& r = spec_.requirements[ri];
    if (r.eventually) continue;  // constructed by the pursuit's vignette
    std::vector<char> mask(pairs.size());
    std::vector<int> candidates;  // per parking place: the pairs run place by place
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      const auto& sl = world.slots()[static_cast<std::size_t>(pairs[k].first)];
      if (k == 0 || pairs[k].first != pairs[k - 1].first) {
        candidates = relatedNear(world, r, parkedBox(sl, models[0]).center2(),
                                 base.relations.radius + 0.5 * max_diagonal);
      }
      const bool holds =
          holdsAmong(eval, world, r,
                     parkedBox(sl, models[static_cast<std::size_t>(pairs[k].second)]), candidates);
      mask[k] = holds != r.negated;
    }
    if (r.probability < 1.0) {
      soft_.push_back(static_cast<int>(ri));
      soft_masks.push_back(std::move(mask));
      continue;
    }
    const long long before = count(pairs.size());
    std::vector<std::pair<int, int>> kept;
    std::vector<std::vector<char>> kept_soft(soft_masks.size());
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      if (!mask[k]) continue;
      kept.push_back(pairs[k]);
      for (std::size_t j = 0; j < soft_masks.size(); ++j) kept_soft[j].push_back(soft_masks[j][k]);
    }
    if (kept.empty()) refuse(r.pos, r.text, before);
    pairs = std::move(kept);
    soft_masks = std::move(kept_soft);
    steps_.push_back({r.text, count(pairs.size())});
  }
  hard_ = pairs;
  if (soft_.size() > 8) {
    throw SpecError(where(spec_.requirements[static_cast<std::size_t>(soft_[8])].pos) +
                    "at most 8 soft requirements ('prefer') per spec");
  }
  // Every combination of soft outcomes must leave a candidate: a soft requirement holds with
  // its probability only if both it and its negation can be drawn with the others.
  combos_.resize(std::size_t{1} << soft_.size());
  for (std::size_t bits = 0; bits < combos_.size(); ++bits) {
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      bool ok = true;
      for (std::size_t j = 0; j < soft_.size() && ok; ++j) {
        ok = (soft_masks[j][k] != 0) == (((bits >> j) & 1U) != 0);
      }
      if (ok) combos_[bits].push_back(pairs[k]);
    }
    if (combos_[bits].empty()) {
      std::string which;
      std::size_t first = 0;
      for (std::size_t j = 0; j < soft_.size(); ++j) {
        const auto& r = spec_.requirements[static_cast<std::size_t>(soft_[j])];
        which += std::string(which.empty() ? "" : ", ") + (((bits >> j) & 1U) ? "" : "not (") +
                 r.text + (((bits >> j) & 1U) ? "" : ")");
        if (j == 0) first = static_cast<std::size_t>(soft_[j]);
      }
      throw SpecError(where(spec_.requirements[first].pos) +
                      "unsatisfiable in this world: soft requirements drawn as " + which +
                      ": 0 of " + std::to_string(count(pairs.size())) + " candidates " +
                      history(steps_));
    }
  }
}

ScenarioDraw CompiledSpec::draw(std::uint64_t seed, std::uint64_t index, std::uint64_t batch_seed,
                                SamplerKind sampler) const {
  ScenarioDraw d;
  d.config = base_;
  scenario::Rng rng(scenario::deriveSeed(seed, 0x5350454344524157ULL));
  scenario::Rng shift(scenario::deriveSeed(batch_seed, 0x48414C544F4E0000ULL));
  int dim = 0;
  auto unit = [&]() {
    const double s = shift.unit();  // one shift per dimension, the same for every index
    double u;
    if (sampler == SamplerKind::kHalton) {
      u = radicalInverse(prime(dim), index + 1) + s;
      u -= std::floor(u);
    } else {
      u = rng.unit();
    }
    ++dim;
    return u;
  };
  scenario::SpecProvenance prov;
  prov.file = spec_.file;
  prov.hash = spec_.hash;
  prov.sampler = sampler == SamplerKind::kHalton ? "halton" : "random";
  for (const auto& [key, dist] : spec_.settings) {
    double v = dist.draw(unit());
    if (!dist.integer) v = scenario::roundMilli(v);
    applySetting(key, v, spec_.cls, &d.config, &d.plan);
    prov.values.emplace_back(key, v);
  }
  std::size_t bits = 0;
  for (std::size_t j = 0; j < soft_.size(); ++j) {
    const auto& r = spec_.requirements[static_cast<std::size_t>(soft_[j])];
    const bool holds = unit() < r.probability;
    if (holds) bits |= std::size_t{1} << j;
    prov.values.emplace_back("prefer " + r.text, holds);
  }
  if (placed_) d.plan.placements = &combos_[bits];
  d.plan.models = models_;
  d.plan.colors = colors_;
  d.plan.target_count = spec_.target.count;
  for (const auto& r : spec_.requirements) {
    if (r.probability < 1.0 || r.negated || r.eventually) continue;
    d.plan.listed.push_back([r](const scenario::SceneRelation& rel) {
      return rel.op == r.op && !rel.eventually &&
             rel.related_class == scenario::toString(r.related) &&
             r.matchesRelated(r.related, rel.related_attributes);
    });
  }
  d.plan.provenance = prov;
  return d;
}

// ------------------------------------------------------------------ independent check
std::vector<std::string> checkScenarioAgainstSpec(const Spec& spec, const scenario::World& world,
                                                  const scenario::GeneratorConfig& base,
                                                  const scenario::Mission& mission,
                                                  const scenario::SimConfig& sim,
                                                  std::vector<RequirementCheck>* soft,
                                                  bool require_listed) {
  std::vector<std::string> fails;
  auto fail = [&](const std::string& s) { fails.push_back(s); };
  if (sim.cls != spec.cls || mission.cls != spec.cls) {
    fail(std::string("class: expected ") + scenario::toString(spec.cls) + ", got " +
         scenario::toString(sim.cls));
    return fails;
  }
  std::vector<const scenario::ScenarioEntity*> targets;
  for (const auto& se : sim.entities) {
    if (se.role == "target") targets.push_back(&se);
  }
  if (targets.empty()) {
    fail("no target in the scenario");
    return fails;
  }
  if (spec.target.count > 0 && static_cast<int>(targets.size()) != spec.target.count) {
    fail("target count: expected " + std::to_string(spec.target.count) + ", got " +
         std::to_string(targets.size()));
  }
  for (const auto* t : targets) {
    for (const auto& a : spec.target.attributes) {
      if (!a.matches(t->entity.attributes)) {
        fail("target " + t->entity.id + ": " + a.key + " '" + t->entity.attributes.str(a.key) +
             "' is not one of " + values(a));
      }
    }
    const bool moving = !t->trajectory.empty();
    if (moving != (spec.cls != ScenarioClass::kAreaSearch)) {
      fail("target " + t->entity.id + (moving ? " moves" : " is parked") + " in a " +
           scenario::toString(spec.cls));
    }
  }
  const scenario::ScenarioEntity& t = *targets.front();
  OrientedBox box = t.entity.box;
  if (!t.trajectory.empty())
    box = scenario::poseBox(box, scenario::sampleTrajectory(t.trajectory, 0.0));
  if (!spec.target.block.empty() || !spec.target.street.empty()) {
    int slot = -1;
    for (int i = 0; i < static_cast<int>(world.slots().size()); ++i) {
      if ((world.slots()[static_cast<std::size_t>(i)].position - box.center2()).norm() < 0.01)
        slot = i;
    }
    const auto* sl = slot >= 0 ? &world.slots()[static_cast<std::size_t>(slot)] : nullptr;
    if (!spec.target.block.empty() &&
        !(sl && sl->block >= 0 &&
          world.blocks()[static_cast<std::size_t>(sl->block)].name == spec.target.block)) {
      fail("target " + t.entity.id + " is not parked in " + spec.target.block);
    }
    if (!spec.target.street.empty() &&
        !(sl && sl->edge >= 0 &&
          world.edges()[static_cast<std::size_t>(sl->edge)].name == spec.target.street)) {
      fail("target " + t.entity.id + " is not parked on \"" + spec.target.street + "\"");
    }
  }
  scenario::RelationEvaluator eval(world, base.relations);
  for (const auto& se : sim.entities) {
    if (se.trajectory.empty() && se.entity.id != t.entity.id)
      eval.addOccluder(se.entity.id, se.entity.box);
  }
  const double dt = base.relations.eventually_dt;
  for (const auto& r : spec.requirements) {
    bool exists = false;
    if (r.eventually) {
      for (int k = 1; k * dt <= mission.time_limit && !exists; ++k) {
        scenario::Subject ts;
        ts.id = t.entity.id;
        ts.cls = t.entity.cls;
        ts.attributes = &t.entity.attributes;
        ts.box = scenario::poseBox(t.entity.box, scenario::sampleTrajectory(t.trajectory, k * dt));
        for (const auto& se : sim.entities) {
          if (!r.matchesRelated(se.entity.cls, se.entity.attributes) || se.trajectory.empty())
            continue;
          scenario::Subject ps;
          ps.id = se.entity.id;
          ps.cls = se.entity.cls;
          ps.attributes = &se.entity.attributes;
          ps.box =
              scenario::poseBox(se.entity.box, scenario::sampleTrajectory(se.trajectory, k * dt));
          if (eval.holds(r.op, eval.measure(ts, ps), ps.cls)) exists = true;
        }
      }
    } else {
      exists = worldRelationHoldsReference(eval, world, r, box);
    }
    const bool holds = exists != r.negated;
    if (r.probability < 1.0) {
      if (soft) soft->push_back({r.text, holds, true});
      // The scene must agree with the outcome the sampler recorded for it.
      if (sim.spec) {
        for (const auto& [name, v] : sim.spec->values) {
          const bool* drawn = std::get_if<bool>(&v);
          if (name == "prefer " + r.text && drawn && *drawn != holds) {
            fail("soft requirement '" + r.text + "' was drawn to " + (*drawn ? "hold" : "fail") +
                 " but " + (holds ? "holds" : "does not hold") + " in the scene");
          }
        }
      }
      continue;
    }
    if (!holds) {
      fail("requirement '" + r.text + "' does not hold for target " + t.entity.id +
           " (recomputed from the scene)");
      continue;
    }
    if (require_listed && !r.negated && !r.eventually) {
      bool listed = false;
      for (const auto& rel : mission.relations) {
        listed = listed || (rel.target_id == t.entity.id && rel.op == r.op && !rel.eventually &&
                            r.matchesRelated(r.related, rel.related_attributes) &&
                            rel.related_class == scenario::toString(r.related));
      }
      if (!listed) fail("requirement '" + r.text + "' holds but the mission does not list it");
    }
  }
  // Drawn values inside their distributions' supports.
  auto inSupport = [&](const std::string& key, double v, double tol) {
    const Distribution* d = spec.setting(key);
    if (!d) return;
    bool ok = v >= d->minValue() - tol && v <= d->maxValue() + tol;
    if (d->kind == Distribution::Kind::kChoice) {
      ok = false;
      for (const auto& c : d->choices) ok = ok || std::abs(v - c.first) <= tol;
    }
    if (!ok) {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%.6g", v);
      fail(key + ": " + buf + " is outside " + d->text());
    }
  };
  auto atMost = [&](const std::string& key, std::size_t n) {
    const Distribution* d = spec.setting(key);
    if (d && static_cast<double>(n) > d->maxValue() + 1e-9) {
      fail(key + ": " + std::to_string(n) + " exceeds " + d->text());
    }
  };
  auto countRole = [&](const std::string& role) {
    std::size_t n = 0;
    for (const auto& se : sim.entities) n += se.role == role;
    return n;
  };
  inSupport("mission.time_limit", mission.time_limit, 0.5);
  if (spec.cls == ScenarioClass::kAreaSearch) {
    atMost("aois.count", mission.aois.size());
    atMost("kozs.count", mission.kozs.size());
    for (const auto& a : mission.aois) {
      const auto& v = a.polygon.vertices();
      if (v.size() != 4) continue;
      inSupport("aois.length", (v[1] - v[0]).norm(), 0.01);
      inSupport("aois.width", (v[3] - v[0]).norm(), 0.01);
    }
  }
  for (const auto& p : mission.priors) inSupport("prior.depth", p.depth, 1e-9);
  if (!mission.routes.empty()) inSupport("route.band", mission.routes.front().band_width, 0.5);
  atMost("confusers.count", countRole("confuser"));
  atMost("traffic.cars", countRole("traffic"));
  atMost("traffic.pedestrians", countRole("pedestrian"));
  const auto& env = sim.environment;
  inSupport("environment.time", env.time_of_day, 1e-3);
  inSupport("environment.snow", env.snow, 1e-3);
  inSupport("environment.rain", env.rain, 1e-3);
  inSupport("environment.dust", env.dust, 1e-3);
  inSupport("environment.fog", env.fog, 1e-3);
  inSupport("environment.foliage", env.foliage, 1e-3);
  inSupport("environment.wind", env.wind_mean.head<2>().norm(), 2e-3);
  inSupport("environment.gusts", env.gust_intensity, 1e-3);
  for (const auto& c : sim.uav.cameras) {
    if (c.name == "front") {
      inSupport("camera.front_pitch", c.mount_rpy.y(), 1e-3);
      inSupport("camera.front_fov", c.hfov_deg, 1e-3);
    } else if (c.name == "down") {
      inSupport("camera.down_fov", c.hfov_deg, 1e-3);
    }
  }
  inSupport("camera.noise", sim.perturbations.gaussian_noise_std, 1e-3);
  inSupport("camera.salt_pepper", sim.perturbations.salt_pepper_probability, 1e-5);
  inSupport("camera.motion_blur", sim.perturbations.motion_blur_px, 1e-3);
  // The value the sampler recorded for a setting, if any (a scene value must agree with it).
  auto drawn = [&](const std::string& key) -> std::optional<double> {
    if (!sim.spec) return std::nullopt;
    for (const auto& [name, v] : sim.spec->values) {
      if (name == key && std::holds_alternative<double>(v)) return std::get<double>(v);
    }
    return std::nullopt;
  };
  auto printed = [](double v) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.3f", v);
    return std::string(buf);
  };
  if (spec.setting("aois.target_offset") && spec.cls == ScenarioClass::kAreaSearch) {
    // Measured from the scene: the target's distance from the centre of the AOI holding it.
    const scenario::AreaOfInterest* held = nullptr;
    for (const auto& a : mission.aois) {
      if (!held && a.polygon.contains(box.center2())) held = &a;
    }
    if (!held || held->polygon.vertices().empty()) {
      fail("aois.target_offset: no AOI holds target " + t.entity.id);
    } else {
      Vec2 c(0, 0);
      for (const auto& v : held->polygon.vertices()) c += v;
      c /= static_cast<double>(held->polygon.vertices().size());
      const double off = (box.center2() - c).norm();
      inSupport("aois.target_offset", off, 0.01);
      const auto want = drawn("aois.target_offset");
      if (want && std::abs(off - *want) > 0.01) {
        fail("aois.target_offset: target " + t.entity.id + " is " + printed(off) +
             " m from the centre of " + held->id + ", drawn " + printed(*want));
      }
    }
  }
  if (const Distribution* d = spec.setting("uav.start_within")) {
    const double far = (Vec2(sim.uav.start.x, sim.uav.start.y) - box.center2()).norm();
    const auto want = drawn("uav.start_within");
    const double limit = want ? std::min(*want, d->maxValue()) : d->maxValue();
    if (far > limit + 1e-3 || far < std::min(120.0, 0.5 * d->minValue()) - 1e-3) {
      fail("uav.start_within: the UAV starts " + printed(far) + " m from target " + t.entity.id +
           ", expected " + printed(std::min(120.0, 0.5 * d->minValue())) + " to " + printed(limit));
    }
  }
  inSupport("uav.altitude_min", sim.uav.altitude_min, 0.5);
  if (const Distribution* d = spec.setting("uav.altitude_max")) {
    const double v = sim.uav.altitude_max;
    if (!(v >= d->minValue() - 0.5 && v <= d->maxValue() + 0.5) &&
        std::abs(v - (sim.uav.altitude_min + 15.0)) > 1e-6) {
      fail("uav.altitude_max: " + std::to_string(v) + " is outside " + d->text());
    }
  }
  return fails;
}

}  // namespace hameritt::generation
