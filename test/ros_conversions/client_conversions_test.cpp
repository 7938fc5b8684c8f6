// ROS message conversions of the baseline clients: the mission message both ways (every shipped
// and test mission survives toMsg -> fromMsg byte for byte as mission.json), camera images and
// intrinsics, claims, and the ADK state read from a message of any type. No ROS master needed.
#include "hameritt/ros/client_conversions.h"

#include <gtest/gtest.h>
#include <std_msgs/String.h>

#include <cmath>

#include "hameritt/ros/mission_conversions.h"
#include "hameritt/scenario/error.h"
#include "hameritt/scenario/mission_io.h"
#include "hameritt/scenario/scenario_io.h"
#include "hameritt/scenario/sim_config_io.h"

namespace hameritt::ros_wrappers {
namespace {

TEST(MissionConversions, RoundTripKeepsEveryField) {
  // The avoid mission has phases and a moving keep-out zone.
  for (const char* file : {"scenarios/default/mission.json", "test/data/replan_mission.json",
                           "test/data/avoid_mission.json"}) {
    const scenario::Mission m = scenario::loadMission(file);
    const hameritt::Mission msg = toMsg(m);
    EXPECT_EQ(msg.scenario_class, scenario::toString(m.cls));
    EXPECT_EQ(msg.areas_of_interest.size(), m.aois.size());
    EXPECT_EQ(scenario::missionJson(fromMsg(msg)), scenario::missionJson(m)) << file;
  }
  // A route mission with an EVENTUALLY_ relation and an integer attribute.
  scenario::Mission m = scenario::loadMission("scenarios/default/mission.json");
  m.cls = scenario::ScenarioClass::kRouteSearch;
  scenario::RouteOfInterest r;
  r.id = "route_1";
  r.polyline = {{0, 0}, {100, 0}};
  r.streets = {"street_1"};
  r.band_width = 40;
  r.band = geometry::bufferPolyline(r.polyline, 40);
  m.routes.push_back(r);
  m.relations.back().eventually = true;
  m.relations.back().time = 12.5;
  const scenario::Mission back = fromMsg(toMsg(m));
  ASSERT_EQ(back.routes.size(), 1u);
  EXPECT_EQ(back.routes[0].band.vertices(), r.band.vertices());
  EXPECT_TRUE(back.relations.back().eventually);
  EXPECT_EQ(back.relations.back().time, 12.5);
  EXPECT_EQ(back.relations.back().related_attributes.integer("storeys", -1), 2);
}

// The phases of a mission, one of each type, survive the message byte for byte; an unknown
// phase type is refused.
TEST(MissionConversions, PhasesRoundTrip) {
  scenario::Mission m = scenario::loadMission("scenarios/default/mission.json");
  const std::string target = m.objective.targets.front().id;
  scenario::MissionPhase search, follow, track, avoid;
  search.id = "search_1";
  search.targets = {target};
  follow.id = "follow_1";
  follow.type = scenario::PhaseType::kFollow;
  follow.targets = {target};
  follow.duration = 75.0;
  follow.follow.distance = 12.0;
  follow.follow.distance_tolerance = 6.0;
  follow.follow.height = 31.0;
  follow.follow.height_tolerance = 7.0;
  follow.follow.approach_s = 34.0;
  track.id = "track_1";
  track.type = scenario::PhaseType::kTrack;
  track.targets = {target};
  track.duration = 40.0;
  track.track.min_box_area = 900.0;
  avoid.id = "avoid_1";
  avoid.type = scenario::PhaseType::kAvoid;
  avoid.avoid.goal = geometry::Vec3(10.5, -20.25, 30.0);
  avoid.avoid.shortest_path_m = 250.5;
  m.phases = {search, follow, track, avoid};
  const std::string json = scenario::missionJson(m);
  hameritt::Mission msg = toMsg(m);
  ASSERT_EQ(msg.phases.size(), 4u);
  EXPECT_EQ(msg.phases[1].type, "follow");
  EXPECT_DOUBLE_EQ(msg.phases[1].follow_height, 31.0);
  EXPECT_EQ(scenario::missionJson(fromMsg(msg)), json);
  EXPECT_DOUBLE_EQ(msg.phases[1].follow_approach_s, 34.0);
  msg.phases[1].follow_distance = 13.0;  // control: a changed field shows
  EXPECT_NE(scenario::missionJson(fromMsg(msg)), json);
  msg.phases[2].type = "escort";
  EXPECT_THROW(fromMsg(msg), scenario::ConfigError);
}

TEST(MissionConversions, UavSpecRoundTripAndBadMessages) {
  const scenario::SimConfig cfg = scenario::loadSimConfig("scenarios/default/sim_config.json");
  const hameritt::UavSpec msg = toMsg(cfg.uav, cfg.scenario_id);
  EXPECT_EQ(msg.scenario_id, cfg.scenario_id);
  ASSERT_EQ(msg.cameras.size(), 2u);
  EXPECT_EQ(msg.cameras[1].frame_id, "uav/camera_down_optical");
  EXPECT_EQ(msg.cameras[1].mount_rpy_deg.y, 90.0);
  const scenario::UavSpec back = fromMsg(msg);
  EXPECT_EQ(back.altitude_min, cfg.uav.altitude_min);
  EXPECT_EQ(back.altitude_max, cfg.uav.altitude_max);
  EXPECT_EQ(back.max_speed, cfg.uav.max_speed);
  EXPECT_EQ(back.start.x, cfg.uav.start.x);
  EXPECT_EQ(back.start.yaw, cfg.uav.start.yaw);
  ASSERT_EQ(back.cameras.size(), cfg.uav.cameras.size());
  for (std::size_t i = 0; i < back.cameras.size(); ++i) {
    const auto& a = back.cameras[i];
    const auto& b = cfg.uav.cameras[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.mount_xyz, b.mount_xyz);
    EXPECT_EQ(a.mount_rpy, b.mount_rpy);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.hfov_deg, b.hfov_deg);
    EXPECT_EQ(a.rate_hz, b.rate_hz);
    EXPECT_EQ(a.modalities, b.modalities);
  }
  hameritt::UavSpec bad = msg;
  bad.altitude_max = bad.altitude_min;
  EXPECT_THROW(fromMsg(bad), scenario::ConfigError);
  bad = msg;
  bad.cameras[0].hfov_deg = 0;
  EXPECT_THROW(fromMsg(bad), scenario::ConfigError);
  bad = msg;
  bad.max_speed = std::nan("");
  EXPECT_THROW(fromMsg(bad), scenario::ConfigError);
}

TEST(MissionConversions, BadMessagesAreConfigErrors) {
  {
    hameritt::Mission avoid = toMsg(scenario::loadMission("test/data/avoid_mission.json"));
    ASSERT_EQ(avoid.phases.size(), 1u);
    avoid.phases[0].type = "hover";
    EXPECT_THROW(fromMsg(avoid), scenario::ConfigError);
    avoid = toMsg(scenario::loadMission("test/data/avoid_mission.json"));
    bool moving = false;
    for (auto& k : avoid.keep_out_zones) {
      if (k.motion.empty()) continue;
      moving = true;
      k.motion_t.pop_back();  // a stamp short
    }
    ASSERT_TRUE(moving);
    EXPECT_THROW(fromMsg(avoid), scenario::ConfigError);
  }
  hameritt::Mission msg = toMsg(scenario::loadMission("scenarios/default/mission.json"));
  msg.relations[1].op = "EVENTUALLY_ON_TOP_OF";  // the prefixed spelling is understood
  EXPECT_TRUE(fromMsg(msg).relations[1].eventually);
  msg.relations[1].op = "BESIDE";
  EXPECT_THROW(fromMsg(msg), scenario::ConfigError);
  msg = toMsg(scenario::loadMission("scenarios/default/mission.json"));
  msg.scenario_class = "treasure_hunt";
  EXPECT_THROW(fromMsg(msg), scenario::ConfigError);
  msg = toMsg(scenario::loadMission("scenarios/default/mission.json"));
  msg.keep_out_zones[0].polygon.resize(2);
  EXPECT_THROW(fromMsg(msg), scenario::ConfigError);
}

TEST(ClientConversions, ImagesDepthAndIntrinsics) {
  sensor_msgs::Image img;
  img.width = 2;
  img.height = 1;
  img.encoding = "bgr8";
  img.step = 8;  // padded rows
  img.data = {1, 2, 3, 4, 5, 6, 0, 0};
  cv::Mat rgb = rgbFromMsg(img);
  EXPECT_EQ(rgb.at<cv::Vec3b>(0, 0), cv::Vec3b(3, 2, 1));
  EXPECT_EQ(rgb.at<cv::Vec3b>(0, 1), cv::Vec3b(6, 5, 4));
  img.encoding = "mono8";
  EXPECT_THROW(rgbFromMsg(img), scenario::ConfigError);

  sensor_msgs::Image depth;
  depth.width = 2;
  depth.height = 1;
  depth.encoding = "16UC1";
  depth.step = 4;
  depth.data = {0xe8, 0x03, 0, 0};  // 1000 mm, none
  const cv::Mat d = depthFromMsg(depth);
  EXPECT_FLOAT_EQ(d.at<float>(0, 0), 1.0f);
  EXPECT_TRUE(std::isinf(d.at<float>(0, 1)));
  depth.data.resize(2);
  EXPECT_THROW(depthFromMsg(depth), scenario::ConfigError);

  sensor_msgs::CameraInfo info;
  info.width = 640;
  info.height = 480;
  info.K = {500, 0, 319.5, 0, 501, 239.5, 0, 0, 1};
  const clients::PinholeCamera c = fromMsg(info);
  EXPECT_EQ(c.fx, 500);
  EXPECT_EQ(c.fy, 501);
  EXPECT_EQ(c.cx, 319.5);
  EXPECT_EQ(c.cy, 239.5);
  info.K[0] = 0;
  EXPECT_THROW(fromMsg(info), scenario::ConfigError);
}

TEST(ClientConversions, ClaimsAndObservations) {
  const scenario::Mission m = scenario::loadMission("scenarios/default/mission.json");
  const auto& target = m.objective.targets.front();
  const hameritt::Detection d =
      makeDetection("me", target, geometry::Vec3(1, 2, 0), 0.75, ros::Time(12.5));
  EXPECT_EQ(d.header.stamp.toSec(), 12.5);
  EXPECT_EQ(d.header.frame_id, "map");
  EXPECT_EQ(d.description, "white Toyota RAV4 (suv)");
  EXPECT_EQ(d.entity_class, "car");
  ASSERT_EQ(d.attributes.size(), 4u);
  EXPECT_EQ(d.attributes[3].key, "color");
  EXPECT_EQ(d.attributes[3].value, "white");
  EXPECT_FLOAT_EQ(d.confidence, 0.75f);

  hameritt::PerceivedEntity e;
  e.entity_id = "car_706";
  e.role = "target";
  e.entity_class = "car";
  for (const auto& a : d.attributes) e.attributes.push_back(a);
  const clients::Observation o = toObservation(e);
  EXPECT_TRUE(clients::matchesDescription(o, target));
}

TEST(ClientConversions, MissionStateFromAnyMessageType) {
  std_msgs::String s;
  s.data = "mission_ended";
  std::vector<std::uint8_t> buf(ros::serialization::serializationLength(s));
  ros::serialization::OStream out(buf.data(), static_cast<std::uint32_t>(buf.size()));
  ros::serialization::serialize(out, s);
  topic_tools::ShapeShifter shifter;
  shifter.morph(ros::message_traits::md5sum(s), ros::message_traits::datatype(s),
                ros::message_traits::definition(s), "0");
  ros::serialization::IStream in(buf.data(), static_cast<std::uint32_t>(buf.size()));
  shifter.read(in);
  const auto r = readMissionState(shifter);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->state, "mission_ended");
  EXPECT_TRUE(r->ended);
}

