#include "hameritt/scenario/mission_io.h"

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/scenario_io.h"
#include "strict_json.h"

namespace hameritt::scenario {

using json = strict_json::json;

namespace {

using strict_json::fmt;
using strict_json::idx;
using Obj = strict_json::Object;

std::vector<geometry::Vec2> points(const json& v, const std::string& path, const std::string& file,
                                   std::size_t min_count) {
  if (!v.is_array()) {
    throw ConfigError(file + ": " + path + ": expected an array of [x, y] points, got " +
                      v.type_name());
  }
  if (v.size() < min_count) {
    throw ConfigError(file + ": " + path + ": expected at least " + std::to_string(min_count) +
                      " points, got " + std::to_string(v.size()));
  }
  std::vector<geometry::Vec2> out;
  out.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    const json& p = v[i];
    if (!p.is_array() || p.size() != 2 || !p[0].is_number() || !p[1].is_number()) {
      throw ConfigError(file + ": " + idx(path, i) + ": expected a point [x, y] of 2 numbers, got " +
                        (p.is_primitive() ? p.dump() : std::string(p.type_name())));
    }
    out.emplace_back(p[0].get<double>(), p[1].get<double>());
    if (!out.back().allFinite()) {
      throw ConfigError(file + ": " + idx(path, i) + ": expected finite coordinates");
    }
  }
  return out;
}

geometry::Polygon polygon(Obj& o, const std::string& key) {
  return geometry::Polygon(points(o.get(key), o.at(key), o.file(), 3));
}

geometry::TimeWindow window(Obj& o) {
  Obj w = o.object("time_window");
  geometry::TimeWindow tw;
  if (w.has("net")) tw.net = w.number("net");
  if (w.has("nlt")) tw.nlt = w.number("nlt");
  w.finish();
  if (!tw.valid()) {
    throw ConfigError(o.file() + ": " + o.at("time_window") + ": expected net <= nlt, got " +
                      fmt(*tw.net) + " > " + fmt(*tw.nlt));
  }
  return tw;
}

Attributes attributes(Obj& o, const std::string& key) {
  const json& a = o.get(key);
  if (!a.is_object()) o.fail(o.at(key), "expected an object", a);
  Attributes out;
  for (auto it = a.begin(); it != a.end(); ++it) {
    if (it->is_string()) {
      out.set(it.key(), it->get<std::string>());
    } else if (strict_json::isInt64(*it)) {
      out.set(it.key(), it->get<std::int64_t>());
    } else {
      o.fail(o.at(key + "." + it.key()),
             "expected a string or an integer within [-2^63, 2^63)", *it);
    }
  }
  return out;
}

TargetDescription readTarget(const json& j, const std::string& path, const std::string& file) {
  Obj o(j, path, file);
  TargetDescription t;
  t.id = o.string("id");
  t.cls = o.string("class");
  t.vehicle_class = o.string("vehicle_class");
  t.make = o.string("make");
  t.model = o.string("model");
  t.color = o.string("color");
  o.finish();
  return t;
}

KeepOutZone readKoz(const json& j, const std::string& path, const std::string& file) {
  Obj o(j, path, file);
  KeepOutZone k;
  k.id = o.string("id");
  k.purpose = o.string("purpose");
  if (k.purpose != "vantage_denial" && k.purpose != "access_denial" && k.purpose != "restricted") {
    o.error("purpose", "expected vantage_denial, access_denial or restricted, got \"" +
                           k.purpose + "\"");
  }
  k.polygon = polygon(o, "polygon");
  {
    Obj alt = o.object("altitude");
    if (alt.has("min")) k.alt_min = alt.number("min");
    if (alt.has("max")) k.alt_max = alt.number("max");
    alt.finish();
    if (k.alt_min && k.alt_max && !(*k.alt_min <= *k.alt_max)) {
      o.error("altitude", "expected min <= max, got " + fmt(*k.alt_min) + " > " + fmt(*k.alt_max));
    }
  }
  k.window = window(o);
  if (o.has("motion")) {
    const json& mv = o.array("motion");
    const std::string mp = o.at("motion");
    for (std::size_t i = 0; i < mv.size(); ++i) {
      const auto a = strict_json::numbers<3>(mv[i], idx(mp, i), file);
      if (!(a[0] >= 0) || (!k.motion.empty() && !(a[0] > k.motion.back().t))) {
        throw ConfigError(file + ": " + idx(mp, i) +
                          ": expected times >= 0 that strictly increase, got t = " + fmt(a[0]));
      }
      k.motion.push_back({a[0], a[1], a[2], 0.0, 0.0});
    }
    if (k.motion.size() < 2) o.error("motion", "expected at least 2 samples {t, x, y}");
  }
  o.finish();
  return k;
}

AreaPrior readPrior(const json& j, const std::string& path, const std::string& file) {
  Obj o(j, path, file);
  AreaPrior p;
  p.aoi_id = o.string("aoi_id");
  const std::int64_t depth = o.integer("depth");
  if (depth < 0 || depth > 16) o.error("depth", "expected an integer in [0, 16], got " +
                                                    std::to_string(depth));
  p.depth = static_cast<int>(depth);
  const json& cells = o.array("cells");
  const std::string cpath = o.at("cells");
  for (std::size_t i = 0; i < cells.size(); ++i) {
    Obj c(cells[i], idx(cpath, i), file);
    PriorCell cell;
    cell.id = c.string("id");
    const std::int64_t row = c.integer("row"), col = c.integer("col");
    const std::int64_t n = std::int64_t{1} << depth;
    if (row < 0 || row >= n) c.error("row", "expected an integer in [0, " + std::to_string(n - 1) +
                                                "], got " + std::to_string(row));
    if (col < 0 || col >= n) c.error("col", "expected an integer in [0, " + std::to_string(n - 1) +
                                                "], got " + std::to_string(col));
    cell.row = static_cast<int>(row);
    cell.col = static_cast<int>(col);
    cell.polygon = polygon(c, "polygon");
    cell.probability = c.number("probability");
    if (!(cell.probability >= 0 && cell.probability <= 1)) {
      c.error("probability", "expected a number in [0, 1], got " + fmt(cell.probability));
    }
    c.finish();
    p.cells.push_back(std::move(cell));
  }
  o.finish();
  return p;
}

RouteOfInterest readRoute(const json& j, const std::string& path, const std::string& file) {
  Obj o(j, path, file);
  RouteOfInterest r;
  r.id = o.string("id");
  r.polyline = points(o.get("polyline"), o.at("polyline"), file, 2);
  const json& streets = o.array("streets");
  for (std::size_t i = 0; i < streets.size(); ++i) {
    if (!streets[i].is_string()) {
      throw ConfigError(file + ": " + idx(o.at("streets"), i) + ": expected a string, got " +
                        streets[i].type_name());
    }
    r.streets.push_back(streets[i].get<std::string>());
  }
  r.band_width = o.number("band_width");
  if (!(r.band_width > 0)) o.error("band_width", "expected a positive width, got " +
                                                     fmt(r.band_width));
  r.band = polygon(o, "band_polygon");
  o.finish();
  return r;
}

SceneRelation readRelation(const json& j, const std::string& path, const std::string& file) {
  Obj o(j, path, file);
  SceneRelation r;
  {
    Obj rel = o.object("related");
    r.related_id = rel.string("id");
    r.related_class = rel.string("class");
    r.related_attributes = attributes(rel, "attributes");
    rel.finish();
  }
  const std::string op = o.string("operator");
  if (!parseRelationOp(op, &r.op, &r.eventually)) {
    o.error("operator", "expected a relation operator (NEXT_TO, ..., PART_OF, EVENTUALLY_*), got \"" +
                            op + "\"");
  }
  r.target_id = o.string("target");
  {
    Obj ev = o.object("evidence");
    if (r.op != RelationOp::kPartOf) {
      r.distance = ev.number("distance");
      r.bearing_deg = ev.number("bearing_deg");
      if (!(r.bearing_deg >= 0 && r.bearing_deg < 360)) {
        ev.error("bearing_deg", "expected degrees in [0, 360), got " + fmt(r.bearing_deg));
      }
      r.dz = ev.number("dz");
      r.line_of_sight = ev.boolean("line_of_sight");
    }
    if (r.eventually) {
      r.time = ev.number("time");
    } else if (ev.has("time")) {
      ev.error("time", "unexpected for an operator without EVENTUALLY_");
    }
    ev.finish();
  }
  const std::string text = o.string("text");
  const std::string expected = relationText(r);
  if (text != expected) o.error("text", "expected \"" + expected + "\", got \"" + text + "\"");
  o.finish();
  return r;
}

MissionPhase readPhase(const json& j, const std::string& path, const std::string& file) {
  Obj o(j, path, file);
  MissionPhase p;
  p.id = o.string("id");
  const std::string type = o.string("type");
  if (!parsePhaseType(type, &p.type)) {
    o.error("type",
            "expected \"search\", \"follow\", \"track\" or \"avoid\", got \"" + type + "\"");
  }
  const json& targets = o.array("targets");
  for (std::size_t i = 0; i < targets.size(); ++i) {
    if (!targets[i].is_string()) {
      throw ConfigError(file + ": " + idx(o.at("targets"), i) + ": expected a string, got " +
                        targets[i].type_name());
    }
    p.targets.push_back(targets[i].get<std::string>());
  }
  const bool timed = p.type == PhaseType::kFollow || p.type == PhaseType::kTrack;
  if (timed) {
    p.duration = o.number("duration");
    if (!(*p.duration > 0))
      o.error("duration", "expected a positive number, got " + fmt(*p.duration));
  } else if (o.has("duration")) {
    o.error("duration", "unexpected for a " + type + " phase (it ends when its goal is met)");
  }
  auto positive = [](Obj& c, const char* key) {
    const double v = c.number(key);
    if (!(v > 0)) c.error(key, "expected a positive number, got " + fmt(v));
    return v;
  };
  auto nonNegative = [](Obj& c, const char* key) {
    const double v = c.number(key);
    if (!(v >= 0)) c.error(key, "expected a number >= 0, got " + fmt(v));
    return v;
  };
  if (p.type == PhaseType::kFollow) {
    Obj e = o.object("envelope");
    p.follow.distance = nonNegative(e, "distance");
    p.follow.distance_tolerance = positive(e, "distance_tolerance");
    p.follow.height = e.number("height");
    p.follow.height_tolerance = positive(e, "height_tolerance");
    e.finish();
    Obj c = o.object("criteria");
    p.follow.min_inside_fraction = c.numberIn("min_inside_fraction", 0, 1);
    p.follow.max_outside_s = nonNegative(c, "max_outside_s");
    p.follow.approach_s = nonNegative(c, "approach_s");
    c.finish();
  } else if (p.type == PhaseType::kTrack) {
    Obj c = o.object("criteria");
    p.track.min_visible_fraction = c.numberIn("min_visible_fraction", 0, 1);
    p.track.min_box_area = nonNegative(c, "min_box_area");
    p.track.min_tracked_fraction = c.numberIn("min_tracked_fraction", 0, 1);
    p.track.max_reacquire_s = nonNegative(c, "max_reacquire_s");
    c.finish();
  } else if (p.type == PhaseType::kAvoid) {
    const json& g = o.get("goal");
    if (!g.is_array() || g.size() != 3 || !g[0].is_number() || !g[1].is_number() ||
        !g[2].is_number()) {
      o.error("goal", "expected a point [x, y, z] of 3 numbers");
    }
    p.avoid.goal = geometry::Vec3(g[0].get<double>(), g[1].get<double>(), g[2].get<double>());
    if (!p.avoid.goal.allFinite()) o.error("goal", "expected finite coordinates");
    p.avoid.goal_radius = positive(o, "goal_radius");
    p.avoid.shortest_path_m = positive(o, "shortest_path_m");
    Obj c = o.object("criteria");
    p.avoid.min_horizontal_separation = positive(c, "min_horizontal_separation");
    p.avoid.min_vertical_separation = positive(c, "min_vertical_separation");
    c.finish();
  }
  o.finish();
  return p;
}

}  // namespace

