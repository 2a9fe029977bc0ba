/// Unit tests of the shaft friction profile (needle/friction.hpp, thesis §6.3.2, Fig. 6.4): the
/// profile's shape, its exact integral against a fine midpoint rule, the lumped thresholds
/// partitioning ∫ f over [0, s_max], and bad parameters.

#include <incise/core/error.hpp>
#include <incise/needle/friction.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace {

using incise::needle::FrictionProfile;

TEST(NeedleFriction, ProfileHasTipBulgeAndFlatShaft) {
  const FrictionProfile f;
  EXPECT_DOUBLE_EQ(f.density(0.0), f.tip_density);
  EXPECT_DOUBLE_EQ(f.density(f.bulge_length), f.shaft_density);
  EXPECT_DOUBLE_EQ(f.density(0.05), f.shaft_density);
  EXPECT_DOUBLE_EQ(f.density(0.5 * f.bulge_length), 0.5 * (f.tip_density + f.shaft_density));
  EXPECT_EQ(f.density(-1e-6), 0.0);
  EXPECT_GT(f.density(0.0), f.density(0.5 * f.bulge_length));
}

TEST(NeedleFriction, IntegralIsExact) {
  INCISE_SEEDED_RNG(rng, 61);
  FrictionProfile f;
  f.tip_density = 55.0;
  f.bulge_length = 3e-3;
  std::uniform_real_distribution<double> pos(-0.002, 0.02);
  for (int trial = 0; trial < 50; ++trial) {
    double a = pos(rng), b = pos(rng);
    if (a > b) std::swap(a, b);
    // Midpoint rule with 2·10⁵ cells of width h: the jump f_tip at s = 0 costs at most
    // f_tip·h/2 and the kink at ℓ O(h²·Δf'), the linear pieces nothing; 1e-12 N for rounding.
    const int m = 200000;
    const double h = (b - a) / m;
    double q = 0.0;
    for (int i = 0; i < m; ++i) q += f.density(a + (i + 0.5) * h) * h;
    EXPECT_NEAR(f.integral(a, b), q, f.tip_density * h / 2 + 1e-12) << a << " " << b;
  }
}

TEST(NeedleFriction, ThresholdsPartitionTheShaftIntegral) {
  INCISE_SEEDED_RNG(rng, 62);
  const FrictionProfile f;
  std::uniform_real_distribution<double> pos(0.0, 0.07);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> s(1 + trial);
    for (double& v : s) v = pos(rng);
    const std::vector<double> t = f.dynamic_thresholds(s);
    double sum = 0.0;
    for (const double v : t) {
      EXPECT_GE(v, 0.0);
      sum += v;
    }
    const double smax = *std::max_element(s.begin(), s.end());
    // Exact sums of exact integrals: rounding only.
    EXPECT_NEAR(sum, f.integral(0.0, smax), 1e-12);
  }
}

TEST(NeedleFriction, BadParametersAreRejected) {
  FrictionProfile f;
  f.validate();
  f.shaft_density = -1.0;
  EXPECT_THROW(f.validate(), incise::ParameterError);
  f = FrictionProfile{};
  f.bulge_length = 0.0;
  EXPECT_THROW(f.validate(), incise::ParameterError);
  f = FrictionProfile{};
  f.static_factor = 0.5;
  EXPECT_THROW(f.validate(), incise::ParameterError);
}

}  // namespace
