#include "hameritt/planning/vehicle_routes.h"

#include <ompl/base/ScopedState.h>
#include <ompl/base/spaces/DubinsStateSpace.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <queue>

#include "hameritt/geometry/oriented_box.h"
#include "hameritt/geometry/segment.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/rng.h"
#include "ompl_glue.h"

namespace hameritt::planning {

namespace ob = ompl::base;
using geometry::Vec2;
using scenario::World;

namespace {

struct Pose {
  Vec2 p;
  double yaw;
};

// The edge nearest p and whether a car heading `yaw` drives it from a to b.
int nearestEdge(const World& w, const Vec2& p, double* dist) {
  int best = -1;
  *dist = std::numeric_limits<double>::infinity();
  for (std::size_t e = 0; e < w.edges().size(); ++e) {
    const auto& ed = w.edges()[e];
    const double d =
        geometry::pointSegmentDistance(p, w.nodes()[ed.a].position, w.nodes()[ed.b].position);
    if (d < *dist) {
      *dist = d;
      best = static_cast<int>(e);
    }
  }
  return best;
}

// Directed traversal of an edge: from node u to node v.
struct Leg {
  int edge, u, v;
};

Leg directed(const World& w, int e, double yaw) {
  const auto& ed = w.edges()[static_cast<std::size_t>(e)];
  const Vec2 d = w.nodes()[ed.b].position - w.nodes()[ed.a].position;
  const bool forward = std::cos(yaw - std::atan2(d.y(), d.x())) >= 0;
  return forward ? Leg{e, ed.a, ed.b} : Leg{e, ed.b, ed.a};
}

// Lane start and end poses of a directed edge.
std::pair<Pose, Pose> lane(const World& w, const Leg& l, const RouteSettings& s) {
  const Vec2 a = w.nodes()[l.u].position, b = w.nodes()[l.v].position;
  const double len = (b - a).norm();
  const Vec2 d = (b - a) / len, n(d.y(), -d.x());
  const double c = std::min(s.corner_clearance, 0.45 * len);
  const double yaw = std::atan2(d.y(), d.x());
  return {Pose{a + d * c + n * s.lane_offset, yaw}, Pose{b - d * c + n * s.lane_offset, yaw}};
}

// Arc length along the directed edge of the projection of p.
double along(const World& w, const Leg& l, const Vec2& p) {
  const Vec2 a = w.nodes()[l.u].position, b = w.nodes()[l.v].position;
  return (p - a).dot((b - a).normalized());
}

// Dijkstra over the street graph from `from` (arriving over edge `in_edge`, no U-turn onto it)
// to `to` (not arriving over `out_edge`, the edge it leaves by), with seeded noisy costs. Returns
// the node sequence, empty when unreachable.
std::vector<int> search(const World& w, int from, int in_edge, int to, std::uint64_t seed,
                        double noise, int out_edge) {
  scenario::Rng rng(seed);
  std::vector<double> cost(w.edges().size());
  for (std::size_t e = 0; e < cost.size(); ++e) {
    const auto& ed = w.edges()[e];
    cost[e] =
        (w.nodes()[ed.b].position - w.nodes()[ed.a].position).norm() * (1 + noise * rng.unit());
  }
  // State: (node, edge it was entered by) so that U-turns can be excluded. The node is an end
  // of the edge, so a state is a directed edge (2 per edge) or a node entered by no edge.
  const std::size_t ne = w.edges().size();
  auto key = [&](int node, int edge) {
    if (edge < 0) return 2 * ne + static_cast<std::size_t>(node);
    return 2 * static_cast<std::size_t>(edge) +
           (w.edges()[static_cast<std::size_t>(edge)].b == node ? 1 : 0);
  };
  std::vector<double> dist(2 * ne + w.nodes().size(), std::numeric_limits<double>::infinity());
  std::vector<std::pair<int, int>> prev(dist.size(), {-1, -1});
  using Item = std::tuple<double, int, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> pq;
  dist[key(from, in_edge)] = 0;
  pq.emplace(0.0, from, in_edge);
  int found_edge = -2;
  while (!pq.empty()) {
    const auto [d, u, ein] = pq.top();
    pq.pop();
    if (d > dist[key(u, ein)]) continue;
    if (u == to && (ein != out_edge || ein < 0)) {
      found_edge = ein;
      break;
    }
    for (int e : w.adjacency()[static_cast<std::size_t>(u)]) {
      if (e == ein) continue;  // no U-turns
      const auto& ed = w.edges()[static_cast<std::size_t>(e)];
      const int v = ed.a == u ? ed.b : ed.a;
      const double nd = d + cost[static_cast<std::size_t>(e)];
      if (nd < dist[key(v, e)]) {
        dist[key(v, e)] = nd;
        prev[key(v, e)] = {u, ein};
        pq.emplace(nd, v, e);
      }
    }
  }
  if (found_edge == -2) return {};
  std::vector<int> nodes;
  int n = to, e = found_edge;
  while (n != -1) {
    nodes.push_back(n);
    const auto p = prev[key(n, e)];
    n = p.first;
    e = p.second;
  }
  std::reverse(nodes.begin(), nodes.end());
  return nodes;
}

int edgeBetween(const World& w, int u, int v) {
  for (int e : w.adjacency()[static_cast<std::size_t>(u)]) {
    const auto& ed = w.edges()[static_cast<std::size_t>(e)];
    if ((ed.a == u && ed.b == v) || (ed.a == v && ed.b == u)) return e;
  }
  return -1;
}

// Validated route pieces of one world, shared between the routes of a batch: the lane and
// corner pieces between street nodes recur in many routes. A piece is a pure function of its
// end poses, the turning radius and the car's size (the world being fixed), so a cached piece
// is the one that would be computed; keys compare the numbers' bits. Thread-safe; stops
// storing at kMaxPoses poses in all.
class PieceCache {
 public:
  using Key = std::array<std::uint64_t, 9>;
  static Key key(const Pose& a, const Pose& b, double radius, const RouteSettings& s) {
    const double v[9] = {a.p.x(), a.p.y(),          a.yaw,          b.p.x(), b.p.y(), b.yaw,
                         radius,  s.vehicle_length, s.vehicle_width};
    Key k;
    static_assert(sizeof(v) == sizeof(k));
    std::memcpy(k.data(), v, sizeof(v));
    return k;
  }
  // The cached piece for `k`, or nullptr.
  std::shared_ptr<const std::vector<Pose>> find(const Key& k) const {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = pieces_.find(k);
    return it == pieces_.end() ? nullptr : it->second;
  }
  void insert(const Key& k, const std::vector<Pose>& piece) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (poses_ + piece.size() + 1 > kMaxPoses) return;
    if (pieces_.emplace(k, std::make_shared<const std::vector<Pose>>(piece)).second) {
      poses_ += piece.size() + 1;
    }
  }

