/// Property tests of the §6.7 interaction loop (needle/insertion.hpp): needle nodes keep their
/// (d_needle, d_perp) coordinates as the needle moves (Fig. 6.5); on seeded random insertion
/// paths and angles every step converges, every topological change keeps validate() true, the
/// mesh at the tip is refined to h_ref, and the rearrangement's fixed point satisfies the
/// friction inequalities at every needle node (stick: |reaction| ≤ static threshold; slip:
/// friction-balanced within the (6.9) threshold and not sliding against the friction); refinement
/// leaves Π unchanged; withdrawing releases every node; a rearrangement cap is a reported
/// status; nonlinear CG and a nonlinear material run the same loop; bad input is rejected.

#include <incise/core/error.hpp>
#include <incise/mesh/slab2d.hpp>
#include <incise/mesh/validate.hpp>
#include <incise/needle/insertion.hpp>
#include <incise/needle/needle_problem.hpp>
#include <incise_test/needle_support.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <memory>
#include <random>

namespace {

using incise::Index;
using incise::Vec2;
using incise::VecX;
using incise::needle::InsertionOptions;
using incise::needle::NeedleInsertion;
using incise::needle::NeedleNode;
using incise::needle::NeedlePose;
using incise::needle::NodeState;
using incise::needle::StepReport;
using incise::needle::StepStatus;

/// The §6.8.1 slab (0.1 × 0.1 × 0.01 m, fixed at x = 0.1) at h_start = h3, refined to h5.
std::unique_ptr<NeedleInsertion> make_slab_sim(InsertionOptions o = {},
                                               const std::string& model = "linear") {
  if (o.h_ref == InsertionOptions{}.h_ref) o.h_ref = incise::mesh::thesis_slab_spacing(5);
  return std::make_unique<NeedleInsertion>(
      incise::mesh::make_thesis_slab(3), incise::test::needle_material(model), 0.01,
      std::vector<incise::needle::FixedLine>{{0, 0.1}}, incise::needle::FrictionProfile{}, o);
}

using incise::test::expect_friction_inequalities;
using incise::test::expect_valid_mesh;

/// The (6.9) threshold on ‖r‖ at the current state (the rule every solve stopped by).
double rule_threshold(NeedleInsertion& sim) {
  incise::needle::NeedleProblem np(sim.problem(), sim.pose(), sim.needle_nodes(),
                                   sim.dynamic_thresholds());
  VecX gr;
  EXPECT_EQ(np.gradient(np.to_rotated(sim.displacement()), gr), incise::EvalStatus::kOk);
  return incise::solver::residual_threshold(sim.stopping_rule(), np.external_force_norm(),
                                            incise::solver::fixed_norm(np, gr), np.size());
}

/// StepReport::needle_force is Σ ∇Π_el over the needle nodes (recomputed here; before release,
/// so only when nothing was released), and the wall holds the needle's pull: the free nodes are
/// in equilibrium to the (6.9) threshold, so the reactions at the fixed nodes balance the needle
/// force to √m times it (m free DOFs).
void expect_needle_force(NeedleInsertion& sim, const StepReport& rep) {
  if (rep.released > 0) return;
  const double threshold = rule_threshold(sim);
  VecX g;
  ASSERT_EQ(sim.problem().gradient(sim.displacement(), g), incise::EvalStatus::kOk);
  Vec2 needle = Vec2::Zero(), wall = Vec2::Zero();
  std::vector<char> is_needle(static_cast<std::size_t>(g.size() / 2), 0);
  for (const NeedleNode& n : sim.needle_nodes()) {
    needle += g.segment<2>(2 * n.vertex);
    is_needle[static_cast<std::size_t>(n.vertex)] = 1;
  }
  double free_sq = 0.0;
  long free = 0;
  for (Eigen::Index v = 0; v < g.size() / 2; ++v) {
    if (sim.problem().is_fixed(2 * v))
      wall += g.segment<2>(2 * v);
    else if (!is_needle[static_cast<std::size_t>(v)]) {
      free_sq += g.segment<2>(2 * v).squaredNorm();
      free += 2;
    }
  }
  // Same gradient, summed in another order: rounding of O(1 N) sums.
  EXPECT_LT((rep.needle_force - needle).norm(), 1e-9 * (1.0 + needle.norm()));
  EXPECT_LE(std::sqrt(free_sq), threshold);
  EXPECT_LE((needle + wall).norm(), std::sqrt(double(free)) * threshold + 1e-12);
}

TEST(NeedleInsertion, NeedleNodesMoveWithTheNeedleByTheirCoordinates) {
  auto sim = make_slab_sim();
  const Vec2 dir(1.0, 0.1);
  std::map<Index, NeedleNode> previous;
  for (int k = 0; k <= 12; ++k) {
    const NeedlePose pose =
        NeedlePose::make(Vec2(-0.004, 0.045) + 0.004 * k * dir.normalized(), dir, 0.12);
    const StepReport rep = sim->step(pose);
    ASSERT_TRUE(rep.ok()) << rep.brief();
    const Eigen::Matrix2Xd x = sim->deformed();
    for (const NeedleNode& n : sim->needle_nodes()) {
      // x = tip − s·t + d_perp·n (Fig. 6.5), to rounding of 0.1 m coordinates.
      EXPECT_LT((x.col(n.vertex) - pose.point(n.coords)).norm(), 1e-15 * 8);
      const auto it = previous.find(n.vertex);
      if (it == previous.end()) continue;
      // Sticking since the last step: both coordinates kept; slipping: d_perp kept (§6.7).
      EXPECT_NEAR(n.coords.perp, it->second.coords.perp, 1e-15);
      if (n.state == NodeState::kStick && it->second.state == NodeState::kStick &&
          rep.rearrangements == 0) {
        EXPECT_NEAR(n.coords.s, it->second.coords.s, 1e-15);
      }
    }
    previous.clear();
    for (const NeedleNode& n : sim->needle_nodes()) previous[n.vertex] = n;
  }
  EXPECT_GT(sim->needle_nodes().size(), 10u);
}

TEST(NeedleInsertion, RandomInsertionsKeepMeshValidAndFrictionInequalities) {
  INCISE_SEEDED_RNG(rng, 6701);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  int sticking = 0, slipping = 0, rearranged = 0;
  const int paths = incise::test::scaled(4);
  for (int path = 0; path < paths; ++path) {
    InsertionOptions o;
    o.epsilon = 1e-6;
    auto sim = make_slab_sim(o);
    const double angle = (uni(rng) - 0.5) * 0.9;  // ±26°
    const Vec2 dir(std::cos(angle), std::sin(angle));
    const Vec2 entry(0.0, 0.035 + 0.03 * uni(rng));
    const double speed = (0.3 + 0.7 * uni(rng)) * sim->options().h_ref;  // per update
    SCOPED_TRACE("path " + std::to_string(path) + " angle " + std::to_string(angle));
    for (double depth = -0.002; depth <= 0.05; depth += speed) {
      const StepReport rep = sim->step(NeedlePose::make(entry + depth * dir, dir, 0.1));
      ASSERT_TRUE(rep.ok()) << rep.brief();
      expect_valid_mesh(*sim);
      if (depth > 0.001) {
        // Refined before the solve at the tip's reference position (§6.7 order).
        ASSERT_TRUE(rep.refined_at.allFinite())
            << "tip not inside the deformed body at depth " << depth;
        const auto e = sim->mesh().locate(rep.refined_at);
        ASSERT_TRUE(e.valid());
        const auto h = sim->mesh().hypotenuse(e);
        EXPECT_LE((sim->mesh().points().col(h[0]) - sim->mesh().points().col(h[1])).norm(),
                  std::sqrt(2.0) * sim->options().h_ref * (1 + 1e-9));
      }
      const auto c = expect_friction_inequalities(*sim);
      sticking += c.first;
      slipping += c.second;
      expect_needle_force(*sim, rep);
      rearranged += rep.rearrangements;
    }
  }
  // The family exercises both states and the rearrangement loop.
  EXPECT_GT(sticking, 0);
  EXPECT_GT(slipping, 0);
  EXPECT_GT(rearranged, 0);
}

TEST(NeedleInsertion, RefinementCarriesTheFieldExactly) {
  INCISE_SEEDED_RNG(rng, 6702);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  incise::mesh::BisectionMesh mesh(incise::mesh::make_thesis_slab(2));
  const auto mat = incise::test::needle_material();
  std::normal_distribution<double> g(0.0, 1e-3);
  VecX u(2 * mesh.points().cols());
  for (Eigen::Index i = 0; i < u.size(); ++i) u[i] = g(rng);
  for (int round = 0; round < 8; ++round) {
    incise::fem::PlaneStressProblem before(mesh.to_mesh_data(), mat, 0.01);
    double e0 = 0.0;
    ASSERT_EQ(before.energy(u, e0), incise::EvalStatus::kOk);
    const Index n0 = mesh.connectivity().num_vertices();
    mesh.refine_around(Vec2(0.1 * uni(rng), 0.1 * uni(rng)), 0.004);
    const Index n1 = mesh.connectivity().num_vertices();
    u.conservativeResize(2 * n1);
    for (Index v = n0; v < n1; ++v) {
      const auto p = mesh.parents(v);
      ASSERT_LT(p[0], v);
      ASSERT_LT(p[1], v);
      EXPECT_LT(
          (mesh.points().col(v) - 0.5 * (mesh.points().col(p[0]) + mesh.points().col(p[1]))).norm(),
          1e-17);
      u.segment<2>(2 * v) = 0.5 * (u.segment<2>(2 * p[0]) + u.segment<2>(2 * p[1]));
    }
    incise::fem::PlaneStressProblem after(mesh.to_mesh_data(), mat, 0.01);
    double e1 = 0.0;
    ASSERT_EQ(after.energy(u, e1), incise::EvalStatus::kOk);
    // Same piecewise-linear field, so the same energy (summation rounding only).
    EXPECT_NEAR(e1, e0, 1e-12 * e0);
  }
  EXPECT_EQ(mesh.parents(0)[0], -1);
}

TEST(NeedleInsertion, WithdrawalReleasesEveryNode) {
  auto sim = make_slab_sim();
  const Vec2 dir(1.0, 0.0);
  int released = 0;
  const double step = 0.003;
  for (double d = -0.003; d <= 0.03; d += step)
    ASSERT_TRUE(sim->step(NeedlePose::make(Vec2(d, 0.05), dir, 0.1)).ok());
  ASSERT_GT(sim->needle_nodes().size(), 5u);
  for (double d = 0.03; d >= -0.006; d -= step) {
    const StepReport rep = sim->step(NeedlePose::make(Vec2(d, 0.05), dir, 0.1));
    ASSERT_TRUE(rep.ok()) << rep.brief();
    released += rep.released;
    expect_valid_mesh(*sim);
  }
  EXPECT_GT(released, 5);
  EXPECT_TRUE(sim->needle_nodes().empty());
}

TEST(NeedleInsertion, RearrangementCapIsAReportedStatus) {
  InsertionOptions o;
  o.max_rearrangements = 0;
  auto sim = make_slab_sim(o);
  const Vec2 dir(1.0, 0.0);
  bool cycled = false;
  for (double d = -0.002; d <= 0.04 && !cycled; d += 0.004) {
    const StepReport rep = sim->step(NeedlePose::make(Vec2(d, 0.05), dir, 0.1));
    if (rep.status == StepStatus::kRearrangementCycle) {
      cycled = true;
      EXPECT_FALSE(rep.message.empty());
      EXPECT_TRUE(sim->displacement().allFinite());
    } else {
      ASSERT_TRUE(rep.ok()) << rep.brief();
    }
  }
  EXPECT_TRUE(cycled);
}

TEST(NeedleInsertion, NonlinearCgAndNeoHookeanRunTheLoop) {
  InsertionOptions o;
  o.relaxation = incise::needle::Relaxation::kNonlinearCg;
  o.epsilon = 1e-4;
  for (const std::string model : {"linear", "neohookean"}) {
    SCOPED_TRACE(model);
    auto sim = make_slab_sim(o, model);
    const Vec2 dir(1.0, -0.2);
    // 0.1 h_ref per update: a needle node moved by a whole element would invert its neighbours
    // in the warm start, which a nonlinear material cannot evaluate (LargeNonlinearStep...).
    for (double d = -0.001; d <= 0.012; d += 0.1 * sim->options().h_ref) {
      const StepReport rep = sim->step(NeedlePose::make(Vec2(0.0, 0.055) + d * dir, dir, 0.1));
      ASSERT_TRUE(rep.ok()) << rep.brief();
      expect_valid_mesh(*sim);
      expect_friction_inequalities(*sim);
    }
    EXPECT_GE(sim->needle_nodes().size(), 2u);  // 12 mm at h_ref = 3.1 mm
  }
}

TEST(NeedleInsertion, LargeNonlinearStepIsAReportedFailure) {
  // Moving the needle nodes by 3 h_ref at once inverts elements of the neo-Hookean warm start
  // (Π = +∞ there): reported, never a crash or NaN displacements.
  InsertionOptions o;
  o.relaxation = incise::needle::Relaxation::kNonlinearCg;
  auto sim = make_slab_sim(o, "neohookean");
  const Vec2 dir(1.0, 0.0);
  bool failed = false;
  for (double d = -0.001; d <= 0.05 && !failed; d += 3 * sim->options().h_ref) {
    const StepReport rep = sim->step(NeedlePose::make(Vec2(d, 0.05), dir, 0.1));
    if (!rep.ok()) {
      failed = true;
      EXPECT_EQ(rep.status, StepStatus::kSolverFailed);
      EXPECT_FALSE(rep.message.empty());
    }
    EXPECT_TRUE(sim->displacement().allFinite());
  }
  EXPECT_TRUE(failed);
}

TEST(NeedleInsertion, RelocationPutsNeedleNodesOnTheShaft) {
  // §6.8.6: intercepted nodes are projected onto the needle (d_perp = 0) and stay there.
  InsertionOptions o;
  o.relocate = true;
  auto sim = make_slab_sim(o);
  const Vec2 dir(1.0, 0.3);
  for (double d = -0.002; d <= 0.03; d += 0.5 * sim->options().h_ref) {
    const NeedlePose pose = NeedlePose::make(Vec2(0.0, 0.04) + d * dir.normalized(), dir, 0.1);
    const StepReport rep = sim->step(pose);
    ASSERT_TRUE(rep.ok()) << rep.brief();
    expect_valid_mesh(*sim);
    const Eigen::Matrix2Xd x = sim->deformed();
    for (const NeedleNode& n : sim->needle_nodes()) {
      // Rounding of 0.1 m coordinates through u = x − X and back (≈ 1e-17 m each).
      EXPECT_LT(std::abs(n.coords.perp), 1e-15);
      EXPECT_LT(std::abs((x.col(n.vertex) - pose.tip).dot(pose.normal())), 1e-15);
    }
  }
  EXPECT_GE(sim->needle_nodes().size(), 5u);
}

TEST(NeedleInsertion, BadInputIsRejected) {
  EXPECT_THROW(NeedlePose::make(Vec2(0, 0), Vec2(0, 0), 0.1), incise::ParameterError);
  EXPECT_THROW(NeedlePose::make(Vec2(0, 0), Vec2(1, 0), 0.0), incise::ParameterError);
  InsertionOptions o;
  o.h_ref = 0.0;
  EXPECT_THROW(make_slab_sim(o), incise::ParameterError);
  EXPECT_THROW(NeedleInsertion(incise::mesh::make_thesis_slab(2), incise::test::needle_material(),
                               -0.01, {}, incise::needle::FrictionProfile{}, InsertionOptions{}),
               incise::ParameterError);
  EXPECT_THROW(
      NeedleInsertion(incise::mesh::make_thesis_slab(2), incise::test::needle_material(), 0.01,
                      {{2, 0.1}}, incise::needle::FrictionProfile{}, InsertionOptions{}),
      incise::ParameterError);
}

}  // namespace
