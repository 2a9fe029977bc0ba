#pragma once
// Private to the delaunay module: a uniform 3D grid of a Surface's triangles and boundary edges,
// kept current by watching the connectivity (§7.4), so that the surface cutter's entry search
// (boundary edges for eq. (5.1), triangles for the tip) costs O(items near the scalpel) instead
// of O(mesh). Cells of side h̄; an item is registered in every cell its bounding box overlaps, at
// the positions it had when it was added; refresh(v) re-registers the items of a node that
// moved (the cutter calls it after every move of an active node, the only nodes that move).
#include <incise/delaunay/surface.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace incise::delaunay::detail {

class SurfaceGrid : public mesh::ConnectivityWatcher {
 public:
  SurfaceGrid(const Surface& surface, double cell) : surface_(surface), cell_(cell) {}

  void init(const mesh::Connectivity& conn) override {
    cells_.clear();
    where_.clear();
    by_vertex_.clear();
    for (const mesh::ElementHandle e : conn.elements()) insert(conn.simplex(e));
    for (const mesh::FaceHandle f : conn.boundary()) insert(conn.simplex(f));
  }
  void element_removed(const mesh::Connectivity&, mesh::ElementHandle,
                       const mesh::Simplex& s) override {
    erase(s);
  }
  void element_added(const mesh::Connectivity& conn, mesh::ElementHandle e) override {
    insert(conn.simplex(e));
  }
  void element_changed(const mesh::Connectivity& conn, mesh::ElementHandle e,
                       const mesh::Simplex& old) override {
    erase(old);
    insert(conn.simplex(e));
  }
  void boundary_removed(const mesh::Connectivity&, mesh::FaceHandle,
                        const mesh::Simplex& s) override {
    erase(s);
  }
  void boundary_added(const mesh::Connectivity& conn, mesh::FaceHandle f) override {
    insert(conn.simplex(f));
  }

  /// Re-registers the triangles and boundary edges incident with v (after v moved).
  void refresh(Index v) {
    const auto it = by_vertex_.find(v);
    if (it == by_vertex_.end()) return;
    const std::vector<mesh::Simplex> mine = it->second;
    for (const mesh::Simplex& s : mine) {
      erase(s);
      insert(s);
    }
  }

  /// The registered simplices with `count` vertices (3: triangles, 2: boundary edges) in the
  /// cells that the bounding box of `points` overlaps, each once, sorted (a fixed order).
  std::vector<mesh::Simplex> near(const std::vector<Vec3>& points, int count) const {
    std::vector<mesh::Simplex> out;
    if (cells_.empty() || points.empty()) return out;
    Vec3 lo = points.front(), hi = points.front();
    for (const Vec3& p : points) {
      if (!p.allFinite()) return out;
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    // Clipped to the cells ever used: a scalpel far away costs no more than the mesh's cells.
    std::array<std::int64_t, 3> a{}, b{};
    for (size_t d = 0; d < 3; ++d) {
      a[d] = std::max(used_lo_[d], key(lo(static_cast<Eigen::Index>(d))));
      b[d] = std::min(used_hi_[d], key(hi(static_cast<Eigen::Index>(d))));
    }
    for (std::int64_t i = a[0]; i <= b[0]; ++i)
      for (std::int64_t j = a[1]; j <= b[1]; ++j)
        for (std::int64_t k = a[2]; k <= b[2]; ++k) {
          const auto it = cells_.find(pack(i, j, k));
          if (it == cells_.end()) continue;
          for (const mesh::Simplex& s : it->second)
            if (s.count() == count) out.push_back(s);
        }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

 private:
  /// floor(x / cell) clamped to ±2²⁰ cells (21 bits a coordinate in the packed key).
  std::int64_t key(double x) const {
    return static_cast<std::int64_t>(std::clamp(std::floor(x / cell_), -1048576.0, 1048575.0));
  }
  static std::int64_t pack(std::int64_t i, std::int64_t j, std::int64_t k) {
    const auto u = [](std::int64_t x) { return static_cast<std::uint64_t>(x) & 0x1fffffu; };
    return static_cast<std::int64_t>((u(i) << 42) | (u(j) << 21) | u(k));
  }
  void insert(const mesh::Simplex& s) {
    if (where_.count(s) != 0) return;  // registered already
    Vec3 lo = surface_.point(s.vertex(0)), hi = lo;
    for (int v = 0; v < s.count(); ++v) {
      by_vertex_[s.vertex(v)].push_back(s);
      lo = lo.cwiseMin(surface_.point(s.vertex(v)));
      hi = hi.cwiseMax(surface_.point(s.vertex(v)));
    }
    std::array<std::int64_t, 3> a{}, b{};
    for (size_t d = 0; d < 3; ++d) {
      a[d] = key(lo(static_cast<Eigen::Index>(d)));
      b[d] = key(hi(static_cast<Eigen::Index>(d)));
      used_lo_[d] = std::min(used_lo_[d], a[d]);
      used_hi_[d] = std::max(used_hi_[d], b[d]);
    }
    std::vector<std::int64_t>& keys = where_[s];
    for (std::int64_t i = a[0]; i <= b[0]; ++i)
      for (std::int64_t j = a[1]; j <= b[1]; ++j)
        for (std::int64_t k = a[2]; k <= b[2]; ++k) {
          cells_[pack(i, j, k)].push_back(s);
          keys.push_back(pack(i, j, k));
        }
  }
  void erase(const mesh::Simplex& s) {
    const auto it = where_.find(s);
    if (it == where_.end()) return;
    for (const std::int64_t c : it->second) {
      auto& cell = cells_[c];
      cell.erase(std::find(cell.begin(), cell.end(), s));
    }
    where_.erase(it);
    for (int v = 0; v < s.count(); ++v) {
      auto& list = by_vertex_[s.vertex(v)];
      list.erase(std::find(list.begin(), list.end(), s));
    }
  }

  const Surface& surface_;
  double cell_;
  std::unordered_map<std::int64_t, std::vector<mesh::Simplex>> cells_;
  std::unordered_map<mesh::Simplex, std::vector<std::int64_t>> where_;
  std::unordered_map<Index, std::vector<mesh::Simplex>> by_vertex_;
  std::array<std::int64_t, 3> used_lo_{1048575, 1048575, 1048575},
      used_hi_{-1048576, -1048576, -1048576};
};

}  // namespace incise::delaunay::detail
