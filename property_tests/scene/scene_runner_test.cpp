// Scene runner, "dynamic-ss22": Δt and η come from the scene or from converged estimates of
// M⁻¹K (thesis §4.1) — an estimate that did not converge never becomes a parameter, and a run
// without usable parameters is not started but reported.

#include <incise/core/error.hpp>
#include <incise/scene/scene_parser.hpp>
#include <incise/scene/scene_runner.hpp>
#include <incise/scene/solution_file.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>
#include <Eigen/SparseCore>
#include <nlohmann/json.hpp>

#include <cmath>
#include <string>

namespace {

using namespace incise;
using Json = nlohmann::json;

/// A small clamped beam loaded at its tip, solved by dynamic relaxation with both parameters
/// estimated.
Json dynamic_beam() {
  return Json::parse(R"({
    "mesh": {"type": "box", "nx": 4, "ny": 1, "nz": 1, "lx": 1.0, "ly": 0.25, "lz": 0.25},
    "material": {"model": "linear", "E": 1e4, "nu": 0.3, "rho": 1000},
    "fixed": [{"type": "plane", "axis": "x", "value": 0.0}],
    "loads": [{"type": "nodal", "region": {"type": "plane", "axis": "x", "value": 1.0},
               "total_force": [0, 0, -0.1]}],
    "solver": {"method": "dynamic-ss22", "tolerance": 1e-6, "max_iterations": 200000}
  })");
}

scene::BuiltScene build(const Json& j) {
  return scene::build_scene(scene::parse_scene(j.dump(), "scene.json", ""));
}

