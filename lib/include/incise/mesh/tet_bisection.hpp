#pragma once
/// \file tet_bisection.hpp
/// Conforming bisection of tetrahedral meshes — the 3D form of the §6.5 edge bisection that the
/// thesis shows as work in progress in §6.9 (Fig. 6.13: "recursive edge bisection in 3D", Fig.
/// 6.14: refinement around a needle) — by the marked-tetrahedron scheme of D. N. Arnold,
/// A. Mukherjee and L. Pouly, "Locally adapted tetrahedral meshes using bisection", SIAM J. Sci.
/// Comput. 22(2):431–448, 2000 (AMP below).
///
/// Marking (AMP §2). The edges of the starting mesh are strictly totally ordered: by length
/// (squared, as computed in double), ties broken by the smaller and then the larger vertex
/// number. Every face marks its maximal edge; every tetrahedron's refinement edge is its maximal
/// edge (so the two faces containing it mark it, and a face shared by two tetrahedra carries the
/// same mark in both). With refinement edge ab and the other vertices c, d, the marks of the
/// faces acd and bcd give the type: P (planar: ac & bc, or ad & bd), A (ac & bd, or ad & bc),
/// M (exactly one of them is cd), O (both cd). Starting tetrahedra are unflagged.
///
/// Bisection rule (AMP §3). Tetrahedron abcd with refinement edge ab is split at the midpoint e
/// into acde and bcde. A child's refinement edge is the mark of the face it inherits (acd or
/// bcd); the halves of the cut faces abc, abd mark the edge opposite e (ac, bc, ad, bd); the new
/// face cde marks cd, except when the parent is flagged planar (Pf), when it marks ev with v the
/// vertex of cd on both children's refinement edges; children of an unflagged planar parent (Pu)
/// are flagged, all other children unflagged. After one bisection every tetrahedron is of type P,
/// and the types cycle A → Pu → Pf → A.
///
/// Conforming closure (AMP §3, the recursion of Fig. 6.7 in 3D): bisect(t) first bisects, by the
/// same procedure, every tetrahedron around t's refinement edge ab whose refinement edge is not
/// ab, until all of them have ab as refinement edge; then one simple bisection replaces all of
/// them by their children in one Connectivity::replace_elements call (§7.3). The mesh is
/// therefore conforming (no hanging node: every face is shared by at most two tetrahedra and the
/// boundary triangulation only gains bisected faces) after every call, and every edit is local.
///
/// Cycles. AMP §3 states that the closure terminates; on the shipped liver we nevertheless
/// observe, rarely, a cycle: the refinement edge of a tetrahedron around (p, q) is itself waiting,
/// through a chain of neighbours, for (p, q) (rare; counts in docs/tet_bisection.md; never on
/// Kuhn cubes, where TetBisection.RandomBisectionsOnKuhnCubes asserts 0).
/// Then (p, q) is split at once in every tetrahedron around it with the rule of an unflagged
/// non-planar parent (children's refinement edges are the marks of the faces they inherit, the
/// new face marks cd), which keeps every face's mark the same in both its tetrahedra and the mesh
/// conforming; num_forced_bisections() counts these splits.
///
/// Guarantees. After every call the mesh is conforming and positively oriented (every split is
/// complete: all tetrahedra around the edge at once), and every call terminates: each recursion
/// level works on an edge not already waiting, and a work limit (kMaxRecursion levels,
/// max_bisections_per_call() simple bisections per public call) turns a runaway into a UsageError
/// instead of an endless loop. On a Kuhn (Freudenthal) cube mesh (generators.hpp,
/// CubeSplit::kKuhn) every tetrahedron is of type A and the scheme is Maubach's newest-vertex
/// bisection: three similarity classes in all (levels mod 3; test
/// TetBisection.RandomBisectionsOnKuhnCubes). On other meshes AMP §4 gives finitely many
/// similarity classes per starting tetrahedron for descendants made by the regular rule; the
/// liver's quality before and after refinement is measured in docs/tet_bisection.md.
///
/// Positions (3×n) are kept here, indexed by vertex (§7.4). Point location descends the
/// bisection tree from the starting tetrahedron containing the point, which is found through a
/// uniform grid of the starting tetrahedra's bounding boxes: cost independent of the number of
/// elements (grid bucket size + tree depth).

