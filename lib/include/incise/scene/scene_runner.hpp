#pragma once
/// \file scene_runner.hpp
/// Runs the solver a scene names on its built problem and evaluates its probes.
///
/// Method → solver (module solver): "cg" → linear_cg (§3.1, stopping rule ‖r‖ ≤ ε‖f_ext‖);
/// "nonlinear-cg" → nonlinear_cg (§2.4.2, secant line search, Polak–Ribière); "newton" →
/// truncated_newton (§2.4.3); "dynamic-ss22" → dynamic_relaxation (§2.5) with Δt and η given
/// or estimated (§4.1: Δt = 0.9·2/√λ_max, η = 2√λ₁, or η from the FFT of an undamped run when
/// spectral_tuning is set; dynamic_parameters(): from a Lanczos run that stopped at its step
/// limit only when θ_max settled, named "not converged");
/// "augmented" → CHOLMOD factorization of the assembled K (fixed DOFs
/// as identity rows) and one direct solve, the initial system of the augmented method
/// (Yeung et al. 2016 §3). "augmented" with tools → an interactive cutting run
/// (interactive::AugmentedCutSession): K⁰ of the uncut body is factored once, then every sweep
/// triangle is cut (thesis §3.2) and the static solution updated by the augmented solver — element
/// stiffness changes and new DOFs as replaced columns, GMRES on the Schur system — without
/// refactorization; the per-step m, GMRES iterations and update times are returned as
/// SceneRunResult::cut_steps. A `slab2d` scene is a needle insertion (thesis §6.7): one
/// needle::NeedleInsertion::step per planned update (BuiltScene::needle_plan), each a row of
/// SceneRunResult::needle_updates; the run stops at the first update whose status is not ok
/// (kSolverFailed: report status = the failed solve's StopReason; kRearrangementCycle:
/// kMaxIterations, the stick–slip cap), the message naming the update and the needle status.
/// Parts built on the way (eigenvalue estimates, FFT, factorization) are
/// recorded in BuiltScene::steps with their cost.

#include <incise/core/environment.hpp>
#include <incise/core/outcome.hpp>
#include <incise/scene/scene_builder.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/report.hpp>

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace incise::interactive {
class AugmentedCutSession;
}  // namespace incise::interactive

