#include "hameritt/generation/generator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>

#include "hameritt/generation/avoid.h"
#include "hameritt/generation/target_slots.h"
#include "hameritt/geometry/segment.h"
#include "hameritt/planning/chase.h"
#include "hameritt/planning/look_at.h"
#include "hameritt/planning/validity.h"
#include "hameritt/planning/vehicle_routes.h"
#include "hameritt/scenario/catalog.h"
#include "hameritt/scenario/city_traffic.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/scenario/signal_compliance.h"
#include "hameritt/scenario/traffic_clearance.h"
#include "hameritt/scenario/trajectory.h"

namespace hameritt::scenario {

using geometry::OrientedBox;
using geometry::Polygon;
using geometry::TimeWindow;
using geometry::Vec2;
using geometry::Vec3;

std::string scenarioId(ScenarioClass cls, std::uint64_t seed) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%s-%016llx", toString(cls),
                static_cast<unsigned long long>(seed));
  return buf;
}

std::uint64_t batchSeed(std::uint64_t seed, std::uint64_t index) {
  return deriveSeed(seed, 0x5343454E00000000ULL + index);
}

namespace {

// The seed of a city scenario's traffic draw (drawCityTraffic).
std::uint64_t cityTrafficSeed(std::uint64_t seed) {
  return deriveSeed(seed, 0x4349545954524146ULL);
}

}  // namespace

int cityScenarioEpisode(const World& world, std::uint64_t seed) {
  return drawCityTrafficEpisode(world, cityTrafficSeed(seed));
}

// Draw order: every random draw is its own statement. C++ leaves the order in which a call's
// arguments (or an expression's operands) are evaluated to the compiler, so two draws in one call
// give g++ and clang different scenarios from one seed. Where draws once shared a call they are
// now taken in the order g++ evaluated them (right to left), which the golden files pin.
namespace {

constexpr int kMaxAttempts = 200;
// Avoid: the goal's distance from the start (m), its radius, the fraction of the top speed that
// sets the time limit (the reference flight at this speed, plus a minute), and the escorted
// zone around the hostile vehicle (side, and how near the start and goal its centre may come).
constexpr double kAvoidGoalDistanceMin = 250.0;
constexpr double kAvoidGoalDistanceMax = 450.0;
constexpr double kAvoidGoalRadius = 5.0;
constexpr double kAvoidNominalSpeedFraction = 0.35;
constexpr double kEscortSide = 30.0;
constexpr double kEscortClearance = 36.0;  // half the diagonal plus 15 m

Vec2 round2(const Vec2& v) { return {roundMilli(v.x()), roundMilli(v.y())}; }

Polygon roundPolygon(const Polygon& p) {
  std::vector<Vec2> v;
  v.reserve(p.size());
  for (const auto& q : p.vertices()) v.push_back(round2(q));
  return Polygon(v);
}

double rangeDraw(Rng& rng, const Range& r) {
  return r.max > r.min ? rng.uniform(r.min, r.max) : r.min;
}

class ScenarioBuilder {
 public:
  ScenarioBuilder(const World& world, const GeneratorConfig& cfg, ScenarioClass cls,
                  std::uint64_t seed, const ScenarioPlan* plan, bool traffic_by_reference)
      : world_(world),
        cfg_(cfg),
        cls_(cls),
        seed_(seed),
        rng_(seed),
        eval_(world, cfg.relations),
        plan_(plan),
        traffic_by_reference_(traffic_by_reference) {
    slot_taken_.assign(world.slots().size(), 0);
    for (std::size_t i = 0; i < world.slots().size(); ++i) {
      if (world.slots()[i].occupant >= 0) slot_taken_[i] = 1;
    }
    int world_cars = 0, world_peds = 0;
    for (const auto& e : world.entities()) {
      if (e.cls == EntityClass::kCar) ++world_cars;
      if (e.cls == EntityClass::kPedestrian) ++world_peds;
    }
    // Scenario ids are drawn from a shuffled pool so that neither order nor number reveals a role.
    const bool city = world.params().type == WorldType::kCity;
    const int car_pool = 96 + (city ? cityCarBound(world) : 0);
    const int ped_pool = 48 + (city ? cityPedestrianBound(world) : 0);
    for (int i = 1; i <= car_pool; ++i) car_ids_.push_back(world_cars + i);
    for (int i = 1; i <= ped_pool; ++i) ped_ids_.push_back(world_peds + i);
    rng_.shuffle(car_ids_);
    rng_.shuffle(ped_ids_);
  }

  Scenario build() {
    Mission& m = sc_.mission;
    SimConfig& s = sc_.sim;
    m.scenario_id = s.scenario_id = scenarioId(cls_, seed_);
    m.cls = s.cls = cls_;
    m.seed = s.seed = seed_;
    m.origin = cfg_.origin;
    s.world = world_.params();
    s.world_fingerprint = world_.fingerprint();
    drawUav();
    switch (cls_) {
      case ScenarioClass::kAreaSearch:
        buildAreaSearch();
        break;
      case ScenarioClass::kRouteSearch:
        buildRouteSearch();
        break;
      case ScenarioClass::kPursuit:
        buildPursuit();
        break;
      case ScenarioClass::kAvoid:
        buildAvoid();  // places the UAV itself, at the start of its reference flight
        break;
      case ScenarioClass::kFollow:
        buildFollow();
        break;
      case ScenarioClass::kTrack:
        buildTrack();
        break;
    }
    if (plan_ && !plan_->kozs.empty()) addSpecKozs();
    if (cls_ != ScenarioClass::kAvoid) placeUavStart();
    if (world_.params().type == WorldType::kCity) {
      addCityTraffic();
    } else {
      addTraffic();
    }
    drawEnvironment();
    s.duration = m.time_limit;
    finalizeRelations();
    finishGroups();
    if (cfg_.perception_paths && cls_ != ScenarioClass::kAvoid) planPerceptionPath();
    if (plan_ && plan_->provenance) sc_.sim.spec = plan_->provenance;
    return std::move(sc_);
  }

 private:
  // ------------------------------------------------------------------ entities
  std::string nextCarId() {
    const int n = car_ids_.back();
    car_ids_.pop_back();
    return "car_" + std::to_string(n);
  }
  std::string nextPedId() {
    const int n = ped_ids_.back();
    ped_ids_.pop_back();
    return "pedestrian_" + std::to_string(n);
  }

  Entity makeCar(const catalog::CarModel& model, const std::string& color, const Vec3& bottom,
                 double yaw) {
    Entity e;
    e.id = nextCarId();
    e.cls = EntityClass::kCar;
    e.attributes.set("vehicle_class", model.vehicle_class);
    e.attributes.set("make", model.make);
    e.attributes.set("model", model.model);
    e.attributes.set("color", color);
    e.box = boxFromPose(
        Vec3(roundMilli(bottom.x()), roundMilli(bottom.y()), roundMilli(bottom.z())),
        roundMilli(geometry::wrapPi(yaw)), Vec3(model.length, model.width, model.height));
    e.block = world_.blockAt(e.box.center2());
    return e;
  }

  Entity parkCar(int slot, const catalog::CarModel& model, const std::string& color) {
    const auto& sl = world_.slots()[static_cast<std::size_t>(slot)];
    slot_taken_[static_cast<std::size_t>(slot)] = 1;
    return makeCar(model, color, Vec3(sl.position.x(), sl.position.y(), sl.ground_z), sl.yaw);
  }

  ScenarioEntity& add(Entity e, const std::string& role, Trajectory traj = {}) {
    ScenarioEntity se;
    se.entity = std::move(e);
    se.role = role;
    se.trajectory = std::move(traj);
    if (se.trajectory.empty()) eval_.addOccluder(se.entity.id, se.entity.box);
    sc_.sim.entities.push_back(std::move(se));
    return sc_.sim.entities.back();
  }

  Subject subjectOf(const Entity& e) const {
    Subject s;
    s.id = e.id;
    s.cls = e.cls;
    s.attributes = &e.attributes;
    s.box = e.box;
    return s;
  }

  // Parked scenario cars other than `except`, as relation subjects.
  std::vector<Subject> parkedSubjects(const std::string& except) const {
    std::vector<Subject> out;
    for (const auto& se : sc_.sim.entities) {
      if (se.trajectory.empty() && se.entity.id != except) out.push_back(subjectOf(se.entity));
    }
    return out;
  }

  // A free slot satisfying `ok`, or -1.
  template <typename Pred>
  int pickSlot(Pred ok, bool kerb_only = false) {
    const auto& slots = world_.slots();
    for (int attempt = 0; attempt < 4 * kMaxAttempts; ++attempt) {
      const int i = static_cast<int>(rng_.uniformInt(0, static_cast<long>(slots.size()) - 1));
      if (slot_taken_[static_cast<std::size_t>(i)]) continue;
      if (kerb_only && slots[static_cast<std::size_t>(i)].driveway) continue;
      if (ok(slots[static_cast<std::size_t>(i)])) return i;
    }
    return -1;
  }

  // ------------------------------------------------------------------ routes and motion
  // A random walk of `n` street edges from `start` without turning back or reusing a node
  // (nor visiting `avoid`).
  std::vector<int> randomWalk(int start, int n, int avoid = -1) {
    std::vector<int> nodes{start};
    std::set<int> seen{start, avoid};
    while (static_cast<int>(nodes.size()) <= n) {
      std::vector<int> next;
      for (int ei : world_.adjacency()[static_cast<std::size_t>(nodes.back())]) {
        const auto& e = world_.edges()[static_cast<std::size_t>(ei)];
        const int other = e.a == nodes.back() ? e.b : e.a;
        if (!seen.count(other)) next.push_back(other);
      }
      if (next.empty()) break;
      const int pick = rng_.pick(next);
      nodes.push_back(pick);
      seen.insert(pick);
    }
    return nodes;
  }

  // True for points at least 20 m inside the neighborhood, where an AOI around them fits.
  bool wellInside(const Vec2& p) const { return insideBy20(world_, p); }

  int randomNode() {
    return static_cast<int>(rng_.uniformInt(0, static_cast<long>(world_.nodes().size()) - 1));
  }

  std::vector<Vec2> nodePositions(const std::vector<int>& nodes) const {
    std::vector<Vec2> out;
    for (int n : nodes) out.push_back(world_.nodes()[static_cast<std::size_t>(n)].position);
    return out;
  }

  DriveSpec driveSpec(double speed) const {
    DriveSpec d;
    d.lane_offset = 0.5 * world_.params().street_width - kLaneOffsetFromKerb;
    d.corner_clearance = 0.5 * world_.params().street_width + 1.0;
    d.cruise_speed = speed;
    return d;
  }

  // Vehicle routes with the same lane and corner clearance as driveSpec().
  planning::RouteSettings routeSettings() const {
    planning::RouteSettings r;
    r.lane_offset = 0.5 * world_.params().street_width - kLaneOffsetFromKerb;
    r.corner_clearance = 0.5 * world_.params().street_width + 1.0;
    return r;
  }

  static planning::SpeedProfile speedProfile(double cruise) {
    planning::SpeedProfile p;
    p.cruise_speed = cruise;
    return p;
  }

  // A random node `hops` street edges from `from` (breadth first, never through `avoid`), or
  // the farthest reachable ones when none is that far; -1 when nothing is reachable.
  int nodeAtHops(int from, int avoid, int hops) {
    std::vector<int> dist(world_.nodes().size(), -1);
    std::vector<int> queue{from};
    dist[static_cast<std::size_t>(from)] = 0;
    if (avoid >= 0) dist[static_cast<std::size_t>(avoid)] = -2;
    for (std::size_t q = 0; q < queue.size(); ++q) {
      const int u = queue[q];
      for (int ei : world_.adjacency()[static_cast<std::size_t>(u)]) {
        const auto& e = world_.edges()[static_cast<std::size_t>(ei)];
        const int v = e.a == u ? e.b : e.a;
        if (dist[static_cast<std::size_t>(v)] != -1) continue;
        dist[static_cast<std::size_t>(v)] = dist[static_cast<std::size_t>(u)] + 1;
        queue.push_back(v);
      }
    }
    const int reach = std::min(hops, dist[static_cast<std::size_t>(queue.back())]);
    if (reach <= 0) return -1;
    std::vector<int> at;
    for (int v : queue) {
      if (dist[static_cast<std::size_t>(v)] == reach) at.push_back(v);
    }
    return rng_.pick(at);
  }

  // The rounded pose `s` metres along a street from `a` in direction `dir`, in the lane.
  static TrajectoryPoint lanePose(const Vec2& a, const Vec2& dir, double s, double lane_offset,
                                  double t) {
    const Vec2 p = a + dir * s + Vec2(dir.y(), -dir.x()) * lane_offset;
    return {t, roundMilli(p.x()), roundMilli(p.y()), 0.0, roundMilli(std::atan2(dir.y(), dir.x()))};
  }

  // ------------------------------------------------------------------ constraints
  AreaOfInterest makeAoi(const std::string& id, const Vec2& contains, double yaw, double len,
                         double wid) {
    AreaOfInterest a;
    a.id = id;
    const Vec2 ax(std::cos(yaw), std::sin(yaw)), ay(-std::sin(yaw), std::cos(yaw));
    const auto b = world_.bounds();
    const double hx = 0.5 * (std::abs(len * ax.x()) + std::abs(wid * ay.x()));
    const double hy = 0.5 * (std::abs(len * ax.y()) + std::abs(wid * ay.y()));
    // The point sits off-centre; the AOI is kept inside the neighborhood where that still
    // contains the point, else centred on it.
    for (int attempt = 0; attempt < 10; ++attempt) {
      const double ox = rng_.uniform(-0.4, 0.4) * len, oy = rng_.uniform(-0.4, 0.4) * wid;
      Vec2 c = contains - ox * ax - oy * ay;
      c.x() = std::clamp(c.x(), b.min.x() + hx, std::max(b.min.x() + hx, b.max.x() - hx));
      c.y() = std::clamp(c.y(), b.min.y() + hy, std::max(b.min.y() + hy, b.max.y() - hy));
      a.polygon = roundPolygon(geometry::orientedRectangle(c, len, wid, yaw));
      if (a.polygon.contains(contains) && a.polygon.boundaryDistance(contains) > 5.0) return a;
    }
    // Near the edge of the neighborhood: keep the off-centre placement (so the point does not
    // fall on a prior-cell corner) and let the AOI reach past the edge.
    const double ox = rng_.uniform(0.1, 0.35) * len, oy = rng_.uniform(0.1, 0.35) * wid;
    a.polygon =
        roundPolygon(geometry::orientedRectangle(contains - ox * ax - oy * ay, len, wid, yaw));
    return a;
  }

