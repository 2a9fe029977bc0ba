#pragma once
/// \file ch3_common.hpp
/// Shared setup of the thesis §3.3 reproductions (verification scaffolding): the generated cube
/// of 729 nodes / 3072 tetrahedra, back face z = 0 fixed, dilating forces on the side faces,
/// linear elasticity ν = 1/4, matrix-free linear CG stopped at ‖r‖ < 1e-3‖f_ex‖ (§3.3), and a
/// cut by a straight blade moved in steps of two sweep triangles.
#include <gtest/gtest.h>

#include <incise/cut/cutter.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/solver/linear_cg.hpp>

#include <array>
#include <vector>

namespace incise::verify {

// Thesis §3.3 (reference values): 108 faces dissected, 143 degenerate elements, 2439 CG
// iterations after the cut without removal; 99 collapses, 13 incollapsible, 3034 elements and
// 823 nodes, 236 iterations with removal.
inline constexpr int kThesisFaces = 108, kThesisDegenerate = 143, kThesisItersWithout = 2439,
                     kThesisCollapses = 99, kThesisIncollapsible = 13, kThesisElements = 3034,
                     kThesisNodes = 823, kThesisItersWith = 236;

constexpr double kE = 1.0e4;       // Pa (the thesis does not state E for this experiment)
constexpr double kNu = 0.25;       // §3.3: "The material has Poisson ratio ν = 1/4"
constexpr double kFaceLoad = 100;  // N per side face, spread over its nodes (dilating)

/// Outward point loads on the four side faces x = 0, x = 1, y = 0, y = 1 (dilating, Fig. 3.12).
inline std::vector<fem::PointLoad> dilating_loads(const mesh::MeshData& m) {
  std::vector<fem::PointLoad> out;
  const int per_face = 81;  // 9×9 nodes on each face of the 8×8×8 box
  for (int axis = 0; axis < 2; ++axis) {
    for (double side : {0.0, 1.0}) {
      for (Index v : fem::nodes_on_plane(m, axis, side)) {
        Vec3 f = Vec3::Zero();
        f[axis] = (side > 0.5 ? 1.0 : -1.0) * kFaceLoad / per_face;
        out.push_back({v, f});
      }
    }
  }
  return out;
}

struct Solve {
  bool attempted = false;  ///< false when the cut left inverted elements (no FEM possible)
  long iterations = 0;
  bool converged = false;
  VecX u;
};

/// Linear CG (§3.1) on the mesh of `cm` with fixed nodes from `cm`, loads on original nodes,
/// warm start from the carried displacements x − X; at most `max_iterations` iterations.
inline Solve solve(const cut::CutMesh& cm, const std::vector<fem::PointLoad>& loads,
                   long max_iterations = 100000) {
  std::vector<Index> map;
  const mesh::MeshData md = cm.to_mesh_data(false, true, &map);
  fem::ElasticProblem p(md, material::Material("linear", {kE, kNu, 0.0, 1000.0}));
  std::vector<Index> fixed;
  VecX u = VecX::Zero(p.size());
  for (Index v = 0; v < cm.num_nodes(); ++v) {
    const Index m = map[static_cast<size_t>(v)];
    if (m < 0) continue;
    if (cm.fixed(v)) fixed.push_back(m);
    u.segment<3>(3 * m) = cm.deformed(v) - cm.reference(v);
  }
  p.fix_nodes(fixed);
  for (const auto& l : loads) {
    const Index m = map[static_cast<size_t>(l.node)];
    if (m >= 0) p.add_point_load({m, l.force});
  }
  p.project(u);
  solver::LinearCgOptions opt;
  opt.stop.rule = solver::ResidualRule::kExternalForce;  // (6.8), the rule of ch. 3
  opt.stop.epsilon = 1e-3;                               // §3.3
  opt.budget.max_iterations = max_iterations;
  const solver::SolverReport r = solver::linear_cg(p, u, opt);
  Solve s;
  s.attempted = true;
  s.iterations = r.iterations;
  s.converged = r.ok();
  s.u = u;
  return s;
}

/// The uncut cube and its equilibrium (deformed positions), computed once.
struct Ch3Cube {
  mesh::MeshData box = mesh::make_box(8, 8, 8, 1, 1, 1, mesh::CubeSplit::kSix);
  std::vector<fem::PointLoad> loads = dilating_loads(box);
  Eigen::Matrix3Xd deformed;  ///< equilibrium before the cut
  bool converged = false;

  Ch3Cube() {
    cut::CutMesh cm = make_mesh(false);
    const Solve before = solve(cm, loads);
    converged = before.converged;
    deformed = cm.reference_matrix();
    for (Index v = 0; v < cm.num_nodes(); ++v) deformed.col(v) += before.u.segment<3>(3 * v);
  }
  /// Cut mesh with the back face fixed, deformed to the equilibrium when `deform`.
  cut::CutMesh make_mesh(bool deform) const {
    cut::CutMesh cm(box);
    for (Index v : fem::nodes_on_plane(box, 2, 0.0)) cm.set_fixed(v, true);  // back face z = 0
    if (deform) cm.set_deformed(deformed);
    return cm;
  }
};

/// A straight blade (a0, b0) moved `steps` times by `move`, two sweep triangles per move.
struct Blade {
  Vec3 a0, b0, move;
  int steps = 6;
};

/// The §3.3 "large diagonal cut" of README.md: across the cube's diagonal, tilted, from above
/// the top face down to 40% of the height.
inline Blade diagonal_blade() {
  constexpr int kSteps = 6;
  return {Vec3(-0.15, 0.05, 1.25), Vec3(1.15, 0.85, 1.15), Vec3(0.05, -0.05, -0.85 / kSteps),
          kSteps};
}

struct CutOutcome {
  cut::CutTotals totals;
  Index degenerate_after = 0;
  Index inverted = 0;
  Index nodes = 0, elements = 0;
  Solve solve;
};

/// Cuts the equilibrium cube along `blade` with the given options, validating after every
/// step; then (no inverted element) the warm-restarted CG when `with_solve`, with at most
/// `max_iterations` iterations.
inline CutOutcome run_cut(const Ch3Cube& cube, const Blade& blade, const cut::CutOptions& opt,
                          bool with_solve = true, long max_iterations = 100000) {
  cut::CutMesh cm = cube.make_mesh(true);
  cut::Cutter cutter(cm, opt);
  CutOutcome out;
  Vec3 a = blade.a0, b = blade.b0;
  for (int s = 0; s < blade.steps; ++s) {
    const Vec3 a2 = a + blade.move, b2 = b + blade.move;
    for (const auto& tri : {std::array<Vec3, 3>{a, b, b2}, std::array<Vec3, 3>{a, b2, a2}}) {
      const cut::CutStepReport r = cutter.step(tri[0], tri[1], tri[2]);
      out.totals.add(r);
      const cut::CutMeshValidation v = cm.validate();
      EXPECT_TRUE(v.ok()) << (v.violations.empty() ? "" : v.violations[0]);
    }
    a = a2;
    b = b2;
  }
  out.degenerate_after = cutter.count_degenerate();
  for (Index v = 0; v < cm.num_nodes(); ++v) out.nodes += cm.unused(v) ? 0 : 1;
  out.elements = cm.num_elements();
  out.inverted = cm.validate().inverted_reference;
  if (with_solve && out.inverted == 0) out.solve = solve(cm, cube.loads, max_iterations);
  return out;
}

}  // namespace incise::verify
