#include <incise/scene/scene_builder.hpp>

#include <incise/core/error.hpp>
#include <incise/core/memory_budget.hpp>
#include <incise/core/timer.hpp>
#include <incise/cut/cutter.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/slab2d.hpp>
#include <incise/mesh/tet_faces.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace incise::scene {

void BuiltScene::record(std::string what, double seconds, std::size_t bytes, std::int64_t flops) {
  steps.push_back(BuildStep{std::move(what), seconds, bytes, flops});
}

namespace {

std::string vec_str(const Vec3& v) {
  std::ostringstream os;
  os << "[" << v[0] << ", " << v[1] << ", " << v[2] << "]";
  return os.str();
}

std::string bbox_str(const mesh::MeshData& m) {
  if (m.num_points() == 0) return "(empty mesh)";
  return "mesh bounding box " + vec_str(m.points.rowwise().minCoeff()) + " to " +
         vec_str(m.points.rowwise().maxCoeff());
}

[[noreturn]] void region_error(const SceneSpec& spec, const std::string& path,
                               const std::string& what, const mesh::MeshData& m) {
  throw ParseError(spec.file, spec.lines.line(path), path + ": " + what + " (" + bbox_str(m) + ")");
}

// Bytes of the mesh arrays: points, cells, facets and tags.
std::uint64_t mesh_bytes(std::uint64_t points, std::uint64_t cell_entries,
                         std::uint64_t facet_entries, std::uint64_t tags) {
  return points * 3 * sizeof(double) + (cell_entries + facet_entries) * sizeof(Index) +
         tags * sizeof(int);
}

std::uint64_t matrix_bytes(const mesh::MeshData& m) {
  return mesh_bytes(static_cast<std::uint64_t>(m.num_points()),
                    static_cast<std::uint64_t>(m.cells.size()),
                    static_cast<std::uint64_t>(m.facets.size()),
                    m.cell_tags.size() + m.point_tags.size() + m.facet_tags.size());
}

// Bytes of the elastic problem of `cells` tetrahedra on `points` nodes: element references and
// cells, and per DOF the load, mass and fixed flag.
std::uint64_t problem_bytes(std::uint64_t points, std::uint64_t cells) {
  return cells * (sizeof(fem::TetReference) + 4 * sizeof(Index)) +
         3 * points * (3 * sizeof(double) + 1);
}

// Bytes of the assembled K of fem::ElasticProblem::set_assembled_product on `m`: per coupled
// node pair (every node with itself, both orders of each distinct edge) the raw tangent's 9
// values and row indices (both triangles stored) and the block copy's values and node index —
// 12 values, the AVX layout's padded 3×4 columns, the largest of the product's layouts (the
// scalar layouts store 9); per element the 20-int scatter map; per DOF a column start and a
// diagonal index.
std::uint64_t assembled_product_bytes(const mesh::MeshData& m) {
  std::vector<std::uint64_t> edges;
  edges.reserve(6 * static_cast<std::size_t>(m.num_cells()));
  for (Index e = 0; e < m.num_cells(); ++e)
    for (int a = 0; a < 4; ++a)
      for (int c = a + 1; c < 4; ++c) {
        const auto p = static_cast<std::uint64_t>(std::min(m.cells(a, e), m.cells(c, e)));
        const auto q = static_cast<std::uint64_t>(std::max(m.cells(a, e), m.cells(c, e)));
        edges.push_back(p << 32 | q);
      }
  std::sort(edges.begin(), edges.end());
  const auto distinct =
      static_cast<std::uint64_t>(std::unique(edges.begin(), edges.end()) - edges.begin());
  const auto points = static_cast<std::uint64_t>(m.num_points());
  const std::uint64_t pairs = points + 2 * distinct;
  return pairs * (9 * (sizeof(double) + sizeof(int)) + 12 * sizeof(double) + sizeof(int)) +
         static_cast<std::uint64_t>(m.num_cells()) * 20 * sizeof(int) +
         3 * points * 2 * sizeof(int);
}

std::string mib(std::uint64_t bytes) {
  std::ostringstream os;
  os.precision(4);
  os << static_cast<double>(bytes) / (1024.0 * 1024.0) << " MiB";
  return os.str();
}

// Refuses a build whose mesh arrays and elastic problem, for a mesh of `size`, are estimated
// above the scene's memory budget; reported at /mesh.
void check_memory(const SceneSpec& spec, const mesh::MeshSize& size) {
  const auto points = static_cast<std::uint64_t>(size.points);
  const auto cells = static_cast<std::uint64_t>(size.cells);
  const std::uint64_t estimate = mesh_bytes(points, 4 * cells, 0, 0) + problem_bytes(points, cells);
  const std::uint64_t budget = memory_budget_bytes(spec);
  if (estimate <= budget) return;
  throw ParseError(spec.file, spec.lines.line("/mesh"),
                   "/mesh: the mesh and its elastic problem need an estimated " + mib(estimate) +
                       " (" + std::to_string(size.cells) + " tetrahedra, " +
                       std::to_string(size.points) + " nodes), more than the memory budget of " +
                       mib(budget) + " (" + memory_budget_origin(spec) + ")");
}

// A generator's refusal of a scene mesh parameter, at its JSON path (the keys of a generated
// mesh are the generator's parameter names).
[[noreturn]] void generator_error(const SceneSpec& spec, const mesh::GeneratorError& e) {
  const std::string path = e.parameter().empty() ? "/mesh" : "/mesh/" + e.parameter();
  throw ParseError(spec.file, spec.lines.line(path), path + ": " + e.what());
}

mesh::MeshData make_mesh(const SceneSpec& spec, std::string& what) {
  const MeshSpec& ms = spec.mesh;
  std::ostringstream os;
  try {
    switch (ms.source) {
      case MeshSpec::Source::kBox: {
        os << "mesh: box " << ms.nx << "x" << ms.ny << "x" << ms.nz << " of " << ms.lx << "x"
           << ms.ly << "x" << ms.lz << " m";
        what = os.str();
        check_memory(spec, mesh::box_size(ms.nx, ms.ny, ms.nz, ms.lx, ms.ly, ms.lz, ms.split));
        return mesh::make_box(ms.nx, ms.ny, ms.nz, ms.lx, ms.ly, ms.lz, ms.split);
      }
      case MeshSpec::Source::kCylinder: {
        os << "mesh: cylinder r=" << ms.radius << " m, L=" << ms.length << " m, " << ms.rings
           << " rings, " << ms.layers << " layers";
        what = os.str();
        check_memory(spec, mesh::cylinder_size(ms.length, ms.radius, ms.rings, ms.layers));
        return mesh::make_cylinder(ms.length, ms.radius, ms.rings, ms.layers);
      }
      case MeshSpec::Source::kFile: {
        // The reader scales before its geometry checks, so that coordinates the scale makes
        // non-finite or flat are reported at their line of the mesh file.
        io::ReadOptions options;
        options.scale = ms.scale;
        io::LoadedMesh loaded = io::read_mesh(ms.file, options);
        what = "mesh: " + ms.file + " (" + loaded.report.format + ")";
        if (ms.scale != 1.0) what += ", coordinates scaled by " + std::to_string(ms.scale);
        check_memory(spec, {loaded.mesh.num_points(), loaded.mesh.num_cells()});
        return std::move(loaded.mesh);
      }
      case MeshSpec::Source::kSlab2d: break;  // build_needle_scene
    }
  } catch (const mesh::GeneratorError& e) {
    generator_error(spec, e);
  }
  throw UsageError("scene mesh source not handled");
}

// Bytes of a needle insertion's starting slab and its plane-stress problem, per triangle and
// node: mesh arrays as above, and the BisectionMesh (connectivity ≈ 4 handles per element and
// vertex, tree node per element) with the triangle references and 2 DOFs per node held by the
// problem. An estimate of the start only: refinement adds O(path / h_ref) triangles.
std::uint64_t slab_bytes(std::uint64_t points, std::uint64_t cells) {
  return mesh_bytes(points, 3 * cells, 0, 0) + cells * (12 * sizeof(Index) + 8 * sizeof(double)) +
         points * (4 * sizeof(Index) + 6 * sizeof(double));
}

/// Sorts b.fixed_nodes, drops repeats and records them: "<what>, N of M starting nodes (nodes
/// refinement creates <on_or_in> them are fixed too)".
void record_fixed_nodes(BuiltScene& b, const std::string& what, const char* on_or_in,
                        const Timer& t) {
  std::sort(b.fixed_nodes.begin(), b.fixed_nodes.end());
  b.fixed_nodes.erase(std::unique(b.fixed_nodes.begin(), b.fixed_nodes.end()), b.fixed_nodes.end());
  b.record(what + ", " + std::to_string(b.fixed_nodes.size()) + " of " +
               std::to_string(b.mesh.num_points()) + " starting nodes (nodes refinement creates " +
               on_or_in + " them are fixed too)",
           t.seconds(), b.fixed_nodes.size() * sizeof(Index));
}

/// The options the 2D and 3D needle insertions share (thesis §6.7), from the scene's solver and
/// needle keys.
void set_insertion_options(const SceneSpec& spec, const ToolSpec& tool,
                           needle::InsertionOptions& o) {
  o.h_ref = tool.h_ref;
  o.epsilon = spec.solver.tolerance;
  o.epsilon_round = spec.solver.tolerance_round;
  o.relaxation = spec.solver.method == SolverSpec::Method::kNonlinearCG
                     ? needle::Relaxation::kNonlinearCg
                     : needle::Relaxation::kLinearCg;
  o.max_iterations = spec.solver.max_iterations;
  o.max_rearrangements = tool.max_rearrangements;
  o.relocate = tool.relocate;
  o.preconditioner = spec.solver.preconditioner;
}

/// A slab2d scene (scene_builder.hpp): the slab, its fixed lines and the needle insertion.
BuiltScene build_needle_scene(const SceneSpec& spec) {
  BuiltScene b;
  b.spec = spec;
  const MeshSpec& ms = spec.mesh;
  const ToolSpec& tool = *spec.needle();
  Timer t;
  // Mesh: checked against the budget from its counts before it is generated.
  const std::string h_path = ms.h_start_level ? "/mesh/h_start_level" : "/mesh/h_start";
  // As for the tetrahedral generators: edges, squared edges and areas stay normal doubles.
  if (!(ms.h_start >= mesh::kMinCellSize && ms.h_start <= mesh::kMaxCellSize)) {
    std::ostringstream e;
    e << h_path << ": h_start = " << ms.h_start
      << " m is outside [1e-100, 1e+100] m (triangle areas would not be representable)";
    throw ParseError(spec.file, spec.lines.line(h_path), e.str());
  }
  const double nx = std::round(ms.width / ms.h_start), ny = std::round(ms.height / ms.h_start);
  const double cells_d = 2 * nx * ny, points_d = (nx + 1) * (ny + 1);
  const auto max_index = static_cast<double>(std::numeric_limits<Index>::max());
  if (!(cells_d <= max_index && points_d <= max_index)) {  // NaN too
    std::ostringstream e;
    e << "/mesh: the slab would have " << cells_d << " triangles on " << points_d
      << " nodes (width / h_start = " << ms.width / ms.h_start
      << ", height / h_start = " << ms.height / ms.h_start << "), more than an Index can number ("
      << std::numeric_limits<Index>::max() << ")";
    throw ParseError(spec.file, spec.lines.line("/mesh"), e.str());
  }
  {
    const auto points = static_cast<std::uint64_t>(points_d);
    const auto cells = static_cast<std::uint64_t>(cells_d);
    const std::uint64_t estimate = slab_bytes(points, cells), budget = memory_budget_bytes(spec);
    if (estimate > budget)
      throw ParseError(spec.file, spec.lines.line("/mesh"),
                       "/mesh: the slab and its plane-stress problem need an estimated " +
                           mib(estimate) + " (" + std::to_string(cells) + " triangles, " +
                           std::to_string(points) + " nodes), more than the memory budget of " +
                           mib(budget) + " (" + memory_budget_origin(spec) + ")");
  }
  try {
    b.mesh = mesh::make_right_triangle_slab(ms.width, ms.height, ms.h_start);
  } catch (const ParameterError&) {  // its message names the generator's check, not the scene
    std::ostringstream m;
    m << h_path << ": expected width and height to be integer multiples of h_start = " << ms.h_start
      << " m (the slab is a grid of squares of side h_start; to 1e-9 relative), got "
      << "width / h_start = " << ms.width / ms.h_start
      << ", height / h_start = " << ms.height / ms.h_start;
    throw ParseError(spec.file, spec.lines.line(h_path), m.str());
  }
  std::ostringstream os;
  os << "mesh: slab2d " << ms.width << " x " << ms.height << " m, h_start = " << ms.h_start << " m"
     << (ms.h_start_level ? " (h" + std::to_string(ms.h_start_level) + ")" : "") << ", thickness "
     << ms.thickness << " m -> " << b.mesh.num_cells() << " triangles, " << b.mesh.num_points()
     << " nodes";
  b.record(os.str(), t.seconds(), matrix_bytes(b.mesh));
  // Fixed lines: each must hold a node of the starting slab.
  t.restart();
  std::vector<needle::FixedLine> lines;
  for (const Region& r : spec.fixed) {
    const auto sel = select_nodes(b.mesh, r);
    if (sel.empty()) region_error(spec, r.path, "region selects no node of the mesh", b.mesh);
    b.fixed_nodes.insert(b.fixed_nodes.end(), sel.begin(), sel.end());
    lines.push_back(needle::FixedLine{r.axis, r.value});
  }
  record_fixed_nodes(b, "fixed lines: " + std::to_string(lines.size()), "on", t);
  // The insertion: plane-stress problem on the slab, friction, options (thesis §6.7).
  t.restart();
  needle::InsertionOptions o;
  set_insertion_options(spec, tool, o);
  b.needle = std::make_unique<needle::NeedleInsertion>(b.mesh, make_material(spec.material),
                                                       ms.thickness, lines, tool.friction, o);
  b.needle_plan = needle_updates(tool);
  std::ostringstream ns;
  ns << "needle insertion: plane-stress problem (material \"" << spec.material.model
     << "\", thickness " << ms.thickness << " m), needle of length " << tool.length << " m, "
     << b.needle_plan.size() << " updates at " << tool.speed << " h_ref (h_ref = " << tool.h_ref
     << " m" << (tool.h_ref_level ? ", h" + std::to_string(tool.h_ref_level) : std::string())
     << "), friction " << tool.friction.shaft_density << " N/m shaft, " << tool.friction.tip_density
     << " N/m tip over " << tool.friction.bulge_length << " m, static factor "
     << tool.friction.static_factor << (tool.relocate ? ", relocation (§6.8.6)" : "");
  b.record(ns.str(), t.seconds(),
           slab_bytes(static_cast<std::uint64_t>(b.mesh.num_points()),
                      static_cast<std::uint64_t>(b.mesh.num_cells())) -
               matrix_bytes(b.mesh));
  b.not_built.push_back(
      "tetrahedral elastic problem, loads and probes: a slab2d scene is a needle insertion on "
      "plane-stress triangles (thesis ch. 6)");
  b.not_built.push_back("sparse stiffness factorization: the needle run relaxes with CG");
  b.not_built.push_back("cut mesh and sweep triangles: the needle refines, it does not cut");
  return b;
}

/// A 3D needle scene (scene_builder.hpp): the tetrahedral mesh, its fixed boxes and the 3D
/// needle insertion (thesis §6.9).
BuiltScene build_needle3d_scene(const SceneSpec& spec);

}  // namespace

