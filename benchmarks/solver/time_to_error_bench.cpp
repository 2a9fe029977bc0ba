/// Time to a relative energy-norm error of 1e-6 (issue 19): process CPU seconds until
/// ‖u − û‖_{K(û)} / ‖û‖_{K(û)} ≤ 1e-6 for linear CG, nonlinear CG (secant, Polak–Ribière, the
/// scene default) and SS22 (Δt, η from the automatic estimate, computed outside the timing), on
/// the 16³×6 mirrored cube of issue 19 (mesh::make_kuhn_cube(16, 0.1), the cube of the thesis'
/// Maubach meshes; 0.1 m, face x = 0 fixed, gravity 9.8 m/s² sideways (−z),
/// E = 1e4 Pa, ν = 0.3, ρ = 1000 kg/m³; Veronda–Westmann with γ = 8 of Table 4.1).
/// û: truncated Newton to ‖r‖ ≤ 1e-11‖f‖ (linear: CG to 1e-13). The error is measured by the
/// iteration observer (its cost is excluded from the solver's time; CostMeter); the time is the
/// process CPU time (all threads) at the first iteration from which the error stays ≤ 1e-6.
/// Counters: cpu_s (to 1e-6), iters (to 1e-6), ms_per_iter, inner_per_iter
/// (SolverReport::inner_iterations / iterations of the run up to the hit: NCG line-search
/// evaluations, SS22 K-products of the quadratic recurrence); ncg-warm: the warm-start secant
/// search (LineSearchKind::kSecantWarmStart); ss22-energy4: SS22 with Π on every 4th step only
/// (DynamicRelaxationOptions::energy_every = 4). BM_PerIteration/<material>/<method>: CPU ms per
/// iteration in a long run (best of batches; the per-iteration table of docs/solvers.md),
/// BM_Evaluation: CPU ms per evaluation at û; BM_EstimateShare/<material>: the automatic Δt/η
/// estimate's CPU against the SS22 solve to 1e-6 it serves (counter estimate_share);
/// BM_DampingSweep/<material>: iterations to 1e-6 over η = factor·2√θ₁. Command:
/// build/release/benchmarks/solver/time_to_error_bench [--benchmark_filter=...]
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/energy_error.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>
#include <incise/solver/truncated_newton.hpp>

#include <benchmark/benchmark.h>

#include <time.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>

