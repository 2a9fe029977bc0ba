#pragma once
/// \file edge.hpp
/// Undirected edges of the Delaunay-cutting meshes (planar Triangulation and Surface).

#include <incise/core/types.hpp>

#include <utility>

namespace incise::delaunay {

/// An undirected edge (p, q) with p < q.
using Edge = std::pair<Index, Index>;
/// The edge {p, q} in canonical order.
inline Edge make_edge(Index p, Index q) {
  return p < q ? Edge{p, q} : Edge{q, p};
}

}  // namespace incise::delaunay
