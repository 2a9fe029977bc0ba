#pragma once
/// \file surface.hpp
/// A triangle surface with boundary embedded in 3D under the local operations of Delaunay
/// cutting on surfaces (thesis §5.3.1): edge flips by the unfolded empty-circle criterion,
/// refusal of topologically impossible flips (Fig. 5.9), Lawson legalization, node removal by
/// ear flips (Fig. 5.10), and the node insertions and movements of the surface cutter.
///
/// The surface is an oriented 2-manifold with boundary on the ch. 7 connectivity (dimension 2,
/// positions in 3D). Every topological change is one Connectivity::replace_elements call (§7.3).
/// Orientation is combinatorial (the Simplex sign, §7.2): a triangle (a, b, c) has normal
/// (b − a) × (c − a), and neighbouring triangles agree (validate() checks the mates, (7.3)).
///
/// Unfolded criterion (§5.3.1: "the incident triangles are unfolded to be coplanar, and then the
/// two-dimensional criterion is used"): for the edge pq with triangles (p, q, c) and (q, p, d),
/// c and d are placed in the plane at their true distances from p and q, on either side of pq,
/// and the exact incircle/orient2d of predicates.hpp decide on these planar coordinates. The
/// thesis notes that termination of flipping by this criterion on a curved surface is not known
/// ("this technique is now truly a heuristic"): legalize() therefore caps its flips and reports
/// when the cap ended it.
///
/// Geometric guards (a surface has no orientation predicate that makes a triangle "inverted"):
/// a new or moved triangle must keep 2·area ≥ kSurfaceMinShape · longest edge², and its normal
/// must make an acute angle with the normal of what it replaces (no fold-over).

#include <incise/core/types.hpp>
#include <incise/delaunay/edge.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <array>
#include <set>
#include <vector>

namespace incise::delaunay {

/// Shape floor of surface triangles: 2·area ≥ 1e-8 · longest edge² (the planar cutter's floor,
/// cutter2d.hpp: flatter triangles are of no use to an element computation).
constexpr double kSurfaceMinShape = 1e-8;

/// Why Surface::try_flip did or did not flip.
enum class FlipStatus {
  kFlipped,      ///< flipped
  kNotAnEdge,    ///< {p, q} is not an edge with two triangles (missing or boundary)
  kConstrained,  ///< marked constrained
  kNotConvex,    ///< the unfolded quadrilateral is not strictly convex
  kTopological,  ///< Fig. 5.9: the new edge already exists (it would occur twice)
  kShape,        ///< a new triangle would be flatter than the floor or fold over
  kRestricted,   ///< a new triangle would have two active nodes (§5.3.2)
};

/// Name of a FlipStatus ("flipped", "not an edge", …).
const char* to_string(FlipStatus s);

/// The unfolded empty-circle test (§5.3.1): p, q, c, d are placed in a plane with p at the
/// origin, q on the positive x-axis, c above and d below at their true distances from p and q;
/// returns the exact incircle sign of the planar points (predicates.hpp): +1 when d lies
/// strictly inside the circle through p, q, c; 0 also when c or d is collinear with pq.
int unfolded_incircle(const Vec3& p, const Vec3& q, const Vec3& c, const Vec3& d);

/// Shapes of the generated test and demonstration surfaces.
enum class SurfaceShape {
  kCylinder,  ///< a 120° patch of a unit-radius cylinder, 2 long
  kBell,  ///< the Gaussian bell of Fig. 5.19: z = 0.4 exp(−(x² + y²)/0.5²) over [−1, 1]²
  kFold,  ///< a 270° patch of a unit-radius cylinder, 2 long: a scalpel meets it twice
};

/// Maps the parameter point (u, v) (the unit square and its continuation beyond it) onto the
/// shape; `normal` receives the unit normal there (the side the generated triangles face).
Vec3 surface_point(SurfaceShape shape, double u, double v, Vec3* normal = nullptr);

/// A regular n × m grid of the unit parameter square (mesh::make_rectangle, alternating
/// diagonals; m = n when m ≤ 0) mapped onto `shape`: 2nm triangles, a disc with boundary.
/// Throws ParameterError for n < 2 or 0 < m < 2.
mesh::MeshData make_surface(SurfaceShape shape, int n, int m = 0);

/// A pleated "monkey saddle" for three-way branching (Fig. 5.18): an equilateral triangle
/// lattice of edge h = 2/n (rows parallel to x, a node at the origin whose six neighbours lie at
/// 0°, 60°, …, 300°; rows y = j h √3/2 for |j| ≤ J, the largest odd J with J h √3/2 ≤ 1; rows of
/// even j hold x = i h, odd j x = (i + ½) h, |x| ≤ 1), lifted to z = slope · r · cos 3θ — zero
/// along the rays θ = 30°, 90°, 150°, …, so a line y = c > 0, z = 0 meets it three times, and
/// every node's star around the origin alternates up and down. Mirror symmetric in x with
/// z(−x, y) = −z(x, y). Throws ParameterError for an odd n < 4 or slope outside (0, 1].
mesh::MeshData make_monkey_saddle(int n, double slope);

/// Triangle surface in 3D (see file comment).
class Surface {
 public:
  /// Takes a triangle mesh (MeshData::dimension == 2) with 3D points. Throws ParameterError when
  /// a coordinate is not finite or beyond 1e60 m, a triangle is flatter than the shape floor, or
  /// the triangles do not form a consistently oriented 2-manifold (validate() fails); UsageError
  /// for an invalid cell set (Connectivity::from_mesh_data).
  explicit Surface(const mesh::MeshData& mesh);

