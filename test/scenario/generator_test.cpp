// Generator and world tests: determinism, placement invariants, trajectories, bad input.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "hameritt/geometry/segment.h"
#include "hameritt/generation/batch.h"
#include "hameritt/scenario/catalog.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/params_table.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/trajectory.h"
#include "test_util.h"

namespace fs = std::filesystem;
using namespace hameritt::scenario;
using hameritt::geometry::Vec2;
using hameritt::scenario::testing::freshTempDir;
using hameritt::scenario::testing::slurp;
using hameritt::scenario::testing::shippedConfig;
using hameritt::scenario::testing::shippedWorld;

namespace {

const ScenarioClass kClasses[] = {ScenarioClass::kAreaSearch, ScenarioClass::kRouteSearch,
                                  ScenarioClass::kPursuit};


const ScenarioEntity* findEntity(const Scenario& s, const std::string& id) {
  for (const auto& e : s.sim.entities) {
    if (e.entity.id == id) return &e;
  }
  return nullptr;
}

// Distance from p to the nearest street centreline segment.
double streetDistance(const World& w, const Vec2& p) {
  double best = 1e18;
  for (const auto& e : w.edges()) {
    best = std::min(best, hameritt::geometry::pointSegmentDistance(p, w.nodes()[e.a].position,
                                                                   w.nodes()[e.b].position));
  }
  return best;
}

}  // namespace

TEST(WorldTest, DeterministicBySeedWithStableFingerprint) {
  const WorldParams p = loadWorldParams(defaultConfigDir() + "/world.json");
  const World a = generateWorld(p);
  const World b = generateWorld(p);
  EXPECT_EQ(a.fingerprint(), b.fingerprint());
  EXPECT_EQ(worldJson(a), worldJson(b));
  WorldParams q = p;
  q.seed = p.seed + 1;
  EXPECT_NE(generateWorld(q).fingerprint(), a.fingerprint());
}

TEST(WorldTest, NeighborhoodHasTheExpectedContent) {
  const World& w = shippedWorld();
  std::map<EntityClass, int> n;
  for (const auto& e : w.entities()) n[e.cls]++;
  EXPECT_GT(n[EntityClass::kHouse], 300);  // about 1 km^2 of suburb
  EXPECT_GT(n[EntityClass::kGarage], 200);
  EXPECT_GT(n[EntityClass::kDriveway], 300);
  EXPECT_GT(n[EntityClass::kFence], 100);
  EXPECT_GT(n[EntityClass::kTree], 300);
  EXPECT_GT(n[EntityClass::kCar], 50);
  EXPECT_GT(w.blocks().size(), 20u);
  const auto b = w.bounds();
  EXPECT_NEAR((b.max - b.min).prod(), 1e6, 1.0);
  // Every id unique; garages carry colour and door count, cars make/model/colour.
  std::set<std::string> ids;
  for (const auto& e : w.entities()) {
    EXPECT_TRUE(ids.insert(e.id).second) << e.id;
    if (e.cls == EntityClass::kGarage) {
      EXPECT_FALSE(e.attributes.str("color").empty());
      EXPECT_GE(e.attributes.integer("doors"), 1);
    }
    if (e.cls == EntityClass::kCar) {
      EXPECT_NE(catalog::findCarModel(e.attributes.str("make"), e.attributes.str("model")), nullptr);
    }
  }
}

TEST(WorldTest, SolidObjectsDoNotOverlapAndStayOffStreets) {
  const World& w = shippedWorld();
  const auto solid = [](EntityClass c) {
    return c == EntityClass::kHouse || c == EntityClass::kGarage || c == EntityClass::kCar;
  };
  int checked = 0;
  for (int i = 0; i < static_cast<int>(w.entities().size()); ++i) {
    const Entity& a = w.entities()[i];
    if (!solid(a.cls)) continue;
    for (int j : w.footprints().near(a.box.center2(), 0.5 * a.box.size.head<2>().norm())) {
      const Entity& b = w.entities()[j];
      if (j <= i || !solid(b.cls)) continue;
      EXPECT_FALSE(hameritt::geometry::footprintsOverlap(a.box, b.box)) << a.id << " " << b.id;
      ++checked;
    }
    if (a.cls != EntityClass::kCar) {
      // Buildings stand beyond half a street and the sidewalk from every centreline.
      double inner = 1e18;
      for (const auto& c : a.box.corners2()) inner = std::min(inner, streetDistance(w, c));
      EXPECT_GE(inner, 0.5 * w.params().street_width + w.params().sidewalk_width - 0.01) << a.id;
    }
  }
  EXPECT_GT(checked, 50);
}

