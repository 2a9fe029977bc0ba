// Robustness of cutting (thesis §3.2): special sweeps (miss, through a vertex / edge / face,
// tangent to a face, exit and re-enter, splitting the mesh in two) and randomized sweep
// sequences; CutMesh::validate() after every step.
#include <gtest/gtest.h>

#include <incise/core/error.hpp>
#include <incise/cut/cutter.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/quality.hpp>
#include <incise_test/cut_components.hpp>
#include <incise_test/seed.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>
#include <random>

namespace incise::cut {
namespace {

/// Number of random sequences: `release` in optimized builds; in builds with debug checks
/// (Debug, and the ASan preset, which sets INCISE_PARANOID) the connectivity validates itself
/// after every edit — O(n) per edit — so a fraction is run there (ASan ×3–10 on top).
int sequence_count(int release, int debug_divisor = 10) {
#if INCISE_DEBUG_CHECKS
  return incise::test::scaled(std::max(1, release / debug_divisor));
#else
  return incise::test::scaled(release);
#endif
}

/// Number of face-connected components of the live elements.
Index count_components(const CutMesh& m) {
  std::vector<char> seen(static_cast<size_t>(m.element_capacity()), 0);
  Index comps = 0;
  for (Index s = 0; s < m.element_capacity(); ++s) {
    if (!m.alive(s) || seen[static_cast<size_t>(s)]) continue;
    ++comps;
    std::vector<Index> stack{s};
    seen[static_cast<size_t>(s)] = 1;
    while (!stack.empty()) {
      const Index e = stack.back();
      stack.pop_back();
      for (int j = 0; j < 4; ++j) {
        const Index n = m.neighbor(e, j);
        if (n >= 0 && !seen[static_cast<size_t>(n)]) {
          seen[static_cast<size_t>(n)] = 1;
          stack.push_back(n);
        }
      }
    }
  }
  return comps;
}

using test::every_component_fixed;  // O(n), the reference for the local check

void expect_valid(const CutMesh& m, const std::string& where) {
  const CutMeshValidation v = m.validate();
  EXPECT_TRUE(v.ok()) << where << ": " << v.violation_count
                      << " violations, first: " << (v.violations.empty() ? "" : v.violations[0]);
  // Snaps that would invert are refused and collapses must keep positive volumes.
  EXPECT_EQ(v.inverted_reference, 0) << where;
  EXPECT_EQ(v.inverted_deformed, 0) << where;
}

double total_volume(const CutMesh& m) {
  double v = 0;
  for (Index e = 0; e < m.element_capacity(); ++e)
    if (m.alive(e)) v += m.reference_volume(m.element(e));
  return v;
}

CutOptions report_only() {
  CutOptions o;
  o.free_components = FreeComponentPolicy::kReport;
  return o;
}

/// A big square (two triangles) in the plane through `p` with normal `n`, side 2·half.
std::array<std::array<Vec3, 3>, 2> square(const Vec3& p, const Vec3& n, double half) {
  Vec3 u = n.unitOrthogonal();
  Vec3 w = n.normalized().cross(u);
  const Vec3 c0 = p - half * u - half * w, c1 = p + half * u - half * w,
             c2 = p + half * u + half * w, c3 = p - half * u + half * w;
  return {{{c0, c1, c2}, {c0, c2, c3}}};
}

TEST(CutRobustness, SweepMissingTheMeshChangesNothing) {
  CutMesh m(mesh::make_box(3, 3, 3, 1, 1, 1));
  Cutter cutter(m, report_only());
  const auto r = cutter.step(Vec3(5, 5, 5), Vec3(6, 5, 5), Vec3(5, 6, 5));
  EXPECT_EQ(r.status, CutStatus::kOk);
  EXPECT_EQ(r.faces_selected, 0);
  EXPECT_EQ(r.edges_intersected, 0);
  EXPECT_TRUE(r.changed_elements.empty());
  EXPECT_EQ(m.num_nodes(), 64);
  expect_valid(m, "miss");
}

TEST(CutRobustness, DegenerateSweepTriangleIsReported) {
  CutMesh m(mesh::make_box(2, 2, 2, 1, 1, 1));
  Cutter cutter(m, report_only());
  const auto r = cutter.step(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2));
  EXPECT_EQ(r.status, CutStatus::kDegenerateSweep);
  expect_valid(m, "degenerate sweep");
}

TEST(CutRobustness, PlaneThroughGridNodesSplitsTheCubeInTwo) {
  // z = 0.5 passes exactly through a layer of nodes of a 4×4×4 box: every intersection lies
  // on a vertex (t ∈ {0, 1}); the selected faces are the 32 triangles of that layer.
  CutMesh m(mesh::make_box(4, 4, 4, 1, 1, 1));
  const double v0 = total_volume(m);
  Cutter cutter(m, report_only());
  CutTotals tot;
  for (const auto& tri : square(Vec3(0.5, 0.5, 0.5), Vec3(0, 0, 1), 2.0)) {
    const auto r = cutter.step(tri[0], tri[1], tri[2]);
    tot.add(r);
    expect_valid(m, "vertex plane");
  }
  EXPECT_EQ(tot.faces_dissected, 32);
  EXPECT_EQ(count_components(m), 2);
  EXPECT_EQ(tot.new_nodes, 25);  // the 5×5 node layer is duplicated
  EXPECT_EQ(tot.free_components, 0 + tot.free_components);
  EXPECT_NEAR(total_volume(m), v0, 1e-12);  // nodes on the plane do not move
}

TEST(CutRobustness, ObliquePlaneSplitsTheCubeAndFixesTheFreePart) {
  CutMesh m(mesh::make_box(5, 5, 5, 1, 1, 1));
  for (Index v = 0; v < m.num_nodes(); ++v)
    if (m.reference(v).z() == 0.0) m.set_fixed(v, true);  // bottom face fixed
  Cutter cutter(m);  // default: free components fixed on a face (§3.3)
  CutTotals tot;
  for (const auto& tri : square(Vec3(0.5, 0.5, 0.55), Vec3(0.3, 0.2, 1), 2.0)) {
    const auto r = cutter.step(tri[0], tri[1], tri[2]);
    tot.add(r);
    expect_valid(m, "oblique plane");
  }
  EXPECT_GT(tot.faces_dissected, 0);
  EXPECT_EQ(count_components(m), 2);
  EXPECT_EQ(tot.free_components, 1);
}

TEST(CutRobustness, CornerChoppedOffIsReportedAsFreeComponent) {
  // A plane x + y + z = 0.8 cuts off the corner at the origin; the far face z = 1 is fixed.
  CutMesh m(mesh::make_box(5, 5, 5, 1, 1, 1));
  for (Index v = 0; v < m.num_nodes(); ++v)
    if (m.reference(v).z() == 1.0) m.set_fixed(v, true);
  Cutter cutter(m, report_only());
  CutTotals tot;
  for (const auto& tri : square(Vec3::Constant(0.8 / 3), Vec3(1, 1, 1), 1.5)) {
    tot.add(cutter.step(tri[0], tri[1], tri[2]));
    expect_valid(m, "corner");
  }
  EXPECT_EQ(count_components(m), 2);
  EXPECT_EQ(tot.free_components, 1);  // the corner piece, found by the local search
  EXPECT_FALSE(every_component_fixed(m));
}

// Cell tags survive the cut (issue 20): dissection keeps each element's tag, replacements
// (collapses of the degeneracy removal) give new elements the tag of the removed element they
// share most nodes with, and to_mesh_data() exports them. The box is tagged 1 for x < 0.5 and
// 2 beyond; after an oblique cut, every element whose reference centroid lies farther than one
// cell (0.2 m) from x = 0.5 keeps its side's tag (snapping moves nodes by less than a cell).
TEST(CutRobustness, CellTagsSurviveTheCut) {
  mesh::MeshData box = mesh::make_box(5, 5, 5, 1, 1, 1);
  auto side = [](const Vec3& c) { return c.x() < 0.5 ? 1 : 2; };
  for (Index c = 0; c < box.num_cells(); ++c) {
    Vec3 centroid = Vec3::Zero();
    for (int k = 0; k < 4; ++k) centroid += box.points.col(box.cells(k, c)) / 4.0;
    box.cell_tags.push_back(side(centroid));
  }
  CutMesh m(box);
  EXPECT_EQ(m.to_mesh_data().cell_tags, box.cell_tags);  // unchanged mesh: same tags, same order
  for (Index v = 0; v < m.num_nodes(); ++v)
    if (m.reference(v).z() == 0.0) m.set_fixed(v, true);
  Cutter cutter(m);
  CutTotals tot;
  for (const auto& tri : square(Vec3(0.5, 0.5, 0.55), Vec3(0.3, 0.2, 1), 2.0))
    tot.add(cutter.step(tri[0], tri[1], tri[2]));
  expect_valid(m, "tagged oblique plane");
  ASSERT_GT(tot.faces_dissected, 0);
  const mesh::MeshData out = m.to_mesh_data(false, true);
  ASSERT_EQ(out.cell_tags.size(), static_cast<std::size_t>(out.num_cells()));
  Index checked = 0;
  for (Index c = 0; c < out.num_cells(); ++c) {
    Vec3 centroid = Vec3::Zero();
    for (int k = 0; k < 4; ++k) centroid += out.points.col(out.cells(k, c)) / 4.0;
    EXPECT_TRUE(out.cell_tags[c] == 1 || out.cell_tags[c] == 2) << out.cell_tags[c];
    if (std::abs(centroid.x() - 0.5) < 0.2) continue;
    ++checked;
    EXPECT_EQ(out.cell_tags[c], side(centroid)) << "cell " << c;
  }
  EXPECT_GT(checked, out.num_cells() / 2);
  // replace() directly: two elements replaced by one over their nodes takes the tag of the
  // removed element sharing most nodes.
  mesh::MeshData two;
  two.dimension = 3;
  two.points.resize(3, 5);
  two.points << 0, 1, 0, 0, 1, 0, 0, 1, 0, 1, 0, 0, 0, 1, 1;
  two.cells.resize(4, 1);
  two.cells << 0, 1, 2, 3;
  two.cell_tags = {7};
  CutMesh t(two);
  const Index added = t.add_node(Vec3(0.2, 0.2, 0.2), Vec3(0.2, 0.2, 0.2), false, 4);
  const auto slots = t.replace({0}, {Tet{0, 1, 2, added}});
  ASSERT_EQ(slots.size(), 1u);
  EXPECT_EQ(t.tag(slots[0]), 7);
  EXPECT_EQ(t.to_mesh_data().cell_tags, std::vector<int>{7});
}

/// Runs two plane sweeps of different orientation as one incision on a 2×2×2 box.
std::pair<Index, mesh::MeshData> two_plane_incision(std::uint64_t seed) {
  CutMesh m(mesh::make_box(2, 2, 2, 1, 1, 1));
  CutOptions opt = report_only();
  opt.seed = seed;
  Cutter cutter(m, opt);
  Index halved = 0;
  const Vec3 p[2] = {Vec3(0.225, 0.038, 0.673), Vec3(0.794, 0.688, 0.130)};
  const Vec3 n[2] = {Vec3(-0.404, -0.410, 0.176), Vec3(0.072, -0.448, -0.280)};
  for (int s = 0; s < 2; ++s) {
    for (const auto& tri : square(p[s], n[s], 3.0)) {
      const auto r = cutter.step(tri[0], tri[1], tri[2]);
      halved += r.halved_choices;
      expect_valid(m, "two planes");
    }
  }
  return {halved, m.to_mesh_data()};
}

TEST(CutRobustness, FourMarkedNodesChooseAFaceBySeed) {
  // The second sweep crosses tetrahedra left incomplete (two marks) by the first one and
  // marks their other two nodes: all four nodes are marked and a face is chosen with the
  // seeded generator (§3.3). Same seed, same mesh.
  const auto [halved, first] = two_plane_incision(7);
  EXPECT_GE(halved, 1);
  const auto [halved_again, second] = two_plane_incision(7);
  EXPECT_EQ(halved_again, halved);
  EXPECT_EQ(first.cells, second.cells);
  EXPECT_EQ(first.points, second.points);
}

/// Records the element slots a ConnectivityWatcher is told about (§7.4).
struct SlotRecorder : mesh::ConnectivityWatcher {
  std::vector<Index> slots;
  void element_removed(const mesh::Connectivity&, mesh::ElementHandle e,
                       const mesh::Simplex&) override {
    slots.push_back(e.index);
  }
  void element_added(const mesh::Connectivity&, mesh::ElementHandle e) override {
    slots.push_back(e.index);
  }
  void element_changed(const mesh::Connectivity&, mesh::ElementHandle e,
                       const mesh::Simplex&) override {
    slots.push_back(e.index);
  }
};

TEST(CutRobustness, WatchersSeeExactlyTheReportedElementChanges) {
  // Every edit of the cutter goes through the connectivity, so a watcher (e.g. a solver that
  // updates changed columns) sees the same element slots the step report lists.
  CutMesh m(mesh::make_box(5, 5, 5, 1, 1, 1));
  SlotRecorder rec;
  m.connectivity().add_watcher(&rec);
  Cutter cutter(m, report_only());
  for (const auto& tri : square(Vec3(0.5, 0.5, 0.55), Vec3(0.3, 0.2, 1), 2.0)) {
    rec.slots.clear();
    const auto r = cutter.step(tri[0], tri[1], tri[2]);
    std::sort(rec.slots.begin(), rec.slots.end());
    rec.slots.erase(std::unique(rec.slots.begin(), rec.slots.end()), rec.slots.end());
    EXPECT_EQ(rec.slots, r.changed_elements);
    EXPECT_FALSE(r.changed_elements.empty());
  }
  m.connectivity().remove_watcher(&rec);
}

TEST(CutRobustness, SweepThroughAnEdgeAndAFaceOnly) {
  // A small triangle whose plane contains one mesh edge and crosses only the elements around
  // it: a valid mesh results whatever is selected.
  CutMesh m(mesh::make_box(3, 3, 3, 1, 1, 1));
  Cutter cutter(m, report_only());
  const double h = 1.0 / 3.0;
  const auto r = cutter.step(Vec3(h, h, -0.1), Vec3(h, h, 1.1), Vec3(2 * h, 2 * h, 0.5));
  expect_valid(m, "edge plane");
  EXPECT_EQ(r.status, CutStatus::kOk);
  // Sweep coinciding with an interior face plane x = 1/3 (contains faces of the mesh).
  const auto r2 = cutter.step(Vec3(h, -0.1, -0.1), Vec3(h, 1.2, -0.1), Vec3(h, -0.1, 1.2));
  expect_valid(m, "face plane");
  EXPECT_GT(r2.faces_dissected, 0);
}

TEST(CutRobustness, SweepTangentToABoundaryFace) {
  CutMesh m(mesh::make_box(3, 3, 3, 1, 1, 1));
  Cutter cutter(m, report_only());
  // In the plane z = 0 of the bottom face: nothing may be dissected (already boundary).
  const auto r = cutter.step(Vec3(-0.5, -0.5, 0), Vec3(2, -0.5, 0), Vec3(-0.5, 2, 0));
  expect_valid(m, "tangent");
  EXPECT_EQ(r.faces_dissected, 0);
  EXPECT_EQ(count_components(m), 1);
}

TEST(CutRobustness, SweepExitsAndReentersTheMesh) {
  // A blade moving along x in the plane y = 0.43 while dipping below z = 0 (leaving the box
  // through the bottom) and coming back in.
  CutMesh m(mesh::make_box(6, 3, 3, 2, 1, 1));
  Cutter cutter(m, report_only());
  const double y = 0.43;
  const double depth[] = {0.5, -0.3, -0.3, 0.5, 0.5};
  CutTotals tot;
  for (int s = 0; s + 1 < 5; ++s) {
    const double x0 = 0.45 * s, x1 = 0.45 * (s + 1);
    const Vec3 a(x0, y, 1.2), b(x1, y, 1.2), c(x0, y, depth[s]), d(x1, y, depth[s + 1]);
    tot.add(cutter.step(a, c, d));
    expect_valid(m, "exit/re-enter a");
    tot.add(cutter.step(a, d, b));
    expect_valid(m, "exit/re-enter b");
  }
  EXPECT_GT(tot.faces_dissected, 0);
}

TEST(CutRobustness, RepeatingTheSameSweepIsIdempotentOnTopology) {
  CutMesh m(mesh::make_box(4, 4, 4, 1, 1, 1));
  Cutter cutter(m, report_only());
  const auto sq = square(Vec3(0.5, 0.5, 0.37), Vec3(0.1, -0.2, 1), 0.3);
  for (const auto& tri : sq) (void)cutter.step(tri[0], tri[1], tri[2]);
  const Index nodes = m.num_nodes();
  for (const auto& tri : sq) {
    const auto r = cutter.step(tri[0], tri[1], tri[2]);
    EXPECT_EQ(r.faces_dissected, 0);  // first intersections only: nothing new
  }
  EXPECT_EQ(m.num_nodes(), nodes);
  expect_valid(m, "repeat");
}

/// Random sweep sequences: a blade segment moving through the box in a few steps,
/// each step two sweep triangles; validate after every triangle.
void random_sequences(const mesh::MeshData& data, int sequences, std::mt19937_64& rng,
                      const Vec3& lo, const Vec3& hi) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec3 size = hi - lo;
  CutTotals tot;
  for (int s = 0; s < sequences; ++s) {
    CutMesh m(data);
    for (Index v = 0; v < m.num_nodes(); ++v)
      if (m.reference(v).x() <= lo.x() + 1e-12) m.set_fixed(v, true);
    CutOptions opt;
    opt.seed = rng();
    opt.remove_degeneracies = u(rng) < 0.7;
    opt.snap_nodes = u(rng) < 0.9;
    Cutter cutter(m, opt);
    auto rnd_point = [&] {
      return Vec3(lo.x() + (u(rng) * 1.4 - 0.2) * size.x(),
                  lo.y() + (u(rng) * 1.4 - 0.2) * size.y(),
                  lo.z() + (u(rng) * 1.4 - 0.2) * size.z());
    };
    Vec3 a = rnd_point(), b = rnd_point();
    const int steps = 1 + static_cast<int>(u(rng) * 4);
    for (int k = 0; k < steps; ++k) {
      const Vec3 move = 0.35 * size.norm() * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
      const Vec3 a2 = a + move, b2 = b + move + 0.1 * size.norm() * Vec3(u(rng) - 0.5, 0, 0);
      tot.add(cutter.step(a, b, b2));
      const auto v1 = m.validate();
      ASSERT_TRUE(v1.ok()) << "sequence " << s << " step " << k << ": " << v1.violations[0];
      tot.add(cutter.step(a, b2, a2));
      const auto v2 = m.validate();
      ASSERT_TRUE(v2.ok()) << "sequence " << s << " step " << k << "b: " << v2.violations[0];
      ASSERT_EQ(v2.inverted_reference, 0) << "sequence " << s;
      // Policy kFixOnFace (default): the local component search must leave no free part.
      ASSERT_TRUE(every_component_fixed(m)) << "sequence " << s << " step " << k;
      a = a2;
      b = b2;
    }
  }
  // The sequences must actually cut: a test that never dissects proves nothing.
  // Many random sequences miss or only graze the mesh; a quarter of a face per sequence on
  // average is a loose floor that still fails if cutting silently stops working.
  EXPECT_GT(tot.faces_dissected, sequences / 4);
  EXPECT_GT(tot.nodes_snapped, 0);
  if (sequences >= 100) {
    EXPECT_GT(tot.collapses + tot.incollapsible, 0);  // degeneracy removal is exercised
  }
  std::cout << "sequences " << sequences << ": faces dissected " << tot.faces_dissected
            << ", snapped " << tot.nodes_snapped << ", refused " << tot.snaps_refused
            << ", degenerate " << tot.degenerate_found << ", collapses " << tot.collapses
            << ", incollapsible " << tot.incollapsible << "\n";
  ::testing::Test::RecordProperty("faces_dissected", tot.faces_dissected);
  ::testing::Test::RecordProperty("collapses", tot.collapses);
  ::testing::Test::RecordProperty("incollapsible", tot.incollapsible);
}