std::vector<NeedleUpdatePlan> needle_updates(const ToolSpec& tool, bool three_d) {
  std::vector<NeedleUpdatePlan> plan;
  const std::vector<Vec3>& p = tool.path;
  double total = 0.0;
  for (std::size_t i = 0; i + 1 < p.size(); ++i) total += (p[i + 1] - p[i]).stableNorm();
  const double step = tool.speed * tool.h_ref;
  // 1e-9 of a step: a path of exactly n steps ends at update n, not n + 1.
  const long n = static_cast<long>(std::ceil(total / step - 1e-9));
  std::size_t seg = 0;
  double seg_start = 0.0;  // distance along the path where segment `seg` starts
  for (long k = 0; k <= n; ++k) {
    const double depth = std::min(total, static_cast<double>(k) * step);
    // The segment the tip is on: the next one at a joint, the last one at the end.
    while (seg + 2 < p.size() && depth >= seg_start + (p[seg + 1] - p[seg]).stableNorm()) {
      seg_start += (p[seg + 1] - p[seg]).stableNorm();
      ++seg;
    }
    const Vec3 d = p[seg + 1] - p[seg];
    const double len = d.stableNorm();
    const Vec3 tip = p[seg] + std::min(1.0, (depth - seg_start) / len) * d;
    NeedleUpdatePlan u;
    if (three_d)
      u.pose3d = needle::NeedlePose3D::make(tip, d, tool.length, tool.radius);
    else
      u.pose = needle::NeedlePose::make(tip.head<2>(), d.head<2>(), tool.length);
    u.depth = depth;
    plan.push_back(u);
  }
  return plan;
}

