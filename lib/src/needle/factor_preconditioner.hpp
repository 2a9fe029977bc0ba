#pragma once
// Private to the needle module: the factor preconditioner of NeedleInsertion3D's linear CG
// (InsertionOptions3D::factor_preconditioner; contract in insertion3d.hpp).
//
// B = the CHOLMOD factor of M, the rotated stiffness K̃ = RᵀKR of the needle problem at its last
// factorization with the DOFs fixed then decoupled (their row and column zero but the diagonal
// K̃_ii). Between factorizations the body is refined (new DOFs appended: vertex order is kept)
// and needle constraints are imposed and released; B r is then M⁻¹ applied to the first n_M
// components and the Jacobi scaling 1/K_ii to the new ones (linear_cg projects the result). B is
// fixed and symmetric positive definite on the free DOFs, so preconditioned CG converges to the
// same solution as plain CG; how fast depends on how far the current system has moved from M,
// hence the refactorization rule (changed_dofs()).

#include <incise/core/types.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/needle/needle_problem.hpp>

#include <string>
#include <vector>

namespace incise::needle::detail {

class FactorPreconditioner {
 public:
  /// Whether a factor exists.
  bool ready() const { return ready_; }
  /// DOFs whose treatment differs from M's: appended DOFs plus DOFs of M whose fixed state in
  /// `np` differs from the factored one (np.size() ≥ the factored size).
  Eigen::Index changed_dofs(const NeedleProblem3D& np) const;
  /// Order of M.
  Eigen::Index size() const { return static_cast<Eigen::Index>(fixed_.size()); }
  /// Factors M of `np` (linear material: K is taken at u = 0). False with `message` when the
  /// assembly or the factorization fails (the old factor is then dropped).
  bool factor(NeedleProblem3D& np, std::string& message);
  /// Prepares the Jacobi scaling of DOFs appended since the factorization (the body's diagonal).
  /// False with `message` when the diagonal is unavailable or not positive.
  bool follow(NeedleProblem3D& np, std::string& message);
  /// z = B r (see file comment); r of np's size at the last follow().
  void apply(const VecX& r, VecX& z);
  /// Whether an apply() failed since the last factor() (a solve with the factor failed: the
  /// CG run that used it must be reported failed).
  bool failed() const { return failed_; }
  /// Factorizations so far.
  int factorizations() const { return factorizations_; }

 private:
  linalg::CholmodFactor factor_;
  bool ready_ = false;
  bool failed_ = false;
  std::vector<char> fixed_;  // per DOF of M: fixed when factored
  VecX inverse_diagonal_;    // 1/K̃_ii of the appended DOFs (0 at fixed ones)
  VecX head_, solution_;     // scratch
  std::uint64_t pattern_version_ = 0;
  Eigen::Index analyzed_size_ = -1;
  int factorizations_ = 0;
};

}  // namespace incise::needle::detail
