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

namespace incise::linalg {

const char* to_string(AugmentedStatus status) {
  switch (status) {
    case AugmentedStatus::kOk: return "ok";
    case AugmentedStatus::kNoFactor: return "no factor";
    case AugmentedStatus::kSingularModifiedSystem: return "singular modified system";
    case AugmentedStatus::kGmresNotConverged: return "GMRES not converged";
    case AugmentedStatus::kNonFinite: return "non-finite data";
  }
  return "unknown";
}

ReducedMatrix remove_fixed_dofs(const SparseMatrix& k, const std::vector<bool>& fixed) {
  INCISE_CHECK(k.rows() == k.cols(), "remove_fixed_dofs: matrix must be square");
  INCISE_CHECK(static_cast<Eigen::Index>(fixed.size()) == k.rows(),
               "remove_fixed_dofs: fixed flags must have one entry per row");
  ReducedMatrix out;
  out.full_to_free.assign(fixed.size(), -1);
  int nf = 0;
  for (size_t i = 0; i < fixed.size(); ++i) {
    if (!fixed[i]) out.full_to_free[i] = nf++;
  }
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<size_t>(k.nonZeros()));
  for (int j = 0; j < k.outerSize(); ++j) {
    const int fj = out.full_to_free[j];
    if (fj < 0) continue;
    for (SparseMatrix::InnerIterator it(k, j); it; ++it) {
      const int fi = out.full_to_free[it.row()];
      if (fi >= 0) trip.emplace_back(fi, fj, it.value());
    }
  }
  out.matrix.resize(nf, nf);
  out.matrix.setFromTriplets(trip.begin(), trip.end());
  out.matrix.makeCompressed();
  return out;
}

// ---------------------------------------------------------------------------------------------
// Base: the factored matrix R (= K at the time of the last (re)factorization) and S of §3.5.

struct AugmentedSystem::Base {
  SparseMatrix matrix;  // K at the snapshot (the factored matrix but for `eliminated_diag`)
  // eliminate_constrained: K_dd > 0 for the DOFs d whose rows and columns the factored matrix
  // replaces by K_dd e_d, 0 elsewhere; empty when none.
  Eigen::VectorXd eliminated_diag;
  bool eliminated(int j) const { return j < eliminated_diag.size() && eliminated_diag(j) > 0; }
  std::unique_ptr<CholmodFactor> factor;
  std::shared_ptr<const LdlFactorData> ldl;
  std::unique_ptr<ClosureLdlSolver> solver;
  Eigen::VectorXd s_diag;                             // D⁻¹ in original order
  Eigen::VectorXd spai_lower, spai_diag, spai_upper;  // S(j+1,j), S(j,j), S(j,j+1)
  FactorStatus status = FactorStatus::kNotAnalyzed;
  std::string message;
  double seconds = 0;      // wall time of make_base (factorization, LDLᵀ copy, S)
  double cpu_seconds = 0;  // CPU time of the thread that ran make_base
  FactorizationCpu times;  // its split, and the background preparation of G
  // prepare_swap: G = (R⁻¹) of this factor on g_l (sorted), computed before the swap.
  std::vector<int> g_l;
  Eigen::MatrixXd g;
};

namespace {

std::uint64_t pattern_signature(const SparseMatrix& a) {
  std::uint64_t h = 1469598103934665603ULL;
  auto mix = [&h](std::uint64_t v) {
    h ^= v;
    h *= 1099511628211ULL;
  };
  mix(static_cast<std::uint64_t>(a.rows()));
  for (Eigen::Index j = 0; j <= a.outerSize(); ++j)
    mix(static_cast<std::uint64_t>(a.outerIndexPtr()[j]));
  for (Eigen::Index k = 0; k < a.nonZeros(); ++k)
    mix(static_cast<std::uint64_t>(a.innerIndexPtr()[k]));
  return h | 1ULL;  // never 0
}

double sparse_column_dot(const SparseMatrix& a, int s, int t) {
  SparseMatrix::InnerIterator is(a, s), it(a, t);
  double sum = 0;
  while (is && it) {
    if (is.row() < it.row()) {
      ++is;
    } else if (it.row() < is.row()) {
      ++it;
    } else {
      sum += is.value() * it.value();
      ++is;
      ++it;
    }
  }
  return sum;
}

// Tridiagonal sparse approximate inverse (Benson & Frederickson 1982; Yeung et al. §3.5):
// column j of S minimises ‖R S_{*j} − e_j‖₂ over vectors supported on {j−1, j, j+1}, solved
// through the 3×3 normal equations G c = R(j, idx) with G_st = R_{*s}·R_{*t}.
void tridiagonal_spai(const SparseMatrix& r, Eigen::VectorXd& lower, Eigen::VectorXd& diag,
                      Eigen::VectorXd& upper) {
  const int n = static_cast<int>(r.rows());
  lower = Eigen::VectorXd::Zero(n);
  diag = Eigen::VectorXd::Zero(n);
  upper = Eigen::VectorXd::Zero(n);
  for (int j = 0; j < n; ++j) {
    int idx[3];
    int cnt = 0;
    for (int t = j - 1; t <= j + 1; ++t) {
      if (t >= 0 && t < n) idx[cnt++] = t;
    }
    Eigen::Matrix3d g = Eigen::Matrix3d::Identity();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (int a = 0; a < cnt; ++a) {
      for (int b = a; b < cnt; ++b) g(a, b) = g(b, a) = sparse_column_dot(r, idx[a], idx[b]);
      rhs(a) = r.coeff(j, idx[a]);
    }
    const Eigen::VectorXd c = g.topLeftCorner(cnt, cnt).ldlt().solve(rhs.head(cnt));
    for (int a = 0; a < cnt; ++a) {
      const int t = idx[a];
      if (t == j) {
        diag(j) = c(a);
      } else if (t == j - 1) {
        upper(j - 1) = c(a);  // S(j−1, j)
      } else {
        lower(j) = c(a);  // S(j+1, j)
      }
    }
  }
}

}  // namespace