std::vector<Index> select_nodes(const mesh::MeshData& m, const Region& r) {
  std::vector<Index> out;
  const Index n = m.num_points();
  if (r.kind == Region::Kind::kTag) {
    std::vector<char> in(static_cast<std::size_t>(n), 0);
    for (std::size_t i = 0; i < m.point_tags.size() && i < in.size(); ++i)
      if (m.point_tags[i] == r.tag) in[i] = 1;
    for (std::size_t c = 0; c < m.cell_tags.size(); ++c)
      if (m.cell_tags[c] == r.tag)
        for (Index k = 0; k < m.cells.rows(); ++k) in[m.cells(k, static_cast<Index>(c))] = 1;
    for (std::size_t f = 0; f < m.facet_tags.size(); ++f)
      if (m.facet_tags[f] == r.tag)
        for (Index k = 0; k < m.facets.rows(); ++k) in[m.facets(k, static_cast<Index>(f))] = 1;
    for (Index i = 0; i < n; ++i)
      if (in[i]) out.push_back(i);
    return out;
  }
  double tol = r.tolerance;
  if (r.kind == Region::Kind::kPlane && tol == 0.0 && n > 0)
    tol = 1e-9 * (m.points.rowwise().maxCoeff() - m.points.rowwise().minCoeff()).norm();
  for (Index i = 0; i < n; ++i) {
    const Vec3 x = m.points.col(i);
    bool in = false;
    switch (r.kind) {
      case Region::Kind::kPlane: in = std::abs(x[r.axis] - r.value) <= tol; break;
      case Region::Kind::kBox:
        in = (x.array() >= r.lo.array()).all() && (x.array() <= r.hi.array()).all();
        break;
      case Region::Kind::kSphere: in = (x - r.center).norm() <= r.radius; break;
      case Region::Kind::kTag: break;
    }
    if (in) out.push_back(i);
  }
  return out;
}

