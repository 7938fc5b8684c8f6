// The traffic episode file of the city (scenario/city_traffic.h): its writer, its strict reader
// and the SHA-256 that a scenario's reference carries.

#include <array>
#include <cstdint>
#include <cstdio>
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
    w.key("lane").value(c.lane).key("vehicle_class").value(c.vehicle_class);
    w.key("make").value(c.make).key("model").value(c.model).key("color").value(c.color);
    w.key("size").numbers({c.size.x(), c.size.y(), c.size.z()});
    w.key("knots").beginArray();
    for (double v : c.knots) w.value(v);
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
    if (p.size() < 8 || p.size() % 2 != 0 || p[0] != p[p.size() - 2] || p[1] != p.back()) {
      l.error("points", "expected a closed polyline x0, y0, x1, y1, ... of at least 4 points");
    }
    for (std::size_t k = 0; k + 1 < p.size(); k += 2) lane.points.emplace_back(p[k], p[k + 1]);
    l.finish();
    e.lanes.push_back(std::move(lane));
  }
  const json& cars = root.array("cars");
  for (std::size_t i = 0; i < cars.size(); ++i) {
    Obj c(cars[i], idx("cars", i), file);
    TrafficEpisode::Car car;
    const std::int64_t lane = c.integer("lane");
    if (lane < 0 || lane >= static_cast<std::int64_t>(e.lanes.size())) {
      c.error("lane", "expected a lane index from 0 to " + std::to_string(e.lanes.size() - 1));
    }
    car.lane = static_cast<int>(lane);
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
  root.finish();
  return e;
}

// SHA-256 after FIPS 180-4, section 6.2.
std::string sha256Hex(const std::string& bytes) {
  static constexpr std::array<std::uint32_t, 64> k = {
      0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4,
      0xab1c5ed5, 0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe,
      0x9bdc06a7, 0xc19bf174, 0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f,
      0x4a7484aa, 0x5cb0a9dc, 0x76f988da, 0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7,
      0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967, 0x27b70a85, 0x2e1b2138, 0x4d2c6dfc,
      0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85, 0xa2bfe8a1, 0xa81a664b,
      0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070, 0x19a4c116,
      0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
      0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7,
      0xc67178f2};
  std::array<std::uint32_t, 8> h = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                    0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
  auto rotr = [](std::uint32_t x, int n) { return (x >> n) | (x << (32 - n)); };
  std::string m = bytes;
  const std::uint64_t bits = static_cast<std::uint64_t>(bytes.size()) * 8;
  m.push_back(static_cast<char>(0x80));
  while (m.size() % 64 != 56) m.push_back('\0');
  for (int i = 7; i >= 0; --i) m.push_back(static_cast<char>((bits >> (8 * i)) & 0xff));
  std::array<std::uint32_t, 64> w{};
  for (std::size_t block = 0; block < m.size(); block += 64) {
    for (int t = 0; t < 16; ++t) {
      const auto* p = reinterpret_cast<const unsigned char*>(m.data() + block + 4 * t);
      w[t] = (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) |
             (std::uint32_t{p[2]} << 8) | std::uint32_t{p[3]};
    }
    for (int t = 16; t < 64; ++t) {
      const std::uint32_t s0 = rotr(w[t - 15], 7) ^ rotr(w[t - 15], 18) ^ (w[t - 15] >> 3);
      const std::uint32_t s1 = rotr(w[t - 2], 17) ^ rotr(w[t - 2], 19) ^ (w[t - 2] >> 10);
      w[t] = w[t - 16] + s0 + w[t - 7] + s1;
    }
    std::uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4], f = h[5], g = h[6], hh = h[7];
    for (int t = 0; t < 64; ++t) {
      const std::uint32_t t1 =
          hh + (rotr(e, 6) ^ rotr(e, 11) ^ rotr(e, 25)) + ((e & f) ^ (~e & g)) + k[t] + w[t];
      const std::uint32_t t2 =
          (rotr(a, 2) ^ rotr(a, 13) ^ rotr(a, 22)) + ((a & b) ^ (a & c) ^ (b & c));
      hh = g;
      g = f;
      f = e;
      e = d + t1;
      d = c;
      c = b;
      b = a;
      a = t1 + t2;
    }
    h[0] += a;
    h[1] += b;
    h[2] += c;
    h[3] += d;
    h[4] += e;
    h[5] += f;
    h[6] += g;
    h[7] += hh;
  }
  std::string out;
  char buf[9];
  for (std::uint32_t v : h) {
    std::snprintf(buf, sizeof(buf), "%08x", v);
    out += buf;
  }
  return out;
}

}  // namespace hameritt::scenario
