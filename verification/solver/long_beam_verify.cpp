/// The long beam of Yeung, Crouch & Pothen 2016 §4 item (1) (seed 004; issue 4 "extremes"):
/// nodes on a regular 5×5×h grid (make_beam, 5-tetrahedra split, unit spacing), clamped at
/// z = 0, linear model (E = 1e4 Pa, ν = 0.3, ρ = 1000 kg/m³) under gravity across the axis.
///
/// Linear CG (plain, §2.4.1, the thesis' solver) to ‖r‖ ≤ 1e-8‖f‖; the condition number of the
/// CG operator (K on the free DOFs) is estimated from the same run by the Lanczos tridiagonal of
/// its coefficients (cg_lanczos_extremes; extreme Ritz values have converged when CG has).
/// Findings (asserted):
/// - κ ∝ h⁴, as for a slender clamped beam in bending (λ_min ∝ EI/L⁴, λ_max ∝ E·spacing);
/// - CG always stays below the bound ½√κ ln(2/ε);
/// - on short beams (h = 8…64) its iteration count grows far slower than √κ (log-log slope
///   ≈ 0.37): the small eigenvalues are a few isolated bending modes λ_j ∝ (j/L)⁴ below the
///   bulk, and CG removes isolated eigenvalues at a few iterations each (§2.4.1 — the same
///   reason §4.5.6's short edge barely matters);
/// - as the beam lengthens the low end of the spectrum fills with bending modes and CG
///   approaches the √κ scaling: local slopes 0.80–0.93 for h = 64…512 (slow run). From
///   h = 128 on the true residual cannot reach 1e-8 (κ ≳ 1e8): reported as `stagnated`.
/// - Dynamic relaxation (SS22, Δt = 0.9·2/√λ_n, η = 2√λ₁ of M⁻¹K; §4.1, §4.6) has no such
///   mechanism: its step count is ∝ √κ(M⁻¹K) ("the number of iterations is proportional to
///   √cond₂(M⁻¹K)", §4.6), which we measure as a log-log slope ≈ 1.
///
/// Default: CG for h = 8, 16, 32, 64, SS22 for h = 8, 16, 32 (seconds). The `slow` entry
/// (INCISE_LONG_BEAM_ALL=1) adds CG for h = 128, 256, 512 and SS22 for h = 64. Not h = 1024
/// (the paper's 25,600-node beam; its augmented solves are papers_yeung2016_beam1024): with
/// κ ≈ 7e11 its attainable accuracy ε_mach·κ ≈ 1e-4 is four decades above the 1e-8 rule, so its
/// iteration count measures finite-precision CG (45,519 in docs/solvers.md's table, 80,438 in a
/// 2026-12-01 run whose h ≤ 256 counts matched that table's to within 1 %), not the spectrum the
/// slopes are about; and it was 90 % of the entry's time.
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/linear_cg.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace incise::solver {
namespace {

bool all_lengths() {
  const char* v = std::getenv("INCISE_LONG_BEAM_ALL");
  return v && std::string(v) == "1";
}

struct BeamRun {
  int h = 0;
  Index nodes = 0;
  SolverReport report;
  LanczosExtremes lanczos;
  double force_norm = 0.0;  // ‖f_ex‖ (N)
};

BeamRun run_beam(int h, long max_iterations) {
  const mesh::MeshData m = mesh::make_beam(h);
  material::Parameters par;
  par.youngs_modulus = 1e4;
  par.poisson_ratio = 0.3;
  par.density = 1000.0;
  fem::ElasticProblem p(m, material::Material("linear", par));
  p.fix_nodes(fem::nodes_on_plane(m, 2, 0.0));
  p.add_gravity(Vec3(-9.8, 0.0, 0.0));
  VecX u = VecX::Zero(p.size());
  CgCoefficients c;
  LinearCgOptions o;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-8;
  o.budget.max_iterations = max_iterations;
  o.coefficients = &c;
  BeamRun r;
  r.h = h;
  r.nodes = m.num_points();
  r.report = linear_cg(p, u, o);
  r.force_norm = p.external_force_norm();
  r.lanczos = cg_lanczos_extremes(c);
  return r;
}

// Least-squares slope of log y against log x.
double log_slope(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = double(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

TEST(LongBeam, CgIterationsVsLanczosCondition_Sec2_4_1) {
  std::vector<int> lengths = {8, 16, 32, 64};
  if (all_lengths()) lengths.insert(lengths.end(), {128, 256, 512});
  std::printf("%6s %7s %-15s %9s %12s %12s %12s %10s %9s %9s\n", "h", "nodes", "CG end", "its",
              "lambda_min", "lambda_max", "kappa(K)", "sqrt(k)", "its/sqrtk", "bound");
  std::vector<double> hs, its, sqrt_kappa, kappa;
  const double eps = 1e-8;
  for (int h : lengths) {
    const BeamRun r = run_beam(h, 400000);
    const double k = r.lanczos.condition();
    // CG error bound (§2.4.1): iterations ≤ ½√κ ln(2/ε) (energy norm; the residual rule is
    // comparable up to √κ, which we ignore: the bound is loose by orders of magnitude here).
    const double bound = 0.5 * std::sqrt(k) * std::log(2.0 / eps);
    std::printf("%6d %7d %-15s %9ld %12.4e %12.4e %12.4e %10.1f %9.3f %9.0f\n", r.h, int(r.nodes),
                to_string(r.report.status), r.report.iterations, r.lanczos.smallest,
                r.lanczos.largest, k, std::sqrt(k), double(r.report.iterations) / std::sqrt(k),
                bound);
    std::fflush(stdout);
    // From h = 128 on (κ ≳ 1e8) the true residual cannot reach 1e-8‖f‖ in double precision
    // (attainable accuracy ≈ ε_mach·κ): CG's recursive residual meets the rule, the recomputed
    // one does not, and linear_cg says `stagnated`. The iteration count is still CG's to the
    // rule; the status and the true residual are reported.
    const bool ok = r.report.ok() || (h >= 128 && r.report.status == StopReason::kStagnated);
    if (!r.report.ok())
      std::printf("       h = %d: %s, true |r|/|f| = %.2e (recursive residual met 1e-8)\n", h,
                  to_string(r.report.status), r.report.residual_norm / r.force_norm);
    ASSERT_TRUE(ok) << "h = " << h << ": " << to_string(r.report.status);
    ASSERT_TRUE(r.lanczos.converged) << "h = " << h;
    EXPECT_LT(double(r.report.iterations), bound);
    hs.push_back(h);
    its.push_back(double(r.report.iterations));
    sqrt_kappa.push_back(std::sqrt(k));
    kappa.push_back(k);
  }
  const double s_its = log_slope(sqrt_kappa, its);
  const double s_kappa = log_slope(hs, kappa);
  const double s_h = log_slope(hs, its);
  std::printf(
      "CG log-log slopes: iterations vs sqrt(kappa) %.3f, kappa vs h %.3f (bending: 4), "
      "iterations vs h %.3f\n",
      s_its, s_kappa, s_h);
  // κ ∝ h⁴: measured 3.97 on 8…64 (h = 8, a 2:1 block, is not slender yet); ±0.3.
  EXPECT_NEAR(s_kappa, 4.0, 0.3);
  // Short beams (h = 8…64): iterations grow much slower than √κ (measured slope 0.37): below
  // 0.6, far from the slope 1 of a spectrum without isolated low eigenvalues; but they grow.
  const std::vector<double> short_its(its.begin(), its.begin() + 4);
  const std::vector<double> short_sqrt(sqrt_kappa.begin(), sqrt_kappa.begin() + 4);
  const double s_short = log_slope(short_sqrt, short_its);
  EXPECT_LT(s_short, 0.6);
  EXPECT_GT(s_short, 0.1);
  if (hs.size() >= 7) {
    // Long beams (the three longest run, h = 128, 256, 512): the bending modes fill the low
    // spectrum and CG approaches √κ scaling. Measured local slopes 0.80 (64→128), 0.88, 0.86
    // (256→512); over 128/256/512: 0.87 (docs/solvers.md's table), 0.91 and 0.89 (two later
    // runs); we require [0.7, 1.1] (1 would be exact √κ scaling).
    const std::size_t n = hs.size();
    const double s_long = log_slope({sqrt_kappa[n - 3], sqrt_kappa[n - 2], sqrt_kappa[n - 1]},
                                    {its[n - 3], its[n - 2], its[n - 1]});
    std::printf("CG slope on the three longest beams: %.3f\n", s_long);
    EXPECT_GT(s_long, 0.7);
    EXPECT_LT(s_long, 1.1);
  }
}

TEST(LongBeam, DynamicRelaxationStepsScaleWithSqrtCondition_Sec4_6) {
  std::vector<int> lengths = {8, 16, 32};
  if (all_lengths()) lengths.push_back(64);
  std::printf("%6s %12s %12s %12s %10s %9s %9s\n", "h", "lambda_1", "lambda_n", "kappa(M^-1K)",
              "sqrt(k)", "SS22 its", "its/sqrtk");
  std::vector<double> sqrt_kappa, steps;
  for (int h : lengths) {
    const mesh::MeshData m = mesh::make_beam(h);
    material::Parameters par;
    par.youngs_modulus = 1e4;
    par.poisson_ratio = 0.3;
    par.density = 1000.0;
    fem::ElasticProblem p(m, material::Material("linear", par));
    p.fix_nodes(fem::nodes_on_plane(m, 2, 0.0));
    p.add_gravity(Vec3(-9.8, 0.0, 0.0));
    const VecX u0 = VecX::Zero(p.size());
    const EigenEstimate big = largest_eigenvalue(p, u0, EigenOptions{1e-8, 50000, 1e-8, 1});
    const EigenEstimate small = smallest_eigenvalue(p, u0, EigenOptions{1e-8, 500, 1e-10, 1});
    ASSERT_TRUE(big.ok() && small.ok());
    VecX u = u0;
    DynamicRelaxationOptions o;
    o.time_step = 0.9 * critical_time_step(big.value);
    o.damping = critical_damping(small.value);
    o.stop.rule = ResidualRule::kExternalForce;
    o.stop.epsilon = 1e-4;
    o.budget.max_iterations = 2000000;
    const SolverReport rep = dynamic_relaxation(p, u, o);
    ASSERT_TRUE(rep.ok()) << to_string(rep.status);
    const double k = big.value / small.value;
    std::printf("%6d %12.4e %12.4e %12.4e %10.1f %9ld %9.3f\n", h, small.value, big.value, k,
                std::sqrt(k), rep.iterations, double(rep.iterations) / std::sqrt(k));
    std::fflush(stdout);
    sqrt_kappa.push_back(std::sqrt(k));
    steps.push_back(double(rep.iterations));
  }
  const double s = log_slope(sqrt_kappa, steps);
  std::printf("SS22 log-log slope: steps vs sqrt(kappa(M^-1 K)) %.3f (§4.6: 1)\n", s);
  // §4.6: steps ∝ √κ(M⁻¹K) for the critically damped explicit iteration (the slowest mode
  // decays like exp(−√λ₁ t) and t = steps·Δt ∝ steps/√λ_n). Measured slope 1.000 (steps/√κ =
  // 6.37 on every beam); ±0.1 allows for the start-up transient on other meshes/loads.
  EXPECT_NEAR(s, 1.0, 0.1);
}

}  // namespace
}  // namespace incise::solver
