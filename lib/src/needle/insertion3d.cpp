#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>
#include <incise/mesh/tet_faces.hpp>
#include <incise/needle/insertion3d.hpp>
#include <incise/needle/needle_problem.hpp>

#include "augmented_path.hpp"
#include "factor_preconditioner.hpp"
#include "stick_slip.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <utility>

namespace incise::needle {

namespace {

constexpr double kBoxTolerance = 1e-9;  // m, as FixedLine's

}  // namespace

NeedleInsertion3D::NeedleInsertion3D(const mesh::MeshData& start,
                                     const material::Material& material,
                                     std::vector<FixedBox> fixed, FrictionProfile friction,
                                     InsertionOptions3D options)
    : material_(material), fixed_(std::move(fixed)), friction_(friction), options_(options) {
  friction_.validate();
  INCISE_CHECK_PARAM(start.dimension == 3 && start.cells.rows() == 4,
                     "a 3D needle insertion needs a tetrahedral mesh (dimension 3, 4 vertices per "
                     "cell), got dimension " +
                         std::to_string(start.dimension));
  INCISE_CHECK_PARAM(std::isfinite(options_.h_ref) && options_.h_ref > 0.0,
                     "h_ref must be finite and > 0, got " + std::to_string(options_.h_ref));
  INCISE_CHECK_PARAM(std::isfinite(options_.h_shaft) && options_.h_shaft >= 0.0,
                     "h_shaft must be finite and >= 0, got " + std::to_string(options_.h_shaft));
  INCISE_CHECK_PARAM(std::isfinite(options_.epsilon) && options_.epsilon > 0.0,
                     "epsilon must be finite and > 0, got " + std::to_string(options_.epsilon));
  INCISE_CHECK_PARAM(std::isfinite(options_.epsilon_round) && options_.epsilon_round >= 0.0,
                     "epsilon_round must be finite and >= 0");
  INCISE_CHECK_PARAM(options_.max_rearrangements >= 0, "max_rearrangements must be >= 0");
  INCISE_CHECK_PARAM(options_.max_iterations > 0, "max_iterations must be > 0");
  INCISE_CHECK_PARAM(options_.max_elements > 0, "max_elements must be > 0");
  INCISE_CHECK_PARAM(options_.solve_path != SolvePath3D::kAugmented || material_.name() == "linear",
                     "the augmented solve path needs the \"linear\" material (it solves the "
                     "linear static problem K a = f), got \"" +
                         material_.name() + "\"");
  INCISE_CHECK_PARAM(options_.refactor_at_m >= 1,
                     "refactor_at_m must be >= 1, got " + std::to_string(options_.refactor_at_m));
  for (const FixedBox& b : fixed_)
    INCISE_CHECK_PARAM(!b.lo.hasNaN() && !b.hi.hasNaN() && (b.lo.array() <= b.hi.array()).all(),
                       "a fixed box needs corners lo <= hi (no NaN)");
  mesh_ = std::make_unique<mesh::TetBisectionMesh>(start);
  const Eigen::Matrix3Xd& x = start.points;
  const double diameter = (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).norm();
  stop_.rule = solver::ResidualRule::kWithReactions;
  stop_.epsilon = options_.epsilon;
  stop_.epsilon_round = options_.epsilon_round;
  stop_.force_scale = material_.parameters().youngs_modulus * diameter * diameter;  // E·H²
  margins_ = {stop_.epsilon_round * stop_.force_scale, stop_.epsilon_round * diameter};
  rebuild_problem();
  INCISE_CHECK_PARAM(
      std::isfinite(options_.refactor_fraction) && options_.refactor_fraction >= 0.0 &&
          options_.refactor_fraction <= 1.0,
      "refactor_fraction must be in [0, 1], got " + std::to_string(options_.refactor_fraction));
  if (options_.solve_path == SolvePath3D::kAugmented)
    augmented_ = std::make_unique<detail::AugmentedNeedlePath>(material_);
  else if (options_.factor_preconditioner && options_.relaxation == Relaxation::kLinearCg &&
           material_.name() == "linear")
    factor_ = std::make_unique<detail::FactorPreconditioner>();
  u_ = VecX::Zero(problem_->size());
  u_end_ = u_;
  increment_ = u_;
}

NeedleInsertion3D::~NeedleInsertion3D() = default;

bool NeedleInsertion3D::is_fixed_vertex(Index v) const {
  const Vec3 p = mesh_->points().col(v);
  for (const FixedBox& b : fixed_)
    if (((p - b.lo).array() >= -kBoxTolerance).all() &&
        ((b.hi - p).array() >= -kBoxTolerance).all())
      return true;
  return false;
}

void NeedleInsertion3D::rebuild_problem() {
  problem_ = std::make_unique<fem::ElasticProblem>(mesh_->to_mesh_data(), material_);
  std::vector<Index> fixed;
  for (Index v = 0; v < problem_->num_nodes(); ++v)
    if (is_fixed_vertex(v)) fixed.push_back(v);
  problem_->fix_nodes(fixed);
  if (options_.assembled_product && material_.linear_geometry() &&
      options_.solve_path == SolvePath3D::kRelaxation)
    problem_->set_assembled_product(true);
}

Eigen::Matrix3Xd NeedleInsertion3D::deformed() const {
  Eigen::Matrix3Xd x = mesh_->points();
  for (Eigen::Index v = 0; v < x.cols(); ++v) x.col(v) += u_.segment<3>(3 * v);
  return x;
}

void NeedleInsertion3D::place_needle_nodes() {
  for (const NeedleNode3D& n : nodes_)
    u_.segment<3>(3 * n.vertex) = pose_.point(n.coords) - mesh_->points().col(n.vertex);
}

void NeedleInsertion3D::refine_at_tip(StepReport3D& rep) {
  const Eigen::Matrix3Xd x = deformed();
  const Vec3 tip = pose_.tip;
  const mesh::CellMatrix& cells = problem_->cells();
  Vec3 reference;
  bool found = false;
  for (Eigen::Index e = 0; e < cells.cols() && !found; ++e) {
    const Vec3 a = x.col(cells(0, e));
    Mat3 m;
    m << x.col(cells(1, e)) - a, x.col(cells(2, e)) - a, x.col(cells(3, e)) - a;
    // Bounding-box test first: most tetrahedra are far from the tip.
    const Vec3 lo = a.cwiseMin(a + m.col(0)).cwiseMin(a + m.col(1)).cwiseMin(a + m.col(2));
    const Vec3 hi = a.cwiseMax(a + m.col(0)).cwiseMax(a + m.col(1)).cwiseMax(a + m.col(2));
    if ((tip.array() < lo.array()).any() || (tip.array() > hi.array()).any()) continue;
    const double det = m.determinant();
    // An inverted deformed tetrahedron (det < 0) still maps barycentrically.
    if (det == 0.0) continue;
    const Vec3 l = m.inverse() * (tip - a);
    const double l0 = 1.0 - l.sum();
    if (l0 < -1e-12 || (l.array() < -1e-12).any()) continue;
    reference = l0 * mesh_->points().col(cells(0, e));
    for (int i = 0; i < 3; ++i) reference += l(i) * mesh_->points().col(cells(i + 1, e));
    found = true;
  }
  if (!found) return;  // the tip is outside the body
  // Through an inverted deformed tetrahedron the mapped point can leave the reference body.
  if (!mesh_->locate(reference).valid()) return;
  rep.refined_at = reference;
  const Index before = mesh_->connectivity().num_vertices();
  mesh_->refine_around(reference, options_.h_ref);
  if (options_.h_shaft > 0.0) {
    if (has_trace_)
      mesh_->refine_along_segment(trace_, reference, options_.h_shaft);
    else
      mesh_->refine_around(reference, options_.h_shaft);
  }
  trace_ = reference;
  has_trace_ = true;
  carry_field(before);
}

int NeedleInsertion3D::carry_field(Index before) {
  const Index after = mesh_->connectivity().num_vertices();
  if (after == before) return 0;
  for (VecX* f : {&u_, &u_end_, &increment_}) {
    f->conservativeResize(3 * static_cast<Eigen::Index>(after));
    // Parents precede their midpoint (p, q < v): increasing order sees parents' values first.
    for (Index v = before; v < after; ++v) {
      const auto p = mesh_->parents(v);
      f->segment<3>(3 * v) = 0.5 * (f->segment<3>(3 * p[0]) + f->segment<3>(3 * p[1]));
    }
  }
  rebuild_problem();
  for (Index v = before; v < after; ++v)
    if (is_fixed_vertex(v))
      for (VecX* f : {&u_, &u_end_, &increment_}) f->segment<3>(3 * v).setZero();
  return after - before;
}

int NeedleInsertion3D::refine_around(const Vec3& x, double h) {
  const Index before = mesh_->connectivity().num_vertices();
  mesh_->refine_around(x, h);
  return carry_field(before);
}

int NeedleInsertion3D::intercept() {
  const Eigen::Matrix3Xd x = deformed();
  const mesh::CellMatrix& cells = problem_->cells();
  const double r = pose_.radius, len = pose_.length;
  const Vec3 base = pose_.base(), d = pose_.tip - base;
  // The shaft's bounding box widened by r: tetrahedra outside it cannot meet the cylinder.
  const Vec3 lo = base.cwiseMin(pose_.tip).array() - r, hi = base.cwiseMax(pose_.tip).array() + r;
  const auto nv = static_cast<std::size_t>(x.cols());
  std::vector<char> is_needle(nv, 0);
  for (const NeedleNode3D& n : nodes_) is_needle[static_cast<std::size_t>(n.vertex)] = 1;
  static constexpr int kEdge[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  int added = 0;
  for (Eigen::Index e = 0; e < cells.cols(); ++e) {
    Vec3 p[4];
    for (int i = 0; i < 4; ++i) p[i] = x.col(cells(i, e));
    const Vec3 tlo = p[0].cwiseMin(p[1]).cwiseMin(p[2]).cwiseMin(p[3]);
    const Vec3 thi = p[0].cwiseMax(p[1]).cwiseMax(p[2]).cwiseMax(p[3]);
    if ((thi.array() < lo.array()).any() || (tlo.array() > hi.array()).any()) continue;
    // Does the axis segment base + β·d, β ∈ [0, 1], meet the tetrahedron? Clip β against its
    // four face planes (Cyrus–Beck; the deformed tetrahedron may be inverted: orient by the
    // opposite vertex).
    double b0 = 0.0, b1 = 1.0;
    bool meets = true;
    for (int f = 0; f < 4 && meets; ++f) {
      const Vec3& a = p[mesh::kTetFace[f][0]];
      Vec3 nrm = (p[mesh::kTetFace[f][1]] - a).cross(p[mesh::kTetFace[f][2]] - a);
      if (nrm.dot(p[f] - a) > 0.0) nrm = -nrm;  // outward: away from the opposite vertex
      const double num = nrm.dot(base - a), den = nrm.dot(d);  // inside: num + β·den ≤ 0
      if (den == 0.0) {
        meets = num <= 0.0;
      } else if (den > 0.0) {
        b1 = std::min(b1, -num / den);
      } else {
        b0 = std::max(b0, -num / den);
      }
      meets = meets && b0 <= b1;
    }
    for (int k = 0; k < 6 && !meets; ++k)
      meets = shaft_approach(pose_, p[kEdge[k][0]], p[kEdge[k][1]]).distance <= r;
    if (!meets) continue;
    for (int i = 0; i < 4; ++i) {
      const Index v = cells(i, e);
      if (is_needle[static_cast<std::size_t>(v)] || problem_->is_fixed(3 * v)) continue;
      NeedleNode3D n;
      n.vertex = v;
      n.state = NodeState::kStick;
      n.coords = pose_.coordinates(p[i]);
      if (n.coords.s < 0.0 || n.coords.s > len) continue;
      if (options_.relocate) {
        // §6.8.6 in 3D: onto the needle's surface (or the axis when the node lies on it).
        const double dist = n.coords.perp.norm();
        n.coords.perp = dist > 0.0 ? Vec2(n.coords.perp * (r / dist)) : Vec2::Zero();
        u_.segment<3>(3 * v) = pose_.point(n.coords) - mesh_->points().col(v);
      }
      n.anchor = n.coords.s;
      nodes_.push_back(n);
      is_needle[static_cast<std::size_t>(v)] = 1;
      ++added;
    }
  }
  return added;
}

void NeedleInsertion3D::update_thresholds() {
  std::vector<char> is_needle(static_cast<std::size_t>(problem_->num_nodes()), 0);
  std::vector<Index> vertices;
  std::vector<double> s;
  for (const NeedleNode3D& n : nodes_) {
    is_needle[static_cast<std::size_t>(n.vertex)] = 1;
    vertices.push_back(n.vertex);
    s.push_back(n.coords.s);
  }
  surface_ = needle::needle_surface(problem_->cells(), is_needle);
  const std::vector<double> area = needle_node_areas(deformed(), surface_, vertices);
  thresholds_ = friction_.surface_thresholds(s, area, pose_.radius);
}

void NeedleInsertion3D::update_surface(StepReport3D& rep) {
  std::vector<char> is_needle(static_cast<std::size_t>(problem_->num_nodes()), 0);
  for (const NeedleNode3D& n : nodes_) is_needle[static_cast<std::size_t>(n.vertex)] = 1;
  surface_ = needle::needle_surface(problem_->cells(), is_needle);
  const Eigen::Matrix3Xd x = deformed();
  rep.surface_faces = static_cast<int>(surface_.cols());
  rep.surface_area = 0.0;
  for (Eigen::Index f = 0; f < surface_.cols(); ++f)
    rep.surface_area += 0.5 * (x.col(surface_(1, f)) - x.col(surface_(0, f)))
                                  .cross(x.col(surface_(2, f)) - x.col(surface_(0, f)))
                                  .norm();
}

bool NeedleInsertion3D::prepare_augmented(StepReport3D& rep) {
  Timer timer;
  const int before = augmented_->factorizations();
  std::string message;
  bool ok = true;
  if (!augmented_->matches(pose_.frame())) {
    ok = augmented_->reset(*problem_, pose_.frame(), message);
  } else {
    augmented_->follow(*problem_);
    // A failed refactorization keeps the old factor, which still serves (no failure).
    if (augmented_->changed_columns() > options_.refactor_at_m) (void)augmented_->refactor();
  }
  rep.factorizations += augmented_->factorizations() - before;
  rep.solve_seconds += timer.seconds();
  if (!ok) {
    rep.status = StepStatus::kSolverFailed;
    rep.message = message;
  }
  return ok;
}

bool NeedleInsertion3D::prepare_factor(StepReport3D& rep) {
  Timer timer;
  NeedleProblem3D np(*problem_, pose_, nodes_, thresholds_);
  std::string message;
  const auto limit =
      static_cast<Eigen::Index>(options_.refactor_fraction * static_cast<double>(np.size()));
  bool ok = true;
  if (!factor_->ready() || factor_->changed_dofs(np) > limit) {
    ok = factor_->factor(np, message);
    ++rep.factorizations;
  }
  ok = ok && factor_->follow(np, message);
  rep.solve_seconds += timer.seconds();
  if (!ok) {
    rep.status = StepStatus::kSolverFailed;
    rep.message = message;
  }
  return ok;
}

StepReport3D NeedleInsertion3D::run(StepReport3D rep) {
  Timer timer;
  for (NeedleNode3D& n : nodes_) n.anchor = n.coords.s;
  update_thresholds();
  if (extrapolate_now_) extrapolate();
  rep.rearrange_seconds += timer.seconds();
  if (augmented_ && !prepare_augmented(rep)) return rep;
  if (factor_ && !prepare_factor(rep)) return rep;
  std::function<void(const VecX&, VecX&)> precondition;
  std::function<bool()> precondition_failed;
  if (factor_) {
    precondition = [this](const VecX& r, VecX& z) { factor_->apply(r, z); };
    precondition_failed = [this] { return factor_->failed(); };
  }
  rep = detail::stick_slip_loop(
      rep, options_.max_rearrangements,
      [&](StepReport3D& r) {
        if (augmented_)
          return augmented_->solve(*problem_, pose_, nodes_, thresholds_, mesh_->points(), u_,
                                   last_gradient_, r);
        return detail::solve<3>(*problem_, pose_, nodes_, thresholds_, options_, stop_,
                                mesh_->points(), u_, last_gradient_, r, precondition,
                                precondition_failed);
      },
      [&] {
        return detail::rearrange<3>(nodes_, thresholds_, friction_.static_factor, last_gradient_,
                                    margins_);
      },
      [&](StepReport3D& r, bool converged) {
        detail::fill_counts<3>(*problem_, pose_.frame(), nodes_, thresholds_, last_gradient_, u_,
                               converged, r);
      },
      [&] { return detail::release(nodes_, thresholds_, pose_.length); });
  timer.restart();
  update_surface(rep);
  rep.rearrange_seconds += timer.seconds();
  return rep;
}

StepReport3D NeedleInsertion3D::step(const NeedlePose3D& pose) {
  pose.validate();
  if (has_pose_) {
    NeedlePose3D p = pose_.moved(pose.tip, pose.direction);
    p.length = pose.length;
    p.radius = pose.radius;
    pose_ = p;
  } else {
    pose_ = pose;
    pose_.direction.normalize();
    pose_.normal = (pose.normal - pose.normal.dot(pose_.direction) * pose_.direction).normalized();
  }
  has_pose_ = true;
  place_needle_nodes();
  StepReport3D rep;
  if (problem_->num_elements() >= options_.max_elements) {
    rep.status = StepStatus::kRefinementBudget;
    rep.message = "the mesh has " + std::to_string(problem_->num_elements()) +
                  " tetrahedra, the refinement budget max_elements is " +
                  std::to_string(options_.max_elements);
    return rep;
  }
  Timer timer;
  const long before = mesh_->num_bisections();
  refine_at_tip(rep);
  rep.bisections = mesh_->num_bisections() - before;
  rep.refine_seconds = timer.seconds();
  timer.restart();
  rep.intercepted = intercept();
  rep.rearrange_seconds = timer.seconds();
  extrapolate_now_ =
      options_.extrapolate && options_.relaxation == Relaxation::kLinearCg && !augmented_;
  rep = run(rep);
  extrapolate_now_ = false;
  increment_ = u_ - u_end_;
  u_end_ = u_;
  return rep;
}

void NeedleInsertion3D::extrapolate() {
  std::vector<char> is_needle(static_cast<std::size_t>(problem_->num_nodes()), 0);
  for (const NeedleNode3D& n : nodes_) is_needle[static_cast<std::size_t>(n.vertex)] = 1;
  for (Index v = 0; v < problem_->num_nodes(); ++v)
    if (!is_needle[static_cast<std::size_t>(v)] && !problem_->is_fixed(3 * v))
      u_.segment<3>(3 * v) += increment_.segment<3>(3 * v);
}

StepReport3D NeedleInsertion3D::settle() {
  INCISE_CHECK(has_pose_, "settle: no step has been taken");
  StepReport3D rep = run(StepReport3D{});
  u_end_ = u_;
  return rep;
}

}  // namespace incise::needle
