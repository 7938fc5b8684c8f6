#include "hameritt/clients/coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hameritt/scenario/error.h"

namespace hameritt::clients {

using geometry::Polygon;
using geometry::Vec2;
using geometry::Vec3;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string fmt(double v) { return scenario::formatNumber(v); }

const scenario::CameraSpec& findCamera(const scenario::UavSpec& uav, const std::string& name) {
  for (const auto& c : uav.cameras) {
    if (c.name == name) return c;
  }
  throw scenario::ConfigError("coverage.camera: no payload camera named '" + name + "'");
}

// A flight line: a polyline flown from front to back.
using Line = std::vector<Vec2>;

double lineLength(const Line& l) {
  double s = 0.0;
  for (std::size_t i = 1; i < l.size(); ++i) s += (l[i] - l[i - 1]).norm();
  return s;
}

// Keeps the part of a polygon (vertex list) where dot(p, n) >= c (Sutherland-Hodgman step).
std::vector<Vec2> clipHalfPlane(const std::vector<Vec2>& poly, const Vec2& n, double c) {
  std::vector<Vec2> out;
  const std::size_t k = poly.size();
  for (std::size_t i = 0; i < k; ++i) {
    const Vec2& a = poly[i];
    const Vec2& b = poly[(i + 1) % k];
    const double da = a.dot(n) - c, db = b.dot(n) - c;
    if (da >= 0) out.push_back(a);
    if ((da >= 0) != (db >= 0)) out.push_back(a + (b - a) * (da / (da - db)));
  }
  return out;
}

// Parallel offset of a polyline by `d` (left positive), mitred, mitre length capped at 3 |d|.
Line offsetPolyline(const std::vector<Vec2>& pts, double d) {
  Line out;
  const std::size_t n = pts.size();
  for (std::size_t i = 0; i < n; ++i) {
    Vec2 dir_in = i > 0 ? (pts[i] - pts[i - 1]).normalized() : Vec2::Zero();
    Vec2 dir_out = i + 1 < n ? (pts[i + 1] - pts[i]).normalized() : Vec2::Zero();
    if (i == 0) dir_in = dir_out;
    if (i + 1 == n) dir_out = dir_in;
    const Vec2 n_in(-dir_in.y(), dir_in.x()), n_out(-dir_out.y(), dir_out.x());
    Vec2 m = n_in + n_out;
    if (m.norm() < 1e-9) m = n_in;
    m.normalize();
    const double c = std::max(m.dot(n_out), 1.0 / 3.0);
    out.push_back(pts[i] + m * (d / c));
  }
  return out;
}

// A cell to sweep: the lines of its lawnmower pattern in their first flying order.
struct Cell {
  std::string id;
  double probability = 0.0;
  std::vector<Line> lines;
  Polygon area;  // for transit distances and staging
};

struct Region {
  std::string id;
  geometry::TimeWindow window;
  Polygon area;
  std::vector<Cell> cells;
};

// The four ways to fly a pattern: forward or reversed line order, each line as given or flipped.
std::vector<Line> variant(const std::vector<Line>& lines, int v) {
  std::vector<Line> out = lines;
  if (v & 1) std::reverse(out.begin(), out.end());
  if (v & 2) {
    for (auto& l : out) std::reverse(l.begin(), l.end());
  }
  return out;
}

double patternLength(const std::vector<Line>& lines) {
  double s = 0.0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    s += lineLength(lines[i]);
    if (i > 0) s += (lines[i].front() - lines[i - 1].back()).norm();
  }
  return s;
}

class Planner {
 public:
  Planner(const scenario::Mission& m, const CoverageSettings& s) : mission_(m), s_(s) {}

  // True when p at time t (estimated) lies too near a keep-out zone that matters at the
  // flight altitude around that time.
  bool blocked(const Vec2& p, double t) const {
    for (const auto& k : mission_.kozs) {
      if (k.alt_min && *k.alt_min > s_.altitude + kAltitudeMargin) continue;
      if (k.alt_max && *k.alt_max < s_.altitude - kAltitudeMargin) continue;
      if (!k.window.overlaps(t - s_.koz_time_slack, t + s_.koz_time_slack)) continue;
      if (k.polygon.distance(p) <= s_.koz_margin) return true;
    }
    return false;
  }

