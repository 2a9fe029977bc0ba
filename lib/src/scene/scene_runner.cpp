#include <incise/scene/scene_runner.hpp>

#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/material/material.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/energy_error.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>
#include <incise/solver/truncated_newton.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <type_traits>

namespace incise::scene {

namespace {

/// Safety factor on the critical time step 2/√λ_max: the power-iteration Rayleigh quotient
/// underestimates λ_max, so 2/√value overestimates the critical step (eigen_estimates.hpp).
constexpr double kTimeStepSafety = 0.9;
/// Restarts of a dynamic relaxation run after unstable steps (each lowers Δt by 0.7, so 8 allow
/// Δt down to 0.058× the estimate), solver::DynamicRelaxationOptions::max_restarts.
constexpr int kMaxRestarts = 8;
/// Undamped SS22 steps sampled for the spectral damping estimate (FFT length).
constexpr long kSpectralSteps = 8192;

/// A factorization refused by the memory budget (linalg::FactorStatus::kOverMemoryBudget):
/// the scene asked for more than its budget, refused like the mesh estimate (build_scene) with a
/// ParseError at /solver/method, before anything was solved or written.
[[noreturn]] void factor_budget_error(const SceneSpec& spec, const std::string& what) {
  throw ParseError(
      spec.file, spec.lines.line("/solver/method"),
      "/solver/method: \"augmented\" needs " + what + " (" + memory_budget_origin(spec) + ")");
}

solver::SolverReport solve_augmented(BuiltScene& scene, VecX& u) {
  fem::ElasticProblem& p = *scene.problem;
  solver::SolverReport rep;
  Timer t;
  const std::uint64_t flops0 = p.flops();
  const VecX zero = VecX::Zero(p.size());
  if (p.assemble_tangent(zero, fem::FixedDofTreatment::kIdentity) != EvalStatus::kOk) {
    rep.status = solver::StopReason::kInverted;
    return rep;
  }
  const auto& k = p.tangent_matrix();
  linalg::CholmodOptions co;
  co.memory_budget_bytes = memory_budget_bytes(scene.spec);
  linalg::CholmodFactor factor(co);
  const linalg::FactorStatus st = factor.compute(k, 1);
  if (st == linalg::FactorStatus::kOverMemoryBudget)
    factor_budget_error(scene.spec, "the CHOLMOD factor of K (" + std::to_string(k.rows()) +
                                        " DOFs): " + factor.message());
  scene.record(
      "sparse stiffness K (" + std::to_string(k.rows()) + " DOFs, " + std::to_string(k.nonZeros()) +
          " nonzeros) and CHOLMOD factor (|L| = " + std::to_string(factor.nnz_l()) +
          "; flops as estimated by CHOLMOD)",
      t.seconds(),
      static_cast<std::size_t>(k.nonZeros() + factor.nnz_l()) * (sizeof(double) + sizeof(int)),
      static_cast<std::int64_t>(factor.factor_flops()));
  rep.flops = p.flops() - flops0 + static_cast<std::uint64_t>(factor.factor_flops());
  if (st != linalg::FactorStatus::kOk) {  // a CHOLMOD warning (kTinyPivot) is a failure too
    rep.status =
        st == linalg::FactorStatus::kNotPositiveDefinite || st == linalg::FactorStatus::kTinyPivot
            ? solver::StopReason::kIndefinite
            : solver::StopReason::kNonFinite;
    rep.message = std::string("CHOLMOD factorization of K: ") + linalg::to_string(st) + ": " +
                  factor.message();
    rep.seconds = t.seconds();
    return rep;
  }
  VecX rhs = p.external_force();
  p.project(rhs);
  VecX x;
  if (factor.solve(rhs, x) != linalg::FactorStatus::kOk || !x.allFinite()) {
    rep.status = solver::StopReason::kNonFinite;
    rep.message = "the CHOLMOD solve of K u = f gave a non-finite u (" + factor.message() + ")";
    rep.seconds = t.seconds();
    return rep;
  }
  p.project(x);
  u = x;
  VecX g;
  double energy = 0;
  const EvalStatus es = p.gradient(u, g, &energy);
  p.project(g);
  rep.iterations = 1;
  rep.residual_norm = g.norm();
  rep.energy = energy;
  rep.threshold = scene.spec.solver.tolerance * p.external_force_norm();
  rep.residual_history = {p.external_force_norm(), rep.residual_norm};
  rep.energy_history = {0.0, energy};
  rep.status = es != EvalStatus::kOk                ? solver::StopReason::kNonFinite
               : rep.residual_norm <= rep.threshold ? solver::StopReason::kConverged
                                                    : solver::StopReason::kStagnated;
  if (es != EvalStatus::kOk)
    rep.message = "the residual or energy at the direct solution is not finite";
  rep.flops = p.flops() - flops0 + static_cast<std::uint64_t>(factor.factor_flops());
  rep.seconds = t.seconds();
  return rep;
}

/// Stop reason of a failed interactive step (interactive::CutSolveStatus → solver::StopReason).
solver::StopReason stop_reason_of(const interactive::AugmentedCutStepReport& r) {
  switch (r.status) {
    case interactive::CutSolveStatus::kOk: return solver::StopReason::kConverged;
    case interactive::CutSolveStatus::kFreeComponent: return solver::StopReason::kIndefinite;
    case interactive::CutSolveStatus::kInvertedElement: return solver::StopReason::kInverted;
    case interactive::CutSolveStatus::kSolverFailed: break;
  }
  switch (r.solve.status) {
    case linalg::AugmentedStatus::kGmresNotConverged: return solver::StopReason::kMaxIterations;
    case linalg::AugmentedStatus::kNonFinite: return solver::StopReason::kNonFinite;
    default: return solver::StopReason::kIndefinite;  // singular modified K, or no factor
  }
}

/// Memory held by a mesh's point and cell arrays (bytes).
std::size_t matrix_bytes_of(const mesh::MeshData& m) {
  return static_cast<std::size_t>(m.points.size()) * sizeof(double) +
         static_cast<std::size_t>(m.cells.size()) * sizeof(Index);
}

VecX displacement_vector(const Eigen::Matrix3Xd& d) {
  return Eigen::Map<const VecX>(d.data(), d.size());
}

/// "augmented" with tools: the interactive cutting run (scene_runner.hpp).
void run_augmented_cut(BuiltScene& scene, SceneRunResult& res, const CutStepObserver& observer,
                       std::ostringstream& detail) {
  const SceneSpec& spec = scene.spec;
  Timer total;
  const double cpu0 = process_cpu_seconds();  // the frames' and the background jobs' CPU
  const material::Material mat = make_material(spec.material);
  const Index n0 = scene.mesh.num_points();
  // The loads of the uncut body, held as nodal forces during the cut (new nodes carry none).
  const Eigen::Matrix3Xd forces =
      Eigen::Map<const Eigen::Matrix3Xd>(scene.external_force.data(), 3, n0);

  Timer t;
  interactive::AugmentedCutOptions options;
  options.update_deformed =
      spec.solver.cut_configuration == SolverSpec::CutConfiguration::kDeformed;
  options.refactor_at_m = spec.solver.refactor_at_m;
  // The session's automatic §3.6 policy in the scene's mode (default the session's, continuous);
  // "none" = never (docs/scenes.md).
  options.automatic_refactorization = spec.solver.refactorization.has_value();
  if (spec.solver.refactorization) options.refactorization_mode = *spec.solver.refactorization;
  options.augmented.solve_threads = spec.solver.solve_threads;
  options.augmented.schur_solver = spec.solver.schur_solver;
  options.augmented.preconditioner = spec.solver.schur_preconditioner;
  options.augmented.cholmod.memory_budget_bytes = memory_budget_bytes(spec);
  auto session = std::make_unique<interactive::AugmentedCutSession>(
      scene.mesh, mat, scene.fixed_nodes, forces, options);
  if (session->system().factorization_status() == linalg::FactorStatus::kOverMemoryBudget)
    factor_budget_error(spec, "the CHOLMOD factor of K0 (" +
                                  std::to_string(session->system().num_dofs()) +
                                  " free DOFs): " + session->system().factorization_message());
  const interactive::AugmentedCutStepReport& init = session->initial_report();
  scene.record("stiffness K0 of the uncut body (" + std::to_string(session->system().num_dofs()) +
                   " free DOFs), its CHOLMOD factor (|L| = " + std::to_string(init.solve.nnz_l) +
                   ") and the initial solve",
               t.seconds(),
               static_cast<std::size_t>(init.solve.nnz_l) * (sizeof(double) + sizeof(int)));

  // A solve per path segment (its two sweep triangles, AugmentedCutSession::frame) or per sweep
  // triangle (step), as the scene's solve_every says.
  const std::size_t per_solve = spec.solver.solve_every == SolverSpec::SolveEvery::kSegment ? 2 : 1;
  std::size_t total_steps = 0;
  for (const ToolSpec& tool : spec.tools) total_steps += sweep_triangles(tool).size() / per_solve;
  bool failed = false;
  solver::StopReason failure = solver::StopReason::kConverged;
  std::string failure_text;
  long gmres_total = 0;
  int refactorizations = 0;  // §3.6 background factorizations swapped in
  int dropped = 0;           // solves whose preconditioner was dropped (GMRES unpreconditioned)
  int amplified = 0;         // solves with an amplification warning (digits may be lost)
  double cut_seconds = 0;
  cut::CutTotals totals;
  auto add_row = [&](int step, int tool, const interactive::AugmentedCutStepReport& r) {
    CutStepRow row;
    row.step = step;
    row.tool = tool;
    row.status = r.brief();
    row.triangles = r.triangles;
    row.degenerate_sweep = r.cut.status == cut::CutStatus::kDegenerateSweep;
    row.faces_dissected = r.cut.faces_dissected;
    row.nodes_snapped = r.cut.nodes_snapped;
    row.new_nodes = static_cast<Index>(r.cut.new_nodes.size());
    row.nodes = session->mesh().num_nodes();
    row.tetrahedra = session->mesh().num_elements();
    row.m = session->system().num_replaced();
    if (r.solved) {
      row.dirichlet = r.solve.dirichlet;
      row.gmres_iterations = r.solve.gmres.iterations;
      row.gmres_relative_residual = r.solve.gmres.relative_residual;
      row.preconditioner_dropped = r.solve.preconditioner_dropped;
      row.preconditioner_rcond = r.solve.preconditioner_rcond;
      dropped += r.solve.preconditioner_dropped ? 1 : 0;
      row.amplification = r.solve.amplification;
      row.amplification_warning = r.solve.amplification_warning;
      amplified += r.solve.amplification_warning ? 1 : 0;
      row.nnz_l = r.solve.nnz_l;
      row.refactorization_started = r.refactorization_started;
      row.refactorization_swapped = r.refactorization_swapped;
      refactorizations += r.refactorization_swapped ? 1 : 0;
      row.seconds_swap = r.solve.seconds_swap;
    }
    row.seconds_cut = r.seconds_cut;
    row.seconds_update = r.seconds_update + r.seconds_solve;
    row.cpu_seconds_update = r.cpu_seconds_update;
    const VecX u = displacement_vector(session->displacement());
    for (const auto& pr : scene.probes) row.probes.push_back(probe_value(pr, u));
    gmres_total += row.gmres_iterations;
    cut_seconds += r.seconds_cut;
    if (!r.ok() && !failed) {
      failed = true;
      failure = stop_reason_of(r);
      failure_text = "step " + std::to_string(step) + ": " + row.status;
    }
    if (observer) observer(row, total_steps, *session);
    res.cut_steps.push_back(std::move(row));
  };
  add_row(0, -1, init);
  int step = 0;
  int triangles_cut = 0;
  for (std::size_t k = 0; k < spec.tools.size(); ++k) {
    const std::vector<std::array<Vec3, 3>> tris = sweep_triangles(spec.tools[k]);
    for (std::size_t i = 0; i < tris.size(); i += per_solve) {
      const interactive::AugmentedCutStepReport r = session->frame(&tris[i], per_solve);
      totals.add(r.cut);
      add_row(++step, static_cast<int>(k), r);
      triangles_cut += r.triangles;
    }
    session->end_incision();
  }

  // The final cut mesh, its held nodes and a matrix-free elastic problem carrying the same
  // nodal forces: the residual of the last augmented solution is recomputed independently.
  t.restart();
  const cut::CutMesh& cm = session->mesh();
  mesh::MeshData final_mesh = live_mesh_data(cm);
  auto check = cut_session_problem(*session, mat, forces);
  std::vector<Index> held;  // the nodes cut_session_problem fixed (all three DOFs)
  Index unused = 0;
  for (Index v = 0; v < cm.num_nodes(); ++v) {
    unused += cm.unused(v);
    if (check->is_fixed(3 * static_cast<Eigen::Index>(v))) held.push_back(v);
  }
  scene.record("cut: " + std::to_string(triangles_cut) + " sweep triangles in " +
                   std::to_string(step) + " solves, " + std::to_string(totals.faces_dissected) +
                   " faces dissected, " + std::to_string(totals.nodes_snapped) +
                   " nodes snapped, " + std::to_string(totals.collapses) + " collapses, " +
                   std::to_string(totals.new_nodes) + " new nodes, " + std::to_string(unused) +
                   " unused nodes -> " + std::to_string(final_mesh.num_cells()) + " tets, " +
                   std::to_string(final_mesh.num_points()) + " nodes",
               cut_seconds, matrix_bytes_of(final_mesh));
  res.u = displacement_vector(session->displacement());
  VecX g;
  double energy = 0;
  const EvalStatus es = check->gradient(res.u, g, &energy);
  check->project(g);
  scene.record("elastic problem on the cut mesh (residual check of the augmented solution)",
               t.seconds(),
               static_cast<std::size_t>(final_mesh.num_cells()) * sizeof(fem::TetReference));

  solver::SolverReport& rep = res.report;
  rep.iterations = static_cast<long>(res.cut_steps.size());
  rep.inner_iterations = gmres_total;
  rep.residual_norm = g.norm();
  rep.energy = energy;
  res.external_force_norm = check->external_force_norm();
  rep.threshold = spec.solver.tolerance * res.external_force_norm;
  rep.residual_history = {res.external_force_norm, rep.residual_norm};
  rep.energy_history = {0.0, energy};
  rep.status = failed                               ? failure
               : es != EvalStatus::kOk              ? solver::StopReason::kNonFinite
               : rep.residual_norm <= rep.threshold ? solver::StopReason::kConverged
                                                    : solver::StopReason::kStagnated;
  rep.seconds = total.seconds();
  rep.cpu_seconds = process_cpu_seconds() - cpu0;
  detail << "interactive cut with the augmented solver (Yeung et al. 2016 §3): K0 factored once "
            "(CHOLMOD, |L| = "
         << init.solve.nnz_l << "), then per "
         << (per_solve == 2 ? "path segment: its two sweep triangles cut" : "sweep triangle: cut")
         << " (thesis §3.2, in the " << to_string(spec.solver.cut_configuration)
         << " configuration), element stiffness changes and new DOFs as replaced columns, GMRES "
         << "on the Schur system (preconditioner: "
         << (spec.solver.schur_solver == linalg::SchurSolver::kDirectCached
                 ? "explicit H R^-1 J"
                 : linalg::to_string(spec.solver.schur_preconditioner))
         << "), step 3 on " << spec.solver.solve_threads
         << (spec.solver.solve_threads == 1 ? " thread; " : " threads; ")
         << (spec.solver.refactor_at_m > 0 ? "background refactorization (§3.6) at m - |D| >= " +
                                                 std::to_string(spec.solver.refactor_at_m) + ", " +
                                                 std::to_string(refactorizations) + " swapped in. "
             : spec.solver.refactorization
                 ? "background refactorization (§3.6), " +
                       std::string(interactive::to_string(*spec.solver.refactorization)) +
                       " policy, " + std::to_string(refactorizations) + " swapped in. "
                 : std::string("no refactorization. "))
         << step << " solves, final m = " << session->system().num_replaced() << ", " << gmres_total
         << " GMRES iterations in all"
         << (dropped > 0 ? "; preconditioner dropped (singular LU, GMRES unpreconditioned) in " +
                               std::to_string(dropped) + " solves"
                         : std::string())
         << (amplified > 0 ? "; amplification warning (digits may be lost) in " +
                                 std::to_string(amplified) + " solves"
                           : std::string())
         << (failed ? "; first failure at " + failure_text : std::string());
  scene.mesh = std::move(final_mesh);
  scene.fixed_nodes = std::move(held);
  scene.external_force = check->external_force();
  scene.problem = std::move(check);
}

/// A needle scene (2D: NeedleInsertion on a slab2d, 3D: NeedleInsertion3D): one step per
/// planned update.
template <class Insertion, class Observer>
void run_needle(BuiltScene& scene, Insertion& sim, SceneRunResult& res, const Observer& observer,
                std::ostringstream& detail) {
  constexpr bool kThreeD = std::is_same_v<Insertion, needle::NeedleInsertion3D>;
  const SceneSpec& spec = scene.spec;
  solver::SolverReport& rep = res.report;
  double update_seconds = 0;      // the updates' own time, without the observer's (frame writing)
  double update_cpu_seconds = 0;  // their process CPU time, likewise
  long cg = 0, rearrangements = 0;
  std::uint64_t flops = 0;
  rep.status = solver::StopReason::kConverged;
  for (std::size_t k = 0; k < scene.needle_plan.size(); ++k) {
    const NeedleUpdatePlan& plan = scene.needle_plan[k];
    Timer t;
    const double cpu0 = process_cpu_seconds();
    const auto r = [&] {
      if constexpr (kThreeD)
        return sim.step(plan.pose3d);
      else
        return sim.step(plan.pose);
    }();
    update_cpu_seconds += process_cpu_seconds() - cpu0;
    NeedleUpdateRow row;
    row.seconds = t.seconds();
    row.update = static_cast<long>(k);
    row.depth = plan.depth;
    if constexpr (kThreeD) {
      row.tip = plan.pose3d.tip;
      row.needle_force = r.needle_force;
    } else {
      row.tip.head<2>() = plan.pose.tip;
      row.needle_force.head<2>() = r.needle_force;
    }
    row.status = r.brief();
    row.sticking = r.sticking;
    row.slipping = r.slipping;
    row.rearrangements = r.rearrangements;
    row.solves = r.solves;
    row.cg_iterations = r.cg_iterations;
    row.max_cg_iterations = r.max_cg_iterations;
    row.bisections = r.bisections;
    row.intercepted = r.intercepted;
    row.released = r.released;
    row.nodes = sim.mesh().connectivity().num_vertices();
    row.triangles = sim.mesh().connectivity().num_elements();
    row.flops = r.flops;
    row.seconds_refine = r.refine_seconds;
    row.seconds_solve = r.solve_seconds;
    row.seconds_rearrange = r.rearrange_seconds;
    row.surface_faces = r.surface_faces;
    row.surface_area = r.surface_area;
    row.factorizations = r.factorizations;
    row.replaced_columns = r.replaced_columns;
    update_seconds += row.seconds;
    cg += r.cg_iterations;
    rearrangements += r.rearrangements;
    flops += r.flops;
    if (observer) observer(row, scene.needle_plan.size(), sim);
    res.needle_updates.push_back(std::move(row));
    if (!r.ok()) {
      rep.status = r.status == needle::StepStatus::kSolverFailed
                       ? (r.last_solver_status == solver::StopReason::kConverged
                              ? solver::StopReason::kNonFinite  // the gradient at the solution
                              : r.last_solver_status)
                       : solver::StopReason::kMaxIterations;  // stick–slip cap or budget
      std::ostringstream m;
      m << "update " << k << " of " << scene.needle_plan.size() << " (depth " << plan.depth
        << " m): " << r.brief();
      rep.message = m.str();
      break;
    }
  }
  constexpr int kD = kThreeD ? 3 : 2;
  // The final refined mesh and its displacement, three components per node (z = 0 in 2D).
  scene.mesh = sim.mesh().to_mesh_data();
  const VecX& ud = sim.displacement();
  const Eigen::Index n = ud.size() / kD;
  res.u = VecX::Zero(3 * n);
  for (Eigen::Index v = 0; v < n; ++v) res.u.segment<kD>(3 * v) = ud.segment<kD>(kD * v);
  double energy = std::numeric_limits<double>::quiet_NaN();
  if (sim.problem().energy(ud, energy) != EvalStatus::kOk)
    energy = std::numeric_limits<double>::quiet_NaN();
  rep.iterations = static_cast<long>(res.needle_updates.size());
  rep.inner_iterations = cg;
  rep.flops = flops;
  rep.energy = energy;
  rep.residual_norm = std::numeric_limits<double>::quiet_NaN();
  rep.seconds = update_seconds;
  rep.cpu_seconds = update_cpu_seconds;
  res.external_force_norm = std::numeric_limits<double>::quiet_NaN();
  // Final checks (as check_final_state for tetrahedra): finite displacement, inverted elements.
  if (!ud.allFinite()) {
    if (rep.ok()) {
      rep.status = solver::StopReason::kNonFinite;
      rep.message = "the needle run ended with a displacement that is not finite";
    }
  } else {
    const auto x = sim.deformed();
    Index inverted = 0;
    for (Eigen::Index c = 0; c < scene.mesh.cells.cols(); ++c) {
      Eigen::Matrix<double, kD, kD> e;
      for (int i = 0; i < kD; ++i)
        e.col(i) = x.col(scene.mesh.cells(i + 1, c)) - x.col(scene.mesh.cells(0, c));
      inverted += e.determinant() <= 0.0 ? 1 : 0;
    }
    res.inverted_elements = inverted;
    if (inverted > 0 && rep.ok() && !spec.material.allow_inversion) {
      rep.status = solver::StopReason::kInverted;
      rep.message = "the needle run ended with " + std::to_string(inverted) + " of " +
                    std::to_string(scene.mesh.num_cells()) +
                    (kThreeD ? " tetrahedra inverted (deformed volume <= 0)"
                             : " triangles inverted (deformed area <= 0)") +
                    ": material \"" + spec.material.model +
                    "\"; use a smaller speed, or set \"allow_inversion\": true under /material "
                    "(linear, stvk) to accept it";
    }
  }
  const auto& o = sim.options();
  detail << "needle insertion (thesis §6.7" << (kThreeD ? ", in 3D §6.9" : "")
         << "): per update move the needle, refine to h_ref = " << o.h_ref
         << " m around the tip (§6.5";
  if constexpr (kThreeD)
    detail << ", tetrahedral bisection; h_shaft = " << o.h_shaft << " m along the trace";
  detail << "), intercept needle nodes (§6.4" << (o.relocate ? ", relocated §6.8.6" : "")
         << "), solve (6.7) by "
         << (o.relaxation != needle::Relaxation::kLinearCg         ? "nonlinear"
             : o.preconditioner == solver::Preconditioner::kJacobi ? "Jacobi-preconditioned linear"
                                                                   : "linear")
         << " CG to (6.9) with eps = " << o.epsilon << ", eps_round = " << o.epsilon_round
         << ", rearrange stick/slip (§6.3.2, at most " << o.max_rearrangements << " per update); "
         << res.needle_updates.size() << " of " << scene.needle_plan.size() << " updates, "
         << rearrangements << " rearrangements, " << cg << " CG iterations in all";
}

/// "the power iteration for lambda_max stopped with max_iterations after 2000 iterations
/// (relative change 3e-05, tolerance 1e-06)" and the estimate's own message.
/// The checks every run ends with (issue 18): a "converged" report must have a finite residual,
/// energy and displacement, and no inverted element unless the scene allows inversion.
void check_final_state(const BuiltScene& scene, SceneRunResult& res) {
  solver::SolverReport& rep = res.report;
  // The direct and augmented solves have no check of their own on f_ext: an overflowing load
  // gives threshold ∞ (the iterative solvers refuse it up front). It is the cause of whatever
  // else went wrong, so its status and message replace the solve's.
  (void)solver::external_force_is_finite(res.external_force_norm, rep);
  const bool finite_u = res.u.allFinite();
  if (rep.ok() && !(finite_u && std::isfinite(rep.residual_norm) && std::isfinite(rep.energy))) {
    rep.status = solver::StopReason::kNonFinite;
    rep.message = std::string("the solver stopped as converged, but its ") +
                  (!finite_u                           ? "displacement"
                   : !std::isfinite(rep.residual_norm) ? "residual"
                                                       : "energy") +
                  " is not finite";
  }
  if (!finite_u || res.u.size() != scene.problem->size()) return;
  const solver::InversionCheck inv = solver::check_inversion(
      scene.problem->points(), scene.problem->cells(), res.u);  // §4.3.1's post-check
  res.inverted_elements = inv.inverted_elements;
  if (res.inverted_elements == 0 || !rep.ok() || scene.spec.material.allow_inversion) return;
  const bool defined = make_material(scene.spec.material).defined_when_inverted();
  std::ostringstream os;
  os << "the solver converged to a state with " << res.inverted_elements << " of "
     << scene.problem->num_elements() << " elements inverted (det F <= 0): material \""
     << scene.spec.material.model << "\" "
     << (defined ? "defines an energy there, but the state is not physical; reduce the load or "
                   "use \"neohookean\", or set \"allow_inversion\": true under /material to "
                   "accept it"
                 : "has no energy there");
  rep.status = solver::StopReason::kInverted;
  rep.message = os.str();
}

}  // namespace

DynamicParameters dynamic_parameters(BuiltScene& scene, const VecX& u,
                                     const solver::LanczosOptions& lanczos) {
  INCISE_CHECK(scene.problem != nullptr, "dynamic_parameters needs a built problem");
  const SolverSpec& s = scene.spec.solver;
  fem::ElasticProblem& p = *scene.problem;
  DynamicParameters dp;
  dp.status = solver::StopReason::kConverged;
  dp.time_step = s.time_step;
  dp.time_step_origin = "given";
  // One Lanczos run gives both λ_max (for Δt) and λ₁ (for η), §4.1.
  const bool need_lanczos = s.time_step <= 0 || (s.damping < 0 && !s.spectral_tuning);
  solver::DynamicParameterEstimate est;
  if (need_lanczos) {
    Timer t;
    solver::DynamicParameterOptions o;
    o.lanczos = lanczos;
    o.lanczos.assembled = lanczos.assembled && scene.lanczos_assembled;
    o.time_step_safety = kTimeStepSafety;
    // η's damping ratio for the reduction the run is to reach: from rest r₀ = f_ext, so the
    // stopping rule ‖r‖ ≤ tolerance·‖f_ext‖ asks for that reduction (docs/solvers.md, "Eighth
    // pass").
    if (s.tolerance > 0 && s.tolerance < 1) o.target_reduction = s.tolerance;
    est = solver::estimate_dynamic_parameters(p, u, o);
    scene.record("lambda_1 and lambda_max of M^-1 K by Lanczos (" + std::to_string(est.products) +
                     " products K.q" +
                     (o.lanczos.assembled ? " by K(u) assembled once" : " matrix-free") + ", " +
                     solver::to_string(est.status) + ")",
                 t.seconds(),
                 5 * static_cast<std::size_t>(p.size()) * sizeof(double) +
                     (o.lanczos.assembled ? scene.lanczos_assembled_bytes : 0),
                 static_cast<std::int64_t>(est.flops));
    // kMaxIterations with θ_max settled: usable bounds (θ₁ ≥ λ₁ over-damps), used and named
    // in the origins below.
    const bool bounds = est.status == solver::StopReason::kMaxIterations && est.time_step > 0;
    if (est.status != solver::StopReason::kConverged && !bounds) {
      dp.status = est.status;
      std::ostringstream os;
      os << (s.time_step <= 0 ? "time step" : "damping")
         << " not estimated: the Lanczos estimate of lambda_1 and lambda_max stopped with "
         << solver::to_string(est.status) << " after " << est.products << " steps (at most "
         << lanczos.max_steps << ", tolerance " << lanczos.tolerance << ")";
      if (!est.message.empty()) os << ": " << est.message;
      os << "; give solver.time_step and solver.damping in the scene";
      dp.message = os.str();
      return dp;
    }
  }
  // Lanczos stopped at its step limit with usable bounds (estimate_dynamic_parameters).
  const std::string unconverged =
      need_lanczos && !est.ok() ? "; not converged: " + est.message : std::string();
  if (s.time_step <= 0) {
    dp.time_step = est.time_step;
    dp.time_step_origin =
        "0.9 x critical 2/sqrt(lambda_max), lambda_max = " + std::to_string(est.lambda_max) +
        " (Lanczos, " + std::to_string(est.products) + " products" + unconverged + ")";
  }
  dp.damping = s.damping;
  dp.damping_origin = "given";
  if (s.damping >= 0) return dp;
  if (s.spectral_tuning) {
    Timer t;
    const solver::SpectralDamping sd =
        solver::damping_from_spectrum(p, u, dp.time_step, kSpectralSteps);
    scene.record("FFTW plan and spectrum of " + std::to_string(sd.steps) +
                     " undamped steps (dominant frequency " + std::to_string(sd.frequency) + " Hz)",
                 t.seconds(), 2 * static_cast<std::size_t>(kSpectralSteps) * sizeof(double),
                 static_cast<std::int64_t>(sd.flops));
    // The undamped run completes all its steps (kMaxIterations) unless it blew up, inverted
    // or turned non-finite; kConverged means u is already in equilibrium (η does not matter).
    if (sd.status == solver::StopReason::kConverged) {
      dp.damping = 0;
      dp.damping_origin = "spectral: already in equilibrium";
      return dp;
    }
    if (sd.status != solver::StopReason::kMaxIterations || !(sd.damping > 0)) {
      const bool completed = sd.status == solver::StopReason::kMaxIterations;
      dp.status = completed ? solver::StopReason::kStagnated : sd.status;
      std::ostringstream os;
      os << "damping not estimated: the undamped run for its spectrum "
         << (completed ? "showed no oscillation (dominant frequency 0) in "
                       : "stopped with " + std::string(solver::to_string(sd.status)) + " after ")
         << sd.steps << " steps at dt = " << dp.time_step
         << " s; give solver.damping in the scene, or a smaller solver.time_step";
      dp.message = os.str();
      return dp;
    }
    dp.damping = sd.damping;
    dp.damping_origin = "spectral: 4 pi f, f = " + std::to_string(sd.frequency) + " Hz";
    return dp;
  }
  dp.damping = est.damping;
  dp.damping_origin =
      "2 zeta sqrt(lambda_1), zeta = " + std::to_string(est.damping_ratio) +
      " (first overshoot = tolerance / 2), lambda_1 = " + std::to_string(est.lambda_min) +
      " (Lanczos" +
      (est.ok()           ? std::string()
       : s.time_step <= 0 ? ", an upper bound: not converged"
                          : ", an upper bound" + unconverged) +
      ")";
  return dp;
}

SceneRunResult run_scene(BuiltScene& scene, const RunObserver& observer,
                         const CutStepObserver& cut_observer,
                         const NeedleUpdateObserver& needle_observer,
                         const NeedleUpdateObserver3D& needle3d_observer, const VecX* reference) {
  SceneRunResult res;
  res.environment = capture_environment();
  if (scene.is_needle()) {
    std::ostringstream detail;
    if (scene.needle)
      run_needle(scene, *scene.needle, res, needle_observer, detail);
    else
      run_needle(scene, *scene.needle3d, res, needle3d_observer, detail);
    res.method_detail = detail.str();
    return res;
  }
  INCISE_CHECK(scene.problem != nullptr, "run_scene needs a built problem");
  const SolverSpec& s = scene.spec.solver;
  auto evaluate_probes = [&] {
    for (const auto& pr : scene.probes) {
      ProbeResult r;
      r.name = pr.spec.name;
      r.value = probe_value(pr, res.u);
      r.reference = pr.spec.reference;
      r.note = pr.spec.note;
      if (r.reference && r.reference->norm() > 0)
        r.relative_error = (r.value - *r.reference).norm() / r.reference->norm();
      res.probes.push_back(r);
    }
  };
  if (s.method == SolverSpec::Method::kAugmented && !scene.spec.tools.empty()) {
    std::ostringstream detail;
    run_augmented_cut(scene, res, cut_observer, detail);
    res.method_detail = detail.str();
    check_final_state(scene, res);
    evaluate_probes();
    return res;
  }
  fem::ElasticProblem& p = *scene.problem;
  res.u = VecX::Zero(p.size());
  res.external_force_norm = p.external_force_norm();
  // The energy norm against a reference (issue 19): (e, e)_{K(û)} by solver::EnergyErrorTrace.
  std::unique_ptr<solver::EnergyErrorTrace> error_trace;
  double reference_norm2 = 0.0;
  if (reference != nullptr) {
    INCISE_CHECK(reference->size() == p.size(),
                 "run_scene: the reference has " + std::to_string(reference->size()) +
                     " values, the problem " + std::to_string(p.size()) + " DOFs");
    error_trace = std::make_unique<solver::EnergyErrorTrace>(p, *reference);
    reference_norm2 = error_trace->energy_error(VecX::Zero(p.size()));
    INCISE_CHECK(reference_norm2 > 0.0 && std::isfinite(reference_norm2),
                 "run_scene: the reference has no positive, finite energy norm (u = 0?)");
    res.has_reference = true;
  }
  auto relative_error = [&](const VecX& u) {
    return std::sqrt(error_trace->energy_error(u) / reference_norm2);
  };

  // Stopping rule, budget and trace observer, the same for every relaxation method.
  solver::RelaxationOptions common;
  common.stop.rule = solver::ResidualRule::kExternalForce;  // ‖r‖ ≤ ε‖f_ext‖, §3.3 / (6.8)
  common.stop.epsilon = s.tolerance;
  common.budget.max_iterations = s.max_iterations;
  if (s.time_budget > 0) common.budget.max_seconds = s.time_budget;
  common.observer = [&](const solver::IterationInfo& info) {
    TraceRow row;
    row.iteration = info.iteration;
    row.residual_norm = info.residual_norm;
    row.energy = info.energy;
    row.flops = info.flops;
    row.seconds = info.seconds;
    row.cpu_seconds = info.cpu_seconds;
    if (error_trace) row.relative_energy_error = relative_error(*info.u);
    for (const auto& pr : scene.probes) row.probes.push_back(probe_value(pr, *info.u));
    res.trace.push_back(std::move(row));
    if (observer) observer(info);
  };

  std::ostringstream detail;
  switch (s.method) {
    case SolverSpec::Method::kCG: {
      solver::LinearCgOptions o;
      static_cast<solver::RelaxationOptions&>(o) = common;
      o.preconditioner = s.preconditioner;
      detail << "linear CG (" << (p.assembled_product() ? "assembled K" : "matrix-free")
             << "), preconditioner " << solver::to_string(s.preconditioner);
      res.report = solver::linear_cg(p, res.u, o);
      break;
    }
    case SolverSpec::Method::kNonlinearCG: {
      solver::NonlinearCgOptions o;
      static_cast<solver::RelaxationOptions&>(o) = common;
      o.beta = s.beta;
      o.line_search = s.line_search;
      o.epsilon_newton = s.line_search_tolerance;
      detail << "nonlinear CG, " << solver::to_string(o.beta) << ", "
             << solver::to_string(o.line_search) << " line search";
      res.report = solver::nonlinear_cg(p, res.u, o);
      break;
    }
    case SolverSpec::Method::kNewton: {
      solver::TruncatedNewtonOptions o;
      static_cast<solver::RelaxationOptions&>(o) = common;
      o.preconditioner = s.preconditioner;
      detail << "truncated Newton, inner CG preconditioner " << solver::to_string(s.preconditioner);
      res.report = solver::truncated_newton(p, res.u, o);
      break;
    }
    case SolverSpec::Method::kDynamicSS22: {
      const DynamicParameters dp = dynamic_parameters(scene, res.u);
      if (!dp.ok()) {  // not run: u = 0, its residual and energy
        res.report.status = dp.status;
        res.report.message = dp.message;
        res.report.residual_norm = res.external_force_norm;
        res.report.threshold = s.tolerance * res.external_force_norm;
        res.report.energy = 0;
        detail << "dynamic relaxation SS22 not run: " << dp.message;
        break;
      }
      solver::DynamicRelaxationOptions o;
      static_cast<solver::RelaxationOptions&>(o) = common;
      o.time_step = dp.time_step;
      o.damping = dp.damping;
      o.max_restarts = kMaxRestarts;
      o.energy_every = s.energy_every;
      // With the assembled K a product costs about half a gradient sweep (docs/solvers.md,
      // "Fourth pass"): the quadratic Π's gradient by recurrence, one K·d per step.
      o.gradient_recurrence = p.assembled_product();
      detail << "dynamic relaxation SS22, dt = " << dp.time_step << " s (" << dp.time_step_origin
             << "), eta = " << dp.damping << " 1/s (" << dp.damping_origin << ")"
             << (o.gradient_recurrence ? ", gradient recurrence on the assembled K" : "");
      res.report = solver::dynamic_relaxation(p, res.u, o);
      if (res.report.restarts > 0)
        detail << "; " << res.report.restarts << " restart(s) after unstable steps, dt lowered to "
               << res.report.time_step << " s";
      break;
    }
    case SolverSpec::Method::kAugmented: {
      detail << "CHOLMOD supernodal factorization of K (fixed DOFs as identity rows), one solve";
      const double cpu0 = process_cpu_seconds();
      res.report = solve_augmented(scene, res.u);
      res.report.cpu_seconds = process_cpu_seconds() - cpu0;
      break;
    }
  }
  res.method_detail = detail.str();
  if (error_trace && res.u.allFinite()) res.relative_energy_error = relative_error(res.u);
  check_final_state(scene, res);
  evaluate_probes();
  return res;
}

}  // namespace incise::scene