// Factors `matrix` and prepares S (§3.5). Runs in the caller's thread or in the background job;
// touches nothing but its arguments.
std::unique_ptr<AugmentedSystem::Base> AugmentedSystem::make_base(
    SparseMatrix matrix, std::unique_ptr<CholmodFactor> factor, const AugmentedOptions& options,
    const std::vector<int>& eliminated, const std::vector<int>& ordering) {
  const Timer timer;
  const double cpu0 = thread_cpu_seconds();
  auto base = std::make_unique<AugmentedSystem::Base>();
  base->matrix = std::move(matrix);
  base->matrix.makeCompressed();
  // The factored matrix: K with the rows and columns of the eliminated DOFs replaced by their
  // diagonal entry ("Fixed DOFs of K⁰", but kept in place so that a release can undo it).
  const int nm = static_cast<int>(base->matrix.rows());
  SparseMatrix masked;
  for (int d : eliminated) {
    if (d < 0 || d >= nm) continue;
    const double kdd = base->matrix.coeff(d, d);
    if (!(kdd > 0) || !std::isfinite(kdd)) continue;  // stays an augmented Dirichlet column
    if (base->eliminated_diag.size() == 0) base->eliminated_diag = Eigen::VectorXd::Zero(nm);
    base->eliminated_diag(d) = kdd;
  }
  if (base->eliminated_diag.size() != 0) {
    masked = base->matrix;
    const Base& b = *base;
    masked.prune([&b](const Eigen::Index& r, const Eigen::Index& c, const double&) {
      return r == c || (!b.eliminated(static_cast<int>(r)) && !b.eliminated(static_cast<int>(c)));
    });
    masked.makeCompressed();
  }
  const SparseMatrix& factored = base->eliminated_diag.size() != 0 ? masked : base->matrix;
  if (!factor) factor = std::make_unique<CholmodFactor>(options.cholmod);
  base->factor = std::move(factor);
  double cpu = thread_cpu_seconds();
  const auto lap = [&cpu]() {
    const double now = thread_cpu_seconds();
    const double d = now - cpu;
    cpu = now;
    return d;
  };
  base->status = base->factor->analyze(factored, pattern_signature(factored), ordering);
  base->times.analyze = lap();
  if (base->status == FactorStatus::kOk) base->status = base->factor->factorize(factored);
  base->times.factorize = lap();
  base->message = base->factor->message();
  if (base->status != FactorStatus::kOk) return base;
  base->ldl = base->factor->extract_ldl();
  if (!base->ldl) {
    base->status = base->factor->info() == FactorStatus::kOk ? FactorStatus::kCholmodError
                                                             : base->factor->info();
    base->message = "could not convert the factor to LDL'";
    return base;
  }
  base->solver = std::make_unique<ClosureLdlSolver>(base->ldl, options.solve_threads);
  const int n = base->ldl->n;
  base->s_diag.resize(n);
  for (int i = 0; i < n; ++i) base->s_diag(i) = 1.0 / base->ldl->d[base->ldl->inverse_perm[i]];
  if (options.preconditioner == SchurPreconditioner::kTridiagonalSpai) {
    tridiagonal_spai(factored, base->spai_lower, base->spai_diag, base->spai_upper);
  }
  base->times.extract = lap();
  base->seconds = timer.seconds();
  base->cpu_seconds = thread_cpu_seconds() - cpu0;
  return base;
}

AugmentedSystem::AugmentedSystem(AugmentedOptions options)
    : options_(options), capacitance_(1.0, options.blas_kernels) {
  INCISE_CHECK_PARAM(options_.solve_threads >= 1, "AugmentedOptions::solve_threads must be >= 1");
  INCISE_CHECK_PARAM(options_.max_amplification > 0 && options_.warn_amplification > 0,
                     "AugmentedOptions::max_amplification and warn_amplification must be > 0");
}

AugmentedSystem::~AugmentedSystem() {
  if (job_.valid()) job_.wait();
  if (job2_.valid()) job2_.wait();
  reap_abandoned(true);
}

FactorStatus AugmentedSystem::initialize(const SparseMatrix& k0) {
  INCISE_CHECK(k0.rows() == k0.cols(), "AugmentedSystem::initialize: K0 must be square");
  SparseMatrix k = k0;
  k.makeCompressed();
  {
    const SparseMatrix kt = k.transpose();
    INCISE_CHECK((kt - k).norm() <= 1e-12 * std::max(1e-300, k.norm()),
                 "AugmentedSystem::initialize: K0 must be symmetric with both triangles stored");
  }
  if (job_.valid()) job_.wait();
  if (job2_.valid()) job2_.wait();
  reap_abandoned(true);
  job_ = {};
  job2_ = {};
  board_.reset();
  changed_since_snapshot2_.clear();
  job_eliminated_.clear();
  job2_eliminated_.clear();
  job_preparing_ = false;
  std::unique_ptr<CholmodFactor> reuse;
  if (base_) reuse = std::move(base_->factor);
  base_ = make_base(std::move(k), std::move(reuse), options_);
  n_ = n_base_ = static_cast<int>(k0.rows());
  diag_scale_ = k0.rows() > 0 ? k0.diagonal().cwiseAbs().maxCoeff() : 1.0;
  if (!(diag_scale_ > 0)) diag_scale_ = 1.0;
  changed_.clear();
  dirichlet_.clear();
  ++base_generation_;
  g_generation_ = 0;
  f_ = Eigen::VectorXd::Zero(n_);
  changed_since_snapshot_.clear();
  snapshot_active_ = false;
  return base_->status;
}

const std::string& AugmentedSystem::factorization_message() const {
  static const std::string kNone;
  return base_ ? base_->message : kNone;
}

double AugmentedSystem::factorization_seconds() const {
  return base_ && base_->status == FactorStatus::kOk ? base_->seconds : 0.0;
}

double AugmentedSystem::factorization_cpu_seconds() const {
  return base_ && base_->status == FactorStatus::kOk ? base_->cpu_seconds : 0.0;
}

FactorizationCpu AugmentedSystem::factorization_cpu() const {
  return base_ && base_->status == FactorStatus::kOk ? base_->times : FactorizationCpu{};
}

FactorStatus AugmentedSystem::factorization_status() const {
  return base_ ? base_->status : FactorStatus::kNotAnalyzed;
}

const AugmentedSystem::Column* AugmentedSystem::changed_column(int j) const {
  auto it = changed_.find(j);
  return it == changed_.end() ? nullptr : &it->second;
}

AugmentedSystem::Column AugmentedSystem::column_of(int j) const {
  if (const Column* c = changed_column(j)) return *c;
  Column col;
  if (j < n_base_) {
    for (SparseMatrix::InnerIterator it(base_->matrix, j); it; ++it)
      col.emplace_back(static_cast<int>(it.row()), it.value());
  }
  return col;
}

void AugmentedSystem::touch_column(int j) {
  if (snapshot_active_) changed_since_snapshot_.insert(j);
  if (job2_.valid()) changed_since_snapshot2_.insert(j);
  if (changed_.count(j) != 0) return;
  changed_.emplace(j, column_of(j));
}

int AugmentedSystem::add_dofs(int count) {
  INCISE_CHECK(count >= 0, "add_dofs: count must be >= 0");
  INCISE_CHECK(base_ != nullptr, "add_dofs before initialize");
  const int first = n_;
  n_ += count;
  f_.conservativeResize(n_);
  for (int j = first; j < n_; ++j) {
    f_(j) = 0;
    touch_column(j);
  }
  return first;
}

