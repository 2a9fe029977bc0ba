#include <incise/delaunay/cutter2d.hpp>

#include <incise/delaunay/predicates.hpp>
#include "boundary_grid.hpp"
#include "incision.hpp"
#include "planar.hpp"
#include "topology.hpp"

#include <incise/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace incise::delaunay {
namespace {

using detail::starting_at;
using mesh::ElementHandle;

/// Parameters (t, s) of the intersection of segments p0→p1 and q0→q1 (double precision, for
/// placing points; the topology is decided by orient2d). False when parallel or not meeting.
bool segment_intersection(const Vec2& p0, const Vec2& p1, const Vec2& q0, const Vec2& q1, double& t,
                          double& s) {
  const Vec2 r = p1 - p0, d = q1 - q0;
  const double den = cross(r, d);
  t = s = 0;  // defined for callers that clamp a near-parallel touch
  if (den == 0) return false;
  t = cross(q0 - p0, d) / den;
  s = cross(q0 - p0, r) / den;
  return t >= 0 && t <= 1 && s >= 0 && s <= 1;
}

}  // namespace

const char* to_string(CutMoveStatus status) {
  return status == CutMoveStatus::kOk ? "ok" : "blocked";
}

Cutter2D::Cutter2D(Triangulation& mesh, Cutter2DOptions options) : mesh_(mesh), options_(options) {
  auto positive = [](double x) { return std::isfinite(x) && x > 0; };
  INCISE_CHECK_PARAM(positive(options.edge) && positive(options.entry) && positive(options.exit),
                     "Cutter2D: thresholds edge, entry and exit must be finite and > 0");
  INCISE_CHECK_PARAM(positive(options.dilation) && options.dilation <= 0.1,
                     "Cutter2D: dilation must be in (0, 0.1] (a fraction of the mean edge)");
  INCISE_CHECK_PARAM(options.max_substeps >= 1, "Cutter2D: max_substeps must be >= 1");
  INCISE_CHECK_PARAM(
      std::isfinite(options.min_angle) && options.min_angle > 0 && options.min_angle < M_PI / 3,
      "Cutter2D: min_angle must be in (0, pi/3) rad");
  const std::vector<Edge> edges = mesh.edges();
  INCISE_CHECK_PARAM(!edges.empty(), "Cutter2D: the mesh has no edges");
  double sum = 0;
  for (const Edge& e : edges) sum += (mesh.point(e.first) - mesh.point(e.second)).norm();
  h_ = sum / static_cast<double>(edges.size());
  eps_edge_ = options.edge * h_;
  eps_entry_ = options.entry * h_;
  eps_exit_ = options.exit * h_;
  delta_ = options.dilation * h_;
  grid_ = std::make_unique<detail::BoundaryGrid>(mesh, h_);
  mesh_.add_watcher(grid_.get());  // calls init: every current boundary edge
}

Cutter2D::~Cutter2D() {
  mesh_.remove_watcher(grid_.get());
}

bool Cutter2D::is_incision_node(Index v) const {
  for (const auto& side : track_.sides)
    if (std::find(side.begin(), side.end(), v) != side.end()) return true;
  return false;
}

bool Cutter2D::boundary_hit(const Vec2& from, const Vec2& to, Index& p, Index& q, double& t) const {
  bool found = false;
  t = std::numeric_limits<double>::infinity();
  for (const auto& e : grid_->near(from, to, 1e-9 * h_)) {
    if (e[0] == active_ || e[1] == active_) continue;
    if (std::find(forbidden_.begin(), forbidden_.end(), make_edge(e[0], e[1])) != forbidden_.end())
      continue;
    const Vec2 a = mesh_.point(e[0]), b = mesh_.point(e[1]);
    // Straddle tests by exact orientation; the parameter in double.
    const int sf = orient2d(a, b, from), st = orient2d(a, b, to);
    const int sa = orient2d(from, to, a), sb = orient2d(from, to, b);
    if (sf == st && sf != 0) continue;
    if (sa == sb && sa != 0) continue;
    if (sf == 0 && st == 0) continue;  // collinear: not a crossing
    double tt, ss;
    if (!segment_intersection(from, to, a, b, tt, ss)) {
      tt = std::clamp(tt, 0.0, 1.0);  // touching within rounding
    }
    if (tt < t) {
      t = tt;
      p = e[0];
      q = e[1];
      found = true;
    }
  }
  return found;
}

