// Semantic checks of sim_config.json, world.json and manifest.json.
#include <map>

#include "hameritt/scenario/signal_compliance.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/traffic_clearance.h"
#include "validation_internal.h"

namespace hameritt::scenario::validation_internal {

void Semantics::simConfig() {
  scenarioId(doc_, "/scenario_id");
  if (exists("/world/params")) worldParams("/world/params");

  IdSet ids(this, "entity id");
  bool has_target = false;
  const json& ents = arrayOrEmpty(doc_, "entities");
  for (std::size_t i = 0; i < ents.size(); ++i) {
    const std::string p = jsonPointerAppend("/entities", i);
    ids.note(ents[i], p);
    has_target = has_target || stringAt(ents[i], "role") == std::optional<std::string>("target");
    trajectoryOrder(arrayOrEmpty(ents[i], "trajectory"), p + "/trajectory");
  }
  if (exists("/traffic")) trafficReference(ids);
  if (exists("/signals")) signalCompliance(ents);
  const bool avoid = stringAt(doc_, "class") == std::optional<std::string>("avoid");
  if (!ents.empty() && !has_target && !avoid) {
    add("/entities", "role_target", "no entity has role 'target'");
  }
  // Aircraft share the entity id space; their trajectories are ordered and continuous (no
  // jump faster than kMaxAircraftSpeed between samples).
  const json& air = arrayOrEmpty(doc_, "aircraft");
  for (std::size_t i = 0; i < air.size(); ++i) {
    const std::string p = jsonPointerAppend("/aircraft", i);
    ids.note(air[i], p);
    const json& traj = arrayOrEmpty(air[i], "trajectory");
    trajectoryOrder(traj, p + "/trajectory");
    trajectorySpeed(traj, p + "/trajectory", kMaxAircraftSpeed);
  }

  IdSet group_ids(this, "group id");
  const json& groups = arrayOrEmpty(doc_, "groups");
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const std::string p = jsonPointerAppend("/groups", i);
    group_ids.note(groups[i], p);
    const json& members = arrayOrEmpty(groups[i], "members");
    for (std::size_t k = 0; k < members.size(); ++k) {
      if (members[k].is_string() && !ids.has(members[k].get<std::string>())) {
        add(jsonPointerAppend(p + "/members", k), "group_member",
            "'" + members[k].get<std::string>() + "' is not an entity of this scenario");
      }
    }
  }
  if (exists("/uav/altitude"))
    altitude(doc_.at(json::json_pointer("/uav/altitude")), "/uav/altitude");
  if (exists("/uav/perception_path")) perceptionPath(ents);
}

void Semantics::trafficReference(IdSet& ids) {
  for (const char* key : {"cars", "pedestrians"}) {
    const json& list = arrayOrEmpty(doc_.at("traffic"), key);
    for (std::size_t i = 0; i < list.size(); ++i) {
      if (list[i].is_string()) {
        ids.noteId(list[i].get<std::string>(),
                   jsonPointerAppend(std::string("/traffic/") + key, i));
      }
    }
  }
  // The reader resolves the reference; its message names the file, the field and what it
  // expected. Issues elsewhere in the document are reported by the other checks.
  try {
    (void)loadSimConfig(file_);
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    if (m.find(": traffic") != std::string::npos || m.find(": signals") != std::string::npos) {
      add("/traffic", "traffic_episode", m);
    }
  }
}

void Semantics::signalCompliance(const json& ents) {
  SimConfig sc;
  try {
    sc = simConfigFromJson(doc_, file_);
  } catch (const ConfigError&) {
    return;  // reported by the schema, the reader's other checks or trafficReference()
  }
  if (!sc.signals) return;
  std::map<std::string, std::size_t> index;
  for (std::size_t i = 0; i < ents.size(); ++i) {
    if (const auto id = stringAt(ents[i], "id")) index.emplace(*id, i);
  }
  for (const auto& se : sc.entities) {
    if (se.entity.cls != EntityClass::kCar || se.role == "traffic" || se.trajectory.size() < 2)
      continue;
    const auto it = index.find(se.entity.id);
    if (it == index.end()) continue;
    for (const SignalEntry& e : signalEntries(se.trajectory, se.entity.box.size.x(), *sc.signals)) {
      if (e.allowed) continue;
      add(jsonPointerAppend("/entities", it->second) + "/trajectory", "signal",
          se.entity.id + " (" + se.role + ") " + describeEntry(e, *sc.signals));
    }
  }
  trafficClearance(sc, index);
}

