// Quality measures of quality.hpp: closed-form values on reference shapes, invariance under
// similarity transforms, agreement with independent formulas, and the §3.2.3 classification.

#include <gtest/gtest.h>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/quality.hpp>
#include <incise_test/seed.hpp>

#include <cmath>
#include <random>

namespace incise::mesh {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Closed-form values are evaluated in double precision from O(1) inputs.
constexpr double kExact = 1e-13;

struct Tet {
  Vec3 p[4];
};

Tet regular() {
  return {{Vec3(1, 1, 1), Vec3(1, -1, -1), Vec3(-1, -1, 1), Vec3(-1, 1, -1)}};
}

Tet corner() {
  return {{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)}};
}

Tet random_tet(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Tet t;
  for (auto& p : t.p) p = Vec3(n(rng), n(rng), n(rng));
  if (signed_volume(t.p[0], t.p[1], t.p[2], t.p[3]) < 0) std::swap(t.p[2], t.p[3]);
  return t;
}

TEST(Quality, RegularTetrahedronClosedForms) {
  const Tet t = regular();
  // Edge 2√2: volume ℓ³/(6√2) = 8/3.
  EXPECT_NEAR(signed_volume(t.p[0], t.p[1], t.p[2], t.p[3]), 8.0 / 3.0, kExact);
  EXPECT_NEAR(aspect_ratio(t.p[0], t.p[1], t.p[2], t.p[3]), std::sqrt(2.0 / 3.0), kExact);
  EXPECT_NEAR(volume_area_quality(t.p[0], t.p[1], t.p[2], t.p[3]), 1.0, kExact);
  for (double a : dihedral_angles(t.p[0], t.p[1], t.p[2], t.p[3]))
    EXPECT_NEAR(a, std::acos(1.0 / 3.0), kExact);
}

TEST(Quality, CornerTetrahedronDihedralAngles) {
  const Tet t = corner();
  EXPECT_NEAR(signed_volume(t.p[0], t.p[1], t.p[2], t.p[3]), 1.0 / 6.0, kExact);
  const auto a = dihedral_angles(t.p[0], t.p[1], t.p[2], t.p[3]);
  // Edges at the right corner (0,1) (0,2) (0,3) are 90°; the others acos(1/√3).
  for (int e = 0; e < 3; ++e) EXPECT_NEAR(a[e], kPi / 2, kExact);
  for (int e = 3; e < 6; ++e) EXPECT_NEAR(a[e], std::acos(1.0 / std::sqrt(3.0)), kExact);
  // Aspect ratio: min height is the distance of the origin to x+y+z=1, 1/√3; max edge √2.
  EXPECT_NEAR(aspect_ratio(t.p[0], t.p[1], t.p[2], t.p[3]), 1.0 / std::sqrt(6.0), kExact);
}

TEST(Quality, EquilateralTriangleClosedForms) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0.5, std::sqrt(3.0) / 2, 0);
  EXPECT_NEAR(signed_area_xy(a, b, c), std::sqrt(3.0) / 4, kExact);
  EXPECT_NEAR(signed_area_xy(a, c, b), -std::sqrt(3.0) / 4, kExact);
  EXPECT_NEAR(aspect_ratio(a, b, c), std::sqrt(3.0) / 2, kExact);
  EXPECT_NEAR(area_length_quality(a, b, c), 1.0, kExact);
  EXPECT_NEAR(area_length_quality(a, c, b), -1.0, kExact);
  for (double x : triangle_angles(a, b, c)) EXPECT_NEAR(x, kPi / 3, kExact);
}