TEST(CutRobustness, RandomSweepSequencesOnACube) {
  INCISE_SEEDED_RNG(rng, 3001);
  random_sequences(mesh::make_box(4, 4, 4, 1, 1, 1), sequence_count(1000), rng, Vec3(0, 0, 0),
                   Vec3(1, 1, 1));
}

TEST(CutRobustness, RandomSweepSequencesOnAFiveSplitBrick) {
  INCISE_SEEDED_RNG(rng, 3002);
  random_sequences(mesh::make_box(4, 3, 2, 2, 1.5, 1, mesh::CubeSplit::kFive), sequence_count(300),
                   rng, Vec3(0, 0, 0), Vec3(2, 1.5, 1));
}

/// Elements touched by a step: changed ones and the stars of moved and new nodes.
std::vector<Index> touched_by(const CutMesh& m, const CutStepReport& r) {
  std::vector<Index> out = r.changed_elements;
  for (const auto* list : {&r.moved_nodes, &r.new_nodes})
    for (Index v : *list)
      for (Index e : m.star(v)) out.push_back(e);
  return out;
}

TEST(CutRobustness, RandomSweepSequencesOnTheLiver) {
  // 1000 sequences on the liver (16 597 tets), 20 blocks of 50 sequences that keep cutting
  // the same copy (cuts across earlier cuts). After every sweep triangle the invariants are
  // checked on the touched elements (CutMesh::validate_local); after every block the whole
  // mesh is validated (CutMesh::validate, i.e. mesh::validate).
  INCISE_SEEDED_RNG(rng, 3003);
  const mesh::MeshData liver =
      io::read_mesh(incise::test::source_path("reference_data/meshes/liver_coarse.mesh")).mesh;
  Vec3 lo = liver.points.rowwise().minCoeff(), hi = liver.points.rowwise().maxCoeff();
  const Vec3 size = hi - lo;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const int sequences = sequence_count(1000, 40);  // 16 597 tets: paranoid checks are costly
  const int block = std::min(50, sequences);
  CutTotals tot;
  for (int first = 0; first < sequences; first += block) {
    CutMesh m(liver);
    for (Index v = 0; v < m.num_nodes(); ++v)
      if (m.reference(v).x() < lo.x() + 0.1 * size.x()) m.set_fixed(v, true);
    CutOptions opt;
    opt.seed = rng();
    opt.remove_degeneracies = (first / block) % 4 != 3;  // every fourth block without
    Cutter cutter(m, opt);  // one cutter per block: its search grid is built once
    for (int s = first; s < std::min(sequences, first + block); ++s) {
      cutter.end_incision();  // a new incision: forget intersections of the previous one
      auto rnd_point = [&] {
        return Vec3(lo.x() + u(rng) * size.x(), lo.y() + u(rng) * size.y(),
                    lo.z() + u(rng) * size.z());
      };
      // A blade 0.3·|size| long through a random interior point, moved in 1–4 steps.
      const Vec3 c = rnd_point();
      const Vec3 d = Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized();
      Vec3 a = c - 0.15 * size.norm() * d, b = c + 0.15 * size.norm() * d;
      const int steps = 1 + static_cast<int>(u(rng) * 4);
      for (int k = 0; k < steps; ++k) {
        const Vec3 move = 0.1 * size.norm() * Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
        const Vec3 a2 = a + move, b2 = b + move;
        for (const auto& tri : {std::array<Vec3, 3>{a, b, b2}, std::array<Vec3, 3>{a, b2, a2}}) {
          const CutStepReport r = cutter.step(tri[0], tri[1], tri[2]);
          tot.add(r);
          const CutMeshValidation v = m.validate_local(touched_by(m, r));
          ASSERT_TRUE(v.ok()) << "sequence " << s << ": " << v.violations[0];
          ASSERT_EQ(v.inverted_reference, 0) << "sequence " << s;
        }
        a = a2;
        b = b2;
      }
    }
    const CutMeshValidation v = m.validate();
    ASSERT_TRUE(v.ok()) << "block at " << first << ": " << v.violations[0];
    EXPECT_TRUE(every_component_fixed(m)) << "block at " << first;
  }
  EXPECT_GT(tot.faces_dissected, sequences / 4);  // loose floor: the test must cut
  std::cout << "liver, " << sequences << " sequences: faces dissected " << tot.faces_dissected
            << ", snapped " << tot.nodes_snapped << ", refused " << tot.snaps_refused
            << ", degenerate " << tot.degenerate_found << ", collapses " << tot.collapses
            << ", incollapsible " << tot.incollapsible << "\n";
}

}  // namespace
}  // namespace incise::cut

