#pragma once
// Topology shared by the planar Triangulation and the 3D Surface (thesis ch. 5 on the ch. 7
// connectivity): oriented triangles, edge incidence, and the two local algorithms whose logic
// does not depend on the geometry — Lawson legalization (§5.2.1) and node removal by ear flips
// (§5.3.1, Fig. 5.10). The geometry enters only through the mesh's flip() and
// is_locally_delaunay() (exact orient2d/incircle in the plane; the unfolded criterion on a
// surface), so one definition of each algorithm serves both.

#include <incise/delaunay/edge.hpp>
#include <incise/mesh/connectivity.hpp>

#include <algorithm>
#include <array>
#include <vector>

namespace incise::delaunay::detail {

/// The vertices of triangle s in the order of its orientation (§7.2: the sorted sequence for
/// sign +1, one swap for −1): counter-clockwise in the plane, right-handed about the surface
/// normal on a surface.
inline std::array<Index, 3> oriented(const mesh::Simplex& s) {
  if (s.sign() > 0) return {s.vertex(0), s.vertex(1), s.vertex(2)};
  return {s.vertex(0), s.vertex(2), s.vertex(1)};
}

/// Rotates an oriented triple so that v comes first.
inline std::array<Index, 3> starting_at(std::array<Index, 3> t, Index v) {
  while (t[0] != v) std::rotate(t.begin(), t.begin() + 1, t.end());
  return t;
}

/// The live triangles incident with edge {p, q}.
inline std::vector<mesh::ElementHandle> incident(const mesh::Connectivity& c, Index p, Index q) {
  std::vector<mesh::ElementHandle> out;
  if (p < 0 || p >= c.num_vertices()) return out;
  for (const mesh::ElementHandle e : c.star(p))
    if (c.simplex(e).contains(q)) out.push_back(e);
  return out;
}

/// The triangle containing the directed edge p→q, or an invalid handle.
inline mesh::ElementHandle left_of(const mesh::Connectivity& c, Index p, Index q) {
  for (const mesh::ElementHandle e : incident(c, p, q)) {
    const auto t = oriented(c.simplex(e));
    for (size_t i = 0; i < 3; ++i)
      if (t[i] == p && t[(i + 1) % 3] == q) return e;
  }
  return {};
}

/// The vertex of triangle e other than p and q.
inline Index third(const mesh::Connectivity& c, mesh::ElementHandle e, Index p, Index q) {
  for (const Index w : oriented(c.simplex(e)))
    if (w != p && w != q) return w;
  return -1;
}

/// Whether vertex v has a triangle and every edge at v has two triangles.
inline bool is_interior_vertex(const mesh::Connectivity& c, Index v) {
  if (v < 0 || v >= c.num_vertices() || c.star_size(v) == 0) return false;
  for (const mesh::ElementHandle e : c.star(v))
    for (const Index w : oriented(c.simplex(e)))
      if (w != v && incident(c, v, w).size() != 2) return false;
  return true;
}

/// All edges, each once, sorted.
inline std::vector<Edge> edges(const mesh::Connectivity& c) {
  std::vector<Edge> out;
  for (const mesh::ElementHandle e : c.elements()) {
    const auto t = oriented(c.simplex(e));
    for (size_t i = 0; i < 3; ++i) out.push_back(make_edge(t[i], t[(i + 1) % 3]));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// The vertices sharing an edge with v, sorted.
inline std::vector<Index> neighbours(const mesh::Connectivity& c, Index v) {
  std::vector<Index> out;
  if (v < 0 || v >= c.num_vertices()) return out;
  for (const mesh::ElementHandle e : c.star(v))
    for (const Index w : oriented(c.simplex(e)))
      if (w != v) out.push_back(w);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// Lawson legalization (§5.2.1): flips edges that are not locally Delaunay, starting from
/// `edges` and continuing with the four outer edges of every flip, at most `max_flips` flips.
/// Returns the number made; illegal edges whose flip m refused go to `refused` when given.
/// Mesh needs is_locally_delaunay(p, q), flip(p, q), connectivity().
template <class Mesh>
long lawson_legalize(Mesh& m, std::vector<Edge> edges, long max_flips,
                     std::vector<Edge>* refused = nullptr) {
  long made = 0;
  while (!edges.empty() && made < max_flips) {
    const Edge e = edges.back();
    edges.pop_back();
    if (m.is_locally_delaunay(e.first, e.second)) continue;
    const auto& c = m.connectivity();
    const mesh::ElementHandle l = left_of(c, e.first, e.second), r = left_of(c, e.second, e.first);
    const Index o1 = third(c, l, e.first, e.second), o2 = third(c, r, e.second, e.first);
    if (!m.flip(e.first, e.second)) {
      if (refused) refused->push_back(e);
      continue;
    }
    ++made;
    for (const Edge& o : {make_edge(e.first, o1), make_edge(o1, e.second), make_edge(e.second, o2),
                          make_edge(o2, e.first)})
      edges.push_back(o);
  }
  return made;
}

/// Replaces the four triangles around v (degree 4) by the two on a diagonal of its link
/// quadrilateral, trying l0–l2 first, then l1–l3 (l in orientation order from the star's first
/// triangle); false (unchanged) when m.replace accepts neither.
template <class Mesh>
bool replace_by_diagonal(Mesh& m, Index v) {
  const mesh::Connectivity& c = m.connectivity();
  const std::vector<mesh::ElementHandle> star = c.star(v);
  std::array<Index, 4> l{};
  l[0] = starting_at(oriented(c.simplex(star[0])), v)[1];
  for (size_t i = 1; i < 4; ++i) {
    const mesh::ElementHandle e = left_of(c, v, l[i - 1]);
    if (!e.valid()) return false;
    l[i] = third(c, e, v, l[i - 1]);
  }
  for (size_t d = 0; d < 2; ++d)
    if (m.replace(star, {{l[d], l[d + 1], l[(d + 2) % 4]}, {l[d], l[(d + 2) % 4], l[(d + 3) % 4]}}))
      return true;
  return false;
}

/// Removes interior vertex v by ear flips (§5.3.1, Fig. 5.10): an ear is an edge (v, w) that
/// m.flip accepts; ears are flipped until v has degree 3, the three triangles become one, and
/// the former link polygon is legalized. Returns false (mesh unchanged when refused before the
/// first flip) when v is not interior, an edge at v is constrained, or no ear can be flipped
/// and (with `diagonal_fallback`, at degree 4) no diagonal of the link is accepted (then the
/// flips made so far stay: the mesh is valid, v keeps its triangles). The planar Triangulation
/// runs without the fallback, so the §5.2 figures stay as measured (with it, the 1000-path run
/// of delaunay_cutter2d_test gives 1 122 entries, 870 exits, 5 886 removals, 687 refused instead
/// of 1 123, 872, 5 893, 659); the Surface with it (a scalpel along a grid line needs it). Mesh
/// needs connectivity(), is_constrained(p, q), flip(p, q), replace(remove, add), legalize(edges).
template <class Mesh>
bool remove_by_ears(Mesh& m, Index v, bool diagonal_fallback) {
  const mesh::Connectivity& c = m.connectivity();
  if (!is_interior_vertex(c, v)) return false;
  for (const Index w : neighbours(c, v))
    if (m.is_constrained(v, w)) return false;
  std::vector<Edge> link;  // link polygon edges and ear diagonals, legalized at the end
  while (c.star_size(v) > 3) {
    bool flipped = false;
    for (const mesh::ElementHandle e : c.star(v)) {
      const auto t = starting_at(oriented(c.simplex(e)), v);
      const mesh::ElementHandle r = left_of(c, t[1], v);
      if (!r.valid()) continue;
      const Index prev = third(c, r, t[1], v);
      link.push_back(make_edge(prev, t[1]));
      link.push_back(make_edge(t[1], t[2]));
      if (m.flip(v, t[1])) {
        link.push_back(make_edge(prev, t[2]));  // the ear's diagonal
        flipped = true;
        break;
      }
    }
    if (!flipped) {
      // No ear: with degree 4 this is v on both diagonals of its link quadrilateral (a scalpel
      // running along a grid line makes it) — every ear has the angle π at v. The four
      // triangles become two, split along either diagonal if the mesh accepts one.
      if (diagonal_fallback && c.star_size(v) == 4 && replace_by_diagonal(m, v)) {
        m.legalize(link);
        return true;
      }
      return false;  // the ears flipped so far stay (the planar cutter's behaviour since §5.2)
    }
  }
  const std::vector<mesh::ElementHandle> star = c.star(v);
  const auto t = starting_at(oriented(c.simplex(star[0])), v);
  const std::array<Index, 3> outer{t[1], t[2], third(c, left_of(c, v, t[2]), v, t[2])};
  if (!m.replace(star, {outer})) {
    m.legalize(link);
    return false;
  }
  for (size_t i = 0; i < 3; ++i) link.push_back(make_edge(outer[i], outer[(i + 1) % 3]));
  m.legalize(link);
  return true;
}

/// The triangles around the boundary node v from its outgoing boundary edge, in orientation
/// order (empty when v has no outgoing boundary edge).
template <class Mesh>
std::vector<mesh::ElementHandle> boundary_fan(const Mesh& m, Index v) {
  const mesh::Connectivity& c = m.connectivity();
  std::vector<mesh::ElementHandle> out;
  mesh::ElementHandle start;
  for (const mesh::ElementHandle e : c.star(v)) {
    const auto t = starting_at(m.triangle(e), v);
    if (m.is_boundary_edge(v, t[1])) start = e;
  }
  for (mesh::ElementHandle e = start; e.valid() && out.size() <= c.star(v).size();) {
    out.push_back(e);
    e = left_of(c, v, starting_at(m.triangle(e), v)[2]);
  }
  return out;
}

/// Dissects the edge from the boundary node a to the interior node n (a branch of an incision
/// reaches n, Fig. 5.14): a's triangles after a–n (in orientation order from its outgoing
/// boundary edge) take a new copy of a, so n becomes a boundary node between a and the copy.
/// Returns the copy, or −1 (unchanged but for an unused vertex when m refuses) otherwise.
template <class Mesh>
Index dissect_from_boundary(Mesh& m, Index a, Index n) {
  const mesh::Connectivity& c = m.connectivity();
  if (!is_interior_vertex(c, n)) return -1;
  const mesh::ElementHandle t1 = left_of(c, a, n);
  const std::vector<mesh::ElementHandle> fa = boundary_fan(m, a);
  const auto it = std::find(fa.begin(), fa.end(), t1);
  if (!t1.valid() || it == fa.end() || it == fa.begin()) return -1;
  const Index copy = m.add_vertex(m.point(a));
  std::vector<mesh::ElementHandle> remove(it, fa.end());
  std::vector<std::array<Index, 3>> add;
  for (const mesh::ElementHandle e : remove) {
    auto t = m.triangle(e);
    for (Index& v : t)
      if (v == a) v = copy;
    add.push_back(t);
  }
  if (!m.replace(remove, add)) return -1;
  return copy;
}

/// The exit of an incision (§5.2.2, Fig. 5.7 (c)–(d)): the interior edge a–n between the active
/// node a and the boundary node n is dissected and contracted into n. The triangles at a–n go;
/// a's other triangles take n (the c_l side) or a new copy n2 of n (the c_r side), and so do
/// n's triangles on the c_r side. Returns n2, or −1 with the mesh unchanged when a–n is not an
/// interior edge, a or n is not a boundary fan, or m.replace refuses (n2 then stays unused).
/// Mesh needs connectivity(), triangle(e), left_of, is_boundary_edge, point, add_vertex, replace.
template <class Mesh>
Index dissect_and_contract(Mesh& m, Index a, Index n) {
  const mesh::Connectivity& c = m.connectivity();
  const mesh::ElementHandle t1 = left_of(c, a, n), t2 = left_of(c, n, a);
  if (!t1.valid() || !t2.valid()) return -1;
  const std::vector<mesh::ElementHandle> fa = boundary_fan(m, a), fn = boundary_fan(m, n);
  const auto ia2 = std::find(fa.begin(), fa.end(), t2), in2 = std::find(fn.begin(), fn.end(), t2);
  if (std::find(fa.begin(), fa.end(), t1) == fa.end() || ia2 == fa.end() ||
      std::find(fn.begin(), fn.end(), t1) == fn.end() || in2 == fn.end())
    return -1;
  const Index n2 = m.add_vertex(m.point(n));
  std::vector<mesh::ElementHandle> remove;
  std::vector<std::array<Index, 3>> add;
  auto substituted = [&](mesh::ElementHandle e, Index from, Index to) {
    auto t = m.triangle(e);
    for (Index& v : t)
      if (v == from) v = to;
    return t;
  };
  for (auto it = fa.begin(); it != fa.end(); ++it) {
    remove.push_back(*it);
    if (*it == t1 || *it == t2) continue;
    // Before t2 (from the outgoing edge a → c_r): the c_r side, copy n2.
    add.push_back(substituted(*it, a, it < ia2 ? n2 : n));
  }
  for (auto it = in2 + 1; it != fn.end(); ++it) {  // n's fan after t2: the c_r side
    remove.push_back(*it);
    add.push_back(substituted(*it, n, n2));
  }
  if (!m.replace(remove, add)) return -1;
  return n2;
}

}  // namespace incise::delaunay::detail
