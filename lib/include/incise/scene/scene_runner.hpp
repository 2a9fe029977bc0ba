#pragma once
/// \file scene_runner.hpp
/// Runs the solver a scene names on its built problem and evaluates its probes.
///
/// Method → solver (module solver): "cg" → linear_cg (§3.1, stopping rule ‖r‖ ≤ ε‖f_ext‖);
/// "nonlinear-cg" → nonlinear_cg (§2.4.2, secant line search, Polak–Ribière); "newton" →
/// truncated_newton (§2.4.3); "dynamic-ss22" → dynamic_relaxation (§2.5) with Δt and η given
/// or estimated (§4.1: Δt = 0.9·2/√λ_max, η = 2√λ₁, or η from the FFT of an undamped run when
/// spectral_tuning is set); "augmented" → CHOLMOD factorization of the assembled K (fixed DOFs
/// as identity rows) and one direct solve, the initial system of the augmented method
/// (Yeung et al. 2016 §3). Parts built on the way (eigenvalue estimates, FFT, factorization) are
/// recorded in BuiltScene::steps with their cost.

#include <incise/scene/scene_builder.hpp>
#include <incise/solver/report.hpp>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace incise::scene {

/// A probe's final value.
struct ProbeResult {
  std::string name;
  Vec3 value = Vec3::Zero();      ///< mean displacement over the probe's nodes (m)
  std::optional<Vec3> reference;  ///< expected value from the scene, if given (m)
  /// ‖value − reference‖/‖reference‖ (NaN without reference).
  double relative_error = std::numeric_limits<double>::quiet_NaN();
};

/// One row of the iteration trace.
struct TraceRow {
  long iteration = 0;
  double residual_norm = 0.0;  ///< ‖r‖₂ (N)
  double energy = 0.0;         ///< Π (J)
  std::uint64_t flops = 0;
  double seconds = 0.0;
  std::vector<Vec3> probes;  ///< probe values at this iteration (m)
};

/// Outcome of run_scene().
struct SceneRunResult {
  solver::SolverReport report;     ///< the solver's report (reason, iterations, flops, time)
  std::string method_detail;       ///< parameters actually used (e.g. Δt, η and their origin)
  VecX u;                          ///< final displacements (m)
  double external_force_norm = 0;  ///< ‖f_ext‖₂ over free DOFs (N)
  std::vector<ProbeResult> probes;
  std::vector<TraceRow> trace;  ///< one row per iteration (initial state first)
};

/// Called after every iteration with the solver's snapshot (u valid during the call).
using RunObserver = std::function<void(const solver::IterationInfo&)>;

/// Runs the scene's solver from u = 0. Numerical failure is reported in result.report.reason,
/// never thrown. Throws UsageError only for a scene whose problem was not built.
SceneRunResult run_scene(BuiltScene& scene, const RunObserver& observer = {});

}  // namespace incise::scene