TEST(GeneratorTest, SameSeedGivesSameBytes) {
  for (ScenarioClass c : kClasses) {
    for (std::uint64_t seed : {1ULL, 42ULL, 0xDEADBEEFULL}) {
      const Scenario a = generateScenario(shippedWorld(), shippedConfig(), c, seed);
      const Scenario b = generateScenario(shippedWorld(), shippedConfig(), c, seed);
      EXPECT_EQ(missionJson(a.mission), missionJson(b.mission));
      EXPECT_EQ(simConfigJson(a.sim), simConfigJson(b.sim));
      const Scenario other = generateScenario(shippedWorld(), shippedConfig(), c, seed + 1);
      EXPECT_NE(simConfigJson(a.sim), simConfigJson(other.sim));
    }
  }
}

TEST(GeneratorTest, BatchIsByteIdenticalWhateverTheJobCount) {
  BatchRequest req;
  req.classes = parseClassList("all");
  req.count = 24;
  req.seed = 77;
  req.out_dir = freshTempDir("jobs1");
  req.jobs = 1;
  generateBatch(shippedWorld(), shippedConfig(), req);
  const std::string one = req.out_dir;
  req.out_dir = freshTempDir("jobs2");
  req.jobs = 2;
  generateBatch(shippedWorld(), shippedConfig(), req);
  const std::string two = req.out_dir;
  req.out_dir = freshTempDir("jobs5");
  req.jobs = 5;
  generateBatch(shippedWorld(), shippedConfig(), req);
  const std::string five = req.out_dir;
  int files = 0;
  for (const auto& e : fs::recursive_directory_iterator(one)) {
    if (!e.is_regular_file()) continue;
    const std::string rel = fs::relative(e.path(), one).string();
    EXPECT_EQ(slurp(e.path().string()), slurp(two + "/" + rel)) << rel;
    EXPECT_EQ(slurp(e.path().string()), slurp(five + "/" + rel)) << rel;
    ++files;
  }
  EXPECT_EQ(files, 2 * 24 + 2);  // two files per scenario, manifest and world
  for (const auto& d : {one, two, five}) fs::remove_all(d);
}

TEST(GeneratorTest, TargetsLieInsideTheirAoiOrBand) {
  for (ScenarioClass c : kClasses) {
    for (std::uint64_t seed = 100; seed < 130; ++seed) {
      const Scenario s = generateScenario(shippedWorld(), shippedConfig(), c, seed);
      ASSERT_FALSE(s.mission.objective.targets.empty());
      for (const auto& t : s.mission.objective.targets) {
        const ScenarioEntity* e = findEntity(s, t.id);
        ASSERT_NE(e, nullptr) << t.id;
        EXPECT_EQ(e->role, "target");
        if (c == ScenarioClass::kRouteSearch) {
          ASSERT_EQ(s.mission.routes.size(), 1u);
          for (double time = 0; time <= e->trajectory.back().t; time += 0.5) {
            const auto p = sampleTrajectory(e->trajectory, time);
            EXPECT_TRUE(s.mission.routes[0].band.contains(Vec2(p.x, p.y))) << seed << " t=" << time;
          }
        } else {
          EXPECT_TRUE(s.mission.aois.front().polygon.contains(e->entity.box.center2())) << seed;
        }
      }
    }
  }
}

