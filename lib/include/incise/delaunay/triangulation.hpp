#pragma once
/// \file triangulation.hpp
/// A planar triangle mesh under the local operations of Delaunay cutting (thesis §5.2): edge
/// flips by the empty-circle criterion (§5.2.1, Fig. 5.3), Lawson legalization of a set of
/// edges, and removal of an interior node by ear flipping (§5.3.1, Fig. 5.10: flip ears until
/// the node has degree 3, remove it, flip back illegal edges).
///
/// Every topological change is one Connectivity::replace_elements call (§7.3). Triangles are
/// counter-clockwise (positive area) and stay so: a flip or an ear is only made when both new
/// triangles are strictly counter-clockwise by the exact orient2d (predicates.hpp). Edges can be
/// marked constrained (incision and boundary edges are never flipped); boundary edges are never
/// flipped either. With exact predicates, legalization terminates (every flip lowers the lifted
/// surface of the constrained triangulation) and never flips a cocircular quadrilateral.

#include <incise/core/types.hpp>
#include <incise/delaunay/edge.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <array>
#include <set>
#include <utility>
#include <vector>

namespace incise::delaunay {

/// Planar triangulation with positions and constrained edges (see file comment).
class Triangulation {
 public:
  /// Takes a 2D triangle mesh (MeshData::dimension == 2, z ignored) whose triangles are
  /// counter-clockwise. Throws ParameterError when the mesh is not 2D, a coordinate is not
  /// finite or beyond 1e60 m, or a triangle is not strictly counter-clockwise (exact orient2d);
  /// UsageError for an
  /// invalid cell set (Connectivity::from_mesh_data).
  explicit Triangulation(const mesh::MeshData& mesh);

  /// The connectivity (thesis ch. 7).
  const mesh::Connectivity& connectivity() const { return conn_; }
  /// Position of vertex v (m).
  Vec2 point(Index v) const { return points_.col(v).head<2>(); }
  /// Positions, 3 × (at least num_vertices), z = 0 (vertices without triangles keep their last
  /// position; columns past num_vertices are spare capacity).
  const Eigen::Matrix3Xd& points() const { return points_; }
  /// The current mesh as arrays (cells in Connectivity slot order; removed vertices stay as
  /// unused points, so indices are stable).
  mesh::MeshData to_mesh_data() const {
    return conn_.to_mesh_data(points_.leftCols(conn_.num_vertices()));
  }
  /// Live triangles.
  Index num_triangles() const { return conn_.num_elements(); }

  /// The live triangles incident with edge {p, q}: 0, 1 or 2.
  std::vector<mesh::ElementHandle> incident(Index p, Index q) const;
  /// Whether {p, q} is an edge with exactly one incident triangle.
  bool is_boundary_edge(Index p, Index q) const { return incident(p, q).size() == 1; }
  /// Whether vertex v has a triangle and no boundary edge.
  bool is_interior_vertex(Index v) const;

  /// Marks (or unmarks) {p, q} as constrained: never flipped.
  void set_constrained(Index p, Index q, bool constrained = true);
  /// Whether {p, q} is marked constrained.
  bool is_constrained(Index p, Index q) const { return constrained_.count(make_edge(p, q)) != 0; }

  /// Whether {p, q} is locally Delaunay (§5.2.1): a boundary, constrained or missing edge is; an
  /// interior edge with triangles (p, q, c) and (q, p, d) is when d is not strictly inside the
  /// circumcircle of (p, q, c) (exact incircle; cocircular counts as Delaunay).
  bool is_locally_delaunay(Index p, Index q) const;

  /// Flips the interior, unconstrained edge {p, q} — triangles (p, q, c), (q, p, d) become
  /// (c, d, q), (d, c, p) — when both new triangles are strictly counter-clockwise (the
  /// quadrilateral is strictly convex). Returns whether it flipped; the new edge is {c, d}.
  bool flip(Index p, Index q);

