// AugmentedCutSession (cut/augmented_cut_session.hpp): after every sweep-triangle step the
// augmented solution (Yeung et al. 2016 §3, column replacements of the thesis §3.2 cut
// changes) equals a fresh factorization of the cut mesh's linear-elastic stiffness system,
// assembled independently by fem::ElasticProblem from CutMesh::to_mesh_data and solved with
// Eigen's SimplicialLDLT. Components left without fixed nodes are a status, not a crash.
#include <incise/core/error.hpp>
#include <incise/fem/elastic_problem.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/interactive/refactorization_policy.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_test/augmented_reference.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <thread>

namespace incise::interactive {
namespace {
using incise::test::admissible;
using incise::test::Reference;
using incise::test::reference_solution;
using incise::test::relative_difference;
using incise::test::tolerance;
using namespace incise::cut;  // the session drives the ch. 3 cutter: its types read unqualified
                              // here

/// Random sequences per body: fewer in builds with debug checks (Debug, and the ASan preset:
/// the connectivity validates itself after every edit).
int sequence_count() {
#if INCISE_DEBUG_CHECKS
  return incise::test::scaled(6);
#else
  return incise::test::scaled(16);
#endif
}

material::Material linear_material() {
  material::Parameters p;
  p.youngs_modulus = 1e4;  // Pa; the comparison is relative, E only scales a
  p.poisson_ratio = 0.25;  // thesis §3.3
  return material::Material("linear", p);
}

/// Augmented options of the tests: GMRES tolerance 1e-14 on eq. 17 (as the augmented
/// equivalence tests), so that the comparison measures the method, not a loose stop.
AugmentedCutOptions test_options() {
  AugmentedCutOptions o;
  o.augmented.gmres.tolerance = 1e-14;
  o.augmented.gmres.max_iterations = 2000;
  return o;
}

/// The replaced columns a refactorization removes, the session's §3.6 rule: all of m when the
/// refactored base eliminates the constrained DOFs (AugmentedOptions::eliminate_constrained,
/// on in the session's defaults), else m − |𝓓| (Dirichlet DOFs stay in 𝓛).
int columns_a_refactorization_removes(const AugmentedCutOptions& o,
                                      const AugmentedCutStepReport& r) {
  return r.m_after_solve - (o.augmented.eliminate_constrained ? 0 : r.solve.dirichlet);
}

/// m after a swap when nothing changed while the job ran: 0 with the elimination, |𝓓| without.
int m_left_by_an_unchanged_swap(const AugmentedCutOptions& o, const AugmentedCutStepReport& q) {
  return o.augmented.eliminate_constrained ? 0 : q.solve.dirichlet;
}

struct Body {
  mesh::MeshData mesh;
  std::vector<Index> fixed;
  std::vector<Vec3> forces;
  Vec3 lo, hi;
  int entry_axis = 2;  ///< random blades enter through the face x[entry_axis] = hi
};

/// Cube 1 m, 3³ cells (6-tet split), back face z = 0 fixed, dilating forces on the side faces
/// (the thesis §3.3 setup in small).
Body small_cube() {
  Body b;
  b.mesh = mesh::make_box(3, 3, 3, 1, 1, 1);
  b.lo = Vec3(0, 0, 0);
  b.hi = Vec3(1, 1, 1);
  for (Index v = 0; v < b.mesh.num_points(); ++v) {
    const Vec3 p = b.mesh.points.col(v);
    Vec3 f = Vec3::Zero();
    if (p.z() < 1e-12) b.fixed.push_back(v);
    if (p.x() < 1e-12) f.x() -= 10;
    if (p.x() > 1 - 1e-12) f.x() += 10;
    if (p.y() < 1e-12) f.y() -= 10;
    if (p.y() > 1 - 1e-12) f.y() += 10;
    b.forces.push_back(f);
  }
  return b;
}

/// Beam 0.5 × 0.5 × 2 m, 2 × 2 × 8 cells, clamped at z = 0, tip load in −x at z = 2.
Body beam() {
  Body b;
  b.mesh = mesh::make_box(2, 2, 8, 0.5, 0.5, 2);
  b.lo = Vec3(0, 0, 0);
  b.hi = Vec3(0.5, 0.5, 2);
  b.entry_axis = 0;
  for (Index v = 0; v < b.mesh.num_points(); ++v) {
    const Vec3 p = b.mesh.points.col(v);
    if (p.z() < 1e-12) b.fixed.push_back(v);
    b.forces.push_back(p.z() > 2 - 1e-12 ? Vec3(-5, 0, 1) : Vec3::Zero());
  }
  return b;
}

Eigen::Matrix3Xd force_matrix(const Body& b) {
  Eigen::Matrix3Xd f(3, static_cast<Index>(b.forces.size()));
  for (size_t v = 0; v < b.forces.size(); ++v) f.col(static_cast<Index>(v)) = b.forces[v];
  return f;
}

/// A blade entering through the face x[entry_axis] = hi[entry_axis] (so that the sweep starts
/// at the boundary, §3.2.1), across the body at a random angle and offset, moved 1–3 times
/// towards lo[entry_axis] with random drift and tilt; each move sweeps two triangles (as in
/// robustness_test.cpp). Draws from `rng` in the constructor and in each next_move().
class RandomBlade {
 public:
  RandomBlade(const Body& body, std::mt19937_64& rng) : body_(body), rng_(rng) {
    const Vec3 size = body.hi - body.lo;
    const int ax = body.entry_axis, ay = (ax + 1) % 3, az = (ax + 2) % 3;
    const double angle = 3.14159265358979 * u_(rng);
    Vec3 center = 0.5 * (body.lo + body.hi), dir = Vec3::Zero();
    center(ay) += (u_(rng) - 0.5) * 0.6 * size(ay);
    center(az) += (u_(rng) - 0.5) * 0.6 * size(az);
    center(ax) = body.hi(ax) + 0.05 * size(ax);
    dir(ay) = std::cos(angle) * size(ay);
    dir(az) = std::sin(angle) * size(az);
    a_ = center - dir;
    b_ = center + dir;
    moves_ = 1 + static_cast<int>(u_(rng) * 3);
  }
  /// Number of moves of this blade (1–3).
  int moves() const { return moves_; }
  /// The two sweep triangles of the next move; the blade ends where the move ends.
  std::array<std::array<Vec3, 3>, 2> next_move() {
    const Vec3 size = body_.hi - body_.lo;
    const int ax = body_.entry_axis;
    Vec3 move = 0.1 * size.norm() * Vec3(u_(rng_) - 0.5, u_(rng_) - 0.5, u_(rng_) - 0.5);
    move(ax) = -(0.15 + 0.3 * u_(rng_)) * size(ax);
    Vec3 tilt = Vec3::Zero();
    tilt(ax) = 0.1 * (u_(rng_) - 0.5) * size(ax);
    const Vec3 a2 = a_ + move, b2 = b_ + move + tilt;
    const std::array<std::array<Vec3, 3>, 2> out{std::array<Vec3, 3>{a_, b_, b2}, {a_, b2, a2}};
    a_ = a2;
    b_ = b2;
    return out;
  }

