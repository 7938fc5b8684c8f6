#include "hameritt/geometry/line_of_sight.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace hameritt::geometry {

namespace {

using Entry = std::pair<std::int64_t, int>;

// Cell indices are clamped to +-2^30 so that they pack into 32 bits each; the clamp is
// monotone, so area lookups stay conservative far out.
constexpr int kMaxCell = 1 << 30;
// Boxes covering more cells than this are filed once under kGlobalKey and tested by every
// query (packed keys are always > -2^62, so the sentinel sorts first).
constexpr std::int64_t kMaxCellsPerBox = 4096;
constexpr std::int64_t kGlobalKey = std::numeric_limits<std::int64_t>::min();

std::int64_t packKey(int ix, int iy) {
  // (ix, iy) ordered lexicographically: a run of iy within one column is a contiguous key range.
  return static_cast<std::int64_t>(ix) * (std::int64_t{1} << 32) +
         (static_cast<std::int64_t>(iy) + (std::int64_t{1} << 31));
}

int cellIndex(double v, double cell, bool* clamped = nullptr) {
  const double q = std::floor(v / cell);
  if (q <= -kMaxCell || q >= kMaxCell) {
    if (clamped != nullptr) *clamped = true;
    return q < 0.0 ? -kMaxCell : kMaxCell;
  }
  return static_cast<int>(q);
}

// Same as boxTolerance() in oriented_box.cpp: the slack OrientedBox uses for touching tests.
double boxTolerance(const OrientedBox& b) {
  return kEpsilon * std::max({1.0, b.center.cwiseAbs().maxCoeff(), b.size.cwiseAbs().maxCoeff()});
}

// Calls f(box) for each box filed under cells (ix, iy0..iy1), in order, until f returns true;
// returns whether it did.
template <class F>
bool anyInColumn(const std::vector<Entry>& cells, int ix, int iy0, int iy1, F f) {
  auto it = std::lower_bound(cells.begin(), cells.end(),
                             Entry{packKey(ix, iy0), std::numeric_limits<int>::min()});
  const std::int64_t last = packKey(ix, iy1);
  for (; it != cells.end() && it->first <= last; ++it) {
    if (f(it->second)) return true;
  }
  return false;
}

// The same for the boxes filed under kGlobalKey.
template <class F>
bool anyGlobal(const std::vector<Entry>& cells, F f) {
  for (auto it = cells.begin(); it != cells.end() && it->first == kGlobalKey; ++it) {
    if (f(it->second)) return true;
  }
  return false;
}

// Appends the boxes filed under cells (ix, iy0..iy1).
void collectColumn(const std::vector<Entry>& cells, int ix, int iy0, int iy1,
                   std::vector<int>* out) {
  anyInColumn(cells, ix, iy0, iy1, [&](int i) {
    out->push_back(i);
    return false;
  });
}

void collectGlobal(const std::vector<Entry>& cells, std::vector<int>* out) {
  anyGlobal(cells, [&](int i) {
    out->push_back(i);
    return false;
  });
}

void collectAll(std::size_t count, std::vector<int>* out) {
  out->resize(count);
  for (std::size_t i = 0; i < count; ++i) (*out)[i] = static_cast<int>(i);
}

// Visiting more cells than this costs more than testing every box.
std::int64_t scanLimit(std::size_t boxes) { return 64 + 4 * static_cast<std::int64_t>(boxes); }

void sortUnique(std::vector<int>* v) {
  std::sort(v->begin(), v->end());
  v->erase(std::unique(v->begin(), v->end()), v->end());
}

// Per-thread marks of the boxes a segment query has met: a box filed under several cells is
// visited once. A box's mark is the number of the last query that met it.
struct Marks {
  std::vector<std::uint32_t> mark;
  std::uint32_t query = 0;
};
thread_local Marks t_marks;

// Calls visit(i) once for each candidate box of the 2D segment [a, b] until one call returns
// true, and returns whether one did. Walks the grid column by column and, in each, looks up only
// the cells spanned by the part of the segment inside that column (padded by a rounding margin;
// boxes are padded by their own tolerance when filed), visiting each box as it is found, so a
// blocked segment stops at its first blocker. Every box, for a segment crossing too many cells or
// reaching past the clamped grid.
template <class Visit>
bool anySegmentCandidate(const std::vector<Entry>& cells, double cell, std::size_t boxes,
                         const Vec2& a, const Vec2& b, Visit visit) {
  const double m = kEpsilon * std::max({1.0, a.cwiseAbs().maxCoeff(), b.cwiseAbs().maxCoeff()});
  const Vec2 lo = a.cwiseMin(b) - Vec2::Constant(m);
  const Vec2 hi = a.cwiseMax(b) + Vec2::Constant(m);
  bool clamped = false;
  const int ix0 = cellIndex(lo.x(), cell, &clamped);
  const int ix1 = cellIndex(hi.x(), cell, &clamped);
  const int iy0 = cellIndex(lo.y(), cell, &clamped);
  const int iy1 = cellIndex(hi.y(), cell, &clamped);
  const std::int64_t visits =
      (static_cast<std::int64_t>(ix1) - ix0 + 1) + (static_cast<std::int64_t>(iy1) - iy0 + 1);
  if (clamped || visits > scanLimit(boxes)) {
    for (std::size_t i = 0; i < boxes; ++i) {
      if (visit(static_cast<int>(i))) return true;
    }
    return false;
  }
  Marks& marks = t_marks;
  if (marks.mark.size() < boxes) marks.mark.resize(boxes, 0);
  if (++marks.query == 0) {  // wrapped: forget every mark
    std::fill(marks.mark.begin(), marks.mark.end(), 0);
    marks.query = 1;
  }
  auto once = [&](int i) {
    std::uint32_t& mk = marks.mark[static_cast<std::size_t>(i)];
    if (mk == marks.query) return false;
    mk = marks.query;
    return visit(i);
  };
  if (anyGlobal(cells, once)) return true;
  const Vec2 d = b - a;
  for (int ix = ix0; ix <= ix1; ++ix) {
    double ylo = lo.y();
    double yhi = hi.y();
    if (d.x() != 0.0) {
      const double cx0 = std::max(lo.x(), ix * cell - m);
      const double cx1 = std::min(hi.x(), (ix + 1) * cell + m);
      const double ta = std::clamp((cx0 - a.x()) / d.x(), 0.0, 1.0);
      const double tb = std::clamp((cx1 - a.x()) / d.x(), 0.0, 1.0);
      const double ya = a.y() + ta * d.y();
      const double yb = a.y() + tb * d.y();
      ylo = std::max(ylo, std::min(ya, yb) - m);
      yhi = std::min(yhi, std::max(ya, yb) + m);
    }
    const int jy0 = std::max(iy0, cellIndex(ylo, cell));
    const int jy1 = std::min(iy1, cellIndex(yhi, cell));
    if (jy0 <= jy1 && anyInColumn(cells, ix, jy0, jy1, once)) return true;
  }
  return false;
}

// Candidate boxes filed under any cell that the (non-NaN) rectangle overlaps, ascending;
// every box when that is more cells than boxes are worth. The result is written into *out_vec
// (emptied first), which callers keep per thread: its storage is reused.
const std::vector<int>& areaCandidates(const std::vector<Entry>& cells, double cell,
                                       std::size_t boxes, const Aabb2& area,
                                       std::vector<int>* out_vec) {
  std::vector<int>& out = *out_vec;
  out.clear();
  if (!(area.min.x() <= area.max.x() && area.min.y() <= area.max.y())) return out;
  const int x0 = cellIndex(area.min.x(), cell);
  const int y0 = cellIndex(area.min.y(), cell);
  const int x1 = cellIndex(area.max.x(), cell);
  const int y1 = cellIndex(area.max.y(), cell);
  const std::int64_t count =
      (static_cast<std::int64_t>(x1) - x0 + 1) * (static_cast<std::int64_t>(y1) - y0 + 1);
  if (count > scanLimit(boxes)) {
    collectAll(boxes, &out);
    return out;
  }
  collectGlobal(cells, &out);
  for (int ix = x0; ix <= x1; ++ix) collectColumn(cells, ix, y0, y1, &out);
  sortUnique(&out);
  return out;
}

// Per-thread candidate lists for the queries below (none of them re-enters another).
thread_local std::vector<int> t_candidates;

bool ignored(const std::vector<int>& ignore, int i) {
  return std::find(ignore.begin(), ignore.end(), i) != ignore.end();
}

}  // namespace

