#include <incise/core/error.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/quality.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace incise::mesh {

namespace {

std::string num(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void check_count(const char* generator, const char* name, int n) {
  if (n < 1)
    throw GeneratorError(
        name, std::string(generator) + ": " + name + " = " + std::to_string(n) + " must be >= 1");
}

void check_length(const char* generator, const char* name, double l) {
  if (!(l > 0 && std::isfinite(l)))
    throw GeneratorError(name, std::string(generator) + ": " + name + " = " + num(l) +
                                   " must be positive and finite");
}

// The cell size length / count along one axis (length itself when count_name is null) must
// lie in [kMinCellSize, kMaxCellSize].
void check_cell_size(const char* generator, const char* length_name, const char* count_name,
                     double length, int count) {
  check_length(generator, length_name, length);
  if (count_name) check_count(generator, count_name, count);
  const double h = count_name ? length / count : length;
  if (!(h >= kMinCellSize && h <= kMaxCellSize))
    throw GeneratorError(length_name,
                         std::string(generator) + ": cell size " + length_name +
                             (count_name ? std::string(" / ") + count_name + " = " + num(length) +
                                               " / " + std::to_string(count)
                                         : std::string()) +
                             " = " + num(h) + " m is outside [" + num(kMinCellSize) + ", " +
                             num(kMaxCellSize) + "] m (cell volumes would not be representable)");
}

void check_index_range(const char* generator, const MeshSize& s) {
  constexpr std::int64_t kMax = std::numeric_limits<Index>::max();
  if (s.points > kMax || s.cells > kMax)
    throw GeneratorError("", std::string(generator) + ": " + std::to_string(s.cells) +
                                 " cells on " + std::to_string(s.points) +
                                 " points are more than an Index can number (" +
                                 std::to_string(kMax) + ")");
}

/// The signed volume of tetrahedron (a, b, c, d) of `p` (mesh/quality.hpp).
double tet_volume(const Eigen::Matrix3Xd& p, Index a, Index b, Index c, Index d) {
  return signed_volume(p.col(a), p.col(b), p.col(c), p.col(d));
}

}  // namespace

MeshSize box_size(int nx, int ny, int nz, double lx, double ly, double lz, CubeSplit split) {
  check_cell_size("make_box", "lx", "nx", lx, nx);
  check_cell_size("make_box", "ly", "ny", ly, ny);
  check_cell_size("make_box", "lz", "nz", lz, nz);
  const std::int64_t cubes = std::int64_t{nx} * ny * nz;
  return {(std::int64_t{nx} + 1) * (std::int64_t{ny} + 1) * (std::int64_t{nz} + 1),
          cubes * (split == CubeSplit::kFive ? 5 : 6)};
}

MeshData make_box(int nx, int ny, int nz, double lx, double ly, double lz, CubeSplit split) {
  check_index_range("make_box", box_size(nx, ny, nz, lx, ly, lz, split));
  MeshData m;
  m.dimension = 3;
  const Index px = nx + 1, py = ny + 1, pz = nz + 1;
  m.points.resize(3, static_cast<Eigen::Index>(px) * py * pz);
  auto node = [&](int i, int j, int k) { return static_cast<Index>(i + px * (j + py * k)); };
  for (int k = 0; k < pz; ++k)
    for (int j = 0; j < py; ++j)
      for (int i = 0; i < px; ++i)
        m.points.col(node(i, j, k)) = Vec3(lx * i / nx, ly * j / ny, lz * k / nz);

  const int per_cube = split == CubeSplit::kFive ? 5 : 6;
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
        if (split != CubeSplit::kFive) {
          // Paths 0 → e_a → e_a + e_b → 7 over the 6 axis permutations (a, b, c); kKuhn
          // reflects the cube's corners (bit flips) by the parity of (i, j, k).
          const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                   {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
          const int mirror =
              split == CubeSplit::kKuhn ? (i & 1) | ((j & 1) << 1) | ((k & 1) << 2) : 0;
          for (const auto& p : perms) {
            const int b1 = 1 << p[0];
            const int b2 = b1 | (1 << p[1]);
            local[count++] = {mirror, b1 ^ mirror, b2 ^ mirror, 7 ^ mirror};
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
          if (tet_volume(m.points, tet[0], tet[1], tet[2], tet[3]) < 0) std::swap(tet[2], tet[3]);
          for (int r = 0; r < 4; ++r) m.cells(r, c) = tet[r];
          ++c;
        }
      }
  return m;
}

MeshData make_kuhn_cube(int n, double side) {
  return make_box(n, n, n, side, side, side, CubeSplit::kKuhn);
}

MeshData make_beam(int h, double spacing) {
  if (h < 2)
    throw GeneratorError(
        "h", "make_beam: h (nodes along the axis) = " + std::to_string(h) + " must be >= 2");
  check_cell_size("make_beam", "spacing", nullptr, spacing, 1);
  return make_box(4, 4, h - 1, 4 * spacing, 4 * spacing, (h - 1) * spacing, CubeSplit::kFive);
}

MeshData make_brick(int n) {
  check_count("make_brick", "n", n);
  if (n > std::numeric_limits<int>::max() / 2)
    throw GeneratorError("n", "make_brick: n = " + std::to_string(n) + " is too large");
  return make_box(n, n, 2 * n, 1.0, 1.0, 2.0, CubeSplit::kFive);
}

MeshSize cylinder_size(double length, double radius, int rings, int layers) {
  check_cell_size("make_cylinder", "radius", "rings", radius, rings);
  check_cell_size("make_cylinder", "length", "layers", length, layers);
  const std::int64_t r = rings;
  return {(1 + 3 * r * (r + 1)) * (std::int64_t{layers} + 1), 18 * r * r * layers};
}

MeshData make_cylinder(double length, double radius, int rings, int layers) {
  check_index_range("make_cylinder", cylinder_size(length, radius, rings, layers));
  constexpr double kTwoPi = 6.28318530717958647692;
  // Cross-section: ring k (k = 0..rings) holds max(1, 6k) nodes; node (k, j) at angle 2πj/(6k).
  std::vector<Index> ring_start(rings + 2, 0);
  for (int k = 0; k <= rings; ++k) ring_start[k + 1] = ring_start[k] + (k == 0 ? 1 : 6 * k);
  const Index per_layer = ring_start[rings + 1];
  std::vector<Vec2> disk(per_layer);
  disk[0] = Vec2::Zero();
  for (int k = 1; k <= rings; ++k)
    for (int j = 0; j < 6 * k; ++j) {
      const double t = kTwoPi * j / (6.0 * k), r = radius * k / rings;
      disk[ring_start[k] + j] = Vec2(r * std::cos(t), r * std::sin(t));
    }
  // Triangulate between consecutive rings by merging the two angle sequences.
  std::vector<std::array<Index, 3>> tris;
  for (int k = 1; k <= rings; ++k) {
    const int n_in = k == 1 ? 1 : 6 * (k - 1), n_out = 6 * k;
    int i = 0, j = 0;
    auto in = [&](int q) { return ring_start[k - 1] + (q % n_in); };
    auto out = [&](int q) { return ring_start[k] + (q % n_out); };
    while (i < n_in || j < n_out) {
      // Advance the ring whose next node comes first in angle: (i+1)/n_in < (j+1)/n_out.
      if (k > 1 && i < n_in && (j == n_out || (i + 1) * n_out < (j + 1) * n_in)) {
        tris.push_back({in(i), out(j), in(i + 1)});
        ++i;
      } else {
        tris.push_back({in(i), out(j), out(j + 1)});
        ++j;
        if (k == 1 && j == n_out) i = n_in;
      }
    }
  }
  MeshData m;
  m.dimension = 3;
  m.points.resize(3, static_cast<Eigen::Index>(per_layer) * (layers + 1));
  for (int l = 0; l <= layers; ++l)
    for (Index v = 0; v < per_layer; ++v)
      m.points.col(static_cast<Eigen::Index>(l) * per_layer + v) =
          Vec3(length * l / layers, disk[v].x(), disk[v].y());
  m.cells.resize(4, static_cast<Eigen::Index>(tris.size()) * layers * 3);
  Eigen::Index c = 0;
  auto emit = [&](std::array<Index, 4> t) {
    if (tet_volume(m.points, t[0], t[1], t[2], t[3]) < 0) std::swap(t[2], t[3]);
    for (int r = 0; r < 4; ++r) m.cells(r, c) = t[r];
    ++c;
  };
  for (int l = 0; l < layers; ++l)
    for (const auto& tri : tris) {
      // Prism: bottom q[0..2], top q[3..5] with q[r+3] above q[r].
      std::array<Index, 6> q;
      for (int r = 0; r < 3; ++r) {
        q[r] = static_cast<Index>(l * per_layer + tri[r]);
        q[r + 3] = static_cast<Index>((l + 1) * per_layer + tri[r]);
      }
      // Dompierre et al.: rotate/reflect so that the smallest index is at bottom position 0.
      const int imin = static_cast<int>(std::min_element(q.begin(), q.end()) - q.begin());
      std::array<Index, 6> p;
      const int base = imin % 3;
      const bool top = imin >= 3;
      for (int r = 0; r < 3; ++r) {
        p[r] = q[(top ? 3 : 0) + (base + r) % 3];
        p[r + 3] = q[(top ? 0 : 3) + (base + r) % 3];
      }
      // Vertex p0 with the opposite triangle (p3,p4,p5), then the pyramid p0 + quad (p1,p2,p5,p4)
      // split along the diagonal through the quad's smallest vertex.
      emit({p[0], p[3], p[4], p[5]});
      const Index quad_min = std::min({p[1], p[2], p[4], p[5]});
      if (quad_min == p[1] || quad_min == p[5]) {
        emit({p[0], p[1], p[2], p[5]});
        emit({p[0], p[1], p[5], p[4]});
      } else {
        emit({p[0], p[1], p[2], p[4]});
        emit({p[0], p[2], p[5], p[4]});
      }
    }
  return m;
}

MeshData make_thesis_cylinder_small() {
  return make_cylinder(0.1, 0.03, 3, 8);
}

MeshData make_thesis_cylinder_large() {
  return make_cylinder(0.1, 0.03, 5, 21);
}

MeshData make_rectangle(int nx, int ny, double lx, double ly, GridDiagonal diagonal) {
  check_cell_size("make_rectangle", "lx", "nx", lx, nx);
  check_cell_size("make_rectangle", "ly", "ny", ly, ny);
  check_index_range("make_rectangle",
                    {(std::int64_t{nx} + 1) * (std::int64_t{ny} + 1), 2 * std::int64_t{nx} * ny});
  MeshData m;
  m.dimension = 2;
  const Index px = nx + 1;
  m.points.resize(3, static_cast<Eigen::Index>(px) * (ny + 1));
  auto node = [&](int i, int j) { return static_cast<Index>(i + px * j); };
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.points.col(node(i, j)) = Vec3(lx * i / nx, ly * j / ny, 0.0);
  m.cells.resize(3, static_cast<Eigen::Index>(nx) * ny * 2);
  Eigen::Index c = 0;
  auto emit = [&](Index a, Index b, Index d) {
    m.cells(0, c) = a;
    m.cells(1, c) = b;
    m.cells(2, c) = d;
    ++c;
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const Index v00 = node(i, j), v10 = node(i + 1, j), v01 = node(i, j + 1),
                  v11 = node(i + 1, j + 1);
      const bool forward = diagonal == GridDiagonal::kForward ||
                           (diagonal == GridDiagonal::kAlternating && (i + j) % 2 == 0);
      if (forward) {
        emit(v00, v10, v11);
        emit(v00, v11, v01);
      } else {
        emit(v00, v10, v01);
        emit(v10, v11, v01);
      }
    }
  return m;
}

}  // namespace incise::mesh
