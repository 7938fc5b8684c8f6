#pragma once
// Typed errors of the scenario module. Each message names the file (when there is one), the
// field (a JSON path) and what was expected.

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace hameritt::scenario {

// A double with all its significant digits, for error messages ("got 1e-05", "got 0.1").
inline std::string formatNumber(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

// The whole of `text` as a finite double (command-line values, CSV fields): false, and `value`
// untouched, for "", "1.5x", "nan", "1e999" or an underflow like "1e-999".
inline bool parseNumber(const std::string& text, double* value) {
  std::size_t used = 0;
  double v = 0.0;
  try {
    v = std::stod(text, &used);  // throws on no number and on ERANGE
  } catch (...) {
    return false;
  }
  if (text.empty() || used != text.size() || !std::isfinite(v)) return false;
  *value = v;
  return true;
}

// Bad configuration or input document: exit code 2 in the command-line tools.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Output could not be written (unwritable directory, full disk): exit code 2.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A scenario could not be generated with the given settings (e.g. no placement satisfies the
// constraints): exit code 1, with the class and seed in the message.
class GenerationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace hameritt::scenario
