#include <incise/interactive/delaunay_cut_session.hpp>

#include <incise/core/error.hpp>
#include <incise/delaunay/predicates.hpp>
#include <incise/fem/plane_stress_problem.hpp>
#include <incise/solver/linear_cg.hpp>

#include <algorithm>
#include <limits>

namespace incise::interactive {

DelaunayCutSession::DelaunayCutSession(const mesh::MeshData& mesh,
                                       const material::Material& material, double thickness,
                                       std::vector<SheetLine> fixed, SheetLine loaded,
                                       const Vec2& traction, DelaunayCutSessionOptions options)
    : material_(material),
      thickness_(thickness),
      fixed_(std::move(fixed)),
      loaded_(loaded),
      traction_(traction),
      options_(options) {
  INCISE_CHECK_PARAM(std::isfinite(thickness) && thickness > 0,
                     "DelaunayCutSession: thickness must be finite and > 0");
  INCISE_CHECK_PARAM(traction.allFinite(), "DelaunayCutSession: traction must be finite");
  for (const SheetLine& l : fixed_)
    INCISE_CHECK_PARAM(l.axis == 0 || l.axis == 1, "DelaunayCutSession: line axis must be 0 or 1");
  INCISE_CHECK_PARAM(loaded.axis == 0 || loaded.axis == 1,
                     "DelaunayCutSession: line axis must be 0 or 1");
  mesh_ = std::make_unique<delaunay::Triangulation>(mesh);
  const Vec2 lo = mesh.points.topRows<2>().rowwise().minCoeff(),
             hi = mesh.points.topRows<2>().rowwise().maxCoeff();
  line_tolerance_ = 1e-9 * (hi - lo).norm();
  cutter_ = std::make_unique<delaunay::Cutter2D>(*mesh_, options.cutter);
  u_.assign(static_cast<size_t>(mesh.num_points()), Vec2::Zero());
  initial_ = solve();
}

DelaunayCutSession::~DelaunayCutSession() = default;

Vec2 DelaunayCutSession::displacement(Index v) const {
  return v >= 0 && static_cast<size_t>(v) < u_.size() ? u_[static_cast<size_t>(v)] : Vec2::Zero();
}

Vec2 DelaunayCutSession::to_reference(const Vec2& x) const {
  // Inside a deformed triangle: its barycentric coordinates applied to the reference one.
  for (const mesh::ElementHandle e : mesh_->connectivity().elements()) {
    const auto t = mesh_->triangle(e);
    const Vec2 a = deformed(t[0]), b = deformed(t[1]), c = deformed(t[2]);
    if (delaunay::orient2d(a, b, x) < 0 || delaunay::orient2d(b, c, x) < 0 ||
        delaunay::orient2d(c, a, x) < 0)
      continue;
    const double area = (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
    if (!(area > 0)) continue;  // inverted in the deformed state: no map through it
    auto cross = [](const Vec2& p, const Vec2& q) { return p.x() * q.y() - p.y() * q.x(); };
    const double la = cross(b - x, c - x) / area, lb = cross(c - x, a - x) / area;
    return la * mesh_->point(t[0]) + lb * mesh_->point(t[1]) + (1 - la - lb) * mesh_->point(t[2]);
  }
  // Outside: moved back by the displacement of the nearest deformed vertex.
  double best = std::numeric_limits<double>::infinity();
  Vec2 shift = Vec2::Zero();
  for (Index v = 0; v < mesh_->connectivity().num_vertices(); ++v) {
    if (mesh_->connectivity().star_size(v) == 0) continue;
    const double d = (deformed(v) - x).squaredNorm();
    if (d < best) {
      best = d;
      shift = displacement(v);
    }
  }
  return x - shift;
}

DelaunayCutStepReport DelaunayCutSession::solve() {
  const Index nv = mesh_->connectivity().num_vertices();
  u_.resize(static_cast<size_t>(nv), Vec2::Zero());
  // New nodes (no displacement yet) start from the mean of their neighbours.
  for (Index v = 0; v < nv; ++v) {
    if (u_[static_cast<size_t>(v)] != Vec2::Zero() || mesh_->connectivity().star_size(v) == 0)
      continue;
    Vec2 sum = Vec2::Zero();
    int n = 0;
    for (const Index w : mesh_->neighbours(v)) {
      sum += u_[static_cast<size_t>(w)];
      ++n;
    }
    if (n > 0) u_[static_cast<size_t>(v)] = sum / n;
  }
  const mesh::MeshData md = mesh_->to_mesh_data();
  fem::PlaneStressProblem p(md, material_, thickness_);
  std::vector<Index> fixed;
  for (Index v = 0; v < nv; ++v) {
    bool fix = mesh_->connectivity().star_size(v) == 0;  // unused nodes carry no stiffness
    for (const SheetLine& l : fixed_)
      fix = fix || std::abs(mesh_->point(v)(l.axis) - l.value) <= line_tolerance_;
    if (fix) fixed.push_back(v);
  }
  p.fix_nodes(fixed);
  p.add_traction_on_line(loaded_.axis, loaded_.value, traction_, line_tolerance_);
  VecX u(p.size());
  for (Index v = 0; v < nv; ++v) u.segment<2>(2 * v) = u_[static_cast<size_t>(v)];
  p.project(u);
  solver::LinearCgOptions o;
  o.stop.rule = solver::ResidualRule::kExternalForce;  // (6.8)
  o.stop.epsilon = options_.tolerance;
  o.budget.max_iterations = options_.max_iterations;
  const solver::SolverReport s = solver::linear_cg(p, u, o);
  DelaunayCutStepReport r;
  r.status = s.status;
  r.message = s.message;
  r.cg_iterations = s.iterations;
  r.residual_norm = s.residual_norm;
  if (u.allFinite())
    for (Index v = 0; v < nv; ++v) u_[static_cast<size_t>(v)] = u.segment<2>(2 * v);
  return r;
}

DelaunayCutStepReport DelaunayCutSession::move_to(const Vec2& x) {
  INCISE_CHECK_PARAM(x.allFinite(), "DelaunayCutSession::move_to: non-finite position");
  const Vec2 ref = to_reference(x);
  const delaunay::CutMove2DReport cut = cutter_->move_to(ref);
  DelaunayCutStepReport r = solve();
  r.cut = cut;
  r.reference_point = ref;
  return r;
}

}  // namespace incise::interactive
