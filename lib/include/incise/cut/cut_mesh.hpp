#pragma once
/// \file cut_mesh.hpp
/// The working tetrahedral mesh of the cutter (thesis ch. 3): the connectivity of ch. 7
/// (`mesh::Connectivity`: Elements, Faces with mates, boundary map, watchers) plus what cutting
/// needs next to it — reference and deformed node positions, fixed-node flags and the original
/// node each node descends from.
///
/// Every topological edit goes through the connectivity's `replace_elements` (collapses,
/// splits, removals) or through `mesh::dissect` (node substitution by change-elements, §7.3),
/// so watchers registered on `connectivity()` see every change. Elements are addressed by
/// their slot index (an `Index`), with the vertex order of `Connectivity::cells()`: the
/// canonical sorted vertices with the first two swapped for a negative sign, so that local
/// node k is `element(e)[k]` and local face j is the face opposite local node j, with the vertex
/// order mesh::kTetFace[j] (outward for a positively oriented element). All queries
/// are local (stars from the vertex→element incidence), so the cost of a cut depends on the
/// cut, not on the mesh size.
#include <incise/core/types.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/mesh_data.hpp>
#include <incise/mesh/tet_faces.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace incise::cut {

/// Four node indices of an oriented tetrahedron (positive reference volume when valid).
using Tet = std::array<Index, 4>;

/// The six edges of a tetrahedron as local node pairs.
inline constexpr int kTetEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

/// Outcome of CutMesh::validate(): every violated invariant, by name and object.
struct [[nodiscard]] CutMeshValidation {
  std::vector<std::string> violations;  ///< "[invariant] message", at most 50 listed
  Index violation_count = 0;            ///< total number of violations found
  Index inverted_reference = 0;  ///< live elements with reference volume ≤ 0 (not an invariant)
  Index inverted_deformed = 0;   ///< live elements with deformed volume ≤ 0 (not an invariant)
  bool ok() const { return violation_count == 0; }
};

/// Tetrahedral mesh with reference (X) and deformed (x) positions, as edited by cutting.
class CutMesh {
 public:
  /// Builds from a 3D MeshData; deformed = reference. Throws ParameterError if the mesh is
  /// not tetrahedral, UsageError (from Connectivity) if its cells do not form a valid mesh.
  explicit CutMesh(const mesh::MeshData& data);

  /// Number of nodes (used and unused; indices 0..num_nodes()−1).
  Index num_nodes() const { return static_cast<Index>(ref_.size()); }
  /// Capacity of element slots (live and free); element indices are < element_capacity().
  Index element_capacity() const { return conn_.element_capacity(); }
  /// Number of live elements.
  Index num_elements() const { return conn_.num_elements(); }
  /// Whether slot e holds a live element.
  bool alive(Index e) const {
    return e >= 0 && e < element_capacity() && conn_.element_at(e).valid();
  }
  /// Nodes of live element e in the cells() order (positive orientation preserved).
  const Tet& element(Index e) const { return tets_[static_cast<size_t>(e)]; }

  /// Reference position of node v (m).
  const Vec3& reference(Index v) const { return ref_[static_cast<size_t>(v)]; }
  /// Deformed position of node v (m).
  const Vec3& deformed(Index v) const { return def_[static_cast<size_t>(v)]; }
  /// Sets both positions of node v (used by snapping; displacement = x − X).
  void set_position(Index v, const Vec3& X, const Vec3& x);
  /// Replaces all deformed positions (3 × num_nodes). Increments positions_version().
  void set_deformed(const Eigen::Matrix3Xd& x);
  /// Counter incremented whenever deformed positions change in bulk.
  std::uint64_t positions_version() const { return positions_version_; }
  /// Reference positions as a 3 × num_nodes matrix.
  Eigen::Matrix3Xd reference_matrix() const;
  /// Deformed positions as a 3 × num_nodes matrix.
  Eigen::Matrix3Xd deformed_matrix() const;

  /// Whether node v is fixed (all displacement components prescribed).
  bool fixed(Index v) const { return fixed_[static_cast<size_t>(v)] != 0; }
  /// Marks node v as fixed or free.
  void set_fixed(Index v, bool f) { fixed_[static_cast<size_t>(v)] = f ? 1 : 0; }
  /// The original node a node descends from through dissection copies (itself otherwise).
  Index origin(Index v) const { return origin_[static_cast<size_t>(v)]; }
  /// Elements containing node v (the star of v, §7.3), unordered.
  std::vector<Index> star(Index v) const;
  /// True if node v belongs to no live element (removed by a collapse or a cut-free).
  bool unused(Index v) const { return conn_.star_size(v) == 0; }

