/// \file augmented_reports_test.cpp
/// What an augmented solve (Yeung, Crouch & Pothen 2016 §3) reports besides its status, on
/// small systems built to trigger each condition: a preconditioner of eq. 17 whose LU is
/// numerically singular (dropped: GMRES unpreconditioned, §3.5), an amplified solution (the
/// accuracy warning and the singularity guard), and a factor of K⁰ or of a background snapshot
/// (§3.6) with CHOLMOD's tiny-pivot warning (never used).

#include <incise/core/error.hpp>
#include <incise/linalg/augmented_system.hpp>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include <cmath>
#include <string>
#include <utility>

namespace incise::test {
namespace {

using linalg::AugmentedOptions;
using linalg::AugmentedReport;
using linalg::AugmentedStatus;
using linalg::AugmentedSystem;
using linalg::FactorStatus;
using linalg::SchurPreconditioner;
using linalg::SchurSolver;
using linalg::SparseMatrix;

SparseMatrix sparse(const Eigen::MatrixXd& a) {
  SparseMatrix s = a.sparseView();
  s.makeCompressed();
  return s;
}

/// 5×5 SPD (diagonally dominant) K⁰ in which DOF 2 couples only to DOFs 0 and 4, so its
/// tridiagonal neighbours 1 and 3 do not see it.
Eigen::MatrixXd k0_matrix() {
  Eigen::MatrixXd k = 4 * Eigen::MatrixXd::Identity(5, 5);
  for (auto [i, j] : {std::pair{0, 2}, {2, 4}, {0, 1}, {3, 4}}) k(i, j) = k(j, i) = 1;
  return k;
}

// A changed column whose diagonal vanishes (K_22 = 0: K stays nonsingular, now indefinite)
// makes H S J = S_22 K_22 = 0 for the diagonal and the tridiagonal-SPAI S alike: the LU is
// singular, GMRES runs unpreconditioned, the report says so, and the solution is still right.
TEST(AugmentedReports, SingularPreconditionerIsReportedAsDropped) {
  const Eigen::MatrixXd k0 = k0_matrix();
  const Eigen::VectorXd f = Eigen::VectorXd::LinSpaced(5, 1, 2);
  Eigen::MatrixXd k = k0;
  k(2, 2) = 0;
  const Eigen::VectorXd expected = k.fullPivLu().solve(f);
  // Dense LU of a 5×5 with κ ≈ 10: round-off only.
  constexpr double kLuSolveTol = 1e-12;
  for (SchurPreconditioner pc :
       {SchurPreconditioner::kDiagonal, SchurPreconditioner::kTridiagonalSpai}) {
    SCOPED_TRACE(linalg::to_string(pc));
    AugmentedOptions o;
    o.preconditioner = pc;
    AugmentedSystem aug(o);
    ASSERT_EQ(aug.initialize(sparse(k0)), FactorStatus::kOk);
    aug.add_element({2}, Eigen::MatrixXd::Constant(1, 1, -k0(2, 2)));
    aug.set_force(f);
    Eigen::VectorXd a, r;
    const AugmentedReport rep = aug.solve(a, r);
    ASSERT_TRUE(rep.ok()) << rep.brief();
    EXPECT_TRUE(rep.preconditioner_dropped);
    EXPECT_FALSE(rep.preconditioner_rcond > linalg::kMinPreconditionerRcond);  // 0 or NaN
    EXPECT_TRUE(rep.message.empty());
    EXPECT_LE((a - expected).norm(), kLuSolveTol * expected.norm());
  }
  // A healthy change keeps the preconditioner; kNone builds none (rcond NaN).
  for (SchurPreconditioner pc : {SchurPreconditioner::kDiagonal, SchurPreconditioner::kNone}) {
    AugmentedOptions o;
    o.preconditioner = pc;
    AugmentedSystem aug(o);
    ASSERT_EQ(aug.initialize(sparse(k0)), FactorStatus::kOk);
    aug.add_element({2}, Eigen::MatrixXd::Constant(1, 1, 1.0));
    aug.set_force(f);
    Eigen::VectorXd a, r;
    const AugmentedReport rep = aug.solve(a, r);
    ASSERT_TRUE(rep.ok()) << rep.brief();
    EXPECT_FALSE(rep.preconditioner_dropped);
    if (pc == SchurPreconditioner::kNone) {
      EXPECT_TRUE(std::isnan(rep.preconditioner_rcond));
    } else {
      EXPECT_GT(rep.preconditioner_rcond, linalg::kMinPreconditionerRcond);
    }
  }
}

// With SchurSolver::kDirectCached the preconditioner is H R⁻¹ J itself, singular exactly when
// the modified K is: DOFs 1 and 3 decoupled from the rest into the singular block [1 1; 1 1]
// leave the LU singular, the load e_1 is not in the range of K, and the failed solve's message
// says that GMRES ran unpreconditioned.
TEST(AugmentedReports, DroppedPreconditionerIsNamedInAFailureMessage) {
  const Eigen::MatrixXd k0 = k0_matrix();
  AugmentedOptions o;
  o.schur_solver = SchurSolver::kDirectCached;
  AugmentedSystem aug(o);
  ASSERT_EQ(aug.initialize(sparse(k0)), FactorStatus::kOk);
  Eigen::MatrixXd now = Eigen::MatrixXd::Zero(4, 4);  // the new block on DOFs 0, 1, 3, 4
  now(0, 0) = now(3, 3) = 4;
  now.block(1, 1, 2, 2).setOnes();
  const std::vector<int> dofs{0, 1, 3, 4};
  Eigen::MatrixXd before(4, 4);
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) before(a, b) = k0(dofs[a], dofs[b]);
  aug.add_element(dofs, now - before);
  aug.set_force(Eigen::VectorXd::Unit(5, 1));
  Eigen::VectorXd a, r;
  const AugmentedReport rep = aug.solve(a, r);
  EXPECT_FALSE(rep.ok());
  EXPECT_TRUE(rep.preconditioner_dropped) << "rcond " << rep.preconditioner_rcond;
  EXPECT_NE(rep.message.find("GMRES ran unpreconditioned"), std::string::npos) << rep.message;
}

// The amplification A = max|K_ii|·‖a‖/‖f̂‖ of K = diag(1, s) under the load e_2 is 1/s: below
// warn_amplification nothing is flagged, between the two bounds the solve is ok with the
// accuracy warning, above max_amplification (1e12) it is a singular system, outputs zeroed.
TEST(AugmentedReports, AmplifiedSolutionsAreWarnedOrRejected) {
  struct AmplifiedCase {
    double s;
    bool ok, warning;
  };
  for (const AmplifiedCase& c : {AmplifiedCase{1e-3, true, false}, AmplifiedCase{1e-10, true, true},
                                 AmplifiedCase{1e-13, false, true}}) {
    SCOPED_TRACE(c.s);
    Eigen::MatrixXd k = Eigen::MatrixXd::Identity(2, 2);
    k(1, 1) = c.s;  // pivot ratio ≥ 1e-13 passes CholmodOptions::min_pivot_ratio = 1e-14
    AugmentedSystem aug;
    ASSERT_EQ(aug.initialize(sparse(k)), FactorStatus::kOk);
    aug.set_force(Eigen::Vector2d(0, 1));
    Eigen::VectorXd a, r;
    const AugmentedReport rep = aug.solve(a, r);
    // A = 1/s up to the rounding of one division.
    EXPECT_NEAR(rep.amplification, 1 / c.s, 1e-14 / c.s);
    EXPECT_EQ(rep.ok(), c.ok) << rep.brief();
    EXPECT_EQ(rep.amplification_warning, c.warning);
    if (!c.ok) {
      EXPECT_EQ(rep.status, AugmentedStatus::kSingularModifiedSystem);
      EXPECT_NE(rep.message.find("max_amplification 1e+12"), std::string::npos) << rep.message;
      EXPECT_EQ(a, Eigen::Vector2d::Zero());
    } else {
      EXPECT_TRUE(rep.message.empty());
      EXPECT_EQ(a(1), 1 / c.s);  // a diagonal solve: exact up to one rounding, as 1/s
    }
  }
  AugmentedOptions bad;
  bad.warn_amplification = 0;
  EXPECT_THROW(AugmentedSystem{bad}, ParameterError);
}

// CHOLMOD's tiny-pivot warning (CholmodOptions::pivot_bound replaced a pivot) is not a usable
// factor for the augmented solves, which need R⁻¹ itself: initialize() returns kTinyPivot and
// solve() kNoFactor with CHOLMOD's message; a background snapshot with a tiny pivot is dropped
// and its status kept, the old factor stays in use.
TEST(AugmentedReports, TinyPivotFactorIsNeverUsed) {
  AugmentedOptions o;
  o.cholmod.pivot_bound = 1e-12;
  Eigen::MatrixXd k = Eigen::MatrixXd::Identity(2, 2);
  k(1, 1) = 1e-20;
  {
    AugmentedSystem aug(o);
    EXPECT_EQ(aug.initialize(sparse(k)), FactorStatus::kTinyPivot);
    EXPECT_NE(aug.factorization_message().find("CHOLMOD_DSMALL"), std::string::npos)
        << aug.factorization_message();
    aug.set_force(Eigen::Vector2d(1, 1));
    Eigen::VectorXd a, r;
    const AugmentedReport rep = aug.solve(a, r);
    EXPECT_EQ(rep.status, AugmentedStatus::kNoFactor);
    EXPECT_NE(rep.message.find("CHOLMOD_DSMALL"), std::string::npos) << rep.message;
  }
  AugmentedSystem aug(o);
  k(1, 1) = 1e-6;  // pivots far above the bound: a usable factor
  ASSERT_EQ(aug.initialize(sparse(k)), FactorStatus::kOk);
  aug.add_element({1}, Eigen::MatrixXd::Constant(1, 1, 1e-20 - 1e-6));  // K ≈ diag(1, 1e-20)
  ASSERT_TRUE(aug.start_refactorization());
  EXPECT_FALSE(aug.wait_for_refactorization());
  EXPECT_EQ(aug.last_refactorization_status(), FactorStatus::kTinyPivot);
  EXPECT_EQ(aug.factored_dofs(), 2);
  EXPECT_EQ(aug.num_replaced(), 1);  // the change is still a replaced column of the old R
}

}  // namespace
}  // namespace incise::test
