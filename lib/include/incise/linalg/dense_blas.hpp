#pragma once
/// \file dense_blas.hpp
/// Dense kernels of the augmented solver (issue 17) through the BLAS/LAPACK that CHOLMOD loads
/// (Debian's alternatives: OpenBLAS, whose kernels use the CPU's widest vector unit; the library
/// itself is compiled for baseline x86-64, where Eigen's dense kernels use SSE2 only). The
/// routines (dgemm, dtrsm, dgetrf, dgetrs) are looked up at run time in the loaded libraries,
/// like blas_threads.hpp's controls; without them every function here falls back to Eigen, with
/// the same results up to the order of the floating-point sums. DenseLu holds a
/// ScopedBlasThreads(1) around its calls; dense_gemm and dense_trsm_right_unit_lower run with the
/// BLAS's current thread count (callers hold the scope once per blocked operation).
/// Measurements: docs/augmented.md, "Frame maximum (issue 17)".

#include <Eigen/Dense>

#include <vector>

namespace incise::linalg {

/// Whether dgemm, dtrsm, dgetrf and dgetrs were found in the process.
bool dense_blas_available();

/// C = α op(A) op(B) + β C for column-major blocks (BLAS dgemm): op(A) is m×k, op(B) k×n, C m×n,
/// leading dimensions lda, ldb, ldc. With β = 0, C need not be initialized. `use_blas` = false
/// (or no BLAS found) takes Eigen's product.
void dense_gemm(bool transpose_a, bool transpose_b, int m, int n, int k, double alpha,
                const double* a, int lda, const double* b, int ldb, double beta, double* c, int ldc,
                bool use_blas = true);

/// B ← B op(L)⁻¹ for a unit-lower-triangular s×s L (BLAS dtrsm, side right, diagonal unit):
/// B is m×s, leading dimension ldb; L leading dimension ldl; only L's strict lower triangle is
/// read. `use_blas` = false (or no BLAS found) takes Eigen's triangular solve.
void dense_trsm_right_unit_lower(bool transpose_l, int m, int s, const double* l, int ldl,
                                 double* b, int ldb, bool use_blas = true);

/// Dense LU with partial pivoting, P A = L U (LAPACK dgetrf/dgetrs; Eigen::PartialPivLU when
/// they are missing or `use_blas` is false). Solves with many right-hand sides at once (BLAS-3).
class DenseLu {
 public:
  explicit DenseLu(bool use_blas = true);
  /// Factors the square matrix `a`. An exactly singular `a` is factored (a zero pivot); its
  /// solves then hold Inf/NaN, as Eigen's do.
  void compute(const Eigen::MatrixXd& a);
  /// Order of the factored matrix (0 before compute()).
  Eigen::Index size() const { return n_; }
  /// B ← A⁻¹ B, or A⁻ᵀ B when `transposed` (B: size() rows, any number of columns).
  void solve_in_place(Eigen::MatrixXd& b, bool transposed = false) const;
  /// A⁻¹ b, or A⁻ᵀ b when `transposed`.
  Eigen::VectorXd solve(const Eigen::VectorXd& b, bool transposed = false) const;
  /// Whether this factorization went through LAPACK.
  bool uses_blas() const { return blas_; }

 private:
  bool blas_;
  Eigen::Index n_ = 0;
  Eigen::MatrixXd lu_;     // LAPACK: L and U in place
  std::vector<int> ipiv_;  // LAPACK: 1-based row interchanges
  Eigen::PartialPivLU<Eigen::MatrixXd> eigen_;
};

}  // namespace incise::linalg
