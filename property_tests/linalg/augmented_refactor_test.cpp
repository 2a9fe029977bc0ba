/// \file augmented_refactor_test.cpp
/// Background re-factorization of Yeung et al. 2016 §3.6: while a second thread (own CHOLMOD
/// common) factors a snapshot of K, updates and solves continue; when its factor is swapped in,
/// m drops to the columns changed since the snapshot (plus the Dirichlet DOFs, which stay
/// augmented), and solutions stay equal to a fresh factorization. Built also with the `tsan`
/// preset (ThreadSanitizer) — see docs/augmented.md.

#include "augmented_reference.hpp"
#include "augmented_stand_in.hpp"

#include <incise/mesh/generators.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <random>
#include <set>
#include <thread>

namespace incise::test {
namespace {

/// Same justification as in augmented_equivalence_test.cpp (tiny meshes, GMRES tol 1e-13).
constexpr double kRefactorRelTol = 1e-9;

/// Duplicates node p (§4.3.2) for elements with centroid x > x_p; returns false if no split.
bool cut_node(CutModel& m, linalg::AugmentedSystem& aug, int p, std::set<int>* touched = nullptr) {
  std::vector<int> moved;
  int star = 0;
  for (size_t e = 0; e < m.tets.size(); ++e) {
    bool inc = false;
    double cx = 0;
    for (int a = 0; a < 4; ++a) {
      inc = inc || m.tets[e][a] == p;
      cx += 0.25 * m.points(0, m.tets[e][a]);
    }
    if (!inc || !m.active[e]) continue;
    ++star;
    if (cx > m.points(0, p)) moved.push_back(static_cast<int>(e));
  }
  if (moved.empty() || static_cast<int>(moved.size()) == star) return false;
  const int q = static_cast<int>(m.points.cols());
  m.points.conservativeResize(3, q + 1);
  m.points.col(q) = m.points.col(p);
  m.node_dof.push_back(aug.add_dofs(3));
  m.num_dofs += 3;
  for (int e : moved) {
    aug.add_element(m.dofs(e), m.element_matrix(e), -1.0);
    if (touched) {
      for (int d : m.dofs(e))
        if (d >= 0) touched->insert(d);
    }
    for (int a = 0; a < 4; ++a) {
      if (m.tets[e][a] == p) m.tets[e][a] = q;
    }
    aug.add_element(m.dofs(e), m.element_matrix(e), +1.0);
    if (touched) {
      for (int d : m.dofs(e))
        if (d >= 0) touched->insert(d);
    }
  }
  return true;
}

void expect_equivalent(linalg::AugmentedSystem& aug, const CutModel& m, Eigen::VectorXd& f,
                       const std::map<int, double>& dir) {
  if (f.size() != m.num_dofs) {
    const Eigen::Index old = f.size();
    f.conservativeResize(m.num_dofs);
    f.tail(m.num_dofs - old).setConstant(0.5);
  }
  aug.set_force(f);
  Eigen::VectorXd a, r;
  const linalg::AugmentedReport rep = aug.solve(a, r);
  ASSERT_TRUE(rep.ok()) << rep.message;
  const ReferenceSolution ref = reference_solve(m.assemble(), f, dir);
  ASSERT_TRUE(ref.ok);
  EXPECT_LE((a - ref.a).norm(), kRefactorRelTol * ref.a.norm());
  EXPECT_LE((r - ref.r).norm(), kRefactorRelTol * (ref.r.norm() + f.norm()));
}

/// The beam of the §3.6 tests below: make_beam(8, 0.1), an AugmentedSystem with `options` and
/// f = 0.25. start(): K⁰ factored; `plane` ← the nodes with DOFs on the mid-plane x = 0.2 (at
/// least `need` of them), the first three cut (§4.3.2), u₀ = 0.01 imposed, and the solve checked
/// against a fresh factorization. Call start() through ASSERT_NO_FATAL_FAILURE; the tests bind
/// the members by `auto& [m, aug, f, dir, plane] = beam`.
struct MidPlaneBeam {
  CutModel m = CutModel::from_mesh(mesh::make_beam(8, 0.1));
  linalg::AugmentedSystem aug;
  Eigen::VectorXd f;
  std::map<int, double> dir;
  std::vector<int> plane;

