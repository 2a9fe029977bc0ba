#include <incise/core/error.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/refine_uniform.hpp>

#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace incise::mesh {
namespace {

using EdgeKey = std::uint64_t;

EdgeKey edge_key(Index a, Index b) {
  if (a > b) std::swap(a, b);
  return (static_cast<EdgeKey>(static_cast<std::uint32_t>(a)) << 32) |
         static_cast<std::uint32_t>(b);
}

// Bey's children (refine_uniform.hpp) as indices into {v0, v1, v2, v3, m01, m02, m03, m12, m13,
// m23}: local vertex slots 0–3, edge midpoints 4–9 in kTetEdges order.
constexpr int kM01 = 4, kM02 = 5, kM03 = 6, kM12 = 7, kM13 = 8, kM23 = 9;
constexpr int kBeyChildren[8][4] = {{0, kM01, kM02, kM03},    {kM01, 1, kM12, kM13},
                                    {kM02, kM12, 2, kM23},    {kM03, kM13, kM23, 3},
                                    {kM01, kM02, kM03, kM13}, {kM01, kM02, kM12, kM13},
                                    {kM02, kM03, kM13, kM23}, {kM02, kM12, kM13, kM23}};
// Children whose orientation is opposite to the parent's in Bey's order: (x01, x02, x12, x13)
// has edge frame (x2−x1, x2−x0, x3−x0)/2, determinant −det(x1−x0, x2−x0, x3−x0)/8; likewise
// (x02, x12, x13, x23) with frame (x1−x0, x1+x3−x0−x2, x3−x0)/2. The other six are positive.
constexpr bool kBeyFlipped[8] = {false, false, false, false, false, true, false, true};

}  // namespace

