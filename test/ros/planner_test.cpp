// rostest: waypoints sent to the planner node make the simulated UAV reach them without a
// keep-out-zone violation; the PlanPath service answers with a valid timed path or an error.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include "hameritt/PlanPath.h"
#include "planner_test_client.h"

using hameritt::geometry::Vec3;

namespace {
std::string param(const std::string& name) {
  std::string v;
  ros::param::get(name, v);
  return v;
}
}  // namespace

TEST(PlannerNode, WaypointsAreReachedWithoutKeepOutViolation) {
  hameritt::testing::FollowerClient client;
  const Vec3 s = client.connect();
  const std::vector<Vec3> wps = {s + Vec3(60, 20, 35), s + Vec3(120, -30, 40),
                                 s + Vec3(40, -60, 30)};
  client.send(wps);
  EXPECT_EQ(client.waitForEnd(240), "done") << client.progress.message;
  for (const auto& w : wps) EXPECT_LT(client.closest(w), 2.0 + 0.5);
  // Nothing blocks this flight: it follows its first plan without replanning.
  EXPECT_EQ(client.max_replans, 0u) << (client.messages.empty() ? "" : client.messages.back());
  const auto mission = hameritt::scenario::loadMission(param("/planner/mission"));
  const auto bad = client.violations(mission);
  EXPECT_TRUE(bad.empty()) << bad.front();
  EXPECT_TRUE(client.crashes.empty());
}

TEST(PlannerNode, PlanPathServiceAnswersWithATimedPathOrAnError) {
  ASSERT_TRUE(ros::service::waitForService("/planner/plan_path", ros::Duration(30)));
  hameritt::PlanPath srv;
  srv.request.start.x = -279.0;
  srv.request.start.y = -258.0;
  srv.request.start.z = 30.0;
  geometry_msgs::Point goal;
  goal.x = -100.0;
  goal.y = -200.0;
  goal.z = 40.0;
  srv.request.waypoints.push_back(goal);
  srv.request.seed = 5;
  ASSERT_TRUE(ros::service::call("/planner/plan_path", srv));
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(srv.response.status, "exact");
  ASSERT_GE(srv.response.path.poses.size(), 2u);
  const auto& last = srv.response.path.poses.back().pose.position;
  EXPECT_NEAR(last.x, goal.x, 1e-3);
  EXPECT_NEAR(last.y, goal.y, 1e-3);
  EXPECT_GT(srv.response.duration, 0.0);
  EXPECT_GT(srv.response.path.poses.back().header.stamp.toSec(),
            srv.response.path.poses.front().header.stamp.toSec());

  srv.request.algorithm = "bfs";
  ASSERT_TRUE(ros::service::call("/planner/plan_path", srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_EQ(srv.response.code, 2);

  srv.request.algorithm = "";
  srv.request.waypoints[0].z = 500.0;  // above the flight band
  ASSERT_TRUE(ros::service::call("/planner/plan_path", srv));
  EXPECT_FALSE(srv.response.success);
  EXPECT_EQ(srv.response.code, 1);
  EXPECT_EQ(srv.response.status, "invalid_goal");
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "planner_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
