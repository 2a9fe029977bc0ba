#pragma once
/// \file energy_error.hpp
/// The convergence measure of thesis §4.2: the energy error (e, e)_{K(û)} = eᵀK(û)e of
/// e = u − û against a reference solution û (computed e.g. by nonlinear CG to 1e-2 followed by
/// truncated Newton to 1e-8, §4.2), traced against seconds and flops of the solver being measured.
///
/// Note: Π(û + e) − Π(û) = ½ eᵀK(û)e + O(‖e‖³) when ∇Π(û) vanishes on the free DOFs; the
/// thesis drops the ½ and plots (e, e)_{K(û)}. We follow the thesis (the factor is immaterial on
/// its log-scale plots) and say so here.

#include <incise/solver/report.hpp>

#include <vector>

namespace incise::solver {

/// Records (e, e)_{K(û)} after every iteration of a solver through its IterationObserver. The
/// Hessian products it evaluates are excluded from the solver's flops and seconds (CostMeter).
class EnergyErrorTrace {
 public:
  /// One recorded iteration.
  struct Sample {
    long iteration = 0;          ///< solver iteration
    double seconds = 0.0;        ///< solver seconds (observer time excluded)
    std::uint64_t flops = 0;     ///< solver flops (observer flops excluded)
    double energy_error = 0.0;   ///< (e, e)_{K(û)} in joules; +∞ if K(û)e failed
    double residual_norm = 0.0;  ///< the solver's ‖r‖₂ (N)
  };

  /// `problem` must outlive the trace; `reference` is û (size problem.size()).
  EnergyErrorTrace(Problem& problem, VecX reference);

  /// (e, e)_{K(û)} for e = u − û, projected (fixed DOFs do not count). +∞ when K(û)·e fails.
  double energy_error(const VecX& u);

  /// Records the starting point u₀ as iteration 0 at cost 0.
  void record_start(const VecX& u0, double residual_norm);

  /// An observer that appends one Sample per solver iteration.
  IterationObserver observer();

  /// All samples in order.
  const std::vector<Sample>& samples() const { return samples_; }

  /// First sample whose energy error is ≤ level, or nullptr.
  const Sample* first_below(double level) const;

 private:
  Problem& problem_;
  VecX reference_;
  VecX e_, ke_;
  std::vector<Sample> samples_;
};

}  // namespace incise::solver