#include <incise/core/types.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <array>
#include <vector>

namespace incise::mesh {

/// A tetrahedral mesh under conforming marked-tetrahedron bisection (see file comment).
class TetBisectionMesh {
 public:
  /// The AMP marking of one tetrahedron: vertices (v[0], v[1]) are the refinement edge, v[2],
  /// v[3] the other two; m0 is the marked edge of face v0 v2 v3, m1 that of face v1 v2 v3 (the
  /// faces v0 v1 v2 and v0 v1 v3 mark the refinement edge).
  struct Marking {
    std::array<Index, 4> v{{-1, -1, -1, -1}};  ///< refinement edge first
    std::array<Index, 2> m0{{-1, -1}};         ///< mark of face (v0, v2, v3)
    std::array<Index, 2> m1{{-1, -1}};         ///< mark of face (v1, v2, v3)
    bool flag = false;                         ///< AMP flag (only planar tetrahedra carry it)
  };

  /// AMP types of a marked tetrahedron (file comment); kPf is a flagged planar one.
  enum class Type { kPu, kPf, kA, kM, kO };

  /// Node of the bisection tree: one per tetrahedron that ever existed.
  struct TreeNode {
    Simplex simplex;                        ///< the oriented tetrahedron
    Marking marking;                        ///< its AMP marking
    int parent = -1;                        ///< parent node, −1 for a root (a starting tet)
    std::array<int, 2> children{{-1, -1}};  ///< the two halves, −1 while a leaf
    int depth = 0;                          ///< bisections from the root
    ElementHandle element;                  ///< the live element while a leaf (stale after)
  };

  /// Takes a tetrahedral mesh (dimension 3, 4 × m cells) with positive signed volumes and marks
  /// it (file comment). Throws ParameterError when the mesh is not 3D tetrahedra or a cell has
  /// non-positive volume (naming the cell), UsageError for an invalid cell set
  /// (Connectivity::from_mesh_data: repeated vertex, index out of range, duplicate face, a face
  /// shared by three cells).
  explicit TetBisectionMesh(const MeshData& tets);

  /// The connectivity (thesis ch. 7) of the current tetrahedra.
  const Connectivity& connectivity() const { return conn_; }
  /// Reference positions (m), 3 × num_vertices.
  const Eigen::Matrix3Xd& points() const { return points_; }
  /// The current mesh as arrays (cells in Connectivity slot order, positively oriented); when
  /// the starting mesh had cell tags, each cell carries the tag of the starting cell it lies in
  /// (its tree root). Point tags are not carried (new vertices have none).
  MeshData to_mesh_data() const;
  /// Simple bisections (edges split) performed so far.
  long num_bisections() const { return bisections_; }
  /// Simple bisections that split an edge out of the AMP order because the closure met a
  /// cycle of refinement edges (file comment); 0 on Kuhn cubes.
  long num_forced_bisections() const { return forced_; }
  /// The edge (p, q) whose midpoint vertex v is, or {−1, −1} for a vertex of the starting mesh.
  /// Vertex numbers never change and p, q < v, so a linear nodal field is carried to the refined
  /// mesh exactly by visiting the new vertices in increasing order and averaging their parents.
  /// Throws UsageError for v out of range.
  std::array<Index, 2> parents(Index v) const;

  /// The refinement edge of live element e, as its two vertices.
  std::array<Index, 2> refinement_edge(ElementHandle e) const;
  /// The AMP marking of live element e.
  const Marking& marking(ElementHandle e) const;
  /// The AMP type of live element e.
  Type type(ElementHandle e) const;
  /// Longest edge length (m) of live element e.
  double longest_edge(ElementHandle e) const;
  /// Similarity signature of live element e: its six squared edge lengths sorted and divided by
  /// the largest, each rounded to a multiple of 1e-9. Similar tetrahedra have equal signatures
  /// (to rounding); used to count the similarity classes of bisection (three on a Kuhn cube).
  std::array<long, 6> similarity_signature(ElementHandle e) const;

  /// Conforming bisection of e's refinement edge with the recursive closure (file comment).
  /// Returns the midpoint vertex. Throws UsageError for a dead handle, or when the closure needs
  /// more than kMaxRecursion levels or max_bisections_per_call() simple bisections (work limit).
  Index bisect(ElementHandle e);

