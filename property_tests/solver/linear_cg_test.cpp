/// Linear CG (thesis §2.4.1, §3.1): equivalence with a dense direct solve, Jacobi variant,
/// stopping rules (6.8)/(6.9), budgets and the indefinite status.
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/eigen_estimates.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>
#include <incise/solver/truncated_newton.hpp>
#include <incise_test/seed.hpp>

#include "test_problems.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

namespace incise::solver {
namespace {

using test::QuadraticProblem;
using test::random_spd_problem;

// CG ≡ dense LDLT on the free block: for ε = 1e-12 relative and cond ≤ 1e3, the error bound
// ‖x − x̂‖ ≤ cond·ε‖x̂‖ gives ≤ 1e-9; 1e-8 leaves a margin for the recursive-residual drift.
constexpr double kDirectTol = 1e-8;

TEST(LinearCg, EqualsDenseLdltOnRandomSpd_Sec2_4_1) {
  INCISE_SEEDED_RNG(rng, 41);
  for (int trial = 0; trial < test::scaled(5); ++trial) {
    const int n = 20 + 7 * trial;
    QuadraticProblem p = random_spd_problem(rng, n, 1e3, 3);
    for (Preconditioner pc : {Preconditioner::kNone, Preconditioner::kJacobi}) {
      VecX u = VecX::Zero(n);
      LinearCgOptions o;
      o.stop.rule = ResidualRule::kExternalForce;
      o.stop.epsilon = 1e-12;
      o.preconditioner = pc;
      const SolverReport rep = linear_cg(p, u, o);
      ASSERT_TRUE(rep.ok()) << to_string(rep.status);
      const VecX x = p.direct_solution();
      EXPECT_LE((u - x).norm(), kDirectTol * x.norm());
      EXPECT_EQ(u[0], 0.0);  // fixed DOFs never move (§3.1)
      EXPECT_LE(rep.residual_norm, rep.threshold);
      EXPECT_EQ(rep.residual_history.size(), std::size_t(rep.iterations + 1));
      EXPECT_GT(rep.flops, 0u);
    }
  }
}

TEST(LinearCg, EnergyHistoryIsExactAndDecreasing) {
  INCISE_SEEDED_RNG(rng, 42);
  QuadraticProblem p = random_spd_problem(rng, 30, 1e2, 2);
  VecX u = VecX::Zero(30);
  LinearCgOptions o;
  o.stop.epsilon = 1e-10;
  const SolverReport rep = linear_cg(p, u, o);
  ASSERT_TRUE(rep.ok());
  double e = 0.0;
  ASSERT_EQ(p.energy(u, e), EvalStatus::kOk);
  // Recursive energy vs recomputed: round-off of O(n) operations on O(1) numbers.
  constexpr double kEnergyTol = 1e-10;
  EXPECT_NEAR(rep.energy_history.back(), e, kEnergyTol * std::max(1.0, std::abs(e)));
  for (std::size_t i = 1; i < rep.energy_history.size(); ++i)
    EXPECT_LE(rep.energy_history[i], rep.energy_history[i - 1]);
}

TEST(LinearCg, JacobiHelpsBadlyScaledDiagonal) {
  // Diagonal scaling makes a badly scaled SPD matrix well conditioned: PCG must need fewer steps.
  INCISE_SEEDED_RNG(rng, 43);
  QuadraticProblem base = random_spd_problem(rng, 40, 10.0, 0);
  VecX s(40);
  for (int i = 0; i < 40; ++i) s[i] = std::pow(10.0, 3.0 * i / 39.0);
  const Eigen::MatrixXd a = s.asDiagonal() * base.matrix() * s.asDiagonal();
  QuadraticProblem p(a, base.rhs(), std::vector<bool>(40, false), VecX::Ones(40));
  LinearCgOptions o;
  o.stop.epsilon = 1e-8;
  o.stop.rule = ResidualRule::kExternalForce;
  VecX u1 = VecX::Zero(40), u2 = VecX::Zero(40);
  const SolverReport plain = linear_cg(p, u1, o);
  o.preconditioner = Preconditioner::kJacobi;
  const SolverReport jac = linear_cg(p, u2, o);
  ASSERT_TRUE(jac.ok());
  EXPECT_LT(jac.iterations, plain.iterations);
}

// LinearCgOptions::apply_preconditioner (the operator preconditioner the 3D needle passes,
// needle/stick_slip.hpp): (a) the exact inverse of the free block gives the direct solution in
// one step; (b) the callback z = D⁻¹ r gives Preconditioner::kJacobi's iterates bit for bit
// (same operations, and linear_cg's projection of z is a no-op there); (c) garbage the callback
// writes at fixed DOFs is projected away (fixed DOFs never move, §3.1); (d) both preconditioner
// options at once are a usage error.
TEST(LinearCg, OperatorPreconditionerExactInverseJacobiEquivalenceAndProjection_Sec2_4_1) {
  INCISE_SEEDED_RNG(rng, 47);
  const int n = 36;
  QuadraticProblem p = random_spd_problem(rng, n, 1e3, 4);
  const VecX x = p.direct_solution();
  const std::vector<int> f = p.free_dofs();
  const int m = int(f.size());
  Eigen::MatrixXd af(m, m);
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j) af(i, j) = p.matrix()(f[i], f[j]);
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(af);
  LinearCgOptions o;
  o.stop.rule = ResidualRule::kExternalForce;
  o.stop.epsilon = 1e-12;
  long calls = 0;
  // (a) + (c): B = (free block of A)⁻¹, with NaN written at the fixed DOFs.
  o.apply_preconditioner = [&](const VecX& r, VecX& z) {
    ++calls;
    VecX rf(m);
    for (int i = 0; i < m; ++i) rf[i] = r[f[i]];
    const VecX zf = ldlt.solve(rf);
    z = VecX::Constant(r.size(), std::nan(""));
    for (int i = 0; i < m; ++i) z[f[i]] = zf[i];
  };
  VecX u = VecX::Zero(n);
  const SolverReport exact = linear_cg(p, u, o);
  ASSERT_TRUE(exact.ok()) << to_string(exact.status) << ": " << exact.message;
  // One step solves K x = b up to the dense factorization's round-off (cond 1e3 · ε ≪ 1e-8).
  EXPECT_EQ(exact.iterations, 1);
  EXPECT_GE(calls, 1);
  EXPECT_LE((u - x).norm(), kDirectTol * x.norm());
  EXPECT_TRUE(u.allFinite());
  for (int i = 0; i < 4; ++i) EXPECT_EQ(u[i], 0.0) << "fixed DOF " << i << " moved";