bool Cutter2D::locate_entry(const Vec2& from, const Vec2& to, Index& p, Index& q, double& t) const {
  // Entering crossings only: from strictly outside (right of p→q), to inside or on it.
  bool found = false;
  t = std::numeric_limits<double>::infinity();
  for (const auto& e : grid_->near(from, to, 1e-9 * h_)) {
    if (std::find(forbidden_.begin(), forbidden_.end(), make_edge(e[0], e[1])) != forbidden_.end())
      continue;
    const Vec2 a = mesh_.point(e[0]), b = mesh_.point(e[1]);
    if (orient2d(a, b, from) >= 0 || orient2d(a, b, to) < 0) continue;
    if (orient2d(from, to, a) * orient2d(from, to, b) > 0) continue;
    double tt, ss;
    if (!segment_intersection(from, to, a, b, tt, ss)) continue;
    if (tt < t) {
      t = tt;
      p = e[0];
      q = e[1];
      found = true;
    }
  }
  return found;
}

void Cutter2D::legalize_around(Index v, CutMove2DReport& r) {
  r.flips += detail::legalize_star(mesh_, v);
}

bool Cutter2D::too_short(Index v) const {
  const Vec2 a = mesh_.point(active_), pv = mesh_.point(v);
  if (options_.short_edge == ShortEdgeRule::kDistance) return (pv - a).norm() < eps_edge_;
  // §5.5: the angles opposite the edge a–v in its two triangles.
  for (const ElementHandle e : mesh_.incident(active_, v)) {
    const auto t = mesh_.triangle(e);
    Index o = -1;
    for (const Index w : t)
      if (w != v && w != active_) o = w;
    const Vec2 po = mesh_.point(o), x = a - po, y = pv - po;
    if (std::atan2(std::abs(cross(x, y)), x.dot(y)) < options_.min_angle) return true;
  }
  return false;
}

void Cutter2D::remove_close_nodes(CutMove2DReport& r) {
  r.removals += detail::remove_close_nodes(
      mesh_, active_, [&](Index v) { return too_short(v); },
      [&](Index v) { return is_incision_node(v); });
}

bool Cutter2D::move_keeping_shape(const Vec2& x) {
  // Every star triangle must keep 2·area ≥ kMinShape · (longest edge)² at x: exact orientation
  // alone admits triangles flat to the last bit (a kinetic approach whose flips keep resetting
  // the stall count can get there), which no element computation can use.
  constexpr double kMinShape = 1e-8;
  for (const ElementHandle e : mesh_.connectivity().star(active_)) {
    const auto t = starting_at(mesh_.triangle(e), active_);
    const Vec2 u = mesh_.point(t[1]), w = mesh_.point(t[2]);
    const double area2 = cross(u - x, w - x);
    const double longest =
        std::max({(u - x).squaredNorm(), (w - x).squaredNorm(), (w - u).squaredNorm()});
    if (!(area2 >= kMinShape * longest)) return false;
  }
  return mesh_.move_vertex(active_, x);
}

void Cutter2D::move_active(const Vec2& target, CutMove2DReport& r) {
  int stalled = 0;  // consecutive half-steps towards a flat triangle without a mesh change
  for (int step = 0; step < options_.max_substeps; ++step) {
    const Vec2 a = mesh_.point(active_);
    const Vec2 d = target - a;
    if (d.norm() <= 1e-12 * h_) return;
    // First time at which a triangle (a, u, w) of the star becomes flat: its orientation is
    // f0 − t·cross(d, w − u) along a + t d.
    double tmin = 1;
    for (const ElementHandle e : mesh_.connectivity().star(active_)) {
      const auto t = starting_at(mesh_.triangle(e), active_);
      const Vec2 u = mesh_.point(t[1]), w = mesh_.point(t[2]);
      const double f0 = cross(u - a, w - a), rate = cross(d, w - u);
      if (rate > 0) tmin = std::min(tmin, f0 / rate);
    }
    const double s = tmin >= 1 ? 1.0 : 0.5 * tmin;
    ++r.substeps;
    if (!move_keeping_shape(a + s * d) && !move_keeping_shape(a + 0.25 * s * d)) {
      r.status = CutMoveStatus::kBlocked;
      r.message = "the active node cannot move without inverting or flattening a triangle";
      return;
    }
    const long changes = mesh_.num_flips() + r.removals + r.splits;
    legalize_around(active_, r);
    remove_close_nodes(r);
    legalize_around(active_, r);
    if (phase_ == CutPhase::kCutting) {
      track_.path.push_back(mesh_.point(active_));
      split_incision(r);
    }
    const bool changed = mesh_.num_flips() + r.removals + r.splits != changes;
    stalled = (s < 1 && !changed) ? stalled + 1 : 0;
    // Ten halvings without a flip, removal or split: the triangle ahead has lost 2¹⁰ of its
    // height against an edge that cannot be flipped (boundary or incision). Stop before it is
    // flat (a sliver is worse than a movement that lags).
    if (stalled >= 10) {
      r.status = CutMoveStatus::kBlocked;
      r.message = "the active node stopped " +
                  std::to_string((mesh_.point(active_) - target).norm() / h_) +
                  " mean edge lengths short of the scalpel: a triangle ahead would flatten "
                  "against an edge that cannot be flipped";
      return;
    }
  }
  if ((mesh_.point(active_) - target).norm() > 1e-12 * h_) {
    r.status = CutMoveStatus::kBlocked;
    r.message = "the active node stopped " +
                std::to_string((mesh_.point(active_) - target).norm() / h_) +
                " mean edge lengths short of the scalpel after max_substeps sub-steps";
  }
}

