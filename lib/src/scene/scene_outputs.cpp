#include <incise/scene/scene_outputs.hpp>

#include <incise/core/atomic_file.hpp>
#include <incise/fem/element_fields.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/io/write_mesh.hpp>
#include <incise/mesh/tet_faces.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

namespace incise::scene {

namespace {

using Json = nlohmann::json;

io::DataArray displacement_array(const VecX& u) {
  io::DataArray a;
  a.name = "displacement";
  a.components = 3;
  a.values.assign(u.data(), u.data() + u.size());
  return a;
}

/// Writes `mesh` with `point` and `cell` arrays atomically in the scene's VTU encoding.
void write_vtu_atomic(const std::string& path, const mesh::MeshData& mesh,
                      const std::vector<io::DataArray>& point,
                      const std::vector<io::DataArray>& cell, io::VtuEncoding encoding) {
  write_atomically(
      path, [&](const std::string& tmp) { io::write_vtu(tmp, mesh, point, cell, encoding); });
}

/// `width` digits of `index`, zero-padded.
std::string padded(long index, std::size_t width) {
  std::string s = std::to_string(index);
  s.insert(0, width > s.size() ? width - s.size() : 0, '0');
  return s;
}

/// A finite number, or JSON null (never NaN or ∞ in a file).
Json num(double v) {
  return std::isfinite(v) ? Json(v) : Json(nullptr);
}

Json vec_json(const Vec3& v) {
  return Json::array({num(v[0]), num(v[1]), num(v[2])});
}

/// A CSV field: the number, or empty when it is not finite (never NaN or ∞ in a file).
struct Field {
  double v;
};
std::ostream& operator<<(std::ostream& os, Field f) {
  if (std::isfinite(f.v)) os << f.v;
  return os;
}

/// Probe column names: <name>_x, <name>_y, <name>_z per probe.
void probe_columns(std::ostream& csv, const BuiltScene& scene) {
  for (const auto& p : scene.probes)
    csv << "," << p.spec.name << "_x," << p.spec.name << "_y," << p.spec.name << "_z";
  csv << "\n";
}

void probe_values(std::ostream& csv, const std::vector<Vec3>& probes) {
  for (const auto& v : probes)
    csv << "," << Field{v[0]} << "," << Field{v[1]} << "," << Field{v[2]};
  csv << "\n";
}

/// A CSV field of free text: commas and quotes replaced by ';'.
std::string csv_text(std::string s) {
  for (char& ch : s)
    if (ch == ',' || ch == '"' || ch == '\n') ch = ';';
  return s;
}

std::string trace_csv(const BuiltScene& scene, const SceneRunResult& res) {
  std::ostringstream csv;
  csv << std::setprecision(10);
  if (scene.is_needle()) {
    // The 2D columns; a 3D scene names the element count "tetrahedra" and appends its own.
    const bool three_d = scene.needle3d != nullptr;
    csv << "update,depth,tip_x,tip_y,sticking,slipping,rearrangements,cg_iterations,"
           "update_seconds,needle_force_x,needle_force_y,status,solves,max_cg_iterations,"
           "bisections,intercepted,released,nodes,"
        << (three_d ? "tetrahedra" : "triangles") << ",flops"
        << (three_d ? ",tip_z,needle_force_z,surface_faces,surface_area,refine_seconds,"
                      "solve_seconds,rearrange_seconds,factorizations,replaced_columns"
                    : "")
        << "\n";
    for (const auto& r : res.needle_updates) {
      csv << r.update << "," << Field{r.depth} << "," << Field{r.tip.x()} << "," << Field{r.tip.y()}
          << "," << r.sticking << "," << r.slipping << "," << r.rearrangements << ","
          << r.cg_iterations << "," << r.seconds << "," << Field{r.needle_force.x()} << ","
          << Field{r.needle_force.y()} << "," << csv_text(r.status) << "," << r.solves << ","
          << r.max_cg_iterations << "," << r.bisections << "," << r.intercepted << "," << r.released
          << "," << r.nodes << "," << r.triangles << "," << r.flops;
      if (three_d)
        csv << "," << Field{r.tip.z()} << "," << Field{r.needle_force.z()} << "," << r.surface_faces
            << "," << Field{r.surface_area} << "," << r.seconds_refine << "," << r.seconds_solve
            << "," << r.seconds_rearrange << "," << r.factorizations << "," << r.replaced_columns;
      csv << "\n";
    }
    return csv.str();
  }
  if (!res.cut_steps.empty()) {
    csv << "step,tool,triangles,status,degenerate_sweep,faces_dissected,nodes_snapped,new_nodes,"
           "nodes,"
           "tetrahedra,m,dirichlet,gmres_iterations,gmres_relative_residual,nnz_l,cut_seconds,"
           "update_seconds,update_cpu_seconds,preconditioner_dropped,amplification,swap_seconds";
    probe_columns(csv, scene);
    for (const auto& c : res.cut_steps) {
      const std::string status = csv_text(c.status);
      csv << c.step << "," << c.tool << "," << c.triangles << "," << status << ","
          << c.degenerate_sweep << "," << c.faces_dissected << "," << c.nodes_snapped << ","
          << c.new_nodes << "," << c.nodes << "," << c.tetrahedra << "," << c.m << ","
          << c.dirichlet << "," << c.gmres_iterations << "," << Field{c.gmres_relative_residual}
          << "," << c.nnz_l << "," << c.seconds_cut << "," << c.seconds_update << ","
          << c.cpu_seconds_update << "," << c.preconditioner_dropped << ","
          << Field{c.amplification} << "," << c.seconds_swap;
      probe_values(csv, c.probes);
    }
  } else {
    csv << "iteration,residual_norm,relative_residual,energy,flops,seconds,cpu_seconds";
    if (res.has_reference) csv << ",relative_energy_error";
    probe_columns(csv, scene);
    for (const auto& row : res.trace) {
      csv << row.iteration << "," << Field{row.residual_norm} << ","
          << Field{row.residual_norm / res.external_force_norm} << "," << Field{row.energy} << ","
          << row.flops << "," << row.seconds << "," << row.cpu_seconds;
      if (res.has_reference) csv << "," << Field{row.relative_energy_error};
      probe_values(csv, row.probes);
    }
  }
  return csv.str();
}

}  // namespace

namespace {

/// Digits of the frame index of iteration and cut-step frames: 6, more when `last` needs more.
std::size_t frame_index_width(long last) {
  return std::max<std::size_t>(6, std::to_string(std::max(last, 0L)).size());
}

}  // namespace

void FrameWriter::frame(const std::string& file, double time) {
  const OutputSpec& outs = scene_.spec.outputs;
  ++frames_;
  pvd_.push_back({time, std::filesystem::path(file).filename().string()});
  write_atomically(outs.vtu + ".pvd", [&](const std::string& tmp) { io::write_pvd(tmp, pvd_); });
}

void FrameWriter::iteration(const solver::IterationInfo& info) {
  const OutputSpec& outs = scene_.spec.outputs;
  if (outs.vtu.empty() || outs.vtu_every <= 0 || info.iteration % outs.vtu_every != 0 ||
      !info.u->allFinite())
    return;
  const std::string file =
      outs.vtu + "_" +
      padded(info.iteration, frame_index_width(scene_.spec.solver.max_iterations)) + ".vtu";
  const FieldArrays f = tet_fields(scene_, *info.u);
  write_vtu_atomic(file, scene_.mesh, f.point, f.cell, outs.vtu_format);
  frame(file, info.time >= 0 ? info.time : static_cast<double>(info.iteration));
}

void FrameWriter::cut_step(const CutStepRow& row, const interactive::AugmentedCutSession& session) {
  const OutputSpec& outs = scene_.spec.outputs;
  const Eigen::Matrix3Xd& d = session.displacement();
  if (outs.vtu.empty() || outs.vtu_every <= 0 || row.step % outs.vtu_every != 0 || !d.allFinite())
    return;
  const std::string file = outs.vtu + "_" + padded(row.step, frame_index_width(0)) + ".vtu";
  const Eigen::Index n0 = static_cast<Eigen::Index>(scene_.external_force.size() / 3);
  const auto problem =
      cut_session_problem(session, make_material(scene_.spec.material),
                          Eigen::Map<const Eigen::Matrix3Xd>(scene_.external_force.data(), 3, n0));
  const VecX u = Eigen::Map<const VecX>(d.data(), d.size());
  VecX g;
  const bool ok = problem->gradient(u, g) == EvalStatus::kOk;
  const FieldArrays f = tet_fields(*problem, u, ok ? &g : nullptr);
  write_vtu_atomic(file, live_mesh_data(session.mesh()), f.point, f.cell, outs.vtu_format);
  frame(file, static_cast<double>(row.step));
}

namespace {

/// Appends `a` to `to` unless it holds a NaN or infinity (never written to a file).
void add_finite(std::vector<io::DataArray>& to, io::DataArray a) {
  for (double v : a.values)
    if (!std::isfinite(v)) return;
  to.push_back(std::move(a));
}

}  // namespace

FieldArrays tet_fields(const BuiltScene& scene, const VecX& u) {
  if (!scene.problem || scene.problem->size() != u.size()) return {{displacement_array(u)}, {}};
  VecX g;
  const bool ok = scene.problem->gradient(u, g) == EvalStatus::kOk;
  return tet_fields(*scene.problem, u, ok ? &g : nullptr);
}

namespace {

/// "displacement" of in-plane displacements u (2 per node, m) with three components, z = 0.
io::DataArray planar_displacement_array(const VecX& u2) {
  const Eigen::Index n = u2.size() / 2;
  io::DataArray u{"displacement", 3, std::vector<double>(static_cast<std::size_t>(3 * n), 0.0)};
  for (Eigen::Index v = 0; v < n; ++v) {
    u.values[static_cast<std::size_t>(3 * v)] = u2[2 * v];
    u.values[static_cast<std::size_t>(3 * v + 1)] = u2[2 * v + 1];
  }
  return u;
}

/// The arrays of a problem `p` with `dim` DOFs per node at u (tet_fields() and tri_fields()):
/// `displacement` (u as 3 components per node), then, when u is p's size, "reaction_force" (3
/// components; when `g`, the gradient at u, is given), "fixed", "loaded", and the cell arrays of
/// fem::element_fields().
template <class P>
FieldArrays state_arrays(const P& p, const VecX& u, const VecX* g, io::DataArray displacement,
                         int dim) {
  FieldArrays out;
  out.point.push_back(std::move(displacement));
  if (p.size() != u.size()) return out;
  fem::ElementFields fields = fem::element_fields(p, u);
  const std::size_t n = static_cast<std::size_t>(p.num_nodes());
  if (g != nullptr && g->size() == p.size()) {
    io::DataArray reaction{"reaction_force", 3, std::vector<double>(3 * n, 0.0)};
    for (Eigen::Index i = 0; i < p.size(); ++i)
      if (p.is_fixed(i))
        reaction.values[static_cast<std::size_t>(3 * (i / dim) + i % dim)] = (*g)[i];
    add_finite(out.point, std::move(reaction));
  }
  io::DataArray fixed{"fixed", 1, std::vector<double>(n, 0.0), io::DataArray::Type::kUInt8};
  io::DataArray loaded{"loaded", 1, std::vector<double>(n, 0.0), io::DataArray::Type::kUInt8};
  const VecX& f = p.external_force();
  for (Eigen::Index i = 0; i < p.size(); ++i) {
    const std::size_t v = static_cast<std::size_t>(i / dim);
    if (p.is_fixed(i)) fixed.values[v] = 1;
    if (f[i] != 0.0) loaded.values[v] = 1;
  }
  out.point.push_back(std::move(fixed));
  out.point.push_back(std::move(loaded));
  add_finite(out.cell, {"strain", 6, std::move(fields.strain)});
  add_finite(out.cell, {"second_piola_stress", 6, std::move(fields.second_piola)});
  add_finite(out.cell, {"cauchy_stress", 6, std::move(fields.cauchy)});
  add_finite(out.cell, {"von_mises_stress", 1, std::move(fields.von_mises)});
  add_finite(out.cell, {"strain_energy_density", 1, std::move(fields.energy_density)});
  out.cell.push_back({"inverted", 1,
                      std::vector<double>(fields.inverted.begin(), fields.inverted.end()),
                      io::DataArray::Type::kUInt8});
  return out;
}

}  // namespace

FieldArrays tet_fields(const fem::ElasticProblem& p, const VecX& u, const VecX* g) {
  return state_arrays(p, u, g, displacement_array(u), 3);
}

FieldArrays tri_fields(const fem::PlaneStressProblem& p, const VecX& u, const VecX* g) {
  return state_arrays(p, u, g, planar_displacement_array(u), 2);
}

namespace {

/// "needle_state" of an insertion's nodes (0 no needle node, 1 sticking, 2 slipping).
template <class Insertion>
io::DataArray needle_state_array(const Insertion& insertion, Index nodes) {
  io::DataArray state{"needle_state", 1, std::vector<double>(static_cast<std::size_t>(nodes))};
  for (const auto& nd : insertion.needle_nodes())
    state.values[static_cast<std::size_t>(nd.vertex)] =
        nd.state == needle::NodeState::kStick ? 1.0 : 2.0;
  return state;
}

}  // namespace

FieldArrays needle_fields(const needle::NeedleInsertion& insertion) {
  const fem::PlaneStressProblem& p = insertion.problem();
  FieldArrays f = tri_fields(p, insertion.displacement());
  f.point.push_back(needle_state_array(insertion, p.num_nodes()));
  return f;
}

FieldArrays needle_fields(const needle::NeedleInsertion3D& insertion, const mesh::MeshData& mesh) {
  const fem::ElasticProblem& p = insertion.problem();
  FieldArrays f = tet_fields(p, insertion.displacement());
  f.point.push_back(needle_state_array(insertion, p.num_nodes()));
  f.cell.push_back(needle_cell_data(insertion, mesh));
  return f;
}

namespace {

/// The zero-padded update index of a needle frame that is due (every vtu_every updates and the
/// last planned one, finite displacement), "" when none is.
template <class Insertion>
std::string needle_frame_index(const OutputSpec& outs, const NeedleUpdateRow& row,
                               std::size_t total_updates, const Insertion& insertion) {
  const long last = static_cast<long>(total_updates) - 1;
  if (outs.vtu.empty() || outs.vtu_every <= 0 ||
      (row.update % outs.vtu_every != 0 && row.update != last) ||
      !insertion.displacement().allFinite())
    return "";
  const std::size_t width = std::max<std::size_t>(4, std::to_string(std::max(last, 0L)).size());
  std::string index = std::to_string(row.update);
  index.insert(0, width > index.size() ? width - index.size() : 0, '0');
  return index;
}

}  // namespace

void FrameWriter::needle_update(const NeedleUpdateRow& row, std::size_t total_updates,
                                const needle::NeedleInsertion& insertion) {
  const OutputSpec& outs = scene_.spec.outputs;
  const std::string index = needle_frame_index(outs, row, total_updates, insertion);
  if (index.empty()) return;
  const std::string file = outs.vtu + "_" + index + ".vtu";
  const FieldArrays f = needle_fields(insertion);
  write_vtu_atomic(file, insertion.mesh().to_mesh_data(), f.point, f.cell, outs.vtu_format);
  frame(file, static_cast<double>(row.update));
}

io::DataArray needle_cell_data(const needle::NeedleInsertion3D& insertion,
                               const mesh::MeshData& mesh) {
  std::vector<std::array<Index, 3>> faces;
  const mesh::CellMatrix& surface = insertion.needle_surface();
  for (Eigen::Index f = 0; f < surface.cols(); ++f)
    faces.push_back({surface(0, f), surface(1, f), surface(2, f)});  // sorted triples
  std::sort(faces.begin(), faces.end());
  io::DataArray a{"needle_faces", 1,
                  std::vector<double>(static_cast<std::size_t>(mesh.num_cells()))};
  for (Eigen::Index c = 0; c < mesh.cells.cols(); ++c)
    for (const auto& lf : mesh::kTetFace) {
      std::array<Index, 3> t{mesh.cells(lf[0], c), mesh.cells(lf[1], c), mesh.cells(lf[2], c)};
      std::sort(t.begin(), t.end());
      if (std::binary_search(faces.begin(), faces.end(), t))
        a.values[static_cast<std::size_t>(c)] += 1.0;
    }
  return a;
}

void write_needle_surface_vtu(const std::string& path, const needle::NeedleInsertion3D& insertion,
                              io::VtuEncoding encoding) {
  mesh::MeshData m;
  m.dimension = 2;
  m.points = insertion.mesh().points();
  m.cells = insertion.needle_surface();
  const Eigen::Matrix3Xd x = insertion.deformed();
  io::DataArray area{"area", 1, std::vector<double>(static_cast<std::size_t>(m.cells.cols()))};
  for (Eigen::Index f = 0; f < m.cells.cols(); ++f)
    area.values[static_cast<std::size_t>(f)] =
        0.5 * (x.col(m.cells(1, f)) - x.col(m.cells(0, f)))
                  .cross(x.col(m.cells(2, f)) - x.col(m.cells(0, f)))
                  .norm();
  const std::vector<io::DataArray> point = {displacement_array(insertion.displacement())};
  write_vtu_atomic(path, m, point, {area}, encoding);
}

void FrameWriter::needle_update(const NeedleUpdateRow& row, std::size_t total_updates,
                                const needle::NeedleInsertion3D& insertion) {
  const OutputSpec& outs = scene_.spec.outputs;
  const std::string index = needle_frame_index(outs, row, total_updates, insertion);
  if (index.empty()) return;
  const std::string file = outs.vtu + "_" + index + ".vtu";
  const std::string surface = outs.vtu + "_needle_" + index + ".vtu";
  const mesh::MeshData m = insertion.mesh().to_mesh_data();
  const FieldArrays f = needle_fields(insertion, m);
  write_vtu_atomic(file, m, f.point, f.cell, outs.vtu_format);
  write_needle_surface_vtu(surface, insertion, outs.vtu_format);
  surface_pvd_.push_back(
      {static_cast<double>(row.update), std::filesystem::path(surface).filename().string()});
  frame(file, static_cast<double>(row.update));
  write_atomically(outs.vtu + "_needle.pvd",
                   [&](const std::string& tmp) { io::write_pvd(tmp, surface_pvd_); });
}

std::vector<std::string> write_outputs(const BuiltScene& scene, const SceneRunResult& result,
                                       const OutputOptions& options) {
  const OutputSpec& outs = scene.spec.outputs;
  std::vector<std::string> written;
  if (!outs.csv.empty()) {
    write_file_atomic(outs.csv, trace_csv(scene, result));
    written.push_back(outs.csv);
  }
  if (!outs.vtu.empty() && result.u.allFinite()) {  // else: summary "not_written"
    const std::string f = outs.vtu + ".vtu";
    std::string f_extra;  // 3D needle: the final needle surface, listed after f
    if (scene.needle) {
      const FieldArrays fields = needle_fields(*scene.needle);
      write_vtu_atomic(f, scene.mesh, fields.point, fields.cell, outs.vtu_format);
    } else if (scene.needle3d) {
      const FieldArrays fields = needle_fields(*scene.needle3d, scene.mesh);
      write_vtu_atomic(f, scene.mesh, fields.point, fields.cell, outs.vtu_format);
      const std::string sf = outs.vtu + "_needle.vtu";
      write_needle_surface_vtu(sf, *scene.needle3d, outs.vtu_format);
      written.push_back(f);
      f_extra = sf;
    } else {  // an augmented cut run has replaced scene.mesh and scene.problem by the cut ones
      const FieldArrays fields = tet_fields(scene, result.u);
      write_vtu_atomic(f, scene.mesh, fields.point, fields.cell, outs.vtu_format);
    }
    written.push_back(f_extra.empty() ? f : f_extra);
    if (options.frames > 0)
      written.push_back(std::to_string(options.frames) + " frames " + outs.vtu +
                        (scene.needle3d
                             ? "_<update>.vtu and " + outs.vtu + "_needle_<update>.vtu, indices " +
                                   outs.vtu + ".pvd and " + outs.vtu + "_needle.pvd"
                         : scene.needle             ? "_<update>.vtu, index " + outs.vtu + ".pvd"
                         : result.cut_steps.empty() ? "_<it>.vtu, index " + outs.vtu + ".pvd"
                                                    : "_<step>.vtu, index " + outs.vtu + ".pvd"));
  }
  if (!options.summary_json.empty()) {
    write_file_atomic(options.summary_json,
                      summary_json(scene, result, options.total_seconds, written));
    written.push_back(options.summary_json);
  }
  return written;
}

FrameTimes frame_times(const SceneRunResult& result) {
  std::vector<double> frame, cut, update, swap;
  for (const auto& c : result.cut_steps) {
    if (c.step == 0) continue;  // the initial factorization and solve
    frame.push_back(c.seconds_cut + c.seconds_update);
    cut.push_back(c.seconds_cut);
    update.push_back(c.seconds_update);
    swap.push_back(c.seconds_swap);
  }
  return {mesh::summarize(frame), mesh::summarize(cut), mesh::summarize(update),
          mesh::summarize(swap)};
}

std::string summary_json(const BuiltScene& scene, const SceneRunResult& result,
                         double total_seconds, const std::vector<std::string>& written) {
  const SceneSpec& spec = scene.spec;
  const solver::SolverReport& rep = result.report;
  Json j;
  j["scene"] = spec.file;
  j["name"] = spec.name;
  j["method"] = to_string(spec.solver.method);
  j["method_detail"] = result.method_detail;
  j["status"] = rep.ok() ? "ok" : "failed";
  j["result"] = solver::to_string(rep.status);
  j["message"] = rep.message;
  j["converged"] = rep.ok();
  j["iterations"] = rep.iterations;
  j["inner_iterations"] = rep.inner_iterations;
  j["residual_norm"] = num(rep.residual_norm);
  j["relative_residual"] = std::isfinite(result.external_force_norm)
                               ? num(rep.residual_norm / result.external_force_norm)
                               : Json(nullptr);
  j["external_force_norm"] = num(result.external_force_norm);
  j["tolerance"] = spec.solver.tolerance;
  j["energy"] = num(rep.energy);
  j["inverted_elements"] =
      result.inverted_elements >= 0 ? Json(result.inverted_elements) : Json(nullptr);
  j["allow_inversion"] = spec.material.allow_inversion;
  j["flops"] = rep.flops;
  j["solver_seconds"] = rep.seconds;
  j["solver_cpu_seconds"] = rep.cpu_seconds;
  j["total_seconds"] = total_seconds;
  for (const auto& [key, value] : result.environment.fields()) j["environment"][key] = value;
  if (spec.solver.method == SolverSpec::Method::kDynamicSS22) {
    j["restarts"] = rep.restarts;
    j["final_time_step"] = rep.time_step;
  }
  if (result.has_reference) j["relative_energy_error"] = num(result.relative_energy_error);
  j["mesh"] = {{"nodes", scene.mesh.num_points()},
               {scene.mesh.dimension == 2 ? "triangles" : "tetrahedra", scene.mesh.num_cells()},
               {"fixed_nodes", scene.fixed_nodes.size()}};
  for (const auto& p : result.probes) {
    Json pj = {{"name", p.name}, {"displacement", vec_json(p.value)}};
    if (p.reference) {
      pj["reference"] = vec_json(*p.reference);
      pj["relative_error"] = num(p.relative_error);
    }
    if (!p.note.empty()) pj["note"] = p.note;
    j["probes"].push_back(pj);
  }
  for (const auto& s : scene.steps)
    j["built"].push_back({{"what", s.what},
                          {"seconds", s.seconds},
                          {"bytes", s.bytes},
                          {"flops", s.flops >= 0 ? Json(s.flops) : Json(nullptr)}});
  j["not_built"] = scene.not_built;
  for (const auto& c : result.cut_steps) {
    Json cj = {{"step", c.step},
               {"tool", c.tool},
               {"triangles", c.triangles},
               {"status", c.status},
               {"degenerate_sweep", c.degenerate_sweep},
               {"faces_dissected", c.faces_dissected},
               {"nodes_snapped", c.nodes_snapped},
               {"new_nodes", c.new_nodes},
               {"nodes", c.nodes},
               {"tetrahedra", c.tetrahedra},
               {"m", c.m},
               {"dirichlet", c.dirichlet},
               {"gmres_iterations", c.gmres_iterations},
               {"gmres_relative_residual", num(c.gmres_relative_residual)},
               {"preconditioner_dropped", c.preconditioner_dropped},
               {"preconditioner_rcond", num(c.preconditioner_rcond)},
               {"amplification", num(c.amplification)},
               {"amplification_warning", c.amplification_warning},
               {"nnz_l", c.nnz_l},
               {"refactorization_started", c.refactorization_started},
               {"refactorization_swapped", c.refactorization_swapped},
               {"cut_seconds", c.seconds_cut},
               {"update_seconds", c.seconds_update},
               {"update_cpu_seconds", c.cpu_seconds_update},
               {"swap_seconds", c.seconds_swap}};
    for (std::size_t k = 0; k < c.probes.size() && k < scene.probes.size(); ++k)
      cj["probes"][scene.probes[k].spec.name] = vec_json(c.probes[k]);
    j["cut_steps"].push_back(cj);
  }
  for (const auto& r : result.needle_updates)
    j["needle_updates"].push_back(
        {{"update", r.update},
         {"depth", num(r.depth)},
         {"tip", scene.needle3d ? Json::array({num(r.tip.x()), num(r.tip.y()), num(r.tip.z())})
                                : Json::array({num(r.tip.x()), num(r.tip.y())})},
         {"status", r.status},
         {"sticking", r.sticking},
         {"slipping", r.slipping},
         {"rearrangements", r.rearrangements},
         {"solves", r.solves},
         {"cg_iterations", r.cg_iterations},
         {"max_cg_iterations", r.max_cg_iterations},
         {"bisections", r.bisections},
         {"intercepted", r.intercepted},
         {"released", r.released},
         {"nodes", r.nodes},
         {"triangles", r.triangles},
         {"needle_force", scene.needle3d
                              ? Json::array({num(r.needle_force.x()), num(r.needle_force.y()),
                                             num(r.needle_force.z())})
                              : Json::array({num(r.needle_force.x()), num(r.needle_force.y())})},
         {"flops", r.flops},
         {"update_seconds", r.seconds}});
  if (scene.needle3d)
    for (std::size_t k = 0; k < result.needle_updates.size(); ++k) {
      const auto& r = result.needle_updates[k];
      Json& row = j["needle_updates"][k];
      row["surface_faces"] = r.surface_faces;
      row["surface_area"] = num(r.surface_area);
      row["refine_seconds"] = r.seconds_refine;
      row["solve_seconds"] = r.seconds_solve;
      row["rearrange_seconds"] = r.seconds_rearrange;
    }
  if (!result.cut_steps.empty()) {
    int dropped = 0;
    for (const auto& c : result.cut_steps) dropped += c.preconditioner_dropped ? 1 : 0;
    j["preconditioner_dropped_solves"] = dropped;
    const FrameTimes t = frame_times(result);
    j["frame_seconds"] = {{"frames", t.frame.count},
                          {"median", t.frame.median},
                          {"p95", t.frame.p95},
                          {"max", t.frame.max}};
    j["cut_seconds"] = {{"median", t.cut.median}, {"p95", t.cut.p95}, {"max", t.cut.max}};
    j["update_seconds"] = {
        {"median", t.update.median}, {"p95", t.update.p95}, {"max", t.update.max}};
    j["swap_seconds"] = {{"median", t.swap.median}, {"p95", t.swap.p95}, {"max", t.swap.max}};
  }
  j["outputs"] = written;
  j["not_written"] = Json::array();
  if (!spec.outputs.vtu.empty() && !result.u.allFinite())
    j["not_written"].push_back(spec.outputs.vtu + ".vtu: the displacement is not finite");
  return j.dump(2) + "\n";
}

}  // namespace incise::scene
