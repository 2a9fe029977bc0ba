/// Property tests of PlaneStressProblem (plane_stress_problem.hpp, thesis §6.3): the global
/// energy → gradient → Hessian-product chain for every material, the assembled tangent and its
/// diagonal against the matrix-free product, the existing solvers (linear CG, nonlinear CG) on
/// it, failure reporting, and bad input.

#include <incise/core/error.hpp>
#include <incise/fem/plane_stress_problem.hpp>
#include <incise/fixtures/deformations.hpp>
#include <incise/fixtures/derivative_check.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>
#include <incise_test/fd_check.hpp>
#include <incise_test/param_names.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cmath>

namespace {

using incise::EvalStatus;
using incise::Index;
using incise::Vec2;
using incise::VecX;
using incise::fem::PlaneStressProblem;
using incise::material::Material;

incise::material::Parameters parameters() {
  incise::material::Parameters p;
  p.youngs_modulus = 3.4e4;
  p.poisson_ratio = 0.34;
  p.gamma = 0.4;
  return p;
}

incise::mesh::MeshData slab() {
  return incise::mesh::make_rectangle(4, 4, 0.1, 0.1, incise::mesh::GridDiagonal::kAlternating);
}

std::vector<Index> left_nodes(const incise::mesh::MeshData& m) {
  std::vector<Index> out;
  for (Index i = 0; i < m.num_points(); ++i)
    if (m.points(0, i) < 1e-12) out.push_back(i);
  return out;
}

class PlaneStressProblemProperty : public ::testing::TestWithParam<std::string> {};

TEST_P(PlaneStressProblemProperty, EnergyGradientHessianChain) {
  INCISE_SEEDED_RNG(rng, 1611);
  const auto mesh = slab();
  PlaneStressProblem p(mesh, Material(GetParam(), parameters()), 0.01);
  p.fix_nodes(left_nodes(mesh));
  p.add_traction_on_line(0, 0.1, Vec2(100.0, -50.0));
  const VecX u = incise::fixtures::random_vector(rng, p.size(), 2e-3);  // strains ~ 8%
  const VecX d = incise::fixtures::random_vector(rng, p.size(), 1e-3);
  VecX g, kd;
  double e0 = 0;
  ASSERT_EQ(p.gradient(u, g, &e0), EvalStatus::kOk);
  ASSERT_EQ(p.hessian_product(u, d, kd), EvalStatus::kOk);
  auto energy = [&](double t) {
    double e = 0;
    EXPECT_EQ(p.energy(u + t * d, e), EvalStatus::kOk);
    return e;
  };
  const double unit = g.norm() * d.norm();
  auto r = incise::fixtures::check_directional_derivative(energy, g.dot(d), 1.0, unit);
  EXPECT_LE(r.best_relative_error, incise::test::kFdTolerance) << r.report;
  EXPECT_GE(r.taylor_order, incise::test::kMinTaylorOrder) << r.report;
  auto grad = [&](double t) {
    VecX gt;
    EXPECT_EQ(p.gradient(u + t * d, gt), EvalStatus::kOk);
    return VecX(gt);
  };
  std::string report;
  const double order = incise::fixtures::vector_taylor_order(grad, kd, 1.0, g.norm(), &report);
  EXPECT_GE(order, incise::test::kMinTaylorOrder) << report;
  // Assembled tangent (fixed rows/columns → identity) and diagonal vs the matrix-free product
  // on free DOFs: the same element arithmetic summed in another order (1e-12 relative).
  Eigen::SparseMatrix<double> k;
  ASSERT_EQ(p.tangent(u, k), EvalStatus::kOk);
  VecX dp = d;
  p.project(dp);
  VecX kdp;
  ASSERT_EQ(p.hessian_product(u, dp, kdp), EvalStatus::kOk);
  p.project(kdp);
  EXPECT_LE((k * dp - kdp).norm(), 1e-12 * kdp.norm());
  VecX diag;
  ASSERT_TRUE(p.hessian_diagonal(u, diag));
  for (Eigen::Index i = 0; i < p.size(); ++i)
    EXPECT_NEAR(diag(i), k.coeff(i, i), 1e-12 * std::abs(k.coeff(i, i))) << i;
  EXPECT_GT(p.flops(), 0u);
  EXPECT_TRUE(p.last_outcome().ok()) << p.last_outcome().brief();
}

INSTANTIATE_TEST_SUITE_P(AllRegistered, PlaneStressProblemProperty,
                         ::testing::ValuesIn(incise::material::registered_material_names()),
                         incise::test::material_param_name);

TEST(PlaneStressProblem, SolversRunOnIt) {
  const auto mesh = slab();
  PlaneStressProblem p(mesh, Material("linear", parameters()), 0.01);
  p.fix_nodes(left_nodes(mesh));
  p.add_traction_on_line(0, 0.1, Vec2(0.0, -340.0));
  // Reference: one direct solve.
  VecX ref = VecX::Zero(p.size()), g;
  Eigen::SparseMatrix<double> k;
  ASSERT_EQ(p.tangent(ref, k), EvalStatus::kOk);
  ASSERT_EQ(p.gradient(ref, g), EvalStatus::kOk);
  p.project(g);
  ref = -Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>>(k).solve(g);
  incise::solver::LinearCgOptions lo;
  lo.stop.epsilon = 1e-12;
  VecX u = VecX::Zero(p.size());
  const auto rep = incise::solver::linear_cg(p, u, lo);
  EXPECT_TRUE(rep.ok()) << rep.brief();
  // Residual 1e-12 relative on a system with κ ~ 1e3: 1e-8 relative in u leaves margin.
  EXPECT_LE((u - ref).norm(), 1e-8 * ref.norm());
  incise::solver::NonlinearCgOptions no;
  no.stop.epsilon = 1e-10;
  VecX v = VecX::Zero(p.size());
  const auto rep2 = incise::solver::nonlinear_cg(p, v, no);
  EXPECT_TRUE(rep2.ok()) << rep2.brief();
  // Residual 1e-10 relative, κ ~ 1e3: 1e-6 relative in u.
  EXPECT_LE((v - ref).norm(), 1e-6 * ref.norm());
}

TEST(PlaneStressProblem, InvertedElementIsReported) {
  const auto mesh = slab();
  PlaneStressProblem p(mesh, Material("neohookean", parameters()), 0.01);
  VecX u = VecX::Zero(p.size());
  // Collapse the whole slab onto the line x = 0 and beyond: every element inverts.
  for (Index i = 0; i < mesh.num_points(); ++i) u(2 * i) = -2.0 * mesh.points(0, i);
  double e = 0;
  EXPECT_EQ(p.energy(u, e), EvalStatus::kInverted);
  EXPECT_TRUE(std::isinf(e));
  EXPECT_FALSE(p.last_outcome().ok());
  EXPECT_EQ(p.last_outcome().status, incise::material::PlaneStressStatus::kInverted);
  EXPECT_GE(p.last_outcome().element, 0);
}

TEST(PlaneStressProblem, NoPlaneStressStateIsReportedAsNonFinite) {
  // Veronda-Westmann with λ = 0 stretched 3× has its S₃₃ root at q² < 0 (plane_stress.hpp).
  auto prm = parameters();
  prm.poisson_ratio = 0.0;
  const auto mesh = slab();
  PlaneStressProblem p(mesh, Material("veronda-westmann", prm), 0.01);
  VecX u = VecX::Zero(p.size());
  for (Index i = 0; i < mesh.num_points(); ++i) u(2 * i) = 2.0 * mesh.points(0, i);
  VecX g;
  EXPECT_EQ(p.gradient(u, g), EvalStatus::kNonFinite);
  EXPECT_EQ(p.last_outcome().status, incise::material::PlaneStressStatus::kNotConverged);
  EXPECT_NE(p.last_outcome().brief().find("did not converge"), std::string::npos);
}

TEST(PlaneStressProblem, BadInputThrows) {
  const Material m("linear", parameters());
  auto mesh = slab();
  EXPECT_THROW(PlaneStressProblem(mesh, m, 0.0), incise::ParameterError);
  EXPECT_THROW(PlaneStressProblem(mesh, m, std::nan("")), incise::ParameterError);
  auto tets = incise::mesh::make_box(1, 1, 1, 1, 1, 1);
  EXPECT_THROW(PlaneStressProblem(tets, m, 0.01), incise::ParameterError);
  auto flipped = mesh;
  std::swap(flipped.cells(0, 0), flipped.cells(1, 0));
  EXPECT_THROW(PlaneStressProblem(flipped, m, 0.01), incise::ParameterError);
  PlaneStressProblem p(mesh, m, 0.01);
  EXPECT_THROW(p.fix_nodes({-1}), incise::UsageError);
  EXPECT_THROW(p.fix_dof(p.size()), incise::UsageError);
  EXPECT_THROW(p.add_traction_on_line(2, 0.0, Vec2(1, 0)), incise::UsageError);
  EXPECT_THROW(p.add_traction_on_line(0, 0.1, Vec2(std::nan(""), 0)), incise::UsageError);
}

TEST(PlaneStressProblem, TractionIsTimesThickness) {
  // t̃ = t·d: the loads on the edge x = 0.1 sum to t·W·d.
  const auto mesh = slab();
  PlaneStressProblem p(mesh, Material("linear", parameters()), 0.02);
  EXPECT_NEAR(p.add_traction_on_line(0, 0.1, Vec2(30.0, -10.0)), 0.1, 1e-15);
  double fx = 0, fy = 0;
  for (Index i = 0; i < p.num_nodes(); ++i) {
    fx += p.external_force()(2 * i);
    fy += p.external_force()(2 * i + 1);
  }
  EXPECT_NEAR(fx, 30.0 * 0.1 * 0.02, 1e-15);
  EXPECT_NEAR(fy, -10.0 * 0.1 * 0.02, 1e-15);
}

}  // namespace

