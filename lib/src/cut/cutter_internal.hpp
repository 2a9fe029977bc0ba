#pragma once
/// \file cutter_internal.hpp
/// Private to the cut module: helpers shared by the source files of Cutter, one per stage of
/// the thesis' §3.2 pipeline (cutter.cpp driver, cutter_select.cpp §3.2.1, cutter_snap.cpp
/// §3.2.2, cutter_degeneracy.cpp and cutter_recipes.cpp §3.2.3, cutter_components.cpp §3.3).
/// Not installed, not part of the public API.

#include <incise/cut/cutter.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace incise::cut {

namespace detail {

/// Face j of element t (nodes mesh::kTetFace[j]) with its node indices sorted ascending; when
/// `parity` is given it receives the parity (0 even, 1 odd) of the sorting permutation, i.e.
/// the orientation of mesh::kTetFace[j] relative to the sorted order.
inline std::array<Index, 3> sorted_face(const Tet& t, int j, int* parity = nullptr) {
  std::array<Index, 3> f{t[static_cast<size_t>(mesh::kTetFace[j][0])],
                         t[static_cast<size_t>(mesh::kTetFace[j][1])],
                         t[static_cast<size_t>(mesh::kTetFace[j][2])]};
  int p = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < 2 - pass; ++i) {
      if (f[static_cast<size_t>(i)] > f[static_cast<size_t>(i + 1)]) {
        std::swap(f[static_cast<size_t>(i)], f[static_cast<size_t>(i + 1)]);
        p ^= 1;
      }
    }
  }
  if (parity) *parity = p;
  return f;
}

}  // namespace detail

/// Uniform hash grid over elements that have a boundary face (deformed bounding boxes at the
/// time each was entered). Invariant (cutter_select.cpp): every node w of an entered element
/// was within `tolerance` of anchor[w] when the element was entered, so widening a query by
/// slack = tolerance + max_w |x_w − anchor[w]| finds every boundary element the current
/// positions would. Entries of removed or no longer boundary elements may remain; queries
/// test every candidate exactly.
struct Cutter::Grid {
  double h = 1.0;
  std::int64_t lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};  ///< occupied cell range
  std::unordered_map<std::int64_t, std::vector<Index>> cells;
  /// Per element slot: the cell range it was entered in (lo > hi: not entered).
  std::vector<std::array<std::int64_t, 6>> range;
  std::vector<Vec3> anchor;  ///< per node (see the invariant)
  double tolerance = 0;      ///< CutOptions::search_grid_slack · h
  double slack = 0;          ///< query widening after the last sync
  static std::int64_t key(std::int64_t i, std::int64_t j, std::int64_t k) {
    constexpr std::int64_t kOff = 1 << 20;
    return ((i + kOff) << 42) | ((j + kOff) << 21) | (k + kOff);
  }
  std::int64_t coord(double x) const { return static_cast<std::int64_t>(std::floor(x / h)); }
};

}  // namespace incise::cut
