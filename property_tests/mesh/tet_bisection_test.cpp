/// Property tests of conforming tetrahedral bisection (mesh/tet_bisection.hpp: the marked
/// tetrahedra of Arnold, Mukherjee & Pouly 2000; thesis §6.9, Fig. 6.13) and of the reflected
/// Kuhn cube (generators.hpp, CubeSplit::kKuhn).
///
/// Random refinement: 10⁴ bisect calls per default run in total — 6000 on Kuhn cubes (n = 2,
/// restarted every 100 calls so that the full validate() after every call stays cheap) and 4000
/// on the shipped liver (reference_data/meshes/liver_coarse.mesh). On the liver the full
/// validate() costs O(mesh) (≈ 20k tetrahedra), so after every call validate_local() checks the
/// elements and vertices the call created (all the call changed: replace_elements only adds
/// those), and the full validate() runs every kLiverFullValidateEvery calls and at the end.
/// After each round: conformity (every face in ≤ 2 tetrahedra; boundary area conserved and
/// every boundary face inside a starting boundary face, so the boundary's union is unchanged;
/// facet_coverage of the exported cells agrees with the connectivity's boundary map), volume
/// conserved, all tetrahedra positive (validate's orientation check). Kuhn cube: the similarity
/// classes (normalised sorted squared edge lengths) of every tetrahedron ever made: exactly 3
/// (Maubach's bisection of a Kuhn tetrahedron cycles through three shapes, levels mod 3). Liver:
/// quality before/after (docs/tet_bisection.md). The `slow` ctest (INCISE_TET_BISECTION_SLOW=1)
/// runs 10 rounds of 1000 calls on an n = 4 Kuhn cube (meshes 10× larger) and 2·10⁴ liver
/// calls.

#include <incise/core/error.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/tet_bisection.hpp>
#include <incise/mesh/tet_faces.hpp>
#include <incise/mesh/validate.hpp>
#include <incise_test/seed.hpp>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <set>

