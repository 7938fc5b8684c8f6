// rostest: perfect perception reports the ground truth of the boxes with enough visible pixels
// (scenario entities from /ground_truth/entities at the image's stamp, parked world cars from
// the world) and nothing else; detection claims are scored (target with first_correct,
// confuser, none); a target seen before the mission runs ends it as a success once it runs
// (maneuver_only: found by sighting).
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <cmath>

#include "adk_test_client.h"
#include "hameritt/BoundingBoxArray.h"
#include "hameritt/Detection.h"
#include "hameritt/DetectionScore.h"
#include "hameritt/EntityStateArray.h"
#include "hameritt/MissionMetrics.h"
#include "hameritt/MissionState.h"
#include "hameritt/PerceptionReport.h"
#include "hameritt/adk/detection_scoring.h"
#include "hameritt/scenario/sim_config_io.h"

using Eigen::Vector3d;
using hameritt::testing::Collector;
using hameritt::testing::spinUntil;

namespace {

std::string param(const std::string& name) {
  std::string v;
  EXPECT_TRUE(ros::param::get(name, v)) << name;
  return v;
}

hameritt::BoundingBox box(const std::string& id, const std::string& role, unsigned visible) {
  hameritt::BoundingBox b;
  b.entity_id = id;
  b.entity_class = "car";
  b.role = role;
  b.instance_id = 7;
  b.x_min = 100;
  b.y_min = 120;
  b.x_max = 140;
  b.y_max = 150;
  b.visible_pixels = visible;
  b.total_pixels = 600;
  b.occlusion = 1.0f - static_cast<float>(visible) / 600.0f;
  return b;
}

hameritt::Detection claim(const Vector3d& p, double stamp) {
  hameritt::Detection d;
  d.header.stamp.fromSec(stamp);
  d.header.frame_id = "map";
  d.client = "adk_perception_test";
  d.description = "white Toyota RAV4";
  d.entity_class = "car";
  d.position.x = p.x();
  d.position.y = p.y();
  d.position.z = p.z();
  d.confidence = 0.9f;
  return d;
}

std::string attribute(const hameritt::PerceivedEntity& e, const std::string& key) {
  for (const auto& kv : e.attributes) {
    if (kv.key == key) return kv.value;
  }
  return "";
}

}  // namespace

