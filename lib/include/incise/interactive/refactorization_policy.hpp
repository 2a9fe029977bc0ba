#pragma once
/// \file refactorization_policy.hpp
/// When to start the background refactorization of Yeung et al. 2016 §3.6 without a hand-set
/// threshold. The augmented update cost grows with m = |𝓛| while a factorization of the
/// current K costs about the same at any m; §3.6 bounds m "by periodically re-computing a full
/// LDLᵀ factorization of K in a process that runs concurrently with the simulation loop".
/// The rule here is the break-even (ski-rental) argument with measured costs: after a fresh
/// factor is in use, the cheapest update seen since then is the floor c₀; every later update
/// of cost c adds c − c₀ to the excess, the time the growth of m has cost so far; once the
/// excess reaches the measured time of one factorization T_f, a refactorization would have
/// paid for itself, and one is started. A swapped-in factor resets floor and excess.
/// Deterministic given the costs it is fed (tests inject them).
///
/// That rule assumes the factorization competes with the updates for the one core. With a
/// second core for background work (issue 17) a factorization costs the frame thread nothing,
/// so RefactorizationMode::kContinuous keeps one running whenever a refactorization would
/// remove a column (m − |𝓓| > 0): the next starts right after the last is swapped in. On the
/// liver path of issue 17, with the swap prepared in the background (linalg::AugmentedOptions::
/// prepare_swap), it had the lower p95 frame time on every path and the lower maximum on 5 of 6
/// runs, at about twice the background CPU (docs/augmented.md, "Refactorization policy"), so
/// it is the default; without prepare_swap it lost.

#include <incise/core/name_table.hpp>

#include <limits>

namespace incise::interactive {

/// When the automatic §3.6 policy starts a background refactorization.
enum class RefactorizationMode {
  kBreakEven,   ///< when the summed extra update cost reaches one factorization (file comment)
  kContinuous,  ///< whenever m − |𝓓| > 0 and no job is pending (a second core does the work)
};

/// Names of the modes (scene key `refactorization`, docs/scenes.md).
inline constexpr NameTable<RefactorizationMode, 2> kRefactorizationModeNames{{{
    {RefactorizationMode::kBreakEven, "break-even"},
    {RefactorizationMode::kContinuous, "continuous"},
}}};

/// The default mode, of AugmentedCutOptions and of scene runs (scene key `refactorization`):
/// continuous, the measured winner on the liver path of issue 17 (docs/augmented.md,
/// "Refactorization policy": lower p95 on all three paths, lower maximum in 5 of 6 runs).
inline constexpr RefactorizationMode kDefaultRefactorizationMode = RefactorizationMode::kContinuous;

/// Name from kRefactorizationModeNames.
inline const char* to_string(RefactorizationMode m) {
  return kRefactorizationModeNames.name(m);
}

/// The rule of the file comment in either mode. Costs in seconds (any consistent unit).
class RefactorizationPolicy {
 public:
  explicit RefactorizationPolicy(RefactorizationMode mode = kDefaultRefactorizationMode)
      : mode_(mode) {}
  /// The mode this policy decides by.
  RefactorizationMode mode() const { return mode_; }
  /// Records one solver update of cost `seconds` (≥ 0); `swapped`: a new factor came into use
  /// in this update (it then starts a new period: this update's cost is the new floor).
  void observe(double seconds, bool swapped);
  /// Whether a refactorization should start now (the caller checks that none is pending and
  /// that m − |𝓓| > 0), with one costing `factorization_seconds`. kBreakEven: excess() ≥
  /// factorization_seconds > 0 (a non-positive or NaN cost never starts one). kContinuous:
  /// always (the costs are still recorded, for excess() and floor()).
  bool should_start(double factorization_seconds) const;
  /// The summed extra update cost since the factor in use came in: Σ (c − floor).
  double excess() const { return excess_; }
  /// The cheapest update since the factor in use came in (+∞ before the first).
  double floor() const { return floor_; }
  /// Forgets the period (as after a swap, without an update).
  void reset();

 private:
  RefactorizationMode mode_;
  double floor_ = std::numeric_limits<double>::infinity();
  double excess_ = 0;
};

/// The synchronous choice of issue 17 (docs/augmented.md, "Synchronous refactorization"): before
/// a solve, the frame thread compares the predicted CPU of the augmented solve at the current m
/// with the measured CPU of one refactorization in the frame thread, and refactors now
/// (AugmentedSystem::refactor_now) when the solve would cost more — m then drops to 0 and the
/// next frames are small too. The prediction is a cost model on measured solves (CPU seconds):
///
///     c(m, k) = ⅔m³ / r + γ·k + ρ·m,
///
/// the fresh dense LU of the m × m capacitance matrix (Yeung et al. 2016 eq. 17 in capacitance
/// form; the cost rule of CapacitanceFactor takes the update only when it is cheaper, so this
/// is an upper bound) at the rate r (flop/s) of the last fresh LU observed with m ≥
/// kMinRateM, the k new columns of G (restricted solves R⁻¹e, AugmentedSystem::
/// columns_without_g) at the last cost per column γ observed with ≥ kMinColumns of them, and
/// the rest of the solve (the product Φ + GΨ, steps 1 and 3) at the last solve's cost per
/// column of 𝓛, ρ. Deterministic given what it is fed (tests feed it directly).
class SynchronousRefactorRule {
 public:
  /// Fresh LUs of smaller m do not set the rate (their BLAS rate is far below the large ones').
  static constexpr int kMinRateM = 256;
  /// Fewer new columns of G than this do not set γ.
  static constexpr int kMinColumns = 16;
  /// Records a solve at m (m > 0) that made k new columns of G and took `cpu_total` seconds,
  /// of which `cpu_capacitance` the capacitance factorization (`fresh`: a fresh LU) and
  /// `cpu_columns` the new columns.
  void observe(int m, int k, double cpu_total, double cpu_capacitance, bool fresh,
               double cpu_columns);
  /// c(m, k) of the class comment; NaN until r, γ and ρ are known.
  double predict(int m, int k) const;
  /// worth_refactoring(predict(m, k), refactor_cpu).
  bool should_refactor(int m, int k, double refactor_cpu) const;
  /// The decision on any prediction (the session's injected models too): predicted >
  /// refactor_cpu > 0, false for a NaN prediction.
  static bool worth_refactoring(double predicted, double refactor_cpu) {
    return refactor_cpu > 0 && predicted > refactor_cpu;
  }
  double lu_rate() const { return lu_rate_; }       ///< r (flop/s; NaN: none observed)
  double column_cost() const { return column_; }    ///< γ (seconds; NaN: none observed)
  double rest_per_column() const { return rest_; }  ///< ρ (seconds; NaN: none observed)

 private:
  double lu_rate_ = std::numeric_limits<double>::quiet_NaN();
  double column_ = std::numeric_limits<double>::quiet_NaN();
  double rest_ = std::numeric_limits<double>::quiet_NaN();
};

}  // namespace incise::interactive
