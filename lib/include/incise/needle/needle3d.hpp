#pragma once
/// \file needle3d.hpp
/// The rigid needle of thesis §6.4 in 3D (§6.9, Fig. 6.14): a straight shaft of radius r, its
/// needle nodes' coordinates, and the needle as a surface of mesh faces ("represented in the
/// mesh by a jagged surface").
///
/// A pose is the tip, the unit shaft direction t (base → tip), the length L, the radius r and a
/// unit normal n1 ⟂ t; n2 = t × n1 completes the right-handed needle frame (t, n1, n2). A point
/// x has needle coordinates d_needle = s = (tip − x)·t (distance behind the tip along the shaft)
/// and d_perp = ((x − tip)·n1, (x − tip)·n2), its offset perpendicular to the shaft in the
/// frame; conversely x = tip − s·t + d_perp₀·n1 + d_perp₁·n2. When the needle moves, needle
/// nodes keep (s, d_perp) relative to the new pose (§6.7), and the frame moves with the needle
/// by the rotation of least angle taking the old t to the new one (moved()), so a needle that
/// only advances or turns does not spin its nodes about the shaft.
///
/// Needle surface (docs/needle.md, "3D"): the mesh faces (triangles of the tetrahedra, interior
/// or boundary) whose three vertices are needle nodes, except the faces all of whose incident
/// tetrahedra have four needle-node vertices (those lie inside the jagged needle, not on it).

#include <incise/core/types.hpp>
#include <incise/mesh/mesh_data.hpp>
#include <incise/needle/needle.hpp>

#include <vector>

namespace incise::needle {

/// Needle coordinates of a point in 3D (Fig. 6.5 with a two-component d_perp).
struct NeedleCoordinates3D {
  double s = 0.0;            ///< d_needle: distance along the shaft behind the tip (m)
  Vec2 perp = Vec2::Zero();  ///< d_perp: offset along (n1, n2) (m)
};

/// The 3D needle node (needle.hpp NeedleNodeT).
using NeedleNode3D = NeedleNodeT<NeedleCoordinates3D>;

/// Pose and shape of the rigid 3D needle (see file comment).
struct NeedlePose3D {
  Vec3 tip = Vec3::Zero();         ///< tip position (m, world = deformed configuration)
  Vec3 direction = Vec3::UnitX();  ///< unit shaft direction t, base → tip
  Vec3 normal = Vec3::UnitY();     ///< unit n1 ⟂ t
  double length = 0.1;             ///< L (m)
  double radius = 1e-3;            ///< r (m)

  /// Pose with tip `tip`, direction `direction` (any non-zero length), length and radius; n1 is
  /// the unit vector of the coordinate axis least aligned with t (lowest index on ties) with
  /// its t component removed. Throws ParameterError as validate().
  static NeedlePose3D make(const Vec3& tip, const Vec3& direction, double length, double radius);
  /// Throws ParameterError when tip is not finite, direction or normal is zero, not finite or
  /// (for normal) not perpendicular to direction within 1e-9 after normalisation, or length or
  /// radius is not finite and > 0.
  void validate() const;
  /// Unit shaft direction t.
  const Vec3& tangent() const { return direction; }
  /// n1.
  const Vec3& normal1() const { return normal; }
  /// n2 = t × n1.
  Vec3 normal2() const { return direction.cross(normal); }
  /// The orthonormal frame (columns t, n1, n2): the rotation R of one needle node (§6.6).
  Mat3 frame() const;
  /// The base end tip − L·t.
  Vec3 base() const { return tip - length * direction; }
  /// (s, d_perp) of world point x.
  NeedleCoordinates3D coordinates(const Vec3& x) const;
  /// World point with needle coordinates c.
  Vec3 point(const NeedleCoordinates3D& c) const;
  /// This needle (length, radius) with tip `tip` and direction `direction` (any non-zero
  /// length), its frame rotated by the least-angle rotation taking t to the new direction (a
  /// half turn about n1 when they are opposite). Throws ParameterError for a bad tip or
  /// direction.
  NeedlePose3D moved(const Vec3& tip, const Vec3& direction) const;
};

/// Closest approach of a segment [a, b] to the needle's axis segment [base, tip].
struct ShaftApproach {
  double distance = 0.0;  ///< least distance between the two segments (m)
  double alpha = 0.0;  ///< where on [a, b] it is attained: a + alpha·(b − a), alpha ∈ [0, 1]
  double s = 0.0;      ///< and on the axis: s behind the tip, in [0, L]
};

/// Closest approach of [a, b] to the axis of `pose` (Ericson, Real-Time Collision Detection,
/// 2005, §5.1.9; for parallel segments one of the closest pairs).
ShaftApproach shaft_approach(const NeedlePose3D& pose, const Vec3& a, const Vec3& b);

/// The needle surface (file comment) of tetrahedra `tets` (4 × m) with needle-node flags
/// `is_needle` (one per vertex): 3 × k faces, each as its sorted vertex triple, sorted. Throws
/// UsageError when tets has not 4 rows or a vertex is out of range of is_needle.
mesh::CellMatrix needle_surface(const mesh::CellMatrix& tets, const std::vector<char>& is_needle);

/// Needle-surface area owned by each vertex in `vertices` (m²): a third of the area, at
/// positions `x` (3 × n, m), of every face of `faces` (3 × k) it is a vertex of. Entry k
/// belongs to vertices[k]; vertices on no face own 0.
std::vector<double> needle_node_areas(const Eigen::Matrix3Xd& x, const mesh::CellMatrix& faces,
                                      const std::vector<Index>& vertices);

}  // namespace incise::needle
