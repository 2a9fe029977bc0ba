// Unit tests of the canonical oriented simplex (thesis §7.1–7.2).
#include <gtest/gtest.h>
#include <incise/core/error.hpp>
#include <incise/mesh/simplex.hpp>
#include <incise_test/seed.hpp>

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <unordered_set>

namespace incise::mesh {
namespace {

// Sign of the permutation sorting `seq` (brute force: count inversions).
int permutation_sign(std::vector<Index> seq) {
  int inv = 0;
  for (std::size_t i = 0; i < seq.size(); ++i)
    for (std::size_t j = i + 1; j < seq.size(); ++j) inv += seq[i] > seq[j] ? 1 : 0;
  return inv % 2 == 0 ? 1 : -1;
}

TEST(Simplex, CanonicalFormCountsSwaps_Sec72) {
  const Simplex s({5, 2, 9});
  EXPECT_EQ(s.count(), 3);
  EXPECT_EQ(s.dimension(), 2);
  EXPECT_EQ(s.vertex(0), 2);
  EXPECT_EQ(s.vertex(1), 5);
  EXPECT_EQ(s.vertex(2), 9);
  EXPECT_EQ(s.sign(), -1);  // (5,2,9) → (2,5,9): one swap
  EXPECT_EQ(s.index(9), 2);
  EXPECT_EQ(s.index(7), -1);
  EXPECT_EQ(Simplex({2, 5, 9}), Simplex({9, 2, 5}));  // even permutation: same simplex
  EXPECT_EQ(Simplex({2, 5, 9}).mate(), Simplex({5, 2, 9}));
  EXPECT_EQ(s.to_string(), "-<2,5,9>");
}

TEST(Simplex, EveryPermutationHasTheRightSign) {
  std::vector<Index> seq{3, 8, 1, 6};
  std::sort(seq.begin(), seq.end());
  do {
    const Simplex s(seq.data(), 4, +1);
    EXPECT_EQ(s.sign(), permutation_sign(seq));
    const Simplex n(seq.data(), 4, -1);
    EXPECT_EQ(n, s.mate());
  } while (std::next_permutation(seq.begin(), seq.end()));
}

TEST(Simplex, RejectsRepeatedVerticesAndBadSizes) {
  EXPECT_THROW(Simplex({1, 2, 1}), UsageError);
  EXPECT_THROW(Simplex({1, 2, 3, 4, 5}), UsageError);
  EXPECT_THROW(Simplex({-1, 2}), UsageError);
  EXPECT_THROW(Simplex({1, 2}, 0), UsageError);
  EXPECT_THROW(Simplex({1, 2, 3}).substituted(1, 3), UsageError);
}

// subn(j) = p(−1)^j ⟨a0..âj..ak⟩ and the boundary of the boundary vanishes: every
// (k−2)-simplex appears in the sum of sub-sub-simplices once with each sign (§7.1).
TEST(Simplex, SubnFollowsBoundaryOperator_Sec71) {
  const Simplex t({0, 1, 2, 3});
  EXPECT_EQ(t.subn(0), Simplex({1, 2, 3}));
  EXPECT_EQ(t.subn(1), Simplex({0, 2, 3}, -1));
  EXPECT_EQ(t.subn(2), Simplex({0, 1, 3}));
  EXPECT_EQ(t.subn(3), Simplex({0, 1, 2}, -1));
  EXPECT_EQ(t.subv(2), t.subn(2));
  for (const Simplex& s : {Simplex({4, 0, 7, 2}), Simplex({4, 7, 2}), Simplex({3, 9, 1, 2}, -1)}) {
    std::map<std::vector<Index>, int> sum;
    for (int i = 0; i < s.count(); ++i)
      for (int j = 0; j < s.count() - 1; ++j) {
        const Simplex r = s.subn(i).subn(j);
        std::vector<Index> key(r.vertices().begin(), r.vertices().begin() + r.count());
        sum[key] += r.sign();
      }
    for (const auto& kv : sum) EXPECT_EQ(kv.second, 0) << s;
  }
}

// Faces of a positively oriented tetrahedron, in the order of (7.1), have outward normals.
TEST(Simplex, FacesOfPositiveTetrahedronPointOutward_Eq71) {
  const std::array<Vec3, 4> x{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)};
  const Vec3 centroid = (x[0] + x[1] + x[2] + x[3]) / 4;
  // Try every labelling: vertex number = position in x, sequence an arbitrary permutation.
  std::vector<Index> seq{0, 1, 2, 3};
  do {
    const Vec3 a = x[seq[0]];
    const double vol = (x[seq[1]] - a).dot((x[seq[2]] - a).cross(x[seq[3]] - a));
    const Simplex t(seq.data(), 4, vol > 0 ? 1 : -1);  // positively oriented simplex
    for (int i = 0; i < 4; ++i) {
      Simplex f = t.subn(i);
      std::array<Index, 3> v{f.vertex(0), f.vertex(1), f.vertex(2)};
      if (f.sign() < 0) std::swap(v[0], v[1]);
      const Vec3 n = (x[v[1]] - x[v[0]]).cross(x[v[2]] - x[v[0]]);
      EXPECT_GT(n.dot(x[v[0]] - centroid), 0.0) << t << " face " << i;
    }
  } while (std::next_permutation(seq.begin(), seq.end()));
}

TEST(Simplex, SupIsInverseOfSubv) {
  INCISE_SEEDED_RNG(rng, 71);
  std::uniform_int_distribution<Index> vert(0, 20);
  for (int trial = 0; trial < 500; ++trial) {
    std::set<Index> vs;
    const int k = 1 + static_cast<int>(rng() % 3);
    while (static_cast<int>(vs.size()) < k + 1) vs.insert(vert(rng));
    std::vector<Index> seq(vs.begin(), vs.end());
    std::shuffle(seq.begin(), seq.end(), rng);
    const Index v = seq.back();
    seq.pop_back();
    const Simplex s(seq.data(), k, (rng() % 2) ? 1 : -1);
    const Simplex up = s.sup(v);
    EXPECT_EQ(up.count(), k + 1);
    EXPECT_EQ(up.subv(v), s);
    // substitution is sup/subv with another apex: ⟨v, σ⟩[v := w] = ⟨w, σ⟩
    EXPECT_EQ(up.substituted(v, 100), s.sup(100));
  }
}

TEST(Simplex, ZeroSimplexHasTwoOrientations) {
  const Simplex e({3, 7});
  EXPECT_EQ(e.subn(0), Simplex({7}));
  EXPECT_EQ(e.subn(1), Simplex({3}, -1));
  EXPECT_NE(Simplex({3}), Simplex({3}, -1));
  EXPECT_EQ(Simplex({3}).sup(1), Simplex({1, 3}));  // p⟨v, a0⟩
}

TEST(Simplex, OrderingIsStrictTotalAndMatesAdjacent) {
  std::vector<Simplex> all;
  for (Index a = 0; a < 4; ++a)
    for (Index b = a + 1; b < 5; ++b)
      for (int s : {1, -1}) all.push_back(Simplex({b, a}, s));
  std::sort(all.begin(), all.end());
  for (std::size_t i = 1; i < all.size(); ++i) {
    EXPECT_TRUE(all[i - 1] < all[i]);
    EXPECT_FALSE(all[i] < all[i - 1]);
  }
  for (std::size_t i = 0; i < all.size(); i += 2) EXPECT_EQ(all[i].mate(), all[i + 1]);
  std::unordered_set<Simplex> set(all.begin(), all.end());
  EXPECT_EQ(set.size(), all.size());
  EXPECT_EQ(set.count(Simplex({0, 1})), 1u);
}

}  // namespace
}  // namespace incise::mesh
