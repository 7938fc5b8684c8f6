// Signalised traffic and crowds of the city world type. Cars: every interior arterial is a
// corridor; each of its four lanes, joined with the opposite lane by a turning loop beyond each
// end of the tile, is a closed ring on which a fixed number of cars drive with the Intelligent
// Driver Model, stopping at the signals' stop lines. Pedestrians: sidewalk strolls, crossings at
// the signalised crosswalks while the crossed street is red, mid-block jaywalking across local
// streets and queues at the bus stops.

#include "hameritt/scenario/city_traffic.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <mutex>

#include "hameritt/geometry/segment.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/trajectory.h"

namespace hameritt::scenario {

using geometry::Vec2;
using geometry::Vec3;

const char* toString(SignalState s) {
  switch (s) {
    case SignalState::kGreen:
      return "green";
    case SignalState::kYellow:
      return "yellow";
    case SignalState::kLeftArrow:
      return "left";
    case SignalState::kRed:
      return "red";
  }
  return "red";
}

SignalState SignalPlan::state(const SignalizedIntersection& i, int axis, double t) const {
  const double c = cycle();
  double tau = std::fmod(t - i.offset, c);
  if (tau < 0) tau += c;
  if (axis == 1) {
    tau -= 0.5 * c;
    if (tau < 0) tau += c;
  }
  if (tau < left) return SignalState::kLeftArrow;
  if (tau < left + green) return SignalState::kGreen;
  if (tau < left + green + yellow) return SignalState::kYellow;
  return SignalState::kRed;
}

namespace {

constexpr double kLaneWidth = 3.5;
constexpr double kLoopRun = 30.0;     // straight run of a lane beyond the tile's last node (m)
constexpr double kLoopSpread = 20.0;  // length over which the lane widens into its loop (m)
constexpr double kLoopExtra = 8.0;    // the inner lane's loop radius exceeds its offset by this (m)
constexpr double kStopBack = 1.0;     // stop line: this far before the crosswalk (m)
constexpr double kGuard = 0.25;       // a car over its stop line on red stays this far short (m)
constexpr double kLookAhead = 150.0;  // a car looks this far ahead for the car it follows (m)
// A turn starts no later than this before the end of the protected arrow (s), so that the
// turning car is out of the box when the axis' through traffic moves.
constexpr double kTurnClose = 4.0;
// At a box where two arterials cross, a car of the inner lane turns left and one of the outer
// lane turns right with these probabilities (otherwise it goes straight on).
constexpr double kLeftTurnProbability = 0.15;
constexpr double kRightTurnProbability = 0.15;

bool isArterial(const World& w, const StreetEdge& e) {
  return e.width >= w.params().city.arterial_width - 1e-9;
}

// 0: a street running roughly north-south, 1: east-west.
int axisOf(const World& w, const StreetEdge& e) {
  const Vec2 d = w.nodes()[e.b].position - w.nodes()[e.a].position;
  return std::abs(d.x()) > std::abs(d.y()) ? 1 : 0;
}

bool onBoundary(const World& w, const Vec2& p) {
  const auto b = w.bounds();
  return p.x() <= b.min.x() + 1e-6 || p.x() >= b.max.x() - 1e-6 || p.y() <= b.min.y() + 1e-6 ||
         p.y() >= b.max.y() - 1e-6;
}

Vec2 unit(double heading) { return {std::cos(heading), std::sin(heading)}; }
Vec2 leftOf(const Vec2& u) { return {-u.y(), u.x()}; }

// A lane polyline with arc lengths: a closed ring or a car's open path.
struct LaneRing {
  std::string name;
  bool closed = true;     // a ring; otherwise an open path whose arc length is clamped
  std::vector<Vec2> pts;  // closed: last == first
  std::vector<double> cum;
  double length = 0.0;

  void finish() {
    cum.assign(1, 0.0);
    for (std::size_t i = 1; i < pts.size(); ++i)
      cum.push_back(cum.back() + (pts[i] - pts[i - 1]).norm());
    length = cum.back();
  }
  double wrap(double s) const {
    if (!closed) return std::clamp(s, 0.0, length);
    double m = std::fmod(s, length);
    return m < 0 ? m + length : m;
  }
  // Index of the segment holding arc length s (wrapped).
  std::size_t segment(double s) const {
    const auto it = std::upper_bound(cum.begin(), cum.end(), wrap(s));
    return std::min<std::size_t>(static_cast<std::size_t>(it - cum.begin()) - 1, pts.size() - 2);
  }
  Vec2 at(double s) const {
    const std::size_t k = segment(s);
    const double u = (wrap(s) - cum[k]) / std::max(1e-9, cum[k + 1] - cum[k]);
    return pts[k] + u * (pts[k + 1] - pts[k]);
  }
  double yawAt(double s) const {
    const Vec2 d = at(s + 1.5) - at(s - 1.5);
    return std::atan2(d.y(), d.x());
  }
};

// The polyline moved `r` to the right of its direction (mitred at the vertices).
std::vector<Vec2> offsetRight(const std::vector<Vec2>& p, double r) {
  std::vector<Vec2> out;
  for (std::size_t i = 0; i < p.size(); ++i) {
    Vec2 n(0, 0);
    if (i > 0) {
      const Vec2 d = (p[i] - p[i - 1]).normalized();
      n += Vec2(d.y(), -d.x());
    }
    if (i + 1 < p.size()) {
      const Vec2 d = (p[i + 1] - p[i]).normalized();
      n += Vec2(d.y(), -d.x());
    }
    n.normalize();
    double cosh = 1.0;
    if (i + 1 < p.size()) {
      const Vec2 d = (p[i + 1] - p[i]).normalized();
      cosh = std::max(0.5, n.dot(Vec2(d.y(), -d.x())));
    }
    out.push_back(p[i] + (r / cosh) * n);
  }
  return out;
}

// A left-turning loop beyond `end` (direction of travel `u`): from the lane `r` to the right of
// the centreline to the opposite lane `r` to its left, widening first so that the turn radius
// is r + kLoopExtra * (lane + 1): the loops of a street's two lanes move apart as they widen, so
// that cars of neighbouring lanes keep their distance where the lanes bend. The loop's first
// and last points are not included.
void appendLoop(const Vec2& end, const Vec2& u, double r, int lane, std::vector<Vec2>* out) {
  const Vec2 n = leftOf(u);
  const double big = r + kLoopExtra * (lane + 1);
  out->push_back(end + kLoopRun * u - r * n);
  const Vec2 c = end + (kLoopRun + kLoopSpread) * u;
  constexpr int kSteps = 8;
  for (int k = 0; k <= kSteps; ++k) {
    const double phi = geometry::kPi * k / kSteps;
    // -n rotated counter-clockwise by phi.
    const Vec2 v = std::cos(phi) * (-n) + std::sin(phi) * u;
    out->push_back(c + big * v);
  }
  out->push_back(end + kLoopRun * u + r * n);
}

struct Corridor {
  int axis = 0;
  std::vector<int> nodes;  // in increasing coordinate of the axis
};

std::vector<Corridor> arterialCorridors(const World& w) {
  std::vector<Corridor> out;
  const auto& edges = w.edges();
  for (int axis = 0; axis < 2; ++axis) {
    std::vector<std::vector<int>> at(w.nodes().size());
    for (int e = 0; e < static_cast<int>(edges.size()); ++e) {
      if (!isArterial(w, edges[e]) || axisOf(w, edges[e]) != axis) continue;
      at[edges[e].a].push_back(e);
      at[edges[e].b].push_back(e);
    }
    std::vector<char> used(edges.size(), 0);
    for (int start = 0; start < static_cast<int>(at.size()); ++start) {
      if (at[start].size() != 1 || used[at[start][0]]) continue;
      Corridor c;
      c.axis = axis;
      int node = start, edge = at[start][0];
      c.nodes.push_back(node);
      while (edge >= 0) {
        used[edge] = 1;
        node = edges[edge].a == node ? edges[edge].b : edges[edge].a;
        c.nodes.push_back(node);
        int next = -1;
        for (int e : at[node]) {
          if (!used[e]) next = e;
        }
        edge = next;
      }
      const auto coord = [&](int n) {
        const Vec2 p = w.nodes()[n].position;
        return axis == 0 ? p.y() : p.x();
      };
      if (coord(c.nodes.front()) > coord(c.nodes.back()))
        std::reverse(c.nodes.begin(), c.nodes.end());
      bool interior = false;
      for (int n : c.nodes) interior = interior || !onBoundary(w, w.nodes()[n].position);
      if (interior && c.nodes.size() >= 3) out.push_back(std::move(c));
    }
  }
  return out;
}

// A sample of a car's arc length s at time t.
struct Sample {
  double t = 0.0;
  double s = 0.0;
};

// Simplifies a 1D motion s(t) sampled every `dt` (non-decreasing s): a sample is added where the
// car passes a ring vertex, and the samples kept are those whose piecewise-linear interpolation
// stays within `tol` of every sample and ends at every vertex sample (so that positions
// interpolated between kept samples stay on the lane).
std::vector<Sample> simplify(const std::vector<double>& s, double dt, const LaneRing& ring,
                             double tol) {
  std::vector<Sample> x{{0.0, s[0]}};
  std::vector<char> hard{1};
  const std::size_t nv = ring.cum.size();
  for (std::size_t k = 1; k < s.size(); ++k) {
    if (s[k] > s[k - 1]) {
      double base = std::floor(s[k - 1] / ring.length) * ring.length;
      std::size_t j = ring.segment(s[k - 1]) + 1;
      for (;;) {
        const double v = base + ring.cum[j];
        if (v >= s[k]) break;
        if (v > s[k - 1]) {
          const double t = dt * (static_cast<double>(k - 1) + (v - s[k - 1]) / (s[k] - s[k - 1]));
          x.push_back({t, v});
          hard.push_back(1);
        }
        if (++j == nv) {
          base += ring.length;
          j = 1;
        }
      }
    }
    x.push_back({dt * static_cast<double>(k), s[k]});
    hard.push_back(0);
  }
  hard.back() = 1;
  std::vector<Sample> keep{x[0]};
  std::size_t a = 0;
  while (a + 1 < x.size()) {
    double lo = -1e300, hi = 1e300;
    std::size_t e = a + 1;
    for (std::size_t i = a + 1; i < x.size(); ++i) {
      const double span = x[i].t - x[a].t;
      const double slope = span > 0 ? (x[i].s - x[a].s) / span : 0.0;
      if (i > a + 1 && (slope < lo || slope > hi)) break;
      e = i;
      if (hard[i] || span <= 0) break;
      lo = std::max(lo, (x[i].s - tol - x[a].s) / span);
      hi = std::min(hi, (x[i].s + tol - x[a].s) / span);
    }
    keep.push_back(x[e]);
    a = e;
  }
  return keep;
}

// What a lane piece is: a link between boxes (or a box and the tile's end), a connector across
// a box (straight on, or a turn) or a loop beyond the tile.
enum class PieceKind { kLink, kThrough, kLeft, kRight, kLoop };

// A piece of a directed lane; cars drive paths of pieces, each starting where the last ends.
struct Piece {
  std::string name;
  PieceKind kind = PieceKind::kLink;
  std::vector<Vec2> pts;
  double length = 0.0;
  int intersection = -1;  // a connector's box
  int axis = 0;           // the axis a connector is entered from
  int next = -1;          // the piece after this one (a link before a box: see below)
  int through = -1, left = -1, right = -1;  // a link before a box: its connectors

