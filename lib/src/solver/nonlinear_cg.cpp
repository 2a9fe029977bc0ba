#include <incise/solver/nonlinear_cg.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace incise::solver {

const char* to_string(BetaRule b) {
  return kBetaRuleNames.name(b);
}

const char* to_string(LineSearchKind l) {
  return kLineSearchNames.name(l);
}

namespace {

struct LineSearchResult {
  StopReason status = StopReason::kConverged;  // kConverged: an admissible α was found
  double alpha = 0.0;
  int evaluations = 0;
  bool recurrence = false;  // g_out, e_out from the quadratic recurrence, not evaluated
  double curvature = 0.0;   // kIndefinite / kNonFinite at α = 0: the slope estimate c there
};

/// Work vectors of the line search, kept across iterations (no allocation per iteration).
struct LineSearchWork {
  VecX xt, s, gt;
  /// kSecantWarmStart: the last search's accepted α and its γ₀ (α = 0: none yet, the first
  /// step takes one K·d).
  double last_alpha = 0.0, last_gamma0 = 0.0;
};

// §4.4.2: solve g(α) = (∇Π(x+αd), d) = 0 for α, starting at α₀ = 0 where the full gradient g0
// is known. γ(α) = −g(α) = (r(α), d). On success `g_out`/`e_out` hold ∇Π and Π at x + αd (when
// no trial point was accepted, α = 0: g0 and e0). The accepted trial's gradient is swapped into
// g_out, not copied.
LineSearchResult line_search(Problem& problem, const VecX& x, const VecX& d, const VecX& g0,
                             double e0, double gamma0, const NonlinearCgOptions& opt,
                             CostMeter& meter, LineSearchWork& work, VecX& g_out, double& e_out) {
  const auto nn = static_cast<std::uint64_t>(x.size());
  LineSearchResult res;
  VecX& xt = work.xt;
  VecX& s = work.s;
  VecX& gt = work.gt;
  double alpha = 0.0, gamma = gamma0;
  double alpha_prev = 0.0, gamma_prev = gamma0;
  double delta0 = 0.0;
  bool accepted = false;  // g_out holds the gradient at x + αd (else it is set from g0 below)
  e_out = e0;
  // Quadratic Π (Problem::energy_is_quadratic): g(α) is linear, so the first step of the
  // secant and Newton searches, α₁ = γ₀/(d, K d), is the exact minimizer along d, the step
  // after it is round-off (|δ₁| < ε_newton|δ₀|: the search ends there), and the trial
  // gradient and energy follow from K·d: ∇Π(x + αd) = g₀ + αKd, Π = e₀ − αγ₀ + ½α²(d, Kd)
  // (γ₀ = −(g₀, d) for a projected d). One K·d per iteration instead of K·d + gradient (the
  // evaluating search below only when the recurrence overflows); the
  // same α, a gradient that differs from an evaluated one by round-off (nonlinear_cg replaces
  // it by an evaluation periodically and before declaring convergence).
  if (problem.energy_is_quadratic() && opt.line_search != LineSearchKind::kScaleDependentSecant) {
    const EvalStatus st = problem.hessian_product(x, d, s);
    ++res.evaluations;
    meter.add(4 * nn);
    if (st != EvalStatus::kOk || !s.allFinite()) {
      res.status = failure_reason(st);
      return res;
    }
    const double c = d.dot(s);
    if (!std::isfinite(c) || c <= 0.0) {
      res.status = std::isfinite(c) ? StopReason::kIndefinite : StopReason::kNonFinite;
      res.curvature = c;
      return res;
    }
    const double a1 = gamma0 / c;
    g_out = g0 + a1 * s;
    e_out = e0 - a1 * gamma0 + 0.5 * a1 * a1 * c;
    meter.add(2 * nn);
    if (g_out.allFinite() && std::isfinite(e_out)) {
      res.alpha = a1;
      res.recurrence = true;
      if (a1 == 0.0) res.status = StopReason::kStagnated;
      return res;
    }
    e_out = e0;  // overflow in the recurrence: the evaluating search below decides
  }
  // Newton: each trial point's gradient, energy and K·d come from one evaluation
  // (Problem::gradient_energy_product), so s already holds K(x + α_j d)·d for j ≥ 1.
  const bool newton = opt.line_search == LineSearchKind::kNewton;
  bool have_product = false;
  bool warm_start_guessed = false;  // the first trial step was the warm-start guess
  const bool warm = opt.line_search == LineSearchKind::kSecantWarmStart;
  // Bracket of the root of g(α): lo = the largest admissible α with γ > 0 (α₀ = 0, γ₀ > 0);
  // hi = the smallest α > lo known to lie beyond it (an admissible trial with γ ≤ 0, or a
  // trial with Π = +∞); +∞ while none is known.
  double lo = 0.0, hi = std::numeric_limits<double>::infinity();
  for (int j = 0; j < opt.j_max; ++j) {
    double c = 0.0;  // estimate of g′(α_j) = (d, K(x + α_j d) d)
    // Warm start (Nocedal & Wright (3.60)): the first trial α = α_prev·γ₀,prev/γ₀ (the same
    // first-order decrease as the last search), i.e. the slope c = γ₀²/(α_prev·γ₀,prev).
    const double guess_c = warm && j == 0 && work.last_alpha > 0.0
                               ? gamma0 * gamma0 / (work.last_alpha * work.last_gamma0)
                               : 0.0;
    const bool warm_guess = std::isfinite(guess_c) && guess_c > 0.0;
    bool need_product =
        (newton && !have_product) ||
        (j == 0 && (opt.line_search == LineSearchKind::kSecant || warm) && !warm_guess);
    if (j == 0 && opt.line_search == LineSearchKind::kScaleDependentSecant) {
      // Finite-difference curvature from a gradient at α₋₁ (4.9).
      xt = x + opt.alpha_minus1 * d;
      const EvalStatus st = problem.gradient(xt, gt);
      ++res.evaluations;
      meter.add(4 * nn);
      if (st == EvalStatus::kOk && gt.allFinite()) {
        const double gamma_m1 = -gt.dot(d);
        c = (gamma0 - gamma_m1) / opt.alpha_minus1;
      } else {
        need_product = true;  // α₋₁ leaves the domain: fall back to one exact product
      }
    }
    if (need_product) {
      // Only the slope c = (d, K d) is needed (a Newton trial's K·d comes with its gradient
      // below): Problem::hessian_curvature, which an element problem sums without forming
      // K·d (issue 19: no scatter, no global vector; the same c up to rounding).
      if (alpha != 0.0) xt = x + alpha * d;  // at α = 0 the product is taken at x itself
      const EvalStatus st = problem.hessian_curvature(alpha != 0.0 ? xt : x, d, c);
      ++res.evaluations;
      meter.add(alpha != 0.0 ? 2 * nn : 0);
      if (st != EvalStatus::kOk || !std::isfinite(c)) {
        if (j == 0) {
          res.status = failure_reason(st);
          return res;
        }
        break;
      }
    } else if (newton) {
      c = d.dot(s);  // K(x + α_j d)·d from the evaluation at α_j
      meter.add(2 * nn);
    } else if (j > 0) {
      c = -(gamma - gamma_prev) / (alpha - alpha_prev);  // secant (4.9)
    } else if (warm_guess) {
      c = guess_c;
    }
    if (j == 0) warm_start_guessed = warm_guess;
    if (!std::isfinite(c) || c <= 0.0) {
      if (j == 0) {
        res.status = std::isfinite(c) ? StopReason::kIndefinite : StopReason::kNonFinite;
        res.curvature = c;
        return res;
      }
      break;  // keep α_j: the secant lost curvature information
    }
    const double step = gamma / c;  // −δ_j
    bool small_step = false;        // the ε_newton test below fired
    if (j == 0) {
      delta0 = std::abs(step);
    } else if (j == 1 && warm_start_guessed) {
      // The first trial was a guess: δ₀ is the first secant estimate of the minimizer, and
      // the guess is kept when it is within epsilon_warm_start of it.
      delta0 = std::abs(alpha + step);
      if (std::abs(step) < opt.epsilon_warm_start * delta0) break;
    } else if (std::abs(step) < opt.epsilon_newton * delta0) {
      small_step = true;  // |δ_j| < ε_newton |δ_0|: δ_j is not added, r_j is reused
    }
    double alpha_new = alpha + step;
    if (small_step) {
      // Bracket safeguard (not in the thesis): a small δ_j only says the secant converged
      // when its slope describes g near α_j. A trial beyond the root, deep in a stiffening
      // region or halved back from Π = +∞, makes the chord slope (4.9) orders of magnitude
      // steeper than g′(α_j), so δ_j is tiny while γ_j ≈ γ₀ (the Veronda–Westmann cylinder
      // at 1000 g took α ≈ 1e-6 for 20,000 iterations, docs/solvers.md). When the directional
      // derivative has not dropped below bracket_sigma·γ₀ and a point beyond the root is
      // known, bisect the bracket instead of stopping.
      if (!(opt.bracket_sigma > 0.0 && std::abs(gamma) > opt.bracket_sigma * gamma0 &&
            std::isfinite(hi)))
        break;
      alpha_new = 0.5 * (lo + hi);
    }
    bool admissible = false;
    double et = 0.0;
    for (int b = 0; b <= opt.max_backtracks; ++b) {
      xt = x + alpha_new * d;
      const EvalStatus st = newton ? problem.gradient_energy_product(xt, d, gt, et, s)
                                   : problem.gradient(xt, gt, &et);
      ++res.evaluations;
      meter.add(2 * nn);
      if (st == EvalStatus::kOk && gt.allFinite() && std::isfinite(et) &&
          (!newton || s.allFinite())) {
        admissible = true;
        have_product = newton;  // st covers K·d too (a non-finite one backtracks)
        break;
      }
      if (alpha_new > lo) hi = std::min(hi, alpha_new);  // Π = +∞ here: beyond the root
      alpha_new = alpha + 0.5 * (alpha_new - alpha);     // backtrack towards the admissible α_j
    }
    if (!admissible) {
      if (j == 0) {
        res.status = StopReason::kInverted;
        return res;
      }
      break;
    }
    alpha_prev = alpha;
    gamma_prev = gamma;
    alpha = alpha_new;
    g_out.swap(gt);
    accepted = true;
    e_out = et;
    gamma = -g_out.dot(d);
    if (alpha > lo && alpha < hi) {
      if (gamma > 0.0)
        lo = alpha;
      else
        hi = std::min(hi, alpha);
    }
    meter.add(2 * nn);
  }
  if (!accepted) g_out = g0;
  work.last_alpha = alpha;
  work.last_gamma0 = gamma0;
  res.alpha = alpha;
  if (alpha == 0.0) res.status = StopReason::kStagnated;
  return res;
}

// SolverReport::message for a run the line search ended (iteration k, 1-based; `steepest`: d
// was r, a restart).
std::string line_search_message(const LineSearchResult& ls, long k, bool steepest,
                                const NonlinearCgOptions& opt) {
  std::ostringstream os;
  os << "iteration " << k << ", line search along "
     << (steepest ? "d = r (steepest descent)" : "the conjugate direction d") << ": ";
  if (ls.status == StopReason::kIndefinite) {
    os << "curvature along d at alpha = 0 is " << ls.curvature
       << " <= 0: the energy is not convex along d at u; truncated Newton "
          "(scene method \"newton\") handles negative curvature, or apply the load in smaller "
          "steps";
  } else if (ls.status == StopReason::kInverted) {
    os << "every trial step, halved " << opt.max_backtracks
       << " times, inverts an element (its energy is not finite): u is at the edge of the "
          "admissible set";
  } else if (ls.status == StopReason::kStagnated) {
    os << "no step length alpha > 0 was accepted (alpha = 0); u is the last iterate";
  } else {
    os << "a non-finite curvature, gradient or energy";
  }
  return os.str();
}

}  // namespace

