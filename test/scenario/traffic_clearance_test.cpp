// The mission's own cars against the ambient traffic (scenario/traffic_clearance.h): the
// separating-axis test, which ambient cars a scenario withholds, and generated city scenarios
// in which no mission car overlaps an ambient car that is left. Each check has a negative
// control that shows it can fail.

#include "hameritt/scenario/traffic_clearance.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "hameritt/generation/generator.h"
#include "hameritt/scenario/city_traffic.h"
#include "test_util.h"

namespace hameritt::scenario {
namespace {

// A car driving along +x at `speed` from x0 at t = 0 (y fixed), over 60 s.
Trajectory driveX(double x0, double y, double speed, double t0 = 0.0) {
  return {{t0, x0, y, 0.0, 0.0}, {t0 + 60.0, x0 + 60.0 * speed, y, 0.0, 0.0}};
}

MovingFootprint moving(const Trajectory& t, double shift = 0.0) {
  MovingFootprint f;
  f.trajectory = &t;
  f.time_shift = shift;
  return f;
}

MovingFootprint standing(double x, double y, double yaw) {
  MovingFootprint f;
  f.pose.x = x;
  f.pose.y = y;
  f.pose.yaw = yaw;
  return f;
}

TEST(TrafficClearance, SeparatingAxesTellRotatedBoxesApart) {
  // Two 4.5 x 1.8 m cars side by side, 1.9 m apart: apart; 1.7 m: overlapping.
  EXPECT_FALSE(rectanglesOverlap(0, 0, 0, 2.25, 0.9, 0, 1.9, 0, 2.25, 0.9));
  EXPECT_TRUE(rectanglesOverlap(0, 0, 0, 2.25, 0.9, 0, 1.7, 0, 2.25, 0.9));
  // A car turned by -45 degrees off the corner of another, 0.41 m apart (Shapely): their
  // bounding boxes and circles meet, the rectangles do not. The control: turned by +45 degrees
  // the same pair overlaps.
  const double k = 0.25 * M_PI;
  EXPECT_FALSE(rectanglesOverlap(0, 0, 0, 2.25, 0.9, 3.0, 2.0, -k, 2.25, 0.9));
  EXPECT_TRUE(rectanglesOverlap(0, 0, 0, 2.25, 0.9, 3.0, 2.0, k, 2.25, 0.9));
  // Symmetric in its arguments.
  EXPECT_FALSE(rectanglesOverlap(3.0, 2.0, -k, 2.25, 0.9, 0, 0, 0, 2.25, 0.9));
  EXPECT_TRUE(rectanglesOverlap(3.0, 2.0, k, 2.25, 0.9, 0, 0, 0, 2.25, 0.9));
}

TEST(TrafficClearance, WithholdsTheCarsThatComeNearAMissionCar) {
  const Trajectory own = driveX(0.0, 0.0, 10.0);  // the mission car: 0 -> 600 m along y = 0
  const Trajectory next_lane = driveX(0.0, 3.5, 10.0);
  const Trajectory close_lane = driveX(0.0, 2.1, 10.0);  // 0.3 m between their sides
  // A car crossing y = 0 at x = 300 m at episode time 130 s: at scenario time 30 s (the mission
  // car's time there) when the episode window starts at 100 s.
  const Trajectory crossing = {{100.0, 300.0, -300.0, 0.0, 0.5 * M_PI},
                               {160.0, 300.0, 300.0, 0.0, 0.5 * M_PI}};
  std::vector<MovingFootprint> traffic = {
      standing(250.0, 0.0, 0.0),   // 0: in the mission car's lane
      moving(next_lane),           // 1: beside it, 1.7 m apart
      moving(close_lane),          // 2: beside it, 0.3 m apart
      moving(crossing, 100.0),     // 3: meets it at the crossing
      standing(250.0, -5.0, 0.0),  // 4: off its lane
  };
  const std::vector<MovingFootprint> mission = {moving(own)};
  EXPECT_EQ(trafficToWithhold(mission, traffic, 60.0), (std::vector<std::size_t>{0, 2, 3}));
  // Without the margin the car 0.3 m away is kept; the others stay as they were.
  EXPECT_EQ(trafficToWithhold(mission, traffic, 60.0, 0.0), (std::vector<std::size_t>{0, 3}));
  // The first overlap: the mission car's front (2.25 m ahead) meets the standing car's back
  // (2.25 m behind 250 m) at 24.55 s; the samples are 0.1 s apart.
  const auto t = firstOverlap(mission[0], traffic[0], 60.0, 0.0);
  ASSERT_TRUE(t.has_value());
  EXPECT_NEAR(*t, 24.6, 1e-9);
  // The controls: the crossing car on scenario time (no shift) is at x = 300 m 30 s too early;
  // a window that ends before the meeting sees none of it.
  traffic[3] = moving(crossing, 0.0);
  EXPECT_EQ(trafficToWithhold(mission, traffic, 60.0, 0.0), (std::vector<std::size_t>{0}));
  EXPECT_TRUE(trafficToWithhold(mission, traffic, 20.0, 0.0).empty());
  EXPECT_TRUE(trafficToWithhold({}, traffic, 60.0).empty());
}

// Generated city scenarios (a route search, a track, a follow): the ambient cars left in memory
// never overlap a mission car; each withheld car, rebuilt from the episode's bytes, comes within
// the clearance of one, and some overlap one: the control, the same check on the cars withheld.
TEST(TrafficClearance, GeneratedCityScenariosKeepTheirCarsApart) {
  GeneratorConfig cfg = testing::shippedConfig();
  cfg.perception_paths = false;
  std::size_t held_total = 0, held_overlapping = 0;
  for (const auto& [cls, seed] :
       {std::pair{ScenarioClass::kRouteSearch, 3ULL}, std::pair{ScenarioClass::kTrack, 4ULL},
        std::pair{ScenarioClass::kFollow, 5ULL}}) {
    const Scenario s = generateScenario(testing::shippedCityWorld(), cfg, cls, seed);
    ASSERT_TRUE(s.sim.traffic.has_value());
    const TrafficEpisodeRef& ref = *s.sim.traffic;
    std::vector<MovingFootprint> own, ambient;
    for (const auto& se : s.sim.entities) {
      if (isMissionCar(se)) own.push_back(footprintOf(se));
      if (se.role == "traffic") ambient.push_back(footprintOf(se));
    }
    ASSERT_FALSE(own.empty());
    EXPECT_EQ(ambient.size() + ref.withheld.size(), ref.car_ids.size());
    EXPECT_TRUE(trafficToWithhold(own, ambient, s.sim.duration, 0.0).empty());
    EXPECT_TRUE(trafficToWithhold(own, ambient, s.sim.duration).empty());
    ASSERT_TRUE(ref.text);
    const TrafficEpisode e = parseTrafficEpisode(*ref.text, "episode");
    std::vector<Trajectory> windows;
    windows.reserve(ref.withheld.size());
    std::vector<MovingFootprint> held;
    for (const auto& id : ref.withheld) {
      const auto i = static_cast<std::size_t>(
          std::find(ref.car_ids.begin(), ref.car_ids.end(), id) - ref.car_ids.begin());
      ASSERT_LT(i, e.cars.size()) << id;
      windows.push_back(episodeCarWindow(e, i, ref.offset, s.sim.duration));
      MovingFootprint f = moving(windows.back());
      f.length = e.cars[i].size.x();
      f.width = e.cars[i].size.y();
      held.push_back(f);
    }
    // Rounded to the millimetre in the window: 1 cm of slack.
    EXPECT_EQ(trafficToWithhold(own, held, s.sim.duration, kTrafficClearance + 0.01).size(),
              held.size());
    held_total += held.size();
    held_overlapping += trafficToWithhold(own, held, s.sim.duration, 0.0).size();
  }
  EXPECT_GT(held_total, 0u);
  EXPECT_GT(held_overlapping, 0u);
}

// An episode's precomputed blocks (SharedTrafficEpisode::clearance) withhold exactly the cars
// that walking each trajectory again withholds, at offsets on and off the blocks' 2 s grid:
// "mission" cars are episode cars seen at other offsets (some pairs near each other, most not).
// Control: blocks moved 1 km away withhold nothing, so the comparison did read them. The
// episode's grid (SharedTrafficEpisode::clearance_index) and a grid of 6 m cells find the same
// cars; a grid built from other blocks than the footprints' is not used.
TEST(TrafficClearance, PrecomputedEpisodeBlocksWithholdTheSameCars) {
  const auto ep = cityTrafficEpisode(testing::shippedCityWorld(), 0);
  ASSERT_EQ(ep->clearance.size(), ep->trajectories.size());
  ASSERT_GT(ep->trajectories.size(), 20u);
  // A grid of small cells: a box spans many, a car is looked at once per query.
  const ClearanceIndex small_cells = clearanceIndex(ep->clearance, 6.0);
  ASSERT_GT(small_cells.nx, 50);
  std::size_t withheld = 0;
  for (const double offset : {0.0, 1.4, 37.8, 200.0, 611.2}) {
    for (const double duration : {60.0, 300.0}) {
      SCOPED_TRACE("offset " + std::to_string(offset) + " duration " + std::to_string(duration));
      std::vector<MovingFootprint> own, walked, cached, far;
      std::vector<ClearanceBlocks> moved(ep->clearance.begin(), ep->clearance.end());
      for (std::size_t i = 0; i < ep->trajectories.size(); ++i) {
        MovingFootprint f = moving(ep->trajectories[i], offset);
        f.length = ep->episode.cars[i].size.x();
        f.width = ep->episode.cars[i].size.y();
        // Every seventh car, 0.6 s later, as one of the mission's: it follows its own path.
        if (i % 7 == 0) {
          MovingFootprint m = f;
          m.time_shift = offset + 0.6;
          own.push_back(m);
        }
        walked.push_back(f);
        f.blocks = &ep->clearance[i];
        cached.push_back(f);
        for (auto& b : moved[i].boxes) {
          b.min_x += 1000.0;
          b.max_x += 1000.0;
        }
      }
      for (std::size_t i = 0; i < cached.size(); ++i) {
        far.push_back(cached[i]);
        far.back().blocks = &moved[i];
      }
      const auto expected = trafficToWithhold(own, walked, duration);
      EXPECT_EQ(trafficToWithhold(own, cached, duration), expected);
      EXPECT_TRUE(trafficToWithhold(own, far, duration).empty());
      // The episode's grid finds the same cars; a grid of the moved blocks none.
      EXPECT_EQ(trafficToWithhold(own, cached, ep->clearance_index, duration), expected);
      const ClearanceIndex far_index = clearanceIndex(moved);
      EXPECT_TRUE(trafficToWithhold(own, far, far_index, duration).empty());
      // The grid of other blocks than the footprints' is not used: the comparison decides.
      EXPECT_EQ(trafficToWithhold(own, far, ep->clearance_index, duration), std::vector<std::size_t>{});
      EXPECT_EQ(trafficToWithhold(own, cached, far_index, duration), expected);
      EXPECT_EQ(trafficToWithhold(own, cached, small_cells, duration), expected);
      // A margin other than the blocks' walks the trajectories.
      EXPECT_EQ(trafficToWithhold(own, far, duration, 0.0),
                trafficToWithhold(own, walked, duration, 0.0));
      withheld += expected.size();
    }
  }
  EXPECT_GT(withheld, 10u);
  std::printf("withheld over 10 windows: %zu\n", withheld);
}

}  // namespace
}  // namespace hameritt::scenario
