/// Uniform 1→8 refinement (Bey 1995, mesh/refine_uniform.hpp): volume kept exactly (up to
/// round-off), 8× cells, a conforming and positively oriented result (validate()), the boundary
/// and the file's facets split into four each, corner children similar to their parent and at
/// most three similarity classes under repeated refinement (Bey's theorem, the quality bound).

#include <gtest/gtest.h>
#include <incise/core/error.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/refine_uniform.hpp>
#include <incise/mesh/tet_faces.hpp>
#include <incise/mesh/validate.hpp>
#include <incise_test/seed.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <set>

namespace incise::mesh {
namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

/// The liver of reference_data (3,721 vertices, 16,597 tetrahedra; MANIFEST.tsv), in metres.
MeshData liver() {
  io::ReadOptions o;
  o.scale = 0.001;
  return io::read_mesh(test::source_path("reference_data/meshes/liver_coarse.mesh"), o).mesh;
}

double cell_volume(const MeshData& m, Eigen::Index c) {
  return signed_volume(m.points.col(m.cells(0, c)), m.points.col(m.cells(1, c)),
                       m.points.col(m.cells(2, c)), m.points.col(m.cells(3, c)));
}

double max_edge(const MeshData& m, Eigen::Index c) {
  double l = 0;
  for (const auto& e : kTetEdges)
    l = std::max(l, (m.points.col(m.cells(e[1], c)) - m.points.col(m.cells(e[0], c))).norm());
  return l;
}

double boundary_area(const MeshData& m) {
  const CellMatrix f = boundary_faces(m);
  double a = 0;
  for (Eigen::Index k = 0; k < f.cols(); ++k)
    a += triangle_area(m.points.col(f(0, k)), m.points.col(f(1, k)), m.points.col(f(2, k)));
  return a;
}

/// Every property of the header's contract on one mesh.
void expect_refinement_properties(const MeshData& m) {
  const MeshData r = refine_uniform(m);
  ASSERT_EQ(r.num_cells(), 8 * m.num_cells());
  ASSERT_EQ(r.points.leftCols(m.num_points()), m.points);  // old points first, unchanged
  const double scale = m.points.cwiseAbs().maxCoeff();
  double total = 0, total_refined = 0;
  for (Index c = 0; c < m.num_cells(); ++c) {
    const double v = cell_volume(m, c);
    const double l = max_edge(m, c);
    // A midpoint is rounded by ≤ ε·|x| per coordinate; the volume is a 3×3 determinant of edge
    // vectors of length ≤ l over 6, so each perturbed coordinate moves it by ≤ l²·ε·|x|/6 and
    // the 12 coordinates of a child by ≤ 2·ε·|x|·l² (factor 2 for the determinant's own rounding).
    const double tol = 4 * kEps * scale * l * l;
    total += v;
    const double q = volume_area_quality(m.points.col(m.cells(0, c)), m.points.col(m.cells(1, c)),
                                         m.points.col(m.cells(2, c)), m.points.col(m.cells(3, c)));
    for (int k = 0; k < 8; ++k) {
      const double vk = cell_volume(r, 8 * c + k);
      total_refined += vk;
      ASSERT_NEAR(vk, v / 8, tol) << "cell " << c << " child " << k;
      ASSERT_GT(vk, 0.0) << "cell " << c << " child " << k;  // positive orientation
      if (k < 4) {
        // Corner children are the parent scaled by 1/2 (quality is scale invariant); the
        // quality is a ratio of volume and areas, each exact up to the rounding bounded above.
        const double qk = volume_area_quality(
            r.points.col(r.cells(0, 8 * c + k)), r.points.col(r.cells(1, 8 * c + k)),
            r.points.col(r.cells(2, 8 * c + k)), r.points.col(r.cells(3, 8 * c + k)));
        ASSERT_NEAR(qk, q, 64 * kEps * scale * l * l / std::abs(v) * std::abs(q) + 1e-14)
            << "corner child " << k << " of cell " << c << " is not similar to its parent";
      }
    }
  }
  // Sum of n terms, each exact to the bound above; relative 1e-12 covers n·ε for n ≤ 10⁴·4.5.
  EXPECT_NEAR(total_refined, total, 1e-12 * total);

  // Conforming, oriented: the ch. 7 invariants with positions (orientation included).
  const Connectivity conn = Connectivity::from_mesh_data(r);
  ValidateOptions vo;
  vo.positions = &r.points;
  const ValidationReport report = validate(conn, vo);
  EXPECT_TRUE(report.ok()) << report.summary();

  // The boundary: each face split into four, the same area (round-off of the sums only).
  EXPECT_EQ(boundary_faces(r).cols(), 4 * boundary_faces(m).cols());
  EXPECT_NEAR(boundary_area(r), boundary_area(m), 1e-12 * boundary_area(m));
  if (m.facets.cols() > 0) {
    const FacetCoverage before = facet_coverage(m.cells, m.facets);
    const FacetCoverage after = facet_coverage(r.cells, r.facets);
    EXPECT_EQ(after.distinct, 4 * before.distinct);
    EXPECT_EQ(after.on_boundary, 4 * before.on_boundary);
    EXPECT_EQ(after.interior, 4 * before.interior);
    EXPECT_EQ(after.boundary_not_listed, 4 * before.boundary_not_listed);
  }
}

TEST(RefineUniform, BoxVolumeConformityOrientationBoundary) {
  expect_refinement_properties(make_box(3, 2, 2, 0.3, 0.2, 0.25));
  expect_refinement_properties(make_box(2, 3, 2, 0.3, 0.2, 0.25, CubeSplit::kFive));
}

TEST(RefineUniform, LiverVolumeConformityOrientationBoundaryFacets) {
  const MeshData m = liver();
  ASSERT_GT(m.facets.cols(), 0);  // the Medit file lists its boundary triangles
  expect_refinement_properties(m);
}

TEST(RefineUniform, PointCountIsVerticesPlusEdges) {
  // A single tetrahedron: 4 + 6 points; two sharing a face: 5 + 9.
  MeshData one;
  one.points.resize(3, 5);
  one.points << 0, 1, 0, 0, 1,  //
      0, 0, 1, 0, 1,            //
      0, 0, 0, 1, 1;
  one.cells.resize(4, 1);
  one.cells << 0, 1, 2, 3;
  one.points.conservativeResize(3, 4);
  EXPECT_EQ(refine_uniform(one).num_points(), 10);
  MeshData two = one;
  two.points.conservativeResize(3, 5);
  two.points.col(4) << 1, 1, 1;
  two.cells.resize(4, 2);
  two.cells.col(0) << 0, 1, 2, 3;
  two.cells.col(1) << 1, 4, 2, 3;  // shares face (1,2,3), opposite side
  ASSERT_GT(cell_volume(two, 1), 0.0);
  const MeshData r = refine_uniform(two);
  EXPECT_EQ(r.num_points(), 5 + 9);
  EXPECT_TRUE(validate(Connectivity::from_mesh_data(r)).ok());
}

TEST(RefineUniform, TagsAreInherited) {
  MeshData m = make_box(1, 1, 2, 1.0, 1.0, 2.0);
  m.cell_tags.resize(static_cast<std::size_t>(m.num_cells()));
  for (std::size_t c = 0; c < m.cell_tags.size(); ++c) m.cell_tags[c] = static_cast<int>(c) + 10;
  m.point_tags.assign(static_cast<std::size_t>(m.num_points()), 3);
  m.point_tags[0] = 7;  // edges at point 0 get 0, all others 3
  m.facets = boundary_faces(m);
  m.facet_tags.resize(static_cast<std::size_t>(m.facets.cols()));
  for (std::size_t k = 0; k < m.facet_tags.size(); ++k) m.facet_tags[k] = static_cast<int>(k);
  const MeshData r = refine_uniform(m);
  for (Index c = 0; c < r.num_cells(); ++c) EXPECT_EQ(r.cell_tags[c], m.cell_tags[c / 8]);
  for (std::size_t k = 0; k < r.facet_tags.size(); ++k)
    EXPECT_EQ(r.facet_tags[k], m.facet_tags[k / 4]);
  ASSERT_EQ(r.point_tags.size(), static_cast<std::size_t>(r.num_points()));
  for (Index p = 0; p < m.num_points(); ++p) EXPECT_EQ(r.point_tags[p], m.point_tags[p]);
  int zero = 0;
  for (Index p = m.num_points(); p < r.num_points(); ++p) {
    EXPECT_TRUE(r.point_tags[p] == 3 || r.point_tags[p] == 0);
    zero += r.point_tags[p] == 0;
  }
  // Exactly the midpoints of point 0's edges: those end at point 0 (refined, so point 0's
  // valence in r equals its valence in m and each neighbour of 0 in r is such a midpoint).
  int valence0 = 0;
  std::set<Index> nbrs;
  for (Index c = 0; c < r.num_cells(); ++c)
    for (int i = 0; i < 4; ++i)
      if (r.cells(i, c) == 0)
        for (int j = 0; j < 4; ++j)
          if (j != i) nbrs.insert(r.cells(j, c));
  valence0 = static_cast<int>(nbrs.size());
  EXPECT_EQ(zero, valence0);
}

/// Sorted edge lengths over the longest, rounded: equal keys ⇔ similar tetrahedra (to 1e-9).
std::array<long long, 6> shape_key(const std::array<Vec3, 4>& t) {
  std::array<double, 6> e{};
  for (int k = 0; k < 6; ++k) e[k] = (t[kTetEdges[k][0]] - t[kTetEdges[k][1]]).norm();
  std::sort(e.begin(), e.end());
  std::array<long long, 6> key{};
  for (int k = 0; k < 6; ++k) key[k] = std::llround(e[k] / e[5] * 1e9);
  return key;
}

// Bey 1995, Theorem (congruence classes): every descendant of a tetrahedron under repeated red
// refinement with his vertex order is similar to one of at most three tetrahedra. With the
// orientation swap (1 ↔ 3) this still holds; it bounds the quality of all levels by that of
// the first.
TEST(RefineUniform, RepeatedRefinementKeepsAtMostThreeSimilarityClasses) {
  INCISE_SEEDED_RNG(rng, 1995);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 10; ++trial) {
    MeshData m;
    m.points = Eigen::Matrix3Xd::NullaryExpr(3, 4, [&]() { return g(rng); });
    m.cells.resize(4, 1);
    m.cells << 0, 1, 2, 3;
    if (cell_volume(m, 0) < 0) std::swap(m.cells(0, 0), m.cells(1, 0));
    double q1 = 0;
    for (int level = 1; level <= 3; ++level) {
      m = refine_uniform(m);
      std::set<std::array<long long, 6>> classes;
      double qmin = 1;
      for (Index c = 0; c < m.num_cells(); ++c) {
        std::array<Vec3, 4> t;
        for (int i = 0; i < 4; ++i) t[i] = m.points.col(m.cells(i, c));
        classes.insert(shape_key(t));
        qmin = std::min(qmin, volume_area_quality(t[0], t[1], t[2], t[3]));
      }
      EXPECT_LE(classes.size(), 3u) << "trial " << trial << " level " << level;
      if (level == 1) q1 = qmin;
      // Round-off of the quality of similar tetrahedra: 1e-9 relative.
      EXPECT_GE(qmin, q1 * (1 - 1e-9)) << "trial " << trial << " level " << level;
    }
  }
}

TEST(RefineUniform, RejectsNonTetrahedralAndBrokenInput) {
  MeshData tri;
  tri.dimension = 2;
  tri.points = Eigen::Matrix3Xd::Zero(3, 3);
  tri.cells.resize(3, 1);
  tri.cells << 0, 1, 2;
  EXPECT_THROW((void)refine_uniform(tri), UsageError);
  MeshData bad = make_box(1, 1, 1, 1, 1, 1);
  bad.cells(2, 0) = bad.num_points();
  EXPECT_THROW((void)refine_uniform(bad), UsageError);
  MeshData facet = make_box(1, 1, 1, 1, 1, 1);
  facet.facets.resize(3, 1);
  facet.facets << 0, 0, 0;  // edge (0, 0) is no edge of a cell
  EXPECT_THROW((void)refine_uniform(facet), UsageError);
  MeshData tags = make_box(1, 1, 1, 1, 1, 1);
  tags.cell_tags = {1};
  EXPECT_THROW((void)refine_uniform(tags), ParameterError);
}

}  // namespace
}  // namespace incise::mesh
