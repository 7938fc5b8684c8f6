#pragma once
// Triangle meshes of the renderer: class models loaded from Wavefront OBJ/MTL with assimp, and
// the procedural pieces (unit quad and box) that streets and driveways are drawn with.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace hameritt::render {

// How a material gets its albedo (and its procedural pattern) in the geometry pass.
enum class MaterialKind : int {
  kPlain = 0,     // the MTL's Kd
  kPaint = 1,     // the instance colour (entity colour attribute, driveway material)
  kFoliage = 2,   // Kd tinted by the instance colour (tree species); scaled about the canopy centre
  kLawn = 3,      // ground: green with a low-frequency world-space variation
  kStreet = 4,    // asphalt with a dashed centre line (street-local coordinates)
  kSidewalk = 5,  // light concrete
  kFacade = 6,    // the instance colour with window bands and storefronts (city buildings)
  kSignal = 7,    // Kd, with red, yellow and green lamps at the top (traffic-light masts)
};

// One material's triangles: indices [first_index, first_index + index_count).
struct Submesh {
  std::string material;
  Eigen::Vector3f kd{0.8f, 0.8f, 0.8f};  // linear RGB
  MaterialKind kind = MaterialKind::kPlain;
  std::uint32_t first_index = 0;
  std::uint32_t index_count = 0;
};

// A vertex as the GPU reads it: position, normal, and the material (albedo Kd in the top 24
// bits as square-root-encoded RGB8, the MaterialKind in the low 8 bits), so that a whole mesh
// is one draw call whatever its number of materials.
struct Vertex {
  float position[3];
  float normal[3];
  std::uint32_t material;
};
static_assert(sizeof(Vertex) == 28, "tightly packed");

// Packs Kd and kind into Vertex::material.
std::uint32_t packMaterial(const Eigen::Vector3f& kd, MaterialKind kind);

struct Mesh {
  std::string name;  // file name or procedural name
  std::vector<Vertex> vertices;
  std::vector<std::uint32_t> indices;
  // By material; foliage submeshes come last, so the indices before foliage_first are the mesh
  // without its canopy.
  std::vector<Submesh> submeshes;
  std::uint32_t foliage_first = 0;  // first index of the foliage (== indices.size() if none)
  Eigen::Vector3f min{0, 0, 0}, max{0, 0, 0};
  // Centre of the foliage triangles' bounds (the canopy is scaled about it).
  Eigen::Vector3f canopy_center{0, 0, 0};

  std::size_t vertexCount() const { return vertices.size(); }
  Eigen::Vector3f position(std::size_t i) const {
    return {vertices[i].position[0], vertices[i].position[1], vertices[i].position[2]};
  }
};

// Loads an OBJ (with its MTL) and merges its meshes by material. Material "paint" becomes
// kPaint, "foliage" kFoliage, every other material keeps its Kd. A normalized class mesh must fit
// the unit box [-0.5, 0.5] x [-0.5, 0.5] x [0, 1] (within 1 %). Throws RenderError naming the
// file when it is missing, malformed, empty or out of its box.
Mesh loadObjMesh(const std::string& path, bool normalized);

// A one-material mesh of planar quads (corners counter-clockwise seen from the front).
Mesh flatMesh(const std::string& name, MaterialKind kind, const Eigen::Vector3f& kd,
              const std::vector<std::array<Eigen::Vector3f, 4>>& quads);
// The unit quad [-0.5, 0.5]^2 at z = 0 facing up (streets), one submesh of `kind`.
Mesh unitQuad(const std::string& name, MaterialKind kind, const Eigen::Vector3f& kd);
// The unit box [-0.5, 0.5]^2 x [0, 1] without its bottom face (driveway slabs).
Mesh unitBox(const std::string& name, MaterialKind kind, const Eigen::Vector3f& kd);

}  // namespace hameritt::render
