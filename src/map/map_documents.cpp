// Reads mission.json and sim_config.json into the map's data, naming the file and field of a bad
// value.
#include "hameritt/scenario/sim_config_io.h"
#include "map_internal.h"

namespace hameritt::map::map_internal {

namespace {

void parseMission(const json& m, const DocReader& r, MapData* d) {
  d->scenario_id = r.stringAt(m, "", "scenario_id");
  d->cls = r.stringAt(m, "", "class");
  d->time_limit = r.numberAt(m, "", "time_limit");

  const json& obj = r.at(m, "", "objective");
  d->objective_type = r.stringAt(obj, "objective", "type");
  d->objective_text = r.stringAt(obj, "objective", "text");
  const json& targets = r.array(r.at(obj, "objective", "targets"), "objective.targets");
  for (std::size_t i = 0; i < targets.size(); ++i) {
    const std::string p = element("objective.targets", i);
    TargetData t;
    t.id = r.stringAt(targets[i], p, "id");
    std::string desc;
    for (const char* key : {"color", "make", "model"}) {
      const json* v = r.find(targets[i], p, key);
      if (v && !r.string(*v, member(p, key)).empty()) {
        desc += (desc.empty() ? "" : " ") + v->get<std::string>();
      }
    }
    if (const json* v = r.find(targets[i], p, "vehicle_class")) {
      const std::string vc = r.string(*v, member(p, "vehicle_class"));
      if (!vc.empty()) desc += (desc.empty() ? "" : " ") + std::string("(") + vc + ")";
    }
    t.description = desc;
    d->targets.push_back(std::move(t));
  }

  const json& aois = r.array(r.at(m, "", "areas_of_interest"), "areas_of_interest");
  for (std::size_t i = 0; i < aois.size(); ++i) {
    const std::string p = element("areas_of_interest", i);
    AoiData a;
    a.id = r.stringAt(aois[i], p, "id");
    a.polygon = r.points(r.at(aois[i], p, "polygon"), member(p, "polygon"), 3);
    a.window = r.window(aois[i], p);
    d->aois.push_back(std::move(a));
  }

  const json& kozs = r.array(r.at(m, "", "keep_out_zones"), "keep_out_zones");
  for (std::size_t i = 0; i < kozs.size(); ++i) {
    const std::string p = element("keep_out_zones", i);
    KozData k;
    k.id = r.stringAt(kozs[i], p, "id");
    k.purpose = r.stringAt(kozs[i], p, "purpose");
    k.polygon = r.points(r.at(kozs[i], p, "polygon"), member(p, "polygon"), 3);
    const json& alt = r.at(kozs[i], p, "altitude");
    k.alt_min = r.optionalNumber(alt, member(p, "altitude"), "min");
    k.alt_max = r.optionalNumber(alt, member(p, "altitude"), "max");
    k.window = r.window(kozs[i], p);
    d->kozs.push_back(std::move(k));
  }

  const json& priors = r.array(r.at(m, "", "area_priors"), "area_priors");
  for (std::size_t i = 0; i < priors.size(); ++i) {
    const std::string p = element("area_priors", i);
    PriorData pr;
    pr.aoi_id = r.stringAt(priors[i], p, "aoi_id");
    const std::string cp = member(p, "cells");
    const json& cells = r.array(r.at(priors[i], p, "cells"), cp);
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const std::string q = element(cp, c);
      CellData cell;
      cell.polygon = r.points(r.at(cells[c], q, "polygon"), member(q, "polygon"), 3);
      cell.probability = r.numberAt(cells[c], q, "probability");
      if (cell.probability < 0.0 || cell.probability > 1.0) {
        r.fail(member(q, "probability"), "expected a probability in [0, 1]");
      }
      pr.cells.push_back(std::move(cell));
    }
    d->priors.push_back(std::move(pr));
  }