  /// Lawson legalization: flips illegal edges, starting from `edges` and continuing with the
  /// four outer edges of every flip, until all reached edges are locally Delaunay. Returns the
  /// number of flips. Terminates (see file comment).
  long legalize(std::vector<Edge> edges);

  /// All edges, each once (canonical order, sorted).
  std::vector<Edge> edges() const;

  /// Removes interior vertex v (§5.3.1, Fig. 5.10): ears around v are flipped until v has degree
  /// 3, the three triangles are replaced by one, and the edges of v's former link polygon are
  /// legalized. An ear is an edge (v, w) whose flip keeps both triangles counter-clockwise; in a
  /// star-shaped polygon of degree ≥ 4 around v one always exists. Returns false (mesh
  /// unchanged) when v is not interior, or an edge at v is constrained. Post: v has no triangle.
  bool remove_vertex(Index v);

  /// The vertices of live triangle e, counter-clockwise.
  std::array<Index, 3> triangle(mesh::ElementHandle e) const;
  /// The triangle containing the directed edge p→q (its third vertex is left of p→q), or an
  /// invalid handle.
  mesh::ElementHandle left_of(Index p, Index q) const;
  /// The vertices sharing an edge with v, in no particular order.
  std::vector<Index> neighbours(Index v) const;

  /// A new vertex at x without triangles; returns its number.
  Index add_vertex(const Vec2& x);
  /// Moves vertex v to x when every triangle of its star stays strictly counter-clockwise;
  /// returns false (v unchanged) otherwise. Throws ParameterError for a non-finite x.
  bool move_vertex(Index v, const Vec2& x);
  /// Replaces the triangles `remove` by `add` (vertex triples, counter-clockwise) in one
  /// replace_elements call when every new triangle is strictly counter-clockwise; returns false
  /// (unchanged) otherwise. The caller keeps the union of the triangles a valid mesh (validate()
  /// checks it in tests).
  bool replace(const std::vector<mesh::ElementHandle>& remove,
               const std::vector<std::array<Index, 3>>& add);
  /// Inserts a vertex at x on the boundary edge {p, q} (its triangle (p, q, r) becomes
  /// (p, x, r) and (x, q, r)); returns it, or −1 (unchanged) when {p, q} is not a boundary edge
  /// or a new triangle would not be strictly counter-clockwise.
  Index split_boundary_edge(Index p, Index q, const Vec2& x);

  /// Inserts a vertex at x on the edge {p, q} (boundary or interior): each incident triangle
  /// (p, q, r) becomes (p, x, r) and (x, q, r). Returns it, or −1 (unchanged) when {p, q} is not
  /// an edge or a new triangle would not be strictly counter-clockwise.
  Index split_edge(Index p, Index q, const Vec2& x);
  /// Inserts a vertex at x inside live triangle e: (a, b, c) becomes (a, b, x), (b, c, x),
  /// (c, a, x). Returns it, or −1 (unchanged) when x is not strictly inside.
  Index split_triangle(mesh::ElementHandle e, const Vec2& x);
  /// The live triangle containing x (closed), by a scan; invalid when none.
  mesh::ElementHandle locate(const Vec2& x) const;

  /// Registers / unregisters an observer of the connectivity's changes (§7.4).
  void add_watcher(mesh::ConnectivityWatcher* w) { conn_.add_watcher(w); }
  /// See add_watcher.
  void remove_watcher(mesh::ConnectivityWatcher* w) { conn_.remove_watcher(w); }

  /// Flips made by flip(), legalize() and remove_vertex() so far.
  long num_flips() const { return flips_; }

  /// Smallest and largest interior angle over live triangles (radians).
  std::pair<double, double> angle_range() const;

 private:
  /// The vertex of triangle e other than p and q.
  Index third(mesh::ElementHandle e, Index p, Index q) const;

  mesh::Connectivity conn_;
  Eigen::Matrix3Xd points_;
  std::set<Edge> constrained_;
  long flips_ = 0;
};

}  // namespace incise::delaunay