 private:
  static constexpr std::size_t kMaxPoses = 2'000'000;  // about 50 MB
  mutable std::mutex mutex_;
  std::map<Key, std::shared_ptr<const std::vector<Pose>>> pieces_;
  std::size_t poses_ = 0;
};

// Street edges bucketed on a square grid: a point within half a street width of an edge lies
// in a cell that the edge's widened bounding box touches, so one cell's edges answer
// onStreet() exactly as the scan over every edge does. A finer grid over the same area marks
// the cells that lie wholly on one street or wholly off every street (with a 1e-6 m margin, far
// above rounding), which answer without a distance; only cells along a kerb scan their edges.
class StreetIndex {
 public:
  explicit StreetIndex(const World& w, double cell_size = 8.0, int fine_per_cell = 8)
      : cell_(cell_size), fine_(cell_size / fine_per_cell) {
    const auto b = w.bounds();
    x0_ = b.min.x() - cell_;
    y0_ = b.min.y() - cell_;
    nx_ = static_cast<int>(std::ceil((b.max.x() - x0_) / cell_)) + 2;
    ny_ = static_cast<int>(std::ceil((b.max.y() - y0_) / cell_)) + 2;
    cells_.resize(static_cast<std::size_t>(nx_ * ny_));
    for (std::size_t e = 0; e < w.edges().size(); ++e) {
      const auto& ed = w.edges()[e];
      const Vec2 a = w.nodes()[ed.a].position, c = w.nodes()[ed.b].position;
      const double h = ed.width / 2;
      segs_.push_back({a, c, h});
      const int i0 = cellX(std::min(a.x(), c.x()) - h), i1 = cellX(std::max(a.x(), c.x()) + h);
      const int j0 = cellY(std::min(a.y(), c.y()) - h), j1 = cellY(std::max(a.y(), c.y()) + h);
      for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) cell(i, j).push_back(static_cast<int>(e));
      }
    }
    classifyFineCells(fine_per_cell);
  }
  // Same answer as planning::onStreet(w, p) (shrink 0) for the world the index was built
  // from; points off the grid fall back to that scan.
  bool onStreet(const World& w, const Vec2& p) const {
    const double fx = (p.x() - x0_) / cell_, fy = (p.y() - y0_) / cell_;
    if (!(fx >= 0 && fy >= 0 && fx < nx_ && fy < ny_)) return planning::onStreet(w, p);
    const double gx = (p.x() - x0_) / fine_, gy = (p.y() - y0_) / fine_;
    if (gx < fnx_ && gy < fny_) {
      const char state =
          fine_state_[static_cast<std::size_t>(static_cast<int>(gy) * fnx_ + static_cast<int>(gx))];
      if (state != kKerb) return state == kOn;
    }
    const std::size_t c =
        static_cast<std::size_t>(static_cast<int>(fy) * nx_ + static_cast<int>(fx));
    for (int e : cells_[c]) {
      const Seg& s = segs_[static_cast<std::size_t>(e)];
      if (geometry::pointSegmentDistance(p, s.a, s.b) <= s.half_width) return true;
    }
    return false;
  }

 private:
  int cellX(double x) const {
    return std::clamp(static_cast<int>(std::floor((x - x0_) / cell_)), 0, nx_ - 1);
  }
  int cellY(double y) const {
    return std::clamp(static_cast<int>(std::floor((y - y0_) / cell_)), 0, ny_ - 1);
  }
  std::vector<int>& cell(int i, int j) { return cells_[static_cast<std::size_t>(j * nx_ + i)]; }

  // Fine cell states: every point of a kOn cell is within half a street width of one edge, no
  // point of a kOff cell is near any edge (decided from the cell centre's distance and the
  // cell's half diagonal, a margin of 1e-6 m either way); kKerb cells need the scan.
  static constexpr char kOff = 0, kOn = 1, kKerb = 2;
  void classifyFineCells(int fine_per_cell) {
    fnx_ = nx_ * fine_per_cell;
    fny_ = ny_ * fine_per_cell;
    fine_state_.assign(static_cast<std::size_t>(fnx_) * static_cast<std::size_t>(fny_), kOff);
    constexpr double kMargin = 1e-6;
    const double half_diag = fine_ * std::sqrt(0.5);
    auto index = [&](double v, double v0, int n) {
      return std::clamp(static_cast<int>(std::floor((v - v0) / fine_)), 0, n - 1);
    };
    for (const Seg& sg : segs_) {
      const double reach = sg.half_width + fine_;
      const int i0 = index(std::min(sg.a.x(), sg.b.x()) - reach, x0_, fnx_);
      const int i1 = index(std::max(sg.a.x(), sg.b.x()) + reach, x0_, fnx_);
      const int j0 = index(std::min(sg.a.y(), sg.b.y()) - reach, y0_, fny_);
      const int j1 = index(std::max(sg.a.y(), sg.b.y()) + reach, y0_, fny_);
      for (int j = j0; j <= j1; ++j) {
        for (int i = i0; i <= i1; ++i) {
          char& st = fine_state_[static_cast<std::size_t>(j * fnx_ + i)];
          if (st == kOn) continue;
          const Vec2 c(x0_ + (i + 0.5) * fine_, y0_ + (j + 0.5) * fine_);
          const double d = geometry::pointSegmentDistance(c, sg.a, sg.b);
          if (d + half_diag <= sg.half_width - kMargin) {
            st = kOn;
          } else if (d - half_diag <= sg.half_width + kMargin) {
            st = kKerb;
          }
        }
      }
    }
  }

  struct Seg {
    Vec2 a, b;
    double half_width;
  };
  std::vector<Seg> segs_;  // street edges: centreline and half width
  double cell_, fine_, x0_ = 0, y0_ = 0;
  int nx_ = 0, ny_ = 0, fnx_ = 0, fny_ = 0;
  std::vector<std::vector<int>> cells_;
  std::vector<char> fine_state_;  // kOff, kOn or kKerb per fine cell, row-major

 public:
  // Route pieces validated on this world.
  mutable PieceCache pieces;
};