namespace {

using incise::Index;
using incise::Vec3;
using incise::mesh::ElementHandle;
using incise::mesh::MeshData;
using incise::mesh::TetBisectionMesh;

// Full validate() of the liver (17k tetrahedra at the start, ≈ 130k after 4000 calls; ≈ 0.3 s
// each there) every 500 calls and at the end; validate_local() covers every call (file comment).
constexpr int kLiverFullValidateEvery = 500;

MeshData liver() {
  return incise::io::read_mesh(incise::test::source_path("reference_data/meshes/liver_coarse.mesh"))
      .mesh;
}

incise::mesh::ValidationReport full_validate(const TetBisectionMesh& m) {
  incise::mesh::ValidateOptions o;
  o.positions = &m.points();
  return incise::mesh::validate(m.connectivity(), o);
}

double tet_volume(const TetBisectionMesh& m, ElementHandle e) {
  const auto& s = m.connectivity().simplex(e);
  const auto& x = m.points();
  return s.sign() * incise::mesh::signed_volume(x.col(s.vertex(0)), x.col(s.vertex(1)),
                                                x.col(s.vertex(2)), x.col(s.vertex(3)));
}

double total_volume(const TetBisectionMesh& m) {
  double v = 0.0;
  for (const ElementHandle e : m.connectivity().elements()) v += tet_volume(m, e);
  return v;
}

double boundary_area(const TetBisectionMesh& m) {
  double a = 0.0;
  for (const auto f : m.connectivity().boundary()) {
    const auto& s = m.connectivity().simplex(f);
    a += incise::mesh::triangle_area(m.points().col(s.vertex(0)), m.points().col(s.vertex(1)),
                                     m.points().col(s.vertex(2)));
  }
  return a;
}

/// A random live element.
ElementHandle random_element(const TetBisectionMesh& m, std::mt19937_64& rng) {
  const auto& conn = m.connectivity();
  ElementHandle e;
  do {
    e = conn.element_at(std::uniform_int_distribution<Index>(0, conn.element_capacity() - 1)(rng));
  } while (!e.valid());
  return e;
}

/// The live elements created since tree node `first_node` (the leaves among the new nodes).
std::vector<ElementHandle> created_since(const TetBisectionMesh& m, std::size_t first_node) {
  std::vector<ElementHandle> out;
  for (std::size_t n = first_node; n < m.tree().size(); ++n)
    if (m.tree()[n].children[0] < 0) out.push_back(m.tree()[n].element);
  return out;
}

/// Conformity and conservation after a round (file comment). `start` is the starting mesh.
void expect_conforming(const TetBisectionMesh& m, const MeshData& start, double volume,
                       double area) {
  const MeshData now = m.to_mesh_data();
  // Every face in at most two tetrahedra.
  std::map<std::array<Index, 3>, int> faces;
  for (Index c = 0; c < now.num_cells(); ++c)
    for (int j = 0; j < 4; ++j) {
      std::array<Index, 3> f{};
      for (int r = 0; r < 3; ++r)
        f[static_cast<std::size_t>(r)] = now.cells(incise::mesh::kTetFace[j][r], c);
      std::sort(f.begin(), f.end());
      ++faces[f];
    }
  for (const auto& kv : faces) ASSERT_LE(kv.second, 2);
  // The connectivity's boundary map equals the boundary of the exported cells.
  incise::mesh::CellMatrix bmap(3, m.connectivity().num_boundary_faces());
  Index k = 0;
  for (const auto f : m.connectivity().boundary()) {
    for (int r = 0; r < 3; ++r) bmap(r, k) = m.connectivity().simplex(f).vertex(r);
    ++k;
  }
  const auto cov = incise::mesh::facet_coverage(now.cells, bmap);
  EXPECT_EQ(cov.interior, 0u);
  EXPECT_EQ(cov.boundary_not_listed, 0u);
  // Volume and boundary area conserved: sums of ≤ 10⁵ positive terms, each rounded once or
  // twice (relative 1e-12 leaves a factor 10 over 10⁵ · 2⁻⁵³).
  EXPECT_NEAR(total_volume(m), volume, 1e-12 * volume);
  EXPECT_NEAR(boundary_area(m), area, 1e-12 * area);
  // Every boundary face lies in a starting boundary face (relative 1e-9 of its size: the
  // midpoints are rounded once per level), so with equal areas the union is unchanged.
  const incise::mesh::CellMatrix sb = incise::mesh::boundary_faces(start);
  for (const auto f : m.connectivity().boundary()) {
    const auto& s = m.connectivity().simplex(f);
    const Vec3 c =
        (m.points().col(s.vertex(0)) + m.points().col(s.vertex(1)) + m.points().col(s.vertex(2))) /
        3.0;
    bool inside = false;
    for (Index t = 0; t < sb.cols() && !inside; ++t) {
      const Vec3 a = start.points.col(sb(0, t)), b = start.points.col(sb(1, t)),
                 d = start.points.col(sb(2, t));
      const Vec3 n = (b - a).cross(d - a);
      const double scale = (b - a).norm() + (d - a).norm();
      if (std::abs(n.normalized().dot(c - a)) > 1e-9 * scale) continue;
      // Barycentric coordinates of c in (a, b, d).
      const double l1 = n.dot((c - a).cross(d - a)) / n.squaredNorm();
      const double l2 = n.dot((b - a).cross(c - a)) / n.squaredNorm();
      inside = l1 >= -1e-9 && l2 >= -1e-9 && l1 + l2 <= 1.0 + 1e-9;
    }
    ASSERT_TRUE(inside) << "boundary face " << s << " is not on the starting boundary";
  }
}

TEST(KuhnCube, CountsOrientationConformity) {
  for (int n : {1, 2, 3, 16}) {
    const MeshData m = incise::mesh::make_kuhn_cube(n, 0.1);
    EXPECT_EQ(m.num_cells(), 6 * n * n * n);  // 24,576 for n = 16
    EXPECT_EQ(m.num_points(), (n + 1) * (n + 1) * (n + 1));
    double v = 0.0;
    for (Index c = 0; c < m.num_cells(); ++c) {
      const double vc =
          incise::mesh::signed_volume(m.points.col(m.cells(0, c)), m.points.col(m.cells(1, c)),
                                      m.points.col(m.cells(2, c)), m.points.col(m.cells(3, c)));
      ASSERT_GT(vc, 0.0);
      v += vc;
    }
    EXPECT_NEAR(v, 1e-3, 1e-15);  // sum of 6n³ exact-ish terms
    // Conforming: the boundary is exactly the cube surface, 2 triangles per square.
    EXPECT_EQ(incise::mesh::boundary_faces(m).cols(), 6 * 2 * n * n);
    const auto conn = incise::mesh::Connectivity::from_mesh_data(m);
    EXPECT_TRUE(incise::mesh::validate(conn).ok());
  }
  // Mirrored: every main diagonal of a cube ends at a corner whose index parity is even, so the
  // vertex (1,1,1) of the n = 2 cube (even) has all 8 cubes' diagonals: degree 8·6 = 48 tets.
  const auto conn = incise::mesh::Connectivity::from_mesh_data(incise::mesh::make_kuhn_cube(2, 1));
  EXPECT_EQ(conn.star_size(1 + 3 * (1 + 3 * 1)), 48);
  EXPECT_THROW(incise::mesh::make_kuhn_cube(0, 1.0), incise::mesh::GeneratorError);
  EXPECT_THROW(incise::mesh::make_kuhn_cube(2, -1.0), incise::mesh::GeneratorError);
}

TEST(TetBisection, KuhnCubeIsMarkedTypeA) {
  TetBisectionMesh m(incise::mesh::make_kuhn_cube(2, 1.0));
  for (const ElementHandle e : m.connectivity().elements()) {
    EXPECT_EQ(m.type(e), TetBisectionMesh::Type::kA);
    const auto r = m.refinement_edge(e);
    // The refinement edge is the main diagonal of its cube (length √3 · 1/2).
    EXPECT_NEAR((m.points().col(r[0]) - m.points().col(r[1])).norm(), std::sqrt(3.0) / 2, 1e-15);
  }
}

TEST(TetBisection, RandomBisectionsOnKuhnCubes) {
  INCISE_SEEDED_RNG(rng, 2101);
  const bool slow = incise::test::env_set("INCISE_TET_BISECTION_SLOW");
  const int n = slow ? 4 : 2;
  // 6000 calls by default; a tenth in builds with debug checks (they validate every edit).
  const int rounds = incise::test::scaled_for_checks(slow ? 10 : 60), per_round = slow ? 1000 : 100;
  std::set<std::array<long, 6>> classes;
  long calls = 0, forced = 0;
  for (int round = 0; round < rounds; ++round) {
    const MeshData start = incise::mesh::make_kuhn_cube(n, 1.0);
    TetBisectionMesh m(start);
    for (const ElementHandle e : m.connectivity().elements())
      classes.insert(m.similarity_signature(e));
    const double volume = total_volume(m), area = boundary_area(m);
    for (int it = 1; it <= per_round; ++it) {
      const std::size_t first = m.tree().size();
      const long before = m.num_bisections();
      const Index v = m.bisect(random_element(m, rng));
      ASSERT_GT(m.num_bisections(), before);
      ASSERT_EQ(v + 1, m.connectivity().num_vertices());
      ++calls;
      if (it % incise::test::kValidateEvery == 0) {
        const auto rep = full_validate(m);
        ASSERT_TRUE(rep.ok()) << rep.summary();
      }
      for (const ElementHandle e : created_since(m, first))
        classes.insert(m.similarity_signature(e));
    }
    expect_conforming(m, start, volume, area);
    forced += m.num_forced_bisections();
  }
  EXPECT_EQ(calls, static_cast<long>(rounds) * per_round);
  EXPECT_EQ(forced, 0);  // the Kuhn cube satisfies Maubach's conditions: never a cycle
  // Maubach's bisection of a Kuhn tetrahedron: three similarity classes, levels mod 3 (the
  // Kuhn tetrahedron, its halves, its quarters); random refinement reaches all three. The
  // signatures (similarity_signature) are exact to a few ulps here (dyadic coordinates), and
  // distinct classes differ by ≥ 1/8 in some entry.
  EXPECT_EQ(classes.size(), 3u);
}

TEST(TetBisection, RandomBisectionsOnTheLiver) {
  INCISE_SEEDED_RNG(rng, 2102);
  // 4000 calls by default; a tenth in builds with debug checks (they validate every edit).
  const int calls = incise::test::scaled_for_checks(
      incise::test::env_set("INCISE_TET_BISECTION_SLOW") ? 20000 : 4000);
  const MeshData start = liver();
  TetBisectionMesh m(start);
  const double volume = total_volume(m), area = boundary_area(m);
  const auto before = incise::mesh::summarize_quality(start);
  for (int it = 1; it <= calls; ++it) {
    const std::size_t first = m.tree().size();
    const Index v0 = m.connectivity().num_vertices();
    m.bisect(random_element(m, rng));
    std::vector<Index> fresh;
    for (Index v = v0; v < m.connectivity().num_vertices(); ++v) fresh.push_back(v);
    incise::mesh::ValidateOptions o;
    o.positions = &m.points();
    const auto local =
        incise::mesh::validate_local(m.connectivity(), created_since(m, first), fresh, o);
    ASSERT_TRUE(local.ok()) << local.summary();
    if (it % kLiverFullValidateEvery == 0 || it == calls) {
      const auto rep = full_validate(m);
      ASSERT_TRUE(rep.ok()) << rep.summary();
    }
  }
  expect_conforming(m, start, volume, area);
  const auto after = incise::mesh::summarize_quality(m.to_mesh_data());
  // docs/tet_bisection.md: the liver's minimum dihedral angle and aspect ratio before and after
  // (printed here for the note). AMP §4 gives finitely many similarity classes per starting
  // tetrahedron but no constant; the bound asserted is measured: the worst descendant keeps more
  // than a third of the starting mesh's worst aspect ratio and minimum dihedral angle (ratios
  // 0.76 and 0.83 after 4000 calls, 0.48 and 0.54 after the slow run's 2·10⁴).
  std::printf("liver: %d bisect calls, %ld simple bisections, %ld forced by a cycle\n", calls,
              m.num_bisections(), m.num_forced_bisections());
  std::printf("liver before: %d tets, min dihedral %.3f deg, p05 %.3f, aspect min %.4f p05 %.4f\n",
              static_cast<int>(before.num_cells), before.min_angle_deg.min,
              before.min_angle_deg.p05, before.aspect_ratio.min, before.aspect_ratio.p05);
  std::printf("liver after:  %d tets, min dihedral %.3f deg, p05 %.3f, aspect min %.4f p05 %.4f\n",
              static_cast<int>(after.num_cells), after.min_angle_deg.min, after.min_angle_deg.p05,
              after.aspect_ratio.min, after.aspect_ratio.p05);
  EXPECT_EQ(after.num_inverted, 0);
  EXPECT_GT(after.min_angle_deg.min, before.min_angle_deg.min / 3.0);
  EXPECT_GT(after.aspect_ratio.min, before.aspect_ratio.min / 3.0);
}

// Issue 20: cell tags survive refinement. Each cell of to_mesh_data() carries its starting
// cell's tag, so the volume of every tag is conserved (and the starting mesh comes back
// unchanged before any bisection).
TEST(TetBisection, CellTagsFollowTheStartingCells) {
  INCISE_SEEDED_RNG(rng, 2106);
  const MeshData start = liver();
  ASSERT_EQ(start.cell_tags.size(), static_cast<std::size_t>(start.num_cells()));
  auto tag_volumes = [](const MeshData& m) {
    std::map<int, double> v;
    for (Eigen::Index c = 0; c < m.cells.cols(); ++c)
      v[m.cell_tags[static_cast<std::size_t>(c)]] +=
          incise::mesh::signed_volume(m.points.col(m.cells(0, c)), m.points.col(m.cells(1, c)),
                                      m.points.col(m.cells(2, c)), m.points.col(m.cells(3, c)));
    return v;
  };
  TetBisectionMesh m(start);
  EXPECT_EQ(m.to_mesh_data().cell_tags, start.cell_tags);
  const auto before = tag_volumes(start);
  ASSERT_GE(before.size(), 2u);  // the liver has more than one label
  for (int i = 0; i < incise::test::scaled_for_checks(300, 4); ++i)
    m.bisect(random_element(m, rng));
  const MeshData refined = m.to_mesh_data();
  ASSERT_EQ(refined.cell_tags.size(), static_cast<std::size_t>(refined.num_cells()));
  EXPECT_GT(refined.num_cells(), start.num_cells());
  const auto after = tag_volumes(refined);
  ASSERT_EQ(after.size(), before.size());
  // A bisection halves a tetrahedron exactly up to rounding of the midpoint: ~1e-15 relative
  // per level on sums of ~2·10⁴ positive terms.
  for (const auto& [tag, v] : before) EXPECT_NEAR(after.at(tag), v, 1e-12 * v) << "tag " << tag;
  // A mesh without tags gives none.
  MeshData untagged = start;
  untagged.cell_tags.clear();
  EXPECT_TRUE(TetBisectionMesh(untagged).to_mesh_data().cell_tags.empty());
}

TEST(TetBisection, ParentsCarryALinearFieldExactly) {
  INCISE_SEEDED_RNG(rng, 2103);
  TetBisectionMesh m(liver());
  // A quarter in builds with debug checks: they validate the whole liver after every edit.
  for (int i = 0; i < incise::test::scaled_for_checks(400, 4); ++i)
    m.bisect(random_element(m, rng));
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Vec3 g(u(rng), u(rng), u(rng));
  const double c = u(rng);
  auto f = [&](Index v) { return c + g.dot(m.points().col(v)); };
  const Index n = m.connectivity().num_vertices();
  std::vector<double> field(static_cast<std::size_t>(n));
  double scale = 0.0;
  for (Index v = 0; v < n; ++v) {
    const auto p = m.parents(v);
    if (p[0] < 0) {
      field[static_cast<std::size_t>(v)] = f(v);
      scale = std::max(scale, std::abs(f(v)));
      continue;
    }
    ASSERT_LT(p[0], v);
    ASSERT_LT(p[1], v);
    ASSERT_EQ(m.points().col(v), (0.5 * (m.points().col(p[0]) + m.points().col(p[1]))).eval());
    field[static_cast<std::size_t>(v)] =
        0.5 * (field[static_cast<std::size_t>(p[0])] + field[static_cast<std::size_t>(p[1])]);
  }
  // Each average and each evaluation rounds a few times; ≤ 30 levels here: relative 1e-13.
  for (Index v = 0; v < n; ++v)
    EXPECT_NEAR(field[static_cast<std::size_t>(v)], f(v), 1e-13 * scale);
  EXPECT_THROW(m.parents(n), incise::UsageError);
  EXPECT_THROW(m.parents(-1), incise::UsageError);
}

TEST(TetBisection, RefineAroundReachesTheSize) {
  TetBisectionMesh m(incise::mesh::make_kuhn_cube(2, 0.1));
  const Vec3 x(0.0371, 0.0613, 0.0237);
  const double h = 0.1 / 64;
  const int calls = m.refine_around(x, h);
  EXPECT_GT(calls, 0);
  EXPECT_LE(m.longest_edge(m.locate(x)), h);
  // Graded, not uniform: far fewer tetrahedra than the uniform mesh of that size (6·64³).
  EXPECT_LT(m.connectivity().num_elements(), 6 * 64 * 64 * 64 / 50);
  EXPECT_TRUE(full_validate(m).ok());
  EXPECT_EQ(m.refine_around(x, h), 0);  // already fine enough
  EXPECT_THROW(m.refine_around(Vec3(-1.0, 0.0, 0.0), h), incise::UsageError);
  EXPECT_THROW(m.refine_around(x, 0.0), incise::UsageError);
  EXPECT_THROW(m.refine_around(x, -1.0), incise::UsageError);
  EXPECT_THROW(m.refine_around(x, std::nan("")), incise::UsageError);
  EXPECT_THROW(m.refine_around(Vec3(std::nan(""), 0.0, 0.0), h), incise::UsageError);
}

TEST(TetBisection, RefineAlongSegmentReachesTheSize) {
  const MeshData start = liver();
  TetBisectionMesh m(start);
  const auto box = incise::mesh::bounding_box(start.points);
  const Vec3 a = box[0] + 0.3 * (box[1] - box[0]), b = box[0] + 0.6 * (box[1] - box[0]);
  const double h = 0.02 * (box[1] - box[0]).norm();
  EXPECT_GT(m.refine_along_segment(a, b, h), 0);
  EXPECT_TRUE(full_validate(m).ok());
  const auto meeting = m.elements_meeting_segment(a, b);
  EXPECT_FALSE(meeting.empty());
  for (const ElementHandle e : meeting) EXPECT_LE(m.longest_edge(e), h);
  // Every tetrahedron containing a sample point of the segment is among them.
  const std::set<ElementHandle> listed(meeting.begin(), meeting.end());
  for (int i = 0; i <= 1000; ++i) {
    const ElementHandle e = m.locate(a + (b - a) * (i / 1000.0));
    if (e.valid()) {
      EXPECT_EQ(listed.count(e), 1u);
    }
  }
  EXPECT_EQ(m.refine_along_segment(a, b, h), 0);
  EXPECT_THROW(m.refine_along_segment(a, b, 0.0), incise::UsageError);
  EXPECT_THROW(m.refine_along_segment(a, Vec3(std::nan(""), 0, 0), h), incise::UsageError);
  // Entirely outside: nothing to refine.
  EXPECT_EQ(m.refine_along_segment(box[1] + Vec3::Ones(), box[1] + 2 * Vec3::Ones(), h), 0);
}

TEST(TetBisection, LocateAgreesWithBruteForce) {
  INCISE_SEEDED_RNG(rng, 2104);
  const MeshData start = liver();
  TetBisectionMesh m(start);
  // A quarter in builds with debug checks: they validate the whole liver after every edit.
  for (int i = 0; i < incise::test::scaled_for_checks(300, 4); ++i)
    m.bisect(random_element(m, rng));
  m.refine_around(start.points.col(0), 1.0);
  const auto box = incise::mesh::bounding_box(start.points);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto elements = m.connectivity().elements();
  int inside = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3 x = box[0] + (box[1] - box[0]).cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
    // Brute force: the most-inside tetrahedron (max of the min barycentric coordinate).
    double best = -1e300;
    for (const ElementHandle e : elements) {
      const auto& s = m.connectivity().simplex(e);
      Eigen::Matrix3d j;
      j << m.points().col(s.vertex(1)) - m.points().col(s.vertex(0)),
          m.points().col(s.vertex(2)) - m.points().col(s.vertex(0)),
          m.points().col(s.vertex(3)) - m.points().col(s.vertex(0));
      const Vec3 l = j.inverse() * (x - m.points().col(s.vertex(0)));
      best = std::max(best, std::min({l(0), l(1), l(2), 1.0 - l.sum()}));
    }
    const ElementHandle t = m.locate(x);
    // Points within 1e-9 of a face are left out of the two-sided check (locate's tolerance is
    // 1e-12; a brute-force coordinate within 1e-9 of 0 may go either way by rounding).
    if (std::abs(best) < 1e-9) continue;
    ASSERT_EQ(t.valid(), best > 0.0) << "x = " << x.transpose();
    if (t.valid()) {
      ++inside;
      const auto& s = m.connectivity().simplex(t);
      Eigen::Matrix3d j;
      j << m.points().col(s.vertex(1)) - m.points().col(s.vertex(0)),
          m.points().col(s.vertex(2)) - m.points().col(s.vertex(0)),
          m.points().col(s.vertex(3)) - m.points().col(s.vertex(0));
      const Vec3 l = j.inverse() * (x - m.points().col(s.vertex(0)));
      EXPECT_GE(std::min({l(0), l(1), l(2), 1.0 - l.sum()}), -1e-12);
    }
  }
  EXPECT_GT(inside, 20);  // the liver fills a good part of its box
  EXPECT_FALSE(m.locate(box[1] + Vec3::Ones()).valid());
  EXPECT_FALSE(m.locate(Vec3(std::nan(""), 0, 0)).valid());
}