  // Waypoints of one pattern flown from `from`, leaving at max(t0, depart): lines cut around
  // keep-out zones, with arrival times.
  std::vector<SearchWaypoint> sweep(const std::vector<Line>& lines, const Vec2& from, double t0,
                                    double depart) const {
    t0 = std::max(t0, depart);
    // Cut each line into its free pieces, timing the unclipped pattern to decide which zones
    // are active where.
    struct Sample {
      Vec2 p;
      bool vertex;
      bool free;
    };
    std::vector<Line> pieces;
    Vec2 here = from;
    double t = t0;
    for (std::size_t li = 0; li < lines.size(); ++li) {
      const Line& line = lines[li];
      t += flightTime((line.front() - here).norm() * (li == 0 ? s_.detour_factor : 1.0),
                      s_.max_speed, s_.accel);
      std::vector<Sample> samples;
      samples.push_back({line.front(), true, !blocked(line.front(), t)});
      for (std::size_t i = 0; i + 1 < line.size(); ++i) {
        const Vec2 a = line[i], b = line[i + 1];
        const double len = (b - a).norm();
        const int n = std::max(1, static_cast<int>(std::ceil(len / s_.sample_step)));
        const double seg_t = flightTime(len, s_.max_speed, s_.accel);
        for (int j = 1; j <= n; ++j) {
          const double u = static_cast<double>(j) / n;
          const Vec2 p = a + (b - a) * u;
          samples.push_back({p, j == n, !blocked(p, t + seg_t * u)});
        }
        t += seg_t;
      }
      // A piece: the first and last samples of a free run and the line's vertices between.
      for (std::size_t i = 0; i < samples.size();) {
        if (!samples[i].free) {
          ++i;
          continue;
        }
        std::size_t j = i;
        while (j + 1 < samples.size() && samples[j + 1].free) ++j;
        Line piece{samples[i].p};
        for (std::size_t k = i + 1; k < j; ++k) {
          if (samples[k].vertex) piece.push_back(samples[k].p);
        }
        if (j > i) piece.push_back(samples[j].p);
        const bool whole_point_line = lineLength(line) < s_.min_line;
        if (lineLength(piece) >= s_.min_line || (whole_point_line && i == 0)) {
          pieces.push_back(std::move(piece));
        }
        i = j + 1;
      }
      here = line.back();
    }
    // Waypoints with arrival times (the follower stops at each waypoint).
    std::vector<SearchWaypoint> out;
    here = from;
    t = t0;
    for (const auto& piece : pieces) {
      for (const auto& p : piece) {
        if (!out.empty() && (p - here).norm() < 1e-6) continue;
        t += flightTime((p - here).norm() * (out.empty() ? s_.detour_factor : 1.0), s_.max_speed,
                        s_.accel);
        out.push_back({Vec3(p.x(), p.y(), s_.altitude), t});
        here = p;
      }
    }
    return out;
  }

  static constexpr double kAltitudeMargin = 1.5;

 private:
  const scenario::Mission& mission_;
  const CoverageSettings& s_;
};

std::vector<Region> buildRegions(const scenario::Mission& mission, const CoverageSettings& s) {
  std::vector<Region> regions;
  for (const auto& aoi : mission.aois) {
    Region r;
    r.id = aoi.id;
    r.window = aoi.window;
    r.area = aoi.polygon;
    const scenario::AreaPrior* prior = nullptr;
    for (const auto& p : mission.priors) {
      if (p.aoi_id == aoi.id) prior = &p;
    }
    if (prior && !prior->cells.empty()) {
      for (const auto& c : prior->cells) {
        r.cells.push_back({c.id, c.probability, {}, c.polygon});
      }
    } else {
      r.cells.push_back({aoi.id, 1.0, {}, aoi.polygon});
    }
    for (auto& c : r.cells) {
      for (const auto& [a, b] : lawnmowerLines(c.area, s.footprint, s.overlap)) {
        c.lines.push_back({a, b});
      }
    }
    regions.push_back(std::move(r));
  }
  for (const auto& route : mission.routes) {
    Region r;
    r.id = route.id;
    r.area = route.band;
    Cell c{route.id, 1.0, {}, route.band};
    const double spacing = s.footprint.across * (1.0 - s.overlap);
    const int k = std::max(1, static_cast<int>(std::ceil(route.band_width / spacing - 1e-9)));
    const double step = route.band_width / k;
    for (int i = 0; i < k; ++i) {
      Line l = offsetPolyline(route.polyline, -0.5 * route.band_width + (i + 0.5) * step);
      if (i % 2 == 1) std::reverse(l.begin(), l.end());
      c.lines.push_back(std::move(l));
    }
    r.cells.push_back(std::move(c));
    regions.push_back(std::move(r));
  }
  return regions;
}

}  // namespace

