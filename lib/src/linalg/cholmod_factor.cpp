#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>
#include <incise/linalg/blas_threads.hpp>
#include <incise/linalg/cholmod_factor.hpp>

#include <cholmod.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <utility>

namespace incise::linalg {

const char* to_string(FactorStatus status) {
  switch (status) {
    case FactorStatus::kOk: return "ok";
    case FactorStatus::kNotAnalyzed: return "not analyzed";
    case FactorStatus::kNotPositiveDefinite: return "not positive definite";
    case FactorStatus::kOutOfMemory: return "out of memory";
    case FactorStatus::kInvalidInput: return "invalid input";
    case FactorStatus::kCholmodError: return "CHOLMOD error";
    case FactorStatus::kTinyPivot: return "tiny pivot";
    case FactorStatus::kOverMemoryBudget: return "over memory budget";
  }
  return "unknown";
}

struct CholmodFactor::Impl {
  cholmod_common common;
  cholmod_factor* factor = nullptr;

  Impl() {
    cholmod_start(&common);
    common.print = 0;  // the library never prints
    common.error_handler = nullptr;
  }
  ~Impl() {
    if (factor != nullptr) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
};

namespace {

/// Non-owning cholmod_sparse view of the lower triangle of a compressed Eigen matrix.
cholmod_sparse view_lower(const SparseMatrix& a) {
  cholmod_sparse s{};
  s.nrow = static_cast<size_t>(a.rows());
  s.ncol = static_cast<size_t>(a.cols());
  s.nzmax = static_cast<size_t>(a.nonZeros());
  s.p = const_cast<int*>(a.outerIndexPtr());
  s.i = const_cast<int*>(a.innerIndexPtr());
  s.nz = nullptr;
  s.x = const_cast<double*>(a.valuePtr());
  s.z = nullptr;
  s.stype = -1;
  s.itype = CHOLMOD_INT;
  s.xtype = CHOLMOD_REAL;
  s.dtype = CHOLMOD_DOUBLE;
  s.sorted = 1;
  s.packed = 1;
  return s;
}

// CHOLMOD's status codes: 0 ok, negative errors, positive warnings. Every warning is a
// distinct, non-ok status: CHOLMOD_NOT_POSDEF (no usable factor), CHOLMOD_DSMALL (a factor of
// a matrix with bounded pivots, kTinyPivot), any other (unknown here) kCholmodError.
FactorStatus status_from_common(const cholmod_common& c, std::string& message) {
  switch (c.status) {
    case CHOLMOD_OK: message.clear(); return FactorStatus::kOk;
    case CHOLMOD_NOT_POSDEF:
      message = "matrix not positive definite";
      return FactorStatus::kNotPositiveDefinite;
    case CHOLMOD_DSMALL: {
      std::ostringstream os;
      os << "CHOLMOD_DSMALL: " << c.ndbounds_hit
         << " pivot(s) of magnitude below pivot_bound = " << c.dbound << " replaced by +-"
         << c.dbound
         << ": the factor is of a perturbed matrix; set pivot_bound = 0 for the exact factor";
      message = os.str();
      return FactorStatus::kTinyPivot;
    }
    case CHOLMOD_OUT_OF_MEMORY:
      message = "CHOLMOD out of memory";
      return FactorStatus::kOutOfMemory;
    case CHOLMOD_INVALID: message = "CHOLMOD: invalid input"; return FactorStatus::kInvalidInput;
    default:
      message = c.status < 0 ? "CHOLMOD status " + std::to_string(c.status)
                             : "CHOLMOD warning " + std::to_string(c.status) +
                                   " (not known to incise): the factor is not used";
      return FactorStatus::kCholmodError;
  }
}

}  // namespace

CholmodFactor::CholmodFactor(CholmodOptions options)
    : impl_(std::make_unique<Impl>()), options_(options) {
  INCISE_CHECK_PARAM(options_.pivot_bound >= 0, "CholmodOptions::pivot_bound must be >= 0");
  INCISE_CHECK_PARAM(!std::isnan(options_.blas_parallel_flops),
                     "CholmodOptions::blas_parallel_flops must not be NaN");
  cholmod_common& c = impl_->common;
  c.dbound = options_.pivot_bound;
  switch (options_.kind) {
    case CholmodKind::kSupernodal: c.supernodal = CHOLMOD_SUPERNODAL; break;
    case CholmodKind::kSimplicialLdl:
      c.supernodal = CHOLMOD_SIMPLICIAL;
      c.final_ll = 0;
      break;
    case CholmodKind::kAuto: c.supernodal = CHOLMOD_AUTO; break;
  }
  switch (options_.ordering) {
    case CholmodOrdering::kDefault: break;
    case CholmodOrdering::kAmd:
      c.nmethods = 1;
      c.method[0].ordering = CHOLMOD_AMD;
      c.postorder = 1;
      break;
    case CholmodOrdering::kMetis:
      c.nmethods = 1;
      c.method[0].ordering = CHOLMOD_METIS;
      c.postorder = 1;
      break;
    case CholmodOrdering::kNatural:
      c.nmethods = 1;
      c.method[0].ordering = CHOLMOD_NATURAL;
      c.postorder = 0;
      break;
  }
}

CholmodFactor::~CholmodFactor() = default;
CholmodFactor::CholmodFactor(CholmodFactor&&) noexcept = default;
CholmodFactor& CholmodFactor::operator=(CholmodFactor&&) noexcept = default;

FactorStatus CholmodFactor::analyze(const SparseMatrix& a, std::uint64_t pattern_version) {
  return analyze(a, pattern_version, {});
}

FactorStatus CholmodFactor::analyze(const SparseMatrix& a, std::uint64_t pattern_version,
                                    const std::vector<int>& permutation) {
  if (a.rows() != a.cols() || !a.isCompressed()) {
    message_ = "analyze: matrix must be square and compressed";
    return status_ = FactorStatus::kInvalidInput;
  }
  if (!permutation.empty()) {
    std::vector<char> seen(static_cast<std::size_t>(a.rows()), 0);
    bool ok = static_cast<Eigen::Index>(permutation.size()) == a.rows();
    for (std::size_t k = 0; ok && k < permutation.size(); ++k) {
      const int i = permutation[k];
      ok = i >= 0 && i < a.rows() && !seen[static_cast<std::size_t>(i)];
      if (ok) seen[static_cast<std::size_t>(i)] = 1;
    }
    if (!ok) {
      message_ = "analyze: the given ordering is not a permutation of the rows";
      return status_ = FactorStatus::kInvalidInput;
    }
  }
  if (impl_->factor != nullptr && pattern_version == pattern_version_ && n_ == a.rows() &&
      analyzed_nnz_ == a.nonZeros()) {
    return status_ = FactorStatus::kOk;
  }
  if (impl_->factor != nullptr) cholmod_free_factor(&impl_->factor, &impl_->common);
  factorized_ = false;
  cholmod_sparse s = view_lower(a);
  if (permutation.empty()) {
    impl_->factor = cholmod_analyze(&s, &impl_->common);
  } else {
    // The given ordering only (postordered, as the computed ones); the options' methods are
    // restored afterwards.
    cholmod_common& c = impl_->common;
    const int nmethods = c.nmethods, ordering = c.method[0].ordering, postorder = c.postorder;
    c.nmethods = 1;
    c.method[0].ordering = CHOLMOD_GIVEN;
    c.postorder = 1;
    std::vector<int> perm = permutation;
    impl_->factor = cholmod_analyze_p(&s, perm.data(), nullptr, 0, &c);
    c.nmethods = nmethods;
    c.method[0].ordering = ordering;
    c.postorder = postorder;
  }
  ++analyses_;
  status_ = status_from_common(impl_->common, message_);
  if (impl_->factor == nullptr) {
    if (status_ == FactorStatus::kOk) status_ = FactorStatus::kCholmodError;
    n_ = 0;
    return status_;
  }
  n_ = static_cast<int>(a.rows());
  analyzed_nnz_ = a.nonZeros();
  pattern_version_ = pattern_version;
  return status_;
}

FactorStatus CholmodFactor::factorize(const SparseMatrix& a) {
  factorized_ = false;
  if (impl_->factor == nullptr) {
    message_ = "factorize before analyze";
    return status_ = FactorStatus::kNotAnalyzed;
  }
  if (a.rows() != n_ || a.cols() != n_ || !a.isCompressed()) {
    message_ = "factorize: size differs from the analyzed matrix";
    return status_ = FactorStatus::kInvalidInput;
  }
  if (!Eigen::Map<const Eigen::VectorXd>(a.valuePtr(), a.nonZeros()).allFinite()) {
    message_ = "matrix has non-finite entries";
    return status_ = FactorStatus::kInvalidInput;
  }
  if (options_.memory_budget_bytes > 0 && estimated_factor_bytes() > options_.memory_budget_bytes) {
    const auto mib = [](std::uint64_t b) {
      std::ostringstream os;
      os.precision(4);
      os << static_cast<double>(b) / (1024.0 * 1024.0) << " MiB";
      return os.str();
    };
    std::ostringstream os;
    os << "the numeric factorization needs an estimated " << mib(estimated_factor_bytes())
       << " (nnz(L) = " << nnz_l() << " from the symbolic analysis of " << n_ << " rows, "
       << (is_supernodal() ? "supernodal" : "simplicial") << "), more than the memory budget of "
       << mib(options_.memory_budget_bytes);
    message_ = os.str();
    return status_ = FactorStatus::kOverMemoryBudget;
  }
  cholmod_sparse s = view_lower(a);
  // One BLAS thread for small factorizations, all cores for large ones (blas_threads.hpp);
  // the scope ends with this function, after which the BLAS workers are parked.
  const BlasThreadSettings& blas = blas_thread_settings();
  const double fl = impl_->common.fl;  // CHOLMOD's estimate from the analysis
  const ScopedBlasThreads blas_scope(blas_threads_for(
      fl > 0.0 ? fl : 0.0, blas.max_threads,
      options_.blas_parallel_flops >= 0.0 ? options_.blas_parallel_flops : blas.parallel_flops));
  last_blas_threads_ = blas_scope.threads();
  cholmod_factorize(&s, impl_->factor, &impl_->common);
  status_ = status_from_common(impl_->common, message_);
  minor_ = static_cast<int>(impl_->factor->minor);
  if (status_ == FactorStatus::kOk && minor_ < n_) {
    status_ = FactorStatus::kNotPositiveDefinite;
    message_ = "matrix not positive definite";
  }
  // Whether a factor exists (kOk, or a tiny-pivot factor of the perturbed matrix).
  auto has_factor = [this] {
    return status_ == FactorStatus::kOk || status_ == FactorStatus::kTinyPivot;
  };
  const cholmod_factor* l = impl_->factor;
  if (has_factor() && l->is_super == 0 && l->is_ll == 0) {
    // A simplicial LDLᵀ factorization also succeeds on an indefinite matrix (CHOLMOD flags only
    // zero pivots there): every pivot D_jj — the first entry of column j — must be positive.
    const int* lp = static_cast<const int*>(l->p);
    const double* lx = static_cast<const double*>(l->x);
    for (int j = 0; j < n_; ++j) {
      if (!(lx[lp[j]] > 0)) {
        status_ = FactorStatus::kNotPositiveDefinite;
        message_ = "matrix not positive definite";
        minor_ = j;
        break;
      }
    }
  }
  rcond_ = has_factor() ? cholmod_rcond(impl_->factor, &impl_->common) : 0.0;
  if (status_ == FactorStatus::kOk && options_.min_pivot_ratio > 0 &&
      !(rcond_ >= options_.min_pivot_ratio)) {
    status_ = FactorStatus::kNotPositiveDefinite;
    message_ = "matrix numerically singular (pivot ratio " + std::to_string(rcond_) + ")";
  }
  if (status_ == FactorStatus::kNotPositiveDefinite) {
    const std::string where =
        minor_ < n_ ? "pivot " + std::to_string(minor_) + " of " + std::to_string(n_) + " failed: "
                    : std::string();
    message_ += " (" + where + "singular or indefinite — check constraints and inverted elements)";
  }
  factorized_ = has_factor();
  return status_;
}

FactorStatus CholmodFactor::compute(const SparseMatrix& a, std::uint64_t pattern_version) {
  const FactorStatus s = analyze(a, pattern_version);
  if (s != FactorStatus::kOk) return s;
  return factorize(a);
}

FactorStatus CholmodFactor::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  if (!factorized_) {
    if (status_ == FactorStatus::kOk) status_ = FactorStatus::kNotAnalyzed;
    return status_;
  }
  if (b.size() != n_) {
    message_ = "solve: right-hand side has wrong size";
    return status_ = FactorStatus::kInvalidInput;
  }
  cholmod_dense bd{};
  bd.nrow = static_cast<size_t>(n_);
  bd.ncol = 1;
  bd.nzmax = static_cast<size_t>(n_);
  bd.d = static_cast<size_t>(n_);
  bd.x = const_cast<double*>(b.data());
  bd.z = nullptr;
  bd.xtype = CHOLMOD_REAL;
  bd.dtype = CHOLMOD_DOUBLE;
  const ScopedBlasThreads blas_scope(1);  // a triangular solve is memory-bound
  cholmod_dense* xd = cholmod_solve(CHOLMOD_A, impl_->factor, &bd, &impl_->common);
  if (xd == nullptr) {
    status_ = status_from_common(impl_->common, message_);
    if (status_ == FactorStatus::kOk) status_ = FactorStatus::kCholmodError;
    return status_;
  }
  x = Eigen::Map<const Eigen::VectorXd>(static_cast<const double*>(xd->x), n_);
  cholmod_free_dense(&xd, &impl_->common);
  return status_ = FactorStatus::kOk;
}

FactorStatus CholmodFactor::modify(const SparseMatrix& delta, ModifyStats* stats) {
  if (stats != nullptr) *stats = ModifyStats{};
  if (!factorized_ || status_ != FactorStatus::kOk) {
    message_ = "modify: no factor (factorize with status ok first)";
    return status_ = FactorStatus::kNotAnalyzed;
  }
  cholmod_factor* l = impl_->factor;
  if (l->is_super != 0) {
    message_ = "modify: the factor is supernodal (use CholmodKind::kSimplicialLdl)";
    return status_ = FactorStatus::kInvalidInput;
  }
  if (delta.rows() != n_ || delta.cols() != n_) {
    message_ = "modify: the change has a different size than the factor";
    return status_ = FactorStatus::kInvalidInput;
  }
  // T: the rows/columns with a nonzero of Δ, and their positions in the factor's order.
  std::vector<int> local(static_cast<size_t>(n_), -1), touched;
  for (int j = 0; j < n_; ++j) {
    for (SparseMatrix::InnerIterator it(delta, j); it; ++it) {
      if (it.value() == 0.0) continue;
      if (!std::isfinite(it.value())) {
        message_ = "modify: the change has non-finite entries";
        return status_ = FactorStatus::kInvalidInput;
      }
      for (const int k : {j, static_cast<int>(it.row())}) {
        if (local[static_cast<size_t>(k)] < 0) {
          local[static_cast<size_t>(k)] = static_cast<int>(touched.size());
          touched.push_back(k);
        }
      }
    }
  }
  const int t = static_cast<int>(touched.size());
  if (stats != nullptr) stats->touched = t;
  if (t == 0) return status_ = FactorStatus::kOk;
  const double t_split = thread_cpu_seconds();
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(t, t);
  for (const int j : touched) {
    for (SparseMatrix::InnerIterator it(delta, j); it; ++it)
      dense(local[static_cast<size_t>(it.row())], local[static_cast<size_t>(j)]) += it.value();
  }
  dense = 0.5 * (dense + dense.transpose()).eval();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(dense);
  if (eig.info() != Eigen::Success) {
    message_ = "modify: eigendecomposition of the change failed";
    return status_ = FactorStatus::kCholmodError;
  }
  const Eigen::VectorXd& lambda = eig.eigenvalues();
  const double drop = 1e-14 * lambda.cwiseAbs().maxCoeff();
  const double t_updown = thread_cpu_seconds();
  if (stats != nullptr) stats->cpu_seconds_split = t_updown - t_split;
  // Rows of C in the factor's order: position = inverse of L->Perm.
  const int* perm = static_cast<const int*>(l->Perm);
  std::vector<int> position(static_cast<size_t>(n_));
  for (int p = 0; p < n_; ++p) position[static_cast<size_t>(perm != nullptr ? perm[p] : p)] = p;
  std::vector<int> order(static_cast<size_t>(t));  // local rows sorted by factor position
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return position[static_cast<size_t>(touched[static_cast<size_t>(a)])] <
           position[static_cast<size_t>(touched[static_cast<size_t>(b)])];
  });
  cholmod_common& c = impl_->common;
  for (const bool update : {true, false}) {
    std::vector<int> cols;
    for (int k = 0; k < t; ++k) {
      if (update ? lambda(k) > drop : lambda(k) < -drop) cols.push_back(k);
    }
    if (stats != nullptr) (update ? stats->rank_update : stats->rank_downdate) = int(cols.size());
    if (cols.empty()) continue;
    cholmod_sparse* cm = cholmod_allocate_sparse(
        static_cast<size_t>(n_), cols.size(), cols.size() * static_cast<size_t>(t),
        /*sorted=*/1, /*packed=*/1, /*stype=*/0, CHOLMOD_REAL, &c);
    if (cm == nullptr) {
      status_ = status_from_common(c, message_);
      if (status_ == FactorStatus::kOk) status_ = FactorStatus::kOutOfMemory;
      factorized_ = false;
      return status_;
    }
    int* cp = static_cast<int*>(cm->p);
    int* ci = static_cast<int*>(cm->i);
    double* cx = static_cast<double*>(cm->x);
    int nz = 0;
    for (size_t q = 0; q < cols.size(); ++q) {
      cp[q] = nz;
      const int k = cols[q];
      const double s = std::sqrt(std::abs(lambda(k)));
      for (const int r : order) {
        const double v = s * eig.eigenvectors()(r, k);
        if (v == 0.0) continue;
        ci[nz] = position[static_cast<size_t>(touched[static_cast<size_t>(r)])];
        cx[nz] = v;
        ++nz;
      }
    }
    cp[cols.size()] = nz;
    const int ok = cholmod_updown(update ? 1 : 0, cm, l, &c);
    cholmod_free_sparse(&cm, &c);
    status_ = status_from_common(c, message_);
    if (!ok && status_ == FactorStatus::kOk) status_ = FactorStatus::kCholmodError;
    if (status_ != FactorStatus::kOk) {
      message_ = "modify: cholmod_updown failed: " + message_;
      factorized_ = false;
      return status_;
    }
  }
  // Every pivot D_jj (first entry of column j of the LDLᵀ factor) must stay positive.
  const int* lp = static_cast<const int*>(l->p);
  const double* lx = static_cast<const double*>(l->x);
  for (int j = 0; j < n_; ++j) {
    if (!(lx[lp[j]] > 0)) {
      message_ = "modify: pivot " + std::to_string(j) +
                 " not positive after the downdate (the "
                 "modified matrix is not positive definite, or round-off: refactor)";
      factorized_ = false;
      minor_ = j;
      return status_ = FactorStatus::kNotPositiveDefinite;
    }
  }
  rcond_ = cholmod_rcond(l, &c);
  if (stats != nullptr) stats->cpu_seconds_updown = thread_cpu_seconds() - t_updown;
  if (options_.min_pivot_ratio > 0 && !(rcond_ >= options_.min_pivot_ratio)) {
    message_ = "modify: matrix numerically singular (pivot ratio " + std::to_string(rcond_) + ")";
    factorized_ = false;
    return status_ = FactorStatus::kNotPositiveDefinite;
  }
  return status_ = FactorStatus::kOk;
}

