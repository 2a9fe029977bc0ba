/// \file ldl_closure_solver_test.cpp
/// Triangular solves restricted to elimination-tree closures (linalg/ldl_closure_solver.hpp;
/// Yeung et al. 2016 §3.3, Appendix Thm. 1–3): closures are ancestor-closed and contain the
/// structure of L⁻¹b; restricted and sparse-right-hand-side solves equal full solves on random
/// sparse SPD matrices with random supports; the threaded backward pass is bit-identical to the
/// serial one.

#include "augmented_stand_in.hpp"
#include "random_spd.hpp"

#include <incise/core/error.hpp>
#include <incise/linalg/cholmod_factor.hpp>
#include <incise/linalg/ldl_closure_solver.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>

namespace incise::test {
namespace {

using linalg::CholmodFactor;
using linalg::CholmodKind;
using linalg::CholmodOptions;
using linalg::CholmodOrdering;
using linalg::ClosureLdlSolver;
using linalg::FactorStatus;
using linalg::SparseMatrix;

/// Restricted and full solves with the same factor differ only in the order of round-off
/// (κ ≲ 1e3 for random_sparse_spd with shift 0.1, ≲ 1e4 for the brick): relative 1e-10 of ‖x‖.
constexpr double kSolveTol = 1e-10;

std::shared_ptr<const linalg::LdlFactorData> factor_of(const SparseMatrix& a, CholmodOptions o) {
  CholmodFactor f(o);
  if (f.compute(a, 1) != FactorStatus::kOk) return nullptr;
  return f.extract_ldl();
}

// A random subset of {0 … n−1} with 1 … max_size entries (repetitions allowed).
std::vector<int> random_support(int n, int max_size, std::mt19937_64& rng) {
  std::uniform_int_distribution<int> size(1, max_size), pick(0, n - 1);
  std::vector<int> s(static_cast<size_t>(size(rng)));
  for (int& i : s) i = pick(rng);
  return s;
}

struct Case {
  std::string name;
  SparseMatrix a;
  CholmodOptions options;
};

std::vector<Case> cases(std::mt19937_64& rng) {
  std::vector<Case> c;
  const CholmodOptions metis{CholmodKind::kSimplicialLdl, CholmodOrdering::kMetis};
  const CholmodOptions amd_super{CholmodKind::kSupernodal, CholmodOrdering::kAmd};
  const CholmodOptions natural{CholmodKind::kSimplicialLdl, CholmodOrdering::kNatural};
  c.push_back({"brick", CutModel::from_mesh(mesh::make_brick(2)).assemble(), amd_super});
  c.push_back({"random 300, METIS", random_sparse_spd(300, 3, 0.1, rng), metis});
  c.push_back({"random 250, AMD supernodal", random_sparse_spd(250, 2, 0.1, rng), amd_super});
  c.push_back({"random 200, natural", random_sparse_spd(200, 4, 0.1, rng), natural});
  c.push_back({"random forest 240 (4 components)", random_sparse_spd(240, 3, 0.1, rng, 4), metis});
  return c;
}

// Thm. 3 (closure = union of root paths) and Thm. 1 (struct(L⁻¹b) ⊆ closure_L(struct b)):
// closures are sorted, ancestor-closed, contain the positions of their indices, and the dense
// forward solve L⁻¹(P b) is exactly zero outside the closure.
TEST(ClosureLdlSolver, ClosuresAreAncestorClosedAndContainTheForwardSolveThm1And3) {
  INCISE_SEEDED_RNG(rng, 3);
  for (const Case& c : cases(rng)) {
    SCOPED_TRACE(c.name);
    const auto ldl = factor_of(c.a, c.options);
    ASSERT_NE(ldl, nullptr);
    ClosureLdlSolver s(ldl);
    EXPECT_GE(s.num_supernodes(), 1);
    EXPECT_LE(s.num_supernodes(), ldl->n);
    const Eigen::MatrixXd l = dense_l(*ldl);
    std::normal_distribution<double> g;
    for (int trial = 0; trial < scaled(10); ++trial) {
      const std::vector<int> b_idx = random_support(ldl->n, 5, rng);
      const std::vector<int> cl = s.closure(b_idx);
      ASSERT_TRUE(std::is_sorted(cl.begin(), cl.end()));
      ASSERT_EQ(std::adjacent_find(cl.begin(), cl.end()), cl.end());  // no duplicates
      auto in_closure = [&cl](int p) { return std::binary_search(cl.begin(), cl.end(), p); };
      for (int i : b_idx) EXPECT_TRUE(in_closure(ldl->inverse_perm[i]));
      for (int p : cl) {
        const int q = ldl->parent[p];
        if (q >= 0) {
          EXPECT_TRUE(in_closure(q)) << "parent of " << p;
        }
      }
      Eigen::VectorXd pb = Eigen::VectorXd::Zero(ldl->n);
      for (int i : b_idx) pb(ldl->inverse_perm[i]) += g(rng);
      const Eigen::VectorXd y = l.triangularView<Eigen::UnitLower>().solve(pb);
      for (int p = 0; p < ldl->n; ++p) {
        if (!in_closure(p)) {
          EXPECT_EQ(y(p), 0.0) << "position " << p;
        }
      }
    }
  }
}

// Thm. 1–3: a solve restricted to closure_L(b) forward and closure_L(wanted) backward equals the
// full solve on the wanted entries; the sparse-RHS solve (restricted forward, full backward)
// equals it everywhere. Duplicate indices in b are summed.
TEST(ClosureLdlSolver, RestrictedSolvesEqualFullSolvesThm1to3) {
  INCISE_SEEDED_RNG(rng, 5);
  for (const Case& c : cases(rng)) {
    SCOPED_TRACE(c.name);
    const auto ldl = factor_of(c.a, c.options);
    ASSERT_NE(ldl, nullptr);
    ClosureLdlSolver s(ldl);
    const int n = ldl->n;
    std::normal_distribution<double> g;
    for (int trial = 0; trial < scaled(20); ++trial) {
      const std::vector<int> bi = random_support(n, 1 + trial % 6, rng);
      std::vector<double> bv(bi.size());
      for (double& v : bv) v = g(rng);
      const std::vector<int> want = random_support(n, 1 + trial % 7, rng);
      Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
      for (size_t k = 0; k < bi.size(); ++k) b(bi[k]) += bv[k];
      Eigen::VectorXd xfull;
      s.solve_dense(b, xfull);
      std::vector<double> xw;
      s.solve_restricted(bi, bv, s.closure(bi), s.closure(want), want, xw);
      ASSERT_EQ(xw.size(), want.size());
      for (size_t k = 0; k < want.size(); ++k)
        EXPECT_NEAR(xw[k], xfull(want[k]), kSolveTol * xfull.norm());
      // Larger closures than needed are allowed (the contract says "contains").
      std::vector<int> more_b = bi, more_w = want;
      more_b.push_back(trial % n);
      more_w.push_back((7 * trial) % n);
      std::vector<double> xm;
      s.solve_restricted(bi, bv, s.closure(more_b), s.closure(more_w), want, xm);
      for (size_t k = 0; k < want.size(); ++k)
        EXPECT_NEAR(xm[k], xfull(want[k]), kSolveTol * xfull.norm());
      Eigen::VectorXd xs;
      s.solve_sparse_rhs(bi, bv, s.closure(bi), xs);
      EXPECT_LE((xs - xfull).norm(), kSolveTol * xfull.norm());
    }
    // The full solve itself against A (backward stable: residual ~ n·eps·‖A‖‖x‖).
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, -1, 1);
    Eigen::VectorXd x;
    s.solve_dense(b, x);
    EXPECT_LE((c.a * x - b).norm(), kSolveTol * b.norm());
  }
}

// Issue 17: the blocked restricted solve with k unit right-hand sides (one forward and one
// backward pass for all of them) equals k single restricted solves on the wanted entries, and
// the full solves; with larger closures than needed too.
TEST(ClosureLdlSolver, BlockedUnitSolvesEqualSingleRestrictedSolvesThm1to3) {
  INCISE_SEEDED_RNG(rng, 17);
  for (const Case& c : cases(rng)) {
    SCOPED_TRACE(c.name);
    const auto ldl = factor_of(c.a, c.options);
    ASSERT_NE(ldl, nullptr);
    ClosureLdlSolver s(ldl);
    const int n = ldl->n;
    for (int trial = 0; trial < scaled(10); ++trial) {
      const std::vector<int> cols = random_support(n, 1 + trial % 9, rng);
      const std::vector<int> want = random_support(n, 1 + trial % 11, rng);
      std::vector<int> more_w = want;
      more_w.push_back((5 * trial) % n);
      for (const std::vector<int>* back : {&want, static_cast<const std::vector<int>*>(&more_w)}) {
        Eigen::MatrixXd x;
        s.solve_restricted_block(cols, s.closure(cols), s.closure(*back), want, x);
        ASSERT_EQ(x.rows(), static_cast<Eigen::Index>(want.size()));
        ASSERT_EQ(x.cols(), static_cast<Eigen::Index>(cols.size()));
        for (std::size_t k = 0; k < cols.size(); ++k) {
          std::vector<double> single;
          s.solve_restricted({cols[k]}, {1.0}, s.closure({cols[k]}), s.closure(*back), want,
                             single);
          Eigen::VectorXd e = Eigen::VectorXd::Zero(n), full;
          e(cols[k]) = 1.0;
          s.solve_dense(e, full);
          for (std::size_t w = 0; w < want.size(); ++w) {
            // Same operations up to the order of the sums: round-off only.
            EXPECT_NEAR(x(static_cast<Eigen::Index>(w), static_cast<Eigen::Index>(k)), single[w],
                        kSolveTol * full.norm());
            EXPECT_NEAR(x(static_cast<Eigen::Index>(w), static_cast<Eigen::Index>(k)),
                        full(want[w]), kSolveTol * full.norm());
          }
        }
      }
    }
  }
}

// Issue 17: with many right-hand sides (the new columns of G joining 𝓛 in one frame), the
// supernodes' parts of the closures go through the dense kernels (dtrsm on the diagonal
// triangle, dgemm below it; ClosureLdlSolver::last_block_dense_supernodes() > 0 is asserted, so
// the BLAS-3 path is the one checked) and still equal the full dense solve (Thm. 1–3), for
// supernodal and simplicial factors, with the backward closure of the wanted set alone or larger.
TEST(ClosureLdlSolver, ManyRhsBlockedSolvesThroughDenseSupernodeKernelsEqualFullSolvesThm1to3) {
  INCISE_SEEDED_RNG(rng, 1717);
  const CholmodOptions metis_super{CholmodKind::kSupernodal, CholmodOrdering::kMetis};
  const CholmodOptions metis{CholmodKind::kSimplicialLdl, CholmodOrdering::kMetis};
  const SparseMatrix brick = CutModel::from_mesh(mesh::make_brick(3)).assemble();
  for (const CholmodOptions& o : {metis_super, metis}) {
    SCOPED_TRACE(o.kind == CholmodKind::kSupernodal ? "supernodal" : "simplicial");
    const auto ldl = factor_of(brick, o);
    ASSERT_NE(ldl, nullptr);
    ClosureLdlSolver s(ldl);
    const int n = ldl->n;
    int dense_blocks = 0;
    for (int trial = 0; trial < scaled(4); ++trial) {
      const std::vector<int> cols = random_support(n, 40 + 30 * trial, rng);
      std::vector<int> want = random_support(n, 60, rng);
      want.insert(want.end(), cols.begin(), cols.end());  // G's rows include its new columns
      std::vector<int> more = want;
      for (int e = 0; e < 20; ++e) more.push_back((37 * e + trial) % n);
      const std::vector<const std::vector<int>*> backs{&want, &more};
      for (const std::vector<int>* back : backs) {
        Eigen::MatrixXd x;
        s.solve_restricted_block(cols, s.closure(cols), s.closure(*back), want, x);
        dense_blocks += s.last_block_dense_supernodes();
        for (std::size_t k = 0; k < cols.size(); ++k) {
          Eigen::VectorXd e = Eigen::VectorXd::Zero(n), full;
          e(cols[k]) = 1.0;
          s.solve_dense(e, full);
          for (std::size_t w = 0; w < want.size(); ++w)
            ASSERT_NEAR(x(static_cast<Eigen::Index>(w), static_cast<Eigen::Index>(k)),
                        full(want[w]), kSolveTol * full.norm())
                << "column " << cols[k] << ", row " << want[w];
        }
      }
    }
    EXPECT_GT(dense_blocks, 0) << "no supernode block reached the dense kernels";
  }
}

// The threaded full backward pass (ClosureLdlSolver with threads > 1) splits the postordered
// elimination forest into a root side and disjoint subtrees; every entry is computed by the
// same operations in the same order, so the result must be bit-identical to the serial pass.
// Matrices: a brick (one tree), a long beam (the paper's shape: a deep separator chain), two
// disconnected bricks (a forest with two roots) and random sparse SPD matrices and forests.
TEST(ClosureLdlSolver, ThreadedBackwardIsBitIdenticalToSerial) {
  const SparseMatrix brick = CutModel::from_mesh(mesh::make_brick(2)).assemble();
  const SparseMatrix beam = CutModel::from_mesh(mesh::make_beam(40, 0.01)).assemble();
  SparseMatrix two(2 * brick.rows(), 2 * brick.cols());
  {
    std::vector<Eigen::Triplet<double>> t;
    for (int j = 0; j < brick.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(brick, j); it; ++it) {
        t.emplace_back(static_cast<int>(it.row()), j, it.value());
        t.emplace_back(static_cast<int>(it.row() + brick.rows()),
                       static_cast<int>(j + brick.cols()), 2.0 * it.value());
      }
    two.setFromTriplets(t.begin(), t.end());
  }
  INCISE_SEEDED_RNG(rng, 11);
  const SparseMatrix random = random_sparse_spd(1500, 3, 0.1, rng);
  const SparseMatrix forest = random_sparse_spd(1200, 3, 0.1, rng, 6);
  std::normal_distribution<double> g;
  int split = 0;  // matrices on which a threaded plan exists (the test must exercise one)
  const SparseMatrix* matrices[] = {&brick, &beam, &two, &random, &forest};
  for (const SparseMatrix* a : matrices) {
    SCOPED_TRACE("n = " + std::to_string(a->rows()));
    const auto ldl = factor_of(*a, {CholmodKind::kSimplicialLdl, CholmodOrdering::kMetis});
    ASSERT_NE(ldl, nullptr);
    ClosureLdlSolver serial(ldl);
    EXPECT_EQ(serial.backward_threads(), 1);
    const int n = static_cast<int>(a->rows());
    std::uniform_int_distribution<int> pick(0, n - 1);
    for (int threads : {2, 3}) {
      ClosureLdlSolver par(ldl, threads);
      if (par.backward_threads() > 1) ++split;
      EXPECT_LE(par.backward_threads(), threads);
      EXPECT_LE(par.backward_serial_fraction(), 1.0);
      EXPECT_LE(par.backward_max_bin_fraction(), 1.0);
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
  EXPECT_GE(split, 6) << "too few threaded plans were exercised";
}

TEST(ClosureLdlSolver, MisuseThrows) {
  EXPECT_THROW(ClosureLdlSolver(nullptr), UsageError);
  INCISE_SEEDED_RNG(rng, 13);
  const auto ldl = factor_of(random_sparse_spd(20, 2, 0.1, rng),
                             {CholmodKind::kSimplicialLdl, CholmodOrdering::kAmd});
  ASSERT_NE(ldl, nullptr);
  EXPECT_THROW(ClosureLdlSolver(ldl, 0), UsageError);
  ClosureLdlSolver s(ldl);
  Eigen::VectorXd x;
  EXPECT_THROW(s.solve_dense(Eigen::VectorXd::Ones(19), x), UsageError);
}

}  // namespace
}  // namespace incise::test