 private:
  const Body& body_;
  std::mt19937_64& rng_;
  std::uniform_real_distribution<double> u_{0.0, 1.0};
  Vec3 a_, b_;
  int moves_ = 1;
};

/// Random sweep sequences (RandomBlade); after every triangle: the augmented solution equals
/// the reference, or the step reports a status.
void random_cuts(const Body& body, int sequences, std::mt19937_64& rng, const char* name) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int compared = 0, cut_steps = 0, failed = 0;
  double worst = 0, max_m = 0;
  for (int s = 0; s < sequences; ++s) {
    AugmentedCutOptions opt = test_options();
    opt.cut.seed = rng();
    opt.cut.remove_degeneracies = u(rng) < 0.7;
    opt.update_deformed = u(rng) < 0.5;
    opt.automatic_refactorization = false;  // updates of K⁰'s factor only (asserted below)
    AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body), opt);
    ASSERT_TRUE(session.initial_report().ok()) << session.initial_report().message;
    const int n0 = session.system().factored_dofs();
    {
      const Reference ref = reference_solution(session, linear_material(), body.forces);
      ASSERT_TRUE(ref.ok);
      ASSERT_LE(relative_difference(session, ref), tolerance(ref)) << name << " initial";
    }
    RandomBlade blade(body, rng);
    for (int k = 0; k < blade.moves(); ++k) {
      for (const std::array<Vec3, 3>& tri : blade.next_move()) {
        const AugmentedCutStepReport r = session.step(tri);
        if (r.cut.faces_dissected > 0) ++cut_steps;
        ASSERT_TRUE(admissible(r));
        if (!r.ok()) {
          ++failed;
          break;
        }
        // Updated without refactoring: the factor in use is still that of K⁰.
        ASSERT_EQ(session.system().factored_dofs(), n0);
        if (opt.update_deformed) {  // the next sweep is placed in x = X + a
          const Index v = session.mesh().num_nodes() - 1;
          ASSERT_EQ(session.mesh().deformed(v),
                    Vec3(session.mesh().reference(v) + session.displacement().col(v)));
        }
        const Reference ref = reference_solution(session, linear_material(), body.forces);
        ASSERT_TRUE(ref.ok) << name << " sequence " << s << ": augmented ok, reference singular"
                            << " m=" << r.solve.m << " amplification " << r.solve.amplification
                            << " gmres its " << r.solve.gmres.iterations << " free comps "
                            << r.cut.free_components << " removed " << r.cut.removed_nodes.size();
        const double d = relative_difference(session, ref);
        worst = std::max(worst, d / tolerance(ref));
        ASSERT_LE(d, tolerance(ref)) << name << " sequence " << s << " move " << k
                                     << " m=" << r.solve.m << " rcond=" << ref.rcond;
        max_m = std::max(max_m, static_cast<double>(r.solve.m));
        ++compared;
      }
      if (failed) break;
    }
    failed = 0;
  }
  // The sequences must cut (a test that never changes the system proves nothing).
  EXPECT_GT(cut_steps, sequences / 4) << name;
  std::cout << name << ": " << sequences << " sequences, " << compared << " steps compared, "
            << cut_steps << " with dissected faces, max m " << max_m
            << ", worst difference / tolerance " << worst << "\n";
}

