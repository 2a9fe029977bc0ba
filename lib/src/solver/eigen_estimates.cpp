#include <incise/solver/eigen_estimates.hpp>

#include <Eigen/Eigenvalues>
#include <incise/solver/linear_cg.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace incise::solver {
namespace {

const VecX& checked_mass(const Problem& problem) {
  const VecX& m = problem.lumped_mass();
  INCISE_CHECK(m.size() == problem.size(), "eigenvalue estimate needs Problem::lumped_mass()");
  INCISE_CHECK((m.array() > 0.0).all(), "lumped masses must be positive");
  return m;
}

VecX start_vector(const Problem& problem, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> dist(-1.0, 1.0);
  VecX x(problem.size());
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = dist(rng);
  problem.project(x);
  return x;
}

}  // namespace

EigenEstimate largest_eigenvalue(Problem& problem, const VecX& u, const EigenOptions& options) {
  const VecX& m = checked_mass(problem);
  CostMeter meter(problem);
  const auto nn = static_cast<std::uint64_t>(u.size());
  EigenEstimate est;
  VecX x = start_vector(problem, options.seed);
  x /= std::sqrt(x.dot(m.cwiseProduct(x)));
  VecX kx;
  double rho_prev = 0.0;
  for (long k = 0; k < options.max_iterations; ++k) {
    const EvalStatus st = problem.hessian_product(u, x, kx);
    if (st != EvalStatus::kOk || !kx.allFinite()) {
      est.status = failure_reason(st);
      break;
    }
    problem.project(kx);
    const double rho = x.dot(kx);  // x is M-normalized
    est.iterations = k + 1;
    if (!std::isfinite(rho)) {
      est.status = StopReason::kNonFinite;
      break;
    }
    if (rho <= 0.0) {
      est.status = StopReason::kIndefinite;
      break;
    }
    est.value = rho;
    est.relative_change = std::abs(rho - rho_prev) / rho;
    x = kx.cwiseQuotient(m);  // M⁻¹ K x
    const double mnorm = std::sqrt(x.dot(m.cwiseProduct(x)));
    meter.add(8 * nn);
    if (!(mnorm > 0.0) || !std::isfinite(mnorm)) {
      est.status = StopReason::kNonFinite;
      break;
    }
    x /= mnorm;
    if (k > 0 && est.relative_change <= options.tolerance) {
      est.status = StopReason::kConverged;
      break;
    }
    rho_prev = rho;
  }
  est.flops = meter.flops();
  return est;
}

EigenEstimate smallest_eigenvalue(Problem& problem, const VecX& u, const EigenOptions& options) {
  const VecX& m = checked_mass(problem);
  CostMeter meter(problem);
  const auto nn = static_cast<std::uint64_t>(u.size());
  EigenEstimate est;
  VecX x = start_vector(problem, options.seed);
  x /= std::sqrt(x.dot(m.cwiseProduct(x)));
  VecX y, kx, b;
  // Jacobi-preconditioned inner CG when the problem has a diagonal; a diagonal that shows K is
  // not positive definite (or not finite) ends the estimate: λ₁ ≤ 0 has no critical damping.
  JacobiDiagonal jd = jacobi_inverse_diagonal(problem, u);
  if (!jd.ok() && jd.status != StopReason::kPreconditionerUnavailable) {
    est.status = jd.status;
    est.message = std::move(jd.message);
    est.flops = meter.flops();
    return est;
  }
  const VecX inv_diag = std::move(jd.inverse);
  const LinearOperator apply = [&](const VecX& in, VecX& out) {
    return problem.hessian_product(u, in, out);
  };
  double rho_prev = 0.0;
  for (long k = 0; k < options.max_iterations; ++k) {
    b = m.cwiseProduct(x);
    const InnerCgResult inner =
        projected_cg(apply, problem, inv_diag, b, y, options.inner_tolerance * b.norm(),
                     10 * u.size() + 10, meter);
    est.inner_iterations += inner.iterations;
    if (inner.status != StopReason::kConverged && inner.status != StopReason::kMaxIterations) {
      est.status = inner.status;
      break;
    }
    const double mnorm = std::sqrt(y.dot(m.cwiseProduct(y)));
    if (!(mnorm > 0.0) || !std::isfinite(mnorm)) {
      est.status = StopReason::kNonFinite;
      break;
    }
    x = y / mnorm;
    const EvalStatus st = problem.hessian_product(u, x, kx);
    if (st != EvalStatus::kOk || !kx.allFinite()) {
      est.status = failure_reason(st);
      break;
    }
    problem.project(kx);
    const double rho = x.dot(kx);
    meter.add(10 * nn);
    est.iterations = k + 1;
    if (!std::isfinite(rho)) {
      est.status = StopReason::kNonFinite;
      break;
    }
    if (rho <= 0.0) {
      est.status = StopReason::kIndefinite;
      break;
    }
    est.value = rho;
    est.relative_change = std::abs(rho - rho_prev) / rho;
    if (k > 0 && est.relative_change <= options.tolerance) {
      est.status = StopReason::kConverged;
      break;
    }
    rho_prev = rho;
  }
  est.flops = meter.flops();
  return est;
}