Footprint groundFootprint(const scenario::CameraSpec& camera, double height) {
  const double f = 0.5 * camera.width / std::tan(0.5 * geometry::degToRad(camera.hfov_deg));
  return {height * camera.width / f, height * camera.height / f};
}

double heightForPixels(const scenario::CameraSpec& camera, double size, double pixels) {
  const double f = 0.5 * camera.width / std::tan(0.5 * geometry::degToRad(camera.hfov_deg));
  return size * f / pixels;
}

WaypointRepairs clearWaypoints(SearchPlan* plan, const planning::WorldValidity& validity,
                               double above) {
  WaypointRepairs out;
  const double top = validity.settings().altitude_max;
  std::vector<SearchLeg> legs;
  for (SearchLeg& leg : plan->legs) {
    std::vector<SearchWaypoint> kept;
    for (SearchWaypoint w : leg.waypoints) {
      if (validity.staticValid(w.position)) {
        kept.push_back(w);
        continue;
      }
      Vec3 q = w.position;
      while (q.z() + 1.0 <= top && !validity.staticValid(q)) q.z() += 1.0;
      q.z() = std::min(q.z() + above, top);
      if (validity.staticValid(q)) {
        w.position = q;
        kept.push_back(w);
        ++out.lifted;
      } else {
        ++out.dropped;
      }
    }
    leg.waypoints = std::move(kept);
    if (!leg.waypoints.empty()) legs.push_back(std::move(leg));
  }
  plan->legs = std::move(legs);
  return out;
}

double flightTime(double distance, double max_speed, double accel) {
  if (distance <= 0) return 0.0;
  const double ramp = max_speed * max_speed / accel;  // distance to speed up and brake
  if (distance < ramp) return 2.0 * std::sqrt(distance / accel);
  return distance / max_speed + max_speed / accel;
}

void CoverageSettings::validate() const {
  auto need = [](bool ok, const char* field, const std::string& what, double v) {
    if (!ok) {
      throw scenario::ConfigError(std::string("coverage.") + field + ": expected " + what +
                                  ", got " + fmt(v));
    }
  };
  need(altitude > 0 && std::isfinite(altitude), "altitude", "metres > 0", altitude);
  need(footprint.across > 0 && std::isfinite(footprint.across), "footprint.across", "metres > 0",
       footprint.across);
  need(footprint.along > 0 && std::isfinite(footprint.along), "footprint.along", "metres > 0",
       footprint.along);
  need(overlap >= 0 && overlap <= 0.9, "overlap", "a fraction in [0, 0.9]", overlap);
  need(max_speed > 0, "max_speed", "m/s > 0", max_speed);
  need(accel > 0, "accel", "m/s^2 > 0", accel);
  need(climb_rate > 0, "climb_rate", "m/s > 0", climb_rate);
  need(detour_factor >= 1, "detour_factor", "a factor >= 1", detour_factor);
  need(koz_margin >= 0, "koz_margin", "metres >= 0", koz_margin);
  need(koz_time_slack >= 0, "koz_time_slack", "seconds >= 0", koz_time_slack);
  need(sample_step > 0, "sample_step", "metres > 0", sample_step);
  need(min_line >= 0, "min_line", "metres >= 0", min_line);
  need(window_margin >= 0, "window_margin", "seconds >= 0", window_margin);
  need(max_leg_waypoints >= 2, "max_leg_waypoints", "an integer >= 2", max_leg_waypoints);
}

CoverageSettings coverageSettingsFor(const scenario::UavSpec& uav, const std::string& camera,
                                     double altitude, double min_car_pixels, double car_width,
                                     double band_margin) {
  const scenario::CameraSpec& cam = findCamera(uav, camera);
  CoverageSettings s;
  const double lo = uav.altitude_min + band_margin, hi = uav.altitude_max - band_margin;
  if (altitude <= 0) {
    if (!(min_car_pixels > 0)) {
      throw scenario::ConfigError("coverage.min_car_pixels: expected pixels > 0, got " +
                                  fmt(min_car_pixels));
    }
    altitude = std::clamp(heightForPixels(cam, car_width, min_car_pixels), lo, std::max(lo, hi));
  } else if (altitude < uav.altitude_min || altitude > uav.altitude_max) {
    throw scenario::ConfigError("coverage.altitude: expected a height inside the altitude band [" +
                                fmt(uav.altitude_min) + ", " + fmt(uav.altitude_max) + "], got " +
                                fmt(altitude));
  }
  s.altitude = altitude;
  s.footprint = groundFootprint(cam, altitude);
  s.max_speed = uav.max_speed;
  s.validate();
  return s;
}