TEST(AugmentedCut, RandomCutsOnACubeMatchAFreshFactorization) {
  INCISE_SEEDED_RNG(rng, 606);
  random_cuts(small_cube(), sequence_count(), rng, "cube");
}

TEST(AugmentedCut, RandomCutsOnABeamMatchAFreshFactorization) {
  INCISE_SEEDED_RNG(rng, 607);
  random_cuts(beam(), sequence_count(), rng, "beam");
}

/// Polls session.solve() until no background refactorization is pending (each solve swaps a
/// finished job in); returns the report of the last solve. Ends when the job has finished: the
/// session does not restart a job in the solve that dropped a failed one.
AugmentedCutStepReport poll_until_swapped(AugmentedCutSession& session, int& polls) {
  AugmentedCutStepReport q = session.solve();
  ++polls;
  while (!q.refactorization_swapped && session.system().refactorization_pending()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    q = session.solve();
    ++polls;
  }
  return q;
}

/// Augmented paper §3.6 with AugmentedCutOptions::refactor_at_m: random cuts in the small cube
/// with a small threshold (a) start background refactorizations, each swapped in by a later
/// solve(); (b) m drops at the swap, to |𝓓| since nothing changed while the job ran, and the
/// factor then covers every DOF; (c) after every step and every swap the solution equals a fresh
/// factorization of the current system (reference_solution, tolerance()). Deterministic: after
/// a step that started a job, session.solve() is polled until no job is pending; how many polls
/// that takes depends on timing, and nothing asserted does.
TEST(AugmentedCut, Sec3_6BackgroundRefactorizationAtThresholdMatchesAFreshFactorization) {
  INCISE_SEEDED_RNG(rng, 608);
  const Body body = small_cube();
  // Columns a refactorization can remove (m − |𝓓|) that trigger one: small against the
  // 50–150 columns one cutting step of the 3³ cube replaces, so that most cutting steps start one.
  constexpr int kThreshold = 24;
  const int sequences = incise::test::scaled(4);
  int started = 0, swapped = 0, compared = 0, polls = 0;
  for (int s = 0; s < sequences; ++s) {
    AugmentedCutOptions opt = test_options();
    opt.cut.seed = rng();
    opt.refactor_at_m = kThreshold;
    AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body), opt);
    ASSERT_TRUE(session.initial_report().ok()) << session.initial_report().message;
    auto compare = [&](const char* when, int k) {
      const Reference ref = reference_solution(session, linear_material(), body.forces);
      ASSERT_TRUE(ref.ok) << when << ", sequence " << s << " move " << k;
      ASSERT_LE(relative_difference(session, ref), tolerance(ref))
          << when << ", sequence " << s << " move " << k << " rcond=" << ref.rcond;
      ++compared;
    };
    RandomBlade blade(body, rng);
    bool failed = false;
    for (int k = 0; k < blade.moves() && !failed; ++k) {
      for (const std::array<Vec3, 3>& tri : blade.next_move()) {
        // Every started job was swapped in below: none is pending at a step.
        ASSERT_FALSE(session.system().refactorization_pending());
        const AugmentedCutStepReport r = session.step(tri);
        ASSERT_TRUE(admissible(r));
        if (!r.ok()) {
          failed = true;
          break;
        }
        ASSERT_FALSE(r.refactorization_swapped);
        ASSERT_EQ(r.refactorization_started,
                  r.solved && columns_a_refactorization_removes(opt, r) >= kThreshold)
            << "m " << r.m_after_solve << " |D| " << r.solve.dirichlet;
        ASSERT_NO_FATAL_FAILURE(compare("after the step", k));
        if (!r.refactorization_started) continue;
        ++started;
        ASSERT_TRUE(session.system().refactorization_pending());
        // (a) Poll: each solve() swaps the job in if it has finished.
        const AugmentedCutStepReport q = poll_until_swapped(session, polls);
        ASSERT_TRUE(q.ok()) << q.message;
        ASSERT_FALSE(q.refactorization_started);  // m′ = 0 after the swap
        ASSERT_TRUE(q.refactorization_swapped)
            << "background factorization failed: "
            << static_cast<int>(session.system().last_refactorization_status());
        ++swapped;
        // (b) m drops to what the swap cannot remove; the new factor covers all current DOFs.
        EXPECT_LT(q.m_after_solve, q.m_before_solve);
        EXPECT_EQ(q.m_before_solve, r.m_after_solve);
        EXPECT_EQ(q.m_after_solve, m_left_by_an_unchanged_swap(opt, q));
        EXPECT_EQ(session.system().factored_dofs(), session.system().num_dofs());
        // (c) The solution with the new factor.
        ASSERT_NO_FATAL_FAILURE(compare("after the swap", k));
      }
    }
  }
  EXPECT_GE(started, 1);
  EXPECT_EQ(swapped, started);
  std::cout << "cube, refactor_at_m " << kThreshold << ": " << sequences << " sequences, "
            << started << " refactorizations started and swapped in, " << compared
            << " solutions compared, " << polls << " polling solves\n";
}

