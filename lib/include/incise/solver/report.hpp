#pragma once
/// \file report.hpp
/// The common outcome report, budgets and stopping rules shared by every incise solver (linear
/// CG, nonlinear CG, truncated Newton, dynamic relaxation). Numerical failure is a reported
/// StopReason, never an exception or a NaN result (DESIGN §1 "Solvers and reports").

#include <incise/core/error.hpp>
#include <incise/core/outcome.hpp>
#include <incise/core/problem.hpp>
#include <incise/core/timer.hpp>
#include <incise/core/types.hpp>

#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

namespace incise::solver {

/// Why a solver returned.
enum class StopReason {
  kConverged,         ///< the stopping rule (3.1)/(6.8) or (6.9) was met
  kMaxIterations,     ///< Budget::max_iterations reached
  kFlopBudget,        ///< Budget::max_flops reached
  kTimeBudget,        ///< Budget::max_seconds reached
  kInverted,          ///< no admissible step: every trial point had Π = +∞ (det F ≤ 0)
  kNonFinite,         ///< a NaN/∞ appeared in a residual, energy or curvature
  kIndefinite,        ///< non-positive curvature dᵀK d ≤ 0 where a minimizer needs it positive
  kLineSearchFailed,  ///< the line search could not find an admissible step length
  kStagnated,         ///< no further progress (zero step, or residual no longer decreasing)
  kUnstable,          ///< explicit dynamics blew up (‖u‖ > blow-up bound, §4.4.1)
  /// Jacobi preconditioning was requested but Problem::hessian_diagonal() returned false (the
  /// problem has no diagonal, or could not evaluate its tangent at u); the solver did not run
  kPreconditionerUnavailable
};

/// Human-readable name ("converged", "max_iterations", ...).
const char* to_string(StopReason r);

/// Resource budgets. A solver stops with the matching StopReason as soon as one is exhausted
/// (checked once per iteration, so it may overshoot by one iteration's cost).
struct Budget {
  long max_iterations = 100000;                                  ///< iterations (outer)
  double max_flops = std::numeric_limits<double>::infinity();    ///< counted flops
  double max_seconds = std::numeric_limits<double>::infinity();  ///< wall-clock seconds
};

/// Which residual norm rule decides convergence.
enum class ResidualRule {
  kExternalForce,  ///< ‖r‖₂ ≤ ε‖f_ex‖₂ — (6.8), the rule of chapters 3 and 4
  kWithReactions  ///< ‖r‖₂ ≤ ε√(‖f_ex‖² + ‖f_react‖²) + (force_scale/√n) ε_round — (6.9)
};

/// Stopping rule parameters (§3.3, §4.2, (6.8), (6.9)). r = −P∇Π(u) is the projected residual;
/// f_react = (I−P)∇Π(u) are the reaction forces at fixed DOFs (§3.1, §6.6).
struct StoppingRule {
  ResidualRule rule = ResidualRule::kWithReactions;  ///< (6.8) or (6.9)
  double epsilon = 1e-3;                             ///< relative tolerance ε (dimensionless)
  double epsilon_round = 1e-12;                      ///< ε_round of (6.9) (dimensionless)
  /// E·d·H (2D) or E·H² (3D) of (6.9), newtons: the scale-free force magnitude. 0 disables the
  /// rounding term (then a zero load with no reactions can only "converge" at r = 0 exactly).
  double force_scale = 0.0;
  double absolute_tolerance = 0.0;  ///< extra additive floor on the threshold, newtons
};

/// Threshold on ‖r‖₂ for the given rule. `n` is the number of unknowns (for (6.9)'s √n).
double residual_threshold(const StoppingRule& rule, double external_force_norm,
                          double reaction_norm, Eigen::Index n);

/// Snapshot passed to an IterationObserver after every iteration.
struct IterationInfo {
  long iteration = 0;          ///< iterations completed
  const VecX* u = nullptr;     ///< current iterate (displacements, m); valid during the call
  double residual_norm = 0.0;  ///< ‖r‖₂ of that iterate (newtons), as the solver knows it
  double energy = 0.0;         ///< Π of that iterate (J), as the solver knows it
  std::uint64_t flops = 0;     ///< flops spent by the solver so far (observer excluded)
  double seconds = 0.0;        ///< seconds spent by the solver so far (observer excluded)
  double cpu_seconds = 0.0;    ///< process CPU seconds so far (all threads; observer excluded)
  /// Simulated time (s) of `u` in dynamic relaxation (ū of (2.56): Σ Δt over the steps taken,
  /// plus ½Δt); −1 for the static solvers, which have no time.
  double time = -1.0;
};

/// Called after every iteration. The time and flops spent inside it are excluded from the
/// solver's budgets and report, so observers (e.g. EnergyErrorTrace) do not bias measurements.
using IterationObserver = std::function<void(const IterationInfo&)>;

/// Options every relaxation solver takes (linear CG, nonlinear CG, truncated Newton, dynamic
/// relaxation): the base of their option structs, so a caller can set these generically, e.g.
/// `static_cast<RelaxationOptions&>(options) = common;`.
struct RelaxationOptions {
  StoppingRule stop;           ///< (6.8) or (6.9)
  Budget budget;               ///< iteration / flop / time budgets
  IterationObserver observer;  ///< called after every iteration with the current iterate
};

/// Outcome of one solver run. [[nodiscard]]: numerical failure is reported here.
/// status: why the solver returned (kConverged: the stopping rule was met); ok() == converged.
struct [[nodiscard]] SolverReport
    : Outcome<StopReason, StopReason::kConverged, StopReason::kMaxIterations> {
  long iterations = 0;        ///< outer iterations (CG steps, NCG steps, Newton steps,
                              ///< time steps) completed
  long inner_iterations = 0;  ///< inner CG steps (truncated Newton), line-search
                              ///< evaluations (nonlinear CG), K-products of the quadratic
                              ///< recurrence (dynamic relaxation); 0 otherwise
  std::uint64_t flops = 0;    ///< counted flops: Problem::flops() delta + solver vector ops
  double seconds = 0.0;       ///< wall-clock seconds (observer time excluded)
  double cpu_seconds = 0.0;   ///< process CPU seconds, all threads (observer time excluded)
  double residual_norm = std::numeric_limits<double>::quiet_NaN();  ///< final ‖r‖₂ (N)
  double threshold = 0.0;  ///< final stopping threshold on ‖r‖₂ (N)
  double energy = std::numeric_limits<double>::quiet_NaN();  ///< final Π (J) when known
  long restarts = 0;       ///< dynamic relaxation: restarts after unstable steps, else 0
  double time_step = 0.0;  ///< dynamic relaxation: the Δt of the final (re)start (s), else 0
  std::vector<double> residual_history;  ///< ‖r‖₂ after each iteration (index 0: start)
  std::vector<double> energy_history;    ///< Π after each iteration (index 0: start)
};

/// Cost meter shared by the solvers: counts Problem::flops() deltas plus explicitly added
/// vector-operation flops, and wall time, both excluding time/flops spent in observers.
class CostMeter {
 public:
  /// Starts measuring `problem` now.
  explicit CostMeter(const Problem& problem);
  /// Adds solver-side flops (vector operations: a dot product of length n is 2n flops).
  void add(std::uint64_t flops) { own_flops_ += flops; }
  /// Flops since construction, observer excluded.
  std::uint64_t flops() const;
  /// Seconds since construction, observer excluded.
  double seconds() const;
  /// Process CPU seconds (all threads) since construction, observer excluded.
  double cpu_seconds() const;
  /// Writes flops(), seconds() and cpu_seconds() into `rep` (every solver's return path).
  void record(SolverReport& rep) const;
  /// Calls `observer` (if set) with `info` (cost fields filled in here) and excludes its cost.
  void observe(const IterationObserver& observer, IterationInfo info);
  /// Budget check: the StopReason for an exhausted budget, or kConverged when none is.
  StopReason exhausted(const Budget& budget, long iterations) const;

