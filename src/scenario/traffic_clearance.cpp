#include "hameritt/scenario/traffic_clearance.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "hameritt/geometry/types.h"

namespace hameritt::scenario {

namespace {

// Fine samples per block of the broad phase: two cars' fine samples are compared only where the
// boxes that bound their footprints over a block meet.
constexpr std::size_t kBlock = 20;
static_assert(kBlock * kClearanceStep == kClearanceBlock);

struct Box : ClearanceBox {
  bool meets(const Box& o) const {
    return min_x <= o.max_x && o.min_x <= max_x && min_y <= o.max_y && o.min_y <= max_y;
  }
  void add(const ClearanceBox& o) {
    min_x = std::min(min_x, o.min_x);
    min_y = std::min(min_y, o.min_y);
    max_x = std::max(max_x, o.max_x);
    max_y = std::max(max_y, o.max_y);
  }
};

// A footprint's position at scenario times that never decrease between calls:
// sampleTrajectory(*f.trajectory, t + f.time_shift) (or the standing pose), its segment searched
// once and then walked on, and the yaw (two wrapPi) only when asked for; the same operations as
// sampleTrajectory's, so the same numbers.
class Cursor {
 public:
  explicit Cursor(const MovingFootprint& f) : f_(f) {}

  bool moving() const { return f_.trajectory && f_.trajectory->size() >= 2; }

  // The position at t; yaw() then gives the yaw there.
  void at(double t, double* x, double* y) {
    pose_ = &f_.pose;
    if (moving()) {
      const Trajectory& tr = *f_.trajectory;
      const double te = t + f_.time_shift;
      const auto by_t = [](double v, const TrajectoryPoint& p) { return v < p.t; };
      if (!searched_) {
        const auto it = std::upper_bound(tr.begin(), tr.end(), te, by_t);
        i_ = it == tr.begin() ? 0 : static_cast<std::size_t>(it - tr.begin()) - 1;
        searched_ = true;
      }
      while (i_ + 1 < tr.size() && tr[i_ + 1].t <= te) ++i_;
      if (te <= tr.front().t) {
        pose_ = &tr.front();
      } else if (i_ + 1 >= tr.size()) {
        pose_ = &tr.back();
      } else {
        pose_ = nullptr;
        const TrajectoryPoint &a = tr[i_], &b = tr[i_ + 1];
        u_ = b.t > a.t ? (te - a.t) / (b.t - a.t) : 1.0;
        *x = a.x + u_ * (b.x - a.x);
        *y = a.y + u_ * (b.y - a.y);
        return;
      }
    }
    *x = pose_->x;
    *y = pose_->y;
  }

  double yaw() const {
    if (pose_) return pose_->yaw;
    const TrajectoryPoint &a = (*f_.trajectory)[i_], &b = (*f_.trajectory)[i_ + 1];
    return geometry::wrapPi(a.yaw + u_ * geometry::wrapPi(b.yaw - a.yaw));
  }

  // Extends b by the trajectory's vertices strictly inside (ta, tb) of scenario time, from the
  // cursor's place on (which at(ta) has set).
  void vertices(double ta, double tb, Box* b) const {
    if (!moving()) return;
    const Trajectory& tr = *f_.trajectory;
    for (std::size_t k = i_ + 1; k < tr.size() && tr[k].t < tb + f_.time_shift; ++k) {
      if (tr[k].t <= ta + f_.time_shift) continue;
      b->min_x = std::min(b->min_x, tr[k].x);
      b->max_x = std::max(b->max_x, tr[k].x);
      b->min_y = std::min(b->min_y, tr[k].y);
      b->max_y = std::max(b->max_y, tr[k].y);
    }
  }

