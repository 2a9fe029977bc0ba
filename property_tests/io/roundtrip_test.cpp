// Round trips (write with the io writers, read back, compare exactly: doubles are written in
// shortest round-trip form) and hand-written files exercising each reader's optional syntax.

#include <incise/io/read_mesh.hpp>
#include <incise/io/write_mesh.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/quality.hpp>
#include <incise_test/seed.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>

#include "io_test_util.hpp"

namespace incise::io {
namespace {

using mesh::MeshData;
using test::temp_path;
using test::write_temp;

// Box with irrational-ish coordinates (random perturbation), cell tags and tagged boundary
// facets: exercises exact double round trip and tag handling.
MeshData tagged_box() {
  INCISE_SEEDED_RNG(rng, 11);
  MeshData m = mesh::make_box(3, 2, 2, 0.3, 0.2, 0.25);
  std::uniform_real_distribution<double> u(-0.01, 0.01);
  for (Index i = 0; i < m.num_points(); ++i) m.points.col(i) += Vec3(u(rng), u(rng), u(rng)) * 0.1;
  for (Index c = 0; c < m.num_cells(); ++c) m.cell_tags.push_back(1 + c % 3);
  // Boundary facets: faces of cells that appear once.
  std::map<std::array<Index, 3>, std::pair<int, std::array<Index, 3>>> faces;
  for (Index c = 0; c < m.num_cells(); ++c)
    for (int skip = 0; skip < 4; ++skip) {
      std::array<Index, 3> f{}, key{};
      int n = 0;
      for (int r = 0; r < 4; ++r)
        if (r != skip) f[n++] = m.cells(r, c);
      key = f;
      std::sort(key.begin(), key.end());
      auto& e = faces[key];
      ++e.first;
      e.second = f;
    }
  std::vector<std::array<Index, 3>> boundary;
  for (const auto& [k, e] : faces)
    if (e.first == 1) boundary.push_back(e.second);
  m.facets.resize(3, static_cast<Eigen::Index>(boundary.size()));
  for (std::size_t f = 0; f < boundary.size(); ++f) {
    for (int r = 0; r < 3; ++r) m.facets(r, static_cast<Eigen::Index>(f)) = boundary[f][r];
    m.facet_tags.push_back(10 + static_cast<int>(f % 2));
  }
  return m;
}

// Exact equality of points and cells (cells in the same order; facets as a multiset per tag).
void expect_same(const MeshData& a, const MeshData& b, bool tags, bool facets) {
  ASSERT_EQ(a.dimension, b.dimension);
  ASSERT_EQ(a.num_points(), b.num_points());
  ASSERT_EQ(a.num_cells(), b.num_cells());
  EXPECT_TRUE(a.points == b.points);  // exact: shortest round-trip formatting
  EXPECT_TRUE(a.cells == b.cells);
  if (tags) {
    EXPECT_EQ(a.cell_tags, b.cell_tags);
  }
  if (facets) {
    auto collect = [](const MeshData& m) {
      std::vector<std::pair<int, std::array<Index, 3>>> v;
      for (Eigen::Index f = 0; f < m.facets.cols(); ++f)
        v.push_back({m.facet_tags.empty() ? 0 : m.facet_tags[f],
                     {m.facets(0, f), m.facets(1, f), m.facets(2, f)}});
      std::sort(v.begin(), v.end());
      return v;
    };
    EXPECT_EQ(collect(a), collect(b));
  }
}

TEST(RoundTrip, GmshBothVersionsMeditAndTetGen) {
  const MeshData m = tagged_box();
  for (int version : {22, 41}) {
    const std::string p = temp_path("rt" + std::to_string(version) + ".msh");
    write_gmsh(p, m, version);
    const LoadedMesh r = read_mesh(p);
    EXPECT_EQ(r.report.format, version == 22 ? "gmsh 2.2" : "gmsh 4.1");
    expect_same(m, r.mesh, true, true);
    EXPECT_EQ(r.report.cell_labels.size(), 3u);
    EXPECT_EQ(r.report.facet_labels.size(), 2u);
  }
  const std::string pm = temp_path("rt.mesh");
  write_medit(pm, m);
  expect_same(m, read_mesh(pm).mesh, true, true);
  const std::string base = temp_path("rt_tg");
  write_tetgen(base, m);
  expect_same(m, read_mesh(base + ".node").mesh, true, false);
}

TEST(RoundTrip, TriangleMeshesInEveryFormat) {
  MeshData m = mesh::make_rectangle(4, 3, 1.0 / 3.0, 0.7, mesh::GridDiagonal::kAlternating);
  for (Index c = 0; c < m.num_cells(); ++c) m.cell_tags.push_back(c % 2 == 0 ? 5 : 6);
  const std::string p22 = temp_path("tri22.msh"), p41 = temp_path("tri41.msh");
  write_gmsh(p22, m, 22);
  write_gmsh(p41, m, 41);
  expect_same(m, read_mesh(p22).mesh, true, false);
  expect_same(m, read_mesh(p41).mesh, true, false);
  const std::string pm3 = temp_path("tri3.mesh"), pm2 = temp_path("tri2.mesh");
  write_medit(pm3, m);
  write_medit(pm2, m, true);
  expect_same(m, read_mesh(pm3).mesh, true, false);
  expect_same(m, read_mesh(pm2).mesh, true, false);
  const std::string po = temp_path("tri.off");
  write_off(po, m);
  const LoadedMesh r = read_mesh(po);
  expect_same(m, r.mesh, false, false);
  EXPECT_FALSE(r.report.surface);  // z = 0 plane
}

// Parses a VTU DataArray by name (or the unnamed Points array) back into numbers.
std::vector<double> vtu_array(const std::string& text, const std::string& name) {
  const auto p = name.empty() ? text.find("<DataArray", text.find("<Points>"))
                              : text.find("Name=\"" + name + "\"");
  if (p == std::string::npos) return {};
  const auto b = text.find('>', p) + 1;
  const auto e = text.find("</DataArray>", b);
  std::istringstream in(text.substr(b, e - b));
  std::vector<double> v;
  for (double x; in >> x;) v.push_back(x);
  return v;
}

TEST(RoundTrip, VtuPointAndCellDataParseBack) {
  const MeshData m = tagged_box();
  DataArray disp{"displacement", 3, {}};
  for (Index i = 0; i < m.num_points(); ++i)
    for (int c = 0; c < 3; ++c) disp.values.push_back(std::sqrt(2.0) * i + c / 7.0);
  const mesh::CellQuality q = mesh::cell_quality(m);
  const DataArray quality{"aspect_ratio", 1, q.aspect_ratio};
  const std::string p = temp_path("rt.vtu");
  write_vtu(p, m, {disp}, {quality}, VtuEncoding::kAscii);
  std::ifstream in(p);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("NumberOfPoints=\"" + std::to_string(m.num_points()) + "\""),
            std::string::npos);
  EXPECT_EQ(vtu_array(text, "displacement"), disp.values);
  EXPECT_EQ(vtu_array(text, "aspect_ratio"), quality.values);
  const auto pts = vtu_array(text, "");
  ASSERT_EQ(pts.size(), 3u * m.num_points());
  for (Index i = 0; i < m.num_points(); ++i)
    for (int c = 0; c < 3; ++c) EXPECT_EQ(pts[3 * i + c], m.points(c, i));
  const auto conn = vtu_array(text, "connectivity");
  ASSERT_EQ(conn.size(), 4u * m.num_cells());
  for (Index c = 0; c < m.num_cells(); ++c)
    for (int r = 0; r < 4; ++r) EXPECT_EQ(conn[4 * c + r], m.cells(r, c));
  const auto offsets = vtu_array(text, "offsets");
  EXPECT_EQ(offsets.back(), 4.0 * m.num_cells());
  const auto types = vtu_array(text, "types");
  EXPECT_TRUE(std::all_of(types.begin(), types.end(), [](double t) { return t == 10; }));
  const auto tags = vtu_array(text, "tag");
  ASSERT_EQ(tags.size(), m.cell_tags.size());
  EXPECT_EQ(tags[4], m.cell_tags[4]);
  // Wrong array length is misuse.
  EXPECT_THROW(write_vtu(p, m, {DataArray{"bad", 2, {1.0}}}), UsageError);
}

// Both encodings read back exactly with read_vtu: points, cells, tags, Float64/Int32/UInt8
// arrays. 16³ = 4096 points make the 1-component Float64 array exactly one 32768-byte block
// (header "last block size" 0) and the 3-component one 1.5 blocks (a partial last block).
TEST(RoundTrip, VtuBinaryAndAsciiReadBackExactly) {
  MeshData m = mesh::make_box(15, 15, 15, 1.0, 1.0, 1.0, mesh::CubeSplit::kSix);
  ASSERT_EQ(m.num_points(), 4096);
  m.cell_tags.assign(static_cast<std::size_t>(m.num_cells()), 0);
  m.point_tags.assign(static_cast<std::size_t>(m.num_points()), 0);
  for (Index c = 0; c < m.num_cells(); ++c) m.cell_tags[c] = static_cast<int>(c % 5) - 2;
  for (Index i = 0; i < m.num_points(); ++i) m.point_tags[i] = static_cast<int>(i % 3);
  DataArray disp{"displacement", 3, {}};
  for (Index i = 0; i < m.num_points(); ++i)
    for (int c = 0; c < 3; ++c) disp.values.push_back(std::sqrt(2.0) * i + c / 7.0 - 1e-300);
  DataArray one{"one_block", 1, std::vector<double>(4096)};
  for (std::size_t i = 0; i < one.values.size(); ++i) one.values[i] = 1.0 / (1.0 + i);
  DataArray marker{"marker", 1, {}, DataArray::Type::kUInt8};
  for (Index i = 0; i < m.num_points(); ++i) marker.values.push_back(i % 2);
  DataArray ints{"ints", 2, {}, DataArray::Type::kInt32};
  for (Index c = 0; c < m.num_cells(); ++c) {
    ints.values.push_back(-static_cast<double>(c));
    ints.values.push_back(2147483647.0);
  }
  std::uintmax_t size[2] = {0, 0};
  for (VtuEncoding e : {VtuEncoding::kBinaryZlib, VtuEncoding::kAscii}) {
    SCOPED_TRACE(to_string(e));
    const std::string p = temp_path(std::string("rt_") + to_string(e) + ".vtu");
    write_vtu(p, m, {disp, one, marker}, {ints}, e);
    size[e == VtuEncoding::kAscii] = std::filesystem::file_size(p);
    const VtuContents r = read_vtu(p);
    EXPECT_EQ(r.mesh.dimension, 3);
    EXPECT_TRUE(r.mesh.points == m.points);
    EXPECT_TRUE(r.mesh.cells == m.cells);
    EXPECT_EQ(r.mesh.cell_tags, m.cell_tags);
    EXPECT_EQ(r.mesh.point_tags, m.point_tags);
    ASSERT_EQ(r.point_data.size(), 3u);
    ASSERT_EQ(r.cell_data.size(), 1u);
    for (const DataArray* want : {&disp, &one, &marker}) {
      const DataArray* got = VtuContents::find(r.point_data, want->name);
      ASSERT_NE(got, nullptr) << want->name;
      EXPECT_EQ(got->values, want->values) << want->name;
      EXPECT_EQ(got->components, want->components) << want->name;
      EXPECT_EQ(got->type, want->type) << want->name;
    }
    EXPECT_EQ(r.cell_data[0].values, ints.values);
    EXPECT_EQ(r.cell_data[0].type, DataArray::Type::kInt32);
  }
  // Compression pays on these arrays (measured ≈ 3×; asserted only "smaller").
  EXPECT_LT(size[0], size[1]);
  // Integer arrays refuse values outside their type.
  EXPECT_THROW(
      write_vtu(temp_path("bad.vtu"), m,
                {DataArray{"m", 1, std::vector<double>(4096, 256.0), DataArray::Type::kUInt8}}),
      UsageError);
  EXPECT_THROW(
      write_vtu(temp_path("bad.vtu"), m,
                {DataArray{"m", 1, std::vector<double>(4096, 0.5), DataArray::Type::kInt32}}),
      UsageError);
}

// The mesh-check arrays are named for what they hold (issue 20): volume or area, dihedral
// angles in 3D, and the shape class as UInt8 with the legend docs/mesh_formats.md gives.
TEST(RoundTrip, QualityArraysNameVolumeDihedralAnglesAndShapeClassLegend) {
  const MeshData tets = tagged_box();
  const auto d3 = quality_cell_data(mesh::cell_quality(tets));
  std::vector<std::string> names;
  for (const auto& a : d3) names.push_back(a.name);
  EXPECT_EQ(names, (std::vector<std::string>{"volume", "aspect_ratio", "shewchuk_quality",
                                             "min_dihedral_angle_deg", "max_dihedral_angle_deg",
                                             "shape_class"}));
  EXPECT_EQ(d3[5].type, DataArray::Type::kUInt8);
  const MeshData tris = mesh::make_rectangle(2, 2, 1.0, 1.0, mesh::GridDiagonal::kForward);
  const auto d2 = quality_cell_data(mesh::cell_quality(tris));
  EXPECT_EQ(d2[0].name, "area");
  EXPECT_EQ(d2[3].name, "min_angle_deg");
  // The legend of shape_class (docs/mesh_formats.md, write_mesh.hpp).
  const char* legend[] = {"good", "needle", "spindle", "sliver", "cap", "flat"};
  for (int k = 0; k < 6; ++k)
    EXPECT_STREQ(mesh::to_string(static_cast<mesh::ShapeClass>(k)), legend[k]) << k;
}

// A truncated binary file is a ParseError naming the file, never a crash.
TEST(RoundTrip, VtuTruncatedBinaryIsParseError) {
  const MeshData m = tagged_box();
  const std::string p = temp_path("trunc.vtu");
  write_vtu(p, m);
  std::ifstream in(p, std::ios::binary);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (std::size_t keep : {text.size() / 2, text.size() - 40}) {
    write_temp("trunc_cut.vtu", text.substr(0, keep));
    try {
      (void)read_vtu(temp_path("trunc_cut.vtu"));
      ADD_FAILURE() << "accepted a file truncated to " << keep << " bytes";
    } catch (const ParseError& e) {
      EXPECT_NE(std::string(e.what()).find("trunc_cut.vtu"), std::string::npos) << e.what();
    }
  }
}

TEST(HandWritten, Gmsh41EntitiesPhysicalNamesParametricNodesAndIgnoredElements) {
  const std::string text =
      "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"
      "$PhysicalNames\n2\n2 11 \"skin\"\n3 21 \"liver tissue\"\n$EndPhysicalNames\n"
      "$Entities\n1 0 1 1\n"
      "7 0 0 0 0\n"               // point entity 7, no physical tag
      "3 0 0 0 1 1 1 1 11 0\n"    // surface 3 → physical 11
      "5 0 0 0 1 1 1 1 21 1 3\n"  // volume 5 → physical 21, bounded by surface 3
      "$EndEntities\n"
      "$Nodes\n2 5 1 50\n"
      "0 7 0 1\n50\n0 0 0\n"  // node tag 50 on a point entity
      "3 5 0 4\n10\n20\n30\n40\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n$EndNodes\n"
      "$Elements\n3 4 1 4\n"
      "0 7 15 1\n1 50\n"       // a point element: ignored
      "2 3 2 1\n2 10 20 30\n"  // a triangle on surface 3
      "3 5 4 2\n3 50 10 20 30\n4 40 30 20 10\n"
      "$EndElements\n$NodeData\n1\n\"x\"\n$EndNodeData\n";
  const LoadedMesh r = read_mesh(write_temp("hand41.msh", text));
  EXPECT_EQ(r.mesh.dimension, 3);
  EXPECT_EQ(r.mesh.num_points(), 5);
  EXPECT_EQ(r.mesh.num_cells(), 2);
  EXPECT_EQ(r.mesh.cell_tags, (std::vector<int>{21, 21}));
  EXPECT_EQ(r.mesh.facet_tags, std::vector<int>{11});
  EXPECT_EQ(r.report.ignored_elements, 1);
  EXPECT_EQ(r.report.physical_names.at(21), "liver tissue");
  // Node tag 50 is index 0, tag 10 index 1.
  EXPECT_EQ(r.mesh.cells(0, 0), 0);
  EXPECT_EQ(r.mesh.cells(1, 0), 1);
}

TEST(HandWritten, Gmsh22PhysicalNamesLinesAndSparseTags) {
  const std::string text =
      "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n"
      "$PhysicalNames\n1\n2 4 \"plate\"\n$EndPhysicalNames\n"
      "$Nodes\n4\n100 0 0 0\n7 1 0 0\n3 1 1 0\n9 0 1 0\n$EndNodes\n"
      "$Elements\n3\n1 1 2 1 1 100 7\n2 2 2 4 1 100 7 3\n3 2 0 100 3 9\n$EndElements\n";
  const LoadedMesh r = read_mesh(write_temp("hand22.msh", text));
  EXPECT_EQ(r.mesh.dimension, 2);
  EXPECT_EQ(r.mesh.num_cells(), 2);
  EXPECT_EQ(r.mesh.cell_tags, (std::vector<int>{4, 0}));
  EXPECT_EQ(r.report.ignored_elements, 1);
  EXPECT_EQ(r.report.physical_names.at(4), "plate");
}

TEST(HandWritten, MeditCommentsSkippedSectionsAnd2D) {
  const std::string text =
      "# comment line\nMeshVersionFormatted 2\nDimension\n2\n"
      "Vertices\n4\n0 0 1\n1 0 1\n1 1 2\n0 1 2   # trailing comment\n"
      "Edges\n1\n1 2 0\nCorners\n2\n1\n3\n"
      "Triangles\n2\n1 2 3 7\n1 3 4 8\nEnd\n";
  const LoadedMesh r = read_mesh(write_temp("hand2d.mesh", text));
  EXPECT_EQ(r.mesh.dimension, 2);
  EXPECT_EQ(r.mesh.num_cells(), 2);
  EXPECT_EQ(r.mesh.cell_tags, (std::vector<int>{7, 8}));
  EXPECT_EQ(r.mesh.point_tags, (std::vector<int>{1, 1, 2, 2}));
  EXPECT_EQ(r.report.ignored_elements, 1);
  EXPECT_EQ(r.report.format, "medit 2");
}

TEST(HandWritten, TetGenZeroBasedWithAttributesMarkersAndComments) {
  write_temp("hand_tg.node",
             "# points\n5 3 1 1\n0 0 0 0 0.5 1\n1 1 0 0 0.5 1\n2 0 1 0 0.5 0\n"
             "3 0 0 1 0.5 0\n4 1 1 1 0.5 2\n");
  const std::string ele = write_temp("hand_tg.ele", "2 4 1\n0 0 1 2 3 3\n1 1 4 2 3 -2 # region\n");
  const LoadedMesh r = read_mesh(ele);
  EXPECT_EQ(r.mesh.num_cells(), 2);
  EXPECT_EQ(r.mesh.cell_tags, (std::vector<int>{3, -2}));
  EXPECT_EQ(r.mesh.point_tags, (std::vector<int>{1, 1, 0, 0, 2}));
  EXPECT_EQ(r.report.format, "tetgen");
}

TEST(HandWritten, OffSurfaceWithColours) {
  const std::string text =
      "OFF\n# a tetrahedron surface\n4 4 6\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
      "3 0 2 1 255 0 0\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
  const LoadedMesh r = read_mesh(write_temp("surf.off", text));
  EXPECT_EQ(r.mesh.dimension, 2);
  EXPECT_EQ(r.mesh.num_cells(), 4);
  EXPECT_TRUE(r.report.surface);
  EXPECT_EQ(r.report.reoriented, 0);  // surfaces have no xy orientation to check
}

TEST(Options, MergeDuplicatesScaleAndSplitPinched) {
  // Two tetrahedra touching in one vertex, given twice (vertex 4 and 5 coincide).
  const std::string text =
      "MeshVersionFormatted 1\nDimension 3\nVertices\n8\n"
      "0 0 0 0\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 0\n1 0 2 0\n0 1 2 0\n0 0 3 0\n"
      "Tetrahedra\n2\n1 2 3 4 1\n5 6 7 8 2\nEnd\n";
  const std::string p = write_temp("pinch.mesh", text);
  ReadOptions o;
  o.split_pinched_vertices = false;
  LoadedMesh r = read_mesh(p, o);
  EXPECT_EQ(r.report.duplicate_vertices, 1);
  EXPECT_EQ(r.report.merged_vertices, 0);
  EXPECT_EQ(r.report.pinched_vertices, 0);
  o.merge_duplicate_vertices = true;
  r = read_mesh(p, o);
  EXPECT_EQ(r.report.merged_vertices, 1);
  EXPECT_EQ(r.report.unused_vertices, 1);  // vertex 5 after the merge
  EXPECT_EQ(r.mesh.cells(0, 1), 3);
  o.split_pinched_vertices = true;
  o.scale = 0.5;
  r = read_mesh(p, o);
  EXPECT_EQ(r.report.pinched_vertices, 1);  // the merged vertex joins two separate cells
  EXPECT_EQ(r.report.added_vertices, 1);
  EXPECT_EQ(r.mesh.num_points(), 9);
  EXPECT_EQ(r.mesh.points.col(8), Vec3(0, 0, 0.5));
  EXPECT_EQ(r.mesh.cells(0, 1), 8);
  EXPECT_EQ(r.mesh.points(2, 7), 1.5);
}

}  // namespace
}  // namespace incise::io