void AugmentedSystem::add_element(const std::vector<int>& dofs, const Eigen::MatrixXd& ke,
                                  double scale) {
  INCISE_CHECK(base_ != nullptr, "add_element before initialize");
  const int s = static_cast<int>(dofs.size());
  INCISE_CHECK(ke.rows() == s && ke.cols() == s, "add_element: Ke must be square, sized like dofs");
  INCISE_CHECK((ke - ke.transpose()).cwiseAbs().maxCoeff() <=
                   1e-10 * std::max(1e-300, ke.cwiseAbs().maxCoeff()),
               "add_element: Ke must be symmetric");
  for (int d : dofs) INCISE_CHECK(d >= -1 && d < n_, "add_element: DOF index out of range");
  for (int a = 0; a < s; ++a) {
    const int j = dofs[a];
    if (j < 0) continue;
    touch_column(j);
    Column& col = changed_[j];
    for (int b = 0; b < s; ++b) {
      const int i = dofs[b];
      if (i < 0) continue;
      const double v = scale * ke(b, a);
      auto it = std::lower_bound(col.begin(), col.end(), std::make_pair(i, -HUGE_VAL));
      if (it != col.end() && it->first == i) {
        it->second += v;
      } else {
        col.insert(it, {i, v});
      }
    }
  }
}

void AugmentedSystem::impose_dirichlet(int dof, double value) {
  INCISE_CHECK(dof >= 0 && dof < n_, "impose_dirichlet: DOF index out of range");
  INCISE_CHECK_PARAM(std::isfinite(value), "impose_dirichlet: value must be finite");
  dirichlet_[dof] = value;
}

void AugmentedSystem::release_dirichlet(int dof) {
  INCISE_CHECK(dof >= 0 && dof < n_, "release_dirichlet: DOF index out of range");
  if (dirichlet_.erase(dof) == 0) return;
  // eliminate_constrained: a DOF eliminated in the factored matrix (or in a pending snapshot's)
  // brings back its row and column of K, so it and every column coupled to it differ from R.
  const auto in = [dof](const std::vector<int>& v) {
    return std::binary_search(v.begin(), v.end(), dof);
  };
  if (base_->eliminated(dof) || in(job_eliminated_) || in(job2_eliminated_)) {
    const Column col = column_of(dof);
    touch_column(dof);
    for (const auto& e : col) touch_column(e.first);
  }
}

std::vector<int> AugmentedSystem::constrained_to_eliminate() const {
  std::vector<int> d;
  if (!options_.eliminate_constrained) return d;
  d.reserve(dirichlet_.size());
  for (const auto& kv : dirichlet_) d.push_back(kv.first);  // sorted (std::map)
  return d;
}

bool AugmentedSystem::eliminated_now(int j) const {
  return base_->eliminated(j) && dirichlet_.count(j) != 0;
}

void AugmentedSystem::set_force(const Eigen::VectorXd& f) {
  INCISE_CHECK(f.size() == n_, "set_force: size must equal num_dofs()");
  f_ = f;
}

std::vector<int> AugmentedSystem::replaced_columns() const {
  std::vector<int> l;
  l.reserve(changed_.size() + dirichlet_.size());
  for (const auto& kv : changed_)
    if (!eliminated_now(kv.first)) l.push_back(kv.first);
  for (const auto& kv : dirichlet_) {
    if (changed_.count(kv.first) == 0 && !base_->eliminated(kv.first)) l.push_back(kv.first);
  }
  std::sort(l.begin(), l.end());
  return l;
}

int AugmentedSystem::num_replaced() const {
  return static_cast<int>(replaced_columns().size());
}

int AugmentedSystem::columns_without_g() const {
  if (!base_) return 0;
  const bool cached = g_generation_ == base_generation_;
  int k = 0;
  for (int j : replaced_columns()) {
    if (j >= n_base_) continue;  // a new DOF: R is the identity there, no column of G
    if (!cached || !std::binary_search(g_l_.begin(), g_l_.end(), j)) ++k;
  }
  return k;
}

SparseMatrix AugmentedSystem::current_matrix() const {
  INCISE_CHECK(base_ != nullptr, "current_matrix before initialize");
  std::vector<int> outer(static_cast<size_t>(n_) + 1, 0);
  std::vector<int> inner;
  std::vector<double> values;
  inner.reserve(static_cast<size_t>(base_->matrix.nonZeros()));
  values.reserve(static_cast<size_t>(base_->matrix.nonZeros()));
  for (int j = 0; j < n_; ++j) {
    outer[j] = static_cast<int>(inner.size());
    if (const Column* c = changed_column(j)) {
      for (const auto& [row, v] : *c) {
        inner.push_back(row);
        values.push_back(v);
      }
    } else if (j < n_base_) {
      for (SparseMatrix::InnerIterator it(base_->matrix, j); it; ++it) {
        inner.push_back(static_cast<int>(it.row()));
        values.push_back(it.value());
      }
    }
  }
  outer[n_] = static_cast<int>(inner.size());
  return Eigen::Map<const SparseMatrix>(n_, n_, static_cast<Eigen::Index>(inner.size()),
                                        outer.data(), inner.data(), values.data());
}

// Drops changed columns whose entries equal the base column again (bitwise; missing entries
// count as 0). Not while a snapshot is pending: swap_in() relies on changed_ for the columns
// changed since the snapshot.
int AugmentedSystem::prune_unchanged_columns() {
  if (snapshot_active_) return 0;
  int pruned = 0;
  for (auto it = changed_.begin(); it != changed_.end();) {
    const int j = it->first;
    // A released eliminated DOF differs from R in its column and in its row, i.e. in every
    // column coupled to it (eliminate_constrained).
    const auto released = [this](int r) {
      return base_->eliminated(r) && dirichlet_.count(r) == 0;
    };
    bool same = j < n_base_ && !released(j);
    for (const auto& e : it->second) same = same && !released(e.first);
    if (same) {
      const Column& c = it->second;
      SparseMatrix::InnerIterator b(base_->matrix, j);
      size_t k = 0;
      while (same && (b || k < c.size())) {
        if (b && (k == c.size() || b.row() < c[k].first)) {
          same = b.value() == 0;
          ++b;
        } else if (!b || c[k].first < b.row()) {
          same = c[k].second == 0;
          ++k;
        } else {
          same = b.value() == c[k].second;
          ++b;
          ++k;
        }
      }
    }
    if (same) {
      it = changed_.erase(it);
      ++pruned;
    } else {
      ++it;
    }
  }
  return pruned;
}

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

// ---------------------------------------------------------------------------------------------
// Solution (§3.1–3.5). solve() runs the steps below in order; each names its equations.