std::vector<std::array<Vec3, 3>> sweep_triangles(const ToolSpec& tool) {
  std::vector<std::array<Vec3, 3>> tris;
  for (std::size_t i = 0; i + 1 < tool.path.size(); ++i) {
    const Vec3& a = tool.path[i];
    const Vec3& b = tool.path[i + 1];
    tris.push_back({a, b, b + tool.blade});
    tris.push_back({a, b + tool.blade, a + tool.blade});
  }
  return tris;
}

std::uint64_t memory_budget_bytes(const SceneSpec& spec) {
  return spec.limits.memory_mb > 0 ? static_cast<std::uint64_t>(spec.limits.memory_mb) << 20
                                   : default_memory_budget_bytes();
}

std::string memory_budget_origin(const SceneSpec& spec) {
  return spec.limits.memory_mb > 0
             ? "limits.memory_mb = " + std::to_string(spec.limits.memory_mb)
             : "by default half the physical memory; set \"limits\": {\"memory_mb\": N} or "
               "incise run --memory-mb N";
}

material::Material make_material(const MaterialSpec& spec) {
  return material::Material(spec.model, spec.parameters);
}

Vec3 probe_value(const ResolvedProbe& probe, const VecX& u) {
  Vec3 s = Vec3::Zero();
  for (Index i : probe.nodes) s += u.segment<3>(3 * static_cast<Eigen::Index>(i));
  return s / static_cast<double>(probe.nodes.size());
}

mesh::MeshData live_mesh_data(const cut::CutMesh& cm) {
  mesh::MeshData m;
  m.dimension = 3;
  m.points = cm.reference_matrix();
  std::vector<cut::Tet> live;
  for (Index e = 0; e < cm.element_capacity(); ++e)
    if (cm.alive(e)) live.push_back(cm.element(e));
  m.cells.resize(4, static_cast<Eigen::Index>(live.size()));
  for (std::size_t e = 0; e < live.size(); ++e)
    for (int k = 0; k < 4; ++k) m.cells(k, static_cast<Eigen::Index>(e)) = live[e][k];
  if (cm.has_tags())
    for (Index e = 0; e < cm.element_capacity(); ++e)
      if (cm.alive(e)) m.cell_tags.push_back(cm.tag(e));
  return m;
}

