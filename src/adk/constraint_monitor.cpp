#include "hameritt/adk/constraint_monitor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <tuple>

#include "hameritt/geometry/segment.h"
#include "hameritt/scenario/error.h"

namespace hameritt::adk {

using geometry::cross2;
using geometry::Vec2;
using geometry::Vec3;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Parameter tolerance for an intersection that lands a hair outside an edge or the segment
// (a segment through a vertex meets both edges there, each at 0 or 1 up to rounding).
constexpr double kParamTol = 1e-9;

double clamp01(double u) { return u < 0.0 ? 0.0 : (u > 1.0 ? 1.0 : u); }

// Parameter interval of [0, 1] where z0 + u (z1 - z0) lies in [lo, hi]; lo > hi when none.
Interval clipLinear(double z0, double z1, double lo, double hi) {
  const double dz = z1 - z0;
  if (dz == 0.0) return (z0 >= lo && z0 <= hi) ? Interval{0.0, 1.0} : Interval{1.0, 0.0};
  double u_lo = (lo - z0) / dz, u_hi = (hi - z0) / dz;
  if (dz < 0.0) std::swap(u_lo, u_hi);
  return {std::max(0.0, u_lo), std::min(1.0, u_hi)};
}

// Mission time at parameter u of a segment from ta to tb; exact at both ends.
double timeAt(double u, double ta, double tb) {
  if (u <= 0.0) return ta;
  if (u >= 1.0) return tb;
  return std::min(tb, ta + u * (tb - ta));
}

Interval windowInterval(const geometry::TimeWindow& w) {
  return {w.net ? *w.net : -kInf, w.nlt ? *w.nlt : kInf};
}

std::vector<Interval> toTime(const std::vector<Interval>& u, double ta, double tb) {
  std::vector<Interval> out;
  out.reserve(u.size());
  for (const auto& i : u) out.push_back({timeAt(i.lo, ta, tb), timeAt(i.hi, ta, tb)});
  return out;
}

std::vector<Interval> clipTo(const std::vector<Interval>& in, const Interval& w) {
  std::vector<Interval> out;
  for (const auto& i : in) {
    const Interval c = intersect(i, w);
    if (c.lo <= c.hi) out.push_back(c);
  }
  return out;
}

std::vector<Interval> prismParams(const scenario::KeepOutZone& zone, const Vec3& a, const Vec3& b) {
  const Interval band = clipLinear(a.z(), b.z(), zone.alt_min ? *zone.alt_min : -kInf,
                                   zone.alt_max ? *zone.alt_max : kInf);
  if (band.lo > band.hi) return {};
  return clipTo(segmentInsidePolygon(zone.polygon, a.head<2>(), b.head<2>()), band);
}

// An event with its sort key: time, then the zone's order, then the kind's order at one
// instant (enter, violation start, violation end, exit).
struct Keyed {
  double t;
  std::size_t zone;
  int rank;
  ConstraintEvent event;
};

int rankOf(ConstraintEvent::Kind k) {
  switch (k) {
    case ConstraintEvent::Kind::kEnter:
      return 0;
    case ConstraintEvent::Kind::kViolationStart:
      return 1;
    case ConstraintEvent::Kind::kViolationEnd:
      return 2;
    case ConstraintEvent::Kind::kExit:
      return 3;
  }
  return 4;
}

}  // namespace

const char* toString(ConstraintEvent::Kind k) {
  switch (k) {
    case ConstraintEvent::Kind::kEnter:
      return "enter";
    case ConstraintEvent::Kind::kExit:
      return "exit";
    case ConstraintEvent::Kind::kViolationStart:
      return "violation_start";
    case ConstraintEvent::Kind::kViolationEnd:
      return "violation_end";
  }
  return "?";
}