// One street index per world (by fingerprint), built once and shared read-only between calls
// and threads; the last few are kept (clearRouteCaches() drops them).
std::mutex street_index_mutex;
std::map<std::uint64_t, std::shared_ptr<const StreetIndex>> street_indexes;

std::shared_ptr<const StreetIndex> streetIndex(const World& w) {
  std::lock_guard<std::mutex> lock(street_index_mutex);
  auto& cache = street_indexes;
  if (auto it = cache.find(w.fingerprint()); it != cache.end()) return it->second;
  auto index = std::make_shared<const StreetIndex>(w);
  if (cache.size() >= 8) cache.clear();
  cache.emplace(w.fingerprint(), index);
  return index;
}

// The car's footprint at a pose is on the street and clear of parked cars. `nearby`, when
// given, holds every occluder that can touch the footprint (see validPoses).
// `fwd` is the unit heading (cos yaw, sin yaw).
// An occluder near a route piece: its footprint centre and the squared sum of its
// circumradius and the car's reach.
struct NearbyBox {
  int index;
  Vec2 center;
  double r2;
};

bool carValid(const World& w, const StreetIndex& streets, const Pose& q, const Vec2& fwd,
              const RouteSettings& s, const std::vector<NearbyBox>* nearby = nullptr) {
  const Vec2 left(-fwd.y(), fwd.x());
  for (double a : {-0.5, 0.5}) {
    for (double b : {-0.5, 0.5}) {
      const Vec2 c = q.p + fwd * (a * s.vehicle_length) + left * (b * s.vehicle_width);
      if (!streets.onStreet(w, c)) return false;
    }
  }
  if (!streets.onStreet(w, q.p)) return false;
  geometry::OrientedBox car;
  car.center = geometry::Vec3(q.p.x(), q.p.y(), 0.8);
  car.size = geometry::Vec3(s.vehicle_length, s.vehicle_width, 1.6);
  car.yaw = q.yaw;
  const auto& occ = w.occluders();
  if (!nearby) {
    const double reach = 0.5 * std::hypot(s.vehicle_length, s.vehicle_width) + 0.1;
    for (int i : occ.near(q.p, reach)) {
      if (geometry::footprintsOverlap(car, occ.box(i))) return false;
    }
    return true;
  }
  for (const NearbyBox& nb : *nearby) {
    // Footprints that overlap have centres within the sum of their circumradii.
    if ((nb.center - q.p).squaredNorm() > nb.r2) continue;
    if (geometry::footprintsOverlap(car, occ.box(nb.index))) return false;
  }
  return true;
}

