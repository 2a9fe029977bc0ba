#pragma once
/// \file truncated_newton.hpp
/// Truncated Newton (Newton-Raphson with an inner linear CG, thesis §2.4.3), safeguarded, used to
/// compute the reference solutions of §4.2 (‖r‖ ≤ 1e-8 ‖f_ex‖; 1e-12 for the linear model).

#include <incise/solver/linear_cg.hpp>
#include <incise/solver/report.hpp>

namespace incise::solver {

/// Options of truncated_newton(). From RelaxationOptions: `stop` is the outer rule (for
/// reference solutions ε = 1e-8 with (6.8)), `budget` counts Newton steps, `observer` is called
/// after every Newton step.
struct TruncatedNewtonOptions : RelaxationOptions {
  long max_inner = 0;  ///< inner CG steps per Newton step; 0: n
  /// Inner tolerance ‖K p − r‖ ≤ η_k‖r‖ with η_k = min(forcing_max, √(‖r‖/‖r₀‖)) (a standard
  /// Eisenstat–Walker-type forcing term; the thesis only says "low tolerances can be used").
  double forcing_max = 0.5;
  Preconditioner preconditioner = Preconditioner::kJacobi;  ///< inner CG preconditioner
  int max_backtracks = 40;  ///< step halvings (inverted trial points or energy increase)
};

/// Minimizes Π from u (updated in place). Newton step p from K(u) p = r by projected CG; when
/// the inner CG meets non-positive curvature it stops there (truncation) and, if no step was
/// built yet, uses the (Jacobi-scaled) steepest-descent direction instead. The step αp starts at
/// α = 1 and is halved while Π(u + αp) = +∞ (inverted elements: never accepted) or while neither
/// the energy decreases (Armijo, c = 1e-4) nor — once energies agree to round-off — the
/// residual decreases. Reports kIndefinite if the steepest-descent fallback has no scale,
/// kLineSearchFailed if halving is exhausted. With kJacobi (the default) the diagonal is taken
/// at every Newton step; one that jacobi_inverse_diagonal() rejects (a free K_ii ≤ 0: kIndefinite,
/// non-finite, unavailable) ends the run there with its status and message naming the step.
SolverReport truncated_newton(Problem& problem, VecX& u, const TruncatedNewtonOptions& options);

}  // namespace incise::solver
