// Scalpel sweep against an edge (delaunay/sweep.hpp, thesis §5.3.2, Fig. 5.15, eq. (5.1)) and
// the maximum movement of Fig. 5.11: one test per form of the coplanarity polynomial (linear,
// quadratic, double root, coplanar: edge in the swept plane and edge parallel to the scalpel),
// touching an endpoint exactly and missing it by 1e-6, and the d_max guarantee on random data.
// Expected values are derived by hand in the comments (not taken from the code).
#include <incise/delaunay/sweep.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace incise::delaunay {
namespace {

// Roots and parameters computed in double from closed forms: 1e-12 is ~1e4 ulps of O(1) values.
constexpr double kExact = 1e-12;

ScalpelSegment seg(const Vec3& head, const Vec3& tail) {
  return {head, tail};
}

TEST(DelaunaySweep, Eq5_1TranslatingScalpelIsTheLinearCase) {
  // A vertical scalpel x: 0 → 2 at y = 0.5 against the edge x = 1, y ∈ [−1, 1] in z = 0:
  // contact at τ = 1/2, z = 0 → λ = 1/2, y = 0.5 = µ·1 + (1 − µ)(−1) → µ = 3/4. A pure
  // translation has c₂ = 0 exactly.
  const auto r = intersect_sweep_edge(seg({0, 0.5, 1}, {0, 0.5, -1}),
                                      seg({2, 0.5, 1}, {2, 0.5, -1}), {1, 1, 0}, {1, -1, 0});
  EXPECT_EQ(r.kind, SweepCase::kLinear) << to_string(r.kind);
  ASSERT_EQ(r.hits.size(), 1u);
  EXPECT_NEAR(r.hits[0].time, 0.5, kExact);
  EXPECT_NEAR(r.hits[0].lambda, 0.5, kExact);
  EXPECT_NEAR(r.hits[0].mu, 0.75, kExact);
}

TEST(DelaunaySweep, Eq5_1RotatingScalpelSolvesTheQuadratic) {
  // In z = 0: T(τ) = (−1 + 2τ, 0), H(τ) − T(τ) = (τ, 1 − τ); the edge is vertical through
  // P = (0, 0.2). Coplanarity: τ·0.2 − (1 − τ)(1 − 2τ) = 0 ⇔ 2τ² − 3.2τ + 1 = 0, roots
  // (3.2 ∓ √2.24)/4 = 0.4258…, 1.174…: one in [0, 1], with λ = (1 − 2τ)/τ and µ = 1/2.
  const auto r = intersect_sweep_edge(seg({-1, 1, 0}, {-1, 0, 0}), seg({2, 0, 0}, {1, 0, 0}),
                                      {0, 0.2, 1}, {0, 0.2, -1});
  EXPECT_EQ(r.kind, SweepCase::kQuadratic) << to_string(r.kind);
  ASSERT_EQ(r.hits.size(), 1u);
  const double tau = (3.2 - std::sqrt(2.24)) / 4;
  EXPECT_NEAR(r.hits[0].time, tau, kExact);
  EXPECT_NEAR(r.hits[0].lambda, (1 - 2 * tau) / tau, kExact);
  EXPECT_NEAR(r.hits[0].mu, 0.5, kExact);
}

TEST(DelaunaySweep, Eq5_1TangentSweepIsTheDoubleRoot) {
  // With s = τ − 1/2: T = (−1 + s, s, 0), H = (1 + s, −s, 0); the edge is the z-axis through the
  // origin. Coplanarity: cross(H − T, −T) = −2s², a double root at τ = 1/2 where the origin is
  // the scalpel's midpoint (λ = 1/2) and the edge's (µ = 1/2).
  const auto r = intersect_sweep_edge(seg({0.5, 0.5, 0}, {-1.5, -0.5, 0}),
                                      seg({1.5, -0.5, 0}, {-0.5, 0.5, 0}), {0, 0, 1}, {0, 0, -1});
  EXPECT_EQ(r.kind, SweepCase::kDoubleRoot) << to_string(r.kind);
  ASSERT_EQ(r.hits.size(), 1u);
  EXPECT_NEAR(r.hits[0].time, 0.5, kExact);
  EXPECT_NEAR(r.hits[0].lambda, 0.5, kExact);
  EXPECT_NEAR(r.hits[0].mu, 0.5, kExact);
}

TEST(DelaunaySweep, Eq5_1EdgeInTheSweptPlaneIsCoplanar) {
  // Scalpel (−2, ±1, 0) translating by +4 in x; the edge a = (0.5, −0.5, 0), b = (1, 0.5, 0)
  // lies in the swept plane z = 0. First contact when x = 0.5: τ = 2.5/4 = 0.625, at a (µ = 1),
  // y = −0.5 = 2λ − 1 → λ = 1/4. The bisection stops at a gap ≤ 1e-8 (1e-9 × the scale ≈ 10),
  // so τ is within 1e-8/4 (the scalpel's speed is 4).
  const auto r = intersect_sweep_edge(seg({-2, 1, 0}, {-2, -1, 0}), seg({2, 1, 0}, {2, -1, 0}),
                                      {0.5, -0.5, 0}, {1, 0.5, 0});
  EXPECT_EQ(r.kind, SweepCase::kCoplanar) << to_string(r.kind);
  ASSERT_EQ(r.hits.size(), 1u);
  EXPECT_NEAR(r.hits[0].time, 0.625, 1e-8);
  EXPECT_NEAR(r.hits[0].lambda, 0.25, 1e-8);
  EXPECT_NEAR(r.hits[0].mu, 1.0, 1e-8);
}

TEST(DelaunaySweep, Eq5_1EdgeParallelToTheScalpelIsCoplanar) {
  // Vertical scalpel z ∈ [−1, 1] at y = 0 translating x: −2 → 2; a vertical edge at x = 0.5:
  // parallel lines are always coplanar (c₀ = c₁ = c₂ = 0). On the scalpel's plane y = 0 the
  // contact is at τ = 0.625 over the whole edge; at y = 0.3 there is none.
  const ScalpelSegment from = seg({-2, 0, 1}, {-2, 0, -1}), to = seg({2, 0, 1}, {2, 0, -1});
  const auto hit = intersect_sweep_edge(from, to, {0.5, 0, 0.5}, {0.5, 0, -0.5});
  EXPECT_EQ(hit.kind, SweepCase::kCoplanar) << to_string(hit.kind);
  ASSERT_EQ(hit.hits.size(), 1u);
  EXPECT_NEAR(hit.hits[0].time, 0.625, 1e-8);
  // The contact point λH + (1 − λ)T equals µa + (1 − µ)b: z = 2λ − 1 = µ·0.5 − (1 − µ)·0.5.
  EXPECT_NEAR(2 * hit.hits[0].lambda - 1, hit.hits[0].mu - 0.5, 1e-8);
  const auto miss = intersect_sweep_edge(from, to, {0.5, 0.3, 0.5}, {0.5, 0.3, -0.5});
  EXPECT_EQ(miss.kind, SweepCase::kCoplanar);
  EXPECT_TRUE(miss.hits.empty());
}

TEST(DelaunaySweep, Eq5_1TouchingAnEndpointIsAHitAndMissingItByAMicronIsNot) {
  // Scalpel (0, 0, [0, 1]) translating x: 0 → 2 (the tail runs along the x-axis). The edge from
  // b = (1, 0, 0) to a = (1, 2, 1) meets the scalpel at x = 1 (τ = 1/2) only in b: λ = 0 (tail),
  // µ = 0 (b). Moving b to y = 1e-6 the edge stays at y ≥ 1e-6 > 0: no contact (1e-6 is 1e3×
  // the range tolerance of the parameters).
  const ScalpelSegment from = seg({0, 0, 1}, {0, 0, 0}), to = seg({2, 0, 1}, {2, 0, 0});
  const auto touch = intersect_sweep_edge(from, to, {1, 2, 1}, {1, 0, 0});
  ASSERT_EQ(touch.hits.size(), 1u) << to_string(touch.kind);
  EXPECT_NEAR(touch.hits[0].time, 0.5, kExact);
  EXPECT_NEAR(touch.hits[0].lambda, 0.0, kExact);
  EXPECT_NEAR(touch.hits[0].mu, 0.0, kExact);
  const auto miss = intersect_sweep_edge(from, to, {1, 2, 1}, {1, 1e-6, 0});
  EXPECT_TRUE(miss.hits.empty()) << to_string(miss.kind);
  // A zero-length edge or scalpel has no contact.
  EXPECT_TRUE(intersect_sweep_edge(from, to, {1, 0, 0.5}, {1, 0, 0.5}).hits.empty());
  EXPECT_TRUE(intersect_sweep_edge(seg({0, 0, 0}, {0, 0, 0}), seg({2, 0, 0}, {2, 0, 0}), {1, 2, 1},
                                   {1, -1, 0})
                  .hits.empty());
}

TEST(DelaunaySweep, Fig5_11MovesBelowDmaxNeverHitAndTheClosestApproachDoes) {
  // Random scalpels and edges in the unit cube: d = max_movement. Ends displaced by 0.99 d in
  // random directions never touch the edge (the Fig. 5.11 argument); translating the scalpel by
  // 1.01 × the closest-point vector does (it passes through the closest point of the edge).
  INCISE_SEEDED_RNG(rng, 511);
  std::uniform_real_distribution<double> U(-1, 1);
  auto rand3 = [&] { return Vec3(U(rng), U(rng), U(rng)); };
  int checked = 0, reached = 0;
  for (int k = 0; k < 300; ++k) {
    const ScalpelSegment s{rand3(), rand3()};
    const Vec3 a = rand3(), b = rand3();
    const double d = max_movement(s, a, b);
    if (!(d > 1e-3)) continue;  // touching already: nothing to test
    ++checked;
    const Vec3 p = 0.99 * d * rand3().normalized(), q = 0.99 * d * rand3().normalized();
    const auto below = intersect_sweep_edge(s, {s.head + p, s.tail + q}, a, b);
    EXPECT_TRUE(below.hits.empty()) << "case " << k << " d_max " << d;
    double u, w;
    segment_distance(s.tail, s.head, b, a, u, w);
    const Vec3 on_scalpel = s.tail + u * (s.head - s.tail), on_edge = b + w * (a - b);
    const Vec3 shift = 1.01 * (on_edge - on_scalpel);
    reached += !intersect_sweep_edge(s, {s.head + shift, s.tail + shift}, a, b).hits.empty();
  }
  EXPECT_GT(checked, 200);
  EXPECT_EQ(reached, checked);
}

}  // namespace
}  // namespace incise::delaunay
