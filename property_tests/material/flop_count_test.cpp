/// Unit tests of the counting scalar (core/flop_count.hpp): the charges stated in its header,
/// Eigen fixed-size interoperability, and that counting does not change values.

#include <incise/core/flop_count.hpp>
#include <incise/material/models.hpp>
#include <incise_test/seed.hpp>

#include <cmath>

namespace {

using incise::Counted;
using incise::FlopScope;

TEST(CountedScalar, ChargesPerOperation) {
  const Counted a(1.5), b(2.0);
  {
    FlopScope s;
    Counted c = a + b;
    c = c - a;
    c = c * b;
    c = c / a;
    c += a;
    EXPECT_EQ(s.flops(), 5u);
    EXPECT_DOUBLE_EQ(c.value(), ((1.5 + 2.0 - 1.5) * 2.0) / 1.5 + 1.5);
  }
  {
    FlopScope s;
    const Counted n = -a;   // sign flip: free
    const bool lt = a < b;  // comparison: free
    EXPECT_TRUE(lt);
    EXPECT_EQ(n.value(), -1.5);
    EXPECT_EQ(s.flops(), 0u);
  }
  {
    FlopScope s;
    (void)exp(a);
    EXPECT_EQ(s.flops(), incise::kExpFlops);
  }
  {
    FlopScope s;
    (void)log(a);
    (void)sqrt(a);
    EXPECT_EQ(s.flops(), incise::kLogFlops + incise::kSqrtFlops);
  }
  {
    FlopScope s;
    (void)log1p(a);
    EXPECT_EQ(s.flops(), incise::kLogFlops);
  }
  EXPECT_EQ(incise::kExpFlops, 50u);  // thesis §4.2: "approximately 50 flops"
}

TEST(CountedScalar, NestedScopesRestoreOuterCount) {
  FlopScope outer;
  Counted x(1.0);
  x = x + 1.0;
  {
    FlopScope inner;
    x = x * 2.0;
    EXPECT_EQ(inner.flops(), 1u);
  }
  EXPECT_EQ(outer.flops(), 2u);
}

TEST(CountedScalar, EigenFixedSizeProductsCountAndMatchDouble) {
  INCISE_SEEDED_RNG(rng, 11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Matrix3d a, b;
  for (int i = 0; i < 9; ++i) {
    a(i) = u(rng);
    b(i) = u(rng);
  }
  const Eigen::Matrix<Counted, 3, 3> ac = a.cast<Counted>(), bc = b.cast<Counted>();
  FlopScope s;
  const Eigen::Matrix<Counted, 3, 3> pc = ac * bc;
  EXPECT_EQ(s.flops(), 45u);  // 27 × and 18 +
  const Eigen::Matrix3d p = a * b;
  for (int i = 0; i < 9; ++i)
    EXPECT_NEAR(pc(i).value(), p(i), 1e-15);  // same ops, same order up to fma
  FlopScope s2;
  const Counted t = ac.trace();
  EXPECT_EQ(s2.flops(), 2u);
  EXPECT_NEAR(t.value(), a.trace(), 1e-15);
  const Eigen::Matrix<Counted, 3, 3> scaled = ac * 2.0;  // mixed Counted × double
  EXPECT_EQ(scaled(0, 0).value(), 2.0 * a(0, 0));
}

TEST(CountedScalar, MaterialKernelsGiveSameValuesAsDouble) {
  // Counting must not change arithmetic: the neo-Hookean stress in both scalar types.
  const incise::material::Lame l{2.0, 1.0, 0.0};
  Eigen::Matrix3d c;
  c << 1.2, 0.1, 0.05, 0.1, 0.9, -0.02, 0.05, -0.02, 1.1;
  incise::material::MaterialState<double> sd;
  incise::material::MaterialState<Counted> sc;
  using incise::material::NeoHookean;
  using incise::material::strain_from_c;
  Eigen::Matrix3d s_d;
  Eigen::Matrix<Counted, 3, 3> s_c;
  NeoHookean::stress(l, strain_from_c<NeoHookean>(c), sd, s_d);
  NeoHookean::stress(l, strain_from_c<NeoHookean>(Eigen::Matrix<Counted, 3, 3>(c.cast<Counted>())),
                     sc, s_c);
  for (int i = 0; i < 9; ++i) EXPECT_EQ(s_c(i).value(), s_d(i));
}

}  // namespace
