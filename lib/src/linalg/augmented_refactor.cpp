#include "augmented_base.hpp"

#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>
#include <incise/linalg/augmented_system.hpp>
#include <incise/linalg/ldl_closure_solver.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <mutex>
#include <sstream>
#include <utility>

/// \file
/// AugmentedSystem: background refactorization (§3.6) and refactor_now.

namespace incise::linalg {

// ---------------------------------------------------------------------------------------------
// Background refactorization (§3.6).

bool AugmentedSystem::may_start_refactorization() const {
  if (!job_.valid()) return true;
  return options_.overlap_stale_columns > 0 && !job2_.valid() &&
         static_cast<int>(changed_since_snapshot_.size()) >= options_.overlap_stale_columns;
}

// prepare_in_job: 𝓛 after the pending job's swap as the last solve saw it (changed since the
// snapshot, and 𝓓), written by the frame thread, read once by the job after its factorization.
struct AugmentedSystem::KeepBoard {
  std::mutex mutex;
  std::vector<int> keep;  // sorted
};

void AugmentedSystem::publish_keep() {
  if (!board_) return;
  std::vector<int> keep(changed_since_snapshot_.begin(), changed_since_snapshot_.end());
  for (const auto& kv : dirichlet_)
    if (changed_since_snapshot_.count(kv.first) == 0 &&
        !std::binary_search(job_eliminated_.begin(), job_eliminated_.end(), kv.first))
      keep.push_back(kv.first);
  std::sort(keep.begin(), keep.end());
  const std::lock_guard<std::mutex> lock(board_->mutex);
  board_->keep = std::move(keep);
}

bool AugmentedSystem::start_refactorization() {
  INCISE_CHECK(base_ != nullptr, "start_refactorization before initialize");
  if (!may_start_refactorization()) return false;
  reap_abandoned(false);
  SparseMatrix snapshot = current_matrix();
  std::vector<int> eliminated = constrained_to_eliminate();
  std::unique_ptr<CholmodFactor> spare;  // a fresh object: its own cholmod_common
  const AugmentedOptions options = options_;
  const bool second = job_.valid();  // overlap: a second, newer snapshot (no prepared G)
  std::shared_ptr<KeepBoard> board;
  if (!second && options_.prepare_in_job && options_.prepare_swap &&
      options_.schur_solver == SchurSolver::kDirectCached)
    board = std::make_shared<KeepBoard>();
  auto job = std::async(std::launch::async, [m = std::move(snapshot), options, f = std::move(spare),
                                             board, eliminated]() mutable {
    std::unique_ptr<Base> base = make_base(std::move(m), std::move(f), options, eliminated);
    if (!board || base->status != FactorStatus::kOk) return base;
    // G of the new factor on the published labels that it factors (prepare_in_job).
    std::vector<int> l;
    {
      const std::lock_guard<std::mutex> lock(board->mutex);
      l = board->keep;
    }
    const int nb = static_cast<int>(base->matrix.rows());
    l.erase(std::lower_bound(l.begin(), l.end(), nb), l.end());
    if (l.empty()) return base;
    const double cpu0 = thread_cpu_seconds();
    ClosureLdlSolver& solver = *base->solver;
    const std::vector<int> closure = solver.closure(l);
    solver.solve_restricted_block(l, closure, closure, l, base->g, options.blas_kernels);
    base->g_l = std::move(l);
    base->times.prepare = thread_cpu_seconds() - cpu0;
    return base;
  });
  if (second) {
    changed_since_snapshot2_.clear();
    job2_ = std::move(job);
    job2_eliminated_ = std::move(eliminated);
  } else {
    changed_since_snapshot_.clear();
    snapshot_active_ = true;
    job_ = std::move(job);
    job_eliminated_ = std::move(eliminated);
    board_ = std::move(board);
    publish_keep();
  }
  return true;
}

void AugmentedSystem::reap_abandoned(bool wait) {
  for (auto it = abandoned_.begin(); it != abandoned_.end();) {
    if (wait || it->wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      (void)it->get();
      it = abandoned_.erase(it);
    } else {
      ++it;
    }
  }
}

// The newer job becomes the only one (after job_ was swapped in, or to replace it).
void AugmentedSystem::promote_second_job() {
  if (!job2_.valid()) return;
  if (job_.valid()) {
    abandoned_.push_back(std::move(job_));
    ++abandoned_count_;
  }
  job_ = std::move(job2_);
  job2_ = {};
  job_eliminated_ = std::move(job2_eliminated_);
  job2_eliminated_.clear();
  board_.reset();  // the newer job prepares in a second stage
  job_preparing_ = false;
  changed_since_snapshot_ = std::move(changed_since_snapshot2_);
  changed_since_snapshot2_.clear();
  snapshot_active_ = true;
}

bool AugmentedSystem::start_preparing(std::unique_ptr<Base>& base) {
  if (!options_.prepare_swap || options_.schur_solver != SchurSolver::kDirectCached ||
      base->status != FactorStatus::kOk)
    return false;
  const int nb = static_cast<int>(base->matrix.rows());
  std::set<int> keep;  // 𝓛 after the swap, on the new base's DOFs
  for (int j : changed_since_snapshot_)
    if (j < nb) keep.insert(j);
  for (const auto& kv : dirichlet_)
    if (kv.first < nb && !base->eliminated(kv.first)) keep.insert(kv.first);
  if (keep.empty()) return false;
  std::vector<int> l(keep.begin(), keep.end());
  job_preparing_ = true;
  job_ = std::async(std::launch::async, [b = std::move(base), l = std::move(l),
                                         dense = options_.blas_kernels]() mutable {
    const double cpu0 = thread_cpu_seconds();
    ClosureLdlSolver& solver = *b->solver;
    const std::vector<int> closure = solver.closure(l);
    solver.solve_restricted_block(l, closure, closure, l, b->g, dense);
    b->g_l = std::move(l);
    b->times.prepare = thread_cpu_seconds() - cpu0;
    return std::move(b);
  });
  return true;
}

bool AugmentedSystem::swap_in(std::unique_ptr<Base> base, const std::set<int>& changed_since) {
  job_preparing_ = false;
  job_eliminated_.clear();
  snapshot_active_ = false;
  last_refactor_status_ = base->status;
  if (base->status != FactorStatus::kOk) return false;
  const int nb = static_cast<int>(base->matrix.rows());
  for (auto it = changed_.begin(); it != changed_.end();) {
    if (changed_since.count(it->first) == 0 && it->first < nb) {
      it = changed_.erase(it);
    } else {
      ++it;
    }
  }
  base_ = std::move(base);
  ++base_generation_;  // a generation, not the address: a new Base may reuse a freed one's
  n_base_ = nb;
  if (!base_->g_l.empty()) {  // prepared in the background (prepare_swap): G's cache
    g_l_ = std::move(base_->g_l);
    g_ = std::move(base_->g);
    base_->g_l.clear();
    base_->g.resize(0, 0);
    g_generation_ = base_generation_;
  }
  changed_since_snapshot_.clear();
  return true;
}

bool AugmentedSystem::refactorization_stage_finished() const {
  return job_.valid() && job_.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
}

bool AugmentedSystem::poll_refactorization() {
  reap_abandoned(false);
  if (!job_.valid()) return false;
  const auto ready = [](std::future<std::unique_ptr<Base>>& j) {
    return j.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
  };
  if (!ready(job_)) {
    // overlap: the newer snapshot's factorization finished first; the older job is abandoned.
    if (!job2_.valid() || !ready(job2_)) return false;
    promote_second_job();
  }
  std::unique_ptr<Base> base = job_.get();
  board_.reset();
  // Not yet prepared (prepare_in_job had nothing to prepare, or is off): G in a second stage.
  if (!job_preparing_ && base->g_l.empty() && start_preparing(base)) return false;
  const bool swapped = swap_in(std::move(base), changed_since_snapshot_);
  promote_second_job();
  return swapped;
}

bool AugmentedSystem::wait_for_refactorization() {
  bool swapped = false;
  while (job_.valid()) {
    std::unique_ptr<Base> base = job_.get();
    board_.reset();
    if (!job_preparing_ && base->g_l.empty() && start_preparing(base)) base = job_.get();
    swapped = swap_in(std::move(base), changed_since_snapshot_) || swapped;
    promote_second_job();
  }
  return swapped;
}

bool AugmentedSystem::refactor_now() {
  INCISE_CHECK(base_ != nullptr, "refactor_now before initialize");
  if (job_.valid()) (void)wait_for_refactorization();
  changed_since_snapshot_.clear();
  return swap_in(make_base(current_matrix(), nullptr, options_, constrained_to_eliminate()), {});
}

// RefactorOrdering::kExtendCurrent: the factor in use's elimination order, each DOF added since
// (≥ n_base_) placed right after the latest-eliminated of its neighbours on the factored DOFs
// (in index order among equals; at the end without one). A DOF a cut adds copies a node, so its
// neighbours are a subset of the original's (and of other new DOFs): eliminated after them, it
// joins the separator of the latest, which keeps the nested dissection's fill (measured on the
// liver: docs/augmented.md, "Synchronous refactorization").
std::vector<int> AugmentedSystem::extended_ordering(const SparseMatrix& k) const {
  INCISE_CHECK(base_ != nullptr && base_->ldl != nullptr, "extended_ordering without a factor");
  INCISE_CHECK(k.rows() == k.cols() && k.rows() >= n_base_,
               "extended_ordering: the matrix must be square of order >= factored_dofs()");
  const int n = static_cast<int>(k.rows());
  const std::vector<int>& inverse = base_->ldl->inverse_perm;  // DOF → position
  const int nb = static_cast<int>(inverse.size());
  std::vector<double> key(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    if (j < nb) {
      key[static_cast<std::size_t>(j)] = inverse[static_cast<std::size_t>(j)];
      continue;
    }
    double latest = -1;
    for (SparseMatrix::InnerIterator it(k, j); it; ++it)
      if (it.row() < nb) latest = std::max(latest, key[static_cast<std::size_t>(it.row())]);
    key[static_cast<std::size_t>(j)] = (latest >= 0 ? latest : n) + 0.5;
  }
  std::vector<int> perm(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) perm[static_cast<std::size_t>(j)] = j;
  std::stable_sort(perm.begin(), perm.end(), [&key](int a, int b) {
    return key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)];
  });
  return perm;
}

