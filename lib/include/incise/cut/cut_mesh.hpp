#pragma once
/// \file cut_mesh.hpp
/// The working tetrahedral mesh of the cutter (thesis ch. 3): reference and deformed node
/// positions, oriented tetrahedra with stable integer handles, node→element incidence (the
/// star of every node), fixed-node flags and the node substitution (dissection) of §7.3.
///
/// Adjacency is derived from the stars (two elements are neighbours when they share three
/// nodes), so an edit only touches the stars of the nodes involved and every query is local:
/// the cost of a cut depends on the cut, not on the mesh size. All topological edits go
/// through `set_element`, `add_element`, `remove_element` and `dissect`; `validate()` checks
/// the simplicial-mesh invariants of §7.2 in the form stated there (each oriented face in at
/// most one element, (7.1)–(7.3); every face in at most two elements with opposite
/// orientations; the star of every node face-connected, the precondition of dissection §7.3).

#include <incise/core/types.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace incise::cut {

/// Four node indices of an oriented tetrahedron (positive reference volume when valid).
using Tet = std::array<Index, 4>;

/// Local face j of a tetrahedron is the face opposite node j, oriented outward:
/// kTetFace[j] lists its three local nodes.
inline constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
/// The six edges of a tetrahedron as local node pairs.
inline constexpr int kTetEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

/// Outcome of CutMesh::validate(): every violated invariant, by name and object.
struct [[nodiscard]] CutMeshValidation {
  std::vector<std::string> violations;  ///< empty when valid (at most 50 are listed)
  Index violation_count = 0;            ///< total number of violations found
  Index inverted_reference = 0;  ///< live elements with reference volume ≤ 0 (not an invariant)
  Index inverted_deformed = 0;   ///< live elements with deformed volume ≤ 0 (not an invariant)
  bool ok() const { return violation_count == 0; }
};

/// Tetrahedral mesh with reference (X) and deformed (x) positions, as edited by cutting.
class CutMesh {
 public:
  /// Builds from a 3D MeshData; deformed = reference. Throws ParameterError if the mesh is
  /// not tetrahedral or refers to a missing node.
  explicit CutMesh(const mesh::MeshData& data);

  Index num_nodes() const { return static_cast<Index>(ref_.size()); }
  /// Capacity of element handles (live and removed); handles are < element_capacity().
  Index element_capacity() const { return static_cast<Index>(tets_.size()); }
  /// Number of live elements.
  Index num_elements() const { return live_elements_; }
  bool alive(Index e) const { return alive_[static_cast<size_t>(e)] != 0; }
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

  bool fixed(Index v) const { return fixed_[static_cast<size_t>(v)] != 0; }
  void set_fixed(Index v, bool f) { fixed_[static_cast<size_t>(v)] = f ? 1 : 0; }
  /// The original node a node descends from through dissection copies (itself otherwise).
  Index origin(Index v) const { return origin_[static_cast<size_t>(v)]; }
  /// Elements containing node v (the star of v), unordered.
  const std::vector<Index>& star(Index v) const { return star_[static_cast<size_t>(v)]; }
  /// True if node v belongs to no live element (removed by a collapse or a cut-free).
  bool unused(Index v) const { return star(v).empty(); }

  /// Element sharing the face opposite local node j of e, or −1 on the boundary.
  Index neighbor(Index e, int j) const;
  /// Local index (0..3) of node v in element e, or −1.
  int local_index(Index e, Index v) const;
  /// Whether node v lies on a boundary face.
  bool on_boundary(Index v) const;

  /// Appends a node with the given positions, fixed flag and origin; returns its index.
  Index add_node(const Vec3& X, const Vec3& x, bool is_fixed, Index origin_node);
  /// Replaces the nodes of element e (change-elements, §7.3); stars are updated.
  void set_element(Index e, const Tet& t);
  /// Adds an element; returns its handle (a removed handle is reused).
  Index add_element(const Tet& t);
  /// Removes element e (its handle becomes free).
  void remove_element(Index e);

  /// Reference signed volume of element t given as nodes (m³).
  double reference_volume(const Tet& t) const;
  /// Deformed signed volume (m³).
  double deformed_volume(const Tet& t) const;

  /// Dissection by node substitution (thesis §7.3): `faces` lists interior faces as
  /// (element, local face) pairs; for each node of those faces its star is split into
  /// (v, C)-connected classes, the class holding the lowest element handle keeps v and every
  /// other class gets a copy (same X, x, fixed flag, origin). The element count is unchanged.
  /// Appends changed element handles to `changed` and new nodes to `new_nodes`; returns the
  /// number of faces that actually ended up on the boundary.
  Index dissect(const std::vector<std::pair<Index, int>>& faces, std::vector<Index>& changed,
                std::vector<Index>& new_nodes);

  /// Checks the invariants listed in the file comment over the whole mesh (O(n)).
  CutMeshValidation validate() const;

  /// Exports the live elements and all nodes. With `compact`, unused nodes are dropped and
  /// `node_map` (old → new, −1 for dropped) is filled. Positions: reference if !deformed.
  mesh::MeshData to_mesh_data(bool deformed_positions = false, bool compact = false,
                              std::vector<Index>* node_map = nullptr) const;

 private:
  void star_remove(Index v, Index e);

  std::vector<Vec3> ref_;
  std::vector<Vec3> def_;
  std::vector<char> fixed_;
  std::vector<Index> origin_;
  std::vector<std::vector<Index>> star_;
  std::vector<Tet> tets_;
  std::vector<char> alive_;
  std::vector<Index> free_;
  Index live_elements_ = 0;
  std::uint64_t positions_version_ = 0;
};

}  // namespace incise::cut
