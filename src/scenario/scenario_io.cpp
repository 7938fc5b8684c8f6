#include "hameritt/scenario/scenario_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "hameritt/scenario/error.h"
#include "hameritt/scenario/json_writer.h"
#include "hameritt/scenario/params_table.h"
#include "signal_plan_io.h"

namespace hameritt::scenario {

namespace fs = std::filesystem;
using geometry::Polygon;
using geometry::Vec2;

std::string hex64(std::uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(v));
  return buf;
}

namespace {

void writePoints(JsonWriter& w, const std::vector<Vec2>& pts) {
  w.beginArray();
  for (const auto& p : pts) w.numbers({p.x(), p.y()});
  w.endArray();
}

void writePolygon(JsonWriter& w, const Polygon& p) { writePoints(w, p.vertices()); }

void writeWindow(JsonWriter& w, const geometry::TimeWindow& tw) {
  w.key("time_window").beginObject();
  if (tw.net) w.key("net").value(*tw.net);
  if (tw.nlt) w.key("nlt").value(*tw.nlt);
  w.endObject();
}

void writeAttributes(JsonWriter& w, const Attributes& a) {
  w.beginObject();
  for (const auto& [k, v] : a.items) {
    w.key(k);
    if (const auto* s = std::get_if<std::string>(&v)) w.value(*s);
    else w.value(std::get<std::int64_t>(v));
  }
  w.endObject();
}

void writePose(JsonWriter& w, const Entity& e) {
  const auto p = e.position();
  w.key("pose").beginObject();
  w.key("x").value(p.x()).key("y").value(p.y()).key("z").value(p.z()).key("yaw").value(e.yaw());
  w.endObject();
  w.key("size").numbers({e.box.size.x(), e.box.size.y(), e.box.size.z()});
}

void writeHeader(JsonWriter& w, const char* kind, const std::string& id, ScenarioClass cls,
                 std::uint64_t seed) {
  w.key("schema").value(kind);
  w.key("schema_version").value(kSchemaVersion);
  w.key("scenario_id").value(id);
  w.key("class").value(toString(cls));
  w.key("seed").value(seed);
}

}  // namespace

std::string relationText(const SceneRelation& r) {
  // Groups are abstract: they are named by id; entities by class, as in the paper.
  const std::string related = r.op == RelationOp::kPartOf ? r.related_id : r.related_class;
  std::string s = "[" + related + "] [" + toString(r.op, r.eventually) + "] [" + r.target_id + "]";
  if (!r.related_attributes.items.empty()) {
    s += " [";
    bool first = true;
    for (const auto& [k, v] : r.related_attributes.items) {
      if (!first) s += ", ";
      first = false;
      s += k + ": ";
      if (const auto* str = std::get_if<std::string>(&v)) s += *str;
      else s += std::to_string(std::get<std::int64_t>(v));
    }
    s += "]";
  }
  return s;
}

