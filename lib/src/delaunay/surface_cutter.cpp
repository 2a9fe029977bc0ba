#include <incise/delaunay/surface_cutter.hpp>

#include "incision.hpp"
#include "surface_grid.hpp"
#include "topology.hpp"

#include <incise/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>

namespace incise::delaunay {
namespace {

using detail::starting_at;
using mesh::ElementHandle;

/// Closest point of segment pq to x.
Vec3 closest_on(const Vec3& p, const Vec3& q, const Vec3& x) {
  const Vec3 d = q - p;
  const double l2 = d.squaredNorm();
  return l2 > 0 ? Vec3(p + std::clamp((x - p).dot(d) / l2, 0.0, 1.0) * d) : p;
}

/// Intersection of the segment tail → head with triangle (a, b, c) (Möller–Trumbore), closed
/// within a relative 1e-9 (a scalpel through a shared edge or vertex is found in every triangle
/// there; double-precision barycentrics are good to ~1e-15, 1e-9 keeps the closed test stable).
bool segment_triangle(const ScalpelSegment& s, const Vec3& a, const Vec3& b, const Vec3& c,
                      Vec3& x) {
  constexpr double kTol = 1e-9;
  const Vec3 d = s.head - s.tail, e1 = b - a, e2 = c - a;
  const Vec3 pv = d.cross(e2);
  const double det = e1.dot(pv);
  if (!(std::abs(det) > 1e-14 * d.norm() * e1.norm() * e2.norm())) return false;
  const Vec3 tv = s.tail - a, qv = tv.cross(e1);
  const double u = tv.dot(pv) / det, v = d.dot(qv) / det, t = e2.dot(qv) / det;
  if (u < -kTol || v < -kTol || u + v > 1 + kTol || t < -kTol || t > 1 + kTol) return false;
  const double uc = std::clamp(u, 0.0, 1.0), vc = std::clamp(v, 0.0, 1.0 - uc);
  x = a + uc * e1 + vc * e2;
  return true;
}

/// The unit normal of a star triangle of v at the crease guard's limit against the triangle
/// beyond its opposite edge, which a step of v by a small part of d would make sharper (surface.hpp
/// guard); zero when there is none.
Vec3 blocking_crease_normal(const Surface& m, Index v, const Vec3& d) {
  const Vec3 x = m.point(v) + 1e-3 * d;
  auto cosine = [](const Vec3& p, const Vec3& q) { return p.dot(q) / (p.norm() * q.norm()); };
  for (const ElementHandle e : m.connectivity().star(v)) {
    auto t = m.triangle(e);
    while (t[0] != v) t = {t[1], t[2], t[0]};
    const ElementHandle beyond = m.left_of(t[2], t[1]);
    if (!beyond.valid()) continue;
    const Vec3 n = (m.point(t[1]) - x).cross(m.point(t[2]) - x), old = m.area_normal(e),
               nb = m.area_normal(beyond);
    if (cosine(n, nb) < std::min(0.5, cosine(old, nb))) return old.normalized();
  }
  return Vec3::Zero();
}

}  // namespace

const char* to_string(SurfaceMoveStatus status) {
  switch (status) {
    case SurfaceMoveStatus::kOk: return "ok";
    case SurfaceMoveStatus::kBlocked: return "blocked";
    case SurfaceMoveStatus::kLost: return "lost";
  }
  return "?";
}

SurfaceCutter::SurfaceCutter(Surface& surface, Cutter2DOptions options)
    : mesh_(surface), options_(options) {
  auto positive = [](double x) { return std::isfinite(x) && x > 0; };
  INCISE_CHECK_PARAM(positive(options.edge) && positive(options.entry) && positive(options.exit),
                     "SurfaceCutter: thresholds edge, entry and exit must be finite and > 0");
  INCISE_CHECK_PARAM(positive(options.dilation) && options.dilation <= 0.1,
                     "SurfaceCutter: dilation must be in (0, 0.1] (a fraction of the mean edge)");
  INCISE_CHECK_PARAM(options.max_substeps >= 1, "SurfaceCutter: max_substeps must be >= 1");
  INCISE_CHECK_PARAM(
      std::isfinite(options.min_angle) && options.min_angle > 0 && options.min_angle < M_PI / 3,
      "SurfaceCutter: min_angle must be in (0, pi/3) rad");
  const std::vector<Edge> edges = mesh_.edges();
  INCISE_CHECK_PARAM(!edges.empty(), "SurfaceCutter: the surface has no edges");
  double sum = 0;
  for (const Edge& e : edges) sum += (mesh_.point(e.first) - mesh_.point(e.second)).norm();
  h_ = sum / static_cast<double>(edges.size());
  eps_edge_ = options.edge * h_;
  eps_entry_ = options.entry * h_;
  eps_exit_ = options.exit * h_;
  delta_ = options.dilation * h_;
  grid_ = std::make_unique<detail::SurfaceGrid>(mesh_, h_);
  mesh_.add_watcher(grid_.get());  // calls init: every current triangle and boundary edge
}

SurfaceCutter::~SurfaceCutter() {
  mesh_.remove_watcher(grid_.get());
}

bool SurfaceCutter::is_forbidden(Index p, Index q) const {
  for (const ForbiddenZone& z : forbidden_)
    if (std::find(z.edges.begin(), z.edges.end(), make_edge(p, q)) != z.edges.end()) return true;
  return false;
}

std::vector<SurfaceCutter::EntryHit> SurfaceCutter::find_entries(const ScalpelSegment& from,
                                                                 const ScalpelSegment& to) const {
  // Eq. (5.1) against every boundary edge; each edge's earliest entering contact (the contact
  // point moving towards the edge's triangle), earliest first, ties by the edge's vertex
  // numbers (deterministic order of coinciding events).
  const mesh::Connectivity& c = mesh_.connectivity();
  std::vector<EntryHit> out;
  for (const mesh::Simplex& s : grid_->near({from.head, from.tail, to.head, to.tail}, 2)) {
    // The swept surface lies in the convex hull of the four scalpel ends, so every contact is
    // in the cells of their bounding box.
    const mesh::FaceHandle f = c.boundary_face(s);
    if (!f.valid()) continue;
    const Index u = s.vertex(0), w = s.vertex(1);
    if (is_forbidden(u, w)) continue;
    const Vec3 pu = mesh_.point(u), pw = mesh_.point(w);
    for (const SweepHit& h : intersect_sweep_edge(from, to, pu, pw).hits) {
      const Vec3 pr = mesh_.point(detail::third(c, c.element(f), u, w));
      const Vec3 along = (pw - pu).normalized();
      Vec3 inward = pr - pu;
      inward -= inward.dot(along) * along;
      const Vec3 velocity =
          h.lambda * (to.head - from.head) + (1 - h.lambda) * (to.tail - from.tail);
      if (!(velocity.dot(inward) > 0)) continue;
      out.push_back({u, w, h});
      break;
    }
  }
  std::sort(out.begin(), out.end(), [](const EntryHit& x, const EntryHit& y) {
    if (x.hit.time != y.hit.time) return x.hit.time < y.hit.time;
    return make_edge(x.p, x.q) < make_edge(y.p, y.q);
  });
  return out;
}

std::vector<SurfaceCutter::EntryHit> SurfaceCutter::find_edge_entries(
    const ScalpelSegment& from, const ScalpelSegment& to) const {
  // Fig. 5.12, third case: the side of the scalpel hits an exposed interior edge — one where it
  // touches the surface from outside, so that it met neither triangle of the edge near the
  // contact before it and meets both after. In the plane normal to the edge (direction e) the
  // surface near the contact is two half-lines, towards the triangles' third vertices r1 and r2,
  // and the scalpel (direction d) a line through the contact moving by v: after the contact it
  // crosses the half-line towards r_i exactly when r_i and v lie on the same side of it,
  // sign det[e, d, r_i − p] = sign det[e, d, v]. Entries need both (a ridge the scalpel comes
  // down on); a scalpel that passes through the surface across an edge has r1 and r2 on
  // opposite sides. Earliest first, ties by the edge's vertex numbers.
  const mesh::Connectivity& c = mesh_.connectivity();
  std::vector<Edge> seen;
  std::vector<EntryHit> out;
  for (const mesh::Simplex& s : grid_->near({from.head, from.tail, to.head, to.tail}, 3)) {
    const ElementHandle t = c.find_element(s);
    if (!t.valid()) continue;
    const auto tv = mesh_.triangle(t);
    for (size_t i = 0; i < 3; ++i) {
      const Index u = tv[i], w = tv[(i + 1) % 3];
      const Edge key = make_edge(u, w);
      if (std::find(seen.begin(), seen.end(), key) != seen.end()) continue;
      seen.push_back(key);
      const ElementHandle t1 = detail::left_of(c, u, w), t2 = detail::left_of(c, w, u);
      if (!t1.valid() || !t2.valid()) continue;  // a boundary edge: the first case
      const Vec3 pu = mesh_.point(u), pw = mesh_.point(w);
      const Vec3 r1 = mesh_.point(detail::third(c, t1, u, w)),
                 r2 = mesh_.point(detail::third(c, t2, u, w));
      // Cheap necessary condition first: f_i(τ) = det[e, d(τ), r_i − p_u] is linear in τ (the
      // scalpel direction d is, and moving the point along the edge does not change it), and
      // r1, r2 must be on one side at the contact, f1 f2 > 0 there. The product of two linear
      // functions is largest on [0, 1] at an end or midway between their roots.
      const Vec3 e = pw - pu, d0 = from.head - from.tail, d1 = to.head - to.tail;
      const double a1 = e.cross(d0).dot(r1 - pu), b1 = e.cross(d1).dot(r1 - pu),
                   a2 = e.cross(d0).dot(r2 - pu), b2 = e.cross(d1).dot(r2 - pu);
      auto f = [](double a, double b, double q) { return a + q * (b - a); };
      auto root = [](double a, double b) { return a != b ? a / (a - b) : 0.0; };
      const double mid = std::clamp(0.5 * (root(a1, b1) + root(a2, b2)), 0.0, 1.0);
      const double slack = 1e-9 * std::max({std::abs(a1 * a2), std::abs(b1 * b2), 1e-300});
      if (!(a1 * a2 > -slack || b1 * b2 > -slack || f(a1, b1, mid) * f(a2, b2, mid) > -slack))
        continue;
      for (const SweepHit& h : intersect_sweep_edge(from, to, pu, pw).hits) {
        if (!(h.mu > 0 && h.mu < 1)) continue;  // through an end node: left to its edges
        const ScalpelSegment at = interpolate(from, to, h.time);
        const Vec3 x = h.mu * pu + (1 - h.mu) * pw, d = at.head - at.tail;
        const Vec3 v = h.lambda * (to.head - from.head) + (1 - h.lambda) * (to.tail - from.tail);
        const Vec3 n = e.cross(d);  // det[e, d, y] = (e × d) · y
        const double sv = n.dot(v), s1 = n.dot(r1 - x), s2 = n.dot(r2 - x);
        // Strict signs beyond round-off relative to the magnitudes involved.
        const double tol = 1e-12 * n.norm();
        if (!(std::abs(sv) > tol * v.norm() && std::abs(s1) > tol * (r1 - x).norm() &&
              std::abs(s2) > tol * (r2 - x).norm()))
          continue;
        if ((sv > 0) != (s1 > 0) || (sv > 0) != (s2 > 0)) continue;
        out.push_back({u, w, h});
        break;
      }
    }
  }
  std::sort(out.begin(), out.end(), [](const EntryHit& x, const EntryHit& y) {
    if (x.hit.time != y.hit.time) return x.hit.time < y.hit.time;
    return make_edge(x.p, x.q) < make_edge(y.p, y.q);
  });
  return out;
}

std::vector<Vec3> SurfaceCutter::star_intersections(const ScalpelSegment& s) const {
  // The distinct intersections of the scalpel with the active triangles, nearest to the active
  // node first (a scalpel through a shared edge or node is one intersection).
  const Vec3 a = mesh_.point(active_);
  std::vector<Vec3> hits;
  for (const ElementHandle e : mesh_.connectivity().star(active_)) {
    const auto t = mesh_.triangle(e);
    Vec3 y;
    if (!segment_triangle(s, mesh_.point(t[0]), mesh_.point(t[1]), mesh_.point(t[2]), y)) continue;
    bool known = false;
    for (const Vec3& z : hits) known = known || (z - y).norm() <= 1e-9 * h_;
    if (!known) hits.push_back(y);
  }
  std::sort(hits.begin(), hits.end(), [&](const Vec3& u, const Vec3& w) {
    return (u - a).squaredNorm() < (w - a).squaredNorm();
  });
  return hits;
}

double SurfaceCutter::d_max(const ScalpelSegment& s) const {
  // Fig. 5.11: the smallest distance from the scalpel to an edge opposite the active node.
  double d = std::numeric_limits<double>::infinity();
  for (const ElementHandle e : mesh_.connectivity().star(active_)) {
    const auto t = starting_at(mesh_.triangle(e), active_);
    d = std::min(d, max_movement(s, mesh_.point(t[1]), mesh_.point(t[2])));
  }
  return d;
}

bool SurfaceCutter::pick_exit_edge(
    const std::function<double(const Vec3&, const Vec3&, Vec3&)>& key, double limit, Index& p,
    Index& q, Vec3& x) const {
  // Over the boundary edges opposite the active node (not forbidden): the smallest key below
  // `limit`, ties broken by the edge's vertex numbers (coinciding events in a fixed order).
  bool found = false;
  double best = limit;
  for (const ElementHandle e : mesh_.connectivity().star(active_)) {
    const auto t = starting_at(mesh_.triangle(e), active_);
    if (!mesh_.is_boundary_edge(t[1], t[2]) || is_forbidden(t[1], t[2])) continue;
    Vec3 y;
    const double k = key(mesh_.point(t[1]), mesh_.point(t[2]), y);
    if (k < best || (found && k == best && make_edge(t[1], t[2]) < make_edge(p, q))) {
      best = k;
      found = true;
      p = t[1];
      q = t[2];
      x = y;
    }
  }
  return found;
}

bool SurfaceCutter::sweep_exit(const ScalpelSegment& from, const ScalpelSegment& to, Index& p,
                               Index& q, Vec3& x) const {
  // The earliest contact of the sweep with such an edge (eq. (5.1)).
  auto first_contact = [&](const Vec3& pu, const Vec3& pw, Vec3& y) {
    const SweepEdgeResult res = intersect_sweep_edge(from, to, pu, pw);
    if (res.hits.empty()) return std::numeric_limits<double>::infinity();
    y = res.hits.front().mu * pu + (1 - res.hits.front().mu) * pw;
    return res.hits.front().time;
  };
  return pick_exit_edge(first_contact, 2.0, p, q, x);
}

bool SurfaceCutter::near_exit(double radius, Index& p, Index& q, Vec3& x) const {
  // Fig. 5.7, predicted exit: such an edge within `radius` of the active node.
  const Vec3 a = mesh_.point(active_);
  auto distance = [&](const Vec3& pu, const Vec3& pw, Vec3& y) {
    y = closest_on(pu, pw, a);
    return (y - a).norm();
  };
  return pick_exit_edge(distance, radius, p, q, x);
}

bool SurfaceCutter::too_short(Index v) const {
  const Vec3 a = mesh_.point(active_), pv = mesh_.point(v);
  if (options_.short_edge == ShortEdgeRule::kDistance) return (pv - a).norm() < eps_edge_;
  // §5.5 (as Cutter2D::too_short): the angles opposite the edge a–v in its triangles.
  for (const mesh::ElementHandle e : mesh_.incident(active_, v)) {
    Index o = -1;
    for (const Index w : mesh_.triangle(e))
      if (w != v && w != active_) o = w;
    const Vec3 x = a - mesh_.point(o), y = pv - mesh_.point(o);
    if (std::atan2(x.cross(y).norm(), x.dot(y)) < options_.min_angle) return true;
  }
  return false;
}

void SurfaceCutter::remove_close_nodes(SurfaceMoveReport& r) {
  r.removals += detail::remove_close_nodes(
      mesh_, active_, [&](Index v) { return too_short(v); },
      [&](Index v) {
        // Restriction 2 of §5.3.2: a node next to another active node separates incisions.
        if (v == track_.left || v == track_.right) return true;  // a tip incision's entry node
        for (const Index w : mesh_.neighbours(v))
          if (w != active_ && mesh_.is_active_node(w)) return true;
        return false;
      });
}

void SurfaceCutter::move_active(const Vec3& target, SurfaceMoveReport& r) {
  int stalled = 0;  // consecutive partial steps without a mesh change
  int slides = 0;   // steps within a blocking triangle's plane (at most 4 per movement)
  for (int step = 0; step < options_.max_substeps; ++step) {
    const Vec3 a = mesh_.point(active_);
    const Vec3 d = target - a;
    if (d.norm() <= 1e-12 * h_) return;
    // The whole way, else halves: a star triangle that would fold or flatten (surface.hpp
    // guards) is approached, and the flips after the step may clear the way.
    double s = 1;
    bool moved = false;
    for (int k = 0; k < 12 && !moved; ++k, s *= 0.5) moved = mesh_.move_vertex(active_, a + s * d);
    if (moved) grid_->refresh(active_);  // its triangles and edges are elsewhere now
    s *= 2;                              // the fraction taken
    ++r.substeps;
    if (!moved && slides < 4) {
      // A star triangle at the 60° crease limit holds the node: slide it within that
      // triangle's plane (its crease stays), towards the scalpel as far as the guards allow.
      const Vec3 n = blocking_crease_normal(mesh_, active_, d);
      const Vec3 dp = d - d.dot(n) * n;
      if (n.squaredNorm() > 0 && dp.norm() > 1e-3 * d.norm()) {
        double f = 1;
        for (int k = 0; k < 12 && !moved; ++k, f *= 0.5)
          moved = mesh_.move_vertex(active_, a + f * dp);
        if (moved) {
          ++slides;
          grid_->refresh(active_);
          s = 0.5;  // partial
        }
      }
    }
    if (!moved) {
      r.status = SurfaceMoveStatus::kBlocked;
      r.message =
          "the active node cannot move towards the scalpel without folding or "
          "flattening a triangle";
      return;
    }
    const long changes = mesh_.num_flips() + r.removals + r.splits;
    detail::legalize_star(mesh_, active_);
    remove_close_nodes(r);
    detail::legalize_star(mesh_, active_);
    if (phase_ == CutPhase::kCutting) {
      track_.path.push_back(mesh_.point(active_));
      split_incision(r);
    }
    const bool changed = mesh_.num_flips() + r.removals + r.splits != changes;
    stalled = (s < 1 && !changed) ? stalled + 1 : 0;
    if (stalled >= 10) {
      r.status = SurfaceMoveStatus::kBlocked;
      r.message = "the active node stopped " +
                  std::to_string((mesh_.point(active_) - target).norm() / h_) +
                  " mean edge lengths short of the scalpel: a triangle ahead would fold or "
                  "flatten against an edge that cannot be flipped";
      return;
    }
  }
  if ((mesh_.point(active_) - target).norm() > 1e-12 * h_) {
    r.status = SurfaceMoveStatus::kBlocked;
    r.message = "the active node stopped short of the scalpel after max_substeps steps";
  }
}

void SurfaceCutter::fix_up(SurfaceMoveReport& r) {
  // Fig. 5.6 on the surface (incision.hpp): the dent is filled, the incision starts.
  if (!detail::fix_up(track_, mesh_, active_, entry_, delta_)) {
    ++r.refused;  // the new vertices, if any, stay unused
    return;
  }
  r.fixed_up = true;
  phase_ = CutPhase::kCutting;
}

void SurfaceCutter::split_incision(SurfaceMoveReport& r) {
  for (int k = 0; k < 16; ++k) {
    ElementHandle tl, tr;
    Index ol, orr;
    if (!detail::cut_edge_triangles(track_, mesh_, active_, tl, tr, ol, orr)) return;
    const Vec3 a = mesh_.point(active_),
               c = 0.5 * (mesh_.point(track_.left) + mesh_.point(track_.right));
    const Vec3 pl = mesh_.point(ol), pr = mesh_.point(orr);
    // Fig. 5.5 by the unfolded criterion: the incision as the edge c–a between (c, a, o_l) and
    // (a, c, o_r).
    if (unfolded_incircle(c, a, pl, pr) <= 0) return;
    // The path point closest to o_l o_r (§5.3.1); the later one on ties (nearer the tip).
    double best = std::numeric_limits<double>::infinity();
    Vec3 x = Vec3::Zero();
    size_t seg = 0;
    for (size_t i = 0; i + 1 < track_.path.size(); ++i) {
      double s, u;
      const double d = segment_distance(track_.path[i], track_.path[i + 1], pl, pr, s, u);
      if (d <= best) {
        best = d;
        x = track_.path[i] + s * (track_.path[i + 1] - track_.path[i]);
        seg = i;
      }
    }
    if (!std::isfinite(best)) return;
    const Index before = track_.left;
    if (!detail::split(track_, mesh_, active_, tl, tr, ol, orr, x, seg, delta_)) {
      ++r.refused;  // two new vertices stay unused
      return;
    }
    mesh_.set_constrained(before, active_, false);  // a tip incision's edge is now a slit
    ++r.splits;
  }
}

bool SurfaceCutter::exit_at(Index p, Index q, const Vec3& x, SurfaceMoveReport& r) {
  const Index n = detail::boundary_node_at(mesh_, p, q, x, eps_exit_);
  std::vector<Edge> closed;
  if (n < 0 || n == track_.left || n == track_.right ||
      !detail::exit(track_, mesh_, active_, n, closed)) {
    ++r.refused;  // the incision goes on
    return false;
  }
  r.exited = true;
  forbidden_.push_back({closed, x});
  phase_ = CutPhase::kOutside;
  active_ = -1;
  return true;
}

bool SurfaceCutter::annihilate(SurfaceMoveReport& r) {
  // Fig. 5.13: the nearest interior node s within ε_edge of the active node a that separates it
  // from another active node b (restriction 2 keeps s from being removed).
  const Vec3 pa = mesh_.point(active_);
  Index s = -1, b = -1;
  double best = std::numeric_limits<double>::infinity();
  for (const Index v : mesh_.neighbours(active_)) {
    if (!mesh_.is_interior_vertex(v)) continue;
    Index w = -1;
    for (const Index u : mesh_.neighbours(v))
      if (u != active_ && mesh_.is_active_node(u) && !is_sibling(u)) w = u;
    const double d = (mesh_.point(v) - pa).norm();
    if (w >= 0 && too_short(v) && d < best) {
      best = d;
      s = v;
      b = w;
    }
  }
  if (s < 0) return false;
  // The edge a–s collapses into s (a's triangles take s; the two at a–s go), so the incision
  // reaches s; then the edge s–b is dissected and contracted as at an exit: the two incisions
  // join through b and both end. Link condition of the collapse: a and s have no common
  // neighbour but the two opposite the edge (else an edge would occur twice).
  const std::vector<ElementHandle> star = mesh_.connectivity().star(active_);
  std::vector<Index> common;
  const std::vector<Index> ns = mesh_.neighbours(s);
  for (const Index v : mesh_.neighbours(active_))
    if (std::binary_search(ns.begin(), ns.end(), v)) common.push_back(v);
  std::vector<std::array<Index, 3>> add;
  for (const ElementHandle e : star) {
    auto t = mesh_.triangle(e);
    if (std::find(t.begin(), t.end(), s) != t.end()) continue;
    for (Index& v : t)
      if (v == active_) v = s;
    add.push_back(t);
  }
  if (common.size() != 2 || add.size() + 2 != star.size() || !mesh_.replace(star, add)) {
    ++r.refused;
    return false;
  }
  mesh_.set_active_node(active_, false);
  active_ = s;  // the incision now ends at s
  mesh_.set_active_node(b, false);
  std::vector<Edge> closed;
  if (!detail::exit(track_, mesh_, s, b, closed)) {
    // The incision reached s, next to b: it cannot go on from there (a triangle would hold two
    // active nodes), so it ends at s; b's incision goes on.
    mesh_.set_active_node(b, true);
    ++r.refused;
    end_incision();
    return true;
  }
  r.annihilated = true;
  forbidden_.push_back({closed, mesh_.point(b)});
  for (Incision& i : incisions_)
    if (i.active == b) {
      i.phase = CutPhase::kOutside;
      i.active = -1;
    }
  phase_ = CutPhase::kOutside;
  active_ = -1;
  return true;
}

void SurfaceCutter::end_incision() {
  phase_ = CutPhase::kOutside;
  active_ = -1;
  track_.path.clear();
}

void SurfaceCutter::advance(const ScalpelSegment& from, const ScalpelSegment& to, double tau,
                            SurfaceMoveReport& r) {
  const double span =
      std::max((to.head - from.head).norm(), (to.tail - from.tail).norm());  // per unit τ
  ScalpelSegment cur = interpolate(from, to, tau);
  const int cap = 4 * options_.max_substeps;
  while (phase_ != CutPhase::kOutside) {
    if (r.submovements >= cap) {
      r.status = SurfaceMoveStatus::kBlocked;
      r.message = "the movement needed more than " + std::to_string(cap) + " sub-movements";
      break;
    }
    ++r.submovements;
    // Fig. 5.11, floored at 10⁻³ h̄ (a scalpel that grazes an opposite edge would otherwise
    // stall; the jump past it is then caught by the sweep and the intersection tests below).
    const double dm = std::max(d_max(cur), 1e-3 * h_);
    const double next_tau = span > 0 ? std::min(1.0, tau + dm / span) : 1.0;
    const ScalpelSegment next = interpolate(from, to, next_tau);
    Index p, q;
    Vec3 x;
    if (sweep_exit(cur, next, p, q, x)) {
      if (phase_ == CutPhase::kDent) {
        end_incision();  // through the surface before the fix-up: the dent stays
        break;
      }
      // Stop ε_exit short of the crossing, then exit at the nearest boundary edge of the star.
      const Vec3 a = mesh_.point(active_);
      const double len = (x - a).norm();
      move_active(len > eps_exit_ ? Vec3(x - eps_exit_ * (x - a) / len) : a, r);
      Index pp, qq;
      Vec3 xx;
      // (Within 2 ε_exit: the node stopped ε_exit short of the crossing, up to rounding.)
      if (phase_ == CutPhase::kCutting && near_exit(2 * eps_exit_, pp, qq, xx))
        exit_at(pp, qq, xx, r);
      if (phase_ != CutPhase::kOutside) {
        r.status = SurfaceMoveStatus::kLost;
        r.message =
            "the scalpel left the surface across a boundary edge where no exit could "
            "be made; the incision ends at the active node";
        end_incision();
      }
      break;
    }
    const std::vector<Vec3> hits = star_intersections(next);
    branch_tau_ = next_tau;  // a branch made here is cut on from there
    r.extra_intersections += hits.empty() ? 0 : static_cast<int>(hits.size()) - 1;
    if (hits.size() >= 2 && phase_ == CutPhase::kCutting && branch(hits, r)) break;
    if (hits.size() >= 2 && edge_ && phase_ == CutPhase::kDent && edge_branch(hits, r)) break;
    if (hits.empty()) {
      r.status = SurfaceMoveStatus::kLost;
      r.message =
          "the scalpel no longer meets the active triangles; the incision ends at the "
          "active node";
      end_incision();
      break;
    }
    move_active(hits.front(), r);
    if (phase_ == CutPhase::kDent && (mesh_.point(active_) - entry_).norm() > eps_entry_)
      tip_ ? tip_fix_up(r) : fix_up(r);
    if (phase_ == CutPhase::kCutting) {
      split_incision(r);
      if (!annihilate(r) && near_exit(eps_exit_, p, q, x)) exit_at(p, q, x, r);
    }
    if (r.status != SurfaceMoveStatus::kOk || next_tau >= 1) break;
    cur = next;
    tau = next_tau;
  }
}

void SurfaceCutter::load(const Incision& i) {
  // The working incision in active_, phase_, entry_, track_; every live active node (this one
  // included) marked on the surface, which then refuses any triangle with two (§5.3.2).
  active_ = loaded_ = i.active;
  phase_ = i.phase;
  entry_ = i.entry;
  track_ = i.track;
  tip_ = i.tip;
  edge_ = i.edge;
  family_ = i.family;
  for (const std::vector<Incision>* list : {&incisions_, &spawned_})
    for (const Incision& o : *list) mesh_.set_active_node(o.active, o.phase != CutPhase::kOutside);
  mesh_.set_active_node(active_, true);
}

SurfaceCutter::Incision SurfaceCutter::store() {
  for (const std::vector<Incision>* list : {&incisions_, &spawned_})
    for (const Incision& o : *list) mesh_.set_active_node(o.active, false);
  // The node loaded too: an incision that ended (lost) leaves it an ordinary node, unmarked.
  mesh_.set_active_node(loaded_, false);
  if (active_ >= 0) mesh_.set_active_node(active_, false);
  return {active_, phase_, entry_, track_, tip_, edge_, 0.0, family_};
}

void SurfaceCutter::merge(SurfaceMoveReport& r, const SurfaceMoveReport& sub) {
  r.entered = r.entered || sub.entered;
  r.fixed_up = r.fixed_up || sub.fixed_up;
  r.exited = r.exited || sub.exited;
  r.tip_entered = r.tip_entered || sub.tip_entered;
  r.edge_entered = r.edge_entered || sub.edge_entered;
  r.annihilated = r.annihilated || sub.annihilated;
  r.branched = r.branched || sub.branched;
  r.branch_ways = std::max(r.branch_ways, sub.branch_ways);
  r.submovements += sub.submovements;
  r.substeps += sub.substeps;
  r.removals += sub.removals;
  r.splits += sub.splits;
  r.refused += sub.refused;
  r.extra_intersections += sub.extra_intersections;
  if (r.status == SurfaceMoveStatus::kOk && sub.status != SurfaceMoveStatus::kOk) {
    r.status = sub.status;
    r.message = sub.message;
  }
}

SurfaceMoveReport SurfaceCutter::move_to(const ScalpelSegment& s) {
  INCISE_CHECK_PARAM(s.head.allFinite() && s.tail.allFinite() &&
                         s.head.cwiseAbs().maxCoeff() <= 1e60 &&
                         s.tail.cwiseAbs().maxCoeff() <= 1e60,
                     "SurfaceCutter::move_to: scalpel ends must be finite, |x| <= 1e60 m");
  INCISE_CHECK_PARAM((s.head - s.tail).norm() > 0,
                     "SurfaceCutter::move_to: the scalpel must have a positive length");
  SurfaceMoveReport r;
  const long flips_before = mesh_.num_flips(), topo_before = mesh_.num_topological_refusals(),
             restricted_before = mesh_.num_restricted();
  if (!placed_) {
    placed_ = true;
    scalpel_ = s;
    r.phase = phase();
    return r;
  }
  const ScalpelSegment from = scalpel_;
  scalpel_ = s;
  // Exits stay closed for entry until the scalpel is 2 ε_exit away from them.
  forbidden_.erase(std::remove_if(forbidden_.begin(), forbidden_.end(),
                                  [&](const ForbiddenZone& z) {
                                    return (closest_on(s.tail, s.head, z.near) - z.near).norm() >
                                           2 * eps_exit_;
                                  }),
                   forbidden_.end());
  // The live incisions, one after the other in the order they were made (they share no
  // triangle, §5.3.2), each over the whole movement; the others' active nodes are marked on the
  // surface meanwhile, so no change makes a triangle with two active nodes.
  for (size_t k = 0; k < incisions_.size(); ++k) {
    load(incisions_[k]);
    SurfaceMoveReport sub;
    advance(from, s, 0.0, sub);
    incisions_[k] = store();
    merge(r, sub);
  }
  // Branches (Fig. 5.14) are live from now (no entry in their triangles); they are cut over the
  // rest of the movement after the entries.
  incisions_.insert(incisions_.end(), spawned_.begin(), spawned_.end());
  std::vector<size_t> branches;  // their places in incisions_
  for (size_t k = incisions_.size() - spawned_.size(); k < incisions_.size(); ++k)
    branches.push_back(k);
  spawned_.clear();
  // Restriction 1 for an entry that snaps to an existing node: none of its triangles may hold
  // an active node (at most one per triangle).
  auto next_to_active = [&](Index v) {
    for (const Index w : mesh_.neighbours(v))
      if (is_active(w)) return true;
    return false;
  };
  // New incisions (Fig. 5.12, first case): every entering contact of the sweep with a boundary
  // edge, earliest first (ties by vertex numbers), each then cut over the rest of the movement.
  for (const EntryHit& e : find_entries(from, s)) {
    // Restriction 1 of §5.3.2: no incision in an edge or triangle that is already active, and
    // none within ε_entry of an incision made in this movement.
    const std::vector<ElementHandle> inc = mesh_.incident(e.p, e.q);
    bool active = inc.size() != 1;
    for (const ElementHandle t : inc)
      for (const Index v : mesh_.triangle(t)) active = active || is_active(v);
    const Vec3 x = e.hit.mu * mesh_.point(e.p) + (1 - e.hit.mu) * mesh_.point(e.q);
    for (const Incision& i : incisions_) active = active || (i.entry - x).norm() < eps_entry_;
    if (active) {
      ++r.rejected_entries;  // mostly the scalpel at its own active node's edges
      continue;
    }
    const Index a = detail::boundary_node_at(mesh_, e.p, e.q, x, eps_entry_);
    if (a < 0 || is_active(a)) {
      ++r.refused;
      continue;
    }
    if (next_to_active(a)) {
      ++r.rejected_entries;  // snapped to an end whose triangles hold an active node
      continue;
    }
    start(a, false, false, e.hit.time, from, s, r);
  }
  // Tip entries (Fig. 5.12, second case): the tip's path through a triangle without an active
  // node (restriction 1) makes an active node inside it.
  for (const TipHit& h : find_tip_entries(from, s)) {
    if (!mesh_.connectivity().is_alive(h.triangle)) {
      ++r.rejected_entries;  // changed by an earlier entry of this movement
      continue;
    }
    bool active = false;
    for (const Index v : mesh_.triangle(h.triangle)) active = active || is_active(v);
    if (active) {
      ++r.rejected_entries;
      continue;
    }
    const Index a = mesh_.split_triangle(h.triangle, h.point);
    if (a < 0) {
      ++r.refused;
      continue;
    }
    start(a, true, false, h.time, from, s, r);
  }
  // Edge entries (Fig. 5.12, third case): the side of the scalpel coming down on an exposed
  // interior edge makes an active node on it (the edge's end within ε_entry when that is an
  // interior node, else a new node splitting the edge's two triangles into four).
  for (const EntryHit& e : find_edge_entries(from, s)) {
    const std::vector<ElementHandle> inc = mesh_.incident(e.p, e.q);
    bool active = inc.size() != 2;  // changed by an earlier entry of this movement
    for (const ElementHandle t : inc)
      for (const Index v : mesh_.triangle(t)) active = active || is_active(v);
    const Vec3 pp = mesh_.point(e.p), pq = mesh_.point(e.q);
    const Vec3 x = e.hit.mu * pp + (1 - e.hit.mu) * pq;
    for (const Incision& i : incisions_) active = active || (i.entry - x).norm() < eps_entry_;
    if (active) {
      ++r.rejected_entries;
      continue;
    }
    Index a = (x - pp).norm() <= (x - pq).norm() ? e.p : e.q;
    const bool snap = (mesh_.point(a) - x).norm() <= eps_entry_ && mesh_.is_interior_vertex(a);
    if (snap && next_to_active(a)) {
      ++r.rejected_entries;  // the end's triangles hold an active node
      continue;
    }
    if (!snap) {
      const mesh::Connectivity& c = mesh_.connectivity();
      const ElementHandle t1 = detail::left_of(c, e.p, e.q), t2 = detail::left_of(c, e.q, e.p);
      const Index r1 = detail::third(c, t1, e.p, e.q), r2 = detail::third(c, t2, e.p, e.q);
      a = mesh_.add_vertex(x);
      if (!mesh_.replace({t1, t2}, {{e.p, a, r1}, {a, e.q, r1}, {e.q, a, r2}, {a, e.p, r2}})) {
        ++r.refused;  // a stays unused
        continue;
      }
    }
    start(a, false, true, e.hit.time, from, s, r);
  }
  // The branches of this movement (Figs. 5.12 third case, 5.14), each cut from the time it was
  // made to the end of the movement; branches of branches in turn (at most 8 rounds; a later
  // round's are cut from the next movement on).
  for (int round = 0; round < 8 && !(branches.empty() && spawned_.empty()); ++round) {
    for (size_t k = incisions_.size(); k < incisions_.size() + spawned_.size(); ++k)
      branches.push_back(k);
    incisions_.insert(incisions_.end(), spawned_.begin(), spawned_.end());
    spawned_.clear();
    const std::vector<size_t> now = std::move(branches);
    branches.clear();
    for (const size_t k : now) {
      load(incisions_[k]);
      SurfaceMoveReport sub;
      advance(from, s, incisions_[k].tau, sub);
      incisions_[k] = store();
      merge(r, sub);
    }
  }
  incisions_.insert(incisions_.end(), spawned_.begin(), spawned_.end());
  spawned_.clear();
  // Incisions that ended (exit, or the scalpel lost) keep only their sides.
  for (auto it = incisions_.begin(); it != incisions_.end();) {
    if (it->phase != CutPhase::kOutside) {
      ++it;
      continue;
    }
    finished_.push_back(*it);
    it = incisions_.erase(it);
  }
  active_ = -1;
  phase_ = CutPhase::kOutside;
  r.flips = mesh_.num_flips() - flips_before;
  r.topological_refusals = mesh_.num_topological_refusals() - topo_before;
  r.restricted = mesh_.num_restricted() - restricted_before;
  r.incisions = static_cast<int>(incisions_.size());
  r.phase = phase();
  return r;
}

void SurfaceCutter::start(Index a, bool tip, bool edge, double tau, const ScalpelSegment& from,
                          const ScalpelSegment& to, SurfaceMoveReport& r) {
  // An edge entry's node is interior like a tip entry's: it goes on as one (tip fix-up) when
  // the scalpel meets its triangles only once, and branches when it meets them on both sides.
  load({a, CutPhase::kDent, mesh_.point(a), IncisionTrack<Vec3>{}, tip || edge, edge, 0.0, -1});
  SurfaceMoveReport sub;
  (edge ? sub.edge_entered : tip ? sub.tip_entered : sub.entered) = true;
  advance(from, to, tau, sub);
  incisions_.push_back(store());
  merge(r, sub);
}

std::vector<SurfaceCutter::TipHit> SurfaceCutter::find_tip_entries(const ScalpelSegment& from,
                                                                   const ScalpelSegment& to) const {
  // The tip (the tail end) moving from → to through a live triangle (those in the cells of the
  // path's bounding box), earliest first, ties by the triangle's smallest vertex number.
  std::vector<TipHit> out;
  const ScalpelSegment path{to.tail, from.tail};  // as a segment tail → head: from → to
  if (!((to.tail - from.tail).norm() > 0)) return out;
  for (const mesh::Simplex& s : grid_->near({from.tail, to.tail}, 3)) {
    const ElementHandle e = mesh_.connectivity().find_element(s);
    if (!e.valid()) continue;
    const auto t = mesh_.triangle(e);
    Vec3 x;
    if (!segment_triangle(path, mesh_.point(t[0]), mesh_.point(t[1]), mesh_.point(t[2]), x))
      continue;
    // Strictly inside (a crossing through an edge or a node is left to the other entries).
    const Vec3 n = mesh_.area_normal(e);
    bool inside = true;
    for (size_t i = 0; i < 3; ++i) {
      const Vec3 p = mesh_.point(t[i]), q = mesh_.point(t[(i + 1) % 3]);
      inside = inside && (q - p).cross(x - p).dot(n) > 1e-6 * n.squaredNorm();
    }
    if (!inside) continue;
    out.push_back({(x - from.tail).norm() / (to.tail - from.tail).norm(), e, x});
  }
  std::sort(out.begin(), out.end(), [&](const TipHit& x, const TipHit& y) {
    if (x.time != y.time) return x.time < y.time;
    const auto tx = mesh_.triangle(x.triangle), ty = mesh_.triangle(y.triangle);
    return *std::min_element(tx.begin(), tx.end()) < *std::min_element(ty.begin(), ty.end());
  });
  return out;
}

void SurfaceCutter::tip_fix_up(SurfaceMoveReport& r) {
  // Fig. 5.12, second case: once the active node is ε_entry from where the tip entered, a node
  // goes in at the entry point, in the active triangle that holds it, and the edge from it to
  // the active node is constrained; it becomes an incision at the first split (Fig. 5.5), which
  // with c_l = c_r = the entry node opens the edge into a slit.
  for (const ElementHandle e : mesh_.connectivity().star(active_)) {
    const auto t = mesh_.triangle(e);
    const Vec3 a = mesh_.point(t[0]), u = mesh_.point(t[1]) - a, w = mesh_.point(t[2]) - a;
    const Vec3 n = u.cross(w);
    // Barycentric coordinates of the entry point projected onto the triangle's plane.
    const Vec3 d = entry_ - a;
    const double s1 = d.cross(w).dot(n) / n.squaredNorm(), s2 = u.cross(d).dot(n) / n.squaredNorm();
    if (s1 <= 1e-3 || s2 <= 1e-3 || s1 + s2 >= 1 - 1e-3) continue;  // inside, off the edges
    const Index c = mesh_.split_triangle(e, a + s1 * u + s2 * w);
    if (c < 0) break;
    mesh_.set_constrained(c, active_);
    track_.left = track_.right = c;
    track_.sides.push_back({c});
    track_.sides.push_back({c});
    track_.path = {entry_, mesh_.point(active_)};
    phase_ = CutPhase::kCutting;
    r.fixed_up = true;
    return;
  }
  ++r.refused;  // tried again after the next step
}

bool SurfaceCutter::is_active(Index v) const {
  for (const Incision& i : incisions_)
    if (i.active == v && i.phase != CutPhase::kOutside) return true;
  return false;
}

CutPhase SurfaceCutter::phase() const {
  CutPhase p = CutPhase::kOutside;
  for (const Incision& i : incisions_)
    if (i.phase == CutPhase::kCutting || p == CutPhase::kOutside) p = i.phase;
  return p;
}

Index SurfaceCutter::active() const {
  return incisions_.empty() ? -1 : incisions_.front().active;
}

std::vector<Index> SurfaceCutter::active_nodes() const {
  std::vector<Index> out;
  for (const Incision& i : incisions_) out.push_back(i.active);
  return out;
}

std::vector<std::vector<Index>> SurfaceCutter::incision_sides() const {
  std::vector<std::vector<Index>> out;
  for (const std::vector<Incision>* list : {&finished_, &incisions_})
    for (const Incision& i : *list)
      for (const auto& side : i.track.sides) out.push_back(side);
  return out;
}

}  // namespace incise::delaunay
