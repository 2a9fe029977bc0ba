#pragma once
/// \file tet_shape.hpp
/// Shape measures used by degeneracy removal (thesis §3.2.3): the aspect ratio
/// min_p d(p, plane(τ∖{p})) / max_{p,q} |p − q| and the six interior dihedral angles, with
/// the needle / spindle / sliver / cap classification by the number of large angles.

#include <incise/core/types.hpp>

#include <array>

namespace incise::cut {

/// Shape class of a flat tetrahedron by its number of large dihedral angles (Fig. 3.8).
enum class DegeneracyShape {
  kNeedle,   ///< no large dihedral angle (short edge or flat triangles)
  kSpindle,  ///< one large angle: a vertex close to an edge of the opposite face
  kSliver,   ///< two large angles at opposite edges: the two edges cross
  kCap       ///< three large angles around one face: a vertex close to that face's interior
};

/// Shape measures of one tetrahedron.
struct TetShape {
  double aspect_ratio = 0.0;         ///< signed min height / max edge length (< 0: inverted)
  std::array<double, 6> dihedral{};  ///< interior dihedral angle (rad) at edge kTetEdge[k]
  int shortest_edge = 0;             ///< index into kTetEdge
};

/// Computes aspect ratio and dihedral angles of tetrahedron p[0..3] (any positions, m).
TetShape tet_shape(const std::array<Vec3, 4>& p);

/// Classifies by the number of dihedral angles above `large_angle` (rad); `large_edges`
/// receives the kTetEdge indices of the large angles (sorted by decreasing angle).
DegeneracyShape classify(const TetShape& s, double large_angle, std::array<int, 6>& large_edges,
                         int& num_large);

}  // namespace incise::cut