TEST(GeneratorTest, PriorsSumToOneAndFavourTheTargetCell) {
  for (std::uint64_t seed = 200; seed < 240; ++seed) {
    const Scenario s = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kAreaSearch, seed);
    ASSERT_EQ(s.mission.priors.size(), s.mission.aois.size());
    const Vec2 target = findEntity(s, s.mission.objective.targets[0].id)->entity.box.center2();
    for (const auto& p : s.mission.priors) {
      const int n = 1 << p.depth;
      EXPECT_GE(n, 2);
      ASSERT_EQ(p.cells.size(), static_cast<std::size_t>(n * n));
      double sum = 0, area = 0, best = 0, target_p = -1;
      for (const auto& c : p.cells) {
        sum += c.probability;
        area += c.polygon.area();
        best = std::max(best, c.probability);
        if (p.aoi_id == "aoi_1" && c.polygon.contains(target)) target_p = c.probability;
      }
      EXPECT_NEAR(sum, 1.0, 1e-9);
      const auto& aoi = *std::find_if(s.mission.aois.begin(), s.mission.aois.end(),
                                      [&](const auto& a) { return a.id == p.aoi_id; });
      EXPECT_NEAR(area, aoi.polygon.area(), 1e-3 * aoi.polygon.area());
      if (p.aoi_id == "aoi_1") {
        EXPECT_EQ(target_p, best) << seed;
        int at_best = 0;
        for (const auto& c : p.cells) at_best += c.probability == best;
        EXPECT_EQ(at_best, 1) << "the target cell's prior is strictly highest";
      }
    }
  }
}

TEST(GeneratorTest, AccessDenialWindowsMatchTheCarsPassage) {
  int kozs = 0;
  for (std::uint64_t seed = 300; seed < 340; ++seed) {
    const Scenario s = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kRouteSearch, seed);
    for (const auto& k : s.mission.kozs) {
      if (k.purpose != "access_denial") continue;
      ASSERT_TRUE(k.window.net && k.window.nlt);
      EXPECT_LT(*k.window.net, *k.window.nlt);
      double end = 0;
      for (const auto& t : s.mission.objective.targets) {
        end = std::max(end, findEntity(s, t.id)->trajectory.back().t);
      }
      // Some target is inside exactly while the window is active (to the 10 ms step).
      bool ever_inside = false;
      for (double time = 0; time <= end; time += 0.01) {
        bool inside = false;
        for (const auto& t : s.mission.objective.targets) {
          const auto p = sampleTrajectory(findEntity(s, t.id)->trajectory, time);
          inside = inside || k.polygon.contains(Vec2(p.x, p.y));
        }
        ever_inside = ever_inside || inside;
        if (inside) {
          EXPECT_TRUE(time >= *k.window.net - 0.011 && time <= *k.window.nlt + 0.011)
              << seed << " " << k.id << " t=" << time;
        }
        if (time > *k.window.net + 0.011 && time < *k.window.nlt - 0.011) {
          EXPECT_TRUE(inside) << seed << " " << k.id << " t=" << time;
        }
      }
      EXPECT_TRUE(ever_inside) << seed << " " << k.id;
      ++kozs;
    }
  }
  EXPECT_GT(kozs, 30);
}

TEST(GeneratorTest, VehicleTrajectoriesStayOnStreets) {
  const World& w = shippedWorld();
  const double half = 0.5 * w.params().street_width;
  for (ScenarioClass c : kClasses) {
    for (std::uint64_t seed = 400; seed < 410; ++seed) {
      const Scenario s = generateScenario(w, shippedConfig(), c, seed);
      for (const auto& e : s.sim.entities) {
        if (e.entity.cls != EntityClass::kCar || e.trajectory.empty()) continue;
        for (std::size_t i = 0; i + 1 < e.trajectory.size(); ++i) {
          EXPECT_GT(e.trajectory[i + 1].t, e.trajectory[i].t);
        }
        const double end = e.trajectory.back().t;
        for (double t = 0; t <= end; t += 1.0) {
          const auto p = sampleTrajectory(e.trajectory, t);
          EXPECT_LE(streetDistance(w, Vec2(p.x, p.y)), half) << e.entity.id << " t=" << t;
          // Speeds stay below the configured maximum (with the sample step as slack).
          const auto q = sampleTrajectory(e.trajectory, t + 1.0);
          EXPECT_LE(std::hypot(q.x - p.x, q.y - p.y), shippedConfig().car_speed.max + 0.5);
        }
      }
    }
  }
}

