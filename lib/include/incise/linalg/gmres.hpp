#pragma once
/// \file gmres.hpp
/// Restarted GMRES(k) with right preconditioning (Saad & Schultz 1986), used for the Schur
/// complement system (H R⁻¹ J) a₂ = H R⁻¹ f̂ of Yeung et al. 2016, eq. 17. Right
/// preconditioning keeps the monitored residual equal to the true residual of eq. 17.

#include <incise/core/outcome.hpp>
#include <incise/core/types.hpp>

#include <functional>
#include <string>
#include <vector>

namespace incise::linalg {

/// y = A x for a square operator; `y` is resized by the callee if needed.
using GmresOperator = std::function<void(const Eigen::VectorXd& x, Eigen::VectorXd& y)>;

/// Options of gmres().
struct GmresOptions {
  int restart = 60;          ///< Krylov dimension before restart (k of GMRES(k)), ≥ 1
  double tolerance = 1e-12;  ///< stop when ‖b − A x‖₂ ≤ tolerance · ‖b‖₂
  int max_iterations = 600;  ///< cap on total Arnoldi steps (operator applications)
  /// A restart cycle that reduces the residual by less than this factor counts as stagnation
  /// (reported as kStagnated: typically a singular or nearly singular operator).
  double stagnation_ratio = 0.999;
};

/// How gmres() ended.
enum class GmresStatus {
  kConverged,      ///< residual below tolerance
  kMaxIterations,  ///< iteration cap reached before the tolerance
  kStagnated,      ///< a full restart cycle made (almost) no progress: operator likely singular
  kBreakdown,      ///< Arnoldi breakdown with a nonzero residual: the operator is singular on
                   ///< the Krylov space (inconsistent singular system)
  kNonFinite       ///< the operator or preconditioner produced NaN/Inf
};

/// Human-readable name of a GmresStatus.
const char* to_string(GmresStatus status);

/// Report of a gmres() run.
struct GmresReport : Outcome<GmresStatus, GmresStatus::kConverged, GmresStatus::kMaxIterations> {
  int iterations = 0;            ///< Arnoldi steps (= operator applications in Arnoldi)
  int restarts = 0;              ///< completed restart cycles
  double relative_residual = 0;  ///< ‖b − A x‖₂ / ‖b‖₂ at exit (Givens estimate)
  std::vector<double> residual_history;  ///< relative residual after each iteration, [0] initial
  /// max|rᵢᵢ| / min|rᵢᵢ| of the triangularised Hessenberg matrix of the last cycle: a cheap
  /// lower estimate of the condition number of A·M⁻¹ on the Krylov space.
  double hessenberg_condition = 1;
};

/// Solves A x = b by restarted GMRES with optional right preconditioner: `precondition(v, z)`
/// computes z = M⁻¹ v (pass an empty function for none). `x` is the initial guess on entry
/// (resized to zero if its size differs from b) and the iterate on exit. b = 0 returns x = 0.
/// Numerical failure, including a non-finite b or initial guess, is reported in the status
/// (kNonFinite); throws ParameterError for bad options.
[[nodiscard]] GmresReport gmres(const GmresOperator& a, const GmresOperator& precondition,
                                const Eigen::VectorXd& b, Eigen::VectorXd& x,
                                const GmresOptions& options = {});

}  // namespace incise::linalg
