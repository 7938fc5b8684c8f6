#include "hameritt/adk/path_csv.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "hameritt/scenario/error.h"

namespace hameritt::adk {

namespace {

using scenario::ConfigError;

std::string trim(const std::string& s) {
  std::size_t b = 0, e = s.size();
  while (b < e && (s[b] == ' ' || s[b] == '\t')) ++b;
  while (e > b && (s[e - 1] == ' ' || s[e - 1] == '\t')) --e;
  return s.substr(b, e - b);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    out.push_back(
        trim(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

std::string shortest(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, r.ptr);
}

}  // namespace

std::vector<PathSample> parsePathCsv(const std::string& text, const std::string& file) {
  static const char* const kRequired[4] = {"t", "x", "y", "z"};
  std::vector<PathSample> out;
  std::vector<std::string> header;
  std::istringstream in(text);
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (trim(line).empty()) continue;
    const std::string where = file + ":" + std::to_string(line_no) + ": ";
    std::vector<std::string> fields = split(line);
    if (header.empty()) {
      if (fields.size() < 4) {
        throw ConfigError(where + "header: expected the columns t,x,y,z first, got '" + line + "'");
      }
      for (std::size_t c = 0; c < fields.size(); ++c) {
        if (c < 4 && fields[c] != kRequired[c]) {
          throw ConfigError(where + "header column " + std::to_string(c + 1) + ": expected '" +
                            kRequired[c] + "' (the header starts t,x,y,z), got '" + fields[c] +
                            "'");
        }
        if (fields[c].empty()) {
          throw ConfigError(where + "header column " + std::to_string(c + 1) +
                            ": expected a column name, got an empty field");
        }
      }
      header = std::move(fields);
      continue;
    }
    if (fields.size() != header.size()) {
      throw ConfigError(where + "expected " + std::to_string(header.size()) +
                        " fields as in the header, got " + std::to_string(fields.size()));
    }
    double v[4];
    for (int c = 0; c < 4; ++c) {
      if (!scenario::parseNumber(fields[static_cast<std::size_t>(c)], &v[c])) {
        throw ConfigError(where + "column " + std::to_string(c + 1) + " (" + kRequired[c] +
                          "): expected a finite number, got '" +
                          fields[static_cast<std::size_t>(c)] + "'");
      }
    }
    if (!out.empty() && !(v[0] > out.back().t)) {
      throw ConfigError(where + "column 1 (t): expected a time after the previous sample's " +
                        shortest(out.back().t) + " (strictly increasing), got " + shortest(v[0]));
    }
    out.push_back(PathSample{v[0], geometry::Vec3(v[1], v[2], v[3])});
  }
  if (header.empty()) throw ConfigError(file + ": empty file: expected a header t,x,y,z");
  if (out.empty()) throw ConfigError(file + ": no samples: expected rows after the header");
  return out;
}

std::vector<PathSample> readPathCsv(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw ConfigError(path + ": cannot read: " + std::strerror(errno));
  std::ostringstream ss;
  ss << f.rdbuf();
  if (f.bad()) throw ConfigError(path + ": read failed");
  return parsePathCsv(ss.str(), path);
}

std::string pathCsv(const std::vector<PathSample>& path) {
  std::string s = "t,x,y,z\n";
  for (const auto& p : path) {
    s += shortest(p.t) + "," + shortest(p.p.x()) + "," + shortest(p.p.y()) + "," +
         shortest(p.p.z()) + "\n";
  }
  return s;
}

}  // namespace hameritt::adk
