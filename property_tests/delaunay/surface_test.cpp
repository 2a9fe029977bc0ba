// Triangle surfaces in 3D (delaunay/surface.hpp, thesis §5.3.1): the generated shapes are valid
// manifolds with boundary; the unfolded empty-circle criterion agrees with the planar one on a
// rotated flat sheet; the flip of Fig. 5.9 is refused; legalization on curved surfaces ends with
// every edge locally Delaunay or unflippable; ear-flip removal (Fig. 5.10) removes interior nodes
// two triangles at a time; bad surfaces are rejected.
#include <incise/core/error.hpp>
#include <incise/delaunay/surface.hpp>
#include <incise/delaunay/triangulation.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/validate.hpp>
#include <incise_test/delaunay_support.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

namespace incise::delaunay {
namespace {

::testing::AssertionResult valid(const Surface& s) {
  const auto r = mesh::validate(s.connectivity());
  if (r.ok()) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << r.violations.front().invariant << ": " << r.violations.front().message;
}

/// Interior grid nodes of an n × n make_surface mesh moved by up to `amount` of the spacing in
/// the parameter square (boundary nodes stay), then mapped onto the shape.
mesh::MeshData jittered(SurfaceShape shape, int n, double amount, std::mt19937_64& rng) {
  mesh::MeshData m = mesh::make_rectangle(n, n, 1.0, 1.0, mesh::GridDiagonal::kAlternating);
  std::uniform_real_distribution<double> U(-amount / n, amount / n);
  for (Index v = 0; v < m.num_points(); ++v) {
    const double u = m.points(0, v), w = m.points(1, v);
    const bool inner = u > 1e-9 && u < 1 - 1e-9 && w > 1e-9 && w < 1 - 1e-9;
    m.points.col(v) = surface_point(shape, u + (inner ? U(rng) : 0), w + (inner ? U(rng) : 0));
  }
  return m;
}

TEST(DelaunaySurface, GeneratedCylinderAndBellAreValidDiscs) {
  for (const SurfaceShape shape : {SurfaceShape::kCylinder, SurfaceShape::kBell}) {
    Surface s(make_surface(shape, 8));
    EXPECT_EQ(s.num_triangles(), 128);
    EXPECT_TRUE(valid(s));
    EXPECT_EQ(test::components(s), 1);
    // A disc: 4·8 boundary edges.
    EXPECT_EQ(s.connectivity().num_boundary_faces(), 32);
  }
}

TEST(DelaunaySurface, PleatedSaddleIsAValidDiscWithAnAlternatingCentre) {
  // make_monkey_saddle(10, 0.3) (Fig. 5.18's surface): 11 rows of 11 and 10 nodes, 10 strips of
  // 19 triangles; the origin's six neighbours at 0°, 60°, … alternately ±0.3 · 0.2 high.
  Surface s(make_monkey_saddle(10, 0.3));
  EXPECT_EQ(s.num_triangles(), 190);
  EXPECT_TRUE(valid(s));
  EXPECT_EQ(test::components(s), 1);
  Index centre = -1;
  for (Index v = 0; v < s.connectivity().num_vertices(); ++v)
    if (s.point(v).norm() < 1e-12) centre = v;
  ASSERT_GE(centre, 0);
  const std::vector<Index> nb = s.neighbours(centre);
  ASSERT_EQ(nb.size(), 6u);
  for (const Index w : nb) {
    const Vec3 p = s.point(w);
    const double theta = std::atan2(p.y(), p.x());
    EXPECT_NEAR(p.z(), 0.06 * std::cos(3 * theta), 1e-12) << "neighbour at " << theta;
    EXPECT_NEAR(std::abs(p.z()), 0.06, 1e-12);
  }
  EXPECT_THROW(make_monkey_saddle(5, 0.3), ParameterError);
  EXPECT_THROW(make_monkey_saddle(2, 0.3), ParameterError);
  EXPECT_THROW(make_monkey_saddle(10, 0), ParameterError);
  EXPECT_THROW(make_monkey_saddle(10, 1.5), ParameterError);
}

TEST(DelaunaySurface, UnfoldedCriterionIsThePlanarOneOnARotatedFlatSheet) {
  // §5.3.1: unfolding two coplanar triangles changes nothing, so on a flat sheet rotated into
  // 3D the unfolded test must give the planar exact incircle's answer for every edge.
  INCISE_SEEDED_RNG(rng, 53);
  std::uniform_real_distribution<double> U(-0.3, 0.3);
  int compared = 0, illegal = 0;
  for (int k = 0; k < 20; ++k) {
    mesh::MeshData flat = mesh::make_rectangle(6, 6, 1.0, 1.0, mesh::GridDiagonal::kForward);
    for (Index v = 0; v < flat.num_points(); ++v) {
      const double x = flat.points(0, v), y = flat.points(1, v);
      if (x > 1e-9 && x < 1 - 1e-9 && y > 1e-9 && y < 1 - 1e-9) {
        flat.points(0, v) += U(rng) / 6;
        flat.points(1, v) += U(rng) / 6;
      }
    }
    const Triangulation planar(flat);
    const Eigen::Matrix3d rot =
        Eigen::AngleAxisd(U(rng) * 5, Vec3(U(rng), U(rng), 1).normalized()).toRotationMatrix();
    mesh::MeshData turned = flat;
    turned.points = rot * flat.points;
    const Surface surface(turned);
    for (const Edge& e : planar.edges()) {
      ++compared;
      const bool legal = planar.is_locally_delaunay(e.first, e.second);
      illegal += !legal;
      EXPECT_EQ(surface.is_locally_delaunay(e.first, e.second), legal)
          << "sheet " << k << " edge " << e.first << "-" << e.second;
    }
  }
  EXPECT_GT(illegal, 50);  // the jitter makes many illegal edges: the comparison has teeth
  EXPECT_GT(compared, 1000);
}

TEST(DelaunaySurface, Fig5_9FlipWhoseNewEdgeExistsIsRefused) {
  // Three triangles around the apex v of a tetrahedron (its fourth face missing): flipping the
  // edge v–a would make b–c, already an edge of (v, b, c): refused, nothing changes.
  mesh::MeshData m;
  m.dimension = 2;
  m.points.resize(3, 4);
  m.points << 0, 1, 0, -1,  //
      0, 0, 1, -1,          //
      1, 0, 0, 0.2;
  m.cells.resize(3, 3);
  m.cells << 0, 0, 0,  //
      1, 2, 3,         //
      2, 3, 1;
  Surface s(m);
  ASSERT_TRUE(valid(s));
  EXPECT_EQ(s.try_flip(0, 1), FlipStatus::kTopological);
  EXPECT_EQ(s.num_topological_refusals(), 1);
  EXPECT_EQ(s.num_flips(), 0);
  EXPECT_EQ(s.num_triangles(), 3);
  EXPECT_TRUE(valid(s));
  // Boundary edges and constrained edges are not flipped either.
  EXPECT_EQ(s.try_flip(1, 2), FlipStatus::kNotAnEdge);
  s.set_constrained(0, 2);
  EXPECT_EQ(s.try_flip(0, 2), FlipStatus::kConstrained);
}

TEST(DelaunaySurface, LegalizationOnCurvedSurfacesEndsWithEveryEdgeDelaunayOrUnflippable) {
  INCISE_SEEDED_RNG(rng, 531);
  long flips = 0;
  for (int k = 0; k < 10; ++k) {
    const SurfaceShape shape = k % 2 ? SurfaceShape::kBell : SurfaceShape::kCylinder;
    Surface s(jittered(shape, 10, 0.4, rng));
    flips += s.legalize(s.edges());
    EXPECT_TRUE(valid(s));
    EXPECT_EQ(s.num_capped_legalizations(), 0);
    for (const Edge& e : s.edges()) {
      if (s.is_locally_delaunay(e.first, e.second)) continue;
      // Not Delaunay: then its flip must be refused (and is then left alone by Lawson).
      const FlipStatus f = s.try_flip(e.first, e.second);
      EXPECT_NE(f, FlipStatus::kFlipped) << "mesh " << k << " edge " << e.first << "-" << e.second;
    }
  }
  EXPECT_GT(flips, 100);  // the jittered grids were far from Delaunay
}

TEST(DelaunaySurface, Fig5_10EarFlipRemovalTakesTwoTrianglesPerInteriorNode) {
  INCISE_SEEDED_RNG(rng, 510);
  int removed = 0;
  for (const SurfaceShape shape : {SurfaceShape::kCylinder, SurfaceShape::kBell}) {
    Surface s(jittered(shape, 10, 0.3, rng));
    std::vector<Index> order(static_cast<size_t>(s.connectivity().num_vertices()));
    for (size_t i = 0; i < order.size(); ++i) order[i] = static_cast<Index>(i);
    std::shuffle(order.begin(), order.end(), rng);
    int here = 0;  // at most 20 removals per surface
    for (const Index v : order) {
      if (!s.is_interior_vertex(v)) {
        EXPECT_FALSE(s.remove_vertex(v));
        continue;
      }
      const Index before = s.num_triangles();
      if (s.remove_vertex(v)) {
        ++removed;
        ++here;
        EXPECT_EQ(s.num_triangles(), before - 2);
        EXPECT_EQ(s.connectivity().star_size(v), 0);
      }
      ASSERT_TRUE(valid(s)) << "after removing " << v;
      if (here == 20) break;
    }
  }
  EXPECT_GE(removed, 30);
}

TEST(DelaunaySurface, Fig5_10DegreeFourNodeOnBothDiagonalsIsRemovedAlongADiagonal) {
  // The centre of a square split into four triangles lies on both diagonals of its link: every
  // ear has the angle π at it, so no ear flip is possible (each is kNotConvex); the removal
  // replaces the four triangles by the two on a diagonal instead. Tilted out of the xy-plane.
  mesh::MeshData m;
  m.dimension = 2;
  m.points.resize(3, 5);
  m.points << 0, 1, 0, -1, 0,  //
      0, 0, 1, 0, -1,          //
      0, 0.3, 0.3, -0.3, -0.3;
  m.cells.resize(3, 4);
  m.cells << 0, 0, 0, 0,  //
      1, 2, 3, 4,         //
      2, 3, 4, 1;
  Surface s(m);
  for (const Index w : {1, 2, 3, 4}) EXPECT_EQ(Surface(m).try_flip(0, w), FlipStatus::kNotConvex);
  EXPECT_TRUE(s.remove_vertex(0));
  EXPECT_EQ(s.num_triangles(), 2);
  EXPECT_EQ(s.connectivity().star_size(0), 0);
  EXPECT_TRUE(valid(s));
}

TEST(DelaunaySurface, RejectsNonManifoldAndFlatInput) {
  mesh::MeshData fan;  // three triangles on the edge 0–1: not a manifold
  fan.dimension = 2;
  fan.points.resize(3, 5);
  fan.points << 0, 1, 0.5, 0.5, 0.5,  //
      0, 0, 1, -1, 0,                 //
      0, 0, 0, 0, 1;
  fan.cells.resize(3, 3);
  fan.cells << 0, 1, 0,  //
      1, 0, 1,           //
      2, 3, 4;
  EXPECT_ANY_THROW(Surface{fan});
  mesh::MeshData flat = make_surface(SurfaceShape::kBell, 3);
  flat.points.col(flat.cells(1, 0)) = flat.points.col(flat.cells(0, 0));
  EXPECT_THROW(Surface{flat}, ParameterError);
  EXPECT_THROW(make_surface(SurfaceShape::kCylinder, 1), ParameterError);
}

}  // namespace
}  // namespace incise::delaunay
