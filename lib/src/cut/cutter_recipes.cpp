/// \file cutter_recipes.cpp
/// The collapse recipes of thesis §3.2.3 (Figs. 3.8, 3.9): needle (collapse the shortest edge),
/// spindle (split the edge opposite the large angle, collapse), sliver (split both crossing
/// edges, collapse the new short edge) and cap (split the face opposite the apex, collapse),
/// each applied as one local replace-elements operation (§7.3) that is refused when it would
/// break the manifold property (Fig. 3.10), invert an element or disconnect a node's star.

#include <incise/mesh/quality.hpp>

#include "cutter_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

namespace incise::cut {

using detail::sorted_face;

namespace {

bool has(const Tet& t, Index v) {
  return t[0] == v || t[1] == v || t[2] == v || t[3] == v;
}

bool has_duplicate(const Tet& t) {
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      if (t[static_cast<size_t>(i)] == t[static_cast<size_t>(j)]) return true;
    }
  }
  return false;
}

Tet substitute(Tet t, Index from, Index to) {
  for (auto& v : t) {
    if (v == from) v = to;
  }
  return t;
}
/// Point of segment pq closest to segment rs: parameters (s along pq, u along rs).
void closest_params(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s, double& sp,
                    double& sr) {
  const Vec3 d1 = q - p, d2 = s - r, w = p - r;
  const double a = d1.dot(d1), b = d1.dot(d2), c = d2.dot(d2), d = d1.dot(w), e = d2.dot(w);
  const double den = a * c - b * b;
  sp = den > 1e-300 ? (b * e - c * d) / den : 0.5;
  sr = den > 1e-300 ? (a * e - b * d) / den : 0.5;
  sp = std::clamp(sp, 0.0, 1.0);
  sr = std::clamp(sr, 0.0, 1.0);
}
constexpr bool same_edge_order() {
  for (int k = 0; k < 6; ++k) {
    if (mesh::kTetEdges[static_cast<size_t>(k)][0] != kTetEdge[k][0] ||
        mesh::kTetEdges[static_cast<size_t>(k)][1] != kTetEdge[k][1])
      return false;
  }
  return true;
}
static_assert(same_edge_order(), "mesh::kTetEdges and cut::kTetEdge must list edges alike");

}  // namespace

bool Cutter::apply_local_op(const std::vector<Index>& old_elements,
                            const std::vector<Tet>& new_tets, CutStepReport& r) {
  for (const Tet& t : new_tets) {
    if (has_duplicate(t)) return false;
    if (!(mesh_.reference_volume(t) > 0) || !(mesh_.deformed_volume(t) > 0)) return false;
  }
  // Surrounding elements E: stars of all involved nodes, minus the old ones.
  std::vector<Index> nodes;
  for (Index e : old_elements)
    for (Index v : mesh_.element(e)) nodes.push_back(v);
  for (const Tet& t : new_tets)
    for (Index v : t) nodes.push_back(v);
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  std::vector<Index> around;
  for (Index v : nodes)
    for (Index e : mesh_.star(v)) around.push_back(e);
  std::sort(around.begin(), around.end());
  around.erase(std::unique(around.begin(), around.end()), around.end());
  std::vector<Index> old_sorted = old_elements;
  std::sort(old_sorted.begin(), old_sorted.end());
  std::vector<Tet> after = new_tets;
  for (Index e : around) {
    if (!std::binary_search(old_sorted.begin(), old_sorted.end(), e))
      after.push_back(mesh_.element(e));
  }
  // Each oriented face at most once; each face in at most two elements (manifold, Fig. 3.10).
  std::map<std::array<Index, 3>, std::array<int, 2>> face_count;
  for (const Tet& t : after) {
    for (int j = 0; j < 4; ++j) {
      int parity = 0;
      const auto f = sorted_face(t, j, &parity);
      auto& c = face_count[f];
      if (++c[static_cast<size_t>(parity)] > 1) return false;
    }
  }
  // Star of every involved node still face-connected (dissection precondition, §7.3).
  for (Index v : nodes) {
    std::vector<size_t> in;
    for (size_t i = 0; i < after.size(); ++i) {
      if (has(after[i], v)) in.push_back(i);
    }
    if (in.size() < 2) continue;
    std::vector<Index> parent(in.size());
    std::iota(parent.begin(), parent.end(), 0);
    auto root = [&parent](Index i) {
      while (parent[static_cast<size_t>(i)] != i) i = parent[static_cast<size_t>(i)];
      return i;
    };
    size_t classes = in.size();
    for (size_t a = 0; a < in.size(); ++a) {
      for (size_t b = a + 1; b < in.size(); ++b) {
        int shared = 0;
        for (Index w : after[in[a]]) shared += has(after[in[b]], w) ? 1 : 0;
        if (shared == 3) {
          const Index ra = root(static_cast<Index>(a)), rb = root(static_cast<Index>(b));
          if (ra != rb) {
            parent[static_cast<size_t>(std::max(ra, rb))] = std::min(ra, rb);
            --classes;
          }
        }
      }
    }
    if (classes != 1) return false;
  }
  // Apply through replace-elements (§7.3).
  for (Index e : old_sorted) r.changed_elements.push_back(e);
  const std::vector<Index> added = mesh_.replace(old_sorted, new_tets);
  for (Index e : added) r.changed_elements.push_back(e);
  // Representatives for the component check: a removed element is replaced by a new one in
  // the same place (or by a surviving neighbour when the operation only removed elements).
  Index stand_in = added.empty() ? -1 : added[0];
  for (Index e : around) {
    if (stand_in < 0 && mesh_.alive(e)) stand_in = e;
  }
  for (Index e : old_sorted) {
    if (!mesh_.alive(e) && stand_in >= 0) replaced_[e] = stand_in;
  }
  for (Index v : nodes) {
    if (mesh_.unused(v)) r.removed_nodes.push_back(v);
  }
  return true;
}

