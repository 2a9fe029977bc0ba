#pragma once
/// \file sweep.hpp
/// Collision of a moving line-segment scalpel with a mesh edge (thesis §5.3.2, Fig. 5.15,
/// eq. (5.1)), and the segment distance behind the maximum movement d_max (Fig. 5.11).
///
/// The scalpel moves from (h, t) to (h′, t′) (head and tail, m), both ends at constant velocity:
/// at time τ ∈ [0, 1] (the thesis' γ = 1 − τ) it is the segment T(τ) → H(τ), H(τ) = h + τ(h′ − h),
/// T(τ) = t + τ(t′ − t). A hit with the edge ab is a triple (τ, λ, µ) with
///   λ H(τ) + (1 − λ) T(τ) = µ a + (1 − µ) b,   λ, µ ∈ [0, 1],
/// which is eq. (5.1) (the thesis' x = (λγ, λ, γ, µ) is this system linearised in the product
/// λγ). Eliminating λ and µ leaves the condition that the scalpel line and the edge line be
/// coplanar, det(H − T, a − b, b − T) = 0: a quadratic c₀ + c₁τ + c₂τ² in τ (the thesis' quadratic
/// in the kernel coordinate α, written in τ so that the degenerate cases are visible in the
/// coefficients). Each root in [0, 1] gives λ, µ by least squares on the 3 × 2 system; a hit is
/// kept when the residual and the ranges hold within a relative tolerance. Cases:
///  - kQuadratic: two distinct real roots (or none: no hit);
///  - kLinear: c₂ ≈ 0 (a translating scalpel has c₂ = 0 exactly): τ = −c₀/c₁;
///  - kDoubleRoot: discriminant ≈ 0 (the scalpel line is tangent to the edge line's sweep);
///  - kCoplanar: c₀ ≈ c₁ ≈ c₂ ≈ 0 — the edge lies in the swept surface or is parallel to the
///    scalpel (parallel lines are always coplanar), so coplanarity has no isolated root. The first
///    contact is then the first τ at which the segment distance (segment_distance) vanishes: 64
///    uniform samples and 60 bisections of the first interval that starts apart and ends touching
///    (a contact shorter than 1/64 of the movement that does not last to a sample is missed —
///    stated, and only possible in this measure-zero case).
/// All decisions are in double precision with relative tolerance kSweepTolerance; the topology of
/// the cutter is decided by what it does with the hit, not by exact predicates.

#include <incise/core/types.hpp>

#include <vector>

namespace incise::delaunay {

/// Relative tolerance of the sweep tests: triple products of doubles carry rounding of about
/// 10 ε_mach ≈ 2e-15 of their permanent; 1e-12 leaves a factor 500 above it.
constexpr double kSweepTolerance = 1e-12;

/// One position of the line-segment scalpel: head and tail (m).
struct ScalpelSegment {
  Vec3 head = Vec3::Zero();  ///< h
  Vec3 tail = Vec3::Zero();  ///< t
};

/// The scalpel at time tau ∈ [0, 1] of the movement from → to (constant velocity of both ends).
ScalpelSegment interpolate(const ScalpelSegment& from, const ScalpelSegment& to, double tau);

/// Which form the coplanarity polynomial of eq. (5.1) took (see file comment).
enum class SweepCase { kQuadratic, kLinear, kDoubleRoot, kCoplanar };

/// Name of a SweepCase ("quadratic", "linear", "double root", "coplanar").
const char* to_string(SweepCase c);

/// One scalpel–edge contact: time τ (γ = 1 − τ), scalpel parameter λ (point λH + (1 − λ)T) and
/// edge parameter µ (point µa + (1 − µ)b), all clamped to [0, 1].
struct SweepHit {
  double time = 0;    ///< τ
  double lambda = 0;  ///< λ: 1 at the head, 0 at the tail
  double mu = 0;      ///< µ: 1 at a, 0 at b
};

/// Result of intersect_sweep_edge: the case and the hits in increasing time (at most two).
struct SweepEdgeResult {
  SweepCase kind = SweepCase::kQuadratic;  ///< form of the polynomial
  std::vector<SweepHit> hits;              ///< contacts, earliest first
};

/// Contacts of the scalpel moving from → to with the segment ab (eq. (5.1), see file comment).
/// A degenerate scalpel or edge (zero length) has no contact.
SweepEdgeResult intersect_sweep_edge(const ScalpelSegment& from, const ScalpelSegment& to,
                                     const Vec3& a, const Vec3& b);

/// Closest points of the segments p0p1 and q0q1: returns their distance and sets s, u ∈ [0, 1]
/// with the points p0 + s(p1 − p0), q0 + u(q1 − q0) (degenerate segments are points).
double segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1, double& s,
                        double& u);

/// Fig. 5.11's maximum movement for one edge: when neither scalpel end moves by d_max or more,
/// the scalpel cannot touch the edge pq. The thesis takes the distance of the two lines; the
/// same argument holds for the segments (the contact point λ(h + p) + (1 − λ)(t + q) lies within
/// |λp + (1 − λ)q| < d_max of the scalpel segment), which is never smaller, so this returns the
/// segment distance.
double max_movement(const ScalpelSegment& scalpel, const Vec3& p, const Vec3& q);

}  // namespace incise::delaunay
