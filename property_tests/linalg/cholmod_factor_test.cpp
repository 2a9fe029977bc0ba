/// \file cholmod_factor_test.cpp
/// The CHOLMOD wrapper (linalg/cholmod_factor.hpp): analyze / factorize / solve against a dense
/// solve for every kind and ordering, the exported LDLᵀ factor (P A Pᵀ = L D Lᵀ and the
/// elimination tree), numeric refactorization with a kept symbolic analysis, and failures
/// (not positive definite, numerically singular, non-finite, misuse) as statuses.

#include "augmented_stand_in.hpp"
#include "random_spd.hpp"

#include <incise/core/error.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <vector>

namespace incise::test {
namespace {

using linalg::CholmodFactor;
using linalg::CholmodKind;
using linalg::CholmodOptions;
using linalg::CholmodOrdering;
using linalg::FactorStatus;
using linalg::SparseMatrix;

/// Direct solves of these SPD matrices (κ ≲ 1e3 for random_sparse_spd with shift 0.1, ≲ 1e4 for
/// the brick) are accurate to ~κ·n·eps ≲ 1e-10; 1e-9 leaves a margin.
constexpr double kSolveTol = 1e-9;

Eigen::VectorXd random_vector(Eigen::Index n, std::mt19937_64& rng) {
  std::normal_distribution<double> g;
  Eigen::VectorXd v(n);
  for (Eigen::Index i = 0; i < n; ++i) v(i) = g(rng);
  return v;
}

// Checks the exported factor against A: permutation, strictly-lower sorted columns, positive D,
// the elimination-tree parents, and P A Pᵀ = L D Lᵀ.
void expect_valid_ldl(const linalg::LdlFactorData& f, const Eigen::MatrixXd& a) {
  const int n = f.n;
  ASSERT_EQ(n, a.rows());
  ASSERT_EQ(static_cast<int>(f.perm.size()), n);
  ASSERT_EQ(static_cast<int>(f.col_ptr.size()), n + 1);
  for (int i = 0; i < n; ++i) EXPECT_EQ(f.inverse_perm[f.perm[i]], i);
  EXPECT_EQ(f.nnz_l(), static_cast<std::int64_t>(f.values.size()) + n);
  for (int j = 0; j < n; ++j) {
    EXPECT_GT(f.d[j], 0.0) << "pivot " << j;
    const int begin = f.col_ptr[j], end = f.col_ptr[j + 1];
    for (int k = begin; k < end; ++k) {
      EXPECT_GT(f.row_idx[k], j);
      if (k > begin) {
        EXPECT_GT(f.row_idx[k], f.row_idx[k - 1]);
      }
    }
    // Parent = first subdiagonal row of column j (Liu 1990; Yeung et al. Appendix Def. 2).
    EXPECT_EQ(f.parent[j], begin < end ? f.row_idx[begin] : -1);
  }
  Eigen::MatrixXd pap(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) pap(i, j) = a(f.perm[i], f.perm[j]);
  const Eigen::MatrixXd l = dense_l(f);
  const Eigen::VectorXd d = Eigen::Map<const Eigen::VectorXd>(f.d.data(), n);
  // Reconstruction error of a backward-stable factorization: O(n·eps·‖A‖) ≈ 1e-13·‖A‖ here.
  EXPECT_LE((l * d.asDiagonal() * l.transpose() - pap).norm(), 1e-12 * a.norm());
}

using Variant = std::tuple<CholmodKind, CholmodOrdering>;

std::string variant_name(const ::testing::TestParamInfo<Variant>& info) {
  const char* kind[] = {"supernodal", "simplicial", "auto"};
  const char* ordering[] = {"default", "amd", "natural", "metis"};
  return std::string(kind[static_cast<int>(std::get<0>(info.param))]) + "_" +
         ordering[static_cast<int>(std::get<1>(info.param))];
}

class CholmodVariants : public ::testing::TestWithParam<Variant> {};

TEST_P(CholmodVariants, SolveMatchesDenseAndLdlReconstructs) {
  CholmodOptions o;
  o.kind = std::get<0>(GetParam());
  o.ordering = std::get<1>(GetParam());
  INCISE_SEEDED_RNG(rng, 11);
  std::vector<SparseMatrix> matrices{CutModel::from_mesh(mesh::make_brick(2)).assemble()};
  for (int k = 0; k < 3; ++k) matrices.push_back(random_sparse_spd(120 + 90 * k, 3, 0.1, rng));
  for (const SparseMatrix& a : matrices) {
    SCOPED_TRACE("n = " + std::to_string(a.rows()));
    CholmodFactor f(o);
    ASSERT_EQ(f.analyze(a, 7), FactorStatus::kOk) << f.message();
    EXPECT_EQ(f.rows(), a.rows());
    ASSERT_EQ(f.factorize(a), FactorStatus::kOk) << f.message();
    EXPECT_EQ(f.info(), FactorStatus::kOk);
    EXPECT_TRUE(f.message().empty());
    EXPECT_EQ(f.minor(), a.rows());
    if (o.kind != CholmodKind::kAuto) {
      EXPECT_EQ(f.is_supernodal(), o.kind == CholmodKind::kSupernodal);
    }
    EXPECT_GT(f.rcond(), 0.0);
    EXPECT_LE(f.rcond(), 1.0);
    EXPECT_GE(f.nnz_l(), a.rows());
    EXPECT_GT(f.factor_flops(), 0.0);
    const Eigen::MatrixXd ad(a);
    const Eigen::LDLT<Eigen::MatrixXd> dense(ad);
    for (int rhs = 0; rhs < 3; ++rhs) {
      const Eigen::VectorXd b = random_vector(a.rows(), rng);
      Eigen::VectorXd x;
      ASSERT_EQ(f.solve(b, x), FactorStatus::kOk);
      const Eigen::VectorXd xd = dense.solve(b);
      EXPECT_LE((x - xd).norm(), kSolveTol * xd.norm());
    }
    const bool supernodal = f.is_supernodal();
    const auto ldl = f.extract_ldl();
    ASSERT_NE(ldl, nullptr);
    expect_valid_ldl(*ldl, ad);
    if (o.ordering == CholmodOrdering::kNatural) {
      for (int i = 0; i < ldl->n; ++i) EXPECT_EQ(ldl->perm[i], i);
    }
    // The export leaves the stored factor as it was (a supernodal one is converted on a copy).
    EXPECT_EQ(f.is_supernodal(), supernodal);
    const Eigen::VectorXd b = random_vector(a.rows(), rng);
    Eigen::VectorXd x;
    ASSERT_EQ(f.solve(b, x), FactorStatus::kOk);
    EXPECT_LE((x - dense.solve(b)).norm(), kSolveTol * x.norm());
  }
}

INSTANTIATE_TEST_SUITE_P(
    KindsAndOrderings, CholmodVariants,
    ::testing::Combine(::testing::Values(CholmodKind::kSupernodal, CholmodKind::kSimplicialLdl,
                                         CholmodKind::kAuto),
                       ::testing::Values(CholmodOrdering::kDefault, CholmodOrdering::kAmd,
                                         CholmodOrdering::kNatural, CholmodOrdering::kMetis)),
    variant_name);

// extract_ldl() of a supernodal LLᵀ factor reads the supernodes straight into LDLᵀ arrays
// (issue 17: no copy and conversion of the factor in every background refactorization). With
// the natural ordering both kinds factor the same P A Pᵀ = A, whose LDLᵀ is unique: the export
// equals the simplicial LDLᵀ factor entry by entry (the supernodal padding as explicit zeros),
// to round-off of the two factorization orders (1e-12 relative; measured ≈ 1e-15).
TEST(CholmodFactor, SupernodalExportEqualsTheSimplicialLdlOfTheSameOrdering) {
  const SparseMatrix a = CutModel::from_mesh(mesh::make_brick(5)).assemble();
  CholmodFactor sn({CholmodKind::kSupernodal, CholmodOrdering::kNatural});
  CholmodFactor simp({CholmodKind::kSimplicialLdl, CholmodOrdering::kNatural});
  ASSERT_EQ(sn.compute(a, 1), FactorStatus::kOk) << sn.message();
  ASSERT_EQ(simp.compute(a, 1), FactorStatus::kOk) << simp.message();
  ASSERT_TRUE(sn.is_supernodal());
  const auto x = sn.extract_ldl();
  const auto y = simp.extract_ldl();
  ASSERT_NE(x, nullptr);
  ASSERT_NE(y, nullptr);
  expect_valid_ldl(*x, Eigen::MatrixXd(a));
  EXPECT_GE(x->nnz_l(), y->nnz_l());  // the padding of relaxed supernodes
  const Eigen::MatrixXd lx = dense_l(*x), ly = dense_l(*y);
  EXPECT_LE((lx - ly).norm(), 1e-12 * ly.norm());
  for (int j = 0; j < x->n; ++j) EXPECT_NEAR(x->d[j], y->d[j], 1e-12 * std::abs(y->d[j])) << j;
}

// analyze() with a given ordering (issue 17's synchronous refactorization extends the factor in
// use's instead of computing one): a random permutation of a random SPD matrix, both kinds —
// the solve equals a dense one (kSolveTol), the exported factor is valid (P A Pᵀ = L D Lᵀ), and
// its elimination order is the given one up to CHOLMOD's postordering, so the pivots are those
// of the dense LDLᵀ of the matrix permuted by it: equal as multisets (sorted, 1e-10 relative).
// Not a permutation (a repeated index, a wrong length) is kInvalidInput.
TEST(CholmodFactor, GivenOrderingFactorsThePermutedMatrix) {
  INCISE_SEEDED_RNG(rng, 1701);
  const SparseMatrix a = random_sparse_spd(120, 4, 0.1, rng);
  const int n = static_cast<int>(a.rows());
  std::vector<int> perm(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) perm[static_cast<std::size_t>(i)] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  Eigen::MatrixXd pap(n, n);
  const Eigen::MatrixXd dense(a);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c)
      pap(r, c) = dense(perm[static_cast<std::size_t>(r)], perm[static_cast<std::size_t>(c)]);
  // The unpivoted LDLᵀ of pap: D = diag(L_chol)².
  const Eigen::MatrixXd lc = Eigen::LLT<Eigen::MatrixXd>(pap).matrixL();
  Eigen::VectorXd pivots = lc.diagonal().cwiseAbs2();
  std::sort(pivots.data(), pivots.data() + n);
  for (CholmodKind kind : {CholmodKind::kSupernodal, CholmodKind::kSimplicialLdl}) {
    CholmodFactor f({kind, CholmodOrdering::kMetis});
    ASSERT_EQ(f.analyze(a, 1, perm), FactorStatus::kOk) << f.message();
    ASSERT_EQ(f.factorize(a), FactorStatus::kOk) << f.message();
    const Eigen::VectorXd b = random_vector(n, rng);
    Eigen::VectorXd x;
    ASSERT_EQ(f.solve(b, x), FactorStatus::kOk);
    const Eigen::VectorXd want = dense.ldlt().solve(b);
    EXPECT_LE((x - want).norm(), kSolveTol * want.norm());
    const auto ldl = f.extract_ldl();
    ASSERT_NE(ldl, nullptr);
    expect_valid_ldl(*ldl, dense);
    std::vector<double> d(ldl->d.begin(), ldl->d.end());
    std::sort(d.begin(), d.end());
    for (int j = 0; j < n; ++j)
      EXPECT_NEAR(d[static_cast<std::size_t>(j)], pivots(j), 1e-10 * std::abs(pivots(j))) << j;
  }
  CholmodFactor g;
  std::vector<int> bad = perm;
  bad[0] = bad[1];
  EXPECT_EQ(g.analyze(a, 1, bad), FactorStatus::kInvalidInput);
  bad = perm;
  bad.pop_back();
  EXPECT_EQ(g.analyze(a, 2, bad), FactorStatus::kInvalidInput);
}

TEST(CholmodFactor, SymbolicAnalysisCachedPerPatternVersion) {
  const SparseMatrix a = CutModel::from_mesh(mesh::make_brick(2)).assemble();
  CholmodFactor f;
  ASSERT_EQ(f.compute(a, 1), FactorStatus::kOk);
  SparseMatrix a2 = a * 2.0;
  ASSERT_EQ(f.compute(a2, 1), FactorStatus::kOk);
  EXPECT_EQ(f.analyses_performed(), 1);
  ASSERT_EQ(f.compute(a2, 2), FactorStatus::kOk);
  EXPECT_EQ(f.analyses_performed(), 2);
}

// Numeric refactorization: new values on the analyzed pattern reuse the analysis, and the
// solves follow the new values — also after a failed factorization of the same pattern.
TEST(CholmodFactor, NumericRefactorizationWithTheSamePattern) {
  INCISE_SEEDED_RNG(rng, 13);
  const SparseMatrix a = random_sparse_spd(200, 3, 0.1, rng);
  for (CholmodKind kind : {CholmodKind::kSupernodal, CholmodKind::kSimplicialLdl}) {
    SCOPED_TRACE(kind == CholmodKind::kSupernodal ? "supernodal" : "simplicial LDL'");
    CholmodFactor f({kind, CholmodOrdering::kMetis});
    ASSERT_EQ(f.compute(a, 1), FactorStatus::kOk);
    for (int round = 0; round < 3; ++round) {
      // Same pattern, other values: A + D with a random positive diagonal D (still SPD).
      SparseMatrix a2 = a;
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      for (int j = 0; j < a2.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(a2, j); it; ++it)
          if (it.row() == j) it.valueRef() += 3.0 * unit(rng);
      ASSERT_EQ(f.analyze(a2, 1), FactorStatus::kOk);  // same version: kept
      ASSERT_EQ(f.factorize(a2), FactorStatus::kOk);
      EXPECT_EQ(f.analyses_performed(), 1);
      const Eigen::VectorXd b = random_vector(a.rows(), rng);
      Eigen::VectorXd x;
      ASSERT_EQ(f.solve(b, x), FactorStatus::kOk);
      const Eigen::VectorXd xd = Eigen::MatrixXd(a2).ldlt().solve(b);
      EXPECT_LE((x - xd).norm(), kSolveTol * xd.norm());
    }
    SparseMatrix bad = a;
    bad.coeffRef(17, 17) = -1.0;  // an existing entry: same pattern
    EXPECT_EQ(f.factorize(bad), FactorStatus::kNotPositiveDefinite);
    Eigen::VectorXd x;
    EXPECT_NE(f.solve(Eigen::VectorXd::Ones(a.rows()), x), FactorStatus::kOk);
    ASSERT_EQ(f.factorize(a), FactorStatus::kOk);  // recovers on the kept analysis
    const Eigen::VectorXd b = random_vector(a.rows(), rng);
    ASSERT_EQ(f.solve(b, x), FactorStatus::kOk);
    EXPECT_LE((a * x - b).norm(), kSolveTol * b.norm());
    EXPECT_EQ(f.analyses_performed(), 1);
  }
}

// Issue 18 (resource limits): the symbolic analysis gives nnz(L), hence the bytes of the numeric
// factorization, before any of it is allocated. The estimate is checked against what CHOLMOD
// actually held at its peak, and a budget below it refuses with kOverMemoryBudget and a message
// stating the estimate, nnz(L) and the budget, leaving no factor.
TEST(CholmodFactor, MemoryBudgetRefusesTheNumericFactorizationFromTheSymbolicEstimate) {
  const SparseMatrix a = CutModel::from_mesh(mesh::make_brick(6)).assemble();
  for (CholmodKind kind : {CholmodKind::kSupernodal, CholmodKind::kSimplicialLdl}) {
    SCOPED_TRACE(kind == CholmodKind::kSupernodal ? "supernodal" : "simplicial LDL'");
    CholmodFactor free({kind, CholmodOrdering::kMetis});
    ASSERT_EQ(free.analyze(a, 1), FactorStatus::kOk);
    const std::uint64_t estimate = free.estimated_factor_bytes();
    EXPECT_GE(estimate, static_cast<std::uint64_t>(free.nnz_l()) * sizeof(double));
    ASSERT_EQ(free.factorize(a), FactorStatus::kOk);
    // The peak also holds the analysis' own workspace (ordering), so it is at least the factor;
    // the estimate may not undershoot the peak by more than 2x nor overshoot it (it counts
    // what factorize allocates, all of which CHOLMOD holds at the peak).
    const double peak = static_cast<double>(free.peak_memory_bytes());
    EXPECT_GE(static_cast<double>(estimate), 0.5 * peak) << "peak " << peak;
    EXPECT_LE(static_cast<double>(estimate), 1.0 * peak) << "peak " << peak;
    RecordProperty(kind == CholmodKind::kSupernodal ? "supernodal_estimate_over_peak"
                                                    : "simplicial_estimate_over_peak",
                   std::to_string(static_cast<double>(estimate) / peak));

    CholmodOptions o{kind, CholmodOrdering::kMetis};
    o.memory_budget_bytes = std::uint64_t{1} << 20;  // 1 MiB
    ASSERT_GT(estimate, o.memory_budget_bytes);
    CholmodFactor bounded(o);
    EXPECT_EQ(bounded.compute(a, 1), FactorStatus::kOverMemoryBudget);
    EXPECT_EQ(bounded.estimated_factor_bytes(), estimate);
    EXPECT_NE(bounded.message().find("the numeric factorization needs an estimated"),
              std::string::npos)
        << bounded.message();
    EXPECT_NE(bounded.message().find("nnz(L) = " + std::to_string(free.nnz_l())), std::string::npos)
        << bounded.message();
    EXPECT_NE(bounded.message().find("more than the memory budget of 1 MiB"), std::string::npos)
        << bounded.message();
    Eigen::VectorXd x;
    EXPECT_NE(bounded.solve(Eigen::VectorXd::Ones(a.rows()), x), FactorStatus::kOk);
    EXPECT_EQ(bounded.extract_ldl(), nullptr);
    // A budget at the estimate lets it through.
    o.memory_budget_bytes = estimate;
    CholmodFactor exact(o);
    EXPECT_EQ(exact.compute(a, 1), FactorStatus::kOk);
  }
}

TEST(CholmodFactor, NotPositiveDefiniteIsAStatus) {
  INCISE_SEEDED_RNG(rng, 5);
  for (CholmodKind kind : {CholmodKind::kSupernodal, CholmodKind::kSimplicialLdl}) {
    SCOPED_TRACE(kind == CholmodKind::kSupernodal ? "supernodal" : "simplicial LDL'");
    // Indefinite: one negative diagonal entry.
    SparseMatrix a = random_sparse_spd(150, 3, 0.1, rng);
    a.coeffRef(5, 5) = -1.0;
    CholmodFactor f({kind, CholmodOrdering::kAmd});
    EXPECT_EQ(f.compute(a, 1), FactorStatus::kNotPositiveDefinite);
    EXPECT_EQ(f.info(), FactorStatus::kNotPositiveDefinite);
    EXPECT_FALSE(f.message().empty());
    EXPECT_LT(f.minor(), a.rows());
    Eigen::VectorXd x;
    EXPECT_NE(f.solve(Eigen::VectorXd::Ones(a.rows()), x), FactorStatus::kOk);
    EXPECT_EQ(f.extract_ldl(), nullptr);
    // Exactly singular: a graph Laplacian (constant on each connected component in its null
    // space). A pivot is 0 in exact arithmetic and a round-off-sized number of either sign in
    // floating point: CHOLMOD flags it, or the pivot ratio falls below min_pivot_ratio = 1e-14.
    SparseMatrix lap = random_sparse_spd(150, 3, 0.1, rng);
    for (int j = 0; j < lap.outerSize(); ++j) {
      double sum = 0;
      for (SparseMatrix::InnerIterator it(lap, j); it; ++it)
        if (it.row() != j) sum += it.value();
      lap.coeffRef(j, j) = -sum;
    }
    ASSERT_LE((lap * Eigen::VectorXd::Ones(lap.rows())).norm(), 1e-12);
    CholmodFactor g({kind, CholmodOrdering::kAmd});
    EXPECT_EQ(g.compute(lap, 1), FactorStatus::kNotPositiveDefinite) << g.message();
  }
}

TEST(CholmodFactor, MinPivotRatioFlagsNumericallySingularMatrices) {
  // diag(1, 1e-15): positive definite, but its pivot ratio 1e-15 is below the default 1e-14.
  SparseMatrix a(2, 2);
  a.insert(0, 0) = 1.0;
  a.insert(1, 1) = 1e-15;
  a.makeCompressed();
  CholmodFactor f({CholmodKind::kSimplicialLdl, CholmodOrdering::kNatural});
  EXPECT_EQ(f.compute(a, 1), FactorStatus::kNotPositiveDefinite);
  EXPECT_NE(f.message().find("pivot ratio"), std::string::npos) << f.message();
  EXPECT_EQ(f.message().find("failed"), std::string::npos) << f.message();  // no pivot failed
  EXPECT_EQ(f.minor(), 2);
  CholmodOptions off{CholmodKind::kSimplicialLdl, CholmodOrdering::kNatural};
  off.min_pivot_ratio = 0;  // disables the check
  CholmodFactor g(off);
  ASSERT_EQ(g.compute(a, 1), FactorStatus::kOk);
  Eigen::VectorXd x;
  ASSERT_EQ(g.solve(Eigen::Vector2d(1.0, 1e-15), x), FactorStatus::kOk);
  EXPECT_NEAR(x(0), 1.0, 1e-15);  // diagonal: exact up to one rounding
  EXPECT_NEAR(x(1), 1.0, 1e-15);
}

// CHOLMOD_DSMALL, the warning that pivot_bound (CHOLMOD's dbound) replaced a tiny pivot, is
// its own status, never kOk: the factor exists and solves the perturbed matrix diag(1, bound).
TEST(CholmodFactor, TinyPivotWarningIsAStatusNotOk) {
  SparseMatrix a(2, 2);
  a.insert(0, 0) = 1.0;
  a.insert(1, 1) = 1e-20;
  a.makeCompressed();
  CholmodOptions o{CholmodKind::kSimplicialLdl, CholmodOrdering::kNatural};
  o.pivot_bound = 1e-12;
  CholmodFactor f(o);
  EXPECT_EQ(f.compute(a, 1), FactorStatus::kTinyPivot) << f.message();
  EXPECT_EQ(f.info(), FactorStatus::kTinyPivot);
  EXPECT_NE(f.message().find("CHOLMOD_DSMALL: 1 pivot(s)"), std::string::npos) << f.message();
  Eigen::VectorXd x;
  ASSERT_EQ(f.solve(Eigen::Vector2d(2.0, 3.0), x), FactorStatus::kOk);
  EXPECT_NEAR(x(0), 2.0, 1e-15);          // diagonal: exact up to one rounding
  EXPECT_NEAR(x(1), 3e12, 1e-15 * 3e12);  // 3 / pivot_bound, not 3 / 1e-20
  const auto ldl = f.extract_ldl();
  ASSERT_NE(ldl, nullptr);
  EXPECT_EQ(ldl->d[1], 1e-12);
  // Without the bound the same matrix has no tiny-pivot warning (the ratio guard speaks).
  CholmodFactor g({CholmodKind::kSimplicialLdl, CholmodOrdering::kNatural});
  EXPECT_EQ(g.compute(a, 1), FactorStatus::kNotPositiveDefinite) << g.message();
  o.pivot_bound = -1;
  EXPECT_THROW(CholmodFactor bad(o), ParameterError);
}

TEST(CholmodFactor, NonFiniteEntriesAreInvalidInput) {
  INCISE_SEEDED_RNG(rng, 7);
  SparseMatrix a = random_sparse_spd(60, 3, 0.1, rng);
  CholmodFactor f;
  ASSERT_EQ(f.compute(a, 1), FactorStatus::kOk);
  a.coeffRef(10, 10) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(f.factorize(a), FactorStatus::kInvalidInput);
  EXPECT_FALSE(f.message().empty());
  Eigen::VectorXd x;
  EXPECT_NE(f.solve(Eigen::VectorXd::Ones(a.rows()), x), FactorStatus::kOk);
  a.coeffRef(10, 10) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(f.factorize(a), FactorStatus::kInvalidInput);
}

TEST(CholmodFactor, MisuseIsAStatus) {
  INCISE_SEEDED_RNG(rng, 9);
  const SparseMatrix a = random_sparse_spd(50, 3, 0.1, rng);
  Eigen::VectorXd x;
  CholmodFactor g;
  EXPECT_EQ(g.solve(Eigen::VectorXd::Ones(50), x), FactorStatus::kNotAnalyzed);
  EXPECT_EQ(g.factorize(a), FactorStatus::kNotAnalyzed);
  EXPECT_EQ(g.extract_ldl(), nullptr);
  SparseMatrix rect(3, 4);
  rect.makeCompressed();
  EXPECT_EQ(g.analyze(rect, 1), FactorStatus::kInvalidInput);
  SparseMatrix uncompressed = a;
  uncompressed.uncompress();
  EXPECT_EQ(g.analyze(uncompressed, 1), FactorStatus::kInvalidInput);
  ASSERT_EQ(g.analyze(a, 1), FactorStatus::kOk);
  EXPECT_EQ(g.solve(Eigen::VectorXd::Ones(50), x), FactorStatus::kNotAnalyzed);  // no factor
  const SparseMatrix other = random_sparse_spd(51, 3, 0.1, rng);
  EXPECT_EQ(g.factorize(other), FactorStatus::kInvalidInput);  // size differs from the analysis
  ASSERT_EQ(g.factorize(a), FactorStatus::kOk);
  EXPECT_EQ(g.solve(Eigen::VectorXd::Ones(49), x), FactorStatus::kInvalidInput);
  // A moved-to factor keeps working.
  CholmodFactor h = std::move(g);
  const Eigen::VectorXd b = random_vector(50, rng);
  ASSERT_EQ(h.solve(b, x), FactorStatus::kOk);
  EXPECT_LE((a * x - b).norm(), kSolveTol * b.norm());
}

// Issue 17 (strategy table): CholmodFactor::modify, A ← A + Δ by cholmod_updown. A random SPD
// matrix takes 30 changes shaped like a cut's — an "element" (the Laplacian of a random
// 4-vertex clique, weights in [0.5, 1.5]) removed or added, some between vertices far apart so
// that L gains fill, and a vertex decoupled to a diagonal entry (a constrained DOF's row and
// column replaced) — and after every change the modified factor's solve equals a dense solve of
// the matrix built explicitly (kSolveTol). A supernodal factor, a size mismatch and a downdate
// that loses definiteness are statuses.
TEST(CholmodFactor, ModifyByUpdownEqualsAFreshFactorizationOverElementChanges) {
  INCISE_SEEDED_RNG(rng, 17);
  const int n = 240;
  SparseMatrix a = random_sparse_spd(n, 3, 0.5, rng);
  CholmodFactor f({CholmodKind::kSimplicialLdl, CholmodOrdering::kMetis});
  ASSERT_EQ(f.compute(a, 1), FactorStatus::kOk);
  std::uniform_int_distribution<int> vertex(0, n - 1);
  std::uniform_real_distribution<double> weight(0.5, 1.5);
  std::vector<SparseMatrix> added;  // elements added so far (removable)
  int updates = 0, downdates = 0;
  for (int step = 0; step < 30; ++step) {
    SparseMatrix delta(n, n);
    std::vector<Eigen::Triplet<double>> t;
    if (step % 7 == 6) {  // decouple vertex v: row/column v replaced by its diagonal entry
      const int v = vertex(rng);
      for (SparseMatrix::InnerIterator it(a, v); it; ++it) {
        if (it.row() == v) continue;
        t.emplace_back(static_cast<int>(it.row()), v, -it.value());
        t.emplace_back(v, static_cast<int>(it.row()), -it.value());
      }
      delta.setFromTriplets(t.begin(), t.end());
    } else if (step % 3 == 2 && !added.empty()) {  // remove an element added before
      delta = -added.back();
      added.pop_back();
    } else {  // add a 4-clique element (vertices anywhere: new fill)
      std::array<int, 4> v{};
      for (int& x : v) x = vertex(rng);
      for (int p = 0; p < 4; ++p)
        for (int q = p + 1; q < 4; ++q) {
          if (v[p] == v[q]) continue;
          const double w = weight(rng);
          t.emplace_back(v[p], v[p], w);
          t.emplace_back(v[q], v[q], w);
          t.emplace_back(v[p], v[q], -w);
          t.emplace_back(v[q], v[p], -w);
        }
      delta.setFromTriplets(t.begin(), t.end());
      added.push_back(delta);
    }
    a = (a + delta).pruned();
    a.makeCompressed();
    CholmodFactor::ModifyStats stats;
    ASSERT_EQ(f.modify(delta, &stats), FactorStatus::kOk) << "step " << step << ": " << f.message();
    updates += stats.rank_update;
    downdates += stats.rank_downdate;
    EXPECT_LE(stats.rank_update + stats.rank_downdate, stats.touched);
    const Eigen::VectorXd b = random_vector(n, rng);
    Eigen::VectorXd x;
    ASSERT_EQ(f.solve(b, x), FactorStatus::kOk);
    const Eigen::VectorXd xd = Eigen::MatrixXd(a).ldlt().solve(b);
    EXPECT_LE((x - xd).norm(), kSolveTol * xd.norm()) << "step " << step;
  }
  EXPECT_GT(updates, 0);  // both directions were exercised
  EXPECT_GT(downdates, 0);
  // Not positive definite after the change: a status, and the factor is not used after it.
  SparseMatrix down(n, n);
  down.insert(5, 5) = -2.0 * a.coeff(5, 5);
  down.makeCompressed();
  EXPECT_EQ(f.modify(down), FactorStatus::kNotPositiveDefinite);
  Eigen::VectorXd x;
  EXPECT_NE(f.solve(Eigen::VectorXd::Ones(n), x), FactorStatus::kOk);
  EXPECT_EQ(f.modify(down), FactorStatus::kNotAnalyzed);
  SparseMatrix small(3, 3);
  ASSERT_EQ(f.compute(a, 2), FactorStatus::kOk);
  EXPECT_EQ(f.modify(small), FactorStatus::kInvalidInput);
  CholmodFactor super({CholmodKind::kSupernodal, CholmodOrdering::kMetis});
  ASSERT_EQ(super.compute(a, 1), FactorStatus::kOk);
  EXPECT_EQ(super.modify(down), FactorStatus::kInvalidInput);
}

}  // namespace
}  // namespace incise::test
