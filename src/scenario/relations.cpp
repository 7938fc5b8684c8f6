#include "hameritt/scenario/relations.h"

#include <algorithm>
#include <cmath>

#include "hameritt/scenario/error.h"

namespace hameritt::scenario {

using geometry::OrientedBox;
using geometry::Vec2;
using geometry::Vec3;

void RelationConfig::validate() const {
  auto positive = [](const char* f, double v) {
    if (!(std::isfinite(v) && v > 0)) {
      throw ConfigError(std::string("generator.relations.") + f +
                        ": expected a positive number, got " + std::to_string(v));
    }
  };
  positive("next_to_distance", next_to_distance);
  positive("radius", radius);
  positive("on_top_tolerance", on_top_tolerance);
  positive("eventually_dt", eventually_dt);
  if (radius < next_to_distance) {
    throw ConfigError("generator.relations.radius: expected at least next_to_distance (" +
                      std::to_string(next_to_distance) + "), got " + std::to_string(radius));
  }
  if (!(bearing_tolerance_deg > 0 && bearing_tolerance_deg < 45)) {
    throw ConfigError(
        "generator.relations.bearing_tolerance_deg: expected a number in (0, 45) so that the "
        "directional operators do not overlap, got " + std::to_string(bearing_tolerance_deg));
  }
  if (max_relations < 1 || max_relations > 32) {
    throw ConfigError("generator.relations.max_relations: expected 1 to 32, got " +
                      std::to_string(max_relations));
  }
}

bool operatorApplies(RelationOp op, EntityClass c) {
  const bool surface = isSurfaceClass(c);
  switch (op) {
    case RelationOp::kOnTopOf:
    case RelationOp::kNotOnTopOf:
      return surface;
    case RelationOp::kNextTo:
    case RelationOp::kNotNextTo:
      return !surface;
    case RelationOp::kLeftOf:
    case RelationOp::kRightOf:
    case RelationOp::kInFrontOf:
    case RelationOp::kOrthogonalTo:
      return !surface && c != EntityClass::kFence;
    case RelationOp::kPartOf:
      return false;
  }
  return false;
}

Subject worldSubject(const World& world, int i) {
  const Entity& e = world.entities()[static_cast<std::size_t>(i)];
  Subject s;
  s.id = e.id;
  s.cls = e.cls;
  s.attributes = &e.attributes;
  s.box = e.box;
  s.world_index = i;
  return s;
}

RelationEvaluator::RelationEvaluator(const World& world, const RelationConfig& config)
    : world_(world), config_(config) {}

void RelationEvaluator::addOccluder(const std::string& id, const OrientedBox& box) {
  ExtraOccluder o;
  o.id = id;
  o.box = box;
  o.cos_yaw = std::cos(box.yaw);
  o.sin_yaw = std::sin(box.yaw);
  const double r = 0.5 * box.size.head<2>().norm() + 0.01;
  const geometry::Vec3 half(r, r, 0.5 * std::abs(box.size.z()) + 0.01);
  o.lo = box.center - half;
  o.hi = box.center + half;
  extra_occluders_.push_back(std::move(o));
}

void RelationEvaluator::removeOccluder(const std::string& id) {
  extra_occluders_.erase(std::remove_if(extra_occluders_.begin(), extra_occluders_.end(),
                                        [&](const auto& o) { return o.id == id; }),
                         extra_occluders_.end());
}

bool RelationEvaluator::lineOfSight(const Subject& a, const Subject& b) const {
  std::vector<int> ignore;
  for (const Subject* s : {&a, &b}) {
    if (s->world_index >= 0) {
      const auto& occ = world_.occludersOf(s->world_index);
      ignore.insert(ignore.end(), occ.begin(), occ.end());
    }
  }
  if (!world_.occluders().clear(a.box.center, b.box.center, ignore)) return false;
  const Vec3 &p = a.box.center, &q = b.box.center;
  const Vec3 lo = p.cwiseMin(q), hi = p.cwiseMax(q);
  for (const ExtraOccluder& o : extra_occluders_) {
    if ((lo.array() > o.hi.array()).any() || (hi.array() < o.lo.array()).any()) continue;
    if (o.id == a.id || o.id == b.id) continue;
    if (o.box.intersectsSegment(p, q, o.cos_yaw, o.sin_yaw)) return false;
  }
  return true;
}

RelationFacts RelationEvaluator::measure(const Subject& target, const Subject& related) const {
  RelationFacts f;
  f.distance = geometry::footprintDistance(target.box, related.box);
  const Vec2 d = related.box.center2() - target.box.center2();
  f.bearing_deg = geometry::wrapDeg360(geometry::radToDeg(std::atan2(d.y(), d.x()) - target.box.yaw));
  f.dz = target.box.minZ() - related.box.maxZ();
  // A point farther from the box centre than its corners (plus 1 mm, far above the polygon's
  // touching tolerance) is outside the footprint: no polygon needed.
  const double corner = 0.5 * related.box.size.head<2>().norm() + 1e-3;
  f.over =
      d.squaredNorm() <= corner * corner && related.box.footprint().contains(target.box.center2());
  // Sight only matters for the operators that need it; surfaces are never occluded.
  if (isSurfaceClass(related.cls)) {
    f.line_of_sight = true;
  } else if (f.distance <= config_.radius) {
    f.line_of_sight = lineOfSight(target, related);
  }
  return f;
}

RelationFacts RelationEvaluator::measureSideways(const Subject& target, const Subject& related,
                                                 std::optional<double> distance) const {
  RelationFacts f;
  f.distance = distance ? *distance : geometry::footprintDistance(target.box, related.box);
  const Vec2 d = related.box.center2() - target.box.center2();
  f.bearing_deg =
      geometry::wrapDeg360(geometry::radToDeg(std::atan2(d.y(), d.x()) - target.box.yaw));
  f.dz = target.box.minZ() - related.box.maxZ();
  if (isSurfaceClass(related.cls)) {
    f.line_of_sight = true;
  } else if (f.distance <= config_.radius) {
    const double tol = config_.bearing_tolerance_deg;
    const bool could = f.distance < config_.next_to_distance ||
                       geometry::angleDiffDeg(f.bearing_deg, 90.0) <= tol ||
                       geometry::angleDiffDeg(f.bearing_deg, 270.0) <= tol;
    if (could) f.line_of_sight = lineOfSight(target, related);
  }
  return f;
}

bool RelationEvaluator::holds(RelationOp op, const RelationFacts& f, EntityClass cls) const {
  if (!operatorApplies(op, cls)) return false;
  const double tol = config_.bearing_tolerance_deg;
  const bool near = f.distance <= config_.radius;
  const bool next = f.distance < config_.next_to_distance && f.line_of_sight;
  const bool on_top = f.over && std::abs(f.dz) <= config_.on_top_tolerance;
  auto facing = [&](double nominal) {
    return near && f.line_of_sight && geometry::angleDiffDeg(f.bearing_deg, nominal) <= tol;
  };
  switch (op) {
    case RelationOp::kNextTo:
      return next;
    case RelationOp::kNotNextTo:
      return near && !next;
    case RelationOp::kOnTopOf:
      return on_top;
    case RelationOp::kNotOnTopOf:
      return near && !on_top;
    case RelationOp::kLeftOf:
      return facing(90.0);
    case RelationOp::kInFrontOf:
      return facing(180.0);
    case RelationOp::kRightOf:
      return facing(270.0);
    case RelationOp::kOrthogonalTo:
      return facing(90.0) || facing(270.0);
    case RelationOp::kPartOf:
      return false;
  }
  return false;
}

std::vector<int> RelationEvaluator::nearbyWorld(const OrientedBox& target) const {
  std::vector<int> out;
  for (const auto& [i, d] : nearbyWorldDistances(target)) out.push_back(i);
  return out;
}

std::vector<std::pair<int, double>> RelationEvaluator::nearbyWorldDistances(
    const OrientedBox& target) const {
  // Footprint index query around the centre, widened by the target's half diagonal, then the
  // exact footprint-to-footprint distance.
  const double reach = config_.radius + 0.5 * target.size.head<2>().norm();
  std::vector<std::pair<int, double>> out;
  for (int i : world_.footprints().near(target.center2(), reach)) {
    // The footprint index keeps every entity box's cosine and sine (box i is entity i's).
    const auto& [c, s] = world_.footprints().trig(i);
    const double d = geometry::footprintDistance(
        target, world_.entities()[static_cast<std::size_t>(i)].box, c, s);
    if (d <= config_.radius) out.emplace_back(i, d);
  }
  return out;
}

namespace {
constexpr RelationOp kSpatialOps[] = {
    RelationOp::kNextTo,  RelationOp::kNotNextTo,   RelationOp::kOnTopOf,
    RelationOp::kNotOnTopOf, RelationOp::kOrthogonalTo, RelationOp::kInFrontOf,
    RelationOp::kRightOf, RelationOp::kLeftOf};

}  // namespace

SceneRelation makeRelation(const Subject& target, const Subject& related, RelationOp op,
                           const RelationFacts& f) {
  SceneRelation r;
  r.related_id = related.id;
  r.related_class = toString(related.cls);
  if (related.attributes) r.related_attributes = *related.attributes;
  r.op = op;
  r.target_id = target.id;
  r.distance = f.distance;
  r.bearing_deg = f.bearing_deg;
  r.dz = f.dz;
  r.line_of_sight = f.line_of_sight;
  return r;
}

std::vector<SceneRelation> RelationEvaluator::allRelations(
    const Subject& target, const std::vector<Subject>& extra,
    const std::vector<const Group*>& groups) const {
  std::vector<SceneRelation> out;
  auto consider = [&](const Subject& related) {
    if (related.id == target.id) return;
    const RelationFacts f = measure(target, related);
    for (RelationOp op : kSpatialOps) {
      if (holds(op, f, related.cls)) out.push_back(makeRelation(target, related, op, f));
    }
  };
  for (int i : nearbyWorld(target.box)) consider(worldSubject(world_, i));
  for (const auto& s : extra) {
    if (geometry::footprintDistance(target.box, s.box) <= config_.radius) consider(s);
  }
  for (const Group* g : groups) {
    SceneRelation r;
    r.related_id = g->id;
    r.related_class = "group";
    r.related_attributes.set("kind", g->kind);
    r.op = RelationOp::kPartOf;
    r.target_id = target.id;
    out.push_back(r);
  }
  return out;
}

bool RelationEvaluator::satisfiedBy(const SceneRelation& rel, const Subject& candidate,
                                    const std::vector<Subject>& extra,
                                    const std::vector<Group>& groups) const {
  if (rel.op == RelationOp::kPartOf) {
    for (const auto& g : groups) {
      if (g.id != rel.related_id) continue;
      return std::find(g.members.begin(), g.members.end(), candidate.id) != g.members.end();
    }
    return false;
  }
  EntityClass cls;
  if (!parseEntityClass(rel.related_class, &cls)) return false;
  auto matches = [&](const Subject& s) {
    return s.id != candidate.id && s.cls == cls && s.attributes &&
           *s.attributes == rel.related_attributes &&
           holds(rel.op, measure(candidate, s), s.cls);
  };
  for (int i : nearbyWorld(candidate.box)) {
    if (matches(worldSubject(world_, i))) return true;
  }
  for (const auto& s : extra) {
    if (geometry::footprintDistance(candidate.box, s.box) <= config_.radius && matches(s)) {
      return true;
    }
  }
  return false;
}

}  // namespace hameritt::scenario