namespace {

void writePhase(JsonWriter& w, const MissionPhase& p) {
  w.beginObject();
  w.key("id").value(p.id).key("type").value(toString(p.type));
  w.key("targets").beginArray();
  for (const auto& t : p.targets) w.value(t);
  w.endArray();
  if (p.duration) w.key("duration").value(*p.duration);
  switch (p.type) {
    case PhaseType::kSearch:
      break;
    case PhaseType::kFollow:
      w.key("envelope").beginObject();
      w.key("distance").value(p.follow.distance);
      w.key("distance_tolerance").value(p.follow.distance_tolerance);
      w.key("height").value(p.follow.height);
      w.key("height_tolerance").value(p.follow.height_tolerance);
      w.endObject();
      w.key("criteria").beginObject();
      w.key("min_inside_fraction").value(p.follow.min_inside_fraction);
      w.key("max_outside_s").value(p.follow.max_outside_s);
      w.key("approach_s").value(p.follow.approach_s);
      w.endObject();
      break;
    case PhaseType::kTrack:
      w.key("criteria").beginObject();
      w.key("min_visible_fraction").value(p.track.min_visible_fraction);
      w.key("min_box_area").value(p.track.min_box_area);
      w.key("min_tracked_fraction").value(p.track.min_tracked_fraction);
      w.key("max_reacquire_s").value(p.track.max_reacquire_s);
      w.endObject();
      break;
    case PhaseType::kAvoid:
      w.key("goal").beginArray();
      w.value(p.avoid.goal.x()).value(p.avoid.goal.y()).value(p.avoid.goal.z());
      w.endArray();
      w.key("goal_radius").value(p.avoid.goal_radius);
      w.key("shortest_path_m").value(p.avoid.shortest_path_m);
      w.key("criteria").beginObject();
      w.key("min_horizontal_separation").value(p.avoid.min_horizontal_separation);
      w.key("min_vertical_separation").value(p.avoid.min_vertical_separation);
      w.endObject();
      break;
  }
  w.endObject();
}

// mission.json into w (emptied first).
void writeMission(JsonWriter& w, const Mission& m) {
  w.clear();
  w.beginObject();
  writeHeader(w, "hameritt/mission", m.scenario_id, m.cls, m.seed);
  w.key("frame").beginObject();
  w.key("type").value("ENU").key("units").value("m");
  w.key("origin").beginObject();
  w.key("latitude").value(m.origin.latitude).key("longitude").value(m.origin.longitude);
  w.key("altitude").value(m.origin.altitude);
  w.endObject().endObject();
  w.key("time_limit").value(m.time_limit);

  w.key("objective").beginObject();
  w.key("type").value(m.objective.type).key("text").value(m.objective.text);
  w.key("targets").beginArray();
  for (const auto& t : m.objective.targets) {
    w.beginObject();
    w.key("id").value(t.id).key("class").value(t.cls).key("vehicle_class").value(t.vehicle_class);
    w.key("make").value(t.make).key("model").value(t.model).key("color").value(t.color);
    w.endObject();
  }
  w.endArray().endObject();

  w.key("areas_of_interest").beginArray();
  for (const auto& a : m.aois) {
    w.beginObject();
    w.key("id").value(a.id);
    w.key("polygon");
    writePolygon(w, a.polygon);
    writeWindow(w, a.window);
    w.endObject();
  }
  w.endArray();

  w.key("keep_out_zones").beginArray();
  for (const auto& k : m.kozs) {
    w.beginObject();
    w.key("id").value(k.id).key("purpose").value(k.purpose);
    w.key("polygon");
    writePolygon(w, k.polygon);
    w.key("altitude").beginObject();
    if (k.alt_min) w.key("min").value(*k.alt_min);
    if (k.alt_max) w.key("max").value(*k.alt_max);
    w.endObject();
    writeWindow(w, k.window);
    if (!k.motion.empty()) {
      w.key("motion").beginArray();
      for (const auto& p : k.motion) w.numbers({p.t, p.x, p.y});
      w.endArray();
    }
    w.endObject();
  }
  w.endArray();

  w.key("area_priors").beginArray();
  for (const auto& p : m.priors) {
    w.beginObject();
    w.key("aoi_id").value(p.aoi_id).key("depth").value(p.depth);
    w.key("cells").beginArray();
    for (const auto& c : p.cells) {
      w.beginObject();
      w.key("id").value(c.id).key("row").value(c.row).key("col").value(c.col);
      w.key("polygon");
      writePolygon(w, c.polygon);
      w.key("probability").value(c.probability);
      w.endObject();
    }
    w.endArray().endObject();
  }
  w.endArray();

  w.key("routes").beginArray();
  for (const auto& r : m.routes) {
    w.beginObject();
    w.key("id").value(r.id);
    w.key("polyline");
    writePoints(w, r.polyline);
    w.key("streets").beginArray();
    for (const auto& s : r.streets) w.value(s);
    w.endArray();
    w.key("band_width").value(r.band_width);
    w.key("band_polygon");
    writePolygon(w, r.band);
    w.endObject();
  }
  w.endArray();

  w.key("scene_relations").beginArray();
  for (const auto& r : m.relations) {
    w.beginObject();
    w.key("related").beginObject();
    w.key("id").value(r.related_id).key("class").value(r.related_class);
    w.key("attributes");
    writeAttributes(w, r.related_attributes);
    w.endObject();
    w.key("operator").value(toString(r.op, r.eventually));
    w.key("target").value(r.target_id);
    w.key("evidence").beginObject();
    if (r.op != RelationOp::kPartOf) {
      w.key("distance").value(roundMilli(r.distance));
      w.key("bearing_deg")
          .value(roundMilli(r.bearing_deg) >= 360.0 ? 0.0 : roundMilli(r.bearing_deg));
      w.key("dz").value(roundMilli(r.dz));
      w.key("line_of_sight").value(r.line_of_sight);
    }
    if (r.time) w.key("time").value(*r.time);
    w.endObject();
    w.key("text").value(relationText(r));
    w.endObject();
  }
  w.endArray();
  // Only missions with phases carry the key: single-phase missions read as they always did.
  if (!m.phases.empty()) {
    w.key("phases").beginArray();
    for (const auto& p : m.phases) writePhase(w, p);
    w.endArray();
  }
  w.endObject();
}

}  // namespace

