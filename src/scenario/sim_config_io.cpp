#include "hameritt/scenario/sim_config_io.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <utility>

#include "hameritt/scenario/city_traffic.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/params_table.h"
#include "hameritt/scenario/scenario_io.h"
#include "signal_plan_io.h"
#include "strict_json.h"

namespace hameritt::scenario {

using json = strict_json::json;

namespace {

using strict_json::fmt;
using strict_json::idx;
using strict_json::numbers;
using Obj = strict_json::Object;

// uav.perception_path: a planner status ("chase": a follow or track mission's chase path), the
// targets seen and a strictly increasing trajectory.
PerceptionPath readPerceptionPath(Obj o) {
  PerceptionPath pp;
  pp.status = o.string("status");
  static const std::set<std::string> kStatuses = {
      "exact", "approximate", "no_solution", "invalid_start", "invalid_goal", "timeout", "chase"};
  if (!kStatuses.count(pp.status)) {
    throw ConfigError(o.file() + ": " + o.at("status") + ": expected a planner status, got \"" +
                      pp.status + "\"");
  }
  pp.camera = o.string("camera");
  const json& seen = o.array("targets_seen");
  for (std::size_t i = 0; i < seen.size(); ++i) {
    if (!seen[i].is_string()) {
      throw ConfigError(o.file() + ": " + idx(o.at("targets_seen"), i) +
                        ": expected a string, got " + seen[i].type_name());
    }
    pp.targets_seen.push_back(seen[i].get<std::string>());
  }
  pp.trajectory = strict_json::trajectory(o.array("trajectory"), o.at("trajectory"), o.file());
  o.finish();
  return pp;
}

std::vector<std::string> strings(const json& v, const std::string& path, const std::string& file) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!v[i].is_string()) {
      throw ConfigError(file + ": " + idx(path, i) + ": expected a string, got " +
                        v[i].type_name());
    }
    out.push_back(v[i].get<std::string>());
  }
  return out;
}

geometry::Vec3 vec3(const json& v, const std::string& path, const std::string& file) {
  const auto a = numbers<3>(v, path, file);
  return {a[0], a[1], a[2]};
}

// The entity box whose minZ() is exactly `z` (the writer prints minZ(); centre + half height
// - half height need not give z back in floating point, so the centre is nudged if needed).
geometry::OrientedBox entityBox(double x, double y, double z, double yaw,
                                const geometry::Vec3& size) {
  geometry::OrientedBox b = boxFromPose({x, y, z}, yaw, size);
  double c = b.center.z();
  for (int i = 0; i < 8 && b.minZ() != z; ++i) {
    c = std::nextafter(c, b.minZ() < z ? INFINITY : -INFINITY);
    b.center.z() = c;
  }
  if (b.minZ() != z) b = boxFromPose({x, y, z}, yaw, size);
  return b;
}

ScenarioEntity readEntity(const json& j, const std::string& path, const std::string& file) {
  Obj o(j, path, file);
  ScenarioEntity se;
  Entity& e = se.entity;
  e.id = o.string("id");
  if (e.id.empty()) throw ConfigError(file + ": " + o.at("id") + ": expected a non-empty id");
  const std::string cls = o.string("class");
  if (!parseEntityClass(cls, &e.cls)) {
    throw ConfigError(file + ": " + o.at("class") + ": expected an entity class, got \"" + cls +
                      "\"");
  }
  se.role = o.string("role");
  {
    const json& a = o.get("attributes");
    if (!a.is_object()) o.fail(o.at("attributes"), "expected an object", a);
    for (auto it = a.begin(); it != a.end(); ++it) {
      if (it->is_string()) {
        e.attributes.set(it.key(), it->get<std::string>());
      } else if (strict_json::isInt64(*it)) {
        e.attributes.set(it.key(), it->get<std::int64_t>());
      } else {
        o.fail(o.at("attributes." + it.key()),
               "expected a string or an integer within [-2^63, 2^63)", *it);
      }
    }
  }
  Obj pose = o.object("pose");
  const double x = pose.number("x"), y = pose.number("y"), z = pose.number("z");
  const double yaw = pose.number("yaw");
  pose.finish();
  const geometry::Vec3 size = vec3(o.get("size"), o.at("size"), file);
  if (!(size.minCoeff() > 0)) {
    throw ConfigError(file + ": " + o.at("size") + ": expected positive sizes");
  }
  e.box = entityBox(x, y, z, yaw, size);
  se.trajectory = strict_json::trajectory(o.array("trajectory"), o.at("trajectory"), file);
  o.finish();
  return se;
}

