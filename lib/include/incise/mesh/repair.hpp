#pragma once
/// \file repair.hpp
/// Repairs of simplicial meshes given as arrays (MeshData), applied by loaders on request.

#include <incise/mesh/mesh_data.hpp>

#include <vector>

namespace incise::mesh {

/// Result of split_pinched_vertices().
struct PinchSplit {
  std::vector<Index> pinched;  ///< original vertices whose star was not face-connected
  std::vector<Index> origin;   ///< origin[k]: original vertex of appended vertex first_new + k
  Index first_new = 0;         ///< number of points before the call
};

/// Splits "pinched" vertices: a vertex v whose star (the cells containing v) falls into several
/// classes of cells connected through facets that contain v — the (v, ∅)-connected classes of
/// thesis §7.3 — violates the connected-star requirement of §7.3 (e.g. two parts of an organ
/// touching in one point). The class containing v's lowest-numbered cell keeps v; every other
/// class gets a new vertex (a copy of v's position and point tag, appended to `points`), which
/// replaces v in its cells and in the facets of `m.facets` that lie on a cell of that class.
/// Existing vertex numbers are unchanged. Cost O(Σ_v |star(v)|·d log). Preconditions: indices
/// in range, no repeated vertex within a cell.
[[nodiscard]] PinchSplit split_pinched_vertices(MeshData& m);

}  // namespace incise::mesh
