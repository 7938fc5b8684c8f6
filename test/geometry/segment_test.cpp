#include "hameritt/geometry/segment.h"

#include <gtest/gtest.h>

#include <cmath>

namespace hameritt::geometry {
namespace {

// Both argument orders and both segment orders must agree.
bool intersectsAnyOrder(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const bool r = segmentsIntersect(a, b, c, d);
  EXPECT_EQ(r, segmentsIntersect(b, a, c, d));
  EXPECT_EQ(r, segmentsIntersect(c, d, a, b));
  EXPECT_EQ(r, segmentsIntersect(d, c, b, a));
  return r;
}

TEST(SegmentTest, PointSegmentDistance) {
  EXPECT_DOUBLE_EQ(pointSegmentDistance(Vec2(1, 1), Vec2(0, 0), Vec2(2, 0)), 1.0);
  EXPECT_DOUBLE_EQ(pointSegmentDistance(Vec2(5, 4), Vec2(0, 0), Vec2(2, 0)), 5.0);
  EXPECT_DOUBLE_EQ(pointSegmentDistance(Vec2(-3, -4), Vec2(0, 0), Vec2(2, 0)), 5.0);
  EXPECT_DOUBLE_EQ(pointSegmentDistance(Vec2(1, 0), Vec2(0, 0), Vec2(2, 0)), 0.0);
  // Zero-length segment: distance to the point.
  EXPECT_DOUBLE_EQ(pointSegmentDistance(Vec2(4, 5), Vec2(1, 1), Vec2(1, 1)), 5.0);
  // Diagonal: (0,2) to the line y = x is sqrt(2).
  EXPECT_NEAR(pointSegmentDistance(Vec2(0, 2), Vec2(0, 0), Vec2(4, 4)), std::sqrt(2.0), 1e-15);
}

TEST(SegmentTest, ClosestPointOnSegment) {
  EXPECT_TRUE(closestPointOnSegment(Vec2(1, 5), Vec2(0, 0), Vec2(2, 0)).isApprox(Vec2(1, 0)));
  EXPECT_EQ(closestPointOnSegment(Vec2(-3, 1), Vec2(0, 0), Vec2(2, 0)), Vec2(0, 0));
  EXPECT_EQ(closestPointOnSegment(Vec2(9, -1), Vec2(0, 0), Vec2(2, 0)), Vec2(2, 0));
  EXPECT_EQ(closestPointOnSegment(Vec2(9, -1), Vec2(3, 3), Vec2(3, 3)), Vec2(3, 3));
  EXPECT_TRUE(closestPointOnSegment(Vec2(0, 2), Vec2(0, 0), Vec2(4, 4)).isApprox(Vec2(1, 1)));
}

TEST(SegmentTest, SegmentsIntersectProperAndDisjoint) {
  EXPECT_TRUE(intersectsAnyOrder(Vec2(0, 0), Vec2(2, 2), Vec2(0, 2), Vec2(2, 0)));
  EXPECT_FALSE(intersectsAnyOrder(Vec2(0, 0), Vec2(2, 0), Vec2(0, 1), Vec2(2, 1)));
  // Lines cross, segments do not (crossing point (3, 3) lies beyond the first segment).
  EXPECT_FALSE(intersectsAnyOrder(Vec2(0, 0), Vec2(2, 2), Vec2(3, 0), Vec2(3, 5)));
  // Near miss by 1e-6.
  EXPECT_FALSE(intersectsAnyOrder(Vec2(0, 0), Vec2(1, 0), Vec2(1 + 1e-6, -1), Vec2(1 + 1e-6, 1)));
}

TEST(SegmentTest, SegmentsIntersectTouchingAndCollinear) {
  // Shared endpoint, T-junction.
  EXPECT_TRUE(intersectsAnyOrder(Vec2(0, 0), Vec2(1, 0), Vec2(1, 0), Vec2(1, 1)));
  EXPECT_TRUE(intersectsAnyOrder(Vec2(0, 0), Vec2(2, 0), Vec2(1, 0), Vec2(1, 3)));
  // Collinear: overlapping, end to end, disjoint, one containing the other.
  EXPECT_TRUE(intersectsAnyOrder(Vec2(0, 0), Vec2(2, 0), Vec2(1, 0), Vec2(3, 0)));
  EXPECT_TRUE(intersectsAnyOrder(Vec2(0, 0), Vec2(1, 0), Vec2(1, 0), Vec2(2, 0)));
  EXPECT_FALSE(intersectsAnyOrder(Vec2(0, 0), Vec2(1, 0), Vec2(2, 0), Vec2(3, 0)));
  EXPECT_TRUE(intersectsAnyOrder(Vec2(0, 0), Vec2(4, 4), Vec2(1, 1), Vec2(2, 2)));
  // Collinear vertical, disjoint.
  EXPECT_FALSE(intersectsAnyOrder(Vec2(0, 0), Vec2(0, 1), Vec2(0, 1.5), Vec2(0, 3)));
}

TEST(SegmentTest, SegmentsIntersectZeroLength) {
  EXPECT_TRUE(intersectsAnyOrder(Vec2(1, 0), Vec2(1, 0), Vec2(0, 0), Vec2(2, 0)));
  EXPECT_FALSE(intersectsAnyOrder(Vec2(1, 1e-3), Vec2(1, 1e-3), Vec2(0, 0), Vec2(2, 0)));
  EXPECT_TRUE(intersectsAnyOrder(Vec2(3, 4), Vec2(3, 4), Vec2(3, 4), Vec2(3, 4)));
  EXPECT_FALSE(intersectsAnyOrder(Vec2(3, 4), Vec2(3, 4), Vec2(3, 5), Vec2(3, 5)));
  // Zero-length segment on an endpoint.
  EXPECT_TRUE(intersectsAnyOrder(Vec2(2, 0), Vec2(2, 0), Vec2(0, 0), Vec2(2, 0)));
}

TEST(SegmentTest, SegmentSegmentDistance) {
  EXPECT_DOUBLE_EQ(segmentSegmentDistance(Vec2(0, 0), Vec2(2, 0), Vec2(0, 1), Vec2(2, 1)), 1.0);
  EXPECT_DOUBLE_EQ(segmentSegmentDistance(Vec2(0, 0), Vec2(2, 2), Vec2(0, 2), Vec2(2, 0)), 0.0);
  EXPECT_DOUBLE_EQ(segmentSegmentDistance(Vec2(0, 0), Vec2(1, 0), Vec2(1, 0), Vec2(1, 1)), 0.0);
  EXPECT_NEAR(segmentSegmentDistance(Vec2(0, 0), Vec2(1, 0), Vec2(2, 1), Vec2(3, 5)),
              std::sqrt(2.0), 1e-15);
  EXPECT_DOUBLE_EQ(segmentSegmentDistance(Vec2(0, 0), Vec2(1, 0), Vec2(3, 0), Vec2(4, 0)), 2.0);
  // T-shape not touching: stem ends 0.5 below the bar.
  EXPECT_DOUBLE_EQ(segmentSegmentDistance(Vec2(-1, 0), Vec2(1, 0), Vec2(0, -3), Vec2(0, -0.5)),
                   0.5);
  // Zero-length vs segment, zero-length vs zero-length.
  EXPECT_DOUBLE_EQ(segmentSegmentDistance(Vec2(1, 3), Vec2(1, 3), Vec2(0, 0), Vec2(2, 0)), 3.0);
  EXPECT_DOUBLE_EQ(segmentSegmentDistance(Vec2(0, 0), Vec2(0, 0), Vec2(3, 4), Vec2(3, 4)), 5.0);
}

TEST(SegmentTest, SegmentIntersectionPoint) {
  auto p = segmentIntersectionPoint(Vec2(0, 0), Vec2(2, 2), Vec2(0, 2), Vec2(2, 0));
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR((*p - Vec2(1, 1)).norm(), 0.0, 1e-15);

  p = segmentIntersectionPoint(Vec2(0, 0), Vec2(4, 2), Vec2(0, 2), Vec2(4, 0));
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR((*p - Vec2(2, 1)).norm(), 0.0, 1e-15);

  // T-junction and end-to-end touching give the single shared point.
  p = segmentIntersectionPoint(Vec2(0, 0), Vec2(2, 0), Vec2(1, 0), Vec2(1, 3));
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR((*p - Vec2(1, 0)).norm(), 0.0, 1e-15);
  p = segmentIntersectionPoint(Vec2(0, 0), Vec2(1, 0), Vec2(1, 0), Vec2(2, 0));
  ASSERT_TRUE(p.has_value());
  EXPECT_NEAR((*p - Vec2(1, 0)).norm(), 0.0, 1e-15);

  // No single point: disjoint, parallel, collinear overlap.
  EXPECT_FALSE(
      segmentIntersectionPoint(Vec2(0, 0), Vec2(2, 2), Vec2(3, 0), Vec2(3, 5)).has_value());
  EXPECT_FALSE(
      segmentIntersectionPoint(Vec2(0, 0), Vec2(2, 0), Vec2(0, 1), Vec2(2, 1)).has_value());
  EXPECT_FALSE(
      segmentIntersectionPoint(Vec2(0, 0), Vec2(2, 0), Vec2(1, 0), Vec2(3, 0)).has_value());
}

TEST(SegmentTest, PolylineLengthAndPointAt) {
  const std::vector<Vec2> line{Vec2(0, 0), Vec2(3, 4), Vec2(3, 10)};
  EXPECT_DOUBLE_EQ(polylineLength(line), 11.0);
  EXPECT_DOUBLE_EQ(polylineLength({}), 0.0);
  EXPECT_DOUBLE_EQ(polylineLength({Vec2(1, 1)}), 0.0);

  EXPECT_EQ(polylinePointAt(line, 0.0), Vec2(0, 0));
  EXPECT_EQ(polylinePointAt(line, -1.0), Vec2(0, 0));
  EXPECT_TRUE(polylinePointAt(line, 2.5).isApprox(Vec2(1.5, 2.0)));
  EXPECT_TRUE(polylinePointAt(line, 5.0).isApprox(Vec2(3, 4)));
  EXPECT_TRUE(polylinePointAt(line, 8.0).isApprox(Vec2(3, 7)));
  EXPECT_EQ(polylinePointAt(line, 100.0), Vec2(3, 10));
  // A repeated point contributes nothing.
  EXPECT_TRUE(polylinePointAt({Vec2(0, 0), Vec2(0, 0), Vec2(2, 0)}, 1.0).isApprox(Vec2(1, 0)));
  EXPECT_EQ(polylinePointAt({Vec2(7, 7)}, 3.0), Vec2(7, 7));
  EXPECT_THROW(polylinePointAt({}, 1.0), GeometryError);
}

TEST(SegmentTest, PointPolylineDistance) {
  const std::vector<Vec2> line{Vec2(0, 0), Vec2(3, 4), Vec2(3, 10)};
  EXPECT_DOUBLE_EQ(pointPolylineDistance(Vec2(0, 10), line), 3.0);
  EXPECT_DOUBLE_EQ(pointPolylineDistance(Vec2(3, 7), line), 0.0);
  EXPECT_DOUBLE_EQ(pointPolylineDistance(Vec2(4, 5), {Vec2(1, 1)}), 5.0);
  EXPECT_THROW(pointPolylineDistance(Vec2(0, 0), {}), GeometryError);
}

}  // namespace
}  // namespace hameritt::geometry
