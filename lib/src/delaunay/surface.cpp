#include <incise/delaunay/predicates.hpp>
#include <incise/delaunay/surface.hpp>
#include "topology.hpp"

#include <incise/core/error.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/validate.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

namespace incise::delaunay {
namespace {

using detail::oriented;
using mesh::ElementHandle;
using mesh::Simplex;

/// Twice the area of (a, b, c) against the floor: 2·area ≥ kSurfaceMinShape · longest².
bool shaped(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double area2 = (b - a).cross(c - a).norm();
  const double longest =
      std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), (c - b).squaredNorm()});
  return area2 >= kSurfaceMinShape * longest && longest > 0;
}

/// cos of the angle between u and w (1 when either is zero).
double cosine(const Vec3& u, const Vec3& w) {
  const double l = u.norm() * w.norm();
  return l > 0 ? u.dot(w) / l : 1.0;
}

/// The crease between a new triangle normal n and a neighbour normal m is admissible when it is
/// no sharper than 60° (cos ≥ kCreaseCos), or no sharper than the crease it replaces, between
/// old_n and old_m. 60°: the shapes cut here have neighbouring normals within ~15° (h̄/R), so a
/// sharper crease is made by the cutter, not by the surface; an existing sharp crease is kept
/// from getting worse but does not block the cutter.
constexpr double kCreaseCos = 0.5;
bool crease_ok(const Vec3& n, const Vec3& m, const Vec3& old_n, const Vec3& old_m) {
  return cosine(n, m) >= std::min(kCreaseCos, cosine(old_n, old_m));
}
bool crease_ok(const Vec3& n, const Vec3& m, const Vec3& old_n) {
  return crease_ok(n, m, old_n, m);
}

/// The unfolding of §5.3.1: planar coordinates of p, q, c, d with p = 0, q on the x-axis, c
/// above and d below, at their true distances from p and q.
std::array<Vec2, 4> unfold(const Vec3& p, const Vec3& q, const Vec3& c, const Vec3& d) {
  const Vec3 u = q - p;
  const double l = u.norm();
  const Vec3 e = u / l;
  auto place = [&](const Vec3& x, double side) {
    const Vec3 r = x - p;
    const double along = r.dot(e);
    return Vec2(along, side * (r - along * e).norm());
  };
  return {Vec2(0, 0), Vec2(l, 0), place(c, 1), place(d, -1)};
}

}  // namespace

int unfolded_incircle(const Vec3& p, const Vec3& q, const Vec3& c, const Vec3& d) {
  if (!((q - p).norm() > 0)) return 0;
  const auto u = unfold(p, q, c, d);
  if (orient2d(u[0], u[1], u[2]) <= 0 || orient2d(u[1], u[0], u[3]) <= 0) return 0;
  return incircle(u[0], u[1], u[2], u[3]);
}

const char* to_string(FlipStatus s) {
  switch (s) {
    case FlipStatus::kFlipped: return "flipped";
    case FlipStatus::kNotAnEdge: return "not an edge";
    case FlipStatus::kConstrained: return "constrained";
    case FlipStatus::kNotConvex: return "not convex";
    case FlipStatus::kTopological: return "topologically impossible";
    case FlipStatus::kShape: return "shape";
    case FlipStatus::kRestricted: return "restricted";
  }
  return "?";
}

Vec3 surface_point(SurfaceShape shape, double u, double v, Vec3* normal) {
  if (shape == SurfaceShape::kCylinder || shape == SurfaceShape::kFold) {
    const double theta = (u - 0.5) * (shape == SurfaceShape::kFold ? 1.5 * M_PI : 2 * M_PI / 3);
    if (normal) *normal = Vec3(std::sin(theta), 0, std::cos(theta));
    return Vec3(std::sin(theta), 2 * v - 1, std::cos(theta));
  }
  // Bell over [−1, 1]²: z = A exp(−r²/w²); normal (−∂z/∂x, −∂z/∂y, 1) normalised.
  constexpr double kA = 0.4, kW = 0.5;
  const double x = 2 * u - 1, y = 2 * v - 1;
  const double z = kA * std::exp(-(x * x + y * y) / (kW * kW));
  const double zx = -2 * x / (kW * kW) * z, zy = -2 * y / (kW * kW) * z;
  if (normal) *normal = Vec3(-zx, -zy, 1).normalized();
  return Vec3(x, y, z);
}

