/// Thesis §3.3, Figures 3.14–3.16: a large diagonal cut in the generated cube of 729 nodes and
/// 3072 tetrahedra (make_box(8,8,8) with the 6-tetrahedron split), back face fixed, dilating
/// forces on the side faces, linear elasticity with ν = 1/4, CG stopped at ‖r‖ < 1e-3‖f_ex‖
/// (§3.3). The cut is made twice — without and with degeneracy removal (§3.2.3, aspect ratio
/// 0.01, large angle 0.99π) — and the CG is warm-restarted from the carried displacements.
/// Printed beside the thesis' numbers; see README.md for the comparison and its caveats.
#include <gtest/gtest.h>

#include <incise/io/read_mesh.hpp>

#include "ch3_common.hpp"

#include <incise_test/seed.hpp>

#include <cmath>
#include <cstdio>
#include <random>

namespace incise::verify {
namespace {

// Our CG iterations after the cut, columns (b), (c), (d) of README.md's table.
constexpr long kReadmeItersB = 560, kReadmeItersC = 335, kReadmeItersD = 221;

/// The diagonal cut of README.md with the given options (cube and equilibrium computed once).
CutOutcome run(bool remove_degeneracies, bool refuse_inverting_snaps, bool remark = true) {
  static const Ch3Cube cube;
  EXPECT_TRUE(cube.converged);
  cut::CutOptions opt;
  opt.remove_degeneracies = remove_degeneracies;
  opt.refuse_inverting_snaps = refuse_inverting_snaps;
  opt.remark_snapped_nodes = remark;
  return run_cut(cube, diagonal_blade(), opt);
}

TEST(Nienhuys2003Ch3, LargeDiagonalCutInTheCube) {
  const mesh::MeshData box = mesh::make_box(8, 8, 8, 1, 1, 1);
  ASSERT_EQ(box.num_points(), 729);  // §3.3: 729 nodes
  ASSERT_EQ(box.num_cells(), 3072);  // §3.3: 3072 elements (8³ cubes × 6)

  // Columns: the thesis; (a) thesis-faithful snapping (no refusal), no removal; (b) snaps
  // that would invert refused (§3.4), no removal; (c) = (b) + degeneracy removal; (d) = (a) +
  // degeneracy removal; (e) = (a) without re-marking after snapping (the thesis' order).
  const CutOutcome a = run(false, false), b = run(false, true), c = run(true, true),
                   d = run(true, false), e = run(false, false, false);
  auto it = [](const CutOutcome& o) {
    return o.solve.attempted ? std::to_string(o.solve.iterations) : std::string("n/a");
  };
  std::printf("Thesis §3.3 large diagonal cut, 8x8x8 cube (729 nodes, 3072 tets)\n");
  std::printf("%-30s %7s %7s %7s %7s %7s\n", "quantity", "thesis", "(a)", "(b)", "(c)", "(d)");
  std::printf("%-30s %7d %7d %7d %7d %7d\n", "faces dissected", kThesisFaces,
              a.totals.faces_dissected, b.totals.faces_dissected, c.totals.faces_dissected,
              d.totals.faces_dissected);
  std::printf("%-30s %7s %7d %7d %7d %7d\n", "nodes snapped", "-", a.totals.nodes_snapped,
              b.totals.nodes_snapped, c.totals.nodes_snapped, d.totals.nodes_snapped);
  std::printf("%-30s %7s %7d %7d %7d %7d\n", "snaps refused (would invert)", "-",
              a.totals.snaps_refused, b.totals.snaps_refused, c.totals.snaps_refused,
              d.totals.snaps_refused);
  std::printf("%-30s %7s %7d %7d %7d %7d\n", "snaps failed", "2", a.totals.snaps_failed,
              b.totals.snaps_failed, c.totals.snaps_failed, d.totals.snaps_failed);
  std::printf("%-30s %7d %7d %7d %7d %7d\n", "degenerate found (AR<0.01)", kThesisDegenerate,
              a.degenerate_after, b.degenerate_after, c.totals.degenerate_found,
              d.totals.degenerate_found);
  std::printf("%-30s %7s %7d %7d %7d %7d\n", "inverted elements after cut", "-", a.inverted,
              b.inverted, c.inverted, d.inverted);
  std::printf("%-30s %7d %7s %7s %7d %7d\n", "edge collapses", kThesisCollapses, "-", "-",
              c.totals.collapses, d.totals.collapses);
  std::printf("%-30s %7d %7s %7s %7d %7d\n", "incollapsible (cut free)", kThesisIncollapsible, "-",
              "-", c.totals.incollapsible, d.totals.incollapsible);
  std::printf("%-30s %7d %7d %7d %7d %7d\n", "elements after", kThesisElements, a.elements,
              b.elements, c.elements, d.elements);
  std::printf("%-30s %7d %7d %7d %7d %7d\n", "nodes after", kThesisNodes, a.nodes, b.nodes, c.nodes,
              d.nodes);
  std::printf(
      "%-30s %7s %7s %7s %7s %7s\n", "CG iterations after the cut",
      (std::to_string(kThesisItersWithout) + "/" + std::to_string(kThesisItersWith)).c_str(),
      it(a).c_str(), it(b).c_str(), it(c).c_str(), it(d).c_str());

  std::printf(
      "(e) thesis order, no refusal, no removal: faces %d, snapped %d, failed %d, "
      "degenerate %d, inverted %d, nodes %d, CG %s\n",
      e.totals.faces_dissected, e.totals.nodes_snapped, e.totals.snaps_failed, e.degenerate_after,
      e.inverted, e.nodes, it(e).c_str());

  for (const CutOutcome* o : {&b, &c}) {
    EXPECT_TRUE(o->solve.converged);
    EXPECT_GT(o->totals.faces_dissected, 0);
    EXPECT_EQ(o->inverted, 0);  // refusing inverting snaps keeps every element positive
  }
  // With removal every element below the aspect-ratio threshold is collapsed or cut free.
  EXPECT_EQ(c.degenerate_after, 0);
  EXPECT_EQ(d.degenerate_after, 0);
  // README, "What matches": dissection keeps the element count; refusing inverting snaps
  // lowers the degenerate count ((a) → (b)); thesis-faithful snapping inverts elements and
  // removal repairs them ((a) → (d)); without re-marking fewer faces are dissected ((e) < (a)).
  EXPECT_EQ(a.elements, 3072);
  EXPECT_EQ(b.elements, 3072);
  EXPECT_LT(b.degenerate_after, a.degenerate_after);
  EXPECT_GT(a.inverted, 0);
  EXPECT_EQ(d.inverted, 0);
  EXPECT_LT(e.totals.faces_dissected, a.totals.faces_dissected);

  // README, "removal makes the warm-restarted CG converge faster: 560 → 335" (b → c), and (d)
  // converges in 221. The counts are those of a deterministic solve; ±10 % admits the rounding
  // changes of an element-kernel rewrite (the issue-14 strain form moved (b) from 569 to 560),
  // a larger move means the README's table is stale. The speed-up itself is asserted with
  // margin: removal saves 40 % here, so ≥ 25 % is required.
  ASSERT_TRUE(d.solve.attempted);
  EXPECT_TRUE(d.solve.converged);
  auto near = [](long measured, long documented) {
    return std::abs(double(measured) - double(documented)) <= 0.1 * double(documented);
  };
  EXPECT_TRUE(near(b.solve.iterations, kReadmeItersB)) << b.solve.iterations;
  EXPECT_TRUE(near(c.solve.iterations, kReadmeItersC)) << c.solve.iterations;
  EXPECT_TRUE(near(d.solve.iterations, kReadmeItersD)) << d.solve.iterations;
  EXPECT_LT(double(c.solve.iterations), 0.75 * double(b.solve.iterations));
}

/// §3.3's second experiment: three large pie-like cuts in a Delaunay tetrahedralization of a
/// cylindrical point cloud (4020 elements, 891 vertices): edge collapses ≈ 5 % of the faces
/// dissected (873 faces), "a handful" of incollapsible degeneracies. incise has no 3D Delaunay
/// mesher, so the unstructured liver mesh (16 597 tets) stands in for an orientation-unbiased
/// mesh: three half-plane cuts through the vertical axis of its bounding box, 120° apart.
TEST(Nienhuys2003Ch3, PieCutsInAnUnstructuredMesh) {
  const mesh::MeshData liver =
      io::read_mesh(incise::test::source_path("reference_data/meshes/liver_coarse.mesh")).mesh;
  cut::CutMesh cm(liver);
  const Vec3 lo = liver.points.rowwise().minCoeff(), hi = liver.points.rowwise().maxCoeff();
  const Vec3 c = 0.5 * (lo + hi);
  const double r = (hi - lo).norm();  // reaches beyond the mesh
  cut::CutOptions opt;
  opt.free_components = cut::FreeComponentPolicy::kReport;
  cut::Cutter cutter(cm, opt);
  cut::CutTotals tot;
  for (int k = 0; k < 3; ++k) {
    const double phi = 2.0 * 3.14159265358979323846 * k / 3.0 + 0.1;
    const Vec3 d(std::cos(phi), std::sin(phi), 0.0);
    // Half-plane {c + s·d + t·e_z : s ≥ 0}: one quad of two sweep triangles, from the outside
    // in (the blade enters through the surface), processed as one incision.
    const Vec3 top_out = c + r * d + Vec3(0, 0, r), bot_out = c + r * d - Vec3(0, 0, r);
    const Vec3 top_in = c + Vec3(0, 0, r), bot_in = c - Vec3(0, 0, r);
    tot.add(cutter.step(top_out, bot_out, bot_in));
    tot.add(cutter.step(top_out, bot_in, top_in));
    cutter.end_incision();
    const cut::CutMeshValidation v = cm.validate();
    EXPECT_TRUE(v.ok()) << (v.violations.empty() ? "" : v.violations[0]);
    EXPECT_EQ(v.inverted_reference, 0);
  }
  const double ratio = tot.faces_dissected > 0 ? 100.0 * tot.collapses / tot.faces_dissected : 0;
  std::printf(
      "Pie cuts (thesis: Delaunay cylinder, 873 faces, collapses ~5%% of faces, a "
      "handful incollapsible)\n");
  std::printf(
      "liver: faces dissected %d, degenerate %d, collapses %d (%.1f%% of faces), "
      "incollapsible %d, snaps %d refused %d failed %d\n",
      tot.faces_dissected, tot.degenerate_found, tot.collapses, ratio, tot.incollapsible,
      tot.nodes_snapped, tot.snaps_refused, tot.snaps_failed);
  EXPECT_GT(tot.faces_dissected, 100);
  EXPECT_EQ(cutter.count_degenerate(), 0);
}

/// §3.3's pie cuts on a cylinder like the thesis' object (4020 elements, 891 vertices):
/// make_cylinder(0.1, 0.03, 4, 14) — 4032 tetrahedra, 915 nodes, a structured O-grid (rings of
/// 6k nodes, prisms split by the Dompierre rule), so its element orientations vary around the
/// axis, unlike the cube's six, but it is not Delaunay. Three pie cuts 60° apart (offset
/// 0.1 rad from the grid's ring nodes; slicing a pie: each through the axis, 6 pieces), each a
/// blade parallel to the axis, longer than the cylinder, moved from 1.3 r outside across the
/// axis to 1.3 r on the other side in 7 moves (14 sweep triangles per cut, 42 in all; the
/// thesis used 45).
/// Three pie cuts (see PieCutsInACylinder) on `cyl`; returns the totals.
cut::CutTotals pie_cuts(const mesh::MeshData& cyl, Index& degenerate_left) {
  cut::CutMesh cm(cyl);
  cut::CutOptions opt;
  opt.free_components = cut::FreeComponentPolicy::kReport;
  cut::Cutter cutter(cm, opt);
  cut::CutTotals tot;
  const double r = 0.03;
  constexpr int kMoves = 7;
  for (int k = 0; k < 3; ++k) {
    const double phi = 3.14159265358979323846 * k / 3.0 + 0.1;
    const Vec3 d(0.0, std::cos(phi), std::sin(phi));  // radial direction (axis = x)
    const Vec3 along(0.14, 0, 0);                     // blade length beyond the cylinder
    Vec3 a = Vec3(-0.02, 0, 0) + 1.3 * r * d, b = a + along;
    const Vec3 move = -(2.6 * r / kMoves) * d;
    for (int s = 0; s < kMoves; ++s) {
      const Vec3 a2 = a + move, b2 = b + move;
      tot.add(cutter.step(a, b, b2));
      tot.add(cutter.step(a, b2, a2));
      a = a2;
      b = b2;
    }
    cutter.end_incision();
    const cut::CutMeshValidation v = cm.validate();
    EXPECT_TRUE(v.ok()) << (v.violations.empty() ? "" : v.violations[0]);
    EXPECT_EQ(v.inverted_reference, 0);
  }
  degenerate_left = cutter.count_degenerate();
  return tot;
}

void print_pie(const char* name, const cut::CutTotals& tot) {
  const double ratio = tot.faces_dissected > 0 ? 100.0 * tot.collapses / tot.faces_dissected : 0;
  std::printf(
      "%s: faces dissected %d, degenerate %d, collapses %d (%.1f%% of faces; thesis ~5%% of "
      "873), incollapsible %d, snaps %d refused %d failed %d\n",
      name, tot.faces_dissected, tot.degenerate_found, tot.collapses, ratio, tot.incollapsible,
      tot.nodes_snapped, tot.snaps_refused, tot.snaps_failed);
}

TEST(Nienhuys2003Ch3, PieCutsInACylinder) {
  const mesh::MeshData cyl = mesh::make_cylinder(0.1, 0.03, 4, 14);
  ASSERT_EQ(cyl.num_cells(), 4032);
  ASSERT_EQ(cyl.num_points(), 915);
  Index left = 0;
  const cut::CutTotals tot = pie_cuts(cyl, left);
  print_pie("O-grid cylinder (4032 tets, 915 nodes)", tot);
  EXPECT_GT(tot.faces_dissected, 100);
  EXPECT_EQ(left, 0);

  // The same cylinder with every interior node moved by a seeded random offset of up to 0.3 of
  // the ring spacing in each coordinate (moves that would invert an element are undone): the
  // element orientations lose the O-grid's regularity, closer to a Delaunay mesh of a point
  // cloud.
  INCISE_SEEDED_RNG(rng, 3133);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  mesh::MeshData jit = cyl;
  const double h = 0.03 / 4, amp = 0.3 * h;
  std::vector<std::vector<Index>> star(static_cast<size_t>(jit.num_points()));
  for (Index e = 0; e < jit.num_cells(); ++e)
    for (int k = 0; k < 4; ++k) star[static_cast<size_t>(jit.cells(k, e))].push_back(e);
  auto positive = [&](Index v) {
    for (Index e : star[static_cast<size_t>(v)]) {
      const auto p = [&](int k) -> Vec3 { return jit.points.col(jit.cells(k, e)); };
      if (!((p(1) - p(0)).dot((p(2) - p(0)).cross(p(3) - p(0))) > 0)) return false;
    }
    return true;
  };
  Index moved = 0;
  for (Index v = 0; v < jit.num_points(); ++v) {
    const Vec3 x = jit.points.col(v);
    const bool surface = x.x() < 1e-12 || x.x() > 0.1 - 1e-12 ||
                         std::hypot(x.y(), x.z()) > 0.03 * std::cos(3.14159265358979 / 24) - 1e-9;
    const Vec3 off(u(rng), u(rng), u(rng));
    if (surface) continue;
    jit.points.col(v) = x + amp * off;
    if (positive(v)) {
      ++moved;
    } else {
      jit.points.col(v) = x;
    }
  }
  const cut::CutTotals tj = pie_cuts(jit, left);
  print_pie("jittered cylinder", tj);
  std::printf("  (%d of %d nodes jittered)\n", moved, jit.num_points());
  EXPECT_GT(tj.faces_dissected, 100);
  EXPECT_EQ(left, 0);
}
}  // namespace
}  // namespace incise::verify
