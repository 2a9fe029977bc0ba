/// \file augmented_components_test.cpp
/// Building blocks of the augmented-matrix method: the CHOLMOD wrapper (analyze / factorize /
/// solve / info, cached symbolic analysis, not-positive-definite as a status), the
/// closure-restricted LDLᵀ solves of Yeung et al. 2016 §3.3 (Appendix Thm. 1–3), and GMRES
/// (eq. 17 solver) with its failure statuses.

#include "augmented_stand_in.hpp"

#include <incise/core/error.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/linalg/gmres.hpp>
#include <incise/linalg/ldl_closure_solver.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <random>

namespace incise::test {
namespace {

using linalg::CholmodFactor;
using linalg::CholmodKind;
using linalg::CholmodOptions;
using linalg::CholmodOrdering;
using linalg::FactorStatus;

/// Direct solves on these small SPD matrices (κ ≲ 1e4) are accurate to ~κ·n·eps ≲ 1e-9.
constexpr double kSolveTol = 1e-9;

linalg::SparseMatrix test_matrix() {
  return CutModel::from_mesh(mesh::make_brick(2)).assemble();
}

class CholmodVariants : public ::testing::TestWithParam<CholmodOptions> {};

TEST_P(CholmodVariants, SolveMatchesDenseAndLdlReconstructs) {
  const linalg::SparseMatrix a = test_matrix();
  CholmodFactor f(GetParam());
  ASSERT_EQ(f.compute(a, 7), FactorStatus::kOk) << f.message();
  INCISE_SEEDED_RNG(rng, 11);
  std::normal_distribution<double> g;
  Eigen::VectorXd b(a.rows());
  for (Eigen::Index i = 0; i < b.size(); ++i) b(i) = g(rng);
  Eigen::VectorXd x;
  ASSERT_EQ(f.solve(b, x), FactorStatus::kOk);
  const Eigen::MatrixXd ad = Eigen::MatrixXd(a);
  const Eigen::VectorXd xd = ad.ldlt().solve(b);
  EXPECT_LE((x - xd).norm(), kSolveTol * xd.norm());
  // P A Pᵀ = L D Lᵀ from the extracted arrays.
  const auto ldl = f.extract_ldl();
  ASSERT_NE(ldl, nullptr);
  const int n = ldl->n;
  Eigen::MatrixXd l = Eigen::MatrixXd::Identity(n, n);
  for (int j = 0; j < n; ++j)
    for (int k = ldl->col_ptr[j]; k < ldl->col_ptr[j + 1]; ++k)
      l(ldl->row_idx[k], j) = ldl->values[k];
  Eigen::MatrixXd pap(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) pap(i, j) = ad(ldl->perm[i], ldl->perm[j]);
  const Eigen::VectorXd d = Eigen::Map<const Eigen::VectorXd>(ldl->d.data(), n);
  // Reconstruction error of a backward-stable factorization: O(n·eps·‖A‖).
  EXPECT_LE((l * d.asDiagonal() * l.transpose() - pap).norm(), 1e-12 * ad.norm());
  // Elimination-tree parent = first subdiagonal row (Liu 1990), always a later position.
  for (int j = 0; j < n; ++j) EXPECT_TRUE(ldl->parent[j] == -1 || ldl->parent[j] > j);
}

INSTANTIATE_TEST_SUITE_P(
    Kinds, CholmodVariants,
    ::testing::Values(CholmodOptions{CholmodKind::kSupernodal, CholmodOrdering::kDefault},
                      CholmodOptions{CholmodKind::kSimplicialLdl, CholmodOrdering::kAmd},
                      CholmodOptions{CholmodKind::kSupernodal, CholmodOrdering::kMetis},
                      CholmodOptions{CholmodKind::kSimplicialLdl, CholmodOrdering::kNatural}));

TEST(CholmodFactor, SymbolicAnalysisCachedPerPatternVersion) {
  const linalg::SparseMatrix a = test_matrix();
  CholmodFactor f;
  ASSERT_EQ(f.compute(a, 1), FactorStatus::kOk);
  linalg::SparseMatrix a2 = a * 2.0;
  ASSERT_EQ(f.compute(a2, 1), FactorStatus::kOk);
  EXPECT_EQ(f.analyses_performed(), 1);
  ASSERT_EQ(f.compute(a2, 2), FactorStatus::kOk);
  EXPECT_EQ(f.analyses_performed(), 2);
}

TEST(CholmodFactor, IndefiniteAndMisuseAreStatuses) {
  linalg::SparseMatrix a = test_matrix();
  a.coeffRef(5, 5) = -1.0;
  CholmodFactor f;
  EXPECT_EQ(f.compute(a, 1), FactorStatus::kNotPositiveDefinite);
  EXPECT_FALSE(f.message().empty());
  Eigen::VectorXd x;
  EXPECT_NE(f.solve(Eigen::VectorXd::Ones(a.rows()), x), FactorStatus::kOk);
  EXPECT_EQ(f.extract_ldl(), nullptr);
  CholmodFactor g;
  EXPECT_EQ(g.factorize(a), FactorStatus::kNotAnalyzed);
  linalg::SparseMatrix rect(3, 4);
  rect.makeCompressed();
  EXPECT_EQ(g.analyze(rect, 1), FactorStatus::kInvalidInput);
}

// Yeung et al. 2016 §3.3, Thm. 1–3: solves restricted to closures equal full solves on the
// wanted entries, for random sparse right-hand sides and random wanted sets.
TEST(ClosureLdlSolver, RestrictedSolvesEqualFullSolvesThm1to3) {
  const linalg::SparseMatrix a = test_matrix();
  CholmodFactor f({CholmodKind::kSupernodal, CholmodOrdering::kMetis});
  ASSERT_EQ(f.compute(a, 1), FactorStatus::kOk);
  linalg::ClosureLdlSolver s(f.extract_ldl());
  INCISE_SEEDED_RNG(rng, 3);
  const int n = static_cast<int>(a.rows());
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::normal_distribution<double> g;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<int> bi, want;
    std::vector<double> bv;
    for (int k = 0; k < 1 + trial % 4; ++k) {
      bi.push_back(pick(rng));
      bv.push_back(g(rng));
    }
    for (int k = 0; k < 1 + trial % 5; ++k) want.push_back(pick(rng));
    Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
    for (size_t k = 0; k < bi.size(); ++k) b(bi[k]) += bv[k];
    Eigen::VectorXd xfull;
    s.solve_dense(b, xfull);
    std::vector<double> xw;
    s.solve_restricted(bi, bv, s.closure(bi), s.closure(want), want, xw);
    for (size_t k = 0; k < want.size(); ++k)
      EXPECT_NEAR(xw[k], xfull(want[k]), kSolveTol * xfull.norm());
    Eigen::VectorXd xs;
    s.solve_sparse_rhs(bi, bv, s.closure(bi), xs);
    EXPECT_LE((xs - xfull).norm(), kSolveTol * xfull.norm());
    // Closures are ancestor-closed (Definition 4 with Thm. 3).
    const std::vector<int> c = s.closure(bi);
    for (int p : c) {
      const int q = s.factor().parent[p];
      if (q >= 0) {
        EXPECT_TRUE(std::binary_search(c.begin(), c.end(), q));
      }
    }
  }
  // Residual of the full solve against A itself.
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1, 1), x;
  s.solve_dense(b, x);
  EXPECT_LE((a * x - b).norm(), kSolveTol * b.norm());
}

