#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "hameritt/geometry/polygon.h"
#include "hameritt/geometry/segment.h"

namespace hameritt::geometry {
namespace {

void expectRing(const Polygon& p, const std::vector<Vec2>& expected, double tol = 1e-12) {
  ASSERT_EQ(p.size(), expected.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NEAR((p.vertices()[i] - expected[i]).norm(), 0.0, tol)
        << "vertex " << i << ": " << p.vertices()[i].transpose();
  }
}

// Deterministic uniform double in [lo, hi) from a fixed-seed engine.
double uniform(std::mt19937& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng()) / 4294967296.0);
}

TEST(BufferTest, StraightSegmentIsExactRectangle) {
  const Polygon p = bufferPolyline({Vec2(0, 0), Vec2(10, 0)}, 2.0);
  expectRing(p, {Vec2(0, -1), Vec2(10, -1), Vec2(10, 1), Vec2(0, 1)});
  EXPECT_DOUBLE_EQ(p.signedArea(), 20.0);
  EXPECT_TRUE(p.isSimple());

  const Polygon d = bufferPolyline({Vec2(0, 0), Vec2(3, 4)}, 2.0);
  EXPECT_NEAR(d.signedArea(), 10.0, 1e-12);  // length 5 x width 2
  EXPECT_TRUE(d.isSimple());
  EXPECT_TRUE(d.contains(Vec2(1.5, 2.0)));
  EXPECT_TRUE(d.contains(Vec2(1.5, 2.0) + Vec2(-0.8, 0.6)));  // exactly half a width away
  EXPECT_FALSE(d.contains(Vec2(1.5, 2.0) + 1.01 * Vec2(-0.8, 0.6)));
  EXPECT_FALSE(d.contains(Vec2(-0.1, -0.1)));  // flat end: nothing behind the start
}

TEST(BufferTest, ConsecutiveDuplicatesAreDropped) {
  const Polygon p =
      bufferPolyline({Vec2(0, 0), Vec2(0, 0), Vec2(10, 0), Vec2(10, 0), Vec2(10, 0)}, 2.0);
  expectRing(p, {Vec2(0, -1), Vec2(10, -1), Vec2(10, 1), Vec2(0, 1)});
}

TEST(BufferTest, StraightThroughVertexAddsNoCorner) {
  const Polygon p = bufferPolyline({Vec2(0, 0), Vec2(4, 0), Vec2(10, 0)}, 2.0);
  EXPECT_DOUBLE_EQ(p.area(), 20.0);
  EXPECT_TRUE(p.contains(Vec2(4, 0.99)));
  EXPECT_TRUE(p.isSimple());
}

TEST(BufferTest, LeftTurnMitre) {
  // Outer (right) side mitres to (11,-1); inner offsets meet at (9,1).
  const Polygon p = bufferPolyline({Vec2(0, 0), Vec2(10, 0), Vec2(10, 10)}, 2.0);
  expectRing(p, {Vec2(0, -1), Vec2(11, -1), Vec2(11, 10), Vec2(9, 10), Vec2(9, 1), Vec2(0, 1)});
  EXPECT_DOUBLE_EQ(p.signedArea(), 40.0);
  EXPECT_TRUE(p.isSimple());
  EXPECT_TRUE(p.contains(Vec2(10.9, -0.9)));  // mitre corner
  EXPECT_FALSE(p.contains(Vec2(8.9, 1.1)));   // inside the turn, beyond half a width
}

TEST(BufferTest, RightTurnMitre) {
  const Polygon p = bufferPolyline({Vec2(0, 0), Vec2(10, 0), Vec2(10, -10)}, 2.0);
  expectRing(p, {Vec2(0, -1), Vec2(9, -1), Vec2(9, -10), Vec2(11, -10), Vec2(11, 1), Vec2(0, 1)});
  EXPECT_DOUBLE_EQ(p.signedArea(), 40.0);
  EXPECT_TRUE(p.isSimple());
}

TEST(BufferTest, SharpTurnBevels) {
  // 135-degree left turn: the mitre would be 2.61 half-widths long, so the outside is bevelled
  // from (10,-1) to (10,0) + (1,1)/sqrt2; the inside offsets meet at (9 - sqrt2, 1).
  const double r = 1.0 / std::sqrt(2.0);
  const Polygon p = bufferPolyline({Vec2(0, 0), Vec2(10, 0), Vec2(0, 10)}, 2.0);
  expectRing(p, {Vec2(0, -1), Vec2(10, -1), Vec2(10 + r, r), Vec2(r, 10 + r), Vec2(-r, 10 - r),
                 Vec2(9 - std::sqrt(2.0), 1), Vec2(0, 1)});
  EXPECT_GT(p.signedArea(), 0.0);
  EXPECT_TRUE(p.isSimple());
  EXPECT_FALSE(p.contains(Vec2(10.9, -0.9)));  // where a mitre would have been
  EXPECT_TRUE(p.contains(Vec2(10.0, -0.99)));
}

TEST(BufferTest, UTurnBevelsAndOverlapCountsInside) {
  // Outside (left, by convention for an exact reversal) bevels straight across the vertex; the
  // inside runs through the vertex. [5,10]x[-1,1] is covered twice.
  const Polygon p = bufferPolyline({Vec2(0, 0), Vec2(10, 0), Vec2(5, 0)}, 2.0);
  expectRing(p, {Vec2(0, -1), Vec2(10, -1), Vec2(10, 0), Vec2(10, 1), Vec2(5, 1), Vec2(5, -1),
                 Vec2(10, -1), Vec2(10, 1), Vec2(0, 1)});
  EXPECT_DOUBLE_EQ(p.signedArea(), 30.0);
  EXPECT_TRUE(p.contains(Vec2(7, 0)));
  EXPECT_TRUE(p.contains(Vec2(7, 0.99)));
  EXPECT_TRUE(p.contains(Vec2(2, -0.5)));
  EXPECT_TRUE(p.contains(Vec2(10, 0)));
  EXPECT_FALSE(p.contains(Vec2(10.5, 0)));
  EXPECT_FALSE(p.contains(Vec2(-0.5, 0)));
  EXPECT_FALSE(p.contains(Vec2(7, 1.01)));
}

