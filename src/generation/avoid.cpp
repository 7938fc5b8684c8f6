#include "hameritt/generation/avoid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>
#include <utility>

#include "hameritt/scenario/error.h"

namespace hameritt::scenario {

using geometry::Vec2;
using geometry::Vec3;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

Vec2 xy(const Vec3& p) { return {p.x(), p.y()}; }

// The band's obstacles and keep-out zones as a grid graph for Lazy Theta*.
class BandGrid {
 public:
  BandGrid(const planning::WorldValidity& band, double cell) : band_(band), cell_(cell) {
    const auto& b = band.bounds();
    const auto& s = band.settings();
    origin_ = Vec3(b.min.x(), b.min.y(), s.altitude_min);
    nx_ = static_cast<int>(std::floor((b.max.x() - b.min.x()) / cell)) + 1;
    ny_ = static_cast<int>(std::floor((b.max.y() - b.min.y()) / cell)) + 1;
    nz_ = static_cast<int>(std::floor((s.altitude_max - s.altitude_min) / cell)) + 1;
    valid_.assign(static_cast<std::size_t>(nx_) * ny_ * nz_, -1);
  }

  std::size_t size() const { return valid_.size(); }
  Vec3 position(std::size_t n) const {
    const int i = static_cast<int>(n % static_cast<std::size_t>(nx_));
    const int j =
        static_cast<int>((n / static_cast<std::size_t>(nx_)) % static_cast<std::size_t>(ny_));
    const int k = static_cast<int>(n / (static_cast<std::size_t>(nx_) * ny_));
    return origin_ + Vec3(i * cell_, j * cell_, k * cell_);
  }
  bool nodeValid(std::size_t n) {
    signed char& v = valid_[n];
    if (v < 0) {
      const Vec3 p = position(n);
      v = band_.staticValid(p) && band_.kozClear(p, 0.0, kInf) ? 1 : 0;
    }
    return v == 1;
  }
  bool lineOfSight(const Vec3& a, const Vec3& b) const {
    return band_.staticSegmentValid(a, b) && band_.kozSegmentClearDuring(a, b, 0.0, kInf);
  }
  // The grid nodes of the cell that holds p (up to 8), valid ones only.
  std::vector<std::size_t> cellCorners(const Vec3& p) {
    std::vector<std::size_t> out;
    const Vec3 q = (p - origin_) / cell_;
    const int i0 = static_cast<int>(std::floor(q.x())), j0 = static_cast<int>(std::floor(q.y()));
    const int k0 = static_cast<int>(std::floor(q.z()));
    for (int dk = 0; dk <= 1; ++dk)
      for (int dj = 0; dj <= 1; ++dj)
        for (int di = 0; di <= 1; ++di) {
          const int i = i0 + di, j = j0 + dj, k = k0 + dk;
          if (i < 0 || j < 0 || k < 0 || i >= nx_ || j >= ny_ || k >= nz_) continue;
          const std::size_t n = index(i, j, k);
          if (nodeValid(n)) out.push_back(n);
        }
    return out;
  }
  // The valid grid neighbours of n (26-connected).
  void neighbours(std::size_t n, std::vector<std::size_t>* out) {
    out->clear();
    const int i = static_cast<int>(n % static_cast<std::size_t>(nx_));
    const int j =
        static_cast<int>((n / static_cast<std::size_t>(nx_)) % static_cast<std::size_t>(ny_));
    const int k = static_cast<int>(n / (static_cast<std::size_t>(nx_) * ny_));
    for (int dk = -1; dk <= 1; ++dk)
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          if (!di && !dj && !dk) continue;
          const int a = i + di, b = j + dj, c = k + dk;
          if (a < 0 || b < 0 || c < 0 || a >= nx_ || b >= ny_ || c >= nz_) continue;
          const std::size_t m = index(a, b, c);
          if (nodeValid(m)) out->push_back(m);
        }
  }

 private:
  std::size_t index(int i, int j, int k) const {
    return (static_cast<std::size_t>(k) * ny_ + j) * nx_ + i;
  }
  const planning::WorldValidity& band_;
  double cell_;
  Vec3 origin_;
  int nx_ = 0, ny_ = 0, nz_ = 0;
  std::vector<signed char> valid_;
};