bool carValid(const World& w, const StreetIndex& streets, const Pose& q, const RouteSettings& s) {
  return carValid(w, streets, q, Vec2(std::cos(q.yaw), std::sin(q.yaw)), s);
}

// The poses, or empty when one of them is invalid. The occluders near the whole piece are
// fetched once instead of once per pose.
// `straight`: the poses lie on the segment from the first to the last (up to rounding), so
// occluders farther from it than their circumradius plus the car's reach (and 1e-6 m) are
// dropped up front: no pose's centre test could pass for them.
std::vector<Pose> validPoses(const World& w, const StreetIndex& streets, std::vector<Pose> poses,
                             const RouteSettings& s, bool straight) {
  if (poses.empty()) return poses;
  geometry::Aabb2 box{poses.front().p, poses.front().p};
  for (const auto& q : poses) {
    box.min = box.min.cwiseMin(q.p);
    box.max = box.max.cwiseMax(q.p);
  }
  const double reach = 0.5 * std::hypot(s.vehicle_length, s.vehicle_width) + 0.1;
  box.min -= Vec2(reach, reach);
  box.max += Vec2(reach, reach);
  std::vector<NearbyBox> nearby;
  for (int i : w.occluders().candidates(box)) {
    const auto& o = w.occluders().box(i);
    const double r = reach + 0.5 * std::hypot(o.size.x(), o.size.y());
    if (straight &&
        geometry::pointSegmentDistance(o.center2(), poses.front().p, poses.back().p) > r + 1e-6) {
      continue;
    }
    nearby.push_back({i, o.center2(), r * r});
  }
  // Consecutive poses mostly share their heading: its sine and cosine are computed once.
  double yaw = std::numeric_limits<double>::quiet_NaN();
  Vec2 fwd(1, 0);
  for (const auto& q : poses) {
    if (!(q.yaw == yaw)) {
      yaw = q.yaw;
      fwd = Vec2(std::cos(yaw), std::sin(yaw));
    }
    if (!carValid(w, streets, q, fwd, s, &nearby)) return {};
  }
  return poses;
}

// Dense Dubins samples (every <= 0.25 m) from a to b, or empty when some sample is invalid.
std::vector<Pose> dubins(const World& w, const StreetIndex& streets, const Pose& a, const Pose& b,
                         double radius, const RouteSettings& s) {
  // Poses on one line with one heading (the usual case for lane segments, up to the 1e-3
  // rounding of the inputs) are joined by a straight segment: OMPL's Dubins code snaps angles
  // within 5e-7 rad of zero and then asserts on the result, which such long near-straight
  // connections can trip.
  const Vec2 ab = b.p - a.p;
  const double straight = ab.norm();
  const double heading = std::atan2(ab.y(), ab.x());
  if (straight > 1e-6 && std::abs(geometry::wrapPi(heading - a.yaw)) < 2e-3 &&
      std::abs(geometry::wrapPi(b.yaw - a.yaw)) < 2e-3) {
    const int n = std::max(1, static_cast<int>(std::ceil(straight / 0.25)));
    const double turn = geometry::wrapPi(b.yaw - a.yaw);
    std::vector<Pose> out;
    out.reserve(static_cast<std::size_t>(n) + 1);
    for (int k = 0; k <= n; ++k) {
      const double u = static_cast<double>(k) / n;
      out.push_back({a.p + ab * u, a.yaw + turn * u});
    }
    return validPoses(w, streets, std::move(out), s, true);
  }
  auto space = std::make_shared<ob::DubinsStateSpace>(radius);
  ob::ScopedState<ob::DubinsStateSpace> sa(space), sb(space), x(space);
  sa->setXY(a.p.x(), a.p.y());
  sa->setYaw(a.yaw);
  sb->setXY(b.p.x(), b.p.y());
  sb->setYaw(b.yaw);
  const double len = space->distance(sa.get(), sb.get());
  const int n = std::max(1, static_cast<int>(std::ceil(len / 0.25)));
  std::vector<Pose> out;
  out.reserve(static_cast<std::size_t>(n) + 1);
  // The curve is computed on the first inner sample and reused (OMPL's four-argument
  // interpolate recomputes it per call; at t = 0 and t = 1 it copies the end states, as here).
  bool first_time = true;
  ob::DubinsStateSpace::DubinsPath path;
  out.push_back(a);
  for (int k = 1; k < n; ++k) {
    space->interpolate(sa.get(), sb.get(), static_cast<double>(k) / n, first_time, path, x.get());
    out.push_back({Vec2(x->getX(), x->getY()), x->getYaw()});
  }
  out.push_back({Vec2(sb->getX(), sb->getY()), sb->getYaw()});
  return validPoses(w, streets, std::move(out), s, false);
}

