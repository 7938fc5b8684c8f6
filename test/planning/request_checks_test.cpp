#include "hameritt/planning/request_checks.h"

#include <gtest/gtest.h>

#include <limits>

namespace hameritt::planning {
namespace {

TEST(CheckPoint, NamesTheFieldAndAxis) {
  EXPECT_EQ(checkPoint(geometry::Vec3(1, 2, 3), "start"), "");
  EXPECT_EQ(checkPoint(geometry::Vec3(1, std::numeric_limits<double>::quiet_NaN(), 3), "start"),
            "start.y: expected a finite coordinate (m), got nan");
}

TEST(CheckWaypoints, AcceptsFiniteListsWithinTheLimit) {
  EXPECT_EQ(checkWaypoints({geometry::Vec3(1, 2, 3)}, "waypoints"), "");
  EXPECT_EQ(checkWaypoints(std::vector<geometry::Vec3>(kMaxWaypoints, geometry::Vec3(1e9, -1e9, 0)),
                           "waypoints"),
            "");
}

TEST(CheckWaypoints, RefusesEmptyHugeAndNonFiniteListsNamingTheField) {
  EXPECT_EQ(checkWaypoints({}, "poses"),
            "poses: expected at least one waypoint (the goal), got none");
  EXPECT_EQ(checkWaypoints(std::vector<geometry::Vec3>(kMaxWaypoints + 1), "poses"),
            "poses: expected at most 1000 waypoints, got 1001");
  std::vector<geometry::Vec3> pts(5, geometry::Vec3(0, 0, 30));
  pts[3].z() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(checkWaypoints(pts, "waypoints"),
            "waypoints[3].z: expected a finite coordinate (m), got nan");
  pts[3].z() = 1;
  pts[0].x() = -std::numeric_limits<double>::infinity();
  EXPECT_NE(checkWaypoints(pts, "waypoints").find("waypoints[0].x: expected a finite"),
            std::string::npos);
}

}  // namespace
}  // namespace hameritt::planning
