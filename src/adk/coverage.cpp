#include "hameritt/adk/coverage.h"

#include <algorithm>
#include <cmath>

#include "hameritt/adk/intervals.h"
#include "hameritt/scenario/error.h"

namespace hameritt::adk {

using geometry::Polygon;
using geometry::Vec2;
using geometry::Vec3;

namespace {

// Keeps the part of a convex polygon where n . (x, y) + c >= 0 (Sutherland-Hodgman).
std::vector<Vec2> clipHalfPlane(const std::vector<Vec2>& poly, const Vec2& n, double c) {
  std::vector<Vec2> out;
  if (poly.empty()) return out;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const Vec2& p = poly[i];
    const Vec2& q = poly[(i + 1) % poly.size()];
    const double fp = n.dot(p) + c, fq = n.dot(q) + c;
    if (fp >= 0.0) out.push_back(p);
    if ((fp >= 0.0) != (fq >= 0.0)) out.push_back(p + (q - p) * (fp / (fp - fq)));
  }
  return out;
}

}  // namespace

void CameraIntrinsics::validate() const {
  if (width < 1 || height < 1) {
    throw InputError("camera intrinsics: expected width and height >= 1, got " +
                     std::to_string(width) + " x " + std::to_string(height));
  }
  if (!(fx > 0.0 && fy > 0.0 && std::isfinite(fx) && std::isfinite(fy) && std::isfinite(cx) &&
        std::isfinite(cy))) {
    throw InputError("camera intrinsics: expected finite fx, fy > 0 and finite cx, cy, got fx " +
                     scenario::formatNumber(fx) + ", fy " + scenario::formatNumber(fy));
  }
}

CameraIntrinsics intrinsicsFromHfov(int width, int height, double hfov_deg) {
  if (width < 1 || height < 1) {
    throw InputError("camera: expected width and height >= 1, got " + std::to_string(width) +
                     " x " + std::to_string(height));
  }
  if (!(hfov_deg > 0.0 && hfov_deg < 180.0)) {
    throw InputError("camera: hfov_deg: expected degrees in (0, 180), got " +
                     scenario::formatNumber(hfov_deg));
  }
  CameraIntrinsics k;
  k.width = width;
  k.height = height;
  k.fx = k.fy = 0.5 * width / std::tan(0.5 * geometry::degToRad(hfov_deg));
  k.cx = 0.5 * (width - 1);
  k.cy = 0.5 * (height - 1);
  return k;
}

Eigen::Isometry3d opticalPose(const Eigen::Isometry3d& world_T_base,
                              const scenario::CameraSpec& camera) {
  const Vec3 rpy = camera.mount_rpy * (geometry::kPi / 180.0);
  Eigen::Isometry3d base_T_link = Eigen::Isometry3d::Identity();
  base_T_link.translation() = camera.mount_xyz;
  base_T_link.linear() =
      (Eigen::AngleAxisd(rpy.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vec3::UnitY()) *
       Eigen::AngleAxisd(rpy.x(), Vec3::UnitX()))
          .toRotationMatrix();
  // REP 103: the optical frame's x is the link's -y, its y the link's -z, its z the link's x.
  Eigen::Matrix3d link_R_optical;
  link_R_optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d link_T_optical = Eigen::Isometry3d::Identity();
  link_T_optical.linear() = link_R_optical;
  return world_T_base * base_T_link * link_T_optical;
}

Polygon groundFootprint(const CameraIntrinsics& k, const Eigen::Isometry3d& world_T_optical,
                        double max_range) {
  k.validate();
  if (!(max_range > 0.0) || !std::isfinite(max_range)) {
    throw InputError("footprint: max_range: expected metres > 0, got " +
                     scenario::formatNumber(max_range));
  }
  const Vec3 c = world_T_optical.translation();
  if (!c.allFinite() || !(c.z() > 0.0)) return Polygon();
  const Eigen::Matrix3d R = world_T_optical.linear();
  // Rays through the outer edges of the corner pixels, in the world frame, clockwise in the
  // image (top-left, top-right, bottom-right, bottom-left).
  const double u0 = -0.5, u1 = k.width - 0.5, v0 = -0.5, v1 = k.height - 0.5;
  const Vec3 corners[4] = {
      R * Vec3((u0 - k.cx) / k.fx, (v0 - k.cy) / k.fy, 1.0),
      R * Vec3((u1 - k.cx) / k.fx, (v0 - k.cy) / k.fy, 1.0),
      R * Vec3((u1 - k.cx) / k.fx, (v1 - k.cy) / k.fy, 1.0),
      R * Vec3((u0 - k.cx) / k.fx, (v1 - k.cy) / k.fy, 1.0),
  };
  const Vec3 axis = R.col(2);
  // Start from the range disk around the camera's ground point, then keep the inside of each
  // frustum plane on the ground: a plane through c with normal n holds the ground points g with
  // n . (g - c) >= 0, i.e. n.xy . g.xy + (-n . c) >= 0 at g.z = 0.
  constexpr int kDiskSides = 64;
  std::vector<Vec2> poly;
  poly.reserve(kDiskSides);
  for (int i = 0; i < kDiskSides; ++i) {
    const double a = 2.0 * geometry::kPi * i / kDiskSides;
    poly.push_back(c.head<2>() + max_range * Vec2(std::cos(a), std::sin(a)));
  }
  for (int i = 0; i < 4 && !poly.empty(); ++i) {
    Vec3 n = corners[i].cross(corners[(i + 1) % 4]);
    if (n.dot(axis) < 0.0) n = -n;  // the optical axis is inside
    poly = clipHalfPlane(poly, n.head<2>(), -n.dot(c));
  }
  // In front of the camera (depth > 0).
  if (!poly.empty()) poly = clipHalfPlane(poly, axis.head<2>(), -axis.dot(c));
  if (poly.size() < 3) return Polygon();
  Polygon out(std::move(poly));
  if (!(out.area() > 1e-9)) return Polygon();
  return out.counterClockwise();
}

