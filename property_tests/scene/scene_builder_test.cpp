// Scene builder: builds only what the scene names, with loads that integrate exactly.

#include <incise/core/error.hpp>
#include <incise/scene/scene_builder.hpp>
#include <incise/scene/scene_parser.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <string>

#include "incise_test/seed.hpp"

namespace {

using incise::scene::build_scene;
using incise::scene::parse_scene;
using Json = nlohmann::json;

// Load sums are a handful of additions of O(1) numbers: round-off only.
constexpr double kSumTol = 1e-12;

Json cantilever() {
  return Json::parse(R"({
    "mesh": {"type": "box", "nx": 6, "ny": 2, "nz": 3, "lx": 1.2, "ly": 0.2, "lz": 0.3},
    "material": {"model": "linear", "E": 1e6, "nu": 0.0, "rho": 1000},
    "fixed": [{"type": "plane", "axis": "x", "value": 0.0}],
    "loads": [{"type": "nodal", "region": {"type": "plane", "axis": "x", "value": 1.2},
               "total_force": [0, -3, 0]}],
    "solver": {"method": "cg"},
    "outputs": {"probes": [{"name": "tip", "region": {"type": "plane", "axis": "x", "value": 1.2}},
                           {"name": "corner", "at": [1.2, 0.2, 0.3]}]}
  })");
}

incise::scene::BuiltScene build(const Json& j) {
  return build_scene(parse_scene(j.dump(), "scene.json", ""));
}

TEST(SceneBuilder, StaticSceneBuildsNoMassNoFactorization) {
  const auto b = build(cantilever());
  EXPECT_EQ(b.mesh.num_points(), 7 * 3 * 4);
  EXPECT_EQ(b.fixed_nodes.size(), 3u * 4u);  // the x = 0 face of a 6×2×3 grid
  bool mass_skipped = false, factor_skipped = false;
  for (const auto& s : b.not_built) {
    mass_skipped |= s.find("time integrator") != std::string::npos;
    factor_skipped |= s.find("factorization") != std::string::npos;
  }
  EXPECT_TRUE(mass_skipped);
  EXPECT_TRUE(factor_skipped);
  // Nodal load: total force exactly the scene's 3 N, on the 12 tip nodes only.
  Eigen::Vector3d total = Eigen::Vector3d::Zero();
  for (int i = 0; i < b.mesh.num_points(); ++i) total += b.external_force.segment<3>(3 * i);
  EXPECT_NEAR(total[1], -3.0, kSumTol);
  ASSERT_EQ(b.probes.size(), 2u);
  EXPECT_EQ(b.probes[0].nodes.size(), 12u);
  ASSERT_EQ(b.probes[1].nodes.size(), 1u);
  EXPECT_TRUE(b.mesh.points.col(b.probes[1].nodes[0]).isApprox(Eigen::Vector3d(1.2, 0.2, 0.3)));
}

TEST(SceneBuilder, GravityLoadIntegratesDensityTimesVolume) {
  Json j = cantilever();
  j["loads"] = {{{"type", "gravity"}, {"g", {0, 0, -9.8}}}};
  const auto b = build(j);
  double fz = 0;
  for (int i = 0; i < b.mesh.num_points(); ++i) fz += b.external_force[3 * i + 2];
  const double expected = -9.8 * 1000 * 1.2 * 0.2 * 0.3;  // ρ g V of the box
  EXPECT_NEAR(fz / expected, 1.0, kSumTol);
}

TEST(SceneBuilder, DynamicSceneSkipsNothingDynamicAndHasMass) {
  Json j = cantilever();
  j["solver"] = {{"method", "dynamic-ss22"}};
  const auto b = build(j);
  for (const auto& s : b.not_built) EXPECT_EQ(s.find("time integrator"), std::string::npos);
  const auto& m = b.problem->lumped_mass();
  ASSERT_EQ(m.size(), 3 * b.mesh.num_points());
  // Each DOF direction carries the whole mass ρV.
  EXPECT_NEAR(m.sum() / 3.0 / (1000 * 1.2 * 0.2 * 0.3), 1.0, kSumTol);
}

