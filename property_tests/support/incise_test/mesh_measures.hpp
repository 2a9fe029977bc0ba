#pragma once
/// \file mesh_measures.hpp
/// Measures of a tetrahedral mesh the verification cases compare against (one definition).

#include <incise/mesh/mesh_data.hpp>

#include <algorithm>

namespace incise::test {

/// The shortest edge of any tetrahedron of `m` (m): what bounds the critical time step of
/// explicit dynamics (thesis §4.5.6). 1e300 for a mesh without cells.
inline double shortest_edge(const mesh::MeshData& m) {
  double h = 1e300;
  for (Index e = 0; e < m.num_cells(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b)
        h = std::min(h, (m.points.col(m.cells(a, e)) - m.points.col(m.cells(b, e))).norm());
  return h;
}

}  // namespace incise::test