std::vector<Interval> segmentInsidePolygon(const geometry::Polygon& polygon, const Vec2& a,
                                           const Vec2& b) {
  std::vector<Interval> out;
  const auto& v = polygon.vertices();
  if (v.size() < 3) return out;
  const Vec2 d = b - a;
  const double dd = d.squaredNorm();
  if (dd == 0.0) {
    if (polygon.contains(a)) out.push_back({0.0, 1.0});
    return out;
  }
  const double len = std::sqrt(dd);
  // Breakpoints: the ends (classified by containment) and every intersection with an edge
  // (on the boundary, hence inside by definition).
  struct Break {
    double u;
    bool boundary;
  };
  std::vector<Break> breaks{{0.0, false}, {1.0, false}};
  for (std::size_t i = 0; i < v.size(); ++i) {
    const Vec2& c = v[i];
    const Vec2& e = v[i + 1 == v.size() ? 0 : i + 1];
    const Vec2 f = e - c;
    const double flen = f.norm();
    if (flen == 0.0) continue;
    const Vec2 w = c - a;
    // A vertex on the segment is a breakpoint whatever the angle of its edges: for an edge
    // almost parallel to the segment the line intersection below is ill-conditioned and may
    // miss it, and the walk would then carry "inside" past the vertex (a sliver zone crossed
    // along an edge; found by test_geometry_oracle.py against Shapely).
    const double vertex_scale =
        std::max({1.0, std::fabs(a.x()), std::fabs(a.y()), std::fabs(c.x()), std::fabs(c.y())});
    if (geometry::pointSegmentDistance(c, a, b) <= geometry::kEpsilon * vertex_scale) {
      breaks.push_back({clamp01(w.dot(d) / dd), true});
    }
    const double denom = cross2(d, f);
    if (std::fabs(denom) > 1e-12 * len * flen) {
      const double u = cross2(w, f) / denom;  // along the segment
      const double s = cross2(w, d) / denom;  // along the edge
      if (u >= -kParamTol && u <= 1.0 + kParamTol && s >= -kParamTol && s <= 1.0 + kParamTol) {
        breaks.push_back({clamp01(u), true});
      }
    } else {
      // Parallel: collinear when c lies on the segment's line; the overlap's ends are the
      // edge's ends projected onto the segment.
      const double offset = std::fabs(cross2(w, d)) / len;
      const double scale =
          std::max({1.0, std::fabs(a.x()), std::fabs(a.y()), std::fabs(c.x()), std::fabs(c.y())});
      if (offset <= geometry::kEpsilon * scale) {
        for (const Vec2& p : {c, e}) {
          const double u = (p - a).dot(d) / dd;
          if (u >= -kParamTol && u <= 1.0 + kParamTol) breaks.push_back({clamp01(u), true});
        }
      }
    }
  }
  std::sort(breaks.begin(), breaks.end(), [](const Break& x, const Break& y) { return x.u < y.u; });
  // Merge equal parameters.
  std::vector<Break> pts;
  for (const auto& br : breaks) {
    if (!pts.empty() && br.u == pts.back().u) {
      pts.back().boundary = pts.back().boundary || br.boundary;
    } else {
      pts.push_back(br);
    }
  }
  auto at = [&](double u) -> Vec2 { return a + d * u; };
  // Walk breakpoint, gap, breakpoint, ...; a run of inside elements is one interval.
  bool open = false;
  double lo = 0.0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const bool in_pt = pts[i].boundary || polygon.contains(at(pts[i].u));
    if (in_pt && !open) {
      open = true;
      lo = pts[i].u;
    } else if (!in_pt && open) {
      // The gap before was inside: the run's supremum is this breakpoint.
      open = false;
      out.push_back({lo, pts[i].u});
    }
    if (i + 1 < pts.size()) {
      const bool in_gap = polygon.contains(at(0.5 * (pts[i].u + pts[i + 1].u)));
      if (in_gap && !open) {
        open = true;
        lo = pts[i].u;
      } else if (!in_gap && open) {
        open = false;
        out.push_back({lo, pts[i].u});
      }
    }
  }
  if (open) out.push_back({lo, pts.back().u});
  return out;
}

