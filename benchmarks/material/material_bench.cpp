// Material-point benchmarks for every registered model (material/models.hpp): S(C) and
// S(C) + ∂S/∂C : H over a batch of 1024 random right Cauchy-Green tensors (each converted to
// the models' strain argument, strain_from_c, inside the timed and counted work). Counters:
// evaluations per second, counted MFLOP/s (per-evaluation flops from the counting scalar), % of the
// vector-add baseline measured in this run and % of the nominal FMA peak.
#include <benchmark/benchmark.h>
#include <incise/core/flop_count.hpp>
#include <incise/fixtures/deformations.hpp>
#include <incise/material/material.hpp>
#include <incise_bench/context.hpp>

#include <string>
#include <vector>

namespace {

using namespace incise;
using material::Mat3T;

constexpr std::size_t kBatch = 1024;

struct Batch {
  std::vector<Mat3> c, h;
};

const Batch& batch() {
  static const Batch b = [] {
    Batch out;
    fixtures::Rng rng(99);
    while (out.c.size() < kBatch) {
      const Mat3 f = Mat3::Identity() + fixtures::random_matrix(rng, 0.3);
      const Mat3 h = fixtures::random_matrix(rng, 0.3);
      if (f.determinant() < 0.2) continue;
      out.c.push_back(f.transpose() * f);
      out.h.push_back(h + h.transpose());
    }
    return out;
  }();
  return b;
}

void material_benchmark(benchmark::State& state, const std::string& name, bool derivative) {
  material::Parameters par;
  par.gamma = 1.0;
  const material::Material m(name, par);
  const material::Lame p = m.lame();
  const Batch& b = batch();
  std::vector<Mat3> s(kBatch), ds(kBatch);
  const std::uint64_t flops = material::visit_model(m.model_index(), [&](auto model) {
    using M = decltype(model);
    // Count once with the counting scalar.
    std::uint64_t counted = 0;
    {
      FlopScope scope;
      material::MaterialState<Counted> st;
      const Mat3T<Counted> c = b.c[0].cast<Counted>();
      Mat3T<Counted> sc;
      M::stress(p, material::strain_from_c<M>(c), st, sc);
      if (derivative) (void)M::stress_derivative(p, st, Mat3T<Counted>(b.h[0].cast<Counted>()));
      benchmark::DoNotOptimize(sc(0, 0).value());
      counted = scope.flops();
    }
    for (auto _ : state) {
      for (std::size_t i = 0; i < kBatch; ++i) {
        material::MaterialState<double> st;
        material::Strain<double> e;
        material::strain_from_c<M>(b.c[i], e);
        M::stress(p, e, st, s[i]);
        if (derivative) ds[i] = M::stress_derivative(p, st, b.h[i]);
      }
      benchmark::DoNotOptimize(s.data());
      benchmark::DoNotOptimize(ds.data());
      benchmark::ClobberMemory();
    }
    return counted;
  });
  const double evals = static_cast<double>(state.iterations()) * static_cast<double>(kBatch);
  const double fl = evals * static_cast<double>(flops);
  state.SetItemsProcessed(static_cast<std::int64_t>(evals));
  state.counters["flops_per_eval"] = static_cast<double>(flops);
  state.counters["MFLOP_per_s"] = benchmark::Counter(fl * 1e-6, benchmark::Counter::kIsRate);
  const double base = bench::vector_add_mflops();
  if (base > 0.0)
    state.counters["pct_vector_add"] =
        benchmark::Counter(fl * 1e-6 / base * 100.0, benchmark::Counter::kIsRate);
  const double peak = bench::fma_peak_mflops();
  if (peak > 0.0)
    state.counters["pct_fma_peak"] =
        benchmark::Counter(fl * 1e-6 / peak * 100.0, benchmark::Counter::kIsRate);
}

// Every registered material is enrolled automatically.
const bool kRegistered = [] {
  for (const std::string& name : material::registered_material_names()) {
    benchmark::RegisterBenchmark(("Material/" + name + "/stress").c_str(), material_benchmark, name,
                                 false);
    benchmark::RegisterBenchmark(("Material/" + name + "/stress+derivative").c_str(),
                                 material_benchmark, name, true);
  }
  return true;
}();

}  // namespace

INCISE_BENCHMARK_MAIN();