bool contains(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

// With the default budget the Lanczos estimate converges, and Δt, η are the §4.1 values of its
// extreme Ritz values (η with the damping ratio of the scene's tolerance); those agree with the
// power and inverse iterations (λ_max to 1e-3, λ₁ from above to 3 %: Lanczos stops when θ₁ moved ≤
// 1 % over each of 8 steps).
TEST(DynamicParameters, ConvergedEstimatesBecomeTheParameters) {
  scene::BuiltScene b = build(dynamic_beam());
  const VecX u = VecX::Zero(b.problem->size());
  const scene::DynamicParameters dp = scene::dynamic_parameters(b, u);
  ASSERT_TRUE(dp.ok()) << dp.brief();
  const solver::DynamicParameterEstimate est = solver::estimate_dynamic_parameters(*b.problem, u);
  ASSERT_TRUE(est.ok()) << est.brief();
  EXPECT_EQ(dp.time_step, 0.9 * solver::critical_time_step(est.lambda_max));  // same computation
  // η = 2ζ√θ₁ with ζ for the scene's tolerance (the reduction its stopping rule asks for)
  EXPECT_EQ(dp.damping, solver::damping_ratio_for(0.5 * b.spec.solver.tolerance) *
                            solver::critical_damping(est.lambda_min));
  const solver::EigenEstimate big = solver::largest_eigenvalue(*b.problem, u);
  const solver::EigenEstimate small = solver::smallest_eigenvalue(*b.problem, u);
  ASSERT_TRUE(big.ok() && small.ok());
  EXPECT_NEAR(est.lambda_max, big.value, 1e-3 * big.value);
  EXPECT_GE(est.lambda_min, small.value * (1 - 1e-6));  // a Ritz value: an upper bound of λ₁
  EXPECT_LE(est.lambda_min, 1.03 * small.value);
  EXPECT_TRUE(contains(dp.time_step_origin, "lambda_max")) << dp.time_step_origin;
  const scene::SceneRunResult res = scene::run_scene(b);
  EXPECT_TRUE(res.report.ok()) << res.report.brief();
  EXPECT_TRUE(contains(res.method_detail, "dynamic relaxation SS22, dt = ")) << res.method_detail;
}

// A Lanczos budget too small to converge: the estimate's status and a message naming it, for
// Δt and, with Δt given, for η.
TEST(DynamicParameters, UnconvergedEigenvalueEstimateIsReportedNotUsed) {
  solver::LanczosOptions two;
  two.min_steps = 1;
  two.max_steps = 2;  // 2 steps cannot show 8 calm steps
  scene::BuiltScene b = build(dynamic_beam());
  const VecX u = VecX::Zero(b.problem->size());
  scene::DynamicParameters dp = scene::dynamic_parameters(b, u, two);
  EXPECT_EQ(dp.status, solver::StopReason::kMaxIterations);
  EXPECT_TRUE(contains(dp.message,
                       "time step not estimated: the Lanczos estimate of lambda_1 and lambda_max "
                       "stopped with max_iterations after 2 steps"))
      << dp.message;
  EXPECT_TRUE(contains(dp.message, "give solver.time_step")) << dp.message;

  Json j = dynamic_beam();
  j["solver"]["time_step"] = 1e-3;
  scene::BuiltScene given = build(j);
  dp = scene::dynamic_parameters(given, u, two);
  EXPECT_EQ(dp.status, solver::StopReason::kMaxIterations);
  EXPECT_EQ(dp.time_step, 1e-3);
  EXPECT_EQ(dp.time_step_origin, "given");
  EXPECT_TRUE(contains(dp.message,
                       "damping not estimated: the Lanczos estimate of lambda_1 and lambda_max "
                       "stopped with max_iterations after 2 steps"))
      << dp.message;
}

// A slender Veronda–Westmann beam (16×4×4 cubes, 0.4 m; EstimateOnSlenderBeam): θ₁ does not
// pass its test in the default 400 Lanczos steps, θ_max has settled. The scene uses the bounds
// (Δt from θ_max, η from θ₁ ≥ λ₁) and names them "not converged" (before: no parameters, the
// run refused to start), §4.1.
TEST(DynamicParameters, SlenderBeamRunsOnTheUnconvergedBoundsAndSaysSo_Sec4_1) {
  Json j = Json::parse(R"({
    "mesh": {"type": "box", "nx": 16, "ny": 4, "nz": 4, "lx": 0.4, "ly": 0.1, "lz": 0.1},
    "material": {"model": "veronda-westmann", "E": 1e4, "nu": 0.3, "rho": 1000, "gamma": 8},
    "fixed": [{"type": "plane", "axis": "x", "value": 0.0}],
    "loads": [{"type": "gravity", "g": [0, 0, -9.8]}],
    "solver": {"method": "dynamic-ss22", "tolerance": 1e-3, "max_iterations": 100000}
  })");
  scene::BuiltScene b = build(j);
  const VecX u = VecX::Zero(b.problem->size());
  const scene::DynamicParameters dp = scene::dynamic_parameters(b, u, solver::LanczosOptions{});
  EXPECT_EQ(dp.status, solver::StopReason::kConverged) << dp.message;
  solver::DynamicParameterOptions o;
  o.target_reduction = 1e-3;
  const solver::DynamicParameterEstimate est =
      solver::estimate_dynamic_parameters(*b.problem, u, o);
  EXPECT_EQ(est.status, solver::StopReason::kMaxIterations);
  EXPECT_EQ(dp.time_step, est.time_step);
  EXPECT_EQ(dp.damping, est.damping);
  EXPECT_GT(dp.time_step, 0.0);
  EXPECT_TRUE(contains(dp.time_step_origin, "not converged: lambda_1 not converged in 400"))
      << dp.time_step_origin;
  EXPECT_TRUE(contains(dp.damping_origin, "an upper bound: not converged")) << dp.damping_origin;
  const scene::SceneRunResult res = scene::run_scene(b);
  EXPECT_TRUE(res.report.ok()) << res.report.brief();
}

// Spectral tuning at a time step 20× the critical one: the undamped run blows up, so there is
// no frequency, and run_scene does not start the relaxation with η = 0 but reports why
// (before: η = 0 was used silently and the damped run blew up after its own steps).
TEST(DynamicParameters, FailedSpectralEstimateStopsTheRunBeforeItStarts) {
  scene::BuiltScene probe = build(dynamic_beam());
  const solver::EigenEstimate big =
      solver::largest_eigenvalue(*probe.problem, VecX::Zero(probe.problem->size()));
  ASSERT_TRUE(big.ok());
  Json j = dynamic_beam();
  j["solver"]["time_step"] = 20 * solver::critical_time_step(big.value);
  j["solver"]["spectral_tuning"] = true;
  scene::BuiltScene b = build(j);
  const scene::SceneRunResult res = scene::run_scene(b);
  EXPECT_EQ(res.report.status, solver::StopReason::kUnstable) << res.report.brief();
  EXPECT_TRUE(contains(res.report.message,
                       "damping not estimated: the undamped run for its spectrum stopped with "
                       "unstable"))
      << res.report.message;
  EXPECT_EQ(res.report.iterations, 0);
  EXPECT_EQ(res.u, VecX::Zero(b.problem->size()));
  EXPECT_EQ(res.report.residual_norm, res.external_force_norm);  // of u = 0
  EXPECT_TRUE(res.trace.empty());
  EXPECT_TRUE(contains(res.method_detail, "dynamic relaxation SS22 not run: damping not"))
      << res.method_detail;
}