TEST(ClientConversions, TargetStateBecomesAVehicleState) {
  hameritt::EntityState e;
  e.pose.position.x = 3.0;
  e.pose.position.y = -4.0;
  e.pose.position.z = 0.1;
  const double yaw = 2.5;
  e.pose.orientation.z = std::sin(0.5 * yaw);
  e.pose.orientation.w = std::cos(0.5 * yaw);
  // 10 m/s along the heading plus 1 m/s across it: the speed is the component along it.
  e.velocity.linear.x = 10.0 * std::cos(yaw) - std::sin(yaw);
  e.velocity.linear.y = 10.0 * std::sin(yaw) + std::cos(yaw);
  clients::VehicleState v = toVehicleState(e, 12.5);
  EXPECT_DOUBLE_EQ(v.t, 12.5);
  EXPECT_DOUBLE_EQ(v.position.x(), 3.0);
  EXPECT_DOUBLE_EQ(v.position.y(), -4.0);
  EXPECT_DOUBLE_EQ(v.position.z(), 0.1);
  EXPECT_NEAR(v.yaw, yaw, 1e-12);
  EXPECT_NEAR(v.speed, 10.0, 1e-12);
  // Backwards (a reversing car): no speed along the heading.
  e.velocity.linear.x = -e.velocity.linear.x;
  e.velocity.linear.y = -e.velocity.linear.y;
  EXPECT_DOUBLE_EQ(toVehicleState(e, 0.0).speed, 0.0);
}

}  // namespace
}  // namespace hameritt::ros_wrappers
