#pragma once
/// \file needle.hpp
/// The rigid line-segment needle of thesis §6.4 and its needle nodes (Fig. 6.5).
///
/// A pose is the tip position, the unit shaft direction t (from the base towards the tip) and
/// the length L; the base is tip − L·t and the normal n = (−t_y, t_x). A point x is described
/// by needle coordinates (Fig. 6.5): d_needle = s = (tip − x)·t, the distance along the shaft
/// behind the tip, and d_perp = (x − tip)·n, its offset perpendicular to the shaft; conversely
/// x = tip − s·t + d_perp·n. When the needle moves, needle nodes keep (s, d_perp) relative to
/// the new pose (§6.7). The point lies alongside the shaft when 0 ≤ s ≤ L.

#include <incise/core/types.hpp>

#include <vector>

namespace incise::needle {

/// Needle coordinates of a point (Fig. 6.5).
struct NeedleCoordinates {
  double s = 0.0;     ///< d_needle: distance along the shaft behind the tip (m)
  double perp = 0.0;  ///< d_perp: offset perpendicular to the shaft, along n (m)
};

/// Pose of the rigid needle (see file comment).
struct NeedlePose {
  Vec2 tip = Vec2::Zero();         ///< tip position (m, world = deformed configuration)
  Vec2 direction = Vec2::UnitX();  ///< shaft direction, base → tip (normalised by validate())
  double length = 0.1;             ///< L (m)

  /// Pose with tip `tip`, direction `direction` (any non-zero length) and length `length`.
  /// Throws ParameterError when tip is not finite, direction is zero or not finite, or length
  /// is not finite and > 0.
  static NeedlePose make(const Vec2& tip, const Vec2& direction, double length);
  /// Throws ParameterError as make() for an inadmissible pose.
  void validate() const;
  /// Unit shaft direction t.
  Vec2 tangent() const { return direction; }
  /// Unit normal n = (−t_y, t_x).
  Vec2 normal() const { return Vec2(-direction.y(), direction.x()); }
  /// The orthonormal needle frame (columns t, n): the rotation R of one needle node (§6.6).
  Eigen::Matrix2d frame() const {
    Eigen::Matrix2d r;
    r << tangent(), normal();
    return r;
  }
  /// The base end tip − L·t.
  Vec2 base() const { return tip - length * direction; }
  /// (s, d_perp) of world point x.
  NeedleCoordinates coordinates(const Vec2& x) const;
  /// World point with needle coordinates c.
  Vec2 point(const NeedleCoordinates& c) const;
};

/// Stick–slip state of a needle node (§6.3.2).
enum class NodeState {
  kStick,  ///< fixed to the needle: both coordinates (s, d_perp) held
  kSlip    ///< constrained to move parallel to the shaft: d_perp held, s free, friction applied
};

/// Name of a NodeState ("stick", "slip").
const char* to_string(NodeState s);

/// A needle node: a mesh vertex attached to the needle (§6.4), with needle coordinates of type
/// `Coordinates` (NeedleCoordinates in 2D, NeedleCoordinates3D in 3D, needle3d.hpp).
template <class Coordinates>
struct NeedleNodeT {
  Index vertex = -1;                    ///< mesh vertex
  NodeState state = NodeState::kStick;  ///< stick or slip
  Coordinates coords;                   ///< (s, d_perp) relative to the current pose
  /// s when the node was last fixed or at the start of the current update: the slip since then,
  /// s − anchor, must oppose the friction force for slipping to be admissible.
  double anchor = 0.0;
  /// For a slipping node, the sign (±1) of the friction force on the material along t: the sign
  /// of the tangential reaction when the node broke loose. 0 while sticking.
  int friction_sign = 0;
};

/// The 2D needle node (Fig. 6.5).
using NeedleNode = NeedleNodeT<NeedleCoordinates>;

}  // namespace incise::needle
