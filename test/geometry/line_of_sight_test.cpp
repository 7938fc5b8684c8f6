#include "hameritt/geometry/line_of_sight.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

namespace hameritt::geometry {
namespace {

OrientedBox makeBox(const Vec3& center, const Vec3& size, double yaw = 0.0) {
  OrientedBox b;
  b.center = center;
  b.size = size;
  b.yaw = yaw;
  return b;
}

double uniform(std::mt19937& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng()) / 4294967296.0);
}

bool ignoredBy(const std::vector<int>& ignore, int i) {
  for (int j : ignore) {
    if (j == i) return true;
  }
  return false;
}

bool bruteClear(const OccluderIndex& index, const Vec3& a, const Vec3& b,
                const std::vector<int>& ignore) {
  for (int i = 0; i < static_cast<int>(index.size()); ++i) {
    if (!ignoredBy(ignore, i) && index.box(i).intersectsSegment(a, b)) return false;
  }
  return true;
}

bool bruteClear2(const OccluderIndex& index, const Vec2& a, const Vec2& b,
                 const std::vector<int>& ignore) {
  for (int i = 0; i < static_cast<int>(index.size()); ++i) {
    if (!ignoredBy(ignore, i) && index.box(i).footprint().intersectsSegment(a, b)) return false;
  }
  return true;
}

std::vector<int> bruteNear(const OccluderIndex& index, const Vec2& p, double radius) {
  std::vector<int> out;
  for (int i = 0; i < static_cast<int>(index.size()); ++i) {
    if (index.box(i).footprint().distance(p) <= radius) out.push_back(i);
  }
  return out;
}

std::vector<int> bruteCandidates(const OccluderIndex& index, const Aabb2& area) {
  std::vector<int> out;
  for (int i = 0; i < static_cast<int>(index.size()); ++i) {
    if (index.box(i).bounds2().overlaps(area)) out.push_back(i);
  }
  return out;
}

