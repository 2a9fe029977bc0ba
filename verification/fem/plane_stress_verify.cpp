/// Verification of the plane-stress triangles (thesis §6.3) by solutions they reproduce exactly
/// and against thin slabs of tetrahedra:
/// - patch test: a linear displacement field prescribed on the boundary of a rectangle with
///   displaced interior nodes is reproduced in the interior (linear model, direct solve), and
///   for every registered material an affine field is an exact equilibrium;
/// - uniaxial dead-load tension of a strip: linear model u = (t x/E, −ν t y/E) and thickness
///   strain −ν t/E; neo-Hookean with ν = 0 (thesis (6.4)) stretch λ₁ with μ(λ₁ − 1/λ₁) = t,
///   λ₂ = q = 1, solved by Newton with the assembled tangent;
/// - the same strip as one layer of tetrahedra: identical in-plane and thickness strains;
/// - a slab clamped at x = 0 and sheared at x = L, tets vs triangles as the thickness shrinks.

#include <incise/core/error.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/fem/plane_stress_problem.hpp>
#include <incise/mesh/generators.hpp>

#include <gtest/gtest.h>

#include <Eigen/SparseCholesky>
#include <cmath>
#include <cstdio>
#include <random>

namespace {

using incise::EvalStatus;
using incise::Index;
using incise::Vec2;
using incise::VecX;
using incise::fem::PlaneStressProblem;
using incise::material::Material;

incise::material::Parameters parameters(double nu) {
  incise::material::Parameters p;
  p.youngs_modulus = 3.4e4;  // the thesis' slab, §6.8
  p.poisson_ratio = nu;
  p.gamma = 0.4;
  return p;
}

std::vector<Index> nodes_at(const incise::mesh::MeshData& m, int axis, double v) {
  std::vector<Index> out;
  for (Index i = 0; i < m.num_points(); ++i)
    if (std::abs(m.points(axis, i) - v) < 1e-12) out.push_back(i);
  return out;
}

/// One Newton step K Δ = −P g with the identity-treated tangent (P: projection), repeated until
/// the projected gradient is below tol·‖f_ext‖ (or `steps` steps). Returns the final norm ratio.
template <class P>
double newton(P& problem, VecX& u, int steps, double tol) {
  VecX g;
  double ratio = 0;
  for (int s = 0; s < steps; ++s) {
    EXPECT_EQ(problem.gradient(u, g), EvalStatus::kOk);
    problem.project(g);
    ratio = g.norm() / std::max(problem.external_force_norm(), 1e-300);
    if (ratio < tol) break;
    Eigen::SparseMatrix<double> k;
    EXPECT_EQ(problem.tangent(u, k), EvalStatus::kOk);
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(k);
    EXPECT_EQ(ldlt.info(), Eigen::Success);
    u -= ldlt.solve(g);
  }
  return ratio;
}

TEST(PlaneStressPatch, LinearFieldReproducedAndAffineIsEquilibrium) {
  incise::mesh::MeshData mesh =
      incise::mesh::make_rectangle(5, 4, 0.1, 0.08, incise::mesh::GridDiagonal::kAlternating);
  std::mt19937_64 rng(1601);
  std::uniform_real_distribution<double> jitter(-0.004, 0.004);  // < h/4: triangles stay valid
  std::vector<char> boundary(static_cast<std::size_t>(mesh.num_points()), 0);
  for (Index i = 0; i < mesh.num_points(); ++i) {
    const double x = mesh.points(0, i), y = mesh.points(1, i);
    boundary[static_cast<std::size_t>(i)] = std::abs(x) < 1e-12 || std::abs(x - 0.1) < 1e-12 ||
                                            std::abs(y) < 1e-12 || std::abs(y - 0.08) < 1e-12;
    if (!boundary[static_cast<std::size_t>(i)]) {
      mesh.points(0, i) += jitter(rng);
      mesh.points(1, i) += jitter(rng);
    }
  }
  Eigen::Matrix2d a;
  a << 1e-3, -4e-4, 6e-4, 2e-3;
  const Vec2 c(1e-4, -2e-4);
  VecX exact(2 * mesh.num_points());
  for (Index i = 0; i < mesh.num_points(); ++i)
    exact.segment<2>(2 * i) = a * mesh.points.col(i).head<2>() + c;
  for (const auto& name : incise::material::registered_material_names()) {
    PlaneStressProblem p(mesh, Material(name, parameters(0.3)), 0.01);
    std::vector<Index> fixed;
    for (Index i = 0; i < mesh.num_points(); ++i)
      if (boundary[static_cast<std::size_t>(i)]) fixed.push_back(i);
    p.fix_nodes(fixed);
    VecX g;
    ASSERT_EQ(p.gradient(exact, g), EvalStatus::kOk);
    p.project(g);
    // Interior residual of an affine field: round-off of the nodal forces, which are
    // ~ μ‖G‖·h·d (h = 0.02 m, d = 0.01 m); 1e-10 of that leaves five digits over ε.
    const double force_scale = Material(name, parameters(0.3)).lame().mu * a.norm() * 0.02 * 0.01;
    EXPECT_LE(g.norm(), 1e-10 * force_scale) << name;
    if (name != "linear") continue;
    VecX u = VecX::Zero(p.size());
    for (Index i : fixed) u.segment<2>(2 * i) = exact.segment<2>(2 * i);
    newton(p, u, 1, 0.0);
    // One direct solve of a linear problem: error κ(K)·ε relative (κ ~ 1e3 here).
    EXPECT_LE((u - exact).lpNorm<Eigen::Infinity>(), 1e-11 * exact.lpNorm<Eigen::Infinity>());
  }
}

constexpr double kL = 0.1, kW = 0.02, kD = 0.01;

/// Strip [0, L]×[0, W], u_x = 0 at x = 0, u_y = 0 at the origin, traction (t, 0) at x = L.
PlaneStressProblem strip(const Material& m, double t, incise::mesh::MeshData& mesh) {
  mesh = incise::mesh::make_rectangle(10, 2, kL, kW, incise::mesh::GridDiagonal::kAlternating);
  PlaneStressProblem p(mesh, m, kD);
  for (Index i : nodes_at(mesh, 0, 0.0)) p.fix_dof(2 * i);
  p.fix_dof(1);
  EXPECT_NEAR(p.add_traction_on_line(0, kL, Vec2(t, 0.0)), kW, 1e-15);
  return p;
}

TEST(PlaneStressStrip, LinearUniaxialMatchesAnalytic) {
  const Material m("linear", parameters(0.34));
  const double t = 340.0;  // Pa: strain 1e-2
  incise::mesh::MeshData mesh;
  PlaneStressProblem p = strip(m, t, mesh);
  VecX u = VecX::Zero(p.size());
  newton(p, u, 1, 0.0);
  const double ex = t / 3.4e4, ey = -0.34 * t / 3.4e4;
  double err = 0;
  for (Index i = 0; i < mesh.num_points(); ++i) {
    err = std::max(err, std::abs(u(2 * i) - ex * mesh.points(0, i)));
    err = std::max(err, std::abs(u(2 * i + 1) - ey * mesh.points(1, i)));
  }
  // Homogeneous state, reproduced exactly by linear triangles: direct-solve round-off only
  // (κ(K) ~ 1e3), two-sided by construction (|u − u_exact|).
  EXPECT_LE(err, 1e-12 * ex * kL);
  std::printf("plane-stress strip, linear: max |u - u_exact| = %.3g m (u_tip = %.6g m)\n", err,
              ex * kL);
}

TEST(PlaneStressStrip, NeoHookeanNuZeroUniaxialMatchesAnalytic) {
  const Material m("neohookean", parameters(0.0));
  const double mu = m.lame().mu, t = 0.5 * mu;  // finite strain: λ₁ ≈ 1.28
  incise::mesh::MeshData mesh;
  PlaneStressProblem p = strip(m, t, mesh);
  VecX u = VecX::Zero(p.size());
  const double ratio = newton(p, u, 30, 1e-13);
  EXPECT_LT(ratio, 1e-13);
  // P₁₁ = λ₁ S₁₁ = μ(λ₁ − 1/λ₁) = t  ⇒  λ₁ = (t/μ + √((t/μ)² + 4))/2; λ₂ = 1 (S₂₂ = 0).
  const double l1 = 0.5 * (t / mu + std::sqrt(t * t / (mu * mu) + 4.0));
  double err = 0;
  for (Index i = 0; i < mesh.num_points(); ++i) {
    err = std::max(err, std::abs(u(2 * i) - (l1 - 1.0) * mesh.points(0, i)));
    err = std::max(err, std::abs(u(2 * i + 1)));
  }
  // Newton converged to 1e-13 of ‖f_ext‖ on a κ ~ 1e3 system: 1e-9 relative is 3 digits
  // above that and two-sided (|u − u_exact|).
  EXPECT_LE(err, 1e-9 * (l1 - 1.0) * kL);
  std::printf("plane-stress strip, neo-Hookean nu=0: lambda1 = %.12f, max |u - u_exact| = %.3g m\n",
              l1, err);
}

TEST(PlaneStressStrip, OneLayerOfTetsHasTheSameStrains) {
  // The strip as tetrahedra (one layer, thickness d) with the same traction: free to contract
  // in y and z, its homogeneous state is the plane-stress one: ε_xx = t/E, ε_yy = ε_zz = −νt/E,
  // and the 2D E₃₃ (from e₃·S·e₃ = 0) equals that ε_zz.
  const double nu = 0.34, t = 340.0;
  const Material m("linear", parameters(nu));
  incise::mesh::MeshData mesh3 = incise::mesh::make_box(10, 2, 1, kL, kW, kD);
  incise::fem::ElasticProblem p3(mesh3, m);
  for (Index i : incise::fem::nodes_on_plane(mesh3, 0, 0.0)) p3.fix_dof(3 * i);
  p3.fix_dof(1);
  p3.fix_dof(2);
  for (Index i = 0; i < mesh3.num_points(); ++i)
    if (std::abs(mesh3.points(0, i)) < 1e-12 && std::abs(mesh3.points(1, i)) < 1e-12)
      p3.fix_dof(3 * i + 1);  // the x = 0, y = 0 edge: no rigid rotation about x
  p3.add_traction_on_plane(0, kL, incise::Vec3(t, 0, 0));
  VecX u3 = VecX::Zero(p3.size());
  newton(p3, u3, 1, 0.0);
  double err3 = 0;
  const double ex = t / 3.4e4, et = -nu * t / 3.4e4;
  for (Index i = 0; i < mesh3.num_points(); ++i) {
    err3 = std::max(err3, std::abs(u3(3 * i) - ex * mesh3.points(0, i)));
    err3 = std::max(err3, std::abs(u3(3 * i + 1) - et * mesh3.points(1, i)));
    err3 = std::max(err3, std::abs(u3(3 * i + 2) - et * mesh3.points(2, i)));
  }
  // Direct-solve round-off on a homogeneous state (κ ~ 1e4).
  EXPECT_LE(err3, 1e-11 * ex * kL);
  incise::material::PlaneStressState<double> st;
  Eigen::Matrix2d e2;
  e2 << ex, 0, 0, et;
  ASSERT_EQ(
      incise::material::PlaneStress<incise::material::LinearElastic>::solve(m.lame(), e2, 0.0, st),
      incise::material::PlaneStressStatus::kOk);
  // −λ/(λ + 2μ)(1 − ν) = −ν: a few roundings.
  EXPECT_NEAR(st.strain.e(2, 2), et, 1e-15 * std::abs(et));
}

/// Mean tip displacement u_x at x = L of a slab [0, L]×[0, W] clamped at x = 0 and pulled by
/// a traction (t, 0) at x = L (the clamp holds the lateral contraction: a boundary layer), with
/// plane-stress triangles on an nx × ny grid and with one layer of tets of thickness d on the
/// same grid. Returns the relative difference tets vs triangles.
double slab_gap(int nx, int ny, double d, bool print) {
  const Material m("linear", parameters(0.34));
  const double w = 0.02, t = 34.0;
  auto mesh2 =
      incise::mesh::make_rectangle(nx, ny, kL, w, incise::mesh::GridDiagonal::kAlternating);
  PlaneStressProblem p2(mesh2, m, d);
  p2.fix_nodes(nodes_at(mesh2, 0, 0.0));
  p2.add_traction_on_line(0, kL, Vec2(t, 0.0));
  VecX u2 = VecX::Zero(p2.size());
  newton(p2, u2, 1, 0.0);
  double tip2 = 0;
  const auto tip_nodes2 = nodes_at(mesh2, 0, kL);
  for (Index i : tip_nodes2) tip2 += u2(2 * i) / static_cast<double>(tip_nodes2.size());
  auto mesh3 = incise::mesh::make_box(nx, ny, 1, kL, w, d);
  incise::fem::ElasticProblem p3(mesh3, m);
  p3.fix_nodes(incise::fem::nodes_on_plane(mesh3, 0, 0.0));
  p3.add_traction_on_plane(0, kL, incise::Vec3(t, 0, 0));
  VecX u3 = VecX::Zero(p3.size());
  newton(p3, u3, 1, 0.0);
  double tip3 = 0;
  const auto tip_nodes3 = incise::fem::nodes_on_plane(mesh3, 0, kL);
  for (Index i : tip_nodes3) tip3 += u3(3 * i) / static_cast<double>(tip_nodes3.size());
  const double gap = std::abs(tip3 - tip2) / std::abs(tip2);
  if (print)
    std::printf("slab %dx%d, d = %.6f m: tip u_x tets %.6e, triangles %.6e, relative gap %.3e\n",
                nx, ny, d, tip3, tip2, gap);
  return gap;
}

TEST(PlaneStressSlab, ThinTetSlabApproachesPlaneStress) {
  const double w = 0.02;
  std::vector<double> coarse;
  for (const double d : {w, w / 4, w / 16, w / 64}) coarse.push_back(slab_gap(20, 4, d, true));
  const double fine = slab_gap(40, 8, w / 64, true);
  // Asserted (observed values in docs/materials.md): as d → 0 the gap settles (the last two
  // thicknesses within 10% of each other: the boundary layer of the 3D clamp has shrunk away),
  // what is left is the difference of two discretizations of one grid, so it shrinks under
  // in-plane refinement; every gap is below 2% (observed ≤ 1.1%).
  EXPECT_LE(std::abs(coarse[3] - coarse[2]), 0.1 * coarse[3]);
  EXPECT_LT(fine, coarse[3]);
  for (const double g : coarse) EXPECT_LT(g, 0.02);
}

}  // namespace