bool CholmodFactor::is_supernodal() const {
  return impl_->factor != nullptr && impl_->factor->is_super != 0;
}

std::int64_t CholmodFactor::nnz_l() const {
  return static_cast<std::int64_t>(impl_->common.lnz);
}

std::uint64_t CholmodFactor::estimated_factor_bytes() const {
  const cholmod_factor* l = impl_->factor;
  if (l == nullptr) return 0;
  const std::uint64_t n = l->n, d = sizeof(double), i = sizeof(int);
  std::uint64_t bytes = 2 * n * d + 5 * n * i;  // CHOLMOD's workspace (Iwork, Xwork, Flag, Head)
  if (l->is_super) {
    bytes +=
        (static_cast<std::uint64_t>(l->xsize) + l->maxcsize) * d +
        (static_cast<std::uint64_t>(l->ssize) + 4 * static_cast<std::uint64_t>(l->nsuper) + n) * i;
  } else {
    const auto lnz = static_cast<std::uint64_t>(std::max(0.0, impl_->common.lnz));
    bytes += lnz * (d + i) + 6 * n * i;
  }
  return bytes;
}

std::uint64_t CholmodFactor::peak_memory_bytes() const {
  return static_cast<std::uint64_t>(impl_->common.memory_usage);
}

double CholmodFactor::factor_flops() const {
  return impl_->common.fl;
}