void Semantics::trafficClearance(const SimConfig& sc,
                                 const std::map<std::string, std::size_t>& index) {
  std::vector<const ScenarioEntity*> own, ambient;
  for (const auto& se : sc.entities) {
    if (isMissionCar(se)) own.push_back(&se);
    if (se.entity.cls == EntityClass::kCar && se.role == "traffic") ambient.push_back(&se);
  }
  std::vector<MovingFootprint> fo, fa;
  for (const auto* se : own) fo.push_back(footprintOf(*se));
  for (const auto* se : ambient) fa.push_back(footprintOf(*se));
  for (const std::size_t i : trafficToWithhold(fo, fa, sc.duration, 0.0)) {
    for (std::size_t m = 0; m < own.size(); ++m) {
      const auto t = firstOverlap(fo[m], fa[i], sc.duration, 0.0);
      if (!t) continue;
      const auto it = index.find(own[m]->entity.id);
      const std::string where = sc.traffic ? std::string("/traffic/withheld")
                                : it != index.end()
                                    ? jsonPointerAppend("/entities", it->second) + "/trajectory"
                                    : std::string("/entities");
      add(where, "traffic_clearance",
          ambient[i]->entity.id + " (traffic) overlaps " + own[m]->entity.id + " (" + own[m]->role +
              ") at t = " + num(*t) + " s: expected the ambient car withheld");
      break;
    }
  }
}

void Semantics::trajectoryOrder(const json& traj, const std::string& pointer) {
  double prev = 0.0;
  for (std::size_t k = 0; k < traj.size(); ++k) {
    if (!traj[k].is_array() || traj[k].empty() || !traj[k][0].is_number()) break;
    const double t = traj[k][0].get<double>();
    const std::string sp = jsonPointerAppend(pointer, k);
    if (k == 0 && t < 0) {
      add(sp, "trajectory_order", "t = " + num(t) + " is before the mission start");
    } else if (k > 0 && !(t > prev)) {
      add(sp, "trajectory_order",
          "t = " + num(t) + " does not increase on the previous sample's t = " + num(prev));
    }
    prev = t;
  }
}

void Semantics::trajectorySpeed(const json& traj, const std::string& pointer, double max_speed) {
  auto sample = [](const json& v, double* out) {
    if (!v.is_array() || v.size() < 4) return false;
    for (int c = 0; c < 4; ++c) {
      if (!v[static_cast<std::size_t>(c)].is_number()) return false;
      out[c] = v[static_cast<std::size_t>(c)].get<double>();
    }
    return true;
  };
  double a[4], b[4];
  for (std::size_t k = 1; k < traj.size(); ++k) {
    if (!sample(traj[k - 1], a) || !sample(traj[k], b) || !(b[0] > a[0])) continue;
    const double d = std::sqrt((b[1] - a[1]) * (b[1] - a[1]) + (b[2] - a[2]) * (b[2] - a[2]) +
                               (b[3] - a[3]) * (b[3] - a[3]));
    const double v = d / (b[0] - a[0]);
    if (!(v <= max_speed)) {
      add(jsonPointerAppend(pointer, k), "trajectory_speed",
          "jumps " + num(d) + " m in " + num(b[0] - a[0]) + " s (" + num(v) + " m/s, more than " +
              num(max_speed) + " m/s): the trajectory is not continuous");
    }
  }
}

void Semantics::perceptionPath(const json& ents) {
  const std::string base = "/uav/perception_path";
  const json& pp = doc_.at(json::json_pointer(base));
  trajectoryOrder(arrayOrEmpty(pp, "trajectory"), base + "/trajectory");
  std::set<std::string> targets;
  for (const auto& e : ents) {
    if (stringAt(e, "role") == std::optional<std::string>("target")) {
      if (auto id = stringAt(e, "id")) targets.insert(*id);
    }
  }
  const json& seen = arrayOrEmpty(pp, "targets_seen");
  for (std::size_t k = 0; k < seen.size(); ++k) {
    if (seen[k].is_string() && !targets.count(seen[k].get<std::string>())) {
      add(jsonPointerAppend(base + "/targets_seen", k), "reference",
          "'" + seen[k].get<std::string>() + "' is not a target of this scenario");
    }
  }
}

