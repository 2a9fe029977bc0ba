/// Thesis ch. 4 (§4.2, §4.4, §4.5, Figs 4.7–4.13): static nonlinear CG vs dynamic relaxation on
/// the cylinder of Table 4.1/4.2 (length 0.1 m, radius 0.03 m, E = 1e4 Pa, ν = 0.3,
/// ρ = 1000 kg/m³, g = 9.8 m/s², γ = 8, one end fixed). Our structured stand-ins for the two
/// Delaunay meshes of Table 4.2: make_thesis_cylinder_small() (1296 tetrahedra, 333 nodes; thesis
/// 1230/308) and make_thesis_cylinder_large() (9450 tetrahedra, 2002 nodes; thesis 9300/1911).
///
/// Per case: a reference û (NCG to 1e-2, then truncated Newton to 1e-8; 1e-12 for the linear
/// model, §4.2); energy error (e, e)_{K(û)} traced against seconds and counted flops for static
/// CG (linear CG for the linear model; nonlinear CG with the Newton, secant and scale-dependent
/// secant line searches, PR and FR) and for SS22 dynamic relaxation with η = 2√λ₁ (inverse
/// iteration) and 2/3, 3/2 of it (the thesis' under/over-damped curves), Δt from the thesis'
/// procedure (§4.4.1). Writes CSV and SVG plots next to the test binary (INCISE_CH4_OUTPUT_DIR)
/// and checks the thesis' conclusions (§4.5.3, §4.5.4, §4.5.5, §4.3.1).
///
/// Default executable (papers_ch4_relaxation_verify): the linear model on the small mesh and the
/// StVK inversion check (§4.3.1). The `slow` executable (papers_ch4_relaxation_all_verify, this
/// file built with INCISE_CH4_SLOW=1): all four models on both meshes plus the figure-specific
/// runs: Fig. 4.8 (ε_newton), Fig. 4.9 (mesh size), Fig. 4.13 (StVK, E = 2e4). Every thesis
/// figure 4.7–4.13 gets one SVG fig4_<n>_analogue_*.svg (top panel: energy error vs seconds, as
/// the thesis plots it; bottom panel: vs counted MFLOP, which is reproducible).
#include <incise/certify/svg_plot.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/energy_error.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>
#include <incise/solver/truncated_newton.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#ifndef INCISE_CH4_OUTPUT_DIR
#define INCISE_CH4_OUTPUT_DIR "."
#endif