// dubins() through the world's piece cache.
std::vector<Pose> cachedDubins(const World& w, const StreetIndex& streets, const Pose& a,
                               const Pose& b, double radius, const RouteSettings& s) {
  const PieceCache::Key k = PieceCache::key(a, b, radius, s);
  if (const auto hit = streets.pieces.find(k)) return *hit;
  std::vector<Pose> piece = dubins(w, streets, a, b, radius, s);
  streets.pieces.insert(k, piece);
  return piece;
}

}  // namespace

void SpeedProfile::validate() const {
  auto need = [](double v, const char* f) {
    if (!(v > 0 && std::isfinite(v))) {
      throw scenario::ConfigError(std::string("route.speed.") + f +
                                  ": expected a positive finite number, got " +
                                  scenario::formatNumber(v));
    }
  };
  need(cruise_speed, "cruise_speed");
  need(accel, "accel");
  need(decel, "decel");
  need(corner_speed, "corner_speed");
  if (corner_speed > cruise_speed) {
    throw scenario::ConfigError("route.speed.corner_speed: expected at most cruise_speed (" +
                                scenario::formatNumber(cruise_speed) + "), got " +
                                scenario::formatNumber(corner_speed));
  }
}

void RouteSettings::validate() const {
  auto need = [](bool ok, const char* f, const std::string& what, double v) {
    if (!ok)
      throw scenario::ConfigError(std::string("route.") + f + ": expected " + what + ", got " +
                                  scenario::formatNumber(v));
  };
  need(lane_offset >= 0 && lane_offset < 10, "lane_offset", "metres in [0, 10)", lane_offset);
  need(corner_clearance > 0 && corner_clearance < 50, "corner_clearance", "metres in (0, 50)",
       corner_clearance);
  need(turn_radius > 0.5 && turn_radius < 50, "turn_radius", "metres in (0.5, 50)", turn_radius);
  need(cost_noise >= 0 && cost_noise <= 10, "cost_noise", "a number in [0, 10]", cost_noise);
  need(vehicle_length > 0 && vehicle_length < 20, "vehicle_length", "metres in (0, 20)",
       vehicle_length);
  need(vehicle_width > 0 && vehicle_width < 5, "vehicle_width", "metres in (0, 5)", vehicle_width);
  need(sample_spacing >= 0.25 && sample_spacing <= 50, "sample_spacing", "metres in [0.25, 50]",
       sample_spacing);
}

void KerbStop::validate() const {
  auto need = [](bool ok, const char* f, const char* what, double v) {
    if (!ok)
      throw scenario::ConfigError(std::string("kerb_stop.") + f + ": expected " + what + ", got " +
                                  scenario::formatNumber(v));
  };
  need(sidewalk_width >= 0 && sidewalk_width <= 20, "sidewalk_width", "metres in [0, 20]",
       sidewalk_width);
  need(stop_back >= 0 && stop_back <= 20, "stop_back", "metres in [0, 20]", stop_back);
  need(kerb_street_width > 0 && kerb_street_width <= 100, "kerb_street_width", "metres in (0, 100]",
       kerb_street_width);
  need(kerb_gap >= 0 && kerb_gap <= 5, "kerb_gap", "metres in [0, 5]", kerb_gap);
  need(decel > 0 && decel <= 10, "decel", "m/s^2 in (0, 10]", decel);
  need(max_decel >= decel && max_decel <= 10, "max_decel", "m/s^2 in [decel, 10]", max_decel);
  need(min_run >= 1 && min_run <= 500, "min_run", "metres in [1, 500]", min_run);
  need(max_slope > 0 && max_slope <= 1, "max_slope", "a slope in (0, 1]", max_slope);
  need(follow_gap >= 0 && follow_gap <= 100, "follow_gap", "metres in [0, 100]", follow_gap);
}

