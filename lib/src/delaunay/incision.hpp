#pragma once
// The incision steps shared by the planar Cutter2D (§5.2.2) and the SurfaceCutter (§5.3.1):
// the topology and bookkeeping of the entry fix-up (Fig. 5.6), the split behind the active node
// (Fig. 5.5), the exit (Fig. 5.7), node snapping on boundary edges and star legalization. The
// geometry is the mesh's (Triangulation: exact planar predicates; Surface: unfolded criterion
// and fold guards), reached through its replace(), legalize(), split_boundary_edge() and
// point(); positions are Vec2 or Vec3.

#include <incise/delaunay/incision_track.hpp>
#include "topology.hpp"

#include <cstddef>
#include <vector>

namespace incise::delaunay::detail {

/// Legalizes the edges of v's star; returns the number of flips.
template <class Mesh>
long legalize_star(Mesh& m, Index v) {
  std::vector<Edge> edges;
  for (const mesh::ElementHandle e : m.connectivity().star(v)) {
    const auto t = m.triangle(e);
    for (size_t i = 0; i < 3; ++i) edges.push_back(make_edge(t[i], t[(i + 1) % 3]));
  }
  return m.legalize(edges);
}

/// An end of the boundary edge {p, q} within `snap` of x, else a new node at x on it (never a
/// new node that close to an existing one: it would make a sliver); −1 when the split is
/// refused.
template <class Mesh, class Vec>
Index boundary_node_at(Mesh& m, Index p, Index q, const Vec& x, double snap) {
  if ((m.point(p) - x).norm() < snap) return p;
  if ((m.point(q) - x).norm() < snap) return q;
  return m.split_boundary_edge(p, q, x);
}

/// Interior neighbours v of a with close(v) true are removed by ear flips (Fig. 5.10) until
/// none is left or none can be removed; `keep(v)` exempts nodes. Returns the number removed.
template <class Mesh, class Close, class Keep>
int remove_close_nodes(Mesh& m, Index a, Close close, Keep keep) {
  int removed = 0;
  for (bool again = true; again;) {
    again = false;
    for (const Index v : m.neighbours(a)) {
      if (keep(v) || !m.is_interior_vertex(v) || !close(v)) continue;
      if (m.remove_vertex(v)) {
        ++removed;
        again = true;
        break;
      }
    }
  }
  return removed;
}

/// Fig. 5.6: fills the dent bl → a → br of the active node a with (bl, cl, a) and (a, cr, br),
/// cl and cr at `entry` moved δ towards bl and br, and starts the incision in `track`. False
/// (cl, cr stay unused, track unchanged) when a has no two distinct boundary neighbours or m
/// refuses.
template <class Mesh, class Vec>
bool fix_up(IncisionTrack<Vec>& track, Mesh& m, Index a, const Vec& entry, double delta) {
  Index bl = -1, br = -1;
  for (const mesh::ElementHandle e : m.connectivity().star(a)) {
    const auto t = starting_at(m.triangle(e), a);
    if (m.is_boundary_edge(a, t[1])) br = t[1];
    if (m.is_boundary_edge(t[2], a)) bl = t[2];
  }
  if (bl < 0 || br < 0 || bl == br) return false;
  auto toward = [&](Index v) { return Vec(entry + delta * (m.point(v) - entry).normalized()); };
  const Index cl = m.add_vertex(toward(bl)), cr = m.add_vertex(toward(br));
  if (!m.replace({}, {{bl, cl, a}, {a, cr, br}})) return false;
  track.left = cl;
  track.right = cr;
  track.sides.push_back({cl});
  track.sides.push_back({cr});
  track.path = {entry, m.point(a)};
  for (const Index v : {cl, cr, a}) legalize_star(m, v);
  return true;
}

/// The triangles at the cut edges, tl = (c_l, a, o_l) and tr = (a, c_r, o_r); false when either
/// is missing or o_l = o_r (nothing to split).
template <class Mesh, class Vec>
bool cut_edge_triangles(const IncisionTrack<Vec>& track, const Mesh& m, Index a,
                        mesh::ElementHandle& tl, mesh::ElementHandle& tr, Index& ol, Index& orr) {
  tl = m.left_of(track.left, a);
  tr = m.left_of(a, track.right);
  if (!tl.valid() || !tr.valid()) return false;
  ol = starting_at(m.triangle(tl), track.left)[2];
  orr = starting_at(m.triangle(tr), a)[2];
  return ol != orr;
}

/// Fig. 5.5: the cut-edge triangles tl, tr become four with a new node pair at x (on path
/// segment `seg`), moved δ towards o_l and o_r; the path restarts at x. False (m unchanged but
/// for two unused vertices) when m refuses.
template <class Mesh, class Vec>
bool split(IncisionTrack<Vec>& track, Mesh& m, Index a, mesh::ElementHandle tl,
           mesh::ElementHandle tr, Index ol, Index orr, const Vec& x, size_t seg, double delta) {
  const Vec xl = x + delta * (m.point(ol) - x).normalized(),
            xr = x + delta * (m.point(orr) - x).normalized();
  const Index nl = m.add_vertex(xl), nr = m.add_vertex(xr);
  if (!m.replace({tl, tr},
                 {{track.left, nl, ol}, {nl, a, ol}, {a, nr, orr}, {nr, track.right, orr}}))
    return false;
  track.left = nl;
  track.right = nr;
  track.sides[track.sides.size() - 2].push_back(nl);
  track.sides.back().push_back(nr);
  track.path.erase(track.path.begin(), track.path.begin() + static_cast<std::ptrdiff_t>(seg) + 1);
  track.path.insert(track.path.begin(), x);
  legalize_star(m, nl);
  legalize_star(m, nr);
  return true;
}

/// Fig. 5.7 (c)–(d): the edge from the active node a to the boundary node n is dissected and
/// contracted (dissect_and_contract); the exit pair ends the sides, and `forbidden` becomes the
/// boundary edges at the pair (closed for entry for a while). False (unchanged) when refused.
template <class Mesh, class Vec>
bool exit(IncisionTrack<Vec>& track, Mesh& m, Index a, Index n, std::vector<Edge>& forbidden) {
  const Index n2 = dissect_and_contract(m, a, n);
  if (n2 < 0) return false;
  if (track.sides.size() >= 2) {
    track.sides[track.sides.size() - 2].push_back(n);
    track.sides.back().push_back(n2);
  }
  forbidden.clear();
  for (const Index v : {n, n2})
    for (const Index w : m.neighbours(v))
      if (m.is_boundary_edge(v, w)) forbidden.push_back(make_edge(v, w));
  for (const Index v : {n, n2}) legalize_star(m, v);
  return true;
}

}  // namespace incise::delaunay::detail
