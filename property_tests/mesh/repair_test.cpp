// split_pinched_vertices (repair.hpp): stars that are not face-connected (thesis §7.3) are
// split so that every class gets its own vertex; connected stars are left alone.

#include <gtest/gtest.h>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/repair.hpp>

namespace incise::mesh {
namespace {

TEST(SplitPinched, BowTieTrianglesGetTwoVertices) {
  // Two triangles sharing only vertex 0 (a 2D pinch).
  MeshData m;
  m.dimension = 2;
  m.points.resize(3, 5);
  m.points << 0, 1, 0, -1, 0,  //
      0, 0, 1, 0, -1,          //
      0, 0, 0, 0, 0;
  m.cells.resize(3, 2);
  m.cells << 0, 0,  //
      1, 3,         //
      2, 4;
  m.point_tags = {7, 1, 1, 2, 2};
  const PinchSplit s = split_pinched_vertices(m);
  ASSERT_EQ(s.pinched, std::vector<Index>{0});
  ASSERT_EQ(s.origin, std::vector<Index>{0});
  EXPECT_EQ(s.first_new, 5);
  EXPECT_EQ(m.num_points(), 6);
  EXPECT_EQ(m.cells(0, 0), 0);  // the class of the lowest cell keeps v
  EXPECT_EQ(m.cells(0, 1), 5);
  EXPECT_EQ(m.points.col(5), m.points.col(0));
  EXPECT_EQ(m.point_tags.back(), 7);
}

TEST(SplitPinched, TwoTetrahedraTouchingInAVertexAndTheirFacets) {
  MeshData m;
  m.dimension = 3;
  m.points.resize(3, 7);
  m.points << 0, 1, 0, 0, -1, 0, 0,  //
      0, 0, 1, 0, 0, -1, 0,          //
      0, 0, 0, 1, 0, 0, -1;
  m.cells.resize(4, 2);
  m.cells << 0, 0,  //
      1, 4,         //
      2, 5,         //
      3, 6;
  // Facets through the pinched vertex on each side.
  m.facets.resize(3, 2);
  m.facets << 0, 0,  //
      1, 4,          //
      2, 5;
  const PinchSplit s = split_pinched_vertices(m);
  ASSERT_EQ(s.pinched, std::vector<Index>{0});
  EXPECT_EQ(m.cells(0, 1), 7);
  EXPECT_EQ(m.facets(0, 0), 0);  // on the first tetrahedron: keeps v
  EXPECT_EQ(m.facets(0, 1), 7);  // on the second: the new vertex
}

TEST(SplitPinched, ConnectedStarsAreUnchanged) {
  for (MeshData m : {make_box(3, 2, 2, 1, 1, 1), make_box(2, 2, 2, 1, 1, 1, CubeSplit::kFive),
                     make_rectangle(3, 3, 1, 1, GridDiagonal::kAlternating)}) {
    const MeshData before = m;
    const PinchSplit s = split_pinched_vertices(m);
    EXPECT_TRUE(s.pinched.empty());
    EXPECT_TRUE(m.cells == before.cells);
    EXPECT_EQ(m.num_points(), before.num_points());
  }
}

}  // namespace
}  // namespace incise::mesh
