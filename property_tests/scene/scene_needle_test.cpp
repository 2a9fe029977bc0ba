// Needle scenes (docs/scenes.md, "Needle scenes"; thesis ch. 6): a `slab2d` mesh with one
// `needle` tool parses into the spec, plans its updates along the path, runs the §6.7 loop
// through run_scene and writes the per-update CSV, the VTU frames and their ParaView index; every
// bad value or 2D/3D mix-up is refused with FILE:LINE, the JSON path and what was expected
// (docs/bad_input.md); numerical failure is a reported status.

#include <incise/core/error.hpp>
#include <incise/io/write_mesh.hpp>
#include <incise/mesh/slab2d.hpp>
#include <incise/scene/scene_outputs.hpp>
#include <incise/scene/scene_parser.hpp>
#include <incise/scene/scene_runner.hpp>

#include <incise_test/files.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "incise_test/seed.hpp"

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using namespace incise;
using scene::MeshSpec;
using scene::parse_scene;
using scene::SolverSpec;
using scene::ToolSpec;

// A small needle scene: the thesis slab at h2 (32 triangles), refined to h4 around the tip, the
// needle along y = 0.05 m from x = 0 to 30 mm at 1 h_ref per update (6 updates).
Json small_needle_scene() {
  return Json::parse(R"({
    "version": 1,
    "name": "small needle",
    "mesh": {"type": "slab2d", "width": 0.1, "height": 0.1, "h_start_level": 2, "thickness": 0.01},
    "material": {"model": "linear", "E": 3.4e4, "nu": 0.34},
    "fixed": [{"type": "plane", "axis": "x", "value": 0.1}],
    "solver": {"method": "cg", "tolerance": 0.01},
    "tools": [{"type": "needle", "path": [[0.0, 0.05], [0.03, 0.05]], "length": 0.1,
               "speed": 1.0, "h_ref_level": 4}]
  })");
}

// A tetrahedral scene to mix with a needle.
Json box_scene() {
  return Json::parse(R"({
    "version": 1,
    "mesh": {"type": "box", "nx": 2, "ny": 2, "nz": 2, "lx": 0.1, "ly": 0.1, "lz": 0.1},
    "material": {"model": "linear", "E": 3.4e4, "nu": 0.34},
    "fixed": [{"type": "plane", "axis": "x", "value": 0.1}],
    "loads": [{"type": "point", "at": [0, 0, 0], "force": [1, 0, 0]}],
    "solver": {"method": "cg"}
  })");
}

std::string error_of(const Json& j) {
  try {
    const scene::SceneSpec s = parse_scene(j.dump(2), "scene.json", "");
    (void)scene::build_scene(s);
  } catch (const ParseError& e) {
    return e.what();
  }
  return "<no error>";
}

// "scene.json:LINE: <path>: <text>" with LINE ≥ 1: the message names the file, a line, the JSON
// path and contains `text`.
void expect_error(const Json& j, const std::string& path, const std::string& text) {
  const std::string e = error_of(j);
  const std::regex located("^scene\\.json:[1-9][0-9]*: ");
  EXPECT_TRUE(std::regex_search(e, located)) << e;
  EXPECT_NE(e.find(": " + path + ": "), std::string::npos) << "expected path " << path << "\n" << e;
  EXPECT_NE(e.find(text), std::string::npos) << "expected \"" << text << "\"\n" << e;
}

fs::path fresh_dir(const std::string& name) {
  return incise::test::fresh_dir("incise_scene_needle_test", name);
}

using incise::test::lines_of;
// The values of the point or cell array named `name` of a VTU file (io::read_vtu, either
// encoding); "types": the VTK cell type of each cell (10 tetrahedra, 5 triangles).
std::vector<double> vtu_array(const fs::path& file, const std::string& name) {
  const io::VtuContents v = io::read_vtu(file.string());
  if (name == "types")
    return std::vector<double>(static_cast<std::size_t>(v.mesh.num_cells()),
                               v.mesh.dimension == 3 ? 10.0 : 5.0);
  for (const auto* arrays : {&v.point_data, &v.cell_data})
    if (const io::DataArray* a = io::VtuContents::find(*arrays, name)) return a->values;
  return {};
}

TEST(SceneNeedle, ShippedSceneParsesIntoTheThesisSlabAndNeedle) {
  const scene::SceneSpec s =
      scene::load_scene(test::source_path("reference_data/scenes/needle_slab.json"));
  EXPECT_EQ(s.mesh.source, MeshSpec::Source::kSlab2d);
  EXPECT_DOUBLE_EQ(s.mesh.width, 0.1);
  EXPECT_DOUBLE_EQ(s.mesh.height, 0.1);
  EXPECT_EQ(s.mesh.h_start_level, 3);
  EXPECT_DOUBLE_EQ(s.mesh.h_start, mesh::thesis_slab_spacing(3));
  EXPECT_DOUBLE_EQ(s.mesh.thickness, 0.01);
  EXPECT_DOUBLE_EQ(s.solver.tolerance, 0.01);
  EXPECT_DOUBLE_EQ(s.solver.tolerance_round, 1e-8);
  ASSERT_NE(s.needle(), nullptr);
  const ToolSpec& t = *s.needle();
  EXPECT_EQ(t.h_ref_level, 6);
  EXPECT_DOUBLE_EQ(t.h_ref, mesh::thesis_slab_spacing(6));
  EXPECT_DOUBLE_EQ(t.speed, 0.3);
  EXPECT_DOUBLE_EQ(t.length, 0.1);
  EXPECT_DOUBLE_EQ(t.friction.shaft_density, 50);
  EXPECT_DOUBLE_EQ(t.friction.tip_density, 150);
  EXPECT_DOUBLE_EQ(t.friction.bulge_length, 0.005);
  EXPECT_DOUBLE_EQ(t.friction.static_factor, 2);
  EXPECT_FALSE(t.relocate);
  EXPECT_EQ(t.max_rearrangements, 100);
  // 70 mm at 0.3 h6 = 0.46875 mm per update: ⌈149.33⌉ = 150 steps after update 0.
  EXPECT_EQ(scene::needle_updates(t).size(), 151u);
}

