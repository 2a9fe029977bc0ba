#pragma once
/// \file svg.hpp
/// An SVG picture of a planar triangle mesh with a scalpel path drawn over it, as the thesis
/// shows its cuts (Fig. 5.16): triangles filled light blue with dark edges, the path as a dashed
/// red polyline. One definition for the ch. 5 reproductions (verification/papers/
/// nienhuys2003_ch5/) and the `outputs.svg` of a 2D Delaunay scene (scene/delaunay_scene.hpp).

#include <incise/delaunay/triangulation.hpp>

#include <string>
#include <vector>

namespace incise::delaunay {

/// The square of the plane a picture shows: [lo.x − margin, lo.x + size + margin] ×
/// [lo.y − margin, lo.y + size + margin] (m), drawn 400 × 400 pixels, y up.
struct SvgFrame {
  Vec2 lo = Vec2::Zero();
  double size = 1.0;    ///< > 0
  double margin = 1.0;  ///< ≥ 0
};

/// The frame of a mesh: its bounding box's lower corner, the larger side, a margin of 5 % of it.
SvgFrame fit_frame(const Triangulation& t);

/// The SVG text (400 × 400 pixels) of the live triangles of `t` and the polyline `path` (may be
/// empty) in `frame`. Throws ParameterError for a frame with size ≤ 0 or margin < 0.
std::string mesh_svg(const Triangulation& t, const std::vector<Vec2>& path, const SvgFrame& frame);

}  // namespace incise::delaunay
