// Reading the ADK's mission state from any message type: definitions and serialized bytes built
// by hand as ROS would send them (little-endian, strings and variable arrays length-prefixed).
#include "hameritt/clients/mission_state.h"

#include <gtest/gtest.h>

#include <cstring>

namespace hameritt::clients {
namespace {

class Bytes {
 public:
  Bytes& u8(std::uint8_t v) {
    b_.push_back(v);
    return *this;
  }
  Bytes& u32(std::uint32_t v) {
    for (int i = 0; i < 4; ++i) b_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
  Bytes& f64(double v) {
    std::uint8_t x[8];
    std::memcpy(x, &v, 8);
    b_.insert(b_.end(), x, x + 8);
    return *this;
  }
  Bytes& str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    b_.insert(b_.end(), s.begin(), s.end());
    return *this;
  }
  Bytes& header(const std::string& frame) { return u32(7).u32(12).u32(500).str(frame); }
  const std::vector<std::uint8_t>& get() const { return b_; }

 private:
  std::vector<std::uint8_t> b_;
};

std::optional<MissionStateReading> read(const std::string& def, const Bytes& b) {
  return readMissionState(def, b.get().data(), b.get().size());
}

TEST(MissionState, StringStateAfterAHeader) {
  const std::string def =
      "# The mission state\nHeader header\nstring state  # running | ended\nfloat64 elapsed\n"
      "================================================================================\n"
      "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n";
  auto r = read(def, Bytes().header("map").str("running").f64(12.5));
  ASSERT_TRUE(r);
  EXPECT_EQ(r->state, "running");
  EXPECT_FALSE(r->ended);
  r = read(def, Bytes().header("map").str("TIMED_OUT").f64(12.5));
  ASSERT_TRUE(r);
  EXPECT_TRUE(r->ended);
}

TEST(MissionState, FieldsOfAnyTypeBeforeTheStateAreSkipped) {
  const std::string def =
      "uint8 RUNNING=0\nstring scenario_id\nfloat64[2] window\nhameritt/Item[] items\nint16 n\n"
      "string status\n"
      "================================================================================\n"
      "MSG: hameritt/Item\nstring name\nfloat32[] values\nduration age\n";
  Bytes b;
  b.str("area_search-7").f64(1.0).f64(2.0).u32(2);
  b.str("a").u32(3).u32(0).u32(0).u32(0).u32(1).u32(2);
  b.str("bb").u32(0).u32(1).u32(2);
  b.u8(5).u8(0);
  b.str("mission_succeeded");
  const auto r = read(def, b);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->state, "mission_succeeded");
  EXPECT_TRUE(r->ended);
}

TEST(MissionState, BoolFlagsAndStdMsgsString) {
  const auto flag = read("Header header\nbool ended\n", Bytes().header("").u8(1));
  ASSERT_TRUE(flag);
  EXPECT_TRUE(flag->ended);
  const auto running = read("Header header\nbool ended\n", Bytes().header("").u8(0));
  ASSERT_TRUE(running);
  EXPECT_FALSE(running->ended);
  const auto s = read("string data\n", Bytes().str("done"));
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->ended);
}

TEST(MissionState, UnreadableMessagesSayNothing) {
  EXPECT_FALSE(read("float64 x\nfloat64 y\n", Bytes().f64(1).f64(2)));  // no state field
  EXPECT_FALSE(read("Header header\nstring state\n", Bytes().u32(1)));  // truncated
  EXPECT_FALSE(read("pkg/Unknown thing\nstring state\n", Bytes().str("ended")));
  EXPECT_FALSE(read("string state\n", Bytes().u32(1000).str("x")));  // length past the end
}

TEST(MissionState, TerminalStateNames) {
  for (const char* s : {"ended", "Done", "SUCCEEDED", "failed", "timeout", "timed_out",
                        "mission_complete", "aborted", "time_up", "crashed"}) {
    EXPECT_TRUE(isTerminalState(s)) << s;
  }
  for (const char* s : {"", "running", "waiting", "searching", "pending", "started", "idle"}) {
    EXPECT_FALSE(isTerminalState(s)) << s;
  }
}

}  // namespace
}  // namespace hameritt::clients
