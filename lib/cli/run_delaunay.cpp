// `incise run` of a Delaunay cutting scene (scene/delaunay_scene.hpp, thesis ch. 5): progress
// lines, the per-movement table's totals and the files written. run.cpp hands a scene over
// here when scene::is_delaunay_scene says its tool is a "scalpel2d" or a "surface_scalpel".

#include <incise/core/error.hpp>
#include <incise/scene/delaunay_scene.hpp>

#include <iostream>
#include <string>

namespace incise::cli {

int run_delaunay_scene_command(const std::string& scene_path, const std::string& summary_json,
                               const std::string& progress, const std::string& csv,
                               std::ostream& out, std::ostream& err) {
  scene::DelaunaySceneSpec spec = scene::load_delaunay_scene(scene_path);
  if (!csv.empty()) spec.csv = csv;
  out << "scene: " << scene_path << (spec.name.empty() ? "" : "  (" + spec.name + ")") << "\n";
  out << "cutter: "
      << (spec.surface ? "delaunay on a surface (SurfaceCutter, thesis 5.3)"
          : spec.cutter == scene::DelaunayCutterKind::kSubdivision
              ? "subdivision (Fig. 5.16 top)"
              : "delaunay in 2D (Cutter2D, thesis 5.2.2)")
      << (spec.has_sheet ? ", cutting a deforming plane-stress sheet (5.5)" : "") << "\n";
  int last_decile = -1;
  auto observer = [&](const scene::DelaunayMovementRow& row, std::size_t total) {
    if (progress == "none") return;
    const int decile = static_cast<int>(10 * (row.movement + 1) / static_cast<long>(total));
    if (decile == last_decile) return;
    last_decile = decile;
    out << "progress " << 10 * decile << "%: movement " << row.movement + 1 << " of " << total
        << ", " << row.triangles << " triangles, status " << row.status << "\n";
  };
  const scene::DelaunayRunResult r = scene::run_delaunay_scene(spec, summary_json, observer);
  out << "\n== summary\n";
  out << "result:          " << r.status << (r.message.empty() ? "" : ": " + r.message) << "\n";
  out << "movements:       " << r.rows.size() << ", " << r.entries << " with an entry, " << r.exits
      << " with an exit, " << r.blocked << " blocked, " << r.lost << " lost\n";
  out << "triangles:       " << r.triangles_before << " -> " << r.triangles_after << " ("
      << (r.triangles_after >= r.triangles_before ? "+" : "")
      << r.triangles_after - r.triangles_before << "), " << r.components << " piece"
      << (r.components == 1 ? "" : "s") << "\n";
  if (!r.rows.empty()) {
    out << "angles:          " << r.rows.back().min_angle << " to " << r.rows.back().max_angle
        << " degrees\n";
    if (spec.has_sheet)
      out << "opening:         " << r.rows.back().opening
          << " m (deformed mouth of the incision)\n";
  }
  out << "time:            " << r.seconds << " s\n";
  out << "== wrote\n";
  for (const auto& w : r.written) out << "  " << w << "\n";
  if (!r.ok()) {
    err << "incise run: no converged solution: " << r.status << ": " << r.message << "\n";
    return 3;
  }
  return 0;
}

}  // namespace incise::cli