// The threaded full backward pass (ClosureLdlSolver with threads > 1) splits the postordered
// elimination forest into a root side and disjoint subtrees; every entry is computed by the
// same operations in the same order, so the result must be bit-identical to the serial pass.
// Matrices: a brick (one tree), a long beam (the paper's shape: a deep separator chain) and two
// disconnected bricks (a forest with two roots).
TEST(ClosureLdlSolver, ThreadedBackwardIsBitIdenticalToSerial) {
  const linalg::SparseMatrix brick = test_matrix();
  const linalg::SparseMatrix beam = CutModel::from_mesh(mesh::make_beam(40, 0.01)).assemble();
  linalg::SparseMatrix two(2 * brick.rows(), 2 * brick.cols());
  {
    std::vector<Eigen::Triplet<double>> t;
    for (int j = 0; j < brick.outerSize(); ++j)
      for (linalg::SparseMatrix::InnerIterator it(brick, j); it; ++it) {
        t.emplace_back(static_cast<int>(it.row()), j, it.value());
        t.emplace_back(static_cast<int>(it.row() + brick.rows()),
                       static_cast<int>(j + brick.cols()), 2.0 * it.value());
      }
    two.setFromTriplets(t.begin(), t.end());
  }
  INCISE_SEEDED_RNG(rng, 11);
  std::normal_distribution<double> g;
  int split = 0;  // matrices on which a threaded plan exists (the test must exercise one)
  const linalg::SparseMatrix* matrices[] = {&brick, &beam, &two};
  for (const linalg::SparseMatrix* a : matrices) {
    CholmodFactor f({CholmodKind::kSimplicialLdl, CholmodOrdering::kMetis});
    ASSERT_EQ(f.compute(*a, 1), FactorStatus::kOk);
    const auto ldl = f.extract_ldl();
    linalg::ClosureLdlSolver serial(ldl);
    EXPECT_EQ(serial.backward_threads(), 1);
    const int n = static_cast<int>(a->rows());
    std::uniform_int_distribution<int> pick(0, n - 1);
    for (int threads : {2, 3}) {
      linalg::ClosureLdlSolver par(ldl, threads);
      if (par.backward_threads() > 1) ++split;
      EXPECT_LE(par.backward_threads(), threads);
      for (int trial = 0; trial < 4; ++trial) {
        Eigen::VectorXd b(n);
        for (int i = 0; i < n; ++i) b(i) = g(rng);
        Eigen::VectorXd x1, x2;
        serial.solve_dense(b, x1);
        par.solve_dense(b, x2);
        ASSERT_EQ(x1.size(), x2.size());
        for (int i = 0; i < n; ++i) ASSERT_EQ(x1(i), x2(i)) << "entry " << i;
        const std::vector<int> bi{pick(rng), pick(rng)};
        const std::vector<double> bv{g(rng), g(rng)};
        serial.solve_sparse_rhs(bi, bv, serial.closure(bi), x1);
        par.solve_sparse_rhs(bi, bv, par.closure(bi), x2);
        for (int i = 0; i < n; ++i) ASSERT_EQ(x1(i), x2(i)) << "entry " << i;
      }
      // The workspace is left at zero: a following restricted solve is unaffected.
      const std::vector<int> bi{pick(rng)}, want{pick(rng)};
      std::vector<double> y1, y2;
      serial.solve_restricted(bi, {1.0}, serial.closure(bi), serial.closure(want), want, y1);
      par.solve_restricted(bi, {1.0}, par.closure(bi), par.closure(want), want, y2);
      EXPECT_EQ(y1, y2);
    }
  }
  EXPECT_GE(split, 4) << "no threaded plan was exercised";
}

