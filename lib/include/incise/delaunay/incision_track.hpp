#pragma once
/// \file incision_track.hpp
/// The state of the incision that ends at an active node, shared by the planar Cutter2D
/// (§5.2.2) and the SurfaceCutter (§5.3.1); the operations on it (fix-up, split, exit) are in
/// lib/src/delaunay/incision.hpp.

#include <incise/core/types.hpp>

#include <vector>

namespace incise::delaunay {

/// The last incision node pair (cut edges (left, a) and (a, right), Fig. 5.5), the scalpel path
/// since that pair, and the node lists of both sides of every incision so far (two lists per
/// incision, in path order). Vec is Vec2 (plane) or Vec3 (surface).
template <class Vec>
struct IncisionTrack {
  Index left = -1;                        ///< c_l
  Index right = -1;                       ///< c_r
  std::vector<Vec> path;                  ///< positions since the last node pair
  std::vector<std::vector<Index>> sides;  ///< two lists per incision
};

}  // namespace incise::delaunay
