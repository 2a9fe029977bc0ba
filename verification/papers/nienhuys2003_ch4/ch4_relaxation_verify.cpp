/// Thesis ch. 4 (§4.2, §4.4, §4.5, Figs 4.7–4.12): static nonlinear CG vs dynamic relaxation on
/// the cylinder of Table 4.1/4.2 (length 0.1 m, radius 0.03 m, E = 1e4 Pa, ν = 0.3,
/// ρ = 1000 kg/m³, g = 9.8 m/s², γ = 8, one end fixed; our structured stand-in for the small
/// Delaunay mesh: make_thesis_cylinder_small(), 1296 tetrahedra, 333 nodes).
///
/// Per material: a reference û (NCG to 1e-2, then truncated Newton to 1e-8; 1e-12 for the
/// linear model, §4.2); energy error (e, e)_{K(û)} traced against seconds and counted flops for
/// static CG (linear CG for the linear model; nonlinear CG with the Newton, secant and
/// scale-dependent secant line searches, PR and FR) and for SS22 dynamic relaxation with
/// η = 2√λ₁ (inverse iteration) and 2/3, 3/2 of it (the thesis' under/over-damped curves), Δt
/// from the thesis' procedure (§4.4.1). Writes CSV and SVG plots next to the test binary
/// (INCISE_CH4_OUTPUT_DIR) and checks the thesis' conclusions (§4.5.4, §4.5.5, §4.3.1).
/// Default run: the linear model; the `slow` entry (INCISE_CH4_ALL=1) adds the three nonlinear
/// models.
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/scene/svg_plot.hpp>
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
#include <cstdlib>
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

bool all_materials() {
  const char* v = std::getenv("INCISE_CH4_ALL");
  return v && std::string(v) == "1";
}

std::unique_ptr<fem::ElasticProblem> cylinder(const std::string& material, mesh::MeshData& m) {
  m = mesh::make_thesis_cylinder_small();
  material::Parameters p;  // Table 4.1
  p.youngs_modulus = 1e4;
  p.poisson_ratio = 0.3;
  p.density = 1000.0;
  p.gamma = material == "veronda-westmann" ? 8.0 : 0.0;
  auto prob = std::make_unique<fem::ElasticProblem>(m, material::Material(material, p));
  prob->fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
  prob->add_gravity(Vec3(0.0, 0.0, -9.8));
  return prob;
}

// Number of tetrahedra with non-positive deformed volume (det F ≤ 0) at displacement u.
int inverted_elements(const mesh::MeshData& m, const VecX& u) {
  int count = 0;
  for (Index e = 0; e < m.num_cells(); ++e) {
    Vec3 x[4];
    for (int a = 0; a < 4; ++a) {
      const Index n = m.cells(a, e);
      x[a] = m.points.col(n) + u.segment<3>(3 * n);
    }
    if ((x[1] - x[0]).cross(x[2] - x[0]).dot(x[3] - x[0]) <= 0.0) ++count;
  }
  return count;
}

struct TracedRun {
  std::string label;
  SolverReport report;
  std::vector<EnergyErrorTrace::Sample> samples;
};

// Counted flops at which the energy error first drops to `level`; +∞ if never.
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

void write_outputs(const std::string& material, const std::vector<TracedRun>& runs) {
  const std::string dir = INCISE_CH4_OUTPUT_DIR;
  std::ofstream csv(dir + "/ch4_energy_error_" + material + ".csv");
  csv << "material,method,iteration,seconds,flops,energy_error,residual_norm\n";
  std::vector<scene::Series> by_flops, by_seconds;
  for (const TracedRun& r : runs) {
    scene::Series sf, ss;
    sf.label = ss.label = r.label;
    for (const auto& s : r.samples) {
      csv << material << ',' << r.label << ',' << s.iteration << ',' << s.seconds << ',' << s.flops
          << ',' << s.energy_error << ',' << s.residual_norm << '\n';
      sf.x.push_back(double(s.flops) * 1e-6);
      sf.y.push_back(s.energy_error);
      ss.x.push_back(s.seconds);
      ss.y.push_back(s.energy_error);
    }
    by_flops.push_back(sf);
    by_seconds.push_back(ss);
  }
  scene::PlotOptions o;
  o.log_y = true;
  o.width = 720;
  o.height = 420;
  o.y_label = "energy error (e,e)_K(u^) [J]";
  o.title = "Cylinder, " + material + ": energy error vs counted flops (cf. thesis Figs 4.10-4.12)";
  o.x_label = "MFLOP";
  std::ofstream(dir + "/ch4_energy_error_vs_flops_" + material + ".svg")
      << scene::svg_line_plot(by_flops, o);
  o.title = "Cylinder, " + material + ": energy error vs seconds (this machine)";
  o.x_label = "seconds";
  std::ofstream(dir + "/ch4_energy_error_vs_seconds_" + material + ".svg")
      << scene::svg_line_plot(by_seconds, o);
}

