#include <incise/scene/scene_runner.hpp>

#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>
#include <incise/solver/cholmod_factor.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>
#include <incise/solver/truncated_newton.hpp>

#include <cmath>
#include <limits>
#include <sstream>

namespace incise::scene {

namespace {

/// Safety factor on the critical time step 2/√λ_max: the power-iteration Rayleigh quotient
/// underestimates λ_max, so 2/√value overestimates the critical step (eigen_estimates.hpp).
constexpr double kTimeStepSafety = 0.9;
/// Undamped SS22 steps sampled for the spectral damping estimate (FFT length).
constexpr long kSpectralSteps = 8192;

solver::SolverReport solve_augmented(BuiltScene& scene, VecX& u) {
  fem::ElasticProblem& p = *scene.problem;
  solver::SolverReport rep;
  Timer t;
  const std::uint64_t flops0 = p.flops();
  const VecX zero = VecX::Zero(p.size());
  if (p.assemble_tangent(zero, fem::FixedDofTreatment::kIdentity) != EvalStatus::kOk) {
    rep.reason = solver::StopReason::kInverted;
    return rep;
  }
  const auto& k = p.tangent_matrix();
  solver::CholmodFactor factor;
  const solver::FactorStatus st = factor.compute(k, 1);
  scene.record(
      "sparse stiffness K (" + std::to_string(k.rows()) + " DOFs, " + std::to_string(k.nonZeros()) +
          " nonzeros) and CHOLMOD factor (|L| = " + std::to_string(factor.nnz_l()) +
          "; flops as estimated by CHOLMOD)",
      t.seconds(),
      static_cast<std::size_t>(k.nonZeros() + factor.nnz_l()) * (sizeof(double) + sizeof(int)),
      static_cast<std::int64_t>(factor.factor_flops()));
  rep.flops = p.flops() - flops0 + static_cast<std::uint64_t>(factor.factor_flops());
  if (st != solver::FactorStatus::kOk) {
    rep.reason = st == solver::FactorStatus::kNotPositiveDefinite ? solver::StopReason::kIndefinite
                                                                  : solver::StopReason::kNonFinite;
    rep.seconds = t.seconds();
    return rep;
  }
  VecX rhs = p.external_force();
  p.project(rhs);
  VecX x;
  if (factor.solve(rhs, x) != solver::FactorStatus::kOk || !x.allFinite()) {
    rep.reason = solver::StopReason::kNonFinite;
    rep.seconds = t.seconds();
    return rep;
  }
  p.project(x);
  u = x;
  VecX g;
  double energy = 0;
  const EvalStatus es = p.gradient(u, g, &energy);
  p.project(g);
  rep.iterations = 1;
  rep.residual_norm = g.norm();
  rep.energy = energy;
  rep.threshold = scene.spec.solver.tolerance * p.external_force_norm();
  rep.residual_history = {p.external_force_norm(), rep.residual_norm};
  rep.energy_history = {0.0, energy};
  rep.reason = es != EvalStatus::kOk                ? solver::StopReason::kNonFinite
               : rep.residual_norm <= rep.threshold ? solver::StopReason::kConverged
                                                    : solver::StopReason::kStagnated;
  rep.flops = p.flops() - flops0 + static_cast<std::uint64_t>(factor.factor_flops());
  rep.seconds = t.seconds();
  return rep;
}

}  // namespace

SceneRunResult run_scene(BuiltScene& scene, const RunObserver& observer) {
  INCISE_CHECK(scene.problem != nullptr, "run_scene needs a built problem");
  fem::ElasticProblem& p = *scene.problem;
  const SolverSpec& s = scene.spec.solver;
  SceneRunResult res;
  res.u = VecX::Zero(p.size());
  res.external_force_norm = p.external_force_norm();

  solver::StoppingRule stop;
  stop.rule = solver::ResidualRule::kExternalForce;  // ‖r‖ ≤ ε‖f_ext‖, thesis §3.3 / (6.8)
  stop.epsilon = s.tolerance;
  solver::Budget budget;
  budget.max_iterations = s.max_iterations;
  if (s.time_budget > 0) budget.max_seconds = s.time_budget;

  auto record_row = [&](const solver::IterationInfo& info) {
    TraceRow row;
    row.iteration = info.iteration;
    row.residual_norm = info.residual_norm;
    row.energy = info.energy;
    row.flops = info.flops;
    row.seconds = info.seconds;
    for (const auto& pr : scene.probes) row.probes.push_back(probe_value(pr, *info.u));
    res.trace.push_back(std::move(row));
    if (observer) observer(info);
  };

  std::ostringstream detail;
  switch (s.method) {
    case SolverSpec::Method::kCG: {
      solver::LinearCgOptions o;
      o.stop = stop;
      o.budget = budget;
      o.preconditioner = s.preconditioner == "jacobi" ? solver::Preconditioner::kJacobi
                                                      : solver::Preconditioner::kNone;
      o.observer = record_row;
      detail << "linear CG (matrix-free), preconditioner " << s.preconditioner;
      res.report = solver::linear_cg(p, res.u, o);
      break;
    }
    case SolverSpec::Method::kNonlinearCG: {
      solver::NonlinearCgOptions o;
      o.stop = stop;
      o.budget = budget;
      o.observer = record_row;
      detail << "nonlinear CG, " << solver::to_string(o.beta) << ", "
             << solver::to_string(o.line_search) << " line search";
      res.report = solver::nonlinear_cg(p, res.u, o);
      break;
    }
    case SolverSpec::Method::kNewton: {
      solver::TruncatedNewtonOptions o;
      o.stop = stop;
      o.budget = budget;
      o.preconditioner = s.preconditioner == "jacobi" ? solver::Preconditioner::kJacobi
                                                      : solver::Preconditioner::kNone;
      o.observer = record_row;
      detail << "truncated Newton, inner CG preconditioner " << s.preconditioner;
      res.report = solver::truncated_newton(p, res.u, o);
      break;
    }
    case SolverSpec::Method::kDynamicSS22: {
      solver::DynamicRelaxationOptions o;
      o.stop = stop;
      o.budget = budget;
      o.observer = record_row;
      double dt = s.time_step;
      std::string dt_origin = "given";
      if (dt <= 0) {
        Timer t;
        const solver::EigenEstimate e = solver::largest_eigenvalue(p, res.u);
        scene.record("largest eigenvalue of M^-1 K by power iteration (" +
                         std::to_string(e.iterations) + " iterations, " +
                         solver::to_string(e.reason) + ")",
                     t.seconds(), 3 * static_cast<std::size_t>(p.size()) * sizeof(double),
                     static_cast<std::int64_t>(e.flops));
        dt = kTimeStepSafety * solver::critical_time_step(e.value);
        dt_origin = "0.9 x critical 2/sqrt(lambda_max), lambda_max = " + std::to_string(e.value);
      }
      double eta = s.damping;
      std::string eta_origin = "given";
      if (eta < 0 && s.spectral_tuning) {
        Timer t;
        const solver::SpectralDamping sd =
            solver::damping_from_spectrum(p, res.u, dt, kSpectralSteps);
        scene.record("FFTW plan and spectrum of " + std::to_string(sd.steps) +
                         " undamped steps (dominant frequency " + std::to_string(sd.frequency) +
                         " Hz)",
                     t.seconds(), 2 * static_cast<std::size_t>(kSpectralSteps) * sizeof(double),
                     static_cast<std::int64_t>(sd.flops));
        eta = sd.damping;
        eta_origin = "spectral: 4 pi f, f = " + std::to_string(sd.frequency) + " Hz";
      } else if (eta < 0) {
        Timer t;
        const solver::EigenEstimate e = solver::smallest_eigenvalue(p, res.u);
        scene.record("smallest eigenvalue of M^-1 K by inverse iteration (" +
                         std::to_string(e.iterations) + " iterations, " +
                         std::to_string(e.inner_iterations) + " inner CG steps, " +
                         solver::to_string(e.reason) + ")",
                     t.seconds(), 5 * static_cast<std::size_t>(p.size()) * sizeof(double),
                     static_cast<std::int64_t>(e.flops));
        eta = solver::critical_damping(e.value);
        eta_origin = "critical 2 sqrt(lambda_1), lambda_1 = " + std::to_string(e.value);
      }
      o.time_step = dt;
      o.damping = eta;
      detail << "dynamic relaxation SS22, dt = " << dt << " s (" << dt_origin << "), eta = " << eta
             << " 1/s (" << eta_origin << ")";
      res.report = solver::dynamic_relaxation(p, res.u, o);
      break;
    }
    case SolverSpec::Method::kAugmented: {
      detail << "CHOLMOD supernodal factorization of K (fixed DOFs as identity rows), one solve";
      res.report = solve_augmented(scene, res.u);
      break;
    }
  }
  res.method_detail = detail.str();
  for (const auto& pr : scene.probes) {
    ProbeResult r;
    r.name = pr.spec.name;
    r.value = probe_value(pr, res.u);
    r.reference = pr.spec.reference;
    if (r.reference && r.reference->norm() > 0)
      r.relative_error = (r.value - *r.reference).norm() / r.reference->norm();
    res.probes.push_back(r);
  }
  return res;
}

}  // namespace incise::scene
