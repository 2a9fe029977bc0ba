// Delaunay cutting scenes (delaunay_scene.hpp, docs/scenes.md "Delaunay cutting scenes").
#include <incise/core/atomic_file.hpp>
#include <incise/core/error.hpp>
#include <incise/core/timer.hpp>
#include <incise/delaunay/scalpel_path.hpp>
#include <incise/delaunay/subdivision.hpp>
#include <incise/delaunay/surface.hpp>
#include <incise/delaunay/surface_cutter.hpp>
#include <incise/delaunay/svg.hpp>
#include <incise/delaunay/triangulation.hpp>
#include <incise/interactive/delaunay_cut_session.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/io/write_mesh.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/scene/delaunay_scene.hpp>
#include <incise/scene/scene_parser.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "json_reader.hpp"
#include "scene_parts.hpp"

namespace incise::scene {

namespace {

using detail::fail;
using detail::Json;
using detail::JsonObject;

constexpr const char* kScalpel2d = "scalpel2d";
constexpr const char* kSurfaceScalpel = "surface_scalpel";
const std::vector<std::string> kShapes = {"cylinder", "bell", "fold"};

delaunay::SurfaceShape shape_of(const std::string& s) {
  if (s == "bell") return delaunay::SurfaceShape::kBell;
  if (s == "fold") return delaunay::SurfaceShape::kFold;
  return delaunay::SurfaceShape::kCylinder;
}

DelaunayMeshSpec parse_mesh(JsonObject o, const std::string& base_dir, bool surface) {
  DelaunayMeshSpec m;
  m.source = o.choice("type", kDelaunayMeshSourceNames);
  switch (m.source) {
    case DelaunayMeshSpec::Source::kRectangle:
      if (surface)
        fail(o.file(), detail::child_path(o.path(), "type"),
             "a \"rectangle\" is planar: a surface_scalpel needs a surface (\"surface\" or a "
             "\"file\" of triangles in 3D)");
      m.nx = o.integer("nx", 1, 1000);
      m.ny = o.integer("ny", 1, 1000);
      m.lx = o.number("lx", detail::positive());
      m.ly = o.number("ly", detail::positive());
      break;
    case DelaunayMeshSpec::Source::kSurface:
      if (!surface)
        fail(o.file(), detail::child_path(o.path(), "type"),
             "a \"surface\" lies in 3D: a scalpel2d needs a planar mesh (\"rectangle\" or a "
             "\"file\" of triangles in z = 0)");
      m.shape = o.choice("shape", kShapes);
      m.nx = o.integer("n", 2, 1000);
      m.ny = o.integer("m", 2, 1000, m.nx);
      break;
    case DelaunayMeshSpec::Source::kFile: {
      const std::string rel = o.string("path");
      const std::string p = detail::child_path(o.path(), "path");
      std::filesystem::path fp(rel);
      if (fp.is_relative() && !base_dir.empty()) fp = std::filesystem::path(base_dir) / fp;
      const std::string ext = fp.extension().string();
      if (ext != ".off" && ext != ".mesh" && ext != ".msh")
        fail(o.file(), p,
             "expected a triangle mesh file ending in .off, .mesh (Medit) or .msh (Gmsh), got \"" +
                 rel + "\"");
      std::error_code ec;
      if (!std::filesystem::is_regular_file(fp, ec))
        fail(o.file(), p, "mesh file not found: " + fp.lexically_normal().string());
      m.file = fp.lexically_normal().string();
      m.scale = o.number("scale", detail::positive(), 1.0);
      break;
    }
  }
  o.finish();
  return m;
}

/// The start mesh; `surface` says whether it must be a surface in 3D. Throws ParseError at
/// /mesh (line added by the caller) when it is not what the scalpel needs.
mesh::MeshData build_mesh(const DelaunayMeshSpec& m, bool surface, const std::string& file) {
  switch (m.source) {
    case DelaunayMeshSpec::Source::kRectangle: return mesh::make_rectangle(m.nx, m.ny, m.lx, m.ly);
    case DelaunayMeshSpec::Source::kSurface:
      return delaunay::make_surface(shape_of(m.shape), m.nx, m.ny);
    case DelaunayMeshSpec::Source::kFile: {
      io::ReadOptions options;
      options.scale = m.scale;
      io::LoadedMesh loaded = io::read_mesh(m.file, options);
      if (loaded.mesh.dimension != 2)
        fail(file, "/mesh/path",
             "expected a triangle mesh, got tetrahedra in " + m.file +
                 " (a Delaunay scene cuts triangle meshes, thesis ch. 5)");
      if (!surface && loaded.report.surface)
        fail(file, "/mesh/path",
             m.file +
                 " is a surface in 3D, not a planar mesh: a scalpel2d cuts planar meshes "
                 "(use a surface_scalpel)");
      return std::move(loaded.mesh);
    }
  }
  throw UsageError("Delaunay mesh source not handled");
}

/// Number of boundary edges of a triangle mesh (edges of one triangle).
Index boundary_edges(const mesh::MeshData& m) {
  std::map<std::pair<Index, Index>, int> count;
  for (Index c = 0; c < m.num_cells(); ++c)
    for (int i = 0; i < 3; ++i) {
      const Index a = m.cells(i, c), b = m.cells((i + 1) % 3, c);
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  return static_cast<Index>(
      std::count_if(count.begin(), count.end(), [](const auto& e) { return e.second == 1; }));
}

/// Mean edge length h̄ of a triangle mesh (each edge once, as the cutters compute it).
double mean_edge(const mesh::MeshData& m) {
  std::set<std::pair<Index, Index>> edges;
  for (Index c = 0; c < m.num_cells(); ++c)
    for (int i = 0; i < 3; ++i) {
      const Index a = m.cells(i, c), b = m.cells((i + 1) % 3, c);
      edges.insert({std::min(a, b), std::max(a, b)});
    }
  double sum = 0;
  for (const auto& [a, b] : edges) sum += (m.points.col(a) - m.points.col(b)).norm();
  return edges.empty() ? 0 : sum / static_cast<double>(edges.size());
}

/// Most movements a scene may plan.
constexpr double kMaxMovements = 1e6;

/// Checks that the start mesh is what the cutter takes, at /mesh, and that the scalpel's
/// movements (samples joined by steps of step · h̄) are at most kMaxMovements, at /tools/0/step.
void check_mesh(const DelaunaySceneSpec& s) {
  const mesh::MeshData m = build_mesh(s.mesh, s.surface, s.file);
  if (s.cutter == DelaunayCutterKind::kDelaunay) {
    const double step = s.step * mean_edge(m);
    double planned = 1;
    auto add = [&](double length) { planned += std::max(1.0, std::ceil(length / step)); };
    for (std::size_t i = 1; i < s.path.size(); ++i) add((s.path[i] - s.path[i - 1]).norm());
    for (std::size_t i = 1; i < s.blade.size(); ++i)
      add(std::max((s.blade[i].head - s.blade[i - 1].head).norm(),
                   (s.blade[i].tail - s.blade[i - 1].tail).norm()));
    if (!(planned <= kMaxMovements)) {
      std::ostringstream os;
      os << "the scalpel's samples joined by movements of step * h = " << step
         << " m (h = the mean edge length of the mesh) take " << planned
         << " movements, more than the limit of 1e6; expected a larger step or a shorter path";
      fail(s.file, "/tools/0/step", os.str());
    }
  }
  try {
    if (s.surface) {
      delaunay::Surface check(m);
    } else {
      delaunay::Triangulation check(m);
    }
  } catch (const Error& e) {
    fail(s.file, "/mesh",
         std::string(s.surface ? "expected an oriented triangle 2-manifold with boundary: "
                               : "expected a planar counter-clockwise triangle mesh: ") +
             e.what());
  }
  if (s.surface && boundary_edges(m) == 0)
    fail(s.file, "/mesh",
         "expected an oriented triangle 2-manifold with boundary, got a closed surface (no "
         "boundary edge for a scalpel to enter at, §5.3)");
}

std::vector<Vec2> parse_path2(const Json& a, const std::string& file, const std::string& path) {
  if (!a.is_array() || a.size() < 2)
    fail(file, path,
         "expected at least two scalpel samples [[x, y], ...] (a scalpel moves between "
         "samples), got " +
             detail::show(a));
  std::vector<Vec2> out;
  for (std::size_t i = 0; i < a.size(); ++i)
    out.push_back(detail::as_vec2(a[i], file, detail::child_path(path, i)));
  return out;
}

std::vector<Vec3> parse_path3(const Json& a, const std::string& file, const std::string& path) {
  if (!a.is_array() || a.size() < 2)
    fail(file, path,
         "expected at least two scalpel samples [[x, y, z], ...] (a scalpel moves between "
         "samples), got " +
             detail::show(a));
  std::vector<Vec3> out;
  for (std::size_t i = 0; i < a.size(); ++i)
    out.push_back(detail::as_vec3(a[i], file, detail::child_path(path, i)));
  return out;
}

void parse_thresholds(JsonObject& o, delaunay::Cutter2DOptions& c) {
  c.short_edge = o.choice("short_edge", kShortEdgeRuleNames, delaunay::ShortEdgeRule::kDistance);
  if (c.short_edge == delaunay::ShortEdgeRule::kAngle) {
    o.forbid("eps_edge", "the \"angle\" rule (§5.5) replaces the distance eps_edge");
    c.min_angle = o.number("min_angle", detail::Range{0, M_PI / 3, true, true}, c.min_angle);
  } else {
    o.forbid("min_angle", "min_angle belongs to \"short_edge\": \"angle\" (§5.5)");
    c.edge = o.number("eps_edge", detail::positive(), c.edge);
  }
  c.entry = o.number("eps_entry", detail::positive(), c.entry);
  c.exit = o.number("eps_exit", detail::positive(), c.exit);
}

SheetSpec parse_sheet(JsonObject o) {
  SheetSpec s;
  s.material =
      detail::parse_material(o.object("material", "a material object {\"model\": ...}"), "");
  s.thickness = o.number("thickness", detail::positive());
  auto line = [&](const Json& j, const std::string& path) {
    JsonObject l(j, path, o.file(), "a line {\"axis\": \"x\" or \"y\", \"value\": m}");
    const std::string axis = l.choice("axis", {"x", "y"});
    const double value = l.number("value", detail::any_finite());
    l.finish();
    return Vec2(axis == "x" ? 0 : 1, value);
  };
  const Json* fixed =
      o.array("fixed", "an array of lines [{\"axis\": ..., \"value\": ...}]", false);
  const std::string fp = detail::child_path(o.path(), "fixed");
  if (fixed->empty())
    fail(o.file(), fp, "expected at least one held line (the sheet is held to be stretched)");
  for (std::size_t i = 0; i < fixed->size(); ++i)
    s.fixed.push_back(line((*fixed)[i], detail::child_path(fp, i)));
  s.loaded = line(o.require("loaded", "a line {\"axis\": ..., \"value\": ...}"),
                  detail::child_path(o.path(), "loaded"));
  s.traction = detail::as_vec2(o.require("traction", "[tx, ty] (Pa)"), o.file(),
                               detail::child_path(o.path(), "traction"));
  if (s.traction.norm() == 0)
    fail(o.file(), detail::child_path(o.path(), "traction"),
         "expected a non-zero traction (the sheet is pre-stretched by it)");
  s.tolerance = o.number("tolerance", detail::Range{0, 1, true, true}, s.tolerance);
  s.max_iterations = o.integer("max_iterations", 1, 100000000, 20000);
  o.finish();
  return s;
}

DelaunaySceneSpec parse_delaunay_root(const Json& root_json, const std::string& file,
                                      const std::string& base_dir) {
  JsonObject root(root_json, "", file,
                  "a Delaunay scene object {\"mesh\": ..., \"tools\": [{\"type\": \"scalpel2d\" "
                  "or \"surface_scalpel\", ...}], ...}");
  DelaunaySceneSpec s;
  s.file = file;
  root.integer("version", 1, 1, 1);
  s.name = root.string("name", "");
  s.description = root.string("description", "");
  const Json* tools = root.array("tools", "an array of one scalpel tool", false);
  if (tools->size() != 1)
    fail(file, "/tools",
         "expected exactly one tool (a scalpel2d or a surface_scalpel), got " +
             std::to_string(tools->size()));
  JsonObject t((*tools)[0], "/tools/0", file, "a tool {\"type\": \"scalpel2d\", ...}");
  s.surface = t.choice("type", {kScalpel2d, kSurfaceScalpel}) == kSurfaceScalpel;
  s.mesh = parse_mesh(root.object("mesh",
                                  "a mesh object {\"type\": \"rectangle\", \"file\" or "
                                  "\"surface\", ...}"),
                      base_dir, s.surface);
  if (s.surface) {
    t.choice("cutter", {"delaunay"}, "delaunay");
    const std::vector<Vec3> head = parse_path3(
        t.require("head", "the scalpel's head samples [[x, y, z], ...]"), file, "/tools/0/head");
    std::vector<Vec3> tail;
    if (t.has("tail")) {
      t.forbid("blade", "give the tail samples or one blade vector, not both");
      tail = parse_path3(*t.get("tail"), file, "/tools/0/tail");
      if (tail.size() != head.size())
        fail(file, "/tools/0/tail",
             "expected as many tail samples as head samples (" + std::to_string(head.size()) +
                 "), got " + std::to_string(tail.size()));
    } else {
      const Vec3 blade = t.vec3("blade");
      if (blade.norm() == 0)
        fail(file, "/tools/0/blade", "expected a non-zero vector from head to tail (m)");
      for (const Vec3& h : head) tail.push_back(h + blade);
    }
    for (std::size_t i = 0; i < head.size(); ++i) {
      if ((head[i] - tail[i]).norm() == 0)
        fail(file, "/tools/0/tail/" + std::to_string(i),
             "expected a scalpel of non-zero length (tail != head)");
      s.blade.push_back({head[i], tail[i]});
    }
  } else {
    s.cutter = t.choice("cutter", kDelaunayCutterNames, DelaunayCutterKind::kDelaunay);
    s.path =
        parse_path2(t.require("path", "the scalpel samples [[x, y], ...]"), file, "/tools/0/path");
  }
  if (s.cutter == DelaunayCutterKind::kSubdivision) {
    for (const char* k : {"step", "eps_edge", "eps_entry", "eps_exit", "short_edge", "min_angle"})
      t.forbid(k, "the subdivision cutter cuts the whole path at once, without thresholds");
  } else {
    s.step = t.number("step", detail::positive(), s.step);
    parse_thresholds(t, s.options);
  }
  t.finish();
  if (const Json* sheet = root.get("sheet")) {
    if (s.surface || s.cutter != DelaunayCutterKind::kDelaunay)
      fail(file, "/sheet",
           "not allowed here: a deforming sheet (§5.5) is cut by a scalpel2d with the "
           "\"delaunay\" cutter");
    s.has_sheet = true;
    s.sheet = parse_sheet(JsonObject(*sheet, "/sheet", file, "a sheet object {\"material\": ...}"));
  }
  if (const Json* out = root.get("outputs")) {
    JsonObject o(*out, "/outputs", file, "an outputs object {\"csv\": ..., \"vtu\": ...}");
    s.csv = o.string("csv", "");
    s.vtu = o.string("vtu", "");
    s.vtu_every = o.integer("vtu_every", 1, 1000000, 1);
    if (s.surface)
      o.forbid("svg", "the SVG picture (Fig. 5.16) is of a planar mesh; a surface has the VTU");
    else
      s.svg = o.string("svg", "");
    o.finish();
  }
  root.finish();
  check_mesh(s);
  return s;
}

// ---- running -------------------------------------------------------------------------------

/// Vertices of live triangles.
template <class Mesh>
Index live_vertices(const Mesh& m) {
  std::set<Index> v;
  for (const auto& e : m.connectivity().elements())
    for (const Index i : m.triangle(e)) v.insert(i);
  return static_cast<Index>(v.size());
}

/// Connected pieces (triangles joined across shared edges).
template <class Mesh>
int pieces(const Mesh& m) {
  std::vector<std::array<Index, 3>> tris;
  for (const auto& e : m.connectivity().elements()) tris.push_back(m.triangle(e));
  std::vector<int> parent(tris.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<int>(i);
  std::function<int(int)> find = [&](int x) {
    while (parent[static_cast<std::size_t>(x)] != x)
      x = parent[static_cast<std::size_t>(x)] =
          parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
    return x;
  };
  std::map<std::pair<Index, Index>, int> first;
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int i = 0; i < 3; ++i) {
      const Index a = tris[t][static_cast<std::size_t>(i)],
                  b = tris[t][static_cast<std::size_t>((i + 1) % 3)];
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = first.find(key);
      if (it == first.end())
        first.emplace(key, static_cast<int>(t));
      else
        parent[static_cast<std::size_t>(find(static_cast<int>(t)))] = find(it->second);
    }
  int n = 0;
  for (std::size_t i = 0; i < parent.size(); ++i)
    n += find(static_cast<int>(i)) == static_cast<int>(i);
  return n;
}

template <class Mesh>
void fill_mesh_columns(const Mesh& m, DelaunayMovementRow& row) {
  row.triangles = m.num_triangles();
  row.vertices = live_vertices(m);
  const auto [lo, hi] = m.angle_range();
  row.min_angle = lo * 180 / M_PI;
  row.max_angle = hi * 180 / M_PI;
}

std::string csv_header(const DelaunaySceneSpec& s) {
  std::string h =
      "movement,triangles,vertices,flips,removals,splits,entered,exited,incisions,status,"
      "min_angle_deg,max_angle_deg";
  if (s.has_sheet) h += ",cg_iterations,residual_N,opening_m";
  return h + "\n";
}

std::string csv_row(const DelaunaySceneSpec& s, const DelaunayMovementRow& r) {
  std::ostringstream os;
  os.precision(10);
  os << r.movement << "," << r.triangles << "," << r.vertices << "," << r.flips << "," << r.removals
     << "," << r.splits << "," << r.entered << "," << r.exited << "," << r.incisions << ","
     << r.status << "," << r.min_angle << "," << r.max_angle;
  if (s.has_sheet) os << "," << r.cg_iterations << "," << r.residual << "," << r.opening;
  os << "\n";
  return os.str();
}

/// VTU frames and their .pvd index.
class Frames {
 public:
  Frames(const DelaunaySceneSpec& s, std::size_t total) : spec_(s), total_(total) {
    width_ = std::max<std::size_t>(4, std::to_string(total == 0 ? 0 : total - 1).size());
  }
  bool due(long movement) const {
    return !spec_.vtu.empty() &&
           (movement % spec_.vtu_every == 0 || static_cast<std::size_t>(movement) + 1 == total_);
  }
  void write(long movement, const mesh::MeshData& m, const std::vector<io::DataArray>& point) {
    std::string num = std::to_string(movement);
    num.insert(0, width_ - std::min(width_, num.size()), '0');
    const std::string path = spec_.vtu + "_" + num + ".vtu";
    write_atomically(path, [&](const std::string& tmp) { io::write_vtu(tmp, m, point); });
    pvd_.push_back(
        {static_cast<double>(movement), std::filesystem::path(path).filename().string()});
    const std::string index = spec_.vtu + ".pvd";
    write_atomically(index, [&](const std::string& tmp) { io::write_pvd(tmp, pvd_); });
    ++frames_;
  }
  long frames() const { return frames_; }

 private:
  const DelaunaySceneSpec& spec_;
  std::size_t total_;
  std::size_t width_ = 4;
  std::vector<io::PvdFrame> pvd_;
  long frames_ = 0;
};

/// The sheet's displacement as a VTU point array (3 components, z = 0).
std::vector<io::DataArray> sheet_point_data(const interactive::DelaunayCutSession& session) {
  io::DataArray d{"displacement", 3, {}};
  const Index n = session.mesh().connectivity().num_vertices();  // to_mesh_data()'s points
  d.values.reserve(static_cast<std::size_t>(3 * n));
  for (Index v = 0; v < n; ++v) {
    const Vec2 u = session.displacement(v);
    d.values.insert(d.values.end(), {u.x(), u.y(), 0.0});
  }
  return {d};
}

/// Largest deformed distance between the two sides' first nodes (the mouth), 0 without two sides.
double opening(const interactive::DelaunayCutSession& session) {
  const auto& sides = session.cutter().incision_sides();
  if (sides.size() < 2 || sides[0].empty() || sides[1].empty()) return 0;
  return (session.deformed(sides[0].front()) - session.deformed(sides[1].front())).norm();
}

std::string summary(const DelaunaySceneSpec& s, const DelaunayRunResult& r,
                    const std::vector<std::string>& written) {
  nlohmann::ordered_json j;
  j["scene"] = s.file;
  j["name"] = s.name;
  j["kind"] = s.has_sheet ? "delaunay-sheet" : (s.surface ? "delaunay-surface" : "delaunay-2d");
  j["cutter"] = s.surface ? "delaunay" : kDelaunayCutterNames.name(s.cutter);
  if (s.cutter == DelaunayCutterKind::kDelaunay) {
    j["short_edge"] = kShortEdgeRuleNames.name(s.options.short_edge);
    j["eps_edge_per_h"] = s.options.edge;
    j["min_angle_rad"] = s.options.min_angle;
    j["eps_entry_per_h"] = s.options.entry;
    j["eps_exit_per_h"] = s.options.exit;
    j["step_per_h"] = s.step;
  }
  j["result"] = r.status;
  j["message"] = r.message;
  j["movements"] = r.rows.size();
  j["triangles_before"] = r.triangles_before;
  j["triangles_after"] = r.triangles_after;
  j["components"] = r.components;
  j["entries"] = r.entries;
  j["exits"] = r.exits;
  j["blocked"] = r.blocked;
  j["lost"] = r.lost;
  if (!r.rows.empty()) {
    j["min_angle_deg"] = r.rows.back().min_angle;
    j["max_angle_deg"] = r.rows.back().max_angle;
    if (s.has_sheet) j["opening_m"] = r.rows.back().opening;
  }
  j["seconds"] = r.seconds;
  nlohmann::ordered_json env;
  for (const auto& [k, v] : r.environment.fields()) env[k] = v;
  j["environment"] = env;
  j["outputs"] = written;
  return j.dump(2) + "\n";
}

}  // namespace

bool is_delaunay_scene(const std::string& path) {
  try {
    const std::string text = detail::read_scene_file(path);
    const Json j = Json::parse(text, nullptr, false);
    if (!j.is_object()) return false;
    const auto tools = j.find("tools");
    if (tools == j.end() || !tools->is_array() || tools->empty() || !(*tools)[0].is_object())
      return false;
    const auto type = (*tools)[0].find("type");
    return type != (*tools)[0].end() && type->is_string() &&
           (*type == kScalpel2d || *type == kSurfaceScalpel);
  } catch (const std::exception&) {
    return false;
  }
}

DelaunaySceneSpec parse_delaunay_scene(const std::string& text, const std::string& file,
                                       const std::string& base_dir) {
  detail::ParsedJson parsed = detail::parse_strict(text, file);
  try {
    DelaunaySceneSpec s = parse_delaunay_root(parsed.value, file, base_dir);
    s.lines = std::move(parsed.lines);
    return s;
  } catch (const ParseError& e) {
    throw detail::with_line(e, file, parsed.lines);
  }
}

DelaunaySceneSpec load_delaunay_scene(const std::string& path) {
  const std::string text = detail::read_scene_file(path);
  return parse_delaunay_scene(text, path, std::filesystem::path(path).parent_path().string());
}

DelaunayRunResult run_delaunay_scene(const DelaunaySceneSpec& s, const std::string& summary_json,
                                     const DelaunayObserver& observer) {
  DelaunayRunResult r;
  r.environment = capture_environment();
  const mesh::MeshData start = build_mesh(s.mesh, s.surface, s.file);
  std::string csv = s.csv.empty() ? "" : csv_header(s);
  Timer timer;
  auto record = [&](DelaunayMovementRow& row, std::size_t total) {
    r.entries += row.entered;
    r.exits += row.exited;
    r.blocked += row.status == "blocked";
    r.lost += row.status == "lost";
    if (!s.csv.empty()) csv += csv_row(s, row);
    r.rows.push_back(row);
    if (observer) observer(row, total);
  };
  std::optional<Frames> frames;
  std::string svg;  // the SVG of a 2D final mesh (delaunay::mesh_svg), when asked for
  auto picture = [&](const delaunay::Triangulation& t) {
    if (!s.svg.empty()) svg = delaunay::mesh_svg(t, s.path, delaunay::fit_frame(t));
  };
  mesh::MeshData final_mesh;
  std::vector<io::DataArray> final_point;

  if (s.surface) {
    delaunay::Surface surface(start);
    delaunay::SurfaceCutter cutter(surface, s.options);
    r.triangles_before = surface.num_triangles();
    const auto moves = delaunay::movement_segments(s.blade, s.step * cutter.mean_edge());
    frames.emplace(s, moves.size());
    for (std::size_t k = 0; k < moves.size(); ++k) {
      const delaunay::SurfaceMoveReport m = cutter.move_to(moves[k]);
      DelaunayMovementRow row;
      row.movement = static_cast<long>(k);
      row.flips = m.flips;
      row.removals = m.removals;
      row.splits = m.splits;
      row.entered = m.entered || m.tip_entered || m.edge_entered;
      row.exited = m.exited;
      row.incisions = m.incisions;
      row.status = delaunay::to_string(m.status);
      fill_mesh_columns(surface, row);
      record(row, moves.size());
      if (frames->due(row.movement)) frames->write(row.movement, surface.to_mesh_data(), {});
    }
    r.triangles_after = surface.num_triangles();
    r.components = pieces(surface);
    final_mesh = surface.to_mesh_data();
  } else if (s.has_sheet) {
    material::Material material(s.sheet.material.model, s.sheet.material.parameters);
    std::vector<interactive::SheetLine> fixed;
    for (const Vec2& l : s.sheet.fixed) fixed.push_back({static_cast<int>(l.x()), l.y()});
    interactive::DelaunayCutSessionOptions o;
    o.cutter = s.options;
    o.tolerance = s.sheet.tolerance;
    o.max_iterations = s.sheet.max_iterations;
    interactive::DelaunayCutSession session(
        start, material, s.sheet.thickness, fixed,
        interactive::SheetLine{static_cast<int>(s.sheet.loaded.x()), s.sheet.loaded.y()},
        s.sheet.traction, o);
    r.triangles_before = session.mesh().num_triangles();
    const auto moves = delaunay::movement_points(s.path, s.step * session.cutter().mean_edge());
    frames.emplace(s, moves.size());
    if (!session.initial_report().ok()) {
      r.status = solver::to_string(session.initial_report().status);
      r.message = "the uncut sheet's solve: " + session.initial_report().message;
    }
    for (std::size_t k = 0; k < moves.size() && r.ok(); ++k) {
      const interactive::DelaunayCutStepReport m = session.move_to(moves[k]);
      DelaunayMovementRow row;
      row.movement = static_cast<long>(k);
      row.flips = m.cut.flips;
      row.removals = m.cut.removals;
      row.splits = m.cut.splits;
      row.entered = m.cut.entered;
      row.exited = m.cut.exited;
      row.incisions = m.cut.phase == delaunay::CutPhase::kOutside ? 0 : 1;
      row.status = m.ok() ? delaunay::to_string(m.cut.status) : solver::to_string(m.status);
      row.cg_iterations = m.cg_iterations;
      row.residual = m.residual_norm;
      row.opening = opening(session);
      fill_mesh_columns(session.mesh(), row);
      if (!m.ok()) {
        r.status = solver::to_string(m.status);
        r.message = "movement " + std::to_string(k) + ": " + m.message;
      }
      record(row, moves.size());
      if (frames->due(row.movement))
        frames->write(row.movement, session.mesh().to_mesh_data(), sheet_point_data(session));
    }
    r.triangles_after = session.mesh().num_triangles();
    r.components = pieces(session.mesh());
    final_mesh = session.mesh().to_mesh_data();
    final_point = sheet_point_data(session);
    picture(session.mesh());
  } else {
    delaunay::Triangulation t(start);
    r.triangles_before = t.num_triangles();
    if (s.cutter == DelaunayCutterKind::kSubdivision) {
      frames.emplace(s, 1);
      const long flips_before = t.num_flips();
      const delaunay::SubdivisionReport m = delaunay::subdivision_cut(t, s.path);
      DelaunayMovementRow row;
      row.flips = t.num_flips() - flips_before;
      row.splits = m.crossings;
      row.entered = m.crossings > 0;
      row.exited = m.dissected > 0;
      row.status = "ok";
      fill_mesh_columns(t, row);
      record(row, 1);
      if (frames->due(0)) frames->write(0, t.to_mesh_data(), {});
    } else {
      delaunay::Cutter2D cutter(t, s.options);
      const auto moves = delaunay::movement_points(s.path, s.step * cutter.mean_edge());
      frames.emplace(s, moves.size());
      for (std::size_t k = 0; k < moves.size(); ++k) {
        const delaunay::CutMove2DReport m = cutter.move_to(moves[k]);
        DelaunayMovementRow row;
        row.movement = static_cast<long>(k);
        row.flips = m.flips;
        row.removals = m.removals;
        row.splits = m.splits;
        row.entered = m.entered;
        row.exited = m.exited;
        row.incisions = cutter.phase() == delaunay::CutPhase::kOutside ? 0 : 1;
        row.status = delaunay::to_string(m.status);
        fill_mesh_columns(t, row);
        record(row, moves.size());
        if (frames->due(row.movement)) frames->write(row.movement, t.to_mesh_data(), {});
      }
    }
    r.triangles_after = t.num_triangles();
    r.components = pieces(t);
    final_mesh = t.to_mesh_data();
    picture(t);
  }
  r.seconds = timer.seconds();

  if (!s.csv.empty()) {
    write_file_atomic(s.csv, csv);
    r.written.push_back(s.csv);
  }
  if (!s.vtu.empty()) {
    const std::string path = s.vtu + ".vtu";
    write_atomically(path,
                     [&](const std::string& tmp) { io::write_vtu(tmp, final_mesh, final_point); });
    r.written.push_back(path);
    if (frames && frames->frames() > 0)
      r.written.push_back(std::to_string(frames->frames()) + " frames " + s.vtu +
                          "_<movement>.vtu, index " + s.vtu + ".pvd");
  }
  if (!s.svg.empty()) {
    write_file_atomic(s.svg, svg);
    r.written.push_back(s.svg);
  }
  if (!summary_json.empty()) {
    std::vector<std::string> all = r.written;
    all.push_back(summary_json);
    write_file_atomic(summary_json, summary(s, r, all));
    r.written.push_back(summary_json);
  }
  return r;
}

}  // namespace incise::scene
