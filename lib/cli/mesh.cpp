// `incise mesh check FILE [--json] [--vtu OUT] [--reorient] [--merge-duplicates] ...`: load a
// mesh, print what the loader found, counts, bounding box and quality, build the connectivity
// and validate the invariants (7.1)-(7.5) of thesis ch. 7 — as text or, with --json, as one JSON
// document (docs/cli.md, "incise mesh check --json"). Exit 0 when valid; 1 (bad input) when
// unreadable (one line "file:line: reason" on stderr) or readable but invalid; 2 on usage errors.

#include <incise/core/error.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/io/write_mesh.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/tet_faces.hpp>
#include <incise/mesh/validate.hpp>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <memory>
#include <optional>
#include <ostream>
#include <set>
#include <sstream>

#include "cli_util.hpp"
#include "commands.hpp"

namespace incise::cli {

namespace {

std::string labels(const std::map<int, Index>& m) {
  if (m.empty()) return "none";
  std::ostringstream os;
  int shown = 0;
  for (const auto& [tag, n] : m) {
    if (shown++ == 8) {
      os << " ... (" << m.size() << " labels)";
      break;
    }
    os << (shown > 1 ? ", " : "") << tag << ": " << n;
  }
  return os.str();
}

void stats_row(std::ostream& out, const char* name, const mesh::Stats& s) {
  out << "  " << std::left << std::setw(24) << name << std::right << std::setprecision(4)
      << std::setw(11) << s.min << std::setw(11) << s.p05 << std::setw(11) << s.median
      << std::setw(11) << s.p95 << std::setw(11) << s.max << "\n";
}

struct CheckOptions {
  std::string file, vtu, scale = "1";
  bool json = false;
  io::ReadOptions read;
  io::VtuEncoding vtu_format = io::VtuEncoding::kBinaryZlib;
};

nlohmann::json stats_json(const mesh::Stats& s) {
  return {{"min", s.min}, {"p05", s.p05}, {"median", s.median}, {"p95", s.p95}, {"max", s.max}};
}

nlohmann::json labels_json(const std::map<int, Index>& m) {
  nlohmann::json j = nlohmann::json::object();
  for (const auto& [tag, n] : m) j[std::to_string(tag)] = n;
  return j;
}

int check(CheckOptions& opt, Context& ctx) {
  reject_extras(ctx.extras, "mesh check",
                [](const std::string&) { return std::string("more than one FILE given"); });
  io::ReadOptions& options = opt.read;
  options.scale = positive_number(opt.scale, "--scale");
  const std::string& file = opt.file;
  const std::string& vtu = opt.vtu;
  // Text to `out` unless --json; the JSON document is built either way and printed at the end.
  std::ostringstream text;
  std::ostream& out = text;
  nlohmann::json j;
  std::ostream& err = ctx.log.error();
  const auto finish = [&](Exit status) {
    if (opt.json)
      ctx.out << j.dump(2) << "\n";
    else
      ctx.out << text.str();
    return exit_code(status);
  };

  io::LoadedMesh loaded;
  try {
    loaded = io::read_mesh(file, options);
  } catch (const ParseError& e) {
    err << e.what() << "\n";
    return exit_code(Exit::kBadInput);
  }
  const mesh::MeshData& m = loaded.mesh;
  const io::LoadReport& rep = loaded.report;
  const bool volume = m.dimension == 3;
  const char* cell_name = volume ? "tetrahedra" : "triangles";

  out << "file:        " << file << " (" << rep.format << ")\n";
  out << "counts:      " << m.num_points() << " vertices, " << m.num_cells() << " " << cell_name;
  if (volume) out << ", " << rep.num_facets << " boundary triangles listed in the file";
  out << (rep.surface ? " (surface in 3D)" : "") << "\n";
  const auto bb = mesh::bounding_box(m.points);
  out << std::setprecision(6) << "bounding box: [" << bb[0].x() << ", " << bb[0].y() << ", "
      << bb[0].z() << "] - [" << bb[1].x() << ", " << bb[1].y() << ", " << bb[1].z() << "], extent "
      << (bb[1] - bb[0]).x() << " x " << (bb[1] - bb[0]).y() << " x " << (bb[1] - bb[0]).z()
      << "\n";
  out << "units:       file units x " << options.scale
      << " (incise works in metres; --scale converts)\n";
  out << "labels:      cells {" << labels(rep.cell_labels) << "}";
  if (volume) out << ", facets {" << labels(rep.facet_labels) << "}";
  out << ", points {" << labels(rep.point_labels) << "}\n";
  for (const auto& [tag, name] : rep.physical_names)
    out << "             physical " << tag << " = \"" << name << "\"\n";
  out << "loader:      " << rep.reoriented << " reoriented, " << rep.duplicate_vertices
      << " duplicate vertices (" << rep.merged_vertices << " merged), " << rep.unused_vertices
      << " unused vertices, " << rep.pinched_vertices << " pinched vertices split, "
      << rep.ignored_elements << " ignored records\n";
  for (const auto& n : rep.notes) out << "  note: " << n << "\n";
  j["file"] = file;
  j["format"] = rep.format;
  j["dimension"] = m.dimension;
  j["surface"] = rep.surface;
  j["counts"] = {{"vertices", m.num_points()}, {"cells", m.num_cells()}, {"cell_kind", cell_name}};
  if (volume) j["counts"]["boundary_triangles_in_file"] = rep.num_facets;
  j["bounding_box"] = {{"min", {bb[0].x(), bb[0].y(), bb[0].z()}},
                       {"max", {bb[1].x(), bb[1].y(), bb[1].z()}}};
  j["scale"] = options.scale;
  j["labels"] = {{"cells", labels_json(rep.cell_labels)},
                 {"points", labels_json(rep.point_labels)}};
  if (volume) j["labels"]["facets"] = labels_json(rep.facet_labels);
  j["physical_names"] = nlohmann::json::object();
  for (const auto& [tag, name] : rep.physical_names)
    j["physical_names"][std::to_string(tag)] = name;
  j["loader"] = {{"reoriented", rep.reoriented},
                 {"duplicate_vertices", rep.duplicate_vertices},
                 {"merged_vertices", rep.merged_vertices},
                 {"unused_vertices", rep.unused_vertices},
                 {"pinched_vertices_split", rep.pinched_vertices},
                 {"ignored_records", rep.ignored_elements},
                 {"notes", rep.notes}};

  const bool planar = !rep.surface;
  const mesh::QualitySummary q = mesh::summarize_quality(m, {}, planar);
  out << "quality:" << std::left << std::setw(18) << "" << std::right << std::setw(11) << "min"
      << std::setw(11) << "p05" << std::setw(11) << "median" << std::setw(11) << "p95"
      << std::setw(11) << "max\n";
  stats_row(out, volume ? "volume" : "area", q.size);
  stats_row(out, "aspect ratio (3.2.3)", q.aspect_ratio);
  stats_row(out, volume ? "Shewchuk V/A_rms^1.5" : "Shewchuk A/l_rms^2", q.shewchuk);
  stats_row(out, volume ? "min dihedral (deg)" : "min angle (deg)", q.min_angle_deg);
  stats_row(out, volume ? "max dihedral (deg)" : "max angle (deg)", q.max_angle_deg);
  stats_row(out, "edge length", q.edge_length);
  out << std::setprecision(10) << "  total " << (volume ? "volume " : "area ") << q.total_size
      << ", inverted " << q.num_inverted << "; shapes (3.2.3, aspect < 0.01):";
  for (int c = 0; c < 6; ++c)
    out << " " << mesh::to_string(static_cast<mesh::ShapeClass>(c)) << " " << q.shape_counts[c];
  out << "\n";
  nlohmann::json& jq = j["quality"];
  jq[volume ? "volume" : "area"] = stats_json(q.size);
  jq["aspect_ratio"] = stats_json(q.aspect_ratio);
  jq["shewchuk"] = stats_json(q.shewchuk);
  jq[volume ? "min_dihedral_deg" : "min_angle_deg"] = stats_json(q.min_angle_deg);
  jq[volume ? "max_dihedral_deg" : "max_angle_deg"] = stats_json(q.max_angle_deg);
  jq["edge_length"] = stats_json(q.edge_length);
  jq[volume ? "total_volume" : "total_area"] = q.total_size;
  jq["inverted"] = q.num_inverted;
  for (int c = 0; c < 6; ++c)
    jq["shapes"][mesh::to_string(static_cast<mesh::ShapeClass>(c))] = q.shape_counts[c];
  j["wrote"] = nullptr;
  j["valid"] = false;
  j["violations"] = nlohmann::json::array();

  if (!vtu.empty()) {
    const mesh::CellQuality cq = mesh::cell_quality(m, {}, planar);
    const std::vector<io::DataArray> cell_data = io::quality_cell_data(cq);
    io::write_vtu(vtu, m, {}, cell_data, opt.vtu_format);
    out << "wrote:       " << vtu << "\n";
    j["wrote"] = vtu;
  }

  mesh::Connectivity conn(m.dimension);
  try {
    conn = mesh::Connectivity::from_mesh_data(m);
  } catch (const UsageError& e) {
    out << "validation:  FAILED to build the connectivity\n";
    err << file << ": invalid mesh: " << e.what() << "\n";
    j["violations"].push_back({{"invariant", "connectivity"}, {"message", e.what()}});
    return finish(Exit::kBadInput);
  }
  mesh::ValidateOptions vo;
  if (planar) vo.positions = &m.points;
  const mesh::ValidationReport v = mesh::validate(conn, vo);
  out << "connectivity: " << conn.num_elements() << " elements, " << conn.num_faces() << " faces, "
      << conn.num_boundary_faces() << " boundary faces";
  out << "\n";
  j["connectivity"] = {{"elements", conn.num_elements()},
                       {"faces", conn.num_faces()},
                       {"boundary_faces", conn.num_boundary_faces()}};
  if (volume && m.facets.cols() > 0) {
    const mesh::FacetCoverage c = mesh::facet_coverage(m.cells, m.facets);
    j["file_facets"] = {{"distinct", c.distinct},
                        {"on_boundary", c.on_boundary},
                        {"interior", c.interior},
                        {"boundary_not_listed", c.boundary_not_listed}};
    out << "file facets: " << c.distinct << " distinct, " << c.on_boundary << " on the boundary, "
        << c.interior << " interior (e.g. subdomain interfaces); " << c.boundary_not_listed
        << " boundary faces not listed\n";
  }
  if (!v.ok()) {
    // -v: every violation found (validate() stops at ValidateOptions::max_violations).
    out << "validation:  " << v.violations.size() << " violations\n"
        << v.summary(ctx.log.verbosity() == Verbosity::kVerbose ? v.violations.size() : 20);
    err << file << ": invalid mesh: [" << v.violations.front().invariant << "] "
        << v.violations.front().message << "\n";
    for (const auto& x : v.violations)
      j["violations"].push_back({{"invariant", x.invariant}, {"message", x.message}});
    return finish(Exit::kBadInput);
  }
  out << "validation:  ok ((7.1)-(7.5), mate symmetry, boundary map, connected stars"
      << (planar ? ", orientation" : "") << ")\n";
  j["valid"] = true;
  return finish(Exit::kOk);
}

}  // namespace

Command add_mesh_check_command(CLI::App& mesh) {
  auto opt = std::make_shared<CheckOptions>();
  CLI::App* app = mesh.add_subcommand(
      "check", "load a mesh, report counts and quality, validate (7.1)-(7.5) (thesis ch. 7)");
  app->add_option("FILE", opt->file,
                  ".msh (Gmsh 2.2/4.1 ASCII), .mesh (Medit), .node/.ele (TetGen), .off")
      ->required();
  app->add_flag("--json", opt->json,
                "print the report as one JSON document (counts, labels, loader, quality, "
                "validity; docs/cli.md)");
  app->add_option("--vtu", opt->vtu, "write the mesh with quality cell data as VTU (ParaView)")
      ->type_name("OUT");
  add_vtu_format_option(app, &opt->vtu_format);
  app->add_flag("--reorient", opt->read.reorient,
                "flip inverted cells instead of rejecting the file");
  app->add_flag("--merge-duplicates", opt->read.merge_duplicate_vertices,
                "merge vertices with identical coordinates");
  app->add_flag_callback(
      "--keep-pinched", [opt] { opt->read.split_pinched_vertices = false; },
      "do not split pinched vertices (star not connected, 7.3)");
  app->add_option("--scale", opt->scale, "multiply coordinates by S (0.001: millimetres to metres)")
      ->type_name("S");
  return {app, [opt](Context& ctx) { return check(*opt, ctx); }};
}

}  // namespace incise::cli
