#pragma once
// Private to the delaunay module: a uniform grid of the boundary edges of a Triangulation, kept
// current by watching the connectivity (§7.4), so that the cutter's collision search costs
// O(edges near the scalpel) instead of O(boundary). Cells of side h̄ (the mean edge length); an
// edge is registered in every cell its bounding box overlaps, at the positions it had when it
// entered the boundary (refresh(v) re-registers the edges of a node that moved).
#include <incise/delaunay/triangulation.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

namespace incise::delaunay::detail {

class BoundaryGrid : public mesh::ConnectivityWatcher {
 public:
  BoundaryGrid(const Triangulation& mesh, double cell) : mesh_(mesh), cell_(cell) {}

  void init(const mesh::Connectivity& conn) override {
    cells_.clear();
    where_.clear();
    by_vertex_.clear();
    for (const mesh::FaceHandle f : conn.boundary()) insert(directed(conn.simplex(f)));
  }
  void boundary_removed(const mesh::Connectivity&, mesh::FaceHandle,
                        const mesh::Simplex& s) override {
    erase(directed(s));
  }
  void boundary_added(const mesh::Connectivity& conn, mesh::FaceHandle f) override {
    insert(directed(conn.simplex(f)));
  }

  /// Re-registers the boundary edges incident with v (after v moved).
  void refresh(Index v) {
    const auto it = by_vertex_.find(v);
    if (it == by_vertex_.end()) return;
    const std::vector<std::array<Index, 2>> mine = it->second;
    for (const auto& e : mine) {
      erase(e);
      insert(e);
    }
  }

  /// The directed boundary edges (interior on the left) registered in the cells that the
  /// bounding box of segment a–b (grown by `margin`) overlaps, each once.
  std::vector<std::array<Index, 2>> near(const Vec2& a, const Vec2& b, double margin) const {
    std::vector<std::array<Index, 2>> out;
    if (cells_.empty() || !a.allFinite() || !b.allFinite()) return out;
    // The query box clipped to the cells ever used: a scalpel far outside the mesh (or a huge
    // coordinate) costs no more than the mesh's own cells.
    const Vec2 qlo(std::min(a.x(), b.x()) - margin, std::min(a.y(), b.y()) - margin);
    const Vec2 qhi(std::max(a.x(), b.x()) + margin, std::max(a.y(), b.y()) + margin);
    const std::array<std::int64_t, 2> lo{std::max(used_lo_[0], clamped_key(qlo.x())),
                                         std::max(used_lo_[1], clamped_key(qlo.y()))};
    const std::array<std::int64_t, 2> hi{std::min(used_hi_[0], clamped_key(qhi.x())),
                                         std::min(used_hi_[1], clamped_key(qhi.y()))};
    for (std::int64_t i = lo[0]; i <= hi[0]; ++i)
      for (std::int64_t j = lo[1]; j <= hi[1]; ++j) {
        const auto it = cells_.find(pack(i, j));
        if (it == cells_.end()) continue;
        for (const auto& e : it->second)
          if (std::find(out.begin(), out.end(), e) == out.end()) out.push_back(e);
      }
    return out;
  }

 private:
  struct EdgeHash {
    std::size_t operator()(const std::array<Index, 2>& e) const {
      return std::hash<std::int64_t>()((static_cast<std::int64_t>(e[0]) << 32) ^ e[1]);
    }
  };
  static std::array<Index, 2> directed(const mesh::Simplex& s) {
    return s.sign() > 0 ? std::array<Index, 2>{s.vertex(0), s.vertex(1)}
                        : std::array<Index, 2>{s.vertex(1), s.vertex(0)};
  }
  /// floor(x / cell) clamped to ±2⁴⁰ (no overflow for any finite x).
  std::int64_t clamped_key(double x) const {
    const double k = std::floor(x / cell_);
    return static_cast<std::int64_t>(std::clamp(k, -1099511627776.0, 1099511627776.0));
  }
  std::array<std::int64_t, 2> key_of(const Vec2& x) const {
    return {clamped_key(x.x()), clamped_key(x.y())};
  }
  static std::int64_t pack(std::int64_t i, std::int64_t j) {
    // Unsigned shift: a negative cell index must not be shifted as a signed value (UB).
    return static_cast<std::int64_t>((static_cast<std::uint64_t>(i) << 32) ^
                                     (static_cast<std::uint64_t>(j) & 0xffffffffu));
  }
  void insert(const std::array<Index, 2>& e) {
    for (const Index v : e) by_vertex_[v].push_back(e);
    const Vec2 a = mesh_.point(e[0]), b = mesh_.point(e[1]);
    const auto lo = key_of(a.cwiseMin(b)), hi = key_of(a.cwiseMax(b));
    std::vector<std::int64_t>& keys = where_[e];
    for (int d = 0; d < 2; ++d) {
      used_lo_[static_cast<size_t>(d)] =
          std::min(used_lo_[static_cast<size_t>(d)], lo[static_cast<size_t>(d)]);
      used_hi_[static_cast<size_t>(d)] =
          std::max(used_hi_[static_cast<size_t>(d)], hi[static_cast<size_t>(d)]);
    }
    for (std::int64_t i = lo[0]; i <= hi[0]; ++i)
      for (std::int64_t j = lo[1]; j <= hi[1]; ++j) {
        cells_[pack(i, j)].push_back(e);
        keys.push_back(pack(i, j));
      }
  }
  void erase(const std::array<Index, 2>& e) {
    const auto it = where_.find(e);
    if (it == where_.end()) return;
    for (const Index v : e) {
      auto& list = by_vertex_[v];
      list.erase(std::remove(list.begin(), list.end(), e), list.end());
      if (list.empty()) by_vertex_.erase(v);
    }
    for (const std::int64_t k : it->second) {
      auto& v = cells_[k];
      v.erase(std::remove(v.begin(), v.end(), e), v.end());
      if (v.empty()) cells_.erase(k);
    }
    where_.erase(it);
  }

  const Triangulation& mesh_;
  double cell_;
  std::unordered_map<std::int64_t, std::vector<std::array<Index, 2>>> cells_;
  std::unordered_map<std::array<Index, 2>, std::vector<std::int64_t>, EdgeHash> where_;
  std::unordered_map<Index, std::vector<std::array<Index, 2>>> by_vertex_;
  // Range of cell keys ever used (grows only).
  std::array<std::int64_t, 2> used_lo_{std::numeric_limits<std::int64_t>::max(),
                                       std::numeric_limits<std::int64_t>::max()};
  std::array<std::int64_t, 2> used_hi_{std::numeric_limits<std::int64_t>::min(),
                                       std::numeric_limits<std::int64_t>::min()};
};

}  // namespace incise::delaunay::detail
