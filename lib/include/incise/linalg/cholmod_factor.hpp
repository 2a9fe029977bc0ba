#pragma once
/// \file cholmod_factor.hpp
/// RAII wrapper of a CHOLMOD sparse Cholesky factorization (analyze / factorize / solve / info),
/// with Eigen types at the boundary. One `cholmod_common` per object: an object may be used by
/// one thread at a time, and different objects may be used concurrently (Yeung et al. 2016
/// §3.6 runs a second object in a background thread).

#include <incise/core/types.hpp>

#include <Eigen/SparseCore>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace incise::linalg {

/// Sparse matrix type at the solver boundary: column-major, 32-bit indices, compressed.
using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

/// Which CHOLMOD factorization to compute.
enum class CholmodKind {
  kSupernodal,     ///< supernodal LLᵀ using BLAS (OpenBLAS) dense kernels
  kSimplicialLdl,  ///< simplicial (column-by-column, no BLAS) LDLᵀ
  kAuto            ///< CHOLMOD's own choice (supernodal when flops/nnz(L) is large)
};

/// Fill-reducing ordering.
enum class CholmodOrdering {
  kDefault,  ///< CHOLMOD default: AMD, and METIS/NESDIS if AMD fill is large (when compiled in)
  kAmd,      ///< approximate minimum degree only
  kNatural,  ///< identity permutation (for tests; usually much more fill)
  kMetis     ///< METIS nested dissection: shallow elimination trees, hence small closures
             ///< (Yeung et al. 2016 §3.4, Thm. 3) — the default of AugmentedSystem
};

/// Options of a CholmodFactor.
struct CholmodOptions {
  CholmodKind kind = CholmodKind::kSupernodal;  ///< see docs/augmented.md for the measurement
  CholmodOrdering ordering = CholmodOrdering::kDefault;
  /// A factorization whose pivot ratio min Dᵢᵢ / max Dᵢᵢ (CHOLMOD's rcond estimate) is below
  /// this is reported as kNotPositiveDefinite ("numerically singular"): CHOLMOD itself only
  /// flags pivots ≤ 0, and an exactly singular matrix usually yields a positive pivot of
  /// round-off size (e.g. a floating component after a cut). 0 disables the check.
  double min_pivot_ratio = 1e-14;
  /// CHOLMOD's dbound: pivots D_jj of a simplicial LDLᵀ with |D_jj| < pivot_bound are replaced
  /// by ±pivot_bound, and the factorization reports kTinyPivot (CHOLMOD_DSMALL); CHOLMOD's
  /// supernodal factorization ignores it. 0 (default) leaves every pivot as computed. ≥ 0.
  double pivot_bound = 0.0;
  /// Memory budget of the numeric factorization (bytes; 0: none). factorize() compares
  /// CholmodFactor::estimated_factor_bytes() — known from the symbolic analysis — with it first
  /// and refuses with kOverMemoryBudget instead of allocating. Callers pass their budget
  /// (e.g. incise::default_memory_budget_bytes(), scene limits.memory_mb).
  std::uint64_t memory_budget_bytes = 0;
  /// BLAS threads of factorize() (blas_threads.hpp): all of blas_thread_settings().max_threads
  /// when CHOLMOD's flop estimate of the factorization (factor_flops()) is at least this, one
  /// thread below it. Negative (default): blas_thread_settings().parallel_flops
  /// (kDefaultBlasParallelFlops unless INCISE_BLAS_PARALLEL_FLOPS is set). solve() always uses
  /// one thread (a triangular solve is memory-bound).
  double blas_parallel_flops = -1.0;
};

/// Outcome of analyze/factorize/solve, in the spirit of Eigen's `info()`.
enum class FactorStatus {
  kOk,
  kNotAnalyzed,          ///< factorize/solve called before analyze (usage error, reported)
  kNotPositiveDefinite,  ///< a pivot ≤ 0: matrix is singular or indefinite; `minor()` says where
  kOutOfMemory,          ///< CHOLMOD could not allocate
  kInvalidInput,         ///< matrix not square, sizes differ from the analysis, NaN entries
  kCholmodError,         ///< any other CHOLMOD failure, or a CHOLMOD warning code incise does
                         ///< not know (the factor is then not used; code in `message()`)
  /// CHOLMOD_DSMALL: pivots below CholmodOptions::pivot_bound were replaced by ±pivot_bound.
  /// The factor exists and solve() works, but it is the factor of a perturbed matrix A + E
  /// (diagonal E, |E_jj| ≤ pivot_bound); callers that need A⁻¹ itself must not accept it.
  kTinyPivot,
  /// The numeric factorization would need more than CholmodOptions::memory_budget_bytes
  /// (estimated_factor_bytes(), from the symbolic analysis): not attempted, no factor; the
  /// message states the estimate, nnz(L) and the budget.
  kOverMemoryBudget
};