/// Issue 18 (resource limits): AugmentedOptions::cholmod.memory_budget_bytes reaches the
/// factorization of K⁰. A budget of 1 KiB, below the estimate of the symbolic analysis,
/// refuses it: the initial report fails with the estimate and the budget in its message, the
/// system reports kOverMemoryBudget, and a step does not solve.
TEST(AugmentedCut, MemoryBudgetRefusesTheInitialFactorizationWithTheEstimate) {
  const Body body = beam();
  AugmentedCutOptions opt = test_options();
  opt.augmented.cholmod.memory_budget_bytes = 1024;
  AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body), opt);
  const AugmentedCutStepReport& init = session.initial_report();
  EXPECT_EQ(init.status, CutSolveStatus::kSolverFailed);
  EXPECT_EQ(session.system().factorization_status(), linalg::FactorStatus::kOverMemoryBudget);
  EXPECT_NE(init.message.find("over memory budget: the numeric factorization needs an estimated"),
            std::string::npos)
      << init.message;
  EXPECT_NE(init.message.find("more than the memory budget of 0.0009766 MiB"), std::string::npos)
      << init.message;
  const double z = 1.1;
  const AugmentedCutStepReport r = session.step(Vec3(-1, -1, z), Vec3(2, -1, z), Vec3(2, 2, z));
  EXPECT_FALSE(r.ok());
  // Without the budget the same session factors and solves.
  AugmentedCutSession free(body.mesh, linear_material(), body.fixed, force_matrix(body),
                           test_options());
  EXPECT_TRUE(free.initial_report().ok()) << free.initial_report().brief();
}

/// A horizontal blade through the whole beam at z = 1.1 m: the upper part loses its fixed
/// nodes. Policy kReport: reported as kFreeComponent, no solve, no crash.
TEST(AugmentedCut, BeamCutInTwoWithReportPolicyIsAStatus) {
  const Body body = beam();
  AugmentedCutOptions opt = test_options();
  opt.cut.free_components = FreeComponentPolicy::kReport;
  AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body), opt);
  ASSERT_TRUE(session.initial_report().ok());
  const double z = 1.1;
  const AugmentedCutStepReport r1 = session.step(Vec3(-1, -1, z), Vec3(2, -1, z), Vec3(2, 2, z));
  const AugmentedCutStepReport r2 = session.step(Vec3(-1, -1, z), Vec3(2, 2, z), Vec3(-1, 2, z));
  EXPECT_GT(r1.cut.faces_dissected + r2.cut.faces_dissected, 0);
  EXPECT_EQ(r2.status, CutSolveStatus::kFreeComponent) << to_string(r2.status);
  EXPECT_FALSE(r2.solved);
  EXPECT_FALSE(r2.message.empty());
  EXPECT_GE(r2.free_components, 1);
}

/// The same cut with policy kFixOnFace: the upper part is fixed on a face at its current
/// displacement (Dirichlet constraints of the augmented system) and the solution equals the
/// reference with those prescribed values.
TEST(AugmentedCut, BeamCutInTwoWithFixOnFaceMatchesTheReference) {
  const Body body = beam();
  AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body),
                              test_options());
  const double z = 1.1;
  const AugmentedCutStepReport r1 = session.step(Vec3(-1, -1, z), Vec3(2, -1, z), Vec3(2, 2, z));
  const AugmentedCutStepReport r2 = session.step(Vec3(-1, -1, z), Vec3(2, 2, z), Vec3(-1, 2, z));
  ASSERT_TRUE(r1.ok()) << r1.message;
  ASSERT_TRUE(r2.ok()) << r2.message;
  EXPECT_GT(r1.cut.components_fixed + r2.cut.components_fixed, 0);
  EXPECT_GT(r1.constrained_fixed + r2.constrained_fixed, 0);
  EXPECT_GT(r1.dofs_added + r2.dofs_added, 0);
  const Reference ref = reference_solution(session, linear_material(), body.forces);
  ASSERT_TRUE(ref.ok);
  EXPECT_LE(relative_difference(session, ref), tolerance(ref));
}

