// rostest: a 6 m/s east wind pushes the UAV (it must lean into the wind to hold position) and
// the controller compensates (it holds position anyway).
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <Eigen/Geometry>

#include "sim_test_client.h"

using hameritt::testing::SimClient;

TEST(SimulatorWind, ControllerLeansIntoTheWindAndHoldsPosition) {
  SimClient client;
  client.connect();
  const auto o = client.step(1);
  const double x0 = o.pose.pose.position.x, y0 = o.pose.pose.position.y;
  client.setPose(x0, y0, 15.0, 0.0);
  client.step(15 * 500);  // climb and settle in the wind
  double worst = 0, lean = 0;
  for (int i = 0; i < 10; ++i) {
    const auto s = client.step(250);
    const auto& p = s.pose.pose.position;
    worst = std::max(worst, std::hypot(std::hypot(p.x - x0, p.y - y0), p.z - 15.0));
    const auto& q = s.pose.pose.orientation;
    const Eigen::Vector3d up = Eigen::Quaterniond(q.w, q.x, q.y, q.z) * Eigen::Vector3d::UnitZ();
    lean += up.x() / 10.0;  // thrust axis tilted towards -x (into an eastward wind) is negative
  }
  EXPECT_LT(worst, 0.5) << "position error in a 6 m/s wind";
  EXPECT_LT(lean, -std::sin(3.0 * M_PI / 180.0)) << "the UAV must lean into the wind to hold";
  EXPECT_TRUE(client.crashes.empty());
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "simulator_wind_test");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