TEST(OccluderIndexTest, InvalidConstructionAndBoxes) {
  EXPECT_THROW(OccluderIndex(0.0), GeometryError);
  EXPECT_THROW(OccluderIndex(-5.0), GeometryError);
  EXPECT_THROW(OccluderIndex{std::numeric_limits<double>::quiet_NaN()}, GeometryError);
  EXPECT_THROW(OccluderIndex{std::numeric_limits<double>::infinity()}, GeometryError);

  OccluderIndex index(10.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_THROW(index.add(makeBox(Vec3(0, 0, 0), Vec3(0, 1, 1))), GeometryError);
  EXPECT_THROW(index.add(makeBox(Vec3(0, 0, 0), Vec3(1, -1, 1))), GeometryError);
  EXPECT_THROW(index.add(makeBox(Vec3(0, 0, 0), Vec3(1, 1, 0))), GeometryError);
  EXPECT_THROW(index.add(makeBox(Vec3(0, 0, 0), Vec3(1, nan, 1))), GeometryError);
  EXPECT_THROW(index.add(makeBox(Vec3(0, 0, 0), Vec3(1, 1, inf))), GeometryError);
  EXPECT_EQ(index.size(), 0u);
  EXPECT_EQ(index.add(makeBox(Vec3(0, 0, 0), Vec3(1, 1, 1))), 0);
  EXPECT_EQ(index.add(makeBox(Vec3(5, 0, 0), Vec3(1, 1, 1))), 1);
  EXPECT_EQ(index.add(makeBox(Vec3(9, 0, 0), Vec3(1, 1, 1))), 2);
  EXPECT_EQ(index.size(), 3u);
  EXPECT_DOUBLE_EQ(index.box(1).center.x(), 5.0);
}

TEST(OccluderIndexTest, StaleIndexThrows) {
  OccluderIndex empty;
  EXPECT_TRUE(empty.clear(Vec3(0, 0, 0), Vec3(10, 0, 0)));  // never added: nothing to build
  EXPECT_TRUE(empty.near(Vec2(0, 0), 100.0).empty());

  OccluderIndex index(10.0);
  index.add(makeBox(Vec3(5, 0, 1), Vec3(1, 1, 2)));
  EXPECT_THROW(index.clear(Vec3(0, 0, 1), Vec3(10, 0, 1)), std::logic_error);
  EXPECT_THROW(index.clear2(Vec2(0, 0), Vec2(10, 0)), std::logic_error);
  EXPECT_THROW(index.near(Vec2(0, 0), 1.0), std::logic_error);
  EXPECT_THROW(index.candidates(Aabb2{Vec2(0, 0), Vec2(1, 1)}), std::logic_error);
  index.build();
  EXPECT_FALSE(index.clear(Vec3(0, 0, 1), Vec3(10, 0, 1)));
  index.add(makeBox(Vec3(50, 0, 1), Vec3(1, 1, 2)));
  EXPECT_THROW(index.clear(Vec3(0, 0, 1), Vec3(10, 0, 1)), std::logic_error);
  index.build();
  EXPECT_FALSE(index.clear(Vec3(40, 0, 1), Vec3(60, 0, 1)));
}

TEST(OccluderIndexTest, WallBlocksAndIgnoreList) {
  OccluderIndex index(20.0);
  const int wall = index.add(makeBox(Vec3(5, 0, 2), Vec3(0.3, 20, 4)));  // z in [0, 4]
  index.build();
  EXPECT_FALSE(index.clear(Vec3(0, 0, 1.5), Vec3(10, 0, 1.5)));
  EXPECT_FALSE(index.clear(Vec3(10, 0, 1.5), Vec3(0, 0, 1.5)));
  EXPECT_TRUE(index.clear(Vec3(0, 0, 4.5), Vec3(10, 0, 4.5)));    // just above: maxZ = 4
  EXPECT_FALSE(index.clear(Vec3(0, 0, 4.0), Vec3(10, 0, 4.0)));   // skimming the top touches
  EXPECT_TRUE(index.clear(Vec3(0, 0, 1.5), Vec3(4.8, 0, 1.5)));   // stops short
  EXPECT_TRUE(index.clear(Vec3(0, 11, 1.5), Vec3(10, 11, 1.5)));  // passes the end
  EXPECT_TRUE(index.clear(Vec3(0, 0, 1.5), Vec3(10, 0, 1.5), {wall}));
  EXPECT_FALSE(index.clear(Vec3(0, 0, 1.5), Vec3(10, 0, 1.5), {7}));
  EXPECT_FALSE(index.clear2(Vec2(0, 0), Vec2(10, 0)));
  EXPECT_TRUE(index.clear2(Vec2(0, 0), Vec2(10, 0), {wall}));
}

TEST(OccluderIndexTest, GrazingCornerCountsAsBlocked) {
  OccluderIndex index(5.0);
  index.add(makeBox(Vec3(0, 0, 0), Vec3(2, 2, 2)));  // footprint [-1,1]^2, z in [-1,1]
  index.build();
  // The line x + y = 2 touches the corner (1, 1) only.
  EXPECT_FALSE(index.clear(Vec3(0, 2, 0), Vec3(2, 0, 0)));
  EXPECT_FALSE(index.clear2(Vec2(0, 2), Vec2(2, 0)));
  EXPECT_TRUE(index.clear(Vec3(0, 2.001, 0), Vec3(2.001, 0, 0)));
  EXPECT_TRUE(index.clear2(Vec2(0, 2.001), Vec2(2.001, 0)));
  // Touching the top corner edge in 3D.
  EXPECT_FALSE(index.clear(Vec3(-3, 1, 1), Vec3(3, 1, 1)));
  EXPECT_TRUE(index.clear(Vec3(-3, 1, 1.001), Vec3(3, 1, 1.001)));
}

TEST(OccluderIndexTest, TouchWithinToleranceAcrossCellLine) {
  // The box's face sits 1e-7 short of the cell line x = 10 and the segment starts 5e-7 past it:
  // a 6e-7 gap, inside the box's 1e-6 touching tolerance (kEpsilon times its 1000 m size).
  OccluderIndex index(10.0);
  index.add(makeBox(Vec3(-490, 0, 0), Vec3(999.9999998, 4, 4)));
  index.build();
  const Vec3 a(10.0000005, 0, 0);
  const Vec3 b(15, 0, 0);
  ASSERT_TRUE(index.box(0).intersectsSegment(a, b));
  EXPECT_FALSE(index.clear(a, b));
  EXPECT_FALSE(index.clear2(a.head<2>(), b.head<2>()));
  EXPECT_EQ(index.near(a.head<2>(), 0.0), std::vector<int>{0});
  EXPECT_TRUE(index.clear(Vec3(10.00001, 0, 0), b));
}

TEST(OccluderIndexTest, Clear2IgnoresHeight) {
  OccluderIndex index(10.0);
  index.add(makeBox(Vec3(5, 0, 11), Vec3(2, 2, 2)));  // canopy at z in [10, 12]
  index.build();
  EXPECT_TRUE(index.clear(Vec3(0, 0, 1), Vec3(10, 0, 1)));
  EXPECT_FALSE(index.clear(Vec3(0, 0, 11), Vec3(10, 0, 11)));
  EXPECT_FALSE(index.clear2(Vec2(0, 0), Vec2(10, 0)));
}

TEST(OccluderIndexTest, LongDiagonalAcrossManyCells) {
  OccluderIndex index(10.0);
  // Filler boxes well off the diagonal y = x (enough of them that the grid walk is used).
  std::vector<int> filler;
  for (int i = -9; i <= 9; ++i) {
    for (int j = 0; j < 10; ++j) {
      const double x = 100.0 * i + 10.0 * j;
      filler.push_back(index.add(makeBox(Vec3(x, x + 60.0, 5), Vec3(4, 4, 10), 0.3)));
      filler.push_back(index.add(makeBox(Vec3(x, x - 60.0, 5), Vec3(4, 4, 10), -0.7)));
    }
  }
  const int target = index.add(makeBox(Vec3(900, 900.5, 5), Vec3(3, 3, 10), 0.2));
  index.build();
  const Vec3 a(-1000, -1000, 3);
  EXPECT_FALSE(index.clear(a, Vec3(1000, 1000, 3)));
  EXPECT_FALSE(index.clear(Vec3(1000, 1000, 3), a));
  EXPECT_TRUE(index.clear(a, Vec3(1000, 1000, 3), {target}));
  EXPECT_TRUE(index.clear(a, Vec3(850, 850, 3)));
  EXPECT_FALSE(index.clear2(Vec2(-1000, -1000), Vec2(1000, 1000)));
  EXPECT_TRUE(index.clear(Vec3(-1000, -1000, 11), Vec3(1000, 1000, 11)));  // over everything
  // A steep, nearly vertical long segment through a filler box.
  const OrientedBox& f = index.box(filler[5]);
  const Vec3 top = f.center + Vec3(0.3, 800, 0);
  const Vec3 bottom = f.center + Vec3(-0.3, -800, 0);
  EXPECT_EQ(index.clear(bottom, top), bruteClear(index, bottom, top, {}));
  EXPECT_FALSE(index.clear(bottom, top));
}

TEST(OccluderIndexTest, NegativeCoordinates) {
  OccluderIndex index(7.0);
  const int box = index.add(makeBox(Vec3(-105.5, -37.2, 1.5), Vec3(3, 3, 3), 0.4));
  index.add(makeBox(Vec3(-300, -400, 1.5), Vec3(10, 2, 3), -1.2));
  index.build();
  EXPECT_FALSE(index.clear(Vec3(-200, -37.2, 1), Vec3(0, -37.2, 1)));
  EXPECT_TRUE(index.clear(Vec3(-200, -30, 1), Vec3(0, -30, 1)));
  EXPECT_FALSE(index.clear(Vec3(-300, -500, 1), Vec3(-300, -300, 1)));
  EXPECT_EQ(index.near(Vec2(-105.5, -37.2), 0.0), std::vector<int>{box});
  EXPECT_EQ(index.near(Vec2(-110, -37.2), 3.0), std::vector<int>{box});  // about 2.6 away
  EXPECT_TRUE(index.near(Vec2(-120, -37.2), 3.0).empty());
  EXPECT_EQ(index.candidates(Aabb2{Vec2(-110, -40), Vec2(-100, -30)}), std::vector<int>{box});
  EXPECT_EQ(index.candidates(Aabb2{Vec2(-1000, -1000), Vec2(0, 0)}), (std::vector<int>{0, 1}));
}

TEST(OccluderIndexTest, NearUsesExactFootprintDistance) {
  OccluderIndex index(4.0);
  index.add(makeBox(Vec3(0, 0, 0), Vec3(2, 2, 1)));               // edge x = 1
  index.add(makeBox(Vec3(10, 0, 0), Vec3(2, 2, 1), 0.25 * kPi));  // left vertex at 10 - sqrt2
  index.add(makeBox(Vec3(-5, -5, 0), Vec3(1, 1, 1)));
  index.build();
  EXPECT_EQ(index.near(Vec2(3, 0), 2.0), std::vector<int>{0});  // exactly 2 away
  EXPECT_TRUE(index.near(Vec2(3, 0), 1.99).empty());
  EXPECT_EQ(index.near(Vec2(3, 0), 5.6), (std::vector<int>{0, 1}));  // 10 - sqrt2 - 3 = 5.586
  EXPECT_EQ(index.near(Vec2(3, 0), 5.5), std::vector<int>{0});
  // The diamond's bounding square reaches (10 - sqrt2, 1.4) but the footprint does not.
  EXPECT_TRUE(index.near(Vec2(8.6, 1.4), 0.1).empty());
  EXPECT_EQ(index.near(Vec2(10, 0), 0.0), std::vector<int>{1});
  EXPECT_TRUE(index.near(Vec2(0, 0), -1.0).empty());
  EXPECT_EQ(index.near(Vec2(0, 0), std::numeric_limits<double>::infinity()),
            (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(index.candidates(Aabb2{Vec2(8.6, 1.3), Vec2(8.7, 1.4)}), std::vector<int>{1});
  EXPECT_TRUE(index.candidates(Aabb2{Vec2(5, 5), Vec2(4, 4)}).empty());  // inverted area
}

TEST(OccluderIndexTest, HugeAndFarBoxes) {
  // With 1 cm cells, x = 2e7 m is past the 2^30 cells the grid packs, and the 1e5 m box spans
  // far more cells than are filed per box.
  OccluderIndex index(0.01);
  const int huge = index.add(makeBox(Vec3(0, 0, 5), Vec3(1e5, 1e5, 10)));
  const int far = index.add(makeBox(Vec3(2e7, 0, 5), Vec3(10, 10, 10)));
  index.build();
  EXPECT_FALSE(index.clear(Vec3(3e4, 3e4, 1), Vec3(3e4 + 1, 3e4, 1)));
  EXPECT_TRUE(index.clear(Vec3(3e4, 3e4, 1), Vec3(3e4 + 1, 3e4, 1), {huge}));
  EXPECT_FALSE(index.clear(Vec3(2e7 - 100, 0, 5), Vec3(2e7 + 100, 0, 5)));
  EXPECT_TRUE(index.clear(Vec3(2e7 - 100, 20, 5), Vec3(2e7 + 100, 20, 5)));
  EXPECT_FALSE(index.clear(Vec3(2e7 + 4, 4, 5), Vec3(2e7 + 4, 4, 5)));  // a point inside
  EXPECT_EQ(index.near(Vec2(2e7 + 6, 0), 1.5), std::vector<int>{far});
  EXPECT_EQ(index.near(Vec2(0, 0), 1.0), std::vector<int>{huge});
  EXPECT_EQ(index.candidates(Aabb2{Vec2(2e7, 0), Vec2(2e7 + 1, 1)}), std::vector<int>{far});
}

// Random boxes and segments: the index must agree with testing every box.
TEST(OccluderIndexTest, RandomizedMatchesBruteForce) {
  std::mt19937 rng(1234567u);
  OccluderIndex index(25.0);
  for (int i = 0; i < 300; ++i) {
    const Vec3 c(uniform(rng, -500, 500), uniform(rng, -500, 500), uniform(rng, 0, 10));
    const Vec3 s(uniform(rng, 0.5, 40), uniform(rng, 0.5, 40), uniform(rng, 0.5, 20));
    index.add(makeBox(c, s, uniform(rng, -kPi, kPi)));
  }
  index.build();

  int blocked = 0;
  int clear = 0;
  int blocked2 = 0;
  for (int k = 0; k < 2000; ++k) {
    Vec3 a(uniform(rng, -600, 600), uniform(rng, -600, 600), uniform(rng, -2, 25));
    Vec3 b;
    switch (k % 4) {
      case 0:  // short
        b = a + Vec3(uniform(rng, -50, 50), uniform(rng, -50, 50), uniform(rng, -5, 5));
        break;
      case 1:  // long, anywhere
        b = Vec3(uniform(rng, -600, 600), uniform(rng, -600, 600), uniform(rng, -2, 25));
        break;
      case 2: {  // from a box corner (touching) outward
        const OrientedBox& box = index.box(static_cast<int>(rng() % index.size()));
        const Vec2 corner = box.corners2()[rng() % 4];
        a = Vec3(corner.x(), corner.y(), box.maxZ());
        b = a + Vec3(uniform(rng, -300, 300), uniform(rng, -300, 300), uniform(rng, 0, 5));
        break;
      }
      default:  // axis-parallel, exactly on cell lines half of the time
        b = a;
        if (k % 8 == 3) {
          a.x() = b.x() = 25.0 * std::round(a.x() / 25.0);
        }
        b.y() = uniform(rng, -600, 600);
        break;
    }
    std::vector<int> ignore;
    if (k % 5 == 0) {
      for (int j = 0; j < 20; ++j) ignore.push_back(static_cast<int>(rng() % index.size()));
    }
    const bool expected = bruteClear(index, a, b, ignore);
    ASSERT_EQ(index.clear(a, b, ignore), expected) << "segment " << k;
    (expected ? clear : blocked)++;

    const Vec2 a2 = a.head<2>();
    const Vec2 b2 = b.head<2>();
    const bool expected2 = bruteClear2(index, a2, b2, ignore);
    ASSERT_EQ(index.clear2(a2, b2, ignore), expected2) << "segment " << k;
    if (!expected2) ++blocked2;
  }
  // Both outcomes must be well represented, or the comparison proves little.
  EXPECT_GT(blocked, 300);
  EXPECT_GT(clear, 300);
  EXPECT_GT(blocked2, blocked);

  int nonempty = 0;
  for (int k = 0; k < 1000; ++k) {
    const Vec2 p(uniform(rng, -600, 600), uniform(rng, -600, 600));
    const double radius = (k % 10 == 0) ? 0.0 : uniform(rng, 0, 80);
    const std::vector<int> got = index.near(p, radius);
    ASSERT_EQ(got, bruteNear(index, p, radius)) << "point " << k;
    if (!got.empty()) ++nonempty;
    const Aabb2 area{p, p + Vec2(uniform(rng, 0, 100), uniform(rng, 0, 100))};
    ASSERT_EQ(index.candidates(area), bruteCandidates(index, area)) << "area " << k;
  }
  EXPECT_GT(nonempty, 200);
}

// Const queries from several threads give the same answers as one thread.
TEST(OccluderIndexTest, ConcurrentQueriesAgree) {
  std::mt19937 rng(99u);
  OccluderIndex index(15.0);
  for (int i = 0; i < 200; ++i) {
    index.add(makeBox(Vec3(uniform(rng, -300, 300), uniform(rng, -300, 300), 3),
                      Vec3(uniform(rng, 1, 20), uniform(rng, 1, 20), 6), uniform(rng, -3, 3)));
  }
  index.build();
  std::vector<Vec3> from;
  std::vector<Vec3> to;
  for (int k = 0; k < 500; ++k) {
    from.emplace_back(uniform(rng, -300, 300), uniform(rng, -300, 300), 2);
    to.emplace_back(uniform(rng, -300, 300), uniform(rng, -300, 300), 2);
  }
  std::vector<char> reference(from.size());
  std::vector<std::size_t> reference_near(from.size());
  for (std::size_t k = 0; k < from.size(); ++k) {
    reference[k] = index.clear(from[k], to[k]);
    reference_near[k] = index.near(from[k].head<2>(), 30.0).size();
  }
  std::vector<std::vector<char>> results(4, std::vector<char>(from.size()));
  std::vector<std::vector<std::size_t>> near_results(4, std::vector<std::size_t>(from.size()));
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (std::size_t k = 0; k < from.size(); ++k) {
        results[t][k] = index.clear(from[k], to[k]);
        near_results[t][k] = index.near(from[k].head<2>(), 30.0).size();
      }
    });
  }
  for (auto& th : threads) th.join();
  for (int t = 0; t < 4; ++t) {
    EXPECT_EQ(results[t], reference);
    EXPECT_EQ(near_results[t], reference_near);
  }
}

}  // namespace
}  // namespace hameritt::geometry
