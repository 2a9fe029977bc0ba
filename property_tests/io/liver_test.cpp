// The real liver of reference_data/meshes (CGAL Mesh_3, Medit): what the loader must say about
// it (reference_data/README.md) and that it validates ((7.1)-(7.5), connected stars,
// orientation) once its two pinched vertices are split.

#include <gtest/gtest.h>
#include <incise/io/read_mesh.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/validate.hpp>
#include <incise_test/seed.hpp>

namespace incise::io {
namespace {

const std::string kLiver = "reference_data/meshes/liver_coarse.mesh";

TEST(Liver, LoaderReportsWhatTheFileHolds) {
  const LoadedMesh r = read_mesh(incise::test::source_path(kLiver));
  const LoadReport& rep = r.report;
  // Counts from the file header lines (reference_data/meshes/README row in MANIFEST.tsv).
  EXPECT_EQ(rep.format, "medit 1");
  EXPECT_EQ(rep.num_cells, 16597);
  EXPECT_EQ(rep.num_facets, 8004);
  EXPECT_EQ(rep.reoriented, 0);  // every tetrahedron positively oriented as read
  EXPECT_EQ(rep.duplicate_vertices, 0);
  EXPECT_EQ(rep.unused_vertices, 0);
  EXPECT_EQ(rep.duplicate_facets, 4002);  // each triangle listed once per side ...
  EXPECT_EQ(rep.opposite_facets, 4002);   // ... with opposite orientation
  EXPECT_EQ(rep.pinched_vertices, 2);
  EXPECT_EQ(rep.added_vertices, 2);
  EXPECT_EQ(rep.num_points, 3721 + 2);
  EXPECT_EQ(rep.cell_labels, (std::map<int, Index>{{1, 118}, {2, 1694}, {3, 14785}}));
  const mesh::QualitySummary q = mesh::summarize_quality(r.mesh);
  EXPECT_EQ(q.num_inverted, 0);
  EXPECT_EQ(q.shape_counts[static_cast<int>(mesh::ShapeClass::kGood)], 16597);
  EXPECT_GT(q.min_angle_deg.min, 10.0);   // measured 10.49°
  EXPECT_LT(q.max_angle_deg.max, 165.0);  // measured 163.1°
}

TEST(Liver, ValidatesAfterSplittingPinchedVertices) {
  const LoadedMesh r = read_mesh(incise::test::source_path(kLiver));
  const mesh::Connectivity conn = mesh::Connectivity::from_mesh_data(r.mesh);
  mesh::ValidateOptions o;
  o.positions = &r.mesh.points;
  const mesh::ValidationReport v = mesh::validate(conn, o);
  EXPECT_TRUE(v.ok()) << v.summary();
  // 3858 boundary triangles: the file's 4002 distinct triangles minus 144 subdomain interfaces.
  EXPECT_EQ(conn.num_boundary_faces(), 3858);
}

TEST(Liver, WithoutSplittingTheStarsOfTwoVerticesAreDisconnected) {
  ReadOptions opt;
  opt.split_pinched_vertices = false;
  const LoadedMesh r = read_mesh(incise::test::source_path(kLiver), opt);
  const mesh::Connectivity conn = mesh::Connectivity::from_mesh_data(r.mesh);
  const mesh::ValidationReport v = mesh::validate(conn);
  EXPECT_EQ(v.count("connected-star"), 2u) << v.summary();
  EXPECT_EQ(v.violations.size(), 2u);
}

}  // namespace
}  // namespace incise::io
