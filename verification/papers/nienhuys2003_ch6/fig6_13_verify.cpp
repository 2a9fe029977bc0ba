/// Thesis Fig. 6.13 (§6.9): "Recursive edge bisection in 3D, with refinement around a single
/// point. On the top 3 levels of refinement, on the bottom 20 levels." Reproduced with
/// mesh::TetBisectionMesh on the 10 cm cube of Fig. 6.14 split into 6 Kuhn tetrahedra
/// (mesh::make_kuhn_cube(1, 0.1)); "k levels" = the tetrahedron containing the point has been
/// bisected k times from its starting tetrahedron (tree depth k). The point lies on the top face
/// so that the graded surface shows the refinement. Writes fig6_13_level{3,20}.vtu (ParaView) and
/// fig6_13_level{3,20}.svg (the top face's boundary triangles, the point in red) next to the
/// binary, and prints the element counts (README.md; the thesis gives none for this figure).

#include <incise/io/write_mesh.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/tet_bisection.hpp>
#include <incise/mesh/validate.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <string>

#ifndef INCISE_CH6_OUTPUT_DIR
#define INCISE_CH6_OUTPUT_DIR "."
#endif

namespace {

using incise::Index;
using incise::Vec3;
using incise::mesh::ElementHandle;
using incise::mesh::TetBisectionMesh;

constexpr double kSide = 0.1;  // m, the cube of Fig. 6.14

/// The top face (z = kSide) boundary triangles of `m` seen from above, the point `x` in red.
void write_top_svg(const std::string& path, const TetBisectionMesh& m, const Vec3& x,
                   const std::string& title) {
  const double px = 4000.0;  // pixels per metre: 400 px for the 0.1 m cube
  std::ofstream out(path);
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"420\" height=\"450\">\n"
      << "<text x=\"10\" y=\"20\" font-size=\"13\">" << title << "</text>\n"
      << "<g transform=\"translate(10,440) scale(1,-1)\">\n"
      << "<g stroke=\"black\" stroke-width=\"0.3\" fill=\"none\">\n";
  for (const auto f : m.connectivity().boundary()) {
    const auto& s = m.connectivity().simplex(f);
    bool top = true;
    for (int i = 0; i < 3; ++i) top = top && m.points()(2, s.vertex(i)) == kSide;
    if (!top) continue;
    out << "<polygon points=\"";
    for (int i = 0; i < 3; ++i)
      out << m.points()(0, s.vertex(i)) * px << "," << m.points()(1, s.vertex(i)) * px << " ";
    out << "\"/>\n";
  }
  out << "</g><circle cx=\"" << x(0) * px << "\" cy=\"" << x(1) * px
      << "\" r=\"2\" fill=\"red\"/></g></svg>\n";
}

TEST(Chapter6, Fig6_13_BisectionAroundAPoint) {
  const Vec3 x(0.0371, 0.0613, kSide);
  std::printf("Fig. 6.13: 10 cm Kuhn cube (6 tetrahedra), point (%.4f, %.4f, %.4f) m\n", x(0), x(1),
              x(2));
  std::printf("%7s %10s %9s %11s %14s %9s\n", "levels", "tetrahedra", "vertices", "bisections",
              "longest at x", "classes");
  for (const int levels : {3, 20}) {
    TetBisectionMesh m(incise::mesh::make_kuhn_cube(1, kSide));
    for (;;) {
      const ElementHandle t = m.locate(x);
      ASSERT_TRUE(t.valid());
      if (m.tree()[static_cast<std::size_t>(m.node_of(t))].depth >= levels) break;
      m.bisect(t);
    }
    incise::mesh::ValidateOptions o;
    o.positions = &m.points();
    const auto rep = incise::mesh::validate(m.connectivity(), o);
    ASSERT_TRUE(rep.ok()) << rep.summary();
    EXPECT_EQ(m.num_forced_bisections(), 0);
    const ElementHandle t = m.locate(x);
    const int depth = m.tree()[static_cast<std::size_t>(m.node_of(t))].depth;
    EXPECT_EQ(depth, levels);  // refine_around stops at the first tet of that depth
    // Maubach on the Kuhn cube of side L: level 3j is the Kuhn tetrahedron scaled by 2^−j
    // (longest edge √3·L·2^−j), level 3j + 2 the level-2 tetrahedron (longest edge L, a cube
    // edge) scaled by 2^−j: for 3 levels √3·L/2, for 20 = 3·6 + 2 levels L·2^−6. Relative
    // 1e-12: a few roundings of dyadic midpoints of 0.1.
    const double expect = levels == 3 ? std::sqrt(3.0) * kSide / 2 : kSide * std::pow(2.0, -6);
    EXPECT_NEAR(m.longest_edge(t), expect, 1e-12 * expect);
    std::set<std::array<long, 6>> classes;
    for (const ElementHandle e : m.connectivity().elements())
      classes.insert(m.similarity_signature(e));
    EXPECT_LE(classes.size(), 3u);  // Maubach: three similarity classes (levels mod 3)
    std::printf("%7d %10d %9d %11ld %14.6g %9zu\n", levels,
                static_cast<int>(m.connectivity().num_elements()),
                static_cast<int>(m.connectivity().num_vertices()), m.num_bisections(),
                m.longest_edge(t), classes.size());
    const std::string base =
        std::string(INCISE_CH6_OUTPUT_DIR) + "/fig6_13_level" + std::to_string(levels);
    incise::io::write_vtu(base + ".vtu", m.to_mesh_data());
    write_top_svg(
        base + ".svg", m, x,
        "Fig. 6.13: " + std::to_string(levels) + " levels around the red point, top face");
  }
}

}  // namespace
