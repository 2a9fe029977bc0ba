#include <incise/core/error.hpp>
#include <incise/solver/ldl_closure_solver.hpp>

#include <algorithm>
#include <utility>

namespace incise::solver {

ClosureLdlSolver::ClosureLdlSolver(std::shared_ptr<const LdlFactorData> factor)
    : factor_(std::move(factor)) {
  INCISE_CHECK(factor_ != nullptr, "ClosureLdlSolver needs a factor");
  work_.assign(static_cast<size_t>(factor_->n), 0.0);
  mark_.assign(static_cast<size_t>(factor_->n), 0);
}

std::vector<int> ClosureLdlSolver::closure(const std::vector<int>& original_indices) {
  const LdlFactorData& f = *factor_;
  if (++stamp_ == 0) {  // wrap-around: clear marks
    std::fill(mark_.begin(), mark_.end(), 0);
    stamp_ = 1;
  }
  std::vector<int> out;
  for (int i : original_indices) {
    INCISE_ASSERT(i >= 0 && i < f.n, "closure: index out of range");
    for (int p = f.inverse_perm[i]; p >= 0 && mark_[p] != stamp_; p = f.parent[p]) {
      mark_[p] = stamp_;
      out.push_back(p);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

void ClosureLdlSolver::forward(const std::vector<int>& closure_positions) {
  const LdlFactorData& f = *factor_;
  const int* cp = f.col_ptr.data();
  const int* ri = f.row_idx.data();
  const double* lv = f.values.data();
  double* x = work_.data();
  for (int j : closure_positions) {
    const double xj = x[j];
    if (xj != 0) {
      for (int k = cp[j]; k < cp[j + 1]; ++k) x[ri[k]] -= lv[k] * xj;
    }
  }
  for (int j : closure_positions) x[j] /= f.d[j];
}

void ClosureLdlSolver::solve_restricted(const std::vector<int>& b_indices,
                                        const std::vector<double>& b_values,
                                        const std::vector<int>& forward_closure,
                                        const std::vector<int>& backward_closure,
                                        const std::vector<int>& wanted,
                                        std::vector<double>& x_wanted) {
  const LdlFactorData& f = *factor_;
  double* x = work_.data();
  for (size_t k = 0; k < b_indices.size(); ++k) x[f.inverse_perm[b_indices[k]]] += b_values[k];
  forward(forward_closure);
  // Entries of the forward result outside backward_closure are never read below, so only the
  // backward closure needs a consistent value: positions in it but not in the forward closure
  // hold 0, which is the exact forward result there (Thm. 1).
  const int* cp = f.col_ptr.data();
  const int* ri = f.row_idx.data();
  const double* lv = f.values.data();
  for (auto it = backward_closure.rbegin(); it != backward_closure.rend(); ++it) {
    const int j = *it;
    double s = x[j];
    for (int k = cp[j]; k < cp[j + 1]; ++k) s -= lv[k] * x[ri[k]];
    x[j] = s;
  }
  x_wanted.resize(wanted.size());
  for (size_t k = 0; k < wanted.size(); ++k) x_wanted[k] = x[f.inverse_perm[wanted[k]]];
  for (int j : forward_closure) x[j] = 0;
  for (int j : backward_closure) x[j] = 0;
}

void ClosureLdlSolver::solve_sparse_rhs(const std::vector<int>& b_indices,
                                        const std::vector<double>& b_values,
                                        const std::vector<int>& forward_closure,
                                        Eigen::VectorXd& x_out) {
  const LdlFactorData& f = *factor_;
  double* x = work_.data();
  for (size_t k = 0; k < b_indices.size(); ++k) x[f.inverse_perm[b_indices[k]]] += b_values[k];
  forward(forward_closure);
  const int* cp = f.col_ptr.data();
  const int* ri = f.row_idx.data();
  const double* lv = f.values.data();
  for (int j = f.n - 1; j >= 0; --j) {
    double s = x[j];
    for (int k = cp[j]; k < cp[j + 1]; ++k) s -= lv[k] * x[ri[k]];
    x[j] = s;
  }
  x_out.resize(f.n);
  for (int p = 0; p < f.n; ++p) {
    x_out[f.perm[p]] = x[p];
    x[p] = 0;
  }
}

void ClosureLdlSolver::solve_dense(const Eigen::VectorXd& b, Eigen::VectorXd& x_out) {
  const LdlFactorData& f = *factor_;
  INCISE_CHECK(b.size() == f.n, "solve_dense: size mismatch");
  double* x = work_.data();
  for (int p = 0; p < f.n; ++p) x[p] = b[f.perm[p]];
  const int* cp = f.col_ptr.data();
  const int* ri = f.row_idx.data();
  const double* lv = f.values.data();
  for (int j = 0; j < f.n; ++j) {
    const double xj = x[j];
    if (xj != 0) {
      for (int k = cp[j]; k < cp[j + 1]; ++k) x[ri[k]] -= lv[k] * xj;
    }
  }
  for (int j = 0; j < f.n; ++j) x[j] /= f.d[j];
  for (int j = f.n - 1; j >= 0; --j) {
    double s = x[j];
    for (int k = cp[j]; k < cp[j + 1]; ++k) s -= lv[k] * x[ri[k]];
    x[j] = s;
  }
  x_out.resize(f.n);
  for (int p = 0; p < f.n; ++p) {
    x_out[f.perm[p]] = x[p];
    x[p] = 0;
  }
}

}  // namespace incise::solver
