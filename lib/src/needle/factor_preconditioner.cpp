#include "factor_preconditioner.hpp"

#include <cmath>

namespace incise::needle::detail {

Eigen::Index FactorPreconditioner::changed_dofs(const NeedleProblem3D& np) const {
  if (!ready_) return np.size();
  Eigen::Index changed = np.size() - size();
  for (Eigen::Index i = 0; i < size(); ++i)
    if ((fixed_[static_cast<std::size_t>(i)] != 0) != np.is_fixed(i)) ++changed;
  return changed;
}

bool FactorPreconditioner::factor(NeedleProblem3D& np, std::string& message) {
  ready_ = false;
  failed_ = false;
  const Eigen::Index n = np.size();
  Eigen::SparseMatrix<double> k;
  if (np.base().tangent(VecX::Zero(n), k) != EvalStatus::kOk) {
    message = "the stiffness for the factor preconditioner could not be assembled";
    return false;
  }
  const Eigen::SparseMatrix<double> r = np.rotation();
  // R has a full 3×3 block at every needle vertex and K full 3×3 node blocks: the (unpruned)
  // product has K's pattern, so the analysis serves until the mesh changes.
  const Eigen::SparseMatrix<double> kr = Eigen::SparseMatrix<double>(r.transpose()) * k * r;
  fixed_.assign(static_cast<std::size_t>(n), 0);
  for (Eigen::Index i = 0; i < n; ++i) fixed_[static_cast<std::size_t>(i)] = np.is_fixed(i);
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<std::size_t>(kr.nonZeros() / 2 + n));
  for (int c = 0; c < kr.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(kr, c); it; ++it) {
      if (it.row() < c) continue;
      const bool decoupled =
          fixed_[static_cast<std::size_t>(it.row())] || fixed_[static_cast<std::size_t>(c)];
      // Zeros are kept as entries: the pattern does not depend on the constraints.
      trip.emplace_back(static_cast<int>(it.row()), c,
                        decoupled && it.row() != c ? 0.0 : it.value());
    }
  linalg::SparseMatrix m(static_cast<int>(n), static_cast<int>(n));
  m.setFromTriplets(trip.begin(), trip.end());
  if (n != analyzed_size_) {
    ++pattern_version_;
    analyzed_size_ = n;
  }
  const linalg::FactorStatus fs = factor_.compute(m, pattern_version_);
  ++factorizations_;
  if (fs != linalg::FactorStatus::kOk) {
    message = std::string("the factor preconditioner's factorization failed (") +
              linalg::to_string(fs) + ": " + factor_.message() + ")";
    analyzed_size_ = -1;
    return false;
  }
  inverse_diagonal_.resize(0);
  ready_ = true;
  return true;
}

bool FactorPreconditioner::follow(NeedleProblem3D& np, std::string& message) {
  const Eigen::Index n = np.size(), nm = size();
  inverse_diagonal_.resize(n - nm);
  if (n == nm) return true;
  // The body's diagonal (original frame; any positive diagonal is a valid scaling), at every
  // new DOF: one fixed now may be released by a rearrangement before the next follow().
  VecX diag;
  if (!np.base().hessian_diagonal(VecX::Zero(n), diag)) {
    message = "the diagonal for the factor preconditioner's new DOFs is unavailable";
    return false;
  }
  for (Eigen::Index i = nm; i < n; ++i) {
    const double d = diag[i];
    if (!(std::isfinite(d) && d > 0.0)) {
      message =
          "the stiffness diagonal at new DOF " + std::to_string(i) + " is not positive and finite";
      return false;
    }
    inverse_diagonal_[i - nm] = 1.0 / d;
  }
  return true;
}

void FactorPreconditioner::apply(const VecX& r, VecX& z) {
  const Eigen::Index nm = size();
  z.resize(r.size());
  head_ = r.head(nm);
  // The fixed DOFs of M are decoupled: their components of M⁻¹r are r_i/K̃_ii, zeroed by the
  // caller's projection when they are still fixed.
  if (factor_.solve(head_, solution_) != linalg::FactorStatus::kOk) {
    failed_ = true;  // reported by the caller (failed()); z = r keeps CG's arithmetic finite
    z = r;
    return;
  }
  z.head(nm) = solution_;
  z.tail(r.size() - nm) = inverse_diagonal_.cwiseProduct(r.tail(r.size() - nm));
}

}  // namespace incise::needle::detail
