#pragma once
/// \file linear_cg.hpp
/// Matrix-free linear conjugate gradients (thesis §2.4.1, pseudo code after (2.42); §3.1 for the
/// fixed-DOF handling by zeroing the constrained residual) and its Jacobi-preconditioned variant
/// (the E Eᵀ = diag K preconditioner of §2.4.1 / §4.6).

#include <incise/core/name_table.hpp>
#include <incise/core/outcome.hpp>
#include <incise/solver/report.hpp>

#include <functional>
#include <vector>

namespace incise::solver {

/// Preconditioner of the CG iterations.
enum class Preconditioner {
  kNone,   ///< plain CG (the thesis' choice)
  kJacobi  ///< diagonal scaling by diag K(u) (Problem::hessian_diagonal); a diagonal that is
           ///< unavailable, non-finite or ≤ 0 at a free DOF stops the solver with the status of
           ///< jacobi_inverse_diagonal() (never a silent switch to kNone)
};

/// Names of the preconditioners (scene key `preconditioner`, docs/scenes.md).
inline constexpr NameTable<Preconditioner, 2> kPreconditionerNames{{{
    {Preconditioner::kNone, "none"},
    {Preconditioner::kJacobi, "jacobi"},
}}};

/// Name from kPreconditionerNames.
inline const char* to_string(Preconditioner p) {
  return kPreconditionerNames.name(p);
}

/// The step lengths α_k and direction updates β_k of a CG run, from which the Lanczos
/// tridiagonal matrix of the (preconditioned) operator follows (Saad, Iterative Methods §6.7.3):
/// T_jj = 1/α_j + β_{j−1}/α_{j−1}, T_{j,j+1} = √β_j/α_j. See cg_lanczos_extremes().
struct CgCoefficients {
  std::vector<double> alpha;  ///< α_k = (r_k, z_k)/(d_k, K d_k), one per completed step
  std::vector<double> beta;   ///< β_k = (r_{k+1}, z_{k+1})/(r_k, z_k), one per completed step
};

/// Options of linear_cg(). From RelaxationOptions: `budget` counts CG steps, `observer` is
/// called after every CG step with the current u.
struct LinearCgOptions : RelaxationOptions {
  Preconditioner preconditioner = Preconditioner::kNone;
  /// Confirm convergence on the true gradient (the recursive residual r_{k+1} = r_k − α K d
  /// drifts from f − K u in floating point): when the recursive residual meets the rule but the
  /// true one does not, CG restarts from u on the true residual (residual replacement); a
  /// replacement that does not lower the true residual ends the run as kStagnated. The reported
  /// residual is always the true one. false: trust the recursive residual (no extra gradient).
  bool recompute_residual = true;
  /// When non-null, cleared and filled with α_k, β_k of every step (for condition estimates).
  CgCoefficients* coefficients = nullptr;
  /// When set, the preconditioner z = B r (B symmetric positive definite on the free DOFs, e.g.
  /// a factor of a nearby stiffness) instead of `preconditioner`, which must then be kNone
  /// (UsageError otherwise). linear_cg projects z after the call (fixed DOFs of z are zeroed).
  std::function<void(const VecX& r, VecX& z)> apply_preconditioner;
};

/// Minimizes the quadratic model Π(u₀) + ∇Π(u₀)·x + ½ xᵀK(u₀)x over x with Px = x, i.e. solves
/// K(u₀) x = −P∇Π(u₀) on the free DOFs, and sets u ← u₀ + x. For a linear problem (Π quadratic)
/// this is the exact static solution (§3.1). K·d comes from Problem::hessian_product at u₀
/// (matrix-free). The residual and the reaction forces are updated recursively with the same
/// unprojected product, so the rule (6.9) costs no extra evaluations. Energy history is exact
/// for a quadratic Π: Π_{k+1} = Π_k − ½ α_k (r_k, z_k).
/// Stops with kIndefinite when dᵀK d ≤ 0 (u is left at the last iterate), kNonFinite or
/// kInverted when an evaluation fails; never writes NaN into u. With kJacobi, a diagonal that
/// jacobi_inverse_diagonal() rejects ends the run before the first step with its status and
/// message (u unchanged).
SolverReport linear_cg(Problem& problem, VecX& u, const LinearCgOptions& options);

/// Linear operator out = A·in used by projected_cg(); returns the evaluation status.
using LinearOperator = std::function<EvalStatus(const VecX& in, VecX& out)>;

/// Outcome of projected_cg(); status: converged / indefinite / max_iterations ...
struct InnerCgResult : Outcome<StopReason, StopReason::kConverged, StopReason::kMaxIterations> {
  long iterations = 0;              ///< CG steps taken
  double residual_norm = 0.0;       ///< final ‖P(b − A x)‖₂ (recursive)
  bool negative_curvature = false;  ///< stopped at dᵀA d ≤ 0
};

/// CG on P A P x = P b started from x = 0 (x is overwritten), for inner solves (truncated
/// Newton §2.4.3, inverse iteration). `problem` supplies the projection P; `inverse_diagonal`,
/// when non-empty, is the Jacobi preconditioner D⁻¹ (zero at fixed DOFs). Stops when
/// ‖r‖₂ ≤ tolerance, after max_iterations, or at non-positive curvature (then x holds the last
/// iterate with positive curvature; x = 0 when the first direction already fails). Flops of the
/// vector operations are added to `meter`.
InnerCgResult projected_cg(const LinearOperator& apply, const Problem& problem,
                           const VecX& inverse_diagonal, const VecX& b, VecX& x, double tolerance,
                           long max_iterations, CostMeter& meter);

/// Outcome of jacobi_inverse_diagonal(); ok(): `inverse` holds D⁻¹, otherwise it is empty and
/// the message names the first offending DOF and its value.
struct [[nodiscard]] JacobiDiagonal
    : Outcome<StopReason, StopReason::kConverged, StopReason::kPreconditionerUnavailable> {
  VecX inverse;  ///< 1/K_ii at free DOFs, 0 at fixed DOFs (size n when ok(), else empty)
};

/// Jacobi preconditioner D⁻¹ = 1/diag K(u) (the E Eᵀ = diag K of §2.4.1) at free DOFs, 0 at
/// fixed DOFs, whose diagonal is never read (they are projected out, §3.1). Status:
/// kPreconditionerUnavailable when Problem::hessian_diagonal() returns false or a vector of the
/// wrong size; kNonFinite when a free K_ii is NaN/∞; kIndefinite when a free K_ii ≤ 0, since
/// then e_iᵀ K e_i ≤ 0 and K is not positive definite (a free DOF without stiffness has
/// K_ii = 0: fix it). Non-finite entries are reported before non-positive ones.
JacobiDiagonal jacobi_inverse_diagonal(Problem& problem, const VecX& u);

}  // namespace incise::solver
