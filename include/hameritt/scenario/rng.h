#pragma once
// Deterministic random numbers: the same seed gives the same sequence on every platform and
// compiler (the standard library's distributions are implementation-defined, so none are used).

#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace hameritt::scenario {

// SplitMix64 (Steele, Lea and Flood 2014): seed expansion and seed derivation.
inline std::uint64_t splitMix64(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// Seed of an independent stream `stream` derived from `seed`.
inline std::uint64_t deriveSeed(std::uint64_t seed, std::uint64_t stream) {
  return splitMix64(splitMix64(seed) ^ splitMix64(stream + 0x632BE59BD9B4E019ULL));
}

// xoshiro256** (Blackman and Vigna 2018) with uniform, integer, normal and choice helpers.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) {
    std::uint64_t x = seed;
    for (auto& s : s_) {
      x = splitMix64(x);
      s = x;
    }
  }

  std::uint64_t next() {
    const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  // Uniform in [0, 1) with 53 random bits.
  double unit() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  // Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * unit(); }
  // Uniform integer in [lo, hi] (inclusive), unbiased by rejection.
  long uniformInt(long lo, long hi) {
    if (hi <= lo) return lo;
    const std::uint64_t range = static_cast<std::uint64_t>(hi - lo) + 1;
    const std::uint64_t limit = UINT64_MAX - UINT64_MAX % range;
    std::uint64_t r;
    do {
      r = next();
    } while (r >= limit);
    return lo + static_cast<long>(r % range);
  }
  bool bernoulli(double p) { return unit() < p; }
  // Normal variate by the Box-Muller transform.
  double normal(double mean, double stddev) {
    double u1 = unit();
    if (u1 < 1e-300) u1 = 1e-300;
    const double u2 = unit();
    return mean + stddev * std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }
  template <typename T>
  const T& pick(const std::vector<T>& v) {
    return v[static_cast<std::size_t>(uniformInt(0, static_cast<long>(v.size()) - 1))];
  }
  // Fisher-Yates shuffle.
  template <typename T>
  void shuffle(std::vector<T>& v) {
    for (std::size_t i = v.size(); i > 1; --i) {
      const auto j = static_cast<std::size_t>(uniformInt(0, static_cast<long>(i) - 1));
      std::swap(v[i - 1], v[j]);
    }
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4];
};

}  // namespace hameritt::scenario
