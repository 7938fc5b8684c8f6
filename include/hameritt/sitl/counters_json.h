#pragma once

#include <cstdint>
#include <initializer_list>
#include <string>
#include <utility>

namespace hameritt::sitl {

// A flat JSON object of named counters, in the given order: {"name": value, ...}. The servers'
// counters go out on ~autopilot_counters in this form (docs/reference/nodes.md).
inline std::string countersJson(
    std::initializer_list<std::pair<const char*, std::uint64_t>> fields) {
  std::string out = "{";
  for (const auto& [k, v] : fields) {
    if (out.size() > 1) out += ", ";
    out += std::string("\"") + k + "\": " + std::to_string(v);
  }
  return out + "}";
}

}  // namespace hameritt::sitl
