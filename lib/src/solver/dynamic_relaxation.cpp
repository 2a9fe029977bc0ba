#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/spectral/dominant_frequency.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace incise::solver {

namespace {

/// ‖Pg‖² (P: the fixed DOFs projected out, `free` holding 1 at free DOFs and 0 at fixed ones)
/// and whether every entry of g is finite, in one pass over g (issue 19: the SS22 step's vector
/// passes; x − x is 0 for finite x and NaN otherwise; four partial sums of each).
bool free_norm2_if_finite(const VecX& g, const VecX& free, double& norm2) {
  const Eigen::Index n = g.size();
  const double* gi = g.data();
  const double* fi = free.data();
  double s[4] = {0.0, 0.0, 0.0, 0.0}, f[4] = {0.0, 0.0, 0.0, 0.0};
  Eigen::Index i = 0;
  for (; i + 4 <= n; i += 4)
    for (int l = 0; l < 4; ++l) {
      const double r = fi[i + l] * gi[i + l];
      s[l] += r * r;
      f[l] += gi[i + l] - gi[i + l];
    }
  for (; i < n; ++i) {
    const double r = fi[i] * gi[i];
    s[0] += r * r;
    f[0] += gi[i] - gi[i];
  }
  norm2 = (s[0] + s[1]) + (s[2] + s[3]);
  return ((f[0] + f[1]) + (f[2] + f[3])) == 0.0;
}

/// ‖u‖² of the new u and u̇ᵀMu̇ of the new u̇ (SS22's update pass, below).
struct UpdateSums {
  double u2 = 0.0;
  double mv2 = 0.0;
};

/// The SS22 update pass over n entries (every array a distinct buffer, so the loop vectorizes
/// without run-time alias checks): a = (−g − η m v)·w, u_new = u + (Δt v + ½Δt² a),
/// v ← v + Δt a, ū_next = u_new + ½Δt v, with four partial sums (one per lane of i mod 4) of
/// u_new² and m v².
UpdateSums ss22_update(Eigen::Index n, const double* __restrict g, const double* __restrict m,
                       const double* __restrict w, const double* __restrict u,
                       double* __restrict u_new, double* __restrict v, double* __restrict ubar,
                       double eta, double dt) {
  const double h2 = 0.5 * dt * dt;
  const double half_dt = 0.5 * dt;
  double s2[4] = {0.0, 0.0, 0.0, 0.0}, k2[4] = {0.0, 0.0, 0.0, 0.0};
  const Eigen::Index n4 = n - n % 4;
  for (Eigen::Index i = 0; i < n; i += 4) {
    const int lanes = i < n4 ? 4 : static_cast<int>(n - n4);
    for (int l = 0; l < lanes; ++l) {
      const Eigen::Index j = i + l;
      const double a = (-g[j] - eta * (m[j] * v[j])) * w[j];
      const double un = u[j] + (dt * v[j] + h2 * a);
      const double vn = v[j] + dt * a;
      u_new[j] = un;
      v[j] = vn;
      ubar[j] = un + half_dt * vn;
      s2[l] += un * un;
      k2[l] += m[j] * (vn * vn);
    }
  }
  return {(s2[0] + s2[1]) + (s2[2] + s2[3]), (k2[0] + k2[1]) + (k2[2] + k2[3])};
}

}  // namespace

