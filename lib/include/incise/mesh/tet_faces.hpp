#pragma once
/// \file tet_faces.hpp
/// The faces of a tetrahedron — the one local face table every module uses — and the boundary
/// triangles of a tetrahedral mesh.

#include <incise/mesh/mesh_data.hpp>

namespace incise::mesh {

/// Local face j of a tetrahedron (v0, v1, v2, v3) is the face opposite v_j; kTetFace[j] lists
/// its three local vertices (a, b, c) ordered so that the normal (x_b − x_a) × (x_c − x_a)
/// points outward, away from v_j, when the tetrahedron is positively oriented (positive signed
/// volume, mesh_data.hpp).
inline constexpr int kTetFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

/// Boundary triangles of the tetrahedra `tets` (4 × m vertex indices): the faces that belong to
/// exactly one tetrahedron, each in the kTetFace order of that tetrahedron (so outward when it is
/// positively oriented), as a 3 × k matrix ordered by their sorted vertex triples. Faces shared
/// by three or more tetrahedra (non-manifold) are not boundary faces. Throws UsageError unless
/// `tets` has 4 rows.
CellMatrix boundary_faces(const CellMatrix& tets);

/// boundary_faces(mesh.cells); throws UsageError unless `mesh` is tetrahedral (dimension 3).
CellMatrix boundary_faces(const MeshData& mesh);

/// How the triangles a mesh file lists (`facets`, 3 × k vertex indices in any order and
/// orientation; duplicates counted once) relate to the boundary of the tetrahedra `tets`.
struct FacetCoverage {
  std::size_t distinct = 0;     ///< distinct listed triangles
  std::size_t on_boundary = 0;  ///< listed triangles that are boundary faces
  std::size_t interior = 0;     ///< listed but not on the boundary (e.g. subdomain interfaces)
  std::size_t boundary_not_listed = 0;  ///< boundary faces (boundary_faces(tets)) not listed
};

/// FacetCoverage of `facets` against boundary_faces(tets). Throws UsageError unless `tets` has 4
/// rows and `facets` 3.
FacetCoverage facet_coverage(const CellMatrix& tets, const CellMatrix& facets);

}  // namespace incise::mesh
