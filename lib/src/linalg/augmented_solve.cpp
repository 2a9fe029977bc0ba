#include "augmented_base.hpp"

#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>
#include <incise/linalg/augmented_system.hpp>
#include <incise/linalg/ldl_closure_solver.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <mutex>
#include <sstream>
#include <utility>

/// \file
/// AugmentedSystem::solve (§3.1–3.5) and its steps.

namespace incise::linalg {

// ---------------------------------------------------------------------------------------------
// Solution (§3.1–3.5). solve() runs the steps below in order; each names its equations.

// The augmented structure of one solve: 𝓛 and 𝓓 (as flags), the columns of J (eq. 5; H of
// eq. 6 is implied by 𝓛), f̂ (eq. 11), their sparsity on the base rows and its closures (§3.3).
struct AugmentedSystem::Augmentation {
  std::vector<int> l;                 // 𝓛, sorted
  std::vector<int> l_base;            // the entries of 𝓛 below n_base (its first ones)
  std::vector<char> is_dirichlet;     // per entry of 𝓛: in 𝓓 (J column e_{𝓛ᵢ})
  std::vector<const Column*> j_cols;  // per entry of 𝓛: the stored column K_{*,𝓛ᵢ} (not 𝓓)
  std::deque<Column> masked;          // columns of J without the rows of eliminated DOFs
  std::vector<int> eliminated;        // 𝓓 ∩ eliminated in R (eliminate_constrained), sorted
  Eigen::VectorXd fhat;               // f̂ of eq. 11 (size n)
  std::vector<int> f_idx;             // struct(f̂) on the base rows, ascending
  std::vector<double> f_val;          // f̂ there
  std::vector<int> j_struct;          // struct(J) on the base rows, ascending
  std::vector<int> step3_struct;      // struct(f̂) ∪ struct(J): that of f̂ − J a₂ (step 3)
  std::vector<int> closure_f;         // closure_L(f̂)           (step 1 forward)
  std::vector<int> closure_y;         // closure_L(𝓛 ∩ base)     (backward, steps 1–2)
  std::vector<int> closure_j;         // closure_L(J)            (step 2 forward)
  std::vector<int> closure_step3;     // closure_L(f̂ − J a₂)     (step 3 forward)
  Eigen::VectorXd jv;                 // workspace for J v (size n), zero between uses

  int m() const { return static_cast<int>(l.size()); }

  // jv += J v (dense accumulation; v has one entry per column of J).
  void add_j_times(const Eigen::VectorXd& v) {
    for (int i = 0; i < m(); ++i) {
      const double vi = v(i);
      if (vi == 0) continue;
      if (is_dirichlet[i]) {
        jv(l[i]) += vi;
      } else {
        for (const auto& [row, kv] : *j_cols[i]) jv(row) += kv * vi;
      }
    }
  }
  // jv ← 0 on struct(J), restoring the invariant after add_j_times().
  void clear_jv() {
    for (int i = 0; i < m(); ++i) {
      if (is_dirichlet[i]) {
        jv(l[i]) = 0;
      } else {
        for (const auto& e : *j_cols[i]) jv(e.first) = 0;
      }
    }
  }
};

// Dense LU of an m×m approximation of H R⁻¹ J used as GMRES's right preconditioner: M = H S J
// (§3.5) or the explicit capacitance matrix (SchurSolver::kDirectCached).
struct AugmentedSystem::SchurLu {
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;
  Eigen::VectorXd row_scale, col_scale;  // equilibration (empty: none)
  bool usable = false;  // factored, and its rcond estimate exceeds kMinPreconditionerRcond
  double rcond = std::numeric_limits<double>::quiet_NaN();  // NaN: not factored

