/// \file yeung2016_verify.cpp
/// Yeung, Crouch & Pothen 2016, §4.3 experiments on the beam meshes of §4.2 item (1): every
/// augmented update of (1) the deformation experiment (Fig. 5, 6: one more constrained node
/// per step) and (2) the advancing planar cut (Fig. 7, 9: one duplicated node per step,
/// opposing forces on the end face) equals a fresh CHOLMOD refactorization of the modified
/// system (Fig. 11b) within a condition-scaled tolerance, GMRES needs at most m iterations
/// (Fig. 11a: iterations bounded by the number of changed columns), and the closures stay a
/// small part of the factor (Fig. 4). Timings are printed, never asserted (benchmarks/).
///
/// Default: h = 32 (800 nodes). INCISE_YEUNG2016_H=1024 (label slow, ctest -L slow) runs the
/// paper's 25,600-node beam.

#include "yeung2016_experiment.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace incise::test {
namespace {

int beam_h() {
  const char* e = std::getenv("INCISE_YEUNG2016_H");
  return e != nullptr ? std::atoi(e) : 32;
}

/// Forward error bound of both solutions: κ(K)·(GMRES tolerance 1e-12 + n·eps). The paper
/// quotes κ up to 3.3e12 for its longest beam (§4.2); our elastic beams are stiffer in the
/// cross-section, and the observed agreement is 1e-12 … 1e-8 (h = 32 … 1024). 1e-6 is the
/// condition-scaled tolerance for h ≤ 1024 with κ ≲ 1e10 measured by CHOLMOD's rcond.
constexpr double kRelTol = 1e-6;

std::vector<yeung2016::Row> check(const yeung2016::Options& opt) {
  yeung2016::Info info;
  const std::vector<yeung2016::Row> rows = yeung2016::run(opt, info);
  EXPECT_EQ(static_cast<int>(rows.size()), opt.steps + 1);
  std::printf("%s: %d nodes, n0 = %d, |L| = %lld\n", info.name.c_str(), info.nodes, info.n0,
              info.nnz_l);
  for (const auto& r : rows) {
    std::printf(
        "step %2d m %3d it %3d closures f/y/Ja2/3 %5d %5d %5d %5d update %.2f ms "
        "refactor+solve %.1f ms error %.1e backward %.1e %s\n",
        r.step, r.m, r.gmres_iterations, r.closure_f, r.closure_y, r.closure_ja2, r.closure_step3,
        1e3 * (r.t_changes + r.t_solve), 1e3 * (r.t_refactor + r.t_refactor_solve), r.rel_error,
        r.rel_residual, r.status.c_str());
    EXPECT_EQ(r.status, "ok") << "step " << r.step;
    EXPECT_GE(r.rel_error, 0.0);
    EXPECT_LE(r.rel_error, kRelTol) << "step " << r.step;
    // Normwise backward error ‖K a − f − r‖/(‖K‖₁‖a‖ + ‖f + r‖) of the augmented solution.
    // GMRES stops at a relative residual 1e-12 of eq. 17; that residual reaches the full
    // system through J (entries of K) — measured ≤ 5e-9 up to the 25,600-node cut (README).
    EXPECT_LE(r.rel_residual, 1e-8) << "step " << r.step;
    EXPECT_LE(r.gmres_iterations, std::max(r.m, 1)) << "step " << r.step;
    EXPECT_LE(r.closure_ja2, info.n0);
  }
  return rows;
}

TEST(Yeung2016, BeamDeformationFig5MatchesRefactorization) {
  yeung2016::Options opt;
  opt.kind = yeung2016::Kind::kDeform;
  opt.h = beam_h();
  opt.steps = 12;
  check(opt);
}

TEST(Yeung2016, BeamCuttingFig7MatchesRefactorization) {
  yeung2016::Options opt;
  opt.kind = yeung2016::Kind::kCut;
  opt.h = beam_h();
  opt.steps = 8;
  check(opt);
}

TEST(Yeung2016, BeamCuttingWithSpaiAndNoPreconditioner) {
  for (auto p :
       {linalg::SchurPreconditioner::kNone, linalg::SchurPreconditioner::kTridiagonalSpai}) {
    yeung2016::Options opt;
    opt.kind = yeung2016::Kind::kCut;
    opt.h = 16;
    opt.steps = 6;
    opt.preconditioner = p;
    check(opt);
  }
}

// Eq. 17 by GMRES preconditioned with the explicit H R⁻¹ J in capacitance form
// (SchurSolver::kDirectCached), on both experiments (beam h as above) and on a brick (§4.2
// item 2): the same agreement with refactorization, and — since the preconditioner equals the
// operator up to round-off amplified by κ(R) — at most 4 GMRES iterations per step (measured
// 1–3, also on the 25,600-node beam cut where HSJ needs up to 47).
TEST(Yeung2016, DirectCachedSchurMatchesRefactorization) {
  for (auto kind : {yeung2016::Kind::kDeform, yeung2016::Kind::kCut}) {
    yeung2016::Options opt;
    opt.kind = kind;
    opt.h = beam_h();
    opt.steps = kind == yeung2016::Kind::kDeform ? 12 : 8;
    opt.schur_solver = linalg::SchurSolver::kDirectCached;
    auto check_direct = [&] {
      for (const auto& r : check(opt))
        EXPECT_LE(r.gmres_iterations, 4) << "step " << r.step << " m " << r.m;
    };
    check_direct();
    opt.geometry = yeung2016::Geometry::kBrick;
    opt.brick_n = 4;
    opt.steps = 6;
    check_direct();
  }
}

}  // namespace
}  // namespace incise::test
