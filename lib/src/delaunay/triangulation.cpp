#include <incise/delaunay/predicates.hpp>
#include <incise/delaunay/triangulation.hpp>

#include <incise/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <string>

namespace incise::delaunay {
namespace {

using mesh::ElementHandle;
using mesh::Simplex;

/// The vertices of triangle s in counter-clockwise order (positive orientation, §7.2: the
/// sorted sequence for sign +1, one swap for −1).
std::array<Index, 3> ccw(const Simplex& s) {
  if (s.sign() > 0) return {s.vertex(0), s.vertex(1), s.vertex(2)};
  return {s.vertex(0), s.vertex(2), s.vertex(1)};
}

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
  std::vector<ElementHandle> out;
  if (p < 0 || p >= conn_.num_vertices()) return out;
  for (const ElementHandle e : conn_.star(p))
    if (conn_.simplex(e).contains(q)) out.push_back(e);
  return out;
}

bool Triangulation::is_interior_vertex(Index v) const {
  if (v < 0 || v >= conn_.num_vertices() || conn_.star_size(v) == 0) return false;
  for (const ElementHandle e : conn_.star(v))
    for (const Index w : ccw(conn_.simplex(e)))
      if (w != v && incident(v, w).size() != 2) return false;
  return true;
}

void Triangulation::set_constrained(Index p, Index q, bool constrained) {
  if (constrained)
    constrained_.insert(make_edge(p, q));
  else
    constrained_.erase(make_edge(p, q));
}

ElementHandle Triangulation::left_of(Index p, Index q) const {
  for (const ElementHandle e : incident(p, q)) {
    const auto t = ccw(conn_.simplex(e));
    for (int i = 0; i < 3; ++i)
      if (t[static_cast<size_t>(i)] == p && t[static_cast<size_t>((i + 1) % 3)] == q) return e;
  }
  return {};
}

Index Triangulation::third(ElementHandle e, Index p, Index q) const {
  for (const Index w : ccw(conn_.simplex(e)))
    if (w != p && w != q) return w;
  return -1;
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
  long made = 0;
  while (!edges.empty()) {
    const Edge e = edges.back();
    edges.pop_back();
    if (is_locally_delaunay(e.first, e.second)) continue;
    const ElementHandle l = left_of(e.first, e.second), r = left_of(e.second, e.first);
    const Index c = third(l, e.first, e.second), d = third(r, e.second, e.first);
    // An illegal interior edge always bounds a strictly convex quadrilateral (d inside the
    // circumcircle of p q c, on the other side of pq), so the flip succeeds.
    if (!flip(e.first, e.second)) continue;
    ++made;
    for (const Edge& o : {make_edge(e.first, c), make_edge(c, e.second), make_edge(e.second, d),
                          make_edge(d, e.first)})
      edges.push_back(o);
  }
  return made;
}

std::vector<Edge> Triangulation::edges() const {
  std::vector<Edge> out;
  for (const ElementHandle e : conn_.elements()) {
    const auto t = ccw(conn_.simplex(e));
    for (int i = 0; i < 3; ++i)
      out.push_back(make_edge(t[static_cast<size_t>(i)], t[static_cast<size_t>((i + 1) % 3)]));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

bool Triangulation::remove_vertex(Index v) {
  if (!is_interior_vertex(v)) return false;
  for (const ElementHandle e : conn_.star(v))
    for (const Index w : ccw(conn_.simplex(e)))
      if (w != v && is_constrained(v, w)) return false;
  std::vector<Edge> link;  // link polygon edges and ear diagonals, legalized at the end
  // Fig. 5.10: flip ears until degree 3. Each flip lowers the degree by one; the loop is
  // bounded by the initial degree (a pass without a flip ends it: reported as false below).
  while (conn_.star_size(v) > 3) {
    bool flipped = false;
    for (const ElementHandle e : conn_.star(v)) {
      const auto t = ccw(conn_.simplex(e));
      const int i = static_cast<int>(std::find(t.begin(), t.end(), v) - t.begin());
      const Index w = t[static_cast<size_t>((i + 1) % 3)];
      const ElementHandle r = left_of(w, v);
      if (!r.valid()) continue;
      const Index prev = third(r, w, v), next = t[static_cast<size_t>((i + 2) % 3)];
      link.push_back(make_edge(prev, w));
      link.push_back(make_edge(w, next));
      if (flip(v, w)) {
        link.push_back(make_edge(prev, next));  // the ear's diagonal
        flipped = true;
        break;
      }
    }
    if (!flipped) return false;  // not star-shaped from v: cannot happen for a valid mesh
  }
  const std::vector<ElementHandle> star = conn_.star(v);
  std::array<Index, 3> outer{};
  {
    // The link triangle, counter-clockwise: the successor of v in each star triangle.
    const auto t = ccw(conn_.simplex(star[0]));
    const int i = static_cast<int>(std::find(t.begin(), t.end(), v) - t.begin());
    outer[0] = t[static_cast<size_t>((i + 1) % 3)];
    outer[1] = t[static_cast<size_t>((i + 2) % 3)];
    outer[2] = third(left_of(v, outer[1]), v, outer[1]);
  }
  conn_.replace_elements(star, {Simplex({outer[0], outer[1], outer[2]})});
  for (int i = 0; i < 3; ++i)
    link.push_back(
        make_edge(outer[static_cast<size_t>(i)], outer[static_cast<size_t>((i + 1) % 3)]));
  legalize(link);
  return true;
}

std::array<Index, 3> Triangulation::triangle(ElementHandle e) const {
  return ccw(conn_.simplex(e));
}

std::vector<Index> Triangulation::neighbours(Index v) const {
  std::vector<Index> out;
  if (v < 0 || v >= conn_.num_vertices()) return out;
  for (const ElementHandle e : conn_.star(v))
    for (const Index w : ccw(conn_.simplex(e)))
      if (w != v) out.push_back(w);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
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
    const auto t = ccw(conn_.simplex(e));
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
  const auto t = ccw(conn_.simplex(inc[0]));
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
    auto t = ccw(conn_.simplex(e));
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
  const auto t = ccw(conn_.simplex(e));
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
    const auto t = ccw(conn_.simplex(e));
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
    const auto t = ccw(conn_.simplex(e));
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
