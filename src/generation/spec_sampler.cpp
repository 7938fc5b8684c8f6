// The spec compiler, its constructive sampler (random or Halton) and the independent checker.

#include "hameritt/generation/spec_sampler.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <tuple>
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

// The spec's target as a relation subject: a car with this box and no attributes.
scenario::Subject specTarget(const OrientedBox& box) {
  static const scenario::Attributes kNone;
  scenario::Subject target;
  target.id = "__spec_target__";
  target.cls = EntityClass::kCar;
  target.attributes = &kNone;
  target.box = box;
  return target;
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

// The centre-line test before measure(): false when the relation cannot hold between these
// boxes (distance or bearing), with the margins of holdsAmong().
bool couldHold(const scenario::RelationConfig& cfg, scenario::RelationOp op,
               const OrientedBox& target, const OrientedBox& related, double d) {
  using scenario::RelationOp;
  if (d > cfg.radius) return false;
  if (op == RelationOp::kNextTo) return d < cfg.next_to_distance + 1e-3;
  double nominal = -1;
  if (op == RelationOp::kLeftOf || op == RelationOp::kOrthogonalTo) nominal = 90.0;
  if (op == RelationOp::kRightOf) nominal = 270.0;
  if (op == RelationOp::kInFrontOf) nominal = 180.0;
  if (nominal < 0) return true;
  const Vec2 dv = related.center2() - target.center2();
  const double bearing =
      geometry::wrapDeg360(geometry::radToDeg(std::atan2(dv.y(), dv.x()) - target.yaw));
  const double tol = cfg.bearing_tolerance_deg + 1e-6;
  return geometry::angleDiffDeg(bearing, nominal) <= tol ||
         (op == RelationOp::kOrthogonalTo && geometry::angleDiffDeg(bearing, 270.0) <= tol);
}

// True when one of `candidates` (a superset of the related entities near the box) stands in the
// requirement's relation to a target with this box (the negation is applied by the caller). The
// same answer as holds(measure()) over nearbyWorldDistances(), but line of sight (the costly
// part) is traced only where the distance and bearing leave the relation possible.
bool holdsAmong(const scenario::RelationEvaluator& eval, const scenario::World& world,
                const Requirement& r, const OrientedBox& box, const std::vector<int>& candidates) {
  const scenario::Subject target = specTarget(box);
  for (int i : candidates) {
    const scenario::Entity& e = world.entities()[static_cast<std::size_t>(i)];
    const auto& [c, s] = world.footprints().trig(i);
    const double d = geometry::footprintDistance(box, e.box, c, s);
    if (!couldHold(eval.config(), r.op, box, e.box, d)) continue;
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
  const scenario::Subject target = specTarget(box);
  for (const auto& [i, d] : eval.nearbyWorldDistances(box)) {
    const scenario::Entity& e = world.entities()[static_cast<std::size_t>(i)];
    if (!r.matchesRelated(e.cls, e.attributes)) continue;
    const scenario::RelationFacts f = eval.measure(target, scenario::worldSubject(world, i));
    if (eval.holds(r.op, f, e.cls)) return true;
  }
  return false;
}

// Whether p lies within `d` m of an intersection (`of` == "intersection") or of the footprint
// of a world entity of class `of`.
bool withinLandmark(const scenario::World& world, const std::string& of, double d, const Vec2& p) {
  if (of == "intersection") {
    for (const auto& n : world.nodes()) {
      if ((n.position - p).norm() <= d) return true;
    }
    return false;
  }
  EntityClass cls;
  if (!scenario::parseEntityClass(of, &cls)) return false;
  for (int i : world.footprints().near(p, d)) {
    if (world.entities()[static_cast<std::size_t>(i)].cls == cls) return true;
  }
  return false;
}

std::string withinText(const TargetSpec& t) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%g", t.within);
  return std::string("within ") + buf + " of " + t.within_of;
}

// The target's box at a route start, as the generator poses the lead car there.
OrientedBox routeStartBox(const scenario::World& world, const scenario::RouteStart& st,
                          const scenario::catalog::CarModel& m) {
  const scenario::TrajectoryPoint p = scenario::routeStartDrive(world, st).pose(st.s);
  return scenario::boxFromPose(Vec3(p.x, p.y, p.z), scenario::roundMilli(geometry::wrapPi(p.yaw)),
                               Vec3(m.length, m.width, m.height));
}

// EVENTUALLY_* on a car that stands with `box0` at t = 0 and later drives `drive` (at most
// `vmax` m/s, its pose sampled every `dt` s): some world entity of the requirement's class and
// look that is not so related at t = 0 comes to stand in the relation along a stretch of the
// lane at least vmax * dt + 1 m long (relation measured every 0.25 m), so that a sample falls
// inside it whatever the speed. Per lane and car size, the relation along the lane is measured
// once (`cache`) and serves every start on it.
class EventualOnLane {
 public:
  static constexpr double kStep = 0.25;
  EventualOnLane(const scenario::RelationEvaluator& eval, const scenario::World& world,
                 const Requirement& r, double vmax)
      : eval_(eval),
        world_(world),
        r_(r),
        need_(static_cast<std::size_t>(
                  std::ceil((vmax * eval.config().eventually_dt + 1.0) / kStep)) +
              1) {}

  bool holds(const OrientedBox& box0, const scenario::LaneDrive& drive) {
    Lane& lane = laneFor(drive, box0.size);
    const scenario::Subject t0 = specTarget(box0);
    const auto first = static_cast<long>(std::max(0.0, std::ceil(drive.begin / kStep)));
    for (std::size_t k = 0; k < lane.entities.size(); ++k) {
      if (lastWindow(&lane, k, drive, box0.size) < first) continue;
      const int i = lane.entities[k];
      const scenario::Entity& e = world_.entities()[static_cast<std::size_t>(i)];
      if (!eval_.holds(r_.op, eval_.measure(t0, scenario::worldSubject(world_, i)), e.cls))
        return true;
    }
    return false;
  }

 private:
  // Per entity near the lane: whether the relation holds at each 0.25 m of it (-1: not yet
  // measured), and the start of the last run of need_ samples where it holds (-2: not yet
  // sought, -1: none).
  struct Lane {
    std::vector<int> entities;
    std::vector<std::vector<signed char>> on;
    std::vector<long> last;
  };

  // The last window of need_ samples where the relation holds with entity k: sought from the
  // lane's end, each window tested from its start, and on a miss at q the next window ends
  // before q. A start at sample j has a window ahead iff j <= this.
  long lastWindow(Lane* lane, std::size_t k, const scenario::LaneDrive& d, const Vec3& size) {
    long& last = lane->last[k];
    if (last != -2) return last;
    last = -1;
    const auto n = static_cast<long>(lane->on[k].size());
    const auto need = static_cast<long>(need_);
    long p = n - need;
    while (p >= 0) {
      long q = p;
      while (q < p + need && at(lane, k, static_cast<std::size_t>(q), d, size)) ++q;
      if (q == p + need) {
        last = p;
        break;
      }
      p = q - need;
    }
    return last;
  }

  bool at(Lane* lane, std::size_t k, std::size_t j, const scenario::LaneDrive& d,
          const Vec3& size) {
    signed char& v = lane->on[k][j];
    if (v >= 0) return v != 0;
    const int i = lane->entities[k];
    const scenario::Entity& e = world_.entities()[static_cast<std::size_t>(i)];
    const auto& [c, sn] = world_.footprints().trig(i);
    const scenario::TrajectoryPoint p = d.pose(static_cast<double>(j) * kStep);
    const OrientedBox box = scenario::boxFromPose(
        Vec3(p.x, p.y, p.z), scenario::roundMilli(geometry::wrapPi(p.yaw)), size);
    const double dist = geometry::footprintDistance(box, e.box, c, sn);
    v = couldHold(eval_.config(), r_.op, box, e.box, dist) &&
        eval_.holds(r_.op, eval_.measure(specTarget(box), scenario::worldSubject(world_, i)),
                    e.cls);
    return v != 0;
  }

  Lane& laneFor(const scenario::LaneDrive& d, const Vec3& size) {
    const auto key = std::make_tuple(std::llround(d.from.x() * 1e3), std::llround(d.from.y() * 1e3),
                                     std::llround(d.dir.x() * 1e6), std::llround(d.dir.y() * 1e6),
                                     std::llround(size.x() * 1e3), std::llround(size.y() * 1e3),
                                     std::llround(size.z() * 1e3));
    auto it = cache_.find(key);
    if (it != cache_.end()) return it->second;
    Lane lane;
    const double half = 0.5 * d.end;
    const Vec2 mid = d.from + d.dir * half;
    const double reach = half + d.lane_offset + eval_.config().radius + 0.5 * size.head<2>().norm();
    const auto n = static_cast<std::size_t>(std::max(0.0, std::floor(d.end / kStep)) + 1);
    lane.entities = relatedNear(world_, r_, mid, reach);
    lane.on.assign(lane.entities.size(), std::vector<signed char>(n, -1));
    lane.last.assign(lane.entities.size(), -2);
    return cache_.emplace(key, std::move(lane)).first->second;
  }

  const scenario::RelationEvaluator& eval_;
  const scenario::World& world_;
  const Requirement& r_;
  std::size_t need_;  // consecutive samples: (vmax * dt + 1 m) / kStep + 1
  std::map<std::tuple<long long, long long, long long, long long, long long, long long, long long>,
           Lane>
      cache_;
};

// A positive relation to a car or pedestrian: the sampler places the related entity.
bool placesRelated(const Requirement& r) {
  return !r.eventually && !r.negated &&
         (r.related == EntityClass::kCar || r.related == EntityClass::kPedestrian);
}

}  // namespace

