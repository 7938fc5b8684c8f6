// COCO RLE: the encoder against a naive column-major encoder written from pycocotools'
// rleEncode, the compressed string against values worked out by hand from rleToString, and the
// round trip string -> runs -> mask.
#include "hameritt/dataset/rle.h"

#include <gtest/gtest.h>

#include <random>

#include "hameritt/dataset/frame.h"

namespace hameritt::dataset {
namespace {

// pycocotools' rleEncode over the column-major mask (instances == id).
std::vector<std::uint32_t> naiveRuns(const std::vector<std::uint16_t>& inst, int w, int h,
                                     std::uint16_t id) {
  std::vector<std::uint32_t> counts;
  bool p = false;
  std::uint32_t c = 0;
  for (int x = 0; x < w; ++x) {
    for (int y = 0; y < h; ++y) {
      const bool v = inst[y * w + x] == id;
      if (v != p) {
        counts.push_back(c);
        c = 0;
        p = v;
      }
      ++c;
    }
  }
  counts.push_back(c);
  return counts;
}

std::vector<std::uint32_t> encode(const std::vector<std::uint16_t>& inst, int w, int h,
                                  std::uint16_t id) {
  const auto extents = instanceExtents(inst.data(), w, h);
  const auto it = extents.find(id);
  return encodeInstanceMask(inst.data(), w, h, id, it == extents.end() ? MaskExtent{} : it->second);
}

void expectRoundTrip(const std::vector<std::uint16_t>& inst, int w, int h, std::uint16_t id) {
  const auto runs = encode(inst, w, h, id);
  EXPECT_EQ(runs, naiveRuns(inst, w, h, id));
  const std::string s = countsToString(runs);
  EXPECT_EQ(countsFromString(s), runs) << s;
  const auto mask = decodeRuns(countsFromString(s), w, h);
  for (int i = 0; i < w * h; ++i) ASSERT_EQ(mask[i], inst[i] == id ? 1 : 0) << "pixel " << i;
}

TEST(Rle, StringMatchesPycocotoolsByHand) {
  EXPECT_EQ(countsToString({3, 1}), "31");
  EXPECT_EQ(countsToString({0, 4}), "04");
  EXPECT_EQ(countsToString({100}), "T3");           // 100 = 3 * 32 + 4: '0' + (4 | 0x20), '0' + 3
  EXPECT_EQ(countsToString({1, 2, 3, 1}), "123O");  // 1 - 2 = -1 -> 0x1f, no continuation
  EXPECT_EQ(countsFromString("123O"), (std::vector<std::uint32_t>{1, 2, 3, 1}));
  EXPECT_EQ(countsFromString("T3"), (std::vector<std::uint32_t>{100}));
}

TEST(Rle, EmptyMask) {
  std::vector<std::uint16_t> inst(6 * 4, 0);
  EXPECT_EQ(encode(inst, 6, 4, 5), (std::vector<std::uint32_t>{24}));
  expectRoundTrip(inst, 6, 4, 5);
}

TEST(Rle, FullMask) {
  std::vector<std::uint16_t> inst(7 * 3, 9);
  EXPECT_EQ(encode(inst, 7, 3, 9), (std::vector<std::uint32_t>{0, 21}));
  expectRoundTrip(inst, 7, 3, 9);
}

TEST(Rle, SinglePixelEverywhere) {
  const int w = 5, h = 4;
  for (int i = 0; i < w * h; ++i) {
    std::vector<std::uint16_t> inst(w * h, 0);
    inst[i] = 3;
    expectRoundTrip(inst, w, h, 3);
  }
}

TEST(Rle, MasksTouchingBorders) {
  const int w = 8, h = 6;
  std::vector<std::uint16_t> inst(w * h, 0);
  for (int y = 0; y < h; ++y) inst[y * w + 0] = 1, inst[y * w + w - 1] = 2;  // left, right
  for (int x = 1; x < w - 1; ++x) inst[x] = 3, inst[(h - 1) * w + x] = 4;    // top, bottom
  for (std::uint16_t id = 1; id <= 4; ++id) expectRoundTrip(inst, w, h, id);
}

TEST(Rle, RandomMasksMatchNaiveEncoder) {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 200; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 40), h = 1 + static_cast<int>(rng() % 40);
    std::vector<std::uint16_t> inst(w * h);
    // Blobs of a few ids over a background, plus noise.
    for (auto& v : inst) v = (rng() % 5 == 0) ? static_cast<std::uint16_t>(rng() % 4) : 0;
    const int bx = static_cast<int>(rng() % w), by = static_cast<int>(rng() % h);
    for (int y = by; y < h && y < by + 10; ++y) {
      for (int x = bx; x < w && x < bx + 12; ++x) inst[y * w + x] = 7;
    }
    for (std::uint16_t id : {1, 2, 3, 7, 11}) expectRoundTrip(inst, w, h, id);
  }
}

TEST(Rle, LargeCountsRoundTrip) {
  const std::vector<std::uint32_t> runs = {307199, 1, 0, 5, 100000, 3, 40};
  EXPECT_EQ(countsFromString(countsToString(runs)), runs);
}

TEST(Rle, BadInputThrows) {
  EXPECT_THROW(countsFromString("0 1"), RleError);   // ' ' < '0'
  EXPECT_THROW(countsFromString("T"), RleError);     // continuation bit, then the end
  EXPECT_THROW(decodeRuns({3, 2}, 2, 2), RleError);  // sums to 5, not 4
  EXPECT_THROW(decodeRuns({1, 2}, 2, 2), RleError);  // sums to 3
  std::vector<std::uint16_t> inst(4, 1);
  MaskExtent outside{0, 0, 2, 1, 4};
  EXPECT_THROW(encodeInstanceMask(inst.data(), 2, 2, 1, outside), RleError);
}

}  // namespace
}  // namespace hameritt::dataset
