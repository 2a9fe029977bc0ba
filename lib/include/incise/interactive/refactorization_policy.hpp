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

#include <limits>

namespace incise::interactive {

/// The break-even rule of the file comment. Costs in seconds (any consistent unit).
class RefactorizationPolicy {
 public:
  /// Records one solver update of cost `seconds` (≥ 0); `swapped`: a new factor came into use
  /// in this update (it then starts a new period: this update's cost is the new floor).
  void observe(double seconds, bool swapped);
  /// Whether a refactorization should start now, with one costing `factorization_seconds`:
  /// excess() ≥ factorization_seconds > 0 (a non-positive or NaN cost never starts one).
  bool should_start(double factorization_seconds) const;
  /// The summed extra update cost since the factor in use came in: Σ (c − floor).
  double excess() const { return excess_; }
  /// The cheapest update since the factor in use came in (+∞ before the first).
  double floor() const { return floor_; }
  /// Forgets the period (as after a swap, without an update).
  void reset();

 private:
  double floor_ = std::numeric_limits<double>::infinity();
  double excess_ = 0;
};

}  // namespace incise::interactive
