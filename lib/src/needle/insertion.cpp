#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>
#include <incise/needle/insertion.hpp>
#include <incise/needle/needle_problem.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>

#include "stick_slip.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace incise::needle {

namespace {

double cross(const Vec2& a, const Vec2& b) {
  return a(0) * b(1) - a(1) * b(0);
}

}  // namespace

const char* to_string(StepStatus s) {
  switch (s) {
    case StepStatus::kOk: return "ok";
    case StepStatus::kSolverFailed: return "solver-failed";
    case StepStatus::kRearrangementCycle: return "rearrangement-cycle";
    case StepStatus::kRefinementBudget: return "refinement-budget";
    case StepStatus::kNotRun: return "not-run";
  }
  return "?";
}

NeedleInsertion::NeedleInsertion(const mesh::MeshData& start, const material::Material& material,
                                 double thickness, std::vector<FixedLine> fixed,
                                 FrictionProfile friction, InsertionOptions options)
    : mesh_(start),
      material_(material),
      thickness_(thickness),
      fixed_lines_(std::move(fixed)),
      friction_(friction),
      options_(options) {
  friction_.validate();
  INCISE_CHECK_PARAM(std::isfinite(thickness) && thickness > 0.0,
                     "thickness must be finite and > 0, got " + std::to_string(thickness));
  INCISE_CHECK_PARAM(std::isfinite(options_.h_ref) && options_.h_ref > 0.0,
                     "h_ref must be finite and > 0, got " + std::to_string(options_.h_ref));
  INCISE_CHECK_PARAM(std::isfinite(options_.epsilon) && options_.epsilon > 0.0,
                     "epsilon must be finite and > 0, got " + std::to_string(options_.epsilon));
  INCISE_CHECK_PARAM(std::isfinite(options_.epsilon_round) && options_.epsilon_round >= 0.0,
                     "epsilon_round must be finite and >= 0");
  INCISE_CHECK_PARAM(options_.max_rearrangements >= 0, "max_rearrangements must be >= 0");
  INCISE_CHECK_PARAM(options_.max_iterations > 0, "max_iterations must be > 0");
  for (const FixedLine& l : fixed_lines_)
    INCISE_CHECK_PARAM((l.axis == 0 || l.axis == 1) && std::isfinite(l.value),
                       "fixed line needs axis 0 or 1 and a finite value");
  const Eigen::Matrix2Xd x = start.points.topRows<2>();
  const double diameter = (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).norm();
  stop_.rule = solver::ResidualRule::kWithReactions;
  stop_.epsilon = options_.epsilon;
  stop_.epsilon_round = options_.epsilon_round;
  stop_.force_scale = material_.parameters().youngs_modulus * thickness_ * diameter;  // E·d·H
  margins_ = {stop_.epsilon_round * stop_.force_scale, stop_.epsilon_round * diameter};
  rebuild_problem();
  u_ = VecX::Zero(problem_->size());
}

NeedleInsertion::~NeedleInsertion() = default;

bool NeedleInsertion::is_fixed_vertex(Index v) const {
  for (const FixedLine& l : fixed_lines_)
    if (std::abs(mesh_.points()(l.axis, v) - l.value) <= 1e-9) return true;
  return false;
}

void NeedleInsertion::rebuild_problem() {
  problem_ = std::make_unique<fem::PlaneStressProblem>(mesh_.to_mesh_data(), material_, thickness_);
  std::vector<Index> fixed;
  for (Index v = 0; v < problem_->num_nodes(); ++v)
    if (is_fixed_vertex(v)) fixed.push_back(v);
  problem_->fix_nodes(fixed);
}

Eigen::Matrix2Xd NeedleInsertion::deformed() const {
  Eigen::Matrix2Xd x = mesh_.points().topRows<2>();
  for (Eigen::Index v = 0; v < x.cols(); ++v) x.col(v) += u_.segment<2>(2 * v);
  return x;
}

void NeedleInsertion::update_thresholds() {
  std::vector<double> s;
  s.reserve(nodes_.size());
  for (const NeedleNode& n : nodes_) s.push_back(n.coords.s);
  thresholds_ = friction_.dynamic_thresholds(s);
}

void NeedleInsertion::place_needle_nodes() {
  for (const NeedleNode& n : nodes_) {
    const Vec2 x = pose_.point(n.coords);
    u_.segment<2>(2 * n.vertex) = x - mesh_.points().col(n.vertex).head<2>();
  }
}

void NeedleInsertion::refine_at_tip() {
  const Eigen::Matrix2Xd x = deformed();
  const Vec2 tip = pose_.tip;
  Vec2 reference;
  bool found = false;
  const mesh::Connectivity& conn = mesh_.connectivity();
  for (const mesh::ElementHandle e : conn.elements()) {
    const mesh::Simplex& s = conn.simplex(e);
    const Vec2 a = x.col(s.vertex(0)), b = x.col(s.vertex(1)), c = x.col(s.vertex(2));
    const double area = cross(b - a, c - a);
    // An inverted deformed triangle (area < 0) still maps barycentrically.
    if (area == 0.0) continue;
    const double la = cross(b - tip, c - tip) / area, lb = cross(c - tip, a - tip) / area;
    const double lc = 1.0 - la - lb;
    if (la < -1e-12 || lb < -1e-12 || lc < -1e-12) continue;
    reference = la * mesh_.points().col(s.vertex(0)).head<2>() +
                lb * mesh_.points().col(s.vertex(1)).head<2>() +
                lc * mesh_.points().col(s.vertex(2)).head<2>();
    found = true;
    break;
  }
  if (!found) return;  // the tip is outside the body
  // Through an inverted deformed triangle the mapped point can leave the reference body
  // (refine_around would throw): no refinement at this step then.
  if (!mesh_.locate(reference).valid()) return;
  refined_at_ = reference;
  const Index before = mesh_.connectivity().num_vertices();
  // Triangles congruent to the uniform h_ref slab's have legs h_ref, hypotenuse √2·h_ref.
  mesh_.refine_around(reference, std::sqrt(2.0) * options_.h_ref * (1.0 + 1e-9));
  const Index after = mesh_.connectivity().num_vertices();
  if (after == before) return;
  u_.conservativeResize(2 * static_cast<Eigen::Index>(after));
  for (Index v = before; v < after; ++v) {
    const auto p = mesh_.parents(v);
    u_.segment<2>(2 * v) = 0.5 * (u_.segment<2>(2 * p[0]) + u_.segment<2>(2 * p[1]));
  }
  rebuild_problem();
  for (Index v = before; v < after; ++v)
    if (is_fixed_vertex(v)) u_.segment<2>(2 * v).setZero();
}