std::vector<std::pair<Vec2, Vec2>> lawnmowerLines(const Polygon& polygon,
                                                  const Footprint& footprint, double overlap) {
  const auto& v = polygon.vertices();
  std::vector<std::pair<Vec2, Vec2>> out;
  if (v.size() < 3) return out;
  // Lines along the longest edge: fewest turns for a rectangle-like cell.
  Vec2 d(1, 0);
  double longest = -1.0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const Vec2 e = v[(i + 1) % v.size()] - v[i];
    if (e.norm() > longest + 1e-9) {
      longest = e.norm();
      d = e.normalized();
    }
  }
  const Vec2 n(-d.y(), d.x());
  double cmin = kInf, cmax = -kInf;
  for (const auto& p : v) {
    cmin = std::min(cmin, p.dot(n));
    cmax = std::max(cmax, p.dot(n));
  }
  const double spacing = footprint.across * (1.0 - overlap);
  const double width = cmax - cmin;
  const int k = std::max(1, static_cast<int>(std::ceil(width / spacing - 1e-9)));
  const double step = width / k;
  const double half_along = 0.5 * footprint.along;
  for (int i = 0; i < k; ++i) {
    const double lo = cmin + i * step, hi = cmin + (i + 1) * step;
    // The strip this line is responsible for, and its extent along the line.
    std::vector<Vec2> strip = clipHalfPlane(v, n, lo - 1e-9);
    strip = clipHalfPlane(strip, -n, -(hi + 1e-9));
    if (strip.empty()) continue;
    double amin = kInf, amax = -kInf;
    for (const auto& p : strip) {
      amin = std::min(amin, p.dot(d));
      amax = std::max(amax, p.dot(d));
    }
    double a0 = amin + half_along, a1 = amax - half_along;
    if (a0 > a1) a0 = a1 = 0.5 * (amin + amax);
    const double o = 0.5 * (lo + hi);
    Vec2 p0 = d * a0 + n * o, p1 = d * a1 + n * o;
    if (i % 2 == 1) std::swap(p0, p1);
    out.emplace_back(p0, p1);
  }
  return out;
}