std::unique_ptr<fem::ElasticProblem> cut_session_problem(
    const interactive::AugmentedCutSession& session, const material::Material& material,
    const Eigen::Matrix3Xd& forces) {
  const cut::CutMesh& cm = session.mesh();
  auto p = std::make_unique<fem::ElasticProblem>(live_mesh_data(cm), material);
  std::vector<Index> held;
  for (Index v = 0; v < cm.num_nodes(); ++v) {
    const int d = session.dof(v);
    if (d < 0 || cm.unused(v) || session.system().is_constrained(d)) held.push_back(v);
  }
  p->fix_nodes(held);
  for (Index v = 0; v < forces.cols(); ++v)
    if (forces.col(v).squaredNorm() > 0) p->add_point_load(fem::PointLoad{v, forces.col(v)});
  return p;
}

namespace {

/// The scene's mesh into b.mesh, recorded as a build step (what, time, bytes); ParseError at
/// /mesh when it is not tetrahedral.
void build_tet_mesh(const SceneSpec& spec, BuiltScene& b) {
  Timer t;
  std::string what;
  b.mesh = make_mesh(spec, what);
  if (b.mesh.dimension != 3)
    throw ParseError(spec.file, spec.lines.line("/mesh"),
                     "/mesh: expected a tetrahedral (3D) mesh, got dimension " +
                         std::to_string(b.mesh.dimension));
  what += " -> " + std::to_string(b.mesh.num_cells()) + " tets, " +
          std::to_string(b.mesh.num_points()) + " nodes";
  b.record(what, t.seconds(), matrix_bytes(b.mesh));
}

BuiltScene build_needle3d_scene(const SceneSpec& spec) {
  BuiltScene b;
  b.spec = spec;
  const ToolSpec& tool = *spec.needle();
  build_tet_mesh(spec, b);
  // Fixed regions as boxes: each must hold a node of the starting mesh.
  Timer t;
  const double inf = std::numeric_limits<double>::infinity();
  const Eigen::Matrix3Xd& x = b.mesh.points;
  const double diagonal = (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).norm();
  std::vector<needle::FixedBox> boxes;
  for (const Region& r : spec.fixed) {
    const auto sel = select_nodes(b.mesh, r);
    if (sel.empty()) region_error(spec, r.path, "region selects no node of the mesh", b.mesh);
    b.fixed_nodes.insert(b.fixed_nodes.end(), sel.begin(), sel.end());
    needle::FixedBox box;
    if (r.kind == Region::Kind::kPlane) {
      // select_nodes' tolerance: 0 means 1e-9 × the bounding-box diagonal.
      const double tol = r.tolerance > 0 ? r.tolerance : 1e-9 * diagonal;
      box.lo = Vec3::Constant(-inf);
      box.hi = Vec3::Constant(inf);
      box.lo[r.axis] = r.value - tol;
      box.hi[r.axis] = r.value + tol;
    } else {
      box.lo = r.lo;
      box.hi = r.hi;
    }
    boxes.push_back(box);
  }
  record_fixed_nodes(b, "fixed regions: " + std::to_string(boxes.size()), "in", t);
  t.restart();
  needle::InsertionOptions3D o;
  set_insertion_options(spec, tool, o);
  o.h_shaft = tool.h_shaft;
  o.max_elements = tool.max_elements;
  if (tool.assembled_product) o.assembled_product = *tool.assembled_product;
  o.extrapolate = tool.extrapolate;
  if (spec.solver.method == SolverSpec::Method::kAugmented) {
    o.solve_path = needle::SolvePath3D::kAugmented;
    o.refactor_at_m = spec.solver.refactor_at_m;
  }
  b.needle3d = std::make_unique<needle::NeedleInsertion3D>(b.mesh, make_material(spec.material),
                                                           boxes, tool.friction, o);
  b.needle_plan = needle_updates(tool, true);
  // The path against the body: the planned tips inside the reference mesh.
  std::size_t inside = 0;
  for (const NeedleUpdatePlan& u : b.needle_plan)
    inside += b.needle3d->mesh().locate(u.pose3d.tip).valid() ? 1 : 0;
  const std::string path_at = tool.path_json + "/path";
  if (inside == 0) {
    std::ostringstream e;
    e << path_at << ": the needle's path never enters the body: none of the "
      << b.needle_plan.size() << " planned tip positions lies inside the mesh (bounding box ["
      << x.rowwise().minCoeff().transpose() << "] to [" << x.rowwise().maxCoeff().transpose()
      << "] m)";
    throw ParseError(spec.file, spec.lines.line(path_at), e.str());
  }
  const double step = tool.speed * tool.h_ref;
  const double inside_length = static_cast<double>(inside) * step;
  const double at_least = inside_length / tool.h_shaft;
  if (at_least > static_cast<double>(tool.max_elements)) {
    const bool given = spec.lines.contains(tool.path_json + "/h_shaft");
    const std::string at = tool.path_json + (given ? "/h_shaft" : "/radius");
    std::ostringstream e;
    e << at << ": needle radius " << tool.radius << " m: refining to h_shaft = " << tool.h_shaft
      << " m" << (given ? "" : " (2 radius)") << " along the " << inside_length
      << " m of path inside the body needs at least " << at_least
      << " tetrahedra (each covers at most h_shaft of the path), more than max_elements = "
      << tool.max_elements << " (the refinement budget): expected a larger radius or h_shaft, or "
      << "a larger max_elements";
    throw ParseError(spec.file, spec.lines.line(at), e.str());
  }
  std::ostringstream ns;
  ns << "needle insertion (3D, §6.9): elastic problem (material \"" << spec.material.model
     << "\"), needle of length " << tool.length << " m and radius " << tool.radius << " m, "
     << b.needle_plan.size() << " updates at " << tool.speed << " h_ref (h_ref = " << tool.h_ref
     << " m around the tip, h_shaft = " << tool.h_shaft << " m along the trace, at most "
     << tool.max_elements << " tetrahedra), friction " << tool.friction.shaft_density
     << " N/m shaft, " << tool.friction.tip_density << " N/m tip over "
     << tool.friction.bulge_length << " m (per area: / 2 pi r), static factor "
     << tool.friction.static_factor << (tool.relocate ? ", relocation (§6.8.6)" : "");
  b.record(ns.str(), t.seconds(), 0);
  b.not_built.push_back(
      "loads and probes: a needle scene is loaded by its needle and refines its mesh at every "
      "update");
  b.not_built.push_back("sparse stiffness factorization: the needle run relaxes with CG");
  b.not_built.push_back("cut mesh and sweep triangles: the needle refines, it does not cut");
  return b;
}

}  // namespace