  // Factors `s`, equilibrated first when asked (max-norm rows, then columns). A numerically
  // singular matrix (rcond ≤ kMinPreconditionerRcond) is not usable: GMRES then runs
  // unpreconditioned (reported: note()), and its breakdown / stagnation / amplification checks
  // report a singular system.
  void factor(Eigen::MatrixXd s, bool equilibrate) {
    if (equilibrate) {
      row_scale = s.cwiseAbs().rowwise().maxCoeff().cwiseMax(1e-300).cwiseInverse();
      s = row_scale.asDiagonal() * s;
      col_scale = s.cwiseAbs().colwise().maxCoeff().transpose().cwiseMax(1e-300).cwiseInverse();
      s = s * col_scale.asDiagonal();
    }
    lu.compute(s);
    rcond = lu.rcond();
    usable = std::isfinite(rcond) && rcond > kMinPreconditionerRcond;
  }
  // The report's preconditioner fields, once factor() ran.
  void note(AugmentedReport& report) const {
    report.preconditioner_rcond = rcond;
    report.preconditioner_dropped = !usable;
  }
  // out = M⁻¹ v.
  void apply(const Eigen::VectorXd& v, Eigen::VectorXd& out) const {
    if (row_scale.size() == 0) {
      out = lu.solve(v);
    } else {
      out = col_scale.cwiseProduct(lu.solve(row_scale.cwiseProduct(v)));
    }
  }
};

// The augmentation procedure of §3.1, items 1–3: 𝓛 and 𝓓, the columns of J (eq. 5) and f̂
// (eq. 11, with f_d kept at constrained rows: the unknown becomes the reaction), and the
// structures the closures are taken of. Reports (and returns false for) a J column with
// non-finite entries or without stiffness.
bool AugmentedSystem::augment(Augmentation& aug, AugmentedReport& report) {
  const int n = n_;
  const int nb = n_base_;
  aug.l = replaced_columns();
  const int m = aug.m();
  report.m = m;
  report.dirichlet = static_cast<int>(dirichlet_.size());
  pos_in_l_.assign(static_cast<size_t>(n), -1);
  for (int i = 0; i < m; ++i) pos_in_l_[aug.l[i]] = i;
  // Constrained DOFs eliminated in R (eliminate_constrained): row and column K_dd e_d in both R
  // and the current system, so they are not in 𝓛 and their rows leave the columns of J.
  std::vector<char> elim_row;
  for (const auto& kv : dirichlet_) {
    if (!base_->eliminated(kv.first)) continue;
    if (elim_row.empty()) elim_row.assign(static_cast<size_t>(nb), 0);
    elim_row[static_cast<size_t>(kv.first)] = 1;
    aug.eliminated.push_back(kv.first);
  }
  report.dirichlet_eliminated = static_cast<int>(aug.eliminated.size());

  // J columns (eq. 5) as pointers to stored columns; Dirichlet columns are e_{𝓛ᵢ}.
  aug.j_cols.assign(m, nullptr);
  aug.is_dirichlet.assign(m, 0);
  for (int i = 0; i < m; ++i) {
    const int j = aug.l[i];
    if (dirichlet_.count(j) != 0) {
      aug.is_dirichlet[i] = 1;
      continue;
    }
    aug.j_cols[i] = changed_column(j);
    if (!elim_row.empty() && aug.j_cols[i] != nullptr) {
      const Column& c = *aug.j_cols[i];
      const auto is_elim = [&elim_row, nb](const std::pair<int, double>& e) {
        return e.first < nb && elim_row[static_cast<size_t>(e.first)] != 0;
      };
      if (std::any_of(c.begin(), c.end(), is_elim)) {
        Column& mc = aug.masked.emplace_back();
        mc.reserve(c.size());
        for (const auto& e : c)
          if (!is_elim(e)) mc.push_back(e);
        aug.j_cols[i] = &mc;
      }
    }
    bool any = false;
    if (aug.j_cols[i] != nullptr) {
      for (const auto& e : *aug.j_cols[i]) {
        if (!std::isfinite(e.second)) {
          report.status = AugmentedStatus::kNonFinite;
          report.message = "column " + std::to_string(j) + " of K has NaN/Inf entries";
          return false;
        }
        any = any || std::abs(e.second) > 1e-13 * diag_scale_;
      }
    }
    if (!any) {
      report.status = AugmentedStatus::kSingularModifiedSystem;
      report.message = "DOF " + std::to_string(j) +
                       " has no stiffness (empty column of K): attach it to elements, constrain "
                       "it with impose_dirichlet(), or stop using it";
      return false;
    }
  }

  // f̂ = f − Σ_{d∈𝓓} K_{*,d} ā_d (eq. 11), and its structure on the base rows.
  aug.fhat = f_;
  for (const auto& [d, value] : dirichlet_) {
    if (value == 0) continue;
    if (const Column* c = changed_column(d)) {
      for (const auto& [row, v] : *c) aug.fhat(row) -= v * value;
    } else if (d < nb) {
      for (SparseMatrix::InnerIterator it(base_->matrix, d); it; ++it)
        aug.fhat(static_cast<int>(it.row())) -= it.value() * value;
    }
  }
  // Eliminated rows: K_dd a_d = K_dd ā_d (the row of R).
  for (int d : aug.eliminated) aug.fhat(d) = base_->eliminated_diag(d) * dirichlet_.at(d);
  for (int i = 0; i < nb; ++i) {
    if (aug.fhat(i) != 0) {
      aug.f_idx.push_back(i);
      aug.f_val.push_back(aug.fhat(i));
    }
  }
  // Structure of J and of 𝓛 on the base rows, and that of f̂ − J a₂ (step 3).
  std::vector<char> in_j(static_cast<size_t>(nb), 0);
  auto add_row = [&](int row) {
    if (row < nb && !in_j[row]) {
      in_j[row] = 1;
      aug.j_struct.push_back(row);
    }
  };
  for (int i = 0; i < m; ++i) {
    if (aug.is_dirichlet[i]) {
      add_row(aug.l[i]);
    } else {
      for (const auto& e : *aug.j_cols[i]) add_row(e.first);
    }
  }
  std::sort(aug.j_struct.begin(), aug.j_struct.end());
  for (int j : aug.l) {
    if (j < nb) aug.l_base.push_back(j);
  }
  aug.step3_struct = aug.f_idx;
  aug.step3_struct.insert(aug.step3_struct.end(), aug.j_struct.begin(), aug.j_struct.end());
  std::sort(aug.step3_struct.begin(), aug.step3_struct.end());
  aug.step3_struct.erase(std::unique(aug.step3_struct.begin(), aug.step3_struct.end()),
                         aug.step3_struct.end());
  aug.jv = Eigen::VectorXd::Zero(n);
  return true;
}

// Elimination-tree closures of the right-hand sides and wanted sets of steps 1–3 (§3.3,
// Appendix Thm. 1–3); their sizes go into the report (Fig. 4 of the paper).
void AugmentedSystem::find_closures(Augmentation& aug, AugmentedReport& report) {
  ClosureLdlSolver& solver = *base_->solver;
  aug.closure_f = solver.closure(aug.f_idx);
  aug.closure_y = solver.closure(aug.l_base);
  aug.closure_j = solver.closure(aug.j_struct);
  aug.closure_step3 = solver.closure(aug.step3_struct);
  report.closure_f = static_cast<int>(aug.closure_f.size());
  report.closure_y = static_cast<int>(aug.closure_y.size());
  report.closure_ja2 = static_cast<int>(aug.closure_j.size());
  report.closure_step3 = static_cast<int>(aug.closure_step3.size());
}

// M = H S J of §3.5 (m × m), S = D⁻¹ (kDiagonal) or the tridiagonal SPAI of R
// (kTridiagonalSpai); S is the identity on the new DOFs.
Eigen::MatrixXd AugmentedSystem::hsj_matrix(const Augmentation& aug) const {
  const int n = n_;
  const int nb = n_base_;
  const int m = aug.m();
  Eigen::MatrixXd mm = Eigen::MatrixXd::Zero(m, m);
  auto s_entry = [&](int t, int r) -> double {  // S(t, r) for |t − r| ≤ 1
    if (t >= nb || r >= nb) return t == r ? 1.0 : 0.0;
    if (options_.preconditioner == SchurPreconditioner::kDiagonal) {
      return t == r ? base_->s_diag(r) : 0.0;
    }
    if (t == r) return base_->spai_diag(r);
    if (t == r - 1) return base_->spai_upper(t);
    return base_->spai_lower(r);
  };
  for (int k = 0; k < m; ++k) {
    auto visit = [&](int r, double v) {
      for (int t = r - 1; t <= r + 1; ++t) {
        if (t < 0 || t >= n || pos_in_l_[t] < 0) continue;
        const double s = s_entry(t, r);
        if (s != 0) mm(pos_in_l_[t], k) += s * v;
      }
    };
    if (aug.is_dirichlet[k]) {
      visit(aug.l[k], 1.0);
    } else {
      for (const auto& e : *aug.j_cols[k]) visit(e.first, e.second);
    }
  }
  return mm;
}

// H R⁻¹ J in the capacitance form (SchurSolver::kDirectCached). Write J_k = R_{*,𝓛ₖ} + E_k for
// a column that is not Dirichlet (E_k = K_{*,𝓛ₖ} − R_{*,𝓛ₖ}; R_{*,𝓛ₖ} = e_{𝓛ₖ} for a new DOF)
// and J_k = e_{𝓛ₖ} for a Dirichlet column. E_k is nonzero only in rows whose own column
// changed (K and R are symmetric), i.e. in rows of 𝓛, so with G = H R⁻¹ Hᵀ (the 𝓛-block of
// R⁻¹; the identity on new DOFs)
//
//     H R⁻¹ J = Φ + G Ψ,   Φ = diag(1 for non-Dirichlet, 0 for Dirichlet columns),
//                          Ψ_{*k} = H E_k (non-Dirichlet) or e_k (Dirichlet).
//
// This is the capacitance matrix of the Sherman–Morrison–Woodbury form of the update. G depends
// only on the set 𝓛 and the factor, not on the column values, so it is kept between solves:
// a DOF that joins 𝓛 costs one restricted solve y = R⁻¹ e_{𝓛ᵢ} (column i of G, and row i by
// the symmetry of G); changed column values cost nothing but the product G Ψ (O(m·nnz(Ψ))).
// Entries of E in rows outside 𝓛 (possible only if K lost its exact symmetry) are left out:
// the matrix is then an approximation, which as GMRES's preconditioner costs iterations, not
// accuracy.
const Eigen::MatrixXd& AugmentedSystem::capacitance_matrix(const Augmentation& aug, int& solves,
                                                           AugmentedReport& report) {
  const std::vector<int>& l_base = aug.l_base;
  const int m = aug.m();
  const int nb = n_base_;
  const int mb = static_cast<int>(l_base.size());
  ClosureLdlSolver& solver = *base_->solver;
  // G on the base entries of 𝓛 (l_base, sorted): kept entries from the cache, new columns by
  // restricted solves.
  std::vector<int> old(mb, -1);  // position of l_base[i] in the cached list (both sorted)
  if (g_generation_ == base_generation_) {
    size_t q = 0;
    for (int i = 0; i < mb; ++i) {
      while (q < g_l_.size() && g_l_[q] < l_base[i]) ++q;
      if (q < g_l_.size() && g_l_[q] == l_base[i]) old[i] = static_cast<int>(q);
    }
  }
  Eigen::MatrixXd g(mb, mb);
  for (int k = 0; k < mb; ++k) {
    if (old[k] < 0) continue;
    for (int i = 0; i < mb; ++i)
      if (old[i] >= 0) g(i, k) = g_(old[i], old[k]);
  }
  solves = 0;
  const Timer new_columns;
  const double cpu_new_columns0 = thread_cpu_seconds();
  // The new columns R⁻¹e_{𝓛ₖ} in one blocked pass (ClosureLdlSolver::solve_restricted_block).
  std::vector<int> fresh_k, fresh_dofs;
  for (int k = 0; k < mb; ++k) {
    if (old[k] >= 0) continue;
    fresh_k.push_back(k);
    fresh_dofs.push_back(l_base[k]);
  }
  if (!fresh_k.empty()) {
    Eigen::MatrixXd y;
    solver.solve_restricted_block(fresh_dofs, solver.closure(fresh_dofs), aug.closure_y, l_base, y,
                                  options_.blas_kernels);
    solves = static_cast<int>(fresh_k.size());
    for (std::size_t c = 0; c < fresh_k.size(); ++c) {
      const int k = fresh_k[c];
      for (int i = 0; i < mb; ++i) {
        g(i, k) = y(i, static_cast<Eigen::Index>(c));
        if (old[i] >= 0) g(k, i) = y(i, static_cast<Eigen::Index>(c));  // symmetry of G
      }
    }
  }
  g_generation_ = base_generation_;
  g_l_ = l_base;
  g_ = std::move(g);  // the cache is also this solve's G
  report.seconds_new_columns = new_columns.seconds();
  report.cpu_seconds_new_columns = thread_cpu_seconds() - cpu_new_columns0;
  const Timer product;

  // Φ + G Ψ, column by column: for each entry (𝓛 position p, value v) of Ψ_{*k}, add v·G_{*p}.
  // 𝓛 is sorted, so its base DOFs (< n_base) are its first mb entries and G is block diagonal:
  // g on them, the identity on the new DOFs.
  // Ψ_{*k} as (label, value) pairs, in the order the column's entries are summed.
  std::vector<std::vector<std::pair<int, double>>> psi(static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k) {
    const int j = aug.l[k];
    auto& col = psi[static_cast<std::size_t>(k)];
    if (aug.is_dirichlet[k]) continue;  // Ψ_{*k} = e_k (marked by an empty list and the flag)
    // E_k = K_{*j} − R_{*j}: merge the stored column with the base column (both sorted).
    const Column& kc = *aug.j_cols[k];
    auto add_e = [&](int row, double v) {
      if (v != 0 && pos_in_l_[row] >= 0) col.emplace_back(row, v);
    };
    size_t a = 0;
    if (j < nb) {
      const bool j_elim = base_->eliminated(j);  // released: R_{*j} = K_jj e_j
      for (SparseMatrix::InnerIterator it(base_->matrix, j); it; ++it) {
        const int row = static_cast<int>(it.row());
        if (row != j && (j_elim || base_->eliminated(row))) continue;  // not an entry of R
        for (; a < kc.size() && kc[a].first < row; ++a) add_e(kc[a].first, kc[a].second);
        if (a < kc.size() && kc[a].first == row) {
          add_e(row, kc[a].second - it.value());
          ++a;
        } else {
          add_e(row, -it.value());
        }
      }
      for (; a < kc.size(); ++a) add_e(kc[a].first, kc[a].second);
    } else {
      for (const auto& [row, v] : kc) add_e(row, row == j ? v - 1.0 : v);
    }
  }
  // Columns whose Ψ (and Dirichlet flag) are those of the last solve on the same G keep their
  // values on the rows of the labels that were in 𝓛 then; only the new labels' rows are summed.
  // The sums run in the same order as a full recomputation, so the matrix is bitwise the same;
  // a frame then costs O(mb·nnz) for the changed columns only (issue 17).
  std::vector<int> prev(static_cast<std::size_t>(m), -1);  // position in the last solve's 𝓛
  if (product_generation_ == base_generation_) {
    size_t q = 0;
    for (int i = 0; i < m; ++i) {
      while (q < product_l_.size() && product_l_[q] < aug.l[i]) ++q;
      if (q < product_l_.size() && product_l_[q] == aug.l[i]) prev[i] = static_cast<int>(q);
    }
  }
  std::vector<int> fresh_rows;
  for (int i = 0; i < m; ++i)
    if (prev[i] < 0) fresh_rows.push_back(i);
  Eigen::MatrixXd s(m, m);
  auto g_entry = [&](int i, int p) -> double {  // G(i, p) on 𝓛 positions
    if (i < mb && p < mb) return g_(i, p);
    return i == p ? 1.0 : 0.0;
  };
  int kept = 0;
  for (int k = 0; k < m; ++k) {
    const auto& col = psi[static_cast<std::size_t>(k)];
    const int pk = prev[k];
    const bool same = pk >= 0 &&
                      product_dirichlet_[static_cast<std::size_t>(pk)] == aug.is_dirichlet[k] &&
                      product_psi_[static_cast<std::size_t>(pk)] == col;
    if (same) {
      ++kept;
      for (int i = 0; i < m; ++i)
        if (prev[i] >= 0) s(i, k) = product_(prev[i], pk);
      if (aug.is_dirichlet[k]) {
        for (int i : fresh_rows) s(i, k) = g_entry(i, k);
        continue;
      }
      // Σ over the column's entries, in their order, for every new row: the entries outside and
      // the rows inside, so that each entry reads one column of G (the same sums per row).
      for (int i : fresh_rows) s(i, k) = 0;
      for (const auto& [row, e] : col) {
        const int p = pos_in_l_[row];
        if (p < mb) {
          const double* gp = g_.col(p).data();
          for (int i : fresh_rows) s(i, k) += e * (i < mb ? gp[i] : 0.0);
        } else {
          for (int i : fresh_rows) s(i, k) += e * (i == p ? 1.0 : 0.0);
        }
      }
      continue;
    }
    s.col(k).setZero();
    if (aug.is_dirichlet[k]) {
      if (k < mb) {
        s.col(k).head(mb) += g_.col(k);
      } else {
        s(k, k) += 1.0;
      }
      continue;
    }
    s(k, k) += 1.0;
    for (const auto& [row, e] : col) {
      const int p = pos_in_l_[row];
      if (p < mb) {
        s.col(k).head(mb) += e * g_.col(p);
      } else {
        s(p, k) += e;
      }
    }
  }
  report.capacitance_columns_kept = kept;
  product_generation_ = base_generation_;
  product_l_ = aug.l;
  product_psi_ = std::move(psi);
  product_dirichlet_ = aug.is_dirichlet;
  product_ = std::move(s);
  report.seconds_capacitance_product = product.seconds();
  return product_;
}

// Step 1 (§3.2; eqs. 18, 19): rhs = H R⁻¹ f̂, the right-hand side of eq. 17. Forward
// substitution on closure_L(f̂), backward only on closure_L(𝓛); on the new DOFs (identity block
// of R) it is f̂ itself.
Eigen::VectorXd AugmentedSystem::schur_rhs(const Augmentation& aug) {
  const int m = aug.m();
  Eigen::VectorXd rhs(m);
  std::vector<double> y_base;
  base_->solver->solve_restricted(aug.f_idx, aug.f_val, aug.closure_f, aug.closure_y, aug.l_base,
                                  y_base);
  int kb = 0;
  for (int i = 0; i < m; ++i) rhs(i) = aug.l[i] < n_base_ ? y_base[kb++] : aug.fhat(aug.l[i]);
  return rhs;
}

// Step 2 (§3.2; eqs. 17, 20): a₂ from (H R⁻¹ J) a₂ = rhs by GMRES. One operator application
// is J v (sparse), a forward substitution on closure_L(J) and a backward one on closure_L(𝓛).
// Right preconditioner: with SchurSolver::kDirectCached the explicit capacitance matrix (it
// keeps the residual of eq. 17 that of the operator step 3 uses; the capacitance form differs
// from the operator by round-off amplified by κ(R)), else `hsj` when usable (§3.5).
Eigen::VectorXd AugmentedSystem::solve_schur_system(Augmentation& aug, const Eigen::VectorXd& rhs,
                                                    const SchurLu& hsj, AugmentedReport& report) {
  const int m = aug.m();
  const int nb = n_base_;
  ClosureLdlSolver& solver = *base_->solver;
  std::vector<double> jv_val(aug.j_struct.size());
  std::vector<double> yb;  // reused by every operator application (no per-iteration allocation)
  GmresOperator op = [&](const Eigen::VectorXd& v, Eigen::VectorXd& out) {
    aug.add_j_times(v);
    for (size_t k = 0; k < aug.j_struct.size(); ++k) jv_val[k] = aug.jv(aug.j_struct[k]);
    solver.solve_restricted(aug.j_struct, jv_val, aug.closure_j, aug.closure_y, aug.l_base, yb);
    out.resize(m);
    int kb = 0;
    for (int i = 0; i < m; ++i) out(i) = aug.l[i] < nb ? yb[kb++] : aug.jv(aug.l[i]);
    aug.clear_jv();
  };
  GmresOperator prec;
  SchurLu direct;
  if (m > 0 && options_.schur_solver == SchurSolver::kDirectCached) {
    // Rows and columns are in different units (displacement per force, per unit displacement)
    // and span many decades on long meshes: equilibrated, so that the LU's condition estimate
    // measures singularity, not scaling.
    if (options_.update_capacitance) {
      // Updated, not refactored (CapacitanceFactor); fresh for a new factor of R.
      const bool fresh = capacitance_generation_ != base_generation_;
      const Eigen::MatrixXd& s = capacitance_matrix(aug, report.schur_solves, report);
      const Timer factor;
      const double cpu0 = thread_cpu_seconds();
      const CapacitanceUpdate u = capacitance_.update(s, aug.l, fresh);
      report.cpu_seconds_capacitance_factor = thread_cpu_seconds() - cpu0;
      report.seconds_capacitance_factor = factor.seconds();
      capacitance_generation_ = base_generation_;
      report.capacitance_refreshed = u.refreshed;
      report.capacitance_rank = u.changed;
      report.capacitance_needed_rank = u.needed_rank;
      report.capacitance_update_flops = u.update_flops;
      report.capacitance_fresh_flops = u.fresh_flops;
      report.preconditioner_rcond = u.rcond;
      report.preconditioner_dropped =
          !(std::isfinite(u.rcond) && u.rcond > kMinPreconditionerRcond);
      if (!report.preconditioner_dropped) {
        prec = [this](const Eigen::VectorXd& v, Eigen::VectorXd& out) {
          capacitance_.solve(v, out);
        };
      }
    } else {
      const Eigen::MatrixXd& s = capacitance_matrix(aug, report.schur_solves, report);
      const Timer factor;
      const double cpu0 = thread_cpu_seconds();
      direct.factor(s, /*equilibrate=*/true);
      report.cpu_seconds_capacitance_factor = thread_cpu_seconds() - cpu0;
      report.seconds_capacitance_factor = factor.seconds();
      direct.note(report);
      if (direct.usable) {
        prec = [&direct](const Eigen::VectorXd& v, Eigen::VectorXd& out) { direct.apply(v, out); };
      }
    }
  } else if (hsj.usable) {
    prec = [&hsj](const Eigen::VectorXd& v, Eigen::VectorXd& out) { hsj.apply(v, out); };
  }
  Eigen::VectorXd a2 = Eigen::VectorXd::Zero(m);
  if (m > 0) {
    report.gmres = gmres(op, prec, rhs, a2, options_.gmres);
  } else {
    report.gmres.status = GmresStatus::kConverged;
  }
  return a2;
}

// Step 3 (§3.2; eq. 16): a₁ = R⁻¹(f̂ − J a₂), written into `displacement`. f̂ − J a₂ is needed
// only on its structure (base rows: restricted forward substitution, then the full backward
// one) and on the new DOFs, where R is the identity and a₁ is the right-hand side itself.
void AugmentedSystem::back_substitute(Augmentation& aug, const Eigen::VectorXd& a2,
                                      Eigen::VectorXd& displacement) {
  aug.add_j_times(a2);
  const std::vector<int>& s3 = aug.step3_struct;
  std::vector<double> b3_val(s3.size());
  for (size_t k = 0; k < s3.size(); ++k) b3_val[k] = aug.fhat(s3[k]) - aug.jv(s3[k]);
  for (int i = n_base_; i < n_; ++i) displacement(i) = aug.fhat(i) - aug.jv(i);
  aug.clear_jv();
  base_->solver->solve_sparse_rhs(s3, b3_val, aug.closure_step3, displacement.data());
}

// Eqs. 8, 9: a₂ into the displacements (𝓛 ∖ 𝓓) and the reactions (𝓓; the prescribed value
// is the displacement there).
void AugmentedSystem::scatter_schur_solution(const Augmentation& aug, const Eigen::VectorXd& a2,
                                             Eigen::VectorXd& displacement,
                                             Eigen::VectorXd& reaction) const {
  for (int i = 0; i < aug.m(); ++i) {
    const int j = aug.l[i];
    if (aug.is_dirichlet[i]) {
      displacement(j) = dirichlet_.at(j);
      reaction(j) = -a2(i);
    } else {
      displacement(j) = a2(i);
    }
  }
  // Eliminated constrained DOFs: the prescribed value, and the reaction (K a)_d − f_d from the
  // current column of K (symmetric), once every displacement is known.
  for (int d : aug.eliminated) displacement(d) = dirichlet_.at(d);
  for (int d : aug.eliminated) {
    double r = -f_(d);
    if (const Column* c = changed_column(d)) {
      for (const auto& [row, v] : *c) r += v * displacement(row);
    } else {
      for (SparseMatrix::InnerIterator it(base_->matrix, d); it; ++it)
        r += it.value() * displacement(static_cast<int>(it.row()));
    }
    reaction(d) = r;
  }
}

// The report's status from GMRES, then the singularity guard (AugmentedOptions::
// max_amplification) and the finiteness of the outputs; failed outputs are zeroed.
void AugmentedSystem::conclude(const Augmentation& aug, Eigen::VectorXd& displacement,
                               Eigen::VectorXd& reaction, AugmentedReport& report) const {
  switch (report.gmres.status) {
    case GmresStatus::kConverged: report.status = AugmentedStatus::kOk; break;
    case GmresStatus::kMaxIterations:
      report.status = AugmentedStatus::kGmresNotConverged;
      report.message =
          "GMRES reached its iteration cap on eq. 17: raise gmres.max_iterations or the restart "
          "length, use a preconditioner, or refactor (start_refactorization) to reduce m";
      break;
    case GmresStatus::kStagnated:
    case GmresStatus::kBreakdown:
      report.status = AugmentedStatus::kSingularModifiedSystem;
      report.message =
          "the modified stiffness appears singular (GMRES " +
          std::string(to_string(report.gmres.status)) +
          "): a cut may have freed a component or a node lost its support; constrain the free "
          "part (impose_dirichlet) or remove its elements";
      break;
    case GmresStatus::kNonFinite:
      report.status = AugmentedStatus::kNonFinite;
      report.message = "NaN/Inf during GMRES: check element matrices and forces";
      break;
  }
  double abar2 = 0;
  for (const auto& kv : dirichlet_) abar2 += kv.second * kv.second;
  const double denom = aug.fhat.norm() + diag_scale_ * std::sqrt(abar2);
  report.amplification = denom > 0 ? diag_scale_ * displacement.norm() / denom : 0.0;
  report.amplification_warning = report.amplification > options_.warn_amplification;
  if (report.status == AugmentedStatus::kOk &&
      !(report.amplification <= options_.max_amplification)) {
    report.status = AugmentedStatus::kSingularModifiedSystem;
    std::ostringstream os;
    os << "the solution is amplified " << report.amplification
       << "x relative to the load (max_amplification " << options_.max_amplification
       << "): the modified stiffness is numerically singular (a cut may have freed a "
          "component); constrain the free part or remove its elements";
    report.message = os.str();
    displacement.setZero();
    reaction.setZero();
  }
  if (!displacement.allFinite() || !reaction.allFinite()) {
    displacement.setZero();
    reaction.setZero();
    if (report.status == AugmentedStatus::kOk) {
      report.status = AugmentedStatus::kNonFinite;
      report.message = "non-finite solution: check element matrices and forces";
    }
  }
  if (report.status != AugmentedStatus::kOk && report.preconditioner_dropped) {
    std::ostringstream os;
    os << " (GMRES ran unpreconditioned: the preconditioner's LU has rcond "
       << report.preconditioner_rcond << " <= " << kMinPreconditionerRcond << ")";
    report.message += os.str();
  }
}

AugmentedReport AugmentedSystem::solve(Eigen::VectorXd& displacement, Eigen::VectorXd& reaction) {
  Timer total;
  const double cpu_total0 = thread_cpu_seconds();
  AugmentedReport report;
  if (board_) publish_keep();  // prepare_in_job: what the pending job will prepare G for
  if (job_.valid()) {          // §3.6: a finished background factor replaces R first
    const Timer swap;
    report.refactorization_swapped = poll_refactorization();
    report.seconds_swap = swap.seconds();
    if (!job_.valid() && !report.refactorization_swapped) {
      report.refactorization_status = last_refactor_status_;
    }
  }
  displacement = Eigen::VectorXd::Zero(n_);
  reaction = Eigen::VectorXd::Zero(n_);
  report.n = n_;
  if (!base_ || base_->status != FactorStatus::kOk) {
    report.status = AugmentedStatus::kNoFactor;
    report.message = "initialize() with a positive definite K0 first";
    if (base_) report.message += " (last factorization: " + base_->message + ")";
    return report;
  }
  if (!f_.allFinite()) {
    report.status = AugmentedStatus::kNonFinite;
    report.message = "the force vector has NaN/Inf entries";
    return report;
  }
  if (options_.prune_unchanged_columns) report.pruned_columns = prune_unchanged_columns();

  // Setup: 𝓛, J, H, f̂ (§3.1), closures (§3.3), the preconditioner M = H S J (§3.5).
  Timer phase;
  report.nnz_l = base_->ldl->nnz_l();
  Augmentation aug;
  if (!augment(aug, report)) return report;
  find_closures(aug, report);
  SchurLu hsj;
  if (options_.preconditioner != SchurPreconditioner::kNone && aug.m() > 0 &&
      options_.schur_solver == SchurSolver::kGmres) {
    hsj.factor(hsj_matrix(aug), /*equilibrate=*/false);
    hsj.note(report);
  }
  report.seconds_setup = phase.seconds();

  phase.restart();
  const Eigen::VectorXd rhs = schur_rhs(aug);
  report.seconds_step1 = phase.seconds();

  phase.restart();
  const Eigen::VectorXd a2 = solve_schur_system(aug, rhs, hsj, report);
  report.seconds_step2 = phase.seconds();

  phase.restart();
  back_substitute(aug, a2, displacement);
  report.seconds_step3 = phase.seconds();

  scatter_schur_solution(aug, a2, displacement, reaction);
  conclude(aug, displacement, reaction, report);
  report.seconds_total = total.seconds();
  report.cpu_seconds_total = thread_cpu_seconds() - cpu_total0;
  return report;
}

}  // namespace incise::linalg
