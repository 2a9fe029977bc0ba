#pragma once
/// \file test_problems.hpp
/// Synthetic incise::Problem implementations for the solver tests (test scaffolding: lives in
/// the test folder, never in lib/). Each counts its own flops honestly (dense matvec 2n², etc.).

#include <incise/core/problem.hpp>

#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace incise::test {

/// Π(x) = ½ xᵀA x − bᵀx with a dense symmetric A (SPD or deliberately indefinite), some fixed
/// DOFs, and positive lumped masses. gradient = A x − b.
class QuadraticProblem : public Problem {
 public:
  QuadraticProblem(Eigen::MatrixXd a, VecX b, std::vector<bool> fixed, VecX mass)
      : a_(std::move(a)), b_(std::move(b)), fixed_(std::move(fixed)), mass_(std::move(mass)) {}

  Eigen::Index size() const override { return b_.size(); }
  EvalStatus energy(const VecX& u, double& e) override {
    e = 0.5 * u.dot(a_ * u) - b_.dot(u);
    flops_ += 2 * n2() + 4 * n();
    return EvalStatus::kOk;
  }
  EvalStatus gradient(const VecX& u, VecX& g, double* e) override {
    g = a_ * u - b_;
    flops_ += 2 * n2() + n();
    if (e) {
      *e = 0.5 * u.dot(g - b_);  // ½uᵀAu − bᵀu = ½uᵀ(Au − b) − ½bᵀu
      flops_ += 3 * n();
    }
    return EvalStatus::kOk;
  }
  EvalStatus hessian_product(const VecX&, const VecX& d, VecX& out) override {
    out = a_ * d;
    flops_ += 2 * n2();
    return EvalStatus::kOk;
  }
  bool hessian_diagonal(const VecX&, VecX& diag) override {
    diag = a_.diagonal();
    return true;
  }
  void project(VecX& v) const override {
    for (Eigen::Index i = 0; i < v.size(); ++i)
      if (fixed_[i]) v[i] = 0.0;
  }
  bool is_fixed(Eigen::Index i) const override { return fixed_[i]; }
  double external_force_norm() const override {
    VecX f = b_;
    project(f);
    return f.norm();
  }
  const VecX& lumped_mass() const override { return mass_; }
  std::uint64_t flops() const override { return flops_; }

  const Eigen::MatrixXd& matrix() const { return a_; }
  const VecX& rhs() const { return b_; }
  /// Indices of the free DOFs.
  std::vector<int> free_dofs() const {
    std::vector<int> f;
    for (int i = 0; i < int(fixed_.size()); ++i)
      if (!fixed_[i]) f.push_back(i);
    return f;
  }
  /// Exact minimizer over free DOFs with fixed DOFs at 0 (dense LDLT of the free block).
  VecX direct_solution() const {
    const std::vector<int> f = free_dofs();
    const int m = int(f.size());
    Eigen::MatrixXd af(m, m);
    VecX bf(m);
    for (int i = 0; i < m; ++i) {
      bf[i] = b_[f[i]];
      for (int j = 0; j < m; ++j) af(i, j) = a_(f[i], f[j]);
    }
    const VecX xf = af.ldlt().solve(bf);
    VecX x = VecX::Zero(size());
    for (int i = 0; i < m; ++i) x[f[i]] = xf[i];
    return x;
  }

 private:
  std::uint64_t n() const { return std::uint64_t(b_.size()); }
  std::uint64_t n2() const { return n() * n(); }
  Eigen::MatrixXd a_;
  VecX b_;
  std::vector<bool> fixed_;
  VecX mass_;
  std::uint64_t flops_ = 0;
};

/// Random SPD quadratic problem of size n with condition number about `cond`, `nfix` fixed DOFs
/// (the first ones), random load and random masses in [0.5, 2].
inline QuadraticProblem random_spd_problem(std::mt19937_64& rng, int n, double cond, int nfix) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> unif(0.0, 1.0);
  Eigen::MatrixXd g(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) g(i, j) = normal(rng);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(g);
  const Eigen::MatrixXd q = qr.householderQ();
  VecX lam(n);
  for (int i = 0; i < n; ++i) lam[i] = std::pow(cond, double(i) / (n - 1));
  const Eigen::MatrixXd a = q * lam.asDiagonal() * q.transpose();
  VecX b(n), m(n);
  for (int i = 0; i < n; ++i) {
    b[i] = normal(rng);
    m[i] = 0.5 + 1.5 * unif(rng);
  }
  std::vector<bool> fixed(n, false);
  for (int i = 0; i < nfix; ++i) fixed[i] = true;
  return QuadraticProblem(0.5 * (a + a.transpose()), b, fixed, m);
}

