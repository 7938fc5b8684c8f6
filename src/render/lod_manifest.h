#pragma once
// models/meshes/lod.json: which coarse OBJ files stand for a class mesh at which stated
// deviation. Parsed from text (no file system, no GL), so that the reader can be fuzzed alone.

#include <Eigen/Core>
#include <set>
#include <string>
#include <vector>

namespace hameritt::render {

// Coarser versions of a class mesh (models/meshes/lod.json) the renderer may draw instead.
constexpr int kMaxLodLevels = 4;

// One coarse level: an OBJ file next to lod.json and its stated deviation from the full mesh.
struct LodFileLevel {
  std::string file;              // a file name without '/'
  double max_deviation_m = 0.0;  // finite, >= 0, increasing from level to level
};

// The coarse levels of one class mesh.
struct LodManifestEntry {
  std::string mesh;                // class mesh name ("house_1"), one of `class_meshes`
  Eigen::Vector3d design_size_m;   // three finite numbers > 0
  std::vector<LodFileLevel> levels;  // 1 to kMaxLodLevels, fine to coarse
};

// Parses the text of lod.json (`path` names it in messages, `dir` is where the level files
// are). Every entry's mesh must be one of `class_meshes` and appear once. Throws RenderError
// "PATH: FIELD: expected ..." for malformed JSON or any field out of place.
std::vector<LodManifestEntry> parseLodManifest(const std::string& text, const std::string& path,
                                               const std::string& dir,
                                               const std::set<std::string>& class_meshes);

}  // namespace hameritt::render
