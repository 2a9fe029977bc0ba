#include <incise/core/error.hpp>
#include <incise/mesh/generators.hpp>

#include <array>
#include <cmath>

namespace incise::mesh {

namespace {

double signed_volume(const Eigen::Matrix3Xd& p, Index a, Index b, Index c, Index d) {
  const Vec3 e1 = p.col(b) - p.col(a);
  const Vec3 e2 = p.col(c) - p.col(a);
  const Vec3 e3 = p.col(d) - p.col(a);
  return e1.dot(e2.cross(e3)) / 6.0;
}

}  // namespace

MeshData make_box(int nx, int ny, int nz, double lx, double ly, double lz, CubeSplit split) {
  INCISE_CHECK_PARAM(nx >= 1 && ny >= 1 && nz >= 1, "make_box: cell counts must be >= 1");
  INCISE_CHECK_PARAM(
      lx > 0 && ly > 0 && lz > 0 && std::isfinite(lx) && std::isfinite(ly) && std::isfinite(lz),
      "make_box: box lengths must be positive and finite");
  MeshData m;
  m.dimension = 3;
  const Index px = nx + 1, py = ny + 1, pz = nz + 1;
  m.points.resize(3, static_cast<Eigen::Index>(px) * py * pz);
  auto node = [&](int i, int j, int k) { return static_cast<Index>(i + px * (j + py * k)); };
  for (int k = 0; k < pz; ++k)
    for (int j = 0; j < py; ++j)
      for (int i = 0; i < px; ++i)
        m.points.col(node(i, j, k)) = Vec3(lx * i / nx, ly * j / ny, lz * k / nz);

  const int per_cube = split == CubeSplit::kSix ? 6 : 5;
  m.cells.resize(4, static_cast<Eigen::Index>(nx) * ny * nz * per_cube);
  Eigen::Index c = 0;
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) {
        // Cube corners by bit pattern b = bx + 2 by + 4 bz.
        std::array<Index, 8> v;
        for (int b = 0; b < 8; ++b)
          v[b] = node(i + (b & 1), j + ((b >> 1) & 1), k + ((b >> 2) & 1));
        std::array<std::array<int, 4>, 6> local;
        int count = 0;
        if (split == CubeSplit::kSix) {
          // Paths 0 → e_a → e_a + e_b → 7 over the 6 axis permutations (a, b, c).
          const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                   {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
          for (const auto& p : perms) {
            const int b1 = 1 << p[0];
            const int b2 = b1 | (1 << p[1]);
            local[count++] = {0, b1, b2, 7};
          }
        } else {
          // Corner tetrahedra cut off the corners of one parity class; central one remains.
          const bool even = ((i + j + k) % 2) == 0;
          const std::array<int, 4> keep =
              even ? std::array<int, 4>{0, 3, 5, 6} : std::array<int, 4>{1, 2, 4, 7};
          for (int corner :
               (even ? std::array<int, 4>{1, 2, 4, 7} : std::array<int, 4>{0, 3, 5, 6})) {
            std::array<int, 4> t{corner, corner ^ 1, corner ^ 2, corner ^ 4};
            local[count++] = t;
          }
          local[count++] = keep;
        }
        for (int t = 0; t < count; ++t) {
          std::array<Index, 4> tet{v[local[t][0]], v[local[t][1]], v[local[t][2]], v[local[t][3]]};
          if (signed_volume(m.points, tet[0], tet[1], tet[2], tet[3]) < 0)
            std::swap(tet[2], tet[3]);
          for (int r = 0; r < 4; ++r) m.cells(r, c) = tet[r];
          ++c;
        }
      }
  return m;
}

}  // namespace incise::mesh
