// `incise cut MESH SWEEPS [--out OUT.vtu] [...]`: cut a tetrahedral mesh along a scalpel sweep
// given as a list of sweep triangles (thesis §3.2; docs/cutting.md), validate the result and
// write it. The cut surfaces are boundary faces of the written mesh (nodes are duplicated
// along them), so they show in ParaView as surfaces.
//
// SWEEPS: a sweep file (io/sweep_file.hpp), coordinates in the mesh file's units (× --scale),
// processed in order; a line "end" finishes an incision (the next triangles start a new one). Exit
// 0 when the result is valid; 1 unreadable input; 2 usage; 3 invalid result (cli_util.hpp Exit;
// a guard: Cutter::step's contract keeps the mesh valid, so no input is known to reach it —
// docs/cli.md, "incise cut and status 3").

#include <incise/core/error.hpp>
#include <incise/cut/cutter.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/io/sweep_file.hpp>
#include <incise/io/write_mesh.hpp>

#include <CLI/CLI.hpp>

#include <memory>
#include <ostream>

#include "cli_util.hpp"
#include "commands.hpp"

namespace incise::cli {

namespace {

struct CutCommandOptions {
  std::string mesh_path, sweep_path, out_path, scale = "1";
  cut::CutOptions options;
  io::VtuEncoding vtu_format = io::VtuEncoding::kBinaryZlib;
};

int cut_command(CutCommandOptions& opt, Context& ctx) {
  reject_extras(ctx.extras, "cut", [](const std::string& a) {
    return "unexpected argument '" + a + "' (expected MESH SWEEPS; see incise cut --help)";
  });
  const double scale = positive_number(opt.scale, "--scale");
  const std::string& mesh_path = opt.mesh_path;
  const std::string& sweep_path = opt.sweep_path;
  const std::string& out_path = opt.out_path;
  cut::CutOptions& options = opt.options;
  std::ostream& out = ctx.out;
  std::ostream& err = ctx.log.error();
  options.free_components = cut::FreeComponentPolicy::kReport;
  try {
    io::ReadOptions ro;
    ro.scale = scale;
    const io::LoadedMesh loaded = io::read_mesh(mesh_path, ro);
    if (loaded.mesh.dimension != 3) {
      err << mesh_path << ": not a tetrahedral mesh\n";
      return exit_code(Exit::kBadInput);
    }
    cut::CutMesh mesh(loaded.mesh);
    cut::Cutter cutter(mesh, options);
    const std::vector<io::SweepEvent> sweep = io::read_sweep_file(sweep_path, scale);
    cut::CutTotals totals;
    Index triangles = 0, degenerate = 0, ended = 0;
    for (const io::SweepEvent& ev : sweep) {
      if (ev.end_incision) {
        cutter.end_incision();
        ++ended;
        continue;
      }
      const cut::CutStepReport r = cutter.step(ev.triangle[0], ev.triangle[1], ev.triangle[2]);
      ++triangles;
      if (r.status == cut::CutStatus::kDegenerateSweep) ++degenerate;
      totals.add(r);
    }
    const cut::CutMeshValidation v = mesh.validate();
    out << "sweep triangles " << triangles << " (degenerate " << degenerate << "), 'end' lines "
        << ended << "\n"
        << "faces selected " << totals.faces_selected << ", dissected " << totals.faces_dissected
        << ", pending " << totals.faces_pending << "\n"
        << "nodes snapped " << totals.nodes_snapped << ", snaps refused " << totals.snaps_refused
        << ", failed " << totals.snaps_failed << "\n"
        << "degenerate " << totals.degenerate_found << ", collapses " << totals.collapses
        << ", incollapsible " << totals.incollapsible << "\n"
        << "new nodes " << totals.new_nodes << ", components without fixed nodes "
        << totals.free_components << " (the mesh file fixes none)"
        << "\n"
        << "result: " << mesh.num_elements() << " elements, valid " << (v.ok() ? "yes" : "NO")
        << "\n";
    for (const auto& s : v.violations) err << "  " << s << "\n";
    if (!out_path.empty()) {
      io::write_vtu(out_path, mesh.to_mesh_data(false, true), {}, {}, opt.vtu_format);
      out << "wrote " << out_path << "\n";
    }
    return exit_code(v.ok() ? Exit::kOk : Exit::kNumericalFailure);
  } catch (const ParseError& e) {
    err << e.what() << "\n";
    return exit_code(Exit::kBadInput);
  }
}

}  // namespace

Command add_cut_command(CLI::App& root) {
  auto opt = std::make_shared<CutCommandOptions>();
  CLI::App* app =
      root.add_subcommand("cut", "cut a tetrahedral mesh along sweep triangles (docs/cutting.md)");
  app->add_option("MESH", opt->mesh_path, "tetrahedral mesh (.msh, .mesh, .node/.ele)")->required();
  app->add_option("SWEEPS", opt->sweep_path,
                  "one sweep triangle per line: ax ay az bx by bz cx cy cz; 'end' ends an "
                  "incision; '#' comments")
      ->required();
  app->add_option("--out", opt->out_path, "write the cut mesh (reference configuration) as VTU")
      ->type_name("OUT.vtu");
  add_vtu_format_option(app, &opt->vtu_format);
  app->add_option("--scale", opt->scale, "multiply mesh and sweep coordinates by S")
      ->type_name("S");
  app->add_flag_callback(
      "--no-snap", [opt] { opt->options.snap_nodes = false; }, "do not snap nodes to the sweep");
  app->add_flag_callback(
      "--no-removal", [opt] { opt->options.remove_degeneracies = false; },
      "keep degenerate elements (no collapse)");
  app->add_flag_callback(
      "--allow-inverting-snaps", [opt] { opt->options.refuse_inverting_snaps = false; },
      "allow snaps that invert an element");
  return {app, [opt](Context& ctx) { return cut_command(*opt, ctx); }};
}

}  // namespace incise::cli
