// Scene outputs (docs/scenes.md, `outputs`): a library caller of run_scene gets the files a scene
// names from FrameWriter (frames during the run) and write_outputs (CSV trace, final VTU, summary
// JSON), each renamed into place, and the list of what was written.

#include <incise/io/write_mesh.hpp>
#include <incise/scene/scene_outputs.hpp>
#include <incise/scene/scene_parser.hpp>
#include <incise/scene/scene_runner.hpp>

#include <incise_test/files.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "incise_test/seed.hpp"

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using namespace incise;

/// An empty folder for one test's files.
fs::path fresh_dir(const std::string& name) {
  return incise::test::fresh_dir("incise_scene_outputs_test", name);
}

using incise::test::lines_of;

/// `index` zero-padded to `width` digits.
std::string padded(long index, std::size_t width) {
  std::string s = std::to_string(index);
  return std::string(width - std::min(width, s.size()), '0') + s;
}
/// Files below `dir` whose name ends in ".tmp" (none may be left behind).
int temporary_files(const fs::path& dir) {
  int n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir)) n += e.path().extension() == ".tmp";
  return n;
}

/// Runs `built` with a FrameWriter on both observers and writes its outputs with a summary.
std::vector<std::string> run_and_write(scene::BuiltScene& built, const std::string& summary,
                                       scene::SceneRunResult& res) {
  scene::FrameWriter frames(built);
  res = scene::run_scene(
      built, [&](const solver::IterationInfo& info) { frames.iteration(info); },
      [&](const scene::CutStepRow& row, std::size_t,
          const interactive::AugmentedCutSession& session) { frames.cut_step(row, session); });
  return scene::write_outputs(built, res, {summary, 1.5, frames.frames()});
}

// The thesis cantilever on a 4x1x1 box by CG, with a trace, frames every 5 iterations, the final
// state and a probe.
TEST(SceneOutputs, RunSceneAndWriteOutputsWriteTheFilesTheSceneNames) {
  const fs::path dir = fresh_dir("cg");
  const std::string csv = (dir / "trace.csv").string(), stem = (dir / "vtu" / "state").string();
  const std::string summary = (dir / "summary" / "run.json").string();
  const Json j = {
      {"mesh",
       {{"type", "box"}, {"nx", 4}, {"ny", 1}, {"nz", 1}, {"lx", 1.2}, {"ly", 0.2}, {"lz", 0.3}}},
      {"material", {{"model", "linear"}, {"E", 1e6}, {"nu", 0.0}}},
      {"fixed", {{{"type", "plane"}, {"axis", "x"}, {"value", 0.0}}}},
      {"loads",
       {{{"type", "nodal"},
         {"region", {{"type", "plane"}, {"axis", "x"}, {"value", 1.2}}},
         {"total_force", {0, -3, 0}}}}},
      {"solver", {{"method", "cg"}}},
      {"outputs",
       {{"csv", csv},
        {"vtu", stem},
        {"vtu_every", 5},
        {"probes", {{{"name", "tip"}, {"at", {1.2, 0.2, 0.3}}}}}}}};
  scene::BuiltScene built = scene::build_scene(scene::parse_scene(j.dump(), "scene.json", ""));
  scene::SceneRunResult res;
  const std::vector<std::string> written = run_and_write(built, summary, res);
  ASSERT_TRUE(res.report.ok());
  ASSERT_GE(res.trace.size(), 6u);  // at least one frame after the initial state

  long frames = 0;
  std::string pvd_files;
  for (const auto& row : res.trace) {
    if (row.iteration % 5 != 0) continue;
    ++frames;
    const std::string name = "state_" + padded(row.iteration, 6) + ".vtu";  // 6 digits
    EXPECT_TRUE(fs::is_regular_file(dir / "vtu" / name)) << name;
    pvd_files += "timestep=\"" + std::to_string(row.iteration) +
                 "\" group=\"\" part=\"0\" file=\"" + name + "\"";
  }
  // The ParaView index lists every frame in order with the iteration as its time.
  const std::string pvd = incise::test::read_file(stem + ".pvd");
  std::string listed;
  for (auto p = pvd.find("timestep="); p != std::string::npos; p = pvd.find("timestep=", p + 1))
    listed += pvd.substr(p, pvd.find("/>", p) - p);
  EXPECT_EQ(listed, pvd_files);
  const std::vector<std::string> expected = {
      csv, stem + ".vtu",
      std::to_string(frames) + " frames " + stem + "_<it>.vtu, index " + stem + ".pvd", summary};
  EXPECT_EQ(written, expected);

  // The trace: a header with the probe's columns, then one row per iteration.
  const std::vector<std::string> rows = lines_of(incise::test::read_file(csv));
  ASSERT_EQ(rows.size(), res.trace.size() + 1);
  EXPECT_EQ(rows[0],
            "iteration,residual_norm,relative_residual,energy,flops,seconds,cpu_seconds,tip_x,"
            "tip_y,tip_z");
  for (std::size_t k = 0; k < res.trace.size(); ++k)
    EXPECT_EQ(rows[k + 1].rfind(std::to_string(res.trace[k].iteration) + ",", 0), 0u)
        << rows[k + 1];

  // The final state: the mesh with its displacement.
  const std::string vtu = incise::test::read_file(stem + ".vtu");
  EXPECT_NE(vtu.find("NumberOfPoints=\"" + std::to_string(built.mesh.num_points()) + "\""),
            std::string::npos);
  EXPECT_NE(vtu.find("Name=\"displacement\""), std::string::npos);

  // The summary names the run and lists the files written before it.
  const Json s = Json::parse(incise::test::read_file(summary));
  EXPECT_EQ(s.at("scene"), "scene.json");
  EXPECT_EQ(s.at("method"), "cg");
  EXPECT_EQ(s.at("result"), "converged");
  EXPECT_EQ(s.at("iterations"), res.report.iterations);
  EXPECT_EQ(s.at("total_seconds"), 1.5);
  EXPECT_EQ(s.at("probes").at(0).at("name"), "tip");
  // The environment of the run (core/environment.hpp), as captured by run_scene.
  for (const auto& [key, value] : res.environment.fields())
    EXPECT_EQ(s.at("environment").at(key), value) << key;
  const std::vector<std::string> before_summary(expected.begin(), expected.end() - 1);
  EXPECT_EQ(s.at("outputs"), Json(before_summary));
  EXPECT_EQ(incise::test::read_file(summary), scene::summary_json(built, res, 1.5, before_summary));
  EXPECT_EQ(temporary_files(dir), 0);
}

