#include "hameritt/geometry/oriented_box.h"

#include <gtest/gtest.h>

#include <random>

#include <cmath>

namespace hameritt::geometry {
namespace {

OrientedBox makeBox(const Vec3& center, const Vec3& size, double yaw) {
  OrientedBox b;
  b.center = center;
  b.size = size;
  b.yaw = yaw;
  return b;
}

void expectNear(const Vec2& a, const Vec2& b, double tol = 1e-12) {
  EXPECT_NEAR((a - b).norm(), 0.0, tol) << a.transpose() << " vs " << b.transpose();
}

TEST(OrientedBoxTest, AxisAlignedCornersBoundsAndContainment) {
  const OrientedBox b = makeBox(Vec3(0, 0, 1), Vec3(4, 2, 2), 0.0);
  EXPECT_DOUBLE_EQ(b.minZ(), 0.0);
  EXPECT_DOUBLE_EQ(b.maxZ(), 2.0);
  const auto c = b.corners2();
  expectNear(c[0], Vec2(-2, -1));
  expectNear(c[1], Vec2(2, -1));
  expectNear(c[2], Vec2(2, 1));
  expectNear(c[3], Vec2(-2, 1));
  expectNear(b.bounds2().min, Vec2(-2, -1));
  expectNear(b.bounds2().max, Vec2(2, 1));
  EXPECT_DOUBLE_EQ(b.footprint().signedArea(), 8.0);

  EXPECT_TRUE(b.contains(Vec3(0, 0, 1)));
  EXPECT_TRUE(b.contains(Vec3(2, 1, 2)));   // corner
  EXPECT_TRUE(b.contains(Vec3(-2, 0, 0)));  // face
  EXPECT_FALSE(b.contains(Vec3(2.001, 0, 1)));
  EXPECT_FALSE(b.contains(Vec3(0, 0, -0.001)));
  EXPECT_FALSE(b.contains(Vec3(0, 0, 2.001)));
}

TEST(OrientedBoxTest, Rotated90) {
  // Length 4 now runs north: footprint [0,2] x [0,4].
  const OrientedBox b = makeBox(Vec3(1, 2, 0), Vec3(4, 2, 2), 0.5 * kPi);
  const auto c = b.corners2();
  expectNear(c[0], Vec2(2, 0));
  expectNear(c[1], Vec2(2, 4));
  expectNear(c[2], Vec2(0, 4));
  expectNear(c[3], Vec2(0, 0));
  expectNear(b.bounds2().min, Vec2(0, 0));
  expectNear(b.bounds2().max, Vec2(2, 4));
  EXPECT_NEAR(b.footprint().signedArea(), 8.0, 1e-12);
  EXPECT_TRUE(b.toBody(Vec3(1, 4, 0.5)).isApprox(Vec3(2, 0, 0.5)));
  EXPECT_TRUE(b.contains(Vec3(1.9, 3.9, 0)));
  EXPECT_FALSE(b.contains(Vec3(2.1, 1, 0)));
  EXPECT_FALSE(b.contains(Vec3(1, 4.1, 0)));
}

TEST(OrientedBoxTest, Rotated45) {
  // A 2x2 square turned 45 degrees is a diamond with corners sqrt(2) out along the axes.
  const double s = std::sqrt(2.0);
  const OrientedBox b = makeBox(Vec3(0, 0, 0), Vec3(2, 2, 2), 0.25 * kPi);
  const auto c = b.corners2();
  expectNear(c[0], Vec2(0, -s));
  expectNear(c[1], Vec2(s, 0));
  expectNear(c[2], Vec2(0, s));
  expectNear(c[3], Vec2(-s, 0));
  expectNear(b.bounds2().min, Vec2(-s, -s));
  expectNear(b.bounds2().max, Vec2(s, s));
  EXPECT_NEAR(b.footprint().area(), 4.0, 1e-12);
  EXPECT_TRUE(b.contains(Vec3(1.4, 0, 0)));
  EXPECT_FALSE(b.contains(Vec3(1.0, 1.0, 0)));  // inside the bounds, outside the diamond
  EXPECT_TRUE(b.contains(Vec3(0.7, 0.7, 0)));
}

TEST(OrientedBoxTest, Rotated30SegmentsInBodyTerms) {
  const double yaw = kPi / 6.0;
  const Vec2 u(std::cos(yaw), std::sin(yaw));  // body x
  const Vec2 v(-u.y(), u.x());                 // body y
  const OrientedBox b = makeBox(Vec3(3, -2, 1), Vec3(4, 2, 2), yaw);
  auto world = [&](double bx, double by, double z) {
    const Vec2 p = Vec2(3, -2) + bx * u + by * v;
    return Vec3(p.x(), p.y(), z);
  };
  EXPECT_TRUE(b.toBody(world(1.5, 0.5, 1.7)).isApprox(Vec3(1.5, 0.5, 0.7)));
  const auto c = b.corners2();
  expectNear(c[1], Vec2(3, -2) + 2 * u - 1 * v);
  expectNear(c[3], Vec2(3, -2) - 2 * u + 1 * v);
  // Segments across the box's width at body x = 2.5 (miss), 1.9 (hit), 2.0 (grazes the face).
  EXPECT_FALSE(b.intersectsSegment(world(2.5, -3, 1), world(2.5, 3, 1)));
  EXPECT_TRUE(b.intersectsSegment(world(1.9, -3, 1), world(1.9, 3, 1)));
  EXPECT_TRUE(b.intersectsSegment(world(2.0, -3, 1), world(2.0, 3, 1)));
  // Through the corner (2, 1) diagonally in body terms.
  EXPECT_TRUE(b.intersectsSegment(world(3, 0, 1), world(1, 2, 1)));
  EXPECT_FALSE(b.intersectsSegment(world(3.01, 0, 1), world(1.01, 2, 1)));
}

TEST(OrientedBoxTest, IntersectsSegment) {
  const OrientedBox b = makeBox(Vec3(0, 0, 1), Vec3(4, 2, 2), 0.0);
  EXPECT_TRUE(b.intersectsSegment(Vec3(-5, 0, 1), Vec3(5, 0, 1)));
  EXPECT_FALSE(b.intersectsSegment(Vec3(-5, 0, 2.5), Vec3(5, 0, 2.5)));  // above
  EXPECT_TRUE(b.intersectsSegment(Vec3(-5, 0, 2), Vec3(5, 0, 2)));       // along the top
  EXPECT_FALSE(b.intersectsSegment(Vec3(-5, 3, 1), Vec3(5, 3, 1)));      // beside
  // Line x + y = 3 grazes the corner (2, 1); x + y = 3.001 misses.
  EXPECT_TRUE(b.intersectsSegment(Vec3(0, 3, 1), Vec3(4, -1, 1)));
  EXPECT_FALSE(b.intersectsSegment(Vec3(0, 3.001, 1), Vec3(4, -0.999, 1)));
  // Ending on the face vs just short of it.
  EXPECT_TRUE(b.intersectsSegment(Vec3(-5, 0, 1), Vec3(-2, 0, 1)));
  EXPECT_FALSE(b.intersectsSegment(Vec3(-5, 0, 1), Vec3(-2.01, 0, 1)));
  // Zero length: point containment.
  EXPECT_TRUE(b.intersectsSegment(Vec3(1, 0.5, 1), Vec3(1, 0.5, 1)));
  EXPECT_FALSE(b.intersectsSegment(Vec3(3, 0, 1), Vec3(3, 0, 1)));
  EXPECT_TRUE(b.intersectsSegment(Vec3(2, 1, 2), Vec3(2, 1, 2)));
  // Vertical segments.
  EXPECT_TRUE(b.intersectsSegment(Vec3(0, 0, -5), Vec3(0, 0, 5)));
  EXPECT_FALSE(b.intersectsSegment(Vec3(3, 0, -5), Vec3(3, 0, 5)));
  // Descending sight line: above the box over its whole footprint, or dipping into it.
  EXPECT_FALSE(b.intersectsSegment(Vec3(-5, 0, 3), Vec3(5, 0, 2.5)));
  EXPECT_TRUE(b.intersectsSegment(Vec3(-5, 0, 3), Vec3(5, 0, 0)));
  // Segment wholly inside.
  EXPECT_TRUE(b.intersectsSegment(Vec3(-1, 0, 1), Vec3(1, 0.5, 1.5)));
}

TEST(OrientedBoxTest, FootprintDistanceAndOverlap) {
  const OrientedBox a = makeBox(Vec3(0, 0, 0), Vec3(2, 2, 1), 0.0);
  const OrientedBox far = makeBox(Vec3(5, 0, 0), Vec3(2, 2, 1), 0.0);
  EXPECT_DOUBLE_EQ(footprintDistance(a, far), 3.0);
  EXPECT_FALSE(footprintsOverlap(a, far));

  // Diamond whose left vertex is at (4 - sqrt2, 0); a's right edge is x = 1.
  const OrientedBox diamond = makeBox(Vec3(4, 0, 0), Vec3(2, 2, 1), 0.25 * kPi);
  EXPECT_NEAR(footprintDistance(a, diamond), 3.0 - std::sqrt(2.0), 1e-12);

  const OrientedBox overlapping = makeBox(Vec3(1.5, 0.5, 7), Vec3(2, 2, 1), 0.3);
  EXPECT_TRUE(footprintsOverlap(a, overlapping));  // heights do not matter
  EXPECT_DOUBLE_EQ(footprintDistance(a, overlapping), 0.0);

  const OrientedBox touching = makeBox(Vec3(2, 0, 0), Vec3(2, 2, 1), 0.0);
  EXPECT_TRUE(footprintsOverlap(a, touching));
  EXPECT_DOUBLE_EQ(footprintDistance(a, touching), 0.0);

  const OrientedBox near_miss = makeBox(Vec3(2.0001, 0, 0), Vec3(2, 2, 1), 0.0);
  EXPECT_FALSE(footprintsOverlap(a, near_miss));
  EXPECT_NEAR(footprintDistance(a, near_miss), 1e-4, 1e-12);

  const OrientedBox inside = makeBox(Vec3(0, 0, 0), Vec3(0.5, 0.5, 1), 1.0);
  EXPECT_TRUE(footprintsOverlap(a, inside));
  EXPECT_TRUE(footprintsOverlap(inside, a));
}

}  // namespace
}  // namespace hameritt::geometry