// A supernodal LLᵀ factor read straight into unit-lower LDLᵀ arrays: column j of supernode s
// (columns k1…k2−1, rows Ls[pi[s]…pi[s+1]), values column-major in Lx from px[s]) gives
// d_j = L_jj² and l_ij = L_ij / L_jj, the padding of relaxed supernodes kept as explicit zeros —
// the arrays cholmod_change_factor's simplicial LDLᵀ copy would give, in one pass and no copy
// of the factor (issue 17: part of every background refactorization's cost).
namespace {
std::shared_ptr<const LdlFactorData> supernodal_to_ldl(const cholmod_factor& l) {
  auto out = std::make_shared<LdlFactorData>();
  const int n = static_cast<int>(l.n);
  out->n = n;
  out->perm.resize(n);
  out->inverse_perm.resize(n);
  const int* perm = static_cast<const int*>(l.Perm);
  for (int i = 0; i < n; ++i) out->perm[i] = perm != nullptr ? perm[i] : i;
  for (int i = 0; i < n; ++i) out->inverse_perm[out->perm[i]] = i;
  const int nsuper = static_cast<int>(l.nsuper);
  const int* super = static_cast<const int*>(l.super);
  const int* pi = static_cast<const int*>(l.pi);
  const int* px = static_cast<const int*>(l.px);
  const int* ls = static_cast<const int*>(l.s);
  const double* lx = static_cast<const double*>(l.x);
  std::int64_t total = 0;
  for (int s = 0; s < nsuper; ++s) {
    const std::int64_t nscol = super[s + 1] - super[s], nsrow = pi[s + 1] - pi[s];
    total += nscol * nsrow - nscol * (nscol + 1) / 2;
  }
  out->col_ptr.assign(n + 1, 0);
  out->d.resize(n);
  out->parent.assign(n, -1);
  out->row_idx.reserve(static_cast<size_t>(total));
  out->values.reserve(static_cast<size_t>(total));
  std::vector<std::pair<int, double>> column;
  for (int s = 0; s < nsuper; ++s) {
    const int k1 = super[s], nscol = super[s + 1] - k1, nsrow = pi[s + 1] - pi[s];
    const int* rows = ls + pi[s];
    const bool sorted = std::is_sorted(rows + nscol, rows + nsrow);
    for (int jj = 0; jj < nscol; ++jj) {
      const int j = k1 + jj;
      const double* col = lx + px[s] + static_cast<std::ptrdiff_t>(jj) * nsrow;
      const double ljj = col[jj];
      out->d[j] = ljj * ljj;
      out->col_ptr[j] = static_cast<int>(out->row_idx.size());
      if (sorted) {
        for (int ii = jj + 1; ii < nsrow; ++ii) {
          out->row_idx.push_back(rows[ii]);
          out->values.push_back(col[ii] / ljj);
        }
      } else {
        column.clear();
        for (int ii = jj + 1; ii < nsrow; ++ii) column.emplace_back(rows[ii], col[ii] / ljj);
        std::sort(column.begin(), column.end());
        for (const auto& [row, value] : column) {
          out->row_idx.push_back(row);
          out->values.push_back(value);
        }
      }
      if (out->col_ptr[j] < static_cast<int>(out->row_idx.size()))
        out->parent[j] = out->row_idx[static_cast<size_t>(out->col_ptr[j])];
    }
  }
  out->col_ptr[n] = static_cast<int>(out->row_idx.size());
  return out;
}
}  // namespace

