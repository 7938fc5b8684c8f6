#include "hameritt/adk/constraint_monitor.h"

#include <gtest/gtest.h>

#include <cmath>

#include "../scenario/test_util.h"
#include "adk_test_util.h"
#include "hameritt/planning/validity.h"

namespace hameritt::adk {
namespace {

using namespace testing;  // NOLINT

using Kind = ConstraintEvent::Kind;

std::vector<Violation> fly(const scenario::Mission& m,
                           const std::vector<std::pair<double, Vec3>>& s,
                           std::vector<ConstraintEvent>* events = nullptr) {
  ConstraintMonitor mon(m);
  for (const auto& [t, p] : s) {
    auto ev = mon.add(t, p);
    if (events) events->insert(events->end(), ev.begin(), ev.end());
  }
  return mon.violations();
}

TEST(SegmentInsidePolygon, CrossingTouchingAlongAnEdgeAndInside) {
  const Polygon sq = square(0, 0, 10, 10);
  // Through the middle: inside for x in [0, 10] of [-5, 15].
  auto r = segmentInsidePolygon(sq, Vec2(-5, 5), Vec2(15, 5));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(r[0].lo, 0.25, 1e-15);
  EXPECT_NEAR(r[0].hi, 0.75, 1e-15);
  // Touching the corner (10, 10) only: a zero-length interval at u = 0.5.
  r = segmentInsidePolygon(sq, Vec2(5, 15), Vec2(15, 5));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(r[0].lo, 0.5, 1e-12);
  EXPECT_NEAR(r[0].hi, 0.5, 1e-12);
  // Along the bottom edge (boundary is inside).
  r = segmentInsidePolygon(sq, Vec2(-10, 0), Vec2(20, 0));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_NEAR(r[0].lo, 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(r[0].hi, 2.0 / 3.0, 1e-15);
  // Wholly inside; starting inside; missing.
  r = segmentInsidePolygon(sq, Vec2(1, 1), Vec2(9, 2));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].lo, 0.0);
  EXPECT_EQ(r[0].hi, 1.0);
  r = segmentInsidePolygon(sq, Vec2(5, 5), Vec2(5, 25));
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].lo, 0.0);
  EXPECT_NEAR(r[0].hi, 0.25, 1e-15);
  EXPECT_TRUE(segmentInsidePolygon(sq, Vec2(-5, 11), Vec2(15, 11)).empty());
  // A point.
  EXPECT_EQ(segmentInsidePolygon(sq, Vec2(3, 3), Vec2(3, 3)).size(), 1u);
  EXPECT_TRUE(segmentInsidePolygon(sq, Vec2(-3, 3), Vec2(-3, 3)).empty());
}

TEST(SegmentInsidePolygon, NonConvexGivesTwoIntervals) {
  // U shape: [0,9]x[0,3] plus the two arms [0,3]x[3,9] and [6,9]x[3,9].
  const Polygon u({Vec2(0, 0), Vec2(9, 0), Vec2(9, 9), Vec2(6, 9), Vec2(6, 3), Vec2(3, 3),
                   Vec2(3, 9), Vec2(0, 9)});
  const auto r = segmentInsidePolygon(u, Vec2(-1, 6), Vec2(10, 6));
  ASSERT_EQ(r.size(), 2u);
  EXPECT_NEAR(r[0].lo * 11 - 1, 0.0, 1e-12);
  EXPECT_NEAR(r[0].hi * 11 - 1, 3.0, 1e-12);
  EXPECT_NEAR(r[1].lo * 11 - 1, 6.0, 1e-12);
  EXPECT_NEAR(r[1].hi * 11 - 1, 9.0, 1e-12);
}