namespace incise::scene {

/// A probe's final value.
struct ProbeResult {
  std::string name;
  Vec3 value = Vec3::Zero();      ///< mean displacement over the probe's nodes (m)
  std::optional<Vec3> reference;  ///< expected value from the scene, if given (m)
  std::string note;               ///< the probe's `note` from the scene ("" = none)
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
  double cpu_seconds = 0.0;  ///< process CPU seconds of the solver so far (all threads)
  /// ‖u − û‖_{K(û)}/‖û‖_{K(û)} against the run's reference û (run_scene's `reference`); NaN
  /// without one (issue 19: time to a relative energy-norm error from the command line)
  double relative_energy_error = std::numeric_limits<double>::quiet_NaN();
  std::vector<Vec3> probes;  ///< probe values at this iteration (m)
};

/// One solve of an interactive cutting run ("augmented" with tools): the initial factorization
/// and solve (step 0), then one row per path segment or per sweep triangle (`solve_every`).
struct CutStepRow {
  int step = 0;                     ///< 0: initial solve; k ≥ 1: the k-th solve after it
  int tool = -1;                    ///< index into SceneSpec::tools (−1 for step 0)
  int triangles = 0;                ///< sweep triangles cut before this solve (0, 1 or 2)
  std::string status;               ///< "ok" or the interactive::CutSolveStatus name (+ advice)
  bool degenerate_sweep = false;    ///< the cutter skipped a zero-area sweep triangle
  Index faces_dissected = 0;        ///< faces dissected by this step (§3.2)
  Index nodes_snapped = 0;          ///< nodes snapped onto the sweep (§3.2.2)
  Index new_nodes = 0;              ///< nodes created by this step
  Index nodes = 0, tetrahedra = 0;  ///< mesh size after the step (nodes incl. unused; live tets)
  int m = 0;                        ///< replaced columns |𝓛| after the step (Yeung et al. §3)
  int dirichlet = 0;                ///< |𝓓|: constrained DOFs among them
  int gmres_iterations = 0;         ///< GMRES iterations on the Schur system (eq. 17)
  double gmres_relative_residual = 0;  ///< its relative residual at exit
  /// GMRES ran unpreconditioned: the preconditioner's LU was numerically singular
  /// (linalg::AugmentedReport::preconditioner_dropped)
  bool preconditioner_dropped = false;
  /// rcond estimate of the preconditioner's LU (linalg::AugmentedReport::preconditioner_rcond;
  /// NaN: none built)
  double preconditioner_rcond = std::numeric_limits<double>::quiet_NaN();
  /// amplification of the solution (linalg::AugmentedReport::amplification, ≤ κ(K)); 0 when
  /// the step did not solve
  double amplification = 0;
  /// amplification above linalg::AugmentedOptions::warn_amplification: digits may be lost
  bool amplification_warning = false;
  std::int64_t nnz_l = 0;                ///< |L| of the factor in use (changes at a swap)
  bool refactorization_started = false;  ///< §3.6 job started after this solve (refactor_at_m)
  bool refactorization_swapped = false;  ///< this solve swapped in a finished job (m dropped)
  double seconds_cut = 0;                ///< wall time of the cut (Cutter::step)
  double seconds_update = 0;             ///< wall time of column replacements + augmented solve
  double seconds_swap = 0;               ///< of seconds_update: swapping in a finished §3.6 factor
  double cpu_seconds_update = 0;         ///< thread CPU time of the same
  std::vector<Vec3> probes;              ///< probe values after the step (m)
};

/// One update of a needle scene (needle::StepReport with where the needle was).
struct NeedleUpdateRow {
  long update = 0;          ///< index into BuiltScene::needle_plan (0: the tip at the path's start)
  double depth = 0;         ///< distance travelled by the tip along the path (m)
  Vec3 tip = Vec3::Zero();  ///< tip position (m; z = 0 in 2D)
  std::string status;       ///< "ok" or the needle::StepStatus name with the message
  int sticking = 0, slipping = 0;     ///< needle nodes in each state after the update
  int rearrangements = 0;             ///< stick–slip passes that changed a state (§6.3.2)
  int solves = 0;                     ///< CG solves (rearrangements + 1 when ok)
  long cg_iterations = 0;             ///< CG iterations over the update's solves
  long max_cg_iterations = 0;         ///< of its longest solve
  long bisections = 0;                ///< simple bisections of the refinement at the tip (§6.5)
  int intercepted = 0, released = 0;  ///< needle nodes added, released (slid off)
  Index nodes = 0, triangles = 0;     ///< mesh size after the update (3D: tetrahedra)
  /// Force the needle exerts on the material (N), needle::StepReport::needle_force; the needle
  /// feels its negative (z = 0 in 2D)
  Vec3 needle_force = Vec3::Zero();
  std::uint64_t flops = 0;  ///< counted flops of the solves
  double seconds = 0;       ///< wall time of the update (move, refine, intercept, solves)
  /// Its parts (needle::StepReportT): refinement, solves, rearrangement with interception.
  double seconds_refine = 0, seconds_solve = 0, seconds_rearrange = 0;
  /// 3D only: needle-surface faces and their area (m²) after the update (needle3d.hpp).
  int surface_faces = 0;
  double surface_area = 0;  ///< see surface_faces
  /// 3D "augmented" only (needle::SolvePath3D::kAugmented): fresh factorizations in the update
  /// and the replaced columns m of its last solve (0 otherwise).
  int factorizations = 0;
  int replaced_columns = 0;  ///< see factorizations
};

/// Outcome of run_scene().
struct SceneRunResult {
  RunEnvironment environment;      ///< machine and build, captured when run_scene started
  solver::SolverReport report;     ///< the solver's report (reason, iterations, flops, time)
  std::string method_detail;       ///< parameters actually used (e.g. Δt, η and their origin)
  VecX u;                          ///< final displacements (m)
  double external_force_norm = 0;  ///< ‖f_ext‖₂ over free DOFs (N)
  std::vector<ProbeResult> probes;
  std::vector<TraceRow> trace;  ///< one row per iteration, from the first
  bool has_reference = false;   ///< run with a reference: trace rows carry the energy error
  /// final ‖u − û‖_{K(û)}/‖û‖_{K(û)} when run with a reference, else NaN
  double relative_energy_error = std::numeric_limits<double>::quiet_NaN();
  /// Interactive cutting run only: one row per solve (initial solve first). The report then
  /// holds iterations = number of solves, inner_iterations = total GMRES iterations and the
  /// residual ‖P(K u − f)‖ recomputed matrix-free on the final cut mesh (scene.problem).
  std::vector<CutStepRow> cut_steps;
  /// Needle scenes only: one row per update run (the report then holds iterations = updates,
  /// inner_iterations = CG iterations in all, flops summed, seconds = the summed update times
  /// (without the observer's, e.g. frame writing), energy = the final elastic energy, residual
  /// NaN: every solve met (6.9), which has no single ‖f_ext‖).
  std::vector<NeedleUpdateRow> needle_updates;
  /// Elements with det F ≤ 0 at u (solver::check_inversion, §4.3.1, on scene.problem's mesh);
  /// −1 when u is not finite (not counted).
  Index inverted_elements = -1;
};

/// Called after every iteration with the solver's snapshot (u valid during the call).
using RunObserver = std::function<void(const solver::IterationInfo&)>;

/// Called after every solve of an interactive cutting run, with the row, the number of sweep
/// triangles in the run and the session (its cut mesh and displacement are those after the
/// step; valid during the call).
using CutStepObserver = std::function<void(const CutStepRow&, std::size_t total_steps,
                                           const interactive::AugmentedCutSession& session)>;

/// Called after every update of a needle scene, with the row, the number of planned updates
/// and the insertion (its mesh, displacement and needle nodes those after the update).
using NeedleUpdateObserver = std::function<void(const NeedleUpdateRow&, std::size_t total_updates,
                                                const needle::NeedleInsertion& insertion)>;
/// The same for a 3D needle scene.
using NeedleUpdateObserver3D = std::function<void(const NeedleUpdateRow&, std::size_t total_updates,
                                                  const needle::NeedleInsertion3D& insertion)>;

/// Δt and η of a "dynamic-ss22" run (thesis §4.1) and where each came from. ok(): both are
/// usable; otherwise status is that of the estimate that failed, the message names it and
/// what the scene can do, and neither value may be used.
struct [[nodiscard]] DynamicParameters : Outcome<solver::StopReason, solver::StopReason::kConverged,
                                                 solver::StopReason::kMaxIterations> {
  double time_step = 0;          ///< Δt (s)
  double damping = 0;            ///< η (1/s)
  std::string time_step_origin;  ///< "given", or the estimate and its value
  std::string damping_origin;    ///< "given", or the estimate and its value
};

/// Δt and η of scene.spec.solver at u: given values (time_step > 0, damping ≥ 0) as they
/// are; otherwise estimated from K(u) and the lumped M (§4.1) by one Lanczos run
/// (solver::estimate_dynamic_parameters with `lanczos`, target_reduction = the scene tolerance):
/// Δt = 0.9·2/√θ_max, η = 2ζ√θ₁ (ζ = solver::damping_ratio_for(tolerance / 2)) or, with
/// spectral_tuning, η = 4πf from the FFT of 8192 undamped steps at Δt. A Lanczos run that used
/// up its steps with θ_max settled gives bounds that are used (θ₁ ≥ λ₁: η over-damps; the
/// origins say "not converged"); any other estimate that did not converge is not: a Lanczos run
/// with steps exhausted before θ_max settled, indefinite or non-finite K, an undamped run that
/// did not complete (its status: unstable, inverted, non-finite) or found no oscillation
/// (kStagnated). Each estimate is recorded in
/// scene.steps. Throws UsageError for a scene whose problem was not built or has no lumped
/// mass (not dynamic).
DynamicParameters dynamic_parameters(BuiltScene& scene, const VecX& u,
                                     const solver::LanczosOptions& lanczos = {});

/// Runs the scene's solver from u = 0. Numerical failure is reported in result.report.status
/// and message, never thrown; a "dynamic-ss22" run whose Δt or η cannot be estimated
/// (dynamic_parameters() not ok) is not run: the report has that status and message, u = 0.
/// Every run ends with the same checks (issue 18): a converged report whose residual, energy or
/// displacement is not finite becomes kNonFinite; a load whose ‖f_ext‖ overflows is kNonFinite
/// from the solver (solver::external_force_is_finite); the inverted elements at u are counted
/// (result.inverted_elements) and a converged state with any becomes kInverted unless the scene
/// sets material.allow_inversion (linear and StVK only). Throws UsageError for a scene whose
/// problem was not built, and ParseError (at /solver/method, naming the estimate and the budget)
/// when the "augmented" solver's CHOLMOD factor is estimated above memory_budget_bytes(spec)
/// from its symbolic analysis — before the numeric factorization, nothing solved.
/// An interactive cutting run replaces scene.mesh, scene.fixed_nodes and scene.problem by the
/// final cut mesh, its held nodes (fixed from the start, fixed by the cutter, unused) and an
/// elastic problem on it carrying the same nodal forces (used to verify the residual).
/// A needle scene replaces scene.mesh by the final refined slab (2D; u with three components
/// per node, z = 0) or tetrahedral mesh (3D); its final check counts inverted elements
/// (deformed area or volume ≤ 0: kInverted unless material.allow_inversion) and non-finite
/// displacements (kNonFinite). A 3D needle update that hits the refinement budget
/// (needle::StepStatus::kRefinementBudget) ends the run with kMaxIterations and its message.
///
/// `reference` (optional, e.g. read_solution() of an earlier run's --write-solution): a
/// relaxation run (cg, nonlinear-cg, newton, dynamic-ss22) then records the relative
/// energy-norm error against it in every trace row (computed in the observer: one K(û)-product
/// per iteration, excluded from the solver's flops and times) and in
/// SceneRunResult::relative_energy_error. Throws UsageError when its size is not the problem's.
SceneRunResult run_scene(BuiltScene& scene, const RunObserver& observer = {},
                         const CutStepObserver& cut_observer = {},
                         const NeedleUpdateObserver& needle_observer = {},
                         const NeedleUpdateObserver3D& needle3d_observer = {},
                         const VecX* reference = nullptr);

}  // namespace incise::scene
