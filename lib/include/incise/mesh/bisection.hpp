#pragma once
/// \file bisection.hpp
/// Edge bisection of right-angled triangle meshes (thesis §6.5, Figs. 6.6–6.8):
/// simple-bisect, the recursive bisect (neighbours' hypotenuses first, Fig. 6.7),
/// refine-around(x, h), and the bisection hierarchy as a binary tree used for point location.
///
/// The hypotenuse of a triangle is its longest edge (for right isosceles triangles the legs
/// are strictly shorter), so bisect is longest-edge bisection and, since the vertex opposite
/// the hypotenuse is the newest, newest-vertex bisection. Bisecting a right isosceles
/// triangle's hypotenuse gives two right isosceles triangles with legs 1/√2 as long: every
/// triangle at depth j of the tree is congruent to its root scaled by 2^(−j/2).
///
/// Every topological change goes through Connectivity::replace_elements (§7.3): one call per
/// simple bisection, replacing the one or two triangles incident with the edge by two or four.
/// Positions (3×n, z = 0) are kept here, indexed by vertex (§7.4).

#include <incise/core/types.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <array>
#include <vector>

namespace incise::mesh {

/// A 2D triangle mesh under edge bisection (see file comment).
class BisectionMesh {
 public:
  /// Node of the bisection tree: one per triangle that ever existed.
  struct TreeNode {
    Simplex simplex;                        ///< the oriented triangle
    int parent = -1;                        ///< parent node, −1 for a root (a starting triangle)
    std::array<int, 2> children{{-1, -1}};  ///< the two halves, −1 while a leaf
    int depth = 0;                          ///< bisections from the root
    ElementHandle element;                  ///< the live element while a leaf (stale afterwards)
  };

  /// Takes a 2D triangle mesh whose triangles are counter-clockwise (positive area). Throws
  /// ParameterError when the mesh is not 2D or a triangle has non-positive area; and
  /// UsageError for an invalid cell set (Connectivity::from_mesh_data).
  explicit BisectionMesh(const MeshData& mesh);

  /// The connectivity (thesis ch. 7) of the current triangles.
  const Connectivity& connectivity() const { return conn_; }
  /// Reference positions (m), 3 × num_vertices, z = 0.
  const Eigen::Matrix3Xd& points() const { return points_; }
  /// The current mesh as arrays (cells in Connectivity slot order).
  MeshData to_mesh_data() const { return conn_.to_mesh_data(points_); }
  /// Simple bisections performed so far.
  long num_bisections() const { return bisections_; }
  /// The edge (p, q) whose midpoint vertex v is (v was made by simple_bisect(p, q)), or
  /// {−1, −1} for a vertex of the starting mesh. Vertex numbers never change, and p, q < v, so
  /// a nodal field of linear elements is carried to a refined mesh exactly by visiting the new
  /// vertices in increasing order and averaging their two parents.
  std::array<Index, 2> parents(Index v) const;

  /// The hypotenuse (longest edge) of live element e, as its two vertices.
  std::array<Index, 2> hypotenuse(ElementHandle e) const;
  /// The live triangles incident with the edge (p, q): 0, 1 or 2.
  std::vector<ElementHandle> incident(Index p, Index q) const;

  /// simple-bisect(p, q) (Fig. 6.6): a new vertex n halfway between p and q; each incident
  /// triangle f becomes f with p := n and f with q := n, in one replace_elements call.
  /// Returns n. Throws UsageError when (p, q) is not an edge or is not the hypotenuse of every
  /// incident triangle.
  Index simple_bisect(Index p, Index q);

  /// bisect(e) (Fig. 6.7): first bisects the hypotenuse of each incident triangle whose
  /// hypotenuse is not (p, q) (recursively), then simple-bisects (p, q). Returns the new vertex
  /// of (p, q). Throws UsageError when (p, q) is not an edge, or when the recursion passes
  /// kMaxRecursion levels (a starting mesh that is not compatibly divisible).
  Index bisect(Index p, Index q);

  /// refine-around(x, h) (§6.5): while the triangle containing x has a hypotenuse longer than
  /// h (m), bisect that hypotenuse. Returns the number of bisect calls. Throws UsageError when
  /// x is outside the mesh or h is not finite and > 0.
  int refine_around(const Vec2& x, double h);

  /// The live triangle containing x (closed triangles; on a shared edge one of them), found
  /// by descending the bisection tree from the root containing x; the none-handle when x is
  /// outside. Cost O(roots + depth).
  ElementHandle locate(const Vec2& x) const;

  /// The bisection tree (roots first, in the order of the starting cells).
  const std::vector<TreeNode>& tree() const { return tree_; }
  /// Tree node of live element e.
  int node_of(ElementHandle e) const;

  /// Recursion limit of bisect.
  static constexpr int kMaxRecursion = 200;

 private:
  Index bisect_impl(Index p, Index q, int level);
  bool contains(const Simplex& t, const Vec2& x) const;

  Connectivity conn_;
  Eigen::Matrix3Xd points_;
  std::vector<TreeNode> tree_;
  int num_roots_ = 0;
  std::vector<int> node_of_slot_;  ///< element slot → tree node of the live element there
  std::vector<std::array<Index, 2>> parents_;  ///< per vertex made by simple_bisect, from
                                               ///< num_start_vertices_ on
  Index num_start_vertices_ = 0;
  long bisections_ = 0;
};

}  // namespace incise::mesh
