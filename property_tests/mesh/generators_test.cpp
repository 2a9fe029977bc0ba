#include <gtest/gtest.h>
#include <incise/core/error.hpp>
#include <incise/mesh/generators.hpp>

#include <map>
#include <set>

namespace incise::mesh {
namespace {

double volume(const MeshData& m, Eigen::Index c) {
  const Vec3 a = m.points.col(m.cells(0, c));
  return (m.points.col(m.cells(1, c)) - a)
             .dot((m.points.col(m.cells(2, c)) - a).cross(m.points.col(m.cells(3, c)) - a)) /
         6.0;
}

// Every interior triangle must be shared by exactly two tetrahedra (conformity); the total
// volume must equal the box volume.
void expect_conforming_box(const MeshData& m, double box_volume) {
  std::map<std::set<Index>, int> faces;
  double total = 0;
  for (Eigen::Index c = 0; c < m.cells.cols(); ++c) {
    const double v = volume(m, c);
    EXPECT_GT(v, 0.0) << "cell " << c;
    total += v;
    for (int skip = 0; skip < 4; ++skip) {
      std::set<Index> f;
      for (int r = 0; r < 4; ++r)
        if (r != skip) f.insert(m.cells(r, c));
      ++faces[f];
    }
  }
  for (const auto& [f, n] : faces) EXPECT_LE(n, 2);
  // Round-off: a sum of n_cells terms each exact to ~1e-16 relative.
  EXPECT_NEAR(total, box_volume, 1e-12 * box_volume);
}

TEST(MakeBox, SixSplitIsConformingAndPositive) {
  const MeshData m = make_box(3, 2, 2, 1.2, 0.2, 0.3, CubeSplit::kSix);
  EXPECT_EQ(m.num_points(), 4 * 3 * 3);
  EXPECT_EQ(m.num_cells(), 3 * 2 * 2 * 6);
  expect_conforming_box(m, 1.2 * 0.2 * 0.3);
}

TEST(MakeBox, FiveSplitIsConformingAndPositive) {
  const MeshData m = make_box(3, 3, 2, 1.0, 1.0, 2.0, CubeSplit::kFive);
  EXPECT_EQ(m.num_cells(), 3 * 3 * 2 * 5);
  expect_conforming_box(m, 2.0);
}

TEST(MakeBox, RejectsBadParameters) {
  EXPECT_THROW(make_box(0, 1, 1, 1, 1, 1), ParameterError);
  EXPECT_THROW(make_box(1, 1, 1, 1, -1, 1), ParameterError);
}

}  // namespace
}  // namespace incise::mesh