TEST(BufferTest, HairpinOverlapStaysInside) {
  // Two left turns 0.5 apart: the two straight bands overlap.
  const Polygon p = bufferPolyline({Vec2(0, 0), Vec2(10, 0), Vec2(10, 0.5), Vec2(0, 0.5)}, 2.0);
  EXPECT_GT(p.signedArea(), 0.0);
  EXPECT_TRUE(p.contains(Vec2(5, 0.25)));
  EXPECT_TRUE(p.contains(Vec2(5, -0.9)));
  EXPECT_TRUE(p.contains(Vec2(5, 1.4)));
  EXPECT_TRUE(p.contains(Vec2(9.5, 0.25)));
  EXPECT_FALSE(p.contains(Vec2(5, 1.6)));
  EXPECT_FALSE(p.contains(Vec2(5, -1.1)));
  EXPECT_FALSE(p.contains(Vec2(11.5, 0.25)));
}

TEST(BufferTest, GentleRouteIsSimpleAndCounterClockwise) {
  const Polygon p =
      bufferPolyline({Vec2(0, 0), Vec2(20, 0), Vec2(40, 10), Vec2(60, 10), Vec2(70, -5)}, 4.0);
  EXPECT_TRUE(p.isSimple());
  EXPECT_GT(p.signedArea(), 0.0);
}

TEST(BufferTest, InvalidInputThrows) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(bufferPolyline({}, 2.0), GeometryError);
  EXPECT_THROW(bufferPolyline({Vec2(1, 1)}, 2.0), GeometryError);
  EXPECT_THROW(bufferPolyline({Vec2(1, 1), Vec2(1, 1), Vec2(1, 1)}, 2.0), GeometryError);
  EXPECT_THROW(bufferPolyline({Vec2(0, 0), Vec2(1, 0)}, 0.0), GeometryError);
  EXPECT_THROW(bufferPolyline({Vec2(0, 0), Vec2(1, 0)}, -1.0), GeometryError);
  EXPECT_THROW(bufferPolyline({Vec2(0, 0), Vec2(1, 0)}, nan), GeometryError);
  EXPECT_THROW(bufferPolyline({Vec2(0, 0), Vec2(nan, 0)}, 1.0), GeometryError);
}

// Random polylines with short segments, sharp turns and exact reversals: every point within
// half a width of a straight portion must be inside, every vertex inside, and nothing farther
// than a full width (the longest allowed mitre) from the polyline.
TEST(BufferTest, RandomPolylinesContainTheirBand) {
  std::mt19937 rng(20240611u);
  int inside_checks = 0;
  int outside_checks = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const double width = uniform(rng, 0.5, 8.0);
    const double h = 0.5 * width;
    std::vector<Vec2> line{Vec2(uniform(rng, -100, 100), uniform(rng, -100, 100))};
    double heading = uniform(rng, -kPi, kPi);
    const int points = 2 + static_cast<int>(rng() % 7);
    for (int i = 1; i < points; ++i) {
      const std::uint32_t kind = rng() % 10;
      if (kind == 0) {
        heading += kPi;  // exact reversal
      } else if (kind == 1) {
        // straight on
      } else {
        heading += uniform(rng, -0.995 * kPi, 0.995 * kPi);
      }
      const double len = (rng() % 3 == 0) ? uniform(rng, 0.05, 1.0) : uniform(rng, 1.0, 25.0);
      line.push_back(line.back() + len * Vec2(std::cos(heading), std::sin(heading)));
    }
    const Polygon band = bufferPolyline(line, width);
    ASSERT_GT(band.signedArea(), 0.0) << "trial " << trial;

    for (const Vec2& v : line) {
      EXPECT_TRUE(band.contains(v)) << "trial " << trial;
      ++inside_checks;
    }
    for (std::size_t i = 1; i < line.size(); ++i) {
      const Vec2 d = (line[i] - line[i - 1]).normalized();
      const Vec2 n(-d.y(), d.x());
      const double len = (line[i] - line[i - 1]).norm();
      for (int k = 0; k < 40; ++k) {
        const double s = uniform(rng, 0.0, len);
        // A quarter of the samples sit exactly on the band's long edges.
        const double lateral = (k % 4 == 0) ? ((k % 8 == 0) ? h : -h) : uniform(rng, -h, h);
        const Vec2 q = line[i - 1] + s * d + lateral * n;
        EXPECT_TRUE(band.contains(q))
            << "trial " << trial << " segment " << i << " s " << s << " lateral " << lateral;
        ++inside_checks;
      }
    }
    const Aabb2 b = band.bounds();
    for (int k = 0; k < 200; ++k) {
      const Vec2 q(uniform(rng, b.min.x() - h, b.max.x() + h),
                   uniform(rng, b.min.y() - h, b.max.y() + h));
      if (pointPolylineDistance(q, line) > width * (1.0 + 1e-9)) {
        EXPECT_FALSE(band.contains(q)) << "trial " << trial << " q " << q.transpose();
        ++outside_checks;
      }
    }
  }
  EXPECT_GT(inside_checks, 10000);
  EXPECT_GT(outside_checks, 10000);
}

}  // namespace
}  // namespace hameritt::geometry
