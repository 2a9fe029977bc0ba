// Element loops on T threads (issue 19; docs/fem_performance.md "Element loops on T threads"):
// ElasticProblem's global sweeps on a 26 × 26 × 26 × 6 = 105,456-tet box at a random
// deformation, with the thread count as the benchmark argument (threads:T). Sweeps:
// Energy (Π alone), GradientEnergy (the fused gradient+energy of nonlinear CG), Product (K·d),
// GradientEnergyProduct (the fused Newton line-search point) and Assembly (the tangent into
// the fixed pattern), for neo-Hookean and Veronda-Westmann. Wall time (UseRealTime) and the
// process CPU time of all threads are both reported; the results are bitwise the same for
// every T (fem_threads_test), so only the time differs.
#include <benchmark/benchmark.h>
#include <incise/fem/elastic_problem.hpp>
#include <incise/fixtures/deformations.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_bench/context.hpp>

#include <string>

namespace {

using namespace incise;

enum class Sweep { kEnergy, kGradientEnergy, kProduct, kGradientEnergyProduct, kAssembly };

const mesh::MeshData& box() {
  static const mesh::MeshData m = mesh::make_box(26, 26, 26, 1.0, 1.0, 1.0);  // 105,456 tets
  return m;
}

void sweep_benchmark(benchmark::State& state, const std::string& name, Sweep sweep) {
  material::Parameters prm;
  prm.youngs_modulus = 1.0e4;
  prm.poisson_ratio = 0.3;
  prm.gamma = 1.0;
  prm.density = 1.0e3;
  fem::ElasticProblem pb(box(), material::Material(name, prm));
  pb.set_threads(static_cast<int>(state.range(0)));
  fixtures::Rng rng(7);
  const VecX u = fixtures::random_vector(rng, pb.size(), 1e-3);  // 2.6% of a cell
  const VecX d = fixtures::random_vector(rng, pb.size(), 1.0);
  VecX g, out;
  double e = 0.0;
  EvalStatus s = pb.assemble_tangent(u);  // builds the pattern outside the timed loop
  if (s != EvalStatus::kOk) state.SkipWithError("inverted state");
  for (auto _ : state) {
    switch (sweep) {
      case Sweep::kEnergy: s = pb.energy(u, e); break;
      case Sweep::kGradientEnergy: s = pb.gradient(u, g, &e); break;
      case Sweep::kProduct: s = pb.hessian_product(u, d, out); break;
      case Sweep::kGradientEnergyProduct: s = pb.gradient_energy_product(u, d, g, e, out); break;
      case Sweep::kAssembly: s = pb.assemble_tangent(u, fem::FixedDofTreatment::kKeep); break;
    }
    benchmark::DoNotOptimize(s);
    benchmark::DoNotOptimize(e);
    benchmark::ClobberMemory();
  }
  const double tets =
      static_cast<double>(pb.num_elements()) * static_cast<double>(state.iterations());
  state.counters["tets_per_s"] = benchmark::Counter(tets, benchmark::Counter::kIsRate);
  state.counters["chunks"] = pb.chunk_schedule().num_chunks();
  state.counters["colours"] = pb.chunk_schedule().num_colours;
}

const bool kRegistered = [] {
  const std::pair<const char*, Sweep> sweeps[] = {
      {"Energy", Sweep::kEnergy},
      {"GradientEnergy", Sweep::kGradientEnergy},
      {"Product", Sweep::kProduct},
      {"GradientEnergyProduct", Sweep::kGradientEnergyProduct},
      {"Assembly", Sweep::kAssembly}};
  for (const std::string name : {"neohookean", "veronda-westmann"})
    for (const auto& [label, sweep] : sweeps)
      benchmark::RegisterBenchmark(("ElementLoops/" + std::string(label) + "/" + name).c_str(),
                                   sweep_benchmark, name, sweep)
          ->ArgName("threads")
          ->Arg(1)
          ->Arg(2)
          ->UseRealTime()
          ->MeasureProcessCPUTime()
          ->Unit(benchmark::kMillisecond);
  return true;
}();

}  // namespace

INCISE_BENCHMARK_MAIN();
