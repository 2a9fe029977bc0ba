/// Unit and property tests of the 3D needle (needle/needle3d.hpp, thesis §6.4 and §6.9): needle
/// coordinates invert point(); the least-rotation frame transport keeps the frame orthonormal,
/// takes t to the new direction and leaves a translated needle's frame alone; the closest
/// approach of a segment to the shaft agrees with dense sampling; the needle surface rule on
/// small meshes; the area ownership and the per-area friction thresholds f(s)·A/(2πr).

#include <incise/core/error.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/needle/friction.hpp>
#include <incise/needle/needle3d.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using incise::Index;
using incise::Mat3;
using incise::Vec2;
using incise::Vec3;
using incise::needle::NeedlePose3D;

Vec3 random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return Vec3(g(rng), g(rng), g(rng)).normalized();
}

TEST(Needle3D, CoordinatesInvertPointAndFrameIsOrthonormal) {
  INCISE_SEEDED_RNG(rng, 6911);
  std::uniform_real_distribution<double> uni(-0.1, 0.1);
  for (int trial = 0; trial < 50; ++trial) {
    const NeedlePose3D p =
        NeedlePose3D::make(Vec3(uni(rng), uni(rng), uni(rng)), 3.0 * random_unit(rng), 0.1, 1e-3);
    const Mat3 r = p.frame();
    // Orthonormal and right-handed up to rounding of unit vectors.
    EXPECT_LT((r.transpose() * r - Mat3::Identity()).norm(), 1e-14);
    EXPECT_NEAR(r.determinant(), 1.0, 1e-14);
    const Vec3 x(uni(rng), uni(rng), uni(rng));
    const auto c = p.coordinates(x);
    EXPECT_LT((p.point(c) - x).norm(), 1e-15 * 10);
    // s is the distance behind the tip along t: the tip has s = 0, the base s = L.
    EXPECT_NEAR(p.coordinates(p.base()).s, 0.1, 1e-15);
    EXPECT_LT(p.coordinates(p.base()).perp.norm(), 1e-15);
  }
}

TEST(Needle3D, MovedTransportsTheFrameByTheLeastRotation) {
  INCISE_SEEDED_RNG(rng, 6912);
  for (int trial = 0; trial < 50; ++trial) {
    const NeedlePose3D p = NeedlePose3D::make(Vec3::Zero(), random_unit(rng), 0.1, 1e-3);
    // A translation keeps the frame exactly.
    const NeedlePose3D q = p.moved(Vec3(0.01, 0.02, 0.03), p.direction);
    EXPECT_LT((q.frame() - p.frame()).norm(), 1e-15);
    const Vec3 d = random_unit(rng);
    const NeedlePose3D m = p.moved(Vec3::Zero(), d);
    EXPECT_LT((m.tangent() - d).norm(), 1e-14);
    const Mat3 r = m.frame();
    EXPECT_LT((r.transpose() * r - Mat3::Identity()).norm(), 1e-13);
    // The least rotation fixes the common normal t × t': it keeps its frame components.
    const Vec3 axis = p.tangent().cross(d).normalized();
    EXPECT_LT((p.frame().transpose() * axis - m.frame().transpose() * axis).norm(), 1e-12);
  }
  // Opposite direction: a half turn about n1.
  const NeedlePose3D p = NeedlePose3D::make(Vec3::Zero(), Vec3::UnitX(), 0.1, 1e-3);
  const NeedlePose3D m = p.moved(Vec3::Zero(), -Vec3::UnitX());
  EXPECT_EQ(m.normal1(), p.normal1());
  EXPECT_THROW(p.moved(Vec3::Zero(), Vec3::Zero()), incise::ParameterError);
  EXPECT_THROW(NeedlePose3D::make(Vec3::Zero(), Vec3::UnitX(), 0.1, 0.0), incise::ParameterError);
}

TEST(Needle3D, ShaftApproachAgreesWithSampling) {
  INCISE_SEEDED_RNG(rng, 6913);
  std::uniform_real_distribution<double> uni(-0.05, 0.05);
  for (int trial = 0; trial < 200; ++trial) {
    const NeedlePose3D p =
        NeedlePose3D::make(Vec3(uni(rng), uni(rng), uni(rng)), random_unit(rng), 0.05, 1e-3);
    const Vec3 a(uni(rng), uni(rng), uni(rng));
    const Vec3 b = trial % 10 == 0 ? Vec3(a + 0.01 * p.tangent())  // parallel edge
                                   : Vec3(uni(rng), uni(rng), uni(rng));
    const auto r = incise::needle::shaft_approach(p, a, b);
    ASSERT_GE(r.alpha, 0.0);
    ASSERT_LE(r.alpha, 1.0);
    ASSERT_GE(r.s, 0.0);
    ASSERT_LE(r.s, p.length);
    // The reported pair is attained...
    const Vec3 on_edge = a + r.alpha * (b - a);
    const Vec3 on_axis = p.tip - r.s * p.tangent();
    EXPECT_NEAR((on_edge - on_axis).norm(), r.distance, 1e-15);
    // ...and no sampled pair is closer (401² samples: spacing ≤ 0.17 m/400, the sampled minimum
    // exceeds the true one by at most that).
    double best = INFINITY;
    for (int i = 0; i <= 400; ++i)
      for (int j = 0; j <= 400; ++j)
        best = std::min(
            best,
            ((a + (i / 400.0) * (b - a)) - (p.base() + (j / 400.0) * (p.tip - p.base()))).norm());
    EXPECT_LE(r.distance, best + 1e-12);
    EXPECT_GE(r.distance, best - 0.17 / 400);
  }
}