TEST(SceneNeedle, DefaultsAndLengthFormsOfTheSpacings) {
  Json j = small_needle_scene();
  j["mesh"].erase("h_start_level");
  j["mesh"]["h_start"] = 0.025;
  j["tools"][0].erase("h_ref_level");
  j["tools"][0]["h_ref"] = 0.00625;
  j["tools"][0].erase("length");
  const scene::SceneSpec s = parse_scene(j.dump(), "scene.json", "");
  EXPECT_EQ(s.mesh.h_start_level, 0);
  EXPECT_DOUBLE_EQ(s.mesh.h_start, 0.025);
  EXPECT_DOUBLE_EQ(s.needle()->h_ref, 0.00625);
  EXPECT_DOUBLE_EQ(s.needle()->length, 0.03);  // default: the path's length
  EXPECT_DOUBLE_EQ(s.solver.tolerance_round, 1e-8);
  // The documented defaults (docs/scenes.md, "Needle scenes").
  EXPECT_EQ(s.needle()->friction.shaft_density, 50.0);
  EXPECT_EQ(s.needle()->friction.tip_density, 150.0);
  EXPECT_EQ(s.needle()->friction.bulge_length, 0.005);
  EXPECT_EQ(s.needle()->friction.static_factor, 2.0);
  EXPECT_FALSE(s.needle()->relocate);
  EXPECT_EQ(s.needle()->max_rearrangements, 100);
  EXPECT_EQ(s.solver.max_iterations, 10000);
  EXPECT_EQ(s.solver.tolerance, 0.01);
  EXPECT_EQ(s.solver.method, SolverSpec::Method::kCG);
  j["solver"].erase("tolerance");
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.tolerance, 1e-8);
}

TEST(SceneNeedle, UpdatesAdvanceTheTipAlongThePathAtTheSpeed) {
  ToolSpec t;
  t.kind = ToolSpec::Kind::kNeedle;
  t.path = {Vec3(0, 0.05, 0), Vec3(0.02, 0.05, 0), Vec3(0.02, 0.08, 0)};  // 20 mm, then 30 mm
  t.length = 0.06;
  t.speed = 0.7;
  t.h_ref = 0.005;  // 3.5 mm per update: 50 mm in 14.3 → 15 steps
  const auto plan = scene::needle_updates(t);
  ASSERT_EQ(plan.size(), 16u);
  for (std::size_t k = 0; k < plan.size(); ++k) {
    const double depth = std::min(0.05, 0.0035 * static_cast<double>(k));
    EXPECT_NEAR(plan[k].depth, depth, 1e-15) << k;  // a few roundings of 0.0035·k
    const bool first = depth < 0.02;                // k ≤ 5 on the first segment
    const Vec2 tip = first ? Vec2(depth, 0.05) : Vec2(0.02, 0.05 + depth - 0.02);
    EXPECT_LT((plan[k].pose.tip - tip).norm(), 1e-15) << k;
    EXPECT_EQ(plan[k].pose.direction, first ? Vec2(1, 0) : Vec2(0, 1)) << k;
    EXPECT_EQ(plan[k].pose.length, 0.06);
  }
}

