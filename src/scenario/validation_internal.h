// Private declarations shared by the validator's sources: JSON helpers and the semantic checker.
#pragma once

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <unordered_map>
#include <utility>

#include "hameritt/geometry/polygon.h"
#include "hameritt/scenario/bounded_json.h"
#include "hameritt/scenario/params_table.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/validation.h"

namespace hameritt::scenario {

namespace validation_internal {

using geometry::Polygon;
using geometry::Vec2;
using nlohmann::json;

// ------------------------------------------------------------------ small helpers

// A value for a message, shortened.
inline std::string brief(const json& v) {
  std::string s = v.dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  return s;
}

inline std::string num(double v) {
  std::ostringstream os;
  os.precision(12);
  os << v;
  return os.str();
}

inline bool isInteger(const json& v) {
  if (v.is_number_integer()) return true;
  if (!v.is_number_float()) return false;
  const double d = v.get<double>();
  return std::isfinite(d) && std::floor(d) == d;
}

inline bool isNonNegativeInteger(const json& v) { return isInteger(v) && v.get<double>() >= 0; }

// v as a T when it is an integer (integer-valued floats included) that T holds exactly;
// nullopt otherwise (a fraction, 1e300, 2^64, or a negative for an unsigned T). Converting an
// out-of-range double is undefined behaviour, so every integer read goes through here.
template <typename T>
std::optional<T> integerAs(const json& v) {
  using Limits = std::numeric_limits<T>;
  if (v.is_number_unsigned()) {
    const auto u = v.get<std::uint64_t>();
    if (u > static_cast<std::uint64_t>(Limits::max())) return std::nullopt;
    return static_cast<T>(u);
  }
  if (v.is_number_integer()) {
    const auto i = v.get<std::int64_t>();
    if (i < 0 && !Limits::is_signed) return std::nullopt;
    if (Limits::is_signed && (i < static_cast<std::int64_t>(Limits::min()) ||
                              i > static_cast<std::int64_t>(Limits::max()))) {
      return std::nullopt;
    }
    return static_cast<T>(i);
  }
  if (!isInteger(v)) return std::nullopt;
  const double d = v.get<double>();
  const double limit = std::ldexp(1.0, Limits::digits);  // 2^bits: the first value T lacks
  if (d >= limit || d < (Limits::is_signed ? -limit : 0.0)) return std::nullopt;
  return static_cast<T>(d);
}

// ------------------------------------------------------------------ semantic checks

inline const json* member(const json& j, const char* key) {
  if (!j.is_object()) return nullptr;
  auto it = j.find(key);
  return it == j.end() ? nullptr : &*it;
}

inline const json& arrayOrEmpty(const json& j, const char* key) {
  static const json kEmpty = json::array();
  const json* m = member(j, key);
  return m && m->is_array() ? *m : kEmpty;
}

inline std::optional<double> numberAt(const json& j, const char* key) {
  const json* m = member(j, key);
  if (!m || !m->is_number()) return std::nullopt;
  return m->get<double>();
}

inline std::optional<std::string> stringAt(const json& j, const char* key) {
  const json* m = member(j, key);
  if (!m || !m->is_string()) return std::nullopt;
  return m->get<std::string>();
}

inline bool toPoint(const json& j, Vec2* out) {
  if (!j.is_array() || j.size() != 2 || !j[0].is_number() || !j[1].is_number()) return false;
  *out = Vec2(j[0].get<double>(), j[1].get<double>());
  return true;
}

inline bool toPoints(const json& j, std::vector<Vec2>* out) {
  if (!j.is_array()) return false;
  out->clear();
  for (const auto& p : j) {
    Vec2 v;
    if (!toPoint(p, &v)) return false;
    out->push_back(v);
  }
  return true;
}

class Semantics {
 public:
  Semantics(const json& doc, std::string file, const std::vector<ValidationIssue>& schema_issues,
            std::vector<ValidationIssue>* out);

  void run(DocumentKind kind);

 private:
  // Ids of one namespace: reports a repeated id at its position.
  class IdSet {
   public:
    IdSet(Semantics* s, std::string what) : s_(s), what_(std::move(what)) {}
    // Notes item[key] (a string) found at item_path; false when it repeats.
    bool note(const json& item, const std::string& item_path, const char* key = "id") {
      const auto id = stringAt(item, key);
      if (!id) return true;
      return noteId(*id, jsonPointerAppend(item_path, key));
    }
    // Notes `id` found at pointer `p`; false when it repeats.
    bool noteId(const std::string& id, const std::string& p) {
      auto [it, fresh] = first_.emplace(id, p);
      if (!fresh) {
        s_->add(p, "unique_id",
                "duplicate " + what_ + " '" + id + "' (first at " + it->second + ")");
      }
      return fresh;
    }
    bool has(const std::string& id) const { return first_.count(id) > 0; }

   private:
    Semantics* s_;
    std::string what_;
    std::unordered_map<std::string, std::string> first_;
  };

  void add(const std::string& path, const std::string& rule, const std::string& message);

  // True when the schema reported something at or below `path`.
  bool schemaFlagged(const std::string& path) const;

  // A simple polygon from j, or nullopt (reported when the points are there but the ring is
  // not simple; malformed point lists are the schema's to report).
  std::optional<Polygon> polygon(const json& j, const std::string& path);

  void timeWindow(const json& owner, const std::string& owner_path);

  void altitude(const json& alt, const std::string& path);

  // scenario_id must be "<class>-<16 hex digits of seed>".
  void scenarioId(const json& entry, const std::string& path);

  // World parameters at `path` (present) must load like config/world.json does.
  void worldParams(const std::string& path);

  bool exists(const std::string& path) const;

  // ---------------------------------------------------------------- mission.json
  void mission();

  void priors(const IdSet& aoi_ids, const std::map<std::string, Polygon>& aois);

  void relations(const IdSet& targets);

  // ---------------------------------------------------------------- sim_config.json
  void simConfig();
  // sim_config.json's "traffic": its car ids, and the episode file it names (present, its
  // SHA-256, the window within the episode, the signal plan shifted with the offset).
  void trafficReference(IdSet& ids);
  // In a city with a signal plan: every car of the mission (any role but "traffic") enters the
  // signalised intersections only when its signal lets it (rule "signal";
  // scenario/signal_compliance.h).
  void signalCompliance(const json& ents);
  // In a city: no car of the mission overlaps an ambient car of the scenario (rule
  // "traffic_clearance", sampled every kClearanceStep; scenario/traffic_clearance.h), at the
  // withheld list of a traffic reference, else at the mission car.
  void trafficClearance(const SimConfig& sc, const std::map<std::string, std::size_t>& index);

  // Samples [t, x, y, z, yaw] of a timed path at `pointer`: t >= 0 and strictly increasing
  // (malformed samples are the schema's to report).
  void trajectoryOrder(const json& traj, const std::string& pointer);
  // Consecutive [t, x, y, z, ...] samples no faster apart than max_speed (m/s); rule
  // "trajectory_speed".
  void trajectorySpeed(const json& traj, const std::string& pointer, double max_speed);

  // The perception-only flight: strictly increasing times from t >= 0, and every target it
  // claims to see is a target entity of this scenario.
  void perceptionPath(const json& ents);

  // ---------------------------------------------------------------- world.json
  void world();

  // ---------------------------------------------------------------- manifest.json
  void manifest();

  const json& doc_;
  std::string file_;
  const std::vector<ValidationIssue>& schema_issues_;
  std::vector<ValidationIssue>* out_;
};

}  // namespace validation_internal

using namespace validation_internal;

}  // namespace hameritt::scenario
