#pragma once
/// \file ldl_closure_solver.hpp
/// Sparse triangular solves with an LDLᵀ factor restricted to elimination-tree closures
/// (Yeung et al. 2016 §3.3, Appendix Thm. 1–3; Gilbert 1994). For a right-hand side b with
/// structure B, L⁻¹b is nonzero only on closure_L(B) = ∪_{v∈B} path(v → root) of the
/// elimination tree (Thm. 1 + 3); to obtain x = L⁻ᵀy at a set W only y on closure_L(W) is
/// needed (Thm. 2 + 3). Closures are sorted position lists (ascending), which is a topological
/// order for the forward solve; the backward solve walks them in reverse.

#include <incise/linalg/cholmod_factor.hpp>

#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace incise::linalg {

/// Solver working on an immutable LdlFactorData (P A Pᵀ = L D Lᵀ). Holds a dense workspace of
/// size n kept at zero between calls; not thread-safe (one object per thread), but several
/// objects may share the same factor.
///
/// With `threads` > 1 the full backward substitution (solve_sparse_rhs, solve_dense) runs on
/// that many threads of the process's worker pool (core/parallel.hpp run_parallel; on the
/// calling thread alone while the pool serves another call): the positions near the root of the
/// elimination forest are processed first, then disjoint subtrees — which need only x on their
/// ancestors — concurrently (planned once at construction; requires the postordered forest CHOLMOD
/// produces, else the pass stays serial). The arithmetic of every entry is unchanged, so the result
/// is bit-identical to the serial pass. The pass is memory-bound (it streams all of L), so the
/// wall-clock gain is bounded by the memory bandwidth that a second core adds (docs/augmented.md).
class ClosureLdlSolver {
 public:
  /// Precondition: factor != nullptr, threads ≥ 1.
  explicit ClosureLdlSolver(std::shared_ptr<const LdlFactorData> factor, int threads = 1);
  ~ClosureLdlSolver();
  ClosureLdlSolver(const ClosureLdlSolver&) = delete;
  ClosureLdlSolver& operator=(const ClosureLdlSolver&) = delete;

  /// The factor in use.
  const LdlFactorData& factor() const { return *factor_; }
  /// Shared handle of the factor.
  const std::shared_ptr<const LdlFactorData>& factor_ptr() const { return factor_; }

  /// closure_L of a set of *original* indices (each < n): the sorted positions of every
  /// elimination-tree ancestor of their positions, themselves included (Thm. 3).
  std::vector<int> closure(const std::vector<int>& original_indices);

  /// Sparse solve A x = b where b has entries `b_values` at original indices `b_indices`
  /// (duplicates are summed). `forward_closure` must contain closure(b_indices) and
  /// `backward_closure` must contain closure(wanted). Writes x at the original indices
  /// `wanted` into `x_wanted` (resized). Cost O(Σ_{j∈closures} |L_{*j}|).
  void solve_restricted(const std::vector<int>& b_indices, const std::vector<double>& b_values,
                        const std::vector<int>& forward_closure,
                        const std::vector<int>& backward_closure, const std::vector<int>& wanted,
                        std::vector<double>& x_wanted);

  /// Blocked restricted solve with the k unit right-hand sides e_c, c ∈ `columns` (original
  /// indices): X = (A⁻¹)_{wanted, columns} (wanted.size() × k). One forward pass over
  /// `forward_closure` (⊇ closure(columns)) and one backward pass over `backward_closure`
  /// (⊇ closure(wanted)) carry all k right-hand sides, so each entry of L is read once per pass
  /// and applied to k contiguous values (issue 17: the new columns of G = H R⁻¹ Hᵀ joining 𝓛 in
  /// one pass instead of k). A supernode's part of a closure (a suffix of its columns) is one
  /// dense block: with enough work (k·s·(s + r) ≥ 4096 multiply-adds for s columns and r rows
  /// below) it goes through BLAS-3 (dtrsm on the diagonal triangle, dgemm on the rows below;
  /// dense_blas.hpp), smaller ones entry by entry. Equal to k calls of solve_restricted up to
  /// the order of the floating-point sums. Cost O(k·Σ_{j∈closures} |L_{*j}|) flops, O(Σ |L_{*j}|)
  /// reads of L. `dense_kernels` false: every block entry by entry (for comparison).
  void solve_restricted_block(const std::vector<int>& columns,
                              const std::vector<int>& forward_closure,
                              const std::vector<int>& backward_closure,
                              const std::vector<int>& wanted, Eigen::MatrixXd& x_wanted,
                              bool dense_kernels = true);