TEST(SceneNeedle, SmallInsertionRunsAndWritesCsvVtuSeriesAndPvd) {
  const fs::path dir = fresh_dir("small");
  Json j = small_needle_scene();
  j["outputs"] = {{"csv", (dir / "updates.csv").string()},
                  {"vtu", (dir / "needle").string()},
                  {"vtu_every", 2}};
  scene::BuiltScene b = scene::build_scene(parse_scene(j.dump(), "scene.json", ""));
  ASSERT_NE(b.needle, nullptr);
  EXPECT_EQ(b.problem, nullptr);
  EXPECT_EQ(b.mesh.num_cells(), 32);  // 2·4² triangles at h2
  ASSERT_EQ(b.needle_plan.size(), 6u);
  scene::FrameWriter frames(b);
  long observed = 0;
  const scene::SceneRunResult res = scene::run_scene(
      b, {}, {},
      [&](const scene::NeedleUpdateRow& row, std::size_t total, const needle::NeedleInsertion& in) {
        EXPECT_EQ(row.update, observed++);
        EXPECT_EQ(total, 6u);
        EXPECT_EQ(row.nodes, in.mesh().connectivity().num_vertices());
        frames.needle_update(row, total, in);
      });
  ASSERT_TRUE(res.report.ok()) << res.report.brief();
  ASSERT_EQ(res.needle_updates.size(), 6u);
  EXPECT_EQ(res.report.iterations, 6);
  // The summary's solver_cpu_seconds: the updates' process CPU, measured (it read 0 before).
  EXPECT_GT(res.report.cpu_seconds, 0.0);
  long cg = 0;
  for (std::size_t k = 0; k < res.needle_updates.size(); ++k) {
    const auto& r = res.needle_updates[k];
    EXPECT_EQ(r.status, "ok");
    EXPECT_DOUBLE_EQ(r.depth, std::min(0.03, 0.00625 * static_cast<double>(k)));
    EXPECT_EQ(r.solves, r.rearrangements + 1);
    if (k > 0) {
      EXPECT_GE(r.triangles, res.needle_updates[k - 1].triangles);  // refined, never coarsened
    }
    cg += r.cg_iterations;
  }
  EXPECT_EQ(res.report.inner_iterations, cg);
  const auto& last = res.needle_updates.back();
  EXPECT_GT(last.sticking + last.slipping, 0);  // the needle holds nodes at 30 mm depth
  EXPECT_GT(last.triangles, 32);                // refined to h4 along the path
  EXPECT_GT(last.needle_force.x(), 0.0);        // the needle pushes the material in +x
  EXPECT_EQ(res.inverted_elements, 0);
  EXPECT_TRUE(std::isfinite(res.report.energy));
  EXPECT_GT(res.report.energy, 0.0);
  // The final mesh is the refined slab; u has z = 0.
  EXPECT_EQ(b.mesh.dimension, 2);
  EXPECT_EQ(b.mesh.num_cells(), last.triangles);
  ASSERT_EQ(res.u.size(), 3 * b.mesh.num_points());
  for (Index v = 0; v < b.mesh.num_points(); ++v) EXPECT_EQ(res.u[3 * v + 2], 0.0);

  // Frames 0, 2, 4 (vtu_every) and 5 (the last), zero-padded to 4 digits; the index lists them.
  EXPECT_EQ(frames.frames(), 4);
  const auto written = scene::write_outputs(b, res, {"", 0.0, frames.frames()});
  ASSERT_EQ(written.size(), 3u);
  EXPECT_EQ(written[2], "4 frames " + (dir / "needle").string() + "_<update>.vtu, index " +
                            (dir / "needle").string() + ".pvd");
  const std::string pvd = incise::test::read_file(dir / "needle.pvd");
  EXPECT_NE(pvd.find("<VTKFile type=\"Collection\""), std::string::npos);
  for (const char* k : {"0", "2", "4", "5"}) {
    const std::string frame = std::string("needle_000") + k + ".vtu";
    EXPECT_NE(pvd.find("timestep=\"" + std::string(k) + "\" group=\"\" part=\"0\" file=\"" + frame +
                       "\""),
              std::string::npos)
        << pvd;
    ASSERT_TRUE(fs::exists(dir / frame)) << frame;
  }
  EXPECT_FALSE(fs::exists(dir / "needle_0001.vtu"));
  // The last frame and the final VTU: triangles (VTK type 5), displacement with z = 0, the
  // needle-node states of the last update.
  for (const fs::path& f : {dir / "needle_0005.vtu", dir / "needle.vtu"}) {
    const fs::path& vtu = f;
    const auto types = vtu_array(vtu, "types");
    ASSERT_EQ(types.size(), static_cast<std::size_t>(last.triangles)) << f;
    for (double t : types) EXPECT_EQ(t, 5.0);
    const auto u = vtu_array(vtu, "displacement");
    ASSERT_EQ(u.size(), static_cast<std::size_t>(3 * last.nodes)) << f;
    for (std::size_t i = 2; i < u.size(); i += 3) EXPECT_EQ(u[i], 0.0);
    const auto state = vtu_array(vtu, "needle_state");
    ASSERT_EQ(state.size(), static_cast<std::size_t>(last.nodes));
    int stick = 0, slip = 0;
    for (double s : state) {
      EXPECT_TRUE(s == 0.0 || s == 1.0 || s == 2.0) << s;
      stick += s == 1.0;
      slip += s == 2.0;
    }
    EXPECT_EQ(stick, last.sticking) << f;
    EXPECT_EQ(slip, last.slipping) << f;
    // The plane-stress fields (docs/mesh_formats.md "Fields"): Σ W·A·d over the triangles is the
    // elastic energy the run reports (the needle acts through constraints: f_ext = 0, Π = Σ A d
    // W₂), computed there by PlaneStressProblem::energy, here from the written cells' W and the
    // file's reference areas. 1e-12 relative: two summation orders of the same ~10² terms.
    const io::VtuContents v = io::read_vtu(vtu.string());
    const auto w = vtu_array(vtu, "strain_energy_density");
    ASSERT_EQ(w.size(), static_cast<std::size_t>(last.triangles)) << f;
    EXPECT_EQ(vtu_array(vtu, "von_mises_stress").size(), w.size()) << f;
    EXPECT_TRUE(vtu_array(vtu, "reaction_force").empty()) << f;
    double energy = 0.0;
    for (Index c = 0; c < v.mesh.num_cells(); ++c) {
      const Vec3 a = v.mesh.points.col(v.mesh.cells(0, c)),
                 b2 = v.mesh.points.col(v.mesh.cells(1, c)),
                 c3 = v.mesh.points.col(v.mesh.cells(2, c));
      energy += w[static_cast<std::size_t>(c)] * 0.5 * (b2 - a).cross(c3 - a).norm() *
                b.spec.mesh.thickness;
    }
    EXPECT_GT(res.report.energy, 0.0);
    EXPECT_NEAR(energy, res.report.energy, 1e-12 * res.report.energy) << f;
  }
  // The CSV: header in the documented order, one row per update.
  const auto csv = lines_of(incise::test::read_file(dir / "updates.csv"));
  ASSERT_EQ(csv.size(), 7u);
  EXPECT_EQ(csv[0],
            "update,depth,tip_x,tip_y,sticking,slipping,rearrangements,cg_iterations,"
            "update_seconds,needle_force_x,needle_force_y,status,solves,max_cg_iterations,"
            "bisections,intercepted,released,nodes,triangles,flops");
  EXPECT_EQ(csv[6].rfind("5,0.03,0.03,0.05,", 0), 0u) << csv[6];
  // The summary JSON names triangles and lists the updates.
  const Json summary = Json::parse(scene::summary_json(b, res, 0.0, written));
  EXPECT_EQ(summary["mesh"]["triangles"], last.triangles);
  ASSERT_EQ(summary["needle_updates"].size(), 6u);
  EXPECT_EQ(summary["needle_updates"][5]["sticking"], last.sticking);
  EXPECT_TRUE(summary["residual_norm"].is_null());  // no single ||f_ext|| for (6.9)
  EXPECT_EQ(summary["status"], "ok");
}