namespace incise::cut {
namespace {

/// §3.2.3 recipes on a single flat element e = (a, b, c, d) of a jittered 4³ box, made by
/// moving its interior node d (reference = deformed) just off the opposite face abc: near the
/// centroid of abc it is a cap, removed by splitting abc and collapsing into d — e and its
/// neighbour across abc become the neighbour's three pieces: +1 element; near the midpoint of
/// edge ab it makes two spindles (e and its neighbour across dab, both containing d and ab),
/// removed by one split of ab at d — the k elements around ab become 2(k − 2) pieces: k − 4
/// more. A needle collapse or a fallback would change the count
/// differently, so the counts pin down which recipe ran (both recipes were inverted before).
TEST(CutRobustness, CapAndSpindleRecipesRemoveSingleFlatElements) {
  for (const bool cap : {true, false}) {
    // Interior nodes jittered (seeded, ≤ 0.15 h per coordinate; all elements stay positive)
    // so that no other node is coplanar with the flattened element's faces.
    INCISE_SEEDED_RNG(rng, 3211);
    std::uniform_real_distribution<double> jitter(-0.15, 0.15);
    const double h = 1.0 / 4;
    mesh::MeshData box = mesh::make_box(4, 4, 4, 1, 1, 1);
    for (Index v = 0; v < box.num_points(); ++v) {
      const Vec3 x = box.points.col(v);
      if ((x.array() > 1e-9).all() && (x.array() < 1 - 1e-9).all())
        box.points.col(v) += h * Vec3(jitter(rng), jitter(rng), jitter(rng));
    }
    CutMesh m(box);
    ASSERT_EQ(m.validate().inverted_reference, 0);
    auto flat = [&m](Index f) {
      const Tet& t = m.element(f);
      return mesh::aspect_ratio(m.reference(t[0]), m.reference(t[1]), m.reference(t[2]),
                                m.reference(t[3])) < 0.01;  // the §3.3 threshold
    };
    Index k_ab = -1, flat_element = -1;
    for (Index e = 0; e < m.element_capacity() && flat_element < 0; ++e) {
      for (int j = 0; j < 4 && flat_element < 0; ++j) {
        const Index d = m.element(e)[static_cast<size_t>(j)];
        if (m.on_boundary(d) || m.neighbor(e, j) < 0) continue;  // interior d, interior face
        const Index ia = m.element(e)[static_cast<size_t>(mesh::kTetFace[j][0])];
        const Index ib = m.element(e)[static_cast<size_t>(mesh::kTetFace[j][1])];
        const Index ic = m.element(e)[static_cast<size_t>(mesh::kTetFace[j][2])];
        const Vec3 a = m.reference(ia), b = m.reference(ib), c = m.reference(ic);
        Vec3 n = (b - a).cross(c - a).normalized();
        if (n.dot(m.reference(d) - a) < 0) n = -n;  // towards d: inside e
        const Vec3 target =
            cap ? Vec3((a + b + c) / 3 + 1e-3 * h * n)
                : Vec3(0.5 * (a + b) + 1e-3 * h * (n + (c - 0.5 * (a + b)).normalized()));
        const Vec3 X = m.reference(d);
        m.set_position(d, target, target);
        int flats = 0;
        for (Index f : m.star(d)) flats += flat(f) ? 1 : 0;
        bool positive = true;
        for (Index f : m.star(d)) positive = positive && m.reference_volume(m.element(f)) > 0;
        // A cap flattens e alone; a node near the middle of edge ab flattens both elements
        // of its star that contain ab (e and its neighbour across face dab).
        if (flats != (cap ? 1 : 2) || !flat(e) || !positive) {
          m.set_position(d, X, X);
          continue;
        }
        const Tet& t = m.element(e);
        const mesh::ShapeInfo info = mesh::classify_tetrahedron(
            m.reference(t[0]), m.reference(t[1]), m.reference(t[2]), m.reference(t[3]));
        ASSERT_EQ(info.shape, cap ? mesh::ShapeClass::kCap : mesh::ShapeClass::kSpindle);
        k_ab = 0;
        for (Index f : m.star(ia)) k_ab += m.local_index(f, ib) >= 0 ? 1 : 0;
        flat_element = e;
      }
    }
    ASSERT_GE(flat_element, 0) << "no single flat element could be made";
    Cutter cutter(m);
    ASSERT_EQ(cutter.count_degenerate(), cap ? 1 : 2);
    const Index before = m.num_elements();
    CutStepReport r;
    cutter.remove_degeneracies_everywhere(r);
    EXPECT_EQ(r.collapses, 1);
    EXPECT_EQ(r.incollapsible, 0);
    EXPECT_EQ(cutter.count_degenerate(), 0);
    EXPECT_EQ(m.num_elements() - before, cap ? 1 : k_ab - 4) << (cap ? "cap" : "spindle");
    expect_valid(m, cap ? "cap" : "spindle");
  }
}

// Issue 17: the boundary search grid is built once and then updated, not rebuilt: after a
// bulk move of the deformed positions (CutMesh::set_deformed after each solve) only the stars
// of nodes that moved more than CutOptions::search_grid_slack cells from where their elements
// were entered are entered again, and queries are widened by the remaining drift. Three
// cutters see the same positions and random scalpel paths (fixed seed): slack 0 (every element
// with a moved node re-entered: the grid of the current positions, as a rebuild every frame
// would give), the default 0.25, and 4 cells (few re-entries, wide queries). The cuts must be
// identical — reports (faces selected and dissected, changed elements, new nodes) and the
// resulting meshes — with one build each and fewer re-entries for the larger slacks.
TEST(CutRobustness, UpdatedSearchGridCutsLikeTheGridOfTheCurrentPositions) {
  INCISE_SEEDED_RNG(rng, 3017);
  const mesh::MeshData box = mesh::make_box(6, 6, 6, 1, 1, 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Index dissected = 0, selected = 0, intersected = 0;
  std::int64_t reentries[3] = {0, 0, 0};
  for (int sequence = 0; sequence < 6; ++sequence) {
    std::vector<std::unique_ptr<CutMesh>> m;
    std::vector<std::unique_ptr<Cutter>> c;
    for (double slack : {0.0, CutOptions{}.search_grid_slack, 4.0}) {
      m.push_back(std::make_unique<CutMesh>(box));
      for (Index v = 0; v < m.back()->num_nodes(); ++v)
        if (m.back()->reference(v).z() < 1e-12) m.back()->set_fixed(v, true);
      CutOptions o;
      o.search_grid_slack = slack;
      c.push_back(std::make_unique<Cutter>(*m.back(), o));
    }
    Vec3 p(0.2 + 0.1 * u(rng), 0.2 + 0.1 * u(rng), 1.1);
    Vec3 dir = Vec3(u(rng) - 0.5, u(rng) - 0.5, 0).normalized();
    for (int k = 0; k < 12; ++k) {
      // A smooth deformation (det F = 1) of amplitude ≤ 0.3 (≈ 1.8 of the search grid's cells,
      // the mean longest boundary edge ≈ 0.17) that changes every step: bulk moves the grid
      // must follow (with slack 4 the entries stay put and only the widened queries find them).
      const double amp = 0.3 * u(rng), phase = 6.28 * u(rng);
      Eigen::Matrix3Xd x(3, m[0]->num_nodes());
      for (Index v = 0; v < m[0]->num_nodes(); ++v) {
        const Vec3 X = m[0]->reference(v);
        x.col(v) = X + amp * Vec3(std::sin(3 * X.z() + phase), std::cos(2 * X.x() + phase), 0);
      }
      for (auto& mesh : m) mesh->set_deformed(x);
      // A random scalpel path: the blade turns by up to ±0.5 rad per step; every third step
      // begins a new incision elsewhere, whose entry only the search grid can find (the
      // remembered incomplete elements of the last incision are forgotten).
      if (k % 3 == 2) {
        for (auto& cutter : c) cutter->end_incision();
        p = Vec3(0.15 + 0.7 * u(rng), 0.15 + 0.7 * u(rng), 1.1);
      }
      const double turn = u(rng) - 0.5;
      dir = Vec3(std::cos(turn) * dir.x() - std::sin(turn) * dir.y(),
                 std::sin(turn) * dir.x() + std::cos(turn) * dir.y(), 0);
      const Vec3 q = p + 0.08 * dir;
      const Vec3 top(0, 0, 0), tip(0, 0, -0.6);
      for (const auto& tri : {std::array<Vec3, 3>{p + top, p + tip, q + tip},
                              std::array<Vec3, 3>{p + top, q + tip, q + top}}) {
        std::vector<CutStepReport> r;
        for (auto& cutter : c) r.push_back(cutter->step(tri[0], tri[1], tri[2]));
        for (std::size_t i = 1; i < r.size(); ++i) {
          ASSERT_EQ(r[i].faces_selected, r[0].faces_selected)
              << "sequence " << sequence << " k " << k << " cutter " << i;
          ASSERT_EQ(r[i].edges_intersected, r[0].edges_intersected);
          ASSERT_EQ(r[i].faces_dissected, r[0].faces_dissected);
          ASSERT_EQ(r[i].changed_elements, r[0].changed_elements);
          ASSERT_EQ(r[i].new_nodes, r[0].new_nodes);
        }
        dissected += r[0].faces_dissected;
        selected += r[0].faces_selected;
        intersected += r[0].edges_intersected;
      }
      p = q;
    }
    for (std::size_t i = 1; i < m.size(); ++i) {
      const CutMesh &a = *m[0], &b = *m[i];
      ASSERT_EQ(a.num_nodes(), b.num_nodes());
      ASSERT_EQ(a.element_capacity(), b.element_capacity());
      for (Index e = 0; e < a.element_capacity(); ++e) {
        ASSERT_EQ(a.alive(e), b.alive(e));
        if (a.alive(e)) {
          ASSERT_EQ(a.element(e), b.element(e));
        }
      }
      for (Index v = 0; v < a.num_nodes(); ++v) ASSERT_EQ(a.reference(v), b.reference(v));
    }
    for (std::size_t i = 0; i < c.size(); ++i) {
      EXPECT_EQ(c[i]->grid_builds(), 1);  // built at the first step, then updated
      reentries[i] += c[i]->grid_reentries();
    }
    expect_valid(*m[0], "updated grid");
  }
  EXPECT_GT(dissected, 0);                // the sweeps cut (else the comparison proves nothing)
  EXPECT_LT(reentries[1], reentries[0]);  // the slack saves re-entries
  EXPECT_LE(reentries[2], reentries[1]);
  std::cout << "edges intersected " << intersected << ", faces selected " << selected
            << ", dissected " << dissected << ", grid re-entries at slack 0 / "
            << CutOptions{}.search_grid_slack << " / 4 cells: " << reentries[0] << " / "
            << reentries[1] << " / " << reentries[2] << "\n";
}

}  // namespace
}  // namespace incise::cut