Eigen::MatrixXd random_nonsymmetric(int n, std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::MatrixXd m(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) m(i, j) = g(rng) / std::sqrt(n);
  m += 3.0 * Eigen::MatrixXd::Identity(n, n);  // eigenvalues clustered around 3: well posed
  return m;
}

TEST(Gmres, ConvergesToDirectSolutionAndReportsHistory) {
  INCISE_SEEDED_RNG(rng, 17);
  const int n = 40;
  const Eigen::MatrixXd m = random_nonsymmetric(n, rng);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 1, 2);
  linalg::GmresOptions o;
  o.tolerance = 1e-12;
  o.restart = 10;  // force restarts
  Eigen::VectorXd x;
  const auto op = [&](const Eigen::VectorXd& v, Eigen::VectorXd& y) { y = m * v; };
  const linalg::GmresReport r = linalg::gmres(op, {}, b, x, o);
  ASSERT_TRUE(r.ok()) << linalg::to_string(r.status);
  EXPECT_GT(r.restarts, 0);
  // Relative error ≤ κ(M)·tolerance with κ(M) ≈ 5 for this spectrum; 1e-10 leaves margin.
  const Eigen::VectorXd xd = m.partialPivLu().solve(b);
  EXPECT_LE((x - xd).norm(), 1e-10 * xd.norm());
  ASSERT_EQ(static_cast<int>(r.residual_history.size()), r.iterations + 1);
  EXPECT_LE(r.residual_history.back(), o.tolerance);
  // With the exact inverse as right preconditioner GMRES needs one iteration.
  const Eigen::PartialPivLU<Eigen::MatrixXd> lu(m);
  const auto prec = [&](const Eigen::VectorXd& v, Eigen::VectorXd& y) { y = lu.solve(v); };
  Eigen::VectorXd x2;
  const linalg::GmresReport r2 = linalg::gmres(op, prec, b, x2, o);
  ASSERT_TRUE(r2.ok());
  EXPECT_EQ(r2.iterations, 1);
}

TEST(Gmres, FailuresAreStatuses) {
  INCISE_SEEDED_RNG(rng, 19);
  const int n = 30;
  const Eigen::MatrixXd m = random_nonsymmetric(n, rng);
  const auto op = [&](const Eigen::VectorXd& v, Eigen::VectorXd& y) { y = m * v; };
  linalg::GmresOptions o;
  o.max_iterations = 3;
  Eigen::VectorXd x;
  const Eigen::VectorXd b = Eigen::VectorXd::Ones(n);
  EXPECT_EQ(linalg::gmres(op, {}, b, x, o).status, linalg::GmresStatus::kMaxIterations);
  EXPECT_TRUE(x.allFinite());
  // Singular, inconsistent: A = diag(1, …, 1, 0), b = e_n.
  Eigen::VectorXd dg = Eigen::VectorXd::Ones(n);
  dg(n - 1) = 0;
  const auto sing = [&](const Eigen::VectorXd& v, Eigen::VectorXd& y) { y = dg.cwiseProduct(v); };
  Eigen::VectorXd en = Eigen::VectorXd::Zero(n);
  en(n - 1) = 1;
  en(0) = 1;
  linalg::GmresOptions o2;
  const linalg::GmresReport r = linalg::gmres(sing, {}, en, x, o2);
  EXPECT_TRUE(r.status == linalg::GmresStatus::kBreakdown ||
              r.status == linalg::GmresStatus::kStagnated)
      << linalg::to_string(r.status);
  EXPECT_TRUE(x.allFinite());
  const auto nan_op = [&](const Eigen::VectorXd& v, Eigen::VectorXd& y) {
    y = v * std::numeric_limits<double>::quiet_NaN();
  };
  EXPECT_EQ(linalg::gmres(nan_op, {}, b, x, o2).status, linalg::GmresStatus::kNonFinite);
  o2.restart = 0;
  EXPECT_THROW((void)linalg::gmres(op, {}, b, x, o2), ParameterError);
}

}  // namespace
}  // namespace incise::test