TEST(AdkPerception, PerfectPerceptionDetectionScoringAndSuccess) {
  ros::NodeHandle nh;
  namespace sc = hameritt::scenario;
  const sc::SimConfig sim = sc::loadSimConfig(param("/adk/sim_config"));
  const sc::World world = sc::generateCheckedWorld(sim, param("/adk/sim_config"));
  const sc::ScenarioEntity* target = nullptr;
  const sc::ScenarioEntity* confuser = nullptr;
  for (const auto& e : sim.entities) {
    if (e.role == "target" && !target) target = &e;
    if (e.role == "confuser" && !confuser) confuser = &e;
  }
  ASSERT_TRUE(target && confuser);
  const sc::Entity* world_car = nullptr;
  for (const auto& e : world.entities()) {
    if (e.cls == sc::EntityClass::kCar) {
      world_car = &e;
      break;
    }
  }
  ASSERT_TRUE(world_car);

  ros::Publisher truth_pub = nh.advertise<hameritt::EntityStateArray>("/ground_truth/entities", 10);
  ros::Publisher boxes_pub = nh.advertise<hameritt::BoundingBoxArray>("/uav/camera/down/boxes", 10);
  ros::Publisher det_pub = nh.advertise<hameritt::Detection>("/perception/detections", 10);
  hameritt::testing::FakeSimulator fake(nh);
  Collector<hameritt::PerceptionReport> reports(nh, "/adk/perfect_perception");
  Collector<hameritt::DetectionScore> scores(nh, "/adk/detection_scores");
  Collector<hameritt::MissionState> state(nh, "/adk/state");
  Collector<hameritt::MissionMetrics> metrics(nh, "/adk/metrics");
  ASSERT_TRUE(spinUntil(
      [&] {
        return truth_pub.getNumSubscribers() > 0 && boxes_pub.getNumSubscribers() > 0 &&
               det_pub.getNumSubscribers() > 0 && reports.connected() && scores.connected() &&
               state.connected();
      },
      30))
      << "adk node not connected";
  ASSERT_TRUE(fake.waitForSubscribers(10));

  // Ground truth at 4 s and 6 s; the target moves 0.8 m east in between (the node must take
  // the ground truth at the image's stamp, 5 s, not the sim_config pose).
  const Vector3d target0 = target->entity.position();
  auto publishTruth = [&](double t, double shift) {
    hameritt::EntityStateArray a;
    a.header.stamp.fromSec(t);
    a.header.frame_id = "map";
    for (const auto& e : sim.entities) {
      const auto truth = hameritt::adk::scenarioEntityAt(e, t);
      hameritt::EntityState s;
      s.header = a.header;
      s.id = truth.id;
      s.entity_class = truth.cls;
      s.role = truth.role;
      s.pose.position.x = truth.position.x() + (e.role == "target" ? shift : 0.0);
      s.pose.position.y = truth.position.y();
      s.pose.position.z = truth.position.z();
      s.pose.orientation.z = std::sin(0.5 * truth.yaw);
      s.pose.orientation.w = std::cos(0.5 * truth.yaw);
      a.entities.push_back(s);
    }
    truth_pub.publish(a);
  };
  publishTruth(4.0, 0.0);
  publishTruth(6.0, 0.8);
  spinUntil([] { return false; }, 0.5);  // let the node take both snapshots first

  hameritt::BoundingBoxArray frame;
  frame.header.stamp.fromSec(5.0);
  frame.header.frame_id = "uav/camera_down_optical";
  frame.camera = "down";
  frame.boxes = {box(target->entity.id, "target", 500), box(confuser->entity.id, "confuser", 19),
                 box(world_car->id, "world", 200), box("house_3", "world", 900)};
  boxes_pub.publish(frame);
  ASSERT_TRUE(reports.waitFor(1, 10)) << "no perfect perception report";
  {
    const auto& r = reports.all[0];
    EXPECT_EQ(r.header.stamp.toSec(), 5.0);
    EXPECT_EQ(r.header.frame_id, "uav/camera_down_optical");
    EXPECT_EQ(r.camera, "down");
    ASSERT_EQ(r.entities.size(), 2u);  // not the confuser (19 < 20 px), not the house
    const auto& t = r.entities[0];
    EXPECT_EQ(t.entity_id, target->entity.id);
    EXPECT_EQ(t.role, "target");
    EXPECT_EQ(t.entity_class, "car");
    EXPECT_EQ(attribute(t, "make"), target->entity.attributes.str("make"));
    EXPECT_EQ(attribute(t, "color"), target->entity.attributes.str("color"));
    EXPECT_NEAR(t.position.x, target0.x() + 0.4, 1e-9);
    EXPECT_NEAR(t.position.y, target0.y(), 1e-9);
    EXPECT_NEAR(t.yaw, target->entity.yaw(), 1e-6);
    EXPECT_EQ(t.box.visible_pixels, 500u);
    const auto& w = r.entities[1];
    EXPECT_EQ(w.entity_id, world_car->id);
    EXPECT_EQ(w.role, "world");
    EXPECT_NEAR(w.position.x, world_car->position().x(), 1e-9);
    EXPECT_NEAR(w.position.y, world_car->position().y(), 1e-9);
    EXPECT_EQ(attribute(w, "make"), world_car->attributes.str("make"));
  }
  // Below the threshold, and a frame with nothing visible (no boxes at all): empty reports.
  frame.boxes = {box(target->entity.id, "target", 19)};
  boxes_pub.publish(frame);
  frame.boxes.clear();
  boxes_pub.publish(frame);
  ASSERT_TRUE(reports.waitFor(3, 10));
  EXPECT_TRUE(reports.all[1].entities.empty());
  EXPECT_TRUE(reports.all[2].entities.empty());

  // Detection claims at 5 s: on the confuser, on nothing, twice on the target.
  const Vector3d confuser_at = hameritt::adk::scenarioEntityAt(*confuser, 5.0).position;
  det_pub.publish(claim(confuser_at + Vector3d(0.5, 0, 0), 5.0));
  det_pub.publish(claim(Vector3d(1000, 1000, 0), 5.0));
  det_pub.publish(claim(target0 + Vector3d(0.4 + 1.0, 0, 0), 5.0));
  det_pub.publish(claim(target0 + Vector3d(0.4, 2.0, 0), 5.0));
  ASSERT_TRUE(scores.waitFor(4, 10));
  EXPECT_EQ(scores.all[0].verdict, "confuser");
  EXPECT_EQ(scores.all[0].matched_entity_id, confuser->entity.id);
  EXPECT_NEAR(scores.all[0].position_error, 0.5, 1e-9);
  EXPECT_FALSE(scores.all[0].first_correct);
  EXPECT_EQ(scores.all[1].verdict, "none");
  EXPECT_EQ(scores.all[1].matched_entity_id, "");
  EXPECT_EQ(scores.all[2].verdict, "target");
  EXPECT_EQ(scores.all[2].matched_entity_id, target->entity.id);
  EXPECT_EQ(scores.all[2].matched_role, "target");
  EXPECT_NEAR(scores.all[2].position_error, 1.0, 1e-9);  // against the ground truth at 5 s
  EXPECT_TRUE(scores.all[2].first_correct);
  EXPECT_EQ(scores.all[3].verdict, "target");
  EXPECT_FALSE(scores.all[3].first_correct);
  EXPECT_EQ(scores.all[2].detection.client, "adk_perception_test");

  // Nothing ends before the mission runs; once sim time and odometry come, the target already
  // seen ends it with success.
  ASSERT_TRUE(spinUntil([&] { return !state.all.empty(); }, 5));
  EXPECT_EQ(state.last().state, "waiting");
  EXPECT_TRUE(metrics.all.empty());
  for (int k = 1; k <= 10; ++k) {
    fake.publish(5.0 + 0.02 * k, Vector3d(0, 0, 0.1), Vector3d::Zero());
    ros::WallDuration(0.005).sleep();
  }
  ASSERT_TRUE(metrics.waitFor(1, 10)) << "no /adk/metrics";
  ASSERT_TRUE(spinUntil([&] { return state.last().state == "succeeded"; }, 5))
      << state.last().state;
  const auto& m = metrics.last();
  EXPECT_EQ(m.outcome, "success");
  EXPECT_EQ(m.mode, "maneuver_only");
  ASSERT_EQ(m.targets.size(), 1u);
  EXPECT_TRUE(m.targets[0].found);
  EXPECT_TRUE(m.targets[0].has_first_seen_time);
  EXPECT_EQ(m.targets[0].first_seen_time, 5.0);
  EXPECT_TRUE(m.targets[0].has_first_correct_time);
  EXPECT_EQ(m.targets[0].first_correct_time, 5.0);
  EXPECT_NEAR(m.targets[0].in_view_time, 0.1, 1e-9);  // one frame at 10 Hz
  EXPECT_EQ(m.detections, 4u);
  EXPECT_EQ(m.correct_detections, 2u);
  EXPECT_EQ(m.false_on_confusers, 1u);
  EXPECT_EQ(m.false_on_nothing, 1u);
  EXPECT_EQ(m.false_on_other_entities, 0u);
  EXPECT_EQ(m.koz_violation_count, 0u);
  EXPECT_EQ(m.metrics_file, "");
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "adk_perception_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