mesh::MeshData make_surface(SurfaceShape shape, int n, int m) {
  INCISE_CHECK_PARAM(n >= 2 && (m <= 0 || m >= 2), "make_surface: n and m must be >= 2");
  mesh::MeshData g =
      mesh::make_rectangle(n, m > 0 ? m : n, 1.0, 1.0, mesh::GridDiagonal::kAlternating);
  for (Index v = 0; v < g.num_points(); ++v)
    g.points.col(v) = surface_point(shape, g.points(0, v), g.points(1, v));
  return g;
}

mesh::MeshData make_monkey_saddle(int n, double slope) {
  INCISE_CHECK_PARAM(n >= 4 && n % 2 == 0, "make_monkey_saddle: n must be even and >= 4");
  INCISE_CHECK_PARAM(slope > 0 && slope <= 1, "make_monkey_saddle: slope must be in (0, 1]");
  const double h = 2.0 / n, dy = h * std::sqrt(3.0) / 2;
  int rows = static_cast<int>(std::floor(1 / dy + 1e-12));
  if (rows % 2 == 0) --rows;
  std::vector<Vec3> points;
  std::vector<std::vector<Index>> row_nodes;
  for (int j = -rows; j <= rows; ++j) {
    std::vector<Index> row;
    const bool odd = (j % 2) != 0;
    const int half = odd ? n / 2 - 1 : n / 2;  // x = (i + ½) h up to (n/2 − ½) h, or i h to 1
    for (int i = -half - (odd ? 1 : 0); i <= half; ++i) {
      const double x = odd ? (i + 0.5) * h : i * h, y = j * dy;
      const double r2 = x * x + y * y;
      // slope · r · cos 3θ = slope · (x³ − 3 x y²) / r², zero at the origin.
      const double z = r2 > 0 ? slope * (x * x * x - 3 * x * y * y) / r2 : 0.0;
      row.push_back(static_cast<Index>(points.size()));
      points.emplace_back(x, y, z);
    }
    row_nodes.push_back(row);
  }
  std::vector<std::array<Index, 3>> tris;
  for (size_t j = 0; j + 1 < row_nodes.size(); ++j) {
    // Zip the lower row A and the upper row B in x order: (a_i, a_i+1, b_k) or (a_i, b_k+1, b_k),
    // counter-clockwise seen from +z.
    const std::vector<Index>&A = row_nodes[j], &B = row_nodes[j + 1];
    size_t i = 0, k = 0;
    while (i + 1 < A.size() || k + 1 < B.size()) {
      const bool take_a =
          k + 1 >= B.size() || (i + 1 < A.size() && points[A[i + 1]].x() < points[B[k + 1]].x());
      if (take_a) {
        tris.push_back({A[i], A[i + 1], B[k]});
        ++i;
      } else {
        tris.push_back({A[i], B[k + 1], B[k]});
        ++k;
      }
    }
  }
  mesh::MeshData g;
  g.dimension = 2;
  g.points.resize(3, static_cast<Index>(points.size()));
  for (size_t v = 0; v < points.size(); ++v) g.points.col(static_cast<Index>(v)) = points[v];
  g.cells.resize(3, static_cast<Index>(tris.size()));
  for (size_t t = 0; t < tris.size(); ++t)
    for (int c = 0; c < 3; ++c) g.cells(c, static_cast<Index>(t)) = tris[t][c];
  return g;
}