KerbStopResult stopAtKerb(const World& w, const scenario::Trajectory& traj, const KerbStop& k,
                          const RouteSettings& s) {
  k.validate();
  s.validate();
  KerbStopResult r;
  r.trajectory = traj;
  if (traj.size() < 2) return r;
  const scenario::TrajectoryPoint& end = traj.back();
  const Vec2 pe(end.x, end.y);
  double dist = 0;
  const int e = nearestEdge(w, pe, &dist);
  if (e < 0) return r;
  const Leg leg = directed(w, e, end.yaw);
  const scenario::StreetEdge& ed = w.edges()[static_cast<std::size_t>(e)];
  const Vec2 a = w.nodes()[static_cast<std::size_t>(leg.u)].position;
  const Vec2 b = w.nodes()[static_cast<std::size_t>(leg.v)].position;
  const double len = (b - a).norm();
  if (len < 1e-6) return r;
  const Vec2 dir = (b - a) / len, right(dir.y(), -dir.x());
  const double yaw = std::atan2(dir.y(), dir.x());
  if (std::abs(geometry::wrapPi(end.yaw - yaw)) > 0.02) return r;  // not along its street
  auto alongOf = [&](const scenario::TrajectoryPoint& p) { return (Vec2(p.x, p.y) - a).dot(dir); };
  auto latOf = [&](const scenario::TrajectoryPoint& p) { return (Vec2(p.x, p.y) - a).dot(right); };
  const double lat_lane = latOf(end), s_end = alongOf(end);
  // The intersection box ahead: the widest crossing street's half width and its crosswalk.
  double box = 0.0;
  for (int ei : w.adjacency()[static_cast<std::size_t>(leg.v)]) {
    if (ei == e) continue;
    box = std::max(box, 0.5 * w.edges()[static_cast<std::size_t>(ei)].width + k.sidewalk_width);
  }
  double s_stop = s_end;
  if (box > 0.0) s_stop = std::min(s_stop, len - box - k.stop_back - 0.5 * s.vehicle_length);
  if (k.behind) {
    const Vec2 q(k.behind->x, k.behind->y);
    const double ql = (q - a).dot(dir), qa = (q - a).dot(right);
    if (ql > -k.follow_gap && ql < len && std::abs(qa) < 0.5 * ed.width &&
        std::cos(k.behind->yaw - yaw) > 0.9) {
      s_stop = std::min(s_stop, ql - k.follow_gap);
    }
  }
  const bool wide = ed.width >= k.kerb_street_width - 1e-9;
  const double lat_stop =
      wide ? std::max(lat_lane, 0.5 * ed.width - k.kerb_gap - 0.5 * s.vehicle_width) : lat_lane;
  if (s_stop >= s_end - 1e-3 && lat_stop <= lat_lane + 0.05) return r;  // already clear
  r.ok = false;
  // The final straight: the samples from the end back that keep the lane and its heading.
  std::size_t k0 = traj.size() - 1;
  while (k0 > 0) {
    const scenario::TrajectoryPoint& p = traj[k0 - 1];
    if (std::abs(latOf(p) - lat_lane) > 0.05 || std::abs(geometry::wrapPi(p.yaw - yaw)) > 0.02 ||
        alongOf(p) > alongOf(traj[k0]) + 1e-6) {
      break;
    }
    --k0;
  }
  const double s_straight = alongOf(traj[k0]);
  // Time and mean speed at arc s of the straight (the sample pair around it).
  auto sampleAt = [&](double sa, double* t, double* v) {
    std::size_t i = k0;
    while (i + 2 < traj.size() && alongOf(traj[i + 1]) <= sa) ++i;
    const double s0 = alongOf(traj[i]), s1 = alongOf(traj[i + 1]);
    const double t0 = traj[i].t, t1 = traj[i + 1].t;
    const double u = s1 > s0 + 1e-9 ? std::clamp((sa - s0) / (s1 - s0), 0.0, 1.0) : 0.0;
    *t = t0 + u * (t1 - t0);
    *v = t1 > t0 + 1e-9 ? (s1 - s0) / (t1 - t0) : 0.0;
  };
  const double dlat = lat_stop - lat_lane;
  const double min_run = std::max(k.min_run, std::abs(dlat) * geometry::kPi / (2 * k.max_slope));
  double s_start = std::max(s_straight, s_stop - min_run), t0 = 0.0, v0 = 0.0;
  for (int it = 0; it < 4; ++it) {
    sampleAt(s_start, &t0, &v0);
    s_start = std::max(s_straight, s_stop - std::max(min_run, v0 * v0 / (2 * k.decel)));
  }
  sampleAt(s_start, &t0, &v0);
  const double run = s_stop - s_start;
  if (run < 1.0 || v0 < 0.5) return r;
  if (std::abs(dlat) * geometry::kPi / (2 * run) > k.max_slope + 1e-9) return r;
  // The blend: along the street s_start -> s_stop, sideways lat_lane -> lat_stop (cosine).
  const int n = std::max(2, static_cast<int>(std::ceil(run / 1.0)));
  std::vector<Pose> poses;
  std::vector<double> arc{0.0};
  for (int j = 0; j <= n; ++j) {
    const double u = static_cast<double>(j) / n;
    const double lat = lat_lane + dlat * 0.5 * (1.0 - std::cos(geometry::kPi * u));
    const double slope = dlat * 0.5 * geometry::kPi * std::sin(geometry::kPi * u) / run;
    const Vec2 p = a + dir * (s_start + run * u) + right * lat;
    const Vec2 h = dir + right * slope;
    poses.push_back(Pose{p, std::atan2(h.y(), h.x())});
    if (j > 0) arc.push_back(arc.back() + (p - poses[poses.size() - 2].p).norm());
  }
  const double decel = v0 * v0 / (2 * arc.back());
  if (decel > k.max_decel) return r;
  const std::shared_ptr<const StreetIndex> index = streetIndex(w);
  for (const Pose& q : poses) {
    if (!carValid(w, *index, q, s)) return r;
  }
  using scenario::roundMilli;
  scenario::Trajectory out;
  for (std::size_t i = 0; i < traj.size(); ++i) {
    if (i >= k0 && alongOf(traj[i]) >= s_start - 1e-3) break;
    out.push_back(traj[i]);
  }
  for (int j = 0; j <= n; ++j) {
    const double c = arc[static_cast<std::size_t>(j)];
    const double t = j == n ? t0 + v0 / decel
                            : t0 + (v0 - std::sqrt(std::max(0.0, v0 * v0 - 2 * decel * c))) / decel;
    const Pose& q = poses[static_cast<std::size_t>(j)];
    scenario::TrajectoryPoint p{roundMilli(t), roundMilli(q.p.x()), roundMilli(q.p.y()), 0.0,
                                roundMilli(q.yaw)};
    if (!out.empty() && !(p.t > out.back().t)) p.t = roundMilli(out.back().t + 1e-3);
    out.push_back(p);
  }
  r.ok = true;
  r.changed = true;
  r.at_kerb = dlat > 0.05;
  r.trajectory = std::move(out);
  return r;
}