  // (b) the Jacobi scaling as a callback against the built-in kJacobi, bitwise.
  const JacobiDiagonal jd = jacobi_inverse_diagonal(p, VecX::Zero(n));
  ASSERT_TRUE(jd.ok());
  LinearCgOptions oj;
  oj.stop = o.stop;
  oj.apply_preconditioner = [&](const VecX& r, VecX& z) { z = jd.inverse.cwiseProduct(r); };
  LinearCgOptions ok = oj;
  ok.apply_preconditioner = nullptr;
  ok.preconditioner = Preconditioner::kJacobi;
  VecX u1 = VecX::Zero(n), u2 = VecX::Zero(n);
  const SolverReport r1 = linear_cg(p, u1, oj), r2 = linear_cg(p, u2, ok);
  ASSERT_TRUE(r1.ok() && r2.ok());
  EXPECT_GT(r1.iterations, 1);
  EXPECT_EQ(r1.iterations, r2.iterations);
  EXPECT_EQ(r1.residual_history, r2.residual_history);
  EXPECT_EQ(u1, u2);

  // (d) both set.
  oj.preconditioner = Preconditioner::kJacobi;
  VecX u3 = VecX::Zero(n);
  EXPECT_THROW((void)linear_cg(p, u3, oj), UsageError);
  EXPECT_EQ(u3, VecX::Zero(n));
}

TEST(LinearCg, ReactionRule6_9ConvergesWithoutExternalLoad) {
  // Prescribed non-zero displacement at a fixed DOF and no load: (6.8) has threshold 0, (6.9)
  // uses the reaction force and converges.
  INCISE_SEEDED_RNG(rng, 44);
  QuadraticProblem q = random_spd_problem(rng, 25, 50.0, 2);
  std::vector<bool> fixed(25, false);
  fixed[0] = fixed[1] = true;
  QuadraticProblem p2(q.matrix(), VecX::Zero(25), fixed, VecX::Ones(25));
  VecX u = VecX::Zero(25);
  u[0] = 0.01;  // prescribed displacement
  LinearCgOptions o;
  o.stop.rule = ResidualRule::kWithReactions;
  o.stop.epsilon = 1e-9;
  o.stop.force_scale = 1.0;
  const SolverReport rep = linear_cg(p2, u, o);
  ASSERT_TRUE(rep.ok()) << to_string(rep.status);
  EXPECT_EQ(u[0], 0.01);
  EXPECT_GT(rep.threshold, 0.0);
}

TEST(LinearCg, ThresholdFormula6_9) {
  StoppingRule r;
  r.rule = ResidualRule::kWithReactions;
  r.epsilon = 1e-3;
  r.epsilon_round = 1e-10;
  r.force_scale = 400.0;
  // ε√(3² + 4²) + 400/√16·1e-10 = 5e-3 + 1e-8, evaluated in floating point.
  EXPECT_DOUBLE_EQ(residual_threshold(r, 3.0, 4.0, 16), 5e-3 + 1e-8);
  r.rule = ResidualRule::kExternalForce;
  EXPECT_DOUBLE_EQ(residual_threshold(r, 3.0, 4.0, 16), 3e-3);
}

TEST(LinearCg, BudgetsHonoured) {
  INCISE_SEEDED_RNG(rng, 45);
  QuadraticProblem p = random_spd_problem(rng, 40, 1e4, 0);
  LinearCgOptions o;
  o.stop.epsilon = 1e-14;
  o.budget.max_iterations = 3;
  VecX u = VecX::Zero(40);
  SolverReport rep = linear_cg(p, u, o);
  EXPECT_EQ(rep.status, StopReason::kMaxIterations);
  EXPECT_EQ(rep.iterations, 3);
  o.budget.max_iterations = 100000;
  o.budget.max_flops = 20000;  // one product costs 2·40² = 3200 flops
  u.setZero();
  rep = linear_cg(p, u, o);
  EXPECT_EQ(rep.status, StopReason::kFlopBudget);
  EXPECT_GE(rep.flops, 20000u);
  EXPECT_LT(rep.flops, 20000u + 2 * 3200u + 2000u);  // overshoot at most one iteration
  o.budget.max_flops = std::numeric_limits<double>::infinity();
  o.budget.max_seconds = 0.0;
  u.setZero();
  rep = linear_cg(p, u, o);
  EXPECT_EQ(rep.status, StopReason::kTimeBudget);
  EXPECT_TRUE(u.allFinite());
}

TEST(LinearCg, IndefiniteReportedNoNaN) {
  INCISE_SEEDED_RNG(rng, 46);
  QuadraticProblem q = random_spd_problem(rng, 20, 10.0, 0);
  Eigen::MatrixXd a = q.matrix() - 5.0 * Eigen::MatrixXd::Identity(20, 20);  // λ ∈ [−4, 5]
  QuadraticProblem p(a, q.rhs(), std::vector<bool>(20, false), VecX::Ones(20));
  VecX u = VecX::Zero(20);
  LinearCgOptions o;
  o.stop.epsilon = 1e-10;
  const SolverReport rep = linear_cg(p, u, o);
  EXPECT_EQ(rep.status, StopReason::kIndefinite);
  EXPECT_TRUE(u.allFinite());
}

// Jacobi never silently becomes plain CG: a free DOF without stiffness (K_ii = 0) is an
// indefinite tangent and named; plain CG, which never touches that DOF, still converges; the
// same DOF fixed is projected out and not reported.
TEST(LinearCg, JacobiReportsAFreeDofWithoutStiffnessAsIndefinite) {
  INCISE_SEEDED_RNG(rng, 48);
  const QuadraticProblem spd = random_spd_problem(rng, 20, 1e2, 2);
  LinearCgOptions o;
  o.stop.epsilon = 1e-10;
  o.preconditioner = Preconditioner::kJacobi;
  QuadraticProblem free_zero = test::without_stiffness_at(spd, 7, /*fixed=*/false);
  VecX u = VecX::Zero(20);
  SolverReport rep = linear_cg(free_zero, u, o);
  EXPECT_EQ(rep.status, StopReason::kIndefinite);
  EXPECT_NE(rep.message.find("free DOF 7 has diagonal entry K_ii = 0, not positive"),
            std::string::npos)
      << rep.message;
  EXPECT_EQ(rep.iterations, 0);
  EXPECT_EQ(u, VecX::Zero(20));
  o.preconditioner = Preconditioner::kNone;
  rep = linear_cg(free_zero, u, o);
  EXPECT_TRUE(rep.ok()) << rep.brief();
  QuadraticProblem fixed_zero = test::without_stiffness_at(spd, 7, /*fixed=*/true);
  o.preconditioner = Preconditioner::kJacobi;
  u.setZero();
  rep = linear_cg(fixed_zero, u, o);
  EXPECT_TRUE(rep.ok()) << rep.brief();
  EXPECT_TRUE(rep.message.empty());
}

// A negative free diagonal entry is kIndefinite, a NaN one kNonFinite (before any step, naming
// the DOF), a missing diagonal kPreconditionerUnavailable; u is never changed.
TEST(LinearCg, JacobiReportsNegativeNonFiniteAndMissingDiagonals) {
  INCISE_SEEDED_RNG(rng, 49);
  const QuadraticProblem spd = random_spd_problem(rng, 12, 10.0, 1);
  LinearCgOptions o;
  o.preconditioner = Preconditioner::kJacobi;
  VecX negative = spd.matrix().diagonal(), nan = negative;
  negative[4] = -2.5;
  nan[9] = std::numeric_limits<double>::quiet_NaN();
  nan[3] = -1.0;  // a non-positive entry too: the non-finite one is reported first
  struct Case {
    VecX diagonal;
    StopReason status;
    const char* names;
  };
  for (const Case& c : {Case{negative, StopReason::kIndefinite,
                             "free DOF 4 has diagonal entry K_ii = -2.5, not positive"},
                        Case{nan, StopReason::kNonFinite, "free DOF 9 has diagonal entry"},
                        Case{VecX(), StopReason::kPreconditionerUnavailable, "hessian_diagonal"}}) {
    test::DiagonalOverride p(spd, c.diagonal);
    VecX u = VecX::Zero(12);
    const SolverReport rep = linear_cg(p, u, o);
    EXPECT_EQ(rep.status, c.status) << rep.brief();
    EXPECT_NE(rep.message.find(c.names), std::string::npos) << rep.message;
    EXPECT_EQ(rep.iterations, 0);
    EXPECT_EQ(u, VecX::Zero(12));
    EXPECT_EQ(rep.residual_norm, spd.external_force_norm());  // the start, not NaN
  }
  // The NaN entry at a fixed DOF (DOF 0) is never read.
  VecX fixed_nan = spd.matrix().diagonal();
  fixed_nan[0] = std::numeric_limits<double>::quiet_NaN();
  test::DiagonalOverride p(spd, fixed_nan);
  const JacobiDiagonal jd = jacobi_inverse_diagonal(p, VecX::Zero(12));
  ASSERT_TRUE(jd.ok()) << jd.brief();
  EXPECT_EQ(jd.inverse[0], 0.0);
  EXPECT_EQ(jd.inverse[5], 1.0 / spd.matrix()(5, 5));
}

TEST(ProjectedCg, SolvesSpdSystemFromZero) {
  INCISE_SEEDED_RNG(rng, 47);
  QuadraticProblem p = random_spd_problem(rng, 30, 100.0, 4);
  CostMeter meter(p);
  VecX x;
  const InnerCgResult res =
      projected_cg([&](const VecX& in, VecX& out) { return p.hessian_product(in, in, out); }, p,
                   VecX(), p.rhs(), x, 1e-12 * p.rhs().norm(), 1000, meter);
  ASSERT_EQ(res.status, StopReason::kConverged);
  EXPECT_LE((x - p.direct_solution()).norm(), kDirectTol * x.norm());
}

// Lanczos extremes from the CG coefficients (Saad §6.7.3) reproduce the extreme eigenvalues of
// the operator: random SPD matrices with spectrum exactly [1, cond] (random_spd_problem).
TEST(LinearCg, LanczosFromCoefficientsFindsExtremeEigenvalues_Sec2_4_1) {
  INCISE_SEEDED_RNG(rng, 47);
  for (int trial = 0; trial < test::scaled(4); ++trial) {
    const int n = 30 + 10 * trial;
    const double cond = std::pow(10.0, 1 + trial);
    QuadraticProblem p = random_spd_problem(rng, n, cond, 0);
    VecX u = VecX::Zero(n);
    CgCoefficients c;
    LinearCgOptions o;
    o.stop.rule = ResidualRule::kExternalForce;
    o.stop.epsilon = 1e-12;
    o.coefficients = &c;
    const SolverReport rep = linear_cg(p, u, o);
    ASSERT_TRUE(rep.ok()) << to_string(rep.status);
    ASSERT_EQ(c.alpha.size(), std::size_t(rep.iterations));
    const LanczosExtremes l = cg_lanczos_extremes(c);
    ASSERT_TRUE(l.converged);
    // A converged CG run has resolved the extreme eigenvectors: the extreme Ritz values agree
    // with the spectrum to far better than 1e-6 (rounding in the recursions, not truncation).
    constexpr double kRitzTol = 1e-6;
    EXPECT_NEAR(l.smallest, 1.0, kRitzTol);
    EXPECT_NEAR(l.largest, cond, kRitzTol * cond);
    EXPECT_NEAR(l.condition(), cond, 2 * kRitzTol * cond);
  }
  EXPECT_THROW((void)cg_lanczos_extremes(CgCoefficients{}), ParameterError);
}

// Issue 18: a load whose norm overflows the doubles (entries 1e155: ||b||^2 > DBL_MAX) made
// the threshold eps ||f_ext|| infinite, and every solver "converged" at once with ||r|| = inf.
// Now each of the four returns kNonFinite before iterating, u unchanged, with the message of
// solver::external_force_is_finite; the same problem at scale 1 converges (control).
TEST(ExternalForce, NormThatOverflowsIsNonFiniteInEverySolver) {
  for (double scale : {1e155, 1.0}) {
    INCISE_SEEDED_RNG(rng, 41);
    QuadraticProblem base = random_spd_problem(rng, 12, 10.0, 2);
    QuadraticProblem p(
        base.matrix(), base.rhs() * scale,
        {true, true, false, false, false, false, false, false, false, false, false, false},
        VecX::Ones(12));
    const bool overflows = !std::isfinite(p.external_force_norm());
    ASSERT_EQ(overflows, scale == 1e155) << p.external_force_norm();
    RelaxationOptions common;
    common.stop.rule = ResidualRule::kExternalForce;
    common.stop.epsilon = 1e-6;
    std::vector<std::pair<const char*, SolverReport>> reports;
    VecX u = VecX::Zero(12);
    {
      LinearCgOptions o;
      static_cast<RelaxationOptions&>(o) = common;
      u.setZero();
      reports.emplace_back("linear_cg", linear_cg(p, u, o));
    }
    {
      NonlinearCgOptions o;
      static_cast<RelaxationOptions&>(o) = common;
      u.setZero();
      reports.emplace_back("nonlinear_cg", nonlinear_cg(p, u, o));
    }
    {
      TruncatedNewtonOptions o;
      static_cast<RelaxationOptions&>(o) = common;
      u.setZero();
      reports.emplace_back("truncated_newton", truncated_newton(p, u, o));
    }
    {
      DynamicRelaxationOptions o;
      static_cast<RelaxationOptions&>(o) = common;
      o.time_step = 0.1;  // 2/sqrt(lambda_max) = 0.63 for cond 10, unit masses
      o.damping = 2.0;
      o.budget.max_iterations = 20000;
      u.setZero();
      reports.emplace_back("dynamic_relaxation", dynamic_relaxation(p, u, o));
      if (overflows) {
        EXPECT_EQ(u.norm(), 0.0);
      }
    }
    for (const auto& [name, rep] : reports) {
      SCOPED_TRACE(std::string(name) + (overflows ? " (entries 1e155)" : " (control)"));
      if (overflows) {
        EXPECT_EQ(rep.status, StopReason::kNonFinite) << rep.brief();
        EXPECT_EQ(rep.iterations, 0);
        EXPECT_NE(rep.message.find("the external load is not finite"), std::string::npos)
            << rep.message;
      } else {
        EXPECT_TRUE(rep.ok()) << rep.brief();
        EXPECT_TRUE(std::isfinite(rep.residual_norm));
      }
    }
  }
}

}  // namespace
}  // namespace incise::solver
