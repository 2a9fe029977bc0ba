// The four-lane eˣ − 1 of the Veronda–Westmann stress (material::detail::expm1_stress(Lanes4),
// issue 19) against a long-double reference and libm's std::expm1.
#include <incise/material/models.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

namespace {

using incise::Lanes4;
using incise::material::detail::expm1_stress;

// Distance in units in the last place of the double nearest to `exact` (at least the spacing
// of the smallest normal numbers).
double ulps(double value, long double exact) {
  const double nearest = static_cast<double>(exact);
  const double spacing = std::max(std::nextafter(std::abs(nearest), INFINITY) - std::abs(nearest),
                                  std::numeric_limits<double>::denorm_min());
  return static_cast<double>(std::abs(static_cast<long double>(value) - exact) / spacing);
}

std::uint64_t bits(double x) {
  std::uint64_t b = 0;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Points: dense where the stress evaluates it (x = 2γ tr E: |x| ≲ 5 for the strains of the
// benchmarks, γ = 8), around every multiple of ½ ln 2 (where k = round(x/ln 2) changes), tiny
// magnitudes, and log-spaced up to the vector limit on both sides.
std::vector<double> sample_points() {
  std::vector<double> xs;
  std::mt19937_64 rng(19);
  std::uniform_real_distribution<double> near(-5.0, 5.0), wide(-700.0, 700.0);
  for (int i = 0; i < 400000; ++i) xs.push_back(near(rng));
  for (int i = 0; i < 100000; ++i) xs.push_back(wide(rng));
  const double half_ln2 = 0.5 * std::log(2.0);
  for (int m = -2000; m <= 2000; ++m) {
    const double c = m * half_ln2;
    if (std::abs(c) >= 700.0) continue;
    double x = c;
    for (int s = 0; s < 4; ++s) x = std::nextafter(x, -INFINITY);
    for (int s = 0; s < 9; ++s, x = std::nextafter(x, INFINITY)) xs.push_back(x);
  }
  for (double e = -300.0; e <= std::log10(700.0); e += 0.01) {
    xs.push_back(std::pow(10.0, e));
    xs.push_back(-std::pow(10.0, e));
  }
  xs.push_back(0.0);
  while (xs.size() % 4 != 0) xs.push_back(1.0);
  return xs;
}

// Reference: expm1l (x86-64 long double: 64-bit significand, 11 more bits than double).
// Bound 2 ulps: the rounding of r = x − k ln 2 (½ ulp of r, carried into eʳ − 1 with a factor
// ≤ 1.2), the series and r² (≤ ½ ulp of the r² term, at most ⅕ of eʳ − 1), and the last
// two additions (½ ulp each, amplified ≤ 1.4× for k = ±1 where 2ᵏ − 1 and 2ᵏ(eʳ − 1) partly
// cancel) add up to less than 2.5 ulps in the worst case; measured 1.975 at x ≈ 0.387
// (k = 1, r ≈ −0.31; printed; 1.88 at x ≈ ½ ln 2 with the series by Horner's scheme before
// issue 19's sixth pass); libm 0.78.
TEST(Expm1Lanes, WithinTwoUlpsOfLongDoubleReference) {
  const std::vector<double> xs = sample_points();
  double worst = 0.0, worst_x = 0.0, worst_libm = 0.0;
  for (std::size_t i = 0; i < xs.size(); i += 4) {
    const Lanes4 v = expm1_stress(Lanes4(xs[i], xs[i + 1], xs[i + 2], xs[i + 3]));
    for (int l = 0; l < 4; ++l) {
      const double x = xs[i + static_cast<std::size_t>(l)];
      const long double exact = expm1l(static_cast<long double>(x));
      const double e = ulps(v[l], exact);
      if (e > worst) {
        worst = e;
        worst_x = x;
      }
      worst_libm = std::max(worst_libm, ulps(std::expm1(x), exact));
    }
  }
  std::printf("expm1_stress(Lanes4): %zu points, worst %.3f ulps at x = %.17g; std::expm1 %.3f\n",
              xs.size(), worst, worst_x, worst_libm);
  EXPECT_LE(worst, 2.0) << "at x = " << worst_x;
}

// Each lane's result depends on its own x only (no cross-lane effect; the same bits in every
// lane position), the exact values at 0 and the limits, and the fallback beyond the vector
// range (overflow to +∞, −1 far left, NaN propagated) is libm's, lane by lane.
TEST(Expm1Lanes, LanesIndependentAndSpecialValues) {
  const double xs[] = {0.3, -1.7, 4.2, 1e-9};
  const Lanes4 a = expm1_stress(Lanes4(xs[0], xs[1], xs[2], xs[3]));
  const Lanes4 b = expm1_stress(Lanes4(xs[3], xs[2], xs[1], xs[0]));
  for (int l = 0; l < 4; ++l) EXPECT_EQ(bits(a[l]), bits(b[3 - l])) << "lane " << l;
  EXPECT_EQ(expm1_stress(Lanes4(0.0))[0], 0.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Lanes4 f = expm1_stress(Lanes4(800.0, -800.0, nan, 0.5));
  EXPECT_EQ(f[0], std::expm1(800.0));  // +∞
  EXPECT_EQ(f[1], -1.0);
  EXPECT_TRUE(std::isnan(f[2]));
  EXPECT_EQ(f[3], std::expm1(0.5));  // a fallback block is libm in every lane
  // Just inside the vector limit: finite and within 2 ulps.
  const Lanes4 g = expm1_stress(Lanes4(699.9, -699.9, 1.0, -1.0));
  EXPECT_LE(ulps(g[0], expm1l(static_cast<long double>(699.9))), 2.0);
  EXPECT_LE(ulps(g[1], expm1l(static_cast<long double>(-699.9))), 2.0);
}

}  // namespace
