// Issue 17: along the scripted scalpel path on the shipped liver (fixtures/organ_path.hpp) with
// the session's default options — the automatic §3.6 refactorization policy (background jobs
// swapped in whenever they finish) and the updated capacitance factorization — every frame's
// solution equals a fresh factorization of the cut mesh's system (reference_solution:
// fem::ElasticProblem + SimplicialLDLT). The default run checks 4 frames at 3 mm; the slow
// run (`ctest -L slow -R organ_path`, INCISE_ORGAN_PATH_SLOW=1) 100 frames at 3 mm and 40 at
// 10 mm.

#include <incise/fixtures/organ_path.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise_test/augmented_reference.hpp>
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
  int solved = 0, dissected = 0, swaps = 0, updated = 0;
  for (int f = 0; f < frames; ++f) {
    for (const auto& tri : path.frame(f, advance)) {
      const AugmentedCutStepReport r = session.step(tri);
      ASSERT_TRUE(r.ok()) << "frame " << f << ": " << r.message;
      dissected += r.cut.faces_dissected;
      swaps += r.refactorization_swapped;
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
            << updated << " with an updated capacitance factorization, worst relative difference "
            << worst << "\n";
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
  if (!slow()) GTEST_SKIP() << "slow: INCISE_ORGAN_PATH_SLOW=1";
  run_path(0.010, 40);
}

}  // namespace
}  // namespace incise::interactive
