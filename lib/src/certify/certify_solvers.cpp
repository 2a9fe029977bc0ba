// Certification checks on static and dynamic solves (`incise certify`, catalogue in certify.cpp):
//   cantilever_table_3_1         tip deflection and CG iterations against thesis Table 3.1 (§3.3)
//   cg_vs_cholmod                linear CG equals the CHOLMOD direct solve (docs/design.md §3)
//   solver_equivalence_cylinder  nonlinear CG and SS22 dynamic relaxation reach the truncated
//                                Newton minimizer on the §4.2 cylinder; residual against flops
//                                (thesis §4.1-4.5, the speed/accuracy trade)
//   augmented_cut_vs_cut_first   the interactive cut updated by the augmented solver (Yeung,
//                                Crouch & Pothen 2016 §3) equals cutting first and solving by CG
// The solves go through the scene layer (build_scene, run_scene), as `incise run` does; the
// cantilever scene is built from the Table 3.1 fixture (<incise/fixtures/cantilever.hpp>).

#include <incise/fixtures/cantilever.hpp>
#include <incise/scene/scene_builder.hpp>
#include <incise/scene/scene_parser.hpp>
#include <incise/scene/scene_runner.hpp>

#include <algorithm>
#include <iterator>
#include <limits>

#include "certify_checks.hpp"

