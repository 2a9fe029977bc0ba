// `incise mesh check FILE [--vtu OUT] [--reorient] [--merge-duplicates]`: load a mesh, print
// what the loader found, counts, bounding box and quality, build the connectivity and validate
// the invariants (7.1)-(7.5) of thesis ch. 7. Exit 0 when valid; 1 when unreadable (one line
// "file:line: reason" on stderr); 3 when readable but invalid; 2 on usage errors.

#include <incise/core/error.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/io/write_mesh.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/tet_faces.hpp>
#include <incise/mesh/validate.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <ostream>
#include <set>
#include <sstream>

#include "cli_util.hpp"
#include "commands.hpp"

namespace incise::cli {

namespace {

constexpr int kExitUnreadable = 1;
constexpr int kExitUsage = 2;
constexpr int kExitInvalid = 3;

void mesh_usage(std::ostream& os) {
  os << "usage: incise mesh check FILE [--vtu OUT] [--reorient] [--merge-duplicates]\n"
        "                         [--keep-pinched] [--scale S]\n"
        "  FILE: .msh (Gmsh 2.2/4.1 ASCII), .mesh (Medit), .node/.ele (TetGen), .off\n"
        "  --vtu OUT            write the mesh with quality cell data as VTU (ParaView)\n"
        "  --reorient           flip inverted cells instead of rejecting the file\n"
        "  --merge-duplicates   merge vertices with identical coordinates\n"
        "  --keep-pinched       do not split pinched vertices (star not connected, §7.3)\n"
        "  --scale S            multiply coordinates by S (0.001: millimetres to metres)\n"
        "exit status: 0 valid, 1 unreadable, 2 usage, 3 invalid\n";
}

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

int check(const Args& args, std::ostream& out, std::ostream& err) {
  std::string file, vtu;
  io::ReadOptions options;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& a = args[i];
    if (a == "--vtu" && i + 1 < args.size()) {
      vtu = args[++i];
    } else if (a == "--reorient") {
      options.reorient = true;
    } else if (a == "--merge-duplicates") {
      options.merge_duplicate_vertices = true;
    } else if (a == "--keep-pinched") {
      options.split_pinched_vertices = false;
    } else if (a == "--scale" && i + 1 < args.size()) {
      try {
        options.scale = positive_number(args[++i], "--scale");
      } catch (const UsageError& e) {
        err << "incise mesh check: " << e.what() << "\n";
        return kExitUsage;
      }
    } else if (a == "-h" || a == "--help") {
      mesh_usage(out);
      return 0;
    } else if (!a.empty() && a[0] == '-') {
      err << "incise mesh check: unknown option '" << a << "'\n";
      mesh_usage(err);
      return kExitUsage;
    } else if (file.empty()) {
      file = a;
    } else {
      err << "incise mesh check: more than one FILE given\n";
      return kExitUsage;
    }
  }
  if (file.empty()) {
    mesh_usage(err);
    return kExitUsage;
  }

  io::LoadedMesh loaded;
  try {
    loaded = io::read_mesh(file, options);
  } catch (const ParseError& e) {
    err << e.what() << "\n";
    return kExitUnreadable;
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

  if (!vtu.empty()) {
    const mesh::CellQuality cq = mesh::cell_quality(m, {}, planar);
    const std::vector<io::DataArray> cell_data = io::quality_cell_data(cq);
    io::write_vtu(vtu, m, {}, cell_data);
    out << "wrote:       " << vtu << "\n";
  }

  mesh::Connectivity conn(m.dimension);
  try {
    conn = mesh::Connectivity::from_mesh_data(m);
  } catch (const UsageError& e) {
    out << "validation:  FAILED to build the connectivity\n";
    err << file << ": invalid mesh: " << e.what() << "\n";
    return kExitInvalid;
  }
  mesh::ValidateOptions vo;
  if (planar) vo.positions = &m.points;
  const mesh::ValidationReport v = mesh::validate(conn, vo);
  out << "connectivity: " << conn.num_elements() << " elements, " << conn.num_faces() << " faces, "
      << conn.num_boundary_faces() << " boundary faces";
  out << "\n";
  if (volume && m.facets.cols() > 0) {
    const mesh::FacetCoverage c = mesh::facet_coverage(m.cells, m.facets);
    out << "file facets: " << c.distinct << " distinct, " << c.on_boundary << " on the boundary, "
        << c.interior << " interior (e.g. subdomain interfaces); " << c.boundary_not_listed
        << " boundary faces not listed\n";
  }
  if (!v.ok()) {
    out << "validation:  " << v.violations.size() << " violations\n" << v.summary(20);
    err << file << ": invalid mesh: [" << v.violations.front().invariant << "] "
        << v.violations.front().message << "\n";
    return kExitInvalid;
  }
  out << "validation:  ok ((7.1)-(7.5), mate symmetry, boundary map, connected stars"
      << (planar ? ", orientation" : "") << ")\n";
  return 0;
}

}  // namespace

int run_mesh(const Args& args, std::ostream& out, std::ostream& err) {
  if (args.empty() || args[0] == "-h" || args[0] == "--help") {
    mesh_usage(args.empty() ? err : out);
    return args.empty() ? kExitUsage : 0;
  }
  if (args[0] == "check") return check(Args(args.begin() + 1, args.end()), out, err);
  err << "incise mesh: unknown subcommand '" << args[0] << "'\n";
  mesh_usage(err);
  return kExitUsage;
}

}  // namespace incise::cli
