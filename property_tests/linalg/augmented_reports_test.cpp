/// \file augmented_reports_test.cpp
/// What an augmented solve (Yeung, Crouch & Pothen 2016 §3) reports besides its status, on
/// small systems built to trigger each condition: a factor of K⁰ or of a background snapshot
/// (§3.6) with CHOLMOD's tiny-pivot warning (never used).

#include <incise/core/error.hpp>
#include <incise/linalg/augmented_system.hpp>

#include <gtest/gtest.h>
#include <Eigen/Dense>

#include <string>

namespace incise::test {
namespace {

using linalg::AugmentedOptions;
using linalg::AugmentedReport;
using linalg::AugmentedStatus;
using linalg::AugmentedSystem;
using linalg::FactorStatus;
using linalg::SparseMatrix;

SparseMatrix sparse(const Eigen::MatrixXd& a) {
  SparseMatrix s = a.sparseView();
  s.makeCompressed();
  return s;
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