// The gradient memo (plane_stress_problem.hpp): for the linear model a gradient at a u that
// differs from the last swept one at a few nodes is g + K·Δu (rounding of order ε‖K‖‖Δu‖:
// 1e-12 relative to ‖g‖ leaves three digits of margin), a second update is never chained onto
// the first (that call sweeps: bitwise equal to a fresh problem), and a bitwise-equal u
// returns the stored result; nonlinear models always sweep.
TEST(PlaneStressProblem, GradientReuseMatchesASweep) {
  INCISE_SEEDED_RNG(rng, 2207);
  const auto mesh = slab();
  for (const std::string model : {"linear", "neohookean"}) {
    SCOPED_TRACE(model);
    const Material mat(model, parameters());
    PlaneStressProblem p(mesh, mat, 0.01);
    p.fix_nodes(left_nodes(mesh));
    p.add_traction_on_line(0, 0.1, Vec2(100.0, -50.0));
    const auto fresh = [&](const VecX& u, VecX& g, double& e) {
      PlaneStressProblem q(mesh, mat, 0.01);
      q.fix_nodes(left_nodes(mesh));
      q.add_traction_on_line(0, 0.1, Vec2(100.0, -50.0));
      ASSERT_EQ(q.gradient(u, g, &e), EvalStatus::kOk);
    };
    VecX u = incise::fixtures::random_vector(rng, p.size(), 1e-3);
    VecX g, gf;
    double e = 0, ef = 0;
    ASSERT_EQ(p.gradient(u, g, &e), EvalStatus::kOk);
    // A few nodes move (as the needle moves its nodes).
    for (const Index v : {3, 7, 12}) u.segment<2>(2 * v) += Vec2(2e-4, -1e-4);
    ASSERT_EQ(p.gradient(u, g, &e), EvalStatus::kOk);
    fresh(u, gf, ef);
    EXPECT_LE((g - gf).norm(), 1e-12 * gf.norm());
    EXPECT_NEAR(e, ef, 1e-12 * (std::abs(ef) + g.norm() * u.norm()));
    if (model != "linear") {
      EXPECT_EQ(g, gf);  // swept
    }
    // Bitwise-equal u: the stored result.
    VecX g2;
    double e2 = 0;
    ASSERT_EQ(p.gradient(u, g2, &e2), EvalStatus::kOk);
    EXPECT_EQ(g2, g);
    EXPECT_EQ(e2, e);
    // A second change: not chained onto the update, swept, bitwise equal to a fresh problem.
    u.segment<2>(2 * 5) += Vec2(-1e-4, 3e-4);
    ASSERT_EQ(p.gradient(u, g, &e), EvalStatus::kOk);
    fresh(u, gf, ef);
    EXPECT_EQ(g, gf);
    EXPECT_EQ(e, ef);
    // A load added afterwards clears the memo.
    p.add_point_load(9, Vec2(1.0, 2.0));
    ASSERT_EQ(p.gradient(u, g2, &e2), EvalStatus::kOk);
    EXPECT_LE((g2.segment<2>(18) - (g.segment<2>(18) - Vec2(1.0, 2.0))).norm(), 1e-12);
  }
}
