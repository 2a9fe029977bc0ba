#pragma once
// Planar vector helpers shared by the 2D cutters (cutter2d.cpp, subdivision.cpp).

#include <incise/core/types.hpp>

namespace incise::delaunay {

/// The z component of the cross product of two plane vectors, a.x b.y − a.y b.x (twice the
/// signed area of the triangle they span; not an exact predicate: predicates.hpp has those).
inline double cross(const Vec2& a, const Vec2& b) {
  return a.x() * b.y() - a.y() * b.x();
}

}  // namespace incise::delaunay