/// §3.6 with Dirichlet DOFs: the beam cut in two, the upper part fixed on a face
/// (FreeComponentPolicy::kFixOnFace), so its stiffness block is singular (rigid motions) and
/// held only by the constraints. Refactorizations started before and after the separation are
/// swapped in (the session's constraint springs keep K positive definite), and the solution
/// equals the reference. The session eliminates the DOFs constrained at a snapshot in the
/// refactored base (AugmentedOptions::eliminate_constrained, on in interactive_options()), so
/// after a swap with nothing changed m = 0 while |𝓓| stays.
TEST(AugmentedCut, Sec3_6RefactorizationAfterAPieceIsFixedOnAFace) {
  const Body body = beam();
  AugmentedCutOptions opt = test_options();
  opt.refactor_at_m = 1;  // any replaced column triggers a job
  AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body), opt);
  const double z = 1.1;
  int polls = 0;
  Index constrained = 0;
  for (const std::array<Vec3, 3>& tri :
       {std::array<Vec3, 3>{Vec3(-1, -1, z), Vec3(2, -1, z), Vec3(2, 2, z)},
        {Vec3(-1, -1, z), Vec3(2, 2, z), Vec3(-1, 2, z)}}) {
    const AugmentedCutStepReport r = session.step(tri);
    ASSERT_TRUE(r.ok()) << r.message;
    constrained += r.constrained_fixed;
    if (!r.refactorization_started) continue;  // the first triangle may only mark edges
    const AugmentedCutStepReport q = poll_until_swapped(session, polls);
    ASSERT_TRUE(q.ok()) << q.message;
    ASSERT_TRUE(q.refactorization_swapped)
        << "background factorization failed, FactorStatus "
        << static_cast<int>(session.system().last_refactorization_status());
    // Nothing changed while the job ran: every constrained DOF is eliminated, none augmented.
    // (q's solve statistics may predate the swap when the job finished during that solve and
    // poll_after_solve swapped it in after it; m_after_solve is taken after the poll.)
    EXPECT_EQ(q.m_after_solve, 0);
    const Reference ref = reference_solution(session, linear_material(), body.forces);
    ASSERT_TRUE(ref.ok);
    EXPECT_LE(relative_difference(session, ref), tolerance(ref));
  }
  // The separating step fixed the upper part on a face, started a job and had it swapped in
  // (above) with those constraints in K's snapshot.
  EXPECT_GT(constrained, 0);
  EXPECT_GT(session.system().factored_dofs(), 0);
  EXPECT_EQ(session.system().factored_dofs(), session.system().num_dofs());
  EXPECT_EQ(session.system().num_replaced(), 0);
  // A solve on the swapped-in base: all constrained DOFs eliminated in it, none in 𝓛.
  const AugmentedCutStepReport last = session.solve();
  ASSERT_TRUE(last.ok()) << last.message;
  EXPECT_EQ(last.solve.dirichlet, static_cast<int>(constrained));
  EXPECT_EQ(last.solve.dirichlet_eliminated, last.solve.dirichlet);
  EXPECT_EQ(last.m_after_solve, 0);
}

TEST(AugmentedCut, NonLinearMaterialIsRejected) {
  const Body body = small_cube();
  material::Parameters p;
  p.youngs_modulus = 1e4;
  p.poisson_ratio = 0.25;
  EXPECT_THROW(AugmentedCutSession(body.mesh, material::Material("neohookean", p), body.fixed,
                                   force_matrix(body)),
               ParameterError);
}

TEST(AugmentedCut, NoFixedNodesIsAStatusNotACrash) {
  const Body body = small_cube();
  AugmentedCutSession session(body.mesh, linear_material(), {}, force_matrix(body), test_options());
  EXPECT_EQ(session.initial_report().status, CutSolveStatus::kSolverFailed);
  EXPECT_NE(session.initial_report().message.find("not positive definite"), std::string::npos)
      << session.initial_report().message;
  const AugmentedCutStepReport r =
      session.step(Vec3(0.5, -1, 2), Vec3(0.5, 2, 2), Vec3(0.5, 2, 0.5));
  EXPECT_FALSE(r.ok());
}

// A CHOLMOD warning on K⁰ is a failed initial factorization, not a solve on a perturbed
// factor: a pivot bound above every pivot of K⁰ (CHOLMOD_DSMALL on all of them) makes the
// initial report kSolverFailed, naming the tiny-pivot status and CHOLMOD's message.
TEST(AugmentedCut, TinyPivotWarningOnK0IsAFailedInitialReport) {
  const Body body = small_cube();
  AugmentedCutOptions o = test_options();
  o.augmented.cholmod.kind = linalg::CholmodKind::kSimplicialLdl;  // the bound applies there
  o.augmented.cholmod.pivot_bound = 1e30;  // N/m; every pivot of K⁰ (E = 1e4 Pa) is below
  AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body), o);
  const AugmentedCutStepReport& init = session.initial_report();
  EXPECT_EQ(init.status, CutSolveStatus::kSolverFailed);
  EXPECT_EQ(init.solve.status, linalg::AugmentedStatus::kNoFactor);
  EXPECT_NE(init.message.find("tiny pivot: CHOLMOD_DSMALL"), std::string::npos) << init.message;
  EXPECT_EQ(session.displacement(), Eigen::Matrix3Xd::Zero(3, body.mesh.num_points()));
}

// The break-even rule of §3.6 (refactorization_policy.hpp) on hand-fed costs: floor = the
// cheapest update of the period, excess = Σ (cost − floor); a start once excess ≥ T_f > 0.
TEST(RefactorizationPolicy, Sec3_6BreakEvenRuleOnInjectedCosts) {
  RefactorizationPolicy p(RefactorizationMode::kBreakEven);
  EXPECT_FALSE(p.should_start(1.0));  // nothing observed
  p.observe(2.0, false);              // floor 2, excess 0
  p.observe(1.0, false);              // floor 1 (cheaper), excess 0 + 0
  EXPECT_EQ(p.floor(), 1.0);
  EXPECT_EQ(p.excess(), 0.0);
  p.observe(2.0, false);  // excess 1
  p.observe(4.0, false);  // excess 1 + 3 = 4
  EXPECT_EQ(p.excess(), 4.0);
  EXPECT_FALSE(p.should_start(4.5));
  EXPECT_TRUE(p.should_start(4.0));
  EXPECT_FALSE(p.should_start(0.0));  // an unknown (zero) factorization cost never starts one
  EXPECT_FALSE(p.should_start(std::numeric_limits<double>::quiet_NaN()));
  p.observe(3.0, true);  // a swapped-in factor: new period, floor 3
  EXPECT_EQ(p.floor(), 3.0);
  EXPECT_EQ(p.excess(), 0.0);
  EXPECT_FALSE(p.should_start(1e-300));
  EXPECT_THROW(p.observe(-1.0, false), ParameterError);
  EXPECT_THROW(p.observe(std::numeric_limits<double>::infinity(), false), ParameterError);
  p.reset();
  EXPECT_EQ(p.excess(), 0.0);
  EXPECT_TRUE(std::isinf(p.floor()));
}

