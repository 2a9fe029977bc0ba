#include <incise/solver/eigen_estimates.hpp>

#include <Eigen/Eigenvalues>
#include <incise/solver/linear_cg.hpp>

#include <algorithm>
#include <cmath>
#include <random>

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
  // Eigen's tridiagonal QR deflates when (s/ε)² ≤ |d_i| + |d_{i+1}|, which presumes entries of
  // order one (its compute() scales first; computeFromTridiagonal() does not): scale by the
  // largest entry, solve, scale back.
  const double scale = std::max(diag.cwiseAbs().maxCoeff(), sub.cwiseAbs().maxCoeff());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
  es.computeFromTridiagonal(diag / scale, sub / scale, Eigen::EigenvaluesOnly);
  out.converged = es.info() == Eigen::Success;
  out.smallest = scale * es.eigenvalues().minCoeff();
  out.largest = scale * es.eigenvalues().maxCoeff();
  return out;
}

}  // namespace incise::solver