TEST(GeneratorTest, EveryClassHasMoversConfusersAndPayload) {
  for (ScenarioClass c : kClasses) {
    int confusers = 0, movers = 0;
    for (std::uint64_t seed = 500; seed < 520; ++seed) {
      const Scenario s = generateScenario(shippedWorld(), shippedConfig(), c, seed);
      for (const auto& e : s.sim.entities) {
        confusers += e.role == "confuser";
        movers += !e.trajectory.empty();
      }
      EXPECT_EQ(s.sim.uav.cameras.size(), 2u);
      EXPECT_LT(s.sim.uav.altitude_min, s.sim.uav.altitude_max);
      EXPECT_FALSE(s.mission.relations.empty());
      for (const auto& k : s.mission.kozs) {
        EXPECT_FALSE(k.polygon.contains(Vec2(s.sim.uav.start.x, s.sim.uav.start.y)));
      }
    }
    EXPECT_GT(confusers, 20) << toString(c);
    EXPECT_GE(movers, 20 * 20) << toString(c);  // 20+ movers per scenario
  }
}

TEST(TrajectoryTest, InsideIntervalOfAStraightCrossing) {
  // 10 m/s along x through the square [10, 20] x [-5, 5]: inside from t = 1 to t = 2.
  const Trajectory traj = {{0, 0, 0, 0, 0}, {3, 30, 0, 0, 0}};
  const auto iv = insideInterval(traj, hameritt::geometry::rectangle(Vec2(10, -5), Vec2(20, 5)));
  ASSERT_TRUE(iv.has_value());
  EXPECT_NEAR(iv->first, 1.0, 1e-12);
  EXPECT_NEAR(iv->second, 2.0, 1e-12);
  EXPECT_FALSE(insideInterval(traj, hameritt::geometry::rectangle(Vec2(10, 6), Vec2(20, 9))));
}

TEST(TrajectoryTest, SamplingInterpolatesAndClamps) {
  const Trajectory traj = {{1, 0, 0, 0, 3.0}, {3, 10, 20, 0, -3.0}};
  const auto mid = sampleTrajectory(traj, 2.0);
  EXPECT_DOUBLE_EQ(mid.x, 5.0);
  EXPECT_DOUBLE_EQ(mid.y, 10.0);
  // Yaw goes the short way through pi, not through zero.
  EXPECT_GT(std::abs(mid.yaw), 3.0);
  EXPECT_DOUBLE_EQ(sampleTrajectory(traj, -5).x, 0.0);
  EXPECT_DOUBLE_EQ(sampleTrajectory(traj, 50).y, 20.0);
}

// ------------------------------------------------------------------ bad input