/// The automatic §3.6 policy (on by default) with an injected cost model — update cost m
/// (columns), factorization cost kFactor — starts the first background refactorization exactly
/// at the first solve where Σ (m − min m) reaches kFactor (computed here from the reports),
/// never while one is pending; after each swap m drops and the period restarts; every solution
/// equals a fresh factorization's. Deterministic: counts, no clocks (a job is waited for).
TEST(AugmentedCut, Sec3_6AutomaticPolicyStartsAtTheBreakEvenSolveAndStaysExact) {
  INCISE_SEEDED_RNG(rng, 609);
  const Body body = small_cube();
  constexpr double kFactor = 150;  // "seconds" of one factorization: a few cutting steps' m
  const int sequences = incise::test::scaled(3);
  int started = 0, swapped = 0;
  for (int s = 0; s < sequences; ++s) {
    AugmentedCutOptions opt = test_options();
    ASSERT_TRUE(opt.automatic_refactorization);  // the default
    ASSERT_EQ(opt.refactor_at_m, 0);
    opt.refactorization_mode = RefactorizationMode::kBreakEven;
    opt.cut.seed = rng();
    opt.update_cost = [](const linalg::AugmentedReport& r) { return static_cast<double>(r.m); };
    opt.factorization_cost = [](const linalg::AugmentedSystem&) { return kFactor; };
    AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body), opt);
    ASSERT_TRUE(session.initial_report().ok()) << session.initial_report().message;
    // The model's own bookkeeping, independent of the policy's: from the initial solve on.
    double floor = session.initial_report().solve.m, excess = 0;
    RandomBlade blade(body, rng);
    for (int k = 0; k < blade.moves(); ++k) {
      for (const std::array<Vec3, 3>& tri : blade.next_move()) {
        ASSERT_FALSE(session.system().refactorization_pending());  // waited for below
        const AugmentedCutStepReport r = session.step(tri);
        ASSERT_TRUE(admissible(r));
        if (!r.ok()) break;
        if (r.solved) {
          floor = std::min(floor, static_cast<double>(r.solve.m));
          excess += r.solve.m - floor;
        }
        const bool expect_start =
            r.solved && excess >= kFactor && columns_a_refactorization_removes(opt, r) > 0;
        ASSERT_EQ(r.refactorization_started, expect_start)
            << "excess " << excess << " m " << r.solve.m << " floor " << floor;
        EXPECT_EQ(session.refactorization_policy().excess(), excess);
        const Reference ref = reference_solution(session, linear_material(), body.forces);
        ASSERT_TRUE(ref.ok);
        ASSERT_LE(relative_difference(session, ref), tolerance(ref)) << "sequence " << s;
        if (!r.refactorization_started) continue;
        ++started;
        ASSERT_TRUE(session.wait_for_refactorization())
            << static_cast<int>(session.system().last_refactorization_status());
        ++swapped;
        EXPECT_EQ(session.refactorization_policy().excess(), 0.0);  // a new period
        floor = std::numeric_limits<double>::infinity();
        excess = 0;
        const AugmentedCutStepReport q = session.solve();
        ASSERT_TRUE(q.ok()) << q.message;
        EXPECT_EQ(q.m_after_solve, m_left_by_an_unchanged_swap(opt, q));  // nothing changed
        floor = std::min(floor, static_cast<double>(q.solve.m));
        excess += q.solve.m - floor;
        const Reference after = reference_solution(session, linear_material(), body.forces);
        ASSERT_TRUE(after.ok);
        ASSERT_LE(relative_difference(session, after), tolerance(after));
      }
    }
  }
  EXPECT_GE(started, 1);  // the model must trigger, or the test proves nothing
  EXPECT_EQ(swapped, started);
}

