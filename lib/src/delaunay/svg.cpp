// SVG picture of a planar triangle mesh and a scalpel path (svg.hpp).
#include <incise/core/error.hpp>
#include <incise/delaunay/svg.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace incise::delaunay {

SvgFrame fit_frame(const Triangulation& t) {
  Vec2 lo = Vec2::Constant(std::numeric_limits<double>::infinity());
  Vec2 hi = -lo;
  for (const auto& e : t.connectivity().elements())
    for (const Index v : t.triangle(e)) {
      lo = lo.cwiseMin(t.point(v));
      hi = hi.cwiseMax(t.point(v));
    }
  SvgFrame f;
  if (!lo.allFinite()) return f;  // no triangles: the unit square
  f.lo = lo;
  f.size = std::max((hi - lo).maxCoeff(), 1e-300);
  f.margin = 0.05 * f.size;
  return f;
}

std::string mesh_svg(const Triangulation& t, const std::vector<Vec2>& path, const SvgFrame& frame) {
  INCISE_CHECK_PARAM(std::isfinite(frame.size) && frame.size > 0 && std::isfinite(frame.margin) &&
                         frame.margin >= 0 && frame.lo.allFinite(),
                     "mesh_svg: the frame needs a finite size > 0 and margin >= 0");
  std::ostringstream f;
  const double s = 400.0 / (frame.size + 2 * frame.margin);
  auto X = [&](const Vec2& p) { return s * (p.x() - frame.lo.x() + frame.margin); };
  auto Y = [&](const Vec2& p) { return s * (frame.size + frame.margin - (p.y() - frame.lo.y())); };
  f << "<svg xmlns='http://www.w3.org/2000/svg' width='400' height='400'>\n"
    << "<rect width='400' height='400' fill='white'/>\n";
  for (const auto& e : t.connectivity().elements()) {
    const auto tri = t.triangle(e);
    f << "<polygon fill='#dde8f4' stroke='#345' stroke-width='0.6' points='";
    for (const Index v : tri) f << X(t.point(v)) << "," << Y(t.point(v)) << " ";
    f << "'/>\n";
  }
  if (!path.empty()) {
    f << "<polyline fill='none' stroke='#c22' stroke-width='1' stroke-dasharray='3,2' points='";
    for (const Vec2& p : path) f << X(p) << "," << Y(p) << " ";
    f << "'/>\n";
  }
  f << "</svg>\n";
  return f.str();
}

}  // namespace incise::delaunay
