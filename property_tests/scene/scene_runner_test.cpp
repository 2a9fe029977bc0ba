// Scene runner, "dynamic-ss22": Δt and η come from the scene or from converged estimates of
// M⁻¹K (thesis §4.1) — an estimate that did not converge never becomes a parameter, and a run
// without usable parameters is not started but reported.

#include <incise/scene/scene_parser.hpp>
#include <incise/scene/scene_runner.hpp>
#include <incise/solver/eigen_estimates.hpp>

#include <gtest/gtest.h>
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

// With the default budgets both estimates converge, and Δt, η are the §4.1 values of them.
TEST(DynamicParameters, ConvergedEstimatesBecomeTheParameters) {
  scene::BuiltScene b = build(dynamic_beam());
  const VecX u = VecX::Zero(b.problem->size());
  const scene::DynamicParameters dp = scene::dynamic_parameters(b, u);
  ASSERT_TRUE(dp.ok()) << dp.brief();
  const solver::EigenEstimate big = solver::largest_eigenvalue(*b.problem, u);
  const solver::EigenEstimate small = solver::smallest_eigenvalue(*b.problem, u);
  ASSERT_TRUE(big.ok() && small.ok());
  EXPECT_EQ(dp.time_step, 0.9 * solver::critical_time_step(big.value));  // same computation
  EXPECT_EQ(dp.damping, solver::critical_damping(small.value));
  EXPECT_TRUE(contains(dp.time_step_origin, "lambda_max")) << dp.time_step_origin;
  const scene::SceneRunResult res = scene::run_scene(b);
  EXPECT_TRUE(res.report.ok()) << res.report.brief();
  EXPECT_TRUE(contains(res.method_detail, "dynamic relaxation SS22, dt = ")) << res.method_detail;
}

// An eigenvalue budget too small to converge: the estimate's status and a message naming it,
// for Δt (power iteration) and, with Δt given, for η (inverse iteration).
TEST(DynamicParameters, UnconvergedEigenvalueEstimateIsReportedNotUsed) {
  solver::EigenOptions two;
  two.max_iterations = 2;  // relative change after 2 steps is far above the 1e-6 tolerance
  scene::BuiltScene b = build(dynamic_beam());
  const VecX u = VecX::Zero(b.problem->size());
  scene::DynamicParameters dp = scene::dynamic_parameters(b, u, two);
  EXPECT_EQ(dp.status, solver::StopReason::kMaxIterations);
  EXPECT_TRUE(contains(dp.message,
                       "time step not estimated: the power iteration for lambda_max stopped "
                       "with max_iterations after 2 iterations"))
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
                       "damping not estimated: the inverse iteration for lambda_1 stopped with "
                       "max_iterations after 2 iterations"))
      << dp.message;
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

}  // namespace