CameraSpec readCamera(const json& j, const std::string& path, const std::string& file) {
  Obj o(j, path, file);
  CameraSpec c;
  c.name = o.string("name");
  Obj mount = o.object("mount");
  c.mount_xyz = vec3(mount.get("xyz"), mount.at("xyz"), file);
  c.mount_rpy = vec3(mount.get("rpy_deg"), mount.at("rpy_deg"), file);
  mount.finish();
  const std::int64_t w = o.integer("width"), h = o.integer("height");
  if (w <= 0 || h <= 0 || w > 16384 || h > 16384) {
    throw ConfigError(file + ": " + o.at("width") + "/height: expected 1..16384 pixels");
  }
  c.width = static_cast<int>(w);
  c.height = static_cast<int>(h);
  c.hfov_deg = o.number("hfov_deg");
  if (!(c.hfov_deg > 0 && c.hfov_deg < 180)) {
    throw ConfigError(file + ": " + o.at("hfov_deg") + ": expected degrees in (0, 180), got " +
                      fmt(c.hfov_deg));
  }
  c.rate_hz = o.number("rate_hz");
  if (!(c.rate_hz > 0)) {
    throw ConfigError(file + ": " + o.at("rate_hz") + ": expected a positive rate, got " +
                      fmt(c.rate_hz));
  }
  c.modalities = strings(o.array("modalities"), o.at("modalities"), file);
  o.finish();
  return c;
}

}  // namespace

SignalPlan readSignalPlan(Obj& sg, const std::string& path, const std::string& file) {
  SignalPlan plan;
  plan.left = sg.numberIn("left", 0, 600);
  plan.green = sg.numberIn("green", 0.001, 600);
  plan.yellow = sg.numberIn("yellow", 0.001, 600);
  plan.all_red = sg.numberIn("all_red", 0, 600);
  plan.sidewalk = sg.numberIn("sidewalk", 0.001, 100);
  const double cycle = sg.number("cycle");
  if (std::abs(cycle - plan.cycle()) > 1e-6) {
    sg.error("cycle", "expected 2 * (left + green + yellow + all_red) = " + fmt(plan.cycle()) +
                          ", got " + fmt(cycle));
  }
  const json& list = sg.array("intersections");
  for (std::size_t i = 0; i < list.size(); ++i) {
    Obj o(list[i], idx(path + ".intersections", i), file);
    SignalizedIntersection si;
    si.id = o.string("id");
    si.position = geometry::Vec2(o.number("x"), o.number("y"));
    si.offset = o.numberIn("offset", 0, plan.cycle());
    for (const char* key : {"heading", "width"}) {
      const json& a = o.get(key);
      if (!a.is_array() || a.size() != 2 || !a[0].is_number() || !a[1].is_number()) {
        o.fail(o.at(key), "expected an array of 2 numbers", a);
      }
      double* dst = std::string(key) == "heading" ? si.heading : si.width;
      dst[0] = a[0].get<double>();
      dst[1] = a[1].get<double>();
    }
    o.finish();
    plan.intersections.push_back(si);
  }
  sg.finish();
  return plan;
}

