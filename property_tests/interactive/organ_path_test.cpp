// Issue 17: along the scripted scalpel path on the shipped liver (fixtures/organ_path.hpp) with
// the session's default options — the automatic §3.6 refactorization policy (background jobs
// swapped in whenever they finish) and the updated capacitance factorization — every frame's
// solution equals a fresh factorization of the cut mesh's system (reference_solution:
// fem::ElasticProblem + SimplicialLDLT). The default run checks 4 frames at 3 mm and 1 at
// 10 mm (and 2 at 10 mm with overlapping background jobs: each checked frame costs ≈ 25 s under
// TSan, label threads); the slow run (`ctest -L slow -R
// organ_path`, INCISE_ORGAN_PATH_SLOW=1) 100 frames at 3 mm and 40 at 10 mm (each way).

#include <incise/cut/cut_mesh.hpp>
#include <incise/cut/cutter.hpp>
#include <incise/fixtures/organ_path.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise_test/augmented_reference.hpp>
#include <incise_test/cut_components.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <cstdlib>
#include <iostream>

namespace incise::interactive {
namespace {

mesh::MeshData liver() {
  io::ReadOptions o;
  o.scale = 0.001;
  return io::read_mesh(test::source_path("reference_data/meshes/liver_coarse.mesh"), o).mesh;
}

bool slow() {
  return std::getenv("INCISE_ORGAN_PATH_SLOW") != nullptr;
}

void run_path(double advance, int frames, const AugmentedCutOptions& options = {}) {
  const mesh::MeshData body = liver();
  const fixtures::OrganPath path = fixtures::organ_path(body);
  const material::Material material = fixtures::organ_material();
  std::vector<Vec3> forces(static_cast<std::size_t>(body.num_points()));
  for (Index v = 0; v < body.num_points(); ++v)
    forces[static_cast<std::size_t>(v)] = path.forces.col(v);
  AugmentedCutSession session(body, material, path.fixed, path.forces, options);
  ASSERT_TRUE(session.initial_report().ok()) << session.initial_report().message;
  double worst = 0;
  int solved = 0, dissected = 0, swaps = 0, updated = 0, two_pending = 0;
  for (int f = 0; f < frames; ++f) {
    for (const auto& tri : path.frame(f, advance)) {
      const AugmentedCutStepReport r = session.step(tri);
      ASSERT_TRUE(r.ok()) << "frame " << f << ": " << r.message;
      dissected += r.cut.faces_dissected;
      swaps += r.refactorization_swapped;
      two_pending += session.system().refactorizations_pending() == 2;
      if (!r.solved) continue;
      ++solved;
      // Refactor every step: the factor in use is the current K's, so only 𝓓 stays augmented.
      if (options.refactor_every_step) {
        EXPECT_EQ(r.m_after_solve, r.solve.dirichlet);
      }
      updated += r.solve.m > 0 && !r.solve.capacitance_refreshed;
      const test::Reference ref = test::reference_solution(session, material, forces);
      ASSERT_TRUE(ref.ok) << "frame " << f;
      const double d = test::relative_difference(session, ref);
      worst = std::max(worst, d);
      // Issue 17's bound: 1e-9 relative (max-norm over nodes). GMRES stops at 1e-12 of the
      // Schur right-hand side (default) and both solves are backward stable; the liver's
      // κ(K_FF) ≈ 1/ref.rcond lets them differ by up to κ·1e-12 — the assertion holds while
      // that is below 1e-9, and says so when not.
      ASSERT_LE(d, 1e-9) << "frame " << f << " m " << r.solve.m << " rcond " << ref.rcond;
    }
  }
  EXPECT_GT(dissected, 0);  // the path cuts
  // On the long paths m grows past the point where a fresh LU is cheaper than the update:
  // the capacitance factorization is then updated (at small m it is refreshed every solve).
  // (Refactoring every step keeps m = |𝓓|, where the capacitance LU is always fresh.)
  if (slow() && !options.refactor_every_step) {
    EXPECT_GT(updated, 0);
  }
  std::cout << frames << " frames at " << advance * 1e3 << " mm: " << solved << " solves compared, "
            << dissected << " faces dissected, " << swaps << " refactorizations swapped in, "
            << updated << " with an updated capacitance factorization, "
            << session.system().refactorizations_abandoned() << " abandoned, " << two_pending
            << " steps left two jobs pending, worst relative "
            << "difference " << worst << "\n";
}

TEST(OrganPath, Issue17EveryFrameEqualsAFreshFactorization3mm) {
  run_path(0.003, slow() ? 100 : 4);
}

// The "refactor every step" strategy (AugmentedCutOptions::refactor_every_step) on the same
// frames.
TEST(OrganPath, Issue17RefactorEveryStepEqualsAFreshFactorization3mm) {
  AugmentedCutOptions options;
  options.refactor_every_step = true;
  run_path(0.003, slow() ? 100 : 2, options);
}

TEST(OrganPath, Issue17EveryFrameEqualsAFreshFactorization10mm) {
  run_path(0.010, slow() ? 40 : 1);
}

// AugmentedOptions::overlap_stale_columns (a second background job once a column changed since
// the pending one's snapshot — threshold 1, so that overlaps happen whenever a job is pending at
// a solve; the older abandoned when the newer finishes first) on the 10 mm path, where it was
// measured (docs/augmented.md, "Stale background jobs"): every frame still equals a fresh
// factorization. Whether jobs overlap depends on timing, so it is printed, not asserted (the
// deterministic overlap test is AugmentedRefactor.OverlappingJobOnAStaleSnapshot...).
TEST(OrganPath, Issue17OverlappingStaleJobsEqualAFreshFactorization10mm) {
  AugmentedCutOptions options;
  options.augmented.overlap_stale_columns = 1;
  run_path(0.010, slow() ? 40 : 2, options);
}

// The same without pauses between the steps (no reference solve until the end), so that a newer
// job can finish before the older and the older is abandoned (timing-dependent: the count is
// printed); the bookkeeping of 𝓛 across swaps and abandonments is then checked by the final
// solve, and again after the last jobs are waited for and swapped in, against a fresh
// factorization within 1e-9 (the bound of run_path).
TEST(OrganPath, Issue17OverlappingJobsWithoutPausesEndEqualToAFreshFactorization10mm) {
  const mesh::MeshData body = liver();
  const fixtures::OrganPath path = fixtures::organ_path(body);
  const material::Material material = fixtures::organ_material();
  std::vector<Vec3> forces(static_cast<std::size_t>(body.num_points()));
  for (Index v = 0; v < body.num_points(); ++v)
    forces[static_cast<std::size_t>(v)] = path.forces.col(v);
  AugmentedCutOptions options;
  options.augmented.overlap_stale_columns = 1;
  AugmentedCutSession session(body, material, path.fixed, path.forces, options);
  ASSERT_TRUE(session.initial_report().ok()) << session.initial_report().message;
  int swaps = 0, two_pending = 0;
  const int frames = slow() ? 40 : 12;
  for (int f = 0; f < frames; ++f) {
    for (const auto& tri : path.frame(f, 0.010)) {
      const AugmentedCutStepReport r = session.step(tri);
      ASSERT_TRUE(r.ok()) << "frame " << f << ": " << r.message;
      swaps += r.refactorization_swapped;
      two_pending += session.system().refactorizations_pending() == 2;
    }
  }
  const test::Reference ref = test::reference_solution(session, material, forces);
  ASSERT_TRUE(ref.ok);
  const double before = test::relative_difference(session, ref);
  EXPECT_LE(before, 1e-9);
  (void)session.wait_for_refactorization();
  EXPECT_EQ(session.system().refactorizations_pending(), 0);
  const AugmentedCutStepReport r = session.solve();
  ASSERT_TRUE(r.ok()) << r.message;
  const double after = test::relative_difference(session, ref);
  EXPECT_LE(after, 1e-9);
  std::cout << frames << " frames at 10 mm without pauses: " << swaps << " swaps, "
            << session.system().refactorizations_abandoned() << " abandoned, " << two_pending
            << " steps left two jobs pending; relative difference " << before << " (last step), "
            << after << " (after the last swap)\n";
}

// The cut step alone on the path (the session's cut options, nodes at their reference
// positions): the component check after every cut (thesis §3.3) is decided by the local search
// from the separated faces, never by the O(n) search over the whole mesh. Before issue 17's
// fix a separated element removed by the degeneracy removal without a stand-in (an isolated
// element cut free) sent the step to the O(n) search (1 step of this path; 5 of 30 frames on
// the refined liver, ≈ 100 ms each). Small parts between the cut surfaces are cut free and
// fixed on a face (FreeComponentPolicy::kFixOnFace, the session's); after every step no
// component may be left free (test::every_component_fixed, an independent O(n) search).
TEST(OrganPath, Issue17CutStepNeedsNoGlobalComponentSearch3mm) {
  const mesh::MeshData body = liver();
  const fixtures::OrganPath path = fixtures::organ_path(body);
  cut::CutMesh mesh(body);
  for (Index v : path.fixed) mesh.set_fixed(v, true);
  cut::Cutter cutter(mesh, AugmentedCutOptions{}.cut);
  cut::CutTotals totals;
  int global = 0, fixed_on_face = 0;
  for (int f = 0; f < 30; ++f) {
    for (const auto& tri : path.frame(f, 0.003)) {
      const cut::CutStepReport r = cutter.step(tri[0], tri[1], tri[2]);
      totals.add(r);
      global += r.full_component_check ? 1 : 0;
      fixed_on_face += static_cast<int>(r.components_fixed);
      EXPECT_FALSE(r.full_component_check) << "frame " << f;
      ASSERT_TRUE(test::every_component_fixed(mesh)) << "frame " << f;
    }
  }
  EXPECT_GT(totals.faces_dissected, 100);                 // the path cuts (measured: 198 faces)
  EXPECT_GT(totals.collapses + totals.incollapsible, 0);  // and removes degenerate elements
  EXPECT_EQ(totals.free_components, fixed_on_face);
  const cut::CutMeshValidation v = mesh.validate();
  EXPECT_TRUE(v.ok()) << (v.violations.empty() ? "" : v.violations[0]);
  std::cout << "30 frames at 3 mm: " << totals.faces_dissected << " faces dissected, "
            << totals.collapses << " collapses, " << totals.incollapsible << " cut free, "
            << totals.free_components << " free parts fixed on a face, O(n) component searches "
            << global << "\n";
}

}  // namespace
}  // namespace incise::interactive
