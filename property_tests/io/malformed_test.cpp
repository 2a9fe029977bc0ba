// Malformed-file tests: every reader reports bad input as ParseError(file, line, "expected ...")
// with the right line and never crashes (issue 2: at least 15 cases).

#include <incise/io/read_mesh.hpp>

#include "io_test_util.hpp"

namespace incise::io {
namespace {

using test::expect_parse_error;
using test::write_temp;

// A valid Gmsh 2.2 file: one tetrahedron (lines numbered in the comments of the tests).
const char* kGmsh22 =
    "$MeshFormat\n"        // 1
    "2.2 0 8\n"            // 2
    "$EndMeshFormat\n"     // 3
    "$Nodes\n"             // 4
    "4\n"                  // 5
    "1 0 0 0\n"            // 6
    "2 1 0 0\n"            // 7
    "3 0 1 0\n"            // 8
    "4 0 0 1\n"            // 9
    "$EndNodes\n"          // 10
    "$Elements\n"          // 11
    "1\n"                  // 12
    "1 4 2 7 7 1 2 3 4\n"  // 13
    "$EndElements\n";      // 14

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto p = s.find(from);
  EXPECT_NE(p, std::string::npos) << from;
  return s.replace(p, from.size(), to);
}

// A valid Medit file: two tetrahedra sharing face (2,3,4), both positive.
const char* kMedit =
    "MeshVersionFormatted 1\n"  // 1
    "Dimension 3\n"             // 2
    "Vertices\n"                // 3
    "5\n"                       // 4
    "0 0 0 1\n"                 // 5
    "1 0 0 1\n"                 // 6
    "0 1 0 1\n"                 // 7
    "0 0 1 1\n"                 // 8
    "1 1 1 2\n"                 // 9
    "Tetrahedra\n"              // 10
    "2\n"                       // 11
    "1 2 3 4 5\n"               // 12
    "2 5 3 4 6\n"               // 13
    "End\n";                    // 14

TEST(Malformed, ValidBaseFilesLoad) {
  const auto g = read_mesh(write_temp("ok.msh", kGmsh22));
  EXPECT_EQ(g.mesh.num_cells(), 1);
  EXPECT_EQ(g.mesh.cell_tags, std::vector<int>{7});
  const auto m = read_mesh(write_temp("ok.mesh", kMedit));
  EXPECT_EQ(m.mesh.num_cells(), 2);
  EXPECT_EQ(m.report.reoriented, 0);
}

TEST(Malformed, GmshTruncatedFile) {
  const std::string s = kGmsh22;
  expect_parse_error(write_temp("trunc.msh", s.substr(0, s.find("3 0 1 0"))), 7,
                     "unexpected end of file: expected node tag");
}

TEST(Malformed, GmshBadNumber) {
  expect_parse_error(write_temp("badnum.msh", replace(kGmsh22, "2 1 0 0", "2 1.0x 0 0")), 7,
                     "bad number: expected x coordinate, got '1.0x'");
}

TEST(Malformed, GmshNaNCoordinate) {
  expect_parse_error(write_temp("nan.msh", replace(kGmsh22, "3 0 1 0", "3 0 nan 0")), 8,
                     "non-finite value: expected a finite y coordinate");
}

TEST(Malformed, GmshInfCoordinate) {
  expect_parse_error(write_temp("inf.msh", replace(kGmsh22, "4 0 0 1", "4 0 0 -inf")), 9,
                     "non-finite value");
  expect_parse_error(write_temp("huge.msh", replace(kGmsh22, "4 0 0 1", "4 0 0 1e400")), 9,
                     "number out of range");
}

TEST(Malformed, GmshNodeIndexOutOfRange) {
  expect_parse_error(write_temp("range.msh", replace(kGmsh22, "1 2 3 4\n", "1 2 3 9\n")), 13,
                     "node index out of range: node tag 9");
}

TEST(Malformed, GmshWrongElementType) {
  expect_parse_error(
      write_temp("hex.msh", replace(kGmsh22, "1 4 2 7 7 1 2 3 4", "1 5 2 7 7 1 2 3 4")), 13,
      "unsupported element type 5");
}

TEST(Malformed, GmshTooManyNodesOnElementLine) {
  expect_parse_error(write_temp("extra.msh", replace(kGmsh22, "1 2 3 4\n", "1 2 3 4 4\n")), 13,
                     "expected end of line");
}

TEST(Malformed, GmshBinaryAndUnknownVersion) {
  expect_parse_error(write_temp("bin.msh", replace(kGmsh22, "2.2 0 8", "2.2 1 8")), 2,
                     "binary .msh is not supported");
  expect_parse_error(write_temp("v3.msh", replace(kGmsh22, "2.2 0 8", "3.0 0 8")), 2,
                     "expected 2.2 or 4.1");
}

TEST(Malformed, GmshDuplicateNodeTag) {
  expect_parse_error(write_temp("dupnode.msh", replace(kGmsh22, "3 0 1 0", "2 0 1 0")), 8,
                     "duplicate node tag");
}

TEST(Malformed, Gmsh41BlockCountMismatchAndTruncation) {
  const std::string g41 =
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"    // 1-3
      "$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n"    // 4-10
      "0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n"   // 11-15
      "$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n"  // 16-19
      "$EndElements\n";                           // 20
  EXPECT_EQ(read_mesh(write_temp("ok41.msh", g41)).mesh.num_cells(), 1);
  expect_parse_error(write_temp("count41.msh", replace(g41, "$Nodes\n1 4 1 4", "$Nodes\n1 5 1 5")),
                     14, "node count mismatch");
  expect_parse_error(write_temp("trunc41.msh", g41.substr(0, g41.find("1 1 2 3 4"))), 18,
                     "unexpected end of file: expected element tag");
}

TEST(Malformed, MeditIndexOutOfRange) {
  expect_parse_error(write_temp("range.mesh", replace(kMedit, "2 5 3 4 6", "2 6 3 4 6")), 13,
                     "expected vertex index (1-based) in [1, 5], got 6");
  expect_parse_error(write_temp("zero.mesh", replace(kMedit, "1 2 3 4 5", "0 2 3 4 5")), 12,
                     "got 0");
}

TEST(Malformed, MeditDuplicateTetrahedron) {
  // Same vertex set, other order (and orientation): reported at the second one's line.
  expect_parse_error(write_temp("dup.mesh", replace(kMedit, "2 5 3 4 6", "2 1 4 3 6")), 13,
                     "duplicate tetrahedron: same vertices as the tetrahedron at line 12");
}

TEST(Malformed, MeditRepeatedVertexInTetrahedron) {
  expect_parse_error(write_temp("rep.mesh", replace(kMedit, "2 5 3 4 6", "2 5 3 5 6")), 13,
                     "degenerate tetrahedron: vertex 5 (1-based) repeated");
}

TEST(Malformed, MeditFlatTetrahedron) {
  // Vertex 5 moved into the plane x + y + z = 1 of face (2,3,4): zero volume.
  expect_parse_error(write_temp("flat.mesh", replace(kMedit, "1 1 1 2", "0.5 0.25 0.25 2")), 13,
                     "degenerate tetrahedron");
}

TEST(Malformed, MeditInvertedTetrahedronAndReorientOption) {
  const std::string path = write_temp("inv.mesh", replace(kMedit, "2 5 3 4 6", "2 5 4 3 6"));
  expect_parse_error(path, 13, "inverted tetrahedron");
  ReadOptions o;
  o.reorient = true;
  const LoadedMesh m = read_mesh(path, o);
  EXPECT_EQ(m.report.reoriented, 1);
  ASSERT_EQ(m.report.notes.size(), 1u);
  EXPECT_NE(m.report.notes[0].find("(line 13)"), std::string::npos) << m.report.notes[0];
}

TEST(Malformed, MeditUnsupportedElementTypeAndUnknownKeyword) {
  expect_parse_error(write_temp("hexa.mesh", replace(kMedit, "End\n", "Hexahedra\n0\nEnd\n")), 14,
                     "unsupported element type 'Hexahedra'");
  expect_parse_error(write_temp("kw.mesh", replace(kMedit, "End\n", "Banana\n0\nEnd\n")), 14,
                     "unknown keyword 'Banana'");
}

TEST(Malformed, MeditTruncatedAndHugeCounts) {
  const std::string s = kMedit;
  expect_parse_error(write_temp("trunc.mesh", s.substr(0, s.find(" 6\nEnd"))), 13,
                     "unexpected end of file: expected reference");
  // A count that does not fit an Index is rejected; a huge one that fits reserves only what
  // the file can hold and then hits the end of the file.
  expect_parse_error(
      write_temp("huge.mesh", replace(kMedit, "Vertices\n5", "Vertices\n99999999999")), 4,
      "value out of range: expected number of vertices");
  expect_parse_error(write_temp("big.mesh", replace(kMedit, "Vertices\n5", "Vertices\n2000000000")),
                     10, "bad number: expected x coordinate, got 'Tetrahedra'");
  expect_parse_error(
      write_temp("bigint.mesh", replace(kMedit, "1 2 3 4 5", "1 2 3 4 99999999999999999999999")),
      12, "integer out of range");
}

TEST(Malformed, TetGenErrors) {
  const std::string node = "5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n";
  const std::string ele = "2 4 0\n1 1 2 3 4\n2 2 5 3 4\n";
  write_temp("tg.node", node);
  const std::string e = write_temp("tg.ele", ele);
  EXPECT_EQ(read_mesh(e).mesh.num_cells(), 2);
  write_temp("tg10.node", node);
  expect_parse_error(write_temp("tg10.ele", "1 10 0\n1 1 2 3 4 5 1 2 3 4 5\n"), 1,
                     "unsupported element type: 10-node tetrahedra");
  write_temp("tgseq.node", replace(node, "3 0 1 0", "7 0 1 0"));
  write_temp("tgseq.ele", ele);
  try {
    (void)read_mesh(test::temp_path("tgseq.ele"));
    ADD_FAILURE() << "no error";
  } catch (const ParseError& err) {
    EXPECT_EQ(err.line(), 4);
    EXPECT_NE(err.file().find("tgseq.node"), std::string::npos);
    EXPECT_NE(err.message().find("expected point number in [3, 3], got 7"), std::string::npos)
        << err.message();
  }
  // Missing partner file.
  const std::string lonely = write_temp("lonely.ele", ele);
  try {
    (void)read_mesh(lonely);
    ADD_FAILURE() << "no error";
  } catch (const ParseError& err) {
    EXPECT_EQ(err.line(), 0);
    EXPECT_NE(err.message().find("cannot open"), std::string::npos);
  }
}

TEST(Malformed, OffErrors) {
  const std::string off = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(read_mesh(write_temp("ok.off", off)).mesh.num_cells(), 1);
  expect_parse_error(write_temp("quad.off", replace(off, "3 0 1 2", "4 0 1 2 0")), 6,
                     "unsupported face with 4 vertices: expected triangles (3)");
  expect_parse_error(write_temp("hdr.off", replace(off, "OFF", "PLY")), 1,
                     "expected OFF, got 'PLY'");
  expect_parse_error(write_temp("idx.off", replace(off, "3 0 1 2", "3 0 1 3")), 6,
                     "expected vertex index (0-based) in [0, 2], got 3");
}

// Issue 18: the OFF reader ignored data after the declared face count (count - 1 dropped a
// triangle, exit 0); now it is refused like the other readers' trailing data.
TEST(Malformed, OffDataAfterTheDeclaredFaces) {
  // The input: a closed tetrahedron surface whose header declares 3 of its 4 faces.
  const std::string tet =
      "OFF\n3 3 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
  expect_parse_error(write_temp("count.off", replace(tet, "3 3 0", "4 3 0")), 10,
                     "unexpected data after the 3 faces the header declares: expected end of "
                     "file, got '3' (is the face count too small?)");
  // Trailing comments and blank lines are no data; a colour after a face is allowed.
  EXPECT_EQ(read_mesh(write_temp("tail.off", replace(tet, "3 3 0", "4 4 0") + "\n# end\n\n"))
                .mesh.num_cells(),
            4);
}

// Issue 18: an inconsistently oriented OFF surface passed the reader and failed later with an
// assertion text naming connectivity.cpp; the reader names the two faces and their edge, and the
// reorient option makes the surface consistent (then the connectivity builds).
TEST(Malformed, InconsistentSurfaceOrientationNamesTheFacesAndReorientFixesIt) {
  const std::string tet =  // face at line 7 flipped relative to its neighbours
      "OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
  const std::string p = write_temp("flip.off", tet);
  expect_parse_error(p, 8,
                     "triangles at lines 7 and 8 traverse their common edge (vertices at lines "
                     "3, 4) in the same direction: the surface is not consistently oriented (the "
                     "reorient option orients each connected part like its first triangle)");
  ReadOptions reorient;
  reorient.reorient = true;
  const LoadedMesh fixed = read_mesh(p, reorient);
  EXPECT_EQ(fixed.report.reoriented, 3);  // oriented like the first triangle (line 7)
  EXPECT_EQ(fixed.mesh.cells.col(0), (Eigen::Vector3i{0, 1, 2}));
  EXPECT_EQ(fixed.mesh.cells.col(1), (Eigen::Vector3i{0, 3, 1}));
  // The 5-vertex Moebius band (triangles (i, i+1, i+2) mod 5) has no consistent orientation.
  const std::string band =
      "OFF\n5 5 0\n1 0 0\n0.3 0.95 0.3\n-0.8 0.6 0.6\n-0.8 -0.6 0.9\n0.3 -0.95 1.2\n"
      "3 0 1 2\n3 1 2 3\n3 2 3 4\n3 3 4 0\n3 4 0 1\n";
  expect_parse_error(write_temp("band.off", band), 12,
                     "triangles at lines 11 and 12 traverse their common edge (vertices at lines "
                     "3, 7) in the same direction: the surface is not orientable",
                     reorient);
}

// Every face of a tetrahedral mesh lies between at most two cells, one on each side; the same
// oriented face twice (overlapping cells) or three cells on a face is refused at the cell's line.
TEST(Malformed, OverlappingAndNonManifoldCells) {
  // Vertex 5 moved below face (2,3,4) (x + y + z < 1), the second cell positively ordered: both
  // cells lie on the vertex-1 side of that face.
  const std::string overlap =
      replace(replace(kMedit, "1 1 1 2", "0.1 0.1 0.1 2"), "2 5 3 4 6", "2 3 5 4 6");
  expect_parse_error(write_temp("overlap.mesh", overlap), 13,
                     "tetrahedra at lines 12 and 13 lie on the same side of their common face "
                     "(vertices at lines 6, 7, 8): they overlap");
  // A third tetrahedron on face (2,3,4).
  std::string three = replace(kMedit, "5\n0 0 0 1", "6\n0 0 0 1");
  three = replace(three, "1 1 1 2\n", "1 1 1 2\n2 2 2 2\n");
  three = replace(three, "2\n1 2 3 4 5\n2 5 3 4 6\n", "3\n1 2 3 4 5\n2 5 3 4 6\n2 6 3 4 6\n");
  expect_parse_error(write_temp("three.mesh", three), 15,
                     "face (vertices at lines 6, 7, 8) shared by 3 tetrahedra (lines 13, 14, 15): "
                     "expected a manifold mesh, each face in at most two tetrahedra");
}

// A scale that makes a coordinate non-finite is refused at the line of that vertex.
TEST(Malformed, ScaleOverflowNamesTheVertexLine) {
  ReadOptions big;
  big.scale = 1e300;
  expect_parse_error(write_temp("scaled.mesh", replace(kMedit, "1 1 1 2", "1e10 1 1 2")), 9,
                     "coordinate 1e+10 times the scale 1e+300 is not finite", big);
}

TEST(Malformed, MissingEmptyAndUnknownFiles) {
  expect_parse_error(write_temp("empty.mesh", ""), 1, "expected MeshVersionFormatted");
  expect_parse_error(write_temp("empty.msh", ""), 1,
                     "unexpected end of file: expected $MeshFormat");
  try {
    (void)read_mesh(test::temp_path("does_not_exist.msh"));
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_NE(e.message().find("cannot open"), std::string::npos);
  }
  try {
    (void)read_mesh(write_temp("mesh.stl", "solid x\n"));
    ADD_FAILURE() << "no error";
  } catch (const ParseError& e) {
    EXPECT_NE(e.message().find("unknown mesh file extension 'stl'"), std::string::npos);
  }
}

TEST(Malformed, GmshElementsBeforeNodesAndNoCells) {
  expect_parse_error(
      write_temp("order.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Elements\n0\n$EndElements\n"),
      4, "$Elements before $Nodes");
  const std::string only_points = replace(kGmsh22, "1 4 2 7 7 1 2 3 4", "1 15 2 7 7 1");
  expect_parse_error(write_temp("nocells.msh", only_points), 0, "no tetrahedra or triangles found");
}

}  // namespace
}  // namespace incise::io
