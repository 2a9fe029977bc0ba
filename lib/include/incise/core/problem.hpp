#pragma once
/// \file problem.hpp
/// The narrow interface through which every solver sees a mechanical problem (docs/design.md
/// §1.1: energy, gradient, Hessian-vector product, projection). The 3D elastic body (fem) and
/// the synthetic test problems implement it, so that one nonlinear CG, one truncated Newton and
/// one dynamic relaxation serve them all.
///
/// Sign convention: the unknown u is the nodal displacement vector (length size()); Π(u) is the
/// potential energy (2.40); gradient(u) = ∇Π(u) = f_int(u) − f_ext, i.e. the negated residual
/// r = f_ext − f_int of §3.1. Constrained (fixed) degrees of freedom are handled by project(),
/// which zeroes them (§3.1: "zeroing the constrained residual").

#include <incise/core/types.hpp>

#include <cmath>
#include <cstdint>
#include <functional>

namespace incise {

/// Outcome of evaluating a problem at a given u.
enum class EvalStatus {
  kOk,        ///< value is finite and meaningful
  kInverted,  ///< some element has det F ≤ 0 where the material is undefined; Π = +∞
  kNonFinite  ///< a NaN or infinity appeared (e.g. overflow at huge stretch)
};

/// Human-readable name of an EvalStatus ("ok", "inverted", "non-finite").
inline const char* to_string(EvalStatus s) {
  switch (s) {
    case EvalStatus::kOk: return "ok";
    case EvalStatus::kInverted: return "inverted";
    case EvalStatus::kNonFinite: return "non-finite";
  }
  return "?";
}

/// A smooth minimization problem Π: R^n → R ∪ {+∞} with linear (fixed-DOF) constraints.
class Problem {
 public:
  virtual ~Problem() = default;

  /// Number of unknowns n.
  virtual Eigen::Index size() const = 0;

  /// Π(u) in joules. Sets `energy` to +∞ and returns kInverted when u leaves the domain.
  virtual EvalStatus energy(const VecX& u, double& energy) = 0;

  /// g = ∇Π(u) (newtons), *not* projected: components at fixed DOFs hold the reaction forces
  /// needed by the stopping rule (6.9). Optionally also returns Π(u).
  virtual EvalStatus gradient(const VecX& u, VecX& g, double* energy = nullptr) = 0;

  /// out = K(u)·d, the tangent (Hessian of Π) applied to d, matrix-free (§3.1), not projected.
  virtual EvalStatus hessian_product(const VecX& u, const VecX& d, VecX& out) = 0;

  /// g = ∇Π(u), Π(u) and out = K(u)·d at one point: what a Newton line search needs at each
  /// trial step (§4.4.2). The default calls gradient() then hessian_product(); a problem may
  /// evaluate all three in one sweep over its elements (ElasticProblem does) with the same
  /// results. On a non-ok status the outputs are as gradient() leaves them.
  virtual EvalStatus gradient_energy_product(const VecX& u, const VecX& d, VecX& g, double& energy,
                                             VecX& out) {
    const EvalStatus s = gradient(u, g, &energy);
    if (s != EvalStatus::kOk) return s;
    return hessian_product(u, d, out);
  }

  /// c = dᵀK(u)d, the curvature of Π along d at u (the secant/Newton line search's first slope,
  /// §4.4.2), when only that scalar is needed. The default takes hessian_product() and the dot
  /// product; a problem may sum element curvatures d_eᵀK_e d_e without forming K·d (ElasticProblem
  /// does): the same value up to rounding. On a non-ok status c is unspecified.
  virtual EvalStatus hessian_curvature(const VecX& u, const VecX& d, double& curvature) {
    VecX kd;
    const EvalStatus s = hessian_product(u, d, kd);
    if (s != EvalStatus::kOk) return s;
    curvature = d.dot(kd);
    return std::isfinite(curvature) ? EvalStatus::kOk : EvalStatus::kNonFinite;
  }

  /// d ↦ K(u)·d for many products at one fixed u (the Lanczos estimate of the automatic Δt and
  /// η): a problem may assemble K(u) once and return its product, the same operator as
  /// hessian_product(u, ·) up to rounding. Default: empty (not offered; callers then call
  /// hessian_product). The function stays valid while the problem lives and is not changed.
  virtual std::function<EvalStatus(const VecX& d, VecX& out)> assembled_hessian(const VecX& u) {
    return {};
  }

  /// True when Π is exactly quadratic in u: K does not depend on u and ∇Π(u + αd) =
  /// ∇Π(u) + α K·d, Π(u + αd) = Π(u) + α ∇Π(u)·d + ½α² dᵀK d for every u, d (linear material,
  /// no geometric nonlinearity, dead loads). Solvers may then update the gradient by that
  /// recurrence instead of evaluating it (nonlinear_cg). Default: false (always safe).
  virtual bool energy_is_quadratic() const { return false; }

  /// Diagonal of K(u), for Jacobi preconditioning. Default: not available (returns false).
  virtual bool hessian_diagonal(const VecX& u, VecX& diag) { return false; }

  /// Zero the components of v at constrained DOFs (v ← P v).
  virtual void project(VecX& v) const = 0;

  /// True when DOF i is constrained (fixed).
  virtual bool is_fixed(Eigen::Index i) const = 0;

  /// ‖f_ext‖₂ over free DOFs, the scale of the stopping rules ‖r‖ ≤ ε‖f_ext‖ (§3.1, (6.9)).
  virtual double external_force_norm() const = 0;

  /// Lumped mass per DOF (kg) for dynamic relaxation (§2.5); empty when the problem has none.
  virtual const VecX& lumped_mass() const {
    static const VecX kEmpty;
    return kEmpty;
  }

  /// Cumulative floating-point operations spent in evaluations so far (counted, not estimated:
  /// element kernels are counted once with a counting scalar and multiplied by element counts).
  virtual std::uint64_t flops() const { return 0; }
};

}  // namespace incise
