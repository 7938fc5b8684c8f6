#include "hameritt/geometry/time_window.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace hameritt::geometry {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(TimeWindowTest, NoBoundsIsAlwaysActive) {
  const TimeWindow w;
  EXPECT_TRUE(w.unbounded());
  EXPECT_TRUE(w.valid());
  EXPECT_TRUE(w.active(-1e9));
  EXPECT_TRUE(w.active(0.0));
  EXPECT_TRUE(w.active(1e9));
  EXPECT_FALSE(w.active(kNaN));
  EXPECT_TRUE(w.overlaps(0.0, 1.0));
  EXPECT_TRUE(w.overlaps(5.0, 5.0));
  EXPECT_FALSE(w.overlaps(2.0, 1.0));  // empty query interval
}

TEST(TimeWindowTest, OnlyNet) {
  TimeWindow w;
  w.net = 10.0;
  EXPECT_FALSE(w.unbounded());
  EXPECT_TRUE(w.valid());
  EXPECT_FALSE(w.active(9.999));
  EXPECT_TRUE(w.active(10.0));
  EXPECT_TRUE(w.active(1e9));
  EXPECT_FALSE(w.overlaps(0.0, 9.99));
  EXPECT_TRUE(w.overlaps(0.0, 10.0));
  EXPECT_TRUE(w.overlaps(20.0, 30.0));
}

TEST(TimeWindowTest, OnlyNlt) {
  TimeWindow w;
  w.nlt = 5.0;
  EXPECT_FALSE(w.unbounded());
  EXPECT_TRUE(w.valid());
  EXPECT_TRUE(w.active(-100.0));
  EXPECT_TRUE(w.active(5.0));
  EXPECT_FALSE(w.active(5.001));
  EXPECT_TRUE(w.overlaps(5.0, 6.0));
  EXPECT_FALSE(w.overlaps(5.1, 6.0));
  EXPECT_TRUE(w.overlaps(-kInf, kInf));
}

TEST(TimeWindowTest, BothBoundsInclusive) {
  TimeWindow w;
  w.net = 10.0;
  w.nlt = 20.0;
  EXPECT_TRUE(w.valid());
  EXPECT_FALSE(w.active(9.9));
  EXPECT_TRUE(w.active(10.0));
  EXPECT_TRUE(w.active(15.0));
  EXPECT_TRUE(w.active(20.0));
  EXPECT_FALSE(w.active(20.1));
  EXPECT_TRUE(w.overlaps(0.0, 10.0));
  EXPECT_TRUE(w.overlaps(20.0, 30.0));
  EXPECT_TRUE(w.overlaps(12.0, 13.0));
  EXPECT_TRUE(w.overlaps(0.0, 100.0));
  EXPECT_FALSE(w.overlaps(0.0, 5.0));
  EXPECT_FALSE(w.overlaps(21.0, 30.0));
  EXPECT_FALSE(w.overlaps(15.0, 12.0));
}

TEST(TimeWindowTest, SingleInstantWindow) {
  TimeWindow w;
  w.net = 5.0;
  w.nlt = 5.0;
  EXPECT_TRUE(w.valid());
  EXPECT_TRUE(w.active(5.0));
  EXPECT_FALSE(w.active(5.0001));
  EXPECT_TRUE(w.overlaps(0.0, 5.0));
}

TEST(TimeWindowTest, InvertedIsInvalidAndNeverActive) {
  TimeWindow w;
  w.net = 20.0;
  w.nlt = 10.0;
  EXPECT_FALSE(w.valid());
  EXPECT_FALSE(w.active(15.0));
  EXPECT_FALSE(w.active(10.0));
  EXPECT_FALSE(w.active(20.0));
  EXPECT_FALSE(w.overlaps(0.0, 100.0));
}

TEST(TimeWindowTest, NonFiniteBoundsAreInvalid) {
  TimeWindow a;
  a.net = kNaN;
  EXPECT_FALSE(a.valid());
  TimeWindow b;
  b.nlt = kNaN;
  EXPECT_FALSE(b.valid());
  TimeWindow c;
  c.net = 0.0;
  c.nlt = kNaN;
  EXPECT_FALSE(c.valid());
  TimeWindow d;
  d.nlt = kInf;
  EXPECT_FALSE(d.valid());
  TimeWindow e;
  e.net = -kInf;
  EXPECT_FALSE(e.valid());
}

}  // namespace
}  // namespace hameritt::geometry
