/// \file cutter_select.cpp
/// Face selection (thesis §3.2.1, Figs. 3.1–3.3): the search from the boundary hits (a hash grid
/// over boundary elements) and the remembered incomplete tetrahedra outward, the first
/// sweep/edge intersection of every edge marking its closest node, and the evaluation of
/// tetrahedra with three (or, halved, four) marked nodes into selected faces.

#include <incise/cut/predicates.hpp>

#include "cutter_internal.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <unordered_set>

namespace incise::cut {

using detail::sorted_face;

namespace {

/// Half-width of the band around t = 1/2 inside which an edge counts as halved and the
/// lowest node index is marked (§3.2.1). Relative to the edge parameter, far above the
/// ~1e-16 relative error of t = d_p/(d_p − d_q).
constexpr double kHalfTie = 1e-12;

}  // namespace

void Cutter::grid_insert(Index e) {
  if (static_cast<Index>(grid_->range.size()) < mesh_.element_capacity())
    grid_->range.resize(static_cast<size_t>(mesh_.element_capacity()), {0, 0, 0, -1, -1, -1});
  auto& range = grid_->range[static_cast<size_t>(e)];
  for (std::int64_t i = range[0]; i <= range[3]; ++i)  // leave the cells it was entered in
    for (std::int64_t j = range[1]; j <= range[4]; ++j)
      for (std::int64_t k = range[2]; k <= range[5]; ++k) {
        auto it = grid_->cells.find(Grid::key(i, j, k));
        if (it == grid_->cells.end()) continue;
        auto& list = it->second;
        list.erase(std::remove(list.begin(), list.end(), e), list.end());
      }
  range = {0, 0, 0, -1, -1, -1};
  if (!mesh_.alive(e)) return;
  bool boundary = false;
  for (int j = 0; j < 4 && !boundary; ++j) boundary = mesh_.neighbor(e, j) < 0;
  if (!boundary) return;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (Index v : mesh_.element(e)) {
    lo = lo.cwiseMin(mesh_.deformed(v));
    hi = hi.cwiseMax(mesh_.deformed(v));
  }
  const std::int64_t c0[3] = {grid_->coord(lo.x()), grid_->coord(lo.y()), grid_->coord(lo.z())};
  const std::int64_t c1[3] = {grid_->coord(hi.x()), grid_->coord(hi.y()), grid_->coord(hi.z())};
  const bool empty = grid_->hi[0] < grid_->lo[0];
  for (int d = 0; d < 3; ++d) {
    grid_->lo[d] = empty ? c0[d] : std::min(grid_->lo[d], c0[d]);
    grid_->hi[d] = empty ? c1[d] : std::max(grid_->hi[d], c1[d]);
  }
  range = {c0[0], c0[1], c0[2], c1[0], c1[1], c1[2]};
  for (std::int64_t i = c0[0]; i <= c1[0]; ++i)
    for (std::int64_t j = c0[1]; j <= c1[1]; ++j)
      for (std::int64_t k = c0[2]; k <= c1[2]; ++k) grid_->cells[Grid::key(i, j, k)].push_back(e);
}

void Cutter::grid_sync_nodes() {
  // Nodes that moved more than the tolerance from their anchor (or are new) are anchored at
  // their current position and their stars entered again; the others keep the invariant of
  // Grid, so the queries' slack is the tolerance plus the largest remaining distance. The scan
  // is O(nodes) of arithmetic; the grid work is proportional to the elements re-entered.
  const Index n = mesh_.num_nodes();
  const Index old_n = static_cast<Index>(grid_->anchor.size());
  grid_->anchor.resize(static_cast<size_t>(n));
  std::vector<Index> reenter;
  double remaining = 0;
  for (Index v = 0; v < n; ++v) {
    const Vec3& x = mesh_.deformed(v);
    Vec3& a = grid_->anchor[static_cast<size_t>(v)];
    const double d = v < old_n ? (x - a).norm() : std::numeric_limits<double>::infinity();
    if (d <= grid_->tolerance) {
      remaining = std::max(remaining, d);
      continue;
    }
    a = x;
    if (mesh_.unused(v)) continue;
    for (Index e : mesh_.star(v)) reenter.push_back(e);
  }
  std::sort(reenter.begin(), reenter.end());
  reenter.erase(std::unique(reenter.begin(), reenter.end()), reenter.end());
  for (Index e : reenter) grid_insert(e);
  grid_reentries_ += static_cast<std::int64_t>(reenter.size());
  grid_->slack = grid_->tolerance + remaining;
  grid_version_ = mesh_.positions_version();
}

void Cutter::collect_seeds(const Vec3 (&tri)[3], std::vector<Index>& seeds) {
  if (grid_version_ == ~std::uint64_t{0}) {
    // Build once: cell size = mean longest edge of the boundary elements.
    double sum = 0;
    Index count = 0;
    for (Index e = 0; e < mesh_.element_capacity(); ++e) {
      if (!mesh_.alive(e)) continue;
      bool boundary = false;
      for (int j = 0; j < 4 && !boundary; ++j) boundary = mesh_.neighbor(e, j) < 0;
      if (!boundary) continue;
      const Tet& t = mesh_.element(e);
      double m = 0;
      for (const auto& ed : kTetEdge)
        m = std::max(m, (mesh_.deformed(t[static_cast<size_t>(ed[0])]) -
                         mesh_.deformed(t[static_cast<size_t>(ed[1])]))
                            .norm());
      sum += m;
      ++count;
    }
    grid_->h = count > 0 && sum > 0 ? sum / count : 1.0;
    grid_->tolerance = options_.search_grid_slack * grid_->h;
    for (Index e = 0; e < mesh_.element_capacity(); ++e) grid_insert(e);
    grid_->anchor.resize(static_cast<size_t>(mesh_.num_nodes()));
    for (Index v = 0; v < mesh_.num_nodes(); ++v)
      grid_->anchor[static_cast<size_t>(v)] = mesh_.deformed(v);
    grid_->slack = 0;
    grid_version_ = mesh_.positions_version();
    ++grid_builds_;
  } else if (grid_version_ != mesh_.positions_version()) {
    grid_sync_nodes();
  }
  const double slack = grid_->slack;
  const Vec3 n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized();
  const Vec3 lo = tri[0].cwiseMin(tri[1]).cwiseMin(tri[2]) - Vec3::Constant(slack);
  const Vec3 hi = tri[0].cwiseMax(tri[1]).cwiseMax(tri[2]) + Vec3::Constant(slack);
  const double h = grid_->h;
  const double reach = 0.5 * h * n.cwiseAbs().sum() + slack;
  // Enumerate only cells inside both Δ's box and the occupied range of the grid.
  const std::int64_t q0[3] = {std::max(grid_->coord(lo.x()), grid_->lo[0]),
                              std::max(grid_->coord(lo.y()), grid_->lo[1]),
                              std::max(grid_->coord(lo.z()), grid_->lo[2])};
  const std::int64_t q1[3] = {std::min(grid_->coord(hi.x()), grid_->hi[0]),
                              std::min(grid_->coord(hi.y()), grid_->hi[1]),
                              std::min(grid_->coord(hi.z()), grid_->hi[2])};
  for (std::int64_t i = q0[0]; i <= q1[0]; ++i)
    for (std::int64_t j = q0[1]; j <= q1[1]; ++j)
      for (std::int64_t k = q0[2]; k <= q1[2]; ++k) {
        const Vec3 centre((i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h);
        if (std::abs(n.dot(centre - tri[0])) > reach * (1 + 1e-9)) continue;  // plane misses cell
        auto it = grid_->cells.find(Grid::key(i, j, k));
        if (it == grid_->cells.end()) continue;
        for (Index e : it->second) seeds.push_back(e);
      }
}

void Cutter::select_faces(const Vec3 (&tri)[3], CutStepReport& r,
                          std::vector<std::pair<Index, int>>& faces) {
  std::vector<Index> seeds;
  collect_seeds(tri, seeds);
  for (Index e : incomplete_) seeds.push_back(e);
  std::sort(seeds.begin(), seeds.end());
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());

  stamp_.resize(static_cast<size_t>(mesh_.element_capacity()), 0);
  done_.resize(static_cast<size_t>(mesh_.element_capacity()), 0);
  ++stamp_value_;
  std::deque<Index> queue;
  for (Index e : seeds) {
    if (e < mesh_.element_capacity() && mesh_.alive(e) &&
        stamp_[static_cast<size_t>(e)] != stamp_value_) {
      stamp_[static_cast<size_t>(e)] = stamp_value_;
      queue.push_back(e);
    }
  }
  std::unordered_set<EdgeKey> tested;
  std::vector<Index> touched;
  while (!queue.empty()) {
    const Index e = queue.front();
    queue.pop_front();
    const Tet& t = mesh_.element(e);
    const Vec3 p[4] = {mesh_.deformed(t[0]), mesh_.deformed(t[1]), mesh_.deformed(t[2]),
                       mesh_.deformed(t[3])};
    ++r.elements_tested;
    if (!triangle_meets_tetrahedron(tri[0], tri[1], tri[2], p)) continue;
    touched.push_back(e);
    for (const auto& ed : kTetEdge) {
      Index a = t[static_cast<size_t>(ed[0])], b = t[static_cast<size_t>(ed[1])];
      const EdgeKey key = edge_key(a, b);
      if (marked_.count(key) || !tested.insert(key).second) continue;
      if (b < a) std::swap(a, b);  // test from the lower index: one answer per edge
      const SegmentHit hit =
          intersect_segment_triangle(mesh_.deformed(a), mesh_.deformed(b), tri[0], tri[1], tri[2]);
      if (!hit.hit) continue;
      const Index mark = hit.t > 0.5 + kHalfTie ? b : a;  // ties → lowest index
      marked_.emplace(key, mesh_.origin(mark));
      ++r.edges_intersected;
    }
    for (int j = 0; j < 4; ++j) {
      const Index nb = mesh_.neighbor(e, j);
      if (nb >= 0 && stamp_[static_cast<size_t>(nb)] != stamp_value_) {
        stamp_[static_cast<size_t>(nb)] = stamp_value_;
        queue.push_back(nb);
      }
    }
  }

  // Evaluate touched and remembered incomplete tetrahedra (§3.2.1, Fig. 3.1, 3.2).
  std::vector<Index> candidates = touched;
  for (Index e : incomplete_) candidates.push_back(e);
  evaluate(candidates, r, faces);
}

void Cutter::evaluate(std::vector<Index> candidates, CutStepReport& r,
                      std::vector<std::pair<Index, int>>& faces) {
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  done_.resize(static_cast<size_t>(mesh_.element_capacity()), 0);
  std::vector<std::array<Index, 3>> chosen;
  for (const auto& [e, j] : faces) chosen.push_back(sorted_face(mesh_.element(e), j));
  for (Index e : candidates) {
    if (!mesh_.alive(e)) {
      incomplete_.erase(e);
      continue;
    }
    if (done_[static_cast<size_t>(e)]) {
      incomplete_.erase(e);
      continue;
    }
    const Tet& t = mesh_.element(e);
    int marks = 0;
    for (const auto& ed : kTetEdge) {
      auto it =
          marked_.find(edge_key(t[static_cast<size_t>(ed[0])], t[static_cast<size_t>(ed[1])]));
      if (it == marked_.end()) continue;
      for (int k : {ed[0], ed[1]}) {
        if (mesh_.origin(t[static_cast<size_t>(k)]) == it->second) marks |= 1 << k;
      }
    }
    const int count = __builtin_popcount(static_cast<unsigned>(marks));
    if (count < 3) {
      if (count > 0) incomplete_.insert(e);
      continue;
    }
    int j = 0;
    if (count == 3) {
      while (marks & (1 << j)) ++j;
    } else {
      // All four nodes marked (edges halved, or two sweeps): seeded choice (§3.3).
      ++r.halved_choices;
      std::vector<int> interior;
      for (int k = 0; k < 4; ++k) {
        if (mesh_.neighbor(e, k) >= 0) interior.push_back(k);
      }
      if (interior.empty()) interior = {0, 1, 2, 3};
      j = interior[static_cast<size_t>(rng_() % interior.size())];
    }
    done_[static_cast<size_t>(e)] = 1;
    incomplete_.erase(e);
    if (mesh_.neighbor(e, j) < 0) continue;  // already a boundary (or cut) face
    const auto key = sorted_face(t, j);
    if (std::find(chosen.begin(), chosen.end(), key) != chosen.end()) continue;
    chosen.push_back(key);
    faces.emplace_back(e, j);
  }
}

}  // namespace incise::cut