// Dihedral angles, aspect ratio and Shewchuk's measure against independent formulas on random
// tetrahedra: cos θ_ij = −n_k·n_l with outward unit face normals; heights from the normal.
TEST(Quality, RandomTetrahedraAgreeWithIndependentFormulas) {
  INCISE_SEEDED_RNG(rng, 42);
  for (int trial = 0; trial < 200; ++trial) {
    const Tet t = random_tet(rng);
    auto outward = [&](int k) {
      Vec3 f[3];
      int n = 0;
      for (int r = 0; r < 4; ++r)
        if (r != k) f[n++] = t.p[r];
      Vec3 nrm = (f[1] - f[0]).cross(f[2] - f[0]).normalized();
      if (nrm.dot(t.p[k] - f[0]) > 0) nrm = -nrm;
      return nrm;
    };
    const auto a = dihedral_angles(t.p[0], t.p[1], t.p[2], t.p[3]);
    for (int e = 0; e < 6; ++e) {
      int k = -1, l = -1;
      for (int r = 0; r < 4; ++r)
        if (r != kTetEdges[e][0] && r != kTetEdges[e][1]) (k < 0 ? k : l) = r;
      // acos is ill-conditioned near 0 and π: compare cosines.
      EXPECT_NEAR(std::cos(a[e]), -outward(k).dot(outward(l)), 1e-9);
    }
    double min_h = 1e300, max_e = 0;
    for (int k = 0; k < 4; ++k) {
      const Vec3 q = t.p[k == 0 ? 1 : 0];
      min_h = std::min(min_h, std::abs(outward(k).dot(t.p[k] - q)));
    }
    for (const auto& e : kTetEdges) max_e = std::max(max_e, (t.p[e[0]] - t.p[e[1]]).norm());
    // Random Gaussian tetrahedra can be quite flat: relative agreement to ~1e-9.
    EXPECT_NEAR(aspect_ratio(t.p[0], t.p[1], t.p[2], t.p[3]), min_h / max_e, 1e-9);
    const double q = volume_area_quality(t.p[0], t.p[1], t.p[2], t.p[3]);
    EXPECT_GT(q, 0.0);
    EXPECT_LE(q, 1.0 + kExact);
  }
}

// Similarity invariance: rotation, translation and scaling leave aspect ratio, Shewchuk quality
// and angles unchanged; a reflection flips the signs of volume and Shewchuk quality only.
TEST(Quality, InvariantUnderSimilarityTransforms) {
  INCISE_SEEDED_RNG(rng, 7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Tet t = random_tet(rng);
    const Mat3 rot = Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().matrix();
    const double s = std::exp(n(rng));
    const Vec3 shift(n(rng), n(rng), n(rng));
    Tet u, r;
    for (int i = 0; i < 4; ++i) {
      u.p[i] = s * rot * t.p[i] + shift;
      r.p[i] = Vec3(-t.p[i].x(), t.p[i].y(), t.p[i].z());
    }
    // Round-off after O(1)-conditioned transforms of O(1) coordinates.
    constexpr double kTol = 1e-9;
    EXPECT_NEAR(aspect_ratio(u.p[0], u.p[1], u.p[2], u.p[3]),
                aspect_ratio(t.p[0], t.p[1], t.p[2], t.p[3]), kTol);
    EXPECT_NEAR(volume_area_quality(u.p[0], u.p[1], u.p[2], u.p[3]),
                volume_area_quality(t.p[0], t.p[1], t.p[2], t.p[3]), kTol);
    EXPECT_NEAR(signed_volume(u.p[0], u.p[1], u.p[2], u.p[3]),
                s * s * s * signed_volume(t.p[0], t.p[1], t.p[2], t.p[3]),
                kTol * s * s * s * (1 + std::abs(signed_volume(t.p[0], t.p[1], t.p[2], t.p[3]))));
    EXPECT_NEAR(signed_volume(r.p[0], r.p[1], r.p[2], r.p[3]),
                -signed_volume(t.p[0], t.p[1], t.p[2], t.p[3]), kTol);
    EXPECT_NEAR(volume_area_quality(r.p[0], r.p[1], r.p[2], r.p[3]),
                -volume_area_quality(t.p[0], t.p[1], t.p[2], t.p[3]), kTol);
    const auto a = dihedral_angles(t.p[0], t.p[1], t.p[2], t.p[3]);
    const auto b = dihedral_angles(u.p[0], u.p[1], u.p[2], u.p[3]);
    for (int e = 0; e < 6; ++e) EXPECT_NEAR(a[e], b[e], 1e-7);
  }
}

