// Branching of surface incisions (thesis §5.3.2, Figs. 5.14 and 5.18; the third entry case of
// Fig. 5.12): the SurfaceCutter members that turn one incision into a family of any number of
// branches, each with its own active node (surface_cutter.hpp).
#include <incise/delaunay/surface_cutter.hpp>

#include "topology.hpp"

#include <algorithm>
#include <array>
#include <vector>

namespace incise::delaunay {

using detail::starting_at;
using mesh::ElementHandle;

std::vector<SurfaceCutter::BranchPoint> SurfaceCutter::branch_points(
    const std::vector<Vec3>& hits) const {
  // Every intersection (nearest to the active node first) strictly inside an active triangle
  // (barycentrics > 10⁻³, so the new node makes no sliver) whose nodes are not next to another
  // active node, one per triangle. The nearest must be one of them (else the incision follows
  // it, no branch); fewer than two: empty. Intersections left out are not followed (counted in
  // extra_intersections like any intersection beyond the first).
  std::vector<BranchPoint> out;
  for (size_t k = 0; k < hits.size(); ++k) {
    ElementHandle tri;
    for (const ElementHandle e : mesh_.connectivity().star(active_)) {
      const auto t = mesh_.triangle(e);
      const Vec3 p = mesh_.point(t[0]), u = mesh_.point(t[1]) - p, w = mesh_.point(t[2]) - p;
      const Vec3 n = u.cross(w), d = hits[k] - p;
      const double s1 = d.cross(w).dot(n) / n.squaredNorm(),
                   s2 = u.cross(d).dot(n) / n.squaredNorm();
      if (s1 > 1e-3 && s2 > 1e-3 && s1 + s2 < 1 - 1e-3) tri = e;
    }
    bool ok = tri.valid();
    for (const BranchPoint& b : out) ok = ok && b.triangle != tri;
    if (ok)
      for (const Index v : mesh_.triangle(tri))
        for (const Index w : mesh_.neighbours(v))
          ok = ok && (w == active_ || !mesh_.is_active_node(w));
    if (ok)
      out.push_back({tri, hits[k]});
    else if (k == 0)
      return {};
  }
  if (out.size() < 2) return {};
  return out;
}

std::vector<Index> SurfaceCutter::branch_nodes(const std::vector<BranchPoint>& at,
                                               SurfaceMoveReport& r) {
  // A node inside each triangle of `at`, in order; one that cannot be made is left out
  // (counted refused), and without the first none are kept as branch nodes (the ones made stay
  // ordinary interior nodes).
  std::vector<Index> nodes;
  for (const BranchPoint& b : at) {
    const Index n = mesh_.split_triangle(b.triangle, b.point);
    if (n < 0) {
      ++r.refused;
      if (nodes.empty()) return {};
      continue;
    }
    nodes.push_back(n);
  }
  return nodes;
}

void SurfaceCutter::dissect_branches(const std::vector<Index>& nodes, std::vector<Index>& holders,
                                     std::vector<Index>& tips, SurfaceMoveReport& r) {
  // The edge from the active node to each node of `nodes` dissected in turn
  // (detail::dissect_from_boundary): the copy of the active node (one of `holders`) that has the
  // edge splits once more, its fan from that edge on taking a new copy. Each dissected node is a
  // slit tip (appended to `tips`); one that cannot be dissected stays an ordinary interior node
  // (counted refused).
  for (const Index n : nodes) {
    Index from = -1;
    for (const Index h : holders)
      if (!mesh_.incident(h, n).empty()) from = h;
    const Index copy = from < 0 ? -1 : detail::dissect_from_boundary(mesh_, from, n);
    if (copy < 0) {
      ++r.refused;
      continue;
    }
    holders.push_back(copy);
    tips.push_back(n);
  }
}

void SurfaceCutter::spawn(const std::vector<Index>& tips, SurfaceMoveReport& r) {
  // New incisions at the slit tips `tips` (boundary nodes), one family (never annihilated
  // with each other), cut from branch_tau_ on; the incision they branch from ends.
  const int family = next_family_++;
  for (const Index n : tips) {
    Incision i{n,     CutPhase::kCutting, mesh_.point(n), IncisionTrack<Vec3>{}, false,
               false, branch_tau_,        family};
    for (const ElementHandle e : mesh_.connectivity().star(n)) {
      const auto t = starting_at(mesh_.triangle(e), n);
      if (mesh_.is_boundary_edge(n, t[1])) i.track.right = t[1];
      if (mesh_.is_boundary_edge(t[2], n)) i.track.left = t[2];
    }
    i.track.sides = {{i.track.left}, {i.track.right}};
    i.track.path = {mesh_.point(n)};
    spawned_.push_back(i);
  }
  r.branched = true;
  r.branch_ways = std::max(r.branch_ways, static_cast<int>(tips.size()));
  phase_ = CutPhase::kOutside;
  active_ = -1;
}

bool SurfaceCutter::branch(const std::vector<Vec3>& hits, SurfaceMoveReport& r) {
  // Figs. 5.14 and 5.18: the scalpel meets the active triangles k ≥ 2 times (a fold, or a
  // pleated star): a node goes in at every intersection branch_points takes, the edges from the
  // active node to them are dissected one after the other, and k incisions with these active
  // nodes — one family — replace the old one. Refused before the mesh changes when the nearest
  // intersection is not taken or fewer than two are; when the nearest node cannot be dissected,
  // refused (the new nodes stay ordinary interior nodes and the incision goes on); a later one
  // that cannot be dissected is left out (with only the nearest made the incision goes on from
  // there alone).
  const std::vector<BranchPoint> at = branch_points(hits);
  if (at.empty()) return false;
  const std::vector<Index> nodes = branch_nodes(at, r);
  if (nodes.size() < 2) return false;  // refused (counted); made nodes stay ordinary
  std::vector<Index> holders{active_}, tips;
  dissect_branches({nodes.front()}, holders, tips, r);
  if (tips.empty()) return false;  // refused (counted); the incision goes on
  dissect_branches(std::vector<Index>(nodes.begin() + 1, nodes.end()), holders, tips, r);
  spawn(tips, r);
  return true;
}

bool SurfaceCutter::edge_branch(const std::vector<Vec3>& hits, SurfaceMoveReport& r) {
  // Fig. 5.12, third case: the active node a sits on the ridge the scalpel hit, an interior
  // node; once the scalpel meets a's triangles on both sides of it, nodes n1, n2, … go in at the
  // intersections branch_points takes and the path n1–a–n2 is dissected in one replace: a's
  // triangles from a→n2 round to a→n1 (orientation order) take a copy a', so a slit n1–a–n2 /
  // n1–a'–n2 opens with n1 and n2 at its ends ("the cut will branch into two incisions"); any
  // further node is dissected from a or a' as in branch(). False with the mesh unchanged (but
  // for unused or ordinary new nodes, counted refused) when the slit cannot be made.
  const std::vector<BranchPoint> at = branch_points(hits);
  if (at.empty()) return false;
  const std::vector<Index> nodes = branch_nodes(at, r);
  if (nodes.size() < 2) return false;  // refused (counted); made nodes stay ordinary
  const Index n1 = nodes[0], n2 = nodes[1];
  const mesh::Connectivity& c = mesh_.connectivity();
  // a's fan from the triangle left of a→n2 round to the one before a→n1.
  std::vector<ElementHandle> part;
  const ElementHandle first = detail::left_of(c, active_, n2);
  for (ElementHandle e = first; e.valid() && part.size() <= c.star(active_).size();) {
    const auto t = starting_at(mesh_.triangle(e), active_);
    part.push_back(e);
    if (t[2] == n1) break;
    e = detail::left_of(c, active_, t[2]);
    if (e == first) break;  // round without meeting n1 (checked below)
  }
  if (part.empty() || part.size() >= c.star(active_).size() ||
      starting_at(mesh_.triangle(part.back()), active_)[2] != n1) {
    ++r.refused;
    return false;
  }
  const Index copy = mesh_.add_vertex(mesh_.point(active_));
  std::vector<std::array<Index, 3>> add;
  for (const ElementHandle e : part) {
    auto t = mesh_.triangle(e);
    for (Index& v : t)
      if (v == active_) v = copy;
    add.push_back(t);
  }
  if (!mesh_.replace(part, add)) {
    ++r.refused;  // copy stays unused; the new nodes stay ordinary interior nodes
    return false;
  }
  std::vector<Index> holders{active_, copy}, tips{n1, n2};
  dissect_branches(std::vector<Index>(nodes.begin() + 2, nodes.end()), holders, tips, r);
  spawn(tips, r);
  return true;
}

bool SurfaceCutter::is_sibling(Index v) const {
  // v is the active node of a live incision of the working incision's family (the branches of
  // one branching, however many: their tips start next to each other, and they move apart).
  if (family_ < 0) return false;
  for (const std::vector<Incision>* list : {&incisions_, &spawned_})
    for (const Incision& i : *list)
      if (i.active == v && i.phase != CutPhase::kOutside && i.family == family_) return true;
  return false;
}

}  // namespace incise::delaunay