Mission missionFromJson(const json& j, const std::string& file) {
  Obj root(j, "", file);
  Mission m;
  const strict_json::Header h = strict_json::header(root, "hameritt/mission");
  m.scenario_id = h.scenario_id;
  m.cls = h.cls;
  m.seed = h.seed;
  {
    Obj frame = root.object("frame");
    const std::string type = frame.string("type");
    if (type != "ENU") frame.error("type", "expected \"ENU\", got \"" + type + "\"");
    const std::string units = frame.string("units");
    if (units != "m") frame.error("units", "expected \"m\", got \"" + units + "\"");
    Obj origin = frame.object("origin");
    m.origin.latitude = origin.number("latitude");
    if (!(m.origin.latitude >= -90 && m.origin.latitude <= 90)) {
      origin.error("latitude", "expected degrees in [-90, 90], got " + fmt(m.origin.latitude));
    }
    m.origin.longitude = origin.number("longitude");
    if (!(m.origin.longitude >= -180 && m.origin.longitude <= 180)) {
      origin.error("longitude", "expected degrees in [-180, 180], got " + fmt(m.origin.longitude));
    }
    m.origin.altitude = origin.number("altitude");
    origin.finish();
    frame.finish();
  }
  m.time_limit = root.number("time_limit");
  if (!(m.time_limit > 0)) root.error("time_limit", "expected a positive number, got " +
                                                        fmt(m.time_limit));
  {
    Obj obj = root.object("objective");
    m.objective.type = obj.string("type");
    if (m.objective.type != "find" && m.objective.type != "track" && m.objective.type != "reach") {
      obj.error("type",
                "expected \"find\", \"track\" or \"reach\", got \"" + m.objective.type + "\"");
    }
    m.objective.text = obj.string("text");
    const json& targets = obj.array("targets");
    for (std::size_t i = 0; i < targets.size(); ++i) {
      m.objective.targets.push_back(readTarget(targets[i], idx("objective.targets", i), file));
    }
    obj.finish();
  }
  const json& aois = root.array("areas_of_interest");
  for (std::size_t i = 0; i < aois.size(); ++i) {
    Obj o(aois[i], idx("areas_of_interest", i), file);
    AreaOfInterest a;
    a.id = o.string("id");
    a.polygon = polygon(o, "polygon");
    a.window = window(o);
    o.finish();
    m.aois.push_back(std::move(a));
  }
  const json& kozs = root.array("keep_out_zones");
  for (std::size_t i = 0; i < kozs.size(); ++i) {
    m.kozs.push_back(readKoz(kozs[i], idx("keep_out_zones", i), file));
  }
  const json& priors = root.array("area_priors");
  for (std::size_t i = 0; i < priors.size(); ++i) {
    m.priors.push_back(readPrior(priors[i], idx("area_priors", i), file));
  }
  const json& routes = root.array("routes");
  for (std::size_t i = 0; i < routes.size(); ++i) {
    m.routes.push_back(readRoute(routes[i], idx("routes", i), file));
  }
  const json& rels = root.array("scene_relations");
  for (std::size_t i = 0; i < rels.size(); ++i) {
    m.relations.push_back(readRelation(rels[i], idx("scene_relations", i), file));
  }
  if (root.has("phases")) {
    const json& phases = root.array("phases");
    if (phases.empty()) root.error("phases", "expected at least one phase (or no key)");
    for (std::size_t i = 0; i < phases.size(); ++i) {
      m.phases.push_back(readPhase(phases[i], idx("phases", i), file));
    }
  }
  root.finish();
  return m;
}

Mission parseMission(const std::string& text, const std::string& file) {
  return missionFromJson(strict_json::parseText(text, file), file);
}

Mission loadMission(const std::string& path) {
  return missionFromJson(strict_json::parseFile(path), path);
}

}  // namespace hameritt::scenario