  /// The connectivity (thesis ch. 7).
  const mesh::Connectivity& connectivity() const { return conn_; }
  /// Position of vertex v (m).
  Vec3 point(Index v) const { return points_.col(v); }
  /// Positions, 3 × (at least num_vertices) (spare capacity past num_vertices).
  const Eigen::Matrix3Xd& points() const { return points_; }
  /// The current mesh as arrays (removed vertices stay as unused points).
  mesh::MeshData to_mesh_data() const;
  /// Live triangles.
  Index num_triangles() const { return conn_.num_elements(); }

  /// The live triangles incident with edge {p, q}: 0, 1 or 2.
  std::vector<mesh::ElementHandle> incident(Index p, Index q) const;
  /// Whether {p, q} is an edge with exactly one triangle.
  bool is_boundary_edge(Index p, Index q) const { return incident(p, q).size() == 1; }
  /// Whether v has a triangle and no boundary edge.
  bool is_interior_vertex(Index v) const;
  /// The vertices of live triangle e in orientation order.
  std::array<Index, 3> triangle(mesh::ElementHandle e) const;
  /// The triangle containing the directed edge p→q, or an invalid handle.
  mesh::ElementHandle left_of(Index p, Index q) const;
  /// The vertices sharing an edge with v, sorted.
  std::vector<Index> neighbours(Index v) const;
  /// All edges, each once, sorted.
  std::vector<Edge> edges() const;
  /// (b − a) × (c − a) of live triangle e = (a, b, c): twice its area along its normal.
  Vec3 area_normal(mesh::ElementHandle e) const;

  /// Marks (or unmarks) {p, q} as constrained: never flipped.
  void set_constrained(Index p, Index q, bool constrained = true);
  /// Whether {p, q} is marked constrained.
  bool is_constrained(Index p, Index q) const { return constrained_.count(make_edge(p, q)) != 0; }

  /// Marks (or unmarks) v as an active node (§5.3.2): no flip or replace makes a triangle with
  /// two marked nodes (so a cutter that marks its active nodes keeps at most one per triangle).
  /// Negative v is ignored.
  void set_active_node(Index v, bool active = true);
  /// Whether v is marked as an active node.
  bool is_active_node(Index v) const { return active_.count(v) != 0; }

