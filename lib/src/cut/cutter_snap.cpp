/// \file cutter_snap.cpp
/// Node snapping (thesis §3.2.2, Fig. 3.6): interior nodes of the selected faces projected onto
/// the sweep plane, boundary nodes within their incident boundary faces (closest candidate),
/// mapped back to the reference configuration; snaps that would invert an element are refused
/// (the improvement §3.4 suggests). Also the re-marking of edges at snapped nodes
/// (docs/cutting.md, "lag").

#include <incise/cut/predicates.hpp>

#include "cutter_internal.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace incise::cut {

namespace {

/// Barycentric slack for "w lies in the face / element" tests (dimensionless): points on a
/// shared face or edge must be found in at least one of the incident simplices.
constexpr double kInsideTol = 1e-9;
/// A node within this fraction of the sweep triangle's longest side from the sweep plane is
/// already on the sweep and is not moved (covers nodes snapped by an earlier, coplanar step).
constexpr double kOnSweepRelEps = 1e-12;

}  // namespace

void Cutter::remark_snapped(const std::vector<Index>& snapped, std::vector<Index>& affected) {
  std::vector<Index> sorted = snapped;
  std::sort(sorted.begin(), sorted.end());
  for (Index v : sorted) {
    for (Index e : mesh_.star(v)) {
      affected.push_back(e);
      const Tet& t = mesh_.element(e);
      for (Index z : t) {
        if (z == v || std::binary_search(sorted.begin(), sorted.end(), z)) continue;
        marked_[edge_key(v, z)] = mesh_.origin(v);
      }
    }
  }
}

bool Cutter::snap_node(Index v, const Vec3& o, const Vec3& n, double scale, CutStepReport& r) {
  const Vec3 x = mesh_.deformed(v);
  if (mesh_.fixed(v)) {
    ++r.snaps_fixed;  // fixed nodes are never moved
    return false;
  }
  if (std::abs(n.dot(x - o)) <= kOnSweepRelEps * scale) {
    ++r.nodes_on_sweep;  // already on the sweep plane (e.g. snapped by an earlier step)
    return true;
  }
  Vec3 w = x;
  bool found = false;
  if (mesh_.on_boundary(v)) {
    // Fig. 3.6: project within each incident boundary face onto plane(Δ) ∩ plane(f).
    double best = std::numeric_limits<double>::infinity();
    for (Index e : mesh_.star(v)) {
      const Tet& t = mesh_.element(e);
      const int lv = mesh_.local_index(e, v);
      for (int j = 0; j < 4; ++j) {
        if (j == lv || mesh_.neighbor(e, j) >= 0) continue;
        const Vec3 a = mesh_.deformed(t[static_cast<size_t>(mesh::kTetFace[j][0])]);
        const Vec3 b = mesh_.deformed(t[static_cast<size_t>(mesh::kTetFace[j][1])]);
        const Vec3 c = mesh_.deformed(t[static_cast<size_t>(mesh::kTetFace[j][2])]);
        Vec3 nf = (b - a).cross(c - a);
        const double area2 = nf.norm();
        if (!(area2 > 0)) continue;
        nf /= area2;
        const double nn = n.dot(nf);
        const double det = 1.0 - nn * nn;
        if (det < 1e-12) continue;  // face parallel to the sweep: no intersection line
        const double r1 = n.dot(o - x), r2 = nf.dot(a - x);
        const double alpha = (r1 - nn * r2) / det, beta = (r2 - nn * r1) / det;
        const Vec3 y = x + alpha * n + beta * nf;
        // barycentric in face abc
        const double l0 = (b - y).cross(c - y).dot(nf) / area2;
        const double l1 = (c - y).cross(a - y).dot(nf) / area2;
        const double l2 = 1.0 - l0 - l1;
        if (l0 < -kInsideTol || l1 < -kInsideTol || l2 < -kInsideTol) continue;
        const double d = (y - x).norm();
        if (d < best) {
          best = d;
          w = y;
          found = true;
        }
      }
    }
  } else {
    w = x - n.dot(x - o) * n;
    found = true;
  }
  if (!found) {
    ++r.snaps_failed;
    ++r.snaps_no_projection;
    return false;
  }
  // Map w back to the reference configuration through the incident element containing it.
  Vec3 W;
  bool located = false;
  for (Index e : mesh_.star(v)) {
    const Tet& t = mesh_.element(e);
    const Vec3 p[4] = {mesh_.deformed(t[0]), mesh_.deformed(t[1]), mesh_.deformed(t[2]),
                       mesh_.deformed(t[3])};
    double l[4];
    if (!barycentric(w, p, l)) continue;
    if (l[0] < -kInsideTol || l[1] < -kInsideTol || l[2] < -kInsideTol || l[3] < -kInsideTol)
      continue;
    W = Vec3::Zero();
    for (int k = 0; k < 4; ++k) W += l[k] * mesh_.reference(t[static_cast<size_t>(k)]);
    located = true;
    break;
  }
  if (!located) {
    ++r.snaps_failed;
    ++r.snaps_outside_star;
    return false;
  }
  const Vec3 X_old = mesh_.reference(v);
  mesh_.set_position(v, W, w);
  if (options_.refuse_inverting_snaps) {
    for (Index e : mesh_.star(v)) {
      const Tet& t = mesh_.element(e);
      if (!(mesh_.reference_volume(t) > 0) || !(mesh_.deformed_volume(t) > 0)) {
        mesh_.set_position(v, X_old, x);
        ++r.snaps_refused;
        return false;
      }
    }
  }
  ++r.nodes_snapped;
  r.moved_nodes.push_back(v);
  return true;
}

void Cutter::snap(const Vec3 (&tri)[3], const std::vector<std::pair<Index, int>>& faces,
                  CutStepReport& r) {
  const Vec3 n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized();
  std::vector<Index> nodes;
  for (const auto& [e, j] : faces)
    for (int k = 0; k < 3; ++k)
      nodes.push_back(mesh_.element(e)[static_cast<size_t>(mesh::kTetFace[j][k])]);
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  const double scale =
      std::max({(tri[1] - tri[0]).norm(), (tri[2] - tri[1]).norm(), (tri[0] - tri[2]).norm()});
  for (Index v : nodes) (void)snap_node(v, tri[0], n, scale, r);
}

}  // namespace incise::cut
