/// Property tests of edge bisection (mesh/bisection.hpp, thesis §6.5) and the right-triangle
/// slabs (mesh/slab2d.hpp): 10⁴ random recursive bisect calls, each followed by validate() and
/// the assertion that every new triangle is right isosceles and congruent to its root scaled by
/// 2^(−depth/2). The default run restarts from an h1 slab every 200 calls (small meshes keep
/// validate() after every step cheap; paranoid builds, which validate every edit themselves,
/// add the test's call every 20th step); the `slow` ctest
/// (INCISE_BISECTION_SLOW=1) grows h2 slabs by 1000 calls each, so the meshes and trees get
/// several times larger and deeper. Also: area and perimeter conserved, point location
/// through the tree, refine-around, bad input.

#include <incise/core/error.hpp>
#include <incise/mesh/bisection.hpp>
#include <incise/mesh/slab2d.hpp>
#include <incise/mesh/validate.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>

namespace {

using incise::Index;
using incise::Vec2;
using incise::mesh::BisectionMesh;
using incise::mesh::ElementHandle;

double edge(const BisectionMesh& m, Index a, Index b) {
  return (m.points().col(a) - m.points().col(b)).norm();
}

/// Right isosceles, hypotenuse = root's hypotenuse · 2^(−depth/2), positive orientation:
/// relative 1e-12 (midpoints are rounded once per level, ≤ 30 levels here).
void expect_congruent(const BisectionMesh& m, ElementHandle e, double root_hyp) {
  const auto& node = m.tree()[static_cast<std::size_t>(m.node_of(e))];
  const auto h = m.hypotenuse(e);
  const auto& s = m.connectivity().simplex(e);
  Index apex = -1;
  for (int i = 0; i < 3; ++i)
    if (s.vertex(i) != h[0] && s.vertex(i) != h[1]) apex = s.vertex(i);
  const double hyp = edge(m, h[0], h[1]);
  const double expect = root_hyp * std::pow(2.0, -0.5 * node.depth);
  EXPECT_NEAR(hyp, expect, 1e-12 * expect);
  EXPECT_NEAR(edge(m, apex, h[0]), edge(m, apex, h[1]), 1e-12 * expect);
  const Eigen::Vector3d l0 = m.points().col(h[0]) - m.points().col(apex);
  const Eigen::Vector3d l1 = m.points().col(h[1]) - m.points().col(apex);
  EXPECT_LE(std::abs(l0.dot(l1)), 1e-12 * expect * expect);
}

TEST(Slab2d, ThesisSpacingsAndCounts) {
  for (int k = 1; k <= 7; ++k) {
    EXPECT_EQ(incise::mesh::thesis_slab_spacing(k), 0.1 / std::pow(2.0, k));
    const auto m = incise::mesh::make_thesis_slab(k);
    EXPECT_EQ(m.dimension, 2);
    EXPECT_EQ(m.num_cells(), 2 * (1 << (2 * k)));
    EXPECT_EQ(m.num_points(), ((1 << k) + 1) * ((1 << k) + 1));
  }
  const auto r = incise::mesh::make_right_triangle_slab(0.3, 0.1, 0.05);
  EXPECT_EQ(r.num_cells(), 2 * 6 * 2);
  EXPECT_THROW(incise::mesh::thesis_slab_spacing(0), incise::ParameterError);
  EXPECT_THROW(incise::mesh::thesis_slab_spacing(8), incise::ParameterError);
  EXPECT_THROW(incise::mesh::make_right_triangle_slab(0.1, 0.1, 0.03), incise::ParameterError);
  EXPECT_THROW(incise::mesh::make_right_triangle_slab(0.1, -0.1, 0.05), incise::ParameterError);
  EXPECT_THROW(incise::mesh::make_right_triangle_slab(0.1, 0.1, 0.0), incise::ParameterError);
}

TEST(Bisection, RandomBisectionsStayValidAndCongruent) {
  INCISE_SEEDED_RNG(rng, 1701);
  const bool slow = incise::test::env_set("INCISE_BISECTION_SLOW");
  const int level = slow ? 2 : 1;
  // 10⁴ bisect calls; a tenth of the rounds in builds with debug checks (paranoid validation
  // after every edit makes the sequence quadratic there: 102 s under ASan, 3.3 s in Release).
  const int rounds = slow ? 10 : incise::test::scaled_for_checks(50), per_round = slow ? 1000 : 200;
  long simple = 0;
  for (int round = 0; round < rounds; ++round) {
    BisectionMesh m(incise::mesh::make_thesis_slab(level));
    const double root_hyp = std::sqrt(2.0) * incise::mesh::thesis_slab_spacing(level);
    for (int it = 1; it <= per_round; ++it) {
      // A random live element and a random edge of it: bisect() must first bisect neighbours
      // whose hypotenuse that edge is not (Fig. 6.7).
      const auto& conn = m.connectivity();
      ElementHandle e;
      do {
        e = conn.element_at(
            std::uniform_int_distribution<Index>(0, conn.element_capacity() - 1)(rng));
      } while (!e.valid());
      const auto& s = conn.simplex(e);
      const int i = std::uniform_int_distribution<int>(0, 2)(rng);
      const long before = m.num_bisections();
      const Index n = m.bisect(s.vertex(i), s.vertex((i + 1) % 3));
      ASSERT_GT(m.num_bisections(), before);
      if (it % incise::test::kValidateEvery == 0) {
        incise::mesh::ValidateOptions o;
        o.positions = &m.points();
        const auto rep = incise::mesh::validate(conn, o);
        ASSERT_TRUE(rep.ok()) << rep.summary();
      }
      for (const ElementHandle t : conn.star(n)) expect_congruent(m, t, root_hyp);
    }
    // Every triangle congruent to its root; no hanging vertex: the area is conserved and
    // every interior edge has two triangles (validate: mates), and the boundary is the square's
    // perimeter 0.4 m.
    double area = 0.0, perimeter = 0.0;
    for (const ElementHandle t : m.connectivity().elements()) {
      expect_congruent(m, t, root_hyp);
      const auto& s = m.connectivity().simplex(t);
      const Eigen::Vector3d a = m.points().col(s.vertex(0)), b = m.points().col(s.vertex(1)),
                            c = m.points().col(s.vertex(2));
      area += 0.5 * std::abs((b - a).cross(c - a)(2));
    }
    for (const auto f : m.connectivity().boundary()) {
      const auto& s = m.connectivity().simplex(f);
      perimeter += edge(m, s.vertex(0), s.vertex(1));
    }
    // Sums of ~10⁴ terms each exact to a few ulps.
    EXPECT_NEAR(area, 0.01, 1e-14);
    EXPECT_NEAR(perimeter, 0.4, 1e-13);
    simple += m.num_bisections();
  }
  EXPECT_GE(simple, static_cast<long>(rounds) * per_round);
}

TEST(Bisection, PointLocationThroughTheTree) {
  INCISE_SEEDED_RNG(rng, 1702);
  BisectionMesh m(incise::mesh::make_thesis_slab(1));
  for (int i = 0; i < 300; ++i) {
    const auto& s = m.connectivity().simplex(m.connectivity().elements()[static_cast<std::size_t>(
        std::uniform_int_distribution<int>(0, m.connectivity().num_elements() - 1)(rng))]);
    m.bisect(s.vertex(0), s.vertex(1));
  }
  std::uniform_real_distribution<double> u(0.0, 0.1);
  for (int i = 0; i < 2000; ++i) {
    const Vec2 x(u(rng), u(rng));
    const ElementHandle t = m.locate(x);
    ASSERT_TRUE(t.valid());
    // The located triangle contains x (barycentric coordinates ≥ −1e-12).
    const auto& s = m.connectivity().simplex(t);
    const Vec2 a = m.points().col(s.vertex(0)).head<2>(), b = m.points().col(s.vertex(1)).head<2>(),
               c = m.points().col(s.vertex(2)).head<2>();
    Eigen::Matrix2d j;
    j << b - a, c - a;
    const Vec2 l = j.inverse() * (x - a);
    EXPECT_GE(l(0), -1e-12);
    EXPECT_GE(l(1), -1e-12);
    EXPECT_LE(l(0) + l(1), 1.0 + 1e-12);
  }
  EXPECT_FALSE(m.locate(Vec2(0.2, 0.05)).valid());
}

TEST(Bisection, RefineAroundReachesTheSize) {
  BisectionMesh m(incise::mesh::make_thesis_slab(1));
  const Vec2 x(0.0371, 0.0613);
  const double h = incise::mesh::thesis_slab_spacing(7);
  const int calls = m.refine_around(x, h);
  EXPECT_GT(calls, 0);
  const auto hyp = m.hypotenuse(m.locate(x));
  EXPECT_LE(edge(m, hyp[0], hyp[1]), h);
  // Graded, not uniform: far fewer triangles than the uniform h7-hypotenuse mesh (2·4⁷·2).
  EXPECT_LT(m.connectivity().num_elements(), 2000);
  incise::mesh::ValidateOptions o;
  o.positions = &m.points();
  EXPECT_TRUE(incise::mesh::validate(m.connectivity(), o).ok());
  EXPECT_EQ(m.refine_around(x, h), 0);  // already fine enough
  EXPECT_THROW(m.refine_around(Vec2(-1.0, 0.0), h), incise::UsageError);
  EXPECT_THROW(m.refine_around(x, 0.0), incise::UsageError);
}

TEST(Bisection, SimpleBisectChecksItsEdge) {
  BisectionMesh m(incise::mesh::make_thesis_slab(1));
  // Node (i, j) = i + 3j: (0,0)–(1,0) is a leg (square side) of its triangle, not a hypotenuse.
  EXPECT_THROW(m.simple_bisect(0, 1), incise::UsageError);
  EXPECT_THROW(m.simple_bisect(0, 8), incise::UsageError);  // not an edge
  EXPECT_THROW(m.bisect(0, 8), incise::UsageError);
  const Index n = m.bisect(0, 1);  // recursive: the square's diagonal first
  EXPECT_EQ(m.connectivity().num_vertices(), n + 1);
  EXPECT_EQ(m.points().col(n), Eigen::Vector3d(0.025, 0.0, 0.0));
  EXPECT_EQ(m.num_bisections(), 2);
}

}  // namespace
