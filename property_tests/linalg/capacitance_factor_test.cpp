/// CapacitanceFactor (linalg/capacitance_factor.hpp): the Schur (capacitance) matrix of
/// Yeung et al. 2016 eq. 17 factored once and then updated (Sherman–Morrison–Woodbury on the
/// changed rows and columns) as labels join or leave and columns change value. Over random
/// sequences of such changes the updated operator's solutions equal a fresh LU's, the
/// condition estimate brackets the true reciprocal condition number, and the fresh
/// refactorization happens by the cost rule (counts, not clocks).

#include <gtest/gtest.h>
#include <incise/core/error.hpp>
#include <incise/linalg/capacitance_factor.hpp>
#include <incise/linalg/dense_blas.hpp>
#include <incise_test/seed.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <random>
#include <set>
#include <vector>

namespace incise::linalg {
namespace {

/// A model of the capacitance matrix: entries keyed by label pairs, S = I + G Ψ-like — the
/// identity plus a random coupling of norm ≤ 0.3 per row (so ‖S − I‖∞ ≤ 0.3 and κ∞(S) ≤
/// 1.3/0.7 < 2), with rows and columns scaled over 6 decades (the units of eq. 17 differ; the
/// factor equilibrates). Labels are DOF numbers.
struct Model {
  std::map<int, double> row_unit, col_unit;     // per-label scales (decades)
  std::map<std::pair<int, int>, double> entry;  // off-diagonal couplings, unscaled
  std::set<int> labels;
  std::mt19937_64& rng;
  std::uniform_real_distribution<double> u{-1.0, 1.0};
  explicit Model(std::mt19937_64& r) : rng(r) {}