// Issue 19: write a solution, read it back exactly, and measure a later run against it: the
// trace carries ‖u − û‖_K/‖û‖_K per iteration and CPU seconds; a run that reproduces the
// reference bit for bit ends at error 0, a looser one strictly between 0 and 1.
TEST(SceneReference, RelativeEnergyErrorPerIterationAgainstAnEarlierRun) {
  Json j = dynamic_beam();
  j["solver"] = {{"method", "cg"}, {"tolerance", 1e-10}, {"max_iterations", 10000}};
  scene::BuiltScene ref_scene = build(j);
  const scene::SceneRunResult ref = scene::run_scene(ref_scene);
  ASSERT_TRUE(ref.report.ok()) << ref.report.brief();
  EXPECT_GT(ref.report.cpu_seconds, 0.0);
  const std::string path = ::testing::TempDir() + "scene_reference_solution.txt";
  scene::write_solution(path, ref.u);
  const VecX back = scene::read_solution(path);
  EXPECT_EQ(back, ref.u);  // 17 significant digits: exact

  scene::BuiltScene same = build(j);
  const scene::SceneRunResult again = scene::run_scene(same, {}, {}, {}, {}, &back);
  ASSERT_TRUE(again.has_reference);
  EXPECT_EQ(again.relative_energy_error, 0.0);
  ASSERT_FALSE(again.trace.empty());
  EXPECT_GT(again.trace.front().relative_energy_error, 0.0);
  EXPECT_LE(again.trace.front().relative_energy_error, 1.0);  // CG minimizes the energy error
  for (std::size_t k = 1; k < again.trace.size(); ++k) {
    // CG decreases the energy-norm error monotonically (§2.4.1); 1e-12 allows round-off
    EXPECT_LE(again.trace[k].relative_energy_error,
              again.trace[k - 1].relative_energy_error * (1 + 1e-12) + 1e-15)
        << k;
    EXPECT_GE(again.trace[k].cpu_seconds, again.trace[k - 1].cpu_seconds);
  }

  j["solver"]["tolerance"] = 1e-3;
  scene::BuiltScene loose = build(j);
  const scene::SceneRunResult l = scene::run_scene(loose, {}, {}, {}, {}, &back);
  EXPECT_GT(l.relative_energy_error, 0.0);
  EXPECT_LT(l.relative_energy_error, 1.0);
  EXPECT_EQ(l.relative_energy_error, l.trace.back().relative_energy_error);

  const VecX wrong = VecX::Zero(3);
  scene::BuiltScene w = build(j);
  EXPECT_THROW((void)scene::run_scene(w, {}, {}, {}, {}, &wrong), UsageError);
  EXPECT_THROW((void)scene::read_solution(path + ".missing"), ParseError);
  VecX nan = ref.u;
  nan[0] = std::nan("");
  EXPECT_THROW(scene::write_solution(path, nan), ParameterError);
}

