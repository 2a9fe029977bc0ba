// Triangulation (delaunay/triangulation.hpp, thesis §5.2.1 and §5.3.1): Lawson legalization
// gives every edge the empty-circle property, maximizes the minimum angle (the maxmin-angle
// property) and recovers the unique Delaunay triangulation from any flipped start; cocircular
// inputs terminate without flips; interior vertices are removed by ear flips (Fig. 5.10) and
// the result is Delaunay again. Connectivity validate() (with orientation) after every edit.
#include <incise/delaunay/predicates.hpp>
#include <incise/delaunay/triangulation.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/validate.hpp>
#include <incise_test/delaunay_support.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <random>

namespace incise::delaunay {
namespace {

using incise::test::valid;

/// A rectangle grid nx × ny (unit cells, forward diagonals) with interior nodes jittered by up
/// to `jitter` cells in each direction (|jitter| < 0.5 keeps every triangle counter-clockwise
/// only for small values; 0.3 is used, checked by the constructor).
mesh::MeshData jittered_grid(int nx, int ny, double jitter, std::mt19937_64& rng) {
  mesh::MeshData m = mesh::make_rectangle(nx, ny, nx, ny);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  for (Index v = 0; v < m.num_points(); ++v) {
    const double x = m.points(0, v), y = m.points(1, v);
    if (x > 0 && x < nx && y > 0 && y < ny) {
      m.points(0, v) += u(rng);
      m.points(1, v) += u(rng);
    }
  }
  return m;
}

::testing::AssertionResult all_delaunay(const Triangulation& t) {
  for (const Edge& e : t.edges())
    if (!t.is_locally_delaunay(e.first, e.second))
      return ::testing::AssertionFailure() << "edge " << e.first << "-" << e.second;
  return ::testing::AssertionSuccess();
}

double area(const Triangulation& t) {
  const mesh::MeshData m = t.to_mesh_data();
  double a = 0;
  for (Index c = 0; c < m.num_cells(); ++c) {
    const Vec2 p = m.points.col(m.cells(0, c)).head<2>(), q = m.points.col(m.cells(1, c)).head<2>(),
               r = m.points.col(m.cells(2, c)).head<2>();
    a += 0.5 * ((q - p).x() * (r - p).y() - (q - p).y() * (r - p).x());
  }
  return a;
}

TEST(DelaunayTriangulation, LegalizeMakesEveryEdgeDelaunayAndRaisesTheMinimumAngle) {
  INCISE_SEEDED_RNG(rng, 5101);
  long flips = 0;
  for (int trial = 0; trial < incise::test::scaled_for_checks(40); ++trial) {
    Triangulation t(jittered_grid(12, 9, 0.3, rng));
    const Index n = t.num_triangles();
    const double before = t.angle_range().first;
    flips += t.legalize(t.edges());
    ASSERT_TRUE(valid(t)) << "trial " << trial;
    ASSERT_TRUE(all_delaunay(t)) << "trial " << trial;
    EXPECT_EQ(t.num_triangles(), n);
    // maxmin-angle (§5.2.1): the Delaunay triangulation of the points maximizes the minimum
    // angle over all triangulations with the same boundary, the start among them.
    EXPECT_GE(t.angle_range().first, before) << "trial " << trial;
    EXPECT_NEAR(area(t), 12.0 * 9.0, 1e-12 * 108);  // flips retile the same region
  }
  EXPECT_GT(flips, 0);  // the jittered grids are not Delaunay to begin with
}

TEST(DelaunayTriangulation, AnyFlippedStartLegalizesToTheSameUniqueTriangulation) {
  INCISE_SEEDED_RNG(rng, 5102);
  for (int trial = 0; trial < incise::test::scaled_for_checks(20); ++trial) {
    Triangulation t(jittered_grid(10, 10, 0.3, rng));
    t.legalize(t.edges());
    const std::vector<Edge> reference = t.edges();
    // Random convex flips scramble it (validate after each), then legalize restores it: the
    // Delaunay triangulation of points in general position (random jitter: no four cocircular)
    // is unique.
    std::uniform_int_distribution<size_t> pick(0, reference.size() - 1);
    int flipped = 0;
    for (int k = 0; k < 300; ++k) {
      const std::vector<Edge> es = t.edges();
      const Edge e = es[pick(rng) % es.size()];
      if (t.flip(e.first, e.second)) {
        ++flipped;
        ASSERT_TRUE(valid(t)) << "trial " << trial << " flip " << k;
      }
    }
    ASSERT_GT(flipped, 50);
    t.legalize(t.edges());
    ASSERT_TRUE(valid(t));
    EXPECT_EQ(t.edges(), reference) << "trial " << trial;
  }
}

TEST(DelaunayTriangulation, CocircularSquaresNeedNoFlipAndTerminate) {
  // Every quadrilateral of a square grid is cocircular: incircle = 0 exactly, both diagonals
  // are Delaunay, and legalization must neither flip nor cycle.
  for (const auto diagonal : {mesh::GridDiagonal::kForward, mesh::GridDiagonal::kAlternating}) {
    Triangulation t(mesh::make_rectangle(16, 16, 1.0, 1.0, diagonal));
    EXPECT_EQ(t.legalize(t.edges()), 0);
    EXPECT_TRUE(all_delaunay(t));
  }
}

TEST(DelaunayTriangulation, BoundaryAndConstrainedEdgesAreNeverFlipped) {
  INCISE_SEEDED_RNG(rng, 5103);
  Triangulation t(jittered_grid(6, 6, 0.3, rng));
  std::vector<Edge> constrained;
  for (const Edge& e : t.edges())
    if (!t.is_boundary_edge(e.first, e.second) && (e.first + e.second) % 3 == 0) {
      t.set_constrained(e.first, e.second);
      constrained.push_back(e);
    }
  ASSERT_FALSE(constrained.empty());
  t.legalize(t.edges());
  for (const Edge& e : constrained) {
    EXPECT_EQ(t.incident(e.first, e.second).size(), 2u) << e.first << "-" << e.second;
    EXPECT_FALSE(t.flip(e.first, e.second));
  }
  for (const Edge& e : t.edges())
    if (t.is_boundary_edge(e.first, e.second)) {
      EXPECT_FALSE(t.flip(e.first, e.second));
    }
  EXPECT_TRUE(valid(t));
}

TEST(DelaunayTriangulation, RemovingInteriorVerticesByEarFlipsKeepsItDelaunay) {
  INCISE_SEEDED_RNG(rng, 5104);
  int removed = 0, refused = 0;
  const int trials = incise::test::scaled_for_checks(10, 5);
  for (int trial = 0; trial < trials; ++trial) {
    Triangulation t(jittered_grid(14, 14, 0.3, rng));
    t.legalize(t.edges());
    std::uniform_int_distribution<Index> pick(0, t.connectivity().num_vertices() - 1);
    for (int k = 0; k < 60; ++k) {
      const Index v = pick(rng);
      const Index n = t.num_triangles();
      if (!t.is_interior_vertex(v)) {
        EXPECT_FALSE(t.remove_vertex(v));  // boundary or already removed: refused, unchanged
        EXPECT_EQ(t.num_triangles(), n);
        ++refused;
        continue;
      }
      ASSERT_TRUE(t.remove_vertex(v)) << "trial " << trial << " vertex " << v;
      ++removed;
      ASSERT_EQ(t.connectivity().star_size(v), 0);
      ASSERT_EQ(t.num_triangles(), n - 2);  // Euler: one vertex less, two triangles less
      ASSERT_TRUE(valid(t)) << "trial " << trial << " vertex " << v;
      ASSERT_TRUE(all_delaunay(t)) << "trial " << trial << " vertex " << v;
      ASSERT_NEAR(area(t), 14.0 * 14.0, 1e-12 * 196);
    }
  }
  EXPECT_GT(removed, 20 * trials);  // of 60 picks per trial, ≈ 2/3 hit an interior vertex
  EXPECT_GT(refused, 0);
}

TEST(DelaunayTriangulation, RejectsClockwiseTrianglesAndBadInput) {
  mesh::MeshData m = mesh::make_rectangle(2, 2, 1, 1);
  std::swap(m.cells(1, 0), m.cells(2, 0));
  EXPECT_THROW(Triangulation{m}, ParameterError);
  m = mesh::make_rectangle(2, 2, 1, 1);
  m.points(0, 4) = std::nan("");
  EXPECT_THROW(Triangulation{m}, ParameterError);
  m = mesh::make_rectangle(2, 2, 1, 1);
  m.cells(0, 0) = 99;
  EXPECT_THROW(Triangulation{m}, ParameterError);
  EXPECT_THROW(Triangulation{mesh::make_box(1, 1, 1, 1, 1, 1)}, ParameterError);
}

}  // namespace
}  // namespace incise::delaunay