SolverReport dynamic_relaxation(Problem& problem, VecX& u,
                                const DynamicRelaxationOptions& options) {
  INCISE_CHECK(u.size() == problem.size(), "dynamic_relaxation: u has the wrong size");
  INCISE_CHECK_PARAM(options.time_step > 0.0 && std::isfinite(options.time_step),
                     "dynamic_relaxation: time_step must be positive");
  INCISE_CHECK_PARAM(options.damping >= 0.0 && std::isfinite(options.damping),
                     "dynamic_relaxation: damping must be non-negative");
  const VecX& m = problem.lumped_mass();
  INCISE_CHECK(m.size() == problem.size(), "dynamic_relaxation needs Problem::lumped_mass()");
  INCISE_CHECK((m.array() > 0.0).all(), "dynamic_relaxation: lumped masses must be positive");

  SolverReport rep;
  CostMeter meter(problem);
  const FixedDofs fixed_dofs(problem);
  const Eigen::Index n = u.size();
  const auto nn = static_cast<std::uint64_t>(n);
  const double eta = options.damping;
  const double fex = problem.external_force_norm();
  if (!external_force_is_finite(fex, rep)) {
    meter.record(rep);
    return rep;
  }
  INCISE_CHECK_PARAM(options.max_restarts >= 0, "dynamic_relaxation: max_restarts must be >= 0");
  INCISE_CHECK_PARAM(options.restart_reduction > 0.0 && options.restart_reduction < 1.0,
                     "dynamic_relaxation: restart_reduction must lie in (0, 1)");
  INCISE_CHECK_PARAM(options.energy_every >= 1, "dynamic_relaxation: energy_every must be >= 1");
  double dt = options.time_step;
  // 1 at free DOFs, 0 at fixed ones (Problem::project: P zeroes the fixed components).
  VecX free = VecX::Ones(n);
  problem.project(free);
  // 1/((1 + ½Δtη) m_i) at free DOFs: the diagonal of (M + θ₁Δt C)⁻¹ of (2.58) with θ₁ = ½,
  // θ₂ = 0, times P — so ü = −P(∇Π(ū) + ηMu̇)/((1 + ½Δtη)M) takes the projection on the way.
  VecX inv_mass;
  const auto set_inv_mass = [&] {
    inv_mass = (m * (1.0 + 0.5 * dt * eta)).cwiseInverse().cwiseProduct(free);
  };
  set_inv_mass();
  const bool restartable = options.max_restarts > 0;
  const bool check_energy = restartable && eta > 0.0;

  // Quadratic Π (Problem::energy_is_quadratic): ∇Π(ū_k) = ∇Π(ū_{k−1}) + K(ū_k − ū_{k−1}) and
  // Π(ū_k) = Π(ū_{k−1}) + ∇Π(ū_{k−1})ᵀΔ + ½ΔᵀKΔ, one K·Δ per step instead of a gradient and
  // energy sweep (a K-product is the cheaper evaluation: an assembled K, or the linear model's
  // matrix-free product, which skips the kinematics). As nonlinear_cg's recurrence: evaluated
  // every kReplaceEvery steps, after a restart, and whenever the recurrence residual meets the
  // stopping rule, so convergence is certified on an evaluated gradient.
  const bool quadratic = options.gradient_recurrence && problem.energy_is_quadratic();
  constexpr long kReplaceEvery = 50;
  long since_evaluated = 0;
  bool have_previous = false;  // last_good, g and energy hold the previous step's ū, ∇Π, Π
  VecX delta, k_delta;

  VecX v = VecX::Zero(n), ubar = u, g, last_good = u;
  double mv2 = 0.0;        // u̇ᵀMu̇ of the current u̇ (summed by the update pass; 0 at rest)
  VecX u_best = u;         // displacement of lowest total energy: where a restart resumes (at rest)
  VecX u_next;             // the update pass' output buffer (then swapped into u)
  bool best_is_u = false;  // this step's u is the new u_best: the update pass swaps it there
  double energy = 0.0, last_energy = 0.0, rnorm = 0.0, threshold = 0.0;
  double e_start = 0.0,
         e_min = 0.0;       // E at the run's first step, lowest E since the last (re)start
  bool have_e = false;      // e_min is set (false at the start and after a restart)
  bool have_start = false;  // e_start is set (once per run)
  long k = 0;
  double t = 0.0;  // simulated time of u: Σ Δt over the steps taken (IterationInfo::time)
  StopReason reason = StopReason::kConverged;
  std::string event;  // what made the last restart necessary
  bool have_residual = false;
  // ū of the next step, computed by the update pass of the step before (the same operations as
  // (2.56) on the updated u and u̇; false at the start and after a restart).
  bool ubar_ready = false;
  // Π on every options.energy_every-th step only (the others: gradient-only sweeps, energy NaN).
  constexpr double kNoEnergy = std::numeric_limits<double>::quiet_NaN();
  long since_energy = 0;              // steps since the last one that evaluated Π
  bool last_good_has_energy = false;  // `energy` belongs to last_good
  // An unstable step: restart from the lowest-energy state with a smaller Δt when allowed.
  bool restarts_used_up = false;  // the run ended because an unstable step found none left
  auto restart = [&](StopReason why, const std::string& what) {
    reason = why;
    event = what;
    if (rep.restarts >= options.max_restarts) {
      restarts_used_up = true;
      return false;
    }
    ++rep.restarts;
    dt *= options.restart_reduction;
    set_inv_mass();
    // Resume at rest from the lowest-energy state: from rest the total energy of a stable damped
    // run only decreases, as at the start (with the old velocity, Π at ū = u + ½Δt·u̇ and the
    // kinetic energy at u̇ can move E up by O(Δt) and fake energy growth).
    u = u_best;
    best_is_u = false;
    v.setZero();
    mv2 = 0.0;
    have_e = false;
    have_previous = false;  // E at the new Δt is measured afresh from the resumed state
    ubar_ready = false;
    meter.add(4 * nn);
    return true;
  };
  double unorm = 0.0;  // ‖u‖ after the update pass (the blow-up test)
  while (true) {
    if (!ubar_ready) ubar = u + (0.5 * dt) * v;  // (2.56), θ₁ = ½
    ubar_ready = false;
    bool recurrence = false;
    if (quadratic && have_previous && since_evaluated < kReplaceEvery) {
      delta = ubar - last_good;
      if (problem.hessian_product(ubar, delta, k_delta) == EvalStatus::kOk) {
        const double e_next = energy + g.dot(delta) + 0.5 * delta.dot(k_delta);
        meter.add(7 * nn);
        if (std::isfinite(e_next)) {
          g += k_delta;
          energy = e_next;
          recurrence = g.allFinite();
        }
      }
      ++rep.inner_iterations;
    }
    EvalStatus st = EvalStatus::kOk;
    bool has_energy = true;  // Π(ū) of this step is known
    if (!recurrence) {
      const bool want_energy = quadratic || options.energy_every <= 1 || k == 0 ||
                               (restartable && !have_e) || since_energy + 1 >= options.energy_every;
      if (want_energy) {
        st = problem.gradient(ubar, g, &energy);
      } else {
        st = problem.gradient(ubar, g);
        energy = kNoEnergy;
      }
      has_energy = want_energy;
      since_evaluated = 0;
    } else {
      ++since_evaluated;
    }
    since_energy = has_energy ? 0 : since_energy + 1;
    // ‖P∇Π(ū)‖² and the finiteness of ∇Π(ū) in one pass (g is not changed before its use).
    double rnorm2 = 0.0;
    if (st != EvalStatus::kOk || !free_norm2_if_finite(g, free, rnorm2) ||
        (has_energy && !std::isfinite(energy))) {
      const StopReason why =
          st == EvalStatus::kInverted ? StopReason::kInverted : StopReason::kNonFinite;
      if (restart(why, why == StopReason::kInverted ? "inverted element" : "non-finite value"))
        continue;
      break;
    }
    if (restartable && has_energy) {
      // Total energy at ū (kinetic from u̇ of this step, u̇ᵀMu̇ summed by the last update pass).
      const double e = energy + 0.5 * mv2;
      if (!have_e) {
        // The run's first E is the scale of the check for good; after a restart E is measured
        // afresh from the resumed state (e_min), against the energy dissipated since the start of
        // the run: from rest at u_best, E is not monotone (a wiggle of order Δtω times the energy
        // of a mode ω: O(1) for high modes near the stability limit) and one step's wiggle exceeded
        // half of the little dissipated since the restart, a false restart every few steps
        // (docs/solvers.md, "Restarts").
        if (!have_start) e_start = e;
        have_start = true;
        e_min = e;
        have_e = true;
      }
      if (check_energy && e > e_min + 0.5 * (e_start - e_min) +
                                  1e-9 * std::max(std::abs(e_start), std::abs(e_min))) {
        if (restart(StopReason::kUnstable, "energy growth")) continue;
        break;
      }
      if (e <= e_min) {
        e_min = e;
        best_is_u = true;  // u_best = u, by the update pass below (no copy)
        meter.add(nn);
      }
    }
    meter.add(5 * nn);          // the residual pass
    rnorm = std::sqrt(rnorm2);  // ‖r‖, r = −P∇Π(ū)
    threshold = residual_threshold(options.stop, fex, fixed_dofs.norm(g), n);
    if (recurrence && rnorm <= threshold) {
      // Certify on an evaluated gradient at the same ū (the recurrence's may have drifted).
      const EvalStatus se = problem.gradient(ubar, g, &energy);
      since_evaluated = 0;
      if (se != EvalStatus::kOk || !g.allFinite() || !std::isfinite(energy)) {
        reason = failure_reason(se == EvalStatus::kOk ? EvalStatus::kNonFinite : se);
        break;
      }
      (void)free_norm2_if_finite(g, free, rnorm2);  // finite: tested above
      meter.add(5 * nn);
      rnorm = std::sqrt(rnorm2);
      threshold = residual_threshold(options.stop, fex, fixed_dofs.norm(g), n);
    }
    if (!has_energy && rnorm <= threshold) {  // the converged point carries Π
      has_energy = problem.energy(ubar, energy) == EvalStatus::kOk && std::isfinite(energy);
      if (!has_energy) energy = kNoEnergy;
    }
    last_good.swap(ubar);  // ū of this step (ubar is rewritten before its next use)
    have_previous = true;
    last_good_has_energy = has_energy;
    if (has_energy) last_energy = energy;
    have_residual = true;
    rep.residual_history.push_back(rnorm);
    rep.energy_history.push_back(energy);
    if (k > 0)
      meter.observe(options.observer,
                    IterationInfo{k, &last_good, rnorm, energy, 0, 0.0, 0.0, t + 0.5 * dt});
    if (rnorm <= threshold) {
      reason = StopReason::kConverged;
      break;
    }
    reason = meter.exhausted(options.budget, k);
    if (reason != StopReason::kConverged) break;
    // a = (−∇Π(ū) − ηMv) ⊙ P(M + ½ΔtηM)⁻¹ (the projection is in inv_mass: 0 at fixed DOFs, and
    // v stays 0 there), then u += Δt v + ½Δt² a (2.59) and v += Δt a (2.60), in one pass; each
    // entry is computed with the operations, in the order, of the former separate vector
    // expressions (same bits). The same pass forms the next step's ū = u + ½Δt u̇ (2.56), with
    // (2.56)'s operations, ‖u‖² (the blow-up test) and u̇ᵀMu̇ (the next step's kinetic energy).
    {
      u_next.resize(n);
      ubar.resize(n);
      const UpdateSums sums = ss22_update(n, g.data(), m.data(), inv_mass.data(), u.data(),
                                          u_next.data(), v.data(), ubar.data(), eta, dt);
      unorm = std::sqrt(sums.u2);
      mv2 = sums.mv2;
      // u_best = u without a copy when this step's u is the new best: its buffer becomes
      // u_best's; then the new u takes over (u_next keeps a spare buffer).
      if (best_is_u) {
        u.swap(u_best);
        best_is_u = false;
      }
      u.swap(u_next);
    }
    ubar_ready = true;
    meter.add(20 * nn);
    ++k;
    t += dt;
    if (!std::isfinite(unorm) || unorm > options.blowup_norm) {
      if (restart(StopReason::kUnstable, "blow-up")) continue;
      break;
    }
  }
  // Hand back the last evaluated admissible point: its residual is the one reported, and its
  // energy (evaluated now when its step skipped Π).
  u = last_good;
  if (have_residual && !last_good_has_energy) {
    double e = 0.0;
    if (problem.energy(last_good, e) == EvalStatus::kOk && std::isfinite(e)) last_energy = e;
  }
  rep.status = reason;
  rep.time_step = dt;
  if (!rep.ok() && restartable && !event.empty()) {
    // Either the restarts ran out (the status is the last event's), or the run stopped for
    // another reason (a budget) after restarts on the way.
    std::ostringstream os;
    if (restarts_used_up)
      os << event << " after " << rep.restarts << " restart(s) (the allowed "
         << options.max_restarts << ")";
    else
      os << rep.restarts << " restart(s) on the way (the last after " << event << ")";
    os << ", dt lowered from " << options.time_step << " s to " << dt << " s";
    rep.message = os.str();
  }
  rep.iterations = k;
  rep.residual_norm = have_residual ? rnorm : std::numeric_limits<double>::quiet_NaN();
  rep.threshold = threshold;
  rep.energy = last_energy;
  meter.record(rep);
  return rep;
}

