#include <incise/core/error.hpp>
#include <incise/mesh/tet_faces.hpp>

#include <algorithm>
#include <array>
#include <iterator>
#include <vector>

namespace incise::mesh {

CellMatrix boundary_faces(const CellMatrix& tets) {
  INCISE_CHECK(tets.rows() == 4, "boundary_faces needs tetrahedra (4 vertex indices per cell)");
  struct Face {
    std::array<Index, 3> key;  // sorted vertices: equal for the two sides of an interior face
    std::array<Index, 3> oriented;
  };
  std::vector<Face> faces;
  faces.reserve(4 * static_cast<std::size_t>(tets.cols()));
  for (Eigen::Index c = 0; c < tets.cols(); ++c)
    for (const auto& f : kTetFace) {
      Face face{{}, {tets(f[0], c), tets(f[1], c), tets(f[2], c)}};
      face.key = face.oriented;
      std::sort(face.key.begin(), face.key.end());
      faces.push_back(face);
    }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) { return a.key < b.key; });
  std::vector<std::size_t> single;  // faces whose key occurs once
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t j = i + 1;
    while (j < faces.size() && faces[j].key == faces[i].key) ++j;
    if (j == i + 1) single.push_back(i);
    i = j;
  }
  CellMatrix out(3, static_cast<Eigen::Index>(single.size()));
  for (std::size_t k = 0; k < single.size(); ++k)
    for (int r = 0; r < 3; ++r) out(r, static_cast<Eigen::Index>(k)) = faces[single[k]].oriented[r];
  return out;
}

CellMatrix boundary_faces(const MeshData& mesh) {
  INCISE_CHECK(mesh.dimension == 3, "boundary_faces needs a tetrahedral mesh");
  return boundary_faces(mesh.cells);
}

FacetCoverage facet_coverage(const CellMatrix& tets, const CellMatrix& facets) {
  INCISE_CHECK(facets.rows() == 3, "facet_coverage: facets must have 3 vertex indices each");
  auto sorted_keys = [](const CellMatrix& tri) {
    std::vector<std::array<Index, 3>> keys;
    keys.reserve(static_cast<std::size_t>(tri.cols()));
    for (Eigen::Index f = 0; f < tri.cols(); ++f) {
      std::array<Index, 3> key{tri(0, f), tri(1, f), tri(2, f)};
      std::sort(key.begin(), key.end());
      keys.push_back(key);
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    return keys;
  };
  const std::vector<std::array<Index, 3>> boundary = sorted_keys(boundary_faces(tets));
  const std::vector<std::array<Index, 3>> listed = sorted_keys(facets);
  std::vector<std::array<Index, 3>> common;
  std::set_intersection(listed.begin(), listed.end(), boundary.begin(), boundary.end(),
                        std::back_inserter(common));
  FacetCoverage c;
  c.distinct = listed.size();
  c.on_boundary = common.size();
  c.interior = listed.size() - common.size();
  c.boundary_not_listed = boundary.size() - common.size();
  return c;
}

}  // namespace incise::mesh