TEST(ConstraintMonitor, SampleFreeCornerCrossingHasExactTimes) {
  // Both samples outside; the segment from (-1, 5) to (5, 11) (line y = x + 6) cuts the corner
  // (0, 10): it enters through the left edge at (0, 6), u = 1/6, and leaves through the top
  // edge at (4, 10), u = 5/6. Over t in [0, 6] that is t = 1 and t = 5.
  std::vector<ConstraintEvent> ev;
  const auto v = fly(squareMission(), {{0.0, Vec3(-1, 5, 10)}, {6.0, Vec3(5, 11, 10)}}, &ev);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].zone_id, "koz_a");
  EXPECT_EQ(v[0].purpose, "restricted");
  EXPECT_NEAR(v[0].t_enter, 1.0, 1e-12);
  EXPECT_NEAR(v[0].t_exit, 5.0, 1e-12);
  EXPECT_NEAR(v[0].duration(), 4.0, 1e-12);
  EXPECT_FALSE(v[0].ongoing);
  ASSERT_EQ(ev.size(), 4u);
  EXPECT_EQ(ev[0].kind, Kind::kEnter);
  EXPECT_EQ(ev[1].kind, Kind::kViolationStart);
  EXPECT_EQ(ev[2].kind, Kind::kViolationEnd);
  EXPECT_EQ(ev[3].kind, Kind::kExit);
  EXPECT_NEAR(ev[0].t, 1.0, 1e-12);
  EXPECT_NEAR((ev[0].position - Vec3(0, 6, 10)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((ev[3].position - Vec3(4, 10, 10)).norm(), 0.0, 1e-12);
  EXPECT_TRUE(ev[0].active);
  EXPECT_TRUE(ev[0].keep_out_zone);
}

TEST(ConstraintMonitor, AltitudeBandAboveBelowAndThrough) {
  const auto m = squareMission();
  EXPECT_TRUE(fly(m, {{0.0, Vec3(-5, 5, 25)}, {20.0, Vec3(15, 5, 25)}}).empty());   // above
  EXPECT_TRUE(fly(m, {{0.0, Vec3(-5, 5, 2)}, {20.0, Vec3(15, 5, 2)}}).empty());     // below
  EXPECT_EQ(fly(m, {{0.0, Vec3(-5, 5, 20)}, {20.0, Vec3(15, 5, 20)}}).size(), 1u);  // on the top
  // Climbing vertically inside the polygon: z = 5 t is in [5, 20] for t in [1, 4].
  const auto v = fly(m, {{0.0, Vec3(5, 5, 0)}, {6.0, Vec3(5, 5, 30)}});
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NEAR(v[0].t_enter, 1.0, 1e-12);
  EXPECT_NEAR(v[0].t_exit, 4.0, 1e-12);
  // Diagonal descent that leaves the band through its bottom before reaching the polygon's
  // far side: x = -5 + t, z = 12 - t; inside x in [0, 10] -> t in [5, 15], z >= 5 -> t <= 7.
  const auto d = fly(m, {{0.0, Vec3(-5, 5, 12)}, {20.0, Vec3(15, 5, -8)}});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_NEAR(d[0].t_enter, 5.0, 1e-12);
  EXPECT_NEAR(d[0].t_exit, 7.0, 1e-12);
  // Open bounds: no minimum means down to any depth.
  scenario::Mission open = m;
  open.kozs[0].alt_min.reset();
  EXPECT_EQ(fly(open, {{0.0, Vec3(-5, 5, 2)}, {20.0, Vec3(15, 5, 2)}}).size(), 1u);
}

TEST(ConstraintMonitor, WindowOpeningAndClosingMidSegment) {
  // Inside the prism for t in [5, 15].
  const std::vector<std::pair<double, Vec3>> path = {{0.0, Vec3(-5, 5, 10)},
                                                     {20.0, Vec3(15, 5, 10)}};
  auto v = fly(squareMission(window(8.0, std::nullopt)), path);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NEAR(v[0].t_enter, 8.0, 1e-12);
  EXPECT_NEAR(v[0].t_exit, 15.0, 1e-12);
  v = fly(squareMission(window(8.0, 12.0)), path);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NEAR(v[0].t_enter, 8.0, 1e-12);
  EXPECT_NEAR(v[0].t_exit, 12.0, 1e-12);
  v = fly(squareMission(window(3.0, 100.0)), path);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NEAR(v[0].t_enter, 5.0, 1e-12);
  // Events: the prism entry at 5 is not active; the violation starts when the window opens.
  std::vector<ConstraintEvent> ev;
  fly(squareMission(window(8.0, std::nullopt)), path, &ev);
  ASSERT_EQ(ev.size(), 4u);
  EXPECT_EQ(ev[0].kind, Kind::kEnter);
  EXPECT_NEAR(ev[0].t, 5.0, 1e-12);
  EXPECT_FALSE(ev[0].active);
  EXPECT_EQ(ev[1].kind, Kind::kViolationStart);
  EXPECT_NEAR(ev[1].t, 8.0, 1e-12);
  EXPECT_NEAR(ev[1].position.x(), 3.0, 1e-12);
  EXPECT_EQ(ev[2].kind, Kind::kViolationEnd);
  EXPECT_EQ(ev[3].kind, Kind::kExit);
}

TEST(ConstraintMonitor, InactiveZoneReportsNothingButTracksInside) {
  const auto m = squareMission(window(100.0, std::nullopt));
  ConstraintMonitor mon(m);
  mon.add(0.0, Vec3(-5, 5, 10));
  mon.add(10.0, Vec3(5, 5, 10));
  EXPECT_TRUE(mon.violations().empty());
  EXPECT_EQ(mon.violationCount(), 0u);
  const auto z = mon.zones();
  ASSERT_EQ(z.size(), 1u);
  EXPECT_TRUE(z[0].inside);
  EXPECT_FALSE(z[0].active);
  EXPECT_FALSE(z[0].violating);
  mon.add(20.0, Vec3(15, 5, 10));
  EXPECT_TRUE(mon.violations().empty());
  EXPECT_FALSE(mon.zones()[0].inside);
  // A window that closed before the crossing.
  EXPECT_TRUE(fly(squareMission(window(std::nullopt, 4.0)),
                  {{0.0, Vec3(-5, 5, 10)}, {20.0, Vec3(15, 5, 10)}})
                  .empty());
}

TEST(ConstraintMonitor, GrazingAVertexIsAZeroLengthViolation) {
  std::vector<ConstraintEvent> ev;
  const auto v = fly(squareMission(), {{0.0, Vec3(5, 15, 10)}, {10.0, Vec3(15, 5, 10)}}, &ev);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NEAR(v[0].t_enter, 5.0, 1e-9);
  EXPECT_NEAR(v[0].duration(), 0.0, 1e-9);
  ASSERT_EQ(ev.size(), 4u);
  EXPECT_EQ(ev[0].kind, Kind::kEnter);
  EXPECT_EQ(ev[3].kind, Kind::kExit);
  // Passing 1 mm outside the vertex is clear.
  EXPECT_TRUE(
      fly(squareMission(), {{0.0, Vec3(5.001, 15, 10)}, {10.0, Vec3(15.001, 5, 10)}}).empty());
}

TEST(ConstraintMonitor, SamplesInsideMergeIntoOneViolationAndOngoingIsReported) {
  ConstraintMonitor mon(squareMission());
  mon.add(0.0, Vec3(-5, 5, 10));
  mon.add(1.0, Vec3(2, 5, 10));
  mon.add(2.0, Vec3(5, 5, 10));
  auto v = mon.violations();
  ASSERT_EQ(v.size(), 1u);
  EXPECT_TRUE(v[0].ongoing);
  EXPECT_NEAR(v[0].t_enter, 5.0 / 7.0, 1e-12);
  EXPECT_EQ(v[0].t_exit, 2.0);
  EXPECT_TRUE(mon.zones()[0].violating);
  mon.add(3.0, Vec3(8, 5, 10));
  const auto ev = mon.add(4.0, Vec3(15, 5, 10));
  v = mon.violations();
  ASSERT_EQ(v.size(), 1u);
  EXPECT_FALSE(v[0].ongoing);
  EXPECT_NEAR(v[0].t_exit, 3.0 + 2.0 / 7.0, 1e-12);
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].kind, Kind::kViolationEnd);
  EXPECT_EQ(ev[1].kind, Kind::kExit);
  // Leave and come back: a second violation.
  mon.add(5.0, Vec3(5, 5, 10));
  EXPECT_EQ(mon.violationCount(), 2u);
  EXPECT_NEAR(mon.violationDuration(), (3.0 + 2.0 / 7.0 - 5.0 / 7.0) + (5.0 - (4.0 + 5.0 / 10.0)),
              1e-12);
}