  /// refine-around(x, h) of §6.5 in 3D: while the tetrahedron containing x has a longest edge
  /// longer than h (m), bisect it. Returns the number of bisect calls. Throws UsageError when x
  /// is not finite or outside the mesh, h is not finite and > 0, or the work limit
  /// (max_bisections_per_call() simple bisections in this call) is reached.
  int refine_around(const Vec3& x, double h);

  /// Refinement along the segment [a, b] (the needle shaft): bisects until every tetrahedron
  /// meeting the closed segment has longest edge ≤ h (m). Tetrahedra are found by descending the
  /// bisection tree (no scan of the mesh). Returns the number of bisect calls (0 when no
  /// tetrahedron meets the segment). Throws UsageError for non-finite a, b, h not finite and
  /// > 0, or the work limit (max_bisections_per_call() simple bisections in this call).
  int refine_along_segment(const Vec3& a, const Vec3& b, double h);

  /// The live tetrahedron containing x (closed, relative tolerance 1e-12 in barycentric
  /// coordinates; on a shared face one of them), found by descending the bisection tree from the
  /// root containing x; the none-handle when x is outside (or not finite).
  ElementHandle locate(const Vec3& x) const;

  /// The live tetrahedra meeting the closed segment [a, b] (tree descent; same tolerance as
  /// locate), in unspecified order.
  std::vector<ElementHandle> elements_meeting_segment(const Vec3& a, const Vec3& b) const;

  /// The bisection tree (roots first, in the order of the starting cells).
  const std::vector<TreeNode>& tree() const { return tree_; }
  /// Tree node of live element e.
  int node_of(ElementHandle e) const;
  /// AMP type of a marking (file comment).
  static Type type_of(const Marking& m);

  /// Sets the work limit of later public calls (simple bisections per call; default
  /// kMaxBisectionsPerCall). Throws UsageError unless n ≥ 1. When a call hits the limit the
  /// mesh stays conforming (every simple bisection is complete) and the call throws.
  void set_max_bisections_per_call(long n);
  /// The current work limit (simple bisections per public call).
  long max_bisections_per_call() const { return max_bisections_; }

  /// Recursion limit of the conforming closure (levels of nested bisect).
  static constexpr int kMaxRecursion = 200;
  /// Work limit: simple bisections per public call (bisect, refine_around,
  /// refine_along_segment).
  static constexpr long kMaxBisectionsPerCall = 2000000;

 private:
  Index bisect_edge(Index p, Index q, int level, long budget_start);
  Index simple_bisect(Index p, Index q, const std::vector<ElementHandle>& around);
  std::vector<ElementHandle> around_edge(Index p, Index q) const;
  double min_barycentric(const Simplex& t, const Vec3& x) const;
  bool meets_segment(const Simplex& t, const Vec3& a, const Vec3& b) const;
  void set_node(ElementHandle e, int node);
  std::vector<int> roots_near(const Vec3& lo, const Vec3& hi) const;

  Connectivity conn_;
  Eigen::Matrix3Xd points_;
  std::vector<TreeNode> tree_;
  int num_roots_ = 0;
  std::vector<int> root_tags_;                 ///< cell tags of the starting cells (or empty)
  std::vector<int> node_of_slot_;              ///< element slot → tree node of its live element
  std::vector<std::array<Index, 2>> parents_;  ///< per new vertex, from num_start_vertices_ on
  Index num_start_vertices_ = 0;
  long bisections_ = 0;
  long forced_ = 0;
  std::vector<std::array<Index, 2>> pending_;  ///< edges of the bisect_edge calls in progress
  long max_bisections_ = kMaxBisectionsPerCall;
  // Uniform grid over the starting mesh's bounding box: cell → roots whose box overlaps it.
  Vec3 grid_lo_ = Vec3::Zero();
  Vec3 grid_cell_ = Vec3::Ones();
  std::array<int, 3> grid_n_{{1, 1, 1}};
  std::vector<int> grid_start_;  ///< CSR offsets, size cells + 1
  std::vector<int> grid_roots_;  ///< root node ids
};

}  // namespace incise::mesh
