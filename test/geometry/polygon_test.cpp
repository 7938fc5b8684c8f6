#include "hameritt/geometry/polygon.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace hameritt::geometry {
namespace {

Polygon square() { return Polygon({Vec2(0, 0), Vec2(4, 0), Vec2(4, 4), Vec2(0, 4)}); }
Polygon squareCw() { return Polygon({Vec2(0, 0), Vec2(0, 4), Vec2(4, 4), Vec2(4, 0)}); }
// L-shape: [0,4]x[0,1] plus [0,1]x[0,4]; the notch is (1,4]x(1,4].
Polygon lShape() {
  return Polygon({Vec2(0, 0), Vec2(4, 0), Vec2(4, 1), Vec2(1, 1), Vec2(1, 4), Vec2(0, 4)});
}

TEST(PolygonTest, AreaCentroidPerimeterBounds) {
  const Polygon sq = square();
  EXPECT_DOUBLE_EQ(sq.signedArea(), 16.0);
  EXPECT_DOUBLE_EQ(sq.area(), 16.0);
  EXPECT_DOUBLE_EQ(squareCw().signedArea(), -16.0);
  EXPECT_DOUBLE_EQ(squareCw().area(), 16.0);
  EXPECT_TRUE(sq.centroid().isApprox(Vec2(2, 2)));
  EXPECT_TRUE(squareCw().centroid().isApprox(Vec2(2, 2)));
  EXPECT_DOUBLE_EQ(sq.perimeter(), 16.0);
  EXPECT_EQ(sq.bounds().min, Vec2(0, 0));
  EXPECT_EQ(sq.bounds().max, Vec2(4, 4));
  EXPECT_EQ(sq.size(), 4u);

  // L: area 4 + 3 = 7, centroid (4*(2,0.5) + 3*(0.5,2.5)) / 7 = (9.5/7, 9.5/7).
  EXPECT_DOUBLE_EQ(lShape().area(), 7.0);
  EXPECT_NEAR((lShape().centroid() - Vec2(9.5 / 7, 9.5 / 7)).norm(), 0.0, 1e-14);
  EXPECT_DOUBLE_EQ(lShape().perimeter(), 16.0);

  const Polygon tri({Vec2(0, 0), Vec2(6, 0), Vec2(0, 3)});
  EXPECT_DOUBLE_EQ(tri.area(), 9.0);
  EXPECT_TRUE(tri.centroid().isApprox(Vec2(2, 1)));
  EXPECT_NEAR(tri.perimeter(), 9.0 + std::sqrt(45.0), 1e-12);
}

TEST(PolygonTest, DegenerateCentroidIsVertexMean) {
  const Polygon line({Vec2(0, 0), Vec2(2, 0), Vec2(4, 0)});
  EXPECT_DOUBLE_EQ(line.area(), 0.0);
  EXPECT_TRUE(line.centroid().isApprox(Vec2(2, 0)));
  EXPECT_TRUE(Polygon({Vec2(1, 1), Vec2(3, 5)}).centroid().isApprox(Vec2(2, 3)));
  EXPECT_DOUBLE_EQ(Polygon().area(), 0.0);
  EXPECT_DOUBLE_EQ(Polygon({Vec2(1, 1), Vec2(3, 1)}).area(), 0.0);
}

TEST(PolygonTest, ContainsInteriorExteriorBoundary) {
  for (const Polygon& sq : {square(), squareCw()}) {
    EXPECT_TRUE(sq.contains(Vec2(2, 2)));
    EXPECT_FALSE(sq.contains(Vec2(5, 2)));
    EXPECT_FALSE(sq.contains(Vec2(-0.5, 2)));
    // Edges and vertices count as inside.
    EXPECT_TRUE(sq.contains(Vec2(4, 2)));
    EXPECT_TRUE(sq.contains(Vec2(2, 0)));
    EXPECT_TRUE(sq.contains(Vec2(2, 4)));
    EXPECT_TRUE(sq.contains(Vec2(0, 0)));
    EXPECT_TRUE(sq.contains(Vec2(4, 4)));
    EXPECT_TRUE(sq.contains(Vec2(0, 4)));
    // Level with the horizontal edges, outside.
    EXPECT_FALSE(sq.contains(Vec2(5, 4)));
    EXPECT_FALSE(sq.contains(Vec2(-1, 0)));
    EXPECT_FALSE(sq.contains(Vec2(5, 0)));
    // Just off / just on the boundary.
    EXPECT_FALSE(sq.contains(Vec2(4 + 1e-6, 2)));
    EXPECT_TRUE(sq.contains(Vec2(4 - 1e-6, 2)));
    EXPECT_FALSE(sq.contains(Vec2(2, -1e-6)));
  }
}

TEST(PolygonTest, ContainsRayThroughVertices) {
  // Diamond: a horizontal ray from (x, 0) passes exactly through vertices.
  const Polygon diamond({Vec2(0, -2), Vec2(2, 0), Vec2(0, 2), Vec2(-2, 0)});
  EXPECT_FALSE(diamond.contains(Vec2(-3, 0)));
  EXPECT_TRUE(diamond.contains(Vec2(-1, 0)));
  EXPECT_TRUE(diamond.contains(Vec2(1, 0)));
  EXPECT_FALSE(diamond.contains(Vec2(3, 0)));
  EXPECT_TRUE(diamond.contains(Vec2(0, 2)));
  EXPECT_TRUE(diamond.contains(Vec2(1, 1)));  // on an edge
  EXPECT_FALSE(diamond.contains(Vec2(1.5, 1.5)));
  EXPECT_FALSE(diamond.contains(Vec2(0, 3)));
}

TEST(PolygonTest, ContainsConcaveWithHorizontalEdges) {
  const Polygon l = lShape();
  EXPECT_TRUE(l.contains(Vec2(0.5, 0.5)));
  EXPECT_TRUE(l.contains(Vec2(3, 0.5)));
  EXPECT_TRUE(l.contains(Vec2(0.5, 3)));
  EXPECT_FALSE(l.contains(Vec2(2, 2)));  // the notch
  EXPECT_FALSE(l.contains(Vec2(3, 1 + 1e-6)));
  EXPECT_TRUE(l.contains(Vec2(2, 1)));    // on the inner horizontal edge
  EXPECT_TRUE(l.contains(Vec2(0.5, 1)));  // level with it, inside
  EXPECT_FALSE(l.contains(Vec2(5, 1)));   // level with it, outside
  EXPECT_FALSE(l.contains(Vec2(-1, 1)));
  EXPECT_TRUE(l.contains(Vec2(1, 1)));  // reflex vertex
  EXPECT_TRUE(l.contains(Vec2(1, 4)));
  EXPECT_FALSE(l.contains(Vec2(2, 4)));  // level with the top edge, in the notch
}

TEST(PolygonTest, ContainsCollinearVertexAndFarOrigin) {
  const Polygon sq5({Vec2(0, 0), Vec2(2, 0), Vec2(4, 0), Vec2(4, 4), Vec2(0, 4)});
  EXPECT_TRUE(sq5.contains(Vec2(2, 0)));
  EXPECT_TRUE(sq5.contains(Vec2(2, 1)));
  EXPECT_FALSE(sq5.contains(Vec2(6, 0)));

  const Vec2 o(123456.0, -654321.0);
  const Polygon far({o + Vec2(0, 0), o + Vec2(4, 0), o + Vec2(4, 4), o + Vec2(0, 4)});
  EXPECT_TRUE(far.contains(o + Vec2(4, 2)));
  EXPECT_TRUE(far.contains(o + Vec2(2, 2)));
  EXPECT_FALSE(far.contains(o + Vec2(4.001, 2)));
  EXPECT_FALSE(Polygon().contains(Vec2(0, 0)));
}

TEST(PolygonTest, Distances) {
  const Polygon sq = square();
  EXPECT_DOUBLE_EQ(sq.boundaryDistance(Vec2(2, 2)), 2.0);
  EXPECT_DOUBLE_EQ(sq.boundaryDistance(Vec2(1, 2)), 1.0);
  EXPECT_DOUBLE_EQ(sq.boundaryDistance(Vec2(6, 2)), 2.0);
  EXPECT_DOUBLE_EQ(sq.boundaryDistance(Vec2(7, 8)), 5.0);
  EXPECT_DOUBLE_EQ(sq.distance(Vec2(2, 2)), 0.0);
  EXPECT_DOUBLE_EQ(sq.distance(Vec2(4, 1)), 0.0);
  EXPECT_DOUBLE_EQ(sq.distance(Vec2(7, 8)), 5.0);
  EXPECT_DOUBLE_EQ(lShape().distance(Vec2(2, 2)), 1.0);
}

TEST(PolygonTest, IntersectsSegment) {
  const Polygon sq = square();
  EXPECT_TRUE(sq.intersectsSegment(Vec2(1, 1), Vec2(2, 2)));    // inside
  EXPECT_TRUE(sq.intersectsSegment(Vec2(-1, 2), Vec2(5, 2)));   // crossing
  EXPECT_FALSE(sq.intersectsSegment(Vec2(5, 0), Vec2(5, 4)));   // beside
  EXPECT_TRUE(sq.intersectsSegment(Vec2(4, 4), Vec2(5, 5)));    // vertex touch
  EXPECT_TRUE(sq.intersectsSegment(Vec2(4, -1), Vec2(4, 5)));   // along an edge
  EXPECT_TRUE(sq.intersectsSegment(Vec2(5, -1), Vec2(-1, 5)));  // diagonal cut of a corner
  EXPECT_TRUE(sq.intersectsSegment(Vec2(2, 2), Vec2(2, 2)));    // zero length inside
  EXPECT_FALSE(sq.intersectsSegment(Vec2(6, 6), Vec2(6, 6)));   // zero length outside
  EXPECT_TRUE(sq.intersectsSegment(Vec2(0, 4), Vec2(0, 4)));    // zero length on vertex
  // Line x + y = 8 touches the square only at (4, 4).
  EXPECT_TRUE(sq.intersectsSegment(Vec2(8, 0), Vec2(0, 8)));
  EXPECT_FALSE(sq.intersectsSegment(Vec2(8.001, 0), Vec2(0, 8.001)));

  const Polygon l = lShape();
  EXPECT_FALSE(l.intersectsSegment(Vec2(2, 2), Vec2(3, 3)));     // within the notch
  EXPECT_TRUE(l.intersectsSegment(Vec2(0.5, 3), Vec2(3, 0.5)));  // through both arms
}

TEST(PolygonTest, IntersectsPolyline) {
  const Polygon sq = square();
  EXPECT_FALSE(sq.intersectsPolyline({}));
  EXPECT_TRUE(sq.intersectsPolyline({Vec2(2, 2)}));
  EXPECT_FALSE(sq.intersectsPolyline({Vec2(5, 5)}));
  EXPECT_FALSE(sq.intersectsPolyline({Vec2(5, -1), Vec2(5, 5), Vec2(3, 5)}));
  EXPECT_TRUE(sq.intersectsPolyline({Vec2(5, -1), Vec2(5, 5), Vec2(3, 5), Vec2(3, 3)}));
  EXPECT_TRUE(sq.intersectsPolyline({Vec2(5, -1), Vec2(5, 5), Vec2(4, 5), Vec2(4, 4)}));
}

TEST(PolygonTest, PolygonIntersectsAndDistance) {
  const Polygon sq = square();
  const Polygon overlapping = rectangle(Vec2(3, 3), Vec2(6, 6));
  const Polygon edge_touch = rectangle(Vec2(4, 0), Vec2(8, 4));
  const Polygon vertex_touch = rectangle(Vec2(4, 4), Vec2(6, 6));
  const Polygon inner = rectangle(Vec2(1, 1), Vec2(2, 2));
  const Polygon apart = rectangle(Vec2(6, 0), Vec2(8, 4));
  const Polygon diagonal_apart = rectangle(Vec2(7, 8), Vec2(9, 10));
  EXPECT_TRUE(sq.intersects(overlapping));
  EXPECT_TRUE(sq.intersects(edge_touch));
  EXPECT_TRUE(sq.intersects(vertex_touch));
  EXPECT_TRUE(sq.intersects(inner));
  EXPECT_TRUE(inner.intersects(sq));
  EXPECT_FALSE(sq.intersects(apart));
  EXPECT_FALSE(apart.intersects(sq));
  EXPECT_FALSE(sq.intersects(Polygon()));

  EXPECT_DOUBLE_EQ(sq.distance(overlapping), 0.0);
  EXPECT_DOUBLE_EQ(sq.distance(inner), 0.0);
  EXPECT_DOUBLE_EQ(sq.distance(vertex_touch), 0.0);
  EXPECT_DOUBLE_EQ(sq.distance(apart), 2.0);
  EXPECT_DOUBLE_EQ(sq.distance(diagonal_apart), 5.0);

  // Bounding boxes overlap but the square sits in the L's notch, 1 away from both arms.
  const Polygon notch = rectangle(Vec2(2, 2), Vec2(3, 3));
  EXPECT_FALSE(lShape().intersects(notch));
  EXPECT_DOUBLE_EQ(lShape().distance(notch), 1.0);
}

TEST(PolygonTest, IsSimple) {
  EXPECT_TRUE(square().isSimple());
  EXPECT_TRUE(squareCw().isSimple());
  EXPECT_TRUE(lShape().isSimple());
  // A straight vertex in the middle of an edge is allowed.
  EXPECT_TRUE(Polygon({Vec2(0, 0), Vec2(2, 0), Vec2(4, 0), Vec2(4, 4), Vec2(0, 4)}).isSimple());
  EXPECT_TRUE(Polygon({Vec2(0, 0), Vec2(1, 0), Vec2(0, 1)}).isSimple());
}

TEST(PolygonTest, IsSimpleRejections) {
  // Bow-tie / figure-eight.
  EXPECT_FALSE(Polygon({Vec2(0, 0), Vec2(2, 2), Vec2(2, 0), Vec2(0, 2)}).isSimple());
  // Two lobes touching at a shared vertex (1, 1).
  EXPECT_FALSE(
      Polygon({Vec2(0, 0), Vec2(2, 0), Vec2(1, 1), Vec2(2, 2), Vec2(0, 2), Vec2(1, 1)}).isSimple());
  // Explicitly closed ring: the last vertex repeats the first.
  EXPECT_FALSE(Polygon({Vec2(0, 0), Vec2(4, 0), Vec2(4, 4), Vec2(0, 4), Vec2(0, 0)}).isSimple());
  // Repeated consecutive vertex.
  EXPECT_FALSE(Polygon({Vec2(0, 0), Vec2(4, 0), Vec2(4, 0), Vec2(4, 4), Vec2(0, 4)}).isSimple());
  // Spike: the edge (4,4)->(4,2) folds back over (4,0)->(4,4); area is 4, not zero.
  const Polygon fold({Vec2(0, 0), Vec2(4, 0), Vec2(4, 4), Vec2(4, 2)});
  EXPECT_DOUBLE_EQ(fold.area(), 4.0);
  EXPECT_FALSE(fold.isSimple());
  // Spike sticking out of a square edge and back.
  EXPECT_FALSE(
      Polygon({Vec2(0, 0), Vec2(4, 0), Vec2(4, 2), Vec2(6, 2), Vec2(4, 2), Vec2(4, 4), Vec2(0, 4)})
          .isSimple());
  // A vertex lying on a non-adjacent edge.
  EXPECT_FALSE(Polygon({Vec2(0, 0), Vec2(4, 0), Vec2(4, 4), Vec2(2, 0)}).isSimple());
  // Too few vertices, zero area, non-finite.
  EXPECT_FALSE(Polygon({Vec2(0, 0), Vec2(1, 0)}).isSimple());
  EXPECT_FALSE(Polygon().isSimple());
  EXPECT_FALSE(Polygon({Vec2(0, 0), Vec2(1, 0), Vec2(2, 0)}).isSimple());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(Polygon({Vec2(0, 0), Vec2(1, 0), Vec2(nan, 1)}).isSimple());
}

TEST(PolygonTest, CounterClockwise) {
  const Polygon ccw = squareCw().counterClockwise();
  ASSERT_EQ(ccw.size(), 4u);
  EXPECT_EQ(ccw.vertices()[0], Vec2(0, 0));
  EXPECT_EQ(ccw.vertices()[1], Vec2(4, 0));
  EXPECT_EQ(ccw.vertices()[2], Vec2(4, 4));
  EXPECT_EQ(ccw.vertices()[3], Vec2(0, 4));
  EXPECT_EQ(square().counterClockwise().vertices(), square().vertices());
}

TEST(PolygonTest, RectangleHelpers) {
  const Polygon r = rectangle(Vec2(0, 0), Vec2(2, 1));
  ASSERT_EQ(r.size(), 4u);
  EXPECT_EQ(r.vertices()[0], Vec2(0, 0));
  EXPECT_EQ(r.vertices()[1], Vec2(2, 0));
  EXPECT_EQ(r.vertices()[2], Vec2(2, 1));
  EXPECT_EQ(r.vertices()[3], Vec2(0, 1));
  // Swapped corners still give the counter-clockwise ring from the min corner.
  EXPECT_EQ(rectangle(Vec2(2, 1), Vec2(0, 0)).vertices(), r.vertices());

  // Centre (1,1), length 4 along yaw 90 degrees (north), width 2.
  const Polygon o = orientedRectangle(Vec2(1, 1), 4.0, 2.0, 0.5 * kPi);
  ASSERT_EQ(o.size(), 4u);
  const Vec2 expected[] = {Vec2(2, -1), Vec2(2, 3), Vec2(0, 3), Vec2(0, -1)};
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR((o.vertices()[i] - expected[i]).norm(), 0.0, 1e-14) << i;
  }
  EXPECT_NEAR(o.signedArea(), 8.0, 1e-12);
}

}  // namespace
}  // namespace hameritt::geometry
