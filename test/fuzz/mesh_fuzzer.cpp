// The renderer's mesh loader (assimp's OBJ/MTL reader and our merge by material):
// loadObjMesh() accepts or throws RenderError. The input is an OBJ text, optionally followed by
// a line "#--mtl--" and the text of its MTL file ("mtllib fuzz.mtl" finds it). The first byte's
// low bit picks a normalized class mesh (unit box check) or a free one.
#include <unistd.h>

#include <cmath>
#include <fstream>

#include "fuzz_util.h"
#include "hameritt/render/renderer.h"
#include "mesh.h"

namespace {

// A private directory for this process's files, removed at exit (a plain char array, so that
// it outlives the static objects destroyed before the atexit handler runs).
char g_dir[] = "/tmp/hameritt_mesh_fuzz_XXXXXX";

std::string workDir() {
  static const bool made = [] {
    if (mkdtemp(g_dir) == nullptr) std::abort();
    std::atexit([] {
      for (const char* f : {"/fuzz.obj", "/fuzz.mtl"}) {
        char path[sizeof(g_dir) + 16];
        std::snprintf(path, sizeof(path), "%s%s", g_dir, f);
        std::remove(path);
      }
      rmdir(g_dir);
    });
    return true;
  }();
  (void)made;
  return g_dir;
}

void writeFile(const std::string& path, const std::string& content) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << content;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace hameritt;
  if (size == 0) return 0;
  const bool normalized = data[0] & 1;
  const std::string all = fuzz::text(data + 1, size - 1);
  const std::string marker = "\n#--mtl--\n";
  const std::size_t cut = all.find(marker);
  writeFile(workDir() + "/fuzz.obj", all.substr(0, cut));
  writeFile(workDir() + "/fuzz.mtl",
            cut == std::string::npos ? std::string() : all.substr(cut + marker.size()));
  try {
    const render::Mesh m = render::loadObjMesh(workDir() + "/fuzz.obj", normalized);
    fuzz::require(!m.indices.empty() && m.indices.size() % 3 == 0, "whole triangles");
    for (const auto i : m.indices) fuzz::require(i < m.vertices.size(), "indices in range");
    for (const auto& v : m.vertices) {
      for (int a = 0; a < 3; ++a) {
        fuzz::require(std::isfinite(v.position[a]) && std::isfinite(v.normal[a]),
                      "finite vertices");
      }
    }
    fuzz::require(m.foliage_first <= m.indices.size(), "foliage_first within the indices");
  } catch (const render::RenderError&) {
  }
  return 0;
}
