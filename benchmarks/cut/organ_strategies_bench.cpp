/// Per-frame strategies side by side on the liver's scalpel path (issue 17; part of the
/// organ_bench executable, whose main benchmark is documented in organ_bench.cpp; the liver:
/// organ_fixture.hpp). BM_LiverStrategies and its arguments are documented below.

#include "organ_fixture.hpp"

#include <benchmark/benchmark.h>
#include <incise/core/problem.hpp>
#include <incise/core/timer.hpp>
#include <incise/fixtures/organ_path.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/solver/linear_cg.hpp>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace incise::bench::organ {
namespace {

// ---------------------------------------------------------------------------------------------
// Issue 17's side-by-side of per-frame strategies, in one run on the same path. The augmented
// session (defaults) cuts and solves; after every frame its system — K = system().current_matrix()
// (n × n, new DOFs included), f = system().force(), the constrained DOFs 𝓓 with the session's
// prescribed values ā — is written as one SPD system K̃ x = b with the rows and columns of 𝓓
// replaced by their diagonal (b_d = K_dd ā_d; b_i = f_i − Σ_d K_id ā_d), and solved by:
//   refactor  — a fresh CHOLMOD factorization (the session's supernodal METIS options; the
//               symbolic analysis kept while the pattern is unchanged) and a solve;
//   updown    — CholmodFactor::modify (cholmod_updown on a simplicial LDLᵀ of K̃ padded to a
//               DOF reserve with a scaled identity, so that new DOFs are a low-rank change too;
//               a fresh factorization with a doubled reserve when the reserve runs out or a
//               modification fails) of ΔK̃ = K̃_f − K̃_{f−1}, then a solve;
//   cg        — Jacobi-preconditioned CG (solver::projected_cg) on K̃ δ = b − K̃ x_{f−1}, warm
//               started from the previous frame's solution (new DOFs start at 0), stopping at
//               ‖r‖₂ ≤ 1e-8‖b‖₂ (or 20·n iterations).
// Statistics are over the frames that change K̃ or b (the others cost every strategy nothing
// but the cut: the session reuses its solution, and so would the alternatives). Timed: thread CPU
// of the strategy's own work from the assembled K̃ (the assembly and ΔK̃ are bookkeeping of this
// benchmark and not counted; the augmented column replacements are counted in its update). The cut
// is the same for every strategy (the session's); frame = cut + solver. Every changed frame's
// solutions are compared with an independent fresh factorization (CHOLMOD simplicial LDLᵀ, AMD):
// max-norm relative difference.
//   every     — a second session in lockstep with AugmentedCutOptions::refactor_every_step
//               (a library option, no scene key): its own cut and update, i.e. a factorization of
//               the current K in the frame thread and a solve with m = |𝓓| (its solution is
//               compared when its DOF count equals the first session's: the same cut).
// Args: refined (0/1), blade advance per frame (0.1 mm units), frames, the augmented session's
// §3.6 policy mode (0 continuous, the default; 1 break-even). bg_cpu_*: CPU of the swapped-in
// background factorizations (their own thread; not in any frame time).

/// K̃ x = b with 𝓓 eliminated symmetrically (see above); x_d = ā_d.
struct FrameSystem {
  incise::linalg::SparseMatrix k;
  Eigen::VectorXd b;
};

FrameSystem frame_system(const incise::interactive::AugmentedCutSession& session) {
  const incise::linalg::AugmentedSystem& sys = session.system();
  const incise::linalg::SparseMatrix k = sys.current_matrix();
  const int n = sys.num_dofs();
  Eigen::VectorXd abar = Eigen::VectorXd::Zero(n);
  std::vector<char> fixed(static_cast<std::size_t>(n), 0);
  for (Index v = 0; v < session.mesh().num_nodes(); ++v) {
    const int d = session.dof(v);
    if (d < 0) continue;
    for (int c = 0; c < 3; ++c)
      if (sys.is_constrained(d + c)) {
        fixed[static_cast<std::size_t>(d + c)] = 1;
        abar(d + c) = session.displacement()(c, v);
      }
  }
  FrameSystem out;
  out.b = sys.force() - k * abar;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(k.nonZeros()));
  for (int j = 0; j < n; ++j) {
    for (incise::linalg::SparseMatrix::InnerIterator it(k, j); it; ++it) {
      const int i = static_cast<int>(it.row());
      if (i == j) {
        t.emplace_back(i, j, it.value() != 0.0 ? it.value() : 1.0);
      } else if (!fixed[static_cast<std::size_t>(i)] && !fixed[static_cast<std::size_t>(j)]) {
        t.emplace_back(i, j, it.value());
      }
    }
  }
  out.k.resize(n, n);
  out.k.setFromTriplets(t.begin(), t.end());
  out.k.makeCompressed();
  for (int d = 0; d < n; ++d)
    if (fixed[static_cast<std::size_t>(d)]) out.b(d) = out.k.coeff(d, d) * abar(d);
  return out;
}

