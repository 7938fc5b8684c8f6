// rostest: the adk node's mission topics carry every field of mission.json (parsed here
// independently with nlohmann::json), the markers cover every AOI, zone, prior cell and route,
// and no target position appears anywhere.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "adk_test_client.h"
#include "hameritt/Mission.h"
#include "hameritt/MissionState.h"
#include "hameritt/ros/adk_conversions.h"
#include "hameritt/scenario/error.h"
#include "hameritt/generation/generator.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/scenario_io.h"

using nlohmann::ordered_json;

namespace {

ordered_json readJson(const std::string& path) {
  std::ifstream f(path);
  EXPECT_TRUE(f.good()) << path;
  return ordered_json::parse(f);
}

std::string param(const std::string& name) {
  std::string v;
  EXPECT_TRUE(ros::param::get(name, v)) << name;
  return v;
}

void expectPolygon(const ordered_json& j, const std::vector<geometry_msgs::Point>& p,
                   const std::string& what) {
  ASSERT_EQ(j.size(), p.size()) << what;
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_EQ(j[i][0].get<double>(), p[i].x) << what << " vertex " << i;
    EXPECT_EQ(j[i][1].get<double>(), p[i].y) << what << " vertex " << i;
    EXPECT_EQ(p[i].z, 0.0) << what;
  }
}

void expectWindow(const ordered_json& j, const hameritt::TimeWindow& w, const std::string& what) {
  EXPECT_EQ(j.contains("net"), static_cast<bool>(w.has_net)) << what;
  EXPECT_EQ(j.contains("nlt"), static_cast<bool>(w.has_nlt)) << what;
  if (j.contains("net")) {
    EXPECT_EQ(j.at("net").get<double>(), w.net) << what;
  }
  if (j.contains("nlt")) {
    EXPECT_EQ(j.at("nlt").get<double>(), w.nlt) << what;
  }
}

std::string attributeText(const ordered_json& v) {
  return v.is_string() ? v.get<std::string>() : v.dump();
}