  void finish() { length = geometry::polylineLength(pts); }
};

struct Car {
  double s = 0.0;  // arc length of the centre along its path
  double v = 0.0;
  double v0 = 12.0;
  double length = 4.5;
  long committed = -1;         // path index of the link whose stop line the car crosses on yellow
  std::vector<int> path;       // pieces, drawn as the car goes
  std::vector<double> base;    // arc length at which each path piece starts
  std::size_t at = 0;          // path index of the piece under the centre
  std::uint64_t turn_rng = 0;  // state of the car's own stream of turn choices
};

// Whether a turn at `si` from `axis` may start at t: during the first part of the axis' arrow,
// so that the turning car clears the box before the axis' through traffic gets green. A right
// turn may also start on the cross street's arrow: its curve meets none of the left turns then.
bool turnOpen(const SignalPlan& plan, const SignalizedIntersection& si, int axis, PieceKind kind,
              double t) {
  for (int a = 0; a < 2; ++a) {
    if (a != axis && kind != PieceKind::kRight) continue;
    if (plan.state(si, a, t) != SignalState::kLeftArrow) continue;
    const double c = plan.cycle();
    double tau = std::fmod(t - si.offset - (a == 1 ? 0.5 * c : 0.0), c);
    if (tau < 0) tau += c;
    if (tau <= plan.left - kTurnClose) return true;
  }
  return false;
}

// The open polyline of a car's path: its pieces' points joined end to start.
LaneRing pathLine(const std::vector<TrafficEpisode::Lane>& lanes, const std::vector<int>& path) {
  LaneRing r;
  r.closed = false;
  for (int id : path) {
    const auto& pts = lanes.at(static_cast<std::size_t>(id)).points;
    r.pts.insert(r.pts.end(), pts.begin() + (r.pts.empty() ? 0 : 1), pts.end());
  }
  r.finish();
  return r;
}

}  // namespace

SignalPlan citySignalPlan(const World& world, std::uint64_t seed) {
  const CityParams& c = world.params().city;
  SignalPlan plan;
  plan.left = c.signal_left;
  plan.green = c.signal_green;
  plan.yellow = c.signal_yellow;
  plan.all_red = c.signal_all_red;
  plan.sidewalk = c.sidewalk_width;
  Rng rng(deriveSeed(seed, 0x5349474E414CULL));
  const auto& edges = world.edges();
  for (int n = 0; n < static_cast<int>(world.nodes().size()); ++n) {
    const Vec2 p = world.nodes()[n].position;
    if (onBoundary(world, p)) continue;
    bool art = false;
    Vec2 dir[2] = {Vec2(0, 0), Vec2(0, 0)};
    double width[2] = {0, 0};
    for (int e : world.adjacency()[n]) {
      const StreetEdge& se = edges[e];
      art = art || isArterial(world, se);
      const int axis = axisOf(world, se);
      Vec2 d = (world.nodes()[se.a == n ? se.b : se.a].position - p).normalized();
      if ((axis == 0 && d.y() < 0) || (axis == 1 && d.x() < 0)) d = -d;
      dir[axis] += d;
      width[axis] = std::max(width[axis], se.width);
    }
    if (!art || width[0] <= 0 || width[1] <= 0) continue;
    SignalizedIntersection si;
    char id[32];
    std::snprintf(id, sizeof(id), "signal_%02d", static_cast<int>(plan.intersections.size()) + 1);
    si.id = id;
    si.position = p;
    for (int a = 0; a < 2; ++a) {
      si.heading[a] = roundMilli(std::atan2(dir[a].y(), dir[a].x()));
      si.width[a] = width[a];
    }
    si.offset = roundMilli(rng.uniform(0.0, plan.cycle()));
    plan.intersections.push_back(si);
  }
  return plan;
}

namespace {

double tileArea(const World& w) {
  const auto b = w.bounds();
  return (b.max.x() - b.min.x()) * (b.max.y() - b.min.y());
}

}  // namespace

int cityCarBound(const World& world) {
  return static_cast<int>(
             std::ceil(2.0 * world.params().city.vehicles_per_km2 * tileArea(world) / 1e6)) +
         8;
}

int cityPedestrianBound(const World& world) {
  return static_cast<int>(
             std::ceil(world.params().city.pedestrians_per_km2 * tileArea(world) / 1e6)) +
         8;
}

namespace {

// Every ring's cars simulated over [0, horizon] with the plan of `seed`.
TrafficEpisode runCars(const World& world, std::uint64_t seed, double horizon,
                       const IdmParams& idm) {
  const CityParams& cp = world.params().city;
  TrafficEpisode out;
  out.length = horizon;
  out.world_fingerprint = world.fingerprint();
  out.plan = citySignalPlan(world, seed);
  const SignalPlan& plan = out.plan;
  const double duration = horizon;
  const double sw = cp.sidewalk_width;
  const double area_km2 = tileArea(world) / 1e6;
  Rng rng(deriveSeed(seed, 0x5452414646494355ULL));

  // Signalised intersection of each node, or -1.
  std::vector<int> signal_of(world.nodes().size(), -1);
  for (int i = 0; i < static_cast<int>(plan.intersections.size()); ++i) {
    for (int n = 0; n < static_cast<int>(world.nodes().size()); ++n) {
      if ((world.nodes()[n].position - plan.intersections[i].position).norm() < 1e-9)
        signal_of[n] = i;
    }
  }

  // ---------------------------------------------------------------- lane pieces
  // Every directed lane of every arterial corridor is cut at each signalised box into links
  // (between boxes) and through connectors (across a box); at a box where two corridors cross,
  // turn connectors join the inner lane to the inner lane on the left and the outer lane to the
  // outer lane on the right; beyond each end of the tile a loop joins a lane to the opposite
  // lane. A car drives a path of pieces, drawn turn by turn as it goes.
  const bool turns = plan.left >= kTurnClose + 1.0;
  std::vector<Piece> pieces;
  auto addPiece = [&](Piece p) {
    for (auto& q : p.pts) q = Vec2(roundMilli(q.x()), roundMilli(q.y()));
    p.finish();
    pieces.push_back(std::move(p));
    return static_cast<int>(pieces.size()) - 1;
  };
  // Per signalised node: the directed lanes through it (their link before the box, through
  // connector and link after it, the box's entry and exit points and the lane's direction).
  struct Approach {
    int corridor = 0, dir = 0, lane = 0, axis = 0;
    int link_in = -1, through = -1, link_out = -1;
    Vec2 entry, exit, u;
  };
  std::map<int, std::vector<Approach>> at_node;
  const std::vector<Corridor> corridors = arterialCorridors(world);
  // Circuits: the pieces of the straight ring of each corridor lane (forward, loop, back, loop),
  // along which the cars start.
  std::vector<std::vector<int>> circuits;
  double inside_total = 0.0;
  for (std::size_t ci = 0; ci < corridors.size(); ++ci) {
    const Corridor& c = corridors[ci];
    std::vector<Vec2> centre;
    for (int n : c.nodes) centre.push_back(world.nodes()[n].position);
    const double inside = geometry::polylineLength(centre);
    const int other = 1 - c.axis;
    for (int lane = 0; lane < 2; ++lane) {
      const double r = (0.5 + lane) * kLaneWidth;
      std::vector<int> first(2), last(2);
      std::vector<std::vector<int>> runs(2);
      for (int dir = 0; dir < 2; ++dir) {
        std::vector<int> nodes = c.nodes;
        std::vector<Vec2> line = centre;
        if (dir == 1) {
          std::reverse(nodes.begin(), nodes.end());
          std::reverse(line.begin(), line.end());
        }
        std::vector<Vec2> p = offsetRight(line, r);
        for (auto& q : p) q = Vec2(roundMilli(q.x()), roundMilli(q.y()));
        std::vector<double> cum{0.0};
        for (std::size_t i = 1; i < p.size(); ++i)
          cum.push_back(cum.back() + (p[i] - p[i - 1]).norm());
        auto pointAt = [&](double s) {
          std::size_t k = 0;
          while (k + 2 < p.size() && cum[k + 1] < s) ++k;
          const double u = (s - cum[k]) / std::max(1e-9, cum[k + 1] - cum[k]);
          const Vec2 q = p[k] + u * (p[k + 1] - p[k]);
          return Vec2(roundMilli(q.x()), roundMilli(q.y()));
        };
        // The sub-polyline from a to b (arc lengths), its ends the given points.
        auto slice = [&](double a, const Vec2& pa, double b, const Vec2& pb) {
          std::vector<Vec2> out{pa};
          for (std::size_t i = 0; i < p.size(); ++i) {
            if (cum[i] > a + 1e-6 && cum[i] < b - 1e-6) out.push_back(p[i]);
          }
          out.push_back(pb);
          return out;
        };
        const std::string tag =
            std::to_string(ci + 1) + (dir == 0 ? "f" : "b") + std::to_string(lane + 1);
        double s_from = 0.0;
        Vec2 p_from = p.front();
        int prev = -1;
        auto link = [&](int piece) {
          if (prev >= 0) pieces[prev].next = piece;
          prev = piece;
          runs[dir].push_back(piece);
        };
        for (std::size_t k = 1; k + 1 < nodes.size(); ++k) {
          const int si = signal_of[nodes[k]];
          if (si < 0) continue;
          const double half = 0.5 * plan.intersections[si].width[other] + sw;
          const double se = cum[k] - half, sx = cum[k] + half;
          const Vec2 pe = pointAt(se), px = pointAt(sx);
          Piece in;
          in.name = "link_" + tag + "_" + std::to_string(runs[dir].size() / 2 + 1);
          in.pts = slice(s_from, p_from, se, pe);
          in.kind = PieceKind::kLink;
          const int in_id = addPiece(std::move(in));
          link(in_id);
          Piece th;
          th.name = "through_" + tag + "_" + plan.intersections[si].id;
          th.pts = slice(se, pe, sx, px);
          th.kind = PieceKind::kThrough;
          th.intersection = si;
          th.axis = c.axis;
          const int th_id = addPiece(std::move(th));
          pieces[in_id].through = th_id;
          link(th_id);
          Approach a;
          a.corridor = static_cast<int>(ci);
          a.dir = dir;
          a.lane = lane;
          a.axis = c.axis;
          a.link_in = in_id;
          a.through = th_id;
          a.entry = pe;
          a.exit = px;
          a.u = (p[k + 1] - p[k - 1]).normalized();
          at_node[nodes[k]].push_back(a);
          s_from = sx;
          p_from = px;
        }
        Piece out;
        out.name = "link_" + tag + "_" + std::to_string(runs[dir].size() / 2 + 1);
        out.pts = slice(s_from, p_from, cum.back(), p.back());
        out.kind = PieceKind::kLink;
        link(addPiece(std::move(out)));
        for (auto& node_approaches : at_node) {
          for (auto& a : node_approaches.second) {
            if (a.corridor == static_cast<int>(ci) && a.dir == dir && a.lane == lane &&
                a.link_out < 0) {
              a.link_out = pieces[a.through].next;
            }
          }
        }
        first[dir] = runs[dir].front();
        last[dir] = runs[dir].back();
      }
      for (int dir = 0; dir < 2; ++dir) {
        const Piece& a = pieces[last[dir]];
        const Vec2 end = a.pts.back();
        const std::vector<Vec2>& line =
            dir == 0 ? centre : std::vector<Vec2>(centre.rbegin(), centre.rend());
        Piece loop;
        loop.name =
            "loop_" + std::to_string(ci + 1) + (dir == 0 ? "f" : "b") + std::to_string(lane + 1);
        loop.kind = PieceKind::kLoop;
        loop.pts.push_back(end);
        appendLoop(line.back(), (line.back() - line[line.size() - 2]).normalized(), r, lane,
                   &loop.pts);
        loop.pts.push_back(pieces[first[1 - dir]].pts.front());
        const int id = addPiece(std::move(loop));
        pieces[last[dir]].next = id;
        pieces[id].next = first[1 - dir];
      }
      std::vector<int> circuit = runs[0];
      circuit.push_back(pieces[last[0]].next);
      circuit.insert(circuit.end(), runs[1].begin(), runs[1].end());
      circuit.push_back(pieces[last[1]].next);
      circuits.push_back(std::move(circuit));
      inside_total += 2.0 * inside;
    }
  }
  // Turn connectors: a cubic Bezier from the box's entry on one lane to its exit on the other.
  for (auto& [node, approaches] : at_node) {
    for (auto& a : approaches) {
      for (const auto& b : approaches) {
        if (b.axis == a.axis || b.lane != a.lane || !turns) continue;
        const double cross = a.u.x() * b.u.y() - a.u.y() * b.u.x();
        const bool left = cross > 0.5, right = cross < -0.5;
        if (!(a.lane == 0 ? left : right)) continue;
        const double k = 0.39 * (b.exit - a.entry).norm();
        const Vec2 c1 = a.entry + k * a.u, c2 = b.exit - k * b.u;
        Piece tp;
        tp.name = std::string(left ? "left_" : "right_") + pieces[a.through].name.substr(8);
        tp.kind = left ? PieceKind::kLeft : PieceKind::kRight;
        tp.intersection = pieces[a.through].intersection;
        tp.axis = a.axis;
        tp.next = b.link_out;
        constexpr int kSteps = 12;
        for (int i = 0; i <= kSteps; ++i) {
          const double u = static_cast<double>(i) / kSteps, w = 1.0 - u;
          tp.pts.push_back(i == 0        ? a.entry
                           : i == kSteps ? b.exit
                                         : w * w * w * a.entry + 3 * w * w * u * c1 +
                                               3 * w * u * u * c2 + u * u * u * b.exit);
        }
        const int id = addPiece(std::move(tp));
        (left ? pieces[a.link_in].left : pieces[a.link_in].right) = id;
      }
    }
  }
  for (const auto& p : pieces) out.lanes.push_back({p.name, p.pts});

  // ---------------------------------------------------------------- cars
  const int car_bound = cityCarBound(world);
  const double steps_warm = std::ceil(idm.warm_up / idm.step);
  const std::size_t steps = static_cast<std::size_t>(std::ceil(duration / idm.step));
  const double sqrt_ab = std::sqrt(idm.max_accel * idm.comfort_decel);
  std::vector<Car> cars;
  std::vector<const catalog::CarModel*> models;
  std::vector<std::string> colors;
  for (std::size_t ri = 0; ri < circuits.size() && inside_total > 0; ++ri) {
    const std::vector<int>& circuit = circuits[ri];
    std::vector<double> starts{0.0};
    for (int id : circuit) starts.push_back(starts.back() + pieces[id].length);
    const double length = starts.back();
    const double want = cp.vehicles_per_km2 * area_km2 * length / inside_total;
    int n = static_cast<int>(std::floor(want + rng.unit()));
    n = std::min(n, static_cast<int>(length / 15.0));
    const double base = n > 0 ? length / n : 0.0;
    // A box on the circuit that a car's body at s would touch.
    auto inZone = [&](double s, double half_len) -> double {
      for (std::size_t q = 0; q + 1 < circuit.size(); ++q) {
        if (pieces[circuit[q + 1]].kind != PieceKind::kThrough) continue;
        const double stop = starts[q + 1] - kStopBack, exit = starts[q + 2];
        if (s + half_len > stop - 0.5 && s - half_len < exit + 0.5) return stop;
      }
      return -1.0;
    };
    std::vector<double> placed;
    const std::size_t first_car = cars.size();
    for (int i = 0; i < n; ++i) {
      Car car;
      const catalog::CarModel& m = catalog::pickModel(rng);
      const std::string color = catalog::pick(rng, catalog::carColors());
      car.length = m.length;
      car.v0 = rng.uniform(11.0, 14.0);
      double s = i * base + rng.uniform(0.0, 0.4 * base);
      const double stop = inZone(s, 0.5 * car.length);
      if (stop >= 0) s = stop - 0.5 * car.length - 0.5;
      if (!placed.empty() && s - placed.back() < 0.5 * (car.length + cars.back().length) + 8.0)
        continue;
      std::size_t q = 0;
      while (q + 1 < circuit.size() && starts[q + 1] <= s) ++q;
      car.path.push_back(circuit[q]);
      car.base.push_back(0.0);
      car.s = s - starts[q];
      placed.push_back(s);
      cars.push_back(std::move(car));
      models.push_back(&m);
      colors.push_back(color);
    }
    // The last car of the circuit keeps its distance to the first one around the loop.
    if (placed.size() >= 2 && placed.front() + length - placed.back() <
                                  0.5 * (cars[first_car].length + cars.back().length) + 8.0) {
      cars.pop_back();
      models.pop_back();
      colors.pop_back();
    }
  }
  const std::size_t nc = cars.size();
  double longest = 0.0;
  for (const Car& c : cars) longest = std::max(longest, c.length);
  for (std::size_t i = 0; i < nc; ++i) {
    cars[i].turn_rng = deriveSeed(seed, 0x5455524E00000000ULL + i);
  }
  // Appends pieces to the car's path until it reaches `ahead` metres beyond its centre.
  auto extend = [&](Car& c, double ahead) {
    while (c.base.back() + pieces[c.path.back()].length < c.s + ahead) {
      const Piece& p = pieces[c.path.back()];
      int next = p.next;
      if (p.through >= 0) {
        next = p.through;
        Rng r(c.turn_rng);
        c.turn_rng = r.next();
        const double u = r.unit();
        if (p.left >= 0 && u < kLeftTurnProbability) next = p.left;
        if (p.right >= 0 && u < kRightTurnProbability) next = p.right;
      }
      c.base.push_back(c.base.back() + p.length);
      c.path.push_back(next);
    }
  };
  for (auto& c : cars) extend(c, kLookAhead + 50.0);
  std::vector<std::vector<double>> track(nc);
  for (auto& tr : track) tr.reserve(steps + 1);
  // The signals at t and at t + step, asked for by many cars in a step: each intersection's
  // state per axis and whether a turn may start, computed once per step (-1: not yet).
  const std::size_t ni = plan.intersections.size();
  std::vector<signed char> state_now(2 * ni), state_next(2 * ni), turn_now(4 * ni);
  struct Occupant {
    std::size_t car;
    double rel;  // the car's centre from the piece's start (m)
  };
  std::vector<std::vector<Occupant>> occupants(pieces.size());
  struct Step {
    double s = 0.0, v = 0.0;
    long committed = -1;
  };
  std::vector<Step> next(nc);
  for (std::size_t k = 0; k <= static_cast<std::size_t>(steps_warm) + steps; ++k) {
    const double t = (static_cast<double>(k) - steps_warm) * idm.step;
    if (t >= -1e-9) {
      for (std::size_t i = 0; i < nc; ++i) track[i].push_back(cars[i].s);
    }
    if (k == static_cast<std::size_t>(steps_warm) + steps) break;
    std::fill(state_now.begin(), state_now.end(), -1);
    std::fill(state_next.begin(), state_next.end(), -1);
    std::fill(turn_now.begin(), turn_now.end(), -1);
    auto stateAt = [&](std::vector<signed char>& memo, double when, int si, int axis) {
      signed char& m = memo[2 * static_cast<std::size_t>(si) + static_cast<std::size_t>(axis)];
      if (m < 0) m = static_cast<signed char>(plan.state(plan.intersections[si], axis, when));
      return static_cast<SignalState>(m);
    };
    for (auto& o : occupants) o.clear();
    for (std::size_t i = 0; i < nc; ++i) {
      const Car& c = cars[i];
      const double rear = c.s - 0.5 * c.length, front = c.s + 0.5 * c.length;
      for (std::size_t q = c.at > 0 ? c.at - 1 : 0; q < c.path.size(); ++q) {
        if (c.base[q] > front) break;
        if (c.base[q] + pieces[c.path[q]].length < rear) continue;
        occupants[c.path[q]].push_back({i, c.s - c.base[q]});
      }
    }
    for (std::size_t i = 0; i < nc; ++i) {
      const Car& c = cars[i];
      const double front = c.s + 0.5 * c.length;
      // The car ahead on the path: the nearest centre ahead of this one on the pieces to come.
      double gap = 1e9, lead_v = c.v;
      bool has_lead = false;
      for (std::size_t q = c.at > 0 ? c.at - 1 : 0; q < c.path.size(); ++q) {
        if (c.base[q] > front + kLookAhead) break;
        // A car on this piece or a later one has its centre at least half its length before
        // the piece's start, so its gap is at least base - longest - front: past the lead found,
        // no later car can be nearer (1e-6: far beyond the gaps' rounding).
        if (has_lead && c.base[q] - longest - front > gap + 1e-6) break;
        for (const Occupant& o : occupants[c.path[q]]) {
          if (o.car == i) continue;
          const double centre = c.base[q] + o.rel;
          if (centre <= c.s) continue;
          const double g = centre - 0.5 * cars[o.car].length - front;
          if (g < gap) {
            gap = g;
            lead_v = cars[o.car].v;
            has_lead = true;
          }
        }
      }
      // The next stop line ahead of the front: the end of a link before a box, less kStopBack.
      double dist = 1e9, box = 0.0;
      std::size_t stop_q = 0;
      bool has_stop = false;
      for (std::size_t q = c.at > 0 ? c.at - 1 : 0; q + 1 < c.path.size(); ++q) {
        const Piece& nx = pieces[c.path[q + 1]];
        if (nx.intersection < 0) continue;
        const double stop = c.base[q + 1] - kStopBack;
        if (stop < front) continue;
        dist = stop - front;
        box = nx.length;
        stop_q = q;
        has_stop = true;
        break;
      }
      bool blocked = false;
      // A commitment holds for the stop line it was made at, until the car has passed it.
      long commit = c.committed == static_cast<long>(stop_q) && has_stop ? c.committed : -1;
      if (has_stop && dist < 200.0) {
        const Piece& conn = pieces[c.path[stop_q + 1]];
        const auto& si = plan.intersections[conn.intersection];
        if (conn.kind == PieceKind::kThrough) {
          const SignalState state = stateAt(state_now, t, conn.intersection, conn.axis);
          if (state == SignalState::kRed || state == SignalState::kLeftArrow) {
            blocked = true;
          } else if (state == SignalState::kYellow && commit != static_cast<long>(stop_q)) {
            if (dist >= c.v * c.v / (2.0 * idm.yellow_stop_decel) - 1e-9) {
              blocked = true;
            } else {
              commit = static_cast<long>(stop_q);
            }
          }
        } else {
          signed char& open = turn_now[4 * static_cast<std::size_t>(conn.intersection) +
                                       2 * static_cast<std::size_t>(conn.axis) +
                                       (conn.kind == PieceKind::kRight ? 1 : 0)];
          if (open < 0) open = turnOpen(plan, si, conn.axis, conn.kind, t) ? 1 : 0;
          if (!open) blocked = true;
        }
        // Do not enter the box without room behind the leader beyond it.
        if (!blocked && commit != static_cast<long>(stop_q) && has_lead && gap > dist &&
            gap + 3.0 * lead_v < dist + box + c.length + idm.min_gap) {
          blocked = true;
        }
      }
      auto idmAccel = [&](double s_gap, double dv, double s0) {
        const double s_star = s0 + std::max(0.0, c.v * idm.time_gap + c.v * dv / (2.0 * sqrt_ab));
        const double g = std::max(s_gap, 0.01);
        return -idm.max_accel * (s_star / g) * (s_star / g);
      };
      const double r = c.v / c.v0;
      double acc = idm.max_accel * (1.0 - r * r * r * r);
      if (has_lead) acc += idmAccel(gap, c.v - lead_v, idm.min_gap);
      if (blocked) {
        acc = std::min(acc, idm.max_accel * (1.0 - r * r * r * r) + idmAccel(dist, c.v, 0.5));
      }
      acc = std::max(acc, -9.0);
      double v1 = c.v + acc * idm.step;
      double ds = 0.0;
      if (v1 < 0) {
        ds = acc < 0 ? c.v * c.v / (-2.0 * acc) : 0.0;
        v1 = 0.0;
      } else {
        ds = 0.5 * (c.v + v1) * idm.step;
      }
      if (has_lead && ds > std::max(0.0, gap - idm.min_gap)) {
        ds = std::max(0.0, gap - idm.min_gap);
        v1 = std::min(v1, lead_v);
      }
      if (blocked && ds > std::max(0.0, dist)) {
        ds = std::max(0.0, dist);
        v1 = 0.0;
      }
      // A car past its stop line but short of the box (it went on yellow and was slowed by the
      // car ahead, or its turn's window closed) stays kGuard short of the box while its signal
      // does not let it in at the end of the step (kGuard: more than the written trajectories'
      // tolerance).
      for (std::size_t q = c.at > 0 ? c.at - 1 : 0; q + 1 < c.path.size(); ++q) {
        const Piece& conn = pieces[c.path[q + 1]];
        if (c.base[q + 1] > front + kStopBack + 1.0) break;
        if (conn.intersection < 0) continue;
        const double entry = c.base[q + 1], stop = entry - kStopBack, guard = entry - kGuard;
        if (front <= stop || front > entry || front + ds <= guard) continue;
        bool closed = false;
        const double te = t + idm.step;
        const SignalState end_state = stateAt(state_next, te, conn.intersection, conn.axis);
        if (conn.kind == PieceKind::kThrough) {
          closed = end_state == SignalState::kRed || end_state == SignalState::kLeftArrow;
        } else {
          // An arrow that lets the turn go shows at t + step.
          closed = !(end_state == SignalState::kLeftArrow ||
                     (conn.kind == PieceKind::kRight &&
                      stateAt(state_next, te, conn.intersection, 1 - conn.axis) ==
                          SignalState::kLeftArrow));
        }
        if (closed) {
          ds = std::max(0.0, guard - front);
          v1 = 0.0;
        }
      }
      Step& nx = next[i];
      nx.s = c.s + ds;
      nx.v = v1;
      nx.committed = commit;
    }
    for (std::size_t i = 0; i < nc; ++i) {
      Car& c = cars[i];
      c.s = next[i].s;
      c.v = next[i].v;
      c.committed = next[i].committed;
      extend(c, kLookAhead + 50.0);
      while (c.at + 1 < c.path.size() && c.base[c.at + 1] <= c.s) ++c.at;
    }
  }
  for (std::size_t i = 0; i < nc; ++i) {
    const Car& c = cars[i];
    TrafficEpisode::Car car;
    car.vehicle_class = models[i]->vehicle_class;
    car.make = models[i]->make;
    car.model = models[i]->model;
    car.color = colors[i];
    car.size = Vec3(models[i]->length, models[i]->width, models[i]->height);
    // The pieces the car drives over the episode, with a margin behind and ahead.
    const double lo = track[i].front() - 10.0, hi = track[i].back() + 10.0;
    std::size_t a = 0, b = c.path.size();
    while (a + 1 < c.path.size() && c.base[a + 1] <= lo) ++a;
    for (std::size_t q = a; q < c.path.size(); ++q) {
      if (c.base[q] > hi) {
        b = q;
        break;
      }
    }
    car.path.assign(c.path.begin() + static_cast<long>(a), c.path.begin() + static_cast<long>(b));
    std::vector<double> s = track[i];
    for (double& v : s) v -= c.base[a];
    const LaneRing line = pathLine(out.lanes, car.path);
    for (const Sample& q : simplify(s, idm.step, line, 0.1)) {
      const double tk = roundMilli(q.t);
      if (!car.knots.empty() && tk <= car.knots[car.knots.size() - 2]) continue;
      car.knots.push_back(tk);
      car.knots.push_back(roundMilli(q.s));
    }
    out.cars.push_back(std::move(car));
  }
  if (static_cast<int>(out.cars.size()) > car_bound) {
    throw GenerationError("city traffic: " + std::to_string(out.cars.size()) +
                          " cars exceed the bound " + std::to_string(car_bound));
  }
  return out;
}

// The part of `tr` (over [0, horizon]) within [t0, t0 + length], shifted to start at 0.
Trajectory window(const Trajectory& tr, double t0, double length) {
  Trajectory out;
  auto shifted = [&](TrajectoryPoint p) {
    p.t = roundMilli(p.t - t0);
    p.x = roundMilli(p.x);
    p.y = roundMilli(p.y);
    p.yaw = roundMilli(p.yaw);
    return p;
  };
  const auto by_t = [](const TrajectoryPoint& p, double t) { return p.t < t; };
  const auto first = std::lower_bound(tr.begin(), tr.end(), t0 + 1e-6, by_t);
  const auto end = std::lower_bound(first, tr.end(), t0 + length - 1e-6, by_t);
  out.reserve(static_cast<std::size_t>(end - first) + 2);
  out.push_back(shifted(sampleTrajectory(tr, t0)));
  out.front().t = 0.0;
  for (auto it = first; it != end; ++it) {
    if (it->t <= t0 + 1e-6) continue;
    // Decoded points are rounded already: only the time moves.
    TrajectoryPoint p = *it;
    p.t = roundMilli(p.t - t0);
    out.push_back(p);
  }
  TrajectoryPoint last = shifted(sampleTrajectory(tr, t0 + length));
  last.t = roundMilli(length);
  if (last.t > out.back().t) out.push_back(last);
  return out;
}

// Holds the last pose of `tr` until `horizon` (a pedestrian pausing at the end).
void holdUntil(Trajectory* tr, double horizon) {
  if (tr->empty() || tr->back().t >= horizon) return;
  TrajectoryPoint q = tr->back();
  q.t = roundMilli(horizon);
  if (q.t > tr->back().t) tr->push_back(q);
}

// The crowd of a city world over [0, horizon] with the signal plan `plan` (at the same clock):
// every pedestrian keeps one activity, repeated until the horizon, so that the crowd moves in
// any window of it. Walkers stroll 60-300 m along a block's sidewalk and pause 2-20 s between
// strolls; crossers walk back and forth between two sidewalk points on either side of a
// crosswalk (at a signalised intersection: waiting at the kerb until the crossed street is red;
// jaywalkers mid-block, off the signals); queuers stand at a bus stop.
std::vector<CityPedestrian> runPedestrians(const World& world, const SignalPlan& plan,
                                           std::uint64_t seed, double horizon) {
  const CityParams& cp = world.params().city;
  const double sw = cp.sidewalk_width;
  const double area_km2 = tileArea(world) / 1e6;
  Rng rng(deriveSeed(seed, 0x43524F5744ULL));
  std::vector<CityPedestrian> out;
  std::vector<int> bus_stops, local_edges;
  for (int e = 0; e < static_cast<int>(world.entities().size()); ++e) {
    if (world.entities()[e].cls == EntityClass::kBusStop) bus_stops.push_back(e);
  }
  for (int e = 0; e < static_cast<int>(world.edges().size()); ++e) {
    const StreetEdge& se = world.edges()[e];
    const Vec2 a = world.nodes()[se.a].position, b = world.nodes()[se.b].position;
    if (!isArterial(world, se) && (b - a).norm() > 50.0 &&
        !(onBoundary(world, a) && onBoundary(world, b))) {
      local_edges.push_back(e);
    }
  }
  std::vector<int> queue_len(bus_stops.size(), 0);
  const int n_peds = static_cast<int>(std::lround(cp.pedestrians_per_km2 * area_km2));
  // Appends a timed point (strictly after the last one).
  auto push = [](Trajectory* tr, double t, const Vec2& p, double yaw) {
    TrajectoryPoint q;
    q.t = roundMilli(t);
    if (!tr->empty() && q.t <= tr->back().t) q.t = tr->back().t + 0.001;
    q.x = roundMilli(p.x());
    q.y = roundMilli(p.y());
    q.yaw = roundMilli(geometry::wrapPi(yaw));
    tr->push_back(q);
  };
  auto heading = [](const Vec2& a, const Vec2& b) {
    return std::atan2(b.y() - a.y(), b.x() - a.x());
  };
  out.reserve(static_cast<std::size_t>(std::max(0, n_peds)));
  for (int i = 0; i < n_peds; ++i) {
    CityPedestrian ped;
    ped.clothing_color = catalog::pick(rng, catalog::clothingColors());
    ped.height = roundMilli(rng.uniform(1.55, 1.9));
    const double speed = rng.uniform(1.1, 1.6);
    const double u = rng.unit();
    if (u < cp.bus_queue_share && !bus_stops.empty()) {
      const std::size_t k =
          static_cast<std::size_t>(rng.uniformInt(0, static_cast<long>(bus_stops.size()) - 1));
      if (queue_len[k] < 8) {
        const Entity& stop = world.entities()[bus_stops[k]];
        const Vec2 dir = unit(stop.box.yaw);
        const Vec2 p =
            stop.box.center2() + (0.5 * stop.box.size.x() + 0.6 + 0.7 * queue_len[k]) * dir;
        ++queue_len[k];
        ped.activity = "queuing";
        ped.pose = {0.0, roundMilli(p.x()), roundMilli(p.y()), 0.0,
                    roundMilli(geometry::wrapPi(stop.box.yaw + geometry::kPi))};
        out.push_back(std::move(ped));
        continue;
      }
    }
    double t = rng.uniform(0.0, 30.0);  // the first departure
    const double d0 = rng.uniform(5.0, 40.0), d1 = rng.uniform(5.0, 40.0);
    if (u < cp.bus_queue_share + cp.crossing_share) {
      const bool jay = rng.bernoulli(cp.jaywalk_probability);
      Vec2 start, a, b, end;
      double cross_speed = speed;
      const SignalizedIntersection* signal = nullptr;
      int other = 0;
      if (jay && !local_edges.empty()) {
        const StreetEdge& se = world.edges()[local_edges[static_cast<std::size_t>(
            rng.uniformInt(0, static_cast<long>(local_edges.size()) - 1))]];
        const Vec2 pa = world.nodes()[se.a].position, pb = world.nodes()[se.b].position;
        const Vec2 ue = (pb - pa).normalized(), ne = leftOf(ue);
        const Vec2 mid = pa + rng.uniform(0.35, 0.65) * (pb - pa);
        const double side = rng.bernoulli(0.5) ? 1.0 : -1.0,
                     along = rng.bernoulli(0.5) ? 1.0 : -1.0;
        const double h = 0.5 * se.width + 0.5 * sw;
        a = mid + side * h * ne;
        b = mid - side * h * ne;
        start = a - along * d0 * ue;
        end = b + along * d1 * ue;
        cross_speed = 1.25 * speed;
        ped.activity = "jaywalking";
      } else if (!jay && !plan.intersections.empty()) {
        signal = &plan.intersections[static_cast<std::size_t>(
            rng.uniformInt(0, static_cast<long>(plan.intersections.size()) - 1))];
        const int axis = static_cast<int>(rng.uniformInt(0, 1));
        other = 1 - axis;
        const double side = rng.bernoulli(0.5) ? 1.0 : -1.0, dir = rng.bernoulli(0.5) ? 1.0 : -1.0;
        const Vec2 ua = unit(signal->heading[axis]), na = leftOf(ua);
        const double c = 0.5 * signal->width[other] + 0.5 * sw,
                     h = 0.5 * signal->width[axis] + 0.5 * sw;
        a = signal->position + side * c * ua - dir * h * na;
        b = signal->position + side * c * ua + dir * h * na;
        start = a - dir * d0 * na;
        end = b + dir * d1 * na;
        // Off the carriageway before the crossed street moves again.
        const double clear = plan.green + plan.yellow + plan.all_red;  // other green -> ours
        cross_speed = std::max(speed, 2.0 * h / std::max(1.0, clear - 1.0));
        ped.activity = "crossing";
      }
      if (!ped.activity.empty()) {
        // Walk while the other axis is green (its left arrow over): the crossed street is red.
        const double cyc = plan.cycle(), half = 0.5 * cyc;
        const double clear = plan.green + plan.yellow + plan.all_red;
        const double length = (b - a).norm();
        const double walk_lo = plan.left,
                     walk_hi = std::max(walk_lo,
                                        std::min(plan.left + plan.green,
                                                 plan.left + clear - length / cross_speed - 0.5));
        Trajectory tr;
        push(&tr, 0.0, start, heading(start, a));
        for (bool forward = true; t < horizon; forward = !forward) {
          const Vec2 &p0 = forward ? start : end, &k0 = forward ? a : b, &k1 = forward ? b : a,
                     &p1 = forward ? end : start;
          const double y0 = heading(p0, k0), y1 = heading(k0, k1), y2 = heading(k1, p1);
          if (t > tr.back().t + 1e-3) push(&tr, t, p0, y0);
          const double ta = t + (k0 - p0).norm() / speed;
          push(&tr, ta, k0, y0);
          double t_cross = ta;
          if (signal) {
            // Phase of the other axis' cycle at arrival.
            double tau = std::fmod(ta - signal->offset - (other == 1 ? half : 0.0), cyc);
            if (tau < 0) tau += cyc;
            if (tau < walk_lo) {
              t_cross = ta + walk_lo - tau;
            } else if (tau > walk_hi) {
              t_cross = ta + cyc - tau + walk_lo;
            }
          }
          if (t_cross > ta + 1e-3) push(&tr, t_cross, k0, y1);
          const double tb = std::max(ta, t_cross) + length / cross_speed;
          push(&tr, tb, k1, y1);
          const double te = tb + (p1 - k1).norm() / speed;
          push(&tr, te, p1, y2);
          t = te + rng.uniform(2.0, 20.0);
        }
        holdUntil(&tr, horizon);
        ped.pose = tr.front();
        ped.trajectory = std::move(tr);
        out.push_back(std::move(ped));
        continue;
      }
    }
    // Strolls along a block's sidewalk ring.
    const Block& blk = world.blocks()[static_cast<std::size_t>(
        rng.uniformInt(0, static_cast<long>(world.blocks().size()) - 1))];
    const double len = geometry::polylineLength(blk.sidewalk);
    double s = rng.uniform(0.0, len);
    ped.activity = "walking";
    Trajectory tr;
    while (t < horizon) {
      const double dist = rng.uniform(60.0, 300.0) * (rng.bernoulli(0.5) ? 1.0 : -1.0);
      Trajectory leg = walkRing(blk.sidewalk, s, s + dist, speed, t);
      // walkRing() holds the start at t = 0 first when t > 0: kept for the first stroll only.
      std::size_t from = tr.empty() || leg.size() < 2 || leg.front().t > 0.0 ? 0 : 1;
      for (std::size_t k = from; k < leg.size(); ++k) {
        if (!tr.empty() && leg[k].t <= tr.back().t) continue;
        tr.push_back(leg[k]);
      }
      s += dist;
      t = tr.back().t + rng.uniform(2.0, 20.0);
    }
    holdUntil(&tr, horizon);
    ped.pose = tr.front();
    ped.trajectory = std::move(tr);
    out.push_back(std::move(ped));
  }
  return out;
}

// Knots [from, to) of `car` decoded along its path.
Trajectory decodeKnots(const TrafficEpisode& e, const TrafficEpisode::Car& car, std::size_t from,
                       std::size_t to) {
  const LaneRing ring = pathLine(e.lanes, car.path);
  Trajectory out;
  out.reserve(to - from);
  for (std::size_t k = from; k < to; ++k) {
    const double s = car.knots[2 * k + 1];
    const Vec2 p = ring.at(s);
    TrajectoryPoint tp;
    tp.t = car.knots[2 * k];
    tp.x = roundMilli(p.x());
    tp.y = roundMilli(p.y());
    tp.yaw = roundMilli(geometry::wrapPi(ring.yawAt(s)));
    out.push_back(tp);
  }
  return out;
}

// The episode as its file reads back (trafficEpisodeJson, parseTrafficEpisode): every number
// is written in its shortest round-trip form, so only what the file does not carry changes:
// -0 is written as 0 (atan2 of a lane's direction tells them apart), and a pedestrian's pose
// and keyframes carry no z (nor the pose a time). gtest
// CityTrafficEpisode.TheEpisodeInMemoryIsTheOneItsFileReadsBack.
void asItsFileReadsBack(TrafficEpisode* e) {
  auto fix = [](double& d) {
    if (d == 0.0) d = 0.0;
  };
  fix(e->length);
  for (double* d : {&e->plan.left, &e->plan.green, &e->plan.yellow, &e->plan.all_red,
                    &e->plan.sidewalk}) {
    fix(*d);
  }
  for (auto& i : e->plan.intersections) {
    for (double* d : {&i.position.x(), &i.position.y(), &i.offset, &i.heading[0], &i.heading[1],
                      &i.width[0], &i.width[1]}) {
      fix(*d);
    }
  }
  for (auto& l : e->lanes) {
    for (auto& p : l.points) {
      fix(p.x());
      fix(p.y());
    }
  }
  for (auto& c : e->cars) {
    for (double& k : c.knots) fix(k);
    for (int k = 0; k < 3; ++k) fix(c.size[k]);
  }
  for (auto& p : e->pedestrians) {
    fix(p.height);
    p.pose = {0.0, p.pose.x, p.pose.y, 0.0, p.pose.yaw};
    fix(p.pose.x);
    fix(p.pose.y);
    fix(p.pose.yaw);
    for (auto& q : p.trajectory) {
      q.z = 0.0;
      fix(q.t);
      fix(q.x);
      fix(q.y);
      fix(q.yaw);
    }
  }
}

std::shared_ptr<SharedTrafficEpisode> decodedEpisode(TrafficEpisode e) {
  auto shared = std::make_shared<SharedTrafficEpisode>();
  shared->episode = std::move(e);
  for (const auto& car : shared->episode.cars) {
    shared->trajectories.push_back(decodeKnots(shared->episode, car, 0, car.knots.size() / 2));
  }
  return shared;
}

struct EpisodeSlot {
  std::once_flag once;
  std::shared_ptr<const SharedTrafficEpisode> value;
};

struct EpisodeCache {
  std::mutex mutex;
  std::vector<std::pair<std::string, std::shared_ptr<EpisodeSlot>>> slots;  // newest last
};

}  // namespace

std::string trafficEpisodeFileName(int index) {
  char name[48];
  std::snprintf(name, sizeof(name), "traffic_episode_%02d.json", index);
  return name;
}

Trajectory episodeCarWindow(const TrafficEpisode& e, std::size_t car, double offset,
                            double duration) {
  const TrafficEpisode::Car& c = e.cars.at(car);
  const std::size_t n = c.knots.size() / 2;
  // The knots from the last at or before `offset` to the first at or after the window's end.
  auto firstAfter = [&](double t, bool strict) {
    std::size_t lo = 0, hi = n;
    while (lo < hi) {
      const std::size_t mid = (lo + hi) / 2;
      const double tm = c.knots[2 * mid];
      if (strict ? tm <= t : tm < t) {
        lo = mid + 1;
      } else {
        hi = mid;
      }
    }
    return lo;
  };
  const std::size_t a = firstAfter(offset, true), b = firstAfter(offset + duration, false);
  return window(decodeKnots(e, c, a > 0 ? a - 1 : 0, std::min(n, b + 1)), offset, duration);
}

namespace {

// A scenario entity `id` of class `cls` and role `role` moving along `window` (its attributes
// and box are the caller's).
ScenarioEntity movingEntity(const std::string& id, EntityClass cls, const char* role,
                            Trajectory window) {
  ScenarioEntity se;
  se.entity.id = id;
  se.entity.cls = cls;
  se.role = role;
  se.trajectory = std::move(window);
  return se;
}

}  // namespace

ScenarioEntity episodeCarEntity(const TrafficEpisode& e, std::size_t car, Trajectory window,
                                const std::string& id) {
  const TrafficEpisode::Car& c = e.cars.at(car);
  ScenarioEntity se = movingEntity(id, EntityClass::kCar, "traffic", std::move(window));
  Entity& en = se.entity;
  en.attributes.set("vehicle_class", c.vehicle_class);
  en.attributes.set("make", c.make);
  en.attributes.set("model", c.model);
  en.attributes.set("color", c.color);
  en.attributes.set("lane", e.lanes.at(static_cast<std::size_t>(c.path.front())).name);
  const TrajectoryPoint p0 = se.trajectory.empty() ? TrajectoryPoint{} : se.trajectory.front();
  en.box = boxFromPose(Vec3(roundMilli(p0.x), roundMilli(p0.y), roundMilli(p0.z)),
                       roundMilli(geometry::wrapPi(p0.yaw)), c.size);
  return se;
}

Trajectory episodePedestrianWindow(const TrafficEpisode& e, std::size_t ped, double offset,
                                   double duration) {
  const Trajectory& tr = e.pedestrians.at(ped).trajectory;
  if (tr.empty()) return {};
  return window(tr, offset, duration);
}

ScenarioEntity cityPedestrianEntity(const CityPedestrian& p, Trajectory window,
                                    const std::string& id) {
  ScenarioEntity se = movingEntity(id, EntityClass::kPedestrian, "pedestrian", std::move(window));
  Entity& en = se.entity;
  en.attributes.set("clothing_color", p.clothing_color);
  en.attributes.set("activity", p.activity);
  const TrajectoryPoint p0 = se.trajectory.empty() ? p.pose : se.trajectory.front();
  en.box = boxFromPose(Vec3(p0.x, p0.y, 0.0), p0.yaw, Vec3(0.5, 0.6, p.height));
  return se;
}

SignalPlan shiftedSignalPlan(const SignalPlan& plan, double offset) {
  SignalPlan out = plan;
  const double cyc = out.cycle();
  for (auto& i : out.intersections) {
    i.offset = roundMilli(std::fmod(std::fmod(i.offset - offset, cyc) + cyc, cyc));
    if (i.offset >= cyc) i.offset = 0.0;
  }
  return out;
}

namespace {

std::uint64_t episodeSeed(const World& world, int index) {
  return deriveSeed(world.params().seed, 0x43415252554EULL + static_cast<std::uint64_t>(index));
}

}  // namespace

std::shared_ptr<const SharedTrafficEpisode> cityTrafficEpisode(const World& world, int index,
                                                               const IdmParams& idm) {
  static EpisodeCache cache;
  char idm_key[300];
  std::snprintf(idm_key, sizeof(idm_key), "%.17g %.17g %.17g %.17g %.17g %.17g %.17g #%d",
                idm.time_gap, idm.min_gap, idm.max_accel, idm.comfort_decel, idm.yellow_stop_decel,
                idm.step, idm.warm_up, index);
  const std::string key = worldParamsJson(world.params()) + idm_key;
  std::shared_ptr<EpisodeSlot> slot;
  {
    std::lock_guard<std::mutex> lock(cache.mutex);
    for (const auto& [k, sl] : cache.slots) {
      if (k == key) slot = sl;
    }
    if (!slot) {
      slot = std::make_shared<EpisodeSlot>();
      if (cache.slots.size() >= 128) cache.slots.erase(cache.slots.begin());
      cache.slots.emplace_back(key, slot);
    }
  }
  // Each episode is simulated once, outside the cache's lock (others are simulated meanwhile).
  std::call_once(slot->once, [&] {
    const std::uint64_t seed = episodeSeed(world, index);
    TrafficEpisode e = runCars(world, seed, kTrafficEpisodeLength, idm);
    e.pedestrians = runPedestrians(world, e.plan, seed, kTrafficEpisodeLength);
    e.index = index;
    auto text = std::make_shared<const std::string>(trafficEpisodeJson(e));
    // Not parsed back from its bytes (that cost a third of an episode): made what a reader of
    // the file gets, so that it decodes exactly these trajectories.
    asItsFileReadsBack(&e);
    auto shared = decodedEpisode(std::move(e));
    shared->sha256 = sha256Hex(*text);
    shared->text = std::move(text);
    shared->clearance.reserve(shared->trajectories.size());
    for (std::size_t i = 0; i < shared->trajectories.size(); ++i) {
      MovingFootprint f;
      f.trajectory = &shared->trajectories[i];
      f.length = shared->episode.cars[i].size.x();
      f.width = shared->episode.cars[i].size.y();
      shared->clearance.push_back(clearanceBlocks(f));
    }
    if (!shared->clearance.empty()) shared->clearance_index = clearanceIndex(shared->clearance);
    slot->value = std::move(shared);
  });
  return slot->value;
}

namespace {

// The random stream of a scenario's traffic draw (drawCityTraffic).
Rng trafficDrawRng(std::uint64_t seed) { return Rng(deriveSeed(seed, 0x5045444553ULL)); }

// The first draw of a scenario's traffic: its episode.
int episodeDraw(Rng& rng, const CityParams& cp) {
  return static_cast<int>(rng.uniformInt(0, static_cast<long>(cp.traffic_episodes) - 1));
}

}  // namespace

int drawCityTrafficEpisode(const World& world, std::uint64_t seed) {
  Rng rng = trafficDrawRng(seed);
  return episodeDraw(rng, world.params().city);
}

CityTrafficDraw drawCityTraffic(const World& world, std::uint64_t seed, double duration,
                                const IdmParams& idm) {
  if (world.params().type != WorldType::kCity) {
    throw GenerationError("city traffic needs a city world");
  }
  if (!(duration > 0)) throw GenerationError("city traffic needs a positive duration");
  const CityParams& cp = world.params().city;
  CityTrafficDraw d;
  if (duration <= 0.5 * kTrafficEpisodeLength) {
    // A window of one of the world's episodes, starting at a time drawn for this scenario (in
    // the first half of the episode, whatever the duration); the signal offsets move with it.
    Rng rng = trafficDrawRng(seed);
    d.episode = episodeDraw(rng, cp);
    d.offset =
        roundMilli(idm.step * std::floor(rng.uniform(0.0, 0.5 * kTrafficEpisodeLength) / idm.step));
    d.plan = shiftedSignalPlan(citySignalPlan(world, episodeSeed(world, d.episode)), d.offset);
  } else {
    d.plan = citySignalPlan(world, seed);
  }
  return d;
}

CityTraffic simulateCityTraffic(const World& world, std::uint64_t seed, double duration,
                                const IdmParams& idm, bool trajectories) {
  const CityTrafficDraw draw = drawCityTraffic(world, seed, duration, idm);
  CityTraffic out;
  if (draw.episode >= 0) {
    out.episode = cityTrafficEpisode(world, draw.episode, idm);
    out.offset = draw.offset;
    out.plan = shiftedSignalPlan(out.episode->episode.plan, out.offset);
    const auto& ep = *out.episode;
    out.cars.resize(ep.trajectories.size());
    for (std::size_t i = 0; trajectories && i < ep.trajectories.size(); ++i) {
      out.cars[i].trajectory = window(ep.trajectories[i], out.offset, duration);
    }
  } else {
    // Longer than an episode's offset range: the scenario's own cars and crowd.
    TrafficEpisode e = runCars(world, seed, duration, idm);
    e.pedestrians = runPedestrians(world, e.plan, seed, duration);
    out.episode = decodedEpisode(std::move(e));
    out.plan = out.episode->episode.plan;
    for (const auto& tr : out.episode->trajectories) out.cars.push_back({tr});
  }
  const TrafficEpisode& e = out.episode->episode;
  const bool windows = trajectories || !out.episode->text;
  out.pedestrians.resize(e.pedestrians.size());
  for (std::size_t i = 0; i < e.pedestrians.size(); ++i) {
    const CityPedestrian& from = e.pedestrians[i];
    CityPedestrian& p = out.pedestrians[i];
    p.activity = from.activity;
    p.clothing_color = from.clothing_color;
    p.height = from.height;
    p.pose = from.pose;
    if (windows && !from.trajectory.empty()) {
      p.trajectory = window(from.trajectory, out.offset, duration);
    }
  }
  return out;
}

}  // namespace hameritt::scenario
