#include <incise/delaunay/predicates.hpp>
#include <incise/delaunay/triangulation.hpp>
#include "topology.hpp"

#include <incise/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace incise::delaunay {
namespace {

using mesh::ElementHandle;
using mesh::Simplex;

using detail::oriented;

double angle_at(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 u = a - p, w = b - p;
  return std::atan2(std::abs(u.x() * w.y() - u.y() * w.x()), u.dot(w));
}

}  // namespace

Triangulation::Triangulation(const mesh::MeshData& mesh) : conn_(2), points_(mesh.points) {
  INCISE_CHECK_PARAM(mesh.dimension == 2, "Triangulation: the mesh must be 2D (triangles)");
  for (Index v = 0; v < mesh.num_points(); ++v)
    INCISE_CHECK_PARAM(
        mesh.points.col(v).allFinite() && mesh.points.col(v).cwiseAbs().maxCoeff() <= 1e60,
        "Triangulation: point " + std::to_string(v) +
            " is not finite or beyond 1e60 m (the predicates' exact range)");
  points_.row(2).setZero();
  for (Index c = 0; c < mesh.num_cells(); ++c) {
    const auto t = mesh.cells.col(c);
    for (int i = 0; i < 3; ++i)
      INCISE_CHECK_PARAM(t(i) >= 0 && t(i) < mesh.num_points(),
                         "Triangulation: triangle " + std::to_string(c) + " has vertex " +
                             std::to_string(t(i)) + " outside [0, " +
                             std::to_string(mesh.num_points()) + ")");
    INCISE_CHECK_PARAM(
        orient2d(points_.col(t(0)).head<2>(), points_.col(t(1)).head<2>(),
                 points_.col(t(2)).head<2>()) > 0,
        "Triangulation: triangle " + std::to_string(c) + " is not strictly counter-clockwise");
  }
  conn_ = mesh::Connectivity::from_mesh_data(mesh);
}

std::vector<ElementHandle> Triangulation::incident(Index p, Index q) const {
  return detail::incident(conn_, p, q);
}

bool Triangulation::is_interior_vertex(Index v) const {
  return detail::is_interior_vertex(conn_, v);
}

void Triangulation::set_constrained(Index p, Index q, bool constrained) {
  if (constrained)
    constrained_.insert(make_edge(p, q));
  else
    constrained_.erase(make_edge(p, q));
}

ElementHandle Triangulation::left_of(Index p, Index q) const {
  return detail::left_of(conn_, p, q);
}

Index Triangulation::third(ElementHandle e, Index p, Index q) const {
  return detail::third(conn_, e, p, q);
}

bool Triangulation::is_locally_delaunay(Index p, Index q) const {
  if (is_constrained(p, q)) return true;
  const ElementHandle l = left_of(p, q), r = left_of(q, p);
  if (!l.valid() || !r.valid()) return true;
  const Index c = third(l, p, q), d = third(r, q, p);
  return incircle(point(p), point(q), point(c), point(d)) <= 0;
}

bool Triangulation::flip(Index p, Index q) {
  if (is_constrained(p, q)) return false;
  const ElementHandle l = left_of(p, q), r = left_of(q, p);
  if (!l.valid() || !r.valid()) return false;
  const Index c = third(l, p, q), d = third(r, q, p);
  // New triangles (c, d, q) and (d, c, p): strictly counter-clockwise iff the quadrilateral
  // p d q c is strictly convex at p and q.
  if (orient2d(point(c), point(d), point(q)) <= 0 || orient2d(point(d), point(c), point(p)) <= 0)
    return false;
  if (!incident(c, d).empty()) return false;  // {c, d} already an edge (non-planar link)
  conn_.replace_elements({l, r}, {Simplex({c, d, q}), Simplex({d, c, p})});
  ++flips_;
  return true;
}

long Triangulation::legalize(std::vector<Edge> edges) {
  // Terminates without a cap (file comment): the cap is never reached.
  return detail::lawson_legalize(*this, std::move(edges), std::numeric_limits<long>::max());
}

std::vector<Edge> Triangulation::edges() const {
  return detail::edges(conn_);
}

bool Triangulation::remove_vertex(Index v) {
  return detail::remove_by_ears(*this, v, /*diagonal_fallback=*/false);
}

std::array<Index, 3> Triangulation::triangle(ElementHandle e) const {
  return oriented(conn_.simplex(e));
}

std::vector<Index> Triangulation::neighbours(Index v) const {
  return detail::neighbours(conn_, v);
}

Index Triangulation::add_vertex(const Vec2& x) {
  INCISE_CHECK_PARAM(x.allFinite(), "Triangulation::add_vertex: non-finite position");
  const Index v = conn_.add_vertex();
  // Capacity doubles (a resize per vertex would copy all positions: O(n) per insertion).
  if (points_.cols() <= v)
    points_.conservativeResize(Eigen::NoChange, std::max<Eigen::Index>(v + 1, 2 * points_.cols()));
  points_.col(v) << x.x(), x.y(), 0.0;
  return v;
}

