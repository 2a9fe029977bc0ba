#include <incise/solver/truncated_newton.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace incise::solver {

SolverReport truncated_newton(Problem& problem, VecX& u, const TruncatedNewtonOptions& options) {
  INCISE_CHECK(u.size() == problem.size(), "truncated_newton: u has the wrong size");
  INCISE_CHECK_PARAM(options.forcing_max > 0.0 && options.forcing_max < 1.0,
                     "truncated_newton: forcing_max must lie in (0, 1)");
  SolverReport rep;
  CostMeter meter(problem);
  const FixedDofs fixed_dofs(problem);
  const Eigen::Index n = u.size();
  const auto nn = static_cast<std::uint64_t>(n);
  const long max_inner = options.max_inner > 0 ? options.max_inner : long(n);
  GradientStart start;
  if (!start_from_gradient(problem, u, options.stop, fixed_dofs, meter, rep, start)) return rep;
  const double fex = start.fex;
  VecX& g = start.g;
  VecX& r = start.r;
  double energy = start.energy;
  double threshold = start.threshold;
  double rnorm = r.norm();
  const double r0 = rnorm;

  long k = 0;
  double last_step_norm = 0.0;
  StopReason reason = StopReason::kConverged;
  VecX p, ut, gt, rt;
  while (true) {
    if (rnorm <= threshold) {
      reason = StopReason::kConverged;
      break;
    }
    reason = meter.exhausted(options.budget, k);
    if (reason != StopReason::kConverged) break;

    // Inner solve K(u) p = r (§2.4.3 (∗)).
    VecX inv_diag;
    if (options.preconditioner == Preconditioner::kJacobi) {
      JacobiDiagonal jd = jacobi_inverse_diagonal(problem, u);
      if (!jd.ok()) {
        reason = jd.status;
        rep.message = "Newton step " + std::to_string(k + 1) + ": " + jd.message;
        break;
      }
      inv_diag = std::move(jd.inverse);
    }
    const double eta = std::min(options.forcing_max, std::sqrt(rnorm / std::max(r0, 1e-300)));
    const double inner_tol = std::max(eta * rnorm, 0.5 * threshold);
    const VecX u_fixed = u;
    const InnerCgResult inner = projected_cg(
        [&](const VecX& in, VecX& out) { return problem.hessian_product(u_fixed, in, out); },
        problem, inv_diag, r, p, inner_tol, max_inner, meter);
    rep.inner_iterations += inner.iterations;
    if (inner.status == StopReason::kNonFinite || inner.status == StopReason::kInverted) {
      reason = inner.status;
      break;
    }
    if (p.squaredNorm() == 0.0) {
      // Negative curvature along the very first direction: scaled steepest descent.
      if (inv_diag.size() == n) {
        p = inv_diag.cwiseProduct(r);
      } else if (last_step_norm > 0.0) {
        p = r * (last_step_norm / rnorm);
      } else {
        reason = StopReason::kIndefinite;
        break;
      }
    }
    const double slope = r.dot(p);  // −∇Π·p > 0 for a descent direction
    meter.add(2 * nn);
    if (!(slope > 0.0)) {
      reason = StopReason::kIndefinite;
      break;
    }

    // Backtracking on Π (never into Π = +∞).
    double alpha = 1.0;
    bool accepted = false;
    double e_new = 0.0;
    for (int b = 0; b <= options.max_backtracks; ++b, alpha *= 0.5) {
      ut = u + alpha * p;
      const EvalStatus st = problem.gradient(ut, gt, &e_new);
      meter.add(2 * nn);
      ++rep.inner_iterations;
      if (st != EvalStatus::kOk || !gt.allFinite() || !std::isfinite(e_new)) continue;
      rt = -gt;
      problem.project(rt);
      const double rnorm_t = rt.norm();
      meter.add(2 * nn);
      const double armijo = energy - 1e-4 * alpha * slope;
      // Near the solution Π(u+αp) − Π(u) is below round-off of Π; then judge by the residual.
      const double roundoff =
          64.0 * std::numeric_limits<double>::epsilon() * std::max(std::abs(energy), 1e-300);
      if (e_new <= armijo || (e_new <= energy + roundoff && rnorm_t < rnorm)) {
        accepted = true;
        rnorm = rnorm_t;
        break;
      }
    }
    if (!accepted) {
      reason = StopReason::kLineSearchFailed;
      break;
    }
    u.swap(ut);
    g.swap(gt);
    r.swap(rt);
    energy = e_new;
    last_step_norm = alpha * p.norm();
    threshold = residual_threshold(options.stop, fex, fixed_dofs.norm(g), n);
    meter.add(4 * nn);
    ++k;
    rep.residual_history.push_back(rnorm);
    rep.energy_history.push_back(energy);
    meter.observe(options.observer, IterationInfo{k, &u, rnorm, energy, 0, 0.0});
  }
  rep.status = reason;
  rep.iterations = k;
  rep.residual_norm = rnorm;
  rep.threshold = threshold;
  rep.energy = energy;
  meter.record(rep);
  return rep;
}

}  // namespace incise::solver
