// Issue 17: along the scripted scalpel path on the shipped liver (fixtures/organ_path.hpp) with
// the session's default options — the automatic §3.6 refactorization policy (background jobs
// swapped in whenever they finish) and the updated capacitance factorization — every frame's
// solution equals a fresh factorization of the cut mesh's system (reference_solution:
// fem::ElasticProblem + SimplicialLDLT). The default run checks 4 frames at 3 mm and 1 at
// 10 mm (and 2 at 10 mm with overlapping background jobs: each checked frame costs ≈ 25 s under
// TSan, label threads); the slow run (`ctest -L slow -R
// organ_path`, INCISE_ORGAN_PATH_SLOW=1) 100 frames at 3 mm and 40 at 10 mm (each way). The
// same with one solve per frame (AugmentedCutSession::frame), and per frame vs per triangle.

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
#include <limits>
#include <memory>
#include <string>
#include <vector>

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

// The liver of the path, its supports, loads and material, and a session on it (the one set-up
// of every session test here).
struct OrganPathLiverSession {
  mesh::MeshData body;
  fixtures::OrganPath path;
  material::Material material;
  std::vector<Vec3> forces;  // path.forces as test::reference_solution takes them
  std::unique_ptr<AugmentedCutSession> session;
};

OrganPathLiverSession organ_path_liver_session(const AugmentedCutOptions& options) {
  OrganPathLiverSession s{liver(), {}, fixtures::organ_material(), {}, nullptr};
  s.path = fixtures::organ_path(s.body);
  s.forces.resize(static_cast<std::size_t>(s.body.num_points()));
  for (Index v = 0; v < s.body.num_points(); ++v)
    s.forces[static_cast<std::size_t>(v)] = s.path.forces.col(v);
  s.session = std::make_unique<AugmentedCutSession>(s.body, s.material, s.path.fixed, s.path.forces,
                                                    options);
  return s;
}

// Cuts frame f of the path: one solve per sweep triangle (step) or one per frame (frame()).
std::vector<AugmentedCutStepReport> organ_path_cut_frame(AugmentedCutSession& session,
                                                         const fixtures::OrganPath& path, int f,
                                                         double advance, bool per_frame) {
  std::vector<AugmentedCutStepReport> reports;
  const auto tris = path.frame(f, advance);
  if (per_frame) {
    reports.push_back(session.frame(tris));
  } else {
    for (const auto& tri : tris) reports.push_back(session.step(tri));
  }
  return reports;
}