std::vector<Interval> prismIntervals(const scenario::KeepOutZone& zone, const Vec3& a,
                                     const Vec3& b, double ta, double tb) {
  if (zone.motion.empty()) return toTime(prismParams(zone, a, b), ta, tb);
  // A moving zone stands where it is at the middle of the step (samples come at the state
  // rate, over which a zone escorting a car moves a metre or two).
  scenario::KeepOutZone here = zone;
  here.polygon = scenario::kozPolygonAt(zone, 0.5 * (ta + tb));
  here.motion.clear();
  return toTime(prismParams(here, a, b), ta, tb);
}

std::vector<Interval> violationIntervals(const scenario::KeepOutZone& zone, const Vec3& a,
                                         const Vec3& b, double ta, double tb) {
  return clipTo(prismIntervals(zone, a, b, ta, tb), windowInterval(zone.window));
}

ConstraintMonitor::ConstraintMonitor(const scenario::Mission& mission) {
  for (const auto& k : mission.kozs) zones_.push_back(ZoneTrack{k, false, false, {}});
  for (const auto& a : mission.aois) {
    AreaTrack t{a, AoiStatus{}};
    t.status.id = a.id;
    areas_.push_back(std::move(t));
  }
}

std::vector<ConstraintEvent> ConstraintMonitor::add(double t, const Vec3& p) {
  const std::string which = "sample " + std::to_string(samples_);
  if (!std::isfinite(t)) {
    throw InputError(which + ": time: expected a finite number, got " + scenario::formatNumber(t));
  }
  if (!p.allFinite()) {
    throw InputError(which + ": position: expected finite x, y, z, got (" +
                     scenario::formatNumber(p.x()) + ", " + scenario::formatNumber(p.y()) + ", " +
                     scenario::formatNumber(p.z()) + ")");
  }
  if (samples_ > 0 && !(t > last_t_)) {
    throw InputError(which + ": time: expected a time after the previous sample's " +
                     scenario::formatNumber(last_t_) + ", got " + scenario::formatNumber(t));
  }
  std::vector<ConstraintEvent> events;
  if (samples_ == 0) {
    segment(p, p, t, t, &events);
  } else {
    segment(last_p_, p, last_t_, t, &events);
  }
  ++samples_;
  last_t_ = t;
  last_p_ = p;
  return events;
}

