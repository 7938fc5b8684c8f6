#pragma once
// Private to the scenario library: the strict reader behind loadMission() and loadSimConfig().
// Every key of an object must be read exactly once (finish() rejects the rest), and every error
// is a ConfigError naming the file, the JSON path ("entities[3].trajectory[2]") and what was
// expected. Documents are nlohmann::ordered_json so that attribute order survives a round trip.

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include "hameritt/scenario/bounded_json.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/scenario.h"

namespace hameritt::scenario::strict_json {

using json = nlohmann::ordered_json;

// A double with all its digits, for messages.
inline std::string fmt(double v) { return formatNumber(v); }

// An integer that std::int64_t holds (JSON integers above 2^63 - 1 would wrap around).
inline bool isInt64(const json& v) {
  return v.is_number_integer() &&
         !(v.is_number_unsigned() &&
           v.get<std::uint64_t>() > static_cast<std::uint64_t>(INT64_MAX));
}

// "path[i]".
inline std::string idx(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

// Parses a whole document text, keeping key order (ConfigError on syntax errors and beyond the
// size and depth limits of bounded_json.h, with `file`).
inline json parseText(const std::string& text, const std::string& file) {
  checkJsonText(text, file);
  try {
    return json::parse(text);
  } catch (const json::exception& e) {  // parse_error, and out_of_range for a number beyond a double
    throw ConfigError(file + ": malformed JSON: " + e.what());
  }
}

// Parses a whole file, keeping key order (ConfigError on I/O or syntax errors, with the file).
inline json parseFile(const std::string& path) { return parseText(readBoundedFile(path), path); }

// A JSON object being read strictly.
class Object {
 public:
  Object(const json& j, std::string path, const std::string& file)
      : j_(j), path_(std::move(path)), file_(file) {
    if (!j_.is_object()) fail(path_.empty() ? std::string("(root)") : path_, "expected an object", j_);
  }

  [[noreturn]] void fail(const std::string& path, const std::string& what, const json& got) const {
    throw ConfigError(file_ + ": " + path + ": " + what + ", got " + got.type_name() +
                      (got.is_primitive() ? " " + got.dump() : std::string()));
  }
  [[noreturn]] void error(const std::string& key, const std::string& what) const {
    throw ConfigError(file_ + ": " + at(key) + ": " + what);
  }

  std::string at(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  bool has(const std::string& key) const { return j_.find(key) != j_.end(); }

  const json& get(const std::string& key) {
    const auto it = j_.find(key);
    if (it == j_.end()) throw ConfigError(file_ + ": " + at(key) + ": missing required key");
    used_.insert(key);
    return *it;
  }
  double number(const std::string& key) {
    const json& v = get(key);
    if (!v.is_number()) fail(at(key), "expected a number", v);
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(at(key), "expected a finite number", v);
    return d;
  }
  double numberIn(const std::string& key, double lo, double hi) {
    const double v = number(key);
    if (!(v >= lo && v <= hi)) {
      error(key, "expected a number in [" + fmt(lo) + ", " + fmt(hi) + "], got " + fmt(v));
    }
    return v;
  }
  std::int64_t integer(const std::string& key) {
    const json& v = get(key);
    if (!isInt64(v)) fail(at(key), "expected an integer within [-2^63, 2^63)", v);
    return v.get<std::int64_t>();
  }
  std::uint64_t unsignedInteger(const std::string& key) {
    const json& v = get(key);
    if (!v.is_number_unsigned()) fail(at(key), "expected a non-negative integer", v);
    return v.get<std::uint64_t>();
  }
  std::string string(const std::string& key) {
    const json& v = get(key);
    if (!v.is_string()) fail(at(key), "expected a string", v);
    return v.get<std::string>();
  }
  bool boolean(const std::string& key) {
    const json& v = get(key);
    if (!v.is_boolean()) fail(at(key), "expected a boolean", v);
    return v.get<bool>();
  }
  const json& array(const std::string& key) {
    const json& v = get(key);
    if (!v.is_array()) fail(at(key), "expected an array", v);
    return v;
  }
  Object object(const std::string& key) { return Object(get(key), at(key), file_); }

  // Unknown keys are errors.
  void finish() const {
    for (auto it = j_.begin(); it != j_.end(); ++it) {
      if (!used_.count(it.key())) throw ConfigError(file_ + ": " + at(it.key()) + ": unknown key");
    }
  }

  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }

 private:
  const json& j_;
  std::string path_;
  const std::string& file_;
  std::set<std::string> used_;
};

// A fixed-length array of numbers.
template <std::size_t N>
std::array<double, N> numbers(const json& v, const std::string& path, const std::string& file) {
  if (!v.is_array() || v.size() != N) {
    throw ConfigError(
        file + ": " + path + ": expected an array of " + std::to_string(N) + " numbers, got " +
        (v.is_array() ? "an array of " + std::to_string(v.size()) : std::string(v.type_name())));
  }
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    if (!v[i].is_number()) {
      throw ConfigError(file + ": " + idx(path, i) + ": expected a number, got " +
                        v[i].type_name());
    }
    out[i] = v[i].get<double>();
  }
  return out;
}

// A timed path [[t, x, y, z, yaw], ...]: times >= 0 and strictly increasing (two samples at
// one time would be a teleport).
inline Trajectory trajectory(const json& v, const std::string& path, const std::string& file) {
  Trajectory out;
  out.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    const std::string p = idx(path, i);
    const auto a = numbers<5>(v[i], p, file);
    if (!(a[0] >= 0)) {
      throw ConfigError(file + ": " + p + ": expected a time >= 0, got " + fmt(a[0]));
    }
    if (!out.empty() && !(a[0] > out.back().t)) {
      throw ConfigError(file + ": " + p + ": expected strictly increasing times, got t = " +
                        fmt(a[0]) + " after " + fmt(out.back().t));
    }
    out.push_back({a[0], a[1], a[2], a[3], a[4]});
  }
  return out;
}

// The header shared by mission.json and sim_config.json (see writeHeader in scenario_io.cpp).
struct Header {
  std::string scenario_id;
  ScenarioClass cls = ScenarioClass::kAreaSearch;
  std::uint64_t seed = 0;
};

// Reads and checks "schema" (== kind), "schema_version", "scenario_id", "class" and "seed".
inline Header header(Object& root, const std::string& kind) {
  const std::string& file = root.file();
  const std::string schema = root.string("schema");
  if (schema != kind) {
    throw ConfigError(file + ": schema: expected \"" + kind + "\", got \"" + schema + "\"");
  }
  const std::int64_t version = root.integer("schema_version");
  if (version != kSchemaVersion) {
    throw ConfigError(file + ": schema_version: expected " + std::to_string(kSchemaVersion) +
                      ", got " + std::to_string(version));
  }
  Header h;
  h.scenario_id = root.string("scenario_id");
  const std::string cls = root.string("class");
  if (!parseScenarioClass(cls, &h.cls)) {
    throw ConfigError(file + ": class: expected area_search, route_search or pursuit, got \"" +
                      cls + "\"");
  }
  h.seed = root.unsignedInteger("seed");
  return h;
}

}  // namespace hameritt::scenario::strict_json