// The augmented structure of one solve: 𝓛 and 𝓓 (as flags), the columns of J (eq. 5; H of
// eq. 6 is implied by 𝓛), f̂ (eq. 11), their sparsity on the base rows and its closures (§3.3).
struct AugmentedSystem::Augmentation {
  std::vector<int> l;                 // 𝓛, sorted
  std::vector<int> l_base;            // the entries of 𝓛 below n_base (its first ones)
  std::vector<char> is_dirichlet;     // per entry of 𝓛: in 𝓓 (J column e_{𝓛ᵢ})
  std::vector<const Column*> j_cols;  // per entry of 𝓛: the stored column K_{*,𝓛ᵢ} (not 𝓓)
  std::deque<Column> masked;          // columns of J without the rows of eliminated DOFs
  std::vector<int> eliminated;        // 𝓓 ∩ eliminated in R (eliminate_constrained), sorted
  Eigen::VectorXd fhat;               // f̂ of eq. 11 (size n)
  std::vector<int> f_idx;             // struct(f̂) on the base rows, ascending
  std::vector<double> f_val;          // f̂ there
  std::vector<int> j_struct;          // struct(J) on the base rows, ascending
  std::vector<int> step3_struct;      // struct(f̂) ∪ struct(J): that of f̂ − J a₂ (step 3)
  std::vector<int> closure_f;         // closure_L(f̂)           (step 1 forward)
  std::vector<int> closure_y;         // closure_L(𝓛 ∩ base)     (backward, steps 1–2)
  std::vector<int> closure_j;         // closure_L(J)            (step 2 forward)
  std::vector<int> closure_step3;     // closure_L(f̂ − J a₂)     (step 3 forward)
  Eigen::VectorXd jv;                 // workspace for J v (size n), zero between uses

  int m() const { return static_cast<int>(l.size()); }

  // jv += J v (dense accumulation; v has one entry per column of J).
  void add_j_times(const Eigen::VectorXd& v) {
    for (int i = 0; i < m(); ++i) {
      const double vi = v(i);
      if (vi == 0) continue;
      if (is_dirichlet[i]) {
        jv(l[i]) += vi;
      } else {
        for (const auto& [row, kv] : *j_cols[i]) jv(row) += kv * vi;
      }
    }
  }
  // jv ← 0 on struct(J), restoring the invariant after add_j_times().
  void clear_jv() {
    for (int i = 0; i < m(); ++i) {
      if (is_dirichlet[i]) {
        jv(l[i]) = 0;
      } else {
        for (const auto& e : *j_cols[i]) jv(e.first) = 0;
      }
    }
  }
};

// Dense LU of an m×m approximation of H R⁻¹ J used as GMRES's right preconditioner: M = H S J
// (§3.5) or the explicit capacitance matrix (SchurSolver::kDirectCached).
struct AugmentedSystem::SchurLu {
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  Eigen::VectorXd row_scale, col_scale;  // equilibration (empty: none)
  bool usable = false;  // factored, and its rcond estimate exceeds kMinPreconditionerRcond
  double rcond = std::numeric_limits<double>::quiet_NaN();  // NaN: not factored

  // Factors `s`, equilibrated first when asked (max-norm rows, then columns). A numerically
  // singular matrix (rcond ≤ kMinPreconditionerRcond) is not usable: GMRES then runs
  // unpreconditioned (reported: note()), and its breakdown / stagnation / amplification checks
  // report a singular system.
  void factor(Eigen::MatrixXd s, bool equilibrate) {
    if (equilibrate) {
      row_scale = s.cwiseAbs().rowwise().maxCoeff().cwiseMax(1e-300).cwiseInverse();
      s = row_scale.asDiagonal() * s;
      col_scale = s.cwiseAbs().colwise().maxCoeff().transpose().cwiseMax(1e-300).cwiseInverse();
      s = s * col_scale.asDiagonal();
    }
    lu.compute(s);
    rcond = lu.rcond();
    usable = std::isfinite(rcond) && rcond > kMinPreconditionerRcond;
  }
  // The report's preconditioner fields, once factor() ran.
  void note(AugmentedReport& report) const {
    report.preconditioner_rcond = rcond;
    report.preconditioner_dropped = !usable;
  }
  // out = M⁻¹ v.
  void apply(const Eigen::VectorXd& v, Eigen::VectorXd& out) const {
    if (row_scale.size() == 0) {
      out = lu.solve(v);
    } else {
      out = col_scale.cwiseProduct(lu.solve(row_scale.cwiseProduct(v)));
    }
  }
};