BuiltScene build_scene(const SceneSpec& spec) {
  if (spec.mesh.source == MeshSpec::Source::kSlab2d) return build_needle_scene(spec);
  if (spec.needle()) return build_needle3d_scene(spec);
  BuiltScene b;
  b.spec = spec;
  build_tet_mesh(spec, b);
  // Fixed nodes.
  Timer t;
  for (const Region& r : spec.fixed) {
    const auto sel = select_nodes(b.mesh, r);
    if (sel.empty()) region_error(spec, r.path, "region selects no node of the mesh", b.mesh);
    b.fixed_nodes.insert(b.fixed_nodes.end(), sel.begin(), sel.end());
  }
  std::sort(b.fixed_nodes.begin(), b.fixed_nodes.end());
  b.fixed_nodes.erase(std::unique(b.fixed_nodes.begin(), b.fixed_nodes.end()), b.fixed_nodes.end());
  if (!spec.fixed.empty())
    b.record("fixed nodes: " + std::to_string(b.fixed_nodes.size()) + " of " +
                 std::to_string(b.mesh.num_points()) + " from " +
                 std::to_string(spec.fixed.size()) + " region(s)",
             t.seconds(), b.fixed_nodes.size() * sizeof(Index));

  // Tools with the augmented solver: the run cuts interactively, one sweep triangle at a time,
  // updating the static solution after every step (scene_runner.hpp); here only the sweep
  // triangles are made, and loads and probes are selected on the uncut mesh.
  const bool interactive_cut =
      !spec.tools.empty() && spec.solver.method == SolverSpec::Method::kAugmented;
  if (interactive_cut) {
    t.restart();
    for (const ToolSpec& tool : spec.tools) {
      const auto tris = sweep_triangles(tool);
      b.sweep_triangles.insert(b.sweep_triangles.end(), tris.begin(), tris.end());
    }
    b.record("sweep triangles: " + std::to_string(b.sweep_triangles.size()) + " from " +
                 std::to_string(spec.tools.size()) +
                 " tool(s), cut during the augmented run (a solve per " +
                 to_string(spec.solver.solve_every) + ")",
             t.seconds(), b.sweep_triangles.size() * sizeof(std::array<Vec3, 3>));
  }
  // Tools: the scalpel cuts the mesh (thesis §3.2) before the problem is built, so loads,
  // probes and the elastic problem see the cut mesh. Fixed flags travel with dissection copies.
  if (!spec.tools.empty() && !interactive_cut) {
    t.restart();
    cut::CutMesh cm(b.mesh);
    for (Index v : b.fixed_nodes) cm.set_fixed(v, true);
    cut::Cutter cutter(cm);
    cut::CutTotals totals;
    int degenerate_sweeps = 0;
    for (const ToolSpec& tool : spec.tools) {
      const auto tris = sweep_triangles(tool);
      for (const auto& tri : tris) {
        const cut::CutStepReport r = cutter.step(tri[0], tri[1], tri[2]);
        degenerate_sweeps += r.status == cut::CutStatus::kDegenerateSweep;
        totals.add(r);
      }
      cutter.end_incision();
      b.sweep_triangles.insert(b.sweep_triangles.end(), tris.begin(), tris.end());
    }
    mesh::MeshData cut_mesh = live_mesh_data(cm);
    b.fixed_nodes.clear();
    Index unused = 0;
    for (Index v = 0; v < cm.num_nodes(); ++v) {
      // Nodes left without elements (collapses, cut-free elements) are fixed so that they
      // carry no free DOF without stiffness.
      if (cm.unused(v)) ++unused;
      if (cm.fixed(v) || cm.unused(v)) b.fixed_nodes.push_back(v);
    }
    b.mesh = std::move(cut_mesh);
    b.record("cut: " + std::to_string(b.sweep_triangles.size()) + " sweep triangles (" +
                 std::to_string(degenerate_sweeps) + " degenerate), " +
                 std::to_string(totals.faces_dissected) + " faces dissected, " +
                 std::to_string(totals.nodes_snapped) + " nodes snapped, " +
                 std::to_string(totals.collapses) + " collapses, " +
                 std::to_string(totals.new_nodes) + " new nodes, " + std::to_string(unused) +
                 " unused nodes -> " + std::to_string(b.mesh.num_cells()) + " tets, " +
                 std::to_string(b.mesh.num_points()) + " nodes (cell tags dropped)",
             t.seconds(), matrix_bytes(b.mesh));
  } else if (spec.tools.empty()) {
    b.not_built.push_back("cut mesh and sweep triangles: no tool named");
  }
  const Index n = b.mesh.num_points();
  const Eigen::Index ndof = 3 * static_cast<Eigen::Index>(n);

  // Loads.
  t.restart();
  b.external_force = VecX::Zero(ndof);
  mesh::CellMatrix bfaces;
  Vec3 gravity = Vec3::Zero();
  for (const LoadSpec& l : spec.loads) {
    switch (l.kind) {
      case LoadSpec::Kind::kGravity:
        // Applied by fem::ElasticProblem::add_gravity below (ρ g V/4 per vertex: the consistent
        // load of linear tetrahedra).
        gravity += l.vector;
        break;
      case LoadSpec::Kind::kPoint: {
        Index best = 0;
        double bd = std::numeric_limits<double>::infinity();
        for (Index i = 0; i < n; ++i) {
          const double d = (b.mesh.points.col(i) - l.at).squaredNorm();
          if (d < bd) bd = d, best = i;
        }
        b.external_force.segment<3>(3 * best) += l.vector;
        break;
      }
      case LoadSpec::Kind::kNodal: {
        const auto sel = select_nodes(b.mesh, l.region);
        if (sel.empty())
          region_error(spec, l.region.path, "region selects no node of the mesh", b.mesh);
        for (Index i : sel)
          b.external_force.segment<3>(3 * i) += l.vector / static_cast<double>(sel.size());
        break;
      }
      case LoadSpec::Kind::kSurface: {
        if (bfaces.size() == 0) bfaces = mesh::boundary_faces(b.mesh);
        const auto sel = select_nodes(b.mesh, l.region);
        std::vector<char> in(static_cast<std::size_t>(n), 0);
        for (Index i : sel) in[i] = 1;
        std::vector<Eigen::Index> loaded;  // boundary triangles with all 3 vertices inside
        for (Eigen::Index f = 0; f < bfaces.cols(); ++f)
          if (in[bfaces(0, f)] && in[bfaces(1, f)] && in[bfaces(2, f)]) loaded.push_back(f);
        if (loaded.empty())
          region_error(spec, l.region.path,
                       "region contains no boundary triangle (all 3 vertices inside) for the "
                       "surface load",
                       b.mesh);
        fem::add_surface_traction(b.mesh.points, bfaces(Eigen::all, loaded), l.vector,
                                  b.external_force);
        break;
      }
    }
  }
  // The elastic problem: material, constraints, loads.
  {
    Timer tp;
    b.problem = std::make_unique<fem::ElasticProblem>(b.mesh, make_material(spec.material));
    if (spec.solver.threads > 0) b.problem->set_threads(spec.solver.threads);
    using Method = SolverSpec::Method;
    const Method method = spec.solver.method;
    if (spec.material.model == material::LinearElastic::kName && method != Method::kAugmented) {
      // The assembled K·d (SolverSpec::assembled_product): on unless the scene says false, and
      // by default only when K in node blocks fits the memory budget beside mesh and problem.
      const bool wanted = spec.solver.assembled_product.value_or(kDefaultAssembledProduct);
      Timer ta;
      const std::uint64_t kbytes = wanted ? assembled_product_bytes(b.mesh) : 0;
      const std::uint64_t others =
          mesh_bytes(static_cast<std::uint64_t>(n),
                     4 * static_cast<std::uint64_t>(b.mesh.num_cells()), 0, 0) +
          problem_bytes(static_cast<std::uint64_t>(n),
                        static_cast<std::uint64_t>(b.mesh.num_cells()));
      const std::uint64_t budget = memory_budget_bytes(spec);
      if (wanted && others + kbytes > budget && spec.solver.assembled_product)
        throw ParseError(spec.file, spec.lines.line("/solver/assembled_product"),
                         "/solver/assembled_product: the assembled K needs an estimated " +
                             mib(kbytes) + " beside the mesh and problem's " + mib(others) +
                             ", more than the memory budget of " + mib(budget) + " (" +
                             memory_budget_origin(spec) + "); set it to false for K·d matrix-free");
      if (wanted && others + kbytes <= budget) {
        b.problem->set_assembled_product(true);
        b.record(
            "K·d from the assembled K in 3x3 node blocks (solver.assembled_product; "
            "assembled at the first product" +
                std::string(method == Method::kDynamicSS22
                                ? "; SS22 by the gradient recurrence, one K·d per step"
                                : "") +
                "; its memory estimated from the mesh's edges)",
            ta.seconds(), kbytes);
      } else {
        b.not_built.push_back(
            wanted ? "assembled K for K·d: an estimated " + mib(kbytes) +
                         " would exceed the memory budget of " + mib(budget) + " (K·d matrix-free)"
                   : std::string("assembled K for K·d: \"assembled_product\": false (K·d "
                                 "matrix-free)"));
      }
    }
    if (method == Method::kDynamicSS22 && !b.problem->assembled_product()) {
      // The Lanczos estimate of Δt and η multiplies by K(u) assembled once
      // (solver::LanczosOptions::assembled) when K in node blocks fits the memory budget beside
      // mesh and problem (with the assembled K·d above it uses that K).
      const std::uint64_t others =
          mesh_bytes(static_cast<std::uint64_t>(n),
                     4 * static_cast<std::uint64_t>(b.mesh.num_cells()), 0, 0) +
          problem_bytes(static_cast<std::uint64_t>(n),
                        static_cast<std::uint64_t>(b.mesh.num_cells()));
      const std::uint64_t kbytes = assembled_product_bytes(b.mesh);
      b.lanczos_assembled = others + kbytes <= memory_budget_bytes(spec);
      b.lanczos_assembled_bytes = b.lanczos_assembled ? kbytes : 0;
    } else {
      b.lanczos_assembled = b.problem->assembled_product();
    }
    b.problem->fix_nodes(b.fixed_nodes);
    for (Index i = 0; i < n; ++i) {
      const Vec3 f = b.external_force.segment<3>(3 * i);
      if (f.squaredNorm() > 0) b.problem->add_point_load(fem::PointLoad{i, f});
    }
    if (gravity.squaredNorm() > 0) b.problem->add_gravity(gravity);
    b.external_force = b.problem->external_force();
    const std::size_t m = static_cast<std::size_t>(b.mesh.num_cells());
    const std::size_t bytes = problem_bytes(static_cast<std::uint64_t>(n), m);
    const auto& ef = b.problem->element_flop_counts();
    b.record("elastic problem: material \"" + spec.material.model + "\", " + std::to_string(m) +
                 " element references; counted flops/element: force " + std::to_string(ef.force) +
                 ", force+K.d " + std::to_string(ef.force_and_product) + "; element loops on " +
                 std::to_string(b.problem->threads()) + " thread(s)" +
                 (interactive_cut ? " (uncut body: gives the load vector; the augmented run "
                                    "assembles its own stiffness)"
                                  : ""),
             tp.seconds(), bytes);
  }
  // A zero effective load (zero forces, forces only on fixed nodes, every node fixed, or forces
  // whose squares underflow) leaves (6.8) without a threshold: refused like "loads": [].
  if (!(b.problem->external_force_norm() != 0.0))  // 0 (NaN/inf: the solver's status)
    throw ParseError(
        spec.file, spec.lines.line("/loads"),
        "/loads: the loads give no force on a free node: ||f_ext|| = 0 over the free DOFs (the "
        "forces are zero, act only on fixed nodes, or underflow the doubles); the stopping rule "
        "||r|| <= tol ||f_ext|| needs f_ext != 0, and u = 0 is the solution");
  b.record("external load vector f_ext: " + std::to_string(spec.loads.size()) +
               " load(s), |f_ext| = " +
               (std::isfinite(b.problem->external_force_norm())
                    ? std::to_string(b.external_force.norm()) + " N"
                    : std::string("not finite (overflows the doubles)")),
           t.seconds(), static_cast<std::size_t>(ndof) * sizeof(double));

  if (spec.solver.method != SolverSpec::Method::kDynamicSS22)
    b.not_built.push_back(
        "time integrator state (velocities, step-size and damping estimates): "
        "the solver \"" +
        std::string(to_string(spec.solver.method)) + "\" is static");
  if (spec.solver.method != SolverSpec::Method::kAugmented)
    b.not_built.push_back("sparse stiffness factorization: only the \"augmented\" solver uses one");
  if (!spec.solver.spectral_tuning)
    b.not_built.push_back("FFTW plan: spectral damping tuning not requested");

  // Probes.
  if (!spec.outputs.probes.empty()) {
    t.restart();
    const Vec3 lo = b.mesh.points.rowwise().minCoeff(), hi = b.mesh.points.rowwise().maxCoeff();
    for (std::size_t k = 0; k < spec.outputs.probes.size(); ++k) {
      const ProbeSpec& p = spec.outputs.probes[k];
      const std::string path = "/outputs/probes/" + std::to_string(k);
      ResolvedProbe rp{p, {}};
      if (p.use_region) {
        rp.nodes = select_nodes(b.mesh, p.region);
        if (rp.nodes.empty())
          region_error(spec, path + "/region", "region selects no node of the mesh", b.mesh);
      } else {
        // 1e-9 relative slack: a probe exactly on the boundary is inside.
        const double slack = 1e-9 * (hi - lo).norm();
        if ((p.at.array() < lo.array() - slack).any() || (p.at.array() > hi.array() + slack).any())
          region_error(spec, path + "/at",
                       "probe location " + vec_str(p.at) + " is outside the mesh", b.mesh);
        Index best = 0;
        double bd = std::numeric_limits<double>::infinity();
        for (Index i = 0; i < n; ++i) {
          const double d = (b.mesh.points.col(i) - p.at).squaredNorm();
          if (d < bd) bd = d, best = i;
        }
        rp.nodes.push_back(best);
      }
      b.probes.push_back(std::move(rp));
    }
    b.record("probes: " + std::to_string(b.probes.size()), t.seconds(), 0);
  }
  return b;
}

}  // namespace incise::scene
