#pragma once
/// \file fd_check.hpp
/// The acceptance thresholds of the finite-difference checks of energies, forces and tangents
/// (material, element and problem property tests; issue 3): one definition, so every suite
/// holds its derivatives to the same standard.

namespace incise::test {

/// Relative error of the best central difference of the 1e-2 … 1e-8 step sweep. On these smooth
/// sums the best step reaches ~1e-9 relative: three digits of margin.
inline constexpr double kFdTolerance = 1e-6;

/// Observed Taylor order of the remainder |Π(x + h d) − Π(x) − h ∇Π·d| (2 in exact arithmetic):
/// at least 1.9 (issue 3).
inline constexpr double kMinTaylorOrder = 1.9;

}  // namespace incise::test
