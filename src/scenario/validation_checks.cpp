// The semantic checker's dispatch and shared checks: issues, polygons, time windows, altitudes,
// ids.
#include "validation_internal.h"

namespace hameritt::scenario::validation_internal {

Semantics::Semantics(const json& doc, std::string file,
                     const std::vector<ValidationIssue>& schema_issues,
                     std::vector<ValidationIssue>* out)
    : doc_(doc), file_(std::move(file)), schema_issues_(schema_issues), out_(out) {}

void Semantics::run(DocumentKind kind) {
  switch (kind) {
    case DocumentKind::kMission:
      mission();
      break;
    case DocumentKind::kSimConfig:
      simConfig();
      break;
    case DocumentKind::kWorld:
      world();
      break;
    case DocumentKind::kManifest:
      manifest();
      break;
  }
}

void Semantics::add(const std::string& path, const std::string& rule, const std::string& message) {
  out_->push_back({file_, path, rule, message});
}

bool Semantics::schemaFlagged(const std::string& path) const {
  for (const auto& i : schema_issues_) {
    if (i.path == path || i.path.compare(0, path.size() + 1, path + "/") == 0) return true;
  }
  return false;
}

std::optional<Polygon> Semantics::polygon(const json& j, const std::string& path) {
  std::vector<Vec2> pts;
  if (!toPoints(j, &pts) || pts.size() < 3) return std::nullopt;
  if (pts.size() > 3 && pts.front() == pts.back()) {
    add(path, "polygon_simple",
        "the first vertex is repeated as the last; rings close implicitly, "
        "so this ring has a zero-length edge");
    return std::nullopt;
  }
  Polygon p(pts);
  if (!p.isSimple()) {
    add(path, "polygon_simple",
        "polygon of " + std::to_string(pts.size()) +
            " vertices is not simple (edges cross or touch, a vertex "
            "repeats, or the area is zero)");
    return std::nullopt;
  }
  return p;
}

void Semantics::timeWindow(const json& owner, const std::string& owner_path) {
  const json* tw = member(owner, "time_window");
  if (!tw) return;
  const auto net = numberAt(*tw, "net"), nlt = numberAt(*tw, "nlt");
  if (net && nlt && *net > *nlt) {
    add(jsonPointerAppend(owner_path, "time_window"), "time_window",
        "net " + num(*net) + " is later than nlt " + num(*nlt));
  }
}

void Semantics::altitude(const json& alt, const std::string& path) {
  const auto lo = numberAt(alt, "min"), hi = numberAt(alt, "max");
  if (lo && hi && *lo > *hi) {
    add(path, "altitude", "min " + num(*lo) + " is above max " + num(*hi));
  }
}

void Semantics::scenarioId(const json& entry, const std::string& path) {
  const auto id = stringAt(entry, "id") ? stringAt(entry, "id") : stringAt(entry, "scenario_id");
  const auto cls = stringAt(entry, "class");
  const json* seed = member(entry, "seed");
  if (!id || !cls || !seed || !isNonNegativeInteger(*seed)) return;
  const auto seed_value = integerAs<std::uint64_t>(*seed);
  if (!seed_value) {
    add(path, "scenario_id", "expected a seed below 2^64, got " + seed->dump());
    return;
  }
  const std::string want = *cls + "-" + hex64(*seed_value);
  if (*id != want) {
    add(path, "scenario_id",
        "expected '" + want + "' for class " + *cls + " and seed " + seed->dump() + ", got '" +
            *id + "'");
  }
}

void Semantics::worldParams(const std::string& path) {
  if (schemaFlagged(path)) return;  // the schema already said what is wrong
  const json& params = doc_.at(json::json_pointer(path));
  try {
    worldParamsFromJson(params, file_);
  } catch (const ConfigError& e) {
    std::string msg = e.what();
    const std::string prefix = file_ + ": ";
    while (msg.compare(0, prefix.size(), prefix) == 0) msg = msg.substr(prefix.size());
    add(path, "world_params", msg);
  }
}

bool Semantics::exists(const std::string& path) const {
  try {
    return doc_.contains(json::json_pointer(path));
  } catch (const json::exception&) {
    return false;
  }
}

}  // namespace hameritt::scenario::validation_internal
