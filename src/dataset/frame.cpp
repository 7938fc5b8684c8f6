#include "hameritt/dataset/frame.h"

#include <cmath>
#include <cstdio>
#include <limits>
#include <set>
#include <stdexcept>

namespace hameritt::dataset {

std::map<std::uint16_t, MaskExtent> instanceExtents(const std::uint16_t* instances, int width,
                                                    int height) {
  // A dense table over the 16-bit ids keeps the pass branch-light; ids are few per frame.
  std::vector<MaskExtent> table(65536);
  std::vector<std::uint16_t> seen;
  for (int y = 0; y < height; ++y) {
    const std::uint16_t* row = instances + static_cast<std::size_t>(y) * width;
    for (int x = 0; x < width; ++x) {
      const std::uint16_t id = row[x];
      if (id == 0) continue;
      MaskExtent& e = table[id];
      if (e.pixels == 0) {
        e.x_min = e.x_max = x;
        e.y_min = e.y_max = y;
        seen.push_back(id);
      } else {
        if (x < e.x_min) e.x_min = x;
        if (x > e.x_max) e.x_max = x;
        e.y_max = y;  // rows are scanned in order
      }
      ++e.pixels;
    }
  }
  std::map<std::uint16_t, MaskExtent> out;
  for (std::uint16_t id : seen) out[id] = table[id];
  return out;
}

std::vector<InstanceAnnotation> annotateFrame(const std::uint16_t* instances, int width, int height,
                                              const std::vector<BoxMeta>& boxes, int* skipped) {
  const auto extents = instanceExtents(instances, width, height);
  std::vector<InstanceAnnotation> out;
  std::set<std::uint16_t> done;
  int skip = 0;
  for (const BoxMeta& b : boxes) {
    const auto it = extents.find(b.instance_id);
    if (b.instance_id == 0 || it == extents.end() || !done.insert(b.instance_id).second) {
      ++skip;
      continue;
    }
    InstanceAnnotation a;
    a.meta = b;
    a.extent = it->second;
    a.counts = encodeInstanceMask(instances, width, height, b.instance_id, a.extent);
    out.push_back(std::move(a));
  }
  if (skipped) *skipped += skip;
  return out;
}

std::string yoloLabels(const std::vector<InstanceAnnotation>& annotations, int width, int height,
                       const std::map<std::string, int>& class_index) {
  std::string out;
  char line[160];
  for (const auto& a : annotations) {
    const auto it = class_index.find(a.meta.entity_class);
    if (it == class_index.end()) continue;
    const double cx = (a.bboxX() + 0.5 * a.bboxW()) / width;
    const double cy = (a.bboxY() + 0.5 * a.bboxH()) / height;
    std::snprintf(line, sizeof(line), "%d %.6f %.6f %.6f %.6f\n", it->second, cx, cy,
                  static_cast<double>(a.bboxW()) / width, static_cast<double>(a.bboxH()) / height);
    out += line;
  }
  return out;
}

std::uint16_t depthToMillimetres(float metres) {
  // Comparisons instead of isfinite/round calls: this runs on every pixel of every frame.
  if (!(metres > 0.0f && metres <= std::numeric_limits<float>::max())) return 0;  // NaN, inf
  const double mm = static_cast<double>(metres) * 1000.0 + 0.5;
  if (mm >= 65535.0) return 65535;
  return static_cast<std::uint16_t>(mm);  // truncation of x + 0.5: round half up
}

std::vector<SplitSpec> parseSplits(const std::string& text) {
  std::vector<SplitSpec> out;
  std::set<std::string> names;
  double sum = 0.0;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const std::size_t comma = text.find(',', pos);
    const std::string part =
        text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    const std::size_t eq = part.find('=');
    if (eq == std::string::npos || eq == 0) {
      throw std::invalid_argument("split '" + part + "': expected NAME=FRACTION");
    }
    SplitSpec s;
    s.name = part.substr(0, eq);
    for (char c : s.name) {
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-')) {
        throw std::invalid_argument("split name '" + s.name + "': expected [A-Za-z0-9_-]+");
      }
    }
    if (!names.insert(s.name).second) {
      throw std::invalid_argument("split name '" + s.name + "' given twice");
    }
    const std::string num = part.substr(eq + 1);
    std::size_t used = 0;
    try {
      s.fraction = std::stod(num, &used);
    } catch (...) {
      used = 0;
    }
    if (num.empty() || used != num.size() || !(s.fraction > 0.0) || s.fraction > 1.0) {
      throw std::invalid_argument("split '" + part + "': expected a fraction in (0, 1], got '" +
                                  num + "'");
    }
    sum += s.fraction;
    out.push_back(s);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  if (std::abs(sum - 1.0) > 1e-6) {
    char buf[64];
    std::snprintf(buf, sizeof(buf), "%.6g", sum);
    throw std::invalid_argument("split fractions sum to " + std::string(buf) + ", expected 1");
  }
  return out;
}

namespace {
// SplitMix64 finaliser (Steele, Lea, Flood: "Fast splittable pseudorandom number generators").
std::uint64_t mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}
}  // namespace

const std::string& assignSplit(const std::vector<SplitSpec>& splits, std::uint64_t seed,
                               const std::string& key) {
  // FNV-1a over the key, mixed with the seed.
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : key) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  const std::uint64_t r = mix(h ^ mix(seed + 0x9e3779b97f4a7c15ull));
  const double u = static_cast<double>(r >> 11) * (1.0 / 9007199254740992.0);
  double acc = 0.0;
  for (const auto& s : splits) {
    acc += s.fraction;
    if (u < acc) return s.name;
  }
  return splits.back().name;
}

}  // namespace hameritt::dataset