std::shared_ptr<const LdlFactorData> CholmodFactor::extract_ldl() {
  if (!factorized_) return nullptr;
  if (impl_->factor->is_super != 0 && impl_->factor->is_ll != 0 &&
      impl_->factor->xtype == CHOLMOD_REAL)
    return supernodal_to_ldl(*impl_->factor);
  cholmod_common& c = impl_->common;
  cholmod_factor* copy = cholmod_copy_factor(impl_->factor, &c);
  if (copy == nullptr) {
    status_ = status_from_common(c, message_);
    return nullptr;
  }
  if (!cholmod_change_factor(CHOLMOD_REAL, /*to_ll=*/0, /*to_super=*/0, /*to_packed=*/1,
                             /*to_monotonic=*/1, copy, &c)) {
    status_ = status_from_common(c, message_);
    cholmod_free_factor(&copy, &c);
    return nullptr;
  }
  auto out = std::make_shared<LdlFactorData>();
  const int n = static_cast<int>(copy->n);
  out->n = n;
  out->perm.resize(n);
  out->inverse_perm.resize(n);
  const int* perm = static_cast<const int*>(copy->Perm);
  for (int i = 0; i < n; ++i) out->perm[i] = perm != nullptr ? perm[i] : i;
  for (int i = 0; i < n; ++i) out->inverse_perm[out->perm[i]] = i;
  const int* lp = static_cast<const int*>(copy->p);
  const int* li = static_cast<const int*>(copy->i);
  const int* lnz = static_cast<const int*>(copy->nz);
  const double* lx = static_cast<const double*>(copy->x);
  out->col_ptr.assign(n + 1, 0);
  out->d.resize(n);
  out->parent.assign(n, -1);
  std::int64_t total = 0;
  for (int j = 0; j < n; ++j) total += lnz[j] - 1;
  out->row_idx.reserve(static_cast<size_t>(total));
  out->values.reserve(static_cast<size_t>(total));
  std::vector<std::pair<int, double>> column;
  for (int j = 0; j < n; ++j) {
    out->col_ptr[j] = static_cast<int>(out->row_idx.size());
    column.clear();
    for (int k = lp[j]; k < lp[j] + lnz[j]; ++k) {
      if (li[k] == j) {
        out->d[j] = lx[k];
      } else {
        column.emplace_back(li[k], lx[k]);
      }
    }
    std::sort(column.begin(), column.end());
    for (const auto& [row, value] : column) {
      out->row_idx.push_back(row);
      out->values.push_back(value);
    }
    if (!column.empty()) out->parent[j] = column.front().first;
  }
  out->col_ptr[n] = static_cast<int>(out->row_idx.size());
  cholmod_free_factor(&copy, &c);
  return out;
}

}  // namespace incise::linalg