// A solve that cannot converge within the scene's budget and a stick–slip iteration capped at 0
// passes are reported statuses: the run stops at that update and says which.
TEST(SceneNeedle, NumericalFailureIsAReportedStatusNamingTheUpdate) {
  Json j = small_needle_scene();
  j["solver"]["max_iterations"] = 1;
  scene::BuiltScene b = scene::build_scene(parse_scene(j.dump(), "scene.json", ""));
  scene::SceneRunResult res = scene::run_scene(b);
  EXPECT_EQ(res.report.status, solver::StopReason::kMaxIterations);
  ASSERT_FALSE(res.needle_updates.empty());
  EXPECT_LT(res.needle_updates.size(), 6u);
  EXPECT_EQ(res.needle_updates.back().status.rfind("solver-failed: ", 0), 0u)
      << res.needle_updates.back().status;
  EXPECT_NE(res.report.message.find("update " + std::to_string(res.needle_updates.back().update) +
                                    " of 6"),
            std::string::npos)
      << res.report.message;

  j = small_needle_scene();
  j["tools"][0]["max_rearrangements"] = 0;
  b = scene::build_scene(parse_scene(j.dump(), "scene.json", ""));
  res = scene::run_scene(b);
  EXPECT_EQ(res.report.status, solver::StopReason::kMaxIterations);
  EXPECT_NE(res.report.message.find("rearrangement-cycle"), std::string::npos)
      << res.report.message;
}

TEST(SceneNeedleBad, NeedleOnATetrahedralMeshAndScalpelOnTheSlab) {
  // A needle on a tetrahedral mesh is a 3D needle scene (§6.9): loaded by the needle only, its
  // path in [x, y, z].
  Json j = box_scene();
  j["tools"] = small_needle_scene()["tools"];
  expect_error(j, "/loads", "not allowed here: a needle scene is loaded by its needle only");
  j.erase("loads");
  expect_error(j, "/tools/0/path/0", "[x, y, z]");
  j = small_needle_scene();
  j["tools"] = Json::parse(
      R"([{"type": "scalpel", "path": [[0, 0, 0], [0.05, 0, 0]], "blade": [0, 0, -0.01]}])");
  expect_error(j, "/tools/0/type",
               "a scalpel cuts tetrahedral meshes (thesis ch. 3): it needs a \"box\", "
               "\"cylinder\" or \"file\" mesh, got a 2D (plane-stress triangle) mesh of type "
               "\"slab2d\" at /mesh");
}

TEST(SceneNeedleBad, SlabWithoutOneNeedle) {
  Json j = small_needle_scene();
  j.erase("tools");
  expect_error(j, "/tools", "a slab2d mesh is driven by a needle");
  j = small_needle_scene();
  j["tools"].push_back(j["tools"][0]);
  expect_error(j, "/tools/1", "a slab2d scene has exactly one needle");
}

TEST(SceneNeedleBad, SlabSceneRefusesTetrahedralParts) {
  Json j = small_needle_scene();
  j["loads"] = box_scene()["loads"];
  expect_error(j, "/loads", "not allowed here: a needle scene is loaded by its needle only");
  j = small_needle_scene();
  j["solver"]["method"] = "newton";
  expect_error(j, "/solver/method", "a slab2d needle scene is solved by \"cg\" or");
  j = small_needle_scene();
  j["solver"]["method"] = "nonlinear-cg";
  j["solver"]["preconditioner"] = "jacobi";
  expect_error(j, "/solver/preconditioner",
               "not allowed here: in a needle scene only \"cg\" takes a preconditioner");
  j = small_needle_scene();
  j["solver"]["time_budget"] = 1;
  expect_error(j, "/solver/time_budget", "not allowed here: a needle run has no wall-clock");
  j = small_needle_scene();
  j["fixed"][0] = Json::parse(R"({"type": "box", "min": [0, 0, 0], "max": [0.1, 0.01, 0]})");
  expect_error(j, "/fixed/0", "a slab2d scene is held on straight lines");
  j = small_needle_scene();
  j["fixed"][0]["axis"] = "z";
  j["fixed"][0]["value"] = 0.0;
  expect_error(j, "/fixed/0", "a slab2d scene is held on straight lines");
  j = small_needle_scene();
  j["fixed"][0]["tolerance"] = 0.001;
  expect_error(j, "/fixed/0/tolerance", "not allowed here: a slab2d scene holds the nodes");
  j = small_needle_scene();
  j["outputs"] = Json::parse(R"({"probes": [{"name": "p", "at": [0.05, 0.05, 0]}]})");
  expect_error(j, "/outputs/probes", "not allowed here: a needle scene refines its mesh");
  // ... and a tetrahedral scene refuses the slab's keys.
  j = box_scene();
  j["solver"]["tolerance_round"] = 1e-8;
  expect_error(j, "/solver/tolerance_round",
               "not allowed here: only a needle scene (a \"slab2d\" mesh, or a needle tool) has "
               "the rounding term");
  j = box_scene();
  j["mesh"]["thickness"] = 0.01;
  expect_error(j, "/mesh/thickness", "unknown key \"thickness\"");
}

