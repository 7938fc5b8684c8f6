#include "mesh.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <fstream>
#include <map>

#include "hameritt/render/renderer.h"

namespace hameritt::render {

namespace {

std::string fmt(float v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", static_cast<double>(v));
  return buf;
}

struct Gathered {
  std::vector<Vertex> vertices;
  std::vector<std::uint32_t> indices;
};

void gather(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent,
            std::map<unsigned, Gathered>* by_material, const std::string& path) {
  const aiMatrix4x4 m = parent * node->mTransformation;
  aiMatrix3x3 nm(m);
  nm.Inverse().Transpose();
  for (unsigned k = 0; k < node->mNumMeshes; ++k) {
    const aiMesh* mesh = scene->mMeshes[node->mMeshes[k]];
    if (!(mesh->mPrimitiveTypes & aiPrimitiveType_TRIANGLE)) continue;
    if (!mesh->HasNormals()) throw RenderError(path + ": mesh without normals");
    Gathered& g = (*by_material)[mesh->mMaterialIndex];
    const auto base = static_cast<std::uint32_t>(g.vertices.size());
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D p = m * mesh->mVertices[i];
      aiVector3D n = nm * mesh->mNormals[i];
      const float len = n.Length();
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z) ||
          !std::isfinite(len) || len <= 0.0f) {
        throw RenderError(path + ": non-finite vertex or zero normal in mesh '" +
                          std::string(mesh->mName.C_Str()) + "'");
      }
      n /= len;
      g.vertices.push_back({{p.x, p.y, p.z}, {n.x, n.y, n.z}, 0});
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines are not drawn
      for (int c = 0; c < 3; ++c) g.indices.push_back(base + face.mIndices[c]);
    }
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c) {
    gather(scene, node->mChildren[c], m, by_material, path);
  }
}

// Appends a submesh's vertices and indices, stamping the material into the vertices.
void append(Mesh* mesh, Submesh s, const std::vector<Vertex>& vertices,
            const std::vector<std::uint32_t>& indices) {
  const auto base = static_cast<std::uint32_t>(mesh->vertices.size());
  const std::uint32_t material = packMaterial(s.kd, s.kind);
  for (Vertex v : vertices) {
    v.material = material;
    mesh->vertices.push_back(v);
  }
  s.first_index = static_cast<std::uint32_t>(mesh->indices.size());
  s.index_count = static_cast<std::uint32_t>(indices.size());
  for (std::uint32_t i : indices) mesh->indices.push_back(base + i);
  mesh->submeshes.push_back(std::move(s));
}

void computeBounds(Mesh* mesh) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = -lo;
  Eigen::Vector3f flo = lo, fhi = hi;
  mesh->foliage_first = static_cast<std::uint32_t>(mesh->indices.size());
  for (const auto& s : mesh->submeshes) {
    if (s.kind == MaterialKind::kFoliage)
      mesh->foliage_first = std::min(mesh->foliage_first, s.first_index);
    for (std::uint32_t i = s.first_index; i < s.first_index + s.index_count; ++i) {
      const Eigen::Vector3f p = mesh->position(mesh->indices[i]);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
      if (s.kind == MaterialKind::kFoliage) {
        flo = flo.cwiseMin(p);
        fhi = fhi.cwiseMax(p);
      }
    }
  }
  mesh->min = lo;
  mesh->max = hi;
  mesh->canopy_center =
      flo.x() <= fhi.x() ? Eigen::Vector3f(0.5f * (flo + fhi)) : Eigen::Vector3f(0, 0, 0);
}

}  // namespace

std::uint32_t packMaterial(const Eigen::Vector3f& kd, MaterialKind kind) {
  auto q = [](float v) {
    return static_cast<std::uint32_t>(std::lround(std::sqrt(std::clamp(v, 0.0f, 1.0f)) * 255.0f));
  };
  return (q(kd.x()) << 24) | (q(kd.y()) << 16) | (q(kd.z()) << 8) |
         static_cast<std::uint32_t>(kind);
}

