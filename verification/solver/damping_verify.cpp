/// Dynamic relaxation parameters on the thesis' cylinder (§4.2, Table 4.1; structured stand-in
/// for the small Delaunay mesh of Table 4.2): critical time step by the thesis' procedure (CFL
/// estimate (2.61) lowered 15 % at a time until an undamped run survives 50 MFLOP, §4.4.1) and by
/// power iteration (2/√λ_n, §4.1); damping η by a sweep (the thesis' manual method), by
/// η = 2√λ₁ (inverse iteration) and by the dominant frequency of an undamped trajectory (FFTW).
/// Prints how close each η gets to the swept optimum. Default: the linear model; the `slow`
/// executable (INCISE_DAMPING_ALL_MATERIALS) runs the three nonlinear models.
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise_test/mesh_measures.hpp>
#include <incise_test/param_names.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

namespace incise::solver {
namespace {

struct Cylinder {
  mesh::MeshData mesh;
  std::unique_ptr<fem::ElasticProblem> problem;
  material::Lame lame;
  double density = 1000.0;
};

Cylinder make(const std::string& material) {
  Cylinder c;
  c.mesh = mesh::make_thesis_cylinder_small();
  material::Parameters p;  // Table 4.1
  p.youngs_modulus = 1e4;
  p.poisson_ratio = 0.3;
  p.density = c.density;
  p.gamma = material == "veronda-westmann" ? 8.0 : 0.0;
  const material::Material mat(material, p);
  c.lame = mat.lame();
  c.problem = std::make_unique<fem::ElasticProblem>(c.mesh, mat);
  c.problem->fix_nodes(fem::nodes_on_plane(c.mesh, 0, 0.0));
  c.problem->add_gravity(Vec3(0.0, 0.0, -9.8));
  return c;
}

DynamicRelaxationOptions options(double dt) {
  DynamicRelaxationOptions o;
  o.time_step = dt;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-4;
  o.budget.max_iterations = 100000;
  return o;
}

class DampingOnCylinder : public ::testing::TestWithParam<std::string> {};

TEST_P(DampingOnCylinder, ThreeWaysAgainstSweep_Sec4_1_Sec4_4_1) {
  Cylinder c = make(GetParam());
  fem::ElasticProblem& p = *c.problem;
  const VecX u0 = VecX::Zero(p.size());

  // Time step two ways.
  const EigenEstimate big = largest_eigenvalue(p, u0, EigenOptions{1e-8, 20000, 1e-8, 1});
  ASSERT_TRUE(big.ok()) << to_string(big.status);
  const double dt_computed = critical_time_step(big.value);
  const double dt_cfl =
      cfl_time_step(test::shortest_edge(c.mesh), c.lame.lambda, c.lame.mu, c.density);
  const StableTimeStep st = find_stable_time_step(p, u0, dt_cfl);
  ASSERT_TRUE(st.found);
  std::printf(
      "[%s] dt: CFL (2.61) %.4g s; thesis procedure %.4g s after %d reductions; "
      "2/sqrt(lambda_n) %.4g s (lambda_n %.4g, %ld power its)\n",
      GetParam().c_str(), dt_cfl, st.time_step, st.reductions, dt_computed, big.value,
      big.iterations);
  // An undamped run that survived 50 MFLOP cannot be far above the linear stability limit
  // (growth per step ~ exp(√(Δt/Δt_crit − 1)·2) would overflow 1e15 well within the budget).
  EXPECT_LT(st.time_step, 1.15 * dt_computed);
  const double dt = 0.9 * std::min(st.time_step, dt_computed);

  // Damping three ways.
  const EigenEstimate small = smallest_eigenvalue(p, u0, EigenOptions{1e-6, 500, 1e-6, 1});
  ASSERT_TRUE(small.ok()) << to_string(small.status);
  const double eta_eig = critical_damping(small.value);
  SpectralDamping sd = damping_from_spectrum(p, u0, dt, 4096);
  if (sd.damping == 0.0) {
    // Stiffening materials raise λ_n as the beam deflects: the step that was stable at the
    // start (and for the thesis' 50 MFLOP, a fraction of the first period) may not be at the
    // bottom of the swing. Retry once at half the step, and say so.
    std::printf("[%s] undamped run at dt = %.4g s ended '%s' after %ld steps; retry at dt/2\n",
                GetParam().c_str(), dt, to_string(sd.status), sd.steps);
    sd = damping_from_spectrum(p, u0, 0.5 * dt, 8192);
  }
  if (sd.damping == 0.0) {
    // The undamped trajectory swings to about twice the static deflection; for StVK this
    // inverts elements near the clamp (§4.3.1) and the run may blow up. That must be a reported
    // status, not a NaN or a crash.
    std::printf("[%s] FFT damping unavailable: undamped run ended '%s' after %ld steps\n",
                GetParam().c_str(), to_string(sd.status), sd.steps);
    EXPECT_TRUE(sd.status == StopReason::kUnstable || sd.status == StopReason::kInverted ||
                sd.status == StopReason::kNonFinite);
  }
  std::vector<double> etas;
  for (int i = -4; i <= 4; ++i) etas.push_back(eta_eig * std::pow(2.0, i / 4.0));
  const DampingSweep sweep = sweep_damping(p, u0, etas, options(dt));
  ASSERT_GT(sweep.best_damping, 0.0);
  auto steps = [&](double eta) {
    DynamicRelaxationOptions o = options(dt);
    o.damping = eta;
    VecX u = u0;
    const SolverReport rep = dynamic_relaxation(p, u, o);
    EXPECT_TRUE(rep.ok()) << "eta " << eta << ": " << to_string(rep.status);
    return rep.iterations;
  };
  const long n_eig = steps(eta_eig), n_fft = sd.damping > 0.0 ? steps(sd.damping) : 0;
  // The automatic η of "dynamic-ss22" scenes: 2ζ√θ₁ from one Lanczos run (issue 19), ζ for the
  // reduction this run's stopping rule asks for (as scenes pass their tolerance).
  DynamicParameterOptions dpo;
  dpo.target_reduction = options(dt).stop.epsilon;
  const DynamicParameterEstimate lz = estimate_dynamic_parameters(p, u0, dpo);
  ASSERT_TRUE(lz.ok()) << lz.brief();
  const long n_lz = steps(lz.damping);
  std::printf(
      "[%s] eta: Lanczos 2*zeta*sqrt(theta_1) %.3g 1/s (zeta %.4f, %ld products; %ld steps, "
      "%.2fx best)\n",
      GetParam().c_str(), lz.damping, lz.damping_ratio, lz.products, n_lz,
      double(n_lz) / sweep.best_iterations);
  // Issue 19: within 1.3× of the swept-optimal step count.
  EXPECT_LE(double(n_lz), 1.3 * double(sweep.best_iterations));
  std::printf(
      "[%s] eta: sweep best %.3g 1/s (%ld steps); 2*sqrt(lambda_1) %.3g (%ld steps, "
      "%.2fx); FFT f = %.3g Hz -> %.3g (%ld steps, %.2fx)\n",
      GetParam().c_str(), sweep.best_damping, sweep.best_iterations, eta_eig, n_eig,
      double(n_eig) / sweep.best_iterations, sd.frequency, sd.damping, n_fft,
      double(n_fft) / sweep.best_iterations);
  for (const DampingTrial& t : sweep.trials)
    std::printf("   eta %8.3f  %-14s %6ld steps\n", t.damping, to_string(t.status), t.iterations);
  // §4.1: η = 2√λ₁ is the optimum of the linear analysis. Linear model: it must be within one
  // sweep step (2^¼) of the swept best up to the sweep's granularity, and cost ≤ 1.5× its steps.
  // Nonlinear models: λ₁ is taken at the reference state, so allow 2× the steps.
  const double step_tol = GetParam() == "linear" ? 1.5 : 2.0;
  EXPECT_LE(double(n_eig), step_tol * double(sweep.best_iterations));
  // StVK: the undamped swing inverts elements near the clamp (§4.3.1) and the spectrum of that
  // trajectory peaks at a higher mode (measured 6.4 Hz vs 2.5 Hz for the linear model), so the
  // FFT estimate over-damps (3.4× the swept best). Reported above, not asserted.
  if (sd.damping > 0.0 && GetParam() != "stvk") {
    EXPECT_LE(double(n_fft), step_tol * double(sweep.best_iterations));
  }
}

#ifdef INCISE_DAMPING_ALL_MATERIALS
INSTANTIATE_TEST_SUITE_P(Materials, DampingOnCylinder,
                         ::testing::Values("stvk", "neohookean", "veronda-westmann"),
                         incise::test::material_param_name);
#else
INSTANTIATE_TEST_SUITE_P(Materials, DampingOnCylinder, ::testing::Values("linear"),
                         incise::test::material_param_name);
#endif

}  // namespace
}  // namespace incise::solver
