#include <incise/core/error.hpp>
#include <incise/mesh/repair.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>

namespace incise::mesh {

namespace {

// Union-find over a small index range.
Index find_root(std::vector<Index>& parent, Index i) {
  while (parent[i] != i) {
    parent[i] = parent[parent[i]];
    i = parent[i];
  }
  return i;
}

}  // namespace

PinchSplit split_pinched_vertices(MeshData& m) {
  const int k = m.dimension + 1;
  INCISE_CHECK(m.dimension == 2 || m.dimension == 3, "split_pinched_vertices: dimension 2 or 3");
  INCISE_CHECK(m.cells.rows() == k, "split_pinched_vertices: cells must have d+1 rows");
  const Index np = m.num_points(), nc = m.num_cells();
  // Vertex → cells (CSR).
  std::vector<Index> start(np + 1, 0);
  for (Index c = 0; c < nc; ++c)
    for (int r = 0; r < k; ++r) {
      const Index v = m.cells(r, c);
      INCISE_CHECK(v >= 0 && v < np, "split_pinched_vertices: vertex index out of range");
      ++start[v + 1];
    }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<Index> star(start.back());
  {
    std::vector<Index> fill(start.begin(), start.end() - 1);
    for (Index c = 0; c < nc; ++c)
      for (int r = 0; r < k; ++r) star[fill[m.cells(r, c)]++] = c;
  }
  PinchSplit out;
  out.first_new = np;
  // (facet minus v packed in 64 bits, local cell index in star(v)).
  std::vector<std::pair<std::uint64_t, Index>> keys;
  std::vector<Index> parent;
  std::vector<std::pair<Index, Index>> substitutions;  // (cell, new vertex) per split class
  std::vector<Index> new_of_cell_local;
  for (Index v = 0; v < np; ++v) {
    const Index n = start[v + 1] - start[v];
    if (n < 2) continue;
    keys.clear();
    for (Index i = 0; i < n; ++i) {
      const Index c = star[start[v] + i];
      std::array<Index, 3> others{};
      int no = 0;
      for (int r = 0; r < k; ++r)
        if (m.cells(r, c) != v) others[no++] = m.cells(r, c);
      // Facets through v: drop one of the other vertices.
      for (int drop = 0; drop < no; ++drop) {
        std::array<Index, 2> key{-1, -1};
        int nk = 0;
        for (int j = 0; j < no; ++j)
          if (j != drop) key[nk++] = others[j];
        if (nk == 2 && key[0] > key[1]) std::swap(key[0], key[1]);
        const std::uint64_t packed =
            (static_cast<std::uint64_t>(static_cast<std::uint32_t>(key[0])) << 32) |
            static_cast<std::uint32_t>(key[1]);
        keys.push_back({packed, i});
      }
    }
    std::sort(keys.begin(), keys.end());
    parent.resize(n);
    std::iota(parent.begin(), parent.end(), 0);
    for (std::size_t j = 1; j < keys.size(); ++j)
      if (keys[j].first == keys[j - 1].first) {
        const Index a = find_root(parent, keys[j].second),
                    b = find_root(parent, keys[j - 1].second);
        if (a != b) parent[std::max(a, b)] = std::min(a, b);
      }
    // Class of the lowest-numbered cell keeps v (star lists cells in increasing order).
    new_of_cell_local.assign(n, -1);
    const Index keep = find_root(parent, 0);
    bool pinched = false;
    for (Index i = 0; i < n; ++i) {
      const Index root = find_root(parent, i);
      if (root == keep) continue;
      if (new_of_cell_local[root] < 0) {
        new_of_cell_local[root] = out.first_new + static_cast<Index>(out.origin.size());
        out.origin.push_back(v);
        pinched = true;
      }
      substitutions.push_back({star[start[v] + i], new_of_cell_local[root]});
    }
    if (pinched) out.pinched.push_back(v);
  }
  if (out.origin.empty()) return out;
  // Apply: new points, cell substitutions, facet substitutions.
  const Index added = static_cast<Index>(out.origin.size());
  m.points.conservativeResize(3, np + added);
  for (Index j = 0; j < added; ++j) m.points.col(np + j) = m.points.col(out.origin[j]);
  if (!m.point_tags.empty())
    for (Index j = 0; j < added; ++j) m.point_tags.push_back(m.point_tags[out.origin[j]]);
  for (const auto& [c, w] : substitutions)
    for (int r = 0; r < k; ++r)
      if (m.cells(r, c) == out.origin[w - np]) m.cells(r, c) = w;
  // Facets: a facet through a split vertex v belongs to the class of a cell containing it.
  if (m.facets.rows() == m.dimension && m.facets.cols() > 0) {
    std::vector<char> is_pinched(np, 0);
    for (Index v : out.pinched) is_pinched[v] = 1;
    auto base = [&](Index w) { return w < np ? w : out.origin[w - np]; };
    for (Eigen::Index f = 0; f < m.facets.cols(); ++f)
      for (int r = 0; r < m.dimension; ++r) {
        const Index v = m.facets(r, f);
        if (v < 0 || v >= np || !is_pinched[v]) continue;
        // Find a cell (now relabelled) that contains the other facet vertices and a copy of v.
        for (Index i = start[v]; i < start[v + 1]; ++i) {
          const Index c = star[i];
          bool contains = true;
          for (int s = 0; s < m.dimension && contains; ++s) {
            if (s == r) continue;
            contains = false;
            for (int q = 0; q < k; ++q) contains |= base(m.cells(q, c)) == base(m.facets(s, f));
          }
          if (!contains) continue;
          for (int q = 0; q < k; ++q) {
            const Index w = m.cells(q, c);
            if (w == v || (w >= np && out.origin[w - np] == v)) m.facets(r, f) = w;
          }
          break;
        }
      }
  }
  return out;
}

}  // namespace incise::mesh
