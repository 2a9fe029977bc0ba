#include <incise/solver/report.hpp>

#include <cmath>

namespace incise::solver {

const char* to_string(StopReason r) {
  switch (r) {
    case StopReason::kConverged: return "converged";
    case StopReason::kMaxIterations: return "max_iterations";
    case StopReason::kFlopBudget: return "flop_budget";
    case StopReason::kTimeBudget: return "time_budget";
    case StopReason::kInverted: return "inverted";
    case StopReason::kNonFinite: return "non_finite";
    case StopReason::kIndefinite: return "indefinite";
    case StopReason::kLineSearchFailed: return "line_search_failed";
    case StopReason::kStagnated: return "stagnated";
    case StopReason::kUnstable: return "unstable";
    case StopReason::kPreconditionerUnavailable: return "preconditioner_unavailable";
  }
  return "?";
}

double residual_threshold(const StoppingRule& rule, double external_force_norm,
                          double reaction_norm, Eigen::Index n) {
  double t = rule.absolute_tolerance;
  if (rule.rule == ResidualRule::kExternalForce) {
    t += rule.epsilon * external_force_norm;  // (6.8)
  } else {
    // (6.9): ε√(‖f_ex‖² + ‖f_react‖²) + (E d H / √n) ε_round.
    t += rule.epsilon * std::hypot(external_force_norm, reaction_norm);
    if (n > 0) t += rule.force_scale / std::sqrt(static_cast<double>(n)) * rule.epsilon_round;
  }
  return t;
}

CostMeter::CostMeter(const Problem& problem) : problem_(problem), start_flops_(problem.flops()) {}

std::uint64_t CostMeter::flops() const {
  return problem_.flops() - start_flops_ - excluded_flops_ + own_flops_;
}

double CostMeter::seconds() const {
  return timer_.seconds() - excluded_seconds_;
}

double CostMeter::cpu_seconds() const {
  return process_cpu_seconds() - cpu_start_ - excluded_cpu_seconds_;
}

void CostMeter::record(SolverReport& rep) const {
  rep.flops = flops();
  rep.seconds = seconds();
  rep.cpu_seconds = cpu_seconds();
}

void CostMeter::observe(const IterationObserver& observer, IterationInfo info) {
  if (!observer) return;
  info.flops = flops();
  info.seconds = seconds();
  info.cpu_seconds = cpu_seconds();
  const std::uint64_t f0 = problem_.flops();
  const double c0 = process_cpu_seconds();
  Timer t;
  observer(info);
  excluded_seconds_ += t.seconds();
  excluded_cpu_seconds_ += process_cpu_seconds() - c0;
  excluded_flops_ += problem_.flops() - f0;
}

StopReason CostMeter::exhausted(const Budget& budget, long iterations) const {
  if (iterations >= budget.max_iterations) return StopReason::kMaxIterations;
  if (static_cast<double>(flops()) >= budget.max_flops) return StopReason::kFlopBudget;
  if (seconds() >= budget.max_seconds) return StopReason::kTimeBudget;
  return StopReason::kConverged;
}

bool external_force_is_finite(double external_force_norm, SolverReport& rep) {
  if (std::isfinite(external_force_norm)) return true;
  rep.status = StopReason::kNonFinite;
  rep.message =
      "the external load is not finite: ||f_ext|| overflows the doubles (a load above ~1.3e154 "
      "N, or a non-finite force): scale the load (or change the units)";
  return false;
}

double fixed_norm(const Problem& problem, const VecX& v) {
  return FixedDofs(problem).norm(v);
}

FixedDofs::FixedDofs(const Problem& problem) {
  for (Eigen::Index i = 0; i < problem.size(); ++i)
    if (problem.is_fixed(i)) dofs_.push_back(i);
}

double FixedDofs::norm(const VecX& v) const {
  double s = 0.0;
  for (const Eigen::Index i : dofs_) s += v[i] * v[i];
  return std::sqrt(s);
}

bool start_from_gradient(Problem& problem, const VecX& u, const StoppingRule& stop,
                         const FixedDofs& fixed_dofs, const CostMeter& meter, SolverReport& rep,
                         GradientStart& out) {
  out.fex = problem.external_force_norm();
  if (!external_force_is_finite(out.fex, rep)) {
    meter.record(rep);
    return false;
  }
  const EvalStatus st = problem.gradient(u, out.g, &out.energy);
  if (st != EvalStatus::kOk || !out.g.allFinite()) {
    rep.status = failure_reason(st);
    meter.record(rep);
    return false;
  }
  out.r = -out.g;
  problem.project(out.r);
  out.threshold = residual_threshold(stop, out.fex, fixed_dofs.norm(out.g), u.size());
  rep.residual_history.push_back(out.r.norm());
  rep.energy_history.push_back(out.energy);
  return true;
}

}  // namespace incise::solver