namespace incise::certify::detail {

namespace {

/// The thesis §3.3 cantilever (fixtures::kCantilever) as a scene: 4n x n x n cubes, clamped at
/// x = 0, the tip load split equally over the tip nodes (fixtures::TipLoad::kEqualPerNode, as
/// in reference_data/scenes/cantilever.json), tip probe.
scene::SceneSpec cantilever_spec(int n, double tolerance) {
  const fixtures::CantileverConstants& c = fixtures::kCantilever;
  scene::SceneSpec s;
  s.file = "<certify cantilever>";
  s.mesh.source = scene::MeshSpec::Source::kBox;
  s.mesh.nx = 4 * n, s.mesh.ny = n, s.mesh.nz = n;
  s.mesh.lx = c.length, s.mesh.ly = c.height, s.mesh.lz = c.depth;
  s.material.model = c.material;
  s.material.parameters.youngs_modulus = c.young;
  s.material.parameters.poisson_ratio = c.poisson;
  scene::Region fixed;
  fixed.kind = scene::Region::Kind::kPlane;
  fixed.axis = 0;
  fixed.value = 0.0;
  s.fixed.push_back(fixed);
  scene::LoadSpec load;
  load.kind = scene::LoadSpec::Kind::kNodal;
  load.region = fixed;
  load.region.value = c.length;
  load.vector = Vec3(0, -c.tip_load, 0);
  s.loads.push_back(load);
  s.solver.tolerance = tolerance;
  s.solver.max_iterations = 100000;
  scene::ProbeSpec tip;
  tip.name = "tip";
  tip.use_region = true;
  tip.region = load.region;
  s.outputs.probes.push_back(tip);
  return s;
}

/// The §4.2 cylinder under gravity as a scene (Table 4.1 parameters, one end fixed).
scene::SceneSpec cylinder_spec(const std::string& model, bool quick) {
  scene::SceneSpec s;
  s.file = "<certify cylinder>";
  s.mesh.source = scene::MeshSpec::Source::kCylinder;
  s.mesh.length = 0.1, s.mesh.radius = 0.03;
  s.mesh.rings = quick ? 2 : 3, s.mesh.layers = quick ? 4 : 8;
  s.material = table_4_1_material(model);
  scene::Region fixed;
  fixed.kind = scene::Region::Kind::kPlane;
  fixed.axis = 0;
  s.fixed.push_back(fixed);
  scene::LoadSpec g;
  g.kind = scene::LoadSpec::Kind::kGravity;
  g.vector = Vec3(0, 0, -9.8);
  s.loads.push_back(g);
  s.solver.max_iterations = 200000;
  return s;
}

}  // namespace

// --- cantilever (thesis §3.3, Table 3.1) ---------------------------------------------------

Measurement measure_cantilever(const CertifyContext& ctx) {
  Measurement r;
  const double y_exact = fixtures::kEulerBernoulli;  // 8.64e-3 m
  // Published reference values, thesis Table 3.1 (avg error %, iterations) for 4n x n x n cubes.
  std::vector<fixtures::Table3_1Row> thesis(std::begin(fixtures::kTable3_1),
                                            std::end(fixtures::kTable3_1));
  if (ctx.quick) thesis.resize(2);
  ReportTable t{"Tip deflection error vs Euler-Bernoulli y = 4F/(Ed)(l/h)^3 = 8.64e-3 m",
                {"mesh (l x h x d)", "nodes", "CG iterations", "thesis iterations",
                 "tip deflection (m)", "avg error (%)", "thesis avg error (%)"},
                {}};
  Series ours{"incise", {}, {}, {}, false}, ref{"thesis Table 3.1", {}, {}, {}, true};
  std::vector<Series> conv;
  double worst = -1e300, prev_err = 1e300;
  bool ok = true;
  for (const fixtures::Table3_1Row& row : thesis) {
    scene::BuiltScene b = scene::build_scene(cantilever_spec(row.n, fixtures::kCantilever.epsilon));
    const scene::SceneRunResult res = scene::run_scene(b);
    if (!res.report.ok()) {
      ok = false;
      r.detail += "CG did not converge on n = " + std::to_string(row.n) + " (" +
                  solver::to_string(res.report.status) + "). ";
    }
    const double y = -res.probes[0].value[1];
    const double err = 100 * (1 - y / y_exact);
    ok = ok && err > 0 && err < prev_err;
    prev_err = err;
    worst = std::max(worst, err - row.avg_error_pct);
    const std::string mesh =
        std::to_string(4 * row.n) + " x " + std::to_string(row.n) + " x " + std::to_string(row.n);
    t.rows.push_back(
        {mesh, std::to_string(b.mesh.num_points()), std::to_string(res.report.iterations),
         fmt(static_cast<double>(row.iterations)), fmt(y), fmt(err), fmt(row.avg_error_pct)});
    ours.x.push_back(b.mesh.num_points()), ours.y.push_back(err);
    ref.x.push_back(b.mesh.num_points()), ref.y.push_back(row.avg_error_pct);
    Series c{mesh, {}, {}, {}, false};
    for (std::size_t i = 0; i < res.report.residual_history.size(); ++i) {
      c.x.push_back(static_cast<double>(i));
      c.y.push_back(res.report.residual_history[i] / res.external_force_norm);
    }
    conv.push_back(c);
  }
  r.value = worst;
  r.conditions_ok = ok;
  r.detail +=
      "Linear elasticity, matrix-free CG to ||r|| < 1e-8 ||f_ext|| (the thesis' rule), "
      "load split equally over the tip nodes. Mesh split: 6 tets per cube (the thesis' "
      "split is not stated).";
  r.tables.push_back(t);
  PlotOptions po;
  po.title = "Cantilever tip error vs mesh size (Table 3.1)";
  po.x_label = "nodes";
  po.y_label = "avg tip error (%)";
  po.log_x = po.log_y = true;
  r.plots.push_back(ReportPlot{po, {ours, ref}});
  PlotOptions pc;
  pc.title = "CG convergence on the cantilever";
  pc.x_label = "iteration";
  pc.y_label = "||r|| / ||f_ext||";
  pc.log_y = true;
  r.plots.push_back(ReportPlot{pc, conv});
  return r;
}

Measurement measure_cg_vs_cholmod(const CertifyContext& ctx) {
  Measurement r;
  scene::SceneSpec s = cantilever_spec(ctx.quick ? 2 : 4, 1e-9);
  scene::BuiltScene b1 = scene::build_scene(s);
  const scene::SceneRunResult cg = scene::run_scene(b1);
  s.solver.method = scene::SolverSpec::Method::kAugmented;
  scene::BuiltScene b2 = scene::build_scene(s);
  const scene::SceneRunResult ch = scene::run_scene(b2);
  r.value = (cg.u - ch.u).norm() / ch.u.norm();
  r.conditions_ok = cg.report.ok() && ch.report.ok();
  r.detail = "Cantilever " + std::to_string(b1.mesh.num_points()) +
             " nodes: CG to ||r|| < 1e-9 ||f|| (" + solver::to_string(cg.report.status) + ", " +
             std::to_string(cg.report.iterations) + " iterations) vs CHOLMOD factor + solve (" +
             solver::to_string(ch.report.status) + ").";
  return r;
}

// --- solvers: equivalence at the minimizer and the speed/accuracy trade (thesis ch. 4) --------

Measurement measure_solver_trade(const CertifyContext& ctx) {
  Measurement r;
  const double tol_ref = 1e-8, tol = ctx.tolerance("solver_equivalence_cylinder", "residual");
  scene::SceneSpec spec = cylinder_spec("neohookean", ctx.quick);
  spec.solver.method = scene::SolverSpec::Method::kNewton;
  spec.solver.preconditioner = solver::Preconditioner::kJacobi;
  spec.solver.tolerance = tol_ref;
  scene::BuiltScene ref_scene = scene::build_scene(spec);
  const scene::SceneRunResult ref = scene::run_scene(ref_scene);
  ReportTable t{
      "Neo-Hookean cylinder under gravity (" + std::to_string(ref_scene.mesh.num_cells()) +
          " tets)",
      {"method", "parameters", "result", "iterations", "MFLOP", "||u - u_ref||/||u_ref||"},
      {}};
  auto row = [&](const std::string& name, const scene::SceneRunResult& res, double diff) {
    t.rows.push_back({name, res.method_detail, solver::to_string(res.report.status),
                      std::to_string(res.report.iterations),
                      fmt(static_cast<double>(res.report.flops) / 1e6), fmt(diff)});
  };
  row("reference: truncated Newton to 1e-8", ref, 0.0);
  bool ok = ref.report.ok();
  double worst = 0;
  std::vector<Series> curves;
  auto trace_series = [](const std::string& label, const scene::SceneRunResult& res) {
    Series c{label, {}, {}, {}, false};
    for (const auto& tr : res.trace) {
      c.x.push_back(static_cast<double>(tr.flops) / 1e6);
      c.y.push_back(tr.residual_norm / res.external_force_norm);
    }
    return c;
  };
  curves.push_back(trace_series("truncated Newton", ref));
  for (auto method :
       {scene::SolverSpec::Method::kNonlinearCG, scene::SolverSpec::Method::kDynamicSS22}) {
    spec.solver.method = method;
    spec.solver.preconditioner = solver::Preconditioner::kNone;
    spec.solver.tolerance = tol;
    scene::BuiltScene b = scene::build_scene(spec);
    const scene::SceneRunResult res = scene::run_scene(b);
    const double diff = (res.u - ref.u).norm() / ref.u.norm();
    ok = ok && res.report.ok();
    worst = std::max(worst, diff);
    row(to_string(method), res, diff);
    curves.push_back(trace_series(to_string(method), res));
  }
  r.value = worst;
  r.conditions_ok = ok;
  r.detail =
      "Nonlinear CG (secant line search, Polak-Ribiere) and SS22 dynamic relaxation (dt "
      "and critical damping from eigenvalue estimates, §4.1) run to ||r|| <= " +
      fmt(tol) +
      " ||f_ext|| and are compared with a truncated-Newton solution to 1e-8. "
      "The plot is the speed/accuracy trade: residual against counted flops.";
  r.tables.push_back(t);
  PlotOptions po;
  po.title = "Speed/accuracy: neo-Hookean cylinder under gravity";
  po.x_label = "MFLOP (counted)";
  po.y_label = "||r|| / ||f_ext||";
  po.log_y = true;
  r.plots.push_back(ReportPlot{po, curves});
  return r;
}

// --- interactive cutting with the augmented solver (Yeung et al. 2016; thesis §3.2) -----------

Measurement measure_augmented_cut(const CertifyContext& ctx) {
  Measurement r;
  // The shipped demo scene, cut in the reference configuration so that the cut-first path
  // (builder cuts, then CG) makes exactly the same mesh.
  scene::SceneSpec spec = scene::load_scene(ctx.data_dir + "/scenes/cube_cut_augmented.json");
  spec.outputs = scene::OutputSpec{};
  spec.solver.cut_configuration = scene::SolverSpec::CutConfiguration::kReference;
  scene::BuiltScene aug_scene = scene::build_scene(spec);
  const scene::SceneRunResult aug = scene::run_scene(aug_scene);
  scene::SceneSpec cg_spec = spec;
  cg_spec.solver.method = scene::SolverSpec::Method::kCG;
  cg_spec.solver.tolerance = 1e-11;
  cg_spec.solver.max_iterations = 100000;
  scene::BuiltScene cg_scene = scene::build_scene(cg_spec);
  const scene::SceneRunResult cg = scene::run_scene(cg_scene);
  const bool same_mesh = aug_scene.mesh.num_points() == cg_scene.mesh.num_points() &&
                         aug_scene.mesh.cells == cg_scene.mesh.cells;
  bool steps_ok = !aug.cut_steps.empty();
  const std::int64_t nnz_l = steps_ok ? aug.cut_steps[0].nnz_l : 0;
  ReportTable t{"Per solve of the interactive run (" + std::to_string(aug_scene.mesh.num_points()) +
                    " nodes after the cut)",
                {"step", "faces dissected", "new nodes", "m", "GMRES iterations",
                 "GMRES rel. residual", "update (ms, thread CPU)", "status"},
                {}};
  Series m_series{"replaced columns m", {}, {}, {}, false};
  Series it_series{"GMRES iterations", {}, {}, {}, false};
  for (const scene::CutStepRow& row : aug.cut_steps) {
    steps_ok = steps_ok && row.status == "ok" && (row.gmres_iterations == 0 || row.nnz_l == nnz_l);
    t.rows.push_back({std::to_string(row.step), std::to_string(row.faces_dissected),
                      std::to_string(row.new_nodes), std::to_string(row.m),
                      std::to_string(row.gmres_iterations), fmt(row.gmres_relative_residual),
                      fmt(row.cpu_seconds_update * 1e3), row.status});
    m_series.x.push_back(row.step), m_series.y.push_back(row.m);
    it_series.x.push_back(row.step), it_series.y.push_back(row.gmres_iterations);
  }
  r.value = same_mesh && cg.u.size() == aug.u.size() ? (aug.u - cg.u).norm() / cg.u.norm()
                                                     : std::numeric_limits<double>::quiet_NaN();
  r.conditions_ok = aug.report.ok() && cg.report.ok() && same_mesh && steps_ok;
  if (!same_mesh) r.detail += "The two paths produced different cut meshes. ";
  if (!steps_ok) r.detail += "A step failed or the factor changed (refactorization). ";
  r.detail +=
      "reference_data/scenes/cube_cut_augmented.json with cut_configuration "
      "\"reference\": " +
      std::to_string(aug.cut_steps.size() ? aug.cut_steps.size() - 1 : 0) +
      " sweep triangles, after each one the augmented solver updates the static "
      "solution (replaced columns, GMRES on the Schur system, no refactorization: the "
      "factor of the uncut K is used throughout). Compared with cutting first and "
      "solving by CG to 1e-11 ||f|| (" +
      solver::to_string(cg.report.status) + ", " + std::to_string(cg.report.iterations) +
      " iterations). Final residual of the augmented solution, recomputed matrix-free "
      "on the cut mesh: " +
      fmt(aug.report.residual_norm / aug.external_force_norm) + " ||f_ext||.";
  r.tables.push_back(t);
  PlotOptions po;
  po.title = "Augmented cutting: m and GMRES iterations per sweep step";
  po.x_label = "step (0 = initial factorization and solve)";
  po.y_label = "count";
  r.plots.push_back(ReportPlot{po, {m_series, it_series}});
  return r;
}

}  // namespace incise::certify::detail