// The corner-edge fast path must agree with the general polygon distance.
TEST(OrientedBoxTest, FootprintDistanceMatchesPolygonDistance) {
  std::mt19937_64 gen(1234);
  auto u = [&](double lo, double hi) {
    return lo + (hi - lo) * (static_cast<double>(gen() >> 11) * 0x1.0p-53);
  };
  int overlapping = 0;
  for (int i = 0; i < 3000; ++i) {
    hameritt::geometry::OrientedBox a, b;
    a.center = {u(-20, 20), u(-20, 20), 0};
    a.size = {u(0.2, 12), u(0.2, 12), 1};
    a.yaw = u(-4, 4);
    b.center = {u(-20, 20), u(-20, 20), 0};
    b.size = {u(0.2, 12), u(0.2, 12), 1};
    b.yaw = u(-4, 4);
    const double fast = hameritt::geometry::footprintDistance(a, b);
    const double slow = a.footprint().distance(b.footprint());
    EXPECT_NEAR(fast, slow, 1e-9) << "pair " << i;
    EXPECT_EQ(hameritt::geometry::footprintsOverlap(a, b), a.footprint().intersects(b.footprint()));
    overlapping += fast == 0.0;
  }
  EXPECT_GT(overlapping, 100);  // both branches exercised
}