// How a placer treats another requirement of the spec while it places its entity.
enum class OtherRole : char {
  kKeep,   // its outcome (hard: as required; soft: as the scene has it) must not change
  kHolds,  // an earlier placing requirement, met: it must keep holding
  kLater,  // a later placing requirement that places its own entity: not constrained here
};

// Where the related car or pedestrian of a placing requirement can go: free parking places
// (a parked car of each look the requirement allows) and points every metre along the
// sidewalks (a standing pedestrian). An option is kept when the relation holds, no negated
// requirement comes to hold with it, and every other requirement keeps its outcome with it as
// an occluder (the entities placed for earlier requirements count as part of the scene); the
// compiler and the generator use the same test.
struct RelatedPlacer {
  static constexpr double kCell = 16.0;
  static constexpr double kStandStep = 1.0;
  const scenario::World& world;
  scenario::RelationEvaluator eval;
  Requirement req;
  std::vector<Requirement> others;  // every other static requirement
  std::vector<int> other_index;     // their indices in the spec's requirements
  ScenarioClass cls;
  std::vector<int> models;          // car looks: catalog models
  std::vector<std::string> colors;  // car colours or pedestrian clothing colours
  std::vector<OrientedBox> stands;  // standing pedestrian boxes
  double max_half_diagonal = 0.5 * std::hypot(0.5, 0.6);  // of the related footprints
  // Grid cells of kCell m: free parking slots (cars) or indices of `stands` (pedestrians).
  std::map<std::pair<int, int>, std::vector<int>> cells;

