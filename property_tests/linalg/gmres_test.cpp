/// \file gmres_test.cpp
/// Restarted, right-preconditioned GMRES (linalg/gmres.hpp; the eq. 17 solver of Yeung et al.
/// 2016): convergence to the requested tolerance on random SPD and nonsymmetric systems,
/// preconditioning, restarts, the special cases of the contract (b = 0, warm start, iteration
/// cap) and its failure statuses and parameter errors.

#include <incise/core/error.hpp>
#include <incise/linalg/gmres.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include <cmath>
#include <limits>
#include <random>

namespace incise::test {
namespace {

using linalg::gmres;
using linalg::GmresOperator;
using linalg::GmresOptions;
using linalg::GmresReport;
using linalg::GmresStatus;

GmresOperator dense_operator(const Eigen::MatrixXd& a) {
  return [&a](const Eigen::VectorXd& x, Eigen::VectorXd& y) { y = a * x; };
}

Eigen::VectorXd random_vector(int n, std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v(i) = g(rng);
  return v;
}

// Q diag(λ) Qᵀ with λ log-spaced in [1, κ] and Q a random orthogonal matrix.
Eigen::MatrixXd random_spd(int n, double kappa, std::mt19937_64& rng) {
  Eigen::MatrixXd z(n, n);
  for (int j = 0; j < n; ++j) z.col(j) = random_vector(n, rng);
  const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(z).householderQ();
  Eigen::VectorXd lambda(n);
  for (int i = 0; i < n; ++i) lambda(i) = std::pow(kappa, static_cast<double>(i) / (n - 1));
  return q * lambda.asDiagonal() * q.transpose();
}

// 3 I + G/√n with G standard normal: eigenvalues in a disc of radius ≈ 1 around 3 (circular
// law), so the matrix is well conditioned (κ ≈ 2) and far from normal.
Eigen::MatrixXd random_nonsymmetric(int n, std::mt19937_64& rng) {
  Eigen::MatrixXd m(n, n);
  for (int j = 0; j < n; ++j) m.col(j) = random_vector(n, rng) / std::sqrt(n);
  return m + 3.0 * Eigen::MatrixXd::Identity(n, n);
}

double true_relative_residual(const Eigen::MatrixXd& a, const Eigen::VectorXd& x,
                              const Eigen::VectorXd& b) {
  return (b - a * x).norm() / b.norm();
}

// The reported (Givens) residual and the true residual ‖b − A x‖/‖b‖ agree up to round-off of
// order n·eps·κ(A) ≤ 1e-11 for these matrices (n ≤ 60, κ ≤ 1e3): that much slack on top of
// the tolerance.
constexpr double kResidualSlack = 1e-11;

TEST(Gmres, ConvergesToTheRequestedToleranceOnRandomSpdAndNonsymmetricSystems) {
  INCISE_SEEDED_RNG(rng, 23);
  for (int trial = 0; trial < scaled(4); ++trial) {
    const int n = 30 + 10 * trial;
    const Eigen::MatrixXd spd = random_spd(n, 1e3, rng);
    const Eigen::MatrixXd nonsym = random_nonsymmetric(n, rng);
    const Eigen::VectorXd b = random_vector(n, rng);
    for (const Eigen::MatrixXd* a : {&spd, &nonsym}) {
      for (double tol : {1e-4, 1e-8, 1e-12}) {
        GmresOptions o;
        o.tolerance = tol;
        Eigen::VectorXd x;
        const GmresReport r = gmres(dense_operator(*a), {}, b, x, o);
        SCOPED_TRACE("n = " + std::to_string(n) + ", tolerance " + std::to_string(tol));
        ASSERT_TRUE(r.ok()) << linalg::to_string(r.status);
        EXPECT_LE(r.relative_residual, tol);
        EXPECT_LE(true_relative_residual(*a, x, b), tol + kResidualSlack);
        // Full GMRES (restart 60 ≥ n) terminates in at most n steps in exact arithmetic.
        EXPECT_LE(r.iterations, n);
        ASSERT_EQ(static_cast<int>(r.residual_history.size()), r.iterations + 1);
        EXPECT_EQ(r.residual_history.front(), 1.0);  // from x = 0: r₀ = b
        // GMRES minimizes the residual over nested Krylov spaces: the history never rises.
        for (size_t k = 1; k < r.residual_history.size(); ++k)
          EXPECT_LE(r.residual_history[k], r.residual_history[k - 1]) << "iteration " << k;
        EXPECT_GE(r.hessenberg_condition, 1.0);
      }
    }
  }
}

TEST(Gmres, SolutionEqualsDirectSolve) {
  INCISE_SEEDED_RNG(rng, 17);
  const int n = 40;
  const Eigen::MatrixXd a = random_nonsymmetric(n, rng);
  const Eigen::VectorXd b = random_vector(n, rng);
  GmresOptions o;
  o.tolerance = 1e-13;
  Eigen::VectorXd x;
  ASSERT_TRUE(gmres(dense_operator(a), {}, b, x, o).ok());
  const Eigen::VectorXd xd = a.partialPivLu().solve(b);
  // Forward error ≤ κ(A)·(residual) with κ(A) ≈ 2 here: 1e-12 leaves a factor of 5 for round-off.
  EXPECT_LE((x - xd).norm(), 1e-12 * xd.norm());
}

// Right preconditioning: GMRES on A M⁻¹ z = b, x = M⁻¹ z. A = B D has columns scaled over four
// decades (D = diag(10^(4i/(n−1)))), so plain GMRES needs many iterations; M = D makes
// A M⁻¹ = B, well conditioned. The monitored residual stays the true residual of A x = b.
TEST(Gmres, RightPreconditioningReducesIterationsAndKeepsTheTrueResidual) {
  INCISE_SEEDED_RNG(rng, 29);
  const int n = 50;
  const Eigen::MatrixXd bmat = random_nonsymmetric(n, rng);
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) d(i) = std::pow(10.0, 4.0 * i / (n - 1));
  const Eigen::MatrixXd a = bmat * d.asDiagonal();
  const Eigen::VectorXd b = random_vector(n, rng);
  GmresOptions o;
  o.tolerance = 1e-10;
  Eigen::VectorXd x0, x1;
  const GmresReport plain = gmres(dense_operator(a), {}, b, x0, o);
  const auto prec = [&d](const Eigen::VectorXd& v, Eigen::VectorXd& z) { z = v.cwiseQuotient(d); };
  const GmresReport pre = gmres(dense_operator(a), prec, b, x1, o);
  ASSERT_TRUE(plain.ok()) << linalg::to_string(plain.status);
  ASSERT_TRUE(pre.ok()) << linalg::to_string(pre.status);
  EXPECT_LT(pre.iterations, plain.iterations);
  // κ(A) ≈ 2e4 here: the true residual may exceed the estimate by n·eps·κ ≈ 2e-10 at most.
  EXPECT_LE(true_relative_residual(a, x1, b), o.tolerance + 1e-9);
  // With the exact inverse as right preconditioner A M⁻¹ = I: one iteration.
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(a);
  const auto exact = [&lu](const Eigen::VectorXd& v, Eigen::VectorXd& z) { z = lu.solve(v); };
  Eigen::VectorXd x2;
  const GmresReport one = gmres(dense_operator(a), exact, b, x2, o);
  ASSERT_TRUE(one.ok());
  EXPECT_EQ(one.iterations, 1);
}

TEST(Gmres, RestartedRunsConvergeAndCountTheirCycles) {
  INCISE_SEEDED_RNG(rng, 31);
  const int n = 60;
  const Eigen::MatrixXd a = random_spd(n, 1e2, rng);
  const Eigen::VectorXd b = random_vector(n, rng);
  GmresOptions o;
  o.tolerance = 1e-10;
  o.restart = 5;
  Eigen::VectorXd x;
  const GmresReport r = gmres(dense_operator(a), {}, b, x, o);
  ASSERT_TRUE(r.ok()) << linalg::to_string(r.status);
  EXPECT_GT(r.iterations, o.restart);  // κ = 100 needs more than 5 steps for 1e-10
  EXPECT_GE(r.restarts, 1);
  // Each completed cycle is `restart` steps; the last one may be partial.
  EXPECT_LE(r.restarts * o.restart, r.iterations);
  EXPECT_LE(r.iterations, (r.restarts + 1) * o.restart);
  EXPECT_LE(true_relative_residual(a, x, b), o.tolerance + kResidualSlack);
  // GMRES(1) is the minimal-residual iteration; it converges when the symmetric part of A is
  // positive definite (for 3 I + G/√n its eigenvalues approach 3 ± √2: positive).
  const Eigen::MatrixXd c = random_nonsymmetric(n, rng);
  o.restart = 1;
  o.max_iterations = 10000;
  Eigen::VectorXd x1;
  const GmresReport r1 = gmres(dense_operator(c), {}, b, x1, o);
  ASSERT_TRUE(r1.ok()) << linalg::to_string(r1.status);
  EXPECT_GE(r1.restarts, r1.iterations - 1);
  EXPECT_LE(r1.restarts, r1.iterations);
  EXPECT_LE(true_relative_residual(c, x1, b), o.tolerance + kResidualSlack);
}

TEST(Gmres, ZeroRightHandSideAndWarmStart) {
  INCISE_SEEDED_RNG(rng, 37);
  const int n = 20;
  const Eigen::MatrixXd a = random_nonsymmetric(n, rng);
  Eigen::VectorXd x = random_vector(n, rng);  // a nonzero initial guess
  const GmresReport zero = gmres(dense_operator(a), {}, Eigen::VectorXd::Zero(n), x);
  EXPECT_EQ(zero.status, GmresStatus::kConverged);
  EXPECT_EQ(zero.iterations, 0);
  EXPECT_EQ(x, Eigen::VectorXd::Zero(n));  // b = 0 returns x = 0 exactly
  // An initial guess of the wrong size is replaced by zero.
  Eigen::VectorXd y(3);
  y.setOnes();
  const Eigen::VectorXd b = random_vector(n, rng);
  ASSERT_TRUE(gmres(dense_operator(a), {}, b, y).ok());
  EXPECT_EQ(y.size(), n);
  GmresOptions loose;
  loose.tolerance = 1e-8;  // y meets 1e-12: a warm start at the solution does no iteration
  EXPECT_EQ(gmres(dense_operator(a), {}, b, y, loose).iterations, 0);
  // A warm start near the solution converges from there: its first history entry is small.
  Eigen::VectorXd w = y + 1e-6 * random_vector(n, rng);
  const GmresReport warm = gmres(dense_operator(a), {}, b, w);
  ASSERT_TRUE(warm.ok());
  EXPECT_LT(warm.residual_history.front(), 1e-4);
}

TEST(Gmres, IterationCapIsAStatusWithAFiniteIterate) {
  INCISE_SEEDED_RNG(rng, 19);
  const int n = 30;
  const Eigen::MatrixXd a = random_spd(n, 1e3, rng);
  const Eigen::VectorXd b = random_vector(n, rng);
  GmresOptions o;
  o.max_iterations = 3;
  Eigen::VectorXd x;
  const GmresReport r = gmres(dense_operator(a), {}, b, x, o);
  EXPECT_EQ(r.status, GmresStatus::kMaxIterations);
  EXPECT_EQ(r.iterations, 3);
  EXPECT_GT(r.relative_residual, o.tolerance);
  EXPECT_TRUE(x.allFinite());
  // The iterate is GMRES's 3-step minimizer: its residual is the reported one (round-off aside).
  EXPECT_NEAR(true_relative_residual(a, x, b), r.relative_residual, kResidualSlack);
  o.max_iterations = 0;
  Eigen::VectorXd x0;
  const GmresReport r0 = gmres(dense_operator(a), {}, b, x0, o);
  EXPECT_EQ(r0.status, GmresStatus::kMaxIterations);
  EXPECT_EQ(r0.iterations, 0);
  EXPECT_EQ(x0, Eigen::VectorXd::Zero(n));
}

TEST(Gmres, SingularOperatorIsBreakdownOrStagnation) {
  const int n = 30;
  // A = diag(1, …, 1, 0) and b = e₀ + e_{n−1}: inconsistent, no solution.
  Eigen::VectorXd dg = Eigen::VectorXd::Ones(n);
  dg(n - 1) = 0;
  const auto sing = [&dg](const Eigen::VectorXd& v, Eigen::VectorXd& y) { y = dg.cwiseProduct(v); };
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  b(n - 1) = 1;
  b(0) = 1;
  Eigen::VectorXd x;
  const GmresReport r = gmres(sing, {}, b, x);
  EXPECT_TRUE(r.status == GmresStatus::kBreakdown || r.status == GmresStatus::kStagnated)
      << linalg::to_string(r.status);
  EXPECT_TRUE(x.allFinite());
  EXPECT_GT(r.relative_residual, 0.5);  // the e_{n−1} part of b cannot be reached: ≥ 1/√2
}

TEST(Gmres, NonFiniteDataIsReported) {
  INCISE_SEEDED_RNG(rng, 41);
  const int n = 12;
  const Eigen::MatrixXd a = random_nonsymmetric(n, rng);
  const Eigen::VectorXd b = random_vector(n, rng);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  Eigen::VectorXd x;
  Eigen::VectorXd bad_b = b;
  bad_b(3) = nan;
  EXPECT_EQ(gmres(dense_operator(a), {}, bad_b, x).status, GmresStatus::kNonFinite);
  bad_b(3) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(gmres(dense_operator(a), {}, bad_b, x).status, GmresStatus::kNonFinite);
  const auto nan_op = [nan](const Eigen::VectorXd& v, Eigen::VectorXd& y) { y = v * nan; };
  EXPECT_EQ(gmres(nan_op, {}, b, x).status, GmresStatus::kNonFinite);
  const auto inf_prec = [](const Eigen::VectorXd& v, Eigen::VectorXd& z) {
    z = v / 0.0;  // ±Inf (or NaN for zero entries)
  };
  EXPECT_EQ(gmres(dense_operator(a), inf_prec, b, x).status, GmresStatus::kNonFinite);
  // A non-finite initial guess is reported, not iterated on.
  Eigen::VectorXd guess = Eigen::VectorXd::Zero(n);
  guess(0) = nan;
  EXPECT_EQ(gmres(dense_operator(a), {}, b, guess).status, GmresStatus::kNonFinite);
}

TEST(Gmres, BadOptionsThrowParameterError) {
  const Eigen::MatrixXd a = Eigen::MatrixXd::Identity(4, 4);
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(4);
  Eigen::VectorXd x;
  GmresOptions o;
  o.restart = 0;
  EXPECT_THROW((void)gmres(dense_operator(a), {}, b, x, o), ParameterError);
  o = {};
  o.tolerance = 0;
  EXPECT_THROW((void)gmres(dense_operator(a), {}, b, x, o), ParameterError);
  o.tolerance = -1e-8;
  EXPECT_THROW((void)gmres(dense_operator(a), {}, b, x, o), ParameterError);
  o.tolerance = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW((void)gmres(dense_operator(a), {}, b, x, o), ParameterError);
  o = {};
  o.max_iterations = -1;
  EXPECT_THROW((void)gmres(dense_operator(a), {}, b, x, o), ParameterError);
  o = {};
  EXPECT_TRUE(gmres(dense_operator(a), {}, b, x, o).ok());  // the defaults are valid
}

}  // namespace
}  // namespace incise::test