SearchPlan planSearch(const scenario::Mission& mission, const CoverageSettings& settings,
                      const SearchProgress& progress) {
  settings.validate();
  SearchPlan plan;
  plan.line_spacing = settings.footprint.across * (1.0 - settings.overlap);
  std::vector<Region> regions = buildRegions(mission, settings);
  const Planner planner(mission, settings);
  const double time_limit = mission.time_limit > 0 ? mission.time_limit : kInf;

  Vec2 pos = progress.position.head<2>();
  double t = progress.time;
  if (progress.position.z() < settings.altitude - 1.0) {
    t += (settings.altitude - progress.position.z()) / settings.climb_rate;
  }
  std::set<std::string> done = progress.covered_cells;
  auto eligible = [&](const Cell& c) {
    return !done.count(c.id) && !c.lines.empty() &&
           (c.probability > 0 || settings.cover_zero_cells);
  };
  auto transit = [&](const Vec2& to) {
    return flightTime((to - pos).norm() * settings.detour_factor, settings.max_speed,
                      settings.accel);
  };

  for (;;) {
    // The region whose search can start first.
    const Region* best = nullptr;
    double best_start = kInf, best_close = kInf;
    for (const auto& r : regions) {
      if (std::none_of(r.cells.begin(), r.cells.end(), eligible)) continue;
      const double arrival = t + flightTime(r.area.distance(pos) * settings.detour_factor,
                                            settings.max_speed, settings.accel);
      const double start = std::max(arrival, r.window.net.value_or(-kInf));
      const double close = std::min(r.window.nlt.value_or(kInf), time_limit);
      if (start > close) {
        for (const auto& c : r.cells) {
          if (eligible(c)) {
            plan.skipped.push_back(c.id + ": " + r.id + " cannot be reached before " + fmt(close) +
                                   " s");
            done.insert(c.id);
          }
        }
        continue;
      }
      if (start < best_start - 1e-9 ||
          (std::abs(start - best_start) <= 1e-9 && close < best_close)) {
        best = &r;
        best_start = start;
        best_close = close;
      }
    }
    if (!best) break;
    const Region& r = *best;
    const double close = best_close;
    bool staged = false, waiting = false;
    // Greedy over the region's cells: probability per metre flown.
    for (;;) {
      const Cell* cell = nullptr;
      std::vector<Line> lines;
      double best_score = 0.0;
      for (const auto& c : r.cells) {
        if (!eligible(c)) continue;
        for (int v = 0; v < 4; ++v) {
          std::vector<Line> ls = variant(c.lines, v);
          const double cost =
              (ls.front().front() - pos).norm() * settings.detour_factor + patternLength(ls) + 1.0;
          // Probability gathered per metre; cells of probability 0 (when swept at all) after
          // every other, nearest first.
          const double score = c.probability > 0 ? c.probability / cost : -cost;
          const double tol = 1e-9 * std::max(std::abs(score), std::abs(best_score));
          bool better = !cell || score > best_score + tol;
          if (cell && std::abs(score - best_score) <= tol) {
            better = c.probability != cell->probability ? c.probability > cell->probability
                                                        : c.id < cell->id;
          }
          if (better) {
            cell = &c;
            lines = std::move(ls);
            best_score = score;
          }
        }
      }
      if (!cell) break;
      done.insert(cell->id);
      const double net = r.window.net.value_or(-kInf);
      const Vec2 entry = lines.front().front();
      if (!staged && t + transit(entry) < net + settings.window_margin) {
        // Early, or nearly: wait just outside the region, near the entry, until it opens.
        Vec2 stage = entry;
        const Vec2 c = r.area.centroid();
        Vec2 out = entry - c;
        if (out.norm() > 1e-6) {
          out.normalize();
          Vec2 q = entry;
          for (int i = 0; i < 400 && r.area.contains(q); ++i) q += out * 1.0;
          q += out * 10.0;
          if (!planner.blocked(q, t + transit(q))) stage = q;
        }
        SearchLeg leg;
        leg.kind = LegKind::kStage;
        leg.region_id = r.id;
        leg.cell_id = cell->id;
        leg.probability = cell->probability;
        leg.completes_cell = false;
        const double eta = t + transit(stage);
        leg.waypoints.push_back({Vec3(stage.x(), stage.y(), settings.altitude), eta});
        plan.legs.push_back(leg);
        pos = stage;
        t = eta;
        waiting = true;
      }
      staged = true;
      // After a stage leg the sweep leaves the stage point when the window opens.
      std::vector<SearchWaypoint> wps = planner.sweep(lines, pos, t, waiting ? net : -kInf);
      if (wps.empty()) {
        plan.skipped.push_back(cell->id + ": every line lies in a keep-out zone");
        continue;
      }
      // The window (or the mission) ends: drop what would be flown after it.
      std::size_t keep = 0;
      while (keep < wps.size() && wps[keep].eta <= close) ++keep;
      if (keep < wps.size()) {
        plan.skipped.push_back(cell->id + ": " + std::to_string(wps.size() - keep) + " of " +
                               std::to_string(wps.size()) + " waypoints after " + fmt(close) +
                               " s (" + r.id + " window or time limit)");
      }
      wps.resize(keep);
      if (wps.empty()) break;  // nothing more fits in this region's window
      const std::size_t chunk = static_cast<std::size_t>(settings.max_leg_waypoints);
      for (std::size_t i = 0; i < wps.size(); i += chunk) {
        SearchLeg leg;
        leg.kind = LegKind::kCover;
        leg.region_id = r.id;
        leg.cell_id = cell->id;
        leg.probability = cell->probability;
        leg.not_before = i == 0 && waiting ? std::max(net, 0.0) : 0.0;
        leg.waypoints.assign(wps.begin() + static_cast<long>(i),
                             wps.begin() + static_cast<long>(std::min(wps.size(), i + chunk)));
        leg.completes_cell = i + chunk >= wps.size();
        plan.legs.push_back(std::move(leg));
      }
      waiting = false;
      pos = wps.back().position.head<2>();
      t = wps.back().eta;
      if (t >= close) break;
    }
    // Whatever is left of this region could not be fitted into its window.
    for (const auto& c : r.cells) {
      if (eligible(c)) {
        plan.skipped.push_back(c.id + ": no time left in " + r.id + "'s window");
        done.insert(c.id);
      }
    }
  }
  return plan;
}

}  // namespace hameritt::clients
