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

}  // namespace incise::linalg