TEST(TetBisection, BadInput) {
  MeshData one;
  one.dimension = 3;
  one.points.resize(3, 4);
  one.points << 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1;
  one.cells.resize(4, 1);
  one.cells << 0, 1, 2, 3;
  EXPECT_NO_THROW(TetBisectionMesh{one});
  MeshData inverted = one;
  inverted.cells << 1, 0, 2, 3;
  EXPECT_THROW(TetBisectionMesh{inverted}, incise::ParameterError);
  MeshData flat = one;
  flat.points.col(3) = Vec3(0.5, 0.5, 0.0);
  EXPECT_THROW(TetBisectionMesh{flat}, incise::ParameterError);
  EXPECT_THROW(TetBisectionMesh{incise::mesh::make_rectangle(2, 2, 1, 1)}, incise::ParameterError);
  MeshData dup = incise::mesh::make_kuhn_cube(1, 1.0);
  dup.cells.conservativeResize(4, dup.cells.cols() + 1);
  dup.cells.col(dup.cells.cols() - 1) = dup.cells.col(0);
  EXPECT_THROW(TetBisectionMesh{dup}, incise::UsageError);
  // A dead handle.
  TetBisectionMesh m(one);
  const ElementHandle e = m.connectivity().elements()[0];
  m.bisect(e);
  EXPECT_THROW(m.bisect(e), incise::UsageError);
  // The work limit turns an oversized request into an error; the mesh stays conforming.
  TetBisectionMesh w(incise::mesh::make_kuhn_cube(2, 1.0));
  w.set_max_bisections_per_call(200);
  EXPECT_THROW(w.refine_around(Vec3(0.3, 0.3, 0.3), 1e-6), incise::UsageError);
  EXPECT_TRUE(full_validate(w).ok());
  EXPECT_THROW(w.set_max_bisections_per_call(0), incise::UsageError);
}

}  // namespace