OccluderIndex::OccluderIndex(double cell) : cell_(cell) {
  if (!std::isfinite(cell) || cell <= 0.0) {
    throw GeometryError("OccluderIndex: cell size must be positive and finite");
  }
}

int OccluderIndex::add(const OrientedBox& box) {
  if (!box.size.allFinite() || (box.size.array() <= 0.0).any()) {
    throw GeometryError("OccluderIndex::add: box size must be positive and finite");
  }
  if (!box.center.allFinite() || !std::isfinite(box.yaw)) {
    throw GeometryError("OccluderIndex::add: box pose must be finite");
  }
  boxes_.push_back(box);
  bounds_.push_back(box.bounds2());
  dirty_ = true;
  return static_cast<int>(boxes_.size() - 1);
}

std::int64_t OccluderIndex::key(int ix, int iy) const { return packKey(ix, iy); }

void OccluderIndex::cellRange(const Aabb2& b, int* x0, int* y0, int* x1, int* y1) const {
  *x0 = cellIndex(b.min.x(), cell_);
  *y0 = cellIndex(b.min.y(), cell_);
  *x1 = cellIndex(b.max.x(), cell_);
  *y1 = cellIndex(b.max.y(), cell_);
}

// Files each box under every cell its bounds (padded by twice its touching tolerance, which
// covers the tolerance rotated into the world frame) overlap.
void OccluderIndex::build() {
  cells_.clear();
  trig_.clear();
  for (const OrientedBox& b : boxes_) trig_.emplace_back(std::cos(b.yaw), std::sin(b.yaw));
  for (std::size_t i = 0; i < boxes_.size(); ++i) {
    const double pad = 2.0 * boxTolerance(boxes_[i]);
    const Aabb2 b{bounds_[i].min - Vec2::Constant(pad), bounds_[i].max + Vec2::Constant(pad)};
    int x0, y0, x1, y1;
    cellRange(b, &x0, &y0, &x1, &y1);
    const std::int64_t count =
        (static_cast<std::int64_t>(x1) - x0 + 1) * (static_cast<std::int64_t>(y1) - y0 + 1);
    const int index = static_cast<int>(i);
    if (count > kMaxCellsPerBox) {
      cells_.emplace_back(kGlobalKey, index);
      continue;
    }
    for (int ix = x0; ix <= x1; ++ix) {
      for (int iy = y0; iy <= y1; ++iy) cells_.emplace_back(key(ix, iy), index);
    }
  }
  std::sort(cells_.begin(), cells_.end());
  dirty_ = false;
}

