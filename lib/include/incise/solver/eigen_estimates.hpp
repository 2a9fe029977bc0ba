#pragma once
/// \file eigen_estimates.hpp
/// Extreme eigenvalues of the generalized problem K w = λ M w (M lumped, K = K(u) tangent) on the
/// free DOFs, which set the dynamic relaxation parameters of thesis §4.1: the critical time step
/// Δt = 2/√λ_n and the critical damping η = 2√λ₁.

#include <incise/core/outcome.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/report.hpp>

namespace incise::solver {

/// An eigenvalue estimate of M⁻¹K (1/s²); status kConverged when the relative change met the
/// tolerance.
struct [[nodiscard]] EigenEstimate
    : Outcome<StopReason, StopReason::kConverged, StopReason::kMaxIterations> {
  double value = 0.0;         ///< Rayleigh quotient (w, K w)/(w, M w) of the final iterate (1/s²)
  long iterations = 0;        ///< outer (power / inverse) iterations
  long inner_iterations = 0;  ///< inner CG steps (inverse iteration)
  double relative_change = 0.0;  ///< |ρ_k − ρ_{k−1}|/ρ_k at exit
  std::uint64_t flops = 0;       ///< counted flops
};

/// Options for the eigenvalue iterations.
struct EigenOptions {
  double tolerance = 1e-6;        ///< stop when |ρ_k − ρ_{k−1}| ≤ tolerance·ρ_k
  long max_iterations = 2000;     ///< outer iterations
  double inner_tolerance = 1e-8;  ///< inverse iteration: relative CG tolerance of K y = M x
  unsigned seed = 12345;          ///< seed of the deterministic random start vector
};

/// Largest eigenvalue λ_n of M⁻¹K at u by power iteration on P M⁻¹ K P with M-normalization.
/// The Rayleigh quotient is a lower bound of λ_n, so 2/√value slightly overestimates the
/// critical time step; use a safety factor. Requires Problem::lumped_mass() (UsageError if
/// empty). Reports kIndefinite if (w,Kw) ≤ 0, kNonFinite/kInverted on failed evaluations.
EigenEstimate largest_eigenvalue(Problem& problem, const VecX& u, const EigenOptions& options = {});

/// Smallest eigenvalue λ₁ of M⁻¹K at u by inverse iteration, each step solving K y = M x on the
/// free DOFs with projected_cg(), Jacobi-preconditioned when Problem::hessian_diagonal() is
/// available (plain CG otherwise). The Rayleigh quotient is an upper bound of λ₁. A diagonal
/// with a free K_ii ≤ 0 (kIndefinite) or a non-finite one (kNonFinite) stops it before the
/// first step, with jacobi_inverse_diagonal()'s message.
EigenEstimate smallest_eigenvalue(Problem& problem, const VecX& u,
                                  const EigenOptions& options = {});

/// Extreme Ritz values of the Lanczos tridiagonal matrix implied by a CG run.
struct [[nodiscard]] LanczosExtremes {
  double smallest = 0.0;  ///< smallest Ritz value (≥ λ_min of the operator), operator units
  double largest = 0.0;   ///< largest Ritz value (≤ λ_max of the operator)
  long steps = 0;         ///< size of the tridiagonal matrix (CG steps used)
  bool converged = true;  ///< false if the tridiagonal QR iteration did not converge
  /// largest/smallest: a lower bound of the spectral condition number κ₂ that converges to it
  /// as CG resolves the extreme eigenvectors (both extremes converge first, §2.4.1).
  double condition() const { return largest / smallest; }
};

/// Extreme eigenvalue estimates of the CG operator (K for plain CG on the free DOFs — not M⁻¹K
/// — or D⁻¹K for Jacobi-preconditioned CG) from the CG coefficients of a linear_cg() run
/// (LinearCgOptions::coefficients), at no extra operator application: the Lanczos tridiagonal
/// T of CgCoefficients and its eigenvalues (Eigen's tridiagonal QR). Throws ParameterError
/// when there are no steps or the coefficient lists differ in length.
LanczosExtremes cg_lanczos_extremes(const CgCoefficients& coefficients);

/// Smallest and largest eigenvalue of the symmetric tridiagonal matrix with diagonal `diag` and
/// off-diagonal `sub` (diag.size() − 1 entries), by bisection on Sturm counts (O(k) per halving,
/// no QR of all k eigenvalues) from Gershgorin brackets, each to an absolute accuracy of
/// 2ε‖T‖ (‖T‖ bounded by Gershgorin: what a QR iteration reaches). The kernel of
/// lanczos_spectrum()'s Ritz values. Throws ParameterError when diag is empty, sub has the wrong
/// length or an entry is not finite.
struct TridiagonalExtremes {
  double smallest = 0.0;
  double largest = 0.0;
};
TridiagonalExtremes tridiagonal_extremes(const VecX& diag, const VecX& sub);

/// Options of lanczos_spectrum().
struct LanczosOptions {
  long min_steps = 12;      ///< never stop before this many steps
  long max_steps = 400;     ///< products of K at most (the estimate's cost cap)
  double tolerance = 0.01;  ///< stop when both extreme Ritz values moved ≤ tolerance (relative)
  long window = 8;          ///< ... over each of the last `window` steps
  /// ... and the Ritz residual of θ₁ (a bound on its distance to an eigenvalue) is at most this
  /// fraction of θ₁ — a plateau of θ₁ between eigenvalues is not accepted
  double residual_tolerance = 0.5;
  double random_fraction = 0.1;  ///< M-norm share of a seeded random vector added to the start
  unsigned seed = 12345;         ///< seed of that random vector
  /// Multiply by K(u) assembled once (Problem::assembled_hessian) when the problem offers it:
  /// the same operator up to rounding at a fraction of a matrix-free product's cost (issue 19,
  /// docs/solvers.md "Fifth pass"), at the memory of one assembled K. false: hessian_product
  /// on every step.
  bool assembled = true;
};

/// Extreme eigenvalue estimates of M⁻¹K(u) on the free DOFs from a Lanczos run.
struct [[nodiscard]] SpectrumEstimate
    : Outcome<StopReason, StopReason::kConverged, StopReason::kMaxIterations> {
  double smallest = 0.0;  ///< smallest Ritz value θ₁ ≥ λ₁ (1/s²): η = critical_damping(θ₁)
  double largest = 0.0;  ///< largest Ritz value θ_k ≤ λ_n (1/s²): Δt = critical_time_step(θ_k)
  long steps = 0;        ///< Lanczos steps = products K·q (each costs one hessian_product)
  std::uint64_t flops = 0;       ///< counted flops (products + vector operations)
  double smallest_change = 0.0;  ///< relative change of θ₁ over the last step
  double largest_change = 0.0;   ///< relative change of θ_k over the last step
  /// Ritz residual of θ₁ relative to θ₁ at the last convergence check (∞ before any)
  double smallest_residual = std::numeric_limits<double>::infinity();
  /// θ_k moved ≤ tolerance over each of the last `window` steps (the top of the spectrum
  /// converges first: set also when θ₁ has not converged and the status is kMaxIterations)
  bool largest_settled = false;
};

/// Both extreme eigenvalues of the generalized problem K(u) w = λ M w on the free DOFs (M
/// lumped) at once, by symmetric Lanczos in the M inner product (no reorthogonalization: lost
/// orthogonality only duplicates converged Ritz values, not the extremes) on M⁻¹PK(u)P,
/// starting from `start` (projected; typically the first acceleration M⁻¹P(f − ∇Π(u)), whose
/// low modes dominate) plus random_fraction of a seeded random vector (for the top of the
/// spectrum). One product K(u)·q per step (by the assembled K when options.assembled and the
/// problem offers it, else hessian_product); the Ritz values of the tridiagonal T_k are the
/// estimates, θ₁ decreasing to λ₁ and θ_k increasing to λ_n. Replaces the power and the
/// inverse iteration of largest_eigenvalue()/smallest_eigenvalue() at a fraction of their cost
/// (docs/solvers.md). kConverged when both moved ≤ tolerance over the last `window` steps and
/// θ₁'s Ritz residual is ≤ residual_tolerance·θ₁,
/// kMaxIterations at max_steps (the values are still bounds, kept), kIndefinite when a
/// Rayleigh quotient (q, Kq) ≤ 0, kNonFinite/kInverted on failed evaluations; an exhausted
/// Krylov space (β = 0: the start lies in an invariant subspace) is kConverged. An empty or
/// zero `start` uses the random vector alone. Requires lumped masses (UsageError otherwise).
SpectrumEstimate lanczos_spectrum(Problem& problem, const VecX& u, const VecX& start,
                                  const LanczosOptions& options = {});

/// Critical time step of explicit SS22 / central differences for eigenvalue λ_n: 2/√λ_n (§4.1).
double critical_time_step(double lambda_max);

/// Critical (optimal) damping η = 2√λ₁ (§4.1) in 1/s.
double critical_damping(double lambda_min);

}  // namespace incise::solver
