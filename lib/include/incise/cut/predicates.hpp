#pragma once
/// \file predicates.hpp
/// Geometric predicates for cutting (thesis §3.2.1): orientation, segment–triangle and
/// triangle–tetrahedron intersection, evaluated in double precision with a stated tolerance.
///
/// Tolerance policy. orient3d(a,b,c,d) = (a−d)·((b−d)×(c−d)) is evaluated in double. Its
/// rounding error is below ~1e-15·|a−d||b−d||c−d| (Shewchuk's static bound for this
/// expression is 7.8e-16 times the permanent). We declare the sign *zero* whenever
/// |orient3d| ≤ kOrientRelEps·|a−d||b−d||c−d| with kOrientRelEps = 1e-12, i.e. three orders
/// of magnitude above rounding noise. Inside that band a configuration is treated as exactly
/// degenerate (a point on the plane, a segment through a triangle edge or vertex). The
/// consequences are deliberate and consistent: a segment touching the sweep triangle's
/// closed boundary counts as intersecting it; a segment lying *in* the sweep plane does not
/// intersect it (its endpoints are reached through the other edges at those nodes).
/// Because every mesh edge is tested once per sweep triangle and the result cached, two
/// tetrahedra sharing an edge always see the same answer.

#include <incise/core/types.hpp>

namespace incise::cut {

/// Relative tolerance under which an orientation determinant is treated as zero (see file
/// comment for the justification).
inline constexpr double kOrientRelEps = 1e-12;

/// Orientation determinant (a−d)·((b−d)×(c−d)) (m³): six times a signed volume. It is
/// negative for a positively oriented tetrahedron (a,b,c,d) in the MeshData convention
/// (signed_volume(a,b,c,d) = det[b−a, c−a, d−a]/6 > 0 ⇔ orient3d(a,b,c,d) < 0).
double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Sign of orient3d with the tolerance band of kOrientRelEps: −1, 0 or +1.
int orient3d_sign(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Signed volume det[b−a, c−a, d−a]/6 of tetrahedron (a,b,c,d) (m³).
double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Result of a segment–triangle test.
struct SegmentHit {
  bool hit = false;  ///< the closed segment meets the closed triangle at a single point
  double t = 0.0;    ///< parameter of the intersection point p + t (q − p), in [0,1]
};

/// Intersection of the closed segment pq with the closed triangle abc. A segment coplanar
/// with the triangle (both endpoints within the tolerance band of its plane) is reported as
/// not intersecting (see file comment). Precondition: abc is not degenerate.
SegmentHit intersect_segment_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b,
                                      const Vec3& c);

/// Whether the closed triangle abc and the closed tetrahedron t[0..3] intersect, up to the
/// tolerance policy: true if an edge of the tetrahedron hits the triangle, an edge of the
/// triangle hits a face of the tetrahedron, or a vertex of the triangle lies inside it.
bool triangle_meets_tetrahedron(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3 (&t)[4]);

/// Barycentric coordinates of p with respect to tetrahedron t[0..3] (sum to 1). Returns
/// false (and leaves `lambda` unspecified) if the tetrahedron is degenerate.
bool barycentric(const Vec3& p, const Vec3 (&t)[4], double (&lambda)[4]);

}  // namespace incise::cut
