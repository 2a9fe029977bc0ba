#pragma once
// Helpers of the Delaunay-cutting tests and verification (property_tests/delaunay,
// verification/papers/nienhuys2003_ch5): validity with orientation, components, and moving a
// Cutter2D along a polyline in bounded steps.
#include <incise/delaunay/cutter2d.hpp>
#include <incise/delaunay/scalpel_path.hpp>
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

}  // namespace incise::test