bool Cutter::try_recipe(Index e, CutStepReport& r) {
  const Tet t = mesh_.element(e);
  std::array<Vec3, 4> X{mesh_.reference(t[0]), mesh_.reference(t[1]), mesh_.reference(t[2]),
                        mesh_.reference(t[3])};
  // §3.2.3 classification by the mesh module (mesh/quality.hpp; its kTetEdges order is
  // kTetEdge's). try_recipe is only called for degenerate elements, so every element is
  // classified here (infinite aspect-ratio threshold; an inverted element is degenerate too).
  const mesh::ShapeInfo info = mesh::classify_tetrahedron(
      X[0], X[1], X[2], X[3],
      {std::numeric_limits<double>::infinity(), options_.large_dihedral_angle});
  const std::array<double, 6> angle = mesh::dihedral_angles(X[0], X[1], X[2], X[3]);
  std::array<int, 6> large{};  // large-angle edges by decreasing angle
  int num_large = 0;
  for (int k = 0; k < 6; ++k) {
    if (info.large_angle_edge[static_cast<size_t>(k)]) large[static_cast<size_t>(num_large++)] = k;
  }
  for (int i = 1; i < num_large; ++i) {  // insertion sort by decreasing angle (≤ 6 entries)
    for (int j = i; j > 0 && angle[static_cast<size_t>(large[static_cast<size_t>(j)])] >
                                 angle[static_cast<size_t>(large[static_cast<size_t>(j - 1)])];
         --j)
      std::swap(large[static_cast<size_t>(j)], large[static_cast<size_t>(j - 1)]);
  }
  int shortest_edge = 0;
  for (int k = 1; k < 6; ++k) {
    if ((X[static_cast<size_t>(kTetEdge[k][0])] - X[static_cast<size_t>(kTetEdge[k][1])]).norm() <
        (X[static_cast<size_t>(kTetEdge[shortest_edge][0])] -
         X[static_cast<size_t>(kTetEdge[shortest_edge][1])])
            .norm())
      shortest_edge = k;
  }

  auto edge_star = [&](Index a, Index b) {
    std::vector<Index> out;
    for (Index f : mesh_.star(a)) {
      if (has(mesh_.element(f), b)) out.push_back(f);
    }
    return out;
  };
  // Collapse u into v: u disappears, elements containing both vanish.
  auto collapse = [&](Index u, Index v) {
    if (mesh_.fixed(u) && !mesh_.fixed(v)) return false;
    std::vector<Index> old = mesh_.star(u);
    std::vector<Tet> nt;
    for (Index f : old) {
      if (!has(mesh_.element(f), v)) nt.push_back(substitute(mesh_.element(f), u, v));
    }
    return apply_local_op(old, nt, r);
  };
  auto needle = [&]() {
    const Index a = t[static_cast<size_t>(kTetEdge[shortest_edge][0])];
    const Index b = t[static_cast<size_t>(kTetEdge[shortest_edge][1])];
    // Prefer keeping boundary nodes (a flat surface keeps its shape).
    const bool ab = mesh_.on_boundary(a), bb = mesh_.on_boundary(b);
    if (ab && !bb) return collapse(b, a) || collapse(a, b);
    return collapse(a, b) || collapse(b, a);
  };
  // The large angle lies at edge k; a spindle's fourth node lies near the *opposite* edge ab
  // (thesis §3.2.3: "the edge opposite the large angle is split"). Split ab at the node p of
  // edge k nearest to line ab and collapse the split node into p.
  auto spindle = [&](int k) {
    Index a = -1, b = -1;
    for (int j = 0; j < 4; ++j) {
      if (j == kTetEdge[k][0] || j == kTetEdge[k][1]) continue;
      (a < 0 ? a : b) = t[static_cast<size_t>(j)];
    }
    const Index others[2] = {t[static_cast<size_t>(kTetEdge[k][0])],
                             t[static_cast<size_t>(kTetEdge[k][1])]};
    const Vec3 d = (mesh_.reference(b) - mesh_.reference(a)).normalized();
    auto dist = [&](Index v) {
      const Vec3 w = mesh_.reference(v) - mesh_.reference(a);
      return (w - w.dot(d) * d).norm();
    };
    const Index p = dist(others[0]) <= dist(others[1]) ? others[0] : others[1];
    std::vector<Index> old = edge_star(a, b);
    std::vector<Tet> nt;
    for (Index f : old) {
      for (Index q : {a, b}) {
        const Tet u = substitute(mesh_.element(f), q, p);
        if (!has_duplicate(u)) nt.push_back(u);
      }
    }
    return apply_local_op(old, nt, r);
  };
  // Split both crossing edges, collapse the short edge between the new nodes (sliver).
  auto sliver = [&](int k1, int k2) {
    const Index a = t[static_cast<size_t>(kTetEdge[k1][0])],
                b = t[static_cast<size_t>(kTetEdge[k1][1])];
    const Index c = t[static_cast<size_t>(kTetEdge[k2][0])],
                d = t[static_cast<size_t>(kTetEdge[k2][1])];
    if (a == c || a == d || b == c || b == d) return false;
    double s1 = 0.5, s2 = 0.5;
    closest_params(mesh_.reference(a), mesh_.reference(b), mesh_.reference(c), mesh_.reference(d),
                   s1, s2);
    s1 = std::clamp(s1, 0.05, 0.95);
    s2 = std::clamp(s2, 0.05, 0.95);
    const Vec3 Xm = 0.5 * ((1 - s1) * mesh_.reference(a) + s1 * mesh_.reference(b) +
                           (1 - s2) * mesh_.reference(c) + s2 * mesh_.reference(d));
    const Vec3 xm = 0.5 * ((1 - s1) * mesh_.deformed(a) + s1 * mesh_.deformed(b) +
                           (1 - s2) * mesh_.deformed(c) + s2 * mesh_.deformed(d));
    const bool fix = (mesh_.fixed(a) && mesh_.fixed(b)) || (mesh_.fixed(c) && mesh_.fixed(d));
    std::vector<Index> old = edge_star(a, b);
    for (Index f : edge_star(c, d)) old.push_back(f);
    std::sort(old.begin(), old.end());
    old.erase(std::unique(old.begin(), old.end()), old.end());
    const Index m = mesh_.add_node(Xm, xm, fix, mesh_.num_nodes());
    std::vector<Tet> nt;
    for (Index f : old) {
      std::vector<Tet> pieces{mesh_.element(f)};
      if (has(pieces[0], a) && has(pieces[0], b))
        pieces = {substitute(pieces[0], a, m), substitute(pieces[0], b, m)};
      std::vector<Tet> out;
      for (const Tet& q : pieces) {
        if (has(q, c) && has(q, d)) {
          out.push_back(substitute(q, c, m));
          out.push_back(substitute(q, d, m));
        } else {
          out.push_back(q);
        }
      }
      for (const Tet& q : out) {
        if (!has_duplicate(q)) nt.push_back(q);
      }
    }
    if (apply_local_op(old, nt, r)) {
      r.new_nodes.push_back(m);
      return true;
    }
    r.removed_nodes.push_back(m);  // created for the attempt, left unused
    return false;
  };
  // Split the face opposite the apex, collapse the new node into the apex (cap).
  auto cap = [&](int apex) {
    const Index d = t[static_cast<size_t>(apex)];
    Index f3[3];
    for (int k = 0; k < 3; ++k) f3[k] = t[static_cast<size_t>(mesh::kTetFace[apex][k])];
    std::vector<Index> old;
    for (Index f : mesh_.star(f3[0])) {
      if (has(mesh_.element(f), f3[1]) && has(mesh_.element(f), f3[2])) old.push_back(f);
    }
    std::vector<Tet> nt;
    for (Index f : old) {
      for (Index q : f3) {
        const Tet u = substitute(mesh_.element(f), q, d);
        if (!has_duplicate(u)) nt.push_back(u);
      }
    }
    return apply_local_op(old, nt, r);
  };

  bool ok = false;
  switch (info.shape) {
    case mesh::ShapeClass::kGood:
    case mesh::ShapeClass::kNeedle: break;
    case mesh::ShapeClass::kSpindle: ok = spindle(large[0]); break;
    case mesh::ShapeClass::kSliver: {
      const int k1 = large[0], k2 = large[1];
      ok = sliver(k1, k2) || spindle(k1) || spindle(k2);
      break;
    }
    case mesh::ShapeClass::kCap:
    case mesh::ShapeClass::kFlat: {  // ≥ 3 large angles: the three largest define the cap
      // Apex: the node near the opposite face's interior, common to the three largest-angle
      // edges (the large angles of a cap are at the edges from the apex; Fig. 3.8).
      int apex = -1;
      for (int j = 0; j < 4 && apex < 0; ++j) {
        bool on_all = true;
        for (int q = 0; q < 3; ++q)
          on_all = on_all && (kTetEdge[large[static_cast<size_t>(q)]][0] == j ||
                              kTetEdge[large[static_cast<size_t>(q)]][1] == j);
        if (on_all) apex = j;
      }
      ok = (apex >= 0 && cap(apex)) || spindle(large[0]);
      break;
    }
  }
  if (!ok) ok = needle();
  if (ok) ++r.collapses;
  return ok;
}

}  // namespace incise::cut
