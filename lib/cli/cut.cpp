// `incise cut MESH SWEEPS [--out OUT.vtu] [...]`: cut a tetrahedral mesh along a scalpel sweep
// given as a list of sweep triangles (thesis §3.2; docs/cutting.md), validate the result and
// write it. The cut surfaces are boundary faces of the written mesh (nodes are duplicated
// along them), so they show in ParaView as surfaces.
//
// SWEEPS: a sweep file (io/sweep_file.hpp), coordinates in the mesh file's units (× --scale),
// processed in order; a line "end" finishes an incision (the next triangles start a new one). Exit
// 0 when the result is valid; 1 unreadable input; 2 usage; 3 invalid result.

#include <incise/core/error.hpp>
#include <incise/cut/cutter.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/io/sweep_file.hpp>
#include <incise/io/write_mesh.hpp>

#include <ostream>

#include "cli_util.hpp"
#include "commands.hpp"

namespace incise::cli {

namespace {

void cut_usage(std::ostream& os) {
  os << "usage: incise cut MESH SWEEPS [--out OUT.vtu] [--no-snap] [--no-removal]\n"
        "                  [--allow-inverting-snaps] [--scale S]\n"
        "  MESH     tetrahedral mesh (.msh, .mesh, .node/.ele)\n"
        "  SWEEPS   one sweep triangle per line: ax ay az bx by bz cx cy cz; 'end' ends an\n"
        "           incision; '#' comments\n"
        "  --out    write the cut mesh (reference configuration) as VTU\n"
        "  --scale  multiply mesh and sweep coordinates by S\n"
        "exit status: 0 valid result, 1 unreadable input, 2 usage, 3 invalid result\n";
}

}  // namespace

int run_cut(const Args& args, std::ostream& out, std::ostream& err) {
  std::string mesh_path, sweep_path, out_path;
  cut::CutOptions options;
  double scale = 1.0;
  for (size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--out" && i + 1 < args.size()) {
      out_path = args[++i];
    } else if (a == "--scale" && i + 1 < args.size()) {
      try {
        scale = positive_number(args[++i], "--scale");
      } catch (const UsageError& e) {
        err << "incise cut: " << e.what() << "\n";
        return 2;
      }
    } else if (a == "--no-snap") {
      options.snap_nodes = false;
    } else if (a == "--no-removal") {
      options.remove_degeneracies = false;
    } else if (a == "--allow-inverting-snaps") {
      options.refuse_inverting_snaps = false;
    } else if (a == "--help" || a == "-h") {
      cut_usage(out);
      return 0;
    } else if (!a.empty() && a[0] == '-') {
      cut_usage(err);
      return 2;
    } else if (mesh_path.empty()) {
      mesh_path = a;
    } else if (sweep_path.empty()) {
      sweep_path = a;
    } else {
      cut_usage(err);
      return 2;
    }
  }
  if (mesh_path.empty() || sweep_path.empty() || !(scale > 0)) {
    cut_usage(err);
    return 2;
  }
  options.free_components = cut::FreeComponentPolicy::kReport;
  try {
    io::ReadOptions ro;
    ro.scale = scale;
    const io::LoadedMesh loaded = io::read_mesh(mesh_path, ro);
    if (loaded.mesh.dimension != 3) {
      err << mesh_path << ": not a tetrahedral mesh\n";
      return 1;
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
      io::write_vtu(out_path, mesh.to_mesh_data(false, true));
      out << "wrote " << out_path << "\n";
    }
    return v.ok() ? 0 : 3;
  } catch (const ParseError& e) {
    err << e.what() << "\n";
    return 1;
  }
}

}  // namespace incise::cli