void ConstraintMonitor::segment(const Vec3& a, const Vec3& b, double ta, double tb,
                                std::vector<ConstraintEvent>* events) {
  std::vector<Keyed> keyed;
  auto position = [&](double t) -> Vec3 {
    if (tb <= ta) return a;
    if (t >= tb) return b;
    return a + (b - a) * ((t - ta) / (tb - ta));
  };
  // Emits the start and end events of `intervals` (time order, within [ta, tb]) given whether
  // the UAV was inside at ta; updates that state to whether it is inside at tb.
  auto transitions = [&](const std::vector<Interval>& intervals, bool* state, std::size_t zone,
                         ConstraintEvent proto, ConstraintEvent::Kind start,
                         ConstraintEvent::Kind end, const geometry::TimeWindow& window) {
    auto emit = [&](ConstraintEvent::Kind kind, double t) {
      ConstraintEvent e = proto;
      e.kind = kind;
      e.t = t;
      e.position = position(t);
      e.active = window.active(t);
      keyed.push_back({t, zone, rankOf(kind), e});
    };
    bool inside = *state;
    for (std::size_t i = 0; i < intervals.size(); ++i) {
      const Interval& iv = intervals[i];
      const bool continues = inside && i == 0 && iv.lo <= ta;
      if (inside && !continues) {
        // Rounding disagreed about the shared sample; close the run there.
        emit(end, ta);
        inside = false;
      }
      if (!continues) emit(start, iv.lo);
      if (iv.hi < tb) {
        emit(end, iv.hi);
        inside = false;
      } else {
        inside = true;
      }
    }
    if (intervals.empty() && inside) {
      emit(end, ta);
      inside = false;
    }
    *state = inside;
  };

  for (std::size_t zi = 0; zi < zones_.size(); ++zi) {
    ZoneTrack& z = zones_[zi];
    const std::vector<Interval> prism = prismIntervals(z.zone, a, b, ta, tb);
    const std::vector<Interval> viol = clipTo(prism, windowInterval(z.zone.window));
    for (const auto& v : viol) {
      if (!z.violations.empty() && v.lo <= z.violations.back().t_exit) {
        z.violations.back().t_exit = std::max(z.violations.back().t_exit, v.hi);
      } else {
        z.violations.push_back(Violation{z.zone.id, z.zone.purpose, v.lo, v.hi, false});
      }
    }
    ConstraintEvent proto;
    proto.keep_out_zone = true;
    proto.id = z.zone.id;
    proto.purpose = z.zone.purpose;
    transitions(prism, &z.in_prism, zi, proto, ConstraintEvent::Kind::kEnter,
                ConstraintEvent::Kind::kExit, z.zone.window);
    transitions(viol, &z.violating, zi, proto, ConstraintEvent::Kind::kViolationStart,
                ConstraintEvent::Kind::kViolationEnd, z.zone.window);
  }
  for (std::size_t ai = 0; ai < areas_.size(); ++ai) {
    AreaTrack& area = areas_[ai];
    const std::vector<Interval> inside =
        toTime(segmentInsidePolygon(area.area.polygon, a.head<2>(), b.head<2>()), ta, tb);
    for (const auto& i : inside) area.status.time_inside += i.length();
    for (const auto& i : clipTo(inside, windowInterval(area.area.window))) {
      area.status.time_inside_active += i.length();
    }
    ConstraintEvent proto;
    proto.keep_out_zone = false;
    proto.id = area.area.id;
    const std::size_t before = keyed.size();
    transitions(inside, &area.status.inside, zones_.size() + ai, proto,
                ConstraintEvent::Kind::kEnter, ConstraintEvent::Kind::kExit, area.area.window);
    for (std::size_t k = before; k < keyed.size(); ++k) {
      if (keyed[k].event.kind == ConstraintEvent::Kind::kEnter) ++area.status.entries;
    }
  }
  std::stable_sort(keyed.begin(), keyed.end(), [](const Keyed& x, const Keyed& y) {
    return std::tie(x.t, x.zone, x.rank) < std::tie(y.t, y.zone, y.rank);
  });
  for (auto& k : keyed) events->push_back(std::move(k.event));
}

std::vector<Violation> ConstraintMonitor::violations() const {
  std::vector<std::pair<std::size_t, Violation>> all;
  for (std::size_t zi = 0; zi < zones_.size(); ++zi) {
    const ZoneTrack& z = zones_[zi];
    for (std::size_t i = 0; i < z.violations.size(); ++i) {
      Violation v = z.violations[i];
      v.ongoing = z.violating && i + 1 == z.violations.size();
      all.emplace_back(zi, v);
    }
  }
  std::stable_sort(all.begin(), all.end(), [](const auto& x, const auto& y) {
    return std::tie(x.second.t_enter, x.first) < std::tie(y.second.t_enter, y.first);
  });
  std::vector<Violation> out;
  out.reserve(all.size());
  for (auto& p : all) out.push_back(std::move(p.second));
  return out;
}

double ConstraintMonitor::violationDuration() const {
  double d = 0.0;
  for (const auto& z : zones_) {
    for (const auto& v : z.violations) d += v.duration();
  }
  return d;
}

std::size_t ConstraintMonitor::violationCount() const {
  std::size_t n = 0;
  for (const auto& z : zones_) n += z.violations.size();
  return n;
}

std::vector<ZoneStatus> ConstraintMonitor::zones() const {
  std::vector<ZoneStatus> out;
  for (const auto& z : zones_) {
    ZoneStatus s;
    s.id = z.zone.id;
    s.purpose = z.zone.purpose;
    s.inside = z.in_prism;
    s.active = samples_ > 0 && z.zone.window.active(last_t_);
    s.violating = z.violating;
    out.push_back(s);
  }
  return out;
}

std::vector<AoiStatus> ConstraintMonitor::areas() const {
  std::vector<AoiStatus> out;
  for (const auto& a : areas_) {
    AoiStatus s = a.status;
    s.active = samples_ > 0 && a.area.window.active(last_t_);
    out.push_back(s);
  }
  return out;
}

}  // namespace hameritt::adk