// The augmentation procedure of §3.1, items 1–3: 𝓛 and 𝓓, the columns of J (eq. 5) and f̂
// (eq. 11, with f_d kept at constrained rows: the unknown becomes the reaction), and the
// structures the closures are taken of. Reports (and returns false for) a J column with
// non-finite entries or without stiffness.
bool AugmentedSystem::augment(Augmentation& aug, AugmentedReport& report) {
  const int n = n_;
  const int nb = n_base_;
  aug.l = replaced_columns();
  const int m = aug.m();
  report.m = m;
  report.dirichlet = static_cast<int>(dirichlet_.size());
  pos_in_l_.assign(static_cast<size_t>(n), -1);
  for (int i = 0; i < m; ++i) pos_in_l_[aug.l[i]] = i;
  // Constrained DOFs eliminated in R (eliminate_constrained): row and column K_dd e_d in both R
  // and the current system, so they are not in 𝓛 and their rows leave the columns of J.
  std::vector<char> elim_row;
  for (const auto& kv : dirichlet_) {
    if (!base_->eliminated(kv.first)) continue;
    if (elim_row.empty()) elim_row.assign(static_cast<size_t>(nb), 0);
    elim_row[static_cast<size_t>(kv.first)] = 1;
    aug.eliminated.push_back(kv.first);
  }
  report.dirichlet_eliminated = static_cast<int>(aug.eliminated.size());

  // J columns (eq. 5) as pointers to stored columns; Dirichlet columns are e_{𝓛ᵢ}.
  aug.j_cols.assign(m, nullptr);
  aug.is_dirichlet.assign(m, 0);
  for (int i = 0; i < m; ++i) {
    const int j = aug.l[i];
    if (dirichlet_.count(j) != 0) {
      aug.is_dirichlet[i] = 1;
      continue;
    }
    aug.j_cols[i] = changed_column(j);
    if (!elim_row.empty() && aug.j_cols[i] != nullptr) {
      const Column& c = *aug.j_cols[i];
      const auto is_elim = [&elim_row, nb](const std::pair<int, double>& e) {
        return e.first < nb && elim_row[static_cast<size_t>(e.first)] != 0;
      };
      if (std::any_of(c.begin(), c.end(), is_elim)) {
        Column& mc = aug.masked.emplace_back();
        mc.reserve(c.size());
        for (const auto& e : c)
          if (!is_elim(e)) mc.push_back(e);
        aug.j_cols[i] = &mc;
      }
    }
    bool any = false;
    if (aug.j_cols[i] != nullptr) {
      for (const auto& e : *aug.j_cols[i]) {
        if (!std::isfinite(e.second)) {
          report.status = AugmentedStatus::kNonFinite;
          report.message = "column " + std::to_string(j) + " of K has NaN/Inf entries";
          return false;
        }
        any = any || std::abs(e.second) > 1e-13 * diag_scale_;
      }
    }
    if (!any) {
      report.status = AugmentedStatus::kSingularModifiedSystem;
      report.message = "DOF " + std::to_string(j) +
                       " has no stiffness (empty column of K): attach it to elements, constrain "
                       "it with impose_dirichlet(), or stop using it";
      return false;
    }
  }

  // f̂ = f − Σ_{d∈𝓓} K_{*,d} ā_d (eq. 11), and its structure on the base rows.
  aug.fhat = f_;
  for (const auto& [d, value] : dirichlet_) {
    if (value == 0) continue;
    if (const Column* c = changed_column(d)) {
      for (const auto& [row, v] : *c) aug.fhat(row) -= v * value;
    } else if (d < nb) {
      for (SparseMatrix::InnerIterator it(base_->matrix, d); it; ++it)
        aug.fhat(static_cast<int>(it.row())) -= it.value() * value;
    }
  }
  // Eliminated rows: K_dd a_d = K_dd ā_d (the row of R).
  for (int d : aug.eliminated) aug.fhat(d) = base_->eliminated_diag(d) * dirichlet_.at(d);
  for (int i = 0; i < nb; ++i) {
    if (aug.fhat(i) != 0) {
      aug.f_idx.push_back(i);
      aug.f_val.push_back(aug.fhat(i));
    }
  }
  // Structure of J and of 𝓛 on the base rows, and that of f̂ − J a₂ (step 3).
  std::vector<char> in_j(static_cast<size_t>(nb), 0);
  auto add_row = [&](int row) {
    if (row < nb && !in_j[row]) {
      in_j[row] = 1;
      aug.j_struct.push_back(row);
    }
  };
  for (int i = 0; i < m; ++i) {
    if (aug.is_dirichlet[i]) {
      add_row(aug.l[i]);
    } else {
      for (const auto& e : *aug.j_cols[i]) add_row(e.first);
    }
  }
  std::sort(aug.j_struct.begin(), aug.j_struct.end());
  for (int j : aug.l) {
    if (j < nb) aug.l_base.push_back(j);
  }
  aug.step3_struct = aug.f_idx;
  aug.step3_struct.insert(aug.step3_struct.end(), aug.j_struct.begin(), aug.j_struct.end());
  std::sort(aug.step3_struct.begin(), aug.step3_struct.end());
  aug.step3_struct.erase(std::unique(aug.step3_struct.begin(), aug.step3_struct.end()),
                         aug.step3_struct.end());
  aug.jv = Eigen::VectorXd::Zero(n);
  return true;
}

// Elimination-tree closures of the right-hand sides and wanted sets of steps 1–3 (§3.3,
// Appendix Thm. 1–3); their sizes go into the report (Fig. 4 of the paper).
void AugmentedSystem::find_closures(Augmentation& aug, AugmentedReport& report) {
  ClosureLdlSolver& solver = *base_->solver;
  aug.closure_f = solver.closure(aug.f_idx);
  aug.closure_y = solver.closure(aug.l_base);
  aug.closure_j = solver.closure(aug.j_struct);
  aug.closure_step3 = solver.closure(aug.step3_struct);
  report.closure_f = static_cast<int>(aug.closure_f.size());
  report.closure_y = static_cast<int>(aug.closure_y.size());
  report.closure_ja2 = static_cast<int>(aug.closure_j.size());
  report.closure_step3 = static_cast<int>(aug.closure_step3.size());
}

// M = H S J of §3.5 (m × m), S = D⁻¹ (kDiagonal) or the tridiagonal SPAI of R
// (kTridiagonalSpai); S is the identity on the new DOFs.
Eigen::MatrixXd AugmentedSystem::hsj_matrix(const Augmentation& aug) const {
  const int n = n_;
  const int nb = n_base_;
  const int m = aug.m();
  Eigen::MatrixXd mm = Eigen::MatrixXd::Zero(m, m);
  auto s_entry = [&](int t, int r) -> double {  // S(t, r) for |t − r| ≤ 1
    if (t >= nb || r >= nb) return t == r ? 1.0 : 0.0;
    if (options_.preconditioner == SchurPreconditioner::kDiagonal) {
      return t == r ? base_->s_diag(r) : 0.0;
    }
    if (t == r) return base_->spai_diag(r);
    if (t == r - 1) return base_->spai_upper(t);
    return base_->spai_lower(r);
  };
  for (int k = 0; k < m; ++k) {
    auto visit = [&](int r, double v) {
      for (int t = r - 1; t <= r + 1; ++t) {
        if (t < 0 || t >= n || pos_in_l_[t] < 0) continue;
        const double s = s_entry(t, r);
        if (s != 0) mm(pos_in_l_[t], k) += s * v;
      }
    };
    if (aug.is_dirichlet[k]) {
      visit(aug.l[k], 1.0);
    } else {
      for (const auto& e : *aug.j_cols[k]) visit(e.first, e.second);
    }
  }
  return mm;
}