void Cutter2D::fix_up(CutMove2DReport& r) {
  if (!detail::fix_up(track_, mesh_, active_, entry_, delta_)) {
    ++r.refused;  // the new vertices, if any, stay unused
    return;
  }
  r.fixed_up = true;
  phase_ = CutPhase::kCutting;
}

void Cutter2D::split_incision(CutMove2DReport& r) {
  for (int k = 0; k < 16; ++k) {
    ElementHandle tl, tr;
    Index ol, orr;
    if (!detail::cut_edge_triangles(track_, mesh_, active_, tl, tr, ol, orr)) return;
    const Vec2 a = mesh_.point(active_),
               c = 0.5 * (mesh_.point(track_.left) + mesh_.point(track_.right));
    const Vec2 pl = mesh_.point(ol), pr = mesh_.point(orr);
    // Fig. 5.5: the incision as the edge c–a in the quadrilateral c, o_r, a, o_l.
    if (orient2d(c, a, pl) <= 0 || orient2d(a, c, pr) <= 0) return;
    if (incircle(c, a, pl, pr) <= 0) return;
    // Where o_l o_r meets the path, or (a curved path that passes beside it) the path point
    // closest to it (§5.3.1: "where the path is closest to the line connecting the nodes
    // opposite the cut edges").
    double best = std::numeric_limits<double>::infinity();
    Vec2 x = Vec2::Zero();
    size_t seg = 0;
    for (size_t i = 0; i + 1 < track_.path.size(); ++i) {
      const Vec2 p0 = track_.path[i], p1 = track_.path[i + 1];
      double t, s2;
      if (segment_intersection(p0, p1, pl, pr, t, s2)) {
        best = 0;
        x = p0 + t * (p1 - p0);
        seg = i;
        continue;  // the last crossing (nearest the tip) wins
      }
      if (best == 0) continue;
      // Closest point of segment p0p1 to segment pl pr: the ends against the other segment.
      auto closest_on = [](const Vec2& q0, const Vec2& q1, const Vec2& y) {
        const Vec2 d = q1 - q0;
        const double l2 = d.squaredNorm();
        const double u = l2 > 0 ? std::clamp((y - q0).dot(d) / l2, 0.0, 1.0) : 0.0;
        return Vec2(q0 + u * d);
      };
      for (const Vec2& cand : {p0, p1, closest_on(p0, p1, pl), closest_on(p0, p1, pr)}) {
        const double dist = (closest_on(pl, pr, cand) - cand).norm();
        if (dist < best) {
          best = dist;
          x = cand;
          seg = i;
        }
      }
    }
    if (!std::isfinite(best)) return;
    if (!detail::split(track_, mesh_, active_, tl, tr, ol, orr, x, seg, delta_)) {
      ++r.refused;
      return;
    }
    ++r.splits;
  }
}

Index Cutter2D::boundary_node_at(Index p, Index q, const Vec2& x, double snap) {
  return detail::boundary_node_at(mesh_, p, q, x, snap);
}

