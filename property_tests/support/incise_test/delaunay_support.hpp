#pragma once
// Helpers of the Delaunay-cutting tests and verification (property_tests/delaunay,
// verification/papers/nienhuys2003_ch5): validity with orientation, components, moving a
// Cutter2D along a polyline in bounded steps, the §5.3.2 one-active-node check and the turned
// scalpel over the pleated saddle (Fig. 5.18).
#include <incise/delaunay/cutter2d.hpp>
#include <incise/delaunay/scalpel_path.hpp>
#include <incise/delaunay/surface_cutter.hpp>
#include <incise/mesh/validate.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

namespace incise::test {

inline ::testing::AssertionResult valid(const delaunay::Triangulation& t) {
  mesh::ValidateOptions o;
  o.positions = &t.points();
  const auto r = mesh::validate(t.connectivity(), o);
  if (r.ok()) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << r.violations.front().invariant << ": " << r.violations.front().message;
}

/// Face-connected components of the live triangles (a Triangulation or a Surface).
template <class Mesh>
int components(const Mesh& t) {
  const auto& c = t.connectivity();
  std::vector<mesh::ElementHandle> all = c.elements();
  std::map<std::pair<Index, int>, int> seen;
  int n = 0;
  for (const auto& s : all) {
    if (seen.count({s.index, s.generation})) continue;
    ++n;
    std::vector<mesh::ElementHandle> stack{s};
    seen[{s.index, s.generation}] = 1;
    while (!stack.empty()) {
      const auto e = stack.back();
      stack.pop_back();
      for (const auto& nb : c.neighbours(e))
        if (nb.valid() && !seen.count({nb.index, nb.generation})) {
          seen[{nb.index, nb.generation}] = 1;
          stack.push_back(nb);
        }
    }
  }
  return n;
}

/// Moves the scalpel along the polyline `path` in steps of at most `step` (m)
/// (delaunay::movement_points). Returns the reports.
inline std::vector<delaunay::CutMove2DReport> cut_along(delaunay::Cutter2D& cutter,
                                                        delaunay::Triangulation& t,
                                                        const std::vector<Vec2>& path,
                                                        double step) {
  (void)t;
  std::vector<delaunay::CutMove2DReport> out;
  for (const Vec2& x : delaunay::movement_points(path, step)) out.push_back(cutter.move_to(x));
  return out;
}

/// Whether some live triangle has two of the cutter's active nodes (§5.3.2 forbids it).
inline bool two_active_in_a_triangle(const delaunay::Surface& s,
                                     const delaunay::SurfaceCutter& cutter) {
  const std::vector<Index> act = cutter.active_nodes();
  for (const mesh::ElementHandle e : s.connectivity().elements()) {
    int n = 0;
    for (const Index v : s.triangle(e)) n += std::count(act.begin(), act.end(), v) > 0;
    if (n > 1) return true;
  }
  return false;
}

/// A scalpel turned over the pleated saddle (delaunay::make_monkey_saddle, Fig. 5.18): a segment
/// centred on (x0, y, 0), y from −1.2 to 1.2 in steps of about `step`, along the z axis until
/// y = y_turn, then tilted towards the direction (cos ψ, sin ψ, 0) in the horizontal plane,
/// reaching it at y = y_turn + turn (φ = ½π min(1, (y − y_turn)/turn) from the vertical); its
/// half-length is `half` until then and grows by `grow` per unit of y after (so it spans the
/// branches as they part). With x0 = ψ = 0 the horizontal scalpel lies in the saddle's zero plane
/// z = 0 across the rays θ = 30°, 90°, 150°: it meets the surface three times, at x = 0, ±√3 y.
inline std::vector<delaunay::ScalpelSegment> saddle_turn(double x0, double y_turn, double turn,
                                                         double psi, double step, double half,
                                                         double grow) {
  std::vector<delaunay::ScalpelSegment> out;
  const int n = static_cast<int>(std::ceil(2.4 / step - 1e-9));
  for (int k = 0; k <= n; ++k) {
    const double y = -1.2 + 2.4 * k / n;
    const double phi = std::clamp((y - y_turn) / turn, 0.0, 1.0) * M_PI / 2;
    const double l = half + grow * std::max(0.0, y - y_turn - turn);
    const Vec3 c(x0, y, 0),
        d(std::sin(phi) * std::cos(psi), std::sin(phi) * std::sin(psi), std::cos(phi));
    out.push_back({c + l * d, c - l * d});
  }
  return out;
}

}  // namespace incise::test
