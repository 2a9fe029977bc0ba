#pragma once
/// \file dynamic_relaxation.hpp
/// Dynamic relaxation (thesis §2.5, §4.1, §4.4.1): explicit SS22 time integration (θ₁ = ½,
/// θ₂ = 0) of M ü + C u̇ + ∇Π(u) = 0 with lumped mass M (Problem::lumped_mass) and lumped
/// damping C = ηM, run until the static residual rule is met; plus the ways of choosing its two
/// parameters Δt and η.

#include <incise/core/outcome.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/report.hpp>

#include <vector>

namespace incise::solver {

/// Options of dynamic_relaxation(). From RelaxationOptions: `stop` is checked on the residual at
/// the evaluation point ū, `budget` counts time steps, `observer` is called after every step
/// with ū and its residual.
struct DynamicRelaxationOptions : RelaxationOptions {
  double time_step = 0.0;     ///< Δt (s), > 0
  double damping = 0.0;       ///< η (1/s), ≥ 0; C = ηM
  double blowup_norm = 1e15;  ///< ‖u‖₂ above this is a blow-up (kUnstable), §4.4.1
  /// Restarts after an unstable step (0: none, the thesis' behaviour — a blow-up, inversion or
  /// non-finite evaluation ends the run). With max_restarts > 0 an unstable step is also one
  /// whose total energy E = Π(ū) + ½u̇ᵀMu̇ regained more than half of what damping has
  /// dissipated over the run (E > E_min + ½(E₀ − E_min), E₀ the run's first E, E_min the lowest
  /// since the last (re)start; a stable damped run loses energy up to a wiggle of E, so
  /// this needs damping > 0); the integration then restarts at rest from the displacement of
  /// lowest E with Δt ← restart_reduction·Δt. SolverReport::restarts and
  /// SolverReport::time_step say so.
  int max_restarts = 0;
  double restart_reduction = 0.7;  ///< Δt factor per restart, in (0, 1)
  /// For a quadratic Π: the gradient recurrence below instead of a gradient+energy sweep per
  /// step. Off by default: it pays only where a K-product is cheaper than the sweep (an
  /// assembled K); it changes the flops a step costs and with them the §4.5.4 flop ratios that
  /// verification/papers/nienhuys2003_ch4 reproduces.
  bool gradient_recurrence = false;
  /// Π is evaluated on every energy_every-th step (≥ 1; default 4, 1 is every step). SS22 needs
  /// only ∇Π ((2.58); the thesis' blow-up test is on ‖u‖, §4.4.1), so the other steps take the
  /// gradient-only sweep, which skips the energy terms of every element (docs/solvers.md,
  /// "Ninth pass"). Steps without Π record NaN in
  /// SolverReport::energy_history and IterationInfo::energy (a blank cell in the CLI's CSV); the
  /// energy-growth test of max_restarts runs on the steps with Π, so growth is caught within
  /// energy_every steps (a restart may then come later; without one the trajectory does not
  /// depend on energy_every). The first step (after a restart
  /// too), the converged step and the returned u always carry Π (SolverReport::energy is
  /// evaluated), and with the gradient recurrence every step does (the recurrence carries Π).
  int energy_every = 4;
};

/// Runs SS22 from rest at u (updated in place). One step (2.56)–(2.60) with θ₁ = ½, θ₂ = 0:
///   ū = u + ½Δt u̇,   ü = −P(∇Π(ū) + ηM u̇) / ((1 + ½Δtη) M),
///   u ← u + Δt u̇ + ½Δt² ü,   u̇ ← u̇ + Δt ü.
/// One gradient evaluation per step, at ū; the stopping rule is checked on ‖P∇Π(ū)‖, so on
/// convergence u is set to that ū (the point whose residual was certified). On blow-up
/// (‖u‖ > blowup_norm, kUnstable), inversion (kInverted) or non-finite values (kNonFinite) u is
/// set to the last evaluated admissible point. With options.max_restarts > 0 those events (and
/// energy growth) restart the integration at a smaller Δt instead, until the restarts are used
/// up (then the status is the last event's, with a message naming the restarts).
/// With options.gradient_recurrence and a quadratic Π (Problem::energy_is_quadratic()) the
/// gradient and energy at ū come from
/// the previous step's by one K-product, ∇Π(ū_k) = ∇Π(ū_{k−1}) + K(ū_k − ū_{k−1}), evaluated
/// instead every 50 steps, after a restart and whenever the recurrence residual meets the
/// stopping rule (convergence is certified on an evaluated gradient); SolverReport::
/// inner_iterations counts those products. Iterates differ from evaluated steps by round-off
/// (test DynamicRelaxationQuadratic.RecurrenceMatchesEvaluatedSteps_Sec2_5).
/// Requires lumped masses (UsageError otherwise).
SolverReport dynamic_relaxation(Problem& problem, VecX& u, const DynamicRelaxationOptions& options);

/// Options of estimate_dynamic_parameters().
struct DynamicParameterOptions {
  LanczosOptions lanczos;  ///< the one Lanczos run (its max_steps caps the cost)
  /// Δt = safety·2/√θ_max, safety in (0, 1) (ParameterError otherwise): θ_max ≤ λ_n
  /// underestimates λ_n, and at the critical step itself the top mode is undamped.
  double time_step_safety = 0.9;
  /// ε, the error reduction the run is to reach (the relative energy-norm error, or the relative
  /// residual of the stopping rule), in (0, 1); 0 asks for critical damping (§4.1). η = 2ζ√θ₁
  /// with ζ = damping_ratio_for(ε/2): the slowest mode's first overshoot takes half the band, the
  /// other half is left to the other modes and to where the steps fall (docs/solvers.md,
  /// "Eighth pass").
  double target_reduction = 1e-6;
};

/// The damping ratio whose first overshoot is `overshoot`: ζ with exp(−πζ/√(1 − ζ²)) =
/// overshoot, i.e. ζ = L/√(π² + L²), L = ln(1/overshoot) (0.9773 for 5e-7; 1 for 0: critical
/// damping). A mode of (4.2) started from rest, y(0) = 1, ẏ(0) = 0, with η = 2ζ√λ stays within
/// |y| ≤ overshoot from its first zero crossing on (x = √λ·t ≈ 13.3 at 5e-7), where critical
/// damping, (1 + x)e^{−x}, needs x ≈ 16.7 to reach 1e-6 — the O(t) factor of §4.1 (the minimum
/// settling time of a second-order system). Throws ParameterError unless 0 ≤ overshoot < 1.
double damping_ratio_for(double overshoot);

/// Automatic Δt and η of dynamic relaxation (§4.1) and what they cost.
struct [[nodiscard]] DynamicParameterEstimate
    : Outcome<StopReason, StopReason::kConverged, StopReason::kMaxIterations> {
  double time_step = 0.0;      ///< Δt = safety·critical_time_step(θ_max) (s)
  double damping = 0.0;        ///< η = ζ·critical_damping(θ₁) = 2ζ√θ₁ (1/s)
  double damping_ratio = 1.0;  ///< ζ = damping_ratio_for(options.target_reduction / 2)
  double lambda_min = 0.0;     ///< θ₁ ≥ λ₁ (1/s²)
  double lambda_max = 0.0;     ///< θ_max ≤ λ_n (1/s²)
  long products = 0;           ///< K·q products spent (= Lanczos steps)
  std::uint64_t flops = 0;     ///< counted flops
};

/// Δt and η at u from one lanczos_spectrum() run started at the first acceleration
/// M⁻¹P(−∇Π(u)) (the load shape, rich in the lowest mode): a few dozen K-products where the
/// power and inverse iterations took thousands (docs/solvers.md). Δt = safety·2/√θ_max,
/// η = 2ζ√θ₁ with ζ = damping_ratio_for(options.target_reduction / 2). The two are estimates
/// (θ₁ ≥ λ₁ raises ζ slightly; λ₁ at the solution of a nonlinear problem differs from λ₁(u);
/// θ_max ≤ λ_n, and λ_n may grow as a stiffening material deforms):
/// run dynamic_relaxation() with max_restarts > 0 so that a too large Δt restarts instead of
/// diverging. Status: the Lanczos run's, or the failed gradient's; Δt, η and the θ are set
/// when it is kConverged, and with kMaxIterations when θ_max has settled
/// (SpectrumEstimate::largest_settled) — then θ₁ ≥ λ₁ is an uncertified upper bound (η
/// over-damps), the message says so, and a caller may use them or raise the step limit
/// (otherwise they stay 0). The result depends only on the
/// problem and u, so a caller relaxing the same mesh again (the same material, fixed set and
/// masses) may reuse it.
DynamicParameterEstimate estimate_dynamic_parameters(Problem& problem, const VecX& u,
                                                     const DynamicParameterOptions& options = {});

/// CFL time-step estimate (2.61) of explicit SS22 with θ₁ = ½: Δt = (2/√3)·h/c with
/// c = √((λ + 2µ)/ρ). h: shortest edge (m), lame_lambda, lame_mu (Pa), density (kg/m³).
double cfl_time_step(double h, double lame_lambda, double lame_mu, double density);

/// Options of find_stable_time_step() (§4.4.1).
struct StableTimeStepOptions {
  double flop_budget = 50e6;  ///< an undamped run must survive this many flops (thesis: 50 MFLOP)
  double blowup_norm = 1e15;  ///< ‖u‖ beyond which the run counts as blown up
  double reduction = 0.85;    ///< multiply Δt by this after each failure ("lowered by 15 %")
  int max_reductions = 60;    ///< give up after this many reductions
  long max_steps = 1000000;   ///< also stop each trial after this many steps
};

/// Outcome of find_stable_time_step().
struct [[nodiscard]] StableTimeStep {
  double time_step = 0.0;   ///< the first Δt whose undamped run survived (s); 0 when none did
  int reductions = 0;       ///< number of 15 % reductions applied
  bool found = false;       ///< a stable Δt was found
  std::uint64_t flops = 0;  ///< total flops spent on the trials
};

/// The thesis' empirical critical time step (§4.4.1): starting from `initial` (e.g.
/// cfl_time_step()), run an undamped simulation from u for options.flop_budget flops; if it blows
/// up (or inverts / turns non-finite), lower Δt by 15 % and retry.
StableTimeStep find_stable_time_step(Problem& problem, const VecX& u, double initial,
                                     const StableTimeStepOptions& options = {});

/// One point of a damping sweep; status: the outcome of its run.
struct DampingTrial : Outcome<StopReason, StopReason::kConverged, StopReason::kMaxIterations> {
  double damping = 0.0;     ///< η (1/s)
  long iterations = 0;      ///< time steps taken
  std::uint64_t flops = 0;  ///< flops taken
};

/// Outcome of sweep_damping().
struct [[nodiscard]] DampingSweep {
  std::vector<DampingTrial> trials;  ///< every η tried, in order
  double best_damping = 0.0;         ///< η of the converged trial with fewest steps; 0 when none
  long best_iterations = 0;          ///< its step count
};

/// The thesis' manual method (§4.4.1) automated: run dynamic_relaxation() from u for each η in
/// `etas` with the given options (damping overwritten) and keep the fastest converged one.
DampingSweep sweep_damping(Problem& problem, const VecX& u, const std::vector<double>& etas,
                           const DynamicRelaxationOptions& options);

/// Outcome of damping_from_spectrum(); status: the outcome of the undamped run.
struct [[nodiscard]] SpectralDamping
    : Outcome<StopReason, StopReason::kConverged, StopReason::kMaxIterations> {
  double damping = 0.0;     ///< η = 2ω = 4πf (1/s); 0 when no oscillation was found
  double frequency = 0.0;   ///< dominant frequency f (Hz) of the undamped trajectory
  double resolution = 0.0;  ///< FFT bin width (Hz)
  long steps = 0;           ///< time steps simulated
  std::uint64_t flops = 0;  ///< flops spent
};

/// η from the dominant frequency of an undamped trajectory (spectrum by FFTW, module spectral):
/// runs `steps` undamped SS22 steps from rest at u, samples s(t) = (u(t) − u₀)·r₀/‖r₀‖ (the
/// displacement along the initial residual, dominated by the lowest mode for a smooth load),
/// and returns η = 2·(2πf), i.e. 2√λ₁ with λ₁ = ω² (§4.1). A run that blows up returns
/// damping 0 with its StopReason.
SpectralDamping damping_from_spectrum(Problem& problem, const VecX& u, double time_step,
                                      long steps);

}  // namespace incise::solver