 private:
  const MovingFootprint& f_;
  std::size_t i_ = 0;  // the segment [i_, i_ + 1] under the last time asked
  bool searched_ = false;
  double u_ = 0.0;
  const TrajectoryPoint* pose_ = nullptr;  // a standing or clamped pose, else interpolated
};

std::size_t fineSamples(double duration) {
  return static_cast<std::size_t>(std::floor(duration / kClearanceStep + 1e-9)) + 1;
}

double reach(const MovingFootprint& f, double margin) {
  return 0.5 * std::hypot(f.length + 2 * margin, f.width + 2 * margin);
}

// The box that holds the footprint over [ta, tb] of scenario time (at(ta) not yet called),
// grown by r: a trajectory is straight between its points, so its positions over the interval
// lie in the box of its ends and the points between them.
Box boxOver(Cursor& c, double ta, double tb, double r) {
  double ax = 0, ay = 0, ex = 0, ey = 0;
  c.at(ta, &ax, &ay);
  Box b;
  b.min_x = b.max_x = ax;
  b.min_y = b.max_y = ay;
  c.vertices(ta, tb, &b);
  c.at(tb, &ex, &ey);
  b.min_x = std::min(b.min_x, ex) - r;
  b.max_x = std::max(b.max_x, ex) + r;
  b.min_y = std::min(b.min_y, ey) - r;
  b.max_y = std::max(b.max_y, ey) + r;
  return b;
}

// The boxes that hold the footprint (grown by margin) over each block of fine samples.
std::vector<Box> blockBoxes(const MovingFootprint& f, std::size_t n, double margin) {
  const double r = reach(f, margin);
  std::vector<Box> out;
  out.reserve((n + kBlock - 1) / kBlock);
  Cursor c(f);
  for (std::size_t k0 = 0; k0 < n; k0 += kBlock) {
    const double ta = static_cast<double>(k0) * kClearanceStep;
    const double tb = static_cast<double>(std::min(k0 + kBlock, n) - 1) * kClearanceStep;
    out.push_back(boxOver(c, ta, tb, r));
  }
  return out;
}

// The same blocks from the footprint's precomputed ones: the scenario's block [ta, tb] is
// [ta, tb] + time_shift of the trajectory's time, which the union of the precomputed blocks
// from the one that holds its start to the one that holds its end contains (a slightly larger
// box, never a smaller one: the fine comparison decides).
// The precomputed blocks e0 .. e1 (of the trajectory's time) that hold the scenario's block j
// of fine samples (of n), unclamped: [ta, tb] + time_shift, nudged outwards.
void episodeBlocks(std::size_t j, std::size_t n, double time_shift, long* e0, long* e1) {
  const std::size_t k0 = j * kBlock;
  const double ta = static_cast<double>(k0) * kClearanceStep + time_shift;
  const double tb =
      static_cast<double>(std::min(k0 + kBlock, n) - 1) * kClearanceStep + time_shift;
  *e0 = static_cast<long>(std::floor(ta / kClearanceBlock - 1e-6));
  *e1 = static_cast<long>(std::floor(tb / kClearanceBlock + 1e-6));
}

// The union of pre[e0 .. e1], each index clamped to pre's range (a footprint stands at its
// last point after its last block).
Box unionOf(const std::vector<ClearanceBox>& pre, long e0, long e1) {
  const long last = static_cast<long>(pre.size()) - 1;
  e0 = std::clamp(e0, 0L, last);
  e1 = std::clamp(e1, 0L, last);
  Box b;
  static_cast<ClearanceBox&>(b) = pre[static_cast<std::size_t>(e0)];
  for (long e = e0 + 1; e <= e1; ++e) b.add(pre[static_cast<std::size_t>(e)]);
  return b;
}

std::vector<Box> cachedBlockBoxes(const MovingFootprint& f, std::size_t n) {
  std::vector<Box> out;
  out.reserve((n + kBlock - 1) / kBlock);
  for (std::size_t j = 0; j * kBlock < n; ++j) {
    long e0 = 0, e1 = 0;
    episodeBlocks(j, n, f.time_shift, &e0, &e1);
    out.push_back(unionOf(f.blocks->boxes, e0, e1));
  }
  return out;
}

// The first fine sample of block `j` at which a and b overlap (grown by margin).
std::optional<double> overlapInBlock(const MovingFootprint& a, const MovingFootprint& b,
                                     std::size_t j, std::size_t n, double margin) {
  const double rr = reach(a, margin) + reach(b, margin);
  Cursor wa(a), wb(b);
  for (std::size_t k = j * kBlock; k < std::min((j + 1) * kBlock, n); ++k) {
    const double t = static_cast<double>(k) * kClearanceStep;
    double px = 0, py = 0, qx = 0, qy = 0;
    wa.at(t, &px, &py);
    wb.at(t, &qx, &qy);
    // std::hypot(dx, dy) > rr, decided by the squares where they are clearly apart or near.
    const double dx = px - qx, dy = py - qy, d2 = dx * dx + dy * dy, r2 = rr * rr;
    if (d2 > r2 * (1 + 1e-9) || (d2 >= r2 * (1 - 1e-9) && std::hypot(dx, dy) > rr)) continue;
    if (rectanglesOverlap(px, py, wa.yaw(), 0.5 * a.length + margin, 0.5 * a.width + margin, qx,
                          qy, wb.yaw(), 0.5 * b.length + margin, 0.5 * b.width + margin)) {
      return t;
    }
  }
  return std::nullopt;
}

}  // namespace

ClearanceBlocks clearanceBlocks(const MovingFootprint& f, double margin) {
  MovingFootprint own = f;
  own.time_shift = 0.0;
  const double r = reach(own, margin);
  ClearanceBlocks out;
  out.margin = margin;
  Cursor c(own);
  // Blocks up to one that starts at or after the last point: from there on the footprint
  // stands at the last point, which that block holds.
  const double end = c.moving() ? own.trajectory->back().t : 0.0;
  const auto count = static_cast<std::size_t>(std::max(0.0, std::floor(end / kClearanceBlock))) + 2;
  out.boxes.reserve(count);
  for (std::size_t e = 0; e < count; ++e) {
    out.boxes.push_back(boxOver(c, static_cast<double>(e) * kClearanceBlock,
                                static_cast<double>(e + 1) * kClearanceBlock, r));
  }
  return out;
}

MovingFootprint footprintOf(const ScenarioEntity& se) {
  MovingFootprint f;
  f.trajectory = &se.trajectory;
  f.pose.x = se.entity.box.center.x();
  f.pose.y = se.entity.box.center.y();
  f.pose.yaw = se.entity.box.yaw;
  f.length = se.entity.box.size.x();
  f.width = se.entity.box.size.y();
  return f;
}

bool isMissionCar(const ScenarioEntity& se) {
  return se.entity.cls == EntityClass::kCar && se.role != "traffic";
}

bool rectanglesOverlap(double ax, double ay, double ayaw, double ahl, double ahw, double bx,
                       double by, double byaw, double bhl, double bhw) {
  const double dx = bx - ax, dy = by - ay;
  const double ca = std::cos(ayaw), sa = std::sin(ayaw), cb = std::cos(byaw), sb = std::sin(byaw);
  // Half the extent of a rectangle (half sizes hl, hw along yaw (c, s)) along the axis (ux, uy).
  auto extent = [](double c, double s, double hl, double hw, double ux, double uy) {
    return hl * std::abs(c * ux + s * uy) + hw * std::abs(-s * ux + c * uy);
  };
  const double axes[4][2] = {{ca, sa}, {-sa, ca}, {cb, sb}, {-sb, cb}};
  for (const auto& u : axes) {
    const double d = std::abs(dx * u[0] + dy * u[1]);
    if (d > extent(ca, sa, ahl, ahw, u[0], u[1]) + extent(cb, sb, bhl, bhw, u[0], u[1])) {
      return false;
    }
  }
  return true;
}

std::optional<double> firstOverlap(const MovingFootprint& a, const MovingFootprint& b,
                                   double duration, double margin) {
  const std::size_t n = fineSamples(duration);
  const std::vector<Box> ba = blockBoxes(a, n, margin), bb = blockBoxes(b, n, margin);
  for (std::size_t j = 0; j < ba.size(); ++j) {
    if (!ba[j].meets(bb[j])) continue;
    if (const auto t = overlapInBlock(a, b, j, n, margin)) return t;
  }
  return std::nullopt;
}

std::vector<std::size_t> trafficToWithhold(const std::vector<MovingFootprint>& mission,
                                           const std::vector<MovingFootprint>& traffic,
                                           double duration, double margin) {
  const std::size_t n = fineSamples(duration);
  std::vector<std::vector<Box>> own;
  own.reserve(mission.size());
  for (const auto& m : mission) own.push_back(blockBoxes(m, n, margin));
  std::vector<std::size_t> out;
  if (mission.empty()) return out;
  for (std::size_t i = 0; i < traffic.size(); ++i) {
    const MovingFootprint& f = traffic[i];
    const std::vector<Box> boxes =
        f.blocks && f.blocks->margin == margin && !f.blocks->boxes.empty()
            ? cachedBlockBoxes(f, n)
            : blockBoxes(f, n, margin);
    bool near = false;
    for (std::size_t m = 0; m < mission.size() && !near; ++m) {
      for (std::size_t j = 0; j < boxes.size() && !near; ++j) {
        near = boxes[j].meets(own[m][j]) &&
               overlapInBlock(mission[m], traffic[i], j, n, margin).has_value();
      }
    }
    if (near) out.push_back(i);
  }
  return out;
}

ClearanceIndex clearanceIndex(const std::vector<ClearanceBlocks>& blocks, double cell) {
  ClearanceIndex ix;
  ix.cell = cell;
  ix.source = &blocks;
  if (blocks.empty()) return ix;
  ix.margin = blocks.front().margin;
  double min_x = 0.0, min_y = 0.0, max_x = 0.0, max_y = 0.0;
  bool first = true;
  for (const auto& b : blocks) {
    if (b.boxes.empty() || b.margin != ix.margin) {
      throw std::invalid_argument("clearanceIndex: a footprint without blocks or of another margin");
    }
    ix.blocks = std::max(ix.blocks, b.boxes.size());
    for (const auto& x : b.boxes) {
      min_x = first ? x.min_x : std::min(min_x, x.min_x);
      min_y = first ? x.min_y : std::min(min_y, x.min_y);
      max_x = first ? x.max_x : std::max(max_x, x.max_x);
      max_y = first ? x.max_y : std::max(max_y, x.max_y);
      first = false;
    }
  }
  ix.x0 = min_x;
  ix.y0 = min_y;
  ix.nx = std::max(1, static_cast<int>(std::floor((max_x - min_x) / cell)) + 1);
  ix.ny = std::max(1, static_cast<int>(std::floor((max_y - min_y) / cell)) + 1);
  const std::size_t cells = static_cast<std::size_t>(ix.nx) * static_cast<std::size_t>(ix.ny);
  ix.start.assign(ix.blocks * cells + 1, 0);
  // Two passes: count each (block, cell)'s footprints, then place them (ascending, as i grows).
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::uint32_t> fill;
    if (pass == 1) {
      for (std::size_t k = 1; k < ix.start.size(); ++k) ix.start[k] += ix.start[k - 1];
      ix.cars.resize(ix.start.back());
      fill.assign(ix.start.begin(), ix.start.end() - 1);
    }
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      const auto& boxes = blocks[i].boxes;
      for (std::size_t e = 0; e < ix.blocks; ++e) {
        const ClearanceBox& b = boxes[std::min(e, boxes.size() - 1)];
        int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
        ix.cellRange(b, &x0, &y0, &x1, &y1);
        for (int y = y0; y <= y1; ++y) {
          for (int x = x0; x <= x1; ++x) {
            const std::size_t k = ix.slot(e, x, y);
            if (pass == 0) {
              ++ix.start[k + 1];
            } else {
              ix.cars[fill[k]++] = static_cast<std::uint32_t>(i);
            }
          }
        }
      }
    }
  }
  return ix;
}

