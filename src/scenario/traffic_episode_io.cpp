// The traffic episode file of the city (scenario/city_traffic.h): its writer, its strict reader
// and the SHA-256 that a scenario's reference carries.

#include <openssl/evp.h>

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "hameritt/scenario/city_traffic.h"
#include "hameritt/scenario/json_writer.h"
#include "hameritt/scenario/scenario_io.h"
#include "signal_plan_io.h"
#include "strict_json.h"

namespace hameritt::scenario {

namespace {

using json = strict_json::json;
using Obj = strict_json::Object;
using strict_json::fmt;
using strict_json::idx;

constexpr const char* kEpisodeFormat = "hameritt/traffic_episode";

// A flat array of numbers at `path`.
std::vector<double> flatNumbers(const json& a, const std::string& path, const std::string& file) {
  std::vector<double> out;
  out.reserve(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a[i].is_number() || !std::isfinite(a[i].get<double>())) {
      throw ConfigError(file + ": " + idx(path, i) + ": expected a finite number, got " +
                        a[i].dump());
    }
    out.push_back(a[i].get<double>());
  }
  return out;
}

}  // namespace

std::string trafficEpisodeJson(const TrafficEpisode& e) {
  std::size_t knots = 0;
  for (const auto& c : e.cars) knots += c.knots.size();
  for (const auto& p : e.pedestrians) knots += 4 * p.trajectory.size() + 8;
  JsonWriter w(false, 4096 + 12 * knots);
  w.beginObject();
  w.key("format").value(kEpisodeFormat).key("schema_version").value(kSchemaVersion);
  w.key("world_fingerprint").value(hex64(e.world_fingerprint));
  w.key("episode").value(e.index).key("length").value(e.length);
  w.key("signals");
  writeSignalPlan(w, e.plan);
  w.key("lanes").beginArray();
  for (const auto& l : e.lanes) {
    w.beginObject().key("name").value(l.name).key("points").beginArray();
    for (const auto& p : l.points) w.value(p.x()).value(p.y());
    w.endArray().endObject();
  }
  w.endArray();
  w.key("cars").beginArray();
  for (const auto& c : e.cars) {
    w.beginObject();
    w.key("path").beginArray();
    for (int p : c.path) w.value(p);
    w.endArray().key("vehicle_class").value(c.vehicle_class);
    w.key("make").value(c.make).key("model").value(c.model).key("color").value(c.color);
    w.key("size").numbers({c.size.x(), c.size.y(), c.size.z()});
    w.key("knots").beginArray();
    for (double v : c.knots) w.value(v);
    w.endArray().endObject();
  }
  w.endArray();
  w.key("pedestrians").beginArray();
  for (const auto& p : e.pedestrians) {
    w.beginObject();
    w.key("activity").value(p.activity).key("clothing_color").value(p.clothing_color);
    w.key("height").value(p.height);
    w.key("pose").numbers({p.pose.x, p.pose.y, p.pose.yaw});
    w.key("keyframes").beginArray();
    for (const auto& q : p.trajectory) w.value(q.t).value(q.x).value(q.y).value(q.yaw);
    w.endArray().endObject();
  }
  w.endArray();
  w.endObject();
  return w.take();
}

