/// The shipped cantilever scene (reference_data/scenes/cantilever.json: thesis §3.3, Table 3.1,
/// 16×4×4 mesh, E = 1e6 Pa, ν = 0, 3 N tip load) solved at the scene's E = 1e6 Pa and at
/// E = 1e9 Pa (strains ≈ 1e-8), with the scene's solver settings, the rule (6.8) and the
/// residual recomputed here from the returned u (r = −P∇Π(u)) — issue 14, item 1:
/// - truncated Newton (the §4.2 reference solver) reaches ‖r‖ ≤ 1e-10‖f_ext‖ for StVK and
///   neo-Hookean;
/// - linear CG cannot reach the thesis' 1e-12 on this mesh in double precision: a displacement
///   rounded to double already has ‖r‖ ≈ 1.2–1.7e-12‖f_ext‖ (‖K‖‖u‖ ≫ ‖f‖). The test asserts
///   instead that CG, restarted from its own result, reaches that rounding floor (computed here
///   as ‖P K δu‖ for a random ½-ulp perturbation δu of u), and that plain CG's true residual is
///   E-independent.
///
/// Before the kernels computed strain from G without forming I + G (tet_kernels.hpp): CG
/// stagnated at 2.7e-11 (E = 1e6) and 1.5e-8 (E = 1e9); Newton's line search failed at 5.6e-4
/// (StVK) and 1.2e-3 (neo-Hookean) at E = 1e9, and StVK at E = 1e6 had not converged after
/// 20000 Newton steps (6.5e-10).
#include <incise/scene/scene_builder.hpp>
#include <incise/scene/scene_parser.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/truncated_newton.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace {

using incise::VecX;

/// The shipped scene with `model` and Young's modulus `e`.
incise::scene::SceneSpec scene_with(const std::string& model, double e) {
  incise::scene::SceneSpec spec =
      incise::scene::load_scene(incise::test::source_path("reference_data/scenes/cantilever.json"));
  spec.material.model = model;
  spec.material.parameters.youngs_modulus = e;
  return spec;
}

/// ‖P∇Π(u)‖/‖f_ext‖ recomputed at u.
double true_relative_residual(incise::fem::ElasticProblem& p, const VecX& u) {
  VecX g;
  EXPECT_EQ(p.gradient(u, g), incise::EvalStatus::kOk);
  p.project(g);
  return g.norm() / p.external_force_norm();
}

/// ‖P K δu‖/‖f_ext‖ for δu_i uniform in ±½ ulp(u_i): the typical residual of u rounded to
/// double, i.e. the accuracy no double-precision solver can beat on this problem.
double rounding_floor(incise::fem::ElasticProblem& p, const VecX& u, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> half(-0.5, 0.5);
  VecX du(u.size());
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    const double a = std::abs(u[i]);
    du[i] = p.is_fixed(i) ? 0.0 : half(rng) * (std::nextafter(a, 2.0 * a + 1.0) - a);
  }
  VecX kdu;
  EXPECT_EQ(p.hessian_product(u, du, kdu), incise::EvalStatus::kOk);
  p.project(kdu);
  return kdu.norm() / p.external_force_norm();
}

TEST(CantileverSceneConvergence, LinearCgReachesRoundingFloorIndependentOfE) {
  INCISE_SEEDED_RNG(rng, 14001);
  constexpr double kThesisEpsilon = 1e-12;  // Table 3.1 / §4.2 reference accuracy
  std::vector<double> plain;
  for (const double e : {1e6, 1e9}) {
    incise::scene::SceneSpec spec = scene_with("linear", e);
    incise::scene::BuiltScene built = incise::scene::build_scene(spec);
    incise::fem::ElasticProblem& p = *built.problem;
    VecX u = VecX::Zero(p.size());
    incise::solver::LinearCgOptions o;
    o.stop.rule = incise::solver::ResidualRule::kExternalForce;
    o.stop.epsilon = kThesisEpsilon;
    o.budget.max_iterations = spec.solver.max_iterations;
    const incise::solver::SolverReport rep = incise::solver::linear_cg(p, u, o);
    plain.push_back(true_relative_residual(p, u));
    std::printf("linear E = %.0e: CG %-10s %4ld iterations, true |r|/|f| = %.2e\n", e,
                incise::solver::to_string(rep.status), rep.iterations, plain.back());
    // CG restarted on the true residual (iterative refinement through the public API) until
    // the residual stops falling; five restarts is more than it ever needs (two or three).
    double best = plain.back();
    for (int restart = 0; restart < 5; ++restart) {
      VecX v = u;
      (void)incise::solver::linear_cg(p, v, o);
      const double r = true_relative_residual(p, v);
      if (!(r < best)) break;
      best = r;
      u = v;
    }
    const double floor = rounding_floor(p, u, rng);
    std::printf("  restarted: true |r|/|f| = %.2e; rounding floor %.2e (thesis: %.0e)\n", best,
                floor, kThesisEpsilon);
    // Within 2× of the floor: the floor estimate's ½-ulp perturbation is 1–2× the size of a
    // correct rounding, and CG stops within the noise of its own last correction.
    EXPECT_LE(best, 2.0 * floor) << "E = " << e;
    // Plain CG confirms convergence on the true residual (residual replacement, linear_cg.hpp),
    // so it reaches the same floor by itself (measured 1.55e-12 and 1.49e-12; before residual
    // replacement it stopped at the recursive residual's drift, 2.2e-11). It reports
    // `stagnated`, honestly: the thesis' 1e-12 is below this mesh's rounding floor.
    EXPECT_LE(plain.back(), 2.0 * floor) << "E = " << e;
  }
  // K ∝ E and u ∝ 1/E: with a scale-free kernel the relative residual of plain CG depends on E
  // only through rounding patterns (measured 1.55e-12 vs 1.49e-12); the old kernels gave
  // 2.7e-11 vs 1.5e-8. Factor 3: two realizations of the same rounding floor.
  EXPECT_LE(plain[1], 3.0 * plain[0]);
  EXPECT_LE(plain[0], 3.0 * plain[1]);
}

TEST(CantileverSceneConvergence, NewtonStvkAndNeoHookeanReach1e10) {
  constexpr double kEpsilon = 1e-10;
  for (const char* model : {"stvk", "neohookean"})
    for (const double e : {1e6, 1e9}) {
      const incise::scene::SceneSpec spec = scene_with(model, e);
      incise::scene::BuiltScene built = incise::scene::build_scene(spec);
      incise::fem::ElasticProblem& p = *built.problem;
      VecX u = VecX::Zero(p.size());
      incise::solver::TruncatedNewtonOptions o;
      o.stop.rule = incise::solver::ResidualRule::kExternalForce;
      o.stop.epsilon = kEpsilon;
      // Newton needs 9–11 steps here; the cap only keeps a regression from running the scene's
      // 20000-step budget (7 min with the old kernels) before failing.
      o.budget.max_iterations = std::min(spec.solver.max_iterations, 200);
      o.preconditioner = spec.solver.preconditioner;
      const incise::solver::SolverReport rep = incise::solver::truncated_newton(p, u, o);
      const double r = true_relative_residual(p, u);
      std::printf("%-10s E = %.0e: Newton %-10s %3ld iterations (%5ld inner), |r|/|f| = %.2e\n",
                  model, e, incise::solver::to_string(rep.status), rep.iterations,
                  rep.inner_iterations, r);
      EXPECT_EQ(rep.status, incise::solver::StopReason::kConverged) << model << " E = " << e;
      EXPECT_LE(r, kEpsilon) << model << " E = " << e;
    }
}

}  // namespace