/// Human-readable name of a FactorStatus.
const char* to_string(FactorStatus status);

/// Unit lower-triangular LDLᵀ factor of a permuted SPD matrix, P A Pᵀ = L D Lᵀ, stored as plain
/// arrays (compressed columns, strictly lower part; the unit diagonal is implicit).
/// Immutable once built: may be shared between threads (e.g. through shared_ptr<const>).
/// Row index i of L refers to permuted position i; `perm[i]` is the original index at position
/// i and `inverse_perm[perm[i]] = i`. The elimination-tree parent of column j is the smallest
/// row index in column j (−1 for a root) — Yeung et al. 2016, Appendix Definition 2, Thm. 3.
struct LdlFactorData {
  int n = 0;                      ///< order of A
  std::vector<int> perm;          ///< position → original index
  std::vector<int> inverse_perm;  ///< original index → position
  std::vector<int> col_ptr;       ///< size n+1
  std::vector<int> row_idx;       ///< sorted ascending within each column, all > column index
  std::vector<double> values;     ///< entries of L below the diagonal
  std::vector<double> d;          ///< diagonal D (all > 0 for an SPD matrix)
  std::vector<int> parent;        ///< elimination tree parent of each position, −1 for roots

  /// Number of stored entries of L including the unit diagonal (|L| in Table I of the paper).
  std::int64_t nnz_l() const { return static_cast<std::int64_t>(values.size()) + n; }
};

/// RAII CHOLMOD factorization of a symmetric positive definite matrix A (only the lower
/// triangle of the Eigen matrix is read). Usage: analyze(A) once per sparsity pattern,
/// factorize(A) per numerical values, then solve(b). The symbolic analysis is cached by the
/// caller-supplied pattern version: analyze() with the same version and the same size and
/// nonzero count is a no-op. Failures are returned as FactorStatus, never thrown; misuse
/// (non-square input) also reports kInvalidInput. A CHOLMOD warning is never kOk: a factor
/// exists (solve() and extract_ldl() work) after kOk or kTinyPivot only.
class CholmodFactor {
 public:
  /// Throws ParameterError for a negative options.pivot_bound.
  explicit CholmodFactor(CholmodOptions options = {});
  ~CholmodFactor();
  CholmodFactor(const CholmodFactor&) = delete;
  CholmodFactor& operator=(const CholmodFactor&) = delete;
  CholmodFactor(CholmodFactor&&) noexcept;
  CholmodFactor& operator=(CholmodFactor&&) noexcept;

  /// Symbolic analysis (ordering, elimination tree, pattern of L) of the pattern of `a`.
  /// Reuses the previous analysis when `pattern_version` equals the previous one and the size
  /// and nonzero count agree. Pass a fresh version whenever the pattern changes.
  [[nodiscard]] FactorStatus analyze(const SparseMatrix& a, std::uint64_t pattern_version);
  /// The same with the fill-reducing ordering given instead of computed (CHOLMOD_GIVEN,
  /// postordered): `permutation[k]` is the row eliminated k-th (LdlFactorData::perm's
  /// convention); empty: the options' ordering. kInvalidInput when it is not a permutation of
  /// the rows.
  [[nodiscard]] FactorStatus analyze(const SparseMatrix& a, std::uint64_t pattern_version,
                                     const std::vector<int>& permutation);

  /// Numerical factorization of `a` (same pattern as analyzed). kNotPositiveDefinite when a
  /// pivot is not positive (minor() is then the failing column, in the permuted order) or the
  /// pivot ratio is below min_pivot_ratio; kTinyPivot when pivot_bound replaced pivots (the
  /// message says how many; the pivot-ratio check is then skipped: the bound sets the ratio);
  /// kInvalidInput for a NaN/Inf entry.
  [[nodiscard]] FactorStatus factorize(const SparseMatrix& a);

  /// analyze(a, version) followed by factorize(a).
  [[nodiscard]] FactorStatus compute(const SparseMatrix& a, std::uint64_t pattern_version);

  /// Solves A x = b with the current factor (dense right-hand side). Returns info().
  [[nodiscard]] FactorStatus solve(const Eigen::VectorXd& b, Eigen::VectorXd& x);