  RelatedPlacer(const scenario::World& w, const scenario::RelationConfig& rc, std::size_t self,
                const std::vector<Requirement>& all, ScenarioClass c)
      : world(w), eval(w, rc), req(all[self]), cls(c) {
    for (std::size_t i = 0; i < all.size(); ++i) {
      if (!all[i].eventually && i != self) {
        others.push_back(all[i]);
        other_index.push_back(static_cast<int>(i));
      }
    }
    auto allowed = [&](const std::string& key, const std::string& v) {
      for (const auto& a : req.attributes) {
        if (a.key == key && !a.values.empty() &&
            std::find(a.values.begin(), a.values.end(), v) == a.values.end())
          return false;
      }
      return true;
    };
    if (req.related == EntityClass::kCar) {
      const auto& cm = scenario::catalog::carModels();
      for (int m = 0; m < static_cast<int>(cm.size()); ++m) {
        const auto& x = cm[static_cast<std::size_t>(m)];
        if (allowed("vehicle_class", x.vehicle_class) && allowed("make", x.make) &&
            allowed("model", x.model)) {
          models.push_back(m);
          max_half_diagonal = std::max(max_half_diagonal, 0.5 * std::hypot(x.length, x.width));
        }
      }
      for (const auto& col : scenario::catalog::carColors()) {
        if (allowed("color", col)) colors.push_back(col);
      }
      for (int i = 0; i < static_cast<int>(world.slots().size()); ++i) {
        const auto& sl = world.slots()[static_cast<std::size_t>(i)];
        if (sl.occupant < 0) cells[cell(sl.position)].push_back(i);
      }
      return;
    }
    for (const auto& col : scenario::catalog::clothingColors()) {
      if (allowed("clothing_color", col)) colors.push_back(col);
    }
    for (const auto& b : world.blocks()) {
      const double ring = geometry::polylineLength(b.sidewalk);
      for (double s = 0; s + kStandStep <= ring + 1e-9; s += kStandStep) {
        const Vec2 p = geometry::polylinePointAt(b.sidewalk, s);
        const Vec2 q = geometry::polylinePointAt(b.sidewalk, std::min(ring, s + 0.5));
        const Vec2 dq = q - p;
        const double yaw = dq.norm() > 1e-9 ? std::atan2(dq.y(), dq.x()) : 0.0;
        const OrientedBox box = scenario::boxFromPose(
            Vec3(scenario::roundMilli(p.x()), scenario::roundMilli(p.y()), 0.0),
            scenario::roundMilli(geometry::wrapPi(yaw)), Vec3(0.5, 0.6, 1.75));
        // Not inside a world entity (a fence, a tree, a parked car on a driveway).
        bool clear = true;
        for (int i : world.footprints().near(p, 2.0)) {
          const auto& [c, sn] = world.footprints().trig(i);
          if (geometry::footprintDistance(box, world.entities()[static_cast<std::size_t>(i)].box, c,
                                          sn) < 0.05)
            clear = false;
        }
        if (!clear) continue;
        cells[cell(p)].push_back(static_cast<int>(stands.size()));
        stands.push_back(box);
      }
    }
  }

  static std::pair<int, int> cell(const Vec2& p) {
    return {static_cast<int>(std::floor(p.x() / kCell)),
            static_cast<int>(std::floor(p.y() / kCell))};
  }

  scenario::Attributes look(const std::string& color, int model) const {
    scenario::Attributes a;
    if (req.related == EntityClass::kCar) {
      const auto& x = scenario::catalog::carModels()[static_cast<std::size_t>(model)];
      a.set("vehicle_class", x.vehicle_class);
      a.set("make", x.make);
      a.set("model", x.model);
      a.set("color", color);
    } else {
      a.set("clothing_color", color);
      a.set("activity", std::string("standing"));
    }
    return a;
  }

  // The id under which the k-th entity placed for an earlier requirement is measured.
  static std::string placedId(std::size_t k) { return "__spec_placed_" + std::to_string(k); }

  // This placer's evaluator with the entities placed so far as occluders.
  scenario::RelationEvaluator sceneEval(const std::vector<scenario::RelatedOption>& placed) const {
    scenario::RelationEvaluator ev = eval;
    for (std::size_t k = 0; k < placed.size(); ++k) ev.addOccluder(placedId(k), placed[k].box);
    return ev;
  }

  // Whether `q` holds (negation not applied) for a target with this box among the world's
  // entities and the placed ones, as the checker sees it with `ev` (which holds the placed
  // entities, and any candidate, as occluders).
  bool sceneHolds(const scenario::RelationEvaluator& ev, const Requirement& q,
                  const OrientedBox& box,
                  const std::vector<scenario::RelatedOption>& placed) const {
    if (worldRelationHoldsPruned(ev, world, q, box)) return true;
    if (placed.empty()) return false;
    const scenario::Subject ts = specTarget(box);
    for (std::size_t k = 0; k < placed.size(); ++k) {
      const scenario::RelatedOption& p = placed[k];
      if (!q.matchesRelated(p.cls, p.attributes)) continue;
      scenario::Subject ps;
      const std::string id = placedId(k);
      ps.id = id;
      ps.cls = p.cls;
      ps.attributes = &p.attributes;
      ps.box = p.box;
      if (ev.holds(q.op, ev.measure(ts, ps), p.cls)) return true;
    }
    return false;
  }

  // Whether this requirement already holds for the target with the entities placed so far.
  bool met(const OrientedBox& target, const std::vector<scenario::RelatedOption>& placed) const {
    if (placed.empty()) return worldRelationHoldsPruned(eval, world, req, target);
    return sceneHolds(sceneEval(placed), req, target, placed);
  }