  const json& routes = r.array(r.at(m, "", "routes"), "routes");
  for (std::size_t i = 0; i < routes.size(); ++i) {
    const std::string p = element("routes", i);
    RouteData rt;
    rt.id = r.stringAt(routes[i], p, "id");
    rt.polyline = r.points(r.at(routes[i], p, "polyline"), member(p, "polyline"), 2);
    rt.band = r.points(r.at(routes[i], p, "band_polygon"), member(p, "band_polygon"), 3);
    rt.band_width = r.numberAt(routes[i], p, "band_width");
    const std::string sp = member(p, "streets");
    const json& streets = r.array(r.at(routes[i], p, "streets"), sp);
    for (std::size_t s = 0; s < streets.size(); ++s) {
      rt.streets.push_back(r.string(streets[s], element(sp, s)));
    }
    d->routes.push_back(std::move(rt));
  }

  if (const json* phases = r.find(m, "", "phases")) {
    r.array(*phases, "phases");
    for (std::size_t i = 0; i < phases->size(); ++i) {
      const std::string p = element("phases", i);
      if (r.stringAt((*phases)[i], p, "type") != "avoid") continue;
      const std::string gp = member(p, "goal");
      const json& g = r.array(r.at((*phases)[i], p, "goal"), gp);
      if (g.size() != 3) r.fail(gp, "expected [x, y, z]");
      GoalData goal;
      goal.position = Vec2(r.number(g[0], element(gp, 0)), r.number(g[1], element(gp, 1)));
      goal.z = r.number(g[2], element(gp, 2));
      goal.radius = r.numberAt((*phases)[i], p, "goal_radius");
      d->goal = goal;
    }
  }

  if (const json* rel = r.find(m, "", "scene_relations")) {
    r.array(*rel, "scene_relations");
    for (std::size_t i = 0; i < rel->size(); ++i) {
      d->relations.push_back(r.stringAt((*rel)[i], element("scene_relations", i), "text"));
    }
  }
}

// A trajectory of [t, x, y, z, yaw] samples (t never decreasing) into mv's times and path.
void readPath(const json& traj_json, const std::string& tp, const DocReader& r, MoverData* mv) {
  const json& traj = r.array(traj_json, tp);
  for (std::size_t k = 0; k < traj.size(); ++k) {
    const std::string q = element(tp, k);
    if (!traj[k].is_array() || traj[k].size() != 5) r.fail(q, "expected [t, x, y, z, yaw]");
    const double t = r.number(traj[k][0], element(q, 0));
    if (!mv->times.empty() && t < mv->times.back()) r.fail(element(q, 0), "time goes backwards");
    mv->times.push_back(t);
    mv->path.emplace_back(r.number(traj[k][1], element(q, 1)), r.number(traj[k][2], element(q, 2)));
  }
}

void parseSimConfig(const json& s, const DocReader& r, MapData* d) {
  const json& entities = r.array(r.at(s, "", "entities"), "entities");
  for (std::size_t i = 0; i < entities.size(); ++i) {
    const std::string p = element("entities", i);
    const json& e = entities[i];
    MoverData mv;
    mv.id = r.stringAt(e, p, "id");
    mv.cls = r.stringAt(e, p, "class");
    mv.role = r.stringAt(e, p, "role");
    const std::string pp = member(p, "pose");
    const json& pose = r.at(e, p, "pose");
    mv.position = Vec2(r.numberAt(pose, pp, "x"), r.numberAt(pose, pp, "y"));
    mv.yaw = r.numberAt(pose, pp, "yaw");
    const std::string zp = member(p, "size");
    const json& size = r.array(r.at(e, p, "size"), zp);
    if (size.size() != 3) r.fail(zp, "expected [length, width, height]");
    mv.length = r.number(size[0], element(zp, 0));
    mv.width = r.number(size[1], element(zp, 1));
    if (mv.length <= 0.0 || mv.width <= 0.0) r.fail(zp, "expected positive sizes");
    readPath(r.at(e, p, "trajectory"), member(p, "trajectory"), r, &mv);
    d->entities.push_back(std::move(mv));
  }
  if (const json* air = r.find(s, "", "aircraft")) {
    r.array(*air, "aircraft");
    for (std::size_t i = 0; i < air->size(); ++i) {
      const std::string p = element("aircraft", i);
      const json& a = (*air)[i];
      MoverData mv;
      mv.id = r.stringAt(a, p, "id");
      mv.cls = r.stringAt(a, p, "model");
      mv.role = "aircraft";
      const std::string zp = member(p, "size");
      const json& size = r.array(r.at(a, p, "size"), zp);
      if (size.size() != 3) r.fail(zp, "expected [length, span, height]");
      mv.length = r.number(size[0], element(zp, 0));
      mv.width = r.number(size[1], element(zp, 1));
      const std::string tp = member(p, "trajectory");
      const json& traj = r.at(a, p, "trajectory");
      readPath(traj, tp, r, &mv);
      if (mv.path.empty()) r.fail(tp, "expected at least one sample");
      mv.position = mv.path.front();
      mv.yaw = r.number(traj[0][4], element(element(tp, 0), 4));
      d->entities.push_back(std::move(mv));
    }
  }
  const json& uav = r.at(s, "", "uav");
  const json& start = r.at(uav, "uav", "start");
  d->uav_start = Vec2(r.numberAt(start, "uav.start", "x"), r.numberAt(start, "uav.start", "y"));
  d->uav_yaw = r.numberAt(start, "uav.start", "yaw");
  const json& alt = r.at(uav, "uav", "altitude");
  d->uav_alt_min = r.numberAt(alt, "uav.altitude", "min");
  d->uav_alt_max = r.numberAt(alt, "uav.altitude", "max");
}

}  // namespace

