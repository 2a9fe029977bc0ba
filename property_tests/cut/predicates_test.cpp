// Unit tests of the cutting predicates (thesis §3.2.1 intersections; tolerance policy of
// predicates.hpp) and of the shape measures of §3.2.3.
#include <gtest/gtest.h>

#include <incise/cut/cut_mesh.hpp>
#include <incise/cut/predicates.hpp>
#include <incise/cut/tet_shape.hpp>

#include <cmath>

namespace incise::cut {
namespace {

const Vec3 kA(0, 0, 0), kB(1, 0, 0), kC(0, 1, 0);

TEST(CutPredicates, SegmentThroughTriangleInterior) {
  const SegmentHit h =
      intersect_segment_triangle(Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 3), kA, kB, kC);
  ASSERT_TRUE(h.hit);
  // t = 1/4 exactly representable: the division is exact to one rounding.
  EXPECT_NEAR(h.t, 0.25, 1e-15);
}

TEST(CutPredicates, SegmentThroughVertexEdgeAndMissing) {
  // Through vertex A and through the midpoint of edge AB: closed triangle counts as hit.
  EXPECT_TRUE(intersect_segment_triangle(Vec3(0, 0, -1), Vec3(0, 0, 1), kA, kB, kC).hit);
  EXPECT_TRUE(intersect_segment_triangle(Vec3(0.5, 0, -1), Vec3(0.5, 0, 1), kA, kB, kC).hit);
  // Just outside the hypotenuse.
  EXPECT_FALSE(intersect_segment_triangle(Vec3(0.6, 0.6, -1), Vec3(0.6, 0.6, 1), kA, kB, kC).hit);
  // Stops short of the plane.
  EXPECT_FALSE(
      intersect_segment_triangle(Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, -0.1), kA, kB, kC).hit);
}

TEST(CutPredicates, EndpointOnPlaneGivesParameterZeroOrOne) {
  const SegmentHit h0 =
      intersect_segment_triangle(Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 1), kA, kB, kC);
  ASSERT_TRUE(h0.hit);
  EXPECT_EQ(h0.t, 0.0);
  const SegmentHit h1 =
      intersect_segment_triangle(Vec3(0.2, 0.2, 1), Vec3(0.2, 0.2, 0), kA, kB, kC);
  ASSERT_TRUE(h1.hit);
  EXPECT_EQ(h1.t, 1.0);
}

TEST(CutPredicates, CoplanarSegmentIsNotAnIntersection) {
  EXPECT_FALSE(intersect_segment_triangle(Vec3(-1, 0.2, 0), Vec3(2, 0.2, 0), kA, kB, kC).hit);
  // Within the tolerance band (1e-14 relative off the plane) still counts as coplanar.
  EXPECT_FALSE(
      intersect_segment_triangle(Vec3(-1, 0.2, 1e-14), Vec3(2, 0.2, -1e-14), kA, kB, kC).hit);
}

TEST(CutPredicates, TriangleMeetsTetrahedronCases) {
  const Vec3 t[4] = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  // Small triangle fully inside (no edge crossings at all).
  EXPECT_TRUE(
      triangle_meets_tetrahedron(Vec3(0.1, 0.1, 0.1), Vec3(0.2, 0.1, 0.1), Vec3(0.1, 0.2, 0.1), t));
  // Large triangle slicing through.
  EXPECT_TRUE(triangle_meets_tetrahedron(Vec3(-5, -5, 0.3), Vec3(5, -5, 0.3), Vec3(0, 5, 0.3), t));
  // Far away.
  EXPECT_FALSE(triangle_meets_tetrahedron(Vec3(5, 5, 5), Vec3(6, 5, 5), Vec3(5, 6, 5), t));
  // Thin triangle piercing two faces without containing a vertex or an edge crossing.
  EXPECT_TRUE(
      triangle_meets_tetrahedron(Vec3(0.1, 0.1, -1), Vec3(0.1, 0.1, 2), Vec3(0.11, 0.1, 2), t));
}

TEST(CutShape, RegularAndFlatTetrahedra) {
  // Regular tetrahedron: height/edge = sqrt(2/3), all dihedral angles acos(1/3).
  const std::array<Vec3, 4> reg{Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, 1, -1), Vec3(-1, -1, 1)};
  const double sign = signed_volume(reg[0], reg[1], reg[2], reg[3]) > 0 ? 1 : -1;
  const TetShape s = tet_shape(reg);
  EXPECT_NEAR(sign * s.aspect_ratio, std::sqrt(2.0 / 3.0), 1e-12);          // round-off only
  for (double a : s.dihedral) EXPECT_NEAR(a, std::acos(1.0 / 3.0), 1e-12);  // round-off only
  // Cap: apex just above the centroid of the base → three large angles (Fig. 3.8).
  const std::array<Vec3, 4> cap{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.3, 0.3, 1e-4)};
  std::array<int, 6> large{};
  int n = 0;
  EXPECT_EQ(classify(tet_shape(cap), 0.99 * M_PI, large, n), DegeneracyShape::kCap);
  // Sliver: two crossing edges almost in one plane → two large angles.
  const std::array<Vec3, 4> sl{Vec3(0, 0, 0), Vec3(1, 1, 0), Vec3(1, 0, 1e-4), Vec3(0, 1, 1e-4)};
  EXPECT_EQ(classify(tet_shape(sl), 0.99 * M_PI, large, n), DegeneracyShape::kSliver);
  // Spindle: apex near the middle of an edge of the base, slightly off.
  const std::array<Vec3, 4> sp{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.5, -1e-4, 1e-4)};
  EXPECT_EQ(classify(tet_shape(sp), 0.99 * M_PI, large, n), DegeneracyShape::kSpindle);
  // Needle: one very short edge, no large angle.
  const std::array<Vec3, 4> nd{Vec3(0, 0, 0), Vec3(1e-3, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  EXPECT_EQ(classify(tet_shape(nd), 0.99 * M_PI, large, n), DegeneracyShape::kNeedle);
  EXPECT_LT(std::abs(tet_shape(nd).aspect_ratio), 0.01);
}

}  // namespace
}  // namespace incise::cut