// Every field of a mission document against the message.
void expectMissionMatches(const ordered_json& j, const hameritt::Mission& m) {
  EXPECT_EQ(m.header.frame_id, "map");
  EXPECT_EQ(m.scenario_id, j.at("scenario_id"));
  EXPECT_EQ(m.scenario_class, j.at("class"));
  EXPECT_EQ(m.seed, j.at("seed").get<std::uint64_t>());
  EXPECT_EQ(m.origin_latitude, j.at("frame").at("origin").at("latitude").get<double>());
  EXPECT_EQ(m.origin_longitude, j.at("frame").at("origin").at("longitude").get<double>());
  EXPECT_EQ(m.origin_altitude, j.at("frame").at("origin").at("altitude").get<double>());
  EXPECT_EQ(m.time_limit, j.at("time_limit").get<double>());

  const auto& obj = j.at("objective");
  EXPECT_EQ(m.objective.type, obj.at("type"));
  EXPECT_EQ(m.objective.text, obj.at("text"));
  ASSERT_EQ(m.objective.targets.size(), obj.at("targets").size());
  for (std::size_t i = 0; i < m.objective.targets.size(); ++i) {
    const auto& t = obj.at("targets")[i];
    const auto& tm = m.objective.targets[i];
    EXPECT_EQ(tm.id, t.at("id"));
    EXPECT_EQ(tm.entity_class, t.at("class"));
    EXPECT_EQ(tm.vehicle_class, t.at("vehicle_class"));
    EXPECT_EQ(tm.make, t.at("make"));
    EXPECT_EQ(tm.model, t.at("model"));
    EXPECT_EQ(tm.color, t.at("color"));
  }

  ASSERT_EQ(m.areas_of_interest.size(), j.at("areas_of_interest").size());
  for (std::size_t i = 0; i < m.areas_of_interest.size(); ++i) {
    const auto& a = j.at("areas_of_interest")[i];
    EXPECT_EQ(m.areas_of_interest[i].id, a.at("id"));
    expectPolygon(a.at("polygon"), m.areas_of_interest[i].polygon, a.at("id"));
    expectWindow(a.at("time_window"), m.areas_of_interest[i].window, a.at("id"));
  }

  ASSERT_EQ(m.keep_out_zones.size(), j.at("keep_out_zones").size());
  for (std::size_t i = 0; i < m.keep_out_zones.size(); ++i) {
    const auto& k = j.at("keep_out_zones")[i];
    const auto& km = m.keep_out_zones[i];
    EXPECT_EQ(km.id, k.at("id"));
    EXPECT_EQ(km.purpose, k.at("purpose"));
    expectPolygon(k.at("polygon"), km.polygon, k.at("id"));
    EXPECT_EQ(static_cast<bool>(km.has_alt_min), k.at("altitude").contains("min"));
    EXPECT_EQ(static_cast<bool>(km.has_alt_max), k.at("altitude").contains("max"));
    if (km.has_alt_min) {
      EXPECT_EQ(km.alt_min, k.at("altitude").at("min").get<double>());
    }
    if (km.has_alt_max) {
      EXPECT_EQ(km.alt_max, k.at("altitude").at("max").get<double>());
    }
    expectWindow(k.at("time_window"), km.window, k.at("id"));
  }

  ASSERT_EQ(m.area_priors.size(), j.at("area_priors").size());
  for (std::size_t i = 0; i < m.area_priors.size(); ++i) {
    const auto& p = j.at("area_priors")[i];
    const auto& pm = m.area_priors[i];
    EXPECT_EQ(pm.aoi_id, p.at("aoi_id"));
    EXPECT_EQ(pm.depth, p.at("depth").get<int>());
    ASSERT_EQ(pm.cells.size(), p.at("cells").size());
    for (std::size_t c = 0; c < pm.cells.size(); ++c) {
      const auto& cell = p.at("cells")[c];
      EXPECT_EQ(pm.cells[c].id, cell.at("id"));
      EXPECT_EQ(pm.cells[c].row, cell.at("row").get<int>());
      EXPECT_EQ(pm.cells[c].col, cell.at("col").get<int>());
      EXPECT_EQ(pm.cells[c].probability, cell.at("probability").get<double>());
      expectPolygon(cell.at("polygon"), pm.cells[c].polygon, cell.at("id"));
    }
  }

  ASSERT_EQ(m.routes.size(), j.at("routes").size());
  for (std::size_t i = 0; i < m.routes.size(); ++i) {
    const auto& r = j.at("routes")[i];
    const auto& rm = m.routes[i];
    EXPECT_EQ(rm.id, r.at("id"));
    EXPECT_EQ(rm.band_width, r.at("band_width").get<double>());
    expectPolygon(r.at("polyline"), rm.polyline, "polyline");
    expectPolygon(r.at("band_polygon"), rm.band, "band");
    EXPECT_EQ(rm.streets, r.at("streets").get<std::vector<std::string>>());
  }

  ASSERT_EQ(m.relations.size(), j.at("scene_relations").size());
  ASSERT_GT(m.relations.size(), 0u);
  for (std::size_t i = 0; i < m.relations.size(); ++i) {
    const auto& r = j.at("scene_relations")[i];
    const auto& rm = m.relations[i];
    EXPECT_EQ(rm.target_id, r.at("target"));
    EXPECT_EQ((rm.eventually ? "EVENTUALLY_" : "") + rm.op, r.at("operator").get<std::string>());
    EXPECT_EQ(rm.related_id, r.at("related").at("id"));
    EXPECT_EQ(rm.related_class, r.at("related").at("class"));
    const auto& attrs = r.at("related").at("attributes");
    ASSERT_EQ(rm.related_attributes.size(), attrs.size());
    std::size_t a = 0;
    for (auto it = attrs.begin(); it != attrs.end(); ++it, ++a) {
      EXPECT_EQ(rm.related_attributes[a].key, it.key());
      EXPECT_EQ(rm.related_attributes[a].value, attributeText(it.value()));
    }
    const auto& ev = r.at("evidence");
    if (rm.op == "PART_OF") {
      // Membership has no geometric evidence: an empty object, zeros in the message.
      EXPECT_TRUE(ev.empty() || ev.contains("time"));
      EXPECT_EQ(rm.distance, 0.0);
      EXPECT_EQ(rm.bearing_deg, 0.0);
      EXPECT_EQ(rm.dz, 0.0);
      EXPECT_FALSE(rm.line_of_sight);
    } else {
      EXPECT_EQ(rm.distance, ev.at("distance").get<double>());
      EXPECT_EQ(rm.bearing_deg, ev.at("bearing_deg").get<double>());
      EXPECT_EQ(rm.dz, ev.at("dz").get<double>());
      EXPECT_EQ(static_cast<bool>(rm.line_of_sight), ev.at("line_of_sight").get<bool>());
    }
    EXPECT_EQ(static_cast<bool>(rm.has_time), ev.contains("time"));
    if (ev.contains("time")) {
      EXPECT_EQ(rm.time, ev.at("time").get<double>());
    }
    EXPECT_EQ(rm.text, r.at("text"));
  }
  // Every key of the document is one of those compared above.
  std::vector<std::string> keys;
  for (auto it = j.begin(); it != j.end(); ++it) keys.push_back(it.key());
  EXPECT_EQ(keys, (std::vector<std::string>{"schema", "schema_version", "scenario_id", "class",
                                            "seed", "frame", "time_limit", "objective",
                                            "areas_of_interest", "keep_out_zones", "area_priors",
                                            "routes", "scene_relations"}));
}

}  // namespace

TEST(AdkMission, MissionTopicMatchesTheJson) {
  ros::NodeHandle nh;
  hameritt::testing::Collector<hameritt::Mission> mission(nh, "/mission");
  ASSERT_TRUE(mission.waitFor(1, 30)) << "no /mission";
  expectMissionMatches(readJson(param("/adk/mission")), mission.last());
}

