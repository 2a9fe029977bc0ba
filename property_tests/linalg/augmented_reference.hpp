#pragma once
/// \file augmented_reference.hpp
/// Test scaffolding: the "fresh factorization" reference of the augmented-system equivalence
/// tests. Solves K a = f + r with a_d = ā_d on 𝓓 and r = 0 off 𝓓 by eliminating 𝓓 and
/// factoring the free block anew with CHOLMOD (no augmented machinery involved).

#include <incise/linalg/augmented_system.hpp>

#include <map>

namespace incise::test {

/// Reference solution; `ok` is false when the free block is not positive definite.
struct ReferenceSolution {
  bool ok = false;
  Eigen::VectorXd a;  ///< displacements
  Eigen::VectorXd r;  ///< reactions K a − f on 𝓓 (zero elsewhere)
  double rcond = 1;   ///< CHOLMOD's pivot-ratio estimate of 1/κ of the free block
};

inline ReferenceSolution reference_solve(const linalg::SparseMatrix& k, const Eigen::VectorXd& f,
                                         const std::map<int, double>& dirichlet) {
  const int n = static_cast<int>(k.rows());
  std::vector<bool> fixed(static_cast<size_t>(n), false);
  Eigen::VectorXd abar = Eigen::VectorXd::Zero(n);
  for (const auto& [d, v] : dirichlet) {
    fixed[d] = true;
    abar(d) = v;
  }
  const linalg::ReducedMatrix red = linalg::remove_fixed_dofs(k, fixed);
  const Eigen::VectorXd rhs_full = f - k * abar;
  Eigen::VectorXd rhs(red.matrix.rows());
  for (int i = 0; i < n; ++i) {
    if (red.full_to_free[i] >= 0) rhs(red.full_to_free[i]) = rhs_full(i);
  }
  ReferenceSolution out;
  out.a = abar;
  if (red.matrix.rows() > 0) {
    linalg::CholmodFactor factor;
    if (factor.compute(red.matrix, 1) != linalg::FactorStatus::kOk) return out;
    out.rcond = factor.rcond();
    Eigen::VectorXd x;
    if (factor.solve(rhs, x) != linalg::FactorStatus::kOk) return out;
    for (int i = 0; i < n; ++i) {
      if (red.full_to_free[i] >= 0) out.a(i) = x(red.full_to_free[i]);
    }
  }
  const Eigen::VectorXd ka = k * out.a - f;
  out.r = Eigen::VectorXd::Zero(n);
  for (const auto& kv : dirichlet) out.r(kv.first) = ka(kv.first);
  out.ok = true;
  return out;
}

}  // namespace incise::test
