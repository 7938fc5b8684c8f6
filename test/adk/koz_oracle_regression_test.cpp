// Regressions found by the Shapely geometry oracle (test/scripts/test_geometry_oracle.py,
// docs/RELIABILITY.md): a segment that runs along an edge of a sliver zone and leaves it at a
// vertex. The edges there are almost parallel to the segment, so their line intersections are
// ill-conditioned; the vertex itself must still end the inside interval.

#include <gtest/gtest.h>

#include "hameritt/adk/constraint_monitor.h"

namespace hameritt::adk {
namespace {

using geometry::Polygon;
using geometry::Vec2;

double insideFraction(const Polygon& p, const Vec2& a, const Vec2& b) {
  double sum = 0.0;
  for (const auto& i : segmentInsidePolygon(p, a, b)) sum += i.length();
  return sum;
}

TEST(KozOracleRegressionTest, SegmentAlongASliverEdgeLeavesAtTheVertex) {
  // Oracle case (seed 1): 1.2 um of the segment lie beyond the last vertex, up to 1.2 um away
  // from the zone; before the fix the whole segment counted as inside.
  const Polygon sliver({{42.95085239791171, 10.75055556025123},
                        {42.950856228646636, 10.750554004933475},
                        {42.950858177590234, 10.750552600495055}});
  const Vec2 a(42.95085671588254, 10.75055365382387), b(42.95085915206204, 10.750551898275845);
  const double f = insideFraction(sliver, a, b);
  EXPECT_GT(f, 0.45);
  EXPECT_LT(f, 0.75);  // Shapely: on the boundary up to u ~ 0.6, then 0.3 to 1.2 um outside
  EXPECT_FALSE(sliver.contains(a + 0.9 * (b - a)));
}

TEST(KozOracleRegressionTest, ExactCollinearOverlapStillCounts) {
  // A square crossed along its bottom edge and beyond: boundary counts as inside.
  const Polygon square({{0, 0}, {4, 0}, {4, 4}, {0, 4}});
  EXPECT_DOUBLE_EQ(insideFraction(square, {-4, 0}, {4, 0}), 0.5);
  EXPECT_DOUBLE_EQ(insideFraction(square, {2, 0}, {6, 0}), 0.5);
}

}  // namespace
}  // namespace hameritt::adk