  void set_column(int j) {  // new random coupling in column j (and row j, to move rows too)
    for (int i : labels) {
      if (i == j) continue;
      entry[{i, j}] = 0.3 * u(rng) / static_cast<double>(labels.size());
      entry[{j, i}] = 0.3 * u(rng) / static_cast<double>(labels.size());
    }
  }
  void change_column(int j) {  // column j only (as a changed column value of eq. 17)
    for (int i : labels)
      if (i != j) entry[{i, j}] = 0.3 * u(rng) / static_cast<double>(labels.size());
  }
  void join(int j) {
    labels.insert(j);
    row_unit[j] = std::pow(10.0, 3 * u(rng));
    col_unit[j] = std::pow(10.0, 3 * u(rng));
    set_column(j);
  }
  void leave(int j) { labels.erase(j); }
  std::vector<int> sorted() const { return {labels.begin(), labels.end()}; }
  Eigen::MatrixXd matrix() const {
    const std::vector<int> l = sorted();
    const auto m = static_cast<Eigen::Index>(l.size());
    Eigen::MatrixXd s(m, m);
    for (Eigen::Index j = 0; j < m; ++j)
      for (Eigen::Index i = 0; i < m; ++i) {
        const int a = l[static_cast<std::size_t>(i)], b = l[static_cast<std::size_t>(j)];
        const auto it = entry.find({a, b});
        const double base = a == b ? 1.0 : (it != entry.end() ? it->second : 0.0);
        s(i, j) = row_unit.at(a) * base * col_unit.at(b);
      }
    return s;
  }
};

// Random joins (a block of labels, as a cut's new columns), leaves and value changes, 50 steps
// per sequence; after each update the solution of S x = b equals a fresh partial-pivoting LU's.
TEST(CapacitanceFactor, UpdatedSolvesEqualAFreshFactorizationOverJoinsLeavesAndChanges) {
  INCISE_SEEDED_RNG(rng, 1717);
  std::uniform_int_distribution<int> label(0, 400);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0;
  int updated = 0, refreshed = 0;
  for (int sequence = 0; sequence < 3; ++sequence) {
    Model model(rng);
    for (int k = 0; k < 40; ++k) model.join(label(rng));
    CapacitanceFactor factor;
    for (int step = 0; step < 50; ++step) {
      if (step > 0) {
        const int joins = static_cast<int>(u(rng) * 6), changes = static_cast<int>(u(rng) * 4);
        for (int k = 0; k < joins; ++k) model.join(label(rng));
        for (int k = 0; k < changes && !model.labels.empty(); ++k) {
          auto it = model.labels.begin();
          std::advance(it, static_cast<long>(u(rng) * static_cast<double>(model.labels.size())));
          if (it == model.labels.end()) --it;
          const double p = u(rng);
          if (p < 0.3) {
            model.leave(*it);
          } else if (p < 0.8) {
            model.change_column(*it);
          } else {
            model.set_column(*it);
          }
        }
      }
      const Eigen::MatrixXd s = model.matrix();
      const CapacitanceUpdate r = factor.update(s, model.sorted());
      (r.refreshed ? refreshed : updated) += 1;
      const Eigen::VectorXd b = Eigen::VectorXd::NullaryExpr(s.rows(), [&]() { return u(rng); });
      Eigen::VectorXd x;
      factor.solve(b, x);
      const Eigen::VectorXd ref = s.partialPivLu().solve(b);
      // Equilibrated, κ(S) < 2 and the Woodbury correction's K = I + VᵀW is as well
      // conditioned as S (det K = det Ŝ / det Ŝ₀): both solutions are backward stable to
      // m·ε·growth ≈ 1e-13; 1e-10 relative leaves three decades for the growth of the
      // accumulated correction.
      const double diff = (x - ref).norm() / ref.norm();
      worst = std::max(worst, diff);
      ASSERT_LE(diff, 1e-10) << "sequence " << sequence << " step " << step << " |C| " << r.changed
                             << (r.refreshed ? " (fresh)" : "");
    }
  }
  // Both paths are exercised: updates (most steps), and fresh factorizations (each sequence's
  // first, then by the cost rule — at these small m a fresh LU is cheap, so it is frequent).
  EXPECT_GT(updated, 50);
  EXPECT_GE(refreshed, 3);
  std::cout << "capacitance updates " << updated << ", fresh " << refreshed << ", worst relative "
            << worst << "\n";
}

// The reported estimate (Hager's 1-norm estimator on the updated, equilibrated operator) is an
// estimate of ‖Ŝ⁻¹‖₁ from below, so rcond_est ≥ the true 1/(‖Ŝ‖₁‖Ŝ⁻¹‖₁); it is rarely off by
// more than a factor 3 (Higham 2002, §15.3); checked two-sided with a factor 10.
TEST(CapacitanceFactor, ConditionEstimateBracketsTheTrueReciprocalCondition) {
  INCISE_SEEDED_RNG(rng, 1718);
  Model model(rng);
  for (int k = 0; k < 30; ++k) model.join(k);
  CapacitanceFactor factor;
  for (int step = 0; step < 20; ++step) {
    model.join(100 + step);
    model.set_column(step);
    if (step % 3 == 0) model.leave(step + 1);
    const Eigen::MatrixXd s = model.matrix();
    const std::vector<int> l = model.sorted();
    const CapacitanceUpdate r = factor.update(s, l);
    // The true value for the operator the factor holds: Ŝ = diag(row) S diag(col) with an
    // identity block (norms max(·, 1) for the block diagonal matrix).
    const Eigen::MatrixXd shat =
        factor.row_scale().asDiagonal() * s * factor.col_scale().asDiagonal();
    const double norm = std::max(1.0, shat.cwiseAbs().colwise().sum().maxCoeff());
    const double inv_norm = std::max(1.0, shat.inverse().cwiseAbs().colwise().sum().maxCoeff());
    const double true_rcond = 1.0 / (norm * inv_norm);
    EXPECT_GE(r.rcond, true_rcond * (1 - 1e-9)) << "step " << step << (r.refreshed ? " fresh" : "");
    EXPECT_LE(r.rcond, 10 * true_rcond) << "step " << step << (r.refreshed ? " fresh" : "");
  }
  // A singular matrix: the estimate is (numerically) zero.
  Eigen::MatrixXd sing = model.matrix();
  sing.col(1) = sing.col(0);
  CapacitanceFactor f2;
  EXPECT_LT(f2.update(sing, model.sorted()).rcond, 1e-13);
}

// The cost rule: a small change updates; a change of most labels refactors (the predicted
// update costs more than ⅔m³); force_fresh refactors.
TEST(CapacitanceFactor, FreshFactorizationByTheCostRule) {
  INCISE_SEEDED_RNG(rng, 1719);
  Model model(rng);
  for (int k = 0; k < 60; ++k) model.join(k);
  CapacitanceFactor factor;
  EXPECT_TRUE(factor.update(model.matrix(), model.sorted()).refreshed);
  model.change_column(5);
  CapacitanceUpdate r = factor.update(model.matrix(), model.sorted());
  EXPECT_FALSE(r.refreshed);
  EXPECT_EQ(r.changed, 1);  // one column
  model.join(100);
  r = factor.update(model.matrix(), model.sorted());
  EXPECT_FALSE(r.refreshed);
  EXPECT_EQ(r.changed, 3);  // column 5, and the new label's row and column
  EXPECT_EQ(factor.fresh_count(), 1);
  for (int k = 0; k < 60; ++k) model.leave(k);
  model.leave(100);
  for (int k = 60; k < 120; ++k) model.join(k);  // all labels replaced
  r = factor.update(model.matrix(), model.sorted());
  EXPECT_TRUE(r.refreshed);
  EXPECT_EQ(factor.fresh_count(), 2);
  EXPECT_TRUE(factor.update(model.matrix(), model.sorted(), /*force_fresh=*/true).refreshed);
  EXPECT_THROW((void)factor.update(model.matrix(), {1, 0}), UsageError);
}

// The dense kernels behind the capacitance factorization and the blocked supernodal solves
// (dense_blas.hpp; issue 17): LAPACK's LU (when the process has it) solves like Eigen's
// partial-pivoting LU, with many right-hand sides and transposed; dgemm in all four transpose
// combinations and the unit-lower dtrsm on sub-blocks (leading dimensions larger than the
// rows) equal Eigen's products and triangular solves. Random well-conditioned matrices
// (identity + 0.5/n-bounded coupling: κ∞ ≤ 3); tolerance 1e-12 relative: ε·n·κ ≈ 1e-13 at
// n = 250, both sides backward stable.
TEST(DenseBlas, LuGemmAndTrsmEqualEigenOnRandomBlocks) {
  INCISE_SEEDED_RNG(rng, 1720);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto random = [&](Eigen::Index r, Eigen::Index c) {
    return Eigen::MatrixXd(Eigen::MatrixXd::NullaryExpr(r, c, [&]() { return u(rng); }));
  };
  std::cout << "dense BLAS/LAPACK found: " << (dense_blas_available() ? "yes" : "no") << "\n";
  for (const int n : {1, 7, 60, 250}) {
    SCOPED_TRACE(n);
    const Eigen::MatrixXd a =
        Eigen::MatrixXd::Identity(n, n) + random(n, n) * (0.5 / static_cast<double>(n));
    const Eigen::MatrixXd b = random(n, 13);
    for (const bool use_blas : {true, false}) {
      DenseLu lu(use_blas);
      EXPECT_EQ(lu.uses_blas(), use_blas && dense_blas_available());
      lu.compute(a);
      ASSERT_EQ(lu.size(), n);
      for (const bool transposed : {false, true}) {
        Eigen::MatrixXd x = b;
        lu.solve_in_place(x, transposed);
        const Eigen::MatrixXd ref = transposed
                                        ? Eigen::MatrixXd(a.transpose().partialPivLu().solve(b))
                                        : Eigen::MatrixXd(a.partialPivLu().solve(b));
        EXPECT_LE((x - ref).norm(), 1e-12 * ref.norm()) << (transposed ? "Aᵀ" : "A");
        const Eigen::VectorXd x0 = lu.solve(b.col(0), transposed);
        EXPECT_LE((x0 - ref.col(0)).norm(), 1e-12 * ref.col(0).norm());
      }
    }
    // dgemm on sub-blocks: C(2:, :) = 0.5 op(A) op(B) − 2 C, through BLAS and through the
    // Eigen fallback (use_blas = false: what runs when no BLAS is loaded); the rows of C
    // outside the block must be left as they were.
    const int m = n + 3, kk = std::max(1, n / 2), nn = 5;
    for (const bool use_blas : {true, false})
      for (const bool ta : {false, true})
        for (const bool tb : {false, true}) {
          SCOPED_TRACE(testing::Message()
                       << "use_blas " << use_blas << " op(A) " << ta << " op(B) " << tb);
          const Eigen::MatrixXd am = ta ? random(kk + 2, m) : random(m + 2, kk);
          const Eigen::MatrixXd bm = tb ? random(nn + 1, kk) : random(kk + 1, nn);
          const Eigen::MatrixXd c0 = random(m + 4, nn);
          const Eigen::MatrixXd opa =
              ta ? Eigen::MatrixXd(am.topRows(kk).transpose()) : Eigen::MatrixXd(am.topRows(m));
          const Eigen::MatrixXd opb =
              tb ? Eigen::MatrixXd(bm.topRows(nn).transpose()) : Eigen::MatrixXd(bm.topRows(kk));
          // β = −2, β = 1 and β = 0 (C's block then NaN before: it must not be read).
          for (const double beta : {-2.0, 1.0, 0.0}) {
            Eigen::MatrixXd c = c0;
            if (beta == 0) c.block(2, 0, m, nn).setConstant(std::nan(""));
            const Eigen::MatrixXd ref =
                0.5 * opa * opb + (beta == 0 ? Eigen::MatrixXd::Zero(m, nn)
                                             : Eigen::MatrixXd(beta * c0.block(2, 0, m, nn)));
            dense_gemm(ta, tb, m, nn, kk, 0.5, am.data(), static_cast<int>(am.rows()), bm.data(),
                       static_cast<int>(bm.rows()), beta, c.data() + 2, static_cast<int>(c.rows()),
                       use_blas);
            EXPECT_LE((c.block(2, 0, m, nn) - ref).norm(), 1e-12 * ref.norm()) << "β " << beta;
            EXPECT_EQ(c.topRows(2), c0.topRows(2));
            EXPECT_EQ(c.bottomRows(2), c0.bottomRows(2));
          }
          // k = 0: C ← β C only.
          Eigen::MatrixXd c = c0;
          dense_gemm(ta, tb, m, nn, 0, 0.5, am.data(), static_cast<int>(am.rows()), bm.data(),
                     static_cast<int>(bm.rows()), -2.0, c.data() + 2, static_cast<int>(c.rows()),
                     use_blas);
          EXPECT_EQ(c.block(2, 0, m, nn), Eigen::MatrixXd(-2.0 * c0.block(2, 0, m, nn)));
        }
    // dtrsm: B ← B L⁻¹ and B ← B L⁻ᵀ for a unit-lower L (upper triangle and diagonal hold
    // garbage, which must not be read), through BLAS and through the Eigen fallback.
    const Eigen::MatrixXd l = random(n + 1, n) * (0.5 / static_cast<double>(n));
    const Eigen::MatrixXd lu_l =
        l.topRows(n).triangularView<Eigen::StrictlyLower>().toDenseMatrix() +
        Eigen::MatrixXd::Identity(n, n);
    for (const bool use_blas : {true, false})
      for (const bool tl : {false, true}) {
        Eigen::MatrixXd bb = random(11, n);
        const Eigen::MatrixXd b0 = bb;
        const Eigen::MatrixXd ref = tl ? Eigen::MatrixXd(b0.topRows(9) * lu_l.transpose().inverse())
                                       : Eigen::MatrixXd(b0.topRows(9) * lu_l.inverse());
        dense_trsm_right_unit_lower(tl, 9, n, l.data(), n + 1, bb.data(), 11, use_blas);
        EXPECT_LE((bb.topRows(9) - ref).norm(), 1e-12 * ref.norm())
            << (tl ? "Lᵀ" : "L") << " use_blas " << use_blas;
        EXPECT_EQ(bb.bottomRows(2), b0.bottomRows(2)) << "rows below the m×s block were written";
      }
  }
}

}  // namespace
}  // namespace incise::linalg
