#pragma once
/// \file cantilever.hpp
/// The cantilever of thesis §3.3 / Table 3.1 and Figure 3.11, shared by the Table 3.1 checks:
/// l = 1.2 m (x), h = 0.2 m (y, the bending direction), d = 0.3 m (z), E = 1e6 Pa, ν = 0,
/// clamped at x = 0, total tip load 3 N in −y at x = l.

#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>

#include <cmath>
#include <map>
#include <memory>
#include <string>

namespace incise::verify {

constexpr double kLength = 1.2, kHeight = 0.2, kDepth = 0.3, kYoung = 1e6, kLoad = 3.0;
/// Euler–Bernoulli tip deflection 4F/(Ed)(l/h)³ (§3.3), published reference 8.64e-3 m.
constexpr double kEulerBernoulli = 4.0 * kLoad / (kYoung * kDepth) * (kLength / kHeight) *
                                   (kLength / kHeight) * (kLength / kHeight);
/// Timoshenko: EB + F l/(κ G A), κ = 5/6, G = E/2 (ν = 0): 8.784e-3 m.
constexpr double kTimoshenko =
    kEulerBernoulli + kLoad * kLength / (5.0 / 6.0 * (kYoung / 2.0) * kHeight * kDepth);

/// Result of one cantilever solve.
struct CantileverResult {
  int nx = 0, ny = 0, nz = 0;
  Index nodes = 0, elements = 0;
  solver::StopReason reason = solver::StopReason::kMaxIterations;
  long iterations = 0;
  double avg_deflection = 0.0;  ///< mean of −u_y over the tip nodes (m)
  double max_deflection = 0.0;  ///< max of −u_y over the tip nodes (m)
  double min_deflection = 0.0;  ///< min of −u_y over the tip nodes (m)
  std::uint64_t flops = 0;
  double seconds = 0.0;
  double residual_norm = 0.0;                 ///< final true ‖r‖ (N)
  double threshold = 0.0;                     ///< the stopping threshold (N)
  bool finite = true;                         ///< u has no NaN/∞
  EvalStatus final_status = EvalStatus::kOk;  ///< Π evaluated at the returned u
};

/// Everything that varies between the cantilever runs (defaults: Table 3.1).
struct CantileverSetup {
  int nx = 16, ny = 4, nz = 4;      ///< cells along l, h, d
  double epsilon = 1e-8;            ///< ‖r‖ ≤ ε‖f_ex‖ (§3.3 uses 1e-8)
  double poisson = 0.0;             ///< ν
  double young = kYoung;            ///< E (Pa)
  std::string material = "linear";  ///< registry name; non-linear models use NCG
  double tip_load = kLoad;          ///< total tip load in −y (N)
  double density = 0.0;             ///< ρ (kg/m³) for the own-weight case
  double gravity = 0.0;             ///< g (m/s²) in −y
  long max_iterations = 200000;     ///< solver budget
  solver::Preconditioner pc = solver::Preconditioner::kNone;
  mesh::CubeSplit split = mesh::CubeSplit::kSix;
};

/// The cantilever problem of `s` on mesh `m` (filled in): clamped at x = 0, tip traction and/or
/// gravity as in solve_cantilever(). `tip` receives the tip nodes.
inline std::unique_ptr<fem::ElasticProblem> make_cantilever(const CantileverSetup& s,
                                                            mesh::MeshData& m,
                                                            std::vector<Index>& tip) {
  m = mesh::make_box(s.nx, s.ny, s.nz, kLength, kHeight, kDepth, s.split);
  material::Parameters par;
  par.youngs_modulus = s.young;
  par.poisson_ratio = s.poisson;
  par.density = s.density;
  const material::Material mat(s.material, par);
  auto prob = std::make_unique<fem::ElasticProblem>(m, mat);
  fem::ElasticProblem& p = *prob;
  p.fix_nodes(fem::nodes_on_plane(m, 0, 0.0));
  if (s.gravity != 0.0) p.add_gravity(Vec3(0.0, -s.gravity, 0.0));
  tip = fem::nodes_on_plane(m, 0, kLength);
  // Tip-face triangles: faces of tetrahedra with all three vertices at x = l.
  std::map<Index, double> weight;
  double total_area = 0.0;
  const double tol = 1e-9;
  for (Index e = 0; e < m.num_cells(); ++e) {
    int on[4], k = 0;
    for (int a = 0; a < 4; ++a)
      if (std::abs(m.points(0, m.cells(a, e)) - kLength) < tol) on[k++] = m.cells(a, e);
    if (k != 3) continue;
    const Vec3 a = m.points.col(on[0]), b = m.points.col(on[1]), c = m.points.col(on[2]);
    const double area = 0.5 * (b - a).cross(c - a).norm();
    total_area += area;
    for (int i = 0; i < 3; ++i) weight[on[i]] += area / 3.0;
  }
  if (s.tip_load != 0.0)
    for (const auto& [node, w] : weight)
      p.add_point_load(fem::PointLoad{node, Vec3(0.0, -s.tip_load * w / total_area, 0.0)});

  return prob;
}

/// Solves the cantilever on make_box(nx, ny, nz, l, h, d), clamped at x = 0: the linear model by
/// matrix-free CG, other models by nonlinear CG (secant, Polak-Ribière), to ‖r‖ ≤ ε‖f_ex‖.
inline CantileverResult solve_cantilever(const CantileverSetup& s) {
  mesh::MeshData m;
  std::vector<Index> tip;
  auto prob = make_cantilever(s, m, tip);
  fem::ElasticProblem& p = *prob;
  VecX u = VecX::Zero(p.size());
  solver::SolverReport rep;
  if (s.material == "linear") {
    solver::LinearCgOptions o;
    o.stop.rule = solver::ResidualRule::kExternalForce;
    o.stop.epsilon = s.epsilon;
    o.preconditioner = s.pc;
    o.budget.max_iterations = s.max_iterations;
    rep = solver::linear_cg(p, u, o);
  } else {
    solver::NonlinearCgOptions o;
    o.stop.rule = solver::ResidualRule::kExternalForce;
    o.stop.epsilon = s.epsilon;
    o.budget.max_iterations = s.max_iterations;
    rep = solver::nonlinear_cg(p, u, o);
  }
  const int nx = s.nx, ny = s.ny, nz = s.nz;

  CantileverResult r;
  r.nx = nx;
  r.ny = ny;
  r.nz = nz;
  r.nodes = m.num_points();
  r.elements = m.num_cells();
  r.reason = rep.reason;
  r.iterations = rep.iterations;
  r.flops = rep.flops;
  r.seconds = rep.seconds;
  r.residual_norm = rep.residual_norm;
  r.threshold = rep.threshold;
  r.min_deflection = 1e300;
  r.max_deflection = -1e300;
  for (Index n : tip) {
    const double y = -u[3 * n + 1];
    r.avg_deflection += y;
    r.max_deflection = std::max(r.max_deflection, y);
    r.min_deflection = std::min(r.min_deflection, y);
  }
  r.avg_deflection /= double(tip.size());
  r.finite = u.allFinite();
  double energy = 0.0;
  r.final_status = p.energy(u, energy);
  return r;
}

/// Table 3.1 shorthand: the 3 N tip load on make_box(nx, ny, nz, ...), linear model.
inline CantileverResult solve_cantilever(
    int nx, int ny, int nz, double epsilon = 1e-8, mesh::CubeSplit split = mesh::CubeSplit::kSix,
    solver::Preconditioner pc = solver::Preconditioner::kNone) {
  CantileverSetup s;
  s.nx = nx;
  s.ny = ny;
  s.nz = nz;
  s.epsilon = epsilon;
  s.split = split;
  s.pc = pc;
  return solve_cantilever(s);
}

/// Observed order p and Richardson limit from three solutions y(h_i) = y∞ − C h_iᵖ with
/// h1 > h2 > h3 (any ratios): p solves (y2−y1)/(y3−y2) = (h1ᵖ−h2ᵖ)/(h2ᵖ−h3ᵖ) by bisection.
struct Richardson {
  double order = 0.0;
  double limit = 0.0;
  bool ok = false;
};

inline Richardson richardson(double h1, double y1, double h2, double y2, double h3, double y3) {
  Richardson out;
  const double target = (y2 - y1) / (y3 - y2);
  if (!(target > 0.0) || !std::isfinite(target)) return out;
  auto ratio = [&](double p) {
    return (std::pow(h1, p) - std::pow(h2, p)) / (std::pow(h2, p) - std::pow(h3, p));
  };
  double lo = 0.05, hi = 8.0;  // ratio(p) increases with p
  if (!(ratio(lo) <= target && ratio(hi) >= target)) return out;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ratio(mid) < target ? lo : hi) = mid;
  }
  out.order = 0.5 * (lo + hi);
  const double c = (y3 - y2) / (std::pow(h2, out.order) - std::pow(h3, out.order));
  out.limit = y3 + c * std::pow(h3, out.order);
  out.ok = true;
  return out;
}

}  // namespace incise::verify