  // Calls `fn` on each option for a target with this box, with `placed` (the entities placed
  // for earlier requirements) in the scene and `roles` (per spec requirement; empty: every
  // other one kKeep); stops when `fn` returns true.
  template <typename Fn>
  void forEachOption(const OrientedBox& target, const std::vector<scenario::RelatedOption>& placed,
                     const std::vector<OtherRole>& roles, Fn fn) const {
    const scenario::RelationConfig& cfg = eval.config();
    static const scenario::Attributes kNone;
    const scenario::Subject ts = specTarget(target);
    std::optional<scenario::RelationEvaluator> scene;
    if (!placed.empty()) scene.emplace(sceneEval(placed));
    const scenario::RelationEvaluator& sev = scene ? *scene : eval;
    auto role = [&](std::size_t k) {
      return roles.empty() ? OtherRole::kKeep : roles[static_cast<std::size_t>(other_index[k])];
    };
    // Centre to centre, the farthest a related entity can stand: the operator's footprint
    // distance plus half of each footprint's diagonal.
    const double op_reach =
        (req.op == scenario::RelationOp::kNextTo ? cfg.next_to_distance + 1e-3 : cfg.radius);
    const double reach = op_reach + 0.5 * target.size.head<2>().norm() + max_half_diagonal + 0.01;
    std::vector<char> before;  // outcomes of the other requirements without the candidate
    bool stop = false;
    auto tryBox = [&](const OrientedBox& box, int slot, const std::vector<int>& looks) {
      const double d = geometry::footprintDistance(target, box);
      if (d < 0.3) return;  // touching the target
      for (const auto& p : placed) {
        // Not in the place of an entity placed for an earlier requirement, nor touching it.
        if ((slot >= 0 && p.slot == slot) || geometry::footprintDistance(p.box, box) < 0.3) return;
      }
      if (!couldHold(cfg, req.op, target, box, d)) return;
      scenario::Subject rs;
      rs.id = "__spec_related__";
      rs.cls = req.related;
      rs.attributes = &kNone;
      rs.box = box;
      const scenario::RelationFacts f = sev.measure(ts, rs);
      if (!sev.holds(req.op, f, req.related)) return;
      if (before.empty()) {
        // The hard ones hold (negations: do not) wherever a placement is sought.
        for (std::size_t k = 0; k < others.size(); ++k) {
          const Requirement& q = others[k];
          const OtherRole ro = role(k);
          before.push_back(ro == OtherRole::kLater   ? 0
                           : ro == OtherRole::kHolds ? 1
                           : q.probability == 1.0    ? !q.negated
                                                     : sceneHolds(sev, q, target, placed));
        }
      }
      scenario::RelationEvaluator with = sev;
      with.addOccluder(rs.id, box);
      std::vector<char> after_world;
      for (std::size_t k = 0; k < others.size(); ++k) {
        const Requirement& q = others[k];
        // An occluder only takes relations away, but NOT_NEXT_TO and NOT_ON_TOP_OF.
        const bool can_appear =
            q.op == scenario::RelationOp::kNotNextTo || q.op == scenario::RelationOp::kNotOnTopOf;
        after_world.push_back(role(k) == OtherRole::kLater || (!before[k] && !can_appear)
                                  ? 0
                                  : sceneHolds(with, q, target, placed));
      }
      for (int m : looks) {
        for (const auto& col : colors) {
          const scenario::Attributes a = look(col, m);
          bool ok = true;
          for (std::size_t k = 0; k < others.size() && ok; ++k) {
            if (role(k) == OtherRole::kLater) continue;
            const Requirement& q = others[k];
            const bool by_it = q.related == req.related && q.matchesRelated(req.related, a) &&
                               eval.holds(q.op, f, req.related);
            ok = (after_world[k] || by_it) == (before[k] != 0);
          }
          if (!ok) continue;
          scenario::RelatedOption o;
          o.cls = req.related;
          o.box = box;
          o.slot = slot;
          o.attributes = a;
          if (fn(o)) {
            stop = true;
            return;
          }
        }
      }
    };
    const auto& cm = scenario::catalog::carModels();
    const Vec2 fwd(std::cos(target.yaw), std::sin(target.yaw));
    const auto [cx, cy] = cell(target.center2());
    const int span = static_cast<int>(std::ceil(reach / kCell));
    for (int gx = cx - span; gx <= cx + span; ++gx) {
      for (int gy = cy - span; gy <= cy + span; ++gy) {
        auto it = cells.find({gx, gy});
        if (it == cells.end()) continue;
        for (int k : it->second) {
          if (req.related == EntityClass::kPedestrian) {
            const OrientedBox& box = stands[static_cast<std::size_t>(k)];
            if ((box.center2() - target.center2()).norm() > reach) continue;
            tryBox(box, -1, {-1});
            if (stop) return;
            continue;
          }
          const auto& sl = world.slots()[static_cast<std::size_t>(k)];
          const Vec2 dv = sl.position - target.center2();
          if (dv.norm() > reach || dv.norm() < 1.0) continue;  // far, or the target's own place
          if (cls == ScenarioClass::kPursuit) {
            // Not in the pursuit target's way as it pulls out of the kerb ahead.
            const double along = dv.dot(fwd), lat = std::abs(dv.x() * fwd.y() - dv.y() * fwd.x());
            if (along > 0 && along < scenario::kPullOut + 12.0 && lat < 4.0) continue;
          }
          for (int m : models) {
            tryBox(parkedBox(sl, cm[static_cast<std::size_t>(m)]), k, {m});
            if (stop) return;
          }
        }
      }
    }
  }

  // The options for a target with this box (all of them, or the first only).
  std::vector<scenario::RelatedOption> options(
      const OrientedBox& target, bool first,
      const std::vector<scenario::RelatedOption>& placed = {},
      const std::vector<OtherRole>& roles = {}) const {
    std::vector<scenario::RelatedOption> out;
    forEachOption(target, placed, roles, [&](const scenario::RelatedOption& o) {
      out.push_back(o);
      return first;
    });
    return out;
  }
};

// The spec's placing requirements in the order written: each places its entity (unless the
// scene already meets it) among its options with the earlier ones' entities in the scene, and
// an earlier one only takes an option that leaves every later one a spot (decided by a search
// over the options, not by drawing whole scenes).
struct PlacerChain {
  std::vector<std::shared_ptr<const RelatedPlacer>> placers;
  std::vector<int> index;  // each placer's requirement in the spec
  std::size_t requirements = 0;

  // The roles of the spec's requirements for placer k, with `active` placers placing (an
  // inactive hard one places after them all; an inactive soft one, drawn to fail, keeps failing).
  std::vector<OtherRole> roles(std::size_t k, const std::vector<char>& active) const {
    std::vector<OtherRole> r(requirements, OtherRole::kKeep);
    for (std::size_t j = 0; j < placers.size(); ++j) {
      if (j == k) continue;
      if (active[j])
        r[static_cast<std::size_t>(index[j])] = j < k ? OtherRole::kHolds : OtherRole::kLater;
      else if (placers[j]->req.probability == 1.0)
        r[static_cast<std::size_t>(index[j])] = OtherRole::kLater;
    }
    return r;
  }

  // The roles for placer k placing alone, before the others (a necessary condition: the
  // placers' joint outcome is decided by complete()).
  std::vector<OtherRole> alone(std::size_t k) const {
    std::vector<OtherRole> r(requirements, OtherRole::kKeep);
    for (std::size_t j = 0; j < placers.size(); ++j) {
      if (j != k) r[static_cast<std::size_t>(index[j])] = OtherRole::kLater;
    }
    return r;
  }

  // The compiler's search at one place tries at most this many options of the earlier placers:
  // a place where the search takes more counts as having no spot (a bound on the search, which
  // grows with the power of the number of placers where they cannot all be met).
  static constexpr long kBudget = 400;