std::string missionJson(const Mission& m) {
  JsonWriter w;
  writeMission(w, m);
  return w.take();
}

void writeSignalPlan(JsonWriter& w, const SignalPlan& sp) {
  w.beginObject();
  w.key("left").value(sp.left).key("green").value(sp.green).key("yellow").value(sp.yellow);
  w.key("all_red").value(sp.all_red).key("sidewalk").value(sp.sidewalk);
  w.key("cycle").value(sp.cycle());
  w.key("intersections").beginArray();
  for (const auto& i : sp.intersections) {
    w.beginObject().key("id").value(i.id).key("x").value(i.position.x());
    w.key("y").value(i.position.y()).key("offset").value(i.offset);
    w.key("heading").numbers({i.heading[0], i.heading[1]});
    w.key("width").numbers({i.width[0], i.width[1]});
    w.endObject();
  }
  w.endArray().endObject();
}

namespace {

// sim_config.json into w (emptied first). traffic_by_reference: a city scenario's episode cars
// and pedestrians are left out of "entities" and named by the "traffic" reference instead.
void writeSimConfig(JsonWriter& w, const SimConfig& s, bool traffic_by_reference = false) {
  if (s.traffic && s.traffic->lean && !traffic_by_reference) {
    throw std::logic_error(s.scenario_id +
                           ": a scenario generated to be written by reference written inline");
  }
  // Room for the whole document up front (a trajectory point takes about 60 characters):
  // growing a 100 KB buffer by doubling would copy it several times.
  std::size_t points = s.uav.perception_path ? s.uav.perception_path->trajectory.size() : 0;
  const std::size_t written =
      s.entities.size() - (s.traffic && traffic_by_reference ? s.traffic->entityCount() : 0);
  for (std::size_t k = 0; k < written; ++k) points += s.entities[k].trajectory.size() + 8;
  for (const auto& a : s.aircraft) points += a.trajectory.size() + 4;
  w.clear(8192 + 64 * points);
  w.beginObject();
  writeHeader(w, "hameritt/sim_config", s.scenario_id, s.cls, s.seed);
  w.key("duration").value(s.duration);
  w.key("world").beginObject();
  w.key("generator").value("hameritt_suburb");
  w.key("fingerprint").value(hex64(s.world_fingerprint));
  w.key("params");
  writeWorldParams(w, s.world);
  w.endObject();

  w.key("entities").beginArray();
  for (std::size_t k = 0; k < written; ++k) {
    const ScenarioEntity& se = s.entities[k];
    const Entity& e = se.entity;
    w.beginObject();
    w.key("id").value(e.id).key("class").value(toString(e.cls)).key("role").value(se.role);
    w.key("attributes");
    writeAttributes(w, e.attributes);
    writePose(w, e);
    w.key("trajectory").beginArray();
    for (const auto& p : se.trajectory) w.numbers({p.t, p.x, p.y, p.z, p.yaw});
    w.endArray();
    w.endObject();
  }
  w.endArray();

  w.key("groups").beginArray();
  for (const auto& g : s.groups) {
    w.beginObject();
    w.key("id").value(g.id).key("kind").value(g.kind);
    w.key("members").beginArray();
    for (const auto& m : g.members) w.value(m);
    w.endArray().endObject();
  }
  w.endArray();
  // Only avoid scenarios carry the key: the other classes' files read as they always did.
  if (!s.aircraft.empty()) {
    w.key("aircraft").beginArray();
    for (const auto& a : s.aircraft) {
      w.beginObject();
      w.key("id").value(a.id).key("model").value(a.model);
      w.key("size").numbers({a.size.x(), a.size.y(), a.size.z()});
      w.key("trajectory").beginArray();
      for (const auto& p : a.trajectory) w.numbers({p.t, p.x, p.y, p.z, p.yaw});
      w.endArray().endObject();
    }
    w.endArray();
  }

  const Environment& env = s.environment;
  w.key("environment").beginObject();
  w.key("time_of_day").value(env.time_of_day);
  w.key("snow").value(env.snow).key("rain").value(env.rain).key("dust").value(env.dust);
  w.key("fog").value(env.fog).key("foliage").value(env.foliage);
  w.key("wind").beginObject();
  w.key("mean").numbers({env.wind_mean.x(), env.wind_mean.y(), env.wind_mean.z()});
  w.key("gust_intensity").value(env.gust_intensity);
  w.endObject().endObject();

  const UavSpec& u = s.uav;
  w.key("uav").beginObject();
  w.key("model").value(u.model);
  w.key("start").beginObject();
  w.key("x").value(u.start.x).key("y").value(u.start.y).key("z").value(u.start.z);
  w.key("yaw").value(u.start.yaw);
  w.endObject();
  w.key("altitude").beginObject().key("min").value(u.altitude_min).key("max").value(u.altitude_max).endObject();
  w.key("max_speed").value(u.max_speed);
  w.key("payload").beginObject().key("cameras").beginArray();
  for (const auto& c : u.cameras) {
    w.beginObject();
    w.key("name").value(c.name);
    w.key("mount").beginObject();
    w.key("xyz").numbers({c.mount_xyz.x(), c.mount_xyz.y(), c.mount_xyz.z()});
    w.key("rpy_deg").numbers({c.mount_rpy.x(), c.mount_rpy.y(), c.mount_rpy.z()});
    w.endObject();
    w.key("width").value(c.width).key("height").value(c.height);
    w.key("hfov_deg").value(c.hfov_deg).key("rate_hz").value(c.rate_hz);
    w.key("modalities").beginArray();
    for (const auto& m : c.modalities) w.value(m);
    w.endArray().endObject();
  }
  w.endArray().endObject();
  if (u.perception_path) {
    const PerceptionPath& pp = *u.perception_path;
    w.key("perception_path").beginObject();
    w.key("status").value(pp.status);
    w.key("camera").value(pp.camera);
    w.key("targets_seen").beginArray();
    for (const auto& id : pp.targets_seen) w.value(id);
    w.endArray();
    w.key("trajectory").beginArray();
    for (const auto& p : pp.trajectory) w.numbers({p.t, p.x, p.y, p.z, p.yaw});
    w.endArray().endObject();
  }
  w.endObject();

  w.key("perturbations").beginObject().key("camera_noise").beginObject();
  w.key("gaussian_std").value(s.perturbations.gaussian_noise_std);
  w.key("salt_pepper_probability").value(s.perturbations.salt_pepper_probability);
  w.key("motion_blur_px").value(s.perturbations.motion_blur_px);
  w.endObject().endObject();
  if (s.signals) {
    w.key("signals");
    writeSignalPlan(w, *s.signals);
  }
  if (s.traffic && traffic_by_reference) {
    const TrafficEpisodeRef& r = *s.traffic;
    w.key("traffic").beginObject();
    w.key("file").value(r.file).key("episode").value(r.episode).key("offset").value(r.offset);
    w.key("sha256").value(r.sha256);
    w.key("cars").beginArray();
    for (const auto& id : r.car_ids) w.value(id);
    w.endArray();
    w.key("pedestrians").beginArray();
    for (const auto& id : r.pedestrian_ids) w.value(id);
    w.endArray();
    if (!r.withheld.empty()) {
      w.key("withheld").beginArray();
      for (const auto& id : r.withheld) w.value(id);
      w.endArray();
    }
    w.endObject();
  }
  if (s.spec) {
    w.key("spec").beginObject();
    w.key("file").value(s.spec->file).key("hash").value(hex64(s.spec->hash));
    w.key("sampler").value(s.spec->sampler);
    w.key("values").beginObject();
    for (const auto& [name, v] : s.spec->values) {
      w.key(name);
      if (const bool* b = std::get_if<bool>(&v))
        w.value(*b);
      else
        w.value(std::get<double>(v));
    }
    w.endObject().endObject();
  }
  w.endObject();
}

}  // namespace

