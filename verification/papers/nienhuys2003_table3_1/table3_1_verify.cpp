/// Thesis §3.3, Table 3.1: tip deflection of the cantilever by linear FEM + matrix-free CG
/// (‖r‖ < 1e-8‖f_ex‖) on the five structured meshes, beside the published numbers. The beam,
/// its references, the published table and the solve: <incise/fixtures/cantilever.hpp>.
/// Default run: the three coarse meshes (425, 1225, 2673 nodes). INCISE_TABLE3_1_ALL=1 (set by
/// the `slow`-labelled ctest entry) adds the 4961- and 8281-node meshes of the table and two
/// finer ones (56×14×14, 64×16×16) for the asymptotic order and the Richardson limit.
#include <incise/fixtures/cantilever.hpp>
#include <incise/fixtures/convergence.hpp>

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <vector>

namespace incise::verify {
namespace {

using fixtures::CantileverResult;
using fixtures::kEulerBernoulli;
using fixtures::kTimoshenko;
using fixtures::Richardson;

// The meshes nx × nx/4 × nx/4: Table 3.1's five (fixtures::kTable3_1, n = nx/4), then two
// beyond the table.
constexpr int kMeshes[] = {16, 24, 32, 40, 48, 56, 64};
constexpr std::size_t kPublishedRows = std::size(fixtures::kTable3_1);

bool all_meshes() {
  const char* v = std::getenv("INCISE_TABLE3_1_ALL");
  return v && std::string(v) == "1";
}

TEST(CantileverTable3_1, ConvergesToTimoshenkoFromBelow) {
  const int count = all_meshes() ? 7 : 3;
  std::vector<CantileverResult> res;
  const fixtures::CantileverConstants& c = fixtures::kCantilever;
  std::printf("Table 3.1 (thesis §3.3): l×h×d = %g×%g×%g m, E = %g Pa, nu = %g, F = %g N\n",
              c.length, c.height, c.depth, c.young, c.poisson, c.tip_load);
  std::printf("Euler-Bernoulli %.4e m, Timoshenko %.4e m; errors relative to Euler-Bernoulli\n",
              kEulerBernoulli, kTimoshenko);
  std::printf("%-12s %6s | %6s %8s %8s | %6s %8s %8s %8s | %8s\n", "elements", "nodes", "it(th)",
              "avg%(th)", "max%(th)", "it", "avg%", "max%", "min%", "vsTimo%");
  for (int i = 0; i < count; ++i) {
    const int nx = kMeshes[i];
    const CantileverResult r = fixtures::solve_cantilever(nx, nx / 4, nx / 4);
    ASSERT_EQ(r.status, solver::StopReason::kConverged) << solver::to_string(r.status);
    // Same meshes as the thesis ((nx+1)(ny+1)(nz+1) nodes; the thesis prints 8181 for 48×12×12).
    ASSERT_EQ(r.nodes, (nx + 1) * (nx / 4 + 1) * (nx / 4 + 1));
    res.push_back(r);
    const double avg = 100 * (kEulerBernoulli - r.avg_deflection) / kEulerBernoulli;
    // Largest error = smallest deflection and vice versa.
    const double mx = 100 * (kEulerBernoulli - r.min_deflection) / kEulerBernoulli;
    const double mn = 100 * (kEulerBernoulli - r.max_deflection) / kEulerBernoulli;
    if (static_cast<std::size_t>(i) < kPublishedRows) {
      const fixtures::Table3_1Row& t = fixtures::kTable3_1[i];
      ASSERT_EQ(4 * t.n, nx);
      std::printf("%3dx%2dx%2d   %6d | %6ld %8.1f %8.1f |", nx, nx / 4, nx / 4, r.nodes,
                  t.iterations, t.avg_error_pct, t.max_error_pct);
    } else {
      std::printf("%3dx%2dx%2d   %6d | %6s %8s %8s |", nx, nx / 4, nx / 4, r.nodes, "-", "-", "-");
    }
    std::printf(" %6ld %8.2f %8.2f %8.2f | %8.2f\n", r.iterations, avg, mx, mn,
                100 * (kTimoshenko - r.avg_deflection) / kTimoshenko);
  }
  for (std::size_t i = 0; i < res.size(); ++i) {
    // FEM stiffer than the beam: every tip node deflects less than Timoshenko, and on the
    // thesis' five meshes less than Euler–Bernoulli too (Table 3.1 caption: "always less than
    // predicted"; on finer meshes the FEM passes EB, which ignores the 1.7 % shear deflection).
    EXPECT_LT(res[i].max_deflection, kTimoshenko);
    if (res[i].nx <= 48) {
      EXPECT_LT(res[i].max_deflection, kEulerBernoulli);
    }
    if (i > 0) {
      EXPECT_GT(res[i].avg_deflection, res[i - 1].avg_deflection);  // errors fall monotonically
      EXPECT_GT(res[i].min_deflection, res[i - 1].min_deflection);
    }
  }
  // Observed order and Richardson extrapolation from the three finest meshes run, with h ∝ 1/nx.
  const std::size_t k = res.size();
  const Richardson rich = fixtures::richardson(1.0 / res[k - 3].nx, res[k - 3].avg_deflection,
                                               1.0 / res[k - 2].nx, res[k - 2].avg_deflection,
                                               1.0 / res[k - 1].nx, res[k - 1].avg_deflection);
  ASSERT_TRUE(rich.ok);
  std::printf(
      "observed order p = %.3f from nx = %d, %d, %d; Richardson limit %.5e m (%+.3f%% "
      "from Timoshenko)\n",
      rich.order, res[k - 3].nx, res[k - 2].nx, res[k - 1].nx, rich.limit,
      100 * (rich.limit - kTimoshenko) / kTimoshenko);
  // Observed order of the compliance 1/δ (δ = average tip deflection) from the same meshes.
  // For a Galerkin method F(δ − δ_h) = ‖u − u_h‖²_E = O(h²) (energy error, linear elements), so
  // δ and 1/δ share the asymptotic order 2. Coarse linear tetrahedra in bending are too stiff by
  // a factor ≈ (1 + c h²) (parasitic shear), δ_h ≈ δ/(1 + c h²): then 1/δ_h = (1 + c h²)/δ is
  // exactly quadratic in h while δ_h carries large higher-order terms when c h² is not small
  // (c h² ≈ 0.3 at nx = 16). That is why the displacement order is pre-asymptotic (≈ 1.4 on
  // 16/24/32) while the compliance order is already ≈ 2 there.
  const Richardson flex = fixtures::richardson(
      1.0 / res[k - 3].nx, 1.0 / res[k - 3].avg_deflection, 1.0 / res[k - 2].nx,
      1.0 / res[k - 2].avg_deflection, 1.0 / res[k - 1].nx, 1.0 / res[k - 1].avg_deflection);
  ASSERT_TRUE(flex.ok);
  std::printf(
      "compliance 1/delta: observed order p = %.3f; Richardson limit delta = %.5e m "
      "(%+.3f%% from Timoshenko)\n",
      flex.order, 1.0 / flex.limit, 100 * (1.0 / flex.limit - kTimoshenko) / kTimoshenko);
  // Measured 1.94 (16/24/32) and 1.985 (48/56/64): ±0.1 is "about 2" and rejects first order
  // or a broken discretization; the shortfall is the small O(h⁴) remainder.
  constexpr double kComplianceOrderTol = 0.1;
  EXPECT_NEAR(flex.order, 2.0, kComplianceOrderTol);
  // Its extrapolated deflection is within 0.5 % of Timoshenko already on the coarse meshes
  // (measured +0.19 %; the 3D clamp restrains warping, which Timoshenko's κ = 5/6 ignores).
  constexpr double kComplianceLimitTol = 0.005;
  EXPECT_NEAR(1.0 / flex.limit, kTimoshenko, kComplianceLimitTol * kTimoshenko);
  if (!all_meshes()) {
    // Displacement order on 16/24/32: pre-asymptotic (see above), measured p ≈ 1.38, rising to
    // ≈ 1.65 (24/32/40) and ≈ 1.9 (48/56/64). Asserted only as a sanity band here; "about 2"
    // is asserted on the compliance above and on the displacement in the slow run.
    EXPECT_GT(rich.order, 1.0);
    EXPECT_LT(rich.order, 2.25);
    return;
  }
  // Linear tetrahedra: displacement error O(h²) for a smooth solution. On 48/56/64 the measured
  // order is ≈ 1.9, still creeping up (clamp corners are mildly singular); ±0.25 admits that and
  // would reject a first-order (p ≈ 1) or broken (p ≫ 2) discretization.
  constexpr double kOrderTol = 0.25;
  EXPECT_NEAR(rich.order, 2.0, kOrderTol);
  // Issue 4 acceptance: extrapolated deflection within 0.5 % of Timoshenko (3D elasticity and
  // Timoshenko's κ = 5/6 beam differ by the clamp's restraint of warping, well below 0.5 %).
  constexpr double kRichardsonTol = 0.005;
  EXPECT_NEAR(rich.limit, kTimoshenko, kRichardsonTol * kTimoshenko);
}

}  // namespace
}  // namespace incise::verify