// The shipped scenario is an area search without routes or EVENTUALLY relations: the same
// conversion on generated route-search and pursuit missions.
TEST(AdkMission, ConversionOfRouteSearchAndPursuitMissions) {
  namespace sc = hameritt::scenario;
  const sc::World world =
      sc::generateWorld(sc::loadWorldParams(sc::defaultConfigDir() + "/world.json"));
  const sc::GeneratorConfig config =
      sc::loadGeneratorConfig(sc::defaultConfigDir() + "/generator.json");
  bool routes = false, eventually = false;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    for (sc::ScenarioClass cls : {sc::ScenarioClass::kRouteSearch, sc::ScenarioClass::kPursuit}) {
      sc::Scenario s;
      try {
        s = sc::generateScenario(world, config, cls, seed);
      } catch (const sc::GenerationError&) {
        continue;  // a seed without a placement; others cover the class
      }
      const std::string text = sc::missionJson(s.mission);
      const ordered_json j = ordered_json::parse(text);
      const hameritt::Mission m =
          hameritt::ros_wrappers::toMsg(sc::missionFromJson(j, "generated"), ros::Time(0));
      expectMissionMatches(j, m);
      routes = routes || !m.routes.empty();
      for (const auto& r : m.relations) eventually = eventually || r.eventually;
    }
  }
  EXPECT_TRUE(routes);
  EXPECT_TRUE(eventually);
}

TEST(AdkMission, MarkersCoverTheMissionAndNoTargetPositionAppears) {
  ros::NodeHandle nh;
  hameritt::testing::Collector<hameritt::Mission> mission(nh, "/mission");
  hameritt::testing::Collector<visualization_msgs::MarkerArray> markers(nh, "/mission/markers");
  ASSERT_TRUE(mission.waitFor(1, 30));
  ASSERT_TRUE(markers.waitFor(1, 30));
  const hameritt::Mission& m = mission.last();
  std::map<std::string, std::size_t> per_ns;
  for (const auto& mk : markers.last().markers) {
    EXPECT_EQ(mk.header.frame_id, "map");
    ++per_ns[mk.ns];
  }
  std::size_t cells = 0;
  for (const auto& p : m.area_priors) cells += p.cells.size();
  EXPECT_EQ(per_ns["aoi"], m.areas_of_interest.size());
  EXPECT_EQ(per_ns["koz"], m.keep_out_zones.size());
  EXPECT_EQ(per_ns["koz_walls"], m.keep_out_zones.size());
  EXPECT_EQ(per_ns["prior"], cells);
  EXPECT_EQ(per_ns["route"], m.routes.size());
  EXPECT_GT(cells, 0u);

  // Targets' positions from the sim_config (which clients never see).
  const ordered_json sim = readJson(param("/adk/sim_config"));
  std::vector<std::pair<double, double>> targets;
  for (const auto& e : sim.at("entities")) {
    if (e.at("role") == "target") targets.emplace_back(e.at("pose").at("x"), e.at("pose").at("y"));
  }
  ASSERT_FALSE(targets.empty());
  auto far = [&](const geometry_msgs::Point& p, const std::string& what) {
    for (const auto& [x, y] : targets) {
      EXPECT_GT(std::hypot(p.x - x, p.y - y), 1.0) << what << " at a target position";
    }
  };
  for (const auto& a : m.areas_of_interest)
    for (const auto& p : a.polygon) far(p, "AOI");
  for (const auto& k : m.keep_out_zones)
    for (const auto& p : k.polygon) far(p, "KOZ");
  for (const auto& pr : m.area_priors) {
    for (const auto& c : pr.cells)
      for (const auto& p : c.polygon) far(p, "prior cell");
  }
  for (const auto& r : m.routes) {
    for (const auto& p : r.polyline) far(p, "route");
    for (const auto& p : r.band) far(p, "band");
  }
  for (const auto& mk : markers.last().markers) {
    far(mk.pose.position, "marker " + mk.ns);
    for (const auto& p : mk.points) far(p, "marker " + mk.ns);
  }
  // Nor as text (the coordinates as written in sim_config).
  for (const auto& e : sim.at("entities")) {
    if (e.at("role") != "target") continue;
    const std::string x = e.at("pose").at("x").dump();
    for (const auto& r : m.relations) EXPECT_EQ(r.text.find(x), std::string::npos);
    EXPECT_EQ(m.objective.text.find(x), std::string::npos);
  }
}

TEST(AdkMission, StateIsWaitingWithoutSimTime) {
  ros::NodeHandle nh;
  hameritt::testing::Collector<hameritt::MissionState> state(nh, "/adk/state");
  ASSERT_TRUE(state.waitFor(1, 30));
  EXPECT_EQ(state.last().state, "waiting");
  EXPECT_EQ(state.last().mode, "maneuver_only");
  EXPECT_EQ(state.last().time_limit, 472.0);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "adk_mission_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
