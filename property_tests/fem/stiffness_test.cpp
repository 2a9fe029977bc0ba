/// fem/stiffness.hpp and the surface-traction load: the element_stiffness() blocks summed over a
/// random mesh equal ElasticProblem's assembled tangent and assemble_stiffness(); the blocks and
/// K⁰ are exactly symmetric; invalid elements give false and a zero block; the consistent
/// traction load totals t·A and has the exact first moment of a constant traction.

#include <incise/core/error.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/fem/stiffness.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/tet_faces.hpp>
#include <incise_test/material_parameters.hpp>
#include <incise_test/param_names.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

namespace {

using incise::EvalStatus;
using incise::Index;
using incise::Vec3;
using incise::VecX;
using incise::fem::ElasticProblem;
using incise::material::Material;
using Mat34 = incise::fem::Mat34T<double>;
using Mat12 = incise::fem::Mat12T<double>;

// Each entry of K is a sum over the few elements that share its two nodes, here added in another
// order (ElasticProblem sums in its sweep order, four lanes at a time) and with the kernel's
// round-off asymmetry averaged: a few ulps of the largest contribution (observed ≤ 1.5e-16 of
// ‖K‖); 1e-14 leaves two digits of margin.
constexpr double kAssemblyTol = 1e-14;

/// A 3×3×2 box (5-split) with its interior and boundary nodes jittered by up to 8% of the cell
/// size, its elements shuffled and one dropped (89 elements: a tail of 1 after blocks of four).
incise::mesh::MeshData random_mesh(std::mt19937_64& rng) {
  incise::mesh::MeshData m =
      incise::mesh::make_box(3, 3, 2, 0.3, 0.3, 0.2, incise::mesh::CubeSplit::kFive);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Index v = 0; v < m.num_points(); ++v)
    m.points.col(v) += 0.008 * Vec3(u(rng), u(rng), u(rng));
  std::vector<Index> perm(static_cast<std::size_t>(m.num_cells()));
  for (std::size_t i = 0; i < perm.size(); ++i) perm[i] = static_cast<Index>(i);
  std::shuffle(perm.begin(), perm.end(), rng);
  const incise::mesh::CellMatrix cells = m.cells;
  m.cells.resize(4, cells.cols() - 1);
  for (Index e = 0; e < m.num_cells(); ++e)
    m.cells.col(e) = cells.col(perm[static_cast<std::size_t>(e)]);
  return m;
}

Mat34 element_columns(const incise::mesh::MeshData& m, const Eigen::Matrix3Xd& x, Index e) {
  Mat34 out;
  for (int a = 0; a < 4; ++a) out.col(a) = x.col(m.cells(a, e));
  return out;
}

/// Σ_τ element_stiffness(τ, u) scattered densely (DOF 3·node + i), in mesh order.
Eigen::MatrixXd summed_blocks(const incise::mesh::MeshData& m, const Material& material,
                              const VecX& u) {
  const Eigen::Index n = 3 * m.num_points();
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(n, n);
  const Eigen::Map<const Eigen::Matrix3Xd> disp(u.data(), 3, m.num_points());
  for (Index e = 0; e < m.num_cells(); ++e) {
    Mat12 ke;
    EXPECT_TRUE(incise::fem::element_stiffness(material, element_columns(m, m.points, e),
                                               element_columns(m, disp, e), ke));
    EXPECT_EQ(ke, ke.transpose()) << "element " << e;
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        k.block<3, 3>(3 * m.cells(a, e), 3 * m.cells(b, e)) += ke.block<3, 3>(3 * a, 3 * b);
  }
  return k;
}

class StiffnessProperty : public ::testing::TestWithParam<std::string> {
 protected:
  Material material() const { return Material(GetParam(), incise::test::fem_test_parameters()); }
};

TEST_P(StiffnessProperty, ElementBlocksSumToTheAssembledMatrix) {
  INCISE_SEEDED_RNG(rng, 1303);
  const incise::mesh::MeshData m = random_mesh(rng);
  ElasticProblem p(m, material());
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  VecX u = VecX::Zero(p.size());
  for (const double amplitude : {0.0, 0.004}) {  // rest and a non-inverting random deformation
    for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = amplitude * unit(rng);
    const Eigen::MatrixXd sum = summed_blocks(m, material(), u);
    ASSERT_EQ(p.assemble_tangent(u, incise::fem::FixedDofTreatment::kKeep), EvalStatus::kOk);
    EXPECT_LE((Eigen::MatrixXd(p.tangent_matrix()) - sum).norm(), kAssemblyTol * sum.norm())
        << "amplitude " << amplitude;
    if (amplitude == 0.0) {
      const Eigen::SparseMatrix<double> k0 = incise::fem::assemble_stiffness(m, material());
      EXPECT_LE((Eigen::MatrixXd(k0) - sum).norm(), kAssemblyTol * sum.norm());
      const Eigen::SparseMatrix<double> k0t = k0.transpose();
      EXPECT_EQ((k0 - k0t).norm(), 0.0);                        // ½(K + Kᵀ): exactly symmetric
      EXPECT_EQ(k0.nonZeros(), p.tangent_matrix().nonZeros());  // the pattern is kept
    }
  }
}

INSTANTIATE_TEST_SUITE_P(AllRegistered, StiffnessProperty,
                         ::testing::ValuesIn(incise::material::registered_material_names()),
                         incise::test::material_param_name);