  /// What modify() did: |T| rows/columns touched by Δ, the ranks of the update and the
  /// downdate (positive and negative eigenvalues of Δ_TT kept), and where the time went.
  struct ModifyStats {
    int touched = 0;
    int rank_update = 0;
    int rank_downdate = 0;
    double cpu_seconds_split = 0;   ///< thread CPU of the eigendecomposition of Δ_TT
    double cpu_seconds_updown = 0;  ///< thread CPU of the cholmod_updown calls and checks
  };
  /// Low-rank modification of the stored factor, A ← A + Δ, by CHOLMOD's multiple-rank
  /// update/downdate (cholmod_updown, Davis & Hager; the Modify module; new fill in L is added
  /// by CHOLMOD). Δ (same order as A, symmetric, both triangles stored) restricted to the
  /// rows/columns T it touches is split by a dense symmetric eigendecomposition into
  /// Δ_TT = V₊Λ₊V₊ᵀ − V₋|Λ₋|V₋ᵀ (|λ| ≤ 1e-14·max|λ| dropped: round-off of the
  /// eigensolver); the factor is updated by P V₊Λ₊^½ first and then downdated by P V₋|Λ₋|^½,
  /// so that the intermediate A + Δ₊ is positive definite whenever A is. Cost: the dense
  /// eigendecomposition O(|T|³) plus CHOLMOD's O(rank · Σ|L_j|) over the etree paths of T.
  /// Precondition: a simplicial factor (CholmodKind::kSimplicialLdl) from factorize() with kOk
  /// (kNotAnalyzed otherwise; a supernodal factor gives kInvalidInput, a wrong size
  /// kInvalidInput). kNotPositiveDefinite when a pivot of the modified factor is ≤ 0 or the
  /// pivot ratio falls below min_pivot_ratio (the factor is then unusable: refactor).
  /// rcond() is updated. Round-off of successive modifications accumulates; callers compare
  /// with a fresh factorization now and then (docs/augmented.md, organ-scale strategies).
  [[nodiscard]] FactorStatus modify(const SparseMatrix& delta, ModifyStats* stats = nullptr);

  /// Status of the last operation.
  FactorStatus info() const { return status_; }
  /// CHOLMOD's message for the last failure (empty when ok).
  const std::string& message() const { return message_; }
  /// Column where factorization stopped (n when successful).
  int minor() const { return minor_; }
  /// Order of the analyzed matrix (0 before analyze).
  int rows() const { return n_; }
  /// CHOLMOD's reciprocal condition estimate of the last factorization (min/max pivot of D).
  double rcond() const { return rcond_; }
  /// Whether the stored factor is supernodal.
  bool is_supernodal() const;
  /// Nonzeros of L as counted by CHOLMOD (including the diagonal; supernodal storage counts
  /// the padded dense blocks).
  std::int64_t nnz_l() const;
  /// Bytes the numeric factorization will allocate, known after analyze() (0 before): the
  /// values and integer pattern of L — supernodal: L->xsize doubles, L->ssize + 4·nsuper + n
  /// ints, plus the largest update matrix (maxcsize doubles); simplicial: nnz(L) doubles and
  /// ints plus 6n ints — and CHOLMOD's workspace (≈ 2n doubles, 5n ints). Read from the
  /// symbolic analysis, before any of it is allocated.
  std::uint64_t estimated_factor_bytes() const;
  /// Peak bytes CHOLMOD has held at once since this object was made (cholmod_common's
  /// memory_usage): what estimated_factor_bytes() predicts, measured.
  std::uint64_t peak_memory_bytes() const;
  /// Floating point operations of the last factorization as estimated by CHOLMOD (fl).
  double factor_flops() const;
  /// BLAS threads the last factorize() ran with (0 before any; 1 below the threshold).
  int last_blas_threads() const { return last_blas_threads_; }
  /// Number of symbolic analyses actually performed (cache misses), for tests.
  int analyses_performed() const { return analyses_; }

  /// Copy of the factor as unit-lower LDLᵀ arrays (a supernodal LLᵀ factor is read supernode
  /// by supernode: d_j = L_jj², l_ij = L_ij/L_jj, the padding of relaxed supernodes kept as
  /// explicit zeros; the stored factor is not modified). Precondition: the last
  /// factorize gave kOk or kTinyPivot; otherwise returns nullptr.
  std::shared_ptr<const LdlFactorData> extract_ldl();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  CholmodOptions options_;
  FactorStatus status_ = FactorStatus::kNotAnalyzed;
  std::string message_;
  int minor_ = 0;
  double rcond_ = 0;
  int n_ = 0;
  int analyses_ = 0;
  std::int64_t analyzed_nnz_ = -1;
  std::uint64_t pattern_version_ = 0;
  bool factorized_ = false;
  int last_blas_threads_ = 0;
};

}  // namespace incise::linalg