TEST(ConstraintMonitor, FirstSampleInsideStartsAViolation) {
  ConstraintMonitor mon(squareMission());
  const auto ev = mon.add(3.0, Vec3(5, 5, 10));
  ASSERT_EQ(ev.size(), 2u);
  EXPECT_EQ(ev[0].kind, Kind::kEnter);
  EXPECT_EQ(ev[1].kind, Kind::kViolationStart);
  EXPECT_EQ(ev[0].t, 3.0);
  const auto v = mon.violations();
  ASSERT_EQ(v.size(), 1u);
  EXPECT_EQ(v[0].t_enter, 3.0);
  EXPECT_TRUE(v[0].ongoing);
}

TEST(ConstraintMonitor, BadSamplesAreErrorsAndLeaveTheMonitorUnchanged) {
  ConstraintMonitor mon(squareMission());
  mon.add(1.0, Vec3(-5, 5, 10));
  EXPECT_THROW(mon.add(1.0, Vec3(5, 5, 10)), InputError);
  EXPECT_THROW(mon.add(0.5, Vec3(5, 5, 10)), InputError);
  EXPECT_THROW(mon.add(std::nan(""), Vec3(5, 5, 10)), InputError);
  EXPECT_THROW(mon.add(2.0, Vec3(5, std::nan(""), 10)), InputError);
  try {
    mon.add(0.5, Vec3(5, 5, 10));
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sample 1: time: expected a time after the previous "
                                         "sample's 1, got 0.5"),
              std::string::npos)
        << e.what();
  }
  EXPECT_EQ(mon.sampleCount(), 1u);
  EXPECT_EQ(mon.lastTime(), 1.0);
  EXPECT_TRUE(mon.violations().empty());
}

