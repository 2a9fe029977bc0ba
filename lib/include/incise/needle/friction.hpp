#pragma once
/// \file friction.hpp
/// The friction force density along the needle shaft (thesis §6.3.2, Fig. 6.4 after DiMaio and
/// Salcudean) and the per-node friction thresholds derived from it.
///
/// The thesis plots a profile that is flat along the shaft with a bulge at the tip ("the force
/// required to make the needle tip cut into the material") but gives no numbers. incise uses a
/// parameterised piecewise-linear profile of the distance s ≥ 0 from the tip, measured along the
/// shaft in deformed coordinates (Fig. 6.4: "used with deformed coordinates"):
///   f(s) = f_shaft + (f_tip − f_shaft)·max(0, 1 − s/ℓ)   (N/m),   f(s) = 0 for s < 0,
/// i.e. f_tip at the tip, falling linearly to the shaft value over the bulge length ℓ. The
/// defaults (f_shaft = 50 N/m, f_tip = 150 N/m, ℓ = 5 mm) are incise's choice: the shape (a tip
/// bulge 3× the shaft value over 5 mm) is assumed, the magnitude was fitted so that the static
/// load of §6.8.3 gives the thesis' Table 6.3 errors on the coarse meshes (docs/needle.md).
///
/// Thresholds (§6.3.2): a needle node stands for the part of the shaft closer to it than to the
/// other needle nodes (lumped like a consistent load of linear elements): with the nodes sorted
/// by s, node k owns [b_k, b_{k+1}] with b_0 = 0, b_k = (s_{k−1} + s_k)/2 and the last interval
/// ending at the largest s. Its dynamic threshold is ∫ f over its interval (N), its static
/// threshold twice that (§6.8.1). In 3D a node's threshold comes from the needle-surface area
/// it owns instead (surface_thresholds()).

#include <vector>

namespace incise::needle {

/// Piecewise-linear shaft friction profile with a tip bulge (see file comment).
struct FrictionProfile {
  double shaft_density = 50.0;  ///< f_shaft, force per shaft length away from the tip (N/m)
  double tip_density = 150.0;   ///< f_tip, force per shaft length at the tip (N/m)
  double bulge_length = 5e-3;   ///< ℓ, length over which f falls from f_tip to f_shaft (m)
  double static_factor = 2.0;   ///< static threshold / dynamic threshold (§6.8.1: 2)

  /// Throws ParameterError when a density is negative or not finite, ℓ is not finite and > 0,
  /// or static_factor is not finite and ≥ 1.
  void validate() const;
  /// f(s) in N/m (0 for s < 0).
  double density(double s) const;
  /// ∫_a^b f(s) ds in N, exactly (a ≤ b; the part below s = 0 contributes nothing).
  double integral(double a, double b) const;
  /// Dynamic thresholds (N) of needle nodes at shaft coordinates s (any order), lumped as in
  /// the file comment; entry k belongs to s[k].
  std::vector<double> dynamic_thresholds(const std::vector<double>& s) const;
  /// Dynamic thresholds (N) of 3D needle nodes (§6.9, Fig. 6.14: friction from the needle
  /// surface's geometry): the profile's force per shaft length spread over the circumference
  /// is the per-area density f(s)/(2πr) (N/m²), and node k, at s[k] owning needle-surface area
  /// area[k] (m², needle3d.hpp needle_node_areas), gets f(s[k])·area[k]/(2πr). Throws
  /// UsageError when the sizes differ and ParameterError when radius is not finite and > 0.
  std::vector<double> surface_thresholds(const std::vector<double>& s,
                                         const std::vector<double>& area, double radius) const;
};

}  // namespace incise::needle