namespace {

/// Eigen-decomposition of the symmetric tridiagonal matrix (diag, sub) of size ≥ 2, returned
/// for the matrix divided by `scale` (its largest entry): Eigen's tridiagonal QR deflates when
/// (s/ε)² ≤ |d_i| + |d_{i+1}|, which presumes entries of order one (its compute() scales first;
/// computeFromTridiagonal() does not). Eigenvalues of the original are scale × those returned.
Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> scaled_tridiagonal_eigen(const VecX& diag,
                                                                        const VecX& sub,
                                                                        int options,
                                                                        double& scale) {
  scale = std::max(diag.cwiseAbs().maxCoeff(), sub.cwiseAbs().maxCoeff());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
  es.computeFromTridiagonal(diag / scale, sub / scale, options);
  return es;
}

/// Number of eigenvalues below x of the symmetric tridiagonal matrix with diagonal a and
/// squared off-diagonal e (e[i] = sub[i]²), k = size of a: the negative pivots of the LDLᵀ
/// factorization of T − xI (Sturm count), a pivot of magnitude < pivmin replaced by −pivmin as
/// in LAPACK's dlaebz so that the count stays monotone in x.
int sturm_count(const std::vector<double>& a, const std::vector<double>& e, double x,
                double pivmin) {
  int count = 0;
  double d = a[0] - x;
  if (std::abs(d) < pivmin) d = -pivmin;
  count += d < 0.0;
  for (std::size_t i = 1; i < a.size(); ++i) {
    d = a[i] - x - e[i - 1] / d;
    if (std::abs(d) < pivmin) d = -pivmin;
    count += d < 0.0;
  }
  return count;
}

/// Eigenvalue number `index` (0-based, ascending) of the symmetric tridiagonal (a, e as in
/// sturm_count) by bisection on the Sturm count, from the bracket guess [lo, hi] (widened until
/// it holds the eigenvalue: count(lo) ≤ index < count(hi)) down to a width of `abstol` —
/// O(k) per halving where a QR of all eigenvalues is O(k²) (issue 19: the QR on every Lanczos
/// step was ≈ 40 % of the estimate's CPU on the Veronda–Westmann cube).
double tridiagonal_eigenvalue(const std::vector<double>& a, const std::vector<double>& e, int index,
                              double lo, double hi, double abstol, double pivmin) {
  double width = std::max(hi - lo, abstol);
  while (sturm_count(a, e, lo, pivmin) > index) {
    lo -= width;
    width *= 4.0;
  }
  width = std::max(hi - lo, abstol);
  while (sturm_count(a, e, hi, pivmin) <= index) {
    hi += width;
    width *= 4.0;
  }
  while (hi - lo > abstol) {
    const double mid = 0.5 * (lo + hi);
    if (mid <= lo || mid >= hi) break;  // no double strictly inside
    (sturm_count(a, e, mid, pivmin) > index ? hi : lo) = mid;
  }
  return 0.5 * (lo + hi);
}

/// s_k², the squared last entry of the unit eigenvector of the smallest eigenvalue θ₁ of an
/// unreduced symmetric tridiagonal T_k (a, e as in sturm_count), in O(k): with the pivots d_j
/// of T − θ₁I = LDLᵀ, det(T_j − xI) = d_1⋯d_j, and for an eigenvalue θ the classical
/// s_k² = det(θI − T_{k−1}) / (d/dx det(xI − T_k))(θ) (Parlett, "The Symmetric Eigenvalue
/// Problem", §7.9) reduces, as d_k(θ) = 0, to s_k² = −1/d_k′(θ), with d_1′ = −1 and
/// d_j′ = −1 + e_{j−1} d′_{j−1}/d²_{j−1}. Below the other eigenvalues of every leading block
/// (interlacing) the pivots d_1 … d_{k−1} are positive and d_j′ ≤ −1, so s_k² ∈ (0, 1]; NaN
/// when that does not hold (the caller then takes the eigenvector solve).
double last_entry_squared_smallest(const std::vector<double>& a, const std::vector<double>& e,
                                   double theta) {
  const std::size_t k = a.size();
  if (k == 1) return 1.0;
  double d = a[0] - theta, dp = -1.0;
  for (std::size_t i = 1; i < k; ++i) {
    if (!(d > 0.0)) return std::numeric_limits<double>::quiet_NaN();
    const double r = e[i - 1] / d;
    dp = -1.0 + r * dp / d;
    d = a[i] - theta - r;
  }
  const double s2 = -1.0 / dp;
  return s2 >= 0.0 && s2 <= 1.0 ? s2 : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

TridiagonalExtremes tridiagonal_extremes(const VecX& diag, const VecX& sub) {
  const Eigen::Index k = diag.size();
  INCISE_CHECK_PARAM(k >= 1 && sub.size() == k - 1,
                     "tridiagonal_extremes: need k >= 1 diagonal and k - 1 off-diagonal entries");
  INCISE_CHECK_PARAM(diag.allFinite() && sub.allFinite(),
                     "tridiagonal_extremes: entries must be finite");
  std::vector<double> a(diag.data(), diag.data() + k), e(static_cast<std::size_t>(k - 1));
  double glo = std::numeric_limits<double>::infinity(), ghi = -glo, tnorm = 0.0, max_e = 0.0;
  for (Eigen::Index i = 0; i < k; ++i) {
    const double r = (i > 0 ? std::abs(sub[i - 1]) : 0.0) + (i + 1 < k ? std::abs(sub[i]) : 0.0);
    glo = std::min(glo, diag[i] - r);
    ghi = std::max(ghi, diag[i] + r);
    tnorm = std::max(tnorm, std::abs(diag[i]) + r);
    if (i + 1 < k) {
      e[static_cast<std::size_t>(i)] = sub[i] * sub[i];
      max_e = std::max(max_e, e[static_cast<std::size_t>(i)]);
    }
  }
  TridiagonalExtremes out;
  if (tnorm == 0.0) return out;  // the zero matrix
  const double abstol = 2.0 * std::numeric_limits<double>::epsilon() * tnorm;
  const double pivmin = std::numeric_limits<double>::min() * std::max(1.0, max_e);
  out.smallest = tridiagonal_eigenvalue(a, e, 0, glo, ghi, abstol, pivmin);
  out.largest = tridiagonal_eigenvalue(a, e, static_cast<int>(k - 1), glo, ghi, abstol, pivmin);
  return out;
}

SpectrumEstimate lanczos_spectrum(Problem& problem, const VecX& u, const VecX& start,
                                  const LanczosOptions& options) {
  INCISE_CHECK_PARAM(options.min_steps >= 1 && options.max_steps >= options.min_steps,
                     "lanczos_spectrum: need 1 <= min_steps <= max_steps");
  INCISE_CHECK_PARAM(options.tolerance >= 0.0 && options.window >= 1,
                     "lanczos_spectrum: tolerance must be >= 0 and window >= 1");
  INCISE_CHECK_PARAM(options.random_fraction >= 0.0,
                     "lanczos_spectrum: random_fraction must be >= 0");
  INCISE_CHECK(start.size() == 0 || start.size() == problem.size(),
               "lanczos_spectrum: start has the wrong size");
  const VecX& m = checked_mass(problem);
  CostMeter meter(problem);
  const auto nn = static_cast<std::uint64_t>(u.size());
  auto mnorm = [&](const VecX& v) { return std::sqrt(v.dot(m.cwiseProduct(v))); };
  SpectrumEstimate est;
  est.status = StopReason::kMaxIterations;
  // q₁: the start direction plus a little of a random one, M-normalized.
  VecX q = start.size() == 0 ? VecX::Zero(problem.size()) : start;
  problem.project(q);
  const double sn = mnorm(q);
  VecX z = start_vector(problem, options.seed);
  const double zn = mnorm(z);
  if (sn > 0.0 && std::isfinite(sn))
    q = q / sn + (options.random_fraction / zn) * z;
  else
    q = z / zn;
  q /= mnorm(q);
  VecX q_prev = VecX::Zero(q.size()), w;
  double beta_prev = 0.0;
  // T_k: diagonal, off-diagonal and its squares (the Sturm counts'); the extreme Ritz values by
  // bisection from brackets at the previous ones (θ₁ decreases and θ_k increases with k, by
  // interlacing), to the accuracy of a QR of T_k (≈ ε‖T_k‖).
  std::vector<double> diag, sub, sub2;
  double lo_prev = 0.0, hi_prev = 0.0, lo_step = 0.0, hi_step = 0.0;
  double tnorm = 0.0, max_sub2 = 0.0;  // Gershgorin bound of ‖T_k‖; largest β²
  long calm = 0;                       // consecutive steps with both changes ≤ tolerance
  long calm_top = 0;                   // consecutive steps with θ_k's change ≤ tolerance
  // K(u) assembled once when the problem offers it (an empty function otherwise, or when an
  // element is inverted at u: then the matrix-free product reports it on the first step).
  const std::function<EvalStatus(const VecX&, VecX&)> product =
      options.assembled ? problem.assembled_hessian(u) : nullptr;
  for (long j = 0; j < options.max_steps; ++j) {
    const EvalStatus st = product ? product(q, w) : problem.hessian_product(u, q, w);
    if (st != EvalStatus::kOk || !w.allFinite()) {
      est.status = failure_reason(st);
      break;
    }
    problem.project(w);             // P K q
    const double alpha = q.dot(w);  // (q, M⁻¹PKq)_M
    if (!std::isfinite(alpha)) {
      est.status = StopReason::kNonFinite;
      break;
    }
    if (alpha <= 0.0) {
      est.status = StopReason::kIndefinite;
      break;
    }
    w = w.cwiseQuotient(m) - alpha * q - beta_prev * q_prev;  // three-term recurrence
    const double beta = mnorm(w);
    meter.add(14 * nn);
    diag.push_back(alpha);
    tnorm = std::max(tnorm, alpha + beta_prev + (std::isfinite(beta) ? beta : 0.0));
    double lo = alpha, hi = alpha;
    if (j > 0) {
      const double abstol = 2.0 * std::numeric_limits<double>::epsilon() * tnorm;
      const double pivmin = std::numeric_limits<double>::min() * std::max(1.0, max_sub2);
      const int k = static_cast<int>(diag.size());
      const double lo_width = std::max({2.0 * lo_step, 16.0 * abstol, j == 1 ? beta_prev : 0.0});
      const double hi_width = std::max({2.0 * hi_step, 16.0 * abstol, j == 1 ? beta_prev : 0.0});
      lo = tridiagonal_eigenvalue(diag, sub2, 0, lo_prev - lo_width, lo_prev, abstol, pivmin);
      hi = tridiagonal_eigenvalue(diag, sub2, k - 1, hi_prev, hi_prev + hi_width, abstol, pivmin);
    }
    est.steps = j + 1;
    est.smallest = lo;
    est.largest = hi;
    if (j > 0) {
      est.smallest_change = std::abs(lo - lo_prev) / lo;
      est.largest_change = std::abs(hi - hi_prev) / hi;
      const bool still =
          est.smallest_change <= options.tolerance && est.largest_change <= options.tolerance;
      calm = still ? calm + 1 : 0;
      calm_top = est.largest_change <= options.tolerance ? calm_top + 1 : 0;
      est.largest_settled = calm_top >= options.window;
      lo_step = std::abs(lo - lo_prev);
      hi_step = std::abs(hi - hi_prev);
    }
    lo_prev = lo;
    hi_prev = hi;
    if (!(beta > 1e-14 * hi) || !std::isfinite(beta)) {
      // invariant subspace reached: the Ritz values are eigenvalues
      est.status = std::isfinite(beta) ? StopReason::kConverged : StopReason::kNonFinite;
      break;
    }
    if (est.steps >= options.min_steps && calm >= options.window) {
      // A plateau of θ₁ can look calm; accept only when θ₁ is also close to an eigenvalue:
      // the Ritz residual ‖M⁻¹PKPy − θ₁y‖_M = β_k|s_k| (s: T's eigenvector of θ₁, s_k its
      // last entry) bounds the distance of θ₁ to the nearest eigenvalue (Parlett, "The
      // Symmetric Eigenvalue Problem", Thm. 13.1.1 with §13.2).
      // s_k from the LDLᵀ pivots of T_k − θ₁I (O(k); issue 19: an eigenvector solve of T_k on
      // every calm step was ≈ 2/3 of the estimate's CPU on the Veronda–Westmann cube), the
      // eigenvector solve only when that formula is not usable.
      double residual = std::numeric_limits<double>::infinity();
      const double s2 = last_entry_squared_smallest(diag, sub2, lo);
      if (std::isfinite(s2)) {
        residual = beta * std::sqrt(s2);
      } else {
        const auto kk = static_cast<Eigen::Index>(diag.size());
        double scale = 1.0;
        const auto es = scaled_tridiagonal_eigen(Eigen::Map<const VecX>(diag.data(), kk),
                                                 Eigen::Map<const VecX>(sub.data(), kk - 1),
                                                 Eigen::ComputeEigenvectors, scale);
        if (es.info() == Eigen::Success) {
          Eigen::Index i_min = 0;
          es.eigenvalues().minCoeff(&i_min);
          residual = beta * std::abs(es.eigenvectors()(kk - 1, i_min));
        }
      }
      est.smallest_residual = residual / lo;
      if (est.smallest_residual <= options.residual_tolerance) {
        est.status = StopReason::kConverged;
        break;
      }
    }
    sub2.push_back(beta * beta);
    max_sub2 = std::max(max_sub2, beta * beta);
    sub.push_back(beta);
    q_prev.swap(q);
    q = w / beta;
    beta_prev = beta;
  }
  if (est.status == StopReason::kIndefinite || est.status == StopReason::kNonFinite ||
      est.status == StopReason::kInverted) {
    if (est.message.empty())
      est.message = std::string("Lanczos step ") + std::to_string(est.steps + 1) + ": " +
                    to_string(est.status);
  }
  est.flops = meter.flops();
  return est;
}

double critical_time_step(double lambda_max) {
  INCISE_CHECK_PARAM(lambda_max > 0.0, "critical_time_step: eigenvalue must be positive");
  return 2.0 / std::sqrt(lambda_max);
}

double critical_damping(double lambda_min) {
  INCISE_CHECK_PARAM(lambda_min > 0.0, "critical_damping: eigenvalue must be positive");
  return 2.0 * std::sqrt(lambda_min);
}

LanczosExtremes cg_lanczos_extremes(const CgCoefficients& c) {
  const std::size_t k = c.alpha.size();
  INCISE_CHECK_PARAM(k > 0 && c.beta.size() == k,
                     "cg_lanczos_extremes: need equally many alpha and beta (at least one)");
  const auto kk = static_cast<Eigen::Index>(k);
  VecX diag(kk), sub(kk > 1 ? kk - 1 : 0);
  for (std::size_t j = 0; j < k; ++j) {
    diag[Eigen::Index(j)] = 1.0 / c.alpha[j] + (j > 0 ? c.beta[j - 1] / c.alpha[j - 1] : 0.0);
    if (j + 1 < k) sub[Eigen::Index(j)] = std::sqrt(c.beta[j]) / c.alpha[j];
  }
  LanczosExtremes out;
  out.steps = long(k);
  if (k == 1) {
    out.smallest = out.largest = diag[0];
    return out;
  }
  double scale = 1.0;
  const auto es = scaled_tridiagonal_eigen(diag, sub, Eigen::EigenvaluesOnly, scale);
  out.converged = es.info() == Eigen::Success;
  out.smallest = scale * es.eigenvalues().minCoeff();
  out.largest = scale * es.eigenvalues().maxCoeff();
  return out;
}

}  // namespace incise::solver