std::string simConfigJson(const SimConfig& s, bool traffic_by_reference) {
  JsonWriter w(true, 64);  // sized by writeSimConfig()
  writeSimConfig(w, s, traffic_by_reference);
  return w.take();
}

std::string worldParamsJson(const WorldParams& p) {
  JsonWriter w;
  writeWorldParams(w, p);
  return w.take();
}

std::string worldJson(const World& world) {
  JsonWriter w;
  w.beginObject();
  w.key("schema").value("hameritt/world");
  w.key("schema_version").value(kSchemaVersion);
  w.key("fingerprint").value(hex64(world.fingerprint()));
  w.key("params");
  writeWorldParams(w, world.params());
  const auto b = world.bounds();
  w.key("bounds").beginObject();
  w.key("min").numbers({b.min.x(), b.min.y()}).key("max").numbers({b.max.x(), b.max.y()});
  w.endObject();
  w.key("streets").beginObject().key("nodes").beginArray();
  for (const auto& n : world.nodes()) w.numbers({n.position.x(), n.position.y()});
  w.endArray().key("edges").beginArray();
  for (const auto& e : world.edges()) {
    w.beginObject();
    w.key("a").value(e.a).key("b").value(e.b).key("width").value(e.width).key("name").value(e.name);
    w.key("entity").value(world.entities()[static_cast<std::size_t>(e.entity)].id);
    w.endObject();
  }
  w.endArray().endObject();
  w.key("blocks").beginArray();
  for (const auto& bl : world.blocks()) {
    w.beginObject();
    w.key("name").value(bl.name);
    w.key("outline");
    writePolygon(w, bl.outline);
    w.key("sidewalk");
    writePoints(w, bl.sidewalk);
    w.endObject();
  }
  w.endArray();
  w.key("parking_slots").beginArray();
  for (const auto& s : world.slots()) {
    w.beginObject();
    w.key("position").numbers({s.position.x(), s.position.y(), s.ground_z});
    w.key("yaw").value(s.yaw).key("driveway").value(s.driveway);
    if (s.occupant >= 0) w.key("occupant").value(world.entities()[static_cast<std::size_t>(s.occupant)].id);
    w.endObject();
  }
  w.endArray();
  w.key("entities").beginArray();
  for (const auto& e : world.entities()) {
    w.beginObject();
    w.key("id").value(e.id).key("class").value(toString(e.cls));
    w.key("attributes");
    writeAttributes(w, e.attributes);
    writePose(w, e);
    w.key("block").value(e.block);
    w.endObject();
  }
  w.endArray();
  w.endObject();
  return w.take();
}

