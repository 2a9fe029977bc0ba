// Exact-sign predicates of delaunay/predicates.hpp (thesis §5.2.1 empty-circle criterion):
// against exact integer arithmetic on near-degenerate point sets (collinear and cocircular
// lattice points, perturbed by one unit, far from the origin), and against the known answer of
// points one ulp apart near a line (where plain double evaluation is wrong).
#include <incise/delaunay/predicates.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <array>
#include <random>
#include <vector>

namespace incise::delaunay {
namespace {

__extension__ typedef __int128 I128;  // GCC/Clang extension (exact reference arithmetic)

int sign(I128 v) {
  return v > 0 ? 1 : (v < 0 ? -1 : 0);
}

/// orient2d on integer coordinates (|x| < 2⁵², so differences < 2⁵³, products < 2¹⁰⁶).
int orient_ref(const std::array<long long, 2>& a, const std::array<long long, 2>& b,
               const std::array<long long, 2>& c) {
  const I128 l = I128(a[0] - c[0]) * I128(b[1] - c[1]);
  const I128 r = I128(a[1] - c[1]) * I128(b[0] - c[0]);
  return sign(l - r);
}

/// incircle on integer coordinates whose differences are < 2²⁵ (terms < 2¹⁰³).
int incircle_ref(const std::array<long long, 2>& a, const std::array<long long, 2>& b,
                 const std::array<long long, 2>& c, const std::array<long long, 2>& d) {
  const I128 adx = a[0] - d[0], ady = a[1] - d[1], bdx = b[0] - d[0], bdy = b[1] - d[1];
  const I128 cdx = c[0] - d[0], cdy = c[1] - d[1];
  const I128 al = adx * adx + ady * ady, bl = bdx * bdx + bdy * bdy, cl = cdx * cdx + cdy * cdy;
  return sign(al * (bdx * cdy - cdx * bdy) + bl * (cdx * ady - adx * cdy) +
              cl * (adx * bdy - bdx * ady));
}

Vec2 v(const std::array<long long, 2>& p, double unit) {
  return Vec2(static_cast<double>(p[0]) * unit, static_cast<double>(p[1]) * unit);
}

/// The lattice points of the circle x² + y² = 5⁸ (r = 625: 20 points in each octant family).
std::vector<std::array<long long, 2>> circle_points() {
  std::vector<std::array<long long, 2>> out;
  const long long r = 625;
  for (long long x = -r; x <= r; ++x)
    for (long long y = -r; y <= r; ++y)
      if (x * x + y * y == r * r) out.push_back({x, y});
  return out;
}

TEST(DelaunayPredicates, OrientMatchesExactIntegersOnNearCollinearPoints) {
  INCISE_SEEDED_RNG(rng, 5001);
  // Points c = a + k (b − a) + δ, δ ∈ {−1, 0, 1}², |b − a| < 2²⁶, |k| < 2²⁰, far from the
  // origin (offset up to 2⁵⁰): the products reach 2⁹² and double evaluation cannot resolve δ;
  // scaled by 2⁻³⁰ as well (a power of two, so the scaled coordinates are exact).
  std::uniform_int_distribution<long long> off(-(1LL << 50), 1LL << 50),
      dir(-(1LL << 26), 1LL << 26), k(-(1LL << 20), 1LL << 20), d(-1, 1);
  int counted[3] = {0, 0, 0}, filtered_wrong = 0;
  for (int i = 0; i < incise::test::scaled(20000); ++i) {
    const std::array<long long, 2> a{off(rng), off(rng)};
    const std::array<long long, 2> step{dir(rng), dir(rng)};
    const long long kk = k(rng);
    const std::array<long long, 2> b{a[0] + step[0], a[1] + step[1]};
    const std::array<long long, 2> c{a[0] + kk * step[0] + d(rng), a[1] + kk * step[1] + d(rng)};
    const int ref = orient_ref(a, b, c);
    ++counted[ref + 1];
    for (const double unit : {1.0, 0x1p-30}) {
      const Vec2 pa = v(a, unit), pb = v(b, unit), pc = v(c, unit);
      ASSERT_EQ(orient2d(pa, pb, pc), ref) << "case " << i;
      ASSERT_EQ(orient2d_exact(pa, pb, pc), ref) << "case " << i;
      // Permutations: cyclic keeps the sign, a swap negates it.
      ASSERT_EQ(orient2d(pb, pc, pa), ref);
      ASSERT_EQ(orient2d(pb, pa, pc), -ref);
      const double naive = (pb - pa).x() * (pc - pa).y() - (pb - pa).y() * (pc - pa).x();
      if ((naive > 0) - (naive < 0) != ref) ++filtered_wrong;
    }
  }
  // Every sign occurs (collinear triples included), and naive double evaluation gets some of
  // them wrong: the test exercises the exact path.
  EXPECT_GT(counted[0], 0);
  EXPECT_GT(counted[1], 0);
  EXPECT_GT(counted[2], 0);
  EXPECT_GT(filtered_wrong, 0);
}

TEST(DelaunayPredicates, IncircleMatchesExactIntegersOnCocircularLatticePoints) {
  INCISE_SEEDED_RNG(rng, 5002);
  const auto circle = circle_points();
  ASSERT_GE(circle.size(), 16u);
  // Three lattice points of the circle scaled by m = 16 383 (still cocircular; differences up
  // to 2²⁴·³, so the determinant's terms reach 2⁹⁹ and double products round), ordered
  // counter-clockwise; a fourth on the circle or moved by one unit; everything translated by up
  // to 2²² and also scaled by 2⁻²⁰ (a power of two: exact).
  std::uniform_int_distribution<size_t> pick(0, circle.size() - 1);
  std::uniform_int_distribution<long long> off(-(1LL << 22), 1LL << 22), d(-1, 1);
  int counted[3] = {0, 0, 0}, naive_wrong = 0;
  for (int i = 0; i < incise::test::scaled(20000); ++i) {
    const std::array<long long, 2> o{off(rng), off(rng)};
    auto at = [&](size_t j, long long dx, long long dy) {
      constexpr long long m = 16383;
      return std::array<long long, 2>{m * circle[j][0] + o[0] + dx, m * circle[j][1] + o[1] + dy};
    };
    std::array<long long, 2> a = at(pick(rng), 0, 0), b = at(pick(rng), 0, 0),
                             c = at(pick(rng), 0, 0);
    const int orient = orient_ref(a, b, c);
    if (orient == 0) continue;  // repeated point
    if (orient < 0) std::swap(b, c);
    const std::array<long long, 2> dd = at(pick(rng), d(rng), d(rng));
    const int ref = incircle_ref(a, b, c, dd);
    ++counted[ref + 1];
    for (const double unit : {1.0, 0x1p-20}) {
      const Vec2 pa = v(a, unit), pb = v(b, unit), pc = v(c, unit), pd = v(dd, unit);
      ASSERT_EQ(incircle(pa, pb, pc, pd), ref) << "case " << i;
      ASSERT_EQ(incircle_exact(pa, pb, pc, pd), ref) << "case " << i;
      ASSERT_EQ(incircle(pb, pc, pa, pd), ref);   // cyclic: same circle, same orientation
      ASSERT_EQ(incircle(pb, pa, pc, pd), -ref);  // clockwise: the sign flips
      const Vec2 ad = pa - pd, bd = pb - pd, cd = pc - pd;
      const double naive = ad.squaredNorm() * (bd.x() * cd.y() - cd.x() * bd.y()) +
                           bd.squaredNorm() * (cd.x() * ad.y() - ad.x() * cd.y()) +
                           cd.squaredNorm() * (ad.x() * bd.y() - bd.x() * ad.y());
      if ((naive > 0) - (naive < 0) != ref) ++naive_wrong;
    }
  }
  EXPECT_GT(counted[0], 0);
  EXPECT_GT(counted[1], 0);  // exactly cocircular quadruples
  EXPECT_GT(counted[2], 0);
  EXPECT_GT(naive_wrong, 0);  // the exact path is needed
}

TEST(DelaunayPredicates, PointsOneUlpApartNearTheDiagonalGetTheExactSide) {
  // p = (0.5 + x·2⁻⁵³, 0.5 + y·2⁻⁵³) against b = (12, 12), c = (24, 24) on the line y = x:
  // orient2d(b, c, p) = 12 (p_y − p_x) exactly, so its sign is sign(y − x) (Shewchuk's
  // classic failure picture for naive evaluation).
  const Vec2 b(12, 12), c(24, 24);
  int naive_wrong = 0;
  for (int x = 0; x < 256; ++x) {
    for (int y = 0; y < 256; ++y) {
      const Vec2 p(0.5 + x * 0x1p-53, 0.5 + y * 0x1p-53);
      const int want = (y > x) - (y < x);
      ASSERT_EQ(orient2d(b, c, p), want) << x << ", " << y;
      ASSERT_EQ(orient2d(p, b, c), want) << x << ", " << y;
      const double naive = (c - b).x() * (p - b).y() - (c - b).y() * (p - b).x();
      if ((naive > 0) - (naive < 0) != want) ++naive_wrong;
    }
  }
  EXPECT_GT(naive_wrong, 1000);
}

}  // namespace
}  // namespace incise::delaunay