  /// Sparse-RHS solve with a full result: restricted forward substitution on
  /// `forward_closure` (⊇ closure(b_indices)), then a full backward substitution (§3.3,
  /// "Sparsity of Solution Step 3"). `x` is resized to n (original ordering).
  void solve_sparse_rhs(const std::vector<int>& b_indices, const std::vector<double>& b_values,
                        const std::vector<int>& forward_closure, Eigen::VectorXd& x);
  /// As above, writing the n entries (original ordering) to `x` (not resized; must not alias
  /// the solver's workspace).
  void solve_sparse_rhs(const std::vector<int>& b_indices, const std::vector<double>& b_values,
                        const std::vector<int>& forward_closure, double* x);

  /// Dense solve A x = b (full forward and backward substitution).
  void solve_dense(const Eigen::VectorXd& b, Eigen::VectorXd& x);

  /// Supernode blocks the last solve_restricted_block() passed to the dense kernels (forward
  /// and backward passes counted separately).
  int last_block_dense_supernodes() const { return last_dense_blocks_; }

  /// Number of fundamental supernodes of L (maximal chains of columns j, j+1, … with
  /// pattern(L_{*j}) = {j+1} ∪ pattern(L_{*,j+1})), detected at construction. The triangular
  /// solves use them: one row list per supernode, contiguous dot products in the backward pass.
  int num_supernodes() const { return num_supernodes_; }

  /// Threads the full backward substitution actually uses (1 when the forest could not be
  /// split, e.g. a single chain, or when 1 was requested).
  int backward_threads() const {
    return static_cast<int>(bins_.size()) > 1 ? static_cast<int>(bins_.size()) : 1;
  }
  /// Fraction of the entries of L that the serial part (root side) of a threaded backward
  /// pass reads, and that the busiest thread reads afterwards; their sum bounds the
  /// wall-clock cost relative to the serial pass (1.0 / 1.0 without threads).
  double backward_serial_fraction() const { return serial_fraction_; }
  double backward_max_bin_fraction() const { return max_bin_fraction_; }

 private:
  void forward_supernode(int j, int j1, double* x);
  template <typename Positions>
  void forward(const Positions& positions, size_t count);
  template <typename Positions>
  void backward(const Positions& positions, size_t count, double* gather_end);
  void plan_threads(int threads);
  // Full backward substitution of work_, then x_out[perm[p]] = work_[p] and work_ = 0.
  void backward_full_to(double* x_out);
  std::shared_ptr<const LdlFactorData> factor_;
  std::vector<double> work_;  // permuted positions, zero between calls
  std::vector<int> slot_;     // solve_restricted_block: position → block row, −1 between calls
  std::vector<int> mark_;
  int stamp_ = 0;
  std::vector<int> super_last_;  // position → last column of its fundamental supernode
  std::vector<double> gather_;   // x on a supernode's row set (backward substitution)
  std::vector<double> acc_;      // updates of a supernode's row set (forward), zero between uses
  std::vector<int> super_rows_;  // row set of each supernode (at its last column), concatenated
  std::vector<std::int64_t> super_row_ptr_;  // column j₁ → start in super_rows_ (size n + 1)
  int num_supernodes_ = 0;
  int last_dense_blocks_ = 0;  // solve_restricted_block: blocks through dgemm/dtrsm
  // Threaded full backward pass: positions processed serially first (ascending; walked
  // descending), then one list of position ranges [first, last] (whole subtrees) per thread.
  std::vector<int> serial_;
  std::vector<std::vector<std::pair<int, int>>> bins_;
  std::vector<std::vector<double>> thread_gather_;  // gather buffers of bins 1, 2, …
  double serial_fraction_ = 1.0;
  double max_bin_fraction_ = 1.0;
};

}  // namespace incise::linalg