namespace {

// sim_config.json's "traffic": the reference to a traffic episode file, resolved: the file is
// read (relative to the directory of `file`), its SHA-256 checked, the window checked to lie
// within the episode and the signal plan to be the episode's shifted by the offset; the
// pedestrians and then the cars not withheld are appended to s.entities: this is where a
// withheld car leaves the scenario, for every reader of it.
TrafficEpisodeRef readTrafficReference(Obj& t, SimConfig& s, const std::string& file,
                                       std::set<std::string>* ids) {
  TrafficEpisodeRef r;
  r.file = t.string("file");
  r.episode = static_cast<int>(t.integer("episode"));
  if (r.episode < 0 || r.episode > 63) t.error("episode", "expected 0 to 63");
  r.offset = t.numberIn("offset", 0, kTrafficEpisodeLength);
  r.sha256 = t.string("sha256");
  if (r.sha256.size() != 64 ||
      r.sha256.find_first_not_of("0123456789abcdef") != std::string::npos) {
    t.error("sha256", "expected 64 lower-case hex digits, got '" + r.sha256 + "'");
  }
  r.car_ids = strings(t.array("cars"), t.at("cars"), file);
  r.pedestrian_ids = strings(t.array("pedestrians"), t.at("pedestrians"), file);
  if (t.has("withheld")) r.withheld = strings(t.array("withheld"), t.at("withheld"), file);
  t.finish();
  if (r.file.empty() || r.file.find('\0') != std::string::npos) {
    t.error("file", "expected a file name");
  }
  const std::string path =
      (std::filesystem::path(file).parent_path() / std::filesystem::path(r.file)).string();
  std::string bytes;
  try {
    bytes = readBoundedFile(path);
  } catch (const ConfigError& e) {
    t.error("file", std::string("expected a readable traffic episode file: ") + e.what());
  }
  const std::string sha = sha256Hex(bytes);
  if (sha != r.sha256) {
    t.error("sha256", "expected the SHA-256 of " + path + " (" + sha + "), got " + r.sha256);
  }
  const TrafficEpisode e = parseTrafficEpisode(bytes, path);
  if (e.index != r.episode) {
    t.error("episode", "expected " + std::to_string(e.index) + " (the episode of " + path +
                           "), got " + std::to_string(r.episode));
  }
  if (e.world_fingerprint != s.world_fingerprint) {
    t.error("file", path + " is an episode of world " + hex64(e.world_fingerprint) +
                        ", not of this scenario's world " + hex64(s.world_fingerprint));
  }
  if (!(r.offset + s.duration <= e.length + 1e-9)) {
    t.error("offset", "expected the window [offset, offset + duration] = [" + fmt(r.offset) + ", " +
                          fmt(r.offset + s.duration) + "] within the episode's [0, " +
                          fmt(e.length) + "] s");
  }
  if (r.car_ids.size() != e.cars.size()) {
    t.error("cars", "expected " + std::to_string(e.cars.size()) + " ids (one per car of " + path +
                        "), got " + std::to_string(r.car_ids.size()));
  }
  if (r.pedestrian_ids.size() != e.pedestrians.size()) {
    t.error("pedestrians", "expected " + std::to_string(e.pedestrians.size()) +
                               " ids (one per pedestrian of " + path + "), got " +
                               std::to_string(r.pedestrian_ids.size()));
  }
  const SignalPlan want = shiftedSignalPlan(e.plan, r.offset);
  bool same = s.signals && s.signals->cycle() == want.cycle() &&
              s.signals->intersections.size() == want.intersections.size();
  for (std::size_t i = 0; same && i < want.intersections.size(); ++i) {
    const auto &a = s.signals->intersections[i], &b = want.intersections[i];
    same = a.id == b.id && std::abs(a.offset - b.offset) < 1e-6 &&
           (a.position - b.position).norm() < 1e-6;
  }
  if (!same) {
    throw ConfigError(file + ": signals: expected the signal plan of " + path +
                      " with every offset shifted by traffic.offset (" + fmt(r.offset) + " s)");
  }
  for (std::size_t i = 0; i < e.pedestrians.size(); ++i) {
    if (!ids->insert(r.pedestrian_ids[i]).second) {
      throw ConfigError(file + ": " + idx("traffic.pedestrians", i) + ": duplicate id \"" +
                        r.pedestrian_ids[i] + "\"");
    }
    s.entities.push_back(cityPedestrianEntity(e.pedestrians[i],
                                              episodePedestrianWindow(e, i, r.offset, s.duration),
                                              r.pedestrian_ids[i]));
  }
  std::set<std::string> withheld;
  for (std::size_t k = 0; k < r.withheld.size(); ++k) {
    const auto it = std::find(r.car_ids.begin(), r.car_ids.end(), r.withheld[k]);
    if (it == r.car_ids.end()) {
      throw ConfigError(file + ": " + idx("traffic.withheld", k) +
                        ": expected one of traffic.cars, got \"" + r.withheld[k] + "\"");
    }
    if (!withheld.insert(r.withheld[k]).second) {
      throw ConfigError(file + ": " + idx("traffic.withheld", k) + ": duplicate id \"" +
                        r.withheld[k] + "\"");
    }
  }
  for (std::size_t i = 0; i < e.cars.size(); ++i) {
    if (!ids->insert(r.car_ids[i]).second) {
      throw ConfigError(file + ": " + idx("traffic.cars", i) + ": duplicate id \"" + r.car_ids[i] +
                        "\"");
    }
    if (withheld.count(r.car_ids[i])) continue;
    s.entities.push_back(
        episodeCarEntity(e, i, episodeCarWindow(e, i, r.offset, s.duration), r.car_ids[i]));
  }
  return r;
}

}  // namespace