bool AugmentedSystem::refactor_now(RefactorOrdering ordering, bool abandon_pending) {
  INCISE_CHECK(base_ != nullptr, "refactor_now before initialize");
  if (!abandon_pending) {
    if (job_.valid()) (void)wait_for_refactorization();
  } else {
    // The pending jobs' snapshots are older than the current K: their results are dropped
    // (std::async futures block on destruction, so they wait in abandoned_ until ready).
    reap_abandoned(false);
    for (auto* j : {&job_, &job2_}) {
      if (!j->valid()) continue;
      abandoned_.push_back(std::move(*j));
      *j = {};
      ++abandoned_count_;
    }
    board_.reset();
    job_eliminated_.clear();
    job2_eliminated_.clear();
    changed_since_snapshot2_.clear();
    job_preparing_ = false;
    snapshot_active_ = false;
  }
  changed_since_snapshot_.clear();
  AugmentedOptions options = options_;
  SparseMatrix k = current_matrix();
  std::vector<int> perm;
  if (ordering == RefactorOrdering::kAmd) options.cholmod.ordering = CholmodOrdering::kAmd;
  if (ordering == RefactorOrdering::kExtendCurrent) perm = extended_ordering(k);
  return swap_in(make_base(std::move(k), nullptr, options, constrained_to_eliminate(), perm), {});
}

}  // namespace incise::linalg