void clearRouteCaches() {
  std::lock_guard<std::mutex> lock(street_index_mutex);
  street_indexes.clear();
}

bool onStreet(const World& w, const Vec2& p, double shrink) {
  for (const auto& ed : w.edges()) {
    if (geometry::pointSegmentDistance(p, w.nodes()[ed.a].position, w.nodes()[ed.b].position) <=
        ed.width / 2 - shrink) {
      return true;
    }
  }
  return false;
}

RouteResult planVehicleRoute(const World& w, const scenario::TrajectoryPoint& start,
                             const RouteGoal& goal, std::uint64_t seed, const SpeedProfile& speed,
                             const RouteSettings& s) {
  speed.validate();
  s.validate();
  detail::silenceOmplOnce();
  RouteResult r;
  const std::shared_ptr<const StreetIndex> index = streetIndex(w);
  const StreetIndex& streets = *index;
  const Pose sp{Vec2(start.x, start.y), start.yaw};
  double d = 0;
  const int e0 = nearestEdge(w, sp.p, &d);
  if (e0 < 0 || !carValid(w, streets, sp, s)) {
    r.status = PlanStatus::kInvalidStart;
    r.message = "start (" + scenario::formatNumber(start.x) + ", " +
                scenario::formatNumber(start.y) + ") is not a clear pose on a street";
    return r;
  }
  const Leg first = directed(w, e0, sp.yaw);
  int goal_node = goal.node;
  std::optional<Pose> gp;
  Leg last{-1, -1, -1};
  if (goal.pose) {
    gp = Pose{Vec2(goal.pose->x, goal.pose->y), goal.pose->yaw};
    double gd = 0;
    const int ge = nearestEdge(w, gp->p, &gd);
    if (ge < 0 || !carValid(w, streets, *gp, s)) {
      r.status = PlanStatus::kInvalidGoal;
      r.message = "goal pose (" + scenario::formatNumber(gp->p.x()) + ", " +
                  scenario::formatNumber(gp->p.y()) + ") is not a clear pose on a street";
      return r;
    }
    last = directed(w, ge, gp->yaw);
    goal_node = last.u;
  } else if (goal_node < 0 || goal_node >= static_cast<int>(w.nodes().size())) {
    r.status = PlanStatus::kInvalidGoal;
    r.message = "goal node " + std::to_string(goal.node) + " does not exist (" +
                std::to_string(w.nodes().size()) + " nodes)";
    return r;
  }
  // Node sequence.
  std::vector<int> nodes;
  const bool same_leg = gp && last.edge == first.edge && last.u == first.u &&
                        along(w, first, gp->p) > along(w, first, sp.p) + 1.0;
  if (same_leg) {
    nodes = {};
  } else {
    nodes = search(w, first.v, first.edge, goal_node, seed, s.cost_noise, gp ? last.edge : -1);
    if (nodes.empty()) {
      r.status = PlanStatus::kNoSolution;
      r.message = "goal node " + std::to_string(goal_node) + " is unreachable without a U-turn";
      return r;
    }
    if (gp) {
      // The last node must lead onto the goal's edge in its direction; and not by a U-turn.
      const int prev_edge =
          nodes.size() >= 2 ? edgeBetween(w, nodes[nodes.size() - 2], nodes.back()) : first.edge;
      if (prev_edge == last.edge) {
        r.status = PlanStatus::kNoSolution;
        r.message = "goal pose needs a U-turn";
        return r;
      }
    }
  }
  // Lane waypoints.
  std::vector<Pose> wps{sp};
  if (same_leg) {
    wps.push_back(*gp);
  } else {
    const auto l0 = lane(w, first, s);
    if (along(w, first, l0.second.p) > along(w, first, sp.p) + 0.5) wps.push_back(l0.second);
    for (std::size_t i = 0; i + 1 < nodes.size(); ++i) {
      const Leg l{edgeBetween(w, nodes[i], nodes[i + 1]), nodes[i], nodes[i + 1]};
      const auto ln = lane(w, l, s);
      wps.push_back(ln.first);
      wps.push_back(ln.second);
    }
    if (gp) {
      const auto ln = lane(w, last, s);
      if (along(w, last, gp->p) > along(w, last, ln.first.p) + 0.5) wps.push_back(ln.first);
      wps.push_back(*gp);
    }
  }
  r.nodes = nodes;
  // Dubins connections, validated densely.
  std::vector<Pose> dense{wps.front()};
  for (std::size_t i = 1; i < wps.size(); ++i) {
    std::vector<Pose> piece;
    for (double radius : {s.turn_radius, 0.7 * s.turn_radius, 0.5 * s.turn_radius}) {
      piece = cachedDubins(w, streets, wps[i - 1], wps[i], radius, s);
      if (!piece.empty()) break;
    }
    if (piece.empty()) {
      r.status = PlanStatus::kNoSolution;
      r.message = "no valid Dubins curve from (" + scenario::formatNumber(wps[i - 1].p.x()) + ", " +
                  scenario::formatNumber(wps[i - 1].p.y()) + ") to (" +
                  scenario::formatNumber(wps[i].p.x()) + ", " +
                  scenario::formatNumber(wps[i].p.y()) + ") on the street surface";
      return r;
    }
    dense.insert(dense.end(), piece.begin() + 1, piece.end());
  }
  // Speed profile over the dense samples: corner speed where the heading turns faster than
  // 1 rad per 25 m, cruise elsewhere; acceleration forward, braking backward; rest at both ends.
  const std::size_t n = dense.size();
  std::vector<double> ds(n, 0.0), cap(n, speed.cruise_speed), v(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) ds[i] = (dense[i].p - dense[i - 1].p).norm();
  for (std::size_t i = 1; i < n; ++i) {
    const double turn = std::abs(geometry::wrapPi(dense[i].yaw - dense[i - 1].yaw));
    if (ds[i] > 1e-9 && turn / ds[i] > 1.0 / 25.0) cap[i] = cap[i - 1] = speed.corner_speed;
  }
  for (std::size_t i = 1; i + 1 < n; ++i) v[i] = cap[i];
  for (std::size_t i = 1; i < n; ++i)
    v[i] = geometry::minSqrt(v[i], v[i - 1] * v[i - 1] + 2 * speed.accel * ds[i]);
  for (std::size_t i = n - 1; i-- > 0;)
    v[i] = geometry::minSqrt(v[i], v[i + 1] * v[i + 1] + 2 * speed.decel * ds[i + 1]);
  using scenario::roundMilli;
  double t = start.t, since = 0.0;
  r.trajectory.push_back({roundMilli(t), roundMilli(dense[0].p.x()), roundMilli(dense[0].p.y()),
                          0.0, roundMilli(dense[0].yaw)});
  for (std::size_t i = 1; i < n; ++i) {
    const double vv = v[i - 1] + v[i];
    t += vv > 1e-9 ? 2 * ds[i] / vv : 0.0;
    r.length += ds[i];
    since += ds[i];
    const bool curve = cap[i] < speed.cruise_speed;
    if (i + 1 == n || since >= (curve ? 0.5 : s.sample_spacing) - 1e-9) {
      scenario::TrajectoryPoint p{roundMilli(t), roundMilli(dense[i].p.x()),
                                  roundMilli(dense[i].p.y()), 0.0, roundMilli(dense[i].yaw)};
      if (!(p.t > r.trajectory.back().t)) p.t = roundMilli(r.trajectory.back().t + 1e-3);
      r.trajectory.push_back(p);
      since = 0.0;
    }
  }
  r.status = PlanStatus::kExact;
  r.message = "exact solution";
  return r;
}

}  // namespace hameritt::planning