TEST(SceneNeedleBad, SlabValues) {
  Json j = small_needle_scene();
  j["solver"]["threads"] = 2;
  expect_error(j, "/solver/threads", "not allowed here: a needle scene rebuilds its problem");
  j = small_needle_scene();
  j["mesh"]["thickness"] = -0.01;
  expect_error(j, "/mesh/thickness", "expected a number > 0, got -0.01");
  j = small_needle_scene();
  j["mesh"]["h_start"] = 0.025;
  expect_error(j, "/mesh", "expected exactly one of \"h_start\" (a length in m) or");
  j["mesh"].erase("h_start");
  j["mesh"].erase("h_start_level");
  expect_error(j, "/mesh", "expected exactly one of \"h_start\" (a length in m) or");
  j = small_needle_scene();
  j["mesh"]["h_start_level"] = 8;
  expect_error(j, "/mesh/h_start_level", "expected an integer in [1, 7], got 8");
  j = small_needle_scene();  // builder: 0.1 / 0.03 is no integer
  j["mesh"].erase("h_start_level");
  j["mesh"]["h_start"] = 0.03;
  j["tools"][0]["h_ref"] = 0.0075;
  j["tools"][0].erase("h_ref_level");
  expect_error(j, "/mesh/h_start",
               "expected width and height to be integer multiples of h_start = 0.03 m (the slab "
               "is a grid of squares of side h_start; to 1e-9 relative), got width / h_start = "
               "3.33333, height / h_start = 3.33333");
  j = small_needle_scene();  // builder: a spacing whose triangle areas underflow
  j["mesh"] = {{"type", "slab2d"},
               {"width", 1e-199},
               {"height", 1e-199},
               {"h_start", 1e-200},
               {"thickness", 0.01}};
  j["fixed"][0]["value"] = 1e-199;
  j["tools"][0] = {{"type", "needle"},
                   {"path", Json::parse("[[0, 5e-200], [3e-200, 5e-200]]")},
                   {"speed", 1.0},
                   {"h_ref", 1e-200}};
  expect_error(j, "/mesh/h_start", "h_start = 1e-200 m is outside [1e-100, 1e+100] m");
  j = small_needle_scene();  // builder: counts beyond an Index, and beyond the memory budget
  j["mesh"].erase("h_start_level");
  j["mesh"]["h_start"] = 1e-90;
  j["tools"][0].erase("h_ref_level");
  j["tools"][0]["h_ref"] = 1e-90;
  j["tools"][0]["speed"] = 1e85;
  expect_error(j, "/mesh", "/mesh: the slab would have 2e+178 triangles on 1e+178 nodes");
  j["mesh"]["h_start"] = j["tools"][0]["h_ref"] = 1e-4;  // 2·10⁶ triangles
  j["tools"][0]["speed"] = 10;
  j["limits"] = {{"memory_mb", 1}};
  expect_error(j, "/mesh", "/mesh: the slab and its plane-stress problem need an estimated");
  j = small_needle_scene();  // builder: no node on x = 0.09 at h2
  j["fixed"][0]["value"] = 0.09;
  expect_error(j, "/fixed/0", "region selects no node of the mesh");
}

TEST(SceneNeedleBad, NeedleValues) {
  Json j = small_needle_scene();
  j["tools"][0]["h_ref_level"] = 1;  // h1 = 0.05 m > h_start = h2
  expect_error(j, "/tools/0/h_ref_level",
               "h_ref = 0.05 m is larger than the mesh's h_start = 0.025 m (/mesh)");
  j = small_needle_scene();
  j["tools"][0].erase("h_ref_level");
  j["tools"][0]["h_ref"] = 0.025 / 2048;
  expect_error(j, "/tools/0/h_ref", "h_start / h_ref = 2048 is more than 1024");
  j = small_needle_scene();
  j["tools"][0]["path"] = Json::parse("[[0.11, 0.05], [0.2, 0.05]]");
  expect_error(j, "/tools/0/path", "the needle's path never enters the body");
  j["tools"][0]["path"] = Json::parse("[[0.0, 0.0], [0.1, 0.0]]");  // along the boundary only
  expect_error(j, "/tools/0/path", "the needle's path never enters the body");
  j = small_needle_scene();
  j["tools"][0]["path"] = Json::parse("[[0.0, 0.05], [0.0, 0.05]]");
  expect_error(j, "/tools/0/path/1", "the needle path segment from point 0 has zero length");
  j["tools"][0]["path"] = Json::parse("[[0.0, 0.05]]");
  expect_error(j, "/tools/0/path", "expected an array of at least 2 points [[x, y], ...]");
  j["tools"][0]["path"] = Json::parse("[[0.0, 0.05, 0.0], [0.03, 0.05, 0.0]]");
  expect_error(j, "/tools/0/path/0", "expected an array of 2 finite numbers [x, y]");
  j = small_needle_scene();
  j["tools"][0]["length"] = 0;
  expect_error(j, "/tools/0/length", "expected a number > 0, got 0");
  j = small_needle_scene();
  j["tools"][0]["speed"] = -1;
  expect_error(j, "/tools/0/speed", "expected a number > 0, got -1");
  j["tools"][0]["speed"] = 1e-6;
  expect_error(j, "/tools/0/speed", "more than the limit of 1e6");
  j = small_needle_scene();
  j["tools"][0]["blade"] = Json::parse("[0, 0, 1]");
  expect_error(j, "/tools/0/blade", "unknown key \"blade\"");
  j = small_needle_scene();
  j["tools"][0]["max_rearrangements"] = -1;
  expect_error(j, "/tools/0/max_rearrangements", "expected an integer in [0, 100000], got -1");
}