MeshData refine_uniform(const MeshData& mesh) {
  INCISE_CHECK(mesh.dimension == 3 && mesh.cells.rows() == 4,
               "refine_uniform needs a tetrahedral mesh (dimension 3, 4 vertices per cell); got "
               "dimension " +
                   std::to_string(mesh.dimension));
  const Index n = mesh.num_points();
  const Index nc = mesh.num_cells();
  for (Index c = 0; c < nc; ++c)
    for (int r = 0; r < 4; ++r)
      INCISE_CHECK(mesh.cells(r, c) >= 0 && mesh.cells(r, c) < n,
                   "refine_uniform: cell " + std::to_string(c) + " has vertex index " +
                       std::to_string(mesh.cells(r, c)) + " outside 0.." + std::to_string(n - 1));
  INCISE_CHECK_PARAM(mesh.cell_tags.empty() || static_cast<Index>(mesh.cell_tags.size()) == nc,
                     "refine_uniform: cell_tags must be empty or one per cell");
  INCISE_CHECK_PARAM(mesh.point_tags.empty() || static_cast<Index>(mesh.point_tags.size()) == n,
                     "refine_uniform: point_tags must be empty or one per point");
  const Index nf = static_cast<Index>(mesh.facets.cols());
  INCISE_CHECK(nf == 0 || mesh.facets.rows() == 3,
               "refine_uniform: facets of a tetrahedral mesh are triangles (3 rows)");
  INCISE_CHECK_PARAM(mesh.facet_tags.empty() || static_cast<Index>(mesh.facet_tags.size()) == nf,
                     "refine_uniform: facet_tags must be empty or one per facet");

  // Distinct edges, sorted: midpoint of edges[k] is point n + k.
  std::vector<EdgeKey> edges;
  edges.reserve(6 * static_cast<std::size_t>(nc));
  for (Index c = 0; c < nc; ++c)
    for (const auto& e : kTetEdges)
      edges.push_back(edge_key(mesh.cells(e[0], c), mesh.cells(e[1], c)));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  INCISE_CHECK(n + edges.size() <= static_cast<std::size_t>(std::numeric_limits<Index>::max()),
               "refine_uniform: the refined mesh has more points than Index can number");
  auto midpoint = [&](Index a, Index b, const char* what, Index which) -> Index {
    const EdgeKey key = edge_key(a, b);
    const auto it = std::lower_bound(edges.begin(), edges.end(), key);
    INCISE_CHECK(it != edges.end() && *it == key, std::string("refine_uniform: ") + what + " " +
                                                      std::to_string(which) + " has edge (" +
                                                      std::to_string(a) + ", " + std::to_string(b) +
                                                      ") that is no edge of a cell");
    return n + static_cast<Index>(it - edges.begin());
  };

  MeshData out;
  out.dimension = 3;
  const Index n_out = n + static_cast<Index>(edges.size());
  out.points.resize(3, n_out);
  out.points.leftCols(n) = mesh.points;
  if (!mesh.point_tags.empty()) {
    out.point_tags = mesh.point_tags;
    out.point_tags.resize(static_cast<std::size_t>(n_out), 0);
  }
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const auto a = static_cast<Index>(edges[k] >> 32);
    const auto b = static_cast<Index>(edges[k] & 0xffffffffu);
    out.points.col(n + static_cast<Index>(k)) = 0.5 * (mesh.points.col(a) + mesh.points.col(b));
    if (!mesh.point_tags.empty() && mesh.point_tags[a] == mesh.point_tags[b])
      out.point_tags[n + k] = mesh.point_tags[a];
  }

  out.cells.resize(4, 8 * static_cast<Eigen::Index>(nc));
  for (Index c = 0; c < nc; ++c) {
    std::array<Index, 10> v{};
    for (int r = 0; r < 4; ++r) v[r] = mesh.cells(r, c);
    for (int e = 0; e < 6; ++e)
      v[4 + e] = midpoint(v[kTetEdges[e][0]], v[kTetEdges[e][1]], "cell", c);
    const bool negative_parent = signed_volume(mesh.points.col(v[0]), mesh.points.col(v[1]),
                                               mesh.points.col(v[2]), mesh.points.col(v[3])) < 0;
    for (int k = 0; k < 8; ++k) {
      std::array<Index, 4> child{};
      for (int r = 0; r < 4; ++r) child[r] = v[kBeyChildren[k][r]];
      // Swapping 1 and 3 keeps the diagonal pairing {0,2},{1,3} of the next refinement.
      if (kBeyFlipped[k] != negative_parent) std::swap(child[1], child[3]);
      for (int r = 0; r < 4; ++r) out.cells(r, 8 * static_cast<Eigen::Index>(c) + k) = child[r];
    }
  }
  if (!mesh.cell_tags.empty()) {
    out.cell_tags.resize(8 * static_cast<std::size_t>(nc));
    for (std::size_t k = 0; k < out.cell_tags.size(); ++k) out.cell_tags[k] = mesh.cell_tags[k / 8];
  }

  out.facets.resize(3, 4 * static_cast<Eigen::Index>(nf));
  for (Index f = 0; f < nf; ++f) {
    const Index a = mesh.facets(0, f), b = mesh.facets(1, f), c = mesh.facets(2, f);
    const Index ab = midpoint(a, b, "facet", f), bc = midpoint(b, c, "facet", f),
                ca = midpoint(c, a, "facet", f);
    const Index kids[4][3] = {{a, ab, ca}, {ab, b, bc}, {ca, bc, c}, {ab, bc, ca}};
    for (int k = 0; k < 4; ++k)
      for (int r = 0; r < 3; ++r) out.facets(r, 4 * static_cast<Eigen::Index>(f) + k) = kids[k][r];
  }
  if (!mesh.facet_tags.empty()) {
    out.facet_tags.resize(4 * static_cast<std::size_t>(nf));
    for (std::size_t k = 0; k < out.facet_tags.size(); ++k)
      out.facet_tags[k] = mesh.facet_tags[k / 4];
  }
  return out;
}

}  // namespace incise::mesh