  // Whether the active placers from k on can each be met, given `placed` (restored on return).
  // `budget`: options left to try (null: no bound).
  bool complete(std::size_t k, const OrientedBox& box, std::vector<scenario::RelatedOption>* placed,
                const std::vector<char>& active, long* budget = nullptr) const {
    while (k < placers.size() && (!active[k] || placers[k]->met(box, *placed))) ++k;
    if (k == placers.size()) return true;
    bool found = false;
    bool last = true;  // no active placer after k: its first option settles it
    for (std::size_t j = k + 1; j < placers.size(); ++j) last = last && !active[j];
    // Options that differ only in looks the spec's requirements do not tell apart are tried once.
    std::set<std::tuple<long long, long long, long long, long long, long long, std::string>> tried;
    placers[k]->forEachOption(box, *placed, roles(k, active),
                              [&](const scenario::RelatedOption& o) {
                                if (last) return found = true;
                                if (budget && --*budget < 0) return true;  // over: no spot
                                if (!tried.insert(key(o)).second) return false;
                                placed->push_back(o);
                                found = complete(k + 1, box, placed, active, budget);
                                placed->pop_back();
                                return found;
                              });
    return found;
  }

  // The entities placed for a target with this box: each active placer in turn draws uniformly
  // among its options that leave the later ones a spot (the first of a seeded permutation that
  // does).
  std::vector<scenario::RelatedOption> draw(const OrientedBox& box, const std::vector<char>& active,
                                            scenario::Rng& rng) const {
    std::vector<scenario::RelatedOption> placed;
    for (std::size_t k = 0; k < placers.size(); ++k) {
      if (!active[k] || placers[k]->met(box, placed)) continue;
      std::vector<scenario::RelatedOption> o =
          placers[k]->options(box, false, placed, roles(k, active));
      bool later = false;
      for (std::size_t j = k + 1; j < placers.size(); ++j) later = later || active[j];
      if (!later && !o.empty()) {
        placed.push_back(
            o[static_cast<std::size_t>(rng.uniformInt(0, static_cast<long>(o.size()) - 1))]);
        continue;
      }
      bool done = false;
      for (std::size_t i = 0; i < o.size() && !done; ++i) {
        const auto j = static_cast<std::size_t>(
            rng.uniformInt(static_cast<long>(i), static_cast<long>(o.size()) - 1));
        std::swap(o[i], o[j]);
        placed.push_back(o[i]);
        done = complete(k + 1, box, &placed, active);
        if (!done) placed.pop_back();
      }
      if (!done) {
        throw scenario::GenerationError("no place beside the target for '" + placers[k]->req.text +
                                        "'");
      }
    }
    return placed;
  }

  // What an option is to the later placers: its box and which requirements its look matches.
  std::tuple<long long, long long, long long, long long, long long, std::string> key(
      const scenario::RelatedOption& o) const {
    const RelatedPlacer& p = *placers.front();  // its requirement and the others: all static ones
    std::string sig(requirements, '0');
    for (std::size_t q = 0; q < p.others.size(); ++q) {
      if (p.others[q].matchesRelated(o.cls, o.attributes))
        sig[static_cast<std::size_t>(p.other_index[q])] = '1';
    }
    if (p.req.matchesRelated(o.cls, o.attributes))
      sig[static_cast<std::size_t>(index.front())] = '1';
    return {std::llround(o.box.center.x() * 1e3), std::llround(o.box.center.y() * 1e3),
            std::llround(o.box.yaw * 1e6),        std::llround(o.box.size.x() * 1e3),
            std::llround(o.box.size.y() * 1e3),   sig};
  }
};

namespace {

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
  } else if (key == "confusers.within") {
    plan->confuser_within = v;
  }
}