double damping_ratio_for(double overshoot) {
  INCISE_CHECK_PARAM(overshoot >= 0.0 && overshoot < 1.0,
                     "damping_ratio_for: overshoot must lie in [0, 1)");
  if (overshoot == 0.0) return 1.0;  // critical damping (§4.1)
  // exp(−πζ/√(1 − ζ²)) = o  ⇔  ζ² (π² + L²) = L²,  L = ln(1/o)
  const double l = -std::log(overshoot);
  const double pi = 3.14159265358979323846;
  return l / std::sqrt(pi * pi + l * l);
}

DynamicParameterEstimate estimate_dynamic_parameters(Problem& problem, const VecX& u,
                                                     const DynamicParameterOptions& options) {
  // Below 1: at Δt = 2/√θ_max the scheme's top mode is undamped for every η ((2.58) with
  // θ₂ = 0 is stable only for Δt < 2/√λ_n), and θ_max ≤ λ_n puts that Δt at or above λ_n's.
  INCISE_CHECK_PARAM(options.time_step_safety > 0.0 && options.time_step_safety < 1.0,
                     "estimate_dynamic_parameters: time_step_safety must lie in (0, 1): at 1 the "
                     "step is at or above the critical step 2/sqrt(lambda_n) (sec. 4.1)");
  DynamicParameterEstimate out;
  INCISE_CHECK_PARAM(options.target_reduction >= 0.0 && options.target_reduction < 1.0,
                     "estimate_dynamic_parameters: target_reduction must lie in [0, 1)");
  out.damping_ratio = damping_ratio_for(0.5 * options.target_reduction);
  CostMeter meter(problem);
  const VecX& m = problem.lumped_mass();
  INCISE_CHECK(m.size() == problem.size(), "estimate_dynamic_parameters needs lumped masses");
  VecX g;
  const EvalStatus st = problem.gradient(u, g);
  if (st != EvalStatus::kOk || !g.allFinite()) {
    out.status = failure_reason(st);
    out.message = "gradient at the start state not admissible";
    out.flops = meter.flops();
    return out;
  }
  VecX a = -g;
  problem.project(a);
  a = a.cwiseQuotient(m);  // first acceleration of SS22 from rest
  const SpectrumEstimate sp = lanczos_spectrum(problem, u, a, options.lanczos);
  out.status = sp.status;
  out.message = sp.message;
  out.products = sp.steps;
  out.flops = meter.flops();
  // Steps used up with θ_max settled (the top of the spectrum converges first, θ₁ slowly: κ ≈
  // 1e6 on a slender beam): the bounds are usable, Δt from θ_max ≤ λ_n (a too large Δt restarts,
  // DynamicRelaxationOptions::max_restarts) and η from θ₁ ≥ λ₁ (over-damps by √(θ₁/λ₁) at most);
  // the status stays kMaxIterations and the message says so (docs/solvers.md, "Restarts").
  const bool bounds = sp.status == StopReason::kMaxIterations && sp.largest_settled;
  if (!(sp.ok() || bounds) || !(sp.smallest > 0.0) || !(sp.largest > 0.0)) {
    if (out.ok()) out.status = StopReason::kIndefinite;
    return out;
  }
  if (bounds) {
    std::ostringstream os;
    os << "lambda_1 not converged in " << sp.steps << " Lanczos steps";
    if (std::isfinite(sp.smallest_residual))
      os << " (Ritz residual " << sp.smallest_residual << " x theta_1)";
    os << "; dt from the settled lambda_max, eta from theta_1 = " << sp.smallest
       << " >= lambda_1, an upper bound: eta over-damps by sqrt(theta_1/lambda_1)";
    out.message = os.str();
  }
  out.lambda_min = sp.smallest;
  out.lambda_max = sp.largest;
  out.time_step = options.time_step_safety * critical_time_step(sp.largest);
  // ζ < 1: the slowest mode of (4.2) from rest settles within ε at its first zero crossing
  // instead of creeping in as (1 + x)e^{−x} (damping_ratio_for; docs/solvers.md, "Eighth pass").
  out.damping = out.damping_ratio * critical_damping(sp.smallest);
  return out;
}

