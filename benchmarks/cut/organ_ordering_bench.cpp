/// The synchronous refactorization's elimination order on the liver (issue 17; part of the
/// organ_bench executable, whose main benchmark is documented in organ_bench.cpp; the liver:
/// organ_fixture.hpp). BM_SynchronousOrdering and its arguments are documented below.

#include "organ_fixture.hpp"

#include <benchmark/benchmark.h>
#include <incise/core/timer.hpp>
#include <incise/fixtures/organ_path.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/linalg/cholmod_factor.hpp>

#include <string>
#include <vector>

namespace incise::bench::organ {
namespace {

// The synchronous refactorization's elimination order (issue 17, docs/augmented.md "Synchronous
// refactorization"): the shipped liver's K after `frames` frames of the 10 mm path (no background
// jobs, so the same K every run), factored supernodally with METIS, AMD and the factor in use's
// ordering extended to the new DOFs (AugmentedSystem::extended_ordering, the default), in turn,
// `rounds` times. Counters: thread CPU of the symbolic analysis, numeric factorization and LDLᵀ
// export (median over the rounds, ms), nnz(L) and CHOLMOD's flop count.
void BM_SynchronousOrdering(benchmark::State& state) {
  const int frames = static_cast<int>(state.range(0)), rounds = static_cast<int>(state.range(1));
  const incise::mesh::MeshData& body = liver(false);
  const incise::fixtures::OrganPath path = incise::fixtures::organ_path(body);
  incise::interactive::AugmentedCutOptions opt;
  opt.automatic_refactorization = false;
  incise::interactive::AugmentedCutSession session(body, incise::fixtures::organ_material(),
                                                   path.fixed, path.forces, opt);
  for (int f = 0; f < frames; ++f) (void)session.frame(path.frame(f, 1e-2));
  incise::linalg::SparseMatrix k = session.system().current_matrix();
  k.makeCompressed();
  const std::vector<int> extended = session.system().extended_ordering(k);
  const char* names[3] = {"metis", "amd", "extended"};
  for (auto _ : state) {
    std::vector<double> t[3][3];
    for (int rep = 0; rep < rounds; ++rep) {
      for (int o = 0; o < 3; ++o) {
        incise::linalg::CholmodOptions co;
        co.kind = incise::linalg::CholmodKind::kSupernodal;
        co.ordering = o == 1 ? incise::linalg::CholmodOrdering::kAmd
                             : incise::linalg::CholmodOrdering::kMetis;
        incise::linalg::CholmodFactor fac(co);
        const double t0 = incise::thread_cpu_seconds();
        const auto st = o == 2 ? fac.analyze(k, 1, extended) : fac.analyze(k, 1);
        const double t1 = incise::thread_cpu_seconds();
        const auto sf = fac.factorize(k);
        const double t2 = incise::thread_cpu_seconds();
        const auto ldl = fac.extract_ldl();
        const double t3 = incise::thread_cpu_seconds();
        if (st != incise::linalg::FactorStatus::kOk || sf != incise::linalg::FactorStatus::kOk ||
            !ldl) {
          state.SkipWithError("factorization failed");
          return;
        }
        t[o][0].push_back(t1 - t0);
        t[o][1].push_back(t2 - t1);
        t[o][2].push_back(t3 - t2);
        state.counters[std::string(names[o]) + "_nnz_l"] = static_cast<double>(fac.nnz_l());
        state.counters[std::string(names[o]) + "_gflop"] = 1e-9 * fac.factor_flops();
      }
    }
    for (int o = 0; o < 3; ++o) {
      state.counters[std::string(names[o]) + "_analyze_ms"] = 1e3 * summarize(t[o][0]).median;
      state.counters[std::string(names[o]) + "_factorize_ms"] = 1e3 * summarize(t[o][1]).median;
      state.counters[std::string(names[o]) + "_extract_ms"] = 1e3 * summarize(t[o][2]).median;
    }
    state.counters["n"] = static_cast<double>(k.rows());
  }
}
BENCHMARK(BM_SynchronousOrdering)->Args({8, 5})->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace incise::bench::organ
