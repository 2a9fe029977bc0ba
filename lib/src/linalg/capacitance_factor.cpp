#include <incise/core/error.hpp>
#include <incise/linalg/capacitance_factor.hpp>

#include <algorithm>
#include <cmath>

namespace incise::linalg {
namespace {

bool strictly_increasing(const std::vector<int>& v) {
  for (std::size_t i = 1; i < v.size(); ++i)
    if (v[i] <= v[i - 1]) return false;
  return true;
}

}  // namespace

CapacitanceFactor::CapacitanceFactor(double refresh_ratio, bool use_blas)
    : refresh_ratio_(refresh_ratio), use_blas_(use_blas), lu0_(use_blas), k_lu_(use_blas) {
  INCISE_CHECK_PARAM(refresh_ratio > 0, "CapacitanceFactor: refresh_ratio must be > 0");
}

void CapacitanceFactor::clear() {
  ref_labels_.clear();
  union_.clear();
  ref_pos_.clear();
  cur_pos_.clear();
  scale_.clear();
  w_cache_.clear();
  s0_.resize(0, 0);
  w_.resize(0, 0);
  vt_.resize(0, 0);
}

void CapacitanceFactor::fresh(const Eigen::MatrixXd& s, const std::vector<int>& labels) {
  const auto m = static_cast<Eigen::Index>(labels.size());
  // Equilibration (max-norm rows, then columns), as the per-solve LU it replaces.
  row_scale_ = s.cwiseAbs().rowwise().maxCoeff().cwiseMax(1e-300).cwiseInverse();
  s0_ = row_scale_.asDiagonal() * s;
  col_scale_ = s0_.cwiseAbs().colwise().maxCoeff().transpose().cwiseMax(1e-300).cwiseInverse();
  s0_ = s0_ * col_scale_.asDiagonal();
  lu0_.compute(s0_);
  ref_labels_ = labels;
  scale_.clear();
  for (Eigen::Index i = 0; i < m; ++i)
    scale_[labels[static_cast<std::size_t>(i)]] = {row_scale_(i), col_scale_(i)};
  union_ = labels;
  ref_pos_.resize(labels.size());
  cur_pos_.resize(labels.size());
  for (std::size_t i = 0; i < labels.size(); ++i) ref_pos_[i] = cur_pos_[i] = static_cast<int>(i);
  w_cache_.clear();
  w_.resize(m, 0);
  vt_.resize(0, m);
  ++fresh_count_;
}

Eigen::VectorXd CapacitanceFactor::solve0(const Eigen::VectorXd& b) const {
  Eigen::VectorXd x = b;  // identity on 𝓤 ∖ 𝓛₀
  Eigen::VectorXd r(static_cast<Eigen::Index>(ref_labels_.size()));
  for (std::size_t u = 0; u < union_.size(); ++u)
    if (ref_pos_[u] >= 0) r(ref_pos_[u]) = b(static_cast<Eigen::Index>(u));
  if (r.size() > 0) r = lu0_.solve(r);
  for (std::size_t u = 0; u < union_.size(); ++u)
    if (ref_pos_[u] >= 0) x(static_cast<Eigen::Index>(u)) = r(ref_pos_[u]);
  return x;
}

Eigen::VectorXd CapacitanceFactor::solve0_transposed(const Eigen::VectorXd& b) const {
  Eigen::VectorXd x = b;
  Eigen::VectorXd r(static_cast<Eigen::Index>(ref_labels_.size()));
  for (std::size_t u = 0; u < union_.size(); ++u)
    if (ref_pos_[u] >= 0) r(ref_pos_[u]) = b(static_cast<Eigen::Index>(u));
  if (r.size() > 0) r = lu0_.solve(r, /*transposed=*/true);
  for (std::size_t u = 0; u < union_.size(); ++u)
    if (ref_pos_[u] >= 0) x(static_cast<Eigen::Index>(u)) = r(ref_pos_[u]);
  return x;
}

// Ŝ⁻¹ b = Ŝ₀⁻¹ b − W K⁻¹ Vᵀ Ŝ₀⁻¹ b (Sherman–Morrison–Woodbury).
Eigen::VectorXd CapacitanceFactor::apply_inverse(const Eigen::VectorXd& b) const {
  Eigen::VectorXd y = solve0(b);
  if (w_.cols() > 0) y -= w_ * k_lu_.solve(Eigen::VectorXd(vt_ * y));
  return y;
}

// Ŝ⁻ᵀ b = Ŝ₀⁻ᵀ (b − V K⁻ᵀ Wᵀ b): the transpose of the expression above.
Eigen::VectorXd CapacitanceFactor::apply_inverse_transposed(const Eigen::VectorXd& b) const {
  if (w_.cols() == 0) return solve0_transposed(b);
  const Eigen::VectorXd z = k_lu_.solve(Eigen::VectorXd(w_.transpose() * b), /*transposed=*/true);
  return solve0_transposed(b - vt_.transpose() * z);
}

// Hager's estimator of ‖Ŝ⁻¹‖₁ (Higham 2002, Alg. 15.4, at most 5 iterations), times ‖Ŝ‖₁.
double CapacitanceFactor::estimate_rcond(const Eigen::MatrixXd& shat) const {
  const Eigen::Index n = shat.rows();
  if (n == 0) return 1.0;
  const double norm1 = shat.cwiseAbs().colwise().sum().maxCoeff();
  Eigen::VectorXd x = Eigen::VectorXd::Constant(n, 1.0 / static_cast<double>(n));
  double estimate = 0;
  for (int it = 0; it < 5; ++it) {
    const Eigen::VectorXd y = apply_inverse(x);
    if (!y.allFinite()) return 0.0;
    estimate = y.lpNorm<1>();
    const Eigen::VectorXd xi = y.unaryExpr([](double v) { return v >= 0 ? 1.0 : -1.0; });
    const Eigen::VectorXd z = apply_inverse_transposed(xi);
    Eigen::Index j = 0;
    const double zmax = z.cwiseAbs().maxCoeff(&j);
    if (it > 0 && zmax <= z.dot(x)) break;
    x.setZero();
    x(j) = 1.0;
  }
  if (!(estimate > 0) || !(norm1 > 0)) return 0.0;
  return 1.0 / (norm1 * estimate);
}

CapacitanceUpdate CapacitanceFactor::update(const Eigen::MatrixXd& s,
                                            const std::vector<int>& labels, bool force_fresh) {
  const auto m = static_cast<Eigen::Index>(labels.size());
  INCISE_CHECK(s.rows() == m && s.cols() == m,
               "CapacitanceFactor::update: the matrix must be square with one row per label");
  INCISE_CHECK(strictly_increasing(labels),
               "CapacitanceFactor::update: labels must be strictly increasing");
  CapacitanceUpdate out;
  auto fresh_report = [&]() {
    fresh(s, labels);
    out.refreshed = true;
    Eigen::MatrixXd shat = row_scale_.asDiagonal() * s * col_scale_.asDiagonal();
    out.rcond = estimate_rcond(shat);
    return out;
  };
  if (force_fresh || fresh_count_ == 0) return fresh_report();

  // 𝓤 = 𝓛₀ ∪ 𝓛 and the positions of both in it.
  std::vector<int> uni;
  uni.reserve(ref_labels_.size() + labels.size());
  std::set_union(ref_labels_.begin(), ref_labels_.end(), labels.begin(), labels.end(),
                 std::back_inserter(uni));
  const auto nu = static_cast<Eigen::Index>(uni.size());
  std::vector<int> ref_pos(uni.size(), -1), cur_of_union(uni.size(), -1), cur_pos(labels.size());
  for (std::size_t u = 0, r = 0, c = 0; u < uni.size(); ++u) {
    if (r < ref_labels_.size() && ref_labels_[r] == uni[u]) ref_pos[u] = static_cast<int>(r++);
    if (c < labels.size() && labels[c] == uni[u]) {
      cur_of_union[u] = static_cast<int>(c);
      cur_pos[c++] = static_cast<int>(u);
    }
  }
  // Scales: kept per label; a label new since the fresh factorization gets its own from S
  // (row max, then column max of the row-scaled column).
  Eigen::VectorXd rs(m), cs(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto it = scale_.find(labels[static_cast<std::size_t>(i)]);
    rs(i) = it != scale_.end() ? it->second.first
                               : 1.0 / std::max(1e-300, s.row(i).cwiseAbs().maxCoeff());
  }
  for (Eigen::Index j = 0; j < m; ++j) {
    const auto it = scale_.find(labels[static_cast<std::size_t>(j)]);
    cs(j) = it != scale_.end()
                ? it->second.second
                : 1.0 / std::max(1e-300, rs.cwiseProduct(s.col(j).cwiseAbs()).maxCoeff());
  }
  // Ŝ on 𝓤 (identity off 𝓛) and D = Ŝ − Ŝ₀ (Ŝ₀: identity off 𝓛₀).
  Eigen::MatrixXd shat = Eigen::MatrixXd::Identity(nu, nu);
  for (Eigen::Index j = 0; j < m; ++j)
    for (Eigen::Index i = 0; i < m; ++i)
      shat(cur_pos[static_cast<std::size_t>(i)], cur_pos[static_cast<std::size_t>(j)]) =
          rs(i) * s(i, j) * cs(j);
  Eigen::MatrixXd d = shat;
  for (Eigen::Index v = 0; v < nu; ++v)
    for (Eigen::Index u = 0; u < nu; ++u) {
      const int ru = ref_pos[static_cast<std::size_t>(u)],
                rv = ref_pos[static_cast<std::size_t>(v)];
      if (ru >= 0 && rv >= 0) {
        d(u, v) -= s0_(ru, rv);
      } else if (u == v) {
        d(u, v) -= 1.0;
      }
    }
  // The cover of D's nonzeros by columns 𝓠 and rows 𝓡: labels that joined or left since the
  // fresh factorization in both; the other nonzeros by columns or by rows, whichever are fewer
  // (a changed column value changes one column; a label joining adds a row and a column).
  std::vector<char> in_q(static_cast<std::size_t>(nu), 0), in_r(static_cast<std::size_t>(nu), 0);
  for (Eigen::Index u = 0; u < nu; ++u)
    if ((ref_pos[static_cast<std::size_t>(u)] >= 0) !=
        (cur_of_union[static_cast<std::size_t>(u)] >= 0))
      in_q[static_cast<std::size_t>(u)] = in_r[static_cast<std::size_t>(u)] = 1;
  std::vector<char> col_nz(static_cast<std::size_t>(nu), 0),
      row_nz(static_cast<std::size_t>(nu), 0);
  for (Eigen::Index v = 0; v < nu; ++v) {
    if (in_q[static_cast<std::size_t>(v)]) continue;
    for (Eigen::Index u = 0; u < nu; ++u)
      if (!in_r[static_cast<std::size_t>(u)] && d(u, v) != 0)
        col_nz[static_cast<std::size_t>(v)] = row_nz[static_cast<std::size_t>(u)] = 1;
  }
  const auto ncols = std::count(col_nz.begin(), col_nz.end(), 1);
  const auto nrows = std::count(row_nz.begin(), row_nz.end(), 1);
  for (Eigen::Index u = 0; u < nu; ++u) {
    if (ncols <= nrows && col_nz[static_cast<std::size_t>(u)])
      in_q[static_cast<std::size_t>(u)] = 1;
    if (ncols > nrows && row_nz[static_cast<std::size_t>(u)]) in_r[static_cast<std::size_t>(u)] = 1;
  }
  std::vector<int> qcols, rrows;
  for (Eigen::Index u = 0; u < nu; ++u) {
    if (in_q[static_cast<std::size_t>(u)]) qcols.push_back(static_cast<int>(u));
    if (in_r[static_cast<std::size_t>(u)]) rrows.push_back(static_cast<int>(u));
  }
  const auto nq = static_cast<Eigen::Index>(qcols.size()),
             nr = static_cast<Eigen::Index>(rrows.size());
  const Eigen::Index rank = nq + nr;
  const auto m0 = static_cast<Eigen::Index>(ref_labels_.size());

  // The 𝓛₀ part of each D column of 𝓠, and how many LU solves with S₀ miss the cache.
  std::vector<Eigen::VectorXd> parts(qcols.size());
  int misses = 0;
  for (std::size_t t = 0; t < qcols.size(); ++t) {
    parts[t].resize(m0);
    for (Eigen::Index q = 0; q < nu; ++q)
      if (ref_pos[static_cast<std::size_t>(q)] >= 0)
        parts[t](ref_pos[static_cast<std::size_t>(q)]) = d(q, qcols[t]);
    const auto it = w_cache_.find(uni[static_cast<std::size_t>(qcols[t])]);
    if (it == w_cache_.end() || it->second.first != parts[t]) ++misses;
  }
  for (int u : rrows)  // Ŝ₀⁻¹ e_u, cached under −1 − label
    if (ref_pos[static_cast<std::size_t>(u)] >= 0 &&
        w_cache_.count(-1 - uni[static_cast<std::size_t>(u)]) == 0)
      ++misses;
  // Cost rule (flops): the update's LU solves, VᵀW and K's LU against a fresh ⅔m³ LU.
  const double mm = static_cast<double>(m), dm0 = static_cast<double>(m0);
  const double k2 = static_cast<double>(rank);
  const double update_flops = 2.0 * dm0 * dm0 * misses + 2.0 * static_cast<double>(nu) * k2 * k2 +
                              (2.0 / 3.0) * k2 * k2 * k2;
  const double fresh_flops = (2.0 / 3.0) * mm * mm * mm;
  out.needed_rank = static_cast<int>(rank);
  out.update_flops = update_flops;
  out.fresh_flops = fresh_flops;
  if (update_flops > refresh_ratio_ * fresh_flops) return fresh_report();

  // U = [D_{*,𝓠}, E_𝓡], W = Ŝ₀⁻¹ U (columns cached by label), Vᵀ = [E_𝓠ᵀ; D̃_{𝓡,*}].
  // The cache misses are solved together: one LU solve with many right-hand sides (BLAS-3,
  // dense_blas.hpp) instead of one triangular pair per column.
  {
    std::vector<Eigen::Index> miss_q;  // t of the 𝓠 columns whose D column changed
    std::vector<int> miss_r;           // union positions of the 𝓡 rows without Ŝ₀⁻¹ e_u
    for (Eigen::Index t = 0; t < nq; ++t) {
      const auto it =
          w_cache_.find(uni[static_cast<std::size_t>(qcols[static_cast<std::size_t>(t)])]);
      if (it == w_cache_.end() || it->second.first != parts[static_cast<std::size_t>(t)])
        miss_q.push_back(t);
    }
    for (int u : rrows)
      if (ref_pos[static_cast<std::size_t>(u)] >= 0 &&
          w_cache_.count(-1 - uni[static_cast<std::size_t>(u)]) == 0)
        miss_r.push_back(u);
    const auto nmq = static_cast<Eigen::Index>(miss_q.size());
    Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m0, nmq + static_cast<Eigen::Index>(miss_r.size()));
    for (Eigen::Index c = 0; c < nmq; ++c)
      rhs.col(c) = parts[static_cast<std::size_t>(miss_q[static_cast<std::size_t>(c)])];
    for (std::size_t c = 0; c < miss_r.size(); ++c)
      rhs(ref_pos[static_cast<std::size_t>(miss_r[c])], nmq + static_cast<Eigen::Index>(c)) = 1.0;
    if (m0 > 0) lu0_.solve_in_place(rhs);
    for (Eigen::Index c = 0; c < nmq; ++c) {
      const auto t = static_cast<std::size_t>(miss_q[static_cast<std::size_t>(c)]);
      w_cache_.insert_or_assign(
          uni[static_cast<std::size_t>(qcols[t])],
          std::make_pair(parts[t], m0 > 0 ? Eigen::VectorXd(rhs.col(c)) : Eigen::VectorXd()));
    }
    for (std::size_t c = 0; c < miss_r.size(); ++c)
      w_cache_.insert_or_assign(
          -1 - uni[static_cast<std::size_t>(miss_r[c])],
          std::make_pair(Eigen::VectorXd(),
                         Eigen::VectorXd(rhs.col(nmq + static_cast<Eigen::Index>(c)))));
    out.new_solves = static_cast<int>(rhs.cols());
  }
  w_.resize(nu, rank);
  vt_ = Eigen::MatrixXd::Zero(rank, nu);
  for (Eigen::Index t = 0; t < nq; ++t) {
    const int u = qcols[static_cast<std::size_t>(t)];
    const auto& sol = w_cache_.at(uni[static_cast<std::size_t>(u)]).second;
    for (Eigen::Index q = 0; q < nu; ++q) {
      const int rq = ref_pos[static_cast<std::size_t>(q)];
      w_(q, t) = rq >= 0 ? sol(rq) : d(q, u);  // identity off 𝓛₀
    }
    vt_(t, u) = 1.0;
  }
  for (Eigen::Index t = 0; t < nr; ++t) {
    const int u = rrows[static_cast<std::size_t>(t)];
    w_.col(nq + t).setZero();
    if (ref_pos[static_cast<std::size_t>(u)] >= 0) {  // the 𝓛₀ column of S₀⁻¹
      const auto& sol = w_cache_.at(-1 - uni[static_cast<std::size_t>(u)]).second;
      for (Eigen::Index q = 0; q < nu; ++q) {
        const int rq = ref_pos[static_cast<std::size_t>(q)];
        if (rq >= 0) w_(q, nq + t) = sol(rq);
      }
    } else {
      w_(u, nq + t) = 1.0;
    }
    vt_.row(nq + t) = d.row(u);
    for (int qc : qcols) vt_(nq + t, qc) = 0.0;  // D̃: the 𝓠 columns are in D_{*,𝓠} E_𝓠ᵀ
  }
  // K = I + Vᵀ W: the 𝓠 rows of Vᵀ are unit rows (rows of W); the 𝓡 rows one product.
  const Eigen::Index c = rank;
  Eigen::MatrixXd k(c, c);
  for (Eigen::Index t = 0; t < nq; ++t) k.row(t) = w_.row(qcols[static_cast<std::size_t>(t)]);
  if (use_blas_) {
    dense_gemm(false, false, static_cast<int>(nr), static_cast<int>(c), static_cast<int>(nu), 1.0,
               vt_.data() + nq, static_cast<int>(c), w_.data(), static_cast<int>(nu), 0.0,
               k.data() + nq, static_cast<int>(c));
  } else {
    k.bottomRows(nr).noalias() = vt_.bottomRows(nr) * w_;
  }
  k.diagonal().array() += 1.0;
  k_lu_.compute(k);
  union_ = std::move(uni);
  ref_pos_ = std::move(ref_pos);
  cur_pos_ = std::move(cur_pos);
  row_scale_ = rs;
  col_scale_ = cs;
  out.changed = static_cast<int>(c);  // rank of the correction
  out.rcond = estimate_rcond(shat);
  return out;
}

void CapacitanceFactor::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
  const auto m = static_cast<Eigen::Index>(cur_pos_.size());
  INCISE_CHECK(b.size() == m, "CapacitanceFactor::solve: one entry per label");
  Eigen::VectorXd bb = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(union_.size()));
  for (Eigen::Index i = 0; i < m; ++i)
    bb(cur_pos_[static_cast<std::size_t>(i)]) = row_scale_(i) * b(i);
  const Eigen::VectorXd y = apply_inverse(bb);
  x.resize(m);
  for (Eigen::Index i = 0; i < m; ++i)
    x(i) = col_scale_(i) * y(cur_pos_[static_cast<std::size_t>(i)]);
}

}  // namespace incise::linalg