namespace {

// Writes `content` to a new file `p` (write() until done, then fsync() when `sync`); throws
// OutputError naming `shown` and the cause (ENOSPC: "No space left on device"). Removes nothing.
void writeWhole(const std::string& p, std::string_view content, bool sync,
                const std::string& shown) {
  const int fd = ::open(p.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw OutputError(shown + ": cannot write: " + std::strerror(errno));
  std::size_t done = 0;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n == 0 ? EIO : errno;
      ::close(fd);
      throw OutputError(shown + ": write failed: " + std::strerror(err));
    }
    done += static_cast<std::size_t>(n);
  }
  if (sync && ::fsync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    throw OutputError(shown + ": write failed: " + std::strerror(err));
  }
  if (::close(fd) != 0) throw OutputError(shown + ": write failed: " + std::strerror(errno));
}

// Flushes a directory's entries (a rename in it) to the disk; best effort.
void syncDirectory(const std::string& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void writeFileAtomic(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp." + std::to_string(::getpid());
  try {
    writeWhole(tmp, content, /*sync=*/true, path);
  } catch (const OutputError&) {
    std::remove(tmp.c_str());
    throw;
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    std::remove(tmp.c_str());
    throw OutputError(path + ": cannot rename into place: " + std::strerror(err));
  }
  syncDirectory(fs::path(path).parent_path().string());
}

void replaceDirectory(const std::string& tmp, const std::string& final_path) {
  if (std::rename(tmp.c_str(), final_path.c_str()) == 0) return;
  if (errno != EEXIST && errno != ENOTEMPTY) {
    throw OutputError(final_path + ": cannot move into place: " + std::strerror(errno));
  }
  std::error_code ec;
  // An older directory of the same name: swap the two in one step, then remove the old one.
  if (::renameat2(AT_FDCWD, tmp.c_str(), AT_FDCWD, final_path.c_str(), RENAME_EXCHANGE) == 0) {
    fs::remove_all(tmp, ec);
    return;
  }
  if (errno != EINVAL && errno != ENOSYS) {
    throw OutputError(final_path + ": cannot move into place: " + std::strerror(errno));
  }
  // A file system without the exchange: move the old one aside, then the new one in.
  const std::string old = final_path + ".old-" + std::to_string(::getpid());
  if (std::rename(final_path.c_str(), old.c_str()) != 0 ||
      std::rename(tmp.c_str(), final_path.c_str()) != 0) {
    throw OutputError(final_path + ": cannot move into place: " + std::strerror(errno));
  }
  fs::remove_all(old, ec);
}

std::string writeScenarioDir(const std::string& dir, const Scenario& s, bool traffic_by_reference) {
  const std::string final_dir = dir + "/" + s.mission.scenario_id;
  const std::string tmp = dir + "/.tmp-" + s.mission.scenario_id + "-" + std::to_string(::getpid());
  std::error_code ec;
  if (::mkdir(tmp.c_str(), 0755) != 0) {
    // A leftover of an interrupted run with the same pid: clear it once and retry.
    if (errno == EEXIST) fs::remove_all(tmp, ec);
    if (errno != EEXIST || ::mkdir(tmp.c_str(), 0755) != 0) {
      throw OutputError(tmp + ": cannot create directory: " + std::strerror(errno));
    }
  }
  try {
    auto put = [&](const char* name, std::string_view content) {
      const std::string p = tmp + "/" + name;
      writeWhole(p, content, /*sync=*/false, p);
    };
    // Both documents are formatted in per-thread writers whose buffers are reused from one
    // scenario to the next, and written from there (the same bytes as missionJson() and
    // simConfigJson()).
    thread_local JsonWriter t_writer;
    writeMission(t_writer, s.mission);
    put("mission.json", t_writer.finish());
    writeSimConfig(t_writer, s.sim, traffic_by_reference);
    put("sim_config.json", t_writer.finish());
    replaceDirectory(tmp, final_dir);
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
  return final_dir;
}

}  // namespace hameritt::scenario