double cfl_time_step(double h, double lame_lambda, double lame_mu, double density) {
  INCISE_CHECK_PARAM(h > 0.0 && density > 0.0 && lame_lambda + 2.0 * lame_mu > 0.0,
                     "cfl_time_step: h, density and λ + 2µ must be positive");
  const double c = std::sqrt((lame_lambda + 2.0 * lame_mu) / density);
  return 2.0 / std::sqrt(3.0) * h / c;  // (2.61)
}

StableTimeStep find_stable_time_step(Problem& problem, const VecX& u, double initial,
                                     const StableTimeStepOptions& options) {
  INCISE_CHECK_PARAM(initial > 0.0, "find_stable_time_step: initial time step must be positive");
  INCISE_CHECK_PARAM(options.reduction > 0.0 && options.reduction < 1.0,
                     "find_stable_time_step: reduction must lie in (0, 1)");
  StableTimeStep out;
  double dt = initial;
  for (int i = 0; i <= options.max_reductions; ++i) {
    DynamicRelaxationOptions o;
    o.time_step = dt;
    o.damping = 0.0;
    o.stop.rule = ResidualRule::kExternalForce;
    o.stop.epsilon = 0.0;  // never "converges": the run must survive the budget
    o.budget.max_flops = options.flop_budget;
    o.budget.max_iterations = options.max_steps;
    o.blowup_norm = options.blowup_norm;
    VecX w = u;
    const SolverReport rep = dynamic_relaxation(problem, w, o);
    out.flops += rep.flops;
    if (rep.status == StopReason::kFlopBudget || rep.status == StopReason::kMaxIterations ||
        rep.status == StopReason::kConverged) {
      out.time_step = dt;
      out.reductions = i;
      out.found = true;
      return out;
    }
    dt *= options.reduction;
  }
  out.reductions = options.max_reductions;
  return out;
}