int NeedleInsertion::intercept() {
  const Eigen::Matrix2Xd x = deformed();
  const mesh::Connectivity& conn = mesh_.connectivity();
  const Vec2 p0 = pose_.base(), d = pose_.tip - p0;
  // The crossing parameter α along edge (p, q), p < q, or a negative value when the edge
  // misses the shaft: a + α e = p0 + β d  ⇒  α = cross(p0 − a, d)/cross(e, d),
  // β = cross(p0 − a, e)/cross(e, d), both in [0, 1].
  const auto crossing = [&](Index p, Index q) {
    const Vec2 a = x.col(p), e = x.col(q) - a;
    const double den = cross(e, d);
    if (den == 0.0) return -1.0;
    const double alpha = cross(p0 - a, d) / den, beta = cross(p0 - a, e) / den;
    if (alpha < 0.0 || alpha > 1.0 || beta < 0.0 || beta > 1.0) return -1.0;
    return alpha;
  };
  // Only the few crossing edges are collected (an edge is seen from each of its triangles),
  // then visited in (p, q) order.
  std::vector<std::pair<std::pair<Index, Index>, double>> edges;
  for (const mesh::ElementHandle e : conn.elements()) {
    const mesh::Simplex& s = conn.simplex(e);
    for (int i = 0; i < 3; ++i) {
      Index p = s.vertex(i), q = s.vertex((i + 1) % 3);
      if (p > q) std::swap(p, q);
      const double alpha = crossing(p, q);
      if (alpha >= 0.0) edges.push_back({{p, q}, alpha});
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::vector<char> is_needle(static_cast<std::size_t>(x.cols()), 0);
  for (const NeedleNode& n : nodes_) is_needle[static_cast<std::size_t>(n.vertex)] = 1;
  int added = 0;
  for (const auto& [edge, alpha] : edges) {
    const auto [p, q] = edge;
    const Index v = alpha < 0.5 ? p : q;
    if (is_needle[static_cast<std::size_t>(v)] || is_fixed_vertex(v)) continue;
    NeedleNode n;
    n.vertex = v;
    n.state = NodeState::kStick;
    n.coords = pose_.coordinates(x.col(v));
    if (n.coords.s < 0.0 || n.coords.s > pose_.length) continue;
    if (options_.relocate) {
      n.coords.perp = 0.0;
      u_.segment<2>(2 * v) = pose_.point(n.coords) - mesh_.points().col(v).head<2>();
    }
    n.anchor = n.coords.s;
    nodes_.push_back(n);
    is_needle[static_cast<std::size_t>(v)] = 1;
    ++added;
  }
  return added;
}

bool NeedleInsertion::solve(StepReport& rep) {
  return detail::solve<2>(*problem_, pose_, nodes_, thresholds_, options_, stop_, mesh_.points(),
                          u_, last_gradient_, rep);
}

int NeedleInsertion::rearrange() {
  return detail::rearrange<2>(nodes_, thresholds_, friction_.static_factor, last_gradient_,
                              margins_);
}

int NeedleInsertion::release() {
  return detail::release(nodes_, thresholds_, pose_.length);
}

void NeedleInsertion::fill_counts(StepReport& rep, bool converged) {
  detail::fill_counts<2>(*problem_, pose_.frame(), nodes_, thresholds_, last_gradient_, u_,
                         converged, rep);
}

StepReport NeedleInsertion::run(StepReport rep) {
  Timer timer;
  for (NeedleNode& n : nodes_) n.anchor = n.coords.s;
  update_thresholds();
  rep.rearrange_seconds += timer.seconds();
  return detail::stick_slip_loop(
      rep, options_.max_rearrangements, [&](StepReport& r) { return solve(r); },
      [&] { return rearrange(); }, [&](StepReport& r, bool c) { fill_counts(r, c); },
      [&] { return release(); });
}

StepReport NeedleInsertion::step(const NeedlePose& pose) {
  pose.validate();
  NeedlePose p = pose;
  p.direction.normalize();
  pose_ = p;
  has_pose_ = true;
  place_needle_nodes();
  StepReport rep;
  Timer timer;
  const long before = mesh_.num_bisections();
  refined_at_.setConstant(std::numeric_limits<double>::quiet_NaN());
  refine_at_tip();
  rep.refined_at = refined_at_;
  rep.bisections = mesh_.num_bisections() - before;
  rep.refine_seconds = timer.seconds();
  timer.restart();
  rep.intercepted = intercept();
  rep.rearrange_seconds = timer.seconds();
  return run(rep);
}

StepReport NeedleInsertion::settle() {
  INCISE_CHECK(has_pose_, "settle: no step has been taken");
  return run(StepReport{});
}

}  // namespace incise::needle