TEST(SceneBuilder, SurfaceTractionIntegratesToTractionTimesArea) {
  Json j = cantilever();
  j["loads"] = {{{"type", "surface"},
                 {"region", {{"type", "plane"}, {"axis", "z"}, {"value", 0.3}}},
                 {"traction", {0, 0, -100}}}};
  const auto b = build(j);
  double fz = 0;
  for (int i = 0; i < b.mesh.num_points(); ++i) fz += b.external_force[3 * i + 2];
  EXPECT_NEAR(fz / (-100 * 1.2 * 0.2), 1.0, kSumTol);
}

TEST(SceneBuilder, ScalpelSweepTriangles) {
  Json j = cantilever();
  j["tools"] = {{{"type", "scalpel"},
                 {"path", {{0.5, -0.1, 0.35}, {0.5, 0.1, 0.35}, {0.6, 0.3, 0.35}}},
                 {"blade", {0, 0, -0.2}}}};
  const auto b = build(j);
  EXPECT_EQ(b.sweep_triangles.size(), 4u);
}

// The shipped cube-cut scene: the scalpel dissects faces (thesis §3.2), adding nodes; the mesh
// stays a valid set of positively oriented tetrahedra and the fixed bottom face stays fixed.
TEST(SceneBuilder, ScalpelCutsTheCube) {
  const auto b = build_scene(
      incise::scene::load_scene(incise::test::source_path("reference_data/scenes/cube_cut.json")));
  EXPECT_GT(b.mesh.num_points(), 9 * 9 * 9);
  EXPECT_EQ(b.mesh.num_cells(), 8 * 8 * 8 * 6);  // no collapses expected away from the cut
  EXPECT_GE(b.fixed_nodes.size(), 81u);
  for (Eigen::Index c = 0; c < b.mesh.cells.cols(); ++c) {
    const Eigen::Vector3d a = b.mesh.points.col(b.mesh.cells(0, c));
    const double v = (b.mesh.points.col(b.mesh.cells(1, c)) - a)
                         .cross(b.mesh.points.col(b.mesh.cells(2, c)) - a)
                         .dot(b.mesh.points.col(b.mesh.cells(3, c)) - a);
    ASSERT_GT(v, 0.0) << "tet " << c;
  }
  bool cut_recorded = false;
  for (const auto& s : b.steps) cut_recorded |= s.what.rfind("cut: ", 0) == 0;
  EXPECT_TRUE(cut_recorded);
}

TEST(SceneBuilderBad, RegionSelectingNoNode) {
  Json j = cantilever();
  j["fixed"][0]["value"] = -1.0;
  try {
    (void)build(j);
    FAIL() << "expected ParseError";
  } catch (const incise::ParseError& e) {
    EXPECT_NE(
        std::string(e.what()).find("scene.json:1: /fixed/0: region selects no node of the mesh"),
        std::string::npos)
        << e.what();
  }
}

TEST(SceneBuilderBad, ProbeOutsideMesh) {
  Json j = cantilever();
  j["outputs"]["probes"][1]["at"] = {5, 0, 0};
  try {
    (void)build(j);
    FAIL() << "expected ParseError";
  } catch (const incise::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("/outputs/probes/1/at: probe location"), std::string::npos)
        << e.what();
  }
}

TEST(SceneBuilderBad, SurfaceLoadWithoutBoundaryTriangle) {
  Json j = cantilever();
  j["loads"] = {{{"type", "surface"},
                 {"region", {{"type", "sphere"}, {"center", {0.6, 0.1, 0.3}}, {"radius", 1e-3}}},
                 {"traction", {0, 0, -100}}}};
  try {
    (void)build(j);
    FAIL() << "expected ParseError";
  } catch (const incise::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("/loads/0/region: region contains no boundary triangle"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