// Lazy Theta* from a to b (both in the band). Nodes: the grid's, then a, then b.
std::vector<Vec3> thetaStar(BandGrid& grid, const Vec3& a, const Vec3& b) {
  if (grid.lineOfSight(a, b)) return {a, b};
  const std::size_t na = grid.size(), nb = grid.size() + 1;
  auto pos = [&](std::size_t n) { return n == na ? a : n == nb ? b : grid.position(n); };
  std::vector<double> g(grid.size() + 2, kInf);
  std::vector<std::size_t> parent(grid.size() + 2, na);
  std::vector<char> closed(grid.size() + 2, 0);
  const std::vector<std::size_t> near_a = grid.cellCorners(a), near_b = grid.cellCorners(b);
  using Entry = std::pair<double, std::size_t>;  // f, node: ties by node index (deterministic)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> open;
  auto push = [&](std::size_t n) { open.push({g[n] + (pos(n) - b).norm(), n}); };
  g[na] = 0.0;
  push(na);
  std::vector<std::size_t> nbrs;
  auto neighboursOf = [&](std::size_t n) {
    if (n == na) {
      nbrs = near_a;
    } else {
      grid.neighbours(n, &nbrs);
      if (std::find(near_b.begin(), near_b.end(), n) != near_b.end()) nbrs.push_back(nb);
    }
  };
  while (!open.empty()) {
    const auto [f, s] = open.top();
    open.pop();
    if (closed[s]) continue;
    if (f > g[s] + (pos(s) - b).norm() + 1e-9) continue;  // stale entry
    // Lazy Theta*: the parent's sight of s was assumed when s was queued; check it now and
    // fall back to the best closed neighbour with a clear edge.
    if (s != na && !grid.lineOfSight(pos(parent[s]), pos(s))) {
      g[s] = kInf;
      neighboursOf(s);
      if (s == nb) nbrs = near_b;
      for (std::size_t m : nbrs) {
        if (!closed[m]) continue;
        const double c = g[m] + (pos(m) - pos(s)).norm();
        if (c < g[s] && grid.lineOfSight(pos(m), pos(s))) {
          g[s] = c;
          parent[s] = m;
        }
      }
      if (!(g[s] < kInf)) continue;  // unreachable this way; it may be queued again
    }
    closed[s] = 1;
    if (s == nb) break;
    neighboursOf(s);
    for (std::size_t m : nbrs) {
      if (closed[m]) continue;
      // Path 2: from s's parent straight to m (its sight is checked when m is expanded).
      const std::size_t p = s == na ? na : parent[s];
      const double c = g[p] + (pos(p) - pos(m)).norm();
      if (c < g[m]) {
        g[m] = c;
        parent[m] = p;
        push(m);
      }
    }
  }
  if (!closed[nb]) return {};
  std::vector<Vec3> path{b};
  for (std::size_t n = nb; n != na; n = parent[n]) path.push_back(pos(parent[n]));
  std::reverse(path.begin(), path.end());
  // Shortcut: from each corner, the farthest later corner in sight.
  std::vector<Vec3> out{path.front()};
  for (std::size_t i = 0; i + 1 < path.size();) {
    std::size_t j = path.size() - 1;
    while (j > i + 1 && !grid.lineOfSight(path[i], path[j])) --j;
    out.push_back(path[j]);
    i = j;
  }
  return out;
}

double polylineLength3(const std::vector<Vec3>& p) {
  double l = 0.0;
  for (std::size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
  return l;
}

}  // namespace