  explicit MidPlaneBeam(const linalg::AugmentedOptions& options = {})
      : aug(options), f(Eigen::VectorXd::Constant(m.num_dofs, 0.25)) {}
  void start(std::size_t need) {
    ASSERT_EQ(aug.initialize(m.assemble()), linalg::FactorStatus::kOk);
    for (int v = 0; v < static_cast<int>(m.points.cols()); ++v)
      if (std::abs(m.points(0, v) - 0.2) < 1e-9 && m.node_dof[v] >= 0) plane.push_back(v);
    ASSERT_GE(plane.size(), need);
    for (int k = 0; k < 3; ++k) ASSERT_TRUE(cut_node(m, aug, plane[k]));
    aug.impose_dirichlet(0, 0.01);
    dir[0] = 0.01;
    expect_equivalent(aug, m, f, dir);
  }
};

// §3.6, Fig. 1: m + m′ drops to m′ when the fresh factor replaces the old one.
TEST(AugmentedRefactor, SwapDropsMToChangesSinceStartSec3_6) {
  MidPlaneBeam beam;
  ASSERT_NO_FATAL_FAILURE(beam.start(6));
  auto& [m, aug, f, dir, plane] = beam;
  const int m_before = aug.num_replaced();
  ASSERT_TRUE(aug.start_refactorization());
  EXPECT_FALSE(aug.start_refactorization());  // one job at a time
  // Changes while the job runs: one more cut (its columns must stay augmented).
  const int nb_before = aug.num_dofs();
  std::set<int> touched;
  ASSERT_TRUE(cut_node(m, aug, plane[3], &touched));
  ASSERT_TRUE(aug.wait_for_refactorization());
  EXPECT_EQ(aug.last_refactorization_status(), linalg::FactorStatus::kOk);
  EXPECT_EQ(aug.factored_dofs(), nb_before);
  const int m_after = aug.num_replaced();
  EXPECT_LT(m_after, m_before);
  // Remaining columns: those changed by the 4th cut and the Dirichlet DOF.
  for (int j : aug.replaced_columns()) EXPECT_TRUE(j == 0 || touched.count(j) != 0) << j;
  expect_equivalent(aug, m, f, dir);
  // With no change since a second snapshot, only the Dirichlet DOF stays in 𝓛.
  ASSERT_TRUE(aug.start_refactorization());
  ASSERT_TRUE(aug.wait_for_refactorization());
  EXPECT_EQ(aug.num_replaced(), 1);
  expect_equivalent(aug, m, f, dir);
  aug.release_dirichlet(0);
  dir.clear();
  EXPECT_EQ(aug.num_replaced(), 0);
  expect_equivalent(aug, m, f, dir);
}

// AugmentedOptions::eliminate_constrained (§3.6 with the treatment of "Fixed DOFs of K⁰",
// issue 17): a refactorization factors K with the rows and columns of the DOFs constrained at
// its snapshot replaced by their diagonal entry, so after the swap 𝓛 holds no constrained DOF
// (m = 0 with nothing changed since the snapshot; without the option m = |𝓓|). Then a new
// cut, a new constraint (augmented, eq. 5), a changed prescribed value, the release of an
// eliminated DOF (it rejoins 𝓛 with its coupled columns) — also while a job whose snapshot
// eliminates it is pending — and its re-imposition: every solve equals a fresh factorization
// (displacements and reactions). GMRES + HSJ (the paper's default) and the capacitance form
// with its updated factorization and the swap prepared in the job (interactive_options()).
TEST(AugmentedRefactor, RefactorizationEliminatesTheConstrainedDofsSec3_6) {
  for (const bool interactive : {false, true}) {
    for (const bool eliminate : {true, false}) {
      SCOPED_TRACE(::testing::Message()
                   << "interactive " << interactive << " eliminate " << eliminate);
      linalg::AugmentedOptions options =
          interactive ? linalg::interactive_options() : linalg::AugmentedOptions{};
      options.eliminate_constrained = eliminate;
      MidPlaneBeam beam(options);
      ASSERT_NO_FATAL_FAILURE(beam.start(6));
      auto& [m, aug, f, dir, plane] = beam;
      for (const auto& [d, v] : {std::pair<int, double>{4, -0.005}, {7, 0.002}}) {
        aug.impose_dirichlet(d, v);
        dir[d] = v;
      }
      expect_equivalent(aug, m, f, dir);
      ASSERT_TRUE(aug.start_refactorization());
      ASSERT_TRUE(aug.wait_for_refactorization());
      EXPECT_EQ(aug.num_replaced(), eliminate ? 0 : 3);  // 𝓓 = {0, 4, 7}
      aug.set_force(f);
      Eigen::VectorXd a, r;
      const linalg::AugmentedReport rep = aug.solve(a, r);
      ASSERT_TRUE(rep.ok()) << rep.message;
      EXPECT_EQ(rep.m, eliminate ? 0 : 3);
      EXPECT_EQ(rep.dirichlet, 3);
      EXPECT_EQ(rep.dirichlet_eliminated, eliminate ? 3 : 0);
      expect_equivalent(aug, m, f, dir);
      // A cut, a new (augmented) constraint, a changed prescribed value.
      ASSERT_TRUE(cut_node(m, aug, plane[3]));
      aug.impose_dirichlet(10, 0.003);
      dir[10] = 0.003;
      aug.impose_dirichlet(4, -0.004);
      dir[4] = -0.004;
      expect_equivalent(aug, m, f, dir);
      // The release of an eliminated DOF: it and its coupled columns rejoin 𝓛 (without the
      // option, its unchanged column leaves 𝓛).
      const std::vector<int> before = aug.replaced_columns();
      aug.release_dirichlet(7);
      dir.erase(7);
      const std::vector<int> after = aug.replaced_columns();
      EXPECT_EQ(std::count(after.begin(), after.end(), 7), eliminate ? 1 : 0);
      if (eliminate) {
        EXPECT_GT(after.size(), before.size() + 1);
      }
      expect_equivalent(aug, m, f, dir);
      aug.impose_dirichlet(7, 0.001);
      dir[7] = 0.001;
      expect_equivalent(aug, m, f, dir);
      // Released while a job whose snapshot eliminates it runs, with a cut beside it.
      ASSERT_TRUE(aug.start_refactorization());
      aug.release_dirichlet(4);
      dir.erase(4);
      ASSERT_TRUE(cut_node(m, aug, plane[4]));
      expect_equivalent(aug, m, f, dir);
      (void)aug.wait_for_refactorization();
      EXPECT_EQ(aug.refactorizations_pending(), 0);
      expect_equivalent(aug, m, f, dir);
      expect_equivalent(aug, m, f, dir);  // after the pruning of the second solve
      // refactor_now: m drops to 0 with the option, to |𝓓| = 3 without.
      ASSERT_TRUE(aug.refactor_now());
      EXPECT_EQ(aug.num_replaced(), eliminate ? 0 : 3);
      expect_equivalent(aug, m, f, dir);
    }
  }
}

// refactor_now(RefactorOrdering, abandon_pending) (issue 17's synchronous refactorization): with
// every ordering, after cuts (new DOFs, which kExtendCurrent places after their latest
// neighbour) and constraints, while a background job is pending, the job is abandoned (counted,
// none pending), m drops to 0 (|𝓓| without the elimination), the solves equal a fresh
// factorization (expect_equivalent's bound), and G is cached afresh on the new factor: the next
// solve makes one column per column of 𝓛 on the factored DOFs (a solve after a cut, kDirectCached).
TEST(AugmentedRefactor, SynchronousRefactorizationAbandonsThePendingJobForEveryOrdering) {
  using linalg::RefactorOrdering;
  for (const RefactorOrdering ordering :
       {RefactorOrdering::kExtendCurrent, RefactorOrdering::kAmd, RefactorOrdering::kOptions}) {
    for (const bool eliminate : {true, false}) {
      SCOPED_TRACE(::testing::Message()
                   << "ordering " << static_cast<int>(ordering) << " eliminate " << eliminate);
      linalg::AugmentedOptions options = linalg::interactive_options();
      options.eliminate_constrained = eliminate;
      MidPlaneBeam beam(options);
      ASSERT_NO_FATAL_FAILURE(beam.start(6));
      auto& [m, aug, f, dir, plane] = beam;
      aug.impose_dirichlet(4, -0.005);
      dir[4] = -0.005;
      expect_equivalent(aug, m, f, dir);
      ASSERT_TRUE(aug.start_refactorization());
      ASSERT_TRUE(cut_node(m, aug, plane[3]));  // changed while the job runs
      ASSERT_EQ(aug.refactorizations_pending(), 1);
      ASSERT_TRUE(aug.refactor_now(ordering, /*abandon_pending=*/true));
      EXPECT_EQ(aug.refactorizations_pending(), 0);
      EXPECT_EQ(aug.refactorizations_abandoned(), 1);
      EXPECT_EQ(aug.num_replaced(), eliminate ? 0 : static_cast<int>(dir.size()));
      EXPECT_EQ(aug.factored_dofs(), m.num_dofs);
      expect_equivalent(aug, m, f, dir);
      ASSERT_TRUE(cut_node(m, aug, plane[4]));
      const Eigen::Index old_size = f.size();
      f.conservativeResize(m.num_dofs);
      f.tail(m.num_dofs - old_size).setConstant(0.5);
      // Uncached: the columns of 𝓛 on the factored DOFs but 𝓓's, whose G the solve after the
      // refactorization made (without the elimination they are in 𝓛 there).
      const int without_g = aug.columns_without_g();
      int uncached = 0;
      for (int j : aug.replaced_columns()) uncached += j < aug.factored_dofs() && dir.count(j) == 0;
      EXPECT_EQ(without_g, uncached);
      EXPECT_GT(without_g, 0);
      aug.set_force(f);
      Eigen::VectorXd a, r;
      const linalg::AugmentedReport rep = aug.solve(a, r);
      ASSERT_TRUE(rep.ok()) << rep.message;
      EXPECT_EQ(rep.schur_solves, without_g);
      EXPECT_EQ(aug.columns_without_g(), 0);  // all cached now
      expect_equivalent(aug, m, f, dir);
    }
  }
}

// AugmentedOptions::prepare_swap (§3.6, issue 17): the swap brings G of the new factor for the
// columns that stay in 𝓛 (changed since the snapshot, and 𝓓), so the solve after it makes no
// new column of G; without it, that solve makes one per kept column of the factored DOFs.
TEST(AugmentedRefactor, PreparedSwapBringsGOfTheKeptColumnsSec3_6) {
  for (const bool prepare : {true, false}) {
    linalg::AugmentedOptions options;
    options.schur_solver = linalg::SchurSolver::kDirectCached;
    options.prepare_swap = prepare;
    MidPlaneBeam beam(options);
    ASSERT_NO_FATAL_FAILURE(beam.start(5));
    auto& [m, aug, f, dir, plane] = beam;
    ASSERT_TRUE(aug.start_refactorization());
    ASSERT_TRUE(cut_node(m, aug, plane[3]));  // changed while the job runs
    ASSERT_TRUE(cut_node(m, aug, plane[4]));
    ASSERT_TRUE(aug.wait_for_refactorization());
    int kept = 0;  // columns of 𝓛 on the factored DOFs: G's
    for (int j : aug.replaced_columns()) kept += j < aug.factored_dofs();
    ASSERT_GT(kept, 1);
    const Eigen::Index old_size = f.size();  // new DOFs: as expect_equivalent loads them
    f.conservativeResize(m.num_dofs);
    f.tail(m.num_dofs - old_size).setConstant(0.5);
    aug.set_force(f);
    Eigen::VectorXd a, r;
    const linalg::AugmentedReport rep = aug.solve(a, r);
    ASSERT_TRUE(rep.ok()) << rep.message;
    EXPECT_EQ(rep.schur_solves, prepare ? 0 : kept) << "prepare_swap " << prepare;
    expect_equivalent(aug, m, f, dir);
  }
}

// AugmentedOptions::prepare_in_job (§3.6, issue 17): the job goes on from its factorization to
// G of the columns the last solve published (changed since the snapshot, and 𝓓), so the first
// poll that finds it finished swaps it in; without it that poll hands the factor back for a
// second stage and a later poll swaps. Part 1 is deterministic: nothing changes after the
// snapshot, so the published set is 𝓓 = {0} and the swap's solve makes no column of G. Part 2:
// columns change and 𝓓 is released while the job runs (the job may read the set before or
// after the solve publishes it, and its G may hold a label no longer in 𝓛); whatever it
// prepared, the swap's solve makes at most the kept columns and every solve equals a fresh
// factorization.
TEST(AugmentedRefactor, JobPreparesGOfThePublishedColumnsWithoutAPollSec3_6) {
  for (const bool in_job : {true, false}) {
    linalg::AugmentedOptions options;
    options.schur_solver = linalg::SchurSolver::kDirectCached;
    options.prepare_swap = true;
    options.prepare_in_job = in_job;
    MidPlaneBeam beam(options);
    ASSERT_NO_FATAL_FAILURE(beam.start(6));
    auto& [m, aug, f, dir, plane] = beam;
    // Part 1.
    ASSERT_TRUE(aug.start_refactorization());
    int polls = 0;
    bool swapped = false;
    while (!swapped && aug.refactorization_pending()) {
      while (!aug.refactorization_stage_finished())
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      swapped = aug.poll_refactorization();
      ++polls;
    }
    ASSERT_TRUE(swapped) << "prepare_in_job " << in_job;
    EXPECT_EQ(polls, in_job ? 1 : 2) << "prepare_in_job " << in_job;
    EXPECT_EQ(aug.num_replaced(), 1);  // 𝓓
    aug.set_force(f);
    Eigen::VectorXd a, r;
    linalg::AugmentedReport rep = aug.solve(a, r);
    ASSERT_TRUE(rep.ok()) << rep.message;
    EXPECT_EQ(rep.schur_solves, 0) << "prepare_in_job " << in_job;
    expect_equivalent(aug, m, f, dir);
    // Part 2.
    ASSERT_TRUE(aug.start_refactorization());
    ASSERT_TRUE(cut_node(m, aug, plane[3]));
    expect_equivalent(aug, m, f, dir);  // publishes the kept columns; may swap
    ASSERT_TRUE(cut_node(m, aug, plane[4]));
    aug.release_dirichlet(0);
    dir.clear();
    (void)aug.wait_for_refactorization();
    EXPECT_EQ(aug.refactorizations_pending(), 0);
    int kept = 0;
    for (int j : aug.replaced_columns()) kept += j < aug.factored_dofs();
    const Eigen::Index old_size = f.size();
    f.conservativeResize(m.num_dofs);
    f.tail(m.num_dofs - old_size).setConstant(0.5);
    aug.set_force(f);
    rep = aug.solve(a, r);
    ASSERT_TRUE(rep.ok()) << rep.message;
    EXPECT_LE(rep.schur_solves, kept) << "prepare_in_job " << in_job;
    expect_equivalent(aug, m, f, dir);
  }
}

// AugmentedOptions::overlap_stale_columns (§3.6 with several jobs, issue 17): once a column has
// changed since the pending job's snapshot (threshold 1 here), a second job may start from the
// current K; at most two run. After both are done, 𝓛 holds only the columns changed since the
// newer snapshot (and 𝓓), whichever job was swapped in or abandoned on the way, and every
// solve equals a fresh factorization. With and without the prepared swap.
TEST(AugmentedRefactor, OverlappingJobOnAStaleSnapshotLeavesOnlyTheNewerChangesSec3_6) {
  for (const int variant : {0, 1, 2}) {  // prepared swap, prepared in the job, not prepared
    const bool prepare = variant < 2;
    linalg::AugmentedOptions options;
    options.schur_solver = linalg::SchurSolver::kDirectCached;
    options.prepare_swap = prepare;
    options.prepare_in_job = variant == 1;
    options.overlap_stale_columns = 1;
    MidPlaneBeam beam(options);
    ASSERT_NO_FATAL_FAILURE(beam.start(6));
    auto& [m, aug, f, dir, plane] = beam;
    ASSERT_TRUE(aug.start_refactorization());
    EXPECT_FALSE(aug.may_start_refactorization());  // nothing changed since its snapshot
    EXPECT_FALSE(aug.start_refactorization());
    ASSERT_TRUE(cut_node(m, aug, plane[3]));  // the first snapshot goes stale
    ASSERT_TRUE(aug.may_start_refactorization()) << "variant " << variant;
    const int n_second = aug.num_dofs();
    ASSERT_TRUE(aug.start_refactorization());
    EXPECT_EQ(aug.refactorizations_pending(), 2);
    std::set<int> touched;  // columns changed since the second snapshot
    ASSERT_TRUE(cut_node(m, aug, plane[4], &touched));
    EXPECT_FALSE(aug.start_refactorization());  // at most two
    ASSERT_TRUE(cut_node(m, aug, plane[5], &touched));
    expect_equivalent(aug, m, f, dir);  // polls: may swap the first in or abandon it
    (void)aug.wait_for_refactorization();
    EXPECT_EQ(aug.refactorizations_pending(), 0);
    EXPECT_EQ(aug.last_refactorization_status(), linalg::FactorStatus::kOk);
    EXPECT_EQ(aug.factored_dofs(), n_second);  // the newer snapshot's factor is in use
    for (int j : aug.replaced_columns()) EXPECT_TRUE(j == 0 || touched.count(j) != 0) << j;
    expect_equivalent(aug, m, f, dir);
  }
}

// Updates and solves keep running in the foreground while background jobs start and finish
// (polled in solve()); every solution equals a fresh factorization. The ThreadSanitizer build
// of this test is the data-race check of §3.6. Step 3 runs its backward pass on two threads
// (AugmentedOptions::solve_threads) meanwhile, so three threads share the factor data. Run
// twice: GMRES (the default), and the explicit capacitance form with prepare_swap, whose G is
// computed by a second background stage.
void concurrent_updates_and_solves(const linalg::AugmentedOptions& base_options) {
  CutModel m = CutModel::from_mesh(mesh::make_beam(10, 0.1));
  linalg::AugmentedOptions options = base_options;
  options.solve_threads = 2;
  linalg::AugmentedSystem aug(options);
  ASSERT_EQ(aug.initialize(m.assemble()), linalg::FactorStatus::kOk);
  Eigen::VectorXd f = Eigen::VectorXd::Constant(m.num_dofs, 0.1);
  std::map<int, double> dir;
  INCISE_SEEDED_RNG(rng, 23);
  const int nodes = static_cast<int>(m.points.cols());
  std::vector<int> candidates;
  for (int v = 0; v < nodes; ++v)
    if (m.node_dof[v] >= 0) candidates.push_back(v);
  std::shuffle(candidates.begin(), candidates.end(), rng);
  int swaps = 0, cuts = 0;
  for (size_t k = 0; k < candidates.size() && cuts < scaled(12); ++k) {
    if (!aug.refactorization_pending()) (void)aug.start_refactorization();
    CutModel trial = m;
    linalg::AugmentedSystem probe;  // check the cut keeps K nonsingular before applying it
    (void)probe.initialize(trial.assemble());
    if (!cut_node(trial, probe, candidates[k])) continue;
    if (!reference_solve(trial.assemble(), Eigen::VectorXd::Zero(trial.num_dofs), dir).ok) continue;
    ASSERT_TRUE(cut_node(m, aug, candidates[k]));
    ++cuts;
    if (k % 3 == 0) {
      const int d = m.node_dof[candidates[(k + 1) % candidates.size()]];
      if (d >= 0) {
        aug.impose_dirichlet(d, 0.02);
        dir[d] = 0.02;
      }
    }
    const int before = aug.factored_dofs();
    expect_equivalent(aug, m, f, dir);
    if (::testing::Test::HasFatalFailure()) return;
    if (aug.factored_dofs() != before) ++swaps;
  }
  if (aug.wait_for_refactorization()) ++swaps;
  expect_equivalent(aug, m, f, dir);
  EXPECT_GT(cuts, 0);
  EXPECT_GT(swaps, 0);
}

TEST(AugmentedRefactor, ConcurrentUpdatesAndSolvesWhileFactoring) {
  concurrent_updates_and_solves({});
}

TEST(AugmentedRefactor, ConcurrentUpdatesAndSolvesWhileFactoringAndPreparingTheSwap) {
  linalg::AugmentedOptions options;
  options.schur_solver = linalg::SchurSolver::kDirectCached;
  options.update_capacitance = true;
  options.prepare_swap = true;
  concurrent_updates_and_solves(options);
}

// The same with the preparation inside the job (prepare_in_job): the job reads the columns each
// solve publishes (a mutex-guarded list), so three threads share that list and the factor data.
TEST(AugmentedRefactor, ConcurrentUpdatesAndSolvesWhileTheJobPreparesTheSwap) {
  concurrent_updates_and_solves(linalg::interactive_options());
}

}  // namespace
}  // namespace incise::test
