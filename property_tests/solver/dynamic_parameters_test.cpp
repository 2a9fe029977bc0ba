/// \file dynamic_parameters_test.cpp
/// Automatic Δt and η (§4.1) from one Lanczos run (solver::estimate_dynamic_parameters) on
/// elastic bodies: its cost against the solve it serves, and SS22 restarts after unstable steps
/// (DynamicRelaxationOptions::max_restarts, §4.4.1) on a stiffening Veronda–Westmann cube whose
/// automatic Δt inverts elements.
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/energy_error.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/truncated_newton.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

namespace incise::solver {
namespace {

material::Parameters table_4_1(const std::string& material) {
  material::Parameters p;  // Table 4.1
  p.youngs_modulus = 1e4;
  p.poisson_ratio = 0.3;
  p.density = 1000.0;
  p.gamma = material == "veronda-westmann" ? 8.0 : 0.0;
  return p;
}

// The thesis' small cylinder (§4.2), gravity 9.8 m/s².
std::unique_ptr<fem::ElasticProblem> cylinder(const std::string& material) {
  const mesh::MeshData m = mesh::make_thesis_cylinder_small();
  auto prob =
      std::make_unique<fem::ElasticProblem>(m, material::Material(material, table_4_1(material)));
  prob->fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
  prob->add_gravity(Vec3(0.0, 0.0, -9.8));
  return prob;
}

// A 0.1 m cube of 6³×6 tetrahedra, face x = 0 fixed, gravity g sideways (−z).
std::unique_ptr<fem::ElasticProblem> cube(const std::string& material, double g) {
  const mesh::MeshData m = mesh::make_box(6, 6, 6, 0.1, 0.1, 0.1);
  auto prob =
      std::make_unique<fem::ElasticProblem>(m, material::Material(material, table_4_1(material)));
  prob->fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
  prob->add_gravity(Vec3(0.0, 0.0, -g));
  return prob;
}

DynamicRelaxationOptions ss22(const DynamicParameterEstimate& d, double epsilon, int restarts) {
  DynamicRelaxationOptions o;
  o.time_step = d.time_step;
  o.damping = d.damping;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = epsilon;
  o.max_restarts = restarts;
  return o;
}

class EstimateCost : public ::testing::TestWithParam<std::string> {};

// Issue 19's budget: the estimate costs ≤ 10 % of the solve it serves, counted in K-products
// against time steps (one gradient evaluation each), to ‖r‖ ≤ 1e-6‖f‖. The counted-flop share
// is printed, not asserted: with K(u) assembled once (LanczosOptions::assembled, the default) a
// product costs 18 flops per node block, far less than a time step (docs/solvers.md, fifth pass:
// 2.8 % and 1.1 %; matrix-free, a Veronda–Westmann K-product costs ≈ 1.4× a gradient and the
// share was 10.1 %). The inverse iteration it replaces took 52,859 and 61,113 inner CG steps.
TEST_P(EstimateCost, AtMostTenPercentOfTheSolve_Sec4_1) {
  auto p = cylinder(GetParam());
  VecX u = VecX::Zero(p->size());
  const DynamicParameterEstimate d = estimate_dynamic_parameters(*p, u);
  ASSERT_TRUE(d.ok()) << d.brief();
  EXPECT_EQ(d.status, StopReason::kConverged);
  const SolverReport rep = dynamic_relaxation(*p, u, ss22(d, 1e-6, 8));
  ASSERT_TRUE(rep.ok()) << rep.brief();
  EXPECT_EQ(rep.restarts, 0);
  EXPECT_LE(double(d.products), 0.1 * double(rep.iterations))
      << d.products << " products, " << rep.iterations << " steps";
  EXPECT_GE(d.products, LanczosOptions{}.min_steps);  // it did run: the cost is not hidden
  std::printf("[%s] estimate: %ld products, %.3g MFLOP; solve: %ld steps, %.3g MFLOP (%.1f %%)\n",
              GetParam().c_str(), d.products, 1e-6 * double(d.flops), rep.iterations,
              1e-6 * double(rep.flops), 100.0 * double(d.flops) / double(rep.flops));
}

INSTANTIATE_TEST_SUITE_P(Materials, EstimateCost, ::testing::Values("linear", "veronda-westmann"),
                         [](const ::testing::TestParamInfo<std::string>& i) {
                           return i.param == "linear" ? std::string("linear") : "veronda";
                         });

// Gravity 20 m/s² sideways on the stiffening Veronda–Westmann cube: λ_n grows as the cube bends,
// so the automatic Δt = 0.9·2/√λ_n(u = 0) turns unstable and elements invert. Without restarts
// that ends the run (inverted); with them Δt is lowered and the run converges to the state
// truncated Newton finds (‖Δu‖ ≤ 1e-4‖u‖: both stop at ‖r‖ ≤ 1e-8‖f‖ and the tangent's
// condition number on this mesh is ~1e3, so their errors are ≲ 1e-5).
TEST(DynamicRelaxationRestarts, StiffeningVerondaWestmannThatInvertedConverges_Sec4_4_1) {
  auto p = cube("veronda-westmann", 20.0);
  VecX u = VecX::Zero(p->size());
  const DynamicParameterEstimate d = estimate_dynamic_parameters(*p, u);
  ASSERT_TRUE(d.ok()) << d.brief();
  const SolverReport plain = dynamic_relaxation(*p, u, ss22(d, 1e-8, 0));
  EXPECT_EQ(plain.status, StopReason::kInverted) << plain.brief();
  u.setZero();
  const SolverReport rep = dynamic_relaxation(*p, u, ss22(d, 1e-8, 8));
  ASSERT_TRUE(rep.ok()) << rep.brief();
  EXPECT_GE(rep.restarts, 1);
  EXPECT_LT(rep.time_step, d.time_step);
  VecX ref = VecX::Zero(p->size());
  TruncatedNewtonOptions tn;
  tn.stop.rule = ResidualRule::kExternalForce;
  tn.stop.epsilon = 1e-8;
  ASSERT_TRUE(truncated_newton(*p, ref, tn).ok());
  EXPECT_LE((u - ref).norm(), 1e-4 * ref.norm());
}

// Restarts used up: the run reports the last event with a message naming the restarts.
TEST(DynamicRelaxationRestarts, ExhaustedRestartsAreReportedNotSilent_Sec4_4_1) {
  auto p = cube("veronda-westmann", 80.0);
  VecX u = VecX::Zero(p->size());
  const DynamicParameterEstimate d = estimate_dynamic_parameters(*p, u);
  ASSERT_TRUE(d.ok()) << d.brief();
  const SolverReport rep = dynamic_relaxation(*p, u, ss22(d, 1e-8, 1));
  EXPECT_FALSE(rep.ok());
  EXPECT_EQ(rep.restarts, 1);
  EXPECT_NE(rep.message.find("after 1 restart(s)"), std::string::npos) << rep.message;
  EXPECT_TRUE(u.allFinite());
}

// Δt just above the stability limit (docs/solvers.md, "Restarts"): 1.15× the automatic Δt on
// the Kuhn Veronda–Westmann cube of EstimateOnKuhnCube is 1.035·2/√θ_max(0). Without restarts
// the run fails; with them one restart (Δt × 0.7, stable) suffices. Before the energy check was
// measured against the whole run's dissipation, the resumed run restarted again on E's wiggle
// from rest (3 restarts, Δt × 0.7³, twice the steps); issue of the eighth pass.
TEST(DynamicRelaxationRestarts, OneRestartJustAboveTheCriticalStep_Sec4_4_1) {
  const mesh::MeshData m = mesh::make_kuhn_cube(6, 0.1);
  fem::ElasticProblem p(m, material::Material("veronda-westmann", table_4_1("veronda-westmann")));
  p.fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
  p.add_gravity(Vec3(0.0, 0.0, -9.8));
  const DynamicParameterEstimate d = estimate_dynamic_parameters(p, VecX::Zero(p.size()));
  ASSERT_TRUE(d.ok()) << d.brief();
  DynamicRelaxationOptions o = ss22(d, 1e-8, 0);
  o.time_step = 1.15 * d.time_step;
  o.budget.max_iterations = 20000;
  VecX u = VecX::Zero(p.size());
  const SolverReport plain = dynamic_relaxation(p, u, o);
  EXPECT_FALSE(plain.ok()) << plain.brief();
  o.max_restarts = 8;
  u.setZero();
  const SolverReport rep = dynamic_relaxation(p, u, o);
  ASSERT_TRUE(rep.ok()) << rep.brief() << " " << rep.message;
  EXPECT_EQ(rep.restarts, 1);
  EXPECT_EQ(rep.time_step, o.time_step * o.restart_reduction);
  VecX ref = VecX::Zero(p.size());
  TruncatedNewtonOptions tn;
  tn.stop.rule = ResidualRule::kExternalForce;
  tn.stop.epsilon = 1e-8;
  ASSERT_TRUE(truncated_newton(p, ref, tn).ok());
  // both stop at ‖r‖ ≤ 1e-8‖f‖, condition number ~1e3 on this mesh: errors ≲ 1e-5 (as above)
  EXPECT_LE((u - ref).norm(), 1e-4 * ref.norm());
  std::printf("plain: %s after %ld steps; restarts: %ld, %ld steps\n", plain.brief().c_str(),
              plain.iterations, rep.restarts, rep.iterations);
}

// A slender Veronda–Westmann beam (0.4 × 0.1 × 0.1 m, 16×4×4 cubes, x = 0 fixed, gravity
// sideways): κ(M⁻¹K) ≈ 2e5, and θ₁ needs 502 Lanczos steps to pass the Ritz-residual test, more
// than the default 400 (docs/solvers.md, "Restarts"). θ_max settles within a few dozen steps, so
// the estimate reports kMaxIterations with the bounds it has — Δt from θ_max (the converged
// run's, round-off apart), η from θ₁ ≥ λ₁ — and SS22 with them and restarts converges. Before,
// Δt = η = 0 and a scene without explicit keys could not run.
TEST(EstimateOnSlenderBeam, UnconvergedLowestModeGivesUsableBoundsAndSaysSo_Sec4_1) {
  const mesh::MeshData m = mesh::make_box(16, 4, 4, 0.4, 0.1, 0.1);
  fem::ElasticProblem p(m, material::Material("veronda-westmann", table_4_1("veronda-westmann")));
  p.fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
  p.add_gravity(Vec3(0.0, 0.0, -9.8));
  const VecX zero = VecX::Zero(p.size());
  const DynamicParameterEstimate d = estimate_dynamic_parameters(p, zero);
  EXPECT_EQ(d.status, StopReason::kMaxIterations);
  EXPECT_EQ(d.products, LanczosOptions{}.max_steps);
  EXPECT_NE(d.message.find("lambda_1 not converged in 400 Lanczos steps"), std::string::npos)
      << d.message;
  DynamicParameterOptions more;
  more.lanczos.max_steps = 2000;
  const DynamicParameterEstimate c = estimate_dynamic_parameters(p, zero, more);
  ASSERT_TRUE(c.ok()) << c.brief();
  EXPECT_GT(c.products, LanczosOptions{}.max_steps);
  // θ_max settled (≤ 1 % per step over 8 steps; in fact to round-off): the same Δt to 1e-9
  EXPECT_NEAR(d.lambda_max, c.lambda_max, 1e-9 * c.lambda_max);
  EXPECT_EQ(d.time_step, 0.9 * critical_time_step(d.lambda_max));
  // θ₁ of T_400 ≥ θ₁ of the longer run from the same start (interlacing; 1e-9: round-off)
  EXPECT_GE(d.lambda_min, c.lambda_min * (1 - 1e-9));
  EXPECT_EQ(d.damping, d.damping_ratio * critical_damping(d.lambda_min));
  DynamicRelaxationOptions o;
  o.time_step = d.time_step;
  o.damping = d.damping;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-6;
  o.max_restarts = 8;
  o.budget.max_iterations = 100000;
  VecX u = zero;
  const SolverReport rep = dynamic_relaxation(p, u, o);
  EXPECT_TRUE(rep.ok()) << rep.brief() << " " << rep.message;
  o.time_step = c.time_step;
  o.damping = c.damping;
  VecX uc = zero;
  const SolverReport repc = dynamic_relaxation(p, uc, o);
  EXPECT_TRUE(repc.ok()) << repc.brief() << " " << repc.message;
  std::printf(
      "theta_1 %.6g (400 steps) against %.6g (%ld steps); SS22 to 1e-6: %ld steps, %ld "
      "restarts, against %ld steps, %ld restarts\n",
      d.lambda_min, c.lambda_min, c.products, rep.iterations, rep.restarts, repc.iterations,
      repc.restarts);
}

namespace kuhn_steps_test {

// SS22 steps from rest until the relative energy-norm error ‖u − û‖_{K(û)}/‖û‖_{K(û)} stays ≤
// 1e-6 (the measure of issue 19; 30 steps held, budget 20,000), with Δt and η given.
long steps_to_1e6(fem::ElasticProblem& p, const VecX& ref, double dt, double eta) {
  EnergyErrorTrace trace(p, ref);
  const double n2 = trace.energy_error(VecX::Zero(p.size()));
  DynamicRelaxationOptions o;
  o.time_step = dt;
  o.damping = eta;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-13;
  o.budget.max_iterations = 20000;
  long hit = -1, last = 0;
  o.observer = [&](const IterationInfo& info) {
    last = info.iteration;
    if (hit >= 0 && info.iteration >= hit + 30) return;  // held; the level is decided
    if (std::sqrt(trace.energy_error(*info.u) / n2) <= 1e-6) {
      if (hit < 0) hit = info.iteration;
    } else {
      hit = -1;
    }
  };
  VecX u = VecX::Zero(p.size());
  const SolverReport rep = dynamic_relaxation(p, u, o);
  EXPECT_TRUE(rep.ok() || hit >= 0) << rep.brief();
  return hit >= 0 && last >= hit + 30 ? hit : -1;
}

}  // namespace kuhn_steps_test

class EstimateOnKuhnCube : public ::testing::TestWithParam<std::string> {};

// A second mesh beside the cylinder of DampingOnCylinder: the mirrored cube of issue 19 at 6³×6
// (0.1 m, face x = 0 fixed, gravity 9.8 m/s² sideways), Table 4.1 materials, error measured in
// the energy norm against û (linear CG to 1e-13, truncated Newton to 1e-11). The automatic η =
// 2ζ√θ₁ (ζ for ε = 1e-6) is within 1.3× of the best of a sweep of η over 2^{±½} around it
// and critical damping (issue 19), and for the linear material needs fewer steps than critical
// damping 2√θ₁ (the one-mode closed form: 0.80×; docs/solvers.md, "Eighth pass").
TEST_P(EstimateOnKuhnCube, WithinSweepAndBelowCriticalDamping_Sec4_1) {
  const mesh::MeshData m = mesh::make_kuhn_cube(6, 0.1);
  fem::ElasticProblem p(m, material::Material(GetParam(), table_4_1(GetParam())));
  p.fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
  p.add_gravity(Vec3(0.0, 0.0, -9.8));
  VecX ref = VecX::Zero(p.size());
  if (GetParam() == "linear") {
    LinearCgOptions o;
    o.stop.rule = ResidualRule::kExternalForce;
    o.stop.epsilon = 1e-13;
    ASSERT_TRUE(linear_cg(p, ref, o).ok());
  } else {
    TruncatedNewtonOptions o;
    o.stop.rule = ResidualRule::kExternalForce;
    o.stop.epsilon = 1e-11;
    ASSERT_TRUE(truncated_newton(p, ref, o).ok());
  }
  const DynamicParameterEstimate d = estimate_dynamic_parameters(p, VecX::Zero(p.size()));
  ASSERT_TRUE(d.ok()) << d.brief();
  EXPECT_EQ(d.damping_ratio, damping_ratio_for(0.5e-6));
  const long n_est = kuhn_steps_test::steps_to_1e6(p, ref, d.time_step, d.damping);
  const double eta_crit = critical_damping(d.lambda_min);
  const long n_crit = kuhn_steps_test::steps_to_1e6(p, ref, d.time_step, eta_crit);
  long best = n_crit;
  double best_eta = eta_crit;
  for (int i = -4; i <= 4; ++i) {
    if (i == 0) continue;  // n_est
    const double eta = d.damping * std::pow(2.0, i / 8.0);
    const long n = kuhn_steps_test::steps_to_1e6(p, ref, d.time_step, eta);
    if (n > 0 && (best < 0 || n < best)) {
      best = n;
      best_eta = eta;
    }
  }
  std::printf(
      "[%s] steps to 1e-6: estimate (zeta %.4f, eta %.4g) %ld, critical (eta %.4g) %ld, "
      "sweep best (eta %.4g) %ld\n",
      GetParam().c_str(), d.damping_ratio, d.damping, n_est, eta_crit, n_crit, best_eta, best);
  ASSERT_GT(n_est, 0);
  ASSERT_GT(n_crit, 0);
  if (n_est < best) {
    best = n_est;
    best_eta = d.damping;
  }
  EXPECT_LE(double(n_est), 1.3 * double(best));
  if (GetParam() == "linear") {
    EXPECT_LT(n_est, n_crit);
  }
}

INSTANTIATE_TEST_SUITE_P(Materials, EstimateOnKuhnCube,
                         ::testing::Values("linear", "neohookean", "veronda-westmann"),
                         [](const ::testing::TestParamInfo<std::string>& i) {
                           return i.param == "veronda-westmann" ? std::string("veronda") : i.param;
                         });

}  // namespace
}  // namespace incise::solver
