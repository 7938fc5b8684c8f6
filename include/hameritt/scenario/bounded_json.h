#pragma once
// Bounds on every JSON document the project reads (scenario files, configurations, manifests,
// dataset annotations), checked before a parser sees the text: a file larger than the size
// limit is refused before it is read, and nesting deeper than the depth limit is refused by a
// linear scan that holds no more than a counter. Without them 200 KB of "[[[..." makes a
// DOM parser build 100,000 nested values and gigabytes of bookkeeping.
//
// The one entry point for a new reader (the scenario language's parser included) is
// readBoundedJsonFile() for a file, or checkJsonText() for a text already in memory; both throw
// ConfigError (exit code 2 in the tools) naming the file and the limit.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace hameritt::scenario {

// Deepest nesting of arrays and objects accepted: the deepest shipped document (a JSON
// Schema in config/schema/) nests 8 levels.
inline constexpr std::size_t kMaxJsonDepth = 64;
// Largest JSON file accepted: 64 MiB, about 1,000 times the largest generated document
// (a sim_config.json of some 70 KB). A reader of bigger documents passes its own limit.
inline constexpr std::uintmax_t kMaxJsonFileBytes = std::uintmax_t{64} << 20;

// Throws ConfigError "FILE: JSON nested deeper than the limit of 64 levels (at byte N)" when
// arrays and objects in `text` (outside strings) nest deeper than `max_depth`.
void checkJsonDepth(std::string_view text, const std::string& file,
                    std::size_t max_depth = kMaxJsonDepth);

// Throws ConfigError naming `file` and the limit when `text` is larger than `max_bytes` or
// nests deeper than `max_depth`.
void checkJsonText(std::string_view text, const std::string& file,
                   std::uintmax_t max_bytes = kMaxJsonFileBytes,
                   std::size_t max_depth = kMaxJsonDepth);

// The whole content of `path`, refusing (ConfigError naming the file and the limit) a file
// larger than `max_bytes` before reading it (and a pipe that delivers more). ConfigError when
// the file cannot be opened or read.
std::string readBoundedFile(const std::string& path, std::uintmax_t max_bytes = kMaxJsonFileBytes);

// readBoundedFile() then checkJsonDepth(): the text of a JSON file within both limits, ready
// for any parser.
std::string readBoundedJsonFile(const std::string& path,
                                std::uintmax_t max_bytes = kMaxJsonFileBytes,
                                std::size_t max_depth = kMaxJsonDepth);

}  // namespace hameritt::scenario