CoverageGrid::CoverageGrid(const scenario::Mission& mission, double cell_size) : cell_(cell_size) {
  if (!(cell_size > 0.0) || !std::isfinite(cell_size)) {
    throw InputError("coverage: cell_size: expected metres > 0, got " +
                     scenario::formatNumber(cell_size));
  }
  for (const auto& aoi : mission.aois) {
    AreaGrid g;
    g.id = aoi.id;
    g.window = aoi.window;
    const geometry::Aabb2 b = aoi.polygon.bounds();
    g.nx = std::max(1, static_cast<int>(std::ceil((b.max.x() - b.min.x()) / cell_)));
    g.ny = std::max(1, static_cast<int>(std::ceil((b.max.y() - b.min.y()) / cell_)));
    g.origin = b.min + Vec2(0.5 * cell_, 0.5 * cell_);
    const std::size_t n = static_cast<std::size_t>(g.nx) * static_cast<std::size_t>(g.ny);
    g.member.assign(n, 0);
    g.prior.assign(n, -1);
    g.covered.assign(n, 0);
    const scenario::AreaPrior* prior = nullptr;
    for (const auto& p : mission.priors) {
      if (p.aoi_id == aoi.id) prior = &p;
    }
    if (prior) {
      g.has_prior = true;
      for (const auto& c : prior->cells) g.prior_probability.push_back(c.probability);
      g.prior_cells.assign(prior->cells.size(), 0);
    }
    for (int iy = 0; iy < g.ny; ++iy) {
      for (int ix = 0; ix < g.nx; ++ix) {
        const Vec2 centre = g.origin + Vec2(ix * cell_, iy * cell_);
        if (!aoi.polygon.contains(centre)) continue;
        const std::size_t i = static_cast<std::size_t>(iy) * g.nx + ix;
        g.member[i] = 1;
        ++g.cells;
        if (!prior) continue;
        for (std::size_t pc = 0; pc < prior->cells.size(); ++pc) {
          if (prior->cells[pc].polygon.contains(centre)) {
            g.prior[i] = static_cast<std::int32_t>(pc);
            ++g.prior_cells[pc];
            break;
          }
        }
      }
    }
    areas_.push_back(std::move(g));
  }
}

int CoverageGrid::addFootprint(const Polygon& footprint, double t) {
  if (footprint.size() < 3) return 0;
  const geometry::Aabb2 fb = footprint.bounds();
  int added = 0;
  for (auto& g : areas_) {
    if (!g.window.active(t)) continue;
    const int x0 = std::max(0, static_cast<int>(std::ceil((fb.min.x() - g.origin.x()) / cell_)));
    const int x1 =
        std::min(g.nx - 1, static_cast<int>(std::floor((fb.max.x() - g.origin.x()) / cell_)));
    const int y0 = std::max(0, static_cast<int>(std::ceil((fb.min.y() - g.origin.y()) / cell_)));
    const int y1 =
        std::min(g.ny - 1, static_cast<int>(std::floor((fb.max.y() - g.origin.y()) / cell_)));
    for (int iy = y0; iy <= y1; ++iy) {
      for (int ix = x0; ix <= x1; ++ix) {
        const std::size_t i = static_cast<std::size_t>(iy) * g.nx + ix;
        if (!g.member[i] || g.covered[i]) continue;
        if (footprint.contains(g.origin + Vec2(ix * cell_, iy * cell_))) {
          g.covered[i] = 1;
          ++added;
        }
      }
    }
  }
  return added;
}

std::vector<AoiCoverage> CoverageGrid::coverage() const {
  std::vector<AoiCoverage> out;
  for (const auto& g : areas_) {
    AoiCoverage c;
    c.aoi_id = g.id;
    c.cells = g.cells;
    c.has_prior = g.has_prior;
    std::vector<int> covered_per_prior(g.prior_cells.size(), 0);
    for (std::size_t i = 0; i < g.covered.size(); ++i) {
      if (!g.covered[i]) continue;
      ++c.covered;
      if (g.prior[i] >= 0) ++covered_per_prior[static_cast<std::size_t>(g.prior[i])];
    }
    c.fraction = g.cells > 0 ? static_cast<double>(c.covered) / g.cells : 0.0;
    for (std::size_t pc = 0; pc < g.prior_cells.size(); ++pc) {
      if (g.prior_cells[pc] > 0) {
        c.prior_weighted += g.prior_probability[pc] * covered_per_prior[pc] /
                            static_cast<double>(g.prior_cells[pc]);
      }
    }
    out.push_back(c);
  }
  return out;
}

double CoverageGrid::priorWeightedCoverage() const {
  double sum = 0.0;
  int n = 0;
  for (const auto& c : coverage()) {
    if (!c.has_prior) continue;
    sum += c.prior_weighted;
    ++n;
  }
  return n > 0 ? sum / n : 0.0;
}

}  // namespace hameritt::adk