// H R⁻¹ J in the capacitance form (SchurSolver::kDirectCached). Write J_k = R_{*,𝓛ₖ} + E_k for
// a column that is not Dirichlet (E_k = K_{*,𝓛ₖ} − R_{*,𝓛ₖ}; R_{*,𝓛ₖ} = e_{𝓛ₖ} for a new DOF)
// and J_k = e_{𝓛ₖ} for a Dirichlet column. E_k is nonzero only in rows whose own column
// changed (K and R are symmetric), i.e. in rows of 𝓛, so with G = H R⁻¹ Hᵀ (the 𝓛-block of
// R⁻¹; the identity on new DOFs)
//
//     H R⁻¹ J = Φ + G Ψ,   Φ = diag(1 for non-Dirichlet, 0 for Dirichlet columns),
//                          Ψ_{*k} = H E_k (non-Dirichlet) or e_k (Dirichlet).
//
// This is the capacitance matrix of the Sherman–Morrison–Woodbury form of the update. G depends
// only on the set 𝓛 and the factor, not on the column values, so it is kept between solves:
// a DOF that joins 𝓛 costs one restricted solve y = R⁻¹ e_{𝓛ᵢ} (column i of G, and row i by
// the symmetry of G); changed column values cost nothing but the product G Ψ (O(m·nnz(Ψ))).
// Entries of E in rows outside 𝓛 (possible only if K lost its exact symmetry) are left out:
// the matrix is then an approximation, which as GMRES's preconditioner costs iterations, not
// accuracy.
const Eigen::MatrixXd& AugmentedSystem::capacitance_matrix(const Augmentation& aug, int& solves,
                                                           AugmentedReport& report) {
  const std::vector<int>& l_base = aug.l_base;
  const int m = aug.m();
  const int nb = n_base_;
  const int mb = static_cast<int>(l_base.size());
  ClosureLdlSolver& solver = *base_->solver;
  // G on the base entries of 𝓛 (l_base, sorted): kept entries from the cache, new columns by
  // restricted solves.
  std::vector<int> old(mb, -1);  // position of l_base[i] in the cached list (both sorted)
  if (g_generation_ == base_generation_) {
    size_t q = 0;
    for (int i = 0; i < mb; ++i) {
      while (q < g_l_.size() && g_l_[q] < l_base[i]) ++q;
      if (q < g_l_.size() && g_l_[q] == l_base[i]) old[i] = static_cast<int>(q);
    }
  }
  Eigen::MatrixXd g(mb, mb);
  for (int k = 0; k < mb; ++k) {
    if (old[k] < 0) continue;
    for (int i = 0; i < mb; ++i)
      if (old[i] >= 0) g(i, k) = g_(old[i], old[k]);
  }
  solves = 0;
  const Timer new_columns;
  const double cpu_new_columns0 = thread_cpu_seconds();
  // The new columns R⁻¹e_{𝓛ₖ} in one blocked pass (ClosureLdlSolver::solve_restricted_block).
  std::vector<int> fresh_k, fresh_dofs;
  for (int k = 0; k < mb; ++k) {
    if (old[k] >= 0) continue;
    fresh_k.push_back(k);
    fresh_dofs.push_back(l_base[k]);
  }
  if (!fresh_k.empty()) {
    Eigen::MatrixXd y;
    solver.solve_restricted_block(fresh_dofs, solver.closure(fresh_dofs), aug.closure_y, l_base, y,
                                  options_.blas_kernels);
    solves = static_cast<int>(fresh_k.size());
    for (std::size_t c = 0; c < fresh_k.size(); ++c) {
      const int k = fresh_k[c];
      for (int i = 0; i < mb; ++i) {
        g(i, k) = y(i, static_cast<Eigen::Index>(c));
        if (old[i] >= 0) g(k, i) = y(i, static_cast<Eigen::Index>(c));  // symmetry of G
      }
    }
  }
  g_generation_ = base_generation_;
  g_l_ = l_base;
  g_ = std::move(g);  // the cache is also this solve's G
  report.seconds_new_columns = new_columns.seconds();
  report.cpu_seconds_new_columns = thread_cpu_seconds() - cpu_new_columns0;
  const Timer product;

  // Φ + G Ψ, column by column: for each entry (𝓛 position p, value v) of Ψ_{*k}, add v·G_{*p}.
  // 𝓛 is sorted, so its base DOFs (< n_base) are its first mb entries and G is block diagonal:
  // g on them, the identity on the new DOFs.
  // Ψ_{*k} as (label, value) pairs, in the order the column's entries are summed.
  std::vector<std::vector<std::pair<int, double>>> psi(static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k) {
    const int j = aug.l[k];
    auto& col = psi[static_cast<std::size_t>(k)];
    if (aug.is_dirichlet[k]) continue;  // Ψ_{*k} = e_k (marked by an empty list and the flag)
    // E_k = K_{*j} − R_{*j}: merge the stored column with the base column (both sorted).
    const Column& kc = *aug.j_cols[k];
    auto add_e = [&](int row, double v) {
      if (v != 0 && pos_in_l_[row] >= 0) col.emplace_back(row, v);
    };
    size_t a = 0;
    if (j < nb) {
      const bool j_elim = base_->eliminated(j);  // released: R_{*j} = K_jj e_j
      for (SparseMatrix::InnerIterator it(base_->matrix, j); it; ++it) {
        const int row = static_cast<int>(it.row());
        if (row != j && (j_elim || base_->eliminated(row))) continue;  // not an entry of R
        for (; a < kc.size() && kc[a].first < row; ++a) add_e(kc[a].first, kc[a].second);
        if (a < kc.size() && kc[a].first == row) {
          add_e(row, kc[a].second - it.value());
          ++a;
        } else {
          add_e(row, -it.value());
        }
      }
      for (; a < kc.size(); ++a) add_e(kc[a].first, kc[a].second);
    } else {
      for (const auto& [row, v] : kc) add_e(row, row == j ? v - 1.0 : v);
    }
  }
  // Columns whose Ψ (and Dirichlet flag) are those of the last solve on the same G keep their
  // values on the rows of the labels that were in 𝓛 then; only the new labels' rows are summed.
  // The sums run in the same order as a full recomputation, so the matrix is bitwise the same;
  // a frame then costs O(mb·nnz) for the changed columns only (issue 17).
  std::vector<int> prev(static_cast<std::size_t>(m), -1);  // position in the last solve's 𝓛
  if (product_generation_ == base_generation_) {
    size_t q = 0;
    for (int i = 0; i < m; ++i) {
      while (q < product_l_.size() && product_l_[q] < aug.l[i]) ++q;
      if (q < product_l_.size() && product_l_[q] == aug.l[i]) prev[i] = static_cast<int>(q);
    }
  }
  std::vector<int> fresh_rows;
  for (int i = 0; i < m; ++i)
    if (prev[i] < 0) fresh_rows.push_back(i);
  Eigen::MatrixXd s(m, m);
  auto g_entry = [&](int i, int p) -> double {  // G(i, p) on 𝓛 positions
    if (i < mb && p < mb) return g_(i, p);
    return i == p ? 1.0 : 0.0;
  };
  int kept = 0;
  for (int k = 0; k < m; ++k) {
    const auto& col = psi[static_cast<std::size_t>(k)];
    const int pk = prev[k];
    const bool same = pk >= 0 &&
                      product_dirichlet_[static_cast<std::size_t>(pk)] == aug.is_dirichlet[k] &&
                      product_psi_[static_cast<std::size_t>(pk)] == col;
    if (same) {
      ++kept;
      for (int i = 0; i < m; ++i)
        if (prev[i] >= 0) s(i, k) = product_(prev[i], pk);
      if (aug.is_dirichlet[k]) {
        for (int i : fresh_rows) s(i, k) = g_entry(i, k);
        continue;
      }
      // Σ over the column's entries, in their order, for every new row: the entries outside and
      // the rows inside, so that each entry reads one column of G (the same sums per row).
      for (int i : fresh_rows) s(i, k) = 0;
      for (const auto& [row, e] : col) {
        const int p = pos_in_l_[row];
        if (p < mb) {
          const double* gp = g_.col(p).data();
          for (int i : fresh_rows) s(i, k) += e * (i < mb ? gp[i] : 0.0);
        } else {
          for (int i : fresh_rows) s(i, k) += e * (i == p ? 1.0 : 0.0);
        }
      }
      continue;
    }
    s.col(k).setZero();
    if (aug.is_dirichlet[k]) {
      if (k < mb) {
        s.col(k).head(mb) += g_.col(k);
      } else {
        s(k, k) += 1.0;
      }
      continue;
    }
    s(k, k) += 1.0;
    for (const auto& [row, e] : col) {
      const int p = pos_in_l_[row];
      if (p < mb) {
        s.col(k).head(mb) += e * g_.col(p);
      } else {
        s(p, k) += e;
      }
    }
  }
  report.capacitance_columns_kept = kept;
  product_generation_ = base_generation_;
  product_l_ = aug.l;
  product_psi_ = std::move(psi);
  product_dirichlet_ = aug.is_dirichlet;
  product_ = std::move(s);
  report.seconds_capacitance_product = product.seconds();
  return product_;
}

