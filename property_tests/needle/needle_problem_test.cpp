/// Property tests of the projected problem (6.7) (needle/needle_problem.hpp, thesis §6.6) on
/// seeded random needles through a right-triangle slab: P_W = R P̃ Rᵀ is the orthogonal
/// projection onto the admissible movements (sticking nodes still, slipping nodes along the
/// shaft); the rotated problem's gradient and Hessian product are the derivatives of its
/// energy; and projected linear CG stopped tightly agrees with a direct CHOLMOD solve of the
/// same constrained system to ≤ 1e-9 relative.

#include <incise/fem/plane_stress_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/slab2d.hpp>
#include <incise/needle/needle_problem.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise_test/needle_support.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

namespace {

using incise::Index;
using incise::Vec2;
using incise::VecX;
using incise::fem::PlaneStressProblem;
using incise::needle::NeedleNode;
using incise::needle::NeedlePose;
using incise::needle::NeedleProblem;
using incise::needle::NodeState;

/// A slab fixed at x = 0.1 with a random needle through it and random needle nodes.
struct SlabCase {
  std::unique_ptr<PlaneStressProblem> base;
  NeedlePose pose;
  std::vector<NeedleNode> nodes;
  std::vector<double> friction;
};

SlabCase make_slab_case(std::mt19937_64& rng, const std::string& model = "linear") {
  const double h = 0.1 / 16;
  const auto mesh = incise::mesh::make_right_triangle_slab(0.1, 0.1, h);
  SlabCase c;
  c.base = std::make_unique<PlaneStressProblem>(mesh, incise::test::needle_material(model), 0.01);
  std::vector<Index> fixed;
  for (Index v = 0; v < mesh.num_points(); ++v)
    if (mesh.points(0, v) > 0.1 - 1e-12) fixed.push_back(v);
  c.base->fix_nodes(fixed);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const double angle = (uni(rng) - 0.5) * 1.2;  // ±34°
  const Vec2 dir(std::cos(angle), std::sin(angle));
  const Vec2 tip = Vec2(0.03 + 0.05 * uni(rng), 0.03 + 0.04 * uni(rng));
  c.pose = NeedlePose::make(tip, dir, 0.2);
  for (Index v = 0; v < mesh.num_points(); ++v) {
    if (c.base->is_fixed(2 * v)) continue;
    const auto nc = c.pose.coordinates(mesh.points.col(v).head<2>());
    if (nc.s < 0.0 || std::abs(nc.perp) > 0.6 * h) continue;
    NeedleNode n;
    n.vertex = v;
    n.coords = nc;
    n.state = uni(rng) < 0.5 ? NodeState::kStick : NodeState::kSlip;
    n.friction_sign = n.state == NodeState::kSlip ? (uni(rng) < 0.5 ? -1 : 1) : 0;
    c.nodes.push_back(n);
    c.friction.push_back(0.05 * uni(rng));
  }
  return c;
}

TEST(NeedleProblem, ProjectionIsOrthogonalOntoAdmissibleMovements) {
  INCISE_SEEDED_RNG(rng, 6601);
  for (int trial = 0; trial < 20; ++trial) {
    SlabCase c = make_slab_case(rng);
    ASSERT_FALSE(c.nodes.empty());
    NeedleProblem p(*c.base, c.pose, c.nodes, c.friction);
    const VecX v = incise::test::gaussian_vector(rng, p.size(), 1.0),
               w = incise::test::gaussian_vector(rng, p.size(), 1.0);
    VecX pv = v, pw = w;
    p.project_original(pv);
    p.project_original(pw);
    VecX ppv = pv;
    p.project_original(ppv);
    // Orthogonal projection: idempotent and symmetric (rounding of O(1) entries).
    EXPECT_LT((ppv - pv).norm(), 1e-13 * v.norm());
    EXPECT_NEAR(pv.dot(w), v.dot(pw), 1e-12 * v.norm() * w.norm());
    for (const NeedleNode& n : c.nodes) {
      const Vec2 m = pv.segment<2>(2 * n.vertex);
      if (n.state == NodeState::kStick)
        EXPECT_EQ(m.norm(), 0.0);
      else  // parallel to the shaft: no component along n
        EXPECT_LT(std::abs(m.dot(c.pose.normal())), 1e-14 * v.norm());
    }
    // Rotated and original frames agree: ‖P_W v‖ = ‖P̃ Rᵀ v‖.
    VecX rv = p.to_rotated(v);
    p.project(rv);
    EXPECT_NEAR(rv.norm(), pv.norm(), 1e-12 * v.norm());
    EXPECT_LT((p.to_original(rv) - pv).norm(), 1e-13 * v.norm());
  }
}

TEST(NeedleProblem, GradientAndHessianAreDerivativesOfTheEnergy) {
  INCISE_SEEDED_RNG(rng, 6602);
  for (const std::string model : {"linear", "neohookean"}) {
    SCOPED_TRACE(model);
    SlabCase c = make_slab_case(rng, model);
    NeedleProblem p(*c.base, c.pose, c.nodes, c.friction);
    const VecX u = incise::test::gaussian_vector(rng, p.size(), 1e-4);
    const VecX d = incise::test::gaussian_vector(rng, p.size(), 1e-4);
    VecX g, hd, gp, gm;
    ASSERT_EQ(p.gradient(u, g), incise::EvalStatus::kOk);
    ASSERT_EQ(p.hessian_product(u, d, hd), incise::EvalStatus::kOk);
    const double eps = 1e-3;  // step along d (‖d‖ ~ 2e-3 m·…, relative 1e-3 of u's scale)
    double ep, em;
    ASSERT_EQ(p.energy(u + eps * d, ep), incise::EvalStatus::kOk);
    ASSERT_EQ(p.energy(u - eps * d, em), incise::EvalStatus::kOk);
    ASSERT_EQ(p.gradient(u + eps * d, gp), incise::EvalStatus::kOk);
    ASSERT_EQ(p.gradient(u - eps * d, gm), incise::EvalStatus::kOk);
    // Central differences: truncation O(eps²) relative ≈ 1e-6 for neo-Hookean at strains
    // ~1e-2, rounding far below; 1e-5 relative keeps a decade of margin (linear: exact).
    const double fd_e = (ep - em) / (2 * eps);
    EXPECT_NEAR(fd_e, g.dot(d), 1e-5 * std::abs(g.dot(d)));
    const VecX fd_g = (gp - gm) / (2 * eps);
    EXPECT_LT((fd_g - hd).norm(), 1e-5 * hd.norm());
  }
}

TEST(NeedleProblem, ProjectedCgMatchesDirectCholmodSolve) {
  INCISE_SEEDED_RNG(rng, 6603);
  for (int trial = 0; trial < 12; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    SlabCase c = make_slab_case(rng);
    NeedleProblem p(*c.base, c.pose, c.nodes, c.friction);
    // Prescribed needle displacements (stick: both components, slip: the normal one) and a
    // random warm start elsewhere.
    VecX u0 = incise::test::gaussian_vector(rng, p.size(), 1e-3);
    for (Eigen::Index i = 0; i < p.size(); ++i)
      if (c.base->is_fixed(i)) u0[i] = 0.0;
    VecX direct = u0;
    const auto d = incise::needle::direct_solve(p, direct);
    ASSERT_TRUE(d.ok()) << d.brief();
    VecX cg = u0;
    incise::solver::LinearCgOptions o;
    o.stop.rule = incise::solver::ResidualRule::kWithReactions;
    // Tight: ‖r‖ ≤ 1e-14·‖f‖ leaves ‖Δu‖/‖u‖ ≲ κ·1e-14 ≈ 1e-11 for κ ~ 1e3 at h4.
    o.stop.epsilon = 1e-14;
    o.stop.epsilon_round = 0.0;
    const auto rep = incise::solver::linear_cg(p, cg, o);
    EXPECT_TRUE(rep.ok() || rep.status == incise::solver::StopReason::kStagnated) << rep.brief();
    // Issue 15: ≤ 1e-9 relative.
    EXPECT_LE((cg - direct).norm(), 1e-9 * direct.norm())
        << "cg iterations " << rep.iterations << " residual " << rep.residual_norm;
    // Both keep the prescribed components.
    for (Eigen::Index i = 0; i < p.size(); ++i)
      if (p.is_fixed(i)) {
        EXPECT_EQ(cg[i], u0[i]);
        EXPECT_EQ(direct[i], u0[i]);
      }
  }
}

}  // namespace
