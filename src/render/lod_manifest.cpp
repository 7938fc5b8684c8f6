#include "lod_manifest.h"

#include <cmath>
#include <nlohmann/json.hpp>

#include "hameritt/render/renderer.h"
#include "hameritt/scenario/bounded_json.h"
#include "hameritt/scenario/error.h"

namespace hameritt::render {

std::vector<LodManifestEntry> parseLodManifest(const std::string& text, const std::string& path,
                                               const std::string& dir,
                                               const std::set<std::string>& class_meshes) {
  nlohmann::json doc;
  try {
    scenario::checkJsonText(text, path);
  } catch (const scenario::ConfigError& e) {
    throw RenderError(e.what());
  }
  try {
    doc = nlohmann::json::parse(text);
  } catch (const std::exception& e) {
    throw RenderError(path + ": not valid JSON: " + e.what());
  }
  auto fail = [&path](const std::string& field, const std::string& expected) {
    throw RenderError(path + ": " + field + ": expected " + expected);
  };
  // A finite number (integer or floating point) at key of object o.
  auto number = [](const nlohmann::json& o, const char* key, double* out) {
    const auto it = o.find(key);
    if (it == o.end() || !it->is_number()) return false;
    *out = it->get<double>();
    return std::isfinite(*out);
  };
  if (!doc.is_object() || !doc.contains("schema") || doc["schema"] != "hameritt_mesh_lod") {
    fail("schema", "\"hameritt_mesh_lod\"");
  }
  if (!doc.contains("schema_version") || doc["schema_version"] != 2) fail("schema_version", "2");
  if (!doc.contains("meshes") || !doc["meshes"].is_array()) fail("meshes", "an array");
  const auto& meshes = doc["meshes"];
  std::vector<LodManifestEntry> entries;
  std::set<std::string> seen;
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const auto& e = meshes[i];
    const std::string at = "meshes[" + std::to_string(i) + "]";
    if (!e.is_object()) fail(at, "an object");
    if (!e.contains("mesh") || !e["mesh"].is_string()) fail(at + ".mesh", "a class mesh name");
    LodManifestEntry entry;
    entry.mesh = e["mesh"].get<std::string>();
    if (class_meshes.count(entry.mesh) == 0) {
      fail(at + ".mesh", "a class mesh name (house_1, car_sedan, ...), got '" + entry.mesh + "'");
    }
    if (!seen.insert(entry.mesh).second) fail(at + ".mesh", "each mesh once");
    const auto& size = e.contains("design_size_m") ? e["design_size_m"] : nlohmann::json();
    bool size_ok = size.is_array() && size.size() == 3;
    for (std::size_t a = 0; size_ok && a < 3; ++a) {
      size_ok = size[a].is_number() && std::isfinite(size[a].get<double>()) &&
                size[a].get<double>() > 0;
      if (size_ok) entry.design_size_m[static_cast<Eigen::Index>(a)] = size[a].get<double>();
    }
    if (!size_ok) fail(at + ".design_size_m", "three numbers > 0 (metres)");
    if (!e.contains("levels") || !e["levels"].is_array() || e["levels"].empty() ||
        e["levels"].size() > static_cast<std::size_t>(kMaxLodLevels)) {
      fail(at + ".levels", "an array of 1 to " + std::to_string(kMaxLodLevels) + " levels");
    }
    double previous = -1.0;
    for (std::size_t l = 0; l < e["levels"].size(); ++l) {
      const auto& level = e["levels"][l];
      const std::string lat = at + ".levels[" + std::to_string(l) + "]";
      if (!level.is_object()) fail(lat, "an object");
      if (!level.contains("file") || !level["file"].is_string() ||
          level["file"].get<std::string>().empty() ||
          level["file"].get<std::string>().find('/') != std::string::npos) {
        fail(lat + ".file", "an OBJ file name in " + dir);
      }
      LodFileLevel lf;
      lf.file = level["file"].get<std::string>();
      if (!number(level, "max_deviation_m", &lf.max_deviation_m) || lf.max_deviation_m < 0) {
        fail(lat + ".max_deviation_m", "a finite number >= 0 (metres)");
      }
      if (lf.max_deviation_m <= previous) {
        fail(lat + ".max_deviation_m",
             "more than the previous level's (levels go from fine to coarse)");
      }
      previous = lf.max_deviation_m;
      entry.levels.push_back(lf);
    }
    entries.push_back(std::move(entry));
  }
  return entries;
}

}  // namespace hameritt::render