class Chapter4 : public ::testing::TestWithParam<std::string> {};

TEST_P(Chapter4, StaticVsDynamicRelaxation_Sec4_5) {
  const std::string material = GetParam();
  if (!all_materials() && material != "linear")
    GTEST_SKIP() << "slow case: INCISE_CH4_ALL=1 (ctest -L slow)";
  mesh::MeshData m;
  auto prob = cylinder(material, m);
  fem::ElasticProblem& p = *prob;
  const VecX u0 = VecX::Zero(p.size());

  // Reference solution (§4.2).
  VecX ref = u0;
  {
    NonlinearCgOptions o;
    o.stop.rule = ResidualRule::kExternalForce;
    o.stop.epsilon = 1e-2;
    o.budget.max_iterations = 20000;
    (void)nonlinear_cg(p, ref, o);
    TruncatedNewtonOptions t;
    t.stop.rule = ResidualRule::kExternalForce;
    t.stop.epsilon = material == "linear" ? 1e-12 : 1e-8;
    t.budget.max_iterations = 200;
    const SolverReport rr = truncated_newton(p, ref, t);
    ASSERT_TRUE(rr.converged()) << "reference: " << to_string(rr.reason);
    std::printf(
        "[%s] reference: %ld Newton steps, %ld inner, |r|/|f| = %.2e, %d inverted "
        "elements, tip sag %.4f m\n",
        material.c_str(), rr.iterations, rr.inner_iterations,
        rr.residual_norm / p.external_force_norm(), inverted_elements(m, ref), -ref.minCoeff());
  }
  const int inverted_at_reference = inverted_elements(m, ref);

  const double flop_budget = 300e6;
  std::vector<TracedRun> runs;
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

  if (material == "linear") {
    trace_run("static CG", [&](VecX& u, IterationObserver obs) {
      LinearCgOptions o;
      o.stop = stop;
      o.budget.max_flops = flop_budget;
      o.observer = std::move(obs);
      return linear_cg(p, u, o);
    });
  }
  const std::vector<std::pair<std::string, LineSearchKind>> searches = {
      {"newton", LineSearchKind::kNewton},
      {"secant", LineSearchKind::kSecant},
      {"scale-dep. secant", LineSearchKind::kScaleDependentSecant}};
  for (const auto& [name, ls] : searches) {
    for (BetaRule beta : {BetaRule::kPolakRibiere, BetaRule::kFletcherReeves}) {
      if (beta == BetaRule::kFletcherReeves && ls != LineSearchKind::kSecant) continue;
      const std::string label = "NCG " + name + (beta == BetaRule::kPolakRibiere ? " PR" : " FR");
      const LineSearchKind kind = ls;
      trace_run(label, [&](VecX& u, IterationObserver obs) {
        NonlinearCgOptions o;
        o.stop = stop;
        o.line_search = kind;
        o.beta = beta;
        o.budget.max_flops = flop_budget;
        o.observer = std::move(obs);
        return nonlinear_cg(p, u, o);
      });
    }
  }

  // Dynamic parameters: Δt by the thesis' procedure, capped by 0.9·2/√λ_n (see
  // verification/solver/damping_verify.cpp: for stiffening materials the procedure's step can
  // become unstable late in the swing); η = 2√λ₁ and 2/3, 3/2 of it.
  const EigenEstimate big = largest_eigenvalue(p, u0, EigenOptions{1e-8, 20000, 1e-8, 1});
  const EigenEstimate small = smallest_eigenvalue(p, u0, EigenOptions{1e-6, 500, 1e-6, 1});
  ASSERT_TRUE(big.converged()) << to_string(big.reason) << " after " << big.iterations;
  ASSERT_TRUE(small.converged()) << to_string(small.reason) << " after " << small.iterations;
  double h = 1e300;
  for (Index e = 0; e < m.num_cells(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        h = std::min(h, (m.points.col(m.cells(a, e)) - m.points.col(m.cells(b, e))).norm());
  const material::Lame lame = p.material().lame();
  const StableTimeStep st =
      find_stable_time_step(p, u0, cfl_time_step(h, lame.lambda, lame.mu, 1000.0));
  ASSERT_TRUE(st.found);
  const double dt = std::min(st.time_step, 0.9 * critical_time_step(big.value));
  const double eta = critical_damping(small.value);
  std::printf("[%s] dt = %.4g s (procedure %.4g, 2/sqrt(lambda_n) %.4g), eta_crit = %.3g 1/s\n",
              material.c_str(), dt, st.time_step, critical_time_step(big.value), eta);
  const std::vector<std::pair<std::string, double>> dampings = {
      {"dynamic (underdamped 2/3)", 2.0 / 3.0 * eta},
      {"dynamic (critical)", eta},
      {"dynamic (overdamped 3/2)", 1.5 * eta}};
  for (const auto& [label, damping] : dampings) {
    const double d = damping;
    trace_run(label, [&](VecX& u, IterationObserver obs) {
      DynamicRelaxationOptions o;
      o.time_step = dt;
      o.damping = d;
      o.stop = stop;
      o.budget.max_flops = flop_budget;
      o.observer = std::move(obs);
      return dynamic_relaxation(p, u, o);
    });
  }
  write_outputs(material, runs);

  for (const TracedRun& r : runs)
    for (const auto& s : r.samples) {
      ASSERT_TRUE(!std::isnan(s.energy_error)) << r.label;
    }
  auto find = [&](const std::string& label) -> const TracedRun& {
    for (const TracedRun& r : runs)
      if (r.label == label) return r;
    throw std::runtime_error("no run " + label);
  };
  auto min_error = [](const TracedRun& r) {
    double lowest = std::numeric_limits<double>::infinity();
    for (const auto& s : r.samples) lowest = std::min(lowest, s.energy_error);
    return lowest;
  };
  // Comparison level: 1e-6 of the initial energy error, or — when the static method of the
  // thesis (linear CG / NCG secant PR) or every dynamic run stops short of that within the
  // 300 MFLOP budget (Veronda-Westmann) — the deepest level both reached.
  const std::string static_label = material == "linear" ? "static CG" : "NCG secant PR";
  const double best_dyn_min =
      std::min({min_error(find("dynamic (critical)")), min_error(find("dynamic (underdamped 2/3)")),
                min_error(find("dynamic (overdamped 3/2)"))});
  const double level = std::max({1e-6 * runs.front().samples.front().energy_error,
                                 min_error(find(static_label)), best_dyn_min});
  std::printf("[%s] to reach energy error %.3g J (%.1e of the initial):\n", material.c_str(), level,
              level / runs.front().samples.front().energy_error);
  std::printf("   %-28s %-18s %8s %10s %9s %8s %9s\n", "method", "end", "iters", "MFLOP", "seconds",
              "iter/s", "MFLOP/it");
  for (const TracedRun& r : runs)
    std::printf("   %-28s %-18s %8ld %10.2f %9.4f %8.0f %9.3f\n", r.label.c_str(),
                to_string(r.report.reason), r.report.iterations, flops_to(r, level) * 1e-6,
                seconds_to(r, level), r.report.iterations / r.report.seconds,
                r.report.flops * 1e-6 / std::max<long>(1, r.report.iterations));
  const double best_dyn = std::min({flops_to(find("dynamic (critical)"), level),
                                    flops_to(find("dynamic (underdamped 2/3)"), level),
                                    flops_to(find("dynamic (overdamped 3/2)"), level)});
  ASSERT_TRUE(std::isfinite(best_dyn)) << "no dynamic run reached the level";
  if (material == "linear") {
    // §4.5.4: "the CG iteration outperforms dynamic relaxation, by approximately a factor 5 to
    // 10". We require linear CG to need at most half the flops of the best dynamic run.
    const double cg = flops_to(find("static CG"), level);
    std::printf("[linear] best dynamic / linear CG flops = %.2f (thesis: 5-10)\n", best_dyn / cg);
    EXPECT_LT(2.0 * cg, best_dyn);
  } else {
    // §4.5.5: "the CG iteration is as quick as a dynamic relaxation with optimal parameters".
    // We require the thesis' setting (secant, PR) within a factor 3 of the best dynamic run.
    const double ncg = flops_to(find("NCG secant PR"), level);
    std::printf("[%s] NCG secant PR / best dynamic flops = %.2f (thesis: about 1)\n",
                material.c_str(), ncg / best_dyn);
    EXPECT_LT(ncg, 3.0 * best_dyn);
    EXPECT_LT(best_dyn, 3.0 * ncg);
  }
  if (material == "stvk") {
    // §4.3.1 / Fig. 4.3: StVK inverts elements near the clamp. Reported; detected by the
    // deformed-volume sign (StVK's energy is finite for det F ≤ 0, so Π cannot flag it).
    std::printf("[stvk] inverted elements at the reference solution: %d\n", inverted_at_reference);
  } else if (material != "linear") {
    EXPECT_EQ(inverted_at_reference, 0);  // log-barrier models never accept det F ≤ 0
  }
}

INSTANTIATE_TEST_SUITE_P(Materials, Chapter4,
                         ::testing::Values("linear", "stvk", "neohookean", "veronda-westmann"),
                         [](const ::testing::TestParamInfo<std::string>& i) {
                           std::string s = i.param;
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s;
                         });

}  // namespace
}  // namespace incise::solver