// A koz statement with the values drawn for its settings (absent: the defaults).
scenario::ScenarioPlan::Koz drawnKoz(const KozSpec& k, const std::map<std::string, double>& v) {
  scenario::ScenarioPlan::Koz z;
  z.purpose = k.purpose;
  z.over = k.over;
  auto get = [&](const char* name) -> std::optional<double> {
    auto it = v.find(k.key + "." + name);
    return it == v.end() ? std::nullopt : std::optional<double>(it->second);
  };
  if (auto c = get("count")) z.count = static_cast<int>(std::lround(*c));
  if (auto x = get("size")) z.size = *x;
  if (auto x = get("margin")) z.margin = *x;
  if (auto x = get("length")) z.length = *x;
  z.aoi = k.aoi;
  z.alt_min = get("alt_min");
  z.alt_max = get("alt_max");
  z.net = get("net");
  z.nlt = get("nlt");
  return z;
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
  const bool route = spec_.cls == ScenarioClass::kRouteSearch;
  // Where the lead car of a route search with requirements starts: every lane start.
  if (route && !spec_.requirements.empty()) route_starts_ = scenario::routeStarts(world);
  std::vector<int> slots;
  if (placed_) {
    for (int i = 0; i < static_cast<int>(world.slots().size()); ++i) {
      if (scenario::targetSlotAllowed(world, i, spec_.cls)) slots.push_back(i);
    }
  }
  auto count = [&](std::size_t pairs) {
    return static_cast<long long>(pairs) * static_cast<long long>(colors_.size());
  };
  const std::size_t places =
      placed_ ? slots.size() : std::max<std::size_t>(1, route_starts_.size());
  steps_.push_back({placed_                 ? "parking places x looks"
                    : route_starts_.empty() ? "looks"
                                            : "route starts x looks",
                    count(places * models_.size())});
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
  for (const auto& k : spec_.kozs) {
    // A zone over the N-th AOI: every scenario has that many (the parser checks aois.count).
    if (k.aoi > base_.aoi_count_min && !spec_.setting("aois.count")) {
      throw SpecError(where(k.aoi_pos) + "aoi " + std::to_string(k.aoi) + ": a scenario may have " +
                      std::to_string(base_.aoi_count_min) +
                      " AOI(s) (config aoi_count_min); set aois { count: ... } to at least " +
                      std::to_string(k.aoi));
    }
  }
  if (spec_.confusers.told_apart >= 0) {
    told_eval_ = std::make_shared<const scenario::RelationEvaluator>(world, base.relations);
  }
  if (!placed_ && route_starts_.empty()) return;
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
  // Near a landmark.
  if (spec_.target.within > 0) {
    const long long before = steps_.back().count;
    std::vector<int> kept;
    for (int i : slots) {
      const Vec2& p = world.slots()[static_cast<std::size_t>(i)].position;
      if (withinLandmark(world, spec_.target.within_of, spec_.target.within,
                         Vec2(scenario::roundMilli(p.x()), scenario::roundMilli(p.y()))))
        kept.push_back(i);
    }
    slots = kept;
    if (slots.empty())
      refuse(spec_.target.within_pos, "target " + withinText(spec_.target), before);
    steps_.push_back({withinText(spec_.target), count(slots.size() * models_.size())});
  }
  std::vector<std::pair<int, int>> pairs;
  for (int s : slots) {
    for (int m : models_) pairs.emplace_back(s, m);
  }
  for (int s = 0; s < static_cast<int>(route_starts_.size()); ++s) {
    for (int m : models_) pairs.emplace_back(s, m);
  }
  // The target's box at t = 0 for a candidate pair.
  auto boxAt = [&](const std::pair<int, int>& p) {
    const auto& cm = models[static_cast<std::size_t>(p.second)];
    return route ? routeStartBox(world, route_starts_[static_cast<std::size_t>(p.first)], cm)
                 : parkedBox(world.slots()[static_cast<std::size_t>(p.first)], cm);
  };
  // The longest footprint diagonal of the models left: one neighbourhood query per place
  // serves them all.
  double max_diagonal = 0;
  for (int m : models_) {
    const auto& cm = models[static_cast<std::size_t>(m)];
    max_diagonal = std::max(max_diagonal, std::hypot(cm.length, cm.width));
  }
  // Requirements, hard ones first narrowing the set, soft ones split it.
  const scenario::RelationEvaluator eval(world, base.relations);
  // Per soft requirement, the pairs where it can be drawn to hold and where it can be drawn to
  // fail (complements, except for a soft placing requirement: where the world does not meet it,
  // a placed entity can make it hold or nothing placed leaves it failing).
  std::vector<std::vector<char>> soft_masks, soft_fail_masks;
  // The requirement that places a car or pedestrian goes last: it is tested on the places
  // that every other requirement left.
  // EVENTUALLY_* ones (measured along a lane) go after the others, on fewer candidates.
  std::vector<std::size_t> order;
  for (std::size_t ri = 0; ri < spec_.requirements.size(); ++ri) {
    if (!placesRelated(spec_.requirements[ri]) && !spec_.requirements[ri].eventually)
      order.push_back(ri);
  }
  for (std::size_t ri = 0; ri < spec_.requirements.size(); ++ri) {
    if (!placesRelated(spec_.requirements[ri]) && spec_.requirements[ri].eventually)
      order.push_back(ri);
  }
  auto chain = std::make_shared<PlacerChain>();
  chain->requirements = spec_.requirements.size();
  for (std::size_t ri = 0; ri < spec_.requirements.size(); ++ri) {
    if (!placesRelated(spec_.requirements[ri])) continue;
    order.push_back(ri);
    chain->placers.push_back(std::make_shared<const RelatedPlacer>(world, base.relations, ri,
                                                                   spec_.requirements, spec_.cls));
    chain->index.push_back(static_cast<int>(ri));
  }
  const std::size_t n_placers = chain->placers.size();
  if (n_placers > 0) {
    chain_ = chain;
    placer_soft_.assign(n_placers, -1);
  }
  // The hard placers written up to placer c: they place together (soft ones place nothing).
  auto hardUpTo = [&](std::size_t c) {
    std::vector<char> active(n_placers, 0);
    int n = 0;
    for (std::size_t j = 0; j <= c; ++j) {
      const bool hard =
          spec_.requirements[static_cast<std::size_t>(chain->index[j])].probability == 1.0;
      active[j] = hard;
      n += hard;
    }
    return std::make_pair(active, n);
  };
  for (const std::size_t ri : order) {
    const Requirement& r = spec_.requirements[ri];
    // The pursuit's running pedestrians: constructed by its vignette.
    if (r.eventually && r.related == EntityClass::kPedestrian) continue;
    std::vector<char> mask(pairs.size()), fail_mask(pairs.size());
    std::vector<int> candidates;  // per parking place: the pairs run place by place
    std::shared_ptr<const RelatedPlacer> placer;
    std::size_t chain_pos = 0;
    std::pair<std::vector<char>, int> joint;  // the hard placers that place with this one
    std::vector<OtherRole> alone;             // roles with this placer first, the others later
    if (placesRelated(r)) {
      while (chain->index[chain_pos] != static_cast<int>(ri)) ++chain_pos;
      placer = chain->placers[chain_pos];
      joint = hardUpTo(chain_pos);
      if (n_placers > 1) alone = chain->alone(chain_pos);
    }
    // No entity of the related class and look in the world (pedestrians, a colour no parked
    // car has): no place meets it through the world, and nothing is measured.
    bool in_world = false;
    for (const auto& e : world.entities()) {
      in_world = in_world ||
                 (scenario::operatorApplies(r.op, e.cls) && r.matchesRelated(e.cls, e.attributes));
    }
    std::optional<EventualOnLane> eventual;
    if (r.eventually) eventual.emplace(eval, world, r, base.car_speed.max);
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      if (eventual) {
        // After t = 0, along the first street the car drives.
        const scenario::LaneDrive drive =
            route ? scenario::routeStartDrive(
                        world, route_starts_[static_cast<std::size_t>(pairs[k].first)])
                  : scenario::pursuitDrive(world, pairs[k].first);
        mask[k] = in_world && eventual->holds(boxAt(pairs[k]), drive);
        fail_mask[k] = !mask[k];  // EVENTUALLY_* is hard only
        continue;
      }
      if (in_world && (k == 0 || pairs[k].first != pairs[k - 1].first)) {
        candidates = relatedNear(world, r, boxAt({pairs[k].first, 0}).center2(),
                                 base.relations.radius + 0.5 * max_diagonal);
      }
      const OrientedBox box = boxAt(pairs[k]);
      const bool in_scene = in_world && holdsAmong(eval, world, r, box, candidates);
      bool holds = in_scene;
      // Constructed: a car or pedestrian that the generator places beside the target.
      if (placer && r.probability == 1.0 && joint.second > 1) {
        // After the earlier hard placers: met with their entities in the scene, or placed.
        std::vector<scenario::RelatedOption> placed;
        long budget = PlacerChain::kBudget;
        holds = chain->complete(0, box, &placed, joint.first, &budget);
      } else if (!holds && placer) {
        // Alone: the other placers place later (their joint outcome: the combinations below).
        holds = !placer->options(box, true, {}, alone).empty();
      }
      mask[k] = holds != r.negated;
      fail_mask[k] = placer ? !in_scene : !mask[k];
    }
    if (r.probability < 1.0) {
      if (placer) placer_soft_[chain_pos] = static_cast<int>(soft_.size());
      soft_.push_back(static_cast<int>(ri));
      soft_masks.push_back(std::move(mask));
      soft_fail_masks.push_back(std::move(fail_mask));
      continue;
    }
    const long long before = count(pairs.size());
    std::vector<std::pair<int, int>> kept;
    std::vector<std::vector<char>> kept_soft(soft_masks.size()), kept_fail(soft_masks.size());
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      if (!mask[k]) continue;
      kept.push_back(pairs[k]);
      for (std::size_t j = 0; j < soft_masks.size(); ++j) {
        kept_soft[j].push_back(soft_masks[j][k]);
        kept_fail[j].push_back(soft_fail_masks[j][k]);
      }
    }
    if (kept.empty()) refuse(r.pos, r.text, before);
    pairs = std::move(kept);
    soft_masks = std::move(kept_soft);
    soft_fail_masks = std::move(kept_fail);
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
        ok = ((bits >> j) & 1U) != 0 ? soft_masks[j][k] != 0 : soft_fail_masks[j][k] != 0;
      }
      if (ok && n_placers > 1) {
        // The placers of this combination together, each leaving the others' outcomes.
        const std::vector<char> active = activePlacers(bits);
        if (std::find(active.begin(), active.end(), 1) != active.end()) {
          std::vector<scenario::RelatedOption> placed;
          long budget = PlacerChain::kBudget;
          ok = chain->complete(0, boxAt(pairs[k]), &placed, active, &budget);
        }
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

std::vector<char> CompiledSpec::activePlacers(std::size_t bits) const {
  std::vector<char> active(placer_soft_.size());
  for (std::size_t j = 0; j < placer_soft_.size(); ++j) {
    active[j] = placer_soft_[j] < 0 || ((bits >> placer_soft_[j]) & 1U) != 0;
  }
  return active;
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
  std::map<std::string, double> drawn;
  for (const auto& [key, dist] : spec_.settings) {
    double v = dist.draw(unit());
    if (!dist.integer) v = scenario::roundMilli(v);
    applySetting(key, v, spec_.cls, &d.config, &d.plan);
    prov.values.emplace_back(key, v);
    drawn[key] = v;
  }
  for (const auto& k : spec_.kozs) d.plan.kozs.push_back(drawnKoz(k, drawn));
  std::size_t bits = 0;
  for (std::size_t j = 0; j < soft_.size(); ++j) {
    const auto& r = spec_.requirements[static_cast<std::size_t>(soft_[j])];
    const bool holds = unit() < r.probability;
    if (holds) bits |= std::size_t{1} << j;
    prov.values.emplace_back("prefer " + r.text, holds);
  }
  if (placed_ || !route_starts_.empty()) d.plan.placements = &combos_[bits];
  if (!route_starts_.empty()) d.plan.route_starts = &route_starts_;
  for (const auto& r : spec_.requirements) {
    if (!r.eventually || r.related == EntityClass::kPedestrian) continue;
    d.plan.eventually.push_back({r.op, [r](EntityClass c, const scenario::Attributes& a) {
                                   return r.matchesRelated(c, a);
                                 }});
  }
  if (spec_.confusers.have_share) d.plan.confuser_share = spec_.confusers.share;
  if (spec_.confusers.told_apart >= 0) {
    const Requirement r = spec_.requirements[static_cast<std::size_t>(spec_.confusers.told_apart)];
    d.plan.confuser_told_apart = [r, ev = told_eval_](const OrientedBox& box) {
      return worldRelationHoldsPruned(*ev, ev->world(), r, box) == r.negated;
    };
  }
  // A soft placing requirement drawn to fail places nothing (its pairs have no such entity).
  const std::vector<char> active = activePlacers(bits);
  if (std::find(active.begin(), active.end(), 1) != active.end()) {
    d.plan.related = [c = chain_, active](const OrientedBox& box, scenario::Rng& rng) {
      return c->draw(box, active, rng);
    };
  }
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
  if (spec.target.within > 0 &&
      !withinLandmark(world, spec.target.within_of, spec.target.within, box.center2())) {
    fail("target " + t.entity.id + " is not " + withinText(spec.target));
  }
  scenario::RelationEvaluator eval(world, base.relations);
  for (const auto& se : sim.entities) {
    if (se.trajectory.empty() && se.entity.id != t.entity.id)
      eval.addOccluder(se.entity.id, se.entity.box);
  }
  const double dt = base.relations.eventually_dt;
  for (const auto& r : spec.requirements) {
    bool exists = false;
    const bool mover = r.related == EntityClass::kCar || r.related == EntityClass::kPedestrian;
    if (r.eventually && !mover) {
      // Some world entity of the class and look that is not so related at t = 0 is at a later
      // sample of the target's trajectory, within the mission's time.
      scenario::Subject ts;
      ts.id = t.entity.id;
      ts.cls = t.entity.cls;
      ts.attributes = &t.entity.attributes;
      ts.box = box;
      const scenario::Subject s0 = ts;
      std::map<int, bool> at0;
      for (int k = 1; k * dt <= mission.time_limit && !exists && !t.trajectory.empty(); ++k) {
        ts.box = scenario::poseBox(t.entity.box, scenario::sampleTrajectory(t.trajectory, k * dt));
        for (const auto& [i, d] : eval.nearbyWorldDistances(ts.box)) {
          const scenario::Entity& e = world.entities()[static_cast<std::size_t>(i)];
          if (!r.matchesRelated(e.cls, e.attributes)) continue;
          const scenario::Subject rel = scenario::worldSubject(world, i);
          if (!eval.holds(r.op, eval.measure(ts, rel), e.cls)) continue;
          auto it = at0.find(i);
          if (it == at0.end())
            it = at0.emplace(i, eval.holds(r.op, eval.measure(s0, rel), e.cls)).first;
          if (!it->second) {
            exists = true;
            break;
          }
        }
      }
    } else if (r.eventually) {
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
      // Cars and pedestrians of the scenario that stand still (parked cars, standing
      // pedestrians) relate to the target at t = 0 like the world's own.
      if (r.related == EntityClass::kCar || r.related == EntityClass::kPedestrian) {
        scenario::Subject ts;
        ts.id = t.entity.id;
        ts.cls = t.entity.cls;
        ts.attributes = &t.entity.attributes;
        ts.box = box;
        for (const auto& se : sim.entities) {
          if (exists || !se.trajectory.empty() || se.entity.id == t.entity.id ||
              !r.matchesRelated(se.entity.cls, se.entity.attributes))
            continue;
          scenario::Subject rs;
          rs.id = se.entity.id;
          rs.cls = se.entity.cls;
          rs.attributes = &se.entity.attributes;
          rs.box = se.entity.box;
          exists = eval.holds(r.op, eval.measure(ts, rs), rs.cls);
        }
      }
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
    if (require_listed && r.eventually && !mover) {
      bool listed = false;
      for (const auto& rel : mission.relations) {
        listed = listed || (rel.target_id == t.entity.id && rel.op == r.op && rel.eventually &&
                            r.matchesRelated(r.related, rel.related_attributes) &&
                            rel.related_class == scenario::toString(r.related));
      }
      if (!listed) fail("requirement '" + r.text + "' holds but the mission does not list it");
    }
  }
  // Look-alikes: what they share with the target, how far they park, and the requirement that
  // tells them apart (measured against the world, as the sampler places them).
  const ConfuserSpec& cs = spec.confusers;
  const Distribution* within = spec.setting("confusers.within");
  if (cs.have_share || cs.told_apart >= 0 || within) {
    const scenario::RelationEvaluator world_eval(world, base.relations);
    std::optional<double> within_drawn;
    if (sim.spec) {
      for (const auto& [name, v] : sim.spec->values) {
        if (name == "confusers.within" && std::holds_alternative<double>(v))
          within_drawn = std::get<double>(v);
      }
    }
    for (const auto& se : sim.entities) {
      if (se.role != "confuser") continue;
      const std::string& id = se.entity.id;
      if (cs.have_share) {
        for (const char* k : {"vehicle_class", "make", "model", "color"}) {
          const bool same = se.entity.attributes.str(k) == t.entity.attributes.str(k);
          const bool want = std::find(cs.share.begin(), cs.share.end(), k) != cs.share.end();
          if (same != want) {
            fail("confuser " + id + ": " + k + " '" + se.entity.attributes.str(k) + "' " +
                 (want ? "differs from" : "is") + " the target's" + (want ? "" : " (not shared)"));
          }
        }
      }
      if (within) {
        const double far = (se.entity.box.center2() - box.center2()).norm();
        const double limit = within_drawn ? *within_drawn : within->maxValue();
        if (far > limit + 1e-3) {
          char buf[160];
          std::snprintf(
              buf, sizeof(buf),
              "confusers.within: confuser %s parks %.3f m from the target, expected at most %.3f",
              id.c_str(), far, limit);
          fail(buf);
        }
      }
      if (cs.told_apart >= 0) {
        const Requirement& r = spec.requirements[static_cast<std::size_t>(cs.told_apart)];
        if (worldRelationHoldsReference(world_eval, world, r, se.entity.box) != r.negated) {
          fail("confuser " + id + " meets '" + r.text + "', which should tell it apart");
        }
      }
    }
  }
  // Keep-out zones: each koz statement's zones, recomputed from the scene (the target's
  // position at t = 0, the world's entities) with the values the sampler recorded, must be in
  // the mission with their purpose, altitude band and window.
  // (Not for a rejection sampler's judgement, require_listed false: zones are added, not found.)
  std::size_t spec_zones = 0;  // of mission.kozs: the koz statements' (not the class's own)
  if (!spec.kozs.empty() && require_listed) {
    std::map<std::string, double> recorded;
    if (sim.spec) {
      for (const auto& [name, v] : sim.spec->values) {
        if (std::holds_alternative<double>(v)) recorded[name] = std::get<double>(v);
      }
    }
    auto same = [](const std::optional<double>& a, const std::optional<double>& b) {
      return a.has_value() == b.has_value() && (!a || std::abs(*a - *b) <= 1e-3);
    };
    for (const auto& k : spec.kozs) {
      const scenario::ScenarioPlan::Koz z = drawnKoz(k, recorded);
      const std::string what = "koz " + k.purpose + " over " + k.over +
                               (k.aoi > 0 ? " " + std::to_string(k.aoi) : std::string());
      const auto want = scenario::specKozPolygons(world, z, box, mission.aois);
      if (want.empty()) {
        fail(what +
             (k.aoi > 0 ? ": no such AOI in the mission" : ": no " + k.over + " in this world"));
      }
      spec_zones += want.size();
      for (const auto& poly : want) {
        bool found = false;
        for (const auto& m : mission.kozs) {
          if (found || m.purpose != k.purpose || !same(m.alt_min, z.alt_min) ||
              !same(m.alt_max, z.alt_max) || !same(m.window.net, z.net) ||
              !same(m.window.nlt, z.nlt) || m.polygon.size() != poly.size())
            continue;
          bool match = true;
          for (std::size_t i = 0; i < poly.size() && match; ++i) {
            match = (m.polygon.vertices()[i] - poly.vertices()[i]).norm() <= 0.01;
          }
          found = match;
        }
        if (!found) {
          const Vec2 c = poly.bounds().min * 0.5 + poly.bounds().max * 0.5;
          char buf[96];
          std::snprintf(buf, sizeof(buf), " (zone centred at %.2f, %.2f)", c.x(), c.y());
          fail(what + ": no such keep-out zone in the mission" + buf);
        }
      }
      for (const char* name : {"count", "size", "margin", "alt_min", "alt_max", "net", "nlt"}) {
        const std::string key = k.key + "." + name;
        const Distribution* d = spec.setting(key);
        if (!d) continue;
        auto it = recorded.find(key);
        if (it == recorded.end()) {
          fail(what + ": " + name + " not recorded in the spec block");
        } else if (!d->contains(it->second)) {
          char buf[64];
          std::snprintf(buf, sizeof(buf), "%.6g", it->second);
          fail(what + ": " + name + " " + buf + " is outside " + d->text());
        }
      }
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
    atMost("kozs.count", mission.kozs.size() - std::min(spec_zones, mission.kozs.size()));
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