TEST(SceneNeedleBad, FrictionValues) {
  const std::pair<const char*, const char*> cases[] = {
      {"shaft_density", "expected a number >= 0, got -1"},
      {"tip_density", "expected a number >= 0, got -1"},
      {"bulge_length", "expected a number > 0, got -1"},
      {"static_factor", "expected a number >= 1, got -1"},
  };
  for (const auto& [key, text] : cases) {
    Json j = small_needle_scene();
    j["tools"][0]["friction"] = {{key, -1}};
    expect_error(j, std::string("/tools/0/friction/") + key, text);
  }
  Json j = small_needle_scene();
  j["tools"][0]["friction"] = {{"static_factor", 0.5}};
  expect_error(j, "/tools/0/friction/static_factor", "expected a number >= 1, got 0.5");
  j["tools"][0]["friction"] = {{"shaft", 1}};
  expect_error(j, "/tools/0/friction/shaft", "unknown key \"shaft\"");
}

}  // namespace

// --- 3D needle scenes (thesis §6.9; docs/scenes.md "Needle scenes", 3D) ----------------------

namespace {

// A small 3D needle scene: a 0.1 m box of 6·4³ tetrahedra fixed at z = 0, a needle of radius
// 2.5 mm along x at y = 52 mm, z = 49 mm from outside to 40 mm depth, refined to 8 mm.
Json small_needle3d_scene() {
  return Json::parse(R"({
    "version": 1,
    "name": "small 3D needle",
    "mesh": {"type": "box", "nx": 4, "ny": 4, "nz": 4, "lx": 0.1, "ly": 0.1, "lz": 0.1},
    "material": {"model": "linear", "E": 3.4e4, "nu": 0.34},
    "fixed": [{"type": "plane", "axis": "z", "value": 0.0}],
    "solver": {"method": "cg", "tolerance": 0.01},
    "tools": [{"type": "needle", "path": [[-0.01, 0.052, 0.049], [0.04, 0.052, 0.049]],
               "length": 0.1, "radius": 0.0025, "speed": 0.5, "h_ref": 0.008}]
  })");
}

}  // namespace