 private:
  const Problem& problem_;
  std::uint64_t start_flops_;
  std::uint64_t own_flops_ = 0;
  std::uint64_t excluded_flops_ = 0;
  double excluded_seconds_ = 0.0;
  double excluded_cpu_seconds_ = 0.0;
  Timer timer_;
  double cpu_start_ = process_cpu_seconds();
};

/// Stop reason for a failed evaluation: kInverted when the problem reported inverted elements,
/// kNonFinite otherwise (including an evaluation that said kOk but produced NaN/inf values).
inline StopReason failure_reason(EvalStatus s) {
  return s == EvalStatus::kInverted ? StopReason::kInverted : StopReason::kNonFinite;
}

/// The start check every solver makes on ‖f_ext‖ (Problem::external_force_norm()): a load whose
/// norm is not finite (it overflows the doubles, e.g. a total force of 1e155 N) would make the
/// threshold of (6.8)/(6.9) infinite, which every residual, ∞ included, would meet. Returns true
/// when ‖f_ext‖ is finite; otherwise sets rep.status = kNonFinite and a message naming the value
/// (the solver then returns without iterating, u unchanged).
bool external_force_is_finite(double external_force_norm, SolverReport& rep);

/// ‖v‖₂ of the components of v at fixed DOFs (the reaction force norm of (6.9) when v = ∇Π).
double fixed_norm(const Problem& problem, const VecX& v);

/// The fixed DOFs of a problem, listed once per solve: the reaction norm of (6.9) is needed
/// every iteration, and Problem::is_fixed is a virtual call per DOF. The fixed set must not
/// change while this lives (it does not during a solve).
class FixedDofs {
 public:
  explicit FixedDofs(const Problem& problem);
  /// fixed_norm(problem, v), summed in the same order.
  double norm(const VecX& v) const;

 private:
  std::vector<Eigen::Index> dofs_;
};

/// The start of the gradient solvers (linear CG, nonlinear CG, truncated Newton).
struct GradientStart {
  VecX g;                  ///< ∇Π(u), unprojected
  VecX r;                  ///< −∇Π(u) with the fixed DOFs projected out
  double energy = 0.0;     ///< Π(u)
  double fex = 0.0;        ///< ‖f_ext‖
  double threshold = 0.0;  ///< the stopping rule's threshold on ‖r‖ at u, (6.8)/(6.9)
};

/// Checks ‖f_ext‖ (external_force_is_finite), evaluates g and Π at u, forms r and the threshold,
/// and records iteration 0's ‖r‖ and Π in rep's histories. Returns false when the load or the
/// evaluation is not finite (or an element is inverted): rep then carries the status and the
/// meter's costs, u is unchanged, and the solver returns rep.
bool start_from_gradient(Problem& problem, const VecX& u, const StoppingRule& stop,
                         const FixedDofs& fixed_dofs, const CostMeter& meter, SolverReport& rep,
                         GradientStart& out);

/// True when every entry of v is finite.
inline bool all_finite(const VecX& v) {
  return v.allFinite();
}

}  // namespace incise::solver