namespace {
std::string writeTemp(const std::string& name, const std::string& content) {
  const std::string dir = freshTempDir("cfg_" + name);
  const std::string path = dir + "/" + name;
  std::ofstream(path) << content;
  return path;
}

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(ConfigTest, ErrorsNameTheFileAndTheField) {
  const std::string good = slurp(defaultConfigDir() + "/world.json");
  auto world_error = [&](const std::string& from, const std::string& to) {
    std::string text = good;
    const auto pos = text.find(from);
    EXPECT_NE(pos, std::string::npos) << from;
    text.replace(pos, from.size(), to);
    const std::string path = writeTemp("world.json", text);
    const std::string msg = errorOf([&] { loadWorldParams(path); });
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    return msg;
  };
  EXPECT_NE(world_error("\"extent_x\": 1000.0", "\"extent_x\": \"wide\"").find("world.extent_x: expected a number"), std::string::npos);
  EXPECT_NE(world_error("\"extent_x\": 1000.0", "\"extent_x\": -5").find("extent_x"), std::string::npos);
  EXPECT_NE(world_error("\"seed\": 1,", "\"seed\": 1, \"colour\": 3,").find("world.colour: unknown key"), std::string::npos);
  EXPECT_NE(world_error("\"lot_depth\": 34.0,", "").find("world.lot_depth: missing required key"), std::string::npos);
  EXPECT_NE(world_error("\"seed\": 1,", "\"seed\": -1,").find("world.seed"), std::string::npos);
  EXPECT_NE(world_error("{", "[").find("malformed JSON"), std::string::npos);

  const std::string gen = slurp(defaultConfigDir() + "/generator.json");
  std::string bad = gen;
  bad.replace(bad.find("\"aoi_length\": [160, 320]"), 24, "\"aoi_length\": [320, 160]");
  const std::string path = writeTemp("generator.json", bad);
  const std::string msg = errorOf([&] { loadGeneratorConfig(path); });
  EXPECT_NE(msg.find(path), std::string::npos) << msg;
  EXPECT_NE(msg.find("generator.aoi_length"), std::string::npos) << msg;
  EXPECT_NE(errorOf([] { loadWorldParams("/nonexistent/world.json"); }).find("cannot open"), std::string::npos);
}

TEST(BatchTest, BadRequestsAreConfigErrors) {
  BatchRequest req;
  req.classes = parseClassList("pursuit");
  req.out_dir = freshTempDir("bad");
  req.count = 0;
  EXPECT_THROW(generateBatch(shippedWorld(), shippedConfig(), req), ConfigError);
  req.count = 1;
  req.jobs = 0;
  EXPECT_THROW(generateBatch(shippedWorld(), shippedConfig(), req), ConfigError);
  EXPECT_THROW(parseClassList("area_search,boat_chase"), ConfigError);
  EXPECT_EQ(parseClassList("route_search,pursuit").size(), 2u);
}

TEST(BatchTest, UnwritableOutputIsAnOutputErrorAndCreatesNothing) {
  const std::string base = freshTempDir("unwritable");
  const std::string file = base + "/plain_file";
  std::ofstream(file) << "x";
  BatchRequest req;
  req.classes = parseClassList("all");
  req.count = 3;
  req.out_dir = file + "/sub";  // a directory below a regular file cannot exist
  EXPECT_THROW(generateBatch(shippedWorld(), shippedConfig(), req), OutputError);
  EXPECT_EQ(std::distance(fs::directory_iterator(base), fs::directory_iterator()), 1);
  fs::remove_all(base);
}

TEST(BatchTest, FailureMidBatchLeavesNoPartialOutput) {
  // Every parking slot taken: route search still works (targets drive), area search cannot
  // place its target. Scenario 0 (route search) is written, scenario 1 fails: all rolled back.
  WorldParams p = loadWorldParams(defaultConfigDir() + "/world.json");
  p.driveway_car_probability = 1.0;
  p.street_parking_probability = 1.0;
  const World full = generateWorld(p);
  BatchRequest req;
  req.classes = parseClassList("route_search,area_search");
  req.count = 4;
  req.jobs = 1;
  req.out_dir = freshTempDir("rollback");
  EXPECT_THROW(generateBatch(full, shippedConfig(), req), GenerationError);
  EXPECT_EQ(std::distance(fs::directory_iterator(req.out_dir), fs::directory_iterator()), 0)
      << "scenario directories, temporaries or a manifest were left behind";
  fs::remove_all(req.out_dir);
}

TEST(BatchTest, ExactSeedRegeneratesOneScenario) {
  const Scenario s = generateScenario(shippedWorld(), shippedConfig(), ScenarioClass::kPursuit, 9191);
  BatchRequest req;
  req.classes = {ScenarioClass::kPursuit};
  req.count = 1;
  req.seed = 9191;
  req.exact_seed = true;
  req.write_world = false;
  req.out_dir = freshTempDir("exact");
  const auto entries = generateBatch(shippedWorld(), shippedConfig(), req);
  ASSERT_EQ(entries.size(), 1u);
  EXPECT_EQ(entries[0].id, s.mission.scenario_id);
  EXPECT_EQ(slurp(req.out_dir + "/" + entries[0].id + "/mission.json"), missionJson(s.mission));
  req.count = 2;
  EXPECT_THROW(generateBatch(shippedWorld(), shippedConfig(), req), ConfigError);
  fs::remove_all(req.out_dir);
}