  /// Element sharing the face opposite local node j of e, or −1 on the boundary.
  Index neighbor(Index e, int j) const;
  /// Local index (0..3) of node v in element e, or −1.
  int local_index(Index e, Index v) const;
  /// Whether node v lies on a boundary face.
  bool on_boundary(Index v) const;

  /// Appends a node (and a connectivity vertex) with the given positions, fixed flag and
  /// origin; returns its index.
  Index add_node(const Vec3& X, const Vec3& x, bool is_fixed, Index origin_node);
  /// replace-elements (§7.3): removes elements `remove`, adds `add` (positively oriented node
  /// quadruples); returns the slots of the added elements. Throws UsageError (from
  /// Connectivity) when the result would not be a pseudo-manifold; callers check first.
  std::vector<Index> replace(const std::vector<Index>& remove, const std::vector<Tet>& add);

  /// Reference signed volume of element t given as nodes (m³).
  double reference_volume(const Tet& t) const;
  /// Deformed signed volume (m³).
  double deformed_volume(const Tet& t) const;

  /// Dissection by node substitution through mesh::dissect (thesis §7.3): `faces` lists
  /// interior faces as (element, local face) pairs. New nodes copy X, x, the fixed flag and
  /// the origin of the node they split from (displacement carried over). The element count
  /// is unchanged. Appends changed element slots to `changed` and new nodes to `new_nodes`;
  /// returns the number of listed faces that ended on the boundary (Fig. 7.7: some may not).
  Index dissect(const std::vector<std::pair<Index, int>>& faces, std::vector<Index>& changed,
                std::vector<Index>& new_nodes);
  /// As above with connectivity face handles (dead handles and boundary faces are skipped).
  Index dissect(const std::vector<mesh::FaceHandle>& faces, std::vector<Index>& changed,
                std::vector<Index>& new_nodes);
  /// Connectivity handle of local face j of element e.
  mesh::FaceHandle face_handle(Index e, int j) const {
    return conn_.opposite_face(conn_.element_at(e), element(e)[static_cast<size_t>(j)]);
  }

  /// mesh::validate() of the connectivity — (7.1)–(7.5), mate symmetry, boundary map,
  /// connected stars, incidence, reference orientation — plus finite positions; counts
  /// inverted elements in both configurations. O(n).
  CutMeshValidation validate() const;

  /// The invariants of validate() restricted to `elements` (live ones; dead handles are
  /// skipped) and their faces and nodes: (7.1) face simplices, (7.3) mates with opposite
  /// simplices and symmetric, boundary faces present in the boundary map (7.5), connected
  /// stars of their nodes (§7.3), node cache, finite positions; inverted elements counted.
  /// Cost O(Σ|star|) over the listed elements' nodes — for checking after every edit of a
  /// large mesh.
  CutMeshValidation validate_local(const std::vector<Index>& elements) const;

  /// The connectivity (register watchers here to follow cuts, §7.4).
  const mesh::Connectivity& connectivity() const { return conn_; }
  /// Mutable access for registering watchers; edits must go through CutMesh.
  mesh::Connectivity& connectivity() { return conn_; }

  /// Whether the elements carry cell tags (the MeshData built from had cell_tags).
  bool has_tags() const { return !tags_.empty(); }
  /// Cell tag of live element e (0 when the mesh has no tags). Tags survive every change:
  /// dissection keeps each element's slot and tag; replace() gives each added element the tag
  /// of the removed element sharing most of its nodes (the first such one).
  int tag(Index e) const { return tags_.empty() ? 0 : tags_[static_cast<size_t>(e)]; }

  /// Exports the live elements and all nodes, with cell_tags when has_tags(). With `compact`,
  /// unused nodes are dropped and `node_map` (old → new, −1 for dropped) is filled. Positions:
  /// reference if !deformed.
  mesh::MeshData to_mesh_data(bool deformed_positions = false, bool compact = false,
                              std::vector<Index>* node_map = nullptr) const;

 private:
  void refresh(Index e);

  mesh::Connectivity conn_;
  std::vector<int> tags_;  ///< per element slot (empty: no tags)
  std::vector<Tet> tets_;  ///< per slot: cells() order of the element's simplex
  std::vector<Vec3> ref_;
  std::vector<Vec3> def_;
  std::vector<char> fixed_;
  std::vector<Index> origin_;
  std::uint64_t positions_version_ = 0;
};

}  // namespace incise::cut