TEST(ConstraintMonitor, AreaOfInterestTimesAndEntries) {
  scenario::Mission m;
  scenario::AreaOfInterest a;
  a.id = "aoi_x";
  a.polygon = square(0, 0, 10, 10);
  a.window = window(7.0, std::nullopt);
  m.aois.push_back(a);
  ConstraintMonitor mon(m);
  std::vector<ConstraintEvent> ev;
  for (auto [t, p] : std::vector<std::pair<double, Vec3>>{
           {0.0, Vec3(-5, 5, 30)}, {20.0, Vec3(15, 5, 30)}, {40.0, Vec3(-5, 5, 30)}}) {
    auto e = mon.add(t, p);
    ev.insert(ev.end(), e.begin(), e.end());
  }
  const auto s = mon.areas();
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(s[0].id, "aoi_x");
  EXPECT_NEAR(s[0].time_inside, 20.0, 1e-12);         // [5, 15] and [25, 35]
  EXPECT_NEAR(s[0].time_inside_active, 18.0, 1e-12);  // [7, 15] and [25, 35]
  EXPECT_EQ(s[0].entries, 2);
  EXPECT_FALSE(s[0].inside);
  EXPECT_TRUE(s[0].active);
  ASSERT_EQ(ev.size(), 4u);
  EXPECT_FALSE(ev[0].keep_out_zone);
  EXPECT_FALSE(ev[0].active);  // entered at 5, before the window opened
  EXPECT_TRUE(ev[2].active);
}

// The monitor against the planner's exact segment check (WorldValidity::kozSegmentClear with
// the margin cancelled by the slack), on random segments around the shipped zones, with and
// without time windows.
TEST(ConstraintMonitor, AgreesWithWorldValidityOnRandomSegments) {
  const auto& world = scenario::testing::shippedWorld();
  planning::ValiditySettings vs;
  vs.margin = 0.1;
  for (const scenario::Mission* m : {&shippedMission(), &windowsMission()}) {
    const planning::WorldValidity validity(world, *m, vs);
    TestRng rng(42);
    int hits = 0, misses = 0;
    for (int i = 0; i < 4000; ++i) {
      const auto& z = m->kozs[static_cast<std::size_t>(i) % m->kozs.size()];
      const geometry::Aabb2 b = z.polygon.bounds();
      auto point = [&] {
        return Vec3(rng.uniform(b.min.x() - 30, b.max.x() + 30),
                    rng.uniform(b.min.y() - 30, b.max.y() + 30), rng.uniform(0, 120));
      };
      const Vec3 a = point(), c = point();
      const double ta = rng.uniform(0, 80), tb = ta + rng.uniform(0.1, 20);
      ConstraintMonitor mon(*m);
      mon.add(ta, a);
      mon.add(tb, c);
      const bool clear = validity.kozSegmentClear(a, c, ta, tb, 0.1);
      EXPECT_EQ(mon.violationCount() == 0, clear)
          << "segment " << i << " (" << a.transpose() << ") t " << ta << " -> (" << c.transpose()
          << ") t " << tb;
      (clear ? misses : hits)++;
    }
    // The draw exercises both answers.
    EXPECT_GT(hits, 300);
    EXPECT_GT(misses, 300);
  }
}

