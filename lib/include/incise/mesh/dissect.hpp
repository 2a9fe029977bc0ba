#pragma once
/// \file dissect.hpp
/// Dissection by node substitution (thesis §7.3, Figures 7.6–7.7; used by cutting, ch. 3).
///
/// Given a set C of faces (closed under mates: the mate of every listed face is added), star(v)
/// of every vertex v is partitioned into (v, C)-connected classes S_{v,1..l}: two elements of
/// star(v) are in one class when a chain of face-neighbours inside star(v) joins them without
/// crossing a face pair of C. When l > 1, the class containing the element with the smallest
/// slot index keeps v (w_{v,1} = v, allowed by §7.3: "a unique vertex w_{v,i} for each class")
/// and every other class S_{v,i} gets a new vertex w_{v,i} (appended: num_vertices(), …). All
/// substitutions are applied in one change_elements call, so Element and Face handles survive
/// (faces of C whose vertices are split end up on the boundary; faces of C that are not
/// separated, Figure 7.7, stay joined). Vertices whose star is one class are unchanged, so a
/// dissection along C = ∅ does nothing. Stars are found with the vertex→element incidence:
/// cost O(Σ_{v ∈ V(C)} |star(v)|·(d+1)) plus the change_elements call.

#include <incise/mesh/connectivity.hpp>

#include <vector>

namespace incise::mesh {

/// One new vertex created by dissect().
struct VertexSplit {
  Index old_vertex;                     ///< the vertex v that was split
  Index new_vertex;                     ///< w_{v,i} (appended vertex number)
  std::vector<ElementHandle> elements;  ///< the class S_{v,i} now using new_vertex
};

/// Result of dissect(): old→new vertex maps.
struct [[nodiscard]] DissectResult {
  std::vector<VertexSplit> splits;  ///< one entry per new vertex, in increasing new_vertex order
  Index first_new_vertex = 0;       ///< num_vertices() before the call
  /// origin[k] = old vertex of new vertex first_new_vertex + k.
  std::vector<Index> origin() const;
  /// Number of new vertices.
  Index num_new_vertices() const { return static_cast<Index>(splits.size()); }
};

/// Dissects `conn` along the faces `cut` (live face handles; mates implied; boundary faces are
/// ignored) by node substitution, §7.3. Post: valid connectivity (if it was valid) in which no
/// element path around any vertex crosses a face of C unless the faces stay joined (Fig. 7.7).
DissectResult dissect(Connectivity& conn, const std::vector<FaceHandle>& cut);

/// Appends one column per new vertex of `result` to `positions` (3×n, n = first_new_vertex),
/// copying the position of the vertex it was split from. Throws UsageError on a size mismatch.
void extend_positions(Eigen::Matrix3Xd& positions, const DissectResult& result);

}  // namespace incise::mesh