/// `p` with DOF k decoupled and without stiffness or load: row and column k of A and b_k zeroed
/// (a node no element uses). Free, it makes K singular; fixed, it is projected out.
inline QuadraticProblem without_stiffness_at(const QuadraticProblem& p, int k, bool fixed) {
  Eigen::MatrixXd a = p.matrix();
  a.row(k).setZero();
  a.col(k).setZero();
  VecX b = p.rhs();
  b[k] = 0.0;
  std::vector<bool> f(static_cast<std::size_t>(p.size()));
  for (int i = 0; i < int(f.size()); ++i) f[i] = p.is_fixed(i);
  f[k] = fixed;
  return QuadraticProblem(a, b, f, p.lumped_mass());
}

/// A QuadraticProblem whose hessian_diagonal() returns `diagonal` instead of diag A, or false
/// when `diagonal` is empty (a problem without a diagonal); every other evaluation is A's.
class DiagonalOverride : public QuadraticProblem {
 public:
  DiagonalOverride(const QuadraticProblem& p, VecX diagonal)
      : QuadraticProblem(p), diagonal_(std::move(diagonal)) {}
  bool hessian_diagonal(const VecX&, VecX& diag) override {
    if (diagonal_.size() == 0) return false;
    diag = diagonal_;
    return true;
  }

 private:
  VecX diagonal_;
};

/// A 1-D chain of n+1 nodes (node 0 clamped) joined by springs of rest length L with a
/// stiffening, inversion-resisting energy per spring of stretch s = 1 + (u_{i+1} − u_i)/L:
///   W(s) = k L [ (s−1)²/2 + c (s−1)⁴/4 + µ (s − 1 − ln s) ],   W = +∞ for s ≤ 0,
/// strictly convex on s > 0 (W″ = kL⁻¹[1 + 3c(s−1)² + µ/s²] in u). Load f_i on every free node.
/// Π(u) = Σ W − fᵀu. A large compressive load drives trial steps into s ≤ 0 (kInverted).
class SpringChain : public Problem {
 public:
  SpringChain(int n, double k, double c, double mu, double rest, VecX load)
      : n_(n), k_(k), c_(c), mu_(mu), l_(rest), f_(std::move(load)), mass_(VecX::Ones(n + 1)) {
    f_[0] = 0.0;
  }
  Eigen::Index size() const override { return n_ + 1; }
  EvalStatus energy(const VecX& u, double& e) override { return gradient_impl(u, nullptr, &e); }
  EvalStatus gradient(const VecX& u, VecX& g, double* e) override {
    double tmp = 0.0;
    return gradient_impl(u, &g, e ? e : &tmp);
  }
  EvalStatus hessian_product(const VecX& u, const VecX& d, VecX& out) override {
    out.setZero(size());
    for (int i = 0; i < n_; ++i) {
      const double s = 1.0 + (u[i + 1] - u[i]) / l_;
      if (!(s > 0.0)) return EvalStatus::kInverted;
      const double h = k_ / l_ * (1.0 + 3.0 * c_ * (s - 1) * (s - 1) + mu_ / (s * s));
      const double dd = h * (d[i + 1] - d[i]);
      out[i] -= dd;
      out[i + 1] += dd;
    }
    flops_ += 16 * std::uint64_t(n_);
    return EvalStatus::kOk;
  }
  bool hessian_diagonal(const VecX& u, VecX& diag) override {
    diag.setZero(size());
    for (int i = 0; i < n_; ++i) {
      const double s = 1.0 + (u[i + 1] - u[i]) / l_;
      if (!(s > 0.0)) return false;
      const double h = k_ / l_ * (1.0 + 3.0 * c_ * (s - 1) * (s - 1) + mu_ / (s * s));
      diag[i] += h;
      diag[i + 1] += h;
    }
    return true;
  }
  void project(VecX& v) const override { v[0] = 0.0; }
  bool is_fixed(Eigen::Index i) const override { return i == 0; }
  double external_force_norm() const override { return f_.norm(); }
  const VecX& lumped_mass() const override { return mass_; }
  std::uint64_t flops() const override { return flops_; }

 private:
  EvalStatus gradient_impl(const VecX& u, VecX* g, double* e) {
    double energy = 0.0;
    if (g) *g = -f_;
    for (int i = 0; i < n_; ++i) {
      const double s = 1.0 + (u[i + 1] - u[i]) / l_;
      if (!(s > 0.0)) {
        *e = std::numeric_limits<double>::infinity();
        return EvalStatus::kInverted;
      }
      const double x = s - 1.0;
      energy += k_ * l_ * (0.5 * x * x + 0.25 * c_ * x * x * x * x + mu_ * (x - std::log(s)));
      if (g) {
        const double w1 = k_ * (x + c_ * x * x * x + mu_ * (1.0 - 1.0 / s));  // dW/du_{i+1}
        (*g)[i] -= w1;
        (*g)[i + 1] += w1;
      }
    }
    energy -= f_.dot(u);
    flops_ += 30 * std::uint64_t(n_);
    *e = energy;
    return std::isfinite(energy) ? EvalStatus::kOk : EvalStatus::kNonFinite;
  }
  int n_;
  double k_, c_, mu_, l_;
  VecX f_;
  VecX mass_;
  std::uint64_t flops_ = 0;
};

}  // namespace incise::test
