#pragma once
/// \file capacitance_factor.hpp
/// A dense factorization of the m×m capacitance (Schur) matrix S = H R⁻¹ J of Yeung et al. 2016
/// eq. 17 that is *updated*, not refactored, when columns join or leave 𝓛 or change value
/// (issue 17). Rows and columns carry labels (the DOFs of 𝓛). A fresh factorization keeps
/// S₀ (equilibrated: row scales, then column scales, fixed per label) and its partial-pivoting
/// LU. A later matrix S on labels 𝓛 is embedded with S₀ in the label union 𝓤 (identity on
/// 𝓤 ∖ 𝓛 and on 𝓤 ∖ 𝓛₀); the difference D = Ŝ − Ŝ₀ is nonzero only in the rows and columns
/// of the labels 𝓒 whose row or column changed (found by exact comparison), so
///     D = D_{*,𝓒} E_𝓒ᵀ + E_𝓒 D̃_{𝓒,*}   (D̃: D with the 𝓒 columns zeroed),  rank ≤ 2|𝓒|,
/// and Ŝ⁻¹ = Ŝ₀⁻¹ − W K⁻¹ Vᵀ Ŝ₀⁻¹ with U = [D_{*,𝓒}, E_𝓒], Vᵀ = [E_𝓒ᵀ; D̃_{𝓒,*}],
/// W = Ŝ₀⁻¹ U and the 2|𝓒|-square K = I + Vᵀ W (Sherman–Morrison–Woodbury). Columns of W are
/// cached by label and recomputed only when their column of U changed, so an update costs
/// O(m²k) for k changed columns plus O(m|𝓒|² + |𝓒|³) for K; when that predicted cost exceeds
/// a fresh factorization's (⅔m³) the factorization is redone (a periodic fresh factorization
/// for accuracy, deterministic in the counts). The reciprocal condition estimate is Hager's
/// 1-norm estimator (Higham, "Accuracy and Stability of Numerical Algorithms", 2nd ed., §15.3,
/// Alg. 15.4) on the updated operator.

#include <incise/linalg/dense_blas.hpp>

#include <Eigen/Dense>

#include <cstdint>
#include <unordered_map>
#include <vector>

namespace incise::linalg {

/// What one CapacitanceFactor::update() did.
struct CapacitanceUpdate {
  bool refreshed = false;  ///< a fresh factorization was made (first call, or cost rule)
  int changed = 0;         ///< r = |𝓠| + |𝓡|: rank of the correction to S₀ (0 if fresh)
  int new_solves = 0;      ///< columns of W computed in this update (LU solves with S₀)
  double rcond = 0;        ///< reciprocal 1-norm condition estimate of the equilibrated S
  /// The cost rule's inputs (0 when the factorization was fresh without it: first call or
  /// force_fresh): the rank the update needed and its predicted flops against a fresh LU's.
  int needed_rank = 0;
  double update_flops = 0;
  double fresh_flops = 0;
};

/// The updatable factorization of the file comment. Not thread-safe.
class CapacitanceFactor {
 public:
  /// `refresh_ratio`: refactor when the predicted update cost exceeds this × a fresh
  /// factorization's (flop counts; > 0). 1 = whichever is cheaper. `use_blas`: the LUs, their
  /// many-right-hand-side solves and VᵀW through LAPACK/BLAS (dense_blas.hpp) when the process
  /// has them; false: Eigen's kernels (the comparison of docs/augmented.md).
  explicit CapacitanceFactor(double refresh_ratio = 1.0, bool use_blas = true);
  /// Makes the operator of `s` (square, size labels.size()) whose rows and columns are labelled
  /// `labels` (strictly increasing): updates the kept factorization, or refactors (first call,
  /// `force_fresh`, or the cost rule). Throws UsageError on mismatched sizes or unsorted labels.
  CapacitanceUpdate update(const Eigen::MatrixXd& s, const std::vector<int>& labels,
                           bool force_fresh = false);
  /// x = S⁻¹ b for the matrix of the last update (b, x: one entry per label, in label order).
  void solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const;
  /// Forgets everything (the next update is fresh).
  void clear();
  /// Row and column scales of the last update, one per label: the factor works on
  /// Ŝ = diag(row) S diag(col), embedded with an identity block on 𝓤 ∖ 𝓛 (its rcond is
  /// that of CapacitanceUpdate::rcond).
  const Eigen::VectorXd& row_scale() const { return row_scale_; }
  const Eigen::VectorXd& col_scale() const { return col_scale_; }  ///< see row_scale()
  /// Number of fresh factorizations so far.
  std::int64_t fresh_count() const { return fresh_count_; }

 private:
  void fresh(const Eigen::MatrixXd& s, const std::vector<int>& labels);
  // x = Ŝ₀⁻¹ b and x = Ŝ₀⁻ᵀ b on the union positions.
  Eigen::VectorXd solve0(const Eigen::VectorXd& b) const;
  Eigen::VectorXd solve0_transposed(const Eigen::VectorXd& b) const;
  // The updated operator and its transpose on union positions (equilibrated space).
  Eigen::VectorXd apply_inverse(const Eigen::VectorXd& b) const;
  Eigen::VectorXd apply_inverse_transposed(const Eigen::VectorXd& b) const;
  double estimate_rcond(const Eigen::MatrixXd& shat) const;

  double refresh_ratio_;
  bool use_blas_;
  std::int64_t fresh_count_ = 0;
  // Fresh state.
  std::vector<int> ref_labels_;                               // 𝓛₀ (sorted)
  Eigen::MatrixXd s0_;                                        // equilibrated S₀
  DenseLu lu0_;                                               // LAPACK (dense_blas.hpp)
  std::unordered_map<int, std::pair<double, double>> scale_;  // label → (row, column) scale
  // Last update.
  std::vector<int> union_;    // 𝓤 (sorted)
  std::vector<int> ref_pos_;  // per union position: position in 𝓛₀ or −1
  std::vector<int> cur_pos_;  // per current label: position in 𝓤
  Eigen::MatrixXd w_;         // Ŝ₀⁻¹ U (|𝓤| × 2|𝓒|)
  Eigen::MatrixXd vt_;        // Vᵀ (2|𝓒| × |𝓤|)
  DenseLu k_lu_;
  Eigen::VectorXd row_scale_, col_scale_;  // per current label
  // Cache of Ŝ₀⁻¹ d for the D columns, by label: the 𝓛₀ part of d and of Ŝ₀⁻¹ d.
  std::unordered_map<int, std::pair<Eigen::VectorXd, Eigen::VectorXd>> w_cache_;
};

}  // namespace incise::linalg