// Step 1 (§3.2; eqs. 18, 19): rhs = H R⁻¹ f̂, the right-hand side of eq. 17. Forward
// substitution on closure_L(f̂), backward only on closure_L(𝓛); on the new DOFs (identity block
// of R) it is f̂ itself.
Eigen::VectorXd AugmentedSystem::schur_rhs(const Augmentation& aug) {
  const int m = aug.m();
  Eigen::VectorXd rhs(m);
  std::vector<double> y_base;
  base_->solver->solve_restricted(aug.f_idx, aug.f_val, aug.closure_f, aug.closure_y, aug.l_base,
                                  y_base);
  int kb = 0;
  for (int i = 0; i < m; ++i) rhs(i) = aug.l[i] < n_base_ ? y_base[kb++] : aug.fhat(aug.l[i]);
  return rhs;
}

// Step 2 (§3.2; eqs. 17, 20): a₂ from (H R⁻¹ J) a₂ = rhs by GMRES. One operator application
// is J v (sparse), a forward substitution on closure_L(J) and a backward one on closure_L(𝓛).
// Right preconditioner: with SchurSolver::kDirectCached the explicit capacitance matrix (it
// keeps the residual of eq. 17 that of the operator step 3 uses; the capacitance form differs
// from the operator by round-off amplified by κ(R)), else `hsj` when usable (§3.5).
Eigen::VectorXd AugmentedSystem::solve_schur_system(Augmentation& aug, const Eigen::VectorXd& rhs,
                                                    const SchurLu& hsj, AugmentedReport& report) {
  const int m = aug.m();
  const int nb = n_base_;
  ClosureLdlSolver& solver = *base_->solver;
  std::vector<double> jv_val(aug.j_struct.size());
  std::vector<double> yb;  // reused by every operator application (no per-iteration allocation)
  GmresOperator op = [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) {
    aug.add_j_times(v);
    for (size_t k = 0; k < aug.j_struct.size(); ++k) jv_val[k] = aug.jv(aug.j_struct[k]);
    solver.solve_restricted(aug.j_struct, jv_val, aug.closure_j, aug.closure_y, aug.l_base, yb);
    out.resize(m);
    int kb = 0;
    for (int i = 0; i < m; ++i) out(i) = aug.l[i] < nb ? yb[kb++] : aug.jv(aug.l[i]);
    aug.clear_jv();
  };
  GmresOperator prec;
  SchurLu direct;
  if (m > 0 && options_.schur_solver == SchurSolver::kDirectCached) {
    // Rows and columns are in different units (displacement per force, per unit displacement)
    // and span many decades on long meshes: equilibrated, so that the LU's condition estimate
    // measures singularity, not scaling.
    if (options_.update_capacitance) {
      // Updated, not refactored (CapacitanceFactor); fresh for a new factor of R.
      const bool fresh = capacitance_generation_ != base_generation_;
      const Eigen::MatrixXd& s = capacitance_matrix(aug, report.schur_solves, report);
      const Timer factor;
      const double cpu0 = thread_cpu_seconds();
      const CapacitanceUpdate u = capacitance_.update(s, aug.l, fresh);
      report.cpu_seconds_capacitance_factor = thread_cpu_seconds() - cpu0;
      report.seconds_capacitance_factor = factor.seconds();
      capacitance_generation_ = base_generation_;
      report.capacitance_refreshed = u.refreshed;
      report.capacitance_rank = u.changed;
      report.capacitance_needed_rank = u.needed_rank;
      report.capacitance_update_flops = u.update_flops;
      report.capacitance_fresh_flops = u.fresh_flops;
      report.preconditioner_rcond = u.rcond;
      report.preconditioner_dropped =
          !(std::isfinite(u.rcond) && u.rcond > kMinPreconditionerRcond);
      if (!report.preconditioner_dropped) {
        prec = [this](const Eigen::VectorXd& v, Eigen::VectorXd& out) {
          capacitance_.solve(v, out);
        };
      }
    } else {
      const Eigen::MatrixXd& s = capacitance_matrix(aug, report.schur_solves, report);
      const Timer factor;
      const double cpu0 = thread_cpu_seconds();
      direct.factor(s, /*equilibrate=*/true);
      report.cpu_seconds_capacitance_factor = thread_cpu_seconds() - cpu0;
      report.seconds_capacitance_factor = factor.seconds();
      direct.note(report);
      if (direct.usable) {
        prec = [&direct](const Eigen::VectorXd& v, Eigen::VectorXd& out) { direct.apply(v, out); };
      }
    }
  } else if (hsj.usable) {
    prec = [&hsj](const Eigen::VectorXd& v, Eigen::VectorXd& out) { hsj.apply(v, out); };
  }
  Eigen::VectorXd a2 = Eigen::VectorXd::Zero(m);
  if (m > 0) {
    report.gmres = gmres(op, prec, rhs, a2, options_.gmres);
  } else {
    report.gmres.status = GmresStatus::kConverged;
  }
  return a2;
}

// Step 3 (§3.2; eq. 16): a₁ = R⁻¹(f̂ − J a₂), written into `displacement`. f̂ − J a₂ is needed
// only on its structure (base rows: restricted forward substitution, then the full backward
// one) and on the new DOFs, where R is the identity and a₁ is the right-hand side itself.
void AugmentedSystem::back_substitute(Augmentation& aug, const Eigen::VectorXd& a2,
                                      Eigen::VectorXd& displacement) {
  aug.add_j_times(a2);
  const std::vector<int>& s3 = aug.step3_struct;
  std::vector<double> b3_val(s3.size());
  for (size_t k = 0; k < s3.size(); ++k) b3_val[k] = aug.fhat(s3[k]) - aug.jv(s3[k]);
  for (int i = n_base_; i < n_; ++i) displacement(i) = aug.fhat(i) - aug.jv(i);
  aug.clear_jv();
  base_->solver->solve_sparse_rhs(s3, b3_val, aug.closure_step3, displacement.data());
}