namespace incise::solver {
namespace {

constexpr double kLength = 0.1;  // Table 4.2 rod length (m)

struct Case {
  std::string material;
  bool large = false;
  double youngs = 1e4;  // Table 4.1; Fig. 4.13 uses 2e4
  std::string name() const {
    std::string s = material + (large ? "_large" : "_small");
    if (youngs != 1e4) s += "_E" + std::to_string(int(youngs));
    for (char& c : s)
      if (c == '-') c = '_';
    return s;
  }
};

struct CylinderSetup {
  mesh::MeshData mesh;
  std::unique_ptr<fem::ElasticProblem> problem;
};

CylinderSetup cylinder(const Case& c) {
  CylinderSetup s;
  s.mesh = c.large ? mesh::make_thesis_cylinder_large() : mesh::make_thesis_cylinder_small();
  material::Parameters p;  // Table 4.1
  p.youngs_modulus = c.youngs;
  p.poisson_ratio = 0.3;
  p.density = 1000.0;
  p.gamma = c.material == "veronda-westmann" ? 8.0 : 0.0;
  s.problem = std::make_unique<fem::ElasticProblem>(s.mesh, material::Material(c.material, p));
  s.problem->fix_nodes(fem::nodes_on_plane(s.mesh, 0, 0.0));
  s.problem->add_gravity(Vec3(0.0, 0.0, -9.8));
  return s;
}

// Reference solution (§4.2): NCG to ‖r‖ ≤ 1e-2‖f‖, then truncated Newton to 1e-8 (1e-12 linear).
SolverReport reference_solution(fem::ElasticProblem& p, const std::string& material, VecX& ref) {
  ref = VecX::Zero(p.size());
  NonlinearCgOptions o;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-2;
  o.budget.max_iterations = 20000;
  (void)nonlinear_cg(p, ref, o);
  TruncatedNewtonOptions t;
  t.stop.rule = ResidualRule::kExternalForce;
  t.stop.epsilon = material == "linear" ? 1e-12 : 1e-8;
  t.budget.max_iterations = 200;
  return truncated_newton(p, ref, t);
}

struct TracedRun {
  std::string label;
  SolverReport report;
  std::vector<EnergyErrorTrace::Sample> samples;
};

// Counted flops / seconds at which the energy error first drops to `level`; +∞ if never.
double flops_to(const TracedRun& r, double level) {
  for (const auto& s : r.samples)
    if (s.energy_error <= level) return double(s.flops);
  return std::numeric_limits<double>::infinity();
}
double seconds_to(const TracedRun& r, double level) {
  for (const auto& s : r.samples)
    if (s.energy_error <= level) return s.seconds;
  return std::numeric_limits<double>::infinity();
}
double min_error(const TracedRun& r) {
  double lowest = std::numeric_limits<double>::infinity();
  for (const auto& s : r.samples) lowest = std::min(lowest, s.energy_error);
  return lowest;
}
const TracedRun& find(const std::vector<TracedRun>& runs, const std::string& label) {
  for (const TracedRun& r : runs)
    if (r.label == label) return r;
  throw std::runtime_error("no run " + label);
}

void write_csv(const std::string& name, const std::vector<TracedRun>& runs) {
  std::ofstream csv(std::string(INCISE_CH4_OUTPUT_DIR) + "/ch4_energy_error_" + name + ".csv");
  csv << "case,method,iteration,seconds,flops,energy_error,residual_norm\n";
  for (const TracedRun& r : runs)
    for (const auto& s : r.samples)
      csv << name << ',' << r.label << ',' << s.iteration << ',' << s.seconds << ',' << s.flops
          << ',' << s.energy_error << ',' << s.residual_norm << '\n';
}

// One SVG with two stacked panels: energy error vs seconds (top, the thesis' axis) and vs
// counted MFLOP (bottom). `runs` may come from several cases (labels say which).
void write_figure(const std::string& file, const std::string& title,
                  const std::vector<TracedRun>& runs) {
  std::vector<certify::Series> by_flops, by_seconds;
  for (const TracedRun& r : runs) {
    certify::Series sf, ss;
    sf.label = ss.label = r.label;
    for (const auto& s : r.samples) {
      sf.x.push_back(double(s.flops) * 1e-6);
      sf.y.push_back(s.energy_error);
      ss.x.push_back(s.seconds);
      ss.y.push_back(s.energy_error);
    }
    by_flops.push_back(sf);
    by_seconds.push_back(ss);
  }
  certify::PlotOptions o;
  o.log_y = true;
  o.width = 760;
  o.height = 420;
  o.y_label = "energy error (e,e)_K(u^) [J]";
  o.title = title + " - vs seconds (this machine)";
  o.x_label = "seconds";
  std::string top = certify::svg_line_plot(by_seconds, o);
  o.title = title + " - vs counted flops";
  o.x_label = "MFLOP";
  std::string bottom = certify::svg_line_plot(by_flops, o);
  // Nest both plots in one SVG document, the second shifted down by one panel height.
  std::ofstream(std::string(INCISE_CH4_OUTPUT_DIR) + "/" + file)
      << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << o.width << "\" height=\""
      << 2 * o.height << "\">\n"
      << top << "<g transform=\"translate(0," << o.height << ")\">\n"
      << bottom << "</g>\n</svg>\n";
}

[[maybe_unused]] std::vector<TracedRun> subset(const std::vector<TracedRun>& runs,
                                               const std::vector<std::string>& labels,
                                               const std::string& suffix) {
  std::vector<TracedRun> out;
  for (const std::string& l : labels) {
    out.push_back(find(runs, l));
    out.back().label += suffix;
  }
  return out;
}

// Inverted tetrahedra (deformed volume ≤ 0) at u, by the solver's post-check.
InversionCheck inversion(const mesh::MeshData& m, const VecX& u) {
  return check_inversion(m.points, m.cells, u);
}

// Distance from the clamp (x = 0) of the farthest inverted tetrahedron, measured at its vertex
// nearest to the clamp; 0 when none is inverted.
double farthest_from_clamp(const mesh::MeshData& m, const InversionCheck& chk) {
  double far = 0.0;
  for (Index e : chk.elements) {
    double near = std::numeric_limits<double>::infinity();
    for (int a = 0; a < 4; ++a) near = std::min(near, m.points(0, m.cells(a, e)));
    far = std::max(far, near);
  }
  return far;
}

struct CaseResult {
  Case c;
  std::vector<TracedRun> runs;
  double level = 0.0;     // comparison level (J)
  double best_dyn = 0.0;  // flops of the best dynamic run to the level
  double static_flops = 0.0;
  InversionCheck inverted;
  double dt = 0.0;           // time step of the damped runs (s)
  int extra_reductions = 0;  // 15 % reductions beyond the thesis' procedure
};

struct RunOptions {
  bool line_searches = true;            // NCG Newton / scale-dep. secant / FR as well
  std::vector<double> newton_epsilons;  // Fig. 4.8: extra Newton line-search runs
};

CaseResult run_case(const Case& c, const RunOptions& ro = {}) {
  CylinderSetup setup = cylinder(c);
  fem::ElasticProblem& p = *setup.problem;
  const mesh::MeshData& m = setup.mesh;
  const std::string tag = "[" + c.name() + "]";
  const VecX u0 = VecX::Zero(p.size());
  CaseResult out;
  out.c = c;

  VecX ref;
  {
    const SolverReport rr = reference_solution(p, c.material, ref);
    EXPECT_TRUE(rr.ok()) << tag << " reference: " << to_string(rr.status);
    out.inverted = inversion(m, ref);
    std::printf(
        "%s reference: %ld Newton steps, %ld inner, |r|/|f| = %.2e, %d inverted elements "
        "(farthest %.4f m from the clamp), tip sag %.4f m\n",
        tag.c_str(), rr.iterations, rr.inner_iterations, rr.residual_norm / p.external_force_norm(),
        out.inverted.inverted_elements, farthest_from_clamp(m, out.inverted), -ref.minCoeff());
  }

  // The large mesh needs more flops per iteration (7.3×) and more iterations (h is 1.7× smaller),
  // and the stiffening / inverting models converge slowly there: 10 GFLOP per run.
  const double flop_budget = c.large ? 10000e6 : 300e6;
  std::vector<TracedRun>& runs = out.runs;
  auto trace_run = [&](const std::string& label, auto&& solve) {
    EnergyErrorTrace trace(p, ref);
    trace.record_start(u0, 0.0);
    VecX u = u0;
    TracedRun r;
    r.label = label;
    r.report = solve(u, trace.observer());
    r.samples = trace.samples();
    runs.push_back(std::move(r));
  };
  StoppingRule stop;
  stop.rule = ResidualRule::kExternalForce;
  stop.epsilon = 1e-7;

  if (c.material == "linear") {
    trace_run("static CG", [&](VecX& u, IterationObserver obs) {
      LinearCgOptions o;
      o.stop = stop;
      o.budget.max_flops = flop_budget;
      o.observer = std::move(obs);
      return linear_cg(p, u, o);
    });
  }
  auto ncg = [&](const std::string& label, LineSearchKind kind, BetaRule beta, double eps) {
    trace_run(label, [&](VecX& u, IterationObserver obs) {
      NonlinearCgOptions o;
      o.stop = stop;
      o.line_search = kind;
      o.beta = beta;
      o.epsilon_newton = eps;
      o.budget.max_flops = flop_budget;
      o.observer = std::move(obs);
      return nonlinear_cg(p, u, o);
    });
  };
  ncg("NCG secant PR", LineSearchKind::kSecant, BetaRule::kPolakRibiere, 0.1);
  if (ro.line_searches) {
    ncg("NCG newton PR", LineSearchKind::kNewton, BetaRule::kPolakRibiere, 0.1);
    ncg("NCG scale-dep. secant PR", LineSearchKind::kScaleDependentSecant, BetaRule::kPolakRibiere,
        0.1);
    ncg("NCG secant FR", LineSearchKind::kSecant, BetaRule::kFletcherReeves, 0.1);
  }
  for (double eps : ro.newton_epsilons) {
    char label[64];
    std::snprintf(label, sizeof label, "NCG newton PR, eps_newton = %g", eps);
    ncg(label, LineSearchKind::kNewton, BetaRule::kPolakRibiere, eps);
  }

  // Dynamic parameters: Δt by the thesis' procedure, capped by 0.9·2/√λ_n (see
  // verification/solver/damping_verify.cpp: for stiffening materials the procedure's step can
  // become unstable late in the swing); η = 2√λ₁ and 2/3, 3/2 of it.
  const EigenEstimate big = largest_eigenvalue(p, u0, EigenOptions{1e-7, 20000, 1e-8, 1});
  const EigenEstimate small = smallest_eigenvalue(p, u0, EigenOptions{1e-6, 500, 1e-6, 1});
  EXPECT_TRUE(big.ok()) << to_string(big.status) << " after " << big.iterations;
  EXPECT_TRUE(small.ok()) << to_string(small.status) << " after " << small.iterations;
  double h = 1e300;
  for (Index e = 0; e < m.num_cells(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        h = std::min(h, (m.points.col(m.cells(a, e)) - m.points.col(m.cells(b, e))).norm());
  const material::Lame lame = p.material().lame();
  const StableTimeStep st =
      find_stable_time_step(p, u0, cfl_time_step(h, lame.lambda, lame.mu, 1000.0));
  EXPECT_TRUE(st.found);
  const double dt = std::min(st.time_step, 0.9 * critical_time_step(big.value));
  const double eta = critical_damping(small.value);
  std::printf("%s dt = %.4g s (procedure %.4g, 2/sqrt(lambda_n) %.4g), eta_crit = %.3g 1/s\n",
              tag.c_str(), dt, st.time_step, critical_time_step(big.value), eta);
  const std::vector<std::pair<std::string, double>> dampings = {
      {"dynamic (underdamped 2/3)", 2.0 / 3.0 * eta},
      {"dynamic (critical)", eta},
      {"dynamic (overdamped 3/2)", 1.5 * eta}};
  // The procedure tests only the first 50 MFLOP from u = 0; when a full damped run still blows
  // up or steps into det F ≤ 0 later in the swing (the tangent stiffens or, for StVK, changes
  // as elements invert), Δt is lowered by 15 % again — the thesis' rule — and all three
  // damped runs are repeated with the common step. The number of extra reductions is reported.
  const std::size_t static_runs = runs.size();
  double dt_used = dt;
  int extra_reductions = 0;
  for (;;) {
    runs.resize(static_runs);
    bool failed = false;
    for (const auto& [label, damping] : dampings) {
      const double d = damping;
      trace_run(label, [&](VecX& u, IterationObserver obs) {
        DynamicRelaxationOptions o;
        o.time_step = dt_used;
        o.damping = d;
        o.stop = stop;
        o.budget.max_flops = flop_budget;
        o.observer = std::move(obs);
        return dynamic_relaxation(p, u, o);
      });
      const StopReason why = runs.back().report.status;
      failed = failed || why == StopReason::kUnstable || why == StopReason::kInverted;
    }
    if (!failed || extra_reductions == 20) break;
    dt_used *= 0.85;
    ++extra_reductions;
  }
  out.dt = dt_used;
  out.extra_reductions = extra_reductions;
  std::printf("%s damped runs: dt = %.4g s after %d extra 15%% reductions\n", tag.c_str(), dt_used,
              extra_reductions);
  write_csv(c.name(), runs);

  for (const TracedRun& r : runs)
    for (const auto& s : r.samples) EXPECT_FALSE(std::isnan(s.energy_error)) << r.label;

  // Comparison level: 1e-6 of the initial energy error, or — when the static method of the
  // thesis (linear CG / NCG secant PR) or every dynamic run stops short of that within the
  // flop budget (Veronda-Westmann) — the deepest level both reached.
  const std::string static_label = c.material == "linear" ? "static CG" : "NCG secant PR";
  const double initial = runs.front().samples.front().energy_error;
  const double best_dyn_min = std::min({min_error(find(runs, "dynamic (critical)")),
                                        min_error(find(runs, "dynamic (underdamped 2/3)")),
                                        min_error(find(runs, "dynamic (overdamped 3/2)"))});
  out.level = std::max({1e-6 * initial, min_error(find(runs, static_label)), best_dyn_min});
  std::printf("%s to reach energy error %.3g J (%.1e of the initial):\n", tag.c_str(), out.level,
              out.level / initial);
  std::printf("   %-34s %-18s %8s %10s %9s %8s %9s\n", "method", "end", "iters", "MFLOP", "seconds",
              "iter/s", "MFLOP/it");
  for (const TracedRun& r : runs)
    std::printf("   %-34s %-18s %8ld %10.2f %9.4f %8.0f %9.3f\n", r.label.c_str(),
                to_string(r.report.status), r.report.iterations, flops_to(r, out.level) * 1e-6,
                seconds_to(r, out.level), r.report.iterations / r.report.seconds,
                r.report.flops * 1e-6 / std::max<long>(1, r.report.iterations));
  out.best_dyn = std::min({flops_to(find(runs, "dynamic (critical)"), out.level),
                           flops_to(find(runs, "dynamic (underdamped 2/3)"), out.level),
                           flops_to(find(runs, "dynamic (overdamped 3/2)"), out.level)});
  out.static_flops = flops_to(find(runs, static_label), out.level);
  EXPECT_TRUE(std::isfinite(out.best_dyn)) << tag << " no dynamic run reached the level";
  return out;
}

// The thesis' conclusions for one case (§4.5.4, §4.5.5, §4.3.1).
void check_conclusions(const CaseResult& r) {
  const std::string tag = "[" + r.c.name() + "]";
  if (r.c.material == "linear") {
    // §4.5.4: "the CG iteration outperforms dynamic relaxation, by approximately a factor 5 to
    // 10". We require linear CG to need at most half the flops of the best dynamic run.
    std::printf("%s best dynamic / linear CG flops = %.2f (thesis: 5-10)\n", tag.c_str(),
                r.best_dyn / r.static_flops);
    EXPECT_LT(2.0 * r.static_flops, r.best_dyn) << tag;
  } else {
    // §4.5.5: "the CG iteration is as quick as a dynamic relaxation with optimal parameters".
    // We require the thesis' setting (secant, PR) within a factor 3 of the best dynamic run.
    std::printf("%s NCG secant PR / best dynamic flops = %.2f (thesis: about 1)\n", tag.c_str(),
                r.static_flops / r.best_dyn);
    EXPECT_LT(r.static_flops, 3.0 * r.best_dyn) << tag;
    EXPECT_LT(r.best_dyn, 3.0 * r.static_flops) << tag;
  }
  if (r.c.material == "neohookean" || r.c.material == "veronda-westmann") {
    EXPECT_EQ(r.inverted.inverted_elements, 0) << tag;  // log-barrier models reject det F ≤ 0
  }
}

std::string figure_title(const Case& c) {
  return "Cylinder (" + std::string(c.large ? "large" : "small") + " mesh), " + c.material +
         (c.youngs != 1e4 ? ", E = " + std::to_string(int(c.youngs)) + " Pa" : "");
}

// §4.3.1 / Fig. 4.3: StVK inverts elements near the clamp under the Table 4.1 load; the
// log-barrier neo-Hookean model does not. StVK's energy is finite at det F ≤ 0, so Π cannot
// flag it: check_inversion() is the post-check that detects it and reports the status.
TEST(Chapter4, StvkInvertsElementsNearTheClamp_Sec4_3_1) {
  for (const std::string material : {"stvk", "neohookean"}) {
    CylinderSetup s = cylinder(Case{material, false, 1e4});
    VecX ref;
    const SolverReport rr = reference_solution(*s.problem, material, ref);
    ASSERT_TRUE(rr.ok()) << material << ": " << to_string(rr.status);
    const InversionCheck chk = inversion(s.mesh, ref);
    const double far = farthest_from_clamp(s.mesh, chk);
    std::printf(
        "[%s] reference: %s, %d of %d tetrahedra inverted, farthest %.4f m from the clamp"
        ", min volume ratio %.3f\n",
        material.c_str(), to_string(chk.status), chk.inverted_elements, int(s.mesh.num_cells()),
        far, chk.min_volume_ratio);
    if (material == "stvk") {
      EXPECT_EQ(chk.status, InversionStatus::kInverted);
      EXPECT_GT(chk.inverted_elements, 0);
      // "Near the clamp": every inverted tetrahedron has a vertex in the first quarter of the
      // rod, i.e. lies in the first two of the eight 0.0125 m layers (clamp at x = 0; 1e-12 m
      // absorbs the rounding of generated node coordinates).
      EXPECT_LE(far, 0.25 * kLength + 1e-12);
      EXPECT_LT(chk.min_volume_ratio, 0.0);
    } else {
      EXPECT_EQ(chk.status, InversionStatus::kNoneInverted);
      EXPECT_EQ(chk.inverted_elements, 0);
    }
  }
}

#ifndef INCISE_CH4_SLOW

// Default run: the linear model on the small mesh (Fig. 4.10 analogue).
TEST(Chapter4, LinearModelSmallMesh_Sec4_5_4_Fig4_10) {
  const CaseResult r = run_case(Case{"linear", false, 1e4});
  check_conclusions(r);
  write_figure("fig4_10_analogue_linear_small.svg", "Fig. 4.10 analogue: " + figure_title(r.c),
               r.runs);
}

#else

class Chapter4All : public ::testing::TestWithParam<Case> {};

// Every model on both meshes; writes the figure analogue each case stands for.
TEST_P(Chapter4All, StaticVsDynamicRelaxation_Sec4_5) {
  const Case c = GetParam();
  RunOptions ro;
  if (c.material == "veronda-westmann" && !c.large) ro.newton_epsilons = {0.5, 0.01, 0.001};
  const CaseResult r = run_case(c, ro);
  check_conclusions(r);
  const std::string title = figure_title(c);
  std::string fig;  // the thesis figure this case is the analogue of
  if (!c.large && c.material == "linear") fig = "fig4_10_analogue_linear_small";
  if (!c.large && c.material == "veronda-westmann") fig = "fig4_11_analogue_vw_small";
  if (!c.large && c.material == "stvk") fig = "fig4_12_analogue_stvk_small";
  if (c.large) fig = "large_mesh_" + c.name();
  if (fig.empty()) fig = "small_mesh_" + c.name();
  write_figure(fig + ".svg", (fig.rfind("fig", 0) == 0 ? "Thesis analogue: " : "") + title,
               subset(
                   r.runs,
                   [&] {
                     std::vector<std::string> l;
                     for (const TracedRun& t : r.runs)
                       if (t.label.find("eps_newton") == std::string::npos) l.push_back(t.label);
                     return l;
                   }(),
                   ""));
  if (c.material == "veronda-westmann" && !c.large) {
    // Fig. 4.7: the three line searches (PR) on Veronda-Westmann.
    write_figure(
        "fig4_7_analogue_line_searches_vw_small.svg", "Fig. 4.7 analogue: line searches, " + title,
        subset(r.runs, {"NCG newton PR", "NCG secant PR", "NCG scale-dep. secant PR"}, ""));
    // Fig. 4.8: the Newton line search's tolerance ε_newton (0.1 is the default run).
    std::vector<TracedRun> eps = subset(r.runs, {"NCG newton PR"}, ", eps_newton = 0.1");
    for (const TracedRun& t : r.runs)
      if (t.label.find("eps_newton") != std::string::npos) eps.push_back(t);
    write_figure("fig4_8_analogue_newton_tolerance_vw_small.svg",
                 "Fig. 4.8 analogue: Newton line-search tolerance, " + title, eps);
    // §4.5.1: "the precise value of ε makes little difference" — reported, not asserted, at
    // the deepest energy error every ε_newton run reached.
    double level = 0.0;
    for (const TracedRun& t : eps) level = std::max(level, min_error(t));
    for (const TracedRun& t : eps)
      std::printf("[fig 4.8] %-36s %10.2f MFLOP, %8.3f s to %.3g J (%.1e of the initial)\n",
                  t.label.c_str(), flops_to(t, level) * 1e-6, seconds_to(t, level), level,
                  level / t.samples.front().energy_error);
  }
}

INSTANTIATE_TEST_SUITE_P(Models, Chapter4All,
                         ::testing::Values(Case{"linear", false, 1e4}, Case{"stvk", false, 1e4},
                                           Case{"neohookean", false, 1e4},
                                           Case{"veronda-westmann", false, 1e4},
                                           Case{"linear", true, 1e4}, Case{"stvk", true, 1e4},
                                           Case{"neohookean", true, 1e4},
                                           Case{"veronda-westmann", true, 1e4}),
                         [](const ::testing::TestParamInfo<Case>& i) { return i.param.name(); });

// Fig. 4.9 / §4.5.3: neo-Hookean on both meshes. "The larger mesh leads to slower convergence,
// but static and dynamic are slowed down by the same amount."
TEST(Chapter4, MeshSizeNeoHookean_Sec4_5_3_Fig4_9) {
  RunOptions ro;
  ro.line_searches = false;
  const CaseResult s = run_case(Case{"neohookean", false, 1e4}, ro);
  const CaseResult l = run_case(Case{"neohookean", true, 1e4}, ro);
  std::vector<TracedRun> both = subset(s.runs, {"NCG secant PR", "dynamic (critical)"}, " (small)");
  for (const TracedRun& t : subset(l.runs, {"NCG secant PR", "dynamic (critical)"}, " (large)"))
    both.push_back(t);
  write_figure("fig4_9_analogue_mesh_size_neohookean.svg",
               "Fig. 4.9 analogue: neo-Hookean, small vs large mesh", both);
  // Slow-down factors at one common relative level: the deeper of the two cases' levels.
  const double rel = std::max(s.level / s.runs.front().samples.front().energy_error,
                              l.level / l.runs.front().samples.front().energy_error);
  auto factor = [&](const std::string& label) {
    return flops_to(find(l.runs, label), rel * l.runs.front().samples.front().energy_error) /
           flops_to(find(s.runs, label), rel * s.runs.front().samples.front().energy_error);
  };
  const double fs = factor("NCG secant PR"), fd = factor("dynamic (critical)");
  std::printf(
      "[fig 4.9] large/small flops to %.1e of the initial error: static %.2f, dynamic "
      "%.2f (ratio %.2f; thesis: the same amount)\n",
      rel, fs, fd, fs / fd);
  // "Slowed down by the same amount": within a factor 2.5 of each other (the per-iteration cost
  // ratio is identical, so this compares iteration growth, which CG and SS22 share as √κ).
  EXPECT_TRUE(std::isfinite(fs) && std::isfinite(fd));
  EXPECT_LT(fs / fd, 2.5);
  EXPECT_GT(fs / fd, 1.0 / 2.5);
}

// Fig. 4.13 / §4.5.5: StVK with E = 2e4: no inversion, and static ≈ dynamic again.
TEST(Chapter4, StiffStvk_Sec4_5_5_Fig4_13) {
  RunOptions ro;
  ro.line_searches = false;
  const CaseResult r = run_case(Case{"stvk", false, 2e4}, ro);
  write_figure("fig4_13_analogue_stiff_stvk_small.svg", "Fig. 4.13 analogue: " + figure_title(r.c),
               r.runs);
  std::printf("[fig 4.13] StVK E = 2e4: %d inverted elements at the reference\n",
              r.inverted.inverted_elements);
  EXPECT_EQ(r.inverted.inverted_elements, 0);  // thesis: "stiffer material does not invert"
  check_conclusions(r);
}

#endif

}  // namespace
}  // namespace incise::solver