// Every reported interval against dense sampling of the same path (1e-3 s): a sample time is
// in a reported violation exactly when the interpolated point is inside an active zone, except
// within 1e-3 s of an interval end.
TEST(ConstraintMonitor, IntervalsAgreeWithDenseSampling) {
  const scenario::Mission& m = windowsMission();
  TestRng rng(7);
  for (int i = 0; i < 60; ++i) {
    const auto& z = m.kozs[static_cast<std::size_t>(i) % m.kozs.size()];
    const geometry::Aabb2 b = z.polygon.bounds();
    std::vector<std::pair<double, Vec3>> path;
    double t = rng.uniform(0, 40);
    for (int k = 0; k < 4; ++k) {
      path.push_back({t, Vec3(rng.uniform(b.min.x() - 10, b.max.x() + 10),
                              rng.uniform(b.min.y() - 10, b.max.y() + 10), rng.uniform(0, 110))});
      t += rng.uniform(1, 8);
    }
    const auto v = fly(m, path);
    for (std::size_t s = 1; s < path.size(); ++s) {
      const auto& [ta, a] = path[s - 1];
      const auto& [tb, c] = path[s];
      for (double tt = ta; tt <= tb; tt += 1e-3) {
        const Vec3 p = a + (c - a) * ((tt - ta) / (tb - ta));
        bool truth = false;
        for (const auto& k : m.kozs) {
          const bool band =
              (!k.alt_min || p.z() >= *k.alt_min) && (!k.alt_max || p.z() <= *k.alt_max);
          if (band && k.window.active(tt) && k.polygon.contains(p.head<2>())) truth = true;
        }
        bool reported = false, near_end = false;
        for (const auto& x : v) {
          if (tt >= x.t_enter && tt <= x.t_exit) reported = true;
          if (std::fabs(tt - x.t_enter) < 1e-3 || std::fabs(tt - x.t_exit) < 1e-3) near_end = true;
        }
        if (!near_end) {
          ASSERT_EQ(truth, reported) << "path " << i << " t " << tt;
        }
      }
    }
  }
}

// A zone that escorts a vehicle moves with it: hovering at (5, 5) is inside the square while it
// stands there and outside once it has moved 20 m east (it leaves at t = 7.5, when its left
// edge at x = 2 t - 10 passes x = 5); the same hover against the zone held still stays
// inside (the control).
TEST(ConstraintMonitor, MovingZoneLeavesAHoveringVehicle) {
  scenario::Mission m = squareMission();
  m.kozs[0].motion = {
      {0.0, 5.0, 5.0, 0.0, 0.0}, {5.0, 5.0, 5.0, 0.0, 0.0}, {15.0, 25.0, 5.0, 0.0, 0.0}};
  std::vector<std::pair<double, Vec3>> hover;
  for (int i = 0; i <= 200; ++i) hover.push_back({0.1 * i, Vec3(5, 5, 10)});
  const auto v = fly(m, hover);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NEAR(v[0].t_enter, 0.0, 1e-12);
  EXPECT_NEAR(v[0].t_exit, 7.5, 0.1);
  EXPECT_FALSE(v[0].ongoing);
  const auto still = fly(squareMission(), hover);
  ASSERT_EQ(still.size(), 1u);
  EXPECT_TRUE(still[0].ongoing);
}

}  // namespace
}  // namespace hameritt::adk