ReferenceFlight shortestFlight(const planning::WorldValidity& band, const Vec3& start,
                               const Vec3& goal, double cell) {
  ReferenceFlight r;
  const double floor_z = band.settings().altitude_min;
  // Take-off and descent columns: obstacles only (below the band).
  planning::ValiditySettings column_settings = band.settings();
  column_settings.altitude_min = 0.0;
  const planning::WorldValidity column(band.world(), band.kozs(), column_settings);
  const Vec3 up(start.x(), start.y(), std::max(floor_z, start.z()));
  const bool landing = goal.z() < floor_z;
  const Vec3 down = landing ? Vec3(goal.x(), goal.y(), floor_z) : goal;
  if (!column.staticSegmentValid(start, up)) {
    r.why = "the take-off column above the start is blocked";
    return r;
  }
  if (landing && !column.staticSegmentValid(down, goal)) {
    r.why = "the descent column above the goal is blocked";
    return r;
  }
  if (!band.staticValid(up) || !band.kozClear(up, 0.0, kInf)) {
    r.why = "the start's column meets an obstacle or a keep-out zone at the band's floor";
    return r;
  }
  if (!band.staticValid(down) || !band.kozClear(down, 0.0, kInf)) {
    r.why = "the goal (or its column at the band's floor) is inside an obstacle or a keep-out zone";
    return r;
  }
  BandGrid grid(band, cell);
  const std::vector<Vec3> mid = thetaStar(grid, up, down);
  if (mid.empty()) {
    r.why = "no flight through the band reaches the goal";
    return r;
  }
  if ((up - start).norm() > 0) r.path.push_back(start);
  r.path.insert(r.path.end(), mid.begin(), mid.end());
  if (landing) r.path.push_back(goal);
  r.length = polylineLength3(r.path);
  r.ok = true;
  return r;
}

Trajectory aircraftTrajectory(const AircraftPattern& pat, double duration) {
  Trajectory out;
  auto add = [&](double t, const Vec3& p, double yaw) {
    const TrajectoryPoint q{roundMilli(t), roundMilli(p.x()), roundMilli(p.y()), roundMilli(p.z()),
                            roundMilli(geometry::wrapPi(yaw))};
    if (out.empty() || q.t > out.back().t) out.push_back(q);
  };
  if (pat.kind == AircraftPattern::Kind::kOrbit) {
    // 24 samples a lap: the chord falls short of the circle by radius * (1 - cos 7.5 deg).
    const double omega = pat.speed / pat.radius;
    const double dt = 2.0 * geometry::kPi / 24.0 / omega;
    for (int i = 0;; ++i) {
      const double t = std::min(i * dt, duration);
      const double a = pat.phase + omega * t;
      const Vec3 p = pat.centre + Vec3(pat.radius * std::cos(a), pat.radius * std::sin(a),
                                       pat.climb * std::sin(a - pat.phase));
      add(t, p, a + 0.5 * geometry::kPi);
      if (t >= duration) break;
    }
    return out;
  }
  const double len = (pat.b - pat.a).norm();
  const Vec3 dir = (pat.b - pat.a) / len;
  const double yaw_ab = std::atan2(dir.y(), dir.x());
  // Unfolded arc length u(t) = s_cross + speed (t - t_cross); the aircraft is at the triangle
  // wave of u over [0, len].
  const double s_cross = (pat.cross - pat.a).dot(dir);
  auto at = [&](double t, bool* toward_b) {
    const double u = s_cross + pat.speed * (t - pat.t_cross);
    const double m = std::fmod(u, 2.0 * len);
    const double w = m < 0 ? m + 2.0 * len : m;
    *toward_b = w < len;
    const double s = *toward_b ? w : 2.0 * len - w;
    return pat.a + (pat.b - pat.a) * (s / len);
  };
  constexpr double kTurn = 0.5;  // s, the yaw swings round before a reversal
  const double u0 = s_cross - pat.speed * pat.t_cross;
  bool fwd = true;
  add(0.0, at(0.0, &fwd), fwd ? yaw_ab : yaw_ab + geometry::kPi);
  // Reversals where u crosses a multiple of len.
  for (double k = std::floor(u0 / len) + 1;; k += 1.0) {
    const double t = pat.t_cross + (k * len - s_cross) / pat.speed;
    if (t >= duration) break;
    if (t - kTurn > 0) {
      const Vec3 p = at(t - kTurn, &fwd);
      add(t - kTurn, p, fwd ? yaw_ab : yaw_ab + geometry::kPi);
    }
    const bool toward_b_after = static_cast<long long>(std::llround(k)) % 2 == 0;
    add(t, std::fmod(std::abs(k), 2.0) < 0.5 ? pat.a : pat.b,
        toward_b_after ? yaw_ab : yaw_ab + geometry::kPi);
  }
  add(duration, at(duration, &fwd), fwd ? yaw_ab : yaw_ab + geometry::kPi);
  return out;
}

