// rostest: a keep-out zone that becomes active mid-flight across the planned path makes the
// follower replan around it, and the flight never enters it while it is active.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include "planner_test_client.h"

using hameritt::geometry::Vec3;

TEST(PlannerReplan, ZoneOpeningAcrossThePathTriggersAReplan) {
  hameritt::testing::FollowerClient client;
  const Vec3 s = client.connect();
  // koz_9 (test/data/replan_mission.json): x in s.x + [215, 245], 200 m wide, from t = 25 s.
  const Vec3 goal = s + Vec3(320, 0, 40);
  client.send({goal});
  EXPECT_EQ(client.waitForEnd(240), "done") << client.progress.message;
  EXPECT_GE(client.max_replans, 1u) << "the zone opening across the path caused no replan";
  bool because_of_zone = false;
  for (const auto& m : client.messages) {
    because_of_zone = because_of_zone || m.find("keep-out zone koz_9 opens across the path") == 0;
  }
  EXPECT_TRUE(because_of_zone) << "no replan for koz_9 opening";
  EXPECT_LT(client.closest(goal), 2.5);
  std::string path;
  ros::param::get("/planner/mission", path);
  const auto mission = hameritt::scenario::loadMission(path);
  const auto bad = client.violations(mission);
  EXPECT_TRUE(bad.empty()) << bad.front();
  EXPECT_TRUE(client.crashes.empty());
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "planner_replan_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