SimConfig simConfigFromJson(const nlohmann::json& j, const std::string& file) {
  return simConfigFromJson(nlohmann::ordered_json(j), file);
}

SimConfig simConfigFromJson(const json& j, const std::string& file) {
  Obj root(j, "", file);
  SimConfig s;
  const strict_json::Header h = strict_json::header(root, "hameritt/sim_config");
  s.scenario_id = h.scenario_id;
  s.cls = h.cls;
  s.seed = h.seed;
  s.duration = root.number("duration");
  if (!(s.duration >= 0)) throw ConfigError(file + ": duration: expected a non-negative number");

  {
    Obj w = root.object("world");
    const std::string gen = w.string("generator");
    if (gen != "hameritt_suburb") {
      throw ConfigError(file + ": world.generator: expected \"hameritt_suburb\", got \"" + gen +
                        "\"");
    }
    const std::string fp = w.string("fingerprint");
    char* end = nullptr;
    const unsigned long long v = std::strtoull(fp.c_str(), &end, 16);
    if (fp.size() != 16 || end != fp.c_str() + fp.size()) {
      throw ConfigError(file + ": world.fingerprint: expected 16 hex digits, got \"" + fp + "\"");
    }
    s.world_fingerprint = v;
    try {
      s.world = worldParamsFromJson(nlohmann::json(w.get("params")), file);
    } catch (const ConfigError& e) {
      // worldParamsFromJson names paths "world.<key>"; here they live under world.params.
      std::string msg = e.what();
      const std::string prefix = file + ": world";
      if (msg.compare(0, prefix.size(), prefix) == 0) {
        msg = prefix + ".params" + msg.substr(prefix.size());
      }
      throw ConfigError(msg);
    }
    w.finish();
  }

  const json& ents = root.array("entities");
  s.entities.reserve(ents.size());
  std::set<std::string> ids;
  for (std::size_t i = 0; i < ents.size(); ++i) {
    s.entities.push_back(readEntity(ents[i], idx("entities", i), file));
    if (!ids.insert(s.entities.back().entity.id).second) {
      throw ConfigError(file + ": " + idx("entities", i) + ".id: duplicate id \"" +
                        s.entities.back().entity.id + "\"");
    }
  }

  const json& groups = root.array("groups");
  for (std::size_t i = 0; i < groups.size(); ++i) {
    Obj g(groups[i], idx("groups", i), file);
    Group grp;
    grp.id = g.string("id");
    grp.kind = g.string("kind");
    grp.members = strings(g.array("members"), g.at("members"), file);
    g.finish();
    s.groups.push_back(std::move(grp));
  }

  if (root.has("aircraft")) {
    const json& air = root.array("aircraft");
    for (std::size_t i = 0; i < air.size(); ++i) {
      Obj a(air[i], idx("aircraft", i), file);
      Aircraft ac;
      ac.id = a.string("id");
      if (ac.id.empty()) throw ConfigError(file + ": " + a.at("id") + ": expected a non-empty id");
      if (!ids.insert(ac.id).second) {
        throw ConfigError(file + ": " + a.at("id") + ": duplicate id \"" + ac.id + "\"");
      }
      ac.model = a.string("model");
      if (ac.model != "fixed_wing" && ac.model != "quadrotor") {
        a.error("model", "expected \"fixed_wing\" or \"quadrotor\", got \"" + ac.model + "\"");
      }
      ac.size = vec3(a.get("size"), a.at("size"), file);
      if (!(ac.size.minCoeff() > 0)) {
        throw ConfigError(file + ": " + a.at("size") + ": expected positive sizes");
      }
      ac.trajectory = strict_json::trajectory(a.array("trajectory"), a.at("trajectory"), file);
      if (ac.trajectory.size() < 2) {
        a.error("trajectory",
                "expected at least 2 samples, got " + std::to_string(ac.trajectory.size()));
      }
      a.finish();
      s.aircraft.push_back(std::move(ac));
    }
  }

  {
    Obj env = root.object("environment");
    Environment& e = s.environment;
    e.time_of_day = env.numberIn("time_of_day", 0, 24);
    e.snow = env.numberIn("snow", 0, 1);
    e.rain = env.numberIn("rain", 0, 1);
    e.dust = env.numberIn("dust", 0, 1);
    e.fog = env.numberIn("fog", 0, 1);
    e.foliage = env.numberIn("foliage", 0, 1);
    Obj wind = env.object("wind");
    e.wind_mean = vec3(wind.get("mean"), wind.at("mean"), file);
    e.gust_intensity = wind.numberIn("gust_intensity", 0, 1);
    wind.finish();
    env.finish();
  }

  {
    Obj u = root.object("uav");
    UavSpec& spec = s.uav;
    spec.model = u.string("model");
    Obj start = u.object("start");
    spec.start.t = 0.0;
    spec.start.x = start.number("x");
    spec.start.y = start.number("y");
    spec.start.z = start.number("z");
    spec.start.yaw = start.number("yaw");
    start.finish();
    Obj alt = u.object("altitude");
    spec.altitude_min = alt.number("min");
    spec.altitude_max = alt.number("max");
    if (!(spec.altitude_min <= spec.altitude_max)) {
      throw ConfigError(file + ": uav.altitude: expected min <= max, got " +
                        fmt(spec.altitude_min) + " > " + fmt(spec.altitude_max));
    }
    alt.finish();
    spec.max_speed = u.number("max_speed");
    if (!(spec.max_speed > 0)) {
      throw ConfigError(file + ": uav.max_speed: expected a positive speed, got " +
                        fmt(spec.max_speed));
    }
    Obj payload = u.object("payload");
    const json& cams = payload.array("cameras");
    for (std::size_t i = 0; i < cams.size(); ++i) {
      spec.cameras.push_back(readCamera(cams[i], idx("uav.payload.cameras", i), file));
    }
    payload.finish();
    if (u.has("perception_path")) {
      spec.perception_path = readPerceptionPath(u.object("perception_path"));
    }
    u.finish();
  }

  {
    Obj p = root.object("perturbations");
    Obj n = p.object("camera_noise");
    s.perturbations.gaussian_noise_std = n.numberIn("gaussian_std", 0, 1);
    s.perturbations.salt_pepper_probability = n.numberIn("salt_pepper_probability", 0, 1);
    s.perturbations.motion_blur_px = n.numberIn("motion_blur_px", 0, 1000);
    n.finish();
    p.finish();
  }
  if (root.has("signals")) {
    Obj sg = root.object("signals");
    s.signals = readSignalPlan(sg, "signals", file);
  }
  if (root.has("traffic")) {
    Obj t = root.object("traffic");
    s.traffic = readTrafficReference(t, s, file, &ids);
  }
  if (root.has("spec")) {
    Obj sp = root.object("spec");
    SpecProvenance prov;
    prov.file = sp.string("file");
    const std::string hash = sp.string("hash");
    if (hash.size() != 16 || hash.find_first_not_of("0123456789abcdef") != std::string::npos) {
      sp.error("hash", "expected 16 lower-case hex digits, got '" + hash + "'");
    }
    prov.hash = std::stoull(hash, nullptr, 16);
    prov.sampler = sp.string("sampler");
    if (prov.sampler != "random" && prov.sampler != "halton") {
      sp.error("sampler", "expected random or halton, got '" + prov.sampler + "'");
    }
    const auto& values = sp.get("values");
    if (!values.is_object()) sp.fail(sp.at("values"), "expected an object", values);
    for (auto it = values.begin(); it != values.end(); ++it) {
      if (it.value().is_boolean()) {
        prov.values.emplace_back(it.key(), it.value().get<bool>());
      } else if (it.value().is_number() && std::isfinite(it.value().get<double>())) {
        prov.values.emplace_back(it.key(), it.value().get<double>());
      } else {
        sp.fail(sp.at("values." + it.key()), "expected a number or a boolean", it.value());
      }
    }
    sp.finish();
    s.spec = prov;
  }
  root.finish();
  return s;
}

SimConfig parseSimConfig(const std::string& text, const std::string& file) {
  return simConfigFromJson(strict_json::parseText(text, file), file);
}

SimConfig loadSimConfig(const std::string& path) {
  return simConfigFromJson(strict_json::parseFile(path), path);
}

World generateCheckedWorld(const SimConfig& config, const std::string& file) {
  World world = generateWorld(config.world);
  if (world.fingerprint() != config.world_fingerprint) {
    throw ConfigError(file + ": world.fingerprint: expected " + hex64(world.fingerprint()) +
                      " for these world parameters, got " + hex64(config.world_fingerprint));
  }
  return world;
}

}  // namespace hameritt::scenario