void ClearanceIndex::cellRange(const ClearanceBox& b, int* x0, int* y0, int* x1, int* y1) const {
  // Clamped as a double first: a box far outside the grid maps to its edge cells.
  auto at = [&](double v, double o, int n) {
    return static_cast<int>(std::clamp(std::floor((v - o) / cell), 0.0, n - 1.0));
  };
  *x0 = at(b.min_x, this->x0, nx);
  *x1 = at(b.max_x, this->x0, nx);
  *y0 = at(b.min_y, this->y0, ny);
  *y1 = at(b.max_y, this->y0, ny);
}

std::vector<std::size_t> trafficToWithhold(const std::vector<MovingFootprint>& mission,
                                           const std::vector<MovingFootprint>& traffic,
                                           const ClearanceIndex& index, double duration,
                                           double margin) {
  bool fits = index.source && index.source->size() == traffic.size() && index.margin == margin &&
              index.blocks > 0;
  for (std::size_t i = 0; fits && i < traffic.size(); ++i) {
    fits = traffic[i].blocks == &(*index.source)[i] &&
           traffic[i].time_shift == traffic.front().time_shift;
  }
  if (!fits) return trafficToWithhold(mission, traffic, duration, margin);
  std::vector<std::size_t> out;
  if (mission.empty() || traffic.empty()) return out;
  const std::size_t n = fineSamples(duration);
  const double shift = traffic.front().time_shift;
  const long last = static_cast<long>(index.blocks) - 1;
  // near[i]: withheld; seen[i]: the query (mission car, block) that last looked at car i.
  std::vector<char> near(traffic.size(), 0);
  std::vector<std::size_t> seen(traffic.size(), 0);
  std::size_t query = 0;
  for (const auto& m : mission) {
    const std::vector<Box> own = blockBoxes(m, n, margin);
    for (std::size_t j = 0; j < own.size(); ++j) {
      ++query;
      long e0 = 0, e1 = 0;
      episodeBlocks(j, n, shift, &e0, &e1);
      int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
      index.cellRange(own[j], &x0, &y0, &x1, &y1);
      // A car whose footprint meets the mission car's at a sample of block j has a box at one of
      // the blocks e0 .. e1 that shares a point, and so a cell, with own[j]: every car the
      // comparison would withhold is a candidate here; the same tests as there then decide.
      for (long e = std::clamp(e0, 0L, last); e <= std::clamp(e1, 0L, last); ++e) {
        for (int y = y0; y <= y1; ++y) {
          for (int x = x0; x <= x1; ++x) {
            const std::size_t k = index.slot(static_cast<std::size_t>(e), x, y);
            for (std::uint32_t c = index.start[k]; c < index.start[k + 1]; ++c) {
              const std::size_t i = index.cars[c];
              if (near[i] || seen[i] == query) continue;
              seen[i] = query;
              near[i] = unionOf(traffic[i].blocks->boxes, e0, e1).meets(own[j]) &&
                        overlapInBlock(m, traffic[i], j, n, margin).has_value();
            }
          }
        }
      }
    }
  }
  for (std::size_t i = 0; i < traffic.size(); ++i) {
    if (near[i]) out.push_back(i);
  }
  return out;
}

}  // namespace hameritt::scenario
