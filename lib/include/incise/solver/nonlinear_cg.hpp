#pragma once
/// \file nonlinear_cg.hpp
/// Nonlinear conjugate gradients (thesis §2.4.2) with the line searches of §4.4.2: Newton,
/// secant (4.9) and scale-dependent secant.

#include <incise/core/name_table.hpp>
#include <incise/solver/report.hpp>

namespace incise::solver {

/// β selection of the nonlinear CG search direction d_k = r_k + β_k d_{k−1}.
enum class BetaRule {
  kFletcherReeves,  ///< β = ‖r_k‖²/‖r_{k−1}‖² — (2.48) (the extracted text drops the square)
  kPolakRibiere  ///< β = max{0, r_kᵀ(r_k − r_{k−1})/‖r_{k−1}‖²} — (2.49)
};

/// Line search of §4.4.2 for the 1-D equation g(α) = (∇Π(x + αd), d) = 0.
enum class LineSearchKind {
  kNewton,                ///< α ← α − g/g′ with g′ = (d, K(x+αd) d): one K·d per step
  kSecant,                ///< g′ by the secant (4.9); K·d only in the first step
  kScaleDependentSecant,  ///< secant also in the first step, from a gradient at α₋₁ (§4.4.2)
  kSecantWarmStart        ///< secant from a guessed first step (no K·d after the first iteration)
};

/// Names of the β rules.
inline constexpr NameTable<BetaRule, 2> kBetaRuleNames{{{
    {BetaRule::kFletcherReeves, "fletcher-reeves"},
    {BetaRule::kPolakRibiere, "polak-ribiere"},
}}};

/// Names of the line searches.
inline constexpr NameTable<LineSearchKind, 4> kLineSearchNames{{{
    {LineSearchKind::kNewton, "newton"},
    {LineSearchKind::kSecant, "secant"},
    {LineSearchKind::kScaleDependentSecant, "scale-dependent-secant"},
    {LineSearchKind::kSecantWarmStart, "secant-warm-start"},
}}};

/// Names from kBetaRuleNames, kLineSearchNames.
const char* to_string(BetaRule b);
const char* to_string(LineSearchKind l);

/// Options of nonlinear_cg(). Defaults are the thesis' choice for §4.5 (secant, Polak-Ribière,
/// ε_newton = 0.1). From RelaxationOptions: `budget` counts outer iterations, `observer` is
/// called after every outer iteration.
struct NonlinearCgOptions : RelaxationOptions {
  BetaRule beta = BetaRule::kPolakRibiere;  ///< (2.48) or (2.49)
  LineSearchKind line_search = LineSearchKind::kSecant;
  double epsilon_newton = 0.1;  ///< stop the line search when |δ_j| < ε_newton |δ_0| (j > 0)
  int j_max = 8;                ///< at most j_max line-search updates per outer iteration
  /// kSecantWarmStart: a guessed first trial α_g is kept when the secant step from it is below
  /// epsilon_warm_start·|α_g + step| (the secant's estimate of the minimizer); otherwise the
  /// search continues with the ε_newton test. 0.02: issue 19's Veronda–Westmann cube needed
  /// 1,439 iterations to 1e-6 at 0.02 against 1,412 for the secant search, 1,869 at 0.05 and
  /// 2,603 at 0.1 (docs/solvers.md).
  double epsilon_warm_start = 0.02;
  /// α₋₁ of the scale-dependent secant (units of α: metres per unit of d; the thesis used
  /// −0.001 for its cylinder, §4.5.1). Scale-dependent by nature.
  double alpha_minus1 = -1e-3;
  /// Bracket safeguard of the ε_newton test (not in the thesis): when that test would end the
  /// search at α_j with |γ_j| > bracket_sigma·γ₀ (the directional derivative reduced by less
  /// than 1 − bracket_sigma) and a trial beyond the root is known (γ ≤ 0, or Π = +∞), the next
  /// trial is the bisection of that bracket instead; the search goes on up to j_max. 0.9: the
  /// curvature constant of the weak Wolfe condition for Newton-like steps (Nocedal & Wright
  /// §3.1); it only catches a search that made no progress (docs/solvers.md). 0 disables it
  /// (the thesis' search; then the cylinder at 100–1000 g stalls, test
  /// NonlinearCgBracket.ThesisSearchStallsOnTheCylinder_Sec4_4_2).
  double bracket_sigma = 0.9;
  long restart_every = 0;   ///< restart d = r every this many steps; 0: every n steps
  int max_backtracks = 30;  ///< halvings of a trial step that lands on Π = +∞ (inverted)
};

/// Minimizes Π from the given u (updated in place). Each outer iteration: choose d (restart to
/// d = r when d is not a descent direction, every restart_every steps, when PR gives β = 0, or
/// when the curvature along a conjugate d is not positive at α = 0),
/// run the line search (the gradient at the accepted α is reused as the next residual, as the
/// thesis does), update β. A trial step into Π = +∞ is halved towards the last admissible α
/// (never accepted); a search that would stop without reducing the directional derivative
/// while the root is bracketed bisects the bracket (bracket_sigma). Reports kIndefinite when the
/// curvature along d = r is not positive at α = 0, kInverted when no admissible α > 0 was found
/// (every trial inverted), kStagnated when α = 0; each with a message naming the iteration, the
/// direction and (kIndefinite) the curvature. For a quadratic Π (Problem::energy_is_quadratic())
/// with the secant or Newton search, each iteration takes one K·d: α = γ₀/(d, Kd) (the step both
/// searches accept) and the gradient and energy at x + αd by the recurrence g + αKd, evaluated
/// instead every 50 iterations and whenever the recurrence residual meets the stopping rule (so
/// convergence is certified on an evaluated gradient). Iterates differ from the evaluating search
/// by round-off only (test NonlinearCgQuadratic.RecurrenceMatchesEvaluatedSearch_Sec2_4_2).
SolverReport nonlinear_cg(Problem& problem, VecX& u, const NonlinearCgOptions& options);

}  // namespace incise::solver