namespace {

using namespace incise;

double process_cpu() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

constexpr int kCells = 16;
constexpr double kLevel = 1e-6;

struct Case {
  std::unique_ptr<fem::ElasticProblem> problem;
  VecX reference;
  double reference_norm2 = 0.0;  // (û, û)_{K(û)}
};

Case& get_case(const std::string& material) {
  static std::map<std::string, Case> cases;
  auto it = cases.find(material);
  if (it != cases.end()) return it->second;
  Case c;
  const mesh::MeshData m = mesh::make_kuhn_cube(kCells, 0.1);
  material::Parameters p;
  p.youngs_modulus = 1e4;
  p.poisson_ratio = 0.3;
  p.density = 1000.0;
  p.gamma = material == "veronda-westmann" ? 8.0 : 0.0;
  // "linear-assembled": the linear model with ElasticProblem::set_assembled_product (K·d from
  // the assembled K, 3×3 blocks, instead of the element sweep).
  const bool assembled = material == "linear-assembled";
  c.problem = std::make_unique<fem::ElasticProblem>(
      m, material::Material(assembled ? "linear" : material, p));
  if (assembled) c.problem->set_assembled_product(true);
  c.problem->fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
  c.problem->add_gravity(Vec3(0.0, 0.0, -9.8));
  c.reference = VecX::Zero(c.problem->size());
  if (material != "veronda-westmann") {
    solver::LinearCgOptions o;
    o.stop.rule = solver::ResidualRule::kExternalForce;
    o.stop.epsilon = 1e-13;
    (void)solver::linear_cg(*c.problem, c.reference, o);
  } else {
    solver::TruncatedNewtonOptions o;
    o.stop.rule = solver::ResidualRule::kExternalForce;
    o.stop.epsilon = 1e-11;
    (void)solver::truncated_newton(*c.problem, c.reference, o);
  }
  solver::EnergyErrorTrace t(*c.problem, c.reference);
  c.reference_norm2 = t.energy_error(VecX::Zero(c.problem->size()));
  return cases.emplace(material, std::move(c)).first->second;
}

/// kNcgWarm: nonlinear CG with the warm-start secant search (LineSearchKind::kSecantWarmStart);
/// kSs22Energy4: SS22 with Π on every 4th step only (DynamicRelaxationOptions::energy_every).
enum class Method { kCg, kNcg, kNcgWarm, kSs22, kSs22Energy4 };

// One solve by `method` with the options `common` (SS22: step dt, damping eta).
template <class P>
solver::SolverReport run_method(Method method, P& p, VecX& u,
                                const solver::RelaxationOptions& common, double dt, double eta) {
  if (method == Method::kCg) {
    solver::LinearCgOptions o;
    static_cast<solver::RelaxationOptions&>(o) = common;
    return solver::linear_cg(p, u, o);
  }
  if (method == Method::kNcg || method == Method::kNcgWarm) {
    solver::NonlinearCgOptions o;
    static_cast<solver::RelaxationOptions&>(o) = common;
    if (method == Method::kNcgWarm) o.line_search = solver::LineSearchKind::kSecantWarmStart;
    return solver::nonlinear_cg(p, u, o);
  }
  solver::DynamicRelaxationOptions o;
  static_cast<solver::RelaxationOptions&>(o) = common;
  o.time_step = dt;
  o.damping = eta;
  o.gradient_recurrence = true;  // the third pass's figures (docs/solvers.md)
  if (method == Method::kSs22Energy4) o.energy_every = 4;
  return solver::dynamic_relaxation(p, u, o);
}

/// The first iteration from which the relative energy-norm error stays ≤ kLevel, the process
/// CPU seconds to it (observer excluded) and the counts of the run stopped there.
struct LevelHit {
  long iteration = -1;       ///< −1: not reached
  double cpu_seconds = NAN;  ///< process CPU to `iteration`
  long evaluations = 0;      ///< SolverReport::inner_iterations of the run stopped at the hit
  long iterations = 0;       ///< SolverReport::iterations of that run
};

LevelHit time_to_level(Case& c, Method method, double dt, double eta) {
  fem::ElasticProblem& p = *c.problem;
  LevelHit out;
  solver::EnergyErrorTrace trace(p, c.reference);
  VecX u = VecX::Zero(p.size());
  // First iteration from which the relative energy-norm error stays ≤ kLevel, and the CPU
  // seconds at it (observer CPU excluded: the observer measures its own and subtracts it).
  long hit = -1;
  double hit_cpu = 0.0, observer_cpu = 0.0;
  const double cpu0 = process_cpu();
  solver::RelaxationOptions common;
  common.stop.rule = solver::ResidualRule::kExternalForce;
  common.stop.epsilon = 1e-12;
  common.budget.max_iterations = 200000;
  common.observer = [&](const solver::IterationInfo& info) {
    const double now = process_cpu();
    const double rel = std::sqrt(trace.energy_error(*info.u) / c.reference_norm2);
    if (rel <= kLevel && hit < 0) {
      hit = info.iteration;
      hit_cpu = now - cpu0 - observer_cpu;
    } else if (rel > kLevel) {
      hit = -1;
    }
    observer_cpu += process_cpu() - now;
    if (hit >= 0 && info.iteration >= hit + 20) throw std::runtime_error("done");
  };
  try {
    (void)run_method(method, p, u, common, dt, eta);
  } catch (const std::runtime_error&) {
    // stopped 20 iterations after the level was reached and held
  }
  if (hit > 0) {  // the same run again, stopped at the hit, for its report's counts
    solver::RelaxationOptions upto = common;
    upto.observer = nullptr;
    upto.budget.max_iterations = hit;
    VecX w = VecX::Zero(p.size());
    const solver::SolverReport r2 = run_method(method, p, w, upto, dt, eta);
    out.evaluations = r2.inner_iterations;
    out.iterations = r2.iterations;
  }
  out.iteration = hit;
  if (hit >= 0) out.cpu_seconds = hit_cpu;
  return out;
}

void BM_TimeToError(benchmark::State& state, const std::string& material, Method method) {
  Case& c = get_case(material);
  fem::ElasticProblem& p = *c.problem;
  double dt = 0.0, eta = 0.0;
  const bool ss22 = method == Method::kSs22 || method == Method::kSs22Energy4;
#ifndef INCISE_TTE_BASELINE
  if (ss22) {
    const solver::DynamicParameterEstimate dp =
        solver::estimate_dynamic_parameters(p, VecX::Zero(p.size()));
    dt = dp.time_step;
    eta = dp.damping;
  }
#else
  // The baseline build (issue 19's before numbers) uses the values the estimate gives.
  dt = material == "linear" ? INCISE_TTE_DT_LINEAR : INCISE_TTE_DT_VW;
  eta = material == "linear" ? INCISE_TTE_ETA_LINEAR : INCISE_TTE_ETA_VW;
#endif
  if (ss22) {
    state.counters["dt_us"] = dt * 1e6;
    state.counters["eta"] = eta;
  }
  LevelHit h;
  for (auto _ : state) {
    h = time_to_level(c, method, dt, eta);
    state.counters["cpu_s"] = h.cpu_seconds;
    state.counters["iters"] = double(h.iteration);
    state.counters["ms_per_iter"] =
        h.iteration > 0 ? 1e3 * h.cpu_seconds / double(h.iteration) : NAN;
  }
  // NCG: line-search evaluations per iteration; SS22: K-products (quadratic recurrence) per step.
  if (h.iterations > 0)
    state.counters["inner_per_iter"] = double(h.evaluations) / double(h.iterations);
  state.counters["tets"] = double(p.num_elements());
}

#ifndef INCISE_TTE_BASELINE
/// The automatic Δt and η against the solve they serve (issue 19: the estimate shall cost
/// ≤ 10 % of it): estimate_dynamic_parameters at u = 0 (process CPU, the best of
/// kEstimateRuns calls: the machine is shared), then SS22 with its Δt, η to the relative
/// energy-norm error 1e-6 (time_to_level, the BM_TimeToError/<material>/ss22 run). Counters:
/// estimate_cpu_s, products (Lanczos K-products), solve_cpu_s, estimate_share =
/// estimate_cpu_s / solve_cpu_s.
constexpr int kEstimateRuns = 3;

void BM_EstimateShare(benchmark::State& state, const std::string& material) {
  Case& c = get_case(material);
  fem::ElasticProblem& p = *c.problem;
  for (auto _ : state) {
    double best = INFINITY;
    solver::DynamicParameterEstimate dp;
    for (int r = 0; r < kEstimateRuns; ++r) {
      const double cpu0 = process_cpu();
      dp = solver::estimate_dynamic_parameters(p, VecX::Zero(p.size()));
      best = std::min(best, process_cpu() - cpu0);
    }
    const LevelHit h = time_to_level(c, Method::kSs22, dp.time_step, dp.damping);
    state.counters["estimate_cpu_s"] = best;
    state.counters["products"] = double(dp.products);
    state.counters["solve_cpu_s"] = h.cpu_seconds;
    state.counters["iters"] = double(h.iteration);
    state.counters["estimate_share"] = best / h.cpu_seconds;
    state.counters["dt_us"] = dp.time_step * 1e6;
    state.counters["eta"] = dp.damping;
  }
}

/// The room in η (docs/solvers.md, "Eighth pass"): SS22 iterations to the relative energy-norm
/// error 1e-6 (time_to_level) with the automatic Δt and η = factor·2√θ₁ (θ₁ of the automatic
/// estimate; factor 1 is the critical damping used before the eighth pass) for the factors of
/// kSweepFactors, and with the automatic η = 2ζ√θ₁. Counters: iters_f<factor> (−1: not reached
/// in 200,000 steps), iters_auto, zeta. Step counts are deterministic.
constexpr double kSweepFactors[] = {0.9, 0.94, 0.96, 0.98, 0.99, 1.0, 1.011, 1.02, 1.05, 1.1};

void BM_DampingSweep(benchmark::State& state, const std::string& material) {
  Case& c = get_case(material);
  fem::ElasticProblem& p = *c.problem;
  for (auto _ : state) {
    const solver::DynamicParameterEstimate dp =
        solver::estimate_dynamic_parameters(p, VecX::Zero(p.size()));
    for (double f : kSweepFactors) {
      const LevelHit h = time_to_level(c, Method::kSs22, dp.time_step,
                                       f * solver::critical_damping(dp.lambda_min));
      char name[32];
      std::snprintf(name, sizeof name, "iters_f%.3f", f);
      state.counters[name] = double(h.iteration);
    }
    state.counters["iters_auto"] =
        double(time_to_level(c, Method::kSs22, dp.time_step, dp.damping).iteration);
    state.counters["zeta"] = dp.damping_ratio;
  }
}
#endif

/// One evaluation at the reference solution û (the per-iteration breakdown: an NCG iteration is
/// one K·d and one gradient+energy plus vector passes, an SS22 step one gradient+energy plus
/// vector passes). Counter ms_per_eval: process CPU ms per call.
/// kCurvature: dᵀK(u)d alone (Problem::hessian_curvature, the nonlinear-CG secant's first slope).
enum class Eval { kGradientEnergy, kGradient, kProduct, kGradientEnergyProduct, kCurvature };

void BM_Evaluation(benchmark::State& state, const std::string& material, Eval what) {
  Case& c = get_case(material);
  fem::ElasticProblem& p = *c.problem;
  const VecX& u = c.reference;
  VecX d = u, g, out;
  double e = 0.0;
  long calls = 0;
  const double cpu0 = process_cpu();
  for (auto _ : state) {
    switch (what) {
      case Eval::kGradientEnergy: (void)p.gradient(u, g, &e); break;
      case Eval::kGradient: (void)p.gradient(u, g); break;
      case Eval::kProduct: (void)p.hessian_product(u, d, out); break;
      case Eval::kGradientEnergyProduct: (void)p.gradient_energy_product(u, d, g, e, out); break;
      case Eval::kCurvature: (void)p.hessian_curvature(u, d, e); break;
    }
    benchmark::DoNotOptimize(g.data());
    benchmark::DoNotOptimize(e);
    benchmark::DoNotOptimize(out.data());
    ++calls;
  }
  state.counters["ms_per_eval"] = 1e3 * (process_cpu() - cpu0) / double(calls);
}

/// Cost of one iteration in a long run (the per-iteration table of docs/solvers.md): from the
/// state after `warm` nonlinear-CG iterations from u = 0 (300 Veronda–Westmann, 60 linear; outside
/// the timing), `kBatches` runs of kBatchIterations iterations of the method, each from that
/// state (SS22 from rest there), with the stopping rule off. Counter ms_per_iter: the smallest
/// process CPU ms per iteration over the batches (the machine is shared: the least disturbed
/// batch is the cost). Each batch includes the solver's start (one gradient+energy sweep).
constexpr int kBatches = 5;
constexpr long kBatchIterations = 20;

void BM_PerIteration(benchmark::State& state, const std::string& material, Method method) {
  Case& c = get_case(material);
  fem::ElasticProblem& p = *c.problem;
  VecX u0 = VecX::Zero(p.size());
  {
    solver::NonlinearCgOptions o;
    o.stop.epsilon = 0.0;
    o.budget.max_iterations = material == "veronda-westmann" ? 300 : 60;
    (void)solver::nonlinear_cg(p, u0, o);
  }
  double dt = 0.0, eta = 0.0;
  if (method == Method::kSs22 || method == Method::kSs22Energy4) {
    const solver::DynamicParameterEstimate dp =
        solver::estimate_dynamic_parameters(p, VecX::Zero(p.size()));
    dt = dp.time_step;
    eta = dp.damping;
  }
  double best = INFINITY;
  for (auto _ : state) {
    for (int b = 0; b < kBatches; ++b) {
      VecX u = u0;
      solver::RelaxationOptions common;
      common.stop.epsilon = 0.0;
      common.budget.max_iterations = kBatchIterations;
      const double cpu0 = process_cpu();
      const solver::SolverReport rep = run_method(method, p, u, common, dt, eta);
      const double cpu = process_cpu() - cpu0;
      if (rep.iterations > 0) best = std::min(best, 1e3 * cpu / double(rep.iterations));
    }
  }
  state.counters["ms_per_iter"] = best;
}

const bool kRegistered = [] {
  auto add = [](const std::string& name, const std::string& m, Method k) {
    benchmark::RegisterBenchmark(name.c_str(),
                                 [m, k](benchmark::State& s) { BM_TimeToError(s, m, k); })
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  };
  add("BM_TimeToError/linear/cg", "linear", Method::kCg);
  add("BM_TimeToError/linear/ncg", "linear", Method::kNcg);
  add("BM_TimeToError/linear/ss22", "linear", Method::kSs22);
  add("BM_TimeToError/linear-assembled/cg", "linear-assembled", Method::kCg);
  add("BM_TimeToError/linear-assembled/ncg", "linear-assembled", Method::kNcg);
  add("BM_TimeToError/linear-assembled/ss22", "linear-assembled", Method::kSs22);
  add("BM_TimeToError/veronda-westmann/ncg", "veronda-westmann", Method::kNcg);
  add("BM_TimeToError/veronda-westmann/ncg-warm", "veronda-westmann", Method::kNcgWarm);
  add("BM_TimeToError/veronda-westmann/ss22", "veronda-westmann", Method::kSs22);
  add("BM_TimeToError/veronda-westmann/ss22-energy4", "veronda-westmann", Method::kSs22Energy4);
#ifndef INCISE_TTE_BASELINE
  for (const std::string m : {"linear", "linear-assembled", "veronda-westmann"})
    benchmark::RegisterBenchmark(("BM_EstimateShare/" + m).c_str(),
                                 [m](benchmark::State& s) { BM_EstimateShare(s, m); })
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  for (const std::string m : {"linear", "veronda-westmann"})
    benchmark::RegisterBenchmark(("BM_DampingSweep/" + m).c_str(),
                                 [m](benchmark::State& s) { BM_DampingSweep(s, m); })
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
#endif
  auto per_iteration = [](const std::string& name, const std::string& m, Method k) {
    benchmark::RegisterBenchmark(name.c_str(),
                                 [m, k](benchmark::State& s) { BM_PerIteration(s, m, k); })
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond);
  };
  for (const std::string m : {"linear", "linear-assembled", "veronda-westmann"}) {
    if (m != "veronda-westmann") per_iteration("BM_PerIteration/" + m + "/cg", m, Method::kCg);
    per_iteration("BM_PerIteration/" + m + "/ncg", m, Method::kNcg);
    if (m == "veronda-westmann")
      per_iteration("BM_PerIteration/" + m + "/ncg-warm", m, Method::kNcgWarm);
    per_iteration("BM_PerIteration/" + m + "/ss22", m, Method::kSs22);
    if (m == "veronda-westmann")
      per_iteration("BM_PerIteration/" + m + "/ss22-energy4", m, Method::kSs22Energy4);
  }
  auto eval = [](const std::string& name, const std::string& m, Eval k) {
    benchmark::RegisterBenchmark(name.c_str(), [m, k](benchmark::State& s) {
      BM_Evaluation(s, m, k);
    })->Unit(benchmark::kMillisecond);
  };
  for (const std::string m : {"linear", "veronda-westmann"}) {
    eval("BM_Evaluation/" + m + "/gradient_energy", m, Eval::kGradientEnergy);
    eval("BM_Evaluation/" + m + "/gradient", m, Eval::kGradient);
    eval("BM_Evaluation/" + m + "/product", m, Eval::kProduct);
    eval("BM_Evaluation/" + m + "/gradient_energy_product", m, Eval::kGradientEnergyProduct);
    eval("BM_Evaluation/" + m + "/curvature", m, Eval::kCurvature);
  }
  return true;
}();

}  // namespace

BENCHMARK_MAIN();