// SynchronousRefactorRule (issue 17): c(m, k) = ⅔m³/r + γk + ρm from what it is fed — NaN (never
// refactor) until r, γ and ρ are known; a fresh LU below kMinRateM or fewer than kMinColumns new
// columns do not set r or γ; the later observation replaces the earlier; should_refactor is
// c > the refactorization's cost > 0.
TEST(RefactorizationPolicy, SynchronousRuleOnInjectedCosts) {
  SynchronousRefactorRule rule;
  EXPECT_TRUE(std::isnan(rule.predict(1000, 100)));
  EXPECT_FALSE(rule.should_refactor(1000, 100, 1e-9));
  // m = 100 < kMinRateM: no rate; k = 10 < kMinColumns: no γ; ρ = (3 − 1 − 0.5) / 100.
  rule.observe(100, 10, 3.0, 1.0, true, 0.5);
  EXPECT_TRUE(std::isnan(rule.lu_rate()));
  EXPECT_TRUE(std::isnan(rule.column_cost()));
  EXPECT_DOUBLE_EQ(rule.rest_per_column(), 0.015);
  EXPECT_TRUE(std::isnan(rule.predict(1000, 100)));
  // m = 300, fresh LU of 2 s: r = ⅔·300³/2 = 9e6; k = 40 in 4 s: γ = 0.1; ρ = (10 − 2 − 4)/300.
  rule.observe(300, 40, 10.0, 2.0, true, 4.0);
  EXPECT_DOUBLE_EQ(rule.lu_rate(), 9e6);
  EXPECT_DOUBLE_EQ(rule.column_cost(), 0.1);
  const double rho = 4.0 / 300;
  EXPECT_DOUBLE_EQ(rule.rest_per_column(), rho);
  const double c = (2.0 / 3.0) * 600.0 * 600.0 * 600.0 / 9e6 + 0.1 * 50 + rho * 600;  // 16 + 5 + 8
  EXPECT_DOUBLE_EQ(rule.predict(600, 50), c);
  EXPECT_TRUE(rule.should_refactor(600, 50, c - 1e-9));
  EXPECT_FALSE(rule.should_refactor(600, 50, c));
  EXPECT_FALSE(rule.should_refactor(600, 50, 0.0));  // no measured refactorization: never
  // An updated (not fresh) capacitance factorization keeps r; the next ρ and γ replace the old.
  rule.observe(400, 20, 5.0, 0.5, false, 1.0);
  EXPECT_DOUBLE_EQ(rule.lu_rate(), 9e6);
  EXPECT_DOUBLE_EQ(rule.column_cost(), 0.05);
  EXPECT_DOUBLE_EQ(rule.rest_per_column(), 3.5 / 400);
}

// The synchronous choice in the session (AugmentedCutOptions::synchronous_refactorization, on by
// default) with an injected cost model — solve cost m + k (columns, new columns of G), a
// refactorization kSync — and no background job (break-even with an infinite factorization
// cost): before each solve the current K is refactored exactly when m + k > kSync (m, k as the
// session sees them: m_before_solve, and columns_without_g() recomputed from the last state);
// after it m is 0 (|𝓓| without the elimination), the step reports the swap, and every
// solution equals a fresh factorization's. Deterministic: counts, no clocks.
TEST(AugmentedCut, SynchronousRefactorizationOnInjectedCostsStaysExact) {
  INCISE_SEEDED_RNG(rng, 1717);
  const Body body = small_cube();
  constexpr double kSync = 120;  // "seconds" of a refactorization: about two cutting steps
  const int sequences = incise::test::scaled(5);
  int synced = 0, skipped = 0;
  for (int s = 0; s < sequences; ++s) {
    const int synced_before = synced;
    AugmentedCutOptions opt = test_options();
    ASSERT_TRUE(opt.synchronous_refactorization);  // the default
    opt.refactorization_mode = RefactorizationMode::kBreakEven;
    opt.factorization_cost = [](const linalg::AugmentedSystem&) {
      return std::numeric_limits<double>::infinity();
    };
    opt.cut.seed = rng();
    int last_k = -1;  // k the model saw at the last decision
    opt.synchronous_solve_cost = [&last_k](int m, int k) {
      last_k = k;
      return static_cast<double>(m + k);
    };
    opt.synchronous_refactor_cost = [](const linalg::AugmentedSystem&) { return kSync; };
    AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body), opt);
    ASSERT_TRUE(session.initial_report().ok()) << session.initial_report().message;
    RandomBlade blade(body, rng);
    for (int k = 0; k < blade.moves(); ++k) {
      for (const std::array<Vec3, 3>& tri : blade.next_move()) {
        last_k = -1;
        const AugmentedCutStepReport r = session.step(tri);
        ASSERT_TRUE(admissible(r));
        if (!r.ok()) break;
        EXPECT_FALSE(r.refactorization_started);  // no background job in this model
        if (!r.solved) continue;
        if (r.m_before_solve == 0) {
          EXPECT_EQ(last_k, -1);  // nothing to decide
          EXPECT_FALSE(r.synchronous_refactorization);
          continue;
        }
        ASSERT_GE(last_k, 0);
        const bool expect = r.m_before_solve + last_k > kSync;
        ASSERT_EQ(r.synchronous_refactorization, expect)
            << "m " << r.m_before_solve << " k " << last_k;
        if (expect) {
          ++synced;
          EXPECT_TRUE(r.refactorization_swapped);
          EXPECT_EQ(r.m_after_solve, m_left_by_an_unchanged_swap(opt, r));
          EXPECT_EQ(r.solve.m, m_left_by_an_unchanged_swap(opt, r));
        } else {
          ++skipped;
          EXPECT_FALSE(r.refactorization_swapped);
        }
        const Reference ref = reference_solution(session, linear_material(), body.forces);
        ASSERT_TRUE(ref.ok);
        ASSERT_LE(relative_difference(session, ref), tolerance(ref)) << "sequence " << s;
      }
    }
    EXPECT_EQ(session.synchronous_refactorizations(), synced - synced_before);
  }
  EXPECT_GE(synced, 1);   // the model must trigger, or the test proves nothing
  EXPECT_GE(skipped, 1);  // and not always
}