void Semantics::world() {
  if (exists("/params")) worldParams("/params");
  if (const json* b = member(doc_, "bounds")) {
    Vec2 lo, hi;
    const json* mn = member(*b, "min");
    const json* mx = member(*b, "max");
    if (mn && mx && toPoint(*mn, &lo) && toPoint(*mx, &hi) &&
        (lo.x() > hi.x() || lo.y() > hi.y())) {
      add("/bounds", "bounds", "min is not below max");
    }
  }
  // Entities first: edges and slots refer to them.
  IdSet ids(this, "entity id");
  std::unordered_map<std::string, std::string> classes;
  const json& ents = arrayOrEmpty(doc_, "entities");
  for (std::size_t i = 0; i < ents.size(); ++i) {
    const std::string p = jsonPointerAppend("/entities", i);
    if (ids.note(ents[i], p)) {
      if (const auto id = stringAt(ents[i], "id"))
        classes[*id] = stringAt(ents[i], "class").value_or("");
    }
  }
  const json& blocks = arrayOrEmpty(doc_, "blocks");
  for (std::size_t i = 0; i < ents.size(); ++i) {
    const json* b = member(ents[i], "block");
    if (b && isInteger(*b) && b->get<double>() >= static_cast<double>(blocks.size())) {
      add(jsonPointerAppend("/entities", i) + "/block", "reference",
          "block index " + b->dump() + " but there are " + std::to_string(blocks.size()) +
              " blocks");
    }
  }
  static const json kNone = json::object();
  const json* streets = member(doc_, "streets");
  const std::size_t n_nodes = arrayOrEmpty(streets ? *streets : kNone, "nodes").size();
  {
    const json& edges = arrayOrEmpty(streets ? *streets : kNone, "edges");
    for (std::size_t i = 0; i < edges.size(); ++i) {
      const std::string p = jsonPointerAppend("/streets/edges", i);
      const json* a = member(edges[i], "a");
      const json* b = member(edges[i], "b");
      for (const json* e : {a, b}) {
        if (e && isInteger(*e) && e->get<double>() >= static_cast<double>(n_nodes)) {
          add(p + (e == a ? "/a" : "/b"), "reference",
              "node index " + e->dump() + " but there are " + std::to_string(n_nodes) + " nodes");
        }
      }
      if (a && b && *a == *b) add(p, "reference", "the edge starts and ends at node " + a->dump());
      if (const auto ent = stringAt(edges[i], "entity")) {
        auto it = classes.find(*ent);
        if (it == classes.end() || it->second != "street") {
          add(p + "/entity", "reference", "'" + *ent + "' is not a street entity of this world");
        }
      }
    }
  }
  IdSet names(this, "block name");
  for (std::size_t i = 0; i < blocks.size(); ++i) {
    const std::string p = jsonPointerAppend("/blocks", i);
    names.note(blocks[i], p, "name");
    if (const json* o = member(blocks[i], "outline")) polygon(*o, p + "/outline");
    std::vector<Vec2> ring;
    if (const json* sw = member(blocks[i], "sidewalk");
        sw && toPoints(*sw, &ring) && ring.size() >= 4) {
      if (ring.front() != ring.back()) {
        add(p + "/sidewalk", "sidewalk_ring", "the sidewalk ring must end at its first point");
      } else {
        ring.pop_back();
        if (!Polygon(ring).isSimple())
          add(p + "/sidewalk", "polygon_simple", "the sidewalk ring is not simple");
      }
    }
  }
  const json& slots = arrayOrEmpty(doc_, "parking_slots");
  for (std::size_t i = 0; i < slots.size(); ++i) {
    if (const auto occ = stringAt(slots[i], "occupant"); occ && !ids.has(*occ)) {
      add(jsonPointerAppend("/parking_slots", i) + "/occupant", "reference",
          "'" + *occ + "' is not an entity of this world");
    }
  }
}

void Semantics::manifest() {
  const json& scen = arrayOrEmpty(doc_, "scenarios");
  const json* count = member(doc_, "count");
  if (count && isInteger(*count) && count->get<double>() != static_cast<double>(scen.size())) {
    add("/scenarios", "manifest_count",
        "count is " + count->dump() + " but " + std::to_string(scen.size()) +
            " scenarios are listed");
  }
  const json& classes = arrayOrEmpty(doc_, "classes");
  IdSet ids(this, "scenario id");
  for (std::size_t i = 0; i < scen.size(); ++i) {
    const json& e = scen[i];
    const std::string p = jsonPointerAppend("/scenarios", i);
    ids.note(e, p);
    const json* index = member(e, "index");
    if (index && isInteger(*index) && index->get<double>() != static_cast<double>(i)) {
      add(p + "/index", "manifest_index",
          "expected index " + std::to_string(i) + ", got " + index->dump());
    }
    const auto cls = stringAt(e, "class");
    if (cls && !classes.empty() && classes[i % classes.size()] != *cls) {
      add(p + "/class", "manifest_class",
          "scenario " + std::to_string(i) + " should have class " +
              classes[i % classes.size()].dump() + " (classes[" + std::to_string(i) + " % " +
              std::to_string(classes.size()) + "])");
    }
    scenarioId(e, p + "/id");
    const auto id = stringAt(e, "id"), path = stringAt(e, "path");
    if (id && path && *id != *path) {
      add(p + "/path", "manifest_path",
          "expected the scenario directory '" + *id + "', got '" + *path + "'");
    }
  }
}

}  // namespace hameritt::scenario::validation_internal