// Issue 19: relaxation scenes of the linear material multiply by the assembled K unless the scene
// says "assembled_product": false (docs/scenes.md, `solver`); SS22 then runs the gradient
// recurrence (one K·d per step). Both ways converge, to the same solution within the bound
// the stopping rule gives: ‖r‖ ≤ ε‖f‖ for each, so ‖u_a − u_m‖ ≤ 2ε‖f‖/λ_min(K) (λ_min from a
// dense eigensolve of K with the fixed DOFs as identity rows, which can only lower it).
TEST(SceneAssembledProduct, DefaultForLinearRelaxationSameSolutionAsMatrixFree) {
  constexpr double kEps = 1e-9;
  for (const char* method : {"cg", "nonlinear-cg", "newton", "dynamic-ss22"}) {
    Json j = dynamic_beam();
    j["solver"] = {{"method", method}, {"tolerance", kEps}, {"max_iterations", 200000}};
    scene::BuiltScene assembled = build(j);
    EXPECT_TRUE(assembled.problem->assembled_product()) << method;
    j["solver"]["assembled_product"] = false;
    scene::BuiltScene matrix_free = build(j);
    EXPECT_FALSE(matrix_free.problem->assembled_product()) << method;
    bool noted = false;
    for (const std::string& s : matrix_free.not_built)
      noted |= contains(s, "\"assembled_product\": false");
    EXPECT_TRUE(noted) << method;
    const scene::SceneRunResult a = scene::run_scene(assembled);
    const scene::SceneRunResult m = scene::run_scene(matrix_free);
    ASSERT_TRUE(a.report.ok()) << method << ": " << a.report.brief();
    ASSERT_TRUE(m.report.ok()) << method << ": " << m.report.brief();
    if (std::string(method) == "dynamic-ss22") {
      EXPECT_GT(a.report.inner_iterations, 0) << "K-products of the recurrence";
      EXPECT_EQ(m.report.inner_iterations, 0);
      EXPECT_TRUE(contains(a.method_detail, "gradient recurrence on the assembled K"))
          << a.method_detail;
    }
    Eigen::SparseMatrix<double> k;
    ASSERT_EQ(matrix_free.problem->tangent(VecX::Zero(matrix_free.problem->size()), k),
              EvalStatus::kOk);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig{Eigen::MatrixXd(k)};
    const double lambda_min = eig.eigenvalues().minCoeff();
    ASSERT_GT(lambda_min, 0.0);
    const double bound = 2.0 * kEps * matrix_free.problem->external_force_norm() / lambda_min;
    EXPECT_LE((a.u - m.u).norm(), bound) << method << ", |u| = " << m.u.norm();
  }
  // Not for the nonlinear materials (their K depends on u): matrix-free, nothing noted.
  Json vw = dynamic_beam();
  vw["material"] = {
      {"model", "veronda-westmann"}, {"E", 1e4}, {"nu", 0.3}, {"rho", 1000}, {"gamma", 8.0}};
  vw["solver"] = {{"method", "nonlinear-cg"}};
  EXPECT_FALSE(build(vw).problem->assembled_product());
}

// Over the memory budget the default falls back to matrix-free products (noted), an explicit
// true is refused with the file, line and key. On the 8³ Kuhn box (729 nodes, 3072 tets, 4184
// edges) mesh and problem take ≈ 0.7 MiB and the assembled K ≈ 1.85 MiB more, so a 1 MiB budget
// separates them and 3 MiB holds both.
TEST(SceneAssembledProduct, OverTheMemoryBudgetDefaultFallsBackExplicitIsRefused) {
  Json j = dynamic_beam();
  j["mesh"] = Json::parse(
      R"({"type": "box", "nx": 8, "ny": 8, "nz": 8, "lx": 1, "ly": 1, "lz": 1, "split": "kuhn"})");
  j["solver"] = {{"method", "cg"}};
  j["limits"] = {{"memory_mb", 1}};
  scene::BuiltScene b = build(j);
  EXPECT_FALSE(b.problem->assembled_product());
  bool noted = false;
  for (const std::string& s : b.not_built) noted |= contains(s, "would exceed the memory budget");
  EXPECT_TRUE(noted);
  j["limits"]["memory_mb"] = 3;  // fits: the default is on again
  EXPECT_TRUE(build(j).problem->assembled_product());
  j["limits"]["memory_mb"] = 1;
  j["solver"]["assembled_product"] = true;
  try {
    (void)build(j);
    ADD_FAILURE() << "an explicit assembled_product over the budget was accepted";
  } catch (const ParseError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("scene.json:", 0), 0u) << what;
    EXPECT_TRUE(contains(what, ": /solver/assembled_product: the assembled K needs an estimated"))
        << what;
    EXPECT_TRUE(contains(what, "more than the memory budget of 1 MiB")) << what;
  }
}

