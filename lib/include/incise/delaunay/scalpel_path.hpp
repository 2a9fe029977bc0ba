#pragma once
/// \file scalpel_path.hpp
/// The movements of a scalpel along sampled positions (thesis §5.2.2, §5.3: the scalpel is
/// moved in discrete steps, each a `move_to`): the first sample, then every segment between
/// consecutive samples in ⌈length / step⌉ equal movements (at least one). One definition for
/// the tests' `cut_along`, the ch. 5 reproductions and the Delaunay scenes (scene/
/// delaunay_scene.hpp).

#include <incise/core/error.hpp>
#include <incise/delaunay/sweep.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace incise::delaunay {

/// Most movements one segment may be divided into (beyond, the count would not fit an int).
inline constexpr double kMaxMovementsPerSegment = 1e8;

/// The scalpel positions of the movements along the polyline `path` (2D or 3D points), in steps
/// of at most `step` (m). Throws ParameterError for step ≤ 0 or not finite, or a segment that
/// needs more than kMaxMovementsPerSegment movements (or has a non-finite length).
template <class Point>
std::vector<Point> movement_points(const std::vector<Point>& path, double step) {
  INCISE_CHECK_PARAM(std::isfinite(step) && step > 0, "movement_points: step must be > 0");
  std::vector<Point> out;
  if (path.empty()) return out;
  out.push_back(path[0]);
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Point a = path[i - 1], b = path[i];
    const double m = std::ceil((b - a).norm() / step);
    INCISE_CHECK_PARAM(m <= kMaxMovementsPerSegment,
                       "movement_points: a segment needs more than 1e8 movements");
    const int n = std::max(1, static_cast<int>(m));
    for (int k = 1; k <= n; ++k) out.push_back(a + (b - a) * (static_cast<double>(k) / n));
  }
  return out;
}

/// The same for a line-segment scalpel (§5.3) sampled as `path`: a segment is divided so that
/// neither end moves more than `step` (m) per movement; both ends move at constant velocity
/// (interpolate(), eq. (5.1)). Throws as movement_points.
inline std::vector<ScalpelSegment> movement_segments(const std::vector<ScalpelSegment>& path,
                                                     double step) {
  INCISE_CHECK_PARAM(std::isfinite(step) && step > 0, "movement_segments: step must be > 0");
  std::vector<ScalpelSegment> out;
  if (path.empty()) return out;
  out.push_back(path[0]);
  for (std::size_t i = 1; i < path.size(); ++i) {
    const ScalpelSegment& a = path[i - 1];
    const ScalpelSegment& b = path[i];
    const double m = std::ceil(std::max((b.head - a.head).norm(), (b.tail - a.tail).norm()) / step);
    INCISE_CHECK_PARAM(m <= kMaxMovementsPerSegment,
                       "movement_segments: a segment needs more than 1e8 movements");
    const int n = std::max(1, static_cast<int>(m));
    for (int k = 1; k <= n; ++k) out.push_back(interpolate(a, b, static_cast<double>(k) / n));
  }
  return out;
}

}  // namespace incise::delaunay