DampingSweep sweep_damping(Problem& problem, const VecX& u, const std::vector<double>& etas,
                           const DynamicRelaxationOptions& options) {
  DampingSweep sweep;
  for (double eta : etas) {
    DynamicRelaxationOptions o = options;
    o.damping = eta;
    VecX w = u;
    const SolverReport rep = dynamic_relaxation(problem, w, o);
    DampingTrial trial;
    trial.status = rep.status;
    trial.damping = eta;
    trial.iterations = rep.iterations;
    trial.flops = rep.flops;
    sweep.trials.push_back(trial);
    if (rep.ok() && (sweep.best_iterations == 0 || rep.iterations < sweep.best_iterations)) {
      sweep.best_damping = eta;
      sweep.best_iterations = rep.iterations;
    }
  }
  return sweep;
}

SpectralDamping damping_from_spectrum(Problem& problem, const VecX& u, double time_step,
                                      long steps) {
  INCISE_CHECK_PARAM(steps >= 16, "damping_from_spectrum: need at least 16 steps");
  SpectralDamping out;
  VecX g;
  if (problem.gradient(u, g) != EvalStatus::kOk || !g.allFinite()) {
    out.status = StopReason::kNonFinite;
    return out;
  }
  VecX dir = -g;
  problem.project(dir);
  const double dn = dir.norm();
  if (!(dn > 0.0)) {
    out.status = StopReason::kConverged;  // already in equilibrium: nothing oscillates
    return out;
  }
  dir /= dn;
  std::vector<double> samples;
  samples.reserve(static_cast<std::size_t>(steps));
  DynamicRelaxationOptions o;
  o.time_step = time_step;
  o.damping = 0.0;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 0.0;
  o.budget.max_iterations = steps;
  o.observer = [&](const IterationInfo& info) { samples.push_back((*info.u - u).dot(dir)); };
  VecX w = u;
  const SolverReport rep = dynamic_relaxation(problem, w, o);
  out.status = rep.status;
  out.steps = rep.iterations;
  out.flops = rep.flops;
  if (rep.status != StopReason::kMaxIterations || samples.size() < 16) return out;
  const spectral::FrequencyEstimate f = spectral::dominant_frequency(samples, time_step);
  out.frequency = f.frequency;
  out.resolution = f.resolution;
  const double pi = 3.14159265358979323846;
  out.damping = 4.0 * pi * f.frequency;
  return out;
}

}  // namespace incise::solver
