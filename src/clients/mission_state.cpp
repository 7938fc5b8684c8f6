#include "hameritt/clients/mission_state.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <map>
#include <sstream>
#include <vector>

namespace hameritt::clients {

namespace {

struct Field {
  std::string type;  // base type ("uint8", "string", "std_msgs/Header", "Foo")
  std::string name;
  int array = -1;  // -1 scalar, 0 variable length, N fixed length
};

using Definitions = std::map<std::string, std::vector<Field>>;

std::string trim(const std::string& s) {
  std::size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

std::string lower(std::string s) {
  for (auto& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Splits a full definition into the top-level message ("") and its nested types ("pkg/Type").
Definitions parseDefinitions(const std::string& text) {
  Definitions defs;
  std::string current;
  defs[current];
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line = line.substr(0, hash);
    line = trim(line);
    if (line.empty()) continue;
    if (line.rfind("===", 0) == 0) continue;
    if (line.rfind("MSG:", 0) == 0) {
      current = trim(line.substr(4));
      defs[current];
      continue;
    }
    std::istringstream ls(line);
    std::string type, name;
    ls >> type >> name;
    if (type.empty() || name.empty()) continue;
    if (name.find('=') != std::string::npos || line.find('=') != std::string::npos) continue;
    Field f;
    f.name = name;
    const std::size_t br = type.find('[');
    if (br != std::string::npos) {
      const std::string n = type.substr(br + 1, type.size() - br - 2);
      f.array = n.empty() ? 0 : std::atoi(n.c_str());
      type = type.substr(0, br);
    }
    f.type = type;
    defs[current].push_back(f);
  }
  return defs;
}

int primitiveSize(const std::string& t) {
  if (t == "bool" || t == "int8" || t == "uint8" || t == "byte" || t == "char") return 1;
  if (t == "int16" || t == "uint16") return 2;
  if (t == "int32" || t == "uint32" || t == "float32") return 4;
  if (t == "int64" || t == "uint64" || t == "float64" || t == "time" || t == "duration") return 8;
  return 0;
}

class Reader {
 public:
  Reader(const Definitions& defs, const std::uint8_t* data, std::size_t size)
      : defs_(defs), data_(data), size_(size) {}

  bool u32(std::uint32_t* v) {
    if (pos_ + 4 > size_) return false;
    std::memcpy(v, data_ + pos_, 4);  // ROS serializes little-endian
    pos_ += 4;
    return true;
  }
  bool u8(std::uint8_t* v) {
    if (pos_ + 1 > size_) return false;
    *v = data_[pos_++];
    return true;
  }
  bool str(std::string* s) {
    std::uint32_t n = 0;
    if (!u32(&n) || pos_ + n > size_) return false;
    s->assign(reinterpret_cast<const char*>(data_ + pos_), n);
    pos_ += n;
    return true;
  }
  bool skipBytes(std::size_t n) {
    if (pos_ + n > size_) return false;
    pos_ += n;
    return true;
  }
  // Skips one value of `type` (a scalar); nested types are looked up by full or short name.
  bool skipValue(const std::string& type, const std::string& package, int depth = 0) {
    if (depth > 32) return false;
    const int p = primitiveSize(type);
    if (p > 0) return skipBytes(static_cast<std::size_t>(p));
    if (type == "string") {
      std::string s;
      return str(&s);
    }
    const std::vector<Field>* fields = find(type, package);
    if (!fields) return false;
    const std::string pkg =
        type.find('/') != std::string::npos ? type.substr(0, type.find('/')) : package;
    for (const auto& f : *fields) {
      if (!skipField(f, pkg, depth + 1)) return false;
    }
    return true;
  }

  bool skipField(const Field& f, const std::string& package, int depth = 0) {
    if (f.array < 0) return skipValue(f.type, package, depth);
    std::uint32_t n = static_cast<std::uint32_t>(f.array);
    if (f.array == 0 && !u32(&n)) return false;
    const int p = primitiveSize(f.type);
    if (p > 0) return skipBytes(static_cast<std::size_t>(p) * n);
    for (std::uint32_t i = 0; i < n; ++i) {
      if (!skipValue(f.type, package, depth)) return false;
    }
    return true;
  }

 private:
  const std::vector<Field>* find(const std::string& type, const std::string& package) const {
    std::vector<std::string> names{type};
    if (type == "Header") names.push_back("std_msgs/Header");
    if (type.find('/') == std::string::npos && !package.empty()) {
      names.push_back(package + "/" + type);
    }
    for (const auto& n : names) {
      auto it = defs_.find(n);
      if (it != defs_.end()) return &it->second;
    }
    // A short name whose package is not known: match on the part after the slash.
    for (const auto& [name, fields] : defs_) {
      const std::size_t s = name.find('/');
      if (!name.empty() && s != std::string::npos && name.substr(s + 1) == type) return &fields;
    }
    // std_msgs/Header is sometimes left out of hand-written definitions.
    if (type == "Header" || type == "std_msgs/Header") {
      static const std::vector<Field> kHeader = {
          {"uint32", "seq", -1}, {"time", "stamp", -1}, {"string", "frame_id", -1}};
      return &kHeader;
    }
    return nullptr;
  }

  const Definitions& defs_;
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t pos_ = 0;
};

}  // namespace

std::optional<MissionStateReading> readMissionState(const std::string& definition,
                                                    const std::uint8_t* data, std::size_t size) {
  static const std::vector<std::string> kStringNames = {"state", "status", "phase", "data"};
  static const std::vector<std::string> kFlagNames = {"ended", "done", "finished", "complete",
                                                      "completed"};
  const Definitions defs = parseDefinitions(definition);
  const auto& top = defs.at("");
  Reader r(defs, data, size);
  for (const auto& f : top) {
    const bool is_string = f.type == "string" && f.array < 0;
    const bool is_flag = f.type == "bool" && f.array < 0;
    if (is_string &&
        std::find(kStringNames.begin(), kStringNames.end(), f.name) != kStringNames.end()) {
      MissionStateReading out;
      if (!r.str(&out.state)) return std::nullopt;
      out.ended = isTerminalState(out.state);
      return out;
    }
    if (is_flag && std::find(kFlagNames.begin(), kFlagNames.end(), f.name) != kFlagNames.end()) {
      MissionStateReading out;
      std::uint8_t v = 0;
      if (!r.u8(&v)) return std::nullopt;
      out.ended = v != 0;
      return out;
    }
    if (!r.skipField(f, "")) return std::nullopt;
  }
  return std::nullopt;
}

bool isTerminalState(const std::string& state) {
  static const std::vector<std::string> kWords = {
      "ended",     "end",     "done",    "finished",  "complete", "completed",
      "succeeded", "success", "failed",  "failure",   "aborted",  "timeout",
      "timed_out", "time_up", "crashed", "cancelled", "canceled", "over"};
  const std::string s = lower(state);
  // Whole name, or one of its words separated by '_', '-', ' ' or ':'.
  std::vector<std::string> words{s};
  std::string w;
  for (char c : s) {
    if (c == '_' || c == '-' || c == ' ' || c == ':') {
      if (!w.empty()) words.push_back(w);
      w.clear();
    } else {
      w += c;
    }
  }
  if (!w.empty()) words.push_back(w);
  for (const auto& x : words) {
    if (std::find(kWords.begin(), kWords.end(), x) != kWords.end()) return true;
  }
  return false;
}

}  // namespace hameritt::clients
