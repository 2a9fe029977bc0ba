#pragma once
/// \file subdivision.hpp
/// The subdivision cutter the thesis compares Delaunay cutting with (§5.1, Fig. 5.2, Fig. 5.16
/// top): every mesh edge the scalpel path crosses is split at the crossing, so each sliced
/// triangle becomes three, and the chain of new edges along the path is dissected. The realized
/// incision follows the path closely; the mesh grows and gets small and flat triangles.
///
/// Applied to a whole path at once (the final mesh of an interactive subdivision cut: the
/// subdivision of an active triangle becomes permanent when the scalpel leaves it). A crossing
/// within `snap` · h̄ of a vertex uses the vertex. A path end inside the mesh gets a node there
/// (its triangle becomes three): the incision ends exactly at the scalpel.

#include <incise/delaunay/triangulation.hpp>

#include <vector>

namespace incise::delaunay {

/// Options of subdivision_cut.
struct SubdivisionOptions {
  double snap = 1e-3;  ///< crossings nearer to a vertex than snap · h̄ use the vertex
};

/// What subdivision_cut did.
struct SubdivisionReport {
  Index triangles_before = 0;  ///< live triangles before
  Index triangles_after = 0;   ///< live triangles after
  int crossings = 0;           ///< edge crossings of the path (new nodes or snapped vertices)
  int dissected = 0;           ///< chain nodes split into two or more copies
  std::vector<Index> chain;    ///< the incision's nodes in path order (before dissection)
};

/// Cuts `mesh` along the polyline `path` (≥ 2 finite points) by subdivision (see file comment).
/// Throws ParameterError for a path of fewer than two points or with a non-finite point.
SubdivisionReport subdivision_cut(Triangulation& mesh, const std::vector<Vec2>& path,
                                  SubdivisionOptions options = {});

}  // namespace incise::delaunay
