#pragma once
/// \file quality.hpp
/// Geometry and quality measures of linear simplices (triangles, tetrahedra) and of whole meshes.
///
/// Measures (all dimensionless unless stated; positions in metres):
/// - signed volume of a tetrahedron, V = (b−a)·((c−a)×(d−a))/6 (m³), positive for positively
///   oriented cells; signed area of a triangle in the xy plane (m²);
/// - the thesis' aspect ratio (Nienhuys 2003, §3.2.3): min over vertices p of the distance of p
///   to the plane (line, in 2D) of the opposite facet, divided by the maximum edge length.
///   A regular tetrahedron has √(2/3) ≈ 0.8165, an equilateral triangle √3/2 ≈ 0.8660; a flat
///   element has 0. §3.2.3 calls an element degenerate when it is below 0.01 (§3.3 example);
/// - interior dihedral angles of a tetrahedron at its six edges (radians), angles of a triangle;
/// - Shewchuk's volume–area measure ("What is a good linear finite element?", 2002, Table 1):
///   q = 3^{7/4}/(2√2) · V / A_rms^{3/2} with A_rms = √(Σ_i A_i² / 4) the root-mean-square of the
///   four face areas; in 2D q = 4/√3 · A / ℓ_rms² with ℓ_rms² = Σ ℓ_i² / 3. Signed (negative for
///   inverted elements), 1 for the regular element, → 0 for any degenerate shape, and it bounds
///   both the interpolation error and the stiffness-matrix conditioning (Shewchuk §6);
/// - the needle/spindle/sliver/cap classification of §3.2.3 (after Bern et al.): a degenerate
///   tetrahedron is classified by the number of large dihedral angles it has.

#include <incise/core/types.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <array>
#include <vector>

