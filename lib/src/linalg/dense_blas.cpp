#include <incise/core/error.hpp>
#include <incise/linalg/blas_threads.hpp>
#include <incise/linalg/dense_blas.hpp>

#include <dlfcn.h>

#include <cstddef>

namespace incise::linalg {

namespace {

// Fortran BLAS/LAPACK entry points (LP64: int indices; the trailing size_t arguments are the
// hidden lengths of the character arguments that gfortran-compiled libraries expect, ignored by
// C implementations such as OpenBLAS's interface layer).
using Dgemm = void (*)(const char*, const char*, const int*, const int*, const int*, const double*,
                       const double*, const int*, const double*, const int*, const double*, double*,
                       const int*, std::size_t, std::size_t);
using Dtrsm = void (*)(const char*, const char*, const char*, const char*, const int*, const int*,
                       const double*, const double*, const int*, double*, const int*, std::size_t,
                       std::size_t, std::size_t, std::size_t);
using Dgetrf = void (*)(const int*, const int*, double*, const int*, int*, int*);
using Dgetrs = void (*)(const char*, const int*, const int*, const double*, const int*, const int*,
                        double*, const int*, int*, std::size_t);

struct Routines {
  Dgemm gemm = nullptr;
  Dtrsm trsm = nullptr;
  Dgetrf getrf = nullptr;
  Dgetrs getrs = nullptr;
  Routines() {
    // NOLINTBEGIN(cppcoreguidelines-pro-type-reinterpret-cast)
    gemm = reinterpret_cast<Dgemm>(dlsym(RTLD_DEFAULT, "dgemm_"));
    trsm = reinterpret_cast<Dtrsm>(dlsym(RTLD_DEFAULT, "dtrsm_"));
    getrf = reinterpret_cast<Dgetrf>(dlsym(RTLD_DEFAULT, "dgetrf_"));
    getrs = reinterpret_cast<Dgetrs>(dlsym(RTLD_DEFAULT, "dgetrs_"));
    // NOLINTEND(cppcoreguidelines-pro-type-reinterpret-cast)
    if (gemm == nullptr || trsm == nullptr || getrf == nullptr || getrs == nullptr)
      gemm = nullptr, trsm = nullptr, getrf = nullptr, getrs = nullptr;
  }
};

const Routines& routines() {
  static const Routines r;
  return r;
}

using ConstBlock = Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>;
using Block = Eigen::Map<Eigen::MatrixXd, 0, Eigen::OuterStride<>>;

}  // namespace

bool dense_blas_available() {
  return routines().gemm != nullptr;
}

void dense_gemm(bool transpose_a, bool transpose_b, int m, int n, int k, double alpha,
                const double* a, int lda, const double* b, int ldb, double beta, double* c, int ldc,
                bool use_blas) {
  if (m == 0 || n == 0) return;
  if (const Dgemm f = use_blas ? routines().gemm : nullptr) {
    const char ta = transpose_a ? 'T' : 'N', tb = transpose_b ? 'T' : 'N';
    f(&ta, &tb, &m, &n, &k, &alpha, a, &lda, b, &ldb, &beta, c, &ldc, 1, 1);
    return;
  }
  Block cm(c, m, n, Eigen::OuterStride<>(ldc));
  if (beta == 0) {
    cm.setZero();
  } else if (beta != 1) {
    cm *= beta;
  }
  if (k == 0) return;
  const ConstBlock am(a, transpose_a ? k : m, transpose_a ? m : k, Eigen::OuterStride<>(lda));
  const ConstBlock bm(b, transpose_b ? n : k, transpose_b ? k : n, Eigen::OuterStride<>(ldb));
  if (transpose_a && transpose_b) {
    cm.noalias() += alpha * am.transpose() * bm.transpose();
  } else if (transpose_a) {
    cm.noalias() += alpha * am.transpose() * bm;
  } else if (transpose_b) {
    cm.noalias() += alpha * am * bm.transpose();
  } else {
    cm.noalias() += alpha * am * bm;
  }
}

void dense_trsm_right_unit_lower(bool transpose_l, int m, int s, const double* l, int ldl,
                                 double* b, int ldb, bool use_blas) {
  if (m == 0 || s == 0) return;
  if (const Dtrsm f = use_blas ? routines().trsm : nullptr) {
    const char side = 'R', uplo = 'L', trans = transpose_l ? 'T' : 'N', diag = 'U';
    const double one = 1.0;
    f(&side, &uplo, &trans, &diag, &m, &s, &one, l, &ldl, b, &ldb, 1, 1, 1, 1);
    return;
  }
  const ConstBlock lm(l, s, s, Eigen::OuterStride<>(ldl));
  Block bm(b, m, s, Eigen::OuterStride<>(ldb));
  if (transpose_l) {  // X Lᵀ = B
    lm.transpose().triangularView<Eigen::UnitUpper>().solveInPlace<Eigen::OnTheRight>(bm);
  } else {  // X L = B
    lm.triangularView<Eigen::UnitLower>().solveInPlace<Eigen::OnTheRight>(bm);
  }
}

DenseLu::DenseLu(bool use_blas) : blas_(use_blas && dense_blas_available()) {}

void DenseLu::compute(const Eigen::MatrixXd& a) {
  INCISE_CHECK(a.rows() == a.cols(), "DenseLu::compute: the matrix must be square");
  n_ = a.rows();
  if (!blas_) {
    eigen_.compute(a);
    return;
  }
  lu_ = a;
  ipiv_.assign(static_cast<std::size_t>(n_), 0);
  if (n_ == 0) return;
  const int n = static_cast<int>(n_);
  int info = 0;
  const ScopedBlasThreads one(1);
  routines().getrf(&n, &n, lu_.data(), &n, ipiv_.data(), &info);
  INCISE_ASSERT(info >= 0, "dgetrf: invalid argument");  // > 0: a zero pivot (see header)
}

void DenseLu::solve_in_place(Eigen::MatrixXd& b, bool transposed) const {
  INCISE_CHECK(b.rows() == n_, "DenseLu::solve: one row per unknown");
  if (n_ == 0 || b.cols() == 0) return;
  if (!blas_) {
    if (transposed) {
      b = eigen_.transpose().solve(b);
    } else {
      b = eigen_.solve(b);
    }
    return;
  }
  const int n = static_cast<int>(n_), nrhs = static_cast<int>(b.cols());
  const char trans = transposed ? 'T' : 'N';
  int info = 0;
  const ScopedBlasThreads one(1);
  routines().getrs(&trans, &n, &nrhs, lu_.data(), &n, ipiv_.data(), b.data(), &n, &info, 1);
  INCISE_ASSERT(info == 0, "dgetrs: invalid argument");
}

Eigen::VectorXd DenseLu::solve(const Eigen::VectorXd& b, bool transposed) const {
  Eigen::MatrixXd x = b;
  solve_in_place(x, transposed);
  return x.col(0);
}

}  // namespace incise::linalg
