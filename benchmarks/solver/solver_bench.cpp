/// Per-iteration cost of the relaxation algorithms (thesis §4.5.2, Table 4.5 analogue): linear
/// CG step, nonlinear CG step (secant line search, Polak-Ribière, ε_newton = 0.1) and SS22
/// dynamic step, for every registered material on both thesis-like cylinder meshes (§4.2:
/// length 0.1 m, radius 0.03 m, E = 1e4 Pa, ν = 0.3, ρ = 1000 kg/m³, g = 9.8 m/s², γ = 8, one
/// end fixed). Counters: iter/s, MFLOP/iter and MFLOP/s from the counted flops (Problem::flops
/// plus solver vector operations), and % of the vector-add baseline measured in this process.
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>
#include <incise_bench/context.hpp>

#include <benchmark/benchmark.h>

#include <memory>
#include <string>

namespace {

using namespace incise;

std::unique_ptr<fem::ElasticProblem> cylinder(const std::string& material, bool large) {
  const mesh::MeshData m =
      large ? mesh::make_thesis_cylinder_large() : mesh::make_thesis_cylinder_small();
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

void set_counters(benchmark::State& state, double iterations, double flops) {
  state.counters["iter/s"] = benchmark::Counter(iterations, benchmark::Counter::kIsRate);
  state.counters["MFLOP/iter"] = flops / iterations * 1e-6;
  state.counters["MFLOP/s"] = benchmark::Counter(flops * 1e-6, benchmark::Counter::kIsRate);
  // % of the vector-add baseline (Table 4.5's "% peak"), as a rate over the same time.
  state.counters["%baseline"] = benchmark::Counter(
      flops * 1e-6 * 100.0 / bench::vector_add_mflops(), benchmark::Counter::kIsRate);
}

void BM_LinearCgStep(benchmark::State& state) {
  auto p = cylinder("linear", state.range(0) != 0);
  double iters = 0, flops = 0;
  for (auto _ : state) {
    VecX u = VecX::Zero(p->size());
    solver::LinearCgOptions o;
    o.stop.epsilon = 0.0;  // run the full budget
    o.budget.max_iterations = 50;
    o.recompute_residual = false;
    const solver::SolverReport rep = solver::linear_cg(*p, u, o);
    iters += double(rep.iterations);
    flops += double(rep.flops);
    benchmark::DoNotOptimize(u.data());
  }
  set_counters(state, iters, flops);
}

void BM_NonlinearCgStep(benchmark::State& state, const std::string& material) {
  auto p = cylinder(material, state.range(0) != 0);
  double iters = 0, flops = 0;
  for (auto _ : state) {
    VecX u = VecX::Zero(p->size());
    solver::NonlinearCgOptions o;
    o.stop.epsilon = 0.0;
    o.budget.max_iterations = 20;
    const solver::SolverReport rep = solver::nonlinear_cg(*p, u, o);
    iters += double(rep.iterations);
    flops += double(rep.flops);
    benchmark::DoNotOptimize(u.data());
  }
  set_counters(state, iters, flops);
}

void BM_DynamicStep(benchmark::State& state, const std::string& material) {
  auto p = cylinder(material, state.range(0) != 0);
  double iters = 0, flops = 0;
  for (auto _ : state) {
    VecX u = VecX::Zero(p->size());
    solver::DynamicRelaxationOptions o;
    o.time_step = 1e-4;  // well below the critical step of both meshes: the run stays bounded
    o.damping = 20.0;
    o.stop.epsilon = 0.0;
    o.budget.max_iterations = 100;
    const solver::SolverReport rep = solver::dynamic_relaxation(*p, u, o);
    iters += double(rep.iterations);
    flops += double(rep.flops);
    benchmark::DoNotOptimize(u.data());
  }
  set_counters(state, iters, flops);
}

BENCHMARK(BM_LinearCgStep)->Arg(0)->Arg(1)->ArgName("large")->Unit(benchmark::kMillisecond);

// Every registered material is enrolled automatically.
const bool kRegistered = [] {
  for (const std::string& name : material::registered_material_names()) {
    benchmark::RegisterBenchmark(("BM_NonlinearCgStep/" + name).c_str(), BM_NonlinearCgStep, name)
        ->Arg(0)
        ->Arg(1)
        ->ArgName("large")
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark(("BM_DynamicStep/" + name).c_str(), BM_DynamicStep, name)
        ->Arg(0)
        ->Arg(1)
        ->ArgName("large")
        ->Unit(benchmark::kMillisecond);
  }
  return true;
}();

}  // namespace

INCISE_BENCHMARK_MAIN();
