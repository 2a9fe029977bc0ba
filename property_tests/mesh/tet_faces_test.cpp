/// The one tetrahedron face table (mesh::kTetFace) and boundary_faces(): face j is opposite
/// vertex j and outward for positively oriented tetrahedra; a mesh's boundary triangles form a
/// closed, outward surface; interior and non-manifold faces are not boundary faces.

#include <gtest/gtest.h>
#include <incise/core/error.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/tet_faces.hpp>
#include <incise_test/seed.hpp>

#include <algorithm>
#include <random>

namespace incise::mesh {
namespace {

Vec3 area_vector(const Eigen::Matrix3Xd& x, Index a, Index b, Index c) {
  return 0.5 * (x.col(b) - x.col(a)).cross(x.col(c) - x.col(a));
}

TEST(TetFace, FaceJIsOppositeVertexJAndOutwardForPositiveTets) {
  INCISE_SEEDED_RNG(rng, 1301);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 1000; ++trial) {
    Eigen::Matrix3Xd x = Eigen::Matrix3Xd::NullaryExpr(3, 4, [&]() { return u(rng); });
    const double v6 = (x.col(1) - x.col(0)).dot((x.col(2) - x.col(0)).cross(x.col(3) - x.col(0)));
    if (std::abs(v6) < 1e-3) continue;    // nearly flat: the sign test below needs a margin
    if (v6 < 0) x.col(0).swap(x.col(1));  // positively oriented
    for (int j = 0; j < 4; ++j) {
      const int* f = kTetFace[j];
      EXPECT_TRUE(f[0] != j && f[1] != j && f[2] != j) << "face " << j;
      EXPECT_TRUE(f[0] != f[1] && f[1] != f[2] && f[0] != f[2]) << "face " << j;
      // Outward: the opposite vertex lies behind the face.
      EXPECT_LT(area_vector(x, f[0], f[1], f[2]).dot(x.col(j) - x.col(f[0])), 0.0)
          << "face " << j << ", trial " << trial;
    }
  }
}

void expect_closed_outward_box_surface(const MeshData& m, double lx, double ly, double lz) {
  const CellMatrix f = boundary_faces(m);
  ASSERT_EQ(f.rows(), 3);
  const Vec3 center(lx / 2, ly / 2, lz / 2);
  double area = 0, volume = 0;
  Vec3 flux = Vec3::Zero();  // Σ outward area vectors of a closed surface = 0
  for (Eigen::Index k = 0; k < f.cols(); ++k) {
    const Vec3 n = area_vector(m.points, f(0, k), f(1, k), f(2, k));
    const Vec3 c = (m.points.col(f(0, k)) + m.points.col(f(1, k)) + m.points.col(f(2, k))) / 3.0;
    EXPECT_GT(n.dot(c - center), 0.0) << "face " << k << " points inward";
    area += n.norm();
    flux += n;
    volume += c.dot(n) / 3.0;  // divergence theorem, ∮ x·n dA / 3 = V (exact for flat faces)
  }
  // Round-off only: sums of ~100 products of O(1) numbers.
  constexpr double kSumTol = 1e-12;
  EXPECT_NEAR(area, 2 * (lx * ly + ly * lz + lx * lz), kSumTol);
  EXPECT_LT(flux.norm(), kSumTol);
  EXPECT_NEAR(volume, lx * ly * lz, kSumTol);
}

// Moved from property_tests/scene (SceneBuilder.BoundaryFacesCoverTheBoxSurface) with the
// function, and extended by the orientation checks.
TEST(BoundaryFaces, CoverTheBoxSurfaceOutward) {
  for (auto split : {CubeSplit::kSix, CubeSplit::kFive}) {
    const MeshData m = make_box(6, 2, 3, 1.2, 0.2, 0.3, split);
    // Every side square of the box is split into two triangles.
    EXPECT_EQ(boundary_faces(m).cols(), 2 * 2 * (6 * 2 + 2 * 3 + 6 * 3));
    expect_closed_outward_box_surface(m, 1.2, 0.2, 0.3);
  }
}

TEST(BoundaryFaces, OneTetIsItsFourFacesInTetFaceOrder) {
  MeshData m;
  m.points = Eigen::Matrix3Xd::Zero(3, 4);
  m.points.col(1) = Vec3::UnitX();
  m.points.col(2) = Vec3::UnitY();
  m.points.col(3) = Vec3::UnitZ();
  m.cells = CellMatrix(4, 1);
  m.cells << 0, 1, 2, 3;
  CellMatrix expected(3, 4);  // columns ordered by sorted vertex triple: faces 3, 2, 1, 0
  expected << 0, 0, 0, 1,     //
      2, 1, 3, 2,             //
      1, 3, 2, 3;
  EXPECT_EQ(boundary_faces(m), expected);
}

TEST(BoundaryFaces, InteriorAndNonManifoldFacesAreNotBoundary) {
  MeshData m;
  m.points = Eigen::Matrix3Xd::Zero(3, 6);
  m.points.col(1) = Vec3::UnitX();
  m.points.col(2) = Vec3::UnitY();
  m.points.col(3) = Vec3(0.2, 0.2, 1);
  m.points.col(4) = Vec3(0.2, 0.2, -1);
  m.points.col(5) = Vec3(1, 1, 0.5);
  m.cells = CellMatrix(4, 2);
  m.cells << 0, 0, 1, 2, 2, 1, 3, 4;  // (0,1,2,3) and (0,2,1,4) share face {0,1,2}
  EXPECT_EQ(boundary_faces(m).cols(), 6);
  m.cells.conservativeResize(4, 3);
  m.cells.col(2) << 1, 2, 0, 5;  // a third tetrahedron on {0,1,2}: non-manifold
  const CellMatrix f = boundary_faces(m);
  EXPECT_EQ(f.cols(), 9);
  for (Eigen::Index k = 0; k < f.cols(); ++k) {
    std::array<Index, 3> key{f(0, k), f(1, k), f(2, k)};
    std::sort(key.begin(), key.end());
    EXPECT_NE(key, (std::array<Index, 3>{0, 1, 2}));
  }
}

TEST(FacetCoverage, CountsListedBoundaryInteriorAndUnlistedFaces) {
  // Two tets sharing face {1, 2, 3}: 6 boundary faces, one interior face.
  CellMatrix tets(4, 2);
  tets << 0, 4, 1, 1, 2, 3, 3, 2;
  const CellMatrix boundary = boundary_faces(tets);
  ASSERT_EQ(boundary.cols(), 6);
  // Listed: two boundary faces (one twice, reversed), the interior face; four boundary faces
  // are not listed.
  CellMatrix listed(3, 4);
  listed.col(0) = boundary.col(0);
  listed.col(1) = boundary.col(0).reverse();
  listed.col(2) = boundary.col(3);
  listed.col(3) << 3, 1, 2;
  const FacetCoverage c = facet_coverage(tets, listed);
  EXPECT_EQ(c.distinct, 3u);
  EXPECT_EQ(c.on_boundary, 2u);
  EXPECT_EQ(c.interior, 1u);
  EXPECT_EQ(c.boundary_not_listed, 4u);
  const FacetCoverage all = facet_coverage(tets, boundary);
  EXPECT_EQ(all.on_boundary, 6u);
  EXPECT_EQ(all.boundary_not_listed, 0u);
  EXPECT_THROW((void)facet_coverage(tets, CellMatrix(4, 1)), UsageError);
}

TEST(BoundaryFaces, RejectsNonTetrahedralInput) {
  MeshData tri;
  tri.dimension = 2;
  tri.points = Eigen::Matrix3Xd::Zero(3, 3);
  tri.cells = CellMatrix(3, 1);
  tri.cells << 0, 1, 2;
  EXPECT_THROW(boundary_faces(tri), UsageError);
  EXPECT_THROW(boundary_faces(tri.cells), UsageError);
}

}  // namespace
}  // namespace incise::mesh
