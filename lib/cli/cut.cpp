// `incise cut MESH SWEEPS [--out OUT.vtu] [...]`: cut a tetrahedral mesh along a scalpel sweep
// given as a list of sweep triangles (thesis §3.2; docs/cutting.md), validate the result and
// write it. The cut surfaces are boundary faces of the written mesh (nodes are duplicated
// along them), so they show in ParaView as surfaces.
//
// SWEEPS: one sweep triangle per line, nine numbers "ax ay az bx by bz cx cy cz" (metres,
// after --scale), processed in order; a line "end" finishes an incision (the next triangles
// start a new one); '#' starts a comment. Exit 0 when the result is valid; 1 unreadable input;
// 2 usage; 3 invalid result.

#include <incise/core/error.hpp>
#include <incise/cut/cutter.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/io/write_mesh.hpp>

#include <fstream>
#include <ostream>
#include <sstream>

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
      scale = std::stod(args[++i]);
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
    std::ifstream in(sweep_path);
    if (!in) {
      err << sweep_path << ": cannot open\n";
      return 1;
    }
    cut::CutTotals totals;
    Index triangles = 0, degenerate = 0, ended = 0;
    std::string line;
    long line_no = 0;
    while (std::getline(in, line)) {
      ++line_no;
      const size_t hash = line.find('#');
      if (hash != std::string::npos) line.resize(hash);
      std::istringstream ls(line);
      std::string first;
      if (!(ls >> first)) continue;
      if (first == "end") {
        cutter.end_incision();
        ++ended;
        continue;
      }
      std::istringstream all(line);
      double v[9];
      for (double& x : v) {
        if (!(all >> x)) {
          err << sweep_path << ":" << line_no << ": expected nine numbers or 'end'\n";
          return 1;
        }
      }
      const cut::CutStepReport r =
          cutter.step(scale * Vec3(v[0], v[1], v[2]), scale * Vec3(v[3], v[4], v[5]),
                      scale * Vec3(v[6], v[7], v[8]));
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