TEST(SceneNeedle3D, SmallInsertionRunsAndWritesCsvVtuSeriesAndNeedleSurface) {
  const fs::path dir = fresh_dir("small3d");
  Json j = small_needle3d_scene();
  j["outputs"] = {{"csv", (dir / "updates.csv").string()},
                  {"vtu", (dir / "needle").string()},
                  {"vtu_every", 4}};
  scene::BuiltScene b = scene::build_scene(parse_scene(j.dump(), "scene.json", ""));
  ASSERT_NE(b.needle3d, nullptr);
  EXPECT_EQ(b.needle, nullptr);
  EXPECT_EQ(b.problem, nullptr);
  ASSERT_EQ(b.needle_plan.size(), 14u);  // 50 mm at 0.5·8 mm per update: updates 0…13
  EXPECT_DOUBLE_EQ(b.needle3d->options().h_shaft, 0.005);  // default 2·radius
  scene::FrameWriter frames(b);
  const scene::SceneRunResult res =
      scene::run_scene(b, {}, {}, {},
                       [&](const scene::NeedleUpdateRow& row, std::size_t total,
                           const needle::NeedleInsertion3D& in) {
                         EXPECT_EQ(row.nodes, in.mesh().connectivity().num_vertices());
                         frames.needle_update(row, total, in);
                       });
  ASSERT_TRUE(res.report.ok()) << res.report.brief();
  ASSERT_EQ(res.needle_updates.size(), 14u);
  EXPECT_GT(res.report.cpu_seconds, 0.0);  // the summary's solver_cpu_seconds
  for (const auto& r : res.needle_updates) {
    EXPECT_EQ(r.status, "ok");
    EXPECT_GE(r.seconds, r.seconds_refine + r.seconds_solve + r.seconds_rearrange - 1e-9);
  }
  const auto& last = res.needle_updates.back();
  EXPECT_GT(last.sticking + last.slipping, 0);
  EXPECT_GT(last.surface_faces, 0);
  EXPECT_GT(last.triangles, 384);         // refined along the path
  EXPECT_GT(last.needle_force.x(), 0.0);  // the needle drags the material in +x
  EXPECT_EQ(res.inverted_elements, 0);
  EXPECT_EQ(b.mesh.dimension, 3);
  EXPECT_EQ(b.mesh.num_cells(), last.triangles);
  ASSERT_EQ(res.u.size(), 3 * b.mesh.num_points());

  // Frames 0, 4, 8, 12 and 13 (the last), each with its needle surface; two indices.
  EXPECT_EQ(frames.frames(), 5);
  const auto written = scene::write_outputs(b, res, {"", 0.0, frames.frames()});
  ASSERT_EQ(written.size(), 4u);
  EXPECT_EQ(written[2], (dir / "needle_needle.vtu").string());
  // CSV: the 2D columns with "tetrahedra", then the 3D ones.
  const auto csv = lines_of(incise::test::read_file(dir / "updates.csv"));
  ASSERT_EQ(csv.size(), 15u);
  EXPECT_NE(csv[0].find(",nodes,tetrahedra,flops,tip_z,needle_force_z,surface_faces,"
                        "surface_area,refine_seconds,solve_seconds,rearrange_seconds,"
                        "factorizations,replaced_columns"),
            std::string::npos)
      << csv[0];
  for (const char* k : {"0000", "0004", "0008", "0012", "0013"}) {
    EXPECT_TRUE(fs::exists(dir / ("needle_" + std::string(k) + ".vtu"))) << k;
    EXPECT_TRUE(fs::exists(dir / ("needle_needle_" + std::string(k) + ".vtu"))) << k;
  }
  EXPECT_NE(
      incise::test::read_file(dir / "needle_needle.pvd").find("file=\"needle_needle_0013.vtu\""),
      std::string::npos);
  // The final VTU: tetrahedra, the needle-face counts of each; the surface VTU: triangles whose
  // areas sum to the reported surface area.
  const fs::path vtu = dir / "needle.vtu";
  const auto types = vtu_array(vtu, "types");
  ASSERT_EQ(types.size(), static_cast<std::size_t>(last.triangles));
  for (double t : types) EXPECT_EQ(t, 10.0);
  const auto faces = vtu_array(vtu, "needle_faces");
  ASSERT_EQ(faces.size(), types.size());
  double incident = 0.0;
  for (double f : faces) {
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 4.0);
    incident += f;
  }
  // Every needle face lies on one or two tetrahedra.
  EXPECT_GE(incident, last.surface_faces);
  EXPECT_LE(incident, 2.0 * last.surface_faces);
  const fs::path surface = dir / "needle_needle.vtu";
  const auto stypes = vtu_array(surface, "types");
  ASSERT_EQ(stypes.size(), static_cast<std::size_t>(last.surface_faces));
  for (double t : stypes) EXPECT_EQ(t, 5.0);
  double area = 0.0;
  for (double a : vtu_array(surface, "area")) area += a;
  // The same areas summed in the same order, printed with 17 digits: rounding only.
  EXPECT_NEAR(area, last.surface_area, 1e-12 * last.surface_area);
}

// The two speed options of the 3D insertion (docs/needle.md) as tool keys: passed through, and
// refused where they do not apply.
TEST(SceneNeedle3D, AssembledProductAndExtrapolateKeys) {
  Json j = small_needle3d_scene();
  {
    const scene::BuiltScene b = scene::build_scene(parse_scene(j.dump(), "scene.json", ""));
    EXPECT_TRUE(b.needle3d->options().assembled_product);  // the library's default
    EXPECT_FALSE(b.needle3d->options().extrapolate);
  }
  j["tools"][0]["assembled_product"] = false;
  EXPECT_FALSE(scene::build_scene(parse_scene(j.dump(), "scene.json", ""))
                   .needle3d->options()
                   .assembled_product);
  j["tools"][0]["assembled_product"] = true;
  j["tools"][0]["extrapolate"] = true;
  {
    const scene::BuiltScene b = scene::build_scene(parse_scene(j.dump(), "scene.json", ""));
    EXPECT_TRUE(b.needle3d->options().assembled_product);
    EXPECT_TRUE(b.needle3d->options().extrapolate);
  }
  Json n = j;
  n["material"]["model"] = "neohookean";
  n["solver"]["method"] = "nonlinear-cg";  // "cg" is for linear elasticity only
  n["tools"][0].erase("extrapolate");
  expect_error(n, "/tools/0/assembled_product", "needs the \"linear\" material");
  Json c = j;
  c["solver"]["method"] = "nonlinear-cg";
  c["tools"][0].erase("assembled_product");
  expect_error(c, "/tools/0/extrapolate", "for solver \"cg\" only");
  Json s = small_needle_scene();
  s["tools"][0]["assembled_product"] = true;
  expect_error(s, "/tools/0/assembled_product", "not allowed here: a needle in a slab2d scene");
  // The relaxation scenes' solver key (docs/scenes.md, `solver`) is not the needle's: refused
  // in both needle scenes, pointing the 3D one at its tool key.
  Json k = small_needle3d_scene();
  k["solver"]["assembled_product"] = true;
  expect_error(k, "/solver/assembled_product",
               "sets it on its needle (/tools/0/assembled_product)");
  Json ks = small_needle_scene();
  ks["solver"]["assembled_product"] = false;
  expect_error(ks, "/solver/assembled_product", "not allowed here: a slab2d needle scene");
  j["tools"][0]["extrapolate"] = "yes";
  expect_error(j, "/tools/0/extrapolate", "");
}