bool Cutter2D::exit_at(Index p, Index q, const Vec2& x, CutMove2DReport& r) {
  const Index n = boundary_node_at(p, q, x, eps_exit_);  // the exit node
  if (n < 0) {
    ++r.refused;
    return false;
  }
  // Make the edge a–n by flipping the edges that segment a→n crosses.
  for (int k = 0; k < 32 && mesh_.incident(active_, n).empty(); ++k) {
    const Vec2 a = mesh_.point(active_), xn = mesh_.point(n);
    bool flipped = false;
    for (const ElementHandle e : mesh_.connectivity().star(active_)) {
      const auto t = starting_at(mesh_.triangle(e), active_);
      if (orient2d(a, mesh_.point(t[1]), xn) >= 0 && orient2d(a, xn, mesh_.point(t[2])) >= 0) {
        flipped = mesh_.flip(t[1], t[2]);
        if (flipped) ++r.flips;
        break;
      }
    }
    if (!flipped) break;
  }
  if (!detail::exit(track_, mesh_, active_, n, forbidden_)) {
    ++r.refused;  // n stays a boundary node; the incision goes on
    return false;
  }
  r.exited = true;
  forbidden_near_ = x;
  phase_ = CutPhase::kOutside;
  active_ = -1;
  return true;
}

CutMove2DReport Cutter2D::move_to(const Vec2& x) {
  // The predicates are exact for coordinates up to ~1e70 (predicates.hpp): refuse what lies
  // beyond (1e60 m is no scalpel position).
  INCISE_CHECK_PARAM(x.allFinite() && x.cwiseAbs().maxCoeff() <= 1e60,
                     "Cutter2D::move_to: scalpel position must be finite with |x|, |y| <= 1e60 m");
  CutMove2DReport r;
  const long flips_before = mesh_.num_flips();
  if (!placed_) {
    placed_ = true;
    scalpel_ = x;
    r.phase = phase_;
    return r;
  }
  const Vec2 from = scalpel_;
  scalpel_ = x;
  if (!forbidden_.empty() && (x - forbidden_near_).norm() > 2 * eps_exit_) forbidden_.clear();

  if (phase_ == CutPhase::kOutside) {
    Index p, q;
    double t;
    if (!locate_entry(from, x, p, q, t)) {
      r.phase = phase_;
      return r;
    }
    const Vec2 e = from + t * (x - from);
    const Index a = boundary_node_at(p, q, e, eps_entry_);
    if (a < 0) {
      ++r.refused;
      r.phase = phase_;
      return r;
    }
    r.entered = true;
    active_ = a;
    entry_ = mesh_.point(a);
    dent_left_ = p;
    dent_right_ = q;
    phase_ = CutPhase::kDent;
  }

  const Vec2 before = mesh_.point(active_);
  const Index moved = active_;
  // Leaving through the dent's mouth before the fix-up: the dent stays (§5.2.2).
  if (phase_ == CutPhase::kDent && dent_left_ != active_ && dent_right_ != active_ &&
      orient2d(mesh_.point(dent_left_), mesh_.point(dent_right_), x) < 0) {
    phase_ = CutPhase::kOutside;
    active_ = -1;
    grid_->refresh(moved);
    r.phase = phase_;
    return r;
  }
  Index hp = -1, hq = -1;
  double ht = 0;
  const bool hit = boundary_hit(before, x, hp, hq, ht);
  const Vec2 goal = hit ? Vec2(before + ht * (x - before)) : x;
  if (hit) {
    // Stop ε_exit short of the boundary and finish the cut there (or, in a dent, leave).
    const double len = (goal - before).norm();
    const Vec2 stop = len > eps_exit_ ? Vec2(goal - eps_exit_ * (goal - before) / len) : before;
    move_active(stop, r);
  } else {
    move_active(goal, r);
  }
  if (phase_ == CutPhase::kDent && (mesh_.point(active_) - entry_).norm() > eps_entry_) fix_up(r);
  if (phase_ == CutPhase::kCutting) {
    split_incision(r);
    if (hit) {
      exit_at(hp, hq, goal, r);
    } else {
      // Exit prediction (Fig. 5.7): the movement extrapolated by ε_exit.
      const Vec2 d = mesh_.point(active_) - before;
      Index pp, qq;
      double tt;
      if (d.norm() > 0 &&
          boundary_hit(mesh_.point(active_), mesh_.point(active_) + eps_exit_ * d.normalized(), pp,
                       qq, tt))
        exit_at(pp, qq, mesh_.point(active_) + tt * eps_exit_ * d.normalized(), r);
    }
  } else if (phase_ == CutPhase::kDent && hit) {
    phase_ = CutPhase::kOutside;  // through the mesh before the fix-up: the dent stays
    active_ = -1;
  }
  // The node that moved keeps its boundary edges registered where they are now.
  if (moved >= 0) grid_->refresh(moved);
  r.flips = mesh_.num_flips() - flips_before;
  r.phase = phase_;
  return r;
}

}  // namespace incise::delaunay
