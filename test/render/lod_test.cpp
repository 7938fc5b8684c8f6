// Level of detail: the coarse meshes of models/meshes/lod.json keep to their stated deviation
// (sampled distances between the loaded meshes), they are drawn only where that deviation
// projects below half a pixel, and a frame with them differs from a full-detail frame only on
// silhouettes: same boxes to the pixel, same labels away from edges, depth within the
// deviation.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "../sanitized.h"
#include "hameritt/scenario/trajectory.h"
#include "mesh.h"
#include "render_test_util.h"

namespace hameritt::render {
namespace {

using testing::cameraRequest;
using testing::defaultRenderer;
using testing::defaultSimConfig;
using testing::defaultWorld;
using testing::uavPose;

// ------------------------------------------------------------------ stated deviations

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
Eigen::Vector3d closestOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  }
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

struct Tri {
  Eigen::Vector3d a, b, c, lo, hi;
};

// Triangles of a mesh in design metres, foliage or the rest.
std::vector<Tri> designTriangles(const Mesh& m, const Eigen::Vector3d& size, bool foliage) {
  std::vector<Tri> out;
  for (const Submesh& s : m.submeshes) {
    if ((s.kind == MaterialKind::kFoliage) != foliage) continue;
    for (std::uint32_t k = s.first_index; k < s.first_index + s.index_count; k += 3) {
      Tri t;
      t.a = m.position(m.indices[k]).cast<double>().cwiseProduct(size);
      t.b = m.position(m.indices[k + 1]).cast<double>().cwiseProduct(size);
      t.c = m.position(m.indices[k + 2]).cast<double>().cwiseProduct(size);
      t.lo = t.a.cwiseMin(t.b).cwiseMin(t.c);
      t.hi = t.a.cwiseMax(t.b).cwiseMax(t.c);
      out.push_back(t);
    }
  }
  return out;
}

// Largest distance from points sampled on `from` (a barycentric grid of spacing <= h on every
// triangle, vertices and edges included) to the surface `to`: a lower estimate of the one-sided
// Hausdorff distance.
double sampledDistance(const std::vector<Tri>& from, const std::vector<Tri>& to, double h) {
  if (from.empty()) return 0.0;
  if (to.empty()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  std::size_t last = 0;  // the previous sample's nearest triangle: a good first guess
  for (const Tri& t : from) {
    const double edge = std::max({(t.b - t.a).norm(), (t.c - t.b).norm(), (t.a - t.c).norm()});
    const int n = std::max(1, static_cast<int>(std::ceil(edge / h)));
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; i + j <= n; ++j) {
        const Eigen::Vector3d p = t.a + (t.b - t.a) * (static_cast<double>(i) / n) +
                                  (t.c - t.a) * (static_cast<double>(j) / n);
        double best = (closestOnTriangle(p, to[last].a, to[last].b, to[last].c) - p).squaredNorm();
        for (std::size_t k = 0; k < to.size(); ++k) {
          const Tri& q = to[k];
          const double box = (p.cwiseMax(q.lo).cwiseMin(q.hi) - p).squaredNorm();
          if (box >= best) continue;
          const double d = (closestOnTriangle(p, q.a, q.b, q.c) - p).squaredNorm();
          if (d < best) {
            best = d;
            last = k;
          }
        }
        worst = std::max(worst, std::sqrt(best));
      }
    }
  }
  return worst;
}

nlohmann::json lodIndex() {
  std::ifstream in(defaultModelsDir() + "/meshes/lod.json");
  return nlohmann::json::parse(in);
}

TEST(RenderLod, StatedDeviationsBoundTheSampledDistancesBetweenFullAndCoarseMeshes) {
  const nlohmann::json index = lodIndex();
  ASSERT_GE(index["meshes"].size(), 10u) << "houses, garages, the deciduous tree and the cars";
  const std::string dir = defaultModelsDir() + "/meshes/";
  for (const auto& e : index["meshes"]) {
    const std::string name = e["mesh"];
    const Mesh fine = loadObjMesh(dir + name + ".obj", true);
    const Eigen::Vector3d size(e["design_size_m"][0], e["design_size_m"][1], e["design_size_m"][2]);
    std::size_t previous = fine.indices.size();
    for (const auto& level : e["levels"]) {
      const Mesh coarse = loadObjMesh(dir + level["file"].get<std::string>(), true);
      const double stated = level["max_deviation_m"];
      double measured = 0.0;
      // Under a sanitizer a coarser grid (1/25 of the samples): the same code, a lower estimate.
      const double h = kSanitized ? 0.25 : 0.05;
      for (bool foliage : {false, true}) {
        const auto a = designTriangles(fine, size, foliage);
        const auto b = designTriangles(coarse, size, foliage);
        measured = std::max({measured, sampledDistance(a, b, h), sampledDistance(b, a, h)});
      }
      const std::string file = level["file"];
      std::printf("%-22s %4zu -> %4zu triangles, deviation stated %.3f m, sampled %.3f m\n",
                  file.c_str(), fine.indices.size() / 3, coarse.indices.size() / 3, stated,
                  measured);
      EXPECT_LE(measured, stated + 1e-6) << file;
      EXPECT_LE(coarse.indices.size(), previous * 7 / 10) << file << ": 30% fewer triangles";
      EXPECT_LT(stated, 1.0) << file << ": within a metre of the full mesh";
      previous = coarse.indices.size();
    }
  }
}

// ------------------------------------------------------------------ frames

Renderer& fullDetailRenderer() {
  static Renderer r = [] {
    RendererOptions o;
    o.lod_max_error_px = 0.0;
    return Renderer(defaultWorld(), defaultSimConfig(), o);
  }();
  return r;
}