TrafficEpisode parseTrafficEpisode(const std::string& text, const std::string& file) {
  const json j = strict_json::parseText(text, file);
  Obj root(j, "", file);
  TrafficEpisode e;
  const std::string format = root.string("format");
  if (format != kEpisodeFormat) {
    root.error("format",
               std::string("expected \"") + kEpisodeFormat + "\", got \"" + format + "\"");
  }
  if (root.integer("schema_version") != kSchemaVersion) {
    root.error("schema_version", "expected " + std::to_string(kSchemaVersion));
  }
  const std::string fp = root.string("world_fingerprint");
  if (fp.size() != 16 || fp.find_first_not_of("0123456789abcdef") != std::string::npos) {
    root.error("world_fingerprint", "expected 16 lower-case hex digits, got \"" + fp + "\"");
  }
  e.world_fingerprint = std::stoull(fp, nullptr, 16);
  const std::int64_t index = root.integer("episode");
  if (index < 0 || index > 63) root.error("episode", "expected 0 to 63");
  e.index = static_cast<int>(index);
  e.length = root.numberIn("length", 1, 1e6);
  {
    Obj sg = root.object("signals");
    e.plan = readSignalPlan(sg, "signals", file);
  }
  const json& lanes = root.array("lanes");
  for (std::size_t i = 0; i < lanes.size(); ++i) {
    Obj l(lanes[i], idx("lanes", i), file);
    TrafficEpisode::Lane lane;
    lane.name = l.string("name");
    const std::vector<double> p = flatNumbers(l.array("points"), l.at("points"), file);
    if (p.size() < 4 || p.size() % 2 != 0) {
      l.error("points", "expected a polyline x0, y0, x1, y1, ... of at least 2 points");
    }
    for (std::size_t k = 0; k + 1 < p.size(); k += 2) lane.points.emplace_back(p[k], p[k + 1]);
    l.finish();
    e.lanes.push_back(std::move(lane));
  }
  const json& cars = root.array("cars");
  for (std::size_t i = 0; i < cars.size(); ++i) {
    Obj c(cars[i], idx("cars", i), file);
    TrafficEpisode::Car car;
    const json& path = c.array("path");
    if (path.empty()) c.error("path", "expected at least one lane piece");
    for (std::size_t k = 0; k < path.size(); ++k) {
      if (!path[k].is_number_integer() || path[k].get<std::int64_t>() < 0 ||
          path[k].get<std::int64_t>() >= static_cast<std::int64_t>(e.lanes.size())) {
        throw ConfigError(file + ": " + idx(c.at("path"), k) +
                          ": expected a lane index from 0 to " +
                          std::to_string(e.lanes.size() - 1) + ", got " + path[k].dump());
      }
      const int id = path[k].get<int>();
      if (k > 0) {
        const auto& a = e.lanes[static_cast<std::size_t>(car.path.back())].points.back();
        const auto& b = e.lanes[static_cast<std::size_t>(id)].points.front();
        if ((a - b).norm() > 1e-6) {
          throw ConfigError(file + ": " + idx(c.at("path"), k) +
                            ": expected a lane piece that starts where the previous one ends");
        }
      }
      car.path.push_back(id);
    }
    car.vehicle_class = c.string("vehicle_class");
    car.make = c.string("make");
    car.model = c.string("model");
    car.color = c.string("color");
    const std::vector<double> size = flatNumbers(c.array("size"), c.at("size"), file);
    if (size.size() != 3 || !(size[0] > 0 && size[1] > 0 && size[2] > 0)) {
      c.error("size", "expected 3 positive numbers (length, width, height)");
    }
    car.size = geometry::Vec3(size[0], size[1], size[2]);
    car.knots = flatNumbers(c.array("knots"), c.at("knots"), file);
    if (car.knots.size() < 4 || car.knots.size() % 2 != 0) {
      c.error("knots", "expected pairs t, s: at least 2 of them");
    }
    if (car.knots[0] != 0.0) c.error("knots", "expected the first knot at t = 0");
    for (std::size_t k = 2; k < car.knots.size(); k += 2) {
      if (!(car.knots[k] > car.knots[k - 2])) {
        throw ConfigError(file + ": " + idx(c.at("knots"), k) + ": expected t increasing, got " +
                          fmt(car.knots[k]) + " after " + fmt(car.knots[k - 2]));
      }
      if (car.knots[k + 1] < car.knots[k - 1]) {
        throw ConfigError(file + ": " + idx(c.at("knots"), k + 1) +
                          ": expected s non-decreasing (cars drive forward), got " +
                          fmt(car.knots[k + 1]) + " after " + fmt(car.knots[k - 1]));
      }
    }
    if (car.knots[car.knots.size() - 2] < e.length) {
      c.error("knots", "expected knots up to the episode's length " + fmt(e.length) + " s");
    }
    c.finish();
    e.cars.push_back(std::move(car));
  }
  const json& peds = root.array("pedestrians");
  for (std::size_t i = 0; i < peds.size(); ++i) {
    Obj o(peds[i], idx("pedestrians", i), file);
    CityPedestrian p;
    p.activity = o.string("activity");
    if (p.activity != "walking" && p.activity != "crossing" && p.activity != "jaywalking" &&
        p.activity != "queuing") {
      o.error("activity",
              "expected walking, crossing, jaywalking or queuing, got \"" + p.activity + "\"");
    }
    p.clothing_color = o.string("clothing_color");
    p.height = o.numberIn("height", 0.5, 2.5);
    const std::vector<double> pose = flatNumbers(o.array("pose"), o.at("pose"), file);
    if (pose.size() != 3) o.error("pose", "expected 3 numbers (x, y, yaw)");
    p.pose.x = pose[0];
    p.pose.y = pose[1];
    p.pose.yaw = pose[2];
    const std::vector<double> k = flatNumbers(o.array("keyframes"), o.at("keyframes"), file);
    if (k.size() % 4 != 0 || (p.activity == "queuing") != k.empty()) {
      o.error("keyframes", p.activity == "queuing"
                               ? "expected none for a pedestrian who queues"
                               : "expected t, x, y, yaw quadruples, the first at t = 0");
    }
    for (std::size_t q = 0; q < k.size(); q += 4) {
      if (q == 0 ? k[0] != 0.0 : !(k[q] > k[q - 4])) {
        throw ConfigError(file + ": " + idx(o.at("keyframes"), q) +
                          (q == 0 ? ": expected the first keyframe at t = 0, got "
                                  : ": expected t increasing, got ") +
                          fmt(k[q]));
      }
      p.trajectory.push_back({k[q], k[q + 1], k[q + 2], 0.0, k[q + 3]});
    }
    if (!p.trajectory.empty() && p.trajectory.back().t < e.length) {
      o.error("keyframes", "expected keyframes up to the episode's length " + fmt(e.length) + " s");
    }
    o.finish();
    e.pedestrians.push_back(std::move(p));
  }
  root.finish();
  return e;
}

// SHA-256 by OpenSSL's libcrypto (the project links it for the TAK bridge's TLS).
std::string sha256Hex(const std::string& bytes) {
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  if (EVP_Digest(bytes.data(), bytes.size(), md, &len, EVP_sha256(), nullptr) != 1) {
    throw std::runtime_error("sha256Hex: OpenSSL EVP_Digest failed");
  }
  std::string out;
  char buf[3];
  for (unsigned int i = 0; i < len; ++i) {
    std::snprintf(buf, sizeof(buf), "%02x", md[i]);
    out += buf;
  }
  return out;
}

}  // namespace hameritt::scenario