TEST(Needle3D, NeedleSurfaceRule) {
  // Two tetrahedra sharing face (1, 2, 3).
  incise::mesh::CellMatrix tets(4, 2);
  tets << 0, 4, 1, 1, 2, 3, 3, 2;
  // Needle nodes 1, 2, 3: the shared face, seen from two tets with three needle vertices.
  auto f = incise::needle::needle_surface(tets, {0, 1, 1, 1, 0});
  ASSERT_EQ(f.cols(), 1);
  EXPECT_EQ(f.col(0), (Eigen::Matrix<Index, 3, 1>() << 1, 2, 3).finished());
  // All five vertices: both tetrahedra have four needle vertices, so every face has only
  // all-needle tetrahedra around it (inside the needle, or on the body's boundary): none.
  f = incise::needle::needle_surface(tets, {1, 1, 1, 1, 1});
  EXPECT_EQ(f.cols(), 0);
  // One all-needle tetrahedron, the other not: only the shared face, which bounds the needle.
  f = incise::needle::needle_surface(tets, {1, 1, 1, 1, 0});
  ASSERT_EQ(f.cols(), 1);
  EXPECT_EQ(f.col(0), (Eigen::Matrix<Index, 3, 1>() << 1, 2, 3).finished());
  EXPECT_THROW(incise::needle::needle_surface(tets, {1, 1}), incise::UsageError);
}

TEST(Needle3D, NodeAreasPartitionTheSurfaceArea) {
  const auto mesh = incise::mesh::make_box(3, 3, 3, 0.03, 0.03, 0.03);
  std::vector<char> flag(static_cast<std::size_t>(mesh.num_points()), 0);
  std::vector<Index> vertices;
  for (Index v = 0; v < mesh.num_points(); ++v)
    if (std::abs(mesh.points(1, v) - 0.01) < 1e-12 || std::abs(mesh.points(2, v) - 0.01) < 1e-12) {
      flag[static_cast<std::size_t>(v)] = 1;
      vertices.push_back(v);
    }
  const auto faces = incise::needle::needle_surface(mesh.cells, flag);
  ASSERT_GT(faces.cols(), 0);
  const auto area = incise::needle::needle_node_areas(mesh.points, faces, vertices);
  double total = 0.0, sum = 0.0;
  for (Eigen::Index f = 0; f < faces.cols(); ++f)
    total += 0.5 * (mesh.points.col(faces(1, f)) - mesh.points.col(faces(0, f)))
                       .cross(mesh.points.col(faces(2, f)) - mesh.points.col(faces(0, f)))
                       .norm();
  for (const double a : area) sum += a;
  EXPECT_NEAR(sum, total, 1e-15 * faces.cols());  // thirds of the same areas, resummed
  for (const double a : area) EXPECT_GE(a, 0.0);
}

TEST(Needle3D, SurfaceThresholdsArePerAreaDensity) {
  const incise::needle::FrictionProfile f;  // 50 N/m shaft, 150 N/m at the tip, ℓ = 5 mm
  const auto t = f.surface_thresholds({0.0, 0.0025, 0.01, -0.001}, {1e-6, 2e-6, 3e-6, 1e-6}, 1e-3);
  const double c = 1.0 / (2 * M_PI * 1e-3);
  ASSERT_EQ(t.size(), 4u);
  EXPECT_DOUBLE_EQ(t[0], 150.0 * 1e-6 * c);
  EXPECT_DOUBLE_EQ(t[1], 100.0 * 2e-6 * c);  // halfway down the bulge
  EXPECT_DOUBLE_EQ(t[2], 50.0 * 3e-6 * c);
  EXPECT_EQ(t[3], 0.0);  // ahead of the tip
  // A full cylinder of length 1 m owns 2πr·1 m: its threshold is the 2D force per length.
  EXPECT_NEAR(f.surface_thresholds({0.01}, {2 * M_PI * 1e-3}, 1e-3)[0], 50.0, 1e-13);
  EXPECT_THROW(f.surface_thresholds({0.0}, {}, 1e-3), incise::UsageError);
  EXPECT_THROW(f.surface_thresholds({0.0}, {1.0}, 0.0), incise::ParameterError);
}

}  // namespace