// Front-camera views along the perception path (the view to the horizon: most instances are far).
std::vector<RenderRequest> frontViews() {
  const auto& cfg = defaultSimConfig();
  std::vector<RenderRequest> views;
  for (double t : {25.0, 45.0, 65.0}) {
    const auto p = scenario::sampleTrajectory(cfg.uav.perception_path->trajectory, t);
    RenderRequest r = cameraRequest(cfg.uav.cameras[0], uavPose(p.x, p.y, p.z, p.yaw), t);
    r.noise = false;
    r.weather = false;
    views.push_back(r);
  }
  return views;
}

TEST(RenderLod, CoarseFrameDiffersFromTheFullOneOnlyOnSilhouettes) {
  Renderer& lod = defaultRenderer();
  Renderer& full = fullDetailRenderer();
  for (const RenderRequest& req : frontViews()) {
    const FrameSet a = lod.render(req);
    const RenderStats sa = lod.lastStats();
    const FrameSet b = full.render(req);
    const RenderStats sb = full.lastStats();
    EXPECT_EQ(sb.lod_instances, 0u);
    EXPECT_EQ(sa.instances, sb.instances) << "the level of detail does not change the culling";
    EXPECT_GE(sa.lod_instances, sa.instances * 4 / 10) << "far instances of a view to the horizon";
    EXPECT_LE(sa.triangles, sb.triangles * 6 / 10) << "at least 40% fewer triangles";

    const int w = req.intrinsics.width, h = req.intrinsics.height;
    auto label = [&](const FrameSet& f, int x, int y) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      return (static_cast<std::uint32_t>(f.semantic[i]) << 16) | f.instance[i];
    };
    int differ = 0, off_edge = 0, depth_far = 0, same = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * w + x;
        const std::uint32_t la = label(a, x, y);
        if (la == label(b, x, y)) {
          ++same;
          if (std::isfinite(b.depth[i]) &&
              !(std::abs(a.depth[i] - b.depth[i]) <= 0.01 * b.depth[i] + 0.5)) {
            ++depth_far;
          }
          continue;
        }
        ++differ;
        // On a silhouette of the full frame: the pixel touches another label there (an edge
        // that moved by less than a pixel), or the label drawn here is within one pixel.
        const std::uint32_t lb = label(b, x, y);
        bool edge = false;
        for (int dy = -1; dy <= 1 && !edge; ++dy) {
          for (int dx = -1; dx <= 1 && !edge; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
            const std::uint32_t n = label(b, xx, yy);
            edge = n == la || n != lb;
          }
        }
        if (!edge) {
          ++off_edge;
          if (std::getenv("HAMERITT_LOD_DEBUG")) {
            std::printf("  off-edge (%d, %d): coarse %s (semantic %u), full %s (semantic %u)\n", x,
                        y, lod.instanceEntityId(la & 0xFFFF).c_str(), la >> 16,
                        lod.instanceEntityId(label(b, x, y) & 0xFFFF).c_str(),
                        label(b, x, y) >> 16);
          }
        }
      }
    }
    std::printf(
        "t %.0f: %zu instances, %zu coarse; triangles %zu -> %zu; labels differ at %d "
        "pixels (%d not on a silhouette), depth off at %d of %d\n",
        req.time, sb.instances, sa.lod_instances, sb.triangles, sa.triangles, differ, off_edge,
        depth_far, same);
    EXPECT_LE(differ, w * h / 200) << "at most 0.5% of the pixels";
    EXPECT_LE(off_edge, differ / 100 + 2) << "label changes are on silhouettes";
    EXPECT_LE(depth_far, same / 1000) << "depth within 1% + 0.5 m where the labels agree";

    // Boxes: the same entities, to the pixel or one.
    std::map<std::string, BoundingBox> boxes_b;
    for (const auto& bx : b.boxes) boxes_b[bx.entity_id] = bx;
    int compared = 0;
    for (const auto& ba : a.boxes) {
      auto it = boxes_b.find(ba.entity_id);
      if (ba.visible_pixels < 20) continue;
      ASSERT_NE(it, boxes_b.end()) << ba.entity_id;
      const BoundingBox& bb = it->second;
      ++compared;
      EXPECT_LE(std::abs(ba.x_min - bb.x_min), 1) << ba.entity_id;
      EXPECT_LE(std::abs(ba.x_max - bb.x_max), 1) << ba.entity_id;
      EXPECT_LE(std::abs(ba.y_min - bb.y_min), 1) << ba.entity_id;
      EXPECT_LE(std::abs(ba.y_max - bb.y_max), 1) << ba.entity_id;
      // An outline that moves by at most half a pixel changes the area by at most half its
      // perimeter (bounded by the box's).
      const int half_perimeter = (bb.x_max - bb.x_min + 1) + (bb.y_max - bb.y_min + 1);
      EXPECT_LE(std::abs(ba.visible_pixels - bb.visible_pixels), half_perimeter + 2)
          << ba.entity_id;
    }
    EXPECT_GE(compared, 3);
  }
}

TEST(RenderLod, NearInstancesKeepTheirFullMesh) {
  // The down camera at 48 m: every instance is nearer than where a coarse mesh would be drawn
  // for a house (0.06 m at 0.5 px needs about 60 m of depth with this camera).
  const auto& cfg = defaultSimConfig();
  const auto p = scenario::sampleTrajectory(cfg.uav.perception_path->trajectory, 45.0);
  RenderRequest r = cameraRequest(cfg.uav.cameras[1], uavPose(p.x, p.y, 10.0, p.yaw), 45.0);
  const FrameSet a = defaultRenderer().render(r);
  EXPECT_GT(defaultRenderer().lastStats().instances, 0u);
  EXPECT_EQ(defaultRenderer().lastStats().lod_instances, 0u);
}

}  // namespace
}  // namespace hameritt::render
