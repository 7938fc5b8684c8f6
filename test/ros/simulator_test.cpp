// rostest: the simulator node on the shipped scenario, driven in lock-step as a client would.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <cmath>

#include "hameritt/generation/generator.h"
#include "hameritt/scenario/sim_config_io.h"
#include "hameritt/scenario/world.h"
#include "sim_test_client.h"

using hameritt::testing::SimClient;
namespace sc = hameritt::scenario;

namespace {

constexpr int kRate = 500;  // physics steps per second (the launch file's default)

std::string simConfigPath() {
  std::string p;
  ros::param::get("/simulator/sim_config", p);
  return p;
}

double dist(const nav_msgs::Odometry& o, double x, double y, double z) {
  return std::hypot(std::hypot(o.pose.pose.position.x - x, o.pose.pose.position.y - y),
                    o.pose.pose.position.z - z);
}

}  // namespace

class SimulatorNode : public ::testing::Test {
 protected:
  void SetUp() override {
    client_.connect();
    const auto o = client_.step(1);
    x0_ = o.pose.pose.position.x;
    y0_ = o.pose.pose.position.y;
  }
  SimClient client_;
  double x0_ = 0, y0_ = 0;
};

TEST_F(SimulatorNode, StartsLandedAtTheScenarioStart) {
  const sc::SimConfig cfg = sc::loadSimConfig(simConfigPath());
  EXPECT_NEAR(x0_, cfg.uav.start.x, 0.05);
  EXPECT_NEAR(y0_, cfg.uav.start.y, 0.05);
  EXPECT_LT(client_.odom.pose.pose.position.z, 0.3);
  EXPECT_EQ(client_.odom.header.frame_id, "map");
  EXPECT_EQ(client_.odom.child_frame_id, "uav/base_link");
}

TEST_F(SimulatorNode, TakesOffAndHoldsAPositionSetpoint) {
  client_.setPose(x0_, y0_, 10.0, 0.0);
  client_.step(8 * kRate);  // climb and settle
  for (int i = 0; i < 10; ++i) {
    const auto o = client_.step(kRate / 2);
    EXPECT_LT(dist(o, x0_, y0_, 10.0), 0.3) << "t=" << client_.last_time;
  }
  EXPECT_TRUE(client_.crashes.empty());
}

TEST_F(SimulatorNode, FollowsASquareOfWaypoints) {
  client_.setPose(x0_, y0_, 12.0, 0.0);
  client_.step(8 * kRate);
  const double square[4][2] = {{20, 0}, {20, 20}, {0, 20}, {0, 0}};
  for (const auto& w : square) {
    const double x = x0_ + w[0], y = y0_ + w[1];
    client_.setPose(x, y, 12.0, 0.0);
    double best = 1e9;
    for (int i = 0; i < 75 && best > 1.0; ++i) best = std::min(best, dist(client_.step(kRate / 5), x, y, 12.0));
    EXPECT_LT(best, 1.0) << "waypoint (" << w[0] << ", " << w[1] << ")";
  }
  EXPECT_TRUE(client_.crashes.empty());
}

TEST_F(SimulatorNode, MovingCarGroundTruthFollowsItsTrajectory) {
  const sc::SimConfig cfg = sc::loadSimConfig(simConfigPath());
  int compared = 0;
  for (int k = 0; k < 6; ++k) {
    client_.step(3 * kRate + 7);
    const double t = client_.truth.header.stamp.toSec();
    EXPECT_NEAR(t, client_.last_time, 1e-6);
    for (const auto& e : client_.truth.entities) {
      for (const auto& se : cfg.entities) {
        if (se.entity.id != e.id || se.trajectory.empty() || se.role != "traffic") continue;
        const sc::TrajectoryPoint p = sc::sampleTrajectory(se.trajectory, t);
        EXPECT_NEAR(e.pose.position.x, p.x, 1e-6) << e.id << " t=" << t;
        EXPECT_NEAR(e.pose.position.y, p.y, 1e-6) << e.id << " t=" << t;
        EXPECT_NEAR(2.0 * std::atan2(e.pose.orientation.z, e.pose.orientation.w),
                    p.yaw + 2 * M_PI * std::round((2.0 * std::atan2(e.pose.orientation.z, e.pose.orientation.w) - p.yaw) / (2 * M_PI)),
                    1e-6);
        ++compared;
      }
    }
  }
  EXPECT_GT(compared, 6 * 10);
}