Surface::Surface(const mesh::MeshData& mesh) : conn_(2), points_(mesh.points) {
  INCISE_CHECK_PARAM(mesh.dimension == 2, "Surface: the mesh must consist of triangles");
  for (Index v = 0; v < mesh.num_points(); ++v)
    INCISE_CHECK_PARAM(
        mesh.points.col(v).allFinite() && mesh.points.col(v).cwiseAbs().maxCoeff() <= 1e60,
        "Surface: point " + std::to_string(v) + " is not finite or beyond 1e60 m");
  for (Index c = 0; c < mesh.num_cells(); ++c) {
    const auto t = mesh.cells.col(c);
    for (int i = 0; i < 3; ++i)
      INCISE_CHECK_PARAM(t(i) >= 0 && t(i) < mesh.num_points(),
                         "Surface: triangle " + std::to_string(c) + " has a vertex out of range");
    INCISE_CHECK_PARAM(shaped(points_.col(t(0)), points_.col(t(1)), points_.col(t(2))),
                       "Surface: triangle " + std::to_string(c) +
                           " is flatter than the shape floor (2·area < " + "1e-8 · longest edge²)");
  }
  conn_ = mesh::Connectivity::from_mesh_data(mesh);
  const mesh::ValidationReport r = mesh::validate(conn_);
  INCISE_CHECK_PARAM(r.ok(), "Surface: not a consistently oriented 2-manifold with boundary (" +
                                 (r.ok() ? std::string() : r.violations.front().message) + ")");
}

mesh::MeshData Surface::to_mesh_data() const {
  return conn_.to_mesh_data(points_.leftCols(conn_.num_vertices()));
}

std::vector<ElementHandle> Surface::incident(Index p, Index q) const {
  return detail::incident(conn_, p, q);
}

bool Surface::is_interior_vertex(Index v) const {
  return detail::is_interior_vertex(conn_, v);
}

std::array<Index, 3> Surface::triangle(ElementHandle e) const {
  return oriented(conn_.simplex(e));
}

ElementHandle Surface::left_of(Index p, Index q) const {
  return detail::left_of(conn_, p, q);
}

std::vector<Index> Surface::neighbours(Index v) const {
  return detail::neighbours(conn_, v);
}

std::vector<Edge> Surface::edges() const {
  return detail::edges(conn_);
}

Vec3 Surface::area_normal(ElementHandle e) const {
  const auto t = triangle(e);
  return (point(t[1]) - point(t[0])).cross(point(t[2]) - point(t[0]));
}

void Surface::set_constrained(Index p, Index q, bool constrained) {
  if (constrained)
    constrained_.insert(make_edge(p, q));
  else
    constrained_.erase(make_edge(p, q));
}

void Surface::set_active_node(Index v, bool active) {
  if (v < 0) return;
  if (active)
    active_.insert(v);
  else
    active_.erase(v);
}

bool Surface::is_locally_delaunay(Index p, Index q) const {
  if (is_constrained(p, q)) return true;
  const ElementHandle l = left_of(p, q), r = left_of(q, p);
  if (!l.valid() || !r.valid()) return true;
  const Index c = detail::third(conn_, l, p, q), d = detail::third(conn_, r, q, p);
  return unfolded_incircle(point(p), point(q), point(c), point(d)) <= 0;
}