  // Sub-quadrant grid of a rectangular AOI (vertices 0..3 counter-clockwise from the
  // local (-x,-y) corner), with the target's cell (if any) holding the highest prior.
  AreaPrior makePrior(const AreaOfInterest& aoi, const Vec2* target) {
    AreaPrior p;
    p.aoi_id = aoi.id;
    p.depth = static_cast<int>(rng_.uniformInt(cfg_.prior_depth_min, cfg_.prior_depth_max));
    const int n = 1 << p.depth;
    const auto& v = aoi.polygon.vertices();
    const Vec2 o = v[0], ex = v[1] - v[0], ey = v[3] - v[0];
    std::vector<Vec2> grid;
    for (int r = 0; r <= n; ++r) {
      for (int c = 0; c <= n; ++c)
        grid.push_back(round2(o + (double(c) / n) * ex + (double(r) / n) * ey));
    }
    auto g = [&](int r, int c) { return grid[static_cast<std::size_t>(r * (n + 1) + c)]; };
    std::vector<double> w;
    int target_cell = -1;
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) {
        PriorCell cell;
        char id[64];
        std::snprintf(id, sizeof(id), "%s_r%dc%d", aoi.id.c_str(), r, c);
        cell.id = id;
        cell.row = r;
        cell.col = c;
        cell.polygon = Polygon({g(r, c), g(r, c + 1), g(r + 1, c + 1), g(r + 1, c)});
        if (target && target_cell < 0 && cell.polygon.contains(*target)) {
          target_cell = static_cast<int>(p.cells.size());
        }
        p.cells.push_back(cell);
        w.push_back(rng_.uniform(0.2, 1.0));
      }
    }
    if (target_cell >= 0) {
      const double mx = *std::max_element(w.begin(), w.end());
      w[static_cast<std::size_t>(target_cell)] = mx * rng_.uniform(1.4, 2.5);
    }
    double sum = 0;
    for (double x : w) sum += x;
    // Probabilities in units of 1e-4, summing to exactly 10000 units.
    std::vector<long> units;
    long total = 0;
    for (double x : w) {
      units.push_back(std::lround(x / sum * 10000.0));
      total += units.back();
    }
    const std::size_t fix = target_cell >= 0
                                ? static_cast<std::size_t>(target_cell)
                                : static_cast<std::size_t>(
                                      std::max_element(units.begin(), units.end()) - units.begin());
    units[fix] += 10000 - total;
    for (std::size_t i = 0; i < units.size(); ++i) p.cells[i].probability = units[i] / 10000.0;
    return p;
  }

  KeepOutZone makeKoz(const Polygon& poly, const std::string& purpose) {
    KeepOutZone k;
    k.id = "koz_" + std::to_string(sc_.mission.kozs.size() + 1);
    k.polygon = roundPolygon(poly);
    k.purpose = purpose;
    return k;
  }

  // ------------------------------------------------------------------ relations
  // Picks the mission's relations for a target from every true one, with per-operator caps
  // so that the description mixes surface, direction, proximity and membership facts.
  std::vector<SceneRelation> selectRelations(std::vector<SceneRelation> all) {
    rng_.shuffle(all);
    std::map<std::string, int> caps = {
        {"ON_TOP_OF", 1},     {"NOT_ON_TOP_OF", 1}, {"PART_OF", 1},
        {"LEFT_OF", 1},       {"RIGHT_OF", 1},      {"IN_FRONT_OF", 1},
        {"ORTHOGONAL_TO", 1}, {"NEXT_TO", 2},       {"NOT_NEXT_TO", 1}};
    std::vector<SceneRelation> out;
    std::set<std::string> used;
    // Membership and surface first (always informative), then the rest in random order.
    std::stable_partition(all.begin(), all.end(), [](const SceneRelation& r) {
      return r.op == RelationOp::kPartOf || r.op == RelationOp::kOnTopOf;
    });
    // A relation and its negation about look-alike related entities (same class and
    // attributes) would read as a contradiction to a client: keep only the first.
    auto contradicts = [&](const SceneRelation& r) {
      for (const auto& o : out) {
        const bool negation = (o.op == RelationOp::kNextTo && r.op == RelationOp::kNotNextTo) ||
                              (o.op == RelationOp::kNotNextTo && r.op == RelationOp::kNextTo) ||
                              (o.op == RelationOp::kOnTopOf && r.op == RelationOp::kNotOnTopOf) ||
                              (o.op == RelationOp::kNotOnTopOf && r.op == RelationOp::kOnTopOf);
        if (negation && o.related_class == r.related_class &&
            o.related_attributes == r.related_attributes) {
          return true;
        }
      }
      return false;
    };
    for (auto& r : all) {
      if (static_cast<int>(out.size()) >= cfg_.relations.max_relations) break;
      const std::string name = toString(r.op, r.eventually);
      auto it = caps.find(name);
      if (it == caps.end() || it->second <= 0) continue;
      if (used.count(r.related_id + name) || contradicts(r)) continue;
      --it->second;
      used.insert(r.related_id + name);
      out.push_back(std::move(r));
    }
    return out;
  }

  // The spec's hard requirements are listed in the description: each one missing from `rels`
  // is taken from `all` (every true relation) and put first, within max_relations.
  void ensureListed(std::vector<SceneRelation>* rels, const std::vector<SceneRelation>& all) {
    if (!plan_) return;
    std::vector<SceneRelation> forced;
    for (const auto& pred : plan_->listed) {
      bool have = false;
      for (const auto& r : *rels) have = have || pred(r);
      for (const auto& r : forced) have = have || pred(r);
      if (have) continue;
      for (const auto& r : all) {
        if (pred(r)) {
          forced.push_back(r);
          break;
        }
      }
    }
    if (forced.empty()) return;
    const std::size_t keep = static_cast<std::size_t>(
        std::max<int>(0, cfg_.relations.max_relations - static_cast<int>(forced.size())));
    // Drop from the end, sparing the relations that another requirement listed.
    auto listed = [&](const SceneRelation& r) {
      for (const auto& pred : plan_->listed) {
        if (pred(r)) return true;
      }
      return false;
    };
    for (std::size_t i = rels->size(); i-- > 0 && rels->size() > keep;) {
      if (!listed((*rels)[i])) rels->erase(rels->begin() + static_cast<std::ptrdiff_t>(i));
    }
    if (rels->size() > keep) rels->resize(keep);
    rels->insert(rels->begin(), forced.begin(), forced.end());
  }

  // EVENTUALLY_* relations of a moving target: the first sample time (on the eventually_dt
  // grid) at which NEXT_TO, LEFT_OF or RIGHT_OF holds with a static entity it did not hold
  // with at t = 0. Stops after `want` relations.
  std::vector<SceneRelation> eventuallyRelations(const Entity& target, const Trajectory& traj,
                                                 const std::vector<SceneRelation>& at_start,
                                                 int want) {
    std::vector<SceneRelation> out;
    constexpr RelationOp kOps[] = {RelationOp::kNextTo, RelationOp::kLeftOf, RelationOp::kRightOf};
    // The sideways operators already seen per related id (bit j for kOps[j]): those holding at
    // t = 0, then those found. Each world and parked entity finds its entry once and keeps a
    // pointer to it (entries are never moved or erased); entities sharing an id share it.
    std::unordered_map<std::string, unsigned char> seen;
    for (const auto& r : at_start) {
      for (int j = 0; j < 3; ++j) {
        if (r.op == kOps[j]) seen[r.related_id] |= static_cast<unsigned char>(1 << j);
      }
    }
    const double dt = cfg_.relations.eventually_dt;
    const double end = traj.back().t;
    const std::vector<Subject> parked = parkedSubjects(target.id);
    // Entities whose three sideways operators are all seen: skipped by index.
    std::vector<char> world_done(world_.entities().size(), 0), parked_done(parked.size(), 0);
    std::vector<unsigned char*> world_seen(world_.entities().size(), nullptr);
    std::vector<unsigned char*> parked_seen(parked.size(), nullptr);
    for (int k = 1; k * dt <= end && static_cast<int>(out.size()) < want; ++k) {
      const double t = k * dt;
      Subject s = subjectOf(target);
      s.box = poseBox(target.box, sampleTrajectory(traj, t));
      // Returns true when all three operators are now seen with rel: then it never needs to
      // be considered again (seen only grows), which the callers remember by index.
      auto consider = [&](const Subject& rel, double distance, unsigned char** entry) {
        if (*entry == nullptr) *entry = &seen[rel.id];
        unsigned char& has = **entry;
        if (has == 7) return true;
        const RelationFacts f = eval_.measureSideways(s, rel, distance);
        for (int j = 0; j < 3; ++j) {
          const RelationOp op = kOps[j];
          if ((has & (1 << j)) != 0 || !eval_.holds(op, f, rel.cls)) continue;
          has |= static_cast<unsigned char>(1 << j);
          if (rel.cls == EntityClass::kStreet || rel.cls == EntityClass::kFence) continue;
          SceneRelation r = makeRelation(s, rel, op, f);
          r.eventually = true;
          r.time = t;
          out.push_back(r);
        }
        return has == 7;
      };
      for (const auto& [i, d] : eval_.nearbyWorldDistances(s.box)) {
        const auto w = static_cast<std::size_t>(i);
        if (!world_done[w] && consider(worldSubject(world_, i), d, &world_seen[w])) {
          world_done[w] = 1;
        }
      }
      for (std::size_t j = 0; j < parked.size(); ++j) {
        if (parked_done[j]) continue;
        const double d = geometry::footprintDistance(s.box, parked[j].box);
        if (d <= cfg_.relations.radius && consider(parked[j], d, &parked_seen[j])) {
          parked_done[j] = 1;
        }
      }
    }
    if (static_cast<int>(out.size()) > want) out.resize(static_cast<std::size_t>(want));
    return out;
  }

  // True when the confuser does not match the target's symbolic description: outside every
  // AOI that the target is in, or some listed relation fails for it.
  bool disambiguated(const Entity& confuser, const std::vector<SceneRelation>& rels,
                     const std::vector<const AreaOfInterest*>& target_aois) {
    for (const auto* a : target_aois) {
      if (!a->polygon.contains(confuser.box.center2())) return true;
    }
    const Subject c = subjectOf(confuser);
    const std::vector<Subject> parked = parkedSubjects(confuser.id);
    const std::vector<Group> groups = currentGroups();
    for (const auto& r : rels) {
      // A parked confuser and a static related entity keep their relation for all time, so the
      // static test also answers EVENTUALLY_*; moving related entities are checked over time.
      if (eval_.satisfiedBy(r, c, parked, groups)) continue;
      if (r.eventually && movingSatisfies(r, confuser)) continue;
      return true;
    }
    return false;
  }

  // True when a moving scenario entity of the relation's class and attributes satisfies it
  // with the (static) candidate at some sample time.
  bool movingSatisfies(const SceneRelation& r, const Entity& candidate) const {
    EntityClass cls;
    if (!parseEntityClass(r.related_class, &cls)) return false;
    const Subject c = subjectOf(candidate);
    const double dt = cfg_.relations.eventually_dt;
    for (const auto& se : sc_.sim.entities) {
      if (se.trajectory.empty() || se.entity.cls != cls ||
          !(se.entity.attributes == r.related_attributes))
        continue;
      for (int k = 1; k * dt <= sc_.mission.time_limit; ++k) {
        Subject m = subjectOf(se.entity);
        m.box = poseBox(se.entity.box, sampleTrajectory(se.trajectory, k * dt));
        if (eval_.holds(r.op, eval_.measure(c, m), cls)) return true;
      }
    }
    return false;
  }

  const ScenarioEntity* scenarioEntity(const std::string& id) const {
    for (const auto& se : sc_.sim.entities) {
      if (se.entity.id == id) return &se;
    }
    return nullptr;
  }

  // The subject of a world or scenario entity posed at time t, or false if unknown.
  bool subjectAt(const std::string& id, double t, Subject* out) const {
    const int w = world_.find(id);
    if (w >= 0) {
      *out = worldSubject(world_, w);
      return true;
    }
    const ScenarioEntity* se = scenarioEntity(id);
    if (!se) return false;
    *out = subjectOf(se->entity);
    if (!se->trajectory.empty())
      out->box = poseBox(se->entity.box, sampleTrajectory(se->trajectory, t));
    return true;
  }

  // Re-evaluates relation r at time t with the final scene; fills its evidence when it holds.
  bool holdsAt(SceneRelation* r, double t) const {
    Subject target, related;
    if (!subjectAt(r->target_id, t, &target) || !subjectAt(r->related_id, t, &related))
      return false;
    const RelationFacts f = eval_.measure(target, related);
    if (!eval_.holds(r->op, f, related.cls)) return false;
    r->distance = f.distance;
    r->bearing_deg = f.bearing_deg;
    r->dz = f.dz;
    r->line_of_sight = f.line_of_sight;
    return true;
  }

  // Final pass once every entity is placed: each listed relation is re-verified against the
  // finished scene (EVENTUALLY_* get their first grid time again), and a confuser that the
  // surviving description no longer tells apart from its target is removed. Repeats until
  // stable, since removing a confuser changes the occluders.
  void finalizeRelations() {
    Mission& m = sc_.mission;
    for (int round = 0; round < 4; ++round) {
      std::vector<SceneRelation> kept;
      const std::vector<Group> groups = currentGroups();
      for (SceneRelation r : m.relations) {
        if (r.op == RelationOp::kPartOf) {
          for (const auto& g : groups) {
            if (g.id == r.related_id &&
                std::find(g.members.begin(), g.members.end(), r.target_id) != g.members.end()) {
              kept.push_back(r);
            }
          }
          continue;
        }
        if (!r.eventually) {
          if (holdsAt(&r, 0.0)) kept.push_back(r);
          continue;
        }
        SceneRelation at0 = r;
        if (holdsAt(&at0, 0.0)) continue;
        const double dt = cfg_.relations.eventually_dt;
        for (int k = 1; k * dt <= m.time_limit; ++k) {
          if (holdsAt(&r, k * dt)) {
            r.time = k * dt;
            kept.push_back(r);
            break;
          }
        }
      }
      m.relations = kept;
      bool removed = false;
      std::vector<ScenarioEntity> entities;
      for (auto& se : sc_.sim.entities) {
        if (se.role == "confuser" && !confuserResolved(se.entity)) {
          eval_.removeOccluder(se.entity.id);
          removed = true;
          continue;
        }
        entities.push_back(std::move(se));
      }
      sc_.sim.entities = std::move(entities);
      if (!removed) break;
    }
  }

  // Whether a confuser is told apart from every target that shares its look.
  bool confuserResolved(const Entity& c) {
    for (const auto& se : sc_.sim.entities) {
      if (se.role != "target") continue;
      const auto& t = se.entity.attributes;
      if (t.str("make") != c.attributes.str("make") ||
          t.str("model") != c.attributes.str("model") ||
          t.str("color") != c.attributes.str("color")) {
        continue;
      }
      if (!sc_.mission.routes.empty()) {
        if (sc_.mission.routes.front().band.intersects(c.box.footprint())) return false;
        continue;
      }
      std::vector<const AreaOfInterest*> aois;
      for (const auto& a : sc_.mission.aois) {
        if (a.polygon.contains(se.entity.box.center2())) aois.push_back(&a);
      }
      std::vector<SceneRelation> rels;
      for (const auto& r : sc_.mission.relations) {
        if (r.target_id == se.entity.id) rels.push_back(r);
      }
      if (!disambiguated(c, rels, aois)) return false;
    }
    return true;
  }

  // Block groups as they stand now (membership by geometry), plus the scenario's own groups.
  std::vector<Group> currentGroups() const {
    std::vector<Group> out = extra_groups_;
    std::map<int, Group> blocks;
    for (const auto& se : sc_.sim.entities) {
      if (!se.trajectory.empty()) continue;
      const int b = world_.blockAt(se.entity.box.center2());
      if (b < 0) continue;
      Group& g = blocks[b];
      g.id = world_.blocks()[static_cast<std::size_t>(b)].name;
      g.kind = "block";
      g.members.push_back(se.entity.id);
    }
    for (auto& kv : blocks) out.push_back(kv.second);
    return out;
  }

  std::vector<const Group*> groupsOf(const std::string& id, const std::vector<Group>& groups) {
    std::vector<const Group*> out;
    for (const auto& g : groups) {
      if (std::find(g.members.begin(), g.members.end(), id) != g.members.end()) out.push_back(&g);
    }
    return out;
  }

  void addConfusers(const Entity& target, const std::vector<SceneRelation>& rels,
                    const std::vector<const AreaOfInterest*>& target_aois,
                    const Polygon* keep_out_of, double min_separation) {
    auto resolves = [&](const Entity& c) {
      if (keep_out_of) return !keep_out_of->intersects(c.box.footprint());
      return disambiguated(c, rels, target_aois);
    };
    const auto* model =
        catalog::findCarModel(target.attributes.str("make"), target.attributes.str("model"));
    std::string color = target.attributes.str("color");
    // A spec's share: the looks that share those attributes with the target and differ in the
    // others.
    std::vector<const catalog::CarModel*> share_models;
    std::vector<std::string> share_colors;
    const bool shared = plan_ && plan_->confuser_share;
    if (shared) {
      auto has = [&](const char* k) {
        return std::find(plan_->confuser_share->begin(), plan_->confuser_share->end(), k) !=
               plan_->confuser_share->end();
      };
      for (const auto& cm : catalog::carModels()) {
        const bool vc = cm.vehicle_class == target.attributes.str("vehicle_class");
        const bool mk = cm.make == target.attributes.str("make");
        const bool md = cm.model == target.attributes.str("model");
        if (vc == has("vehicle_class") && mk == has("make") && md == has("model"))
          share_models.push_back(&cm);
      }
      for (const auto& c : catalog::carColors()) {
        if ((c == color) == has("color")) share_colors.push_back(c);
      }
      if (share_models.empty() || share_colors.empty()) return;  // no such look-alike
    }
    const int n =
        static_cast<int>(rng_.uniformInt(cfg_.confuser_count_min, cfg_.confuser_count_max));
    for (int k = 0; k < n; ++k) {
      // Alternate: outside the AOI first, then inside it but without the described context.
      const bool want_inside = !target_aois.empty() && (k % 2 == 1);
      bool placed = false;
      for (int attempt = 0; attempt < 60 && !placed; ++attempt) {
        auto fits = [&](const ParkingSlot& sl) {
          if ((sl.position - target.box.center2()).norm() < min_separation) return false;
          if (keep_out_of && keep_out_of->distance(sl.position) < 8.0) return false;
          if (!target_aois.empty()) {
            const bool inside = target_aois.front()->polygon.contains(sl.position);
            if (inside != want_inside) return false;
          }
          return true;
        };
        int slot;
        if (plan_ && plan_->confuser_within) {
          // A spec's distance: drawn among every free place that close (no retries).
          std::vector<int> near;
          for (int i = 0; i < static_cast<int>(world_.slots().size()); ++i) {
            const ParkingSlot& sl = world_.slots()[static_cast<std::size_t>(i)];
            if (!slot_taken_[static_cast<std::size_t>(i)] &&
                (sl.position - target.box.center2()).norm() <= *plan_->confuser_within && fits(sl))
              near.push_back(i);
          }
          slot = near.empty() ? -1 : rng_.pick(near);
        } else {
          slot = pickSlot(fits);
        }
        if (slot < 0) break;
        if (shared) {
          model = rng_.pick(share_models);
          color = rng_.pick(share_colors);
        }
        Entity c = parkCar(slot, *model, color);
        const bool told_apart =
            !plan_ || !plan_->confuser_told_apart || plan_->confuser_told_apart(c.box);
        if (told_apart && resolves(c)) {
          add(std::move(c), "confuser");
          placed = true;
        } else {
          slot_taken_[static_cast<std::size_t>(slot)] = 0;
          car_ids_.push_back(std::stoi(c.id.substr(4)));
        }
      }
    }
  }

  // The spec's related cars and pedestrians beside a parked target (parked traffic cars or
  // standing pedestrians), drawn among the options that the spec compiler accepts.
  void placeRelated(const OrientedBox& target_box) {
    if (!plan_ || !plan_->related) return;
    for (const RelatedOption& o : plan_->related(target_box, rng_)) placeRelatedOption(o);
  }

  void placeRelatedOption(const RelatedOption& o) {
    Entity e;
    e.cls = o.cls;
    e.attributes = o.attributes;
    e.box = o.box;
    if (o.cls == EntityClass::kCar) {
      e.id = nextCarId();
      e.block = world_.blockAt(e.box.center2());
      if (o.slot >= 0) slot_taken_[static_cast<std::size_t>(o.slot)] = 1;
      add(std::move(e), "traffic");
    } else {
      e.id = nextPedId();
      add(std::move(e), "pedestrian");
    }
  }

  // ------------------------------------------------------------------ classes
  void drawTargetLook(const catalog::CarModel** model, std::string* color) {
    if (plan_) {
      *model = plan_->models.empty()
                   ? &catalog::pickModel(rng_)
                   : &catalog::carModels()[static_cast<std::size_t>(rng_.pick(plan_->models))];
      *color = catalog::pick(rng_, plan_->colors.empty() ? catalog::carColors() : plan_->colors);
      return;
    }
    *model = &catalog::pickModel(rng_);
    *color = catalog::pick(rng_, catalog::carColors());
  }

  TargetDescription describe(const Entity& e) {
    TargetDescription d;
    d.id = e.id;
    d.vehicle_class = e.attributes.str("vehicle_class");
    d.make = e.attributes.str("make");
    d.model = e.attributes.str("model");
    d.color = e.attributes.str("color");
    return d;
  }

  static std::string lookText(const TargetDescription& d) {
    return d.color + " " + d.make + " " + d.model + " (" + d.vehicle_class + ")";
  }

  void buildAreaSearch() {
    Mission& m = sc_.mission;
    m.time_limit = std::round(rangeDraw(rng_, cfg_.time_limit_area_search));
    const catalog::CarModel* model;
    std::string color;
    drawTargetLook(&model, &color);
    int slot;
    if (plan_ && plan_->placements) {
      // Constructive: one of the spec's feasible placements, drawn directly.
      if (plan_->placements->empty()) throw GenerationError("no feasible placement for the target");
      const auto& pl = rng_.pick(*plan_->placements);
      slot = pl.first;
      model = &catalog::carModels()[static_cast<std::size_t>(pl.second)];
    } else {
      slot = pickSlot([this](const ParkingSlot& s) { return wellInside(s.position); });
    }
    if (slot < 0) throw GenerationError("no free parking slot for the target");
    Entity target = parkCar(slot, *model, color);
    const Vec2 tp = target.box.center2();
    add(target, "target");
    placeRelated(target.box);
    m.objective.type = "find";
    m.objective.targets.push_back(describe(target));
    m.objective.text = "Find the " + lookText(m.objective.targets.back()) + ".";

    // AOIs: the first holds the target; the others lie elsewhere and do not overlap it.
    const int n_aoi = static_cast<int>(rng_.uniformInt(cfg_.aoi_count_min, cfg_.aoi_count_max));
    const double yaw0 = rng_.uniform(-0.3, 0.3);
    for (int i = 0; i < n_aoi; ++i) {
      const std::string id = "aoi_" + std::to_string(i + 1);
      const double len = rangeDraw(rng_, cfg_.aoi_length), wid = rangeDraw(rng_, cfg_.aoi_width);
      AreaOfInterest a;
      if (i == 0 && plan_ && plan_->aoi_target_offset) {
        // The target at this distance from the AOI's centre, in a random direction.
        const double phi = rng_.uniform(-geometry::kPi, geometry::kPi);
        const Vec2 c = tp - *plan_->aoi_target_offset * Vec2(std::cos(phi), std::sin(phi));
        a.id = id;
        a.polygon = roundPolygon(geometry::orientedRectangle(c, len, wid, yaw0));
        if (!a.polygon.contains(tp))
          throw GenerationError("target AOI does not contain the target");
      } else if (i == 0) {
        a = makeAoi(id, tp, yaw0, len, wid);
        if (!a.polygon.contains(tp))
          throw GenerationError("target AOI does not contain the target");
      } else {
        bool ok = false;
        for (int attempt = 0; attempt < 30 && !ok; ++attempt) {
          const auto b = world_.bounds();
          const double py = rng_.uniform(b.min.y(), b.max.y());  // "Draw order" at the top
          const double px = rng_.uniform(b.min.x(), b.max.x());
          const Vec2 p(px, py);
          a = makeAoi(id, p, rng_.uniform(-0.3, 0.3), len, wid);
          ok = !a.polygon.intersects(m.aois.front().polygon);
        }
        if (!ok) break;
      }
      if (rng_.bernoulli(cfg_.aoi_window_probability)) {
        const double net = std::round(rng_.uniform(0.0, 0.3) * m.time_limit);
        a.window.net = net;
        if (rng_.bernoulli(0.5)) a.window.nlt = std::round(rng_.uniform(net + 60.0, m.time_limit));
      }
      m.aois.push_back(a);
    }
    for (const auto& a : m.aois) m.priors.push_back(makePrior(a, a.id == "aoi_1" ? &tp : nullptr));

    // KOZs that deny the easy vantage points: over the target, and over the street beside it.
    const int n_koz = static_cast<int>(rng_.uniformInt(cfg_.koz_count_min, cfg_.koz_count_max));
    {
      const double dy = rng_.uniform(-8, 8);  // one draw per statement: "Draw order" at the top
      const double dx = rng_.uniform(-8, 8);
      const Vec2 c = tp + Vec2(dx, dy);
      const double kw = rng_.uniform(30, 60);
      const double kl = rng_.uniform(30, 60);
      KeepOutZone k = makeKoz(geometry::orientedRectangle(c, kl, kw, yaw0), "vantage_denial");
      k.alt_min = 0.0;
      k.alt_max = std::round(uav_.altitude_max + 20.0);
      m.kozs.push_back(k);
    }
    if (n_koz >= 2) {
      int best = -1;
      double best_d = 1e18;
      for (int ei = 0; ei < static_cast<int>(world_.edges().size()); ++ei) {
        const auto& e = world_.edges()[static_cast<std::size_t>(ei)];
        const double d = geometry::pointSegmentDistance(tp, world_.nodes()[e.a].position,
                                                        world_.nodes()[e.b].position);
        if (d < best_d) best_d = d, best = ei;
      }
      const auto& e = world_.edges()[static_cast<std::size_t>(best)];
      const Vec2 a = world_.nodes()[e.a].position, b = world_.nodes()[e.b].position;
      const double w = e.width + 2 * world_.sidewalkWidth();
      KeepOutZone k = makeKoz(
          geometry::orientedRectangle(0.5 * (a + b), std::max(10.0, (b - a).norm() - e.width), w,
                                      std::atan2((b - a).y(), (b - a).x())),
          "vantage_denial");
      k.alt_min = 0.0;
      k.alt_max = std::round(rng_.uniform(25.0, 40.0));
      m.kozs.push_back(k);
    }
    for (int i = 2; i < n_koz; ++i) {
      const auto& aoi = m.aois.front().polygon;
      const auto bb = aoi.bounds();
      for (int attempt = 0; attempt < 20; ++attempt) {
        const double cy = rng_.uniform(bb.min.y(), bb.max.y());  // "Draw order" at the top
        const double cx = rng_.uniform(bb.min.x(), bb.max.x());
        const Vec2 c(cx, cy);
        if (!aoi.contains(c)) continue;
        const double kyaw = rng_.uniform(-0.5, 0.5);
        const double kw = rng_.uniform(20, 50);
        const double kl = rng_.uniform(20, 50);
        KeepOutZone k = makeKoz(geometry::orientedRectangle(c, kl, kw, kyaw), "restricted");
        if (rng_.bernoulli(plan_ && plan_->koz_window_probability ? *plan_->koz_window_probability
                                                                  : 0.5)) {
          k.window.net = std::round(rng_.uniform(0.0, 0.5) * m.time_limit);
          k.window.nlt = std::round(*k.window.net + rng_.uniform(60.0, 0.5 * m.time_limit));
        }
        m.kozs.push_back(k);
        break;
      }
    }
    if (world_.params().type == WorldType::kCity) addBuildingKoz(tp);

    finishStaticTarget(target, {&m.aois.front()}, nullptr);
  }

  // Relations and confusers of a parked target.
  void finishStaticTarget(const Entity& target, const std::vector<const AreaOfInterest*>& aois,
                          const Polygon* keep_out_of) {
    const std::vector<Group> groups = currentGroups();
    const auto all = eval_.allRelations(subjectOf(target), parkedSubjects(target.id),
                                        groupsOf(target.id, groups));
    std::vector<SceneRelation> rels = selectRelations(all);
    ensureListed(&rels, all);
    addConfusers(target, rels, aois, keep_out_of, 40.0);
    for (auto& r : rels) sc_.mission.relations.push_back(r);
  }

  void buildRouteSearch() {
    Mission& m = sc_.mission;
    m.time_limit = std::round(rangeDraw(rng_, cfg_.time_limit_route_search));
    // The lead car plans a route (planning::planVehicleRoute) from its lane on a random street
    // to a goal node a few edges on; the route of interest is the centreline through its nodes.
    const int want = static_cast<int>(rng_.uniformInt(cfg_.route_edges_min, cfg_.route_edges_max));
    const planning::RouteSettings rs = routeSettings();
    const planning::SpeedProfile speed = speedProfile(rangeDraw(rng_, cfg_.car_speed));
    std::vector<int> nodes;
    planning::RouteResult lead;
    Vec2 lane_dir(1, 0);
    std::uint64_t route_seed = 0;
    int goal = -1;
    // A spec's feasible starts (constructive: the next one in a seeded order until one has a
    // route), else random ones.
    const bool from_spec = plan_ && plan_->route_starts && plan_->placements;
    std::vector<std::size_t> order;
    int attempts = kMaxAttempts;
    if (from_spec) {
      for (std::size_t i = 0; i < plan_->placements->size(); ++i) order.push_back(i);
      rng_.shuffle(order);
      attempts = static_cast<int>(std::min<std::size_t>(order.size(), 60));
    }
    int lead_model = -1;
    for (int attempt = 0; attempt < attempts && nodes.empty(); ++attempt) {
      int n0, n1;
      TrajectoryPoint start;
      if (from_spec) {
        const auto& pl = (*plan_->placements)[order[static_cast<std::size_t>(attempt)]];
        const RouteStart& st = (*plan_->route_starts)[static_cast<std::size_t>(pl.first)];
        const LaneDrive drive = routeStartDrive(world_, st);
        n0 = st.from;
        n1 = st.to;
        lead_model = pl.second;
        route_seed = rng_.next();
        goal = nodeAtHops(n1, n0, want - 1);
        if (goal < 0) continue;
        lane_dir = drive.dir;
        start = drive.pose(st.s);
      } else {
        n0 = randomNode();
        const auto& adj = world_.adjacency()[static_cast<std::size_t>(n0)];
        if (adj.empty()) continue;
        const auto& e = world_.edges()[static_cast<std::size_t>(rng_.pick(adj))];
        n1 = e.a == n0 ? e.b : e.a;
        const Vec2 a = world_.nodes()[static_cast<std::size_t>(n0)].position;
        const Vec2 b = world_.nodes()[static_cast<std::size_t>(n1)].position;
        const double len = (b - a).norm();
        // Some way along the first street, so that a trailing car 12 m behind still starts on
        // it and well inside the band (not on its end cap).
        const double s0 = 20.0 + rng_.uniform(0.0, 0.2) * len;
        route_seed = rng_.next();
        goal = nodeAtHops(n1, n0, want - 1);
        if (goal < 0 || s0 > len - rs.corner_clearance - 2.0) continue;
        lane_dir = (b - a) / len;
        start = lanePose(a, lane_dir, s0, rs.lane_offset, 0.0);
      }
      planning::RouteGoal g;
      g.node = goal;
      lead = planning::planVehicleRoute(world_, start, g, route_seed, speed, rs);
      if (!lead.ok() || lead.nodes.empty() || lead.nodes.front() != n1) continue;
      std::vector<int> candidate{n0};
      candidate.insert(candidate.end(), lead.nodes.begin(), lead.nodes.end());
      if (std::set<int>(candidate.begin(), candidate.end()).size() != candidate.size()) continue;
      if (candidate.size() < 3) continue;
      nodes = candidate;
    }
    if (nodes.empty()) throw GenerationError("no route of interest found");
    RouteOfInterest route;
    route.id = "route_1";
    route.polyline = nodePositions(nodes);
    for (std::size_t i = 0; i + 1 < nodes.size(); ++i) {
      for (int ei : world_.adjacency()[static_cast<std::size_t>(nodes[i])]) {
        const auto& e = world_.edges()[static_cast<std::size_t>(ei)];
        if ((e.a == nodes[i] && e.b == nodes[i + 1]) || (e.b == nodes[i] && e.a == nodes[i + 1])) {
          if (route.streets.empty() || route.streets.back() != e.name)
            route.streets.push_back(e.name);
        }
      }
    }
    route.band_width = std::round(rangeDraw(rng_, cfg_.band_width));
    route.band = roundPolygon(geometry::bufferPolyline(route.polyline, route.band_width));
    m.routes.push_back(route);

    // One car, or a convoy of two: the second starts 12 m behind in the same lane, departs
    // 2.5 s later with the same seed and stops 12 m short of the lead car's stop, so it follows
    // the same streets (checked: else the scenario keeps one target).
    std::vector<Trajectory> trajs{lead.trajectory};
    if (plan_ && plan_->target_count > 0 ? plan_->target_count == 2 : rng_.bernoulli(0.5)) {
      const TrajectoryPoint& l0 = lead.trajectory.front();
      TrajectoryPoint start = l0;
      start.x = roundMilli(l0.x - 12.0 * lane_dir.x());
      start.y = roundMilli(l0.y - 12.0 * lane_dir.y());
      start.t = 2.5;
      const TrajectoryPoint& le = lead.trajectory.back();
      planning::RouteGoal g;
      g.pose = TrajectoryPoint{0.0, roundMilli(le.x - 12.0 * std::cos(le.yaw)),
                               roundMilli(le.y - 12.0 * std::sin(le.yaw)), 0.0, le.yaw};
      const planning::RouteResult follow =
          planning::planVehicleRoute(world_, start, g, route_seed, speed, rs);
      std::vector<int> fnodes = follow.nodes;
      fnodes.push_back(goal);
      if (follow.ok() && fnodes == lead.nodes) {
        Trajectory traj = follow.trajectory;
        start.t = 0.0;
        traj.insert(traj.begin(), start);  // waits in its lane until it departs
        trajs.push_back(traj);
      }
    }
    // In the city each stops clear of the intersection ahead, on an arterial at the kerb; the
    // second 12 m behind the first (else the scenario keeps one target).
    if (auto st = cityStop(trajs[0])) trajs[0] = std::move(*st);
    if (trajs.size() == 2) {
      if (auto st = cityStop(trajs[1], &trajs[0])) {
        trajs[1] = std::move(*st);
      } else {
        trajs.pop_back();
      }
    }
    const int n_targets = static_cast<int>(trajs.size());
    Group convoy;
    convoy.id = "convoy_1";
    convoy.kind = "convoy";
    std::vector<Entity> targets;
    for (int i = 0; i < n_targets; ++i) {
      const catalog::CarModel* model;
      std::string color;
      drawTargetLook(&model, &color);
      if (i == 0 && lead_model >= 0)
        model = &catalog::carModels()[static_cast<std::size_t>(lead_model)];
      // In the city each car waits at the signals (the second behind the first as well).
      trajs[static_cast<std::size_t>(i)] =
          obeyCitySignals(trajs[static_cast<std::size_t>(i)], model->length,
                          i > 0 ? &trajs[0] : nullptr, i > 0 ? targets[0].box.size.x() : 0.0);
      const Trajectory& traj = trajs[static_cast<std::size_t>(i)];
      Entity e = makeCar(*model, color, Vec3(traj[0].x, traj[0].y, traj[0].z), traj[0].yaw);
      targets.push_back(e);
      convoy.members.push_back(e.id);
      m.objective.targets.push_back(describe(e));
    }
    m.objective.type = "find";
    m.objective.text =
        "Find the " + lookText(m.objective.targets[0]) +
        (n_targets == 2 ? " and the " + lookText(m.objective.targets[1]) : std::string()) +
        " travelling along route_1.";
    if (n_targets == 2) extra_groups_.push_back(convoy);

    // Access denial: a street of the route, closed for exactly the time the target cars are on
    // it (from the first car's entry to the last car's exit).
    std::vector<int> edge_choices;
    for (int k = 1; k + 1 < static_cast<int>(nodes.size()); ++k) edge_choices.push_back(k);
    if (edge_choices.empty()) edge_choices.push_back(0);
    rng_.shuffle(edge_choices);
    const int n_denied = std::min<int>(n_targets, static_cast<int>(edge_choices.size()));
    std::sort(edge_choices.begin(), edge_choices.begin() + n_denied);
    for (int d = 0; d < n_denied; ++d) {
      const auto k = static_cast<std::size_t>(edge_choices[static_cast<std::size_t>(d)]);
      const Vec2 a = route.polyline[k], b = route.polyline[k + 1];
      const double w = world_.params().street_width;
      const Polygon street = roundPolygon(geometry::orientedRectangle(
          0.5 * (a + b), (b - a).norm() - w, w, std::atan2((b - a).y(), (b - a).x())));
      std::optional<double> enter, exit;
      for (const auto& traj : trajs) {
        const auto interval = insideInterval(traj, street);
        if (!interval) continue;
        enter = enter ? std::min(*enter, interval->first) : interval->first;
        exit = exit ? std::max(*exit, interval->second) : interval->second;
      }
      if (!enter) continue;
      KeepOutZone koz = makeKoz(street, "access_denial");
      koz.window.net = std::floor(*enter * 1000.0) / 1000.0;
      koz.window.nlt = std::ceil(*exit * 1000.0) / 1000.0;
      koz.alt_min = 0.0;
      koz.alt_max = std::round(uav_.altitude_max + 20.0);
      m.kozs.push_back(koz);
    }

    for (int i = 0; i < n_targets; ++i) {
      add(targets[static_cast<std::size_t>(i)], "target", trajs[static_cast<std::size_t>(i)]);
    }
    for (int i = 0; i < n_targets; ++i) {
      movingTargetRelations(targets[static_cast<std::size_t>(i)],
                            trajs[static_cast<std::size_t>(i)], {});
      if (i == 0) listEventually(targets[0], trajs[0]);
      addConfusers(targets[static_cast<std::size_t>(i)], {}, {}, &route.band, 40.0);
    }
  }

  void movingTargetRelations(const Entity& target, const Trajectory& traj,
                             const std::vector<Subject>& extra) {
    const std::vector<Group> groups = currentGroups();
    std::vector<const Group*> mine = groupsOf(target.id, groups);
    std::vector<Subject> others = parkedSubjects(target.id);
    others.insert(others.end(), extra.begin(), extra.end());
    const auto at_start = eval_.allRelations(subjectOf(target), others, mine);
    std::vector<SceneRelation> rels = selectRelations(at_start);
    const int n_ev = std::max(1, cfg_.relations.max_relations / 3);
    if (static_cast<int>(rels.size()) > cfg_.relations.max_relations - n_ev)
      rels.resize(static_cast<std::size_t>(cfg_.relations.max_relations - n_ev));
    ensureListed(&rels, at_start);
    for (auto& r : eventuallyRelations(target, traj, at_start, n_ev)) rels.push_back(r);
    for (auto& r : rels) sc_.mission.relations.push_back(r);
  }

  // A spec's EVENTUALLY_* requirements on the world's entities: for each, the first sample
  // (every eventually_dt, up to the time limit) at which a matching world entity that is not so
  // related at t = 0 stands in the relation, added to the mission's relations unless listed.
  void listEventually(const Entity& target, const Trajectory& traj) {
    if (!plan_ || plan_->eventually.empty()) return;
    const double dt = cfg_.relations.eventually_dt;
    const double end = std::min(sc_.mission.time_limit, traj.back().t + dt);
    Subject s0 = subjectOf(target);
    s0.box = poseBox(target.box, sampleTrajectory(traj, 0.0));
    for (const auto& ev : plan_->eventually) {
      for (int k = 1; k * dt <= end; ++k) {
        Subject s = s0;
        s.box = poseBox(target.box, sampleTrajectory(traj, k * dt));
        std::optional<SceneRelation> found;
        for (const auto& [i, d] : eval_.nearbyWorldDistances(s.box)) {
          const Entity& e = world_.entities()[static_cast<std::size_t>(i)];
          if (!operatorApplies(ev.op, e.cls) || !ev.matches(e.cls, e.attributes)) continue;
          const Subject rel = worldSubject(world_, i);
          const RelationFacts f = eval_.measure(s, rel);
          if (!eval_.holds(ev.op, f, e.cls) || eval_.holds(ev.op, eval_.measure(s0, rel), e.cls)) {
            continue;
          }
          found = makeRelation(s, rel, ev.op, f);
          break;
        }
        if (!found) continue;
        found->eventually = true;
        found->time = k * dt;
        bool have = false;
        for (const auto& r : sc_.mission.relations) {
          have = have || (r.eventually && r.op == found->op && r.target_id == found->target_id &&
                          r.related_id == found->related_id);
        }
        if (!have) sc_.mission.relations.push_back(*found);
        break;
      }
    }
  }

  // A spec's keep-out zones, after the class's own (specKozPolygons).
  void addSpecKozs() {
    const ScenarioEntity* target = nullptr;
    for (const auto& se : sc_.sim.entities) {
      if (!target && se.role == "target") target = &se;
    }
    if (!target) return;
    OrientedBox box = target->entity.box;
    if (!target->trajectory.empty()) box = poseBox(box, sampleTrajectory(target->trajectory, 0.0));
    for (const auto& z : plan_->kozs) {
      for (const Polygon& poly : specKozPolygons(world_, z, box, sc_.mission.aois)) {
        KeepOutZone k = makeKoz(poly, z.purpose);
        k.alt_min = z.alt_min;
        k.alt_max = z.alt_max;
        k.window.net = z.net;
        k.window.nlt = z.nlt;
        sc_.mission.kozs.push_back(k);
      }
    }
  }

  // A car parked at a kerb slot that drives off at `depart`: it waits, pulls out into its lane
  // ahead of the slot, then follows a planned route (planVehicleRoute) to a node 6-12 street
  // edges away. Takes the slot (*slot); with use_spec, a spec's placements choose the slot and
  // *model. *route (optional) receives the route's nodes and what planned it.
  struct DriveOffRoute {
    std::vector<int> nodes;  // street nodes passed, the goal node last
    std::uint64_t seed = 0;
    planning::SpeedProfile speed;
    TrajectoryPoint end;  // where the route stops (before cityStop moves the stop)
  };
  static constexpr double kChaseSpeedFraction = 0.75;
  Trajectory driveOff(double depart, bool use_spec, const catalog::CarModel** model, int* slot,
                      DriveOffRoute* route_out = nullptr) {
    const planning::RouteSettings rs = routeSettings();
    double cruise = rangeDraw(rng_, cfg_.car_speed);
    // A follow or track target drives no faster than kChaseSpeedFraction of the UAV's top
    // speed: its follower must gain on it after a turn, a stop or a loss (at car_speed's
    // 13 m/s against the UAV's 12 the follow baseline trailed by 15-28 m, the envelope 18).
    if (route_out == &pursuit_route_ &&
        (cls_ == ScenarioClass::kFollow || cls_ == ScenarioClass::kTrack)) {
      cruise = std::min(cruise, kChaseSpeedFraction * uav_.max_speed);
    }
    const planning::SpeedProfile speed = speedProfile(cruise);
    constexpr double kPullOutTime = 6.0;  // seconds, from rest to rest
    Trajectory traj;
    std::vector<int> tried;  // slots without a route, skipped on later attempts
    std::vector<std::size_t> order;
    int attempts = 20;
    if (use_spec && plan_ && plan_->placements) {
      for (std::size_t i = 0; i < plan_->placements->size(); ++i) order.push_back(i);
      rng_.shuffle(order);
      attempts = static_cast<int>(std::min<std::size_t>(order.size(), 60));
    }
    for (int attempt = 0; attempt < attempts && traj.empty(); ++attempt) {
      if (use_spec && plan_ && plan_->placements) {
        // Constructive: the next of the spec's feasible placements, in a seeded order.
        if (attempt >= static_cast<int>(order.size())) break;
        const auto& pl = (*plan_->placements)[order[static_cast<std::size_t>(attempt)]];
        *slot = pl.first;
        *model = &catalog::carModels()[static_cast<std::size_t>(pl.second)];
      } else {
        *slot = pickSlot([&](const ParkingSlot& s) { return pursuitSlotFits(world_, s); }, true);
      }
      if (*slot < 0) break;
      slot_taken_[static_cast<std::size_t>(*slot)] = 1;
      const ParkingSlot& s = world_.slots()[static_cast<std::size_t>(*slot)];
      const auto& e = world_.edges()[static_cast<std::size_t>(s.edge)];
      const Vec2 pa = world_.nodes()[e.a].position, pb = world_.nodes()[e.b].position;
      const Vec2 fwd(std::cos(s.yaw), std::sin(s.yaw));
      const bool ab = (pb - pa).dot(fwd) > 0;
      const int first = ab ? e.a : e.b, second = ab ? e.b : e.a;
      const Vec2 from = ab ? pa : pb, dir = ((ab ? pb : pa) - from).normalized();
      const Vec2 right(dir.y(), -dir.x());
      const double along0 = (s.position - from).dot(dir), lat0 = (s.position - from).dot(right);
      // Waiting, then a cosine blend from the kerb into the lane, at rest at both ends
      // (peak 2.6 m/s, 1.4 m/s^2).
      const TrajectoryPoint kerb{0.0, roundMilli(s.position.x()), roundMilli(s.position.y()),
                                 roundMilli(s.ground_z), roundMilli(s.yaw)};
      Trajectory prefix{kerb, kerb};
      prefix[1].t = depart;
      constexpr int kSteps = 10;
      for (int j = 1; j <= kSteps; ++j) {
        const double u = static_cast<double>(j) / kSteps;  // fraction of the distance
        const double w = 0.5 * (1.0 - std::cos(geometry::kPi * u));
        const double lat = lat0 + (rs.lane_offset - lat0) * w;
        const double dlat =
            (rs.lane_offset - lat0) * 0.5 * geometry::kPi * std::sin(geometry::kPi * u) / kPullOut;
        const Vec2 p = from + dir * (along0 + kPullOut * u) + right * lat;
        const Vec2 h = dir + right * dlat;
        const double t = depart + kPullOutTime / geometry::kPi * std::acos(1.0 - 2.0 * u);
        prefix.push_back({roundMilli(t), roundMilli(p.x()), roundMilli(p.y()), 0.0,
                          roundMilli(std::atan2(h.y(), h.x()))});
      }
      const int goal = nodeAtHops(second, first, static_cast<int>(rng_.uniformInt(6, 12)) - 1);
      const std::uint64_t route_seed = rng_.next();
      if (goal < 0) {
        tried.push_back(*slot);
        continue;
      }
      planning::RouteGoal g;
      g.node = goal;
      const planning::RouteResult route =
          planning::planVehicleRoute(world_, prefix.back(), g, route_seed, speed, rs);
      if (!route.ok() || route.trajectory.size() < 2) {
        tried.push_back(*slot);
        continue;
      }
      traj = prefix;
      traj.insert(traj.end(), route.trajectory.begin() + 1, route.trajectory.end());
      if (route_out) *route_out = DriveOffRoute{route.nodes, route_seed, speed, traj.back()};
    }
    for (int t : tried) slot_taken_[static_cast<std::size_t>(t)] = 0;
    if (traj.empty()) {
      throw GenerationError("no free kerb slot with a route for the pursuit target");
    }
    return traj;
  }

  void buildPursuit() {
    Mission& m = sc_.mission;
    m.time_limit = std::round(rangeDraw(rng_, cfg_.time_limit_pursuit));
    const catalog::CarModel* model;
    std::string color;
    drawTargetLook(&model, &color);
    // The target waits at the kerb, the pedestrians run at it, and it drives off: it pulls out
    // into its lane ahead of the slot, then follows a planned route (planVehicleRoute) to a
    // node 6-12 street edges away.
    // (A track target waits longer, and its UAV starts nearer: see placeUavStart.)
    const double depart = std::round(rangeDraw(
        rng_, cls_ == ScenarioClass::kTrack ? cfg_.track_depart_time : cfg_.depart_time));
    depart_ = depart;
    int slot = -1;
    Trajectory traj = driveOff(depart, true, &model, &slot, &pursuit_route_);
    const ParkingSlot& sl = world_.slots()[static_cast<std::size_t>(slot)];
    slot_taken_[static_cast<std::size_t>(slot)] = 1;
    const Vec2 fwd(std::cos(sl.yaw), std::sin(sl.yaw));
    if (auto st = cityStop(traj)) traj = std::move(*st);
    traj = obeyCitySignals(traj, model->length);
    Entity target = makeCar(*model, color, Vec3(traj[0].x, traj[0].y, traj[0].z), traj[0].yaw);
    m.objective.type = "track";
    m.objective.targets.push_back(describe(target));
    m.objective.text = "Track the " + lookText(m.objective.targets.back()) +
                       " that pedestrians chase, and keep it in view after it drives off.";

    // Vignette: two or three pedestrians run along the sidewalk at the car, then after it.
    Group vignette;
    vignette.id = "vignette_1";
    vignette.kind = "vignette";
    const Block& block = world_.blocks()[static_cast<std::size_t>(sl.block)];
    const int n_ped = static_cast<int>(rng_.uniformInt(2, 3));
    std::vector<Subject> runners;
    const double ring = geometry::polylineLength(block.sidewalk);
    double s_car = 0;  // arc length of the sidewalk point nearest the car
    {
      double best = 1e18, acc = 0;
      for (std::size_t i = 0; i + 1 < block.sidewalk.size(); ++i) {
        const Vec2 a = block.sidewalk[i], b = block.sidewalk[i + 1];
        const Vec2 q = geometry::closestPointOnSegment(sl.position, a, b);
        const double d = (q - sl.position).norm();
        if (d < best) best = d, s_car = acc + (q - a).norm();
        acc += (b - a).norm();
      }
    }
    for (int i = 0; i < n_ped; ++i) {
      const double speed = rangeDraw(rng_, cfg_.runner_speed);
      const double lead = rng_.uniform(25.0, 45.0);
      const double dir = (block.sidewalk.size() > 1 &&
                          (geometry::polylinePointAt(block.sidewalk, std::fmod(s_car + 1.0, ring)) -
                           geometry::polylinePointAt(block.sidewalk, s_car))
                                  .dot(fwd) > 0)
                             ? 1.0
                             : -1.0;
      // Start behind the car (against its heading) and run past it in its direction.
      const double s0 = s_car - dir * lead;
      const double s1 = s_car + dir * rng_.uniform(8.0, 20.0);
      const double t_arrive = depart - rng_.uniform(0.0, 3.0);
      const double t0 = std::max(1.0, t_arrive - lead / speed);
      Trajectory pt = walkRing(block.sidewalk, s0, s1, speed, t0);
      Entity p;
      p.id = nextPedId();
      p.cls = EntityClass::kPedestrian;
      p.attributes.set("clothing_color", catalog::pick(rng_, catalog::clothingColors()));
      p.attributes.set("activity", std::string("running"));
      p.box = boxFromPose(Vec3(pt[0].x, pt[0].y, 0.0), pt[0].yaw,
                          Vec3(0.5, 0.6, roundMilli(rng_.uniform(1.6, 1.9))));
      p.block = -1;
      vignette.members.push_back(p.id);
      add(p, "vignette", pt);
    }
    vignette.members.push_back(target.id);
    extra_groups_.push_back(vignette);

    // AOI around where the car waits, valid until it departs.
    const double len = rangeDraw(rng_, cfg_.aoi_length), wid = rangeDraw(rng_, cfg_.aoi_width);
    AreaOfInterest aoi = makeAoi("aoi_1", target.box.center2(), rng_.uniform(-0.3, 0.3), len, wid);
    aoi.window.nlt = depart;
    m.aois.push_back(aoi);
    const Vec2 tp = target.box.center2();
    m.priors.push_back(makePrior(aoi, &tp));
    add(target, "target", traj);
    placeRelated(target.box);

    // Pedestrian subjects at the moment they are nearest the car, for EVENTUALLY_NEXT_TO.
    movingTargetRelations(target, traj, {});
    listEventually(target, traj);
    // The runners reach the car: EVENTUALLY_NEXT_TO with the first runner, at the first
    // grid time they are next to it.
    for (const auto& se : sc_.sim.entities) {
      if (se.role != "vignette") continue;
      const double dt = cfg_.relations.eventually_dt;
      for (int k = 1; k * dt <= depart + 10.0; ++k) {
        const double t = k * dt;
        Subject ts = subjectOf(target);
        ts.box = poseBox(target.box, sampleTrajectory(traj, t));
        Subject ps = subjectOf(se.entity);
        ps.box = poseBox(se.entity.box, sampleTrajectory(se.trajectory, t));
        const RelationFacts f = eval_.measure(ts, ps);
        if (eval_.holds(RelationOp::kNextTo, f, EntityClass::kPedestrian)) {
          SceneRelation r = makeRelation(ts, ps, RelationOp::kNextTo, f);
          r.eventually = true;
          r.time = t;
          m.relations.push_back(r);
          break;
        }
      }
      break;
    }
    std::vector<const AreaOfInterest*> aois{&m.aois.front()};
    std::vector<SceneRelation> rels;
    for (const auto& r : m.relations) rels.push_back(r);
    addConfusers(target, rels, aois, nullptr, 60.0);
  }

  // ------------------------------------------------------------------ follow
  // The follow class: pursuit's scene (a car that drives off after the pedestrians reach it),
  // in two phases: find it, then keep inside the envelope behind and above it for a drawn
  // duration. The scored duration starts at the first entry into the envelope after the find,
  // within an approach allowance: the time to close kFindReach (the farthest a find lies from
  // the envelope) on a target that drives away, at half the UAV's top speed, within
  // [kMinApproach, kMaxApproach]. The time limit is pursuit's plus the allowance and duration.
  void buildFollow() {
    buildPursuit();
    Mission& m = sc_.mission;
    const std::string target = m.objective.targets.front().id;
    MissionPhase search;
    search.id = "search_1";
    search.type = PhaseType::kSearch;
    search.targets = {target};
    MissionPhase follow;
    follow.id = "follow_1";
    follow.type = PhaseType::kFollow;
    follow.targets = {target};
    FollowPhaseSpec& f = follow.follow;
    f.distance = std::round(rangeDraw(rng_, cfg_.follow_distance));
    f.distance_tolerance = std::round(rangeDraw(rng_, cfg_.follow_distance_tolerance));
    f.height_tolerance = std::round(rangeDraw(rng_, cfg_.follow_height_tolerance));
    // h* +- H inside the altitude band (the band is at least 15 m, H at most 7 m: validate()).
    f.height =
        std::clamp(std::round(rangeDraw(rng_, cfg_.follow_height)),
                   uav_.altitude_min + f.height_tolerance, uav_.altitude_max - f.height_tolerance);
    const double duration = std::round(rangeDraw(rng_, cfg_.follow_duration));
    follow.duration = duration;
    constexpr double kFindReach = 200.0, kMinApproach = 10.0, kMaxApproach = 60.0;  // m, s, s
    f.approach_s =
        std::clamp(std::ceil(kFindReach / (0.5 * uav_.max_speed)), kMinApproach, kMaxApproach);
    m.phases = {search, follow};
    m.time_limit += f.approach_s + duration;
    char text[256];
    std::snprintf(text, sizeof(text),
                  " Then reach it within %.0f s and follow it for %.0f s: %.0f +- %.0f m behind it "
                  "and %.0f +- %.0f m above it.",
                  f.approach_s, duration, f.distance, f.distance_tolerance, f.height,
                  f.height_tolerance);
    m.objective.text =
        "Find the " + lookText(m.objective.targets.front()) + " that pedestrians chase." + text;
  }

  // ------------------------------------------------------------------ track
  // The track class: pursuit's scene with one or two moving targets (the second, drawn from
  // track_targets_min/max, waits in the lane 12 m behind the first one's kerb slot and drives
  // the same streets two seconds behind it, a convoy: when no such route exists the scenario
  // keeps one target), in two phases: find them, then keep them in a camera's view for
  // a drawn duration. Look-alike parked cars (addConfusers) stand along the streets, and the
  // routes pass the street trees and buildings that occlude the targets. The time limit is
  // pursuit's plus the duration.
  void buildTrack() {
    buildPursuit();
    Mission& m = sc_.mission;
    const int n_targets =
        static_cast<int>(rng_.uniformInt(cfg_.track_targets_min, cfg_.track_targets_max));
    if (n_targets == 2) addConvoyTarget();
    std::vector<std::string> ids;
    for (const auto& t : m.objective.targets) ids.push_back(t.id);
    MissionPhase search;
    search.id = "search_1";
    search.type = PhaseType::kSearch;
    search.targets = ids;
    MissionPhase track;
    track.id = "track_1";
    track.type = PhaseType::kTrack;
    track.targets = ids;
    TrackPhaseSpec& c = track.track;
    c.min_visible_fraction = cfg_.track_min_visible_fraction;
    c.min_box_area = cfg_.track_min_box_area;
    c.min_tracked_fraction = cfg_.track_min_tracked_fraction;
    c.max_reacquire_s = cfg_.track_max_reacquire_s;
    const double duration = std::round(rangeDraw(rng_, cfg_.track_duration));
    track.duration = duration;
    m.phases = {search, track};
    m.time_limit += duration;
    const bool two = m.objective.targets.size() == 2;
    char text[256];
    std::snprintf(text, sizeof(text),
                  " Then keep %s in a camera's view for %.0f s (tracked: at least %.0f %% of it "
                  "visible and a box of at least %.0f px; tracked %.0f %% of the time, every loss "
                  "reacquired within %.0f s).",
                  two ? "both" : "it", duration, 100.0 * c.min_visible_fraction, c.min_box_area,
                  100.0 * c.min_tracked_fraction, c.max_reacquire_s);
    m.objective.text =
        "Find the " + lookText(m.objective.targets.front()) + " that pedestrians chase" +
        (two ? " and the " + lookText(m.objective.targets[1]) + " behind it" : std::string()) +
        "." + text;
  }

  // The track class's second target: a car of its own look that waits in the lane 12 m behind
  // the first target's kerb slot, drives the same streets kConvoyTimeGap behind the first
  // target at cruise (the two-second rule; both set off from rest and speed up alike, so the
  // gap is never less) and stops 12 m short of the first target's stop (checked: else none).
  // It sets off before the first target has pulled out when the wait's 22 m exceed the gap.
  static constexpr double kConvoyTimeGap = 2.0;  // s
  // The point of a trajectory `arc` m of path on from its point `from` (its last if shorter).
  static TrajectoryPoint arcPoint(const Trajectory& traj, std::size_t from, double arc) {
    for (std::size_t i = from + 1; i < traj.size(); ++i) {
      arc -= std::hypot(traj[i].x - traj[i - 1].x, traj[i].y - traj[i - 1].y);
      if (arc <= 0.0) return traj[i];
    }
    return traj.back();
  }
  // When a trajectory passes closest to a point (linear between its samples).
  static double passTime(const Trajectory& traj, const TrajectoryPoint& at) {
    double best = std::numeric_limits<double>::infinity(), t = traj.front().t;
    for (std::size_t i = 1; i < traj.size(); ++i) {
      const Vec2 a(traj[i - 1].x, traj[i - 1].y), b(traj[i].x, traj[i].y), q(at.x, at.y);
      const Vec2 ab = b - a;
      const double u = std::clamp(ab.squaredNorm() > 1e-12 ? (q - a).dot(ab) / ab.squaredNorm()
                                                           : 0.0, 0.0, 1.0);
      const double d = (a + u * ab - q).squaredNorm();
      if (d < best) best = d, t = traj[i - 1].t + u * (traj[i].t - traj[i - 1].t);
    }
    return t;
  }
  void addConvoyTarget() {
    Mission& m = sc_.mission;
    const catalog::CarModel* model;
    std::string color;
    drawTargetLook(&model, &color);
    const ScenarioEntity* lead = nullptr;
    for (const auto& se : sc_.sim.entities) {
      if (se.role == "target") lead = &se;
    }
    if (!lead || lead->trajectory.size() < 13 || pursuit_route_.nodes.empty()) return;
    // The end of the pull-out (kSteps = 10), kPullOut ahead of the kerb slot: the second car
    // waits 12 m behind the slot, in the lane.
    const TrajectoryPoint& p = lead->trajectory[11];
    const double back = kPullOut + 12.0;
    TrajectoryPoint start = p;
    start.x = roundMilli(p.x - back * std::cos(p.yaw));
    start.y = roundMilli(p.y - back * std::sin(p.yaw));
    start.t = p.t;
    const TrajectoryPoint& le = pursuit_route_.end;
    planning::RouteGoal g;
    g.pose = TrajectoryPoint{0.0, roundMilli(le.x - 12.0 * std::cos(le.yaw)),
                             roundMilli(le.y - 12.0 * std::sin(le.yaw)), 0.0, le.yaw};
    const planning::RouteResult follow = planning::planVehicleRoute(
        world_, start, g, pursuit_route_.seed, pursuit_route_.speed, routeSettings());
    std::vector<int> fnodes = follow.nodes;
    fnodes.push_back(pursuit_route_.nodes.back());
    if (!follow.ok() || follow.trajectory.size() < 2 || fnodes != pursuit_route_.nodes) return;
    // Both cars set off from rest on the same streets with the same speeds, so past the first
    // car's speed-up (and a first corner's) their time gap stays what it is 60 m on: the
    // second car's departure is shifted to make it kConvoyTimeGap (and at least 0.5 s in the
    // lane). Times are linear in the departure, so the shift is the replanned trajectory.
    const TrajectoryPoint mark = arcPoint(lead->trajectory, 11, 60.0);
    const double gap = passTime(follow.trajectory, mark) - mark.t;
    const double depart = roundMilli(std::max(p.t + kConvoyTimeGap - gap, 0.5));
    Trajectory traj = follow.trajectory;
    for (auto& q : traj) q.t = roundMilli(q.t + (depart - p.t));
    TrajectoryPoint wait = traj.front();
    wait.t = 0.0;
    traj.insert(traj.begin(), wait);  // waits in its lane until it departs
    // In the city it stops 12 m behind the first target (else none).
    const std::optional<Trajectory> stopped = cityStop(traj, &lead->trajectory);
    if (!stopped) return;
    traj = *stopped;
    // In the city it stops at the signals, and behind the first target while that one waits.
    traj = obeyCitySignals(traj, model->length, &lead->trajectory, lead->entity.box.size.x());
    Entity target = makeCar(*model, color, Vec3(traj[0].x, traj[0].y, traj[0].z), traj[0].yaw);
    m.objective.targets.push_back(describe(target));
    add(target, "target", traj);
  }

  // ------------------------------------------------------------------ avoid
  // The avoid class: fly from an intersection to a goal (a viewpoint in the flight band or a
  // landing spot at an intersection) among scripted aircraft, past a keep-out zone that
  // escorts a hostile vehicle and up to two static restricted zones near the direct line.
  void buildAvoid() {
    Mission& m = sc_.mission;
    const planning::ValiditySettings vs = planning::validitySettingsFor(uav_);
    const double amin = uav_.altitude_min, amax = uav_.altitude_max;
    Vec3 start(0, 0, 0), goal(0, 0, 0);
    bool landing = false;
    ReferenceFlight ref;
    for (int attempt = 0; attempt < 40 && !ref.ok; ++attempt) {
      m.kozs.clear();
      const Vec2 s = world_.nodes()[static_cast<std::size_t>(randomNode())].position;
      if (!insideBy(s, 30.0)) continue;
      landing = rng_.bernoulli(0.5);
      bool placed = false;
      for (int g = 0; g < 60 && !placed; ++g) {
        Vec2 q;
        double z = 0.0;
        if (landing) {
          q = world_.nodes()[static_cast<std::size_t>(randomNode())].position;
        } else {
          const double qy = rng_.uniform(world_.bounds().min.y(), world_.bounds().max.y());
          const double qx = rng_.uniform(world_.bounds().min.x(), world_.bounds().max.x());
          q = Vec2(qx, qy);
          z = std::round(rng_.uniform(amin + 5.0, amax - 5.0));
        }
        const double d = (q - s).norm();
        if (!insideBy(q, 30.0) || d < kAvoidGoalDistanceMin || d > kAvoidGoalDistanceMax) continue;
        start = Vec3(roundMilli(s.x()), roundMilli(s.y()), 0.0);
        goal = Vec3(roundMilli(q.x()), roundMilli(q.y()), z);
        placed = true;
      }
      if (!placed) continue;
      // Static restricted zones near the direct line, clear of the start and the goal; some
      // low enough to fly over.
      const Vec2 s2(start.x(), start.y()), g2(goal.x(), goal.y());
      const Vec2 dir = (g2 - s2).normalized(), left(-dir.y(), dir.x());
      const int n_koz = static_cast<int>(rng_.uniformInt(0, 2));
      for (int i = 0; i < n_koz; ++i) {
        const double u = rng_.uniform(0.3, 0.7);
        const double off = rng_.uniform(-20.0, 20.0);
        const double kl = rng_.uniform(30.0, 70.0);
        const double kw = rng_.uniform(20.0, 50.0);
        const double kyaw = std::atan2(dir.y(), dir.x()) + rng_.uniform(-0.4, 0.4);
        const bool tall = rng_.bernoulli(0.5);
        const double low = std::round(amin + rng_.uniform(8.0, 20.0));
        const Vec2 c = s2 + (g2 - s2) * u + left * off;
        KeepOutZone k = makeKoz(geometry::orientedRectangle(c, kl, kw, kyaw), "restricted");
        if (k.polygon.distance(s2) < 25.0 || k.polygon.distance(g2) < 25.0) continue;
        k.alt_min = 0.0;
        k.alt_max = tall ? std::round(amax + 20.0) : std::min(low, amax - 6.0);
        m.kozs.push_back(k);
      }
      const planning::WorldValidity band(world_, m.kozs, vs);
      ref = shortestFlight(band, start, goal);
    }
    if (!ref.ok) throw GenerationError("no start and goal with a flight between them");
    uav_.start = {0.0, start.x(), start.y(), 0.0,
                  roundMilli(rng_.uniform(-geometry::kPi, geometry::kPi))};
    sc_.sim.uav = uav_;
    const double shortest = std::round(ref.length * 100.0) / 100.0;
    m.time_limit = std::round(shortest / (kAvoidNominalSpeedFraction * uav_.max_speed) + 60.0);

    addHostileEscort(start, goal);
    addAircraft(ref, start, goal, vs);

    MissionPhase phase;
    phase.id = "avoid_1";
    phase.type = PhaseType::kAvoid;
    phase.avoid.goal = goal;
    phase.avoid.goal_radius = kAvoidGoalRadius;
    phase.avoid.shortest_path_m = shortest;
    m.phases.push_back(phase);
    m.objective.type = "reach";
    char text[256];
    std::snprintf(text, sizeof(text),
                  landing ? "Land within %.0f m of (%.1f, %.1f) before the time limit"
                          : "Fly to within %.0f m of the viewpoint (%.1f, %.1f, %.1f) before the "
                            "time limit",
                  kAvoidGoalRadius, goal.x(), goal.y(), goal.z());
    m.objective.text = std::string(text) +
                       ", keeping at least 5 m horizontally or 3 m vertically from every other "
                       "aircraft and out of the keep-out zones.";
  }

  // True for points at least `inset` metres inside the neighborhood bounds.
  bool insideBy(const Vec2& p, double inset) const {
    const auto& b = world_.bounds();
    return p.x() >= b.min.x() + inset && p.x() <= b.max.x() - inset && p.y() >= b.min.y() + inset &&
           p.y() <= b.max.y() - inset;
  }

  // A hostile car that drives a few blocks, escorted by a square keep-out zone over the whole
  // band; preferably across the direct line, never within 36 m of the start or the goal.
  void addHostileEscort(const Vec3& start, const Vec3& goal) {
    const Vec2 s2(start.x(), start.y()), g2(goal.x(), goal.y());
    const double horizon = sc_.mission.time_limit;
    Trajectory chosen;
    for (int attempt = 0; attempt < 40; ++attempt) {
      const int hops = static_cast<int>(rng_.uniformInt(4, 8));
      const std::vector<int> nodes = randomWalk(randomNode(), hops);
      if (nodes.size() < 2) continue;
      DriveSpec spec = driveSpec(rangeDraw(rng_, cfg_.car_speed));
      spec.depart_delay = rng_.uniform(0.0, 10.0);
      if (world_.params().type == WorldType::kCity) {
        // Out of the first node's intersection box (so that it meets that node's signal, if
        // any, at its stop line like the rest).
        const CityParams& cp = world_.params().city;
        spec.start_offset = 0.5 * cp.arterial_width + cp.sidewalk_width + 4.0;
      }
      Trajectory traj = planDrive(nodePositions(nodes), spec);
      bool clear = true;
      for (double t = 0.0; t <= horizon + 1.0 && clear; t += 1.0) {
        const TrajectoryPoint p = sampleTrajectory(traj, t);
        const Vec2 q(p.x, p.y);
        clear = (q - s2).norm() >= kEscortClearance && (q - g2).norm() >= kEscortClearance;
      }
      if (!clear) continue;
      bool crosses = false;
      for (std::size_t i = 1; i < traj.size() && !crosses; ++i) {
        crosses = geometry::segmentsIntersect(Vec2(traj[i - 1].x, traj[i - 1].y),
                                              Vec2(traj[i].x, traj[i].y), s2, g2);
      }
      if (chosen.empty() || crosses) chosen = std::move(traj);
      if (crosses) break;
    }
    if (chosen.empty())
      throw GenerationError("no route for the hostile vehicle clear of the start and goal");
    const auto& model = catalog::pickModel(rng_);
    if (auto st = cityStop(chosen)) chosen = std::move(*st);
    chosen = obeyCitySignals(chosen, model.length);
    Entity e = makeCar(model, catalog::pick(rng_, catalog::carColors()),
                       Vec3(chosen[0].x, chosen[0].y, chosen[0].z), chosen[0].yaw);
    KeepOutZone k = makeKoz(
        geometry::orientedRectangle(Vec2(chosen[0].x, chosen[0].y), kEscortSide, kEscortSide, 0.0),
        "restricted");
    k.alt_min = 0.0;
    k.alt_max = std::round(uav_.altitude_max + 20.0);
    for (const auto& p : chosen) k.motion.push_back({p.t, p.x, p.y, 0.0, 0.0});
    sc_.mission.kozs.push_back(k);
    add(std::move(e), "hostile", std::move(chosen));
  }

  // 2-6 aircraft: the first half cross the reference flight about when the UAV would get
  // there (at 60 % of its top speed after the climb), the rest circle near it (or cross where
  // no lap fits). Each clears the static obstacles, keeps 20 m from the start's column and the
  // goal radius + 15 m from the goal horizontally, and 10 m from the aircraft before it.
  void addAircraft(const ReferenceFlight& ref, const Vec3& start, const Vec3& goal,
                   const planning::ValiditySettings& vs) {
    const planning::WorldValidity band(world_, std::vector<KeepOutZone>{}, vs);
    const double amin = uav_.altitude_min, amax = uav_.altitude_max;
    const double horizon = sc_.mission.time_limit;
    std::vector<Vec2> ref2;
    for (const auto& p : ref.path) ref2.push_back(Vec2(p.x(), p.y()));
    const double ref_len = geometry::polylineLength(ref2);
    const double t_climb = amin / 3.0;
    const double v_nominal = 0.6 * uav_.max_speed;
    const Vec2 s2(start.x(), start.y()), g2(goal.x(), goal.y());
    auto clearOfEnds = [&](const Vec2& a, const Vec2& b) {
      return geometry::pointSegmentDistance(s2, a, b) >= 20.0 &&
             geometry::pointSegmentDistance(g2, a, b) >= kAvoidGoalRadius + 15.0;
    };
    const int n = static_cast<int>(rng_.uniformInt(2, 6));
    const int n_cross = (n + 1) / 2;
    int crossing = 0;
    std::vector<Aircraft>& fleet = sc_.sim.aircraft;
    for (int i = 0; i < n; ++i) {
      Aircraft ac;
      ac.id = "aircraft_" + std::to_string(i + 1);
      const bool fixed_wing = rng_.bernoulli(0.5);
      ac.model = fixed_wing ? "fixed_wing" : "quadrotor";
      ac.size = fixed_wing ? Vec3(1.2, 2.0, 0.35) : Vec3(0.6, 0.6, 0.25);
      const double speed = fixed_wing ? rng_.uniform(10.0, 16.0) : rng_.uniform(4.0, 9.0);
      bool crossed = false;  // the kind of the pattern that fitted
      for (int attempt = 0; attempt < 60 && ac.trajectory.empty(); ++attempt) {
        // Among tall buildings (the city) long chords and wide laps rarely fit: after 30
        // attempts they shrink to half, and the last 15 of a crossing aircraft fly head-on. An
        // orbit that found no room in 40 attempts crosses instead (10 chords, then head-on).
        const double reach = attempt < 30 ? 1.0 : 0.5;
        const bool crossing_slot = i < n_cross;
        const bool cross_now = crossing_slot || attempt >= 40;
        const bool head_on = cross_now && attempt >= (crossing_slot ? 45 : 50);
        AircraftPattern pat;
        pat.speed = roundMilli(speed);
        const double along = rng_.uniform(0.25, 0.75) * ref_len;
        const Vec2 c = geometry::polylinePointAt(ref2, along);
        const Vec2 ahead = geometry::polylinePointAt(ref2, std::min(ref_len, along + 1.0));
        const double heading = std::atan2(ahead.y() - c.y(), ahead.x() - c.x());
        if (head_on) {
          // Last resort among tall buildings: head-on along the reference flight's longest leg,
          // a little above it (what clears the leg clears anything higher), 25 m short of its
          // ends. An orbit's slot that gets here tries the second-longest leg and the longest
          // one 10 m higher in turn (the longest leg may hold the crossing aircraft already).
          pat.kind = AircraftPattern::Kind::kCrossing;
          const double lift = rng_.uniform(0.5, 3.0);
          const double jitter = rng_.uniform(-6.0, 6.0);
          std::size_t leg = 0, leg2 = 0;
          double leg_len = 0.0, leg_start = 0.0, leg2_len = 0.0, leg2_start = 0.0, acc = 0.0;
          for (std::size_t k = 1; k < ref.path.size(); ++k) {
            const double h = (ref.path[k] - ref.path[k - 1]).head<2>().norm();
            if (h > leg_len) {
              leg2 = leg, leg2_len = leg_len, leg2_start = leg_start;
              leg = k, leg_len = h, leg_start = acc;
            } else if (h > leg2_len) {
              leg2 = k, leg2_len = h, leg2_start = acc;
            }
            acc += h;
          }
          const bool second = !crossing_slot && attempt % 2 == 1;
          const double above = !crossing_slot && !second ? 10.0 : 0.0;
          if (second) leg = leg2, leg_len = leg2_len, leg_start = leg2_start;
          if (leg_len < 60.0) continue;
          const Vec3 p0 = ref.path[leg - 1], p1 = ref.path[leg];
          const double u = 25.0 / leg_len;
          Vec3 a3 = p0 + (p1 - p0) * (1.0 - u), b3 = p0 + (p1 - p0) * u;  // towards the start
          const double top = std::max(a3.z(), b3.z()) + above;
          if (above > 0 && top > amax) continue;
          const double up = above + (top + lift <= amax ? lift : 0.0);
          a3.z() += up;
          b3.z() += up;
          if (!clearOfEnds(a3.head<2>(), b3.head<2>())) continue;
          pat.a = Vec3(roundMilli(a3.x()), roundMilli(a3.y()), roundMilli(a3.z()));
          pat.b = Vec3(roundMilli(b3.x()), roundMilli(b3.y()), roundMilli(b3.z()));
          pat.cross = 0.5 * (pat.a + pat.b);
          pat.t_cross = std::max(0.0, t_climb + (leg_start + 0.5 * leg_len) / v_nominal + jitter);
        } else if (cross_now) {
          pat.kind = AircraftPattern::Kind::kCrossing;
          const double turn = rng_.uniform(0.7, 2.4);
          const double side = rng_.bernoulli(0.5) ? 1.0 : -1.0;
          const double h1 = reach * rng_.uniform(60.0, 150.0);
          const double h2 = reach * rng_.uniform(60.0, 150.0);
          const double zc = rng_.uniform(amin + 2.0, std::min(amax - 2.0, amin + 12.0));
          const double dz = rng_.uniform(-6.0, 6.0);
          const double jitter = rng_.uniform(-6.0, 6.0);
          const double yaw = heading + side * turn;
          const Vec2 d(std::cos(yaw), std::sin(yaw));
          const double za = std::clamp(zc - dz * h1 / (h1 + h2), amin + 2.0, amax - 2.0);
          const double zb = std::clamp(zc + dz * h2 / (h1 + h2), amin + 2.0, amax - 2.0);
          const Vec2 a2 = c - d * h1, b2 = c + d * h2;
          if (!insideBy(a2, 5.0) || !insideBy(b2, 5.0) || !clearOfEnds(a2, b2)) continue;
          pat.a = Vec3(roundMilli(a2.x()), roundMilli(a2.y()), roundMilli(za));
          pat.b = Vec3(roundMilli(b2.x()), roundMilli(b2.y()), roundMilli(zb));
          pat.cross = pat.a + (pat.b - pat.a) * (h1 / (h1 + h2));
          pat.t_cross = std::max(0.0, t_climb + along / v_nominal + jitter);
        } else {
          pat.kind = AircraftPattern::Kind::kOrbit;
          const double side = rng_.bernoulli(0.5) ? 1.0 : -1.0;  // "Draw order" at the top
          const double off = reach * rng_.uniform(30.0, 90.0) * side;
          const double radius = reach * rng_.uniform(25.0, 60.0);
          const double climb = rng_.uniform(0.0, 4.0);
          const double z = rng_.uniform(amin + 2.0 + climb, amax - 2.0 - climb);
          pat.phase = rng_.uniform(-geometry::kPi, geometry::kPi);
          const Vec2 centre = c + Vec2(-std::sin(heading), std::cos(heading)) * off;
          if (!insideBy(centre, radius + 5.0) || std::abs((centre - s2).norm() - radius) < 20.0 ||
              std::abs((centre - g2).norm() - radius) < kAvoidGoalRadius + 15.0) {
            continue;
          }
          pat.centre = Vec3(roundMilli(centre.x()), roundMilli(centre.y()), roundMilli(z));
          pat.radius = roundMilli(radius);
          pat.climb = roundMilli(climb);
        }
        Trajectory traj = aircraftTrajectory(pat, horizon);
        bool ok = true;
        for (std::size_t k = 1; k < traj.size() && ok; ++k) {
          ok = band.staticSegmentValid(Vec3(traj[k - 1].x, traj[k - 1].y, traj[k - 1].z),
                                       Vec3(traj[k].x, traj[k].y, traj[k].z));
        }
        for (const auto& other : fleet) {
          for (double t = 0.0; t <= horizon && ok; t += 0.5) {
            const TrajectoryPoint p = sampleTrajectory(traj, t),
                                  q = sampleTrajectory(other.trajectory, t);
            ok = std::hypot(std::hypot(p.x - q.x, p.y - q.y), p.z - q.z) >= 10.0;
          }
        }
        if (ok) {
          ac.trajectory = std::move(traj);
          crossed = pat.kind == AircraftPattern::Kind::kCrossing;
        }
      }
      if (ac.trajectory.empty()) continue;
      if (crossed) ++crossing;
      fleet.push_back(std::move(ac));
    }
    if (fleet.size() < 2 || crossing < 1) {
      throw GenerationError("fewer than two aircraft (or none crossing) fit the airspace");
    }
  }

  // ------------------------------------------------------------------ everything else
  void drawUav() {
    uav_.altitude_min = std::round(rangeDraw(rng_, cfg_.uav_altitude_min));
    uav_.altitude_max =
        std::round(std::max(uav_.altitude_min + 15.0, rangeDraw(rng_, cfg_.uav_altitude_max)));
    uav_.max_speed = cfg_.uav_max_speed;
    CameraSpec front;
    front.name = "front";
    front.mount_xyz = Vec3(0.12, 0.0, -0.03);
    front.mount_rpy = Vec3(0.0, roundMilli(rangeDraw(rng_, cfg_.front_pitch)), 0.0);
    front.width = cfg_.camera_width;
    front.height = cfg_.camera_height;
    front.hfov_deg = roundMilli(rangeDraw(rng_, cfg_.front_hfov));
    front.rate_hz = cfg_.camera_rate_hz;
    front.modalities = {"rgb", "depth", "segmentation", "instances"};
    CameraSpec down = front;
    down.name = "down";
    down.mount_xyz = Vec3(0.0, 0.0, -0.06);
    down.mount_rpy = Vec3(0.0, 90.0, 0.0);
    down.hfov_deg = roundMilli(rangeDraw(rng_, cfg_.down_hfov));
    uav_.cameras = {front, down};
  }

  // The UAV starts on the ground at an intersection away from the targets and outside every
  // keep-out zone.
  void placeUavStart() {
    Vec2 first_target(0, 0);
    for (const auto& se : sc_.sim.entities) {
      if (se.role == "target") {
        first_target = se.entity.box.center2();
        break;
      }
    }
    auto allowed = [&](const Vec2& p, double far) {
      const double d = (p - first_target).norm();
      if (d < std::min(120.0, 0.5 * far) || d > far) return false;
      for (const auto& k : sc_.mission.kozs) {
        if (k.polygon.distance(p) < 5.0) return false;
      }
      return true;
    };
    if (plan_ && plan_->uav_start_within) {
      // A spec's band: drawn from every intersection in it (constructive, no retries).
      std::vector<Vec2> feasible;
      for (const auto& n : world_.nodes()) {
        if (allowed(n.position, *plan_->uav_start_within)) feasible.push_back(n.position);
      }
      if (feasible.empty()) {
        throw GenerationError(
            "no intersection within uav.start_within of the target outside "
            "the keep-out zones");
      }
      const Vec2 p = rng_.pick(feasible);
      uav_.start = {0.0, p.x(), p.y(), 0.0,
                    roundMilli(rng_.uniform(-geometry::kPi, geometry::kPi))};
      sc_.sim.uav = uav_;
      return;
    }
    // A track mission's search must be feasible: the UAV starts within max(240 m, 60 % of its
    // top speed x (departure - kTrackLead)) of the target, so that even at top speed (240 m:
    // 20 s) it arrives kTrackLead s before the target departs and the area's window closes,
    // for its climb and the sweep of the area's likeliest cell (track departures are 50-80 s).
    // Elsewhere the start lies 120-600 m from the target.
    constexpr double kTrackLead = 30.0;  // s
    const double far =
        cls_ == ScenarioClass::kTrack
            ? std::clamp(0.6 * uav_.max_speed * (depart_ - kTrackLead), 240.0, 600.0)
            : 600.0;
    for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
      const Vec2 p = world_.nodes()[static_cast<std::size_t>(randomNode())].position;
      if (!allowed(p, far)) continue;
      uav_.start = {0.0, p.x(), p.y(), 0.0,
                    roundMilli(rng_.uniform(-geometry::kPi, geometry::kPi))};
      sc_.sim.uav = uav_;
      return;
    }
    throw GenerationError("no UAV start position outside the keep-out zones");
  }

  // Ambient traffic (cars driving a few blocks, then stopping) and strolling pedestrians.
  void addTraffic() {
    const int cars =
        static_cast<int>(rng_.uniformInt(cfg_.traffic_count_min, cfg_.traffic_count_max));
    for (int i = 0; i < cars; ++i) {
      const int hops = static_cast<int>(rng_.uniformInt(2, 5));  // "Draw order" at the top
      std::vector<int> nodes = randomWalk(randomNode(), hops);
      if (nodes.size() < 2) continue;
      DriveSpec spec = driveSpec(rangeDraw(rng_, cfg_.car_speed));
      const std::vector<Vec2> path = nodePositions(nodes);
      spec.start_offset = rng_.uniform(0.0, 0.5) * (path[1] - path[0]).norm();
      spec.depart_delay = rng_.uniform(0.0, 20.0);
      Trajectory traj = planDrive(path, spec);
      const auto& model = catalog::pickModel(rng_);
      Entity e = makeCar(model, catalog::pick(rng_, catalog::carColors()),
                         Vec3(traj[0].x, traj[0].y, traj[0].z), traj[0].yaw);
      add(std::move(e), "traffic", std::move(traj));
    }
    const int peds =
        static_cast<int>(rng_.uniformInt(cfg_.pedestrian_count_min, cfg_.pedestrian_count_max));
    for (int i = 0; i < peds; ++i) {
      const Block& b = world_.blocks()[static_cast<std::size_t>(
          rng_.uniformInt(0, static_cast<long>(world_.blocks().size()) - 1))];
      const double ring = geometry::polylineLength(b.sidewalk);
      const double s0 = rng_.uniform(0.0, ring);
      const double span = rng_.uniform(60.0, 300.0);  // "Draw order" at the top
      const double dist = span * (rng_.bernoulli(0.5) ? 1.0 : -1.0);
      const double start = rng_.uniform(0.0, 30.0);
      const double speed = rangeDraw(rng_, cfg_.pedestrian_speed);
      Trajectory traj = walkRing(b.sidewalk, s0, s0 + dist, speed, start);
      Entity p;
      p.id = nextPedId();
      p.cls = EntityClass::kPedestrian;
      p.attributes.set("clothing_color", catalog::pick(rng_, catalog::clothingColors()));
      p.attributes.set("activity", std::string("walking"));
      p.box = boxFromPose(Vec3(traj[0].x, traj[0].y, 0.0), traj[0].yaw,
                          Vec3(0.5, 0.6, roundMilli(rng_.uniform(1.55, 1.9))));
      add(std::move(p), "pedestrian", std::move(traj));
    }
  }

  // In a city area search, half the time: a restricted KOZ that is a building's volume (its
  // footprint grown by kBuildingStandoff, from the ground to kBuildingStandoff above the roof),
  // a building of the target's AOI whose zone stays 15 m clear of the target. Drawn from a
  // stream of its own, so that the rest of the scenario is unchanged.
  void addBuildingKoz(const Vec2& target) {
    constexpr double kBuildingStandoff = 5.0;
    Rng r(deriveSeed(seed_, 0x424C44474B4F5AULL));
    if (!r.bernoulli(0.5)) return;
    const Polygon& aoi = sc_.mission.aois.front().polygon;
    std::vector<const Entity*> fits;
    for (const auto& e : world_.entities()) {
      if (e.cls != EntityClass::kBuilding || !aoi.contains(e.box.center2())) continue;
      const Polygon zone =
          geometry::orientedRectangle(e.box.center2(), e.box.size.x() + 2 * kBuildingStandoff,
                                      e.box.size.y() + 2 * kBuildingStandoff, e.box.yaw);
      if (zone.contains(target) || zone.distance(target) < 15.0) continue;
      fits.push_back(&e);
    }
    if (fits.empty()) return;
    const Entity& b =
        *fits[static_cast<std::size_t>(r.uniformInt(0, static_cast<long>(fits.size()) - 1))];
    KeepOutZone k = makeKoz(roundPolygon(geometry::orientedRectangle(
                                b.box.center2(), b.box.size.x() + 2 * kBuildingStandoff,
                                b.box.size.y() + 2 * kBuildingStandoff, b.box.yaw)),
                            "restricted");
    k.alt_min = 0.0;
    k.alt_max = std::ceil(b.box.maxZ() + kBuildingStandoff);
    sc_.mission.kozs.push_back(k);
  }

  static bool sameSignalPlan(const SignalPlan& a, const SignalPlan& b) {
    if (a.cycle() != b.cycle() || a.left != b.left ||
        a.intersections.size() != b.intersections.size())
      return false;
    for (std::size_t i = 0; i < a.intersections.size(); ++i) {
      if (a.intersections[i].offset != b.intersections[i].offset) return false;
    }
    return true;
  }

  // A mission car's trajectory that ends in a lane, in the city: it stops before the
  // intersection ahead and, on an arterial, pulls over to the kerb (planning::stopAtKerb), so
  // that the ambient traffic keeps its lanes and boxes; `lead`: the car ahead of it in a convoy,
  // stopped already. nullopt when the stop has to move and cannot (the caller keeps a lead's
  // trajectory as it is and drops a follower); in the suburb the trajectory unchanged.
  std::optional<Trajectory> cityStop(const Trajectory& traj, const Trajectory* lead = nullptr) {
    if (world_.params().type != WorldType::kCity) return traj;
    const CityParams& cp = world_.params().city;
    planning::KerbStop k;
    k.sidewalk_width = cp.sidewalk_width;
    k.kerb_street_width = cp.arterial_width;
    if (lead && !lead->empty()) k.behind = lead->back();
    planning::KerbStopResult r = planning::stopAtKerb(world_, traj, k, routeSettings());
    if (!r.ok) return std::nullopt;
    return std::move(r.trajectory);
  }

  std::uint64_t citySeed() const { return cityTrafficSeed(seed_); }

  // A mission vehicle's trajectory (car length `length`), in the city retimed to wait at the stop
  // lines of the signal plan that the scenario's traffic carries (drawn before the traffic is
  // added), behind `lead` when it follows one; in the suburb unchanged.
  Trajectory obeyCitySignals(const Trajectory& traj, double length,
                             const Trajectory* lead = nullptr, double lead_length = 0.0) {
    if (world_.params().type != WorldType::kCity) return traj;
    if (!city_signals_) {
      city_signals_ = drawCityTraffic(world_, citySeed(), sc_.mission.time_limit).plan;
    }
    return obeySignals(traj, length, *city_signals_, lead, lead_length);
  }

  // The city's signalised ambient traffic and crowd (scenario/city_traffic.h), drawn from a
  // stream of its own over the mission's time limit. The crowd and the cars come last: when they
  // are a window of a shared traffic episode, a batch writes them as a reference
  // (SimConfig::traffic) and a reader appends them again, pedestrians first.
  void addCityTraffic() {
    CityTraffic traffic =
        simulateCityTraffic(world_, citySeed(), sc_.mission.time_limit, {}, !traffic_by_reference_);
    if (city_signals_ && !sameSignalPlan(*city_signals_, traffic.plan)) {
      // The mission's vehicles were retimed for a plan drawn with a time limit on the other side
      // of half an episode's length.
      throw GenerationError(
          "the city's signal plan changed after the mission's vehicles obeyed it");
    }
    TrafficEpisodeRef ref;
    const TrafficEpisode& ep = traffic.episode->episode;
    // Written by reference, the episode's cars and walking pedestrians are only named (nothing
    // of the scene reads them); those who stand are occluders and members of their block.
    const bool lean = traffic_by_reference_ && traffic.episode->text;
    if (lean) ref.lean = 0;
    for (std::size_t i = 0; i < traffic.pedestrians.size(); ++i) {
      CityPedestrian& ped = traffic.pedestrians[i];
      ref.pedestrian_ids.push_back(nextPedId());
      if (lean && !ep.pedestrians[i].trajectory.empty()) continue;
      ScenarioEntity se =
          cityPedestrianEntity(ped, std::move(ped.trajectory), ref.pedestrian_ids.back());
      se.entity.block = world_.blockAt(se.entity.box.center2());
      add(std::move(se.entity), "pedestrian", std::move(se.trajectory));
      if (lean) ++*ref.lean;
    }
    // The episode's cars never see the mission's own: those that would come near one are
    // withheld from this scenario (each still takes its id, so that the others keep theirs).
    std::vector<MovingFootprint> own, ambient;
    for (const auto& se : sc_.sim.entities) {
      if (isMissionCar(se)) own.push_back(footprintOf(se));
    }
    for (std::size_t i = 0; i < traffic.cars.size(); ++i) {
      MovingFootprint f;
      f.trajectory = &traffic.episode->trajectories[i];
      f.time_shift = traffic.offset;
      f.length = ep.cars[i].size.x();
      f.width = ep.cars[i].size.y();
      if (i < traffic.episode->clearance.size()) f.blocks = &traffic.episode->clearance[i];
      ambient.push_back(f);
    }
    const std::vector<std::size_t> held = trafficToWithhold(
        own, ambient, traffic.episode->clearance_index, sc_.mission.time_limit);
    for (std::size_t i = 0, h = 0; i < traffic.cars.size(); ++i) {
      const std::string id = nextCarId();
      ref.car_ids.push_back(id);
      if (h < held.size() && held[h] == i) {
        ref.withheld.push_back(id);
        ++h;
        continue;
      }
      if (lean) continue;
      ScenarioEntity se = episodeCarEntity(ep, i, std::move(traffic.cars[i].trajectory), id);
      se.entity.block = world_.blockAt(se.entity.box.center2());
      sc_.sim.entities.push_back(std::move(se));
    }
    if (traffic.episode->text) {
      ref.file = "../" + trafficEpisodeFileName(ep.index);
      ref.episode = ep.index;
      ref.offset = traffic.offset;
      ref.sha256 = traffic.episode->sha256;
      ref.text = traffic.episode->text;
      sc_.sim.traffic = std::move(ref);
    }
    sc_.sim.signals = std::move(traffic.plan);
  }

  void drawEnvironment() {
    Environment& env = sc_.sim.environment;
    env.time_of_day = roundMilli(rangeDraw(rng_, cfg_.time_of_day));
    const double wp = cfg_.weather_probability;
    if (rng_.bernoulli(wp)) {
      (rng_.bernoulli(0.5) ? env.snow : env.rain) = roundMilli(rng_.uniform(0.05, 1.0));
    }
    if (rng_.bernoulli(wp * 0.5)) env.dust = roundMilli(rng_.uniform(0.05, 1.0));
    if (rng_.bernoulli(wp)) env.fog = roundMilli(rng_.uniform(0.05, 1.0));
    env.foliage = roundMilli(rangeDraw(rng_, cfg_.foliage));
    const double ws = rangeDraw(rng_, cfg_.wind_speed), wd = rng_.uniform(0, 2 * geometry::kPi);
    env.wind_mean = Vec3(roundMilli(ws * std::cos(wd)), roundMilli(ws * std::sin(wd)), 0.0);
    env.gust_intensity = roundMilli(rangeDraw(rng_, cfg_.gust_intensity));
    Perturbations& p = sc_.sim.perturbations;
    p.gaussian_noise_std = roundMilli(rangeDraw(rng_, cfg_.noise_std) * 1000.0) / 1000.0;
    p.salt_pepper_probability = std::round(rangeDraw(rng_, cfg_.salt_pepper) * 1e5) / 1e5;
    p.motion_blur_px = roundMilli(rangeDraw(rng_, cfg_.motion_blur_px));
    if (plan_) {
      if (plan_->snow) env.snow = roundMilli(*plan_->snow);
      if (plan_->rain) env.rain = roundMilli(*plan_->rain);
      if (plan_->dust) env.dust = roundMilli(*plan_->dust);
      if (plan_->fog) env.fog = roundMilli(*plan_->fog);
    }
  }

  void finishGroups() { sc_.sim.groups = currentGroups(); }

  // The perception-only flight of a follow or track mission (planning::planChasePath): climb at
  // the start to mid-band, then pursue the phase's first target and keep its chase point to the
  // time limit. follow: the envelope's centre (d* behind along the car's path, h* above it),
  // with the camera that sees it best; track: straight above it at mid-band, with the camera
  // that scores the phase (down). False (and the look-at flight instead) for the other classes,
  // when the chase cannot go on (a keep-out zone over it), or when it sees the target less than
  // half of the time after catching up.
  bool planChase(const planning::WorldValidity& validity,
                 const planning::UavPlannerSettings& settings, const Vec3& ground, const Vec3& air,
                 double climbed) {
    const UavSpec& uav = sc_.sim.uav;
    const MissionPhase* phase = nullptr;
    for (const auto& p : sc_.mission.phases) {
      if (p.type == PhaseType::kFollow || p.type == PhaseType::kTrack) phase = &p;
    }
    if (phase == nullptr || phase->targets.empty()) return false;
    const ScenarioEntity* target = nullptr;
    for (const auto& se : sc_.sim.entities) {
      if (se.entity.id == phase->targets.front()) target = &se;
    }
    if (target == nullptr || target->trajectory.empty()) return false;
    const bool follow = phase->type == PhaseType::kFollow;
    planning::ChaseSettings chase;
    chase.behind = follow ? phase->follow.distance : 0.0;
    chase.height = follow ? phase->follow.height : air.z();
    // The camera that sees the target best from the chase point: facing it with the front
    // camera, or the down camera with the target along the image's width (turned a quarter) or
    // its height; track: the down camera, which scores the phase. The first of the best.
    std::vector<std::pair<std::string, double>> options = {{"down", 0.0}};
    if (follow) options = {{"front", 0.0}, {"down", 0.5 * geometry::kPi}, {"down", 0.0}};
    std::optional<planning::ChaseResult> best;
    const CameraSpec* best_camera = nullptr;
    for (const auto& [name, yaw_offset] : options) {
      for (const auto& c : uav.cameras) {
        if (c.name != name) continue;
        chase.yaw_offset = yaw_offset;
        planning::ChaseResult r = planning::planChasePath(
            validity, c, air, climbed, sc_.mission.time_limit, target->trajectory,
            target->entity.box.size, uav.altitude_min, uav.altitude_max, settings, chase);
        if (r.status != planning::PlanStatus::kExact) return false;  // the same flight for all
        if (!best || r.seen > best->seen) {
          best = std::move(r);
          best_camera = &c;
        }
      }
    }
    if (!best) return false;
    const planning::ChaseResult& r = *best;
    const CameraSpec* camera = best_camera;
    PerceptionPath pp;
    pp.status = "chase";
    pp.camera = camera->name;
    // A chase that does not see the target at least half of the time after catching up (held
    // behind a tower in the city) gives way to the look-at flight.
    if (!(r.frames > 0 && r.seen * 2 >= r.frames)) return false;
    pp.targets_seen.push_back(target->entity.id);
    pp.trajectory = {{0.0, ground.x(), ground.y(), ground.z(), uav.start.yaw}};
    for (const auto& k : r.path) pp.trajectory.push_back(k);
    sc_.sim.uav.perception_path = pp;
    return true;
  }

  // The perception-only flight (planning::planLookAtPath with the down camera over the
  // mission's validity): climb at the start to mid-band, hover there until every moving target
  // has stopped, then visit a viewpoint of each target (parked: its box centre; moving: the
  // centre of its box where it stops, so a view is only claimed once it is there). Seeded from
  // the scenario seed; a planning failure is written as its status with what was planned.
  void planPerceptionPath() {
    const UavSpec& uav = sc_.sim.uav;
    const planning::WorldValidity validity(world_, sc_.mission, planning::validitySettingsFor(uav));
    planning::UavPlannerSettings settings;
    settings.speed.max_speed = uav.max_speed;
    settings.time_limit = 600.0;  // iteration budgets end the search: deterministic under load
    std::vector<planning::LookAtTarget> targets;
    double hold = 0.0;  // when the last moving target has stopped
    for (const auto& se : sc_.sim.entities) {
      if (se.role != "target") continue;
      planning::LookAtTarget t;
      t.id = se.entity.id;
      OrientedBox box = se.entity.box;
      if (!se.trajectory.empty()) {
        box = poseBox(se.entity.box, se.trajectory.back());
        hold = std::max(hold, se.trajectory.back().t);
      }
      t.point = box.center;
      targets.push_back(t);
    }
    const Vec3 ground(uav.start.x, uav.start.y, uav.start.z);
    const Vec3 air(uav.start.x, uav.start.y,
                   roundMilli(0.5 * (uav.altitude_min + uav.altitude_max)));
    const double climbed = roundMilli((air.z() - ground.z()) / settings.speed.climb_rate);
    if (planChase(validity, settings, ground, air, climbed)) return;
    const double t0 = std::max(climbed + 1.0, std::ceil(hold));
    PerceptionPath pp;
    pp.trajectory = {{0.0, ground.x(), ground.y(), ground.z(), uav.start.yaw},
                     {climbed, air.x(), air.y(), air.z(), uav.start.yaw},
                     {t0, air.x(), air.y(), air.z(), uav.start.yaw}};
    // The down camera first; the front camera when that does not see every target (a keep-out
    // zone over a target denies the overhead view), keeping whichever sees more.
    std::optional<planning::LookAtResult> best;
    for (const char* name : {"down", "front"}) {
      for (const auto& c : uav.cameras) {
        if (c.name != name) continue;
        planning::LookAtResult r = planning::planLookAtPath(
            validity, c, air, t0, targets, settings, deriveSeed(seed_, 0x4C4F4F4B00000000ULL));
        if (!best || r.viewpoints.size() > best->viewpoints.size()) {
          best = std::move(r);
          pp.camera = c.name;
        }
      }
      if (best && best->status == planning::PlanStatus::kExact) break;
    }
    if (!best) return;  // no camera to plan for
    const planning::LookAtResult& r = *best;
    pp.status = planning::toString(r.status);
    for (const auto& v : r.viewpoints) pp.targets_seen.push_back(v.target_id);
    for (const auto& q : r.flight.path) {
      if (q.t > pp.trajectory.back().t) pp.trajectory.push_back(q);
    }
    sc_.sim.uav.perception_path = pp;
  }

  const World& world_;
  const GeneratorConfig& cfg_;
  ScenarioClass cls_;
  std::uint64_t seed_;
  Rng rng_;
  RelationEvaluator eval_;
  Scenario sc_;
  UavSpec uav_;
  std::vector<char> slot_taken_;
  DriveOffRoute pursuit_route_;  // the pursuit target's route (track: the convoy follows it)
  double depart_ = 0.0;          // when the pursuit target drives off (s)
  std::vector<int> car_ids_, ped_ids_;
  std::vector<Group> extra_groups_;
  const ScenarioPlan* plan_;
  bool traffic_by_reference_ = false;
  std::optional<SignalPlan> city_signals_;  // the plan the city traffic will carry, once drawn
};

}  // namespace

Scenario generateScenario(const World& world, const GeneratorConfig& config, ScenarioClass cls,
                          std::uint64_t seed, const ScenarioPlan* plan, bool traffic_by_reference) {
  try {
    return ScenarioBuilder(world, config, cls, seed, plan, traffic_by_reference).build();
  } catch (const GenerationError& e) {
    throw GenerationError(std::string(toString(cls)) + " seed " + std::to_string(seed) + ": " +
                          e.what());
  }
}

}  // namespace hameritt::scenario