// §3.2.3 (Fig. 3.8): needle (0 large angles), spindle (1), sliver (2), cap (3).
TEST(Quality, Sec323ClassificationOfDegenerateShapes) {
  const double eps = 1e-4;
  // Needle: one very short edge (a,b), no large dihedral angle.
  const ShapeInfo needle =
      classify_tetrahedron(Vec3(0, 0, 0), Vec3(eps, 0, 0), Vec3(0.5, 1, 0), Vec3(0.5, 0, 1));
  EXPECT_EQ(needle.shape, ShapeClass::kNeedle);
  EXPECT_EQ(needle.num_large_angles, 0);
  // Spindle: c close to the middle of edge (a,b), d off the line: large angle at edge (c,d).
  const ShapeInfo spindle =
      classify_tetrahedron(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, eps, 0), Vec3(0, 0, 1));
  EXPECT_EQ(spindle.shape, ShapeClass::kSpindle);
  EXPECT_TRUE(spindle.large_angle_edge[5]);  // edge (2,3)
  // Sliver: four nearly coplanar points forming a square; large angles at both diagonals.
  const ShapeInfo sliver =
      classify_tetrahedron(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, -1, eps), Vec3(0, 1, eps));
  EXPECT_EQ(sliver.shape, ShapeClass::kSliver);
  EXPECT_TRUE(sliver.large_angle_edge[0]);  // (0,1)
  EXPECT_TRUE(sliver.large_angle_edge[5]);  // (2,3)
  // Cap: d just above the centroid of triangle (a,b,c): large angles at the edges through d.
  const ShapeInfo cap =
      classify_tetrahedron(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, std::sqrt(3.0) / 2, 0),
                           Vec3(0.5, std::sqrt(3.0) / 6, eps));
  EXPECT_EQ(cap.shape, ShapeClass::kCap);
  EXPECT_TRUE(cap.large_angle_edge[2] && cap.large_angle_edge[4] && cap.large_angle_edge[5]);
  // Well-shaped elements are not classified.
  const Tet t = regular();
  EXPECT_EQ(classify_tetrahedron(t.p[0], t.p[1], t.p[2], t.p[3]).shape, ShapeClass::kGood);
  // Thresholds are the §3.3 example's: aspect 0.01, large angle 0.99π.
  const ShapeThresholds th;
  EXPECT_EQ(th.degenerate_aspect_ratio, 0.01);
  EXPECT_NEAR(th.large_angle, 0.99 * kPi, kExact);
  // 2D: needle (short edge) and cap (one large angle).
  EXPECT_EQ(classify_triangle(Vec3(0, 0, 0), Vec3(eps, 0, 0), Vec3(0.5, 1, 0)).shape,
            ShapeClass::kNeedle);
  EXPECT_EQ(classify_triangle(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, eps, 0)).shape,
            ShapeClass::kCap);
  EXPECT_STREQ(to_string(ShapeClass::kSliver), "sliver");
}

TEST(Quality, SummarizeUsesNearestRankPercentiles) {
  std::vector<double> v;
  for (int i = 100; i >= 1; --i) v.push_back(i);
  const Stats s = summarize(v);
  EXPECT_EQ(s.count, 100);
  EXPECT_EQ(s.min, 1);
  EXPECT_EQ(s.p05, 5);
  EXPECT_EQ(s.median, 50);
  EXPECT_EQ(s.p95, 95);
  EXPECT_EQ(s.max, 100);
  EXPECT_DOUBLE_EQ(s.mean, 50.5);
  EXPECT_EQ(summarize({}).count, 0);
}

TEST(Quality, MeshSummaryOfBoxAndInvertedCell) {
  MeshData m = make_box(2, 2, 2, 1.0, 2.0, 3.0, CubeSplit::kSix);
  QualitySummary q = summarize_quality(m);
  EXPECT_EQ(q.num_cells, 48);
  EXPECT_EQ(q.num_inverted, 0);
  // Round-off in a sum of 48 volumes.
  EXPECT_NEAR(q.total_size, 6.0, 1e-13);
  // Unique edges of the 6-split 2×2×2 box: 3·(3·3·2) axis + face diagonals + 8 main diagonals.
  EXPECT_EQ(q.edge_length.count, 54 + 3 * 3 * 2 * 2 + 8);
  std::swap(m.cells(2, 0), m.cells(3, 0));
  q = summarize_quality(m);
  EXPECT_EQ(q.num_inverted, 1);
  EXPECT_LT(q.shewchuk.min, 0.0);
  const auto bb = bounding_box(m.points);
  EXPECT_EQ(bb[0], Vec3(0, 0, 0));
  EXPECT_EQ(bb[1], Vec3(1, 2, 3));
}

}  // namespace
}  // namespace incise::mesh