TEST_F(SimulatorNode, FlyingIntoAHouseIsACrash) {
  // A house near the start with a clear straight approach at 4 m above ground.
  const sc::SimConfig cfg = sc::loadSimConfig(simConfigPath());
  const sc::World world = sc::generateWorld(cfg.world);
  const Eigen::Vector3d from(x0_, y0_, 4.0);
  std::string house_id;
  Eigen::Vector3d goal;
  double best = 1e9;
  for (int i = 0; i < static_cast<int>(world.entities().size()); ++i) {
    const auto& e = world.entities()[i];
    if (e.cls != sc::EntityClass::kHouse || e.box.size.z() < 5.0) continue;
    const Eigen::Vector3d c(e.box.center.x(), e.box.center.y(), 4.0);
    const double d = (c - from).norm();
    if (d > best || d > 120) continue;
    bool clear = true;
    for (double off : {-0.6, 0.0, 0.6}) {
      const Eigen::Vector3d side = off * Eigen::Vector3d(-(c - from).y(), (c - from).x(), 0).normalized();
      for (double dz : {-0.4, 0.4}) {
        clear = clear && world.occluders().clear(from + side + Eigen::Vector3d(0, 0, dz),
                                                 c + side + Eigen::Vector3d(0, 0, dz),
                                                 world.occludersOf(i));
      }
    }
    if (clear) best = d, house_id = e.id, goal = c;
  }
  ASSERT_FALSE(house_id.empty()) << "no house with a clear approach near the start";
  client_.setPose(x0_, y0_, 4.0, 0.0);
  client_.step(5 * kRate);
  ASSERT_TRUE(client_.crashes.empty());
  client_.setPose(goal.x(), goal.y(), 4.0, 0.0);
  for (int i = 0; i < 60 && client_.crashes.empty(); ++i) {
    client_.step(kRate / 2);
    ros::spinOnce();
  }
  ros::WallDuration(0.1).sleep();
  ros::spinOnce();
  ASSERT_FALSE(client_.crashes.empty()) << "no crash flying into " << house_id;
  EXPECT_EQ(client_.crashes.front().entity_id, house_id);
  // The UAV stops where it hit.
  const auto a = client_.step(kRate);
  const auto b = client_.step(kRate);
  EXPECT_LT(dist(a, b.pose.pose.position.x, b.pose.pose.position.y, b.pose.pose.position.z), 1e-6);
}

TEST_F(SimulatorNode, SameInputsGiveIdenticalOdometry) {
  auto run = [&]() {
    std::vector<nav_msgs::Odometry> out;
    client_.reset();
    client_.setPose(x0_ + 5, y0_ - 3, 8.0, 0.5);
    for (int i = 0; i < 12; ++i) out.push_back(client_.step(kRate / 4));
    client_.setVelocity(2.0, 1.0, 0.0, 0.2);
    for (int i = 0; i < 12; ++i) out.push_back(client_.step(kRate / 4));
    return out;
  };
  const auto first = run();
  const auto second = run();
  ASSERT_EQ(first.size(), second.size());
  for (std::size_t i = 0; i < first.size(); ++i) {
    EXPECT_EQ(first[i].header.stamp, second[i].header.stamp);
    EXPECT_EQ(first[i].pose.pose.position.x, second[i].pose.pose.position.x) << i;
    EXPECT_EQ(first[i].pose.pose.position.y, second[i].pose.pose.position.y) << i;
    EXPECT_EQ(first[i].pose.pose.position.z, second[i].pose.pose.position.z) << i;
    EXPECT_EQ(first[i].pose.pose.orientation.w, second[i].pose.pose.orientation.w) << i;
    EXPECT_EQ(first[i].twist.twist.linear.x, second[i].twist.twist.linear.x) << i;
  }
  EXPECT_GT(first.back().pose.pose.position.z, 5.0);
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "simulator_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