TEST(SceneNeedle3DBad, PathRadiusFixedAndKeys) {
  // A path that never enters the body.
  Json j = small_needle3d_scene();
  j["tools"][0]["path"] = Json::parse("[[-0.05, 0.05, 0.05], [-0.02, 0.05, 0.05]]");
  expect_error(j, "/tools/0/path", "the needle's path never enters the body");
  // A radius whose refinement cannot fit the budget.
  j = small_needle3d_scene();
  j["tools"][0]["radius"] = 1e-6;
  j["tools"][0]["max_elements"] = 1000;
  expect_error(j, "/tools/0/radius",
               "needle radius 1e-06 m: refining to h_shaft = 2e-06 m (2 radius) along the");
  j["tools"][0]["h_shaft"] = 1e-6;
  expect_error(j, "/tools/0/h_shaft", "more than max_elements = 1000");
  // The 3D needle needs its radius; the slab's needle refuses it.
  j = small_needle3d_scene();
  j["tools"][0].erase("radius");
  expect_error(j, "/tools/0", "radius");
  Json s = small_needle_scene();
  s["tools"][0]["radius"] = 0.001;
  expect_error(s, "/tools/0/radius", "not allowed here: a needle in a slab2d scene is a line");
  // Fixed regions: planes and boxes only.
  j = small_needle3d_scene();
  j["fixed"][0] = Json::parse(R"({"type": "sphere", "center": [0, 0, 0], "radius": 0.02})");
  expect_error(j, "/fixed/0", "a 3D needle scene is held on planes and boxes");
  // One tool; a solver of the projected problem.
  j = small_needle3d_scene();
  j["tools"].push_back(j["tools"][0]);
  expect_error(j, "/tools/1", "a needle scene has exactly one tool");
  j = small_needle3d_scene();
  j["solver"]["method"] = "newton";
  expect_error(j, "/solver/method", "a 3D needle scene is solved by \"cg\", \"nonlinear-cg\" or");
  Json s2 = small_needle_scene();
  s2["solver"] = Json::parse(R"({"method": "augmented"})");
  expect_error(s2, "/solver/method", "a slab2d needle scene is solved by \"cg\" or");
}

// "augmented" in a 3D needle scene: needle::SolvePath3D::kAugmented (Yeung et al. 2016 §3.1).
TEST(SceneNeedle3D, AugmentedSolverKeyRunsTheInsertionAndMatchesCg) {
  Json j = small_needle3d_scene();
  j["solver"] = Json::parse(R"({"method": "augmented", "refactor_at_m": 50})");
  scene::BuiltScene b = scene::build_scene(parse_scene(j.dump(), "scene.json", ""));
  EXPECT_EQ(b.needle3d->options().solve_path, needle::SolvePath3D::kAugmented);
  EXPECT_EQ(b.needle3d->options().refactor_at_m, 50);
  const scene::SceneRunResult res = scene::run_scene(b);
  ASSERT_TRUE(res.report.ok()) << res.report.brief();
  int factorizations = 0;
  for (const auto& r : res.needle_updates) {
    EXPECT_EQ(r.status, "ok");
    EXPECT_EQ(r.cg_iterations, 0);
    factorizations += r.factorizations;
  }
  EXPECT_GT(factorizations, 1);
  EXPECT_GT(res.needle_updates.back().replaced_columns, 0);
  // The same insertion by CG at ε = 1e-9: the same needle force to 1e-6 of its largest value
  // (insertion3d_test's EveryStepEqualsADirectFactorizationAndTightCg bounds the same).
  Json c = small_needle3d_scene();
  c["solver"]["tolerance"] = 1e-9;
  scene::BuiltScene bc = scene::build_scene(parse_scene(c.dump(), "scene.json", ""));
  const scene::SceneRunResult rc = scene::run_scene(bc);
  ASSERT_EQ(rc.needle_updates.size(), res.needle_updates.size());
  double fmax = 0.0, dev = 0.0;
  for (std::size_t k = 0; k < rc.needle_updates.size(); ++k) {
    fmax = std::max(fmax, rc.needle_updates[k].needle_force.norm());
    dev = std::max(dev,
                   (rc.needle_updates[k].needle_force - res.needle_updates[k].needle_force).norm());
  }
  ASSERT_GT(fmax, 0.0);
  EXPECT_LE(dev, 1e-6 * fmax) << dev << " N of " << fmax;
  // Keys: the (6.9) ones and the cutting run's are refused, refactor_at_m >= 1.
  for (const char* key :
       {"tolerance", "tolerance_round", "max_iterations", "cut_configuration", "solve_every"}) {
    Json k = j;
    k["solver"][key] = key == std::string("cut_configuration") ? Json("deformed")
                       : key == std::string("solve_every")     ? Json("segment")
                                                               : Json(1e-3);
    expect_error(k, std::string("/solver/") + key, "not allowed here");
  }
  Json m = j;
  m["solver"]["refactor_at_m"] = 0;
  expect_error(m, "/solver/refactor_at_m", "");
  Json n = j;
  n["material"]["model"] = "neohookean";
  expect_error(n, "/solver/method", "\"augmented\" factorizes the constant linear stiffness");
  Json a = j;
  a["tools"][0]["assembled_product"] = true;
  expect_error(a, "/tools/0/assembled_product", "the \"augmented\" solver factors K instead");
}