  /// The unfolded empty-circle criterion (§5.3.1, file comment): true for a boundary,
  /// constrained or missing edge, and for an interior edge whose unfolded opposite vertex d is
  /// not strictly inside the circumcircle of the unfolded (p, q, c).
  bool is_locally_delaunay(Index p, Index q) const;
  /// Flips the interior edge {p, q} — (p, q, c), (q, p, d) become (c, d, q), (d, c, p) — when the
  /// unfolded quadrilateral is strictly convex, {c, d} is not already an edge (Fig. 5.9) and the
  /// new triangles pass the shape and fold guards. Returns what happened.
  FlipStatus try_flip(Index p, Index q);
  /// try_flip(p, q) == kFlipped.
  bool flip(Index p, Index q) { return try_flip(p, q) == FlipStatus::kFlipped; }
  /// Lawson legalization by the unfolded criterion from `edges`, at most
  /// kMaxFlipsPerLegalize flips (termination on a curved surface is not known, §5.3.1).
  /// Returns the number of flips.
  long legalize(std::vector<Edge> edges);
  /// The flip cap of one legalize() call.
  static constexpr long kMaxFlipsPerLegalize = 4096;

  /// Removes interior vertex v by ear flips (Fig. 5.10; the ear is an edge whose flip the
  /// unfolded test accepts). False when v is not interior, has a constrained edge, or no ear
  /// flip is possible (the mesh stays valid; v keeps its triangles).
  bool remove_vertex(Index v);

  /// A new vertex at x without triangles. Throws ParameterError for a non-finite x.
  Index add_vertex(const Vec3& x);
  /// Moves v to x when every triangle of its star passes the shape floor and keeps its normal
  /// within 90° of its current one, of the triangle beyond its edge opposite v, and of its star
  /// neighbours; false (unchanged) otherwise.
  bool move_vertex(Index v, const Vec3& x);
  /// Replaces the triangles `remove` by `add` (vertex triples in orientation order) in one
  /// replace_elements call when every new triangle passes the shape floor and the fold and
  /// crease guards (file comment) and has at most one active node; false (unchanged) otherwise.
  bool replace(const std::vector<mesh::ElementHandle>& remove,
               const std::vector<std::array<Index, 3>>& add);
  /// Inserts a vertex at x on the boundary edge {p, q}: its triangle (p, q, r) becomes two.
  /// Returns it, or −1 (unchanged) when {p, q} is not a boundary edge or replace refuses.
  Index split_boundary_edge(Index p, Index q, const Vec3& x);

  /// Inserts a vertex at x in live triangle e: (a, b, c) becomes (a, b, x), (b, c, x), (c, a, x)
  /// when replace accepts them. Returns it, or −1 (x stays an unused vertex) otherwise.
  Index split_triangle(mesh::ElementHandle e, const Vec3& x);

  /// Registers / unregisters an observer of the connectivity's changes (§7.4).
  void add_watcher(mesh::ConnectivityWatcher* w) { conn_.add_watcher(w); }
  /// See add_watcher.
  void remove_watcher(mesh::ConnectivityWatcher* w) { conn_.remove_watcher(w); }

  /// Flips made so far.
  long num_flips() const { return flips_; }
  /// Flips refused as topologically impossible (Fig. 5.9) so far.
  long num_topological_refusals() const { return topological_; }
  /// Flips and replacements refused because a triangle would get two active nodes (§5.3.2).
  long num_restricted() const { return restricted_; }
  /// legalize() calls that stopped at the flip cap so far.
  long num_capped_legalizations() const { return capped_; }
  /// Smallest and largest interior angle over live triangles (radians).
  std::pair<double, double> angle_range() const;

 private:
  bool admissible(const std::vector<mesh::ElementHandle>& remove,
                  const std::vector<std::array<Index, 3>>& add) const;

  mesh::Connectivity conn_;
  Eigen::Matrix3Xd points_;
  std::set<Edge> constrained_;
  std::set<Index> active_;
  long flips_ = 0, topological_ = 0, capped_ = 0;
  mutable long restricted_ = 0;  // counted by the const admissibility test
};

}  // namespace incise::delaunay
