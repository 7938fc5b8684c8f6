// Coverage search: footprint geometry, lawnmower coverage, prior order, keep-out zones and
// windows, on the shipped scenario and on small hand-made missions.
#include "hameritt/clients/coverage.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "hameritt/clients/public_config.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/rng.h"
#include "hameritt/scenario/world.h"
#include "../scenario/test_util.h"

namespace hameritt::clients {
namespace {

using geometry::Polygon;
using geometry::Vec2;
using geometry::Vec3;

const char* kMission = "scenarios/default/mission.json";
const char* kSimConfig = "scenarios/default/sim_config.json";

const scenario::UavSpec& defaultUav() {
  static const scenario::SimConfig sim = loadPublicSimConfig(kSimConfig);
  return sim.uav;
}

// True when p lies in the swath of the segment [a, b]: the segment's Minkowski sum with the
// footprint rectangle, turned along the segment (the camera's yaw follows the flight).
bool inSwath(const Vec2& p, const Vec2& a, const Vec2& b, const Footprint& f) {
  const Vec2 d = b - a;
  const double len = d.norm();
  const Vec2 u = len > 1e-9 ? Vec2(d / len) : Vec2(1, 0);
  const Vec2 n(-u.y(), u.x());
  const double along = (p - a).dot(u), across = (p - a).dot(n);
  const double eps = 1e-6;
  if (len <= 1e-9) {
    // A single point: either orientation of the footprint.
    return (std::abs(along) <= 0.5 * f.along + eps && std::abs(across) <= 0.5 * f.across + eps);
  }
  return std::abs(across) <= 0.5 * f.across + eps && along >= -0.5 * f.along - eps &&
         along <= len + 0.5 * f.along + eps;
}

// Sample points of a polygon on a grid of `step` metres.
std::vector<Vec2> samples(const Polygon& poly, double step) {
  std::vector<Vec2> out;
  const auto b = poly.bounds();
  for (double x = b.min.x() + 0.5 * step; x < b.max.x(); x += step) {
    for (double y = b.min.y() + 0.5 * step; y < b.max.y(); y += step) {
      if (poly.contains(Vec2(x, y))) out.emplace_back(x, y);
    }
  }
  for (const auto& v : poly.vertices()) out.push_back(v);
  return out;
}

// The flight segments of each cell's sweep (consecutive waypoints of its cover legs).
std::map<std::string, std::vector<std::pair<Vec2, Vec2>>> sweeps(const SearchPlan& plan) {
  std::map<std::string, std::vector<std::pair<Vec2, Vec2>>> out;
  std::map<std::string, Vec2> last;
  for (const auto& leg : plan.legs) {
    if (leg.kind != LegKind::kCover) continue;
    for (const auto& w : leg.waypoints) {
      const Vec2 p = w.position.head<2>();
      auto it = last.find(leg.cell_id);
      out[leg.cell_id].emplace_back(it == last.end() ? p : it->second, p);
      last[leg.cell_id] = p;
    }
  }
  return out;
}

bool covered(const Vec2& p, const std::vector<std::pair<Vec2, Vec2>>& segs, const Footprint& f) {
  for (const auto& [a, b] : segs) {
    if (inSwath(p, a, b, f)) return true;
  }
  return false;
}

// A square AOI centred at c, side 2 h, with a 2x2 prior (row-major probabilities).
scenario::Mission squareMission(const Vec2& c, double h, const std::vector<double>& p) {
  scenario::Mission m;
  m.scenario_id = "test";
  m.time_limit = 10000;
  scenario::AreaOfInterest aoi;
  aoi.id = "aoi_1";
  aoi.polygon = geometry::rectangle(c - Vec2(h, h), c + Vec2(h, h));
  m.aois.push_back(aoi);
  scenario::AreaPrior prior;
  prior.aoi_id = "aoi_1";
  for (int r = 0; r < 2; ++r) {
    for (int k = 0; k < 2; ++k) {
      scenario::PriorCell cell;
      cell.row = r;
      cell.col = k;
      cell.id = "aoi_1_r" + std::to_string(r) + "c" + std::to_string(k);
      const Vec2 lo = c + Vec2(k == 0 ? -h : 0, r == 0 ? -h : 0);
      cell.polygon = geometry::rectangle(lo, lo + Vec2(h, h));
      cell.probability = p[static_cast<std::size_t>(2 * r + k)];
      prior.cells.push_back(cell);
    }
  }
  m.priors.push_back(prior);
  return m;
}

CoverageSettings defaultSettings() { return coverageSettingsFor(defaultUav(), "down"); }

TEST(Coverage, FootprintFromTheCameraAndDefaultAltitudeKeepsCarsAt25Pixels) {
  const auto& uav = defaultUav();
  const scenario::CameraSpec* down = nullptr;
  for (const auto& c : uav.cameras) {
    if (c.name == "down") down = &c;
  }
  ASSERT_NE(down, nullptr);
  const Footprint f = groundFootprint(*down, 40.0);
  EXPECT_NEAR(f.across, 2 * 40.0 * std::tan(geometry::degToRad(down->hfov_deg) / 2), 1e-9);
  EXPECT_NEAR(f.along / f.across, static_cast<double>(down->height) / down->width, 1e-12);

  const CoverageSettings s = defaultSettings();
  EXPECT_GE(s.altitude, uav.altitude_min);
  EXPECT_LE(s.altitude, uav.altitude_max);
  const double fx = 0.5 * down->width / std::tan(geometry::degToRad(down->hfov_deg) / 2);
  EXPECT_GE(1.8 * fx / s.altitude, 25.0 - 1e-6);  // a car's width in pixels
  EXPECT_NEAR(s.footprint.across, groundFootprint(*down, s.altitude).across, 1e-9);

  EXPECT_THROW(coverageSettingsFor(uav, "down", uav.altitude_max + 1), scenario::ConfigError);
  EXPECT_THROW(coverageSettingsFor(uav, "belly"), scenario::ConfigError);
  CoverageSettings bad = s;
  bad.overlap = 1.5;
  EXPECT_THROW(bad.validate(), scenario::ConfigError);
}

TEST(Coverage, LawnmowerSwathsCoverRandomQuadrilaterals) {
  scenario::Rng rng(7);
  const Footprint f{40.0, 30.0};
  for (int trial = 0; trial < 50; ++trial) {
    // A jittered, rotated rectangle-like convex quadrilateral.
    const double w = rng.uniform(10, 150), h = rng.uniform(10, 150), yaw = rng.uniform(-3, 3);
    std::vector<Vec2> v;
    const Vec2 corners[4] = {{-w / 2, -h / 2}, {w / 2, -h / 2}, {w / 2, h / 2}, {-w / 2, h / 2}};
    for (const auto& c : corners) {
      const Vec2 j = c + Vec2(rng.uniform(-3, 3), rng.uniform(-3, 3));
      v.emplace_back(std::cos(yaw) * j.x() - std::sin(yaw) * j.y(),
                     std::sin(yaw) * j.x() + std::cos(yaw) * j.y());
    }
    const Polygon poly(v);
    const auto lines = lawnmowerLines(poly, f, 0.2);
    ASSERT_FALSE(lines.empty());
    for (const auto& p : samples(poly, 2.0)) {
      bool in = false;
      for (const auto& [a, b] : lines) in = in || inSwath(p, a, b, f);
      ASSERT_TRUE(in) << "trial " << trial << " point " << p.transpose();
    }
    // Neighbouring lines overlap by at least 20 %.
    for (std::size_t i = 1; i < lines.size(); ++i) {
      const Vec2 u = (lines[0].second - lines[0].first).normalized();
      const Vec2 n(-u.y(), u.x());
      const double gap = std::abs((lines[i].first - lines[i - 1].first).dot(n));
      EXPECT_LE(gap, f.across * 0.8 + 1e-9);
    }
  }
}

TEST(Coverage, EveryCellWithPositiveProbabilityIsSwept) {
  scenario::Mission m = scenario::loadMission(kMission);
  m.kozs.clear();
  for (auto& a : m.aois) a.window = {};
  m.time_limit = 1e6;
  const CoverageSettings s = defaultSettings();
  const SearchPlan plan = planSearch(m, s, {Vec3(-279.147, -258.585, 0), 0.0, {}});
  EXPECT_TRUE(plan.skipped.empty()) << plan.skipped.front();
  const auto swept = sweeps(plan);
  int cells = 0;
  for (const auto& prior : m.priors) {
    for (const auto& cell : prior.cells) {
      if (cell.probability <= 0) continue;
      ++cells;
      ASSERT_TRUE(swept.count(cell.id)) << cell.id << " never swept";
      for (const auto& p : samples(cell.polygon, 2.0)) {
        ASSERT_TRUE(covered(p, swept.at(cell.id), s.footprint))
            << cell.id << " point " << p.transpose() << " not seen";
      }
    }
  }
  EXPECT_EQ(cells, 20);
  for (const auto& leg : plan.legs) {
    EXPECT_LE(leg.waypoints.size(), static_cast<std::size_t>(s.max_leg_waypoints));
    for (const auto& w : leg.waypoints) EXPECT_DOUBLE_EQ(w.position.z(), s.altitude);
  }
}

TEST(Coverage, NoWaypointInAnActiveKeepOutZoneAndTheRestIsStillSwept) {
  scenario::Mission m = scenario::loadMission(kMission);
  for (auto& a : m.aois) a.window = {};
  m.time_limit = 1e6;
  // A timed zone over part of aoi_2 as well, active only early on.
  scenario::KeepOutZone timed;
  timed.id = "koz_timed";
  timed.polygon = geometry::rectangle(Vec2(-240, -140), Vec2(-200, -100));
  timed.window.nlt = 1.0;
  m.kozs.push_back(timed);
  CoverageSettings s = defaultSettings();
  const SearchPlan plan = planSearch(m, s, {Vec3(-279.147, -258.585, 0), 0.0, {}});
  ASSERT_FALSE(plan.legs.empty());
  int through_timed_polygon = 0;
  Vec2 last(1e9, 1e9);
  for (const auto& leg : plan.legs) {
    for (const auto& w : leg.waypoints) {
      for (const auto& k : m.kozs) {
        if (k.alt_min && *k.alt_min > s.altitude) continue;
        if (k.alt_max && *k.alt_max < s.altitude) continue;
        if (!k.window.active(w.eta)) continue;
        EXPECT_GT(k.polygon.distance(w.position.head<2>()), s.koz_margin - 1e-9)
            << leg.cell_id << " waypoint at " << w.position.transpose() << " in " << k.id;
      }
      const Vec2 p = w.position.head<2>();
      if (leg.kind == LegKind::kCover && last.x() < 1e8) {
        through_timed_polygon += timed.polygon.intersectsSegment(last, p);
      }
      last = p;
    }
  }
  // The timed zone has closed when the UAV gets there: its area is swept like any other.
  EXPECT_GT(through_timed_polygon, 0);
  // Away from the zones (farther than margin + half a line spacing + the sampling step), every
  // point of every cell is still seen.
  const auto swept = sweeps(plan);
  const double clear = s.koz_margin + 0.5 * plan.line_spacing + 2 * s.sample_step;
  for (const auto& prior : m.priors) {
    for (const auto& cell : prior.cells) {
      if (cell.probability <= 0) continue;
      for (const auto& p : samples(cell.polygon, 3.0)) {
        bool near_zone = false;
        for (const auto& k : m.kozs) {
          const bool in_band = !(k.alt_max && *k.alt_max < s.altitude - 1.5);
          near_zone |= in_band && k.id != "koz_timed" && k.polygon.distance(p) < clear;
        }
        if (near_zone) continue;
        ASSERT_TRUE(swept.count(cell.id)) << cell.id;
        EXPECT_TRUE(covered(p, swept.at(cell.id), s.footprint))
            << cell.id << " point " << p.transpose();
      }
    }
  }
}

TEST(Coverage, HigherProbabilityCellsFirstWhenEquidistant) {
  const std::vector<std::vector<double>> priors = {
      {0.1, 0.4, 0.2, 0.3}, {0.4, 0.1, 0.2, 0.3}, {0.2, 0.3, 0.4, 0.1}, {0.3, 0.2, 0.1, 0.4}};
  const char* ids[] = {"aoi_1_r0c0", "aoi_1_r0c1", "aoi_1_r1c0", "aoi_1_r1c1"};
  for (const auto& p : priors) {
    const scenario::Mission m = squareMission(Vec2(100, 50), 100, p);
    const CoverageSettings s = defaultSettings();
    // Start over the centre: every cell's nearest entry is as far as every other's.
    const SearchPlan plan = planSearch(m, s, {Vec3(100, 50, s.altitude), 0.0, {}});
    ASSERT_FALSE(plan.legs.empty());
    const auto best = std::max_element(p.begin(), p.end()) - p.begin();
    EXPECT_EQ(plan.legs.front().cell_id, ids[best]);
    // Every cell is visited once, and the order of visits is a permutation of the four.
    std::vector<std::string> order;
    for (const auto& leg : plan.legs) {
      if (order.empty() || order.back() != leg.cell_id) order.push_back(leg.cell_id);
    }
    EXPECT_EQ(order.size(), 4u);
  }
  // Far away and on the cells' line of symmetry: ordered by probability where distances tie.
  const scenario::Mission m = squareMission(Vec2(0, 0), 100, {0.3, 0.4, 0.1, 0.2});
  const CoverageSettings s = defaultSettings();
  const SearchPlan far = planSearch(m, s, {Vec3(0, -5000, s.altitude), 0.0, {}});
  ASSERT_FALSE(far.legs.empty());
  EXPECT_EQ(far.legs.front().cell_id, "aoi_1_r0c1");  // 0.4 beats 0.3 at the same distance
}

TEST(Coverage, ZeroProbabilityCellsAreSkippedUnlessAsked) {
  const scenario::Mission m = squareMission(Vec2(0, 0), 80, {0.0, 0.5, 0.5, 0.0});
  CoverageSettings s = defaultSettings();
  SearchPlan plan = planSearch(m, s, {Vec3(0, 0, 0), 0.0, {}});
  for (const auto& leg : plan.legs) EXPECT_GT(leg.probability, 0.0) << leg.cell_id;
  s.cover_zero_cells = true;
  plan = planSearch(m, s, {Vec3(0, 0, 0), 0.0, {}});
  ASSERT_FALSE(plan.legs.empty());
  EXPECT_EQ(plan.legs.back().probability, 0.0);
  EXPECT_GT(plan.legs.front().probability, 0.0);
}

TEST(Coverage, AreaWindowsAreRespected) {
  const scenario::Mission m = scenario::loadMission(kMission);
  const CoverageSettings s = defaultSettings();
  const SearchPlan plan = planSearch(m, s, {Vec3(-279.147, -258.585, 0), 0.0, {}});
  ASSERT_FALSE(plan.legs.empty());
  std::map<std::string, geometry::TimeWindow> windows;
  for (const auto& a : m.aois) windows[a.id] = a.window;
  // aoi_1 ([48, 192]) can be started before aoi_2 opens (130): it comes first.
  EXPECT_EQ(plan.legs.front().region_id, "aoi_1");
  std::set<std::string> regions;
  for (const auto& leg : plan.legs) {
    regions.insert(leg.region_id);
    if (leg.kind != LegKind::kCover) continue;
    const auto& w = windows.at(leg.region_id);
    EXPECT_GE(leg.not_before, 0.0);
    for (const auto& wp : leg.waypoints) {
      EXPECT_TRUE(w.active(wp.eta)) << leg.cell_id << " at " << wp.eta;
      EXPECT_LE(wp.eta, m.time_limit);
    }
  }
  EXPECT_EQ(regions.size(), 2u);  // both areas get searched
  // aoi_1's window closes long before it can be swept whole: the rest is reported skipped.
  bool skipped_aoi1 = false;
  for (const auto& msg : plan.skipped) skipped_aoi1 |= msg.rfind("aoi_1", 0) == 0;
  EXPECT_TRUE(skipped_aoi1);

  // Starting after aoi_1's window has closed: only aoi_2.
  const SearchPlan late = planSearch(m, s, {Vec3(-279.147, -258.585, s.altitude), 200.0, {}});
  ASSERT_FALSE(late.legs.empty());
  for (const auto& leg : late.legs) EXPECT_EQ(leg.region_id, "aoi_2");
}

TEST(Coverage, EarlyArrivalWaitsOutsideTheAreaUntilItsWindowOpens) {
  scenario::Mission m = squareMission(Vec2(300, 0), 60, {0.25, 0.25, 0.25, 0.25});
  m.aois[0].window.net = 300.0;
  m.aois[0].window.nlt = 600.0;
  const CoverageSettings s = defaultSettings();
  const SearchPlan plan = planSearch(m, s, {Vec3(0, 0, 0), 0.0, {}});
  ASSERT_GE(plan.legs.size(), 2u);
  const SearchLeg& stage = plan.legs[0];
  EXPECT_EQ(stage.kind, LegKind::kStage);
  ASSERT_EQ(stage.waypoints.size(), 1u);
  EXPECT_FALSE(m.aois[0].polygon.contains(stage.waypoints[0].position.head<2>()));
  EXPECT_LT(stage.waypoints[0].eta, 300.0);
  const SearchLeg& first = plan.legs[1];
  EXPECT_EQ(first.kind, LegKind::kCover);
  EXPECT_DOUBLE_EQ(first.not_before, 300.0);
  EXPECT_GE(first.waypoints.front().eta, 300.0);
  // Covered cells are not planned again.
  SearchProgress progress{Vec3(0, 0, 0), 0.0, {"aoi_1_r0c0", "aoi_1_r0c1", "aoi_1_r1c0"}};
  const SearchPlan rest = planSearch(m, s, progress);
  for (const auto& leg : rest.legs) EXPECT_EQ(leg.cell_id, "aoi_1_r1c1");
}

TEST(Coverage, RouteBandsAreSweptAlongTheRoute) {
  scenario::Mission m;
  m.time_limit = 1000;
  m.cls = scenario::ScenarioClass::kRouteSearch;
  scenario::RouteOfInterest r;
  r.id = "route_1";
  r.polyline = {Vec2(0, 0), Vec2(200, 0), Vec2(200, 150)};
  r.band_width = 60;
  r.band = geometry::bufferPolyline(r.polyline, r.band_width);
  m.routes.push_back(r);
  const CoverageSettings s = defaultSettings();
  const SearchPlan plan = planSearch(m, s, {Vec3(-50, 0, 0), 0.0, {}});
  ASSERT_FALSE(plan.legs.empty());
  std::vector<std::pair<Vec2, Vec2>> segs;
  Vec2 last(1e9, 1e9);
  for (const auto& leg : plan.legs) {
    EXPECT_EQ(leg.region_id, "route_1");
    for (const auto& w : leg.waypoints) {
      const Vec2 p = w.position.head<2>();
      EXPECT_LE(r.band.distance(p), 1e-6) << p.transpose();
      if (last.x() < 1e8) segs.emplace_back(last, p);
      last = p;
    }
  }
  // The band along the straight parts is seen (corners are mitred: checked loosely).
  for (const auto& p : samples(r.band, 4.0)) {
    if (p.x() > 160 && p.y() < 40) continue;  // the corner
    EXPECT_TRUE(covered(p, segs, s.footprint)) << p.transpose();
  }
}

TEST(Coverage, PlansAreDeterministicAndFlightTimeIsTrapezoidal) {
  const scenario::Mission m = scenario::loadMission(kMission);
  const CoverageSettings s = defaultSettings();
  const SearchProgress start{Vec3(-279.147, -258.585, 0), 0.0, {}};
  const SearchPlan a = planSearch(m, s, start), b = planSearch(m, s, start);
  ASSERT_EQ(a.legs.size(), b.legs.size());
  for (std::size_t i = 0; i < a.legs.size(); ++i) {
    ASSERT_EQ(a.legs[i].waypoints.size(), b.legs[i].waypoints.size());
    for (std::size_t j = 0; j < a.legs[i].waypoints.size(); ++j) {
      EXPECT_EQ(a.legs[i].waypoints[j].position, b.legs[i].waypoints[j].position);
      EXPECT_EQ(a.legs[i].waypoints[j].eta, b.legs[i].waypoints[j].eta);
    }
  }
  EXPECT_DOUBLE_EQ(flightTime(0, 12, 2), 0.0);
  EXPECT_DOUBLE_EQ(flightTime(72, 12, 2), 12.0);  // exactly the ramp: 6 s up, 6 s down
  EXPECT_DOUBLE_EQ(flightTime(172, 12, 2), 12.0 + 100.0 / 12.0);
  EXPECT_DOUBLE_EQ(flightTime(8, 12, 2), 4.0);
}

// In the city a rooftop can stand above the sweep altitude: the waypoint is lifted over it (the
// raw box's top plus the margin, independently), a tower above the band drops its waypoint (and
// an emptied leg), and a free waypoint is left alone.
TEST(CoverageTest, SweepWaypointsAreLiftedOverRooftopsAndDroppedAboveTheBand) {
  const scenario::World& city = scenario::testing::shippedCityWorld();
  planning::ValiditySettings vs;  // margin 1 m
  vs.altitude_min = 20.0;
  vs.altitude_max = 62.0;
  const planning::WorldValidity validity(city, std::vector<scenario::KeepOutZone>{}, vs);
  const geometry::OrientedBox* low = nullptr;
  const geometry::OrientedBox* tower = nullptr;
  for (const auto& e : city.entities()) {
    if (e.cls != scenario::EntityClass::kBuilding) continue;
    const double top = e.box.maxZ();
    if (!low && top > 30.0 && top < 50.0) low = &e.box;
    if (!tower && top > 70.0) tower = &e.box;
  }
  ASSERT_TRUE(low && tower);
  // A free point: high above the low building.
  const Vec3 free(low->center.x(), low->center.y(), 60.0);
  ASSERT_TRUE(validity.staticValid(free));
  SearchPlan plan;
  SearchLeg a, b;
  a.waypoints = {{Vec3(low->center.x(), low->center.y(), 26.0), 10.0}, {free, 20.0}};
  b.waypoints = {{Vec3(tower->center.x(), tower->center.y(), 26.0), 30.0}};
  plan.legs = {a, b};
  const WaypointRepairs r = clearWaypoints(&plan, validity);
  EXPECT_EQ(r.lifted, 1);
  EXPECT_EQ(r.dropped, 1);
  ASSERT_EQ(plan.legs.size(), 1u);
  ASSERT_EQ(plan.legs[0].waypoints.size(), 2u);
  const Vec3 lifted = plan.legs[0].waypoints[0].position;
  EXPECT_DOUBLE_EQ(lifted.x(), low->center.x());
  EXPECT_GT(lifted.z(), low->maxZ() + vs.margin);
  EXPECT_LE(lifted.z(), low->maxZ() + vs.margin + 2.0 + 1e-9);
  EXPECT_EQ(plan.legs[0].waypoints[0].eta, 10.0);
  EXPECT_EQ(plan.legs[0].waypoints[1].position, free);
}

}  // namespace
}  // namespace hameritt::clients