TEST(ElementStiffness, InvalidElementsGiveFalseAndAZeroBlock) {
  Mat34 x;
  x << 0, 1, 0, 0,  //
      0, 0, 1, 0,   //
      0, 0, 0, 1;
  const Mat34 rest = Mat34::Zero();
  Mat12 k;
  for (const char* model : {"linear", "neohookean"}) {
    const Material m(model, incise::test::fem_test_parameters());
    ASSERT_TRUE(incise::fem::element_stiffness(m, x, rest, k));
    EXPECT_GT(k.norm(), 0.0);
    Mat34 flipped = x;
    flipped.col(0).swap(flipped.col(1));  // negative reference volume
    k.setOnes();
    EXPECT_FALSE(incise::fem::element_stiffness(m, flipped, rest, k));
    EXPECT_EQ(k, Mat12::Zero());
  }
  // Node 4 pushed through the opposite face: det F < 0, undefined for the log-term model.
  Mat34 through = Mat34::Zero();
  through(2, 3) = -2.0;
  const Material neo("neohookean", incise::test::fem_test_parameters());
  k.setOnes();
  EXPECT_FALSE(incise::fem::element_stiffness(neo, x, through, k));
  EXPECT_EQ(k, Mat12::Zero());
}

TEST(SurfaceTraction, TotalForceIsTractionTimesAreaWithTheExactFirstMoment) {
  INCISE_SEEDED_RNG(rng, 1307);
  incise::mesh::MeshData m = random_mesh(rng);
  const incise::mesh::CellMatrix faces = incise::mesh::boundary_faces(m);
  const Vec3 t(3.0, -40.0, 7.5);  // N/m²
  VecX f = VecX::Zero(3 * m.num_points());
  const double area = incise::fem::add_surface_traction(m.points, faces, t, f);
  double area_ref = 0.0;
  Vec3 first_moment = Vec3::Zero();  // ∫ x dA over the triangles
  for (Eigen::Index k = 0; k < faces.cols(); ++k) {
    const Vec3 a = m.points.col(faces(0, k)), b = m.points.col(faces(1, k)),
               c = m.points.col(faces(2, k));
    const double ak = 0.5 * (b - a).cross(c - a).norm();
    area_ref += ak;
    first_moment += ak * (a + b + c) / 3.0;
  }
  Vec3 total = Vec3::Zero();
  Eigen::Matrix3d moment = Eigen::Matrix3d::Zero();  // Σ_v f_v ⊗ x_v = t ⊗ ∫ x dA
  for (Index v = 0; v < m.num_points(); ++v) {
    total += f.segment<3>(3 * v);
    moment += f.segment<3>(3 * v) * m.points.col(v).transpose();
  }
  // Sums of ~150 triangle terms of O(1): round-off only.
  constexpr double kSumTol = 1e-12;
  EXPECT_NEAR(area, area_ref, kSumTol * area_ref);
  EXPECT_LE((total - t * area).norm(), kSumTol * t.norm() * area);
  EXPECT_LE((moment - t * first_moment.transpose()).norm(),
            kSumTol * t.norm() * first_moment.norm());
  // The box's surface is 2(0.3·0.3 + 2·0.3·0.2) m² before jitter; the jitter changes it < 10%.
  EXPECT_NEAR(area, 0.42, 0.042);
}

TEST(SurfaceTraction, TractionOnAPlaneLoadsTheBoundaryFacesInIt) {
  const incise::mesh::MeshData m = incise::mesh::make_box(4, 2, 3, 0.8, 0.2, 0.3);
  ElasticProblem p(m, Material("linear", incise::test::fem_test_parameters()));
  const Vec3 t(0.0, 0.0, -250.0);
  const double area = p.add_traction_on_plane(2, 0.3, t);
  constexpr double kSumTol = 1e-12;  // a few dozen additions of O(1) numbers
  EXPECT_NEAR(area, 0.8 * 0.2, kSumTol);
  Vec3 total = Vec3::Zero();
  for (Index v = 0; v < p.num_nodes(); ++v) {
    total += p.external_force().segment<3>(3 * v);
    if (m.points(2, v) != 0.3) {
      EXPECT_EQ(p.external_force().segment<3>(3 * v), Vec3::Zero());
    }
  }
  EXPECT_LE((total - t * area).norm(), kSumTol * t.norm() * area);
  EXPECT_EQ(p.add_traction_on_plane(2, 0.15, t), 0.0);  // an interior plane has no boundary face
}

TEST(SurfaceTraction, RejectsBadInput) {
  const incise::mesh::MeshData m = incise::mesh::make_box(1, 1, 1, 1.0, 1.0, 1.0);
  const incise::mesh::CellMatrix faces = incise::mesh::boundary_faces(m);
  VecX f = VecX::Zero(3 * m.num_points());
  VecX short_f = VecX::Zero(3);
  EXPECT_THROW(incise::fem::add_surface_traction(m.points, faces, Vec3::UnitX(), short_f),
               incise::UsageError);
  EXPECT_THROW(incise::fem::add_surface_traction(
                   m.points, faces, Vec3(std::numeric_limits<double>::quiet_NaN(), 0, 0), f),
               incise::UsageError);
  incise::mesh::CellMatrix bad = faces;
  bad(1, 0) = m.num_points();
  EXPECT_THROW(incise::fem::add_surface_traction(m.points, bad, Vec3::UnitX(), f),
               incise::UsageError);
  EXPECT_THROW(incise::fem::add_surface_traction(m.points, m.cells, Vec3::UnitX(), f),
               incise::UsageError);
}

}  // namespace
