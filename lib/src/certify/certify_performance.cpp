// Certification check performance_table_4_5 (`incise certify`, catalogue in certify.cpp): the
// cost per iteration of linear CG, nonlinear CG (Newton and secant line searches) and SS22
// dynamic relaxation on the §4.2 cylinder, against thesis Table 4.5 (§4.5.2). The counted MFLOP
// per iteration is compared with the thesis; iterations/s, MFLOP/s and the percentage of the
// vector-add baseline (core/baseline.hpp, the thesis' machine measure, taken in this process)
// are measured in thread CPU time and displayed only, never asserted.

#include <incise/core/baseline.hpp>
#include <incise/core/timer.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/scene/scene_builder.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>

#include <algorithm>
#include <memory>
#include <string>

#include "certify_checks.hpp"

namespace incise::certify::detail {

namespace {

/// One row of thesis Table 4.5 (published reference values: "% peak" of the 246 MFLOP/s
/// vector-add baseline, iterations per second and MFLOP per iteration on a 1 GHz Pentium III).
struct Table45Row {
  const char* material;
  const char* method;       ///< "static" (linear CG / nonlinear CG) or "dynamic" (SS22)
  const char* line_search;  ///< "newton", "secant" or "" (linear CG, dynamic)
  bool large;               ///< the large mesh of Table 4.2
  double percent_peak, iterations_per_second, mflop_per_iteration;
};

const Table45Row kTable45[] = {
    {"linear", "dynamic", "", false, 49, 628, 0.2},
    {"linear", "static", "", false, 56, 708, 0.2},
    {"stvk", "static", "newton", false, 48, 71, 1.7},
    {"stvk", "static", "secant", false, 53, 113, 1.2},
    {"stvk", "dynamic", "", false, 62, 426, 0.4},
    {"neohookean", "static", "newton", false, 85, 109, 1.9},
    {"neohookean", "static", "secant", false, 77, 144, 1.3},
    {"neohookean", "dynamic", "", false, 54, 356, 0.4},
    {"veronda-westmann", "static", "newton", false, 90, 91, 2.4},
    {"veronda-westmann", "static", "secant", false, 80, 120, 1.7},
    {"veronda-westmann", "dynamic", "", false, 61, 327, 0.5},
    {"neohookean", "static", "newton", true, 73, 12, 14.2},
    {"neohookean", "static", "secant", true, 66, 16, 9.9},
    {"neohookean", "dynamic", "", true, 49, 41, 2.9},
};

/// The §4.2 cylinder (Table 4.1 parameters, one end fixed, gravity), small or large mesh.
std::unique_ptr<fem::ElasticProblem> table_4_5_cylinder(const std::string& model, bool large) {
  const mesh::MeshData m =
      large ? mesh::make_thesis_cylinder_large() : mesh::make_thesis_cylinder_small();
  auto p =
      std::make_unique<fem::ElasticProblem>(m, scene::make_material(table_4_1_material(model)));
  p->fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
  p->add_gravity(Vec3(0.0, 0.0, -9.8));
  return p;
}

/// Runs `iterations` iterations of the row's method from u = 0 (no stopping test: ε = 0) and
/// returns its report (counted flops, iterations actually done).
solver::SolverReport run_table_4_5_method(fem::ElasticProblem& p, const Table45Row& row,
                                          long iterations) {
  VecX u = VecX::Zero(p.size());
  const std::string method = row.method, ls = row.line_search;
  if (method == "dynamic") {
    solver::DynamicRelaxationOptions o;
    o.time_step = 1e-4;  // below the critical step of both meshes: the run stays bounded
    o.damping = 20.0;    // the cost of a step does not depend on Δt or η
    o.stop.epsilon = 0.0;
    o.budget.max_iterations = iterations;
    return solver::dynamic_relaxation(p, u, o);
  }
  if (std::string(row.material) == "linear") {
    solver::LinearCgOptions o;
    o.stop.epsilon = 0.0;
    o.budget.max_iterations = iterations;
    o.recompute_residual = false;
    return solver::linear_cg(p, u, o);
  }
  solver::NonlinearCgOptions o;  // the thesis' §4.5 settings: PR, ε_newton = 0.1
  o.stop.epsilon = 0.0;
  o.budget.max_iterations = iterations;
  o.line_search =
      ls == "newton" ? solver::LineSearchKind::kNewton : solver::LineSearchKind::kSecant;
  return solver::nonlinear_cg(p, u, o);
}

}  // namespace

Measurement measure_table_4_5(const CertifyContext& ctx) {
  Measurement r;
  // Thread CPU seconds spent repeating each row's run (the thesis captured the first 1.0 s).
  const double cpu_seconds = ctx.quick ? 0.02 : 0.5;
  const double baseline = vector_add_mflops();  // measured now, in this process
  ReportTable t{
      "Per iteration, from u = 0 (ours measured in this process; thesis Table 4.5 "
      "values on a 1 GHz Pentium III, baseline 246 MFLOP/s)",
      {"material", "method", "line search", "mesh", "MFLOP/iter (ours, counted)",
       "MFLOP/iter (thesis)", "iter/s (ours)", "iter/s (thesis)", "MFLOP/s (ours)",
       "% of baseline (ours)", "% peak (thesis)"},
      {}};
  Series ours{"incise (counted)", {}, {}, {}, false}, ref{"thesis Table 4.5", {}, {}, {}, true};
  PlotOptions po;
  double worst = 1;
  bool ok = true;
  int k = 0;
  for (const Table45Row& row : kTable45) {
    if (row.large && ctx.quick) continue;
    auto p = table_4_5_cylinder(row.material, row.large);
    const std::string method = row.method;
    const long iterations = method == "dynamic"                     ? 100
                            : std::string(row.material) == "linear" ? 50
                                                                    : 20;
    // Counted flops per iteration: deterministic, compared with the thesis.
    const solver::SolverReport first = run_table_4_5_method(*p, row, iterations);
    if (first.iterations <= 0 || (first.iterations < iterations && !first.ok())) {
      ok = false;
      r.detail += std::string(row.material) + " " + row.method + ": stopped after " +
                  std::to_string(first.iterations) + " iterations (" +
                  solver::to_string(first.status) + "). ";
    }
    const double mflop_iter =
        static_cast<double>(first.flops) / 1e6 / std::max<long>(1, first.iterations);
    // Rates: repeat the same run for at least cpu_seconds of thread CPU time (displayed only).
    double iters = 0, flops = 0;
    const double start = thread_cpu_seconds();
    double elapsed = 0;
    do {
      const solver::SolverReport rep = run_table_4_5_method(*p, row, iterations);
      iters += static_cast<double>(rep.iterations);
      flops += static_cast<double>(rep.flops);
      elapsed = thread_cpu_seconds() - start;
    } while (elapsed < cpu_seconds);
    const double mflops = flops / 1e6 / elapsed;
    worst = std::max(
        {worst, mflop_iter / row.mflop_per_iteration, row.mflop_per_iteration / mflop_iter});
    const std::string mesh = std::string(row.large ? "large" : "small") + " (" +
                             std::to_string(p->num_elements()) + " tets)";
    t.rows.push_back({row.material, row.method, row.line_search, mesh, fmt(mflop_iter),
                      fmt(row.mflop_per_iteration), fmt(iters / elapsed),
                      fmt(row.iterations_per_second), fmt(mflops), fmt(100 * mflops / baseline),
                      fmt(row.percent_peak)});
    // Short category label: material, then CG / nonlinear CG line search N(ewton) or S(ecant)
    // / SS22, "(L)" for the large mesh.
    const std::string mat = row.material;
    const std::string short_mat = mat == "linear"       ? "lin"
                                  : mat == "stvk"       ? "StVK"
                                  : mat == "neohookean" ? "NH"
                                                        : "VW";
    const std::string short_method = method == "dynamic"          ? "SS22"
                                     : row.line_search[0] == '\0' ? "CG"
                                     : row.line_search[0] == 'n'  ? "N"
                                                                  : "S";
    const std::string label = short_mat + " " + short_method + (row.large ? " (L)" : "");
    po.x_categories.push_back(label);
    ours.x.push_back(k), ours.y.push_back(mflop_iter);
    ref.x.push_back(k), ref.y.push_back(row.mflop_per_iteration);
    ++k;
  }
  r.value = worst;
  r.conditions_ok = ok;
  r.detail +=
      "Each row runs its method from u = 0 on the §4.2 cylinder (Table 4.1 parameters, gravity, "
      "one end fixed; our O-grid meshes instead of the thesis' Delaunay meshes of 1230 and 9300 "
      "elements): linear CG 50 iterations, nonlinear CG (Polak-Ribiere, epsilon_newton = 0.1) 20 "
      "iterations, SS22 100 steps (dt = 1e-4 s, eta = 20/s). MFLOP/iter is counted "
      "(deterministic) and compared with the thesis; iter/s, MFLOP/s and % of the vector-add "
      "baseline (a <- a + b on 1024 doubles, measured in this process: " +
      fmt(baseline) + " MFLOP/s) are thread CPU time rates over " + fmt(cpu_seconds) +
      " s per row, displayed and never asserted. The thesis' kernels ran at 48-90 % of its "
      "baseline; the add is bound by loads and stores, the element kernels by arithmetic, so a "
      "modern core can exceed 100 %.";
  r.tables.push_back(t);
  po.title = "MFLOP per iteration (Table 4.5)";
  po.y_label = "MFLOP / iteration";
  po.x_label = "material (lin, StVK, NH, VW), method (CG; nonlinear CG, N/S line search; SS22)";
  po.width = 900;
  po.log_y = true;
  r.plots.push_back(ReportPlot{po, {ours, ref}});
  return r;
}

}  // namespace incise::certify::detail
