#include <incise/delaunay/predicates.hpp>
#include <incise/delaunay/subdivision.hpp>

#include "planar.hpp"

#include <incise/core/error.hpp>

#include <algorithm>
#include <map>
#include <set>
#include <tuple>

namespace incise::delaunay {
namespace {

using mesh::ElementHandle;

/// A node at x: a vertex within snap of x, else a new node on the edge or in the triangle that
/// contains x; −1 when x is outside the mesh.
Index node_at(Triangulation& m, const Vec2& x, double snap) {
  const ElementHandle e = m.locate(x);
  if (!e.valid()) return -1;
  const auto t = m.triangle(e);
  for (const Index v : t)
    if ((m.point(v) - x).norm() < snap) return v;
  for (int i = 0; i < 3; ++i)
    if (orient2d(m.point(t[static_cast<size_t>(i)]), m.point(t[static_cast<size_t>((i + 1) % 3)]),
                 x) == 0)
      return m.split_edge(t[static_cast<size_t>(i)], t[static_cast<size_t>((i + 1) % 3)], x);
  return m.split_triangle(e, x);
}

}  // namespace

SubdivisionReport subdivision_cut(Triangulation& m, const std::vector<Vec2>& path,
                                  SubdivisionOptions options) {
  INCISE_CHECK_PARAM(path.size() >= 2, "subdivision_cut: the path needs at least two points");
  for (const Vec2& p : path)
    INCISE_CHECK_PARAM(p.allFinite() && p.cwiseAbs().maxCoeff() <= 1e60,
                       "subdivision_cut: path point not finite or beyond 1e60 m");
  INCISE_CHECK_PARAM(std::isfinite(options.snap) && options.snap > 0 && options.snap < 0.5,
                     "subdivision_cut: snap must be in (0, 0.5)");
  SubdivisionReport r;
  r.triangles_before = m.num_triangles();
  const std::vector<Edge> start_edges = m.edges();
  double sum = 0;
  for (const Edge& e : start_edges) sum += (m.point(e.first) - m.point(e.second)).norm();
  const double snap =
      options.snap * sum / static_cast<double>(std::max<size_t>(1, start_edges.size()));

  auto add_chain = [&](Index v) {
    if (v >= 0 && (r.chain.empty() || r.chain.back() != v)) r.chain.push_back(v);
  };
  add_chain(node_at(m, path[0], snap));
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const Vec2 s = path[i], t = path[i + 1];
    // Crossings of s→t with the current edges, in order along the segment.
    std::vector<std::tuple<double, Index, Index>> hits;
    for (const Edge& e : m.edges()) {
      const Vec2 a = m.point(e.first), b = m.point(e.second);
      const int oa = orient2d(s, t, a), ob = orient2d(s, t, b);
      if (oa == ob) continue;  // same side, or the edge lies on the path's line
      const int os = orient2d(a, b, s), ot = orient2d(a, b, t);
      if (os == ot && os != 0) continue;
      const double den = cross(t - s, b - a);
      if (den == 0) continue;
      const double tt = std::clamp(cross(a - s, b - a) / den, 0.0, 1.0);
      hits.emplace_back(tt, e.first, e.second);
    }
    std::sort(hits.begin(), hits.end());
    for (const auto& [tt, p, q] : hits) {
      if (m.incident(p, q).empty()) continue;  // split already (a crossing at the same point)
      const Vec2 x = s + tt * (t - s);
      Index v = -1;
      if ((m.point(p) - x).norm() < snap)
        v = p;
      else if ((m.point(q) - x).norm() < snap)
        v = q;
      else
        v = m.split_edge(p, q, x);
      if (v < 0) continue;
      ++r.crossings;
      add_chain(v);
    }
  }
  add_chain(node_at(m, path.back(), snap));

  // Dissect along the chain: at every chain node, the star is split into the groups of
  // triangles connected across non-chain edges; every group but the first gets a copy.
  std::map<Index, Index> original;  // copy → chain node it was made from
  std::map<Index, std::set<Index>> chain_nb;
  for (size_t i = 0; i + 1 < r.chain.size(); ++i) {
    const Index a = r.chain[i], b = r.chain[i + 1];
    if (m.incident(a, b).empty()) continue;  // not joined by an edge: not an incision link
    chain_nb[a].insert(b);
    chain_nb[b].insert(a);
  }
  auto orig = [&](Index v) {
    const auto it = original.find(v);
    return it == original.end() ? v : it->second;
  };
  std::set<Index> done;
  for (const Index v : r.chain) {
    if (!done.insert(v).second) continue;
    const std::set<Index>& nb = chain_nb[v];
    const std::vector<ElementHandle> star = m.connectivity().star(v);
    std::vector<int> group(star.size(), -1);
    int groups = 0;
    for (size_t k = 0; k < star.size(); ++k) {
      if (group[k] >= 0) continue;
      std::vector<size_t> stack{k};
      group[k] = groups;
      while (!stack.empty()) {
        const size_t j = stack.back();
        stack.pop_back();
        for (const Index w : m.triangle(star[j])) {
          if (w == v || nb.count(orig(w))) continue;  // across a chain edge: not connected
          for (size_t l = 0; l < star.size(); ++l)
            if (group[l] < 0 && m.connectivity().simplex(star[l]).contains(w)) {
              group[l] = groups;
              stack.push_back(l);
            }
        }
      }
      ++groups;
    }
    if (groups <= 1) continue;
    std::vector<ElementHandle> remove;
    std::vector<std::array<Index, 3>> add;
    std::vector<Index> copies{v};
    for (int g = 1; g < groups; ++g) copies.push_back(m.add_vertex(m.point(v)));
    for (size_t k = 0; k < star.size(); ++k) {
      if (group[k] == 0) continue;
      auto t = m.triangle(star[k]);
      for (Index& w : t)
        if (w == v) w = copies[static_cast<size_t>(group[k])];
      remove.push_back(star[k]);
      add.push_back(t);
    }
    if (m.replace(remove, add)) {
      ++r.dissected;
      for (size_t g = 1; g < copies.size(); ++g) original[copies[g]] = v;
    }
  }
  r.triangles_after = m.num_triangles();
  return r;
}

}  // namespace incise::delaunay