bool Surface::admissible(const std::vector<ElementHandle>& remove,
                         const std::vector<std::array<Index, 3>>& add) const {
  auto removed = [&](ElementHandle e) {
    return std::find(remove.begin(), remove.end(), e) != remove.end();
  };
  Vec3 all = Vec3::Zero();
  for (const ElementHandle e : remove) all += area_normal(e);
  std::vector<Vec3> normal(add.size()), origin(add.size());
  for (size_t k = 0; k < add.size(); ++k) {
    const auto& t = add[k];
    for (const Index v : t)
      if (v < 0 || v >= conn_.num_vertices()) return false;
    if (is_active_node(t[0]) + is_active_node(t[1]) + is_active_node(t[2]) > 1) {
      ++restricted_;  // §5.3.2: at most one active node per triangle
      return false;
    }
    const Vec3 a = point(t[0]), b = point(t[1]), c = point(t[2]);
    if (!shaped(a, b, c)) return false;
    normal[k] = (b - a).cross(c - a);
    // Its origin: the removed triangles it shares an edge with (a substituted or split
    // triangle's), else all removed, else (pure addition) the triangles at its vertices.
    Vec3 ref = Vec3::Zero();
    for (const ElementHandle e : remove) {
      const auto o = triangle(e);
      int shared = 0;
      for (const Index v : t) shared += std::count(o.begin(), o.end(), v) > 0;
      if (shared >= 2) ref += area_normal(e);
    }
    if (ref.isZero()) ref = all;
    if (remove.empty())
      for (const Index v : t)
        for (const ElementHandle e : conn_.star(v)) ref += area_normal(e);
    origin[k] = ref;
    if (!(normal[k].dot(ref) > 0)) return false;  // turned over
    // Creases with the staying triangles across its edges.
    for (size_t i = 0; i < 3; ++i) {
      const ElementHandle beyond = left_of(t[(i + 1) % 3], t[i]);
      if (!beyond.valid() || removed(beyond)) continue;
      const ElementHandle before = left_of(t[i], t[(i + 1) % 3]);
      const Vec3 old = before.valid() && removed(before) ? area_normal(before) : ref;
      if (!crease_ok(normal[k], area_normal(beyond), old)) return false;
    }
  }
  // Creases between new triangles sharing an edge.
  for (size_t k = 0; k < add.size(); ++k)
    for (size_t l = k + 1; l < add.size(); ++l) {
      int shared = 0;
      for (const Index v : add[k]) shared += std::count(add[l].begin(), add[l].end(), v) > 0;
      if (shared >= 2 && !crease_ok(normal[k], normal[l], origin[k], origin[l])) return false;
    }
  return true;
}

FlipStatus Surface::try_flip(Index p, Index q) {
  if (is_constrained(p, q)) return FlipStatus::kConstrained;
  const ElementHandle l = left_of(p, q), r = left_of(q, p);
  if (!l.valid() || !r.valid()) return FlipStatus::kNotAnEdge;
  const Index c = detail::third(conn_, l, p, q), d = detail::third(conn_, r, q, p);
  if (c == d || !incident(c, d).empty()) {
    ++topological_;  // Fig. 5.9: {c, d} would occur twice in the complex
    return FlipStatus::kTopological;
  }
  // New triangles (c, d, q) and (d, c, p): strictly convex unfolded quadrilateral p d q c.
  const auto u = unfold(point(p), point(q), point(c), point(d));
  if (orient2d(u[2], u[3], u[1]) <= 0 || orient2d(u[3], u[2], u[0]) <= 0)
    return FlipStatus::kNotConvex;
  if ((is_active_node(c) && is_active_node(d)) ||
      ((is_active_node(c) || is_active_node(d)) && (is_active_node(p) || is_active_node(q)))) {
    ++restricted_;
    return FlipStatus::kRestricted;  // §5.3.2: the edge separates two active nodes
  }
  if (!admissible({l, r}, {{c, d, q}, {d, c, p}})) return FlipStatus::kShape;
  conn_.replace_elements({l, r}, {Simplex({c, d, q}), Simplex({d, c, p})});
  ++flips_;
  return FlipStatus::kFlipped;
}

long Surface::legalize(std::vector<Edge> edges) {
  // Whether a flip is admissible depends on the creases with the triangles around the
  // quadrilateral (admissible()), so an edge refused early may become flippable after later
  // flips: the refused edges are retried until a pass flips nothing.
  long made = 0;
  for (long pass = -1; pass != 0 && made < kMaxFlipsPerLegalize;) {
    std::vector<Edge> refused;
    pass = detail::lawson_legalize(*this, std::move(edges), kMaxFlipsPerLegalize - made, &refused);
    made += pass;
    edges = std::move(refused);
  }
  if (made >= kMaxFlipsPerLegalize) ++capped_;
  return made;
}

bool Surface::remove_vertex(Index v) {
  return detail::remove_by_ears(*this, v, /*diagonal_fallback=*/true);
}