// RefactorizationMode::kContinuous: a start whenever asked (the caller checks m − |𝓓| > 0 and
// that no job is pending), the costs still recorded; it is the default (with prepare_swap).
TEST(RefactorizationPolicy, Sec3_6ContinuousModeAlwaysStartsAndIsTheDefault) {
  EXPECT_EQ(RefactorizationPolicy().mode(), RefactorizationMode::kContinuous);
  EXPECT_EQ(AugmentedCutOptions().refactorization_mode, RefactorizationMode::kContinuous);
  EXPECT_TRUE(AugmentedCutOptions().augmented.prepare_swap);  // the session prepares its swaps
  RefactorizationPolicy p(RefactorizationMode::kContinuous);
  EXPECT_TRUE(p.should_start(1.0));  // nothing observed, no excess
  p.observe(2.0, false);
  p.observe(5.0, false);
  EXPECT_EQ(p.excess(), 3.0);
  EXPECT_TRUE(p.should_start(1e9));
  EXPECT_TRUE(p.should_start(0.0));
  EXPECT_STREQ(to_string(RefactorizationMode::kContinuous), "continuous");
  EXPECT_EQ(kRefactorizationModeNames.find("break-even"), RefactorizationMode::kBreakEven);
}

/// Continuous mode in the session: after every solve that leaves m > |𝓓| with no job pending a
/// background refactorization starts (the test waits for each, so m drops to |𝓓|), and every
/// solution equals a fresh factorization's. Deterministic: no clocks decide (jobs are waited for).
TEST(AugmentedCut, Sec3_6ContinuousPolicyStartsAfterEverySolveThatLeavesColumnsAndStaysExact) {
  INCISE_SEEDED_RNG(rng, 611);
  const Body body = small_cube();
  int started = 0;
  AugmentedCutOptions opt = test_options();
  ASSERT_EQ(opt.refactorization_mode, RefactorizationMode::kContinuous);  // the default
  opt.cut.seed = rng();
  AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body), opt);
  ASSERT_TRUE(session.initial_report().ok()) << session.initial_report().message;
  RandomBlade blade(body, rng);
  for (int k = 0; k < blade.moves(); ++k) {
    for (const std::array<Vec3, 3>& tri : blade.next_move()) {
      ASSERT_FALSE(session.system().refactorization_pending());  // waited for below
      const AugmentedCutStepReport r = session.step(tri);
      ASSERT_TRUE(admissible(r));
      if (!r.ok()) break;
      ASSERT_EQ(r.refactorization_started,
                r.solved && columns_a_refactorization_removes(opt, r) > 0)
          << "m " << r.m_after_solve << " |D| " << r.solve.dirichlet;
      const Reference ref = reference_solution(session, linear_material(), body.forces);
      ASSERT_TRUE(ref.ok);
      ASSERT_LE(relative_difference(session, ref), tolerance(ref));
      if (!r.refactorization_started) continue;
      ++started;
      ASSERT_TRUE(session.wait_for_refactorization());
      const AugmentedCutStepReport q = session.solve();
      ASSERT_TRUE(q.ok()) << q.message;
      EXPECT_EQ(q.m_after_solve, m_left_by_an_unchanged_swap(opt, q));  // nothing changed
      EXPECT_FALSE(q.refactorization_started);                          // nothing left to remove
      const Reference after = reference_solution(session, linear_material(), body.forces);
      ASSERT_TRUE(after.ok);
      ASSERT_LE(relative_difference(session, after), tolerance(after));
    }
  }
  EXPECT_GE(started, 2);  // the blade must change the system, or the test proves nothing
}

/// refactor_at_m > 0 overrides the automatic policy; automatic_refactorization = false with
/// refactor_at_m = 0 never refactors — with a cost model that would start a job at every solve.
TEST(AugmentedCut, Sec3_6RefactorAtMOverridesTheAutomaticPolicy) {
  const Body body = small_cube();
  for (const bool automatic : {true, false}) {
    AugmentedCutOptions opt = test_options();
    opt.automatic_refactorization = automatic;
    opt.refactor_at_m = automatic ? 1000000 : 0;
    opt.update_cost = [](const linalg::AugmentedReport& r) { return static_cast<double>(r.m); };
    opt.factorization_cost = [](const linalg::AugmentedSystem&) { return 1e-300; };
    AugmentedCutSession session(body.mesh, linear_material(), body.fixed, force_matrix(body), opt);
    int solved = 0;
    for (const std::array<Vec3, 3>& tri :
         {std::array<Vec3, 3>{Vec3(0.3, -0.1, 1.2), Vec3(0.3, -0.1, 0.5), Vec3(0.3, 1.1, 0.5)},
          {Vec3(0.3, -0.1, 1.2), Vec3(0.3, 1.1, 0.5), Vec3(0.3, 1.1, 1.2)}}) {
      const AugmentedCutStepReport r = session.step(tri);
      ASSERT_TRUE(r.ok()) << r.message;
      solved += r.solved && r.solve.m > 0;
      EXPECT_FALSE(r.refactorization_started);
    }
    EXPECT_GT(solved, 0);  // the model would have started a job at these solves
    EXPECT_FALSE(session.system().refactorization_pending());
  }
}

}  // namespace
}  // namespace incise::interactive