Mesh loadObjMesh(const std::string& path, bool normalized) {
  {
    std::ifstream probe(path);
    if (!probe) throw RenderError(path + ": model file missing or unreadable");
  }
  Assimp::Importer importer;
  // Keep the file's per-face normals (generate flat ones only where a face has none); corners
  // with the same position and normal become one vertex, shaded once per instance.
  const aiScene* scene =
      importer.ReadFile(path, aiProcess_Triangulate | aiProcess_GenNormals |
                                  aiProcess_JoinIdenticalVertices | aiProcess_SortByPType |
                                  aiProcess_ValidateDataStructure | aiProcess_FindInvalidData);
  if (scene == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode) {
    throw RenderError(path + ": malformed model: " + importer.GetErrorString());
  }
  std::map<unsigned, Gathered> by_material;
  gather(scene, scene->mRootNode, aiMatrix4x4(), &by_material, path);

  Mesh mesh;
  mesh.name = path;
  std::vector<std::pair<Submesh, const Gathered*>> parts;
  for (auto& [mi, g] : by_material) {
    if (g.indices.empty()) continue;
    const aiMaterial* mat = scene->mMaterials[mi];
    aiString name;
    mat->Get(AI_MATKEY_NAME, name);
    Submesh s;
    s.material = name.C_Str();
    if (s.material == AI_DEFAULT_MATERIAL_NAME) {
      throw RenderError(path +
                        ": faces without a material defined in the .mtl file (usemtl and "
                        "mtllib are required)");
    }
    aiColor3D kd(0.8f, 0.8f, 0.8f);
    mat->Get(AI_MATKEY_COLOR_DIFFUSE, kd);
    s.kd = Eigen::Vector3f(kd.r, kd.g, kd.b);
    if (s.material == "paint") {
      s.kind = MaterialKind::kPaint;
    } else if (s.material == "foliage") {
      s.kind = MaterialKind::kFoliage;
    }
    parts.emplace_back(std::move(s), &g);
  }
  // Foliage last (see Mesh::foliage_first).
  std::stable_sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) {
    return (a.first.kind == MaterialKind::kFoliage) < (b.first.kind == MaterialKind::kFoliage);
  });
  for (auto& [s, g] : parts) append(&mesh, s, g->vertices, g->indices);
  if (mesh.indices.empty()) throw RenderError(path + ": malformed model: no triangles");
  computeBounds(&mesh);
  if (normalized) {
    const float tol = 0.01f;
    const bool fits = mesh.min.x() >= -0.5f - tol && mesh.max.x() <= 0.5f + tol &&
                      mesh.min.y() >= -0.5f - tol && mesh.max.y() <= 0.5f + tol &&
                      mesh.min.z() >= -tol && mesh.max.z() <= 1.0f + tol;
    if (!fits) {
      throw RenderError(path +
                        ": model does not fit the unit box [-0.5, 0.5] x [-0.5, 0.5] x "
                        "[0, 1]: bounds [" +
                        fmt(mesh.min.x()) + ", " + fmt(mesh.max.x()) + "] x [" + fmt(mesh.min.y()) +
                        ", " + fmt(mesh.max.y()) + "] x [" + fmt(mesh.min.z()) + ", " +
                        fmt(mesh.max.z()) + "]");
    }
  }
  return mesh;
}

Mesh flatMesh(const std::string& name, MaterialKind kind, const Eigen::Vector3f& kd,
              const std::vector<std::array<Eigen::Vector3f, 4>>& quads) {
  std::vector<Vertex> vertices;
  std::vector<std::uint32_t> indices;
  for (const auto& q : quads) {
    const Eigen::Vector3f n = (q[1] - q[0]).cross(q[2] - q[0]).normalized();
    const auto base = static_cast<std::uint32_t>(vertices.size());
    for (const auto& p : q) vertices.push_back({{p.x(), p.y(), p.z()}, {n.x(), n.y(), n.z()}, 0});
    indices.insert(indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  Mesh m;
  m.name = name;
  Submesh s;
  s.material = name;
  s.kd = kd;
  s.kind = kind;
  append(&m, s, vertices, indices);
  computeBounds(&m);
  return m;
}

Mesh unitQuad(const std::string& name, MaterialKind kind, const Eigen::Vector3f& kd) {
  return flatMesh(name, kind, kd,
                  {{{{-0.5f, -0.5f, 0}, {0.5f, -0.5f, 0}, {0.5f, 0.5f, 0}, {-0.5f, 0.5f, 0}}}});
}

Mesh unitBox(const std::string& name, MaterialKind kind, const Eigen::Vector3f& kd) {
  const float h = 0.5f;
  return flatMesh(name, kind, kd,
                  {{{{-h, -h, 1}, {h, -h, 1}, {h, h, 1}, {-h, h, 1}}},    // top
                   {{{h, -h, 0}, {h, h, 0}, {h, h, 1}, {h, -h, 1}}},      // +x
                   {{{-h, h, 0}, {-h, -h, 0}, {-h, -h, 1}, {-h, h, 1}}},  // -x
                   {{{h, h, 0}, {-h, h, 0}, {-h, h, 1}, {h, h, 1}}},      // +y
                   {{{-h, -h, 0}, {h, -h, 0}, {h, -h, 1}, {-h, -h, 1}}}});
}

}  // namespace hameritt::render
