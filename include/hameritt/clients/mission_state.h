#pragma once
// The ADK's mission state, read without depending on its message type: the clients subscribe
// to /adk/state as "any message" and look in it for a top-level field that says whether the
// mission is over. ROS-free: works on the message definition text (as ROS transmits it in the
// connection header, nested types after "=====" lines) and the serialized bytes.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace hameritt::clients {

// What a mission-state message says.
struct MissionStateReading {
  std::string state;  // the value of the string field found ("" when only a flag was found)
  bool ended = false;
};

// Decodes the first top-level field that tells the mission's state: a string named state,
// status, phase or data (std_msgs/String), or a bool named ended, done, finished, complete or
// completed. Fields before it may be any ROS type (primitives, time, duration, strings, nested
// messages, fixed and variable arrays). std::nullopt when the definition has no such field, or
// it cannot be decoded (truncated bytes, a type without definition).
std::optional<MissionStateReading> readMissionState(const std::string& definition,
                                                    const std::uint8_t* data, std::size_t size);

// True for state names that mean the mission is over: ended, done, finished, complete(d),
// succeeded, success, failed, failure, aborted, timeout, timed_out, time_up, crashed,
// cancelled (case-insensitive, also as a word of a longer name like "mission_failed").
bool isTerminalState(const std::string& state);

}  // namespace hameritt::clients
