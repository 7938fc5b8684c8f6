// COP message conversions: claims and perfect-perception reports in, tracks out, a track as the
// TAK bridge sees it, the mission's targets and zones.
#include "hameritt/ros/cop_conversions.h"

#include <gtest/gtest.h>

namespace hameritt::ros_wrappers {
namespace {

hameritt::KeyValue kv(const std::string& k, const std::string& v) {
  hameritt::KeyValue x;
  x.key = k;
  x.value = v;
  return x;
}

TEST(CopConversions, ClaimsAndPerfectPerceptionBecomeObservations) {
  hameritt::Detection d;
  d.header.stamp = ros::Time(12.5);
  d.client = "color_shape_detector";
  d.entity_class = "car";
  d.attributes = {kv("color", "white"), kv("make", "Toyota")};
  d.position.x = 1;
  d.position.y = 2;
  d.position.z = 0.1;
  d.confidence = 1.5f;  // clamped
  const cop::Observation o = fromMsg(d, 3.0);
  EXPECT_DOUBLE_EQ(o.stamp, 12.5);
  EXPECT_EQ(o.position, Eigen::Vector3d(1, 2, 0.1));
  EXPECT_EQ(o.attributes.at("make"), "Toyota");
  EXPECT_DOUBLE_EQ(o.confidence, 1.0);
  EXPECT_EQ(o.source, "color_shape_detector");
  EXPECT_TRUE(o.entity_id.empty());
  EXPECT_DOUBLE_EQ(o.sigma, 3.0);

  hameritt::PerceptionReport r;
  r.header.stamp = ros::Time(3.0);
  r.entities.resize(2);
  r.entities[0].entity_id = "car_706";
  r.entities[0].entity_class = "car";
  r.entities[0].attributes = {kv("color", "white")};
  r.entities[1].entity_id = "ped_3";
  r.entities[1].entity_class = "pedestrian";
  r.entities[1].position.x = -4;
  const std::vector<cop::Observation> os = fromMsg(r, 0.5);
  ASSERT_EQ(os.size(), 2u);
  EXPECT_EQ(os[0].entity_id, "car_706");
  EXPECT_EQ(os[0].source, "perfect_perception");
  EXPECT_DOUBLE_EQ(os[0].confidence, 1.0);
  EXPECT_EQ(os[1].entity_class, "pedestrian");
  EXPECT_DOUBLE_EQ(os[1].position.x(), -4);
  EXPECT_DOUBLE_EQ(os[1].stamp, 3.0);
}

TEST(CopConversions, MissionTargetsAndZones) {
  hameritt::Mission m;
  hameritt::TargetDescription t;
  t.id = "car_706";
  t.entity_class = "car";
  t.make = "Toyota";
  t.color = "white";
  m.objective.targets.push_back(t);
  hameritt::AreaOfInterest a;
  a.id = "aoi_1";
  a.polygon.resize(3);
  a.polygon[1].x = 10;
  m.areas_of_interest.push_back(a);
  hameritt::KeepOutZone k;
  k.id = "koz_1";
  k.purpose = "restricted";
  k.polygon.resize(4);
  k.has_alt_max = true;
  k.alt_max = 50;
  m.keep_out_zones.push_back(k);
  const auto targets = targetsOf(m);
  ASSERT_EQ(targets.size(), 1u);
  EXPECT_EQ(targets[0].attributes,
            (std::map<std::string, std::string>{{"color", "white"}, {"make", "Toyota"}}));
  const auto zones = zonesOf(m);
  ASSERT_EQ(zones.size(), 2u);
  EXPECT_FALSE(zones[0].keep_out);
  EXPECT_DOUBLE_EQ(zones[0].polygon[1].x(), 10);
  EXPECT_TRUE(zones[1].keep_out);
  EXPECT_EQ(zones[1].purpose, "restricted");
  EXPECT_FALSE(zones[1].alt_min.has_value());
  EXPECT_DOUBLE_EQ(*zones[1].alt_max, 50);
}

TEST(CopConversions, TrackToMessageToTakReport) {
  cop::OperationalPicture picture;
  picture.setTargets({{"car_706", "car", {{"color", "white"}}}});
  cop::Observation o;
  o.stamp = 5.0;
  o.position = Eigen::Vector3d(7, -3, 0.2);
  o.entity_class = "car";
  o.attributes = {{"color", "white"}};
  o.confidence = 0.9;
  o.source = "perfect_perception";
  o.entity_id = "car_706";
  o.sigma = 0.5;
  picture.update({o});
  const hameritt::CopTrack m = toMsg(picture.tracks().begin()->second);
  EXPECT_EQ(m.id, "T0001");
  EXPECT_NEAR(m.position.x, 7, 1e-6);
  EXPECT_NEAR(m.position.z, 0.2, 1e-6);
  EXPECT_DOUBLE_EQ(m.first_seen.toSec(), 5.0);
  EXPECT_EQ(m.entity_id, "car_706");
  EXPECT_EQ(m.target_id, "car_706");
  EXPECT_NEAR(m.target_belief, 0.9, 1e-9);
  ASSERT_EQ(m.sources.size(), 1u);
  EXPECT_NEAR(m.position_covariance[0], 0.25, 0.01);
  const cop::TrackReport r = toTrackReport(m);
  EXPECT_NEAR(r.ce, 0.5, 0.01);  // 1-sigma of the larger horizontal axis
  EXPECT_NEAR(r.le, 0.5, 0.01);
  EXPECT_EQ(r.attributes.at("color"), "white");
  EXPECT_EQ(r.target_id, "car_706");
}

}  // namespace
}  // namespace hameritt::ros_wrappers