bool Triangulation::move_vertex(Index v, const Vec2& x) {
  INCISE_CHECK_PARAM(x.allFinite(), "Triangulation::move_vertex: non-finite position");
  for (const ElementHandle e : conn_.star(v)) {
    std::array<Vec2, 3> p;
    const auto t = oriented(conn_.simplex(e));
    for (int i = 0; i < 3; ++i)
      p[static_cast<size_t>(i)] =
          t[static_cast<size_t>(i)] == v ? x : point(t[static_cast<size_t>(i)]);
    if (orient2d(p[0], p[1], p[2]) <= 0) return false;
  }
  points_(0, v) = x.x();
  points_(1, v) = x.y();
  return true;
}

bool Triangulation::replace(const std::vector<ElementHandle>& remove,
                            const std::vector<std::array<Index, 3>>& add) {
  std::vector<Simplex> simplices;
  for (const auto& t : add) {
    for (const Index v : t)
      if (v < 0 || v >= points_.cols()) return false;
    if (orient2d(point(t[0]), point(t[1]), point(t[2])) <= 0) return false;
    simplices.emplace_back(Simplex({t[0], t[1], t[2]}));
  }
  conn_.replace_elements(remove, simplices);
  return true;
}

Index Triangulation::split_boundary_edge(Index p, Index q, const Vec2& x) {
  const std::vector<ElementHandle> inc = incident(p, q);
  if (inc.size() != 1) return -1;
  const auto t = oriented(conn_.simplex(inc[0]));
  // Rotate so that the triangle reads (a, b, r) with {a, b} = {p, q}.
  int i = 0;
  while (t[static_cast<size_t>(i)] == p || t[static_cast<size_t>(i)] == q) ++i;
  const Index r = t[static_cast<size_t>(i)], a = t[static_cast<size_t>((i + 1) % 3)],
              b = t[static_cast<size_t>((i + 2) % 3)];
  if (!x.allFinite() || orient2d(point(a), x, point(r)) <= 0 ||
      orient2d(x, point(b), point(r)) <= 0)
    return -1;
  const Index n = add_vertex(x);
  replace(inc, {{a, n, r}, {n, b, r}});
  return n;
}

Index Triangulation::split_edge(Index p, Index q, const Vec2& x) {
  const std::vector<ElementHandle> inc = incident(p, q);
  if (inc.empty() || !x.allFinite()) return -1;
  const Index n = conn_.num_vertices();
  std::vector<std::array<Index, 3>> add;
  for (const ElementHandle e : inc) {
    auto t = oriented(conn_.simplex(e));
    while (t[0] == p || t[0] == q) std::rotate(t.begin(), t.begin() + 1, t.end());
    // t = (r, a, b) with {a, b} = {p, q}: (a, n, r) and (n, b, r).
    add.push_back({t[1], n, t[0]});
    add.push_back({n, t[2], t[0]});
  }
  for (const auto& t : add) {
    std::array<Vec2, 3> pts;
    for (int i = 0; i < 3; ++i)
      pts[static_cast<size_t>(i)] =
          t[static_cast<size_t>(i)] == n ? x : point(t[static_cast<size_t>(i)]);
    if (orient2d(pts[0], pts[1], pts[2]) <= 0) return -1;
  }
  add_vertex(x);
  replace(inc, add);
  return n;
}

Index Triangulation::split_triangle(ElementHandle e, const Vec2& x) {
  if (!conn_.is_alive(e) || !x.allFinite()) return -1;
  const auto t = oriented(conn_.simplex(e));
  for (int i = 0; i < 3; ++i)
    if (orient2d(point(t[static_cast<size_t>(i)]), point(t[static_cast<size_t>((i + 1) % 3)]), x) <=
        0)
      return -1;
  const Index n = add_vertex(x);
  replace({e}, {{t[0], t[1], n}, {t[1], t[2], n}, {t[2], t[0], n}});
  return n;
}

ElementHandle Triangulation::locate(const Vec2& x) const {
  for (const ElementHandle e : conn_.elements()) {
    const auto t = oriented(conn_.simplex(e));
    bool in = true;
    for (int i = 0; i < 3 && in; ++i)
      in = orient2d(point(t[static_cast<size_t>(i)]), point(t[static_cast<size_t>((i + 1) % 3)]),
                    x) >= 0;
    if (in) return e;
  }
  return {};
}

std::pair<double, double> Triangulation::angle_range() const {
  double lo = 4, hi = 0;
  for (const ElementHandle e : conn_.elements()) {
    const auto t = oriented(conn_.simplex(e));
    for (int i = 0; i < 3; ++i) {
      const double a =
          angle_at(point(t[static_cast<size_t>(i)]), point(t[static_cast<size_t>((i + 1) % 3)]),
                   point(t[static_cast<size_t>((i + 2) % 3)]));
      lo = std::min(lo, a);
      hi = std::max(hi, a);
    }
  }
  return {lo, hi};
}

}  // namespace incise::delaunay
