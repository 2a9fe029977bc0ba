/// Nonlinear CG (§2.4.2, line searches §4.4.2) and truncated Newton (§2.4.3) on a convex
/// nonlinear spring chain with an inversion barrier; statuses on +∞ regions and indefinite
/// problems; budgets.
#include <incise/solver/energy_error.hpp>
#include <incise/solver/nonlinear_cg.hpp>
#include <incise/solver/truncated_newton.hpp>
#include <incise_test/seed.hpp>

#include "test_problems.hpp"

#include <gtest/gtest.h>

#include <string>

namespace incise::solver {
namespace {

using test::QuadraticProblem;
using test::SpringChain;

SpringChain make_chain(std::mt19937_64& rng, int n, double load_scale) {
  std::uniform_real_distribution<double> unif(-1.0, 1.0);
  VecX f(n + 1);
  for (int i = 0; i <= n; ++i) f[i] = load_scale * unif(rng);
  return SpringChain(n, 100.0, 50.0, 0.5, 0.1, f);
}

VecX newton_reference(SpringChain& p) {
  VecX u = VecX::Zero(p.size());
  TruncatedNewtonOptions o;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-12;
  const SolverReport rep = truncated_newton(p, u, o);
  EXPECT_TRUE(rep.ok()) << to_string(rep.status);
  return u;
}

TEST(TruncatedNewton, ReachesReferenceTolerance_Sec4_2) {
  INCISE_SEEDED_RNG(rng, 51);
  SpringChain p = make_chain(rng, 40, 20.0);
  VecX u = VecX::Zero(p.size());
  TruncatedNewtonOptions o;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-8;  // §4.2 reference tolerance
  const SolverReport rep = truncated_newton(p, u, o);
  ASSERT_TRUE(rep.ok()) << to_string(rep.status);
  EXPECT_LE(rep.residual_norm, 1e-8 * p.external_force_norm());
  EXPECT_LT(rep.iterations, 30);  // superlinear: a handful of Newton steps
  EXPECT_EQ(u[0], 0.0);
}

TEST(TruncatedNewton, QuadraticInOneStepWithTightInnerSolve) {
  INCISE_SEEDED_RNG(rng, 52);
  QuadraticProblem p = test::random_spd_problem(rng, 25, 100.0, 2);
  VecX u = VecX::Zero(25);
  TruncatedNewtonOptions o;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-10;
  const SolverReport rep = truncated_newton(p, u, o);
  ASSERT_TRUE(rep.ok());
  // Inexact inner solves (forcing η ≤ 0.5) converge superlinearly: ≤ 8 steps from 1 to 1e-10.
  EXPECT_LE(rep.iterations, 8);
  EXPECT_LE((u - p.direct_solution()).norm(), 1e-8 * u.norm());
}

struct NcgCase {
  BetaRule beta;
  LineSearchKind ls;
};

class NonlinearCgEquivalence : public ::testing::TestWithParam<NcgCase> {};

TEST_P(NonlinearCgEquivalence, MatchesNewtonAtMinimizer_Sec2_4_2_Sec4_4_2) {
  INCISE_SEEDED_RNG(rng, 53);
  SpringChain p = make_chain(rng, 30, 20.0);
  const VecX ref = newton_reference(p);
  VecX u = VecX::Zero(p.size());
  NonlinearCgOptions o;
  o.beta = GetParam().beta;
  o.line_search = GetParam().ls;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-9;
  o.alpha_minus1 = -1e-4;
  o.budget.max_iterations = 20000;
  const SolverReport rep = nonlinear_cg(p, u, o);
  ASSERT_TRUE(rep.ok()) << to_string(rep.status) << " after " << rep.iterations;
  // ‖u − û‖ ≤ ‖r‖/λ_min(K) with λ_min ≥ k/L·(1+µ/s²)/n² ~ 1 N/m here and ‖r‖ ≤ 1e-9‖f‖ ≈
  // 1e-7 N, so 1e-6 m leaves a factor 10.
  constexpr double kMinimizerTol = 1e-6;
  EXPECT_LE((u - ref).norm(), kMinimizerTol);
  EXPECT_EQ(u[0], 0.0);
  EXPECT_GT(rep.inner_iterations, 0);
  EXPECT_EQ(rep.energy_history.size(), std::size_t(rep.iterations + 1));
}

INSTANTIATE_TEST_SUITE_P(
    AllRules, NonlinearCgEquivalence,
    ::testing::Values(NcgCase{BetaRule::kFletcherReeves, LineSearchKind::kNewton},
                      NcgCase{BetaRule::kFletcherReeves, LineSearchKind::kSecant},
                      NcgCase{BetaRule::kFletcherReeves, LineSearchKind::kScaleDependentSecant},
                      NcgCase{BetaRule::kPolakRibiere, LineSearchKind::kNewton},
                      NcgCase{BetaRule::kPolakRibiere, LineSearchKind::kSecant},
                      NcgCase{BetaRule::kPolakRibiere, LineSearchKind::kScaleDependentSecant},
                      NcgCase{BetaRule::kFletcherReeves, LineSearchKind::kSecantWarmStart},
                      NcgCase{BetaRule::kPolakRibiere, LineSearchKind::kSecantWarmStart}));

TEST(NonlinearCg, QuadraticLikeLinearCg) {
  // On a quadratic Π the exact Newton line search makes NCG-FR linear CG: n steps at most in
  // exact arithmetic; we allow 2n for round-off.
  INCISE_SEEDED_RNG(rng, 54);
  QuadraticProblem p = test::random_spd_problem(rng, 20, 30.0, 1);
  VecX u = VecX::Zero(20);
  NonlinearCgOptions o;
  o.beta = BetaRule::kFletcherReeves;
  o.line_search = LineSearchKind::kNewton;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-10;
  const SolverReport rep = nonlinear_cg(p, u, o);
  ASSERT_TRUE(rep.ok());
  EXPECT_LE(rep.iterations, 40);
  EXPECT_LE((u - p.direct_solution()).norm(), 1e-8 * u.norm());
}

TEST(NonlinearCg, InfiniteEnergyRegionNeverEnteredNoNaN) {
  // A huge compressive load: the minimizer sits close to s → 0 where Π = +∞. Every trial point
  // that inverts a spring must be rejected; the result is finite and admissible either way.
  INCISE_SEEDED_RNG(rng, 55);
  const int n = 10;
  VecX f = VecX::Zero(n + 1);
  f[n] = -1e4;  // pushes the free end through the clamp if unopposed
  SpringChain p(n, 100.0, 0.0, 0.01, 0.1, f);
  for (LineSearchKind ls :
       {LineSearchKind::kNewton, LineSearchKind::kSecant, LineSearchKind::kScaleDependentSecant,
        LineSearchKind::kSecantWarmStart}) {
    VecX u = VecX::Zero(n + 1);
    NonlinearCgOptions o;
    o.line_search = ls;
    o.stop.epsilon = 1e-8;
    o.budget.max_iterations = 2000;
    const SolverReport rep = nonlinear_cg(p, u, o);
    SCOPED_TRACE(to_string(ls));
    EXPECT_TRUE(u.allFinite());
    double e = 0.0;
    EXPECT_EQ(p.energy(u, e), EvalStatus::kOk) << "returned an inverted state";
    EXPECT_TRUE(std::isfinite(rep.residual_norm));
    for (double h : rep.energy_history) EXPECT_TRUE(std::isfinite(h));
  }
  VecX u = VecX::Zero(n + 1);
  TruncatedNewtonOptions to;
  to.stop.epsilon = 1e-8;
  const SolverReport rep = truncated_newton(p, u, to);
  EXPECT_TRUE(u.allFinite());
  double e = 0.0;
  EXPECT_EQ(p.energy(u, e), EvalStatus::kOk);
  EXPECT_TRUE(rep.ok()) << to_string(rep.status);
}

TEST(NonlinearCg, StartInsideInvertedRegionReportsInverted) {
  VecX f = VecX::Zero(6);
  SpringChain p(5, 1.0, 0.0, 1.0, 0.1, f);
  VecX u = VecX::Zero(6);
  u[3] = -1.0;  // spring 3 has s < 0
  NonlinearCgOptions o;
  const SolverReport rep = nonlinear_cg(p, u, o);
  EXPECT_EQ(rep.status, StopReason::kInverted);
  TruncatedNewtonOptions to;
  const SolverReport rep2 = truncated_newton(p, u, to);
  EXPECT_EQ(rep2.status, StopReason::kInverted);
}

TEST(NonlinearCg, IndefiniteProblemReportsStatus) {
  INCISE_SEEDED_RNG(rng, 56);
  QuadraticProblem q = test::random_spd_problem(rng, 15, 10.0, 0);
  const Eigen::MatrixXd a = q.matrix() - 20.0 * Eigen::MatrixXd::Identity(15, 15);  // negative
  QuadraticProblem p(a, q.rhs(), std::vector<bool>(15, false), VecX::Ones(15));
  for (LineSearchKind ls :
       {LineSearchKind::kNewton, LineSearchKind::kSecant, LineSearchKind::kScaleDependentSecant,
        LineSearchKind::kSecantWarmStart}) {
    VecX u = VecX::Zero(15);
    NonlinearCgOptions o;
    o.line_search = ls;
    const SolverReport rep = nonlinear_cg(p, u, o);
    EXPECT_EQ(rep.status, StopReason::kIndefinite) << to_string(ls);
    // The message names the direction (negative curvature along a conjugate d restarts with
    // d = r, so only d = r ends the run), the curvature and the alternative.
    EXPECT_NE(rep.message.find("d = r (steepest descent): curvature along d"), std::string::npos)
        << rep.message;
    EXPECT_NE(rep.message.find("newton"), std::string::npos) << rep.message;
    EXPECT_TRUE(u.allFinite());
  }
  VecX u = VecX::Zero(15);
  TruncatedNewtonOptions to;
  to.preconditioner = Preconditioner::kNone;
  const SolverReport rep = truncated_newton(p, u, to);
  EXPECT_EQ(rep.status, StopReason::kIndefinite);
  EXPECT_TRUE(u.allFinite());
}

// Truncated Newton's default Jacobi inner CG: a free DOF without stiffness stops it at the
// first Newton step with kIndefinite naming step and DOF (plain inner CG converges: it never
// touches the DOF); fixed, the same DOF is not reported.
TEST(TruncatedNewton, JacobiReportsAFreeDofWithoutStiffness) {
  INCISE_SEEDED_RNG(rng, 58);
  const QuadraticProblem spd = test::random_spd_problem(rng, 16, 50.0, 2);
  TruncatedNewtonOptions to;
  to.stop.epsilon = 1e-10;
  QuadraticProblem free_zero = test::without_stiffness_at(spd, 11, /*fixed=*/false);
  VecX u = VecX::Zero(16);
  SolverReport rep = truncated_newton(free_zero, u, to);
  EXPECT_EQ(rep.status, StopReason::kIndefinite);
  EXPECT_NE(
      rep.message.find("Newton step 1: free DOF 11 has diagonal entry K_ii = 0, not positive"),
      std::string::npos)
      << rep.message;
  EXPECT_EQ(rep.iterations, 0);
  to.preconditioner = Preconditioner::kNone;
  u.setZero();
  rep = truncated_newton(free_zero, u, to);
  EXPECT_TRUE(rep.ok()) << rep.brief();
  to.preconditioner = Preconditioner::kJacobi;
  QuadraticProblem fixed_zero = test::without_stiffness_at(spd, 11, /*fixed=*/true);
  u.setZero();
  rep = truncated_newton(fixed_zero, u, to);
  EXPECT_TRUE(rep.ok()) << rep.brief();
  // A problem without a diagonal: Jacobi is refused, not replaced.
  test::DiagonalOverride none(spd, VecX());
  u.setZero();
  rep = truncated_newton(none, u, to);
  EXPECT_EQ(rep.status, StopReason::kPreconditionerUnavailable);
  EXPECT_EQ(u, VecX::Zero(16));
}

TEST(NonlinearCg, BudgetsHonoured) {
  INCISE_SEEDED_RNG(rng, 57);
  SpringChain p = make_chain(rng, 60, 20.0);
  NonlinearCgOptions o;
  o.stop.epsilon = 1e-14;
  o.budget.max_iterations = 5;
  VecX u = VecX::Zero(p.size());
  SolverReport rep = nonlinear_cg(p, u, o);
  EXPECT_EQ(rep.status, StopReason::kMaxIterations);
  EXPECT_EQ(rep.iterations, 5);
  o.budget.max_iterations = 1000000;
  o.budget.max_flops = 5e4;
  u.setZero();
  rep = nonlinear_cg(p, u, o);
  EXPECT_EQ(rep.status, StopReason::kFlopBudget);
  TruncatedNewtonOptions to;
  to.stop.epsilon = 1e-14;
  to.budget.max_iterations = 1;
  u.setZero();
  rep = truncated_newton(p, u, to);
  EXPECT_EQ(rep.status, StopReason::kMaxIterations);
  EXPECT_EQ(rep.iterations, 1);
}

// check_inversion (§4.3.1 post-check): random rotations + stretches keep every tetrahedron
// positive (ratio = det F), a reflection of one vertex through the opposite face inverts exactly
// that element, and the status says so.
TEST(InversionCheck, DetectsExactlyTheReflectedElements_Sec4_3_1) {
  INCISE_SEEDED_RNG(rng, 4321);
  std::uniform_real_distribution<double> unif(-1.0, 1.0);
  // Two tetrahedra sharing the face (1, 2, 3); the second is (4, 3, 2, 1)-oriented positively.
  Eigen::Matrix3Xd x(3, 5);
  x << 0, 1, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 0, 1, 1;
  Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic> cells(4, 2);
  cells << 0, 4, 1, 2, 2, 1, 3, 3;
  auto volume = [&](int e, const VecX& u) {
    Vec3 p[4];
    for (int a = 0; a < 4; ++a) p[a] = x.col(cells(a, e)) + u.segment<3>(3 * cells(a, e));
    return (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0]);
  };
  ASSERT_GT(volume(0, VecX::Zero(15)), 0.0);
  ASSERT_GT(volume(1, VecX::Zero(15)), 0.0);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Quaterniond q(unif(rng), unif(rng), unif(rng), unif(rng));
    const Mat3 f = q.normalized().toRotationMatrix() * (1.5 + 0.5 * unif(rng));
    VecX u(15);
    for (int n = 0; n < 5; ++n) u.segment<3>(3 * n) = f * x.col(n) - x.col(n);
    const InversionCheck ok = check_inversion(x, cells, u);
    EXPECT_EQ(ok.status, InversionStatus::kNoneInverted);
    EXPECT_EQ(ok.inverted_elements, 0);
    // min det F of a uniform deformation is det f (1e-12: rounding of 3×3 products).
    EXPECT_NEAR(ok.min_volume_ratio, f.determinant(), 1e-12 * f.determinant());
  }
  // Push vertex 0 through the face (1, 2, 3): only element 0 inverts.
  VecX u = VecX::Zero(15);
  u.segment<3>(0) = Vec3(0.6, 0.6, 0.6);
  const InversionCheck bad = check_inversion(x, cells, u);
  EXPECT_EQ(bad.status, InversionStatus::kInverted);
  EXPECT_EQ(bad.inverted_elements, 1);
  ASSERT_EQ(bad.elements.size(), 1u);
  EXPECT_EQ(bad.elements[0], 0);
  EXPECT_LT(bad.min_volume_ratio, 0.0);
  EXPECT_STREQ(to_string(bad.status), "inverted");
  EXPECT_THROW((void)check_inversion(x, cells, VecX::Zero(14)), ParameterError);
}

}  // namespace
}  // namespace incise::solver