SolverReport nonlinear_cg(Problem& problem, VecX& u, const NonlinearCgOptions& options) {
  INCISE_CHECK(u.size() == problem.size(), "nonlinear_cg: u has the wrong size");
  INCISE_CHECK_PARAM(options.j_max >= 1, "nonlinear_cg: j_max must be at least 1");
  INCISE_CHECK_PARAM(options.epsilon_newton >= 0.0, "nonlinear_cg: epsilon_newton < 0");
  INCISE_CHECK_PARAM(options.epsilon_warm_start >= 0.0, "nonlinear_cg: epsilon_warm_start < 0");
  INCISE_CHECK_PARAM(options.bracket_sigma >= 0.0 && options.bracket_sigma < 1.0,
                     "nonlinear_cg: bracket_sigma must be in [0, 1)");
  INCISE_CHECK_PARAM(options.alpha_minus1 != 0.0, "nonlinear_cg: alpha_minus1 must be non-zero");
  SolverReport rep;
  CostMeter meter(problem);
  const FixedDofs fixed_dofs(problem);
  const Eigen::Index n = u.size();
  const auto nn = static_cast<std::uint64_t>(n);
  const long restart_every = options.restart_every > 0 ? options.restart_every : long(n);
  GradientStart start;
  if (!start_from_gradient(problem, u, options.stop, fixed_dofs, meter, rep, start)) return rep;
  const double fex = start.fex;
  VecX& g = start.g;
  VecX& r = start.r;
  double energy = start.energy;
  double threshold = start.threshold;
  VecX d = r;
  double rr = r.squaredNorm();
  double rnorm = std::sqrt(rr);

  long k = 0, since_restart = 0, since_evaluated = 0;
  constexpr long kReplaceEvery = 50;  // quadratic Π: recurrence steps between evaluated gradients
  StopReason reason = StopReason::kConverged;
  VecX g_new, r_new;
  LineSearchWork work;
  while (true) {
    if (rnorm <= threshold) {
      reason = StopReason::kConverged;
      break;
    }
    reason = meter.exhausted(options.budget, k);
    if (reason != StopReason::kConverged) break;

    double gamma0 = r.dot(d);
    if (!(gamma0 > 0.0) || since_restart >= restart_every) {
      d = r;  // restart with steepest descent
      gamma0 = rr;
      since_restart = 0;
    }
    double e_new = energy;
    LineSearchResult ls =
        line_search(problem, u, d, g, energy, gamma0, options, meter, work, g_new, e_new);
    rep.inner_iterations += ls.evaluations;
    if (ls.status == StopReason::kIndefinite && since_restart != 0) {
      // (d, K d) ≤ 0 along a conjugate direction: restart with steepest descent, as for a d that
      // is not a descent direction; only negative curvature along d = r ends the run.
      d = r;
      gamma0 = rr;
      since_restart = 0;
      e_new = energy;
      ls = line_search(problem, u, d, g, energy, gamma0, options, meter, work, g_new, e_new);
      rep.inner_iterations += ls.evaluations;
    }
    if (ls.status != StopReason::kConverged) {
      reason = ls.status;
      rep.message = line_search_message(ls, k + 1, since_restart == 0, options);
      break;
    }
    u += ls.alpha * d;
    g.swap(g_new);
    energy = e_new;
    r_new = -g;
    problem.project(r_new);
    double rr_new = r_new.squaredNorm();
    if (ls.recurrence) {
      // Gradient replacement (as CG's residual replacement): every kReplaceEvery recurrence
      // steps, and whenever the recurrence residual meets the stopping rule, the gradient and
      // energy are evaluated at u, so round-off drift can neither fake convergence nor grow.
      ++since_evaluated;
      if (since_evaluated >= kReplaceEvery ||
          std::sqrt(rr_new) <= residual_threshold(options.stop, fex, fixed_dofs.norm(g), n)) {
        const EvalStatus st = problem.gradient(u, g, &energy);
        ++rep.inner_iterations;
        since_evaluated = 0;
        if (st != EvalStatus::kOk || !g.allFinite()) {
          reason = failure_reason(st);
          break;
        }
        r_new = -g;
        problem.project(r_new);
        rr_new = r_new.squaredNorm();
        meter.add(2 * nn);
      }
    }
    double beta = 0.0;
    if (options.beta == BetaRule::kFletcherReeves)
      beta = rr_new / rr;  // (2.48)
    else
      beta = std::max(0.0, (rr_new - r_new.dot(r)) / rr);  // (2.49)
    r.swap(r_new);
    rr = rr_new;
    rnorm = std::sqrt(rr);
    d = r + beta * d;
    ++since_restart;
    if (beta == 0.0) since_restart = 0;  // PR reset = steepest descent restart
    threshold = residual_threshold(options.stop, fex, fixed_dofs.norm(g), n);
    meter.add(12 * nn);
    ++k;
    rep.residual_history.push_back(rnorm);
    rep.energy_history.push_back(energy);
    meter.observe(options.observer, IterationInfo{k, &u, rnorm, energy, 0, 0.0});
    if (!std::isfinite(rnorm) || !std::isfinite(beta)) {
      reason = StopReason::kNonFinite;
      break;
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

}  // namespace incise::solver
