// Unit tests of the cutting predicates (thesis §3.2.1 intersections; tolerance policy of
// predicates.hpp) and of the shape measures of §3.2.3.
#include <gtest/gtest.h>

#include <incise/cut/cut_mesh.hpp>
#include <incise/cut/predicates.hpp>
#include <incise/mesh/quality.hpp>

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

/// The §3.2.3 shapes the cutter's recipes dispatch on, classified by mesh/quality.hpp (the one
/// classification; cut::kTetEdge and mesh::kTetEdges agree, asserted in cutter_recipes.cpp).
TEST(CutShape, RecipeShapesByTheMeshClassification) {
  const mesh::ShapeThresholds th;  // thesis §3.3: AR < 0.01, large angle > 0.99π
  auto cls = [&th](const std::array<Vec3, 4>& p) {
    return mesh::classify_tetrahedron(p[0], p[1], p[2], p[3], th);
  };
  // Cap: apex 3 just above the centroid of the base → three large angles (Fig. 3.8), at the
  // apex edges (0,3), (1,3), (2,3) — the cutter finds the apex as their common node.
  const auto cap = cls({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.3, 0.3, 1e-4)});
  EXPECT_EQ(cap.shape, mesh::ShapeClass::kCap);
  EXPECT_TRUE(cap.large_angle_edge[2] && cap.large_angle_edge[4] && cap.large_angle_edge[5]);
  // Sliver: two crossing edges almost in one plane → two large angles, at (0,1) and (2,3).
  const auto sl = cls({Vec3(0, 0, 0), Vec3(1, 1, 0), Vec3(1, 0, 1e-4), Vec3(0, 1, 1e-4)});
  EXPECT_EQ(sl.shape, mesh::ShapeClass::kSliver);
  EXPECT_TRUE(sl.large_angle_edge[0] && sl.large_angle_edge[5]);
  // Spindle: node 3 near the middle of edge (0,1), slightly off → one large angle, at the
  // opposite edge (2,3); the recipe splits (0,1), the edge opposite the large angle.
  const auto sp = cls({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.5, -1e-4, 1e-4)});
  EXPECT_EQ(sp.shape, mesh::ShapeClass::kSpindle);
  EXPECT_TRUE(sp.large_angle_edge[5]);
  // Needle: one very short edge, no large angle.
  const auto nd = cls({Vec3(0, 0, 0), Vec3(1e-3, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)});
  EXPECT_EQ(nd.shape, mesh::ShapeClass::kNeedle);
  EXPECT_LT(nd.aspect_ratio, 0.01);
}

}  // namespace
}  // namespace incise::cut