bool same_pattern(const incise::linalg::SparseMatrix& a, const incise::linalg::SparseMatrix& b) {
  return a.rows() == b.rows() && a.nonZeros() == b.nonZeros() &&
         std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1, b.outerIndexPtr()) &&
         std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr());
}

/// `a` (n × n) padded to order `size` with `scale`·I.
incise::linalg::SparseMatrix padded(const incise::linalg::SparseMatrix& a, int size, double scale) {
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(a.nonZeros() + size - a.rows()));
  for (int j = 0; j < a.outerSize(); ++j)
    for (incise::linalg::SparseMatrix::InnerIterator it(a, j); it; ++it)
      t.emplace_back(static_cast<int>(it.row()), j, it.value());
  for (int j = static_cast<int>(a.rows()); j < size; ++j) t.emplace_back(j, j, scale);
  incise::linalg::SparseMatrix out(size, size);
  out.setFromTriplets(t.begin(), t.end());
  out.makeCompressed();
  return out;
}

/// The quadratic ½xᵀK̃x − bᵀx as a solver::Problem for projected_cg (no fixed DOFs: 𝓓 is
/// eliminated in K̃; only project() and the products are used by the CG).
class AssembledQuadratic : public incise::Problem {
 public:
  AssembledQuadratic(const incise::linalg::SparseMatrix& k, const Eigen::VectorXd& b)
      : k_(k), b_(b) {}
  Eigen::Index size() const override { return b_.size(); }
  incise::EvalStatus energy(const incise::VecX& u, double& e) override {
    e = 0.5 * u.dot(k_ * u) - b_.dot(u);
    return incise::EvalStatus::kOk;
  }
  incise::EvalStatus gradient(const incise::VecX& u, incise::VecX& g, double* e) override {
    g = k_ * u - b_;
    if (e != nullptr) *e = 0.5 * u.dot(g - b_);
    return incise::EvalStatus::kOk;
  }
  incise::EvalStatus hessian_product(const incise::VecX&, const incise::VecX& d,
                                     incise::VecX& out) override {
    out = k_ * d;
    return incise::EvalStatus::kOk;
  }
  void project(incise::VecX&) const override {}
  bool is_fixed(Eigen::Index) const override { return false; }
  double external_force_norm() const override { return b_.norm(); }

 private:
  const incise::linalg::SparseMatrix& k_;
  const Eigen::VectorXd& b_;
};

/// The session's displacement at its `n` DOFs (the layout of its system's matrix).
Eigen::VectorXd dof_displacement(const incise::interactive::AugmentedCutSession& session, int n) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  for (Index v = 0; v < session.mesh().num_nodes(); ++v) {
    const int d = session.dof(v);
    if (d >= 0)
      for (int k = 0; k < 3; ++k) x(d + k) = session.displacement()(k, v);
  }
  return x;
}

double max_relative(const Eigen::VectorXd& x, const Eigen::VectorXd& ref) {
  const double scale = ref.cwiseAbs().maxCoeff();
  const double diff = (x.head(ref.size()) - ref).cwiseAbs().maxCoeff();
  return scale > 0 ? diff / scale : diff;
}