void run_path(double advance, int frames, const AugmentedCutOptions& options = {},
              bool per_frame = false, int* updated_out = nullptr, int* synchronous_out = nullptr) {
  const OrganPathLiverSession organ = organ_path_liver_session(options);
  AugmentedCutSession& session = *organ.session;
  ASSERT_TRUE(session.initial_report().ok()) << session.initial_report().message;
  double worst = 0;
  int solved = 0, dissected = 0, swaps = 0, updated = 0, two_pending = 0;
  for (int f = 0; f < frames; ++f) {
    for (const AugmentedCutStepReport& r :
         organ_path_cut_frame(session, organ.path, f, advance, per_frame)) {
      ASSERT_TRUE(r.ok()) << "frame " << f << ": " << r.message;
      EXPECT_EQ(r.triangles, per_frame ? 2 : 1);
      dissected += r.cut.faces_dissected;
      swaps += r.refactorization_swapped;
      two_pending += session.system().refactorizations_pending() == 2;
      if (!r.solved) continue;
      ++solved;
      // Refactor every step: the factor in use is the current K's, so only 𝓓 stays augmented,
      // and not even 𝓓 when the refactorization eliminates it (eliminate_constrained, on in
      // the session's defaults).
      if (options.refactor_every_step) {
        EXPECT_EQ(r.m_after_solve, options.augmented.eliminate_constrained ? 0 : r.solve.dirichlet);
        EXPECT_EQ(r.solve.dirichlet_eliminated,
                  options.augmented.eliminate_constrained ? r.solve.dirichlet : 0);
      }
      updated += r.solve.m > 0 && !r.solve.capacitance_refreshed;
      const test::Reference ref = test::reference_solution(session, organ.material, organ.forces);
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
  // Whether the capacitance factorization is ever updated rather than refreshed depends on m,
  // i.e. on how soon the background jobs are swapped in (timing): printed, not asserted here;
  // Issue17UpdatedCapacitanceEqualsAFreshFactorizationWithoutBackgroundJobs1mm asserts it.
  if (updated_out) *updated_out = updated;
  if (synchronous_out) *synchronous_out = session.synchronous_refactorizations();
  std::cout << frames << " frames at " << advance * 1e3 << " mm"
            << (per_frame ? ", one solve per frame: " : ", one solve per sweep triangle: ")
            << solved << " solves compared, " << dissected << " faces dissected, " << swaps
            << " refactorizations swapped in, " << updated
            << " with an updated capacitance factorization, "
            << session.system().refactorizations_abandoned() << " abandoned, "
            << session.synchronous_refactorizations() << " synchronous refactorizations, "
            << two_pending << " steps left two jobs pending, worst relative "
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

// One solve per frame (AugmentedCutSession::frame: both sweep triangles of a blade advance cut,
// then one solve) on the same paths: every frame's solution equals a fresh factorization of the
// mesh the frame left (the bound of run_path).
TEST(OrganPath, Issue17OneSolvePerFrameEqualsAFreshFactorization3mm) {
  run_path(0.003, slow() ? 100 : 4, {}, true);
}

TEST(OrganPath, Issue17OneSolvePerFrameEqualsAFreshFactorization10mm) {
  run_path(0.010, slow() ? 40 : 2, {}, true);
}

// The updated capacitance factorization (CapacitanceFactor: Sherman–Morrison–Woodbury on the
// last fresh LU) on the liver path, deterministically: with the background policy off m grows
// frame by frame, the cost rule updates instead of refreshing on some frames, and every frame
// equals a fresh factorization (the bound of run_path). With the default background jobs
// whether that happens depends on their timing (issue 17: prepare_in_job keeps m small enough
// that a fresh LU is cheaper on every solve of some runs).
TEST(OrganPath, Issue17UpdatedCapacitanceEqualsAFreshFactorizationWithoutBackgroundJobs1mm) {
  AugmentedCutOptions options;
  options.automatic_refactorization = false;
  int updated = 0;
  run_path(0.001, slow() ? 60 : 20, options, true, &updated);
  EXPECT_GT(updated, 0);
}

// The synchronous refactorization (AugmentedCutOptions::synchronous_refactorization, issue 17)
// on the liver's 10 mm path, deterministically: no background job (break-even with an infinite
// factorization cost) and an injected cost model — the solve costs m, a refactorization 500 —
// so the frame thread refactors (the factor in use's ordering extended to the new DOFs) before
// every solve that starts with m > 500, from frame 3 on (m = 639 there); every frame equals a
// fresh factorization (the bound of run_path). 4 frames by default, 40 in the slow run.
TEST(OrganPath, Issue17SynchronousRefactorizationEqualsAFreshFactorization10mm) {
  AugmentedCutOptions options;
  options.refactorization_mode = RefactorizationMode::kBreakEven;
  options.factorization_cost = [](const linalg::AugmentedSystem&) {
    return std::numeric_limits<double>::infinity();
  };
  options.synchronous_solve_cost = [](int m, int) { return static_cast<double>(m); };
  options.synchronous_refactor_cost = [](const linalg::AugmentedSystem&) { return 500.0; };
  int synchronous = 0;
  run_path(0.010, slow() ? 40 : 4, options, true, nullptr, &synchronous);
  EXPECT_GE(synchronous, 1);
}

// Final cut meshes equal: the same live element slots with the same nodes, the same nodes with
// the same reference positions.
::testing::AssertionResult organ_path_same_mesh(const cut::CutMesh& a, const cut::CutMesh& b) {
  if (a.num_nodes() != b.num_nodes() || a.element_capacity() != b.element_capacity())
    return ::testing::AssertionFailure()
           << "nodes " << a.num_nodes() << " vs " << b.num_nodes() << ", element slots "
           << a.element_capacity() << " vs " << b.element_capacity();
  for (Index e = 0; e < a.element_capacity(); ++e) {
    if (a.alive(e) != b.alive(e) || (a.alive(e) && a.element(e) != b.element(e)))
      return ::testing::AssertionFailure() << "element slot " << e << " differs";
  }
  for (Index v = 0; v < a.num_nodes(); ++v) {
    if (a.unused(v) != b.unused(v) || a.reference(v) != b.reference(v))
      return ::testing::AssertionFailure() << "node " << v << " differs";
  }
  return ::testing::AssertionSuccess();
}

// step(tri) is the frame of one triangle: with the background policy off (a swap's timing would
// make the solves differ), stepping the 10 mm path triangle by triangle through step() and
// through frame() on one-triangle vectors gives bitwise the same reports, meshes and
// displacements.
TEST(OrganPath, Issue17OneTriangleFrameIsBitwiseStep) {
  AugmentedCutOptions options;
  options.automatic_refactorization = false;
  const OrganPathLiverSession a = organ_path_liver_session(options);
  const OrganPathLiverSession b = organ_path_liver_session(options);
  Index dissected = 0;
  for (int f = 0; f < 3; ++f) {
    for (const auto& tri : a.path.frame(f, 0.010)) {
      const AugmentedCutStepReport ra = a.session->step(tri);
      const AugmentedCutStepReport rb = b.session->frame(std::vector<std::array<Vec3, 3>>{tri});
      ASSERT_TRUE(ra.ok()) << ra.message;
      EXPECT_EQ(ra.status, rb.status);
      EXPECT_EQ(ra.triangles, 1);
      EXPECT_EQ(rb.triangles, 1);
      EXPECT_EQ(ra.cut.changed_elements, rb.cut.changed_elements);
      EXPECT_EQ(ra.elements_added, rb.elements_added);
      EXPECT_EQ(ra.dofs_added, rb.dofs_added);
      EXPECT_EQ(ra.m_before_solve, rb.m_before_solve);
      EXPECT_EQ(ra.m_after_solve, rb.m_after_solve);
      EXPECT_EQ(ra.solve.gmres.iterations, rb.solve.gmres.iterations);
      ASSERT_TRUE(a.session->displacement() == b.session->displacement()) << "frame " << f;
      dissected += ra.cut.faces_dissected;
    }
  }
  EXPECT_GT(dissected, 0);  // the frames cut
  EXPECT_TRUE(organ_path_same_mesh(a.session->mesh(), b.session->mesh()));
  EXPECT_TRUE(a.session->displacement() == b.session->displacement());  // bitwise
}

// Per frame vs per triangle. Cutting in the reference configuration (update_deformed = false)
// the cutter sees the same positions either way, so the final meshes are identical and the two
// solutions (other DOF numbering and summation order, both exact) equal within 1e-9 relative,
// the bound of run_path. In the deformed configuration (the default) the second triangle of a
// frame meets the nodes where the last frame's solve left them rather than where an intermediate
// solve would have moved them, so the meshes may legitimately differ: that run only prints
// whether they did (each way's exactness is the tests above).
TEST(OrganPath, Issue17PerFrameAndPerTriangleCutTheSameMeshInTheReferenceConfiguration10mm) {
  for (const bool deformed : {false, true}) {
    AugmentedCutOptions options;
    options.update_deformed = deformed;
    const OrganPathLiverSession per_triangle = organ_path_liver_session(options);
    const OrganPathLiverSession per_frame = organ_path_liver_session(options);
    const int frames = slow() ? 20 : 4;
    int solves_triangle = 0, solves_frame = 0;
    for (int f = 0; f < frames; ++f) {
      for (const AugmentedCutStepReport& r :
           organ_path_cut_frame(*per_triangle.session, per_triangle.path, f, 0.010, false)) {
        ASSERT_TRUE(r.ok()) << r.message;
        solves_triangle += r.solved;
      }
      for (const AugmentedCutStepReport& r :
           organ_path_cut_frame(*per_frame.session, per_frame.path, f, 0.010, true)) {
        ASSERT_TRUE(r.ok()) << r.message;
        solves_frame += r.solved;
      }
    }
    EXPECT_LT(solves_frame, solves_triangle);
    const ::testing::AssertionResult same =
        organ_path_same_mesh(per_triangle.session->mesh(), per_frame.session->mesh());
    double difference = -1;  // of the solutions, where the meshes are the same
    if (same) {
      const test::Reference ref =
          test::reference_solution(*per_frame.session, per_frame.material, per_frame.forces);
      ASSERT_TRUE(ref.ok);
      difference = test::relative_difference(*per_triangle.session, ref);
      EXPECT_LE(difference, 1e-9);
      EXPECT_LE(test::relative_difference(*per_frame.session, ref), 1e-9);
    }
    if (!deformed) {
      EXPECT_TRUE(same);
    }
    std::cout << frames << " frames at 10 mm, cut in the " << (deformed ? "deformed" : "reference")
              << " configuration: " << solves_triangle << " solves per triangle, " << solves_frame
              << " per frame; final meshes "
              << (same ? "identical" : "differ (" + std::string(same.message()) + ")")
              << ", per-triangle solution vs the per-frame mesh's fresh factorization "
              << difference << "\n";
  }
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
  AugmentedCutOptions options;
  options.augmented.overlap_stale_columns = 1;
  const OrganPathLiverSession organ = organ_path_liver_session(options);
  AugmentedCutSession& session = *organ.session;
  ASSERT_TRUE(session.initial_report().ok()) << session.initial_report().message;
  int swaps = 0, two_pending = 0;
  const int frames = slow() ? 40 : 12;
  for (int f = 0; f < frames; ++f) {
    for (const auto& tri : organ.path.frame(f, 0.010)) {
      const AugmentedCutStepReport r = session.step(tri);
      ASSERT_TRUE(r.ok()) << "frame " << f << ": " << r.message;
      swaps += r.refactorization_swapped;
      two_pending += session.system().refactorizations_pending() == 2;
    }
  }
  const test::Reference ref = test::reference_solution(session, organ.material, organ.forces);
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
            << session.system().refactorizations_abandoned() << " abandoned, "
            << session.synchronous_refactorizations() << " synchronous refactorizations, "
            << two_pending << " steps left two jobs pending; relative difference " << before
            << " (last step), " << after << " (after the last swap)\n";
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