// The augmented cutting demo: one CSV row and (vtu_every 1) one frame of the cut mesh per solve.
TEST(SceneOutputs, InteractiveCutRunWritesOneRowAndOneFramePerSolve) {
  const fs::path dir = fresh_dir("cut");
  scene::SceneSpec spec =
      scene::load_scene(test::source_path("reference_data/scenes/cube_cut_augmented.json"));
  spec.outputs.csv = (dir / "steps.csv").string();
  spec.outputs.vtu = (dir / "cube").string();
  spec.outputs.vtu_every = 1;
  scene::BuiltScene built = scene::build_scene(spec);
  scene::SceneRunResult res;
  const std::vector<std::string> written = run_and_write(built, "", res);
  ASSERT_TRUE(res.report.ok());
  EXPECT_GT(res.report.cpu_seconds, 0.0);  // the summary's solver_cpu_seconds (it read 0 before)
  const std::size_t solves = res.cut_steps.size();
  ASSERT_GE(solves, 2u);
  EXPECT_EQ(written,
            (std::vector<std::string>{spec.outputs.csv, spec.outputs.vtu + ".vtu",
                                      std::to_string(solves) + " frames " + spec.outputs.vtu +
                                          "_<step>.vtu, index " + spec.outputs.vtu + ".pvd"}));
  const std::vector<std::string> rows = lines_of(incise::test::read_file(spec.outputs.csv));
  ASSERT_EQ(rows.size(), solves + 1);
  EXPECT_EQ(rows[0].rfind("step,tool,triangles,status,", 0), 0u) << rows[0];
  // Each solve carries whether GMRES ran unpreconditioned (a dropped singular preconditioner)
  // and the amplification of its solution: the columns after the timings, and the summary's
  // cut_steps (with the amplification warning).
  EXPECT_NE(rows[0].find(",update_cpu_seconds,preconditioner_dropped,amplification,swap_seconds"),
            std::string::npos)
      << rows[0];
  // Issue 17: per-frame times (frame = cut + update, after the initial solve) summarized by
  // median, p95 and max; the max equals the largest row, computed here from the rows.
  {
    const Json summary = Json::parse(scene::summary_json(built, res, 0.0, written));
    double max_frame = 0, max_swap = 0;
    for (std::size_t k = 1; k < solves; ++k) {
      max_frame =
          std::max(max_frame, res.cut_steps[k].seconds_cut + res.cut_steps[k].seconds_update);
      max_swap = std::max(max_swap, res.cut_steps[k].seconds_swap);
    }
    const Json& f = summary["frame_seconds"];
    EXPECT_EQ(f["frames"], static_cast<int>(solves) - 1);
    EXPECT_EQ(f["max"], max_frame);
    EXPECT_LE(f["median"].get<double>(), f["p95"].get<double>());
    EXPECT_LE(f["p95"].get<double>(), f["max"].get<double>());
    EXPECT_GT(f["median"].get<double>(), 0.0);
    EXPECT_EQ(summary["swap_seconds"]["max"], max_swap);
    EXPECT_EQ(summary["cut_steps"][1]["swap_seconds"], res.cut_steps[1].seconds_swap);
    // The parts are consistent with the frame: per step the swap is a part of the update, so
    // swap ≤ update ≤ frame and cut ≤ frame step by step, hence for every order statistic.
    for (std::size_t k = 1; k < solves; ++k)
      EXPECT_LE(res.cut_steps[k].seconds_swap, res.cut_steps[k].seconds_update) << "step " << k;
    for (const char* stat : {"median", "p95", "max"}) {
      for (const char* part : {"cut_seconds", "update_seconds"})
        EXPECT_LE(summary[part][stat].get<double>(), f[stat].get<double>()) << part << " " << stat;
      EXPECT_LE(summary["swap_seconds"][stat].get<double>(),
                summary["update_seconds"][stat].get<double>())
          << stat;
    }
  }
  const Json summary = Json::parse(scene::summary_json(built, res, 0.0, written));
  ASSERT_EQ(summary["cut_steps"].size(), solves);
  for (std::size_t k = 0; k < solves; ++k) {
    const Json& c = summary["cut_steps"][k];
    EXPECT_EQ(c["preconditioner_dropped"], res.cut_steps[k].preconditioner_dropped);
    EXPECT_EQ(c["amplification"], res.cut_steps[k].amplification);
    EXPECT_EQ(c["amplification_warning"], res.cut_steps[k].amplification_warning);
    const double rcond = res.cut_steps[k].preconditioner_rcond;  // NaN (none built): null
    if (std::isfinite(rcond)) {
      EXPECT_EQ(c["preconditioner_rcond"], rcond);
    } else {
      EXPECT_TRUE(c["preconditioner_rcond"].is_null());
    }
  }
  // The dropped preconditioner as the run's count (issue 14.3): here none is dropped, and one
  // marked dropped (as AugmentedReport reports a singular H S J) is counted.
  EXPECT_EQ(summary["preconditioner_dropped_solves"], 0);
  scene::SceneRunResult dropped = res;
  dropped.cut_steps[1].preconditioner_dropped = true;
  dropped.cut_steps[1].preconditioner_rcond = 1e-17;
  const Json sd = Json::parse(scene::summary_json(built, dropped, 0.0, written));
  EXPECT_EQ(sd["preconditioner_dropped_solves"], 1);
  EXPECT_EQ(sd["cut_steps"][1]["preconditioner_rcond"], 1e-17);
  EXPECT_GT(res.cut_steps[0].amplification, 0.0);  // the loaded initial solve (steps that
                                                   // change nothing are not solved: 0)
  for (std::size_t k = 0; k < solves; ++k)
    EXPECT_TRUE(
        fs::is_regular_file(spec.outputs.vtu + "_" + padded(static_cast<long>(k), 6) + ".vtu"))
        << k;
  EXPECT_NE(incise::test::read_file(spec.outputs.vtu + ".pvd")
                .find("timestep=\"" + std::to_string(solves - 1) +
                      "\" group=\"\" part=\"0\" file=\"cube_" +
                      padded(static_cast<long>(solves - 1), 6) + ".vtu\""),
            std::string::npos);
  // The final state is on the final cut mesh (the run replaced built.mesh by it).
  EXPECT_NE(incise::test::read_file(spec.outputs.vtu + ".vtu")
                .find("NumberOfPoints=\"" + std::to_string(built.mesh.num_points()) + "\""),
            std::string::npos);
  EXPECT_EQ(temporary_files(dir), 0);
}