void BM_LiverStrategies(benchmark::State& state) {
  using incise::linalg::CholmodFactor;
  using incise::linalg::FactorStatus;
  const auto& [refined, advance, frames, body, path, material] = LiverPath(state);
  incise::interactive::AugmentedCutOptions aug_options;
  aug_options.refactorization_mode = refactorization_mode(state.range(3));
  for (auto _ : state) {
    incise::interactive::AugmentedCutSession session(body, material, path.fixed, path.forces,
                                                     aug_options);
    if (!session.initial_report().ok()) {
      state.SkipWithError(session.initial_report().message.c_str());
      return;
    }
    // The same path with AugmentedCutOptions::refactor_every_step, in lockstep.
    incise::interactive::AugmentedCutOptions every;
    every.refactor_every_step = true;
    incise::interactive::AugmentedCutSession session_every(body, material, path.fixed, path.forces,
                                                           every);
    FrameSystem prev = frame_system(session);
    const int n0 = static_cast<int>(prev.k.rows());
    // refactor: the session's factorization options.
    CholmodFactor refactor(incise::interactive::AugmentedCutOptions::supernodal_defaults().cholmod);
    std::uint64_t version = 1;
    // updown: simplicial LDLᵀ of K̃ padded to a reserve of DOFs.
    const double pad_scale = prev.k.diagonal().sum() / n0;
    int reserve = n0 + std::max(300, n0 / 8);
    auto updown = std::make_unique<CholmodFactor>(incise::linalg::CholmodOptions{
        incise::linalg::CholmodKind::kSimplicialLdl, incise::linalg::CholmodOrdering::kMetis});
    if (updown->compute(padded(prev.k, reserve, pad_scale), 1) != FactorStatus::kOk ||
        refactor.compute(prev.k, version) != FactorStatus::kOk) {
      state.SkipWithError("initial factorization failed");
      return;
    }
    Eigen::VectorXd x_cg;
    if (refactor.solve(prev.b, x_cg) != FactorStatus::kOk) {
      state.SkipWithError("initial solve failed");
      return;
    }
    std::vector<double> cut, aug, ref_t, upd_t, cg_t, every_t;
    double err_every = 0;
    int every_mismatch = 0;
    double err_aug = 0, err_ref = 0, err_upd = 0, err_cg = 0, worst_cg_res = 0;
    int changed = 0, updown_refactors = 0, updown_failures = 0, rank_max = 0, touched_max = 0;
    long cg_iterations = 0, cg_iter_max = 0;
    double rank_sum = 0, split_sum = 0, updown_sum = 0, bg_cpu = 0;
    int aug_swaps = 0, aug_m_max = 0;
    bool failed = false;
    for (int f = 0; f < frames && !failed; ++f) {
      double c = 0, u = 0, e = 0;
      for (const auto& tri : path.frame(f, advance)) {
        const incise::interactive::AugmentedCutStepReport r = session.step(tri);
        c += r.cpu_seconds_cut;
        u += r.cpu_seconds_update;
        if (!r.ok()) failed = true;
        if (r.refactorization_swapped) {
          ++aug_swaps;
          bg_cpu += session.system().factorization_cpu_seconds();
        }
        aug_m_max = std::max(aug_m_max, r.m_after_solve);
        const incise::interactive::AugmentedCutStepReport re = session_every.step(tri);
        e += re.cpu_seconds_update;
        if (!re.ok()) failed = true;
      }
      cut.push_back(c);
      aug.push_back(u);
      every_t.push_back(e);
      FrameSystem cur = frame_system(session);
      const bool pattern = same_pattern(cur.k, prev.k);
      const bool unchanged =
          pattern &&
          std::equal(cur.k.valuePtr(), cur.k.valuePtr() + cur.k.nonZeros(), prev.k.valuePtr()) &&
          cur.b == prev.b;
      if (unchanged) {  // statistics over the changed frames only
        cut.pop_back();
        aug.pop_back();
        every_t.pop_back();
        continue;
      }
      ++changed;
      const int n = static_cast<int>(cur.k.rows());
      // Independent reference (not timed).
      CholmodFactor reference(incise::linalg::CholmodOptions{
          incise::linalg::CholmodKind::kSimplicialLdl, incise::linalg::CholmodOrdering::kAmd});
      Eigen::VectorXd x_ref;
      if (reference.compute(cur.k, 1) != FactorStatus::kOk ||
          reference.solve(cur.b, x_ref) != FactorStatus::kOk) {
        state.SkipWithError("reference factorization failed");
        return;
      }
      // Augmented: the session's displacement at the DOFs.
      err_aug = std::max(err_aug, max_relative(dof_displacement(session, n), x_ref));
      if (session_every.system().num_dofs() == n) {  // the same cut (solutions agree to 1e-12)
        err_every = std::max(err_every, max_relative(dof_displacement(session_every, n), x_ref));
      } else {
        ++every_mismatch;
      }
      // Refactor every frame.
      {
        const double t0 = incise::thread_cpu_seconds();
        if (!pattern) ++version;
        Eigen::VectorXd x;
        const bool ok = refactor.compute(cur.k, version) == FactorStatus::kOk &&
                        refactor.solve(cur.b, x) == FactorStatus::kOk;
        ref_t.push_back(incise::thread_cpu_seconds() - t0);
        if (!ok) {
          state.SkipWithError("refactor strategy failed");
          return;
        }
        err_ref = std::max(err_ref, max_relative(x, x_ref));
      }
      // cholmod_updown of the padded factor.
      {
        const incise::linalg::SparseMatrix delta =
            n <= reserve ? incise::linalg::SparseMatrix((padded(cur.k, reserve, pad_scale) -
                                                         padded(prev.k, reserve, pad_scale))
                                                            .pruned())
                         : incise::linalg::SparseMatrix();
        const double t0 = incise::thread_cpu_seconds();
        CholmodFactor::ModifyStats stats;
        bool ok = n <= reserve;
        if (ok) {
          ok = updown->modify(delta, &stats) == FactorStatus::kOk;
          updown_failures += ok ? 0 : 1;
        }
        if (!ok) {  // reserve exhausted or modification failed: a fresh factor
          ++updown_refactors;
          while (reserve < n + 300) reserve *= 2;
          updown = std::make_unique<CholmodFactor>(
              incise::linalg::CholmodOptions{incise::linalg::CholmodKind::kSimplicialLdl,
                                             incise::linalg::CholmodOrdering::kMetis});
          ok = updown->compute(padded(cur.k, reserve, pad_scale), 1) == FactorStatus::kOk;
        }
        Eigen::VectorXd bp = Eigen::VectorXd::Zero(reserve), x;
        bp.head(n) = cur.b;
        ok = ok && updown->solve(bp, x) == FactorStatus::kOk;
        upd_t.push_back(incise::thread_cpu_seconds() - t0);
        if (!ok) {
          state.SkipWithError("updown strategy failed");
          return;
        }
        rank_max = std::max(rank_max, stats.rank_update + stats.rank_downdate);
        rank_sum += stats.rank_update + stats.rank_downdate;
        split_sum += stats.cpu_seconds_split;
        updown_sum += stats.cpu_seconds_updown;
        touched_max = std::max(touched_max, stats.touched);
        err_upd = std::max(err_upd, max_relative(x, x_ref));
      }
      // Warm-started Jacobi-PCG.
      {
        const double t0 = incise::thread_cpu_seconds();
        Eigen::VectorXd x0 = Eigen::VectorXd::Zero(n);
        x0.head(std::min<Eigen::Index>(n, x_cg.size())) =
            x_cg.head(std::min<Eigen::Index>(n, x_cg.size()));
        const Eigen::VectorXd r0 = cur.b - cur.k * x0;
        const Eigen::VectorXd inv_diag = cur.k.diagonal().cwiseInverse();
        AssembledQuadratic q(cur.k, cur.b);
        incise::solver::CostMeter meter(q);
        Eigen::VectorXd dx;
        const incise::solver::InnerCgResult res = incise::solver::projected_cg(
            [&](const incise::VecX& in, incise::VecX& out) {
              out = cur.k * in;
              return incise::EvalStatus::kOk;
            },
            q, inv_diag, r0, dx, 1e-8 * cur.b.norm(), 20L * n, meter);
        x_cg = x0 + dx;
        cg_t.push_back(incise::thread_cpu_seconds() - t0);
        cg_iterations += res.iterations;
        cg_iter_max = std::max(cg_iter_max, res.iterations);
        worst_cg_res = std::max(worst_cg_res, (cur.b - cur.k * x_cg).norm() / cur.b.norm());
        err_cg = std::max(err_cg, max_relative(x_cg, x_ref));
      }
      prev = std::move(cur);
    }
    if (failed) state.counters["session_failed"] = 1;
    const auto put = [&](const std::string& name, const std::vector<double>& solver) {
      std::vector<double> frame(solver.size());
      for (std::size_t i = 0; i < solver.size(); ++i) frame[i] = cut[i] + solver[i];
      const auto s = summarize(solver), fr = summarize(frame);
      state.counters[name + "_med_ms"] = 1e3 * fr.median;
      state.counters[name + "_p95_ms"] = 1e3 * fr.p95;
      state.counters[name + "_max_ms"] = 1e3 * fr.max;
      state.counters[name + "_solver_med_ms"] = 1e3 * s.median;
    };
    put("aug", aug);
    put("refactor", ref_t);
    put("updown", upd_t);
    put("cg", cg_t);
    put("every", every_t);
    state.counters["aug_swaps"] = aug_swaps;
    state.counters["aug_m_max"] = aug_m_max;
    state.counters["bg_cpu_total_s"] = bg_cpu;
    state.counters["bg_cpu_mean_ms"] = aug_swaps > 0 ? 1e3 * bg_cpu / aug_swaps : 0;
    state.counters["err_every"] = err_every;
    state.counters["every_dof_mismatch"] = every_mismatch;
    const auto sc = summarize(cut);
    state.counters["cut_med_ms"] = 1e3 * sc.median;
    state.counters["frames_changed"] = changed;
    state.counters["err_aug"] = err_aug;
    state.counters["err_refactor"] = err_ref;
    state.counters["err_updown"] = err_upd;
    state.counters["err_cg"] = err_cg;
    state.counters["cg_residual_max"] = worst_cg_res;
    state.counters["cg_iter_mean"] = changed > 0 ? static_cast<double>(cg_iterations) / changed : 0;
    state.counters["cg_iter_max"] = static_cast<double>(cg_iter_max);
    state.counters["updown_refactors"] = updown_refactors;
    state.counters["updown_failures"] = updown_failures;
    state.counters["updown_rank_max"] = rank_max;
    state.counters["updown_touched_max"] = touched_max;
    state.counters["updown_rank_mean"] = changed > 0 ? rank_sum / changed : 0;
    state.counters["updown_split_mean_ms"] = changed > 0 ? 1e3 * split_sum / changed : 0;
    state.counters["updown_cholmod_mean_ms"] = changed > 0 ? 1e3 * updown_sum / changed : 0;
    state.counters["n_final"] = static_cast<double>(prev.k.rows());
    state.counters["n0"] = n0;
  }
}
// Shipped liver at 1, 3 and 10 mm per frame (100 frames), and the refined liver at 3 mm.
BENCHMARK(BM_LiverStrategies)
    ->Args({0, 10, 100, 0})
    ->Args({0, 30, 100, 0})
    ->Args({0, 100, 100, 0})
    ->Args({0, 10, 100, 1})
    ->Args({0, 30, 100, 1})
    ->Args({0, 100, 100, 1})
    ->Args({1, 30, 100, 0})
    ->Iterations(1)
    ->Unit(benchmark::kSecond);

}  // namespace
}  // namespace incise::bench::organ