MapData parseDocuments(const json& mission, const json& sim, const std::string& mission_file,
                       const std::string& sim_file) {
  MapData d;
  const DocReader mr(mission_file), sr(sim_file);
  parseMission(mission, mr, &d);
  parseSimConfig(sim, sr, &d);
  if (sim.is_object() && sim.contains("traffic")) {
    // A batch's city scenario: its traffic cars and crowd are a window of a shared traffic
    // episode file, resolved (and checked) by the simulator's reader.
    const scenario::SimConfig full = scenario::loadSimConfig(sim_file);
    const std::size_t n = full.traffic ? full.traffic->entityCount() : 0;
    for (std::size_t i = full.entities.size() - n; i < full.entities.size(); ++i) {
      const scenario::ScenarioEntity& se = full.entities[i];
      MoverData mv;
      mv.id = se.entity.id;
      mv.cls = scenario::toString(se.entity.cls);
      mv.role = se.role;
      mv.position = Vec2(se.entity.box.center.x(), se.entity.box.center.y());
      mv.yaw = se.entity.box.yaw;
      mv.length = se.entity.box.size.x();
      mv.width = se.entity.box.size.y();
      for (const auto& q : se.trajectory) {
        mv.times.push_back(q.t);
        mv.path.emplace_back(q.x, q.y);
      }
      d.entities.push_back(std::move(mv));
    }
  }
  const std::string sim_id = sr.stringAt(sim, "", "scenario_id");
  if (sim_id != d.scenario_id) {
    sr.fail("scenario_id",
            "'" + sim_id + "' does not match " + mission_file + " ('" + d.scenario_id + "')");
  }
  for (std::size_t i = 0; i < d.targets.size(); ++i) {
    const bool found = std::any_of(d.entities.begin(), d.entities.end(),
                                   [&](const MoverData& m) { return m.id == d.targets[i].id; });
    if (!found) {
      mr.fail(element("objective.targets", i) + ".id",
              "'" + d.targets[i].id + "' is not among the entities of " + sim_file);
    }
  }
  return d;
}

}  // namespace hameritt::map::map_internal