// The variants taking the yaw's cosine and sine (kept per box by OccluderIndex) give exactly
// the answers of the plain ones.
TEST(OrientedBoxTest, VariantsWithGivenTrigMatchExactly) {
  using hameritt::geometry::OrientedBox;
  using hameritt::geometry::Vec3;
  std::mt19937_64 gen(25);
  std::uniform_real_distribution<double> pos(-30.0, 30.0), len(0.5, 12.0), ang(-4.0, 4.0);
  auto box = [&] {
    OrientedBox b;
    b.center = Vec3(pos(gen), pos(gen), len(gen));
    b.size = Vec3(len(gen), len(gen), len(gen));
    b.yaw = ang(gen);
    return b;
  };
  int hits = 0;
  for (int i = 0; i < 20000; ++i) {
    const OrientedBox a = box(), b = box();
    const double c = std::cos(b.yaw), s = std::sin(b.yaw);
    ASSERT_EQ(hameritt::geometry::footprintDistance(a, b),
              hameritt::geometry::footprintDistance(a, b, c, s));
    ASSERT_EQ(b.corners2(), b.corners2(c, s));
    const Vec3 p(pos(gen), pos(gen), len(gen)), q(pos(gen), pos(gen), len(gen));
    ASSERT_EQ(b.contains(p), b.contains(p, c, s));
    ASSERT_EQ(b.intersectsSegment(p, q), b.intersectsSegment(p, q, c, s));
    hits += b.intersectsSegment(p, q);
  }
  EXPECT_GT(hits, 100);  // both answers exercised
}