// Issue 19 (docs/solvers.md, fifth pass): the Lanczos estimate of a "dynamic-ss22" scene's Δt and
// η multiplies by K(u) assembled once only when that K fits the memory budget beside mesh and
// problem (the sizes of OverTheMemoryBudgetDefaultFallsBackExplicitIsRefused: 1 MiB separates,
// 3 MiB holds both); the build step names which way it ran, and both give the same Ritz values
// up to the rounding Lanczos without reorthogonalization amplifies (1e-6 relative; the 1 %
// stopping tolerance dwarfs it).
TEST(SceneLanczos, AssembledKOnlyWithinTheMemoryBudget) {
  Json j = dynamic_beam();
  j["mesh"] = Json::parse(
      R"({"type": "box", "nx": 8, "ny": 8, "nz": 8, "lx": 1, "ly": 1, "lz": 1, "split": "kuhn"})");
  j["material"] = {
      {"model", "veronda-westmann"}, {"E", 1e4}, {"nu", 0.3}, {"rho", 1000}, {"gamma", 8.0}};
  j["solver"] = {{"method", "dynamic-ss22"}};
  const auto estimate = [&](int memory_mb, bool& assembled) {
    j["limits"] = {{"memory_mb", memory_mb}};
    scene::BuiltScene b = build(j);
    assembled = b.lanczos_assembled;
    const scene::DynamicParameters dp = scene::dynamic_parameters(b, VecX::Zero(b.problem->size()));
    EXPECT_EQ(dp.status, solver::StopReason::kConverged);
    bool named = false;
    for (const scene::BuildStep& s : b.steps) {
      if (!contains(s.what, "Lanczos") ||
          !contains(s.what, assembled ? "by K(u) assembled once" : "matrix-free"))
        continue;
      named = true;
      // The step's memory: 5 Lanczos vectors, plus the assembled K's estimate when assembled.
      const std::size_t vectors = 5 * static_cast<std::size_t>(b.problem->size()) * sizeof(double);
      EXPECT_EQ(s.bytes, vectors + (assembled ? b.lanczos_assembled_bytes : 0));
      EXPECT_EQ(b.lanczos_assembled_bytes > 0, assembled);
    }
    EXPECT_TRUE(named) << memory_mb << " MiB";
    return dp;
  };
  bool small = true, large = false;
  const scene::DynamicParameters m = estimate(1, small);
  const scene::DynamicParameters a = estimate(3, large);
  EXPECT_FALSE(small);
  EXPECT_TRUE(large);
  EXPECT_NEAR(a.time_step, m.time_step, 1e-6 * m.time_step);
  EXPECT_NEAR(a.damping, m.damping, 1e-6 * m.damping);
}

// Scene key `energy_every` (issue 19, docs/solvers.md "Ninth pass"): by default SS22 evaluates
// Π on every 4th step (the trace's other rows carry NaN, a blank CSV cell), `"energy_every": 1`
// on every step; the steps themselves do not depend on it (no restart here: same count, same
// u bitwise), the reported Π is evaluated either way, and 0 or a static method is refused.
TEST(SceneEnergyEvery, DefaultEveryFourthStepKeyOneEveryStepSameRun) {
  Json j = dynamic_beam();
  j["material"] = {
      {"model", "veronda-westmann"}, {"E", 1e4}, {"nu", 0.3}, {"rho", 1000}, {"gamma", 8.0}};
  j["solver"]["tolerance"] = 1e-4;
  scene::BuiltScene b4 = build(j);
  const scene::SceneRunResult every4 = scene::run_scene(b4);
  j["solver"]["energy_every"] = 1;
  scene::BuiltScene b1 = build(j);
  const scene::SceneRunResult every1 = scene::run_scene(b1);
  ASSERT_TRUE(every4.report.ok() && every1.report.ok()) << every4.report.brief();
  ASSERT_EQ(every4.report.restarts, 0);
  EXPECT_EQ(every4.report.iterations, every1.report.iterations);
  EXPECT_EQ(every4.u, every1.u);
  EXPECT_EQ(every4.report.energy, every1.report.energy);
  ASSERT_EQ(every4.trace.size(), every1.trace.size());
  ASSERT_GT(every4.trace.size(), 40U);
  long with4 = 0;
  for (std::size_t i = 0; i < every4.trace.size(); ++i) {
    EXPECT_TRUE(std::isfinite(every1.trace[i].energy)) << "row " << i;
    if (std::isfinite(every4.trace[i].energy)) {
      ++with4;
      EXPECT_EQ(every4.trace[i].energy, every1.trace[i].energy) << "row " << i;
    }
  }
  // Steps 4, 8, ... (the trace starts at step 1) and the converged last one.
  const long rows = static_cast<long>(every4.trace.size());
  EXPECT_GE(with4, rows / 4);
  EXPECT_LE(with4, rows / 4 + 1);
  j["solver"]["energy_every"] = 0;
  EXPECT_THROW((void)build(j), ParseError);
  j["solver"] = {{"method", "cg"}, {"energy_every", 2}};
  EXPECT_THROW((void)build(j), ParseError);
}

}  // namespace
