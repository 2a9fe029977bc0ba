/// The augmented solve's kernels on the liver of organ_fixture.hpp (issue 17; part of the
/// organ_bench executable, whose main benchmark is documented in organ_bench.cpp): the new
/// columns of G (BM_NewColumnsOfG) and the capacitance matrix's dense LU (BM_CapacitanceLu,
/// BM_CapacitanceFresh). Arguments beside each benchmark.

#include "organ_fixture.hpp"

#include <benchmark/benchmark.h>
#include <incise/fixtures/organ_path.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/linalg/capacitance_factor.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/linalg/dense_blas.hpp>
#include <incise/linalg/ldl_closure_solver.hpp>

#include <algorithm>
#include <cstddef>
#include <random>
#include <utility>
#include <vector>

namespace incise::bench::organ {
namespace {

/// A rows × cols matrix of uniform entries in [−1, 1] from std::mt19937 with the given seed: the
/// same matrix whatever ran before in the process (Eigen's Random draws from std::rand's shared
/// state).
Eigen::MatrixXd seeded_uniform(Eigen::Index rows, Eigen::Index cols, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd a(rows, cols);
  for (Eigen::Index j = 0; j < cols; ++j)
    for (Eigen::Index i = 0; i < rows; ++i) a(i, j) = u(rng);
  return a;
}

// The k new columns R⁻¹e of G = H R⁻¹ Hᵀ for DOFs joining 𝓛, one restricted solve each (0), one
// blocked pass entry by entry (1) or with its supernode blocks through dgemm/dtrsm (2; both
// ClosureLdlSolver::solve_restricted_block), on the liver's K⁰ factor
// (METIS; simplicial LDLᵀ, or supernodal as the session's defaults — linalg::interactive_options —
// whose LDLᵀ copy has the wide supernodes the blocked pass hands to dgemm/dtrsm): 𝓛 = the DOFs of
// the 300 nodes nearest the path's first blade position (m = 900), k of them joining. CPU time is
// the measure. Args: single / blocked / blocked dense (0/1/2), refined liver, supernodal (0/1), k.
void BM_NewColumnsOfG(benchmark::State& state) {
  const bool blocked = state.range(0) != 0;
  const bool dense = state.range(0) == 2;
  const incise::mesh::MeshData& body = liver(state.range(1) != 0);
  const incise::fixtures::OrganPath path = incise::fixtures::organ_path(body);
  incise::interactive::AugmentedCutOptions opt;
  opt.automatic_refactorization = false;
  incise::interactive::AugmentedCutSession session(body, incise::fixtures::organ_material(),
                                                   path.fixed, path.forces, opt);
  const incise::linalg::SparseMatrix k0 = session.system().current_matrix();
  incise::linalg::CholmodFactor factor({state.range(2) != 0
                                            ? incise::linalg::CholmodKind::kSupernodal
                                            : incise::linalg::CholmodKind::kSimplicialLdl,
                                        incise::linalg::CholmodOrdering::kMetis});
  const auto joining_count = static_cast<std::size_t>(state.range(3) > 0 ? state.range(3) : 40);
  if (factor.compute(k0, 1) != incise::linalg::FactorStatus::kOk) {
    state.SkipWithError("factorization failed");
    return;
  }
  incise::linalg::ClosureLdlSolver solver(factor.extract_ldl());
  const Vec3 blade = path.frame(0, 0.0)[0][1];
  std::vector<std::pair<double, Index>> near;
  for (Index v = 0; v < body.num_points(); ++v)
    if (session.dof(v) >= 0) near.emplace_back((body.points.col(v) - blade).norm(), v);
  std::partial_sort(near.begin(), near.begin() + 300, near.end());
  std::vector<int> l;
  for (int i = 0; i < 300; ++i)
    for (int c = 0; c < 3; ++c)
      l.push_back(session.dof(near[static_cast<std::size_t>(i)].second) + c);
  std::sort(l.begin(), l.end());
  std::vector<int> joining;
  for (std::size_t i = 0; i < l.size() && joining.size() < joining_count;
       i += std::max<std::size_t>(1, l.size() / joining_count))
    joining.push_back(l[i]);
  const std::vector<int> closure_y = solver.closure(l);
  double checksum = 0;
  for (auto _ : state) {
    if (blocked) {
      Eigen::MatrixXd y;
      solver.solve_restricted_block(joining, solver.closure(joining), closure_y, l, y, dense);
      checksum += y(0, 0);
    } else {
      std::vector<double> y;
      for (int j : joining) {
        const std::vector<int> e{j};
        solver.solve_restricted(e, {1.0}, solver.closure(e), closure_y, l, y);
        checksum += y[0];
      }
    }
  }
  benchmark::DoNotOptimize(checksum);
  state.counters["m"] = static_cast<double>(l.size());
  state.counters["k"] = static_cast<double>(joining.size());
  state.counters["closure_y"] = static_cast<double>(closure_y.size());
  state.counters["nnz_l"] = static_cast<double>(factor.extract_ldl()->nnz_l());
}
BENCHMARK(BM_NewColumnsOfG)
    ->Args({0, 0, 0, 40})
    ->Args({1, 0, 0, 40})
    ->Args({2, 0, 0, 40})
    ->Args({0, 1, 0, 40})
    ->Args({1, 1, 0, 40})
    ->Args({2, 1, 0, 40})
    ->Args({0, 0, 1, 40})
    ->Args({1, 0, 1, 40})
    ->Args({2, 0, 1, 40})
    ->Args({0, 0, 1, 150})
    ->Args({1, 0, 1, 150})
    ->Args({2, 0, 1, 150})
    ->Unit(benchmark::kMillisecond);

// The capacitance matrix's dense LU (linalg::DenseLu, the kernel of CapacitanceFactor's fresh
// factorization) at the m the liver path reaches: LAPACK's dgetrf of the loaded BLAS vs Eigen's
// PartialPivLU (SSE2 in this build), factorization + one solve with 100 right-hand sides (the
// W columns of an update). A random well-conditioned matrix (identity + coupling of norm ≤ 0.5).
// CPU time is the measure. Args: m, LAPACK (1) or Eigen (0).
void BM_CapacitanceLu(benchmark::State& state) {
  const auto m = static_cast<Eigen::Index>(state.range(0));
  const Eigen::MatrixXd a =
      Eigen::MatrixXd::Identity(m, m) + seeded_uniform(m, m, 1) * (0.5 / static_cast<double>(m));
  const Eigen::MatrixXd b = seeded_uniform(m, 100, 2);
  incise::linalg::DenseLu lu(state.range(1) != 0);
  double checksum = 0;
  for (auto _ : state) {
    lu.compute(a);
    Eigen::MatrixXd x = b;
    lu.solve_in_place(x);
    checksum += x(0, 0);
  }
  benchmark::DoNotOptimize(checksum);
  state.counters["lapack"] = lu.uses_blas() ? 1 : 0;
}
// A fresh CapacitanceFactor::update (force_fresh) on the same matrices: equilibration, the LU
// and Hager's condition estimate (≤ 5 iterations of two solves) — what a capacitance refresh
// costs a frame beside the bare LU above. Args: m, LAPACK (1) or Eigen (0).
void BM_CapacitanceFresh(benchmark::State& state) {
  const auto m = static_cast<Eigen::Index>(state.range(0));
  const Eigen::MatrixXd a =
      Eigen::MatrixXd::Identity(m, m) + seeded_uniform(m, m, 1) * (0.5 / static_cast<double>(m));
  std::vector<int> labels(static_cast<std::size_t>(m));
  for (std::size_t i = 0; i < labels.size(); ++i) labels[i] = static_cast<int>(i);
  incise::linalg::CapacitanceFactor factor(1.0, state.range(1) != 0);
  double checksum = 0;
  for (auto _ : state) checksum += factor.update(a, labels, /*force_fresh=*/true).rcond;
  benchmark::DoNotOptimize(checksum);
}
BENCHMARK(BM_CapacitanceFresh)
    ->Args({1000, 0})
    ->Args({1000, 1})
    ->Args({1500, 1})
    ->Unit(benchmark::kMillisecond);

BENCHMARK(BM_CapacitanceLu)
    ->Args({500, 0})
    ->Args({500, 1})
    ->Args({1000, 0})
    ->Args({1000, 1})
    ->Args({1500, 0})
    ->Args({1500, 1})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace incise::bench::organ
