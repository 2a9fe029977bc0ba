#pragma once
/// \file refine_uniform.hpp
/// Uniform ("red") refinement of a tetrahedral mesh: every tetrahedron is split into eight by
/// its six edge midpoints, after Bey's rule (J. Bey, "Tetrahedral grid refinement", Computing
/// 55 (1995) 355–378, Algorithm RedRefinement): with the vertices ordered (x0, x1, x2, x3) and
/// x_ij the midpoint of edge (i, j), the children are the four corner tetrahedra
///     (x0, x01, x02, x03), (x01, x1, x12, x13), (x02, x12, x2, x23), (x03, x13, x23, x3)
/// — each similar to the parent, scaled by 1/2 — and the four tetrahedra of the inner
/// octahedron split along its diagonal x02–x13:
///     (x01, x02, x03, x13), (x01, x02, x12, x13), (x02, x03, x13, x23), (x02, x12, x13, x23).
/// Bey's order makes some children negatively oriented; those get vertices 1 and 3 swapped.
/// The swap keeps the pairing {0,2}, {1,3} that picks the next level's diagonal, so Bey's
/// theorem (all descendants under repeated refinement fall into at most three similarity
/// classes, hence the quality never degrades beyond the first level) still holds (test
/// `RefineUniform.RepeatedRefinementKeepsAtMostThreeSimilarityClasses`).
///
/// Faces are split into four by their edge midpoints whichever diagonal is chosen, so the
/// refinement of a conforming mesh is conforming.

#include <incise/mesh/mesh_data.hpp>

namespace incise::mesh {

/// One uniform 1→8 refinement of a tetrahedral mesh (Bey's rule, file comment). The result
/// has the input's points first, with their indices and tags unchanged, followed by one
/// midpoint per distinct edge (in increasing order of the sorted endpoint pair); a midpoint's
/// point tag is its endpoints' tag when they agree and 0 otherwise. Cell c's children are cells
/// 8c … 8c+7 (the four corner tetrahedra, then the four octahedron tetrahedra) and inherit its
/// cell tag; each child is positively oriented when its parent is. Each listed facet (a, b, c)
/// becomes facets 4k … 4k+3 — (a, m_ab, m_ca), (m_ab, b, m_bc), (m_ca, m_bc, c),
/// (m_ab, m_bc, m_ca) — with the parent's orientation and tag. Exact in exact arithmetic:
/// every child has 1/8 of its parent's volume. Throws UsageError unless `mesh` is tetrahedral
/// (dimension 3, 4 rows of cells) with vertex indices in range and every facet edge an edge of
/// some cell; ParameterError when the tag arrays are sized neither 0 nor their count.
MeshData refine_uniform(const MeshData& mesh);

}  // namespace incise::mesh