Index Surface::add_vertex(const Vec3& x) {
  INCISE_CHECK_PARAM(x.allFinite(), "Surface::add_vertex: non-finite position");
  const Index v = conn_.add_vertex();
  // Capacity doubles (a resize per vertex would copy all positions: O(n) per insertion).
  if (points_.cols() <= v)
    points_.conservativeResize(Eigen::NoChange, std::max<Eigen::Index>(v + 1, 2 * points_.cols()));
  points_.col(v) = x;
  return v;
}

bool Surface::move_vertex(Index v, const Vec3& x) {
  if (!x.allFinite()) return false;
  // Each star triangle (v, b, c) at x: above the shape floor, not turned over, and no crease
  // made sharper than 60° (unless it was, then not sharper than it was) with the triangle
  // beyond bc — which does not move, so no triangle folds over in several small turns — nor
  // with its star neighbour across v–c.
  const std::vector<ElementHandle> star = conn_.star(v);
  std::vector<std::array<Vec3, 2>> after(star.size());  // new and old normal
  std::vector<Index> second(star.size());
  for (size_t k = 0; k < star.size(); ++k) {
    const auto t = detail::starting_at(triangle(star[k]), v);
    const Vec3 b = point(t[1]), c = point(t[2]), old = area_normal(star[k]);
    const Vec3 n = (b - x).cross(c - x);
    if (!shaped(x, b, c) || !(n.dot(old) > 0)) return false;
    const ElementHandle beyond = left_of(t[2], t[1]);
    if (beyond.valid() && !crease_ok(n, area_normal(beyond), old)) return false;
    after[k] = {n, old};
    second[k] = t[1];
  }
  for (size_t k = 0; k < star.size(); ++k) {
    const Index c = detail::starting_at(triangle(star[k]), v)[2];
    for (size_t l = 0; l < star.size(); ++l)
      if (second[l] == c && !crease_ok(after[k][0], after[l][0], after[k][1], after[l][1]))
        return false;
  }
  points_.col(v) = x;
  return true;
}

bool Surface::replace(const std::vector<ElementHandle>& remove,
                      const std::vector<std::array<Index, 3>>& add) {
  if (!admissible(remove, add)) return false;
  std::vector<Simplex> simplices;
  for (const auto& t : add) simplices.emplace_back(Simplex({t[0], t[1], t[2]}));
  conn_.replace_elements(remove, simplices);
  return true;
}

Index Surface::split_boundary_edge(Index p, Index q, const Vec3& x) {
  const std::vector<ElementHandle> inc = incident(p, q);
  if (inc.size() != 1 || !x.allFinite()) return -1;
  auto t = oriented(conn_.simplex(inc[0]));
  while (t[0] == p || t[0] == q) std::rotate(t.begin(), t.begin() + 1, t.end());
  // t = (r, a, b) with {a, b} = {p, q}: (a, n, r) and (n, b, r).
  const Index n = add_vertex(x);
  if (!replace(inc, {{t[1], n, t[0]}, {n, t[2], t[0]}})) return -1;  // n stays unused
  return n;
}

Index Surface::split_triangle(ElementHandle e, const Vec3& x) {
  if (!conn_.is_alive(e) || !x.allFinite()) return -1;
  const auto t = triangle(e);
  const Index n = add_vertex(x);
  if (!replace({e}, {{t[0], t[1], n}, {t[1], t[2], n}, {t[2], t[0], n}})) return -1;
  return n;
}

std::pair<double, double> Surface::angle_range() const {
  double lo = 4, hi = 0;
  for (const ElementHandle e : conn_.elements()) {
    const auto t = triangle(e);
    for (size_t i = 0; i < 3; ++i) {
      const Vec3 p = point(t[i]), a = point(t[(i + 1) % 3]) - p, b = point(t[(i + 2) % 3]) - p;
      const double angle = std::atan2(a.cross(b).norm(), a.dot(b));
      lo = std::min(lo, angle);
      hi = std::max(hi, angle);
    }
  }
  return {lo, hi};
}

}  // namespace incise::delaunay
