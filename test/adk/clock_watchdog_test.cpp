#include "hameritt/adk/clock_watchdog.h"

#include <gtest/gtest.h>

#include <limits>

#include "hameritt/adk/intervals.h"

namespace hameritt::adk {
namespace {

TEST(ClockWatchdog, StallsOnlyAfterTheClockStartedAndStoppedForTheTimeout) {
  ClockWatchdog w(5.0);
  w.clock(0.0, 100.0);  // the simulator waiting for its subscribers (t = 0)
  EXPECT_EQ(w.stalled(200.0), "");
  w.clock(0.004, 201.0);
  w.clock(1.0, 202.0);
  EXPECT_EQ(w.stalled(206.9), "");
  w.clock(1.0, 206.0);  // the same time again is not progress
  const std::string why = w.stalled(207.5);
  EXPECT_NE(why.find("sim time stopped at 1.000 s"), std::string::npos) << why;
  EXPECT_NE(why.find("simulator dead or stalled"), std::string::npos) << why;
  w.clock(1.1, 208.0);
  EXPECT_EQ(w.stalled(208.0), "");
  EXPECT_LT(w.lateStart(), 0.0);
}

TEST(ClockWatchdog, ZeroTimeoutNeverStallsAndBadTimeoutsThrow) {
  ClockWatchdog off(0.0);
  off.clock(1.0, 0.0);
  EXPECT_EQ(off.stalled(1e9), "");
  EXPECT_THROW(ClockWatchdog(-1.0), InputError);
  EXPECT_THROW(ClockWatchdog{std::numeric_limits<double>::infinity()}, InputError);
}

TEST(ClockWatchdog, ReportsALateStart) {
  ClockWatchdog w(5.0);
  w.clock(42.5, 0.0);
  w.clock(43.0, 0.1);
  EXPECT_EQ(w.lateStart(), 42.5);
  ClockWatchdog early(5.0);
  early.clock(0.5, 0.0);
  early.clock(50.0, 1.0);
  EXPECT_LT(early.lateStart(), 0.0);
}

}  // namespace
}  // namespace hameritt::adk