std::vector<std::string> checkAvoidScenario(const World& world, const Mission& mission,
                                            const SimConfig& sim) {
  std::vector<std::string> out;
  const AvoidPhaseSpec* spec = nullptr;
  for (const auto& p : mission.phases) {
    if (p.type == PhaseType::kAvoid) spec = &p.avoid;
  }
  if (!spec) {
    out.push_back("mission.json: phases: no avoid phase");
    return out;
  }
  const UavSpec& uav = sim.uav;
  const Vec3 start(uav.start.x, uav.start.y, uav.start.z);
  std::vector<KeepOutZone> statics;
  for (const auto& k : mission.kozs) {
    if (k.motion.empty()) statics.push_back(k);
  }
  const planning::ValiditySettings vs = planning::validitySettingsFor(uav);
  const planning::WorldValidity band(world, statics, vs);
  planning::ValiditySettings column_settings = vs;
  column_settings.altitude_min = 0.0;
  const planning::WorldValidity all(world, mission.kozs, column_settings);
  if (!all.staticValid(start)) {
    out.push_back("sim_config.json: uav.start: inside an obstacle or out of bounds (" +
                  all.explain(start, 0.0) + ")");
  }
  for (const auto& k : mission.kozs) {
    if (k.window.active(0.0) && kozPolygonAt(k, 0.0).contains(xy(start))) {
      out.push_back("sim_config.json: uav.start: inside keep-out zone " + k.id + " at t = 0");
    }
  }
  for (const auto& a : sim.aircraft) {
    const TrajectoryPoint p = sampleTrajectory(a.trajectory, 0.0);
    if (std::hypot(p.x - start.x(), p.y - start.y()) < spec->min_horizontal_separation &&
        std::abs(p.z - start.z()) < spec->min_vertical_separation) {
      out.push_back("sim_config.json: aircraft " + a.id +
                    ": within the separation minimum of the UAV's start at t = 0");
    }
    for (std::size_t i = 1; i < a.trajectory.size(); ++i) {
      const auto& q0 = a.trajectory[i - 1];
      const auto& q1 = a.trajectory[i];
      const Vec3 p0(q0.x, q0.y, q0.z), p1(q1.x, q1.y, q1.z);
      const double v = (p1 - p0).norm() / (q1.t - q0.t);
      if (!(v <= kMaxAircraftSpeed)) {
        out.push_back("sim_config.json: aircraft " + a.id + ".trajectory[" + std::to_string(i) +
                      "]: jumps at " + formatNumber(v) + " m/s (the most is " +
                      formatNumber(kMaxAircraftSpeed) + "): not continuous");
        break;
      }
      if (!band.staticSegmentValid(p0, p1)) {
        out.push_back("sim_config.json: aircraft " + a.id + ".trajectory[" + std::to_string(i) +
                      "]: passes through a static obstacle or leaves the flight band");
        break;
      }
    }
  }
  const Vec3& goal = spec->goal;
  if (!all.staticValid(goal)) {
    out.push_back("mission.json: phases: avoid goal: inside an obstacle or out of bounds (" +
                  all.explain(goal, 0.0) + ")");
    return out;
  }
  const double straight = (goal - start).norm();
  if (spec->shortest_path_m < straight - 0.01) {
    out.push_back("mission.json: phases: avoid shortest_path_m " +
                  formatNumber(spec->shortest_path_m) + " is shorter than the straight line (" +
                  formatNumber(straight) + " m)");
  }
  const ReferenceFlight f = shortestFlight(band, start, goal);
  if (!f.ok) {
    out.push_back("mission.json: phases: avoid goal: unreachable from the start: " + f.why);
  } else if (std::abs(f.length - spec->shortest_path_m) > 0.01 * f.length) {
    out.push_back("mission.json: phases: avoid shortest_path_m " +
                  formatNumber(spec->shortest_path_m) + " but the shortest flight found is " +
                  formatNumber(f.length) + " m");
  }
  return out;
}

}  // namespace hameritt::scenario