// The shipped cantilever (Table 3.1 mesh, CG to 1e-8) at convergence: the final VTU's reaction
// forces at the fixed nodes sum to minus the applied load (global equilibrium: Σ f_int = 0 over
// all nodes and f_int = f_ext at free nodes up to the residual), with the markers and the cell
// fields of docs/mesh_formats.md, in both encodings. Tolerance: ‖r‖ ≤ 1e-8·‖f_ext‖ bounds the
// free-node imbalance by √n·1e-8·‖f_ext‖ ≈ 2e-7 N; 1e-6 N (of 3 N) is above it.
TEST(SceneOutputs, CantileverReactionsBalanceTheLoadInTheFinalVtu) {
  const fs::path dir = fresh_dir("reactions");
  for (const char* format : {"binary", "ascii"}) {
    SCOPED_TRACE(format);
    scene::SceneSpec spec =
        scene::load_scene(test::source_path("reference_data/scenes/cantilever.json"));
    spec.outputs.csv.clear();
    spec.outputs.vtu = (dir / format).string();
    spec.outputs.vtu_format =
        std::string(format) == "ascii" ? io::VtuEncoding::kAscii : io::VtuEncoding::kBinaryZlib;
    scene::BuiltScene built = scene::build_scene(spec);
    scene::SceneRunResult res;
    (void)run_and_write(built, "", res);
    ASSERT_TRUE(res.report.ok()) << res.report.message;
    const std::string text = incise::test::read_file(spec.outputs.vtu + ".vtu");
    EXPECT_EQ(text.find("vtkZLibDataCompressor") != std::string::npos,
              std::string(format) == "binary");
    const io::VtuContents v = io::read_vtu(spec.outputs.vtu + ".vtu");
    const io::DataArray* r = io::VtuContents::find(v.point_data, "reaction_force");
    const io::DataArray* fixed = io::VtuContents::find(v.point_data, "fixed");
    const io::DataArray* loaded = io::VtuContents::find(v.point_data, "loaded");
    const io::DataArray* u = io::VtuContents::find(v.point_data, "displacement");
    ASSERT_TRUE(r && fixed && loaded && u);
    EXPECT_EQ(fixed->type, io::DataArray::Type::kUInt8);
    Vec3 sum = Vec3::Zero();
    long n_fixed = 0, n_loaded = 0;
    for (Index i = 0; i < v.mesh.num_points(); ++i) {
      const Vec3 ri(r->values[3 * i], r->values[3 * i + 1], r->values[3 * i + 2]);
      sum += ri;
      n_fixed += fixed->values[i] != 0;
      n_loaded += loaded->values[i] != 0;
      if (fixed->values[i] == 0) {
        EXPECT_EQ(ri.norm(), 0.0) << "free node " << i;
      }
      EXPECT_EQ(u->values[3 * i + 1], res.u[3 * i + 1]);  // exact in both encodings
    }
    EXPECT_NEAR(sum.y(), 3.0, 1e-6);  // the load is 3 N in −y
    EXPECT_NEAR(sum.x(), 0.0, 1e-6);
    EXPECT_NEAR(sum.z(), 0.0, 1e-6);
    EXPECT_EQ(n_fixed, static_cast<long>(built.fixed_nodes.size()));
    EXPECT_EQ(n_loaded, 5 * 5);  // the nodes of the 4×4-cell loose end
    for (const char* name : {"strain", "second_piola_stress", "cauchy_stress"})
      EXPECT_EQ(io::VtuContents::find(v.cell_data, name)->components, 6) << name;
    for (const char* name : {"von_mises_stress", "strain_energy_density", "inverted"})
      EXPECT_EQ(io::VtuContents::find(v.cell_data, name)->components, 1) << name;
    // Σ W·v(τ) = the elastic energy; with the work f_extᵀu = 2·that at equilibrium (linear
    // model), Π = −½ f_extᵀu: the summary's energy. Tolerance 1e-6 relative (the residual).
    const io::DataArray* w = io::VtuContents::find(v.cell_data, "strain_energy_density");
    double elastic = 0;
    for (Index e = 0; e < v.mesh.num_cells(); ++e)
      elastic += w->values[e] * built.problem->reference(e).volume;
    EXPECT_NEAR(-elastic, res.report.energy, 1e-6 * std::abs(res.report.energy));
  }
}

// A scene without outputs: nothing is written and nothing is listed.
TEST(SceneOutputs, SceneWithoutOutputsWritesNothing) {
  const fs::path dir = fresh_dir("none");
  scene::SceneSpec spec =
      scene::load_scene(test::source_path("reference_data/scenes/cantilever.json"));
  spec.outputs = scene::OutputSpec{};
  spec.mesh.nx = 4, spec.mesh.ny = 1, spec.mesh.nz = 1;
  scene::BuiltScene built = scene::build_scene(spec);
  const fs::path cwd = fs::current_path();
  fs::current_path(dir);  // relative outputs would land here
  scene::SceneRunResult res;
  const std::vector<std::string> written = run_and_write(built, "", res);
  fs::current_path(cwd);
  EXPECT_TRUE(written.empty());
  EXPECT_TRUE(fs::is_empty(dir));
}

}  // namespace
