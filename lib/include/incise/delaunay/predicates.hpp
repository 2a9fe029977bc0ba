#pragma once
/// \file predicates.hpp
/// Exact-sign 2D predicates for Delaunay cutting (thesis §5.2.1: the empty-circle criterion
/// decides every flip, so its sign must not depend on round-off — otherwise flips can cycle on
/// near-cocircular points).
///
/// Each predicate is evaluated first in double precision with a static error bound (a forward
/// bound on the rounding of the expression, relative to its permanent: orient2d (3 + 16ε)ε,
/// incircle (10 + 96ε)ε, ε = 2⁻⁵³). When |value| exceeds the bound its sign is certain;
/// otherwise the determinant is recomputed exactly as a floating-point expansion (sums of
/// non-overlapping doubles built with error-free TwoSum and FMA-based TwoProduct) and the sign
/// of the exact value is returned. The results are therefore the signs of the exact
/// determinants of the given double coordinates, provided no intermediate product underflows
/// or overflows: coordinates (and their differences) of magnitude in [1e-70, 1e70] or zero.
/// Test: delaunay_predicates_test (against exact integer arithmetic on near-degenerate sets).

#include <incise/core/types.hpp>

namespace incise::delaunay {

/// Orientation of (a, b, c): +1 counter-clockwise, −1 clockwise, 0 collinear (exact sign of
/// det[b − a, c − a]).
int orient2d(const Vec2& a, const Vec2& b, const Vec2& c);

/// Empty-circle test: for a counter-clockwise triangle (a, b, c), +1 when d lies strictly inside
/// its circumcircle, −1 strictly outside, 0 on it (exact sign of the lifted 3 × 3 determinant
/// with rows (x − d, y − d, |p − d|²), p = a, b, c). For a clockwise triangle the sign flips.
int incircle(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);

/// The same signs computed by the exact expansion path only (no filter); for tests and for
/// measuring the filter.
int orient2d_exact(const Vec2& a, const Vec2& b, const Vec2& c);
/// See orient2d_exact.
int incircle_exact(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d);

}  // namespace incise::delaunay
