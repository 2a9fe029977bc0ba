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

#include <limits>
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

/// Whether a displacement field inverts elements (post-check of a solution, thesis §4.3.1).
enum class InversionStatus {
  kNoneInverted,  ///< every tetrahedron keeps a positive deformed volume
  kInverted       ///< at least one tetrahedron has deformed volume ≤ 0 (det F ≤ 0)
};

/// Human-readable name ("none_inverted", "inverted").
const char* to_string(InversionStatus s);

/// Outcome of check_inversion().
struct [[nodiscard]] InversionCheck {
  InversionStatus status = InversionStatus::kNoneInverted;  ///< any element inverted?
  int inverted_elements = 0;                                ///< how many (det F ≤ 0)
  /// min over elements of deformed/reference volume = min det F (dimensionless; ≤ 0 iff
  /// inverted; 1 for a rigid motion); +∞ for an empty mesh.
  double min_volume_ratio = std::numeric_limits<double>::infinity();
  std::vector<Index> elements;  ///< indices of the inverted elements, ascending
};

/// Post-check of a solution u (3 displacements per node, m) on a tetrahedral mesh: which
/// elements have non-positive deformed volume. Material models that are defined for det F ≤ 0
/// (linear, St. Venant–Kirchhoff) report EvalStatus::kOk there, so a solver cannot see the
/// inversion; the thesis observed it for StVK near the clamp of its cylinder (§4.3.1, Fig. 4.3).
/// `points` is 3×n (m), `cells` 4×m vertex indices with positive reference volume.
/// Throws ParameterError on mismatched sizes or a non-tetrahedral cell matrix.
InversionCheck check_inversion(const Eigen::Matrix3Xd& points,
                               const Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic>& cells,
                               const VecX& u);

}  // namespace incise::solver
