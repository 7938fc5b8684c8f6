#pragma once
// Timed UAV paths as CSV, for checking a flown or planned path offline (hameritt_check_path).
//
// Format: a header line whose first four columns are exactly `t,x,y,z` (mission time in
// seconds, ENU metres); further named columns (yaw, vx, ...) are allowed and ignored, so a log
// with more fields can be checked as it is. Then one row per sample with as many fields as the
// header; t, x, y, z finite numbers; t strictly increasing. Fields may be padded with spaces;
// CRLF line ends and empty lines are accepted; there are no comments and no quoting.

#include <string>
#include <vector>

#include "hameritt/geometry/types.h"

namespace hameritt::adk {

struct PathSample {
  double t = 0.0;
  geometry::Vec3 p{0, 0, 0};
};

// Parses CSV text; `file` names the source in errors. Throws scenario::ConfigError
// "FILE:LINE: column N (name): expected ..., got '...'" for the first problem, or
// "FILE: no samples" for a file without rows.
std::vector<PathSample> parsePathCsv(const std::string& text, const std::string& file);

// Reads and parses a CSV file (ConfigError naming the file when it cannot be read).
std::vector<PathSample> readPathCsv(const std::string& path);

// The path as CSV text with the `t,x,y,z` header, numbers in the shortest form that reads back
// to the same double.
std::string pathCsv(const std::vector<PathSample>& path);

}  // namespace hameritt::adk