namespace incise::mesh {

/// Signed volume (m³) of tetrahedron (a,b,c,d): (b−a)·((c−a)×(d−a))/6. Positive when
/// (b−a, c−a, d−a) is a right-handed frame (the orientation used throughout incise).
double signed_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Signed area (m²) of triangle (a,b,c) projected on the xy plane; positive counter-clockwise.
double signed_area_xy(const Vec3& a, const Vec3& b, const Vec3& c);

/// Unsigned area (m²) of triangle (a,b,c) in space, |(b−a)×(c−a)|/2.
double triangle_area(const Vec3& a, const Vec3& b, const Vec3& c);

/// The six edges of a tetrahedron as local vertex pairs, in the order used by every per-edge
/// array returned here: (0,1) (0,2) (0,3) (1,2) (1,3) (2,3).
constexpr std::array<std::array<int, 2>, 6> kTetEdges = {
    {{{0, 1}}, {{0, 2}}, {{0, 3}}, {{1, 2}}, {{1, 3}}, {{2, 3}}}};

/// Interior dihedral angles (radians, in [0, π]) of the tetrahedron at its six edges in
/// kTetEdges order. The angle at edge (i,j) is the angle between the components of
/// (p_k − p_i) and (p_l − p_i) orthogonal to the edge, computed with atan2 so that it is
/// accurate near 0 and π. Independent of orientation; flat tetrahedra give angles 0 or π.
/// Precondition: no vertex lies on the line through the others' edges (otherwise NaN-free but
/// meaningless 0 is returned for the affected edge).
std::array<double, 6> dihedral_angles(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Interior angles (radians) of triangle (a,b,c) at a, b and c.
std::array<double, 3> triangle_angles(const Vec3& a, const Vec3& b, const Vec3& c);

/// Thesis aspect ratio of a tetrahedron (§3.2.3): min_p d(p, plane(τ∖{p})) / max_{p,q} |p−q|.
/// Heights are computed as 3|V|/A_opposite. Returns 0 for a flat or collapsed element.
double aspect_ratio(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Thesis aspect ratio of a triangle: min height / max edge (height = 2·area / opposite edge).
double aspect_ratio(const Vec3& a, const Vec3& b, const Vec3& c);

/// Shewchuk's volume–area quality of a tetrahedron, 3^{7/4}/(2√2) · V / A_rms^{3/2}; signed,
/// 1 for the regular tetrahedron. Returns 0 when all faces have zero area.
double volume_area_quality(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Shewchuk's area–length quality of a triangle in the xy plane, 4/√3 · A / ℓ_rms² (signed by
/// the xy orientation); 1 for the equilateral triangle. With `signed_xy` false the unsigned
/// area in space is used (surface triangles).
double area_length_quality(const Vec3& a, const Vec3& b, const Vec3& c, bool signed_xy = true);

/// Shape class of §3.2.3. Only degenerate elements (aspect ratio below the threshold) are
/// classified; the others are kGood.
enum class ShapeClass {
  kGood,     ///< aspect ratio ≥ threshold
  kNeedle,   ///< degenerate, no large dihedral angle (a short edge): collapse shortest edge
  kSpindle,  ///< one large angle: split the opposite edge, collapse the shortest edge
  kSliver,   ///< two large angles (on opposite edges): split both, collapse the short edge
  kCap,      ///< three large angles (around one vertex): insert a node in the opposite face
  kFlat      ///< ≥ 4 large angles or undefined angles (collapsed to a line/point)
};

/// Name of a shape class ("good", "needle", ...).
const char* to_string(ShapeClass c);

/// Thresholds of the §3.2.3 classification; defaults are the values of the thesis' example in
/// §3.3 ("aspect ratio less than 0.01", "dihedral angle ... exceeds 0.99π").
struct ShapeThresholds {
  double degenerate_aspect_ratio = 0.01;               ///< below this an element is degenerate
  double large_angle = 0.99 * 3.14159265358979323846;  ///< radians; larger is "large"
};

/// Classification of one tetrahedron: class, its aspect ratio, and which edges (kTetEdges
/// order) carry a large dihedral angle.
struct ShapeInfo {
  ShapeClass shape = ShapeClass::kGood;
  double aspect_ratio = 0;
  std::array<bool, 6> large_angle_edge{};  ///< true for edges whose dihedral angle is large
  int num_large_angles = 0;
};

/// Classifies a tetrahedron per §3.2.3 (needle: 0 large angles, spindle: 1, sliver: 2,
/// cap: 3). For triangles (2D) see classify_triangle.
ShapeInfo classify_tetrahedron(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d,
                               const ShapeThresholds& t = {});

/// 2D analogue (Bern–Eppstein): a degenerate triangle is a needle (no large angle, short edge)
/// or a cap (one large angle, reported as kCap). large_angle_edge[i] marks the edge opposite
/// vertex i (i < 3).
ShapeInfo classify_triangle(const Vec3& a, const Vec3& b, const Vec3& c,
                            const ShapeThresholds& t = {});

/// Five-number-like summary of a sample: min, 5th percentile, median, mean, 95th percentile,
/// max. All zero (count 0) for an empty sample.
struct Stats {
  Index count = 0;
  double min = 0, p05 = 0, median = 0, mean = 0, p95 = 0, max = 0;
};

/// Summary of a sample (copies and partially sorts it). Percentiles by nearest rank.
Stats summarize(std::vector<double> values);

/// Per-cell quality measures of a mesh (one entry per cell).
struct CellQuality {
  int dimension = 3;                 ///< of the mesh measured: 3 tetrahedra, 2 triangles
  std::vector<double> size;          ///< signed volume (m³) or signed xy area (m²)
  std::vector<double> aspect_ratio;  ///< thesis aspect ratio (§3.2.3)
  std::vector<double> shewchuk;      ///< volume–area (3D) / area–length (2D) quality
  std::vector<double> min_angle;     ///< min dihedral (3D) / min angle (2D), radians
  std::vector<double> max_angle;     ///< max dihedral (3D) / max angle (2D), radians
  std::vector<ShapeClass> shape;     ///< §3.2.3 class
};

/// Computes CellQuality for every cell. For dimension-2 meshes the sign of `size` and
/// `shewchuk` is the xy orientation when `planar` is true, else they are unsigned.
CellQuality cell_quality(const MeshData& m, const ShapeThresholds& t = {}, bool planar = true);

/// Summary of a mesh's quality.
struct QualitySummary {
  int dimension = 3;
  Index num_cells = 0;
  Index num_inverted = 0;  ///< cells with negative signed size (planar / volume meshes)
  Index num_zero = 0;      ///< cells with exactly zero size
  double total_size = 0;   ///< Σ signed size (volume m³ / area m²)
  Stats size, aspect_ratio, shewchuk, min_angle_deg, max_angle_deg, edge_length;
  std::array<Index, 6> shape_counts{};  ///< indexed by ShapeClass
};

/// Quality summary of a mesh (angles reported in degrees, edge lengths over unique edges).
QualitySummary summarize_quality(const MeshData& m, const ShapeThresholds& t = {},
                                 bool planar = true);

/// Axis-aligned bounding box of a point set (lo, hi); both zero for an empty set.
std::array<Vec3, 2> bounding_box(const Eigen::Matrix3Xd& points);

}  // namespace incise::mesh
