#include <incise/solver/linear_cg.hpp>

#include <cmath>
#include <limits>
#include <sstream>

namespace incise::solver {
namespace {

// z = D⁻¹ r (or r when no preconditioner).
void precondition(const VecX& inv_diag, const VecX& r, VecX& z) {
  if (inv_diag.size() == 0)
    z = r;
  else
    z = inv_diag.cwiseProduct(r);
}

}  // namespace

JacobiDiagonal jacobi_inverse_diagonal(Problem& problem, const VecX& u) {
  JacobiDiagonal out;
  VecX diag;
  if (!problem.hessian_diagonal(u, diag) || diag.size() != u.size()) {
    out.status = StopReason::kPreconditionerUnavailable;
    out.message =
        "Jacobi preconditioning requested, but Problem::hessian_diagonal() gave no diagonal at u "
        "(the problem provides none, or its tangent cannot be evaluated there): use "
        "Preconditioner::kNone";
    return out;
  }
  Eigen::Index non_finite = -1, non_positive = -1;
  for (Eigen::Index i = 0; i < diag.size(); ++i) {
    if (problem.is_fixed(i)) continue;
    if (!std::isfinite(diag[i])) {
      non_finite = i;
      break;
    }
    if (!(diag[i] > 0.0) && non_positive < 0) non_positive = i;
  }
  const Eigen::Index bad = non_finite >= 0 ? non_finite : non_positive;
  if (bad >= 0) {
    std::ostringstream os;
    os << "free DOF " << bad << " has diagonal entry K_ii = " << diag[bad];
    if (non_finite >= 0) {
      out.status = StopReason::kNonFinite;
      os << ": the tangent is not finite there";
    } else {
      out.status = StopReason::kIndefinite;
      os << ", not positive, so K is not positive definite (e_i^T K e_i <= 0): fix a DOF "
            "without stiffness (K_ii = 0); where K is indefinite away from the solution, "
            "truncated Newton with Preconditioner::kNone truncates at negative curvature";
    }
    out.message = os.str();
    return out;
  }
  out.inverse.resize(diag.size());
  for (Eigen::Index i = 0; i < diag.size(); ++i)
    out.inverse[i] = problem.is_fixed(i) ? 0.0 : 1.0 / diag[i];
  out.status = StopReason::kConverged;
  return out;
}

SolverReport linear_cg(Problem& problem, VecX& u, const LinearCgOptions& options) {
  INCISE_CHECK(u.size() == problem.size(), "linear_cg: u has the wrong size");
  INCISE_CHECK(
      !options.apply_preconditioner || options.preconditioner == Preconditioner::kNone,
      "linear_cg: apply_preconditioner and a Preconditioner other than kNone are both set");
  // z = B r for the operator preconditioner, projected; D⁻¹ r or r otherwise.
  const auto precondition = [&](const VecX& inv_diag, const VecX& r, VecX& z) {
    if (!options.apply_preconditioner) return incise::solver::precondition(inv_diag, r, z);
    options.apply_preconditioner(r, z);
    problem.project(z);
  };
  SolverReport rep;
  CostMeter meter(problem);
  const FixedDofs fixed_dofs(problem);
  const Eigen::Index n = u.size();
  const auto nn = static_cast<std::uint64_t>(n);
  const VecX u0 = u;

  GradientStart start;
  if (!start_from_gradient(problem, u, options.stop, fixed_dofs, meter, rep, start)) return rep;
  const double fex = start.fex;
  VecX& g = start.g;  // full (unprojected) gradient ∇Π(u) = K x − f, tracked recursively
  VecX& r = start.r;
  double energy = start.energy;
  double threshold = start.threshold;
  double rnorm = r.norm();
  VecX inv_diag;
  if (options.preconditioner == Preconditioner::kJacobi) {
    JacobiDiagonal jd = jacobi_inverse_diagonal(problem, u0);
    if (!jd.ok()) {
      rep.status = jd.status;
      rep.message = std::move(jd.message);
      rep.residual_norm = rnorm;
      rep.threshold = threshold;
      rep.energy = energy;
      meter.record(rep);
      return rep;
    }
    inv_diag = std::move(jd.inverse);
  }

  VecX z, d, q(n);
  precondition(inv_diag, r, z);
  double rz = r.dot(z);
  d = z;
  meter.add(6 * nn);

  if (options.coefficients) {
    options.coefficients->alpha.clear();
    options.coefficients->beta.clear();
  }
  long k = 0;
  StopReason reason = StopReason::kConverged;
  bool confirmed = false;  // the true residual was evaluated at the final u
  double last_replaced = std::numeric_limits<double>::infinity();
  while (true) {
    if (rnorm <= threshold) {
      reason = StopReason::kConverged;
      if (!options.recompute_residual) break;
      // The recursive residual drifts from the true one by round-off (≈ eps·κ(K)·‖f‖). Confirm
      // on the true gradient; when it misses the rule, replace the residual by the true one and
      // restart CG from u (residual replacement), unless the previous replacement made no
      // progress: then the true residual is at its round-off floor and the run stagnated.
      VecX gt;
      double e = 0.0;
      const EvalStatus st = problem.gradient(u, gt, &e);
      if (st != EvalStatus::kOk || !gt.allFinite()) {
        reason = failure_reason(st);
        break;
      }
      r = -gt;
      problem.project(r);
      const double true_norm = r.norm();
      g = gt;
      energy = e;
      rnorm = true_norm;
      threshold = residual_threshold(options.stop, fex, fixed_dofs.norm(g), n);
      meter.add(4 * nn);
      confirmed = true;
      if (true_norm <= threshold) break;
      if (true_norm >= last_replaced) {
        reason = StopReason::kStagnated;
        break;
      }
      last_replaced = true_norm;
      confirmed = false;
      precondition(inv_diag, r, z);
      rz = r.dot(z);
      d = z;
      continue;
    }
    reason = meter.exhausted(options.budget, k);
    if (reason != StopReason::kConverged) break;

    const EvalStatus st = problem.hessian_product(u0, d, q);
    if (st != EvalStatus::kOk || !q.allFinite()) {
      reason = failure_reason(st);
      break;
    }
    const double curvature = d.dot(q);  // d is projected, so dᵀq = dᵀ P K P d
    if (!std::isfinite(curvature)) {
      reason = StopReason::kNonFinite;
      break;
    }
    if (curvature <= 0.0) {
      reason = StopReason::kIndefinite;
      break;
    }
    const double alpha = rz / curvature;
    u += alpha * d;
    g += alpha * q;  // ∇Π(u + αd) = ∇Π(u) + αK d, including the reaction components
    r = -g;
    problem.project(r);
    precondition(inv_diag, r, z);
    const double rz_new = r.dot(z);
    energy -= 0.5 * alpha * rz;  // exact decrease of a quadratic along a CG step
    const double beta = rz_new / rz;
    if (options.coefficients) {
      options.coefficients->alpha.push_back(alpha);
      options.coefficients->beta.push_back(beta);
    }
    rz = rz_new;
    d = z + beta * d;
    rnorm = r.norm();
    threshold = residual_threshold(options.stop, fex, fixed_dofs.norm(g), n);
    meter.add(20 * nn);
    ++k;
    rep.residual_history.push_back(rnorm);
    rep.energy_history.push_back(energy);
    meter.observe(options.observer, IterationInfo{k, &u, rnorm, energy, 0, 0.0});
    if (!std::isfinite(rnorm) || !std::isfinite(beta)) {
      reason = StopReason::kNonFinite;
      break;
    }
  }

  if (!u.allFinite()) u = u0;  // never hand back NaN
  if (options.recompute_residual && !confirmed && reason != StopReason::kNonFinite &&
      reason != StopReason::kInverted) {
    VecX gt;
    double e = 0.0;
    if (problem.gradient(u, gt, &e) == EvalStatus::kOk && gt.allFinite()) {
      VecX rt = -gt;
      problem.project(rt);
      rnorm = rt.norm();
      energy = e;
      threshold = residual_threshold(options.stop, fex, fixed_dofs.norm(gt), n);
      // The recursive residual met the rule but the true one may not: report honestly.
      if (reason == StopReason::kConverged && rnorm > threshold) reason = StopReason::kStagnated;
    }
  }
  rep.status = reason;
  rep.iterations = k;
  rep.residual_norm = rnorm;
  rep.threshold = threshold;
  rep.energy = energy;
  meter.record(rep);
  return rep;
}

InnerCgResult projected_cg(const LinearOperator& apply, const Problem& problem,
                           const VecX& inverse_diagonal, const VecX& b, VecX& x, double tolerance,
                           long max_iterations, CostMeter& meter) {
  const Eigen::Index n = b.size();
  const auto nn = static_cast<std::uint64_t>(n);
  InnerCgResult res;
  x.setZero(n);
  VecX r = b;
  problem.project(r);
  VecX z, d, q(n);
  precondition(inverse_diagonal, r, z);
  double rz = r.dot(z);
  d = z;
  double rnorm = r.norm();
  meter.add(6 * nn);
  long k = 0;
  while (true) {
    res.residual_norm = rnorm;
    if (rnorm <= tolerance) {
      res.status = StopReason::kConverged;
      break;
    }
    if (k >= max_iterations) {
      res.status = StopReason::kMaxIterations;
      break;
    }
    const EvalStatus st = apply(d, q);
    if (st != EvalStatus::kOk || !q.allFinite()) {
      res.status = failure_reason(st);
      break;
    }
    problem.project(q);
    const double curvature = d.dot(q);
    if (!std::isfinite(curvature)) {
      res.status = StopReason::kNonFinite;
      break;
    }
    if (curvature <= 0.0) {
      res.status = StopReason::kIndefinite;
      res.negative_curvature = true;
      break;
    }
    const double alpha = rz / curvature;
    x += alpha * d;
    r -= alpha * q;
    precondition(inverse_diagonal, r, z);
    const double rz_new = r.dot(z);
    const double beta = rz_new / rz;
    rz = rz_new;
    d = z + beta * d;
    rnorm = r.norm();
    meter.add(16 * nn);
    ++k;
    if (!std::isfinite(rnorm)) {
      res.status = StopReason::kNonFinite;
      break;
    }
  }
  res.iterations = k;
  if (!x.allFinite()) x.setZero();
  return res;
}

}  // namespace incise::solver
