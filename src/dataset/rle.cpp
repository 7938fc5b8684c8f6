#include "hameritt/dataset/rle.h"

#include <algorithm>

namespace hameritt::dataset {

std::vector<std::uint32_t> encodeInstanceMask(const std::uint16_t* instances, int width, int height,
                                              std::uint16_t id, const MaskExtent& extent) {
  std::vector<std::uint32_t> counts;
  const std::uint64_t total =
      static_cast<std::uint64_t>(width) * static_cast<std::uint64_t>(height);
  if (total > 0xffffffffull) throw RleError("mask of " + std::to_string(total) + " pixels");
  if (extent.empty()) {
    counts.push_back(static_cast<std::uint32_t>(total));
    return counts;
  }
  if (extent.x_min < 0 || extent.y_min < 0 || extent.x_max >= width || extent.y_max >= height ||
      extent.x_min > extent.x_max || extent.y_min > extent.y_max) {
    throw RleError("mask extent outside the " + std::to_string(width) + "x" +
                   std::to_string(height) + " image");
  }
  // Zeros before the first scanned column, then the extent's columns (rows outside
  // [y_min, y_max] are zeros by definition of the extent), then zeros after the last column.
  bool value = false;
  std::uint32_t run = 0;
  auto zeros = [&](std::uint32_t n) {
    if (n == 0) return;
    if (value) {
      counts.push_back(run);
      run = 0;
      value = false;
    }
    run += n;
  };
  const auto h = static_cast<std::uint32_t>(height);
  zeros(static_cast<std::uint32_t>(extent.x_min) * h);
  for (int x = extent.x_min; x <= extent.x_max; ++x) {
    zeros(static_cast<std::uint32_t>(extent.y_min));
    const std::uint16_t* p = instances + static_cast<std::size_t>(extent.y_min) * width + x;
    for (int y = extent.y_min; y <= extent.y_max; ++y, p += width) {
      const bool v = *p == id;
      if (v != value) {
        counts.push_back(run);
        run = 0;
        value = v;
      }
      ++run;
    }
    zeros(static_cast<std::uint32_t>(height - 1 - extent.y_max));
  }
  zeros(static_cast<std::uint32_t>(width - 1 - extent.x_max) * h);
  counts.push_back(run);
  return counts;
}

std::string countsToString(const std::vector<std::uint32_t>& counts) {
  std::string s;
  s.reserve(counts.size() * 2);
  for (std::size_t i = 0; i < counts.size(); ++i) {
    long long x = static_cast<long long>(counts[i]);
    if (i > 2) x -= static_cast<long long>(counts[i - 2]);
    bool more = true;
    while (more) {
      char c = static_cast<char>(x & 0x1f);
      x >>= 5;  // arithmetic shift, as in maskApi.c
      more = (c & 0x10) ? x != -1 : x != 0;
      if (more) c |= 0x20;
      s.push_back(static_cast<char>(c + 48));
    }
  }
  return s;
}

std::vector<std::uint32_t> countsFromString(const std::string& s) {
  std::vector<std::uint32_t> counts;
  std::size_t p = 0;
  while (p < s.size()) {
    long long x = 0;
    int k = 0;
    bool more = true;
    while (more) {
      if (p >= s.size()) throw RleError("RLE counts string ends inside a count");
      const int c = static_cast<unsigned char>(s[p]) - 48;
      if (c < 0 || c > 0x3f) {
        throw RleError(std::string("RLE counts string: bad character '") + s[p] + "'");
      }
      if (k > 12) throw RleError("RLE counts string: count too long");
      x |= static_cast<long long>(c & 0x1f) << (5 * k);
      more = (c & 0x20) != 0;
      ++p;
      ++k;
      if (!more && (c & 0x10)) x |= -(1ll << (5 * k));
    }
    if (counts.size() > 2) x += static_cast<long long>(counts[counts.size() - 2]);
    if (x < 0 || x > 0xffffffffll) throw RleError("RLE counts string: count out of range");
    counts.push_back(static_cast<std::uint32_t>(x));
  }
  return counts;
}

std::vector<std::uint8_t> decodeRuns(const std::vector<std::uint32_t>& counts, int width,
                                     int height) {
  const std::size_t total = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<std::uint8_t> mask(total, 0);
  std::size_t pos = 0;
  bool value = false;
  for (std::uint32_t c : counts) {
    if (pos + c > total) throw RleError("RLE runs exceed the image size");
    if (value) {
      for (std::size_t i = pos; i < pos + c; ++i) {
        const std::size_t x = i / static_cast<std::size_t>(height);
        const std::size_t y = i % static_cast<std::size_t>(height);
        mask[y * static_cast<std::size_t>(width) + x] = 1;
      }
    }
    pos += c;
    value = !value;
  }
  if (pos != total) {
    throw RleError("RLE runs sum to " + std::to_string(pos) + ", expected " +
                   std::to_string(total));
  }
  return mask;
}

}  // namespace hameritt::dataset