// Eqs. 8, 9: a₂ into the displacements (𝓛 ∖ 𝓓) and the reactions (𝓓; the prescribed value
// is the displacement there).
void AugmentedSystem::scatter_schur_solution(const Augmentation& aug, const Eigen::VectorXd& a2,
                                             Eigen::VectorXd& displacement,
                                             Eigen::VectorXd& reaction) const {
  for (int i = 0; i < aug.m(); ++i) {
    const int j = aug.l[i];
    if (aug.is_dirichlet[i]) {
      displacement(j) = dirichlet_.at(j);
      reaction(j) = -a2(i);
    } else {
      displacement(j) = a2(i);
    }
  }
  // Eliminated constrained DOFs: the prescribed value, and the reaction (K a)_d − f_d from the
  // current column of K (symmetric), once every displacement is known.
  for (int d : aug.eliminated) displacement(d) = dirichlet_.at(d);
  for (int d : aug.eliminated) {
    double r = -f_(d);
    if (const Column* c = changed_column(d)) {
      for (const auto& [row, v] : *c) r += v * displacement(row);
    } else {
      for (SparseMatrix::InnerIterator it(base_->matrix, d); it; ++it)
        r += it.value() * displacement(static_cast<int>(it.row()));
    }
    reaction(d) = r;
  }
}

// The report's status from GMRES, then the singularity guard (AugmentedOptions::
// max_amplification) and the finiteness of the outputs; failed outputs are zeroed.
void AugmentedSystem::conclude(const Augmentation& aug, Eigen::VectorXd& displacement,
                               Eigen::VectorXd& reaction, AugmentedReport& report) const {
  switch (report.gmres.status) {
    case GmresStatus::kConverged: report.status = AugmentedStatus::kOk; break;
    case GmresStatus::kMaxIterations:
      report.status = AugmentedStatus::kGmresNotConverged;
      report.message =
          "GMRES reached its iteration cap on eq. 17: raise gmres.max_iterations or the restart "
          "length, use a preconditioner, or refactor (start_refactorization) to reduce m";
      break;
    case GmresStatus::kStagnated:
    case GmresStatus::kBreakdown:
      report.status = AugmentedStatus::kSingularModifiedSystem;
      report.message =
          "the modified stiffness appears singular (GMRES " +
          std::string(to_string(report.gmres.status)) +
          "): a cut may have freed a component or a node lost its support; constrain the free "
          "part (impose_dirichlet) or remove its elements";
      break;
    case GmresStatus::kNonFinite:
      report.status = AugmentedStatus::kNonFinite;
      report.message = "NaN/Inf during GMRES: check element matrices and forces";
      break;
  }
  double abar2 = 0;
  for (const auto& kv : dirichlet_) abar2 += kv.second * kv.second;
  const double denom = aug.fhat.norm() + diag_scale_ * std::sqrt(abar2);
  report.amplification = denom > 0 ? diag_scale_ * displacement.norm() / denom : 0.0;
  report.amplification_warning = report.amplification > options_.warn_amplification;
  if (report.status == AugmentedStatus::kOk &&
      !(report.amplification <= options_.max_amplification)) {
    report.status = AugmentedStatus::kSingularModifiedSystem;
    std::ostringstream os;
    os << "the solution is amplified " << report.amplification
       << "x relative to the load (max_amplification " << options_.max_amplification
       << "): the modified stiffness is numerically singular (a cut may have freed a "
          "component); constrain the free part or remove its elements";
    report.message = os.str();
    displacement.setZero();
    reaction.setZero();
  }
  if (!displacement.allFinite() || !reaction.allFinite()) {
    displacement.setZero();
    reaction.setZero();
    if (report.status == AugmentedStatus::kOk) {
      report.status = AugmentedStatus::kNonFinite;
      report.message = "non-finite solution: check element matrices and forces";
    }
  }
  if (report.status != AugmentedStatus::kOk && report.preconditioner_dropped) {
    std::ostringstream os;
    os << " (GMRES ran unpreconditioned: the preconditioner's LU has rcond "
       << report.preconditioner_rcond << " <= " << kMinPreconditionerRcond << ")";
    report.message += os.str();
  }
}

AugmentedReport AugmentedSystem::solve(Eigen::VectorXd& displacement, Eigen::VectorXd& reaction) {
  Timer total;
  const double cpu_total0 = thread_cpu_seconds();
  AugmentedReport report;
  if (board_) publish_keep();  // prepare_in_job: what the pending job will prepare G for
  if (job_.valid()) {          // §3.6: a finished background factor replaces R first
    const Timer swap;
    report.refactorization_swapped = poll_refactorization();
    report.seconds_swap = swap.seconds();
    if (!job_.valid() && !report.refactorization_swapped) {
      report.refactorization_status = last_refactor_status_;
    }
  }
  displacement = Eigen::VectorXd::Zero(n_);
  reaction = Eigen::VectorXd::Zero(n_);
  report.n = n_;
  if (!base_ || base_->status != FactorStatus::kOk) {
    report.status = AugmentedStatus::kNoFactor;
    report.message = "initialize() with a positive definite K0 first";
    if (base_) report.message += " (last factorization: " + base_->message + ")";
    return report;
  }
  if (!f_.allFinite()) {
    report.status = AugmentedStatus::kNonFinite;
    report.message = "the force vector has NaN/Inf entries";
    return report;
  }
  if (options_.prune_unchanged_columns) report.pruned_columns = prune_unchanged_columns();

  // Setup: 𝓛, J, H, f̂ (§3.1), closures (§3.3), the preconditioner M = H S J (§3.5).
  Timer phase;
  report.nnz_l = base_->ldl->nnz_l();
  Augmentation aug;
  if (!augment(aug, report)) return report;
  find_closures(aug, report);
  SchurLu hsj;
  if (options_.preconditioner != SchurPreconditioner::kNone && aug.m() > 0 &&
      options_.schur_solver == SchurSolver::kGmres) {
    hsj.factor(hsj_matrix(aug), /*equilibrate=*/false);
    hsj.note(report);
  }
  report.seconds_setup = phase.seconds();

  phase.restart();
  const Eigen::VectorXd rhs = schur_rhs(aug);
  report.seconds_step1 = phase.seconds();

  phase.restart();
  const Eigen::VectorXd a2 = solve_schur_system(aug, rhs, hsj, report);
  report.seconds_step2 = phase.seconds();

  phase.restart();
  back_substitute(aug, a2, displacement);
  report.seconds_step3 = phase.seconds();

  scatter_schur_solution(aug, a2, displacement, reaction);
  conclude(aug, displacement, reaction, report);
  report.seconds_total = total.seconds();
  report.cpu_seconds_total = thread_cpu_seconds() - cpu_total0;
  return report;
}

}  // namespace incise::linalg