void OccluderIndex::requireBuilt() const {
  if (dirty_) throw std::logic_error("OccluderIndex: query after add() without build()");
}

bool OccluderIndex::clear(const Vec3& a, const Vec3& b, const std::vector<int>& ignore) const {
  requireBuilt();
  if (!a.allFinite() || !b.allFinite()) throw GeometryError("OccluderIndex::clear: non-finite");
  return !anySegmentCandidate(cells_, cell_, boxes_.size(), a.head<2>(), b.head<2>(), [&](int i) {
    const auto& [c, s] = trig_[static_cast<std::size_t>(i)];
    return !ignored(ignore, i) && boxes_[i].intersectsSegment(a, b, c, s);
  });
}

// The 2D segment meets a footprint exactly when, lifted to the box's mid-height, it meets the
// box, so the 3D slab test (and its tolerance) serves both variants.
bool OccluderIndex::clear2(const Vec2& a, const Vec2& b, const std::vector<int>& ignore) const {
  requireBuilt();
  if (!a.allFinite() || !b.allFinite()) throw GeometryError("OccluderIndex::clear2: non-finite");
  return !anySegmentCandidate(cells_, cell_, boxes_.size(), a, b, [&](int i) {
    if (ignored(ignore, i)) return false;
    const double z = boxes_[i].center.z();
    const auto& [c, s] = trig_[static_cast<std::size_t>(i)];
    return boxes_[i].intersectsSegment(Vec3(a.x(), a.y(), z), Vec3(b.x(), b.y(), z), c, s);
  });
}

// Exact footprint distances over the boxes filed near the query square, which is padded by
// the point's rounding tolerance so that a footprint touching p within tolerance is not missed.
std::vector<int> OccluderIndex::near(const Vec2& p, double radius) const {
  requireBuilt();
  if (!p.allFinite() || std::isnan(radius)) throw GeometryError("OccluderIndex::near: non-finite");
  std::vector<int> out;
  if (radius < 0.0) return out;
  const double pad = radius + 2.0 * kEpsilon * std::max(1.0, p.cwiseAbs().maxCoeff());
  const Aabb2 area{p - Vec2::Constant(pad), p + Vec2::Constant(pad)};
  for (int i : areaCandidates(cells_, cell_, boxes_.size(), area, &t_candidates)) {
    // Exact point-to-rectangle distance in the box frame.
    const OrientedBox& b = boxes_[i];
    const Vec2 d = p - b.center2();
    const auto& [c, s] = trig_[static_cast<std::size_t>(i)];  // std::cos, std::sin of b.yaw
    const double lx = std::max(std::abs(c * d.x() + s * d.y()) - 0.5 * b.size.x(), 0.0);
    const double ly = std::max(std::abs(-s * d.x() + c * d.y()) - 0.5 * b.size.y(), 0.0);
    const double scale = std::max({1.0, p.cwiseAbs().maxCoeff(), b.size.x(), b.size.y(),
                                   b.center2().cwiseAbs().maxCoeff()});
    if (std::sqrt(lx * lx + ly * ly) <= radius + kEpsilon * scale) {
      out.push_back(i);
    }
  }
  return out;
}

std::vector<int> OccluderIndex::candidates(const Aabb2& area) const {
  requireBuilt();
  if (area.min.hasNaN() || area.max.hasNaN()) {
    throw GeometryError("OccluderIndex::candidates: NaN area");
  }
  std::vector<int> out;
  for (int i : areaCandidates(cells_, cell_, boxes_.size(), area, &t_candidates)) {
    if (bounds_[i].overlaps(area)) out.push_back(i);
  }
  return out;
}

}  // namespace hameritt::geometry
