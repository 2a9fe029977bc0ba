// The `incise` Python module (pybind11; docs/python.md): load and check a mesh, run a scene and get
// its arrays and report, run the certification catalogue and get its results. A thin layer: every
// computation is the library's; arrays are copied into NumPy arrays (the library's storage is not
// exposed, so nothing a script holds can dangle); library exceptions become Python exceptions
// (ParseError → incise.ParseError, a ValueError, with file:line; ParameterError/UsageError →
// ValueError; anything else → RuntimeError). Numerical failures are not exceptions: they are the
// status fields of the returned reports, as in the library.

#include <incise/certify/certify.hpp>
#include <incise/core/environment.hpp>
#include <incise/core/error.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/validate.hpp>
#include <incise/scene/scene_builder.hpp>
#include <incise/scene/scene_outputs.hpp>
#include <incise/scene/scene_parser.hpp>
#include <incise/scene/scene_runner.hpp>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <string>
#include <vector>

namespace py = pybind11;

namespace {

using namespace incise;

/// Copies a column-major 3 × n (or k × n) matrix into a NumPy array of shape (n, rows).
template <typename Matrix>
py::array_t<typename Matrix::Scalar> rows_of(const Matrix& m, Eigen::Index rows) {
  using Scalar = typename Matrix::Scalar;
  py::array_t<Scalar> out({static_cast<py::ssize_t>(m.cols()), static_cast<py::ssize_t>(rows)});
  auto a = out.template mutable_unchecked<2>();
  for (Eigen::Index j = 0; j < m.cols(); ++j)
    for (Eigen::Index i = 0; i < rows; ++i) a(j, i) = m(i, j);
  return out;
}

py::array_t<double> vector_of(const std::vector<double>& v) {
  py::array_t<double> out(static_cast<py::ssize_t>(v.size()));
  std::copy(v.begin(), v.end(), out.mutable_data());
  return out;
}

py::dict mesh_arrays(const mesh::MeshData& m) {
  py::dict d;
  d["dimension"] = m.dimension;
  d["points"] = rows_of(m.points, 3);
  d["cells"] = rows_of(m.cells, m.cells.rows());
  d["cell_tags"] = m.cell_tags;
  return d;
}

py::dict environment_dict() {
  py::dict d;
  for (const auto& [key, value] : capture_environment().fields()) d[key.c_str()] = value;
  return d;
}

/// read_mesh + what the reader found + the ch. 7 invariants + per-cell quality.
py::dict check_mesh(const std::string& path, bool reorient, bool merge_duplicates, double scale) {
  io::ReadOptions opt;
  opt.reorient = reorient;
  opt.merge_duplicate_vertices = merge_duplicates;
  opt.scale = scale;
  const io::LoadedMesh loaded = io::read_mesh(path, opt);
  const mesh::MeshData& m = loaded.mesh;
  py::dict d = mesh_arrays(m);
  const io::LoadReport& r = loaded.report;
  py::dict report;
  report["file"] = r.file;
  report["format"] = r.format;
  report["num_points"] = r.num_points;
  report["num_cells"] = r.num_cells;
  report["num_facets"] = r.num_facets;
  report["surface"] = r.surface;
  report["reoriented"] = r.reoriented;
  report["duplicate_vertices"] = r.duplicate_vertices;
  report["merged_vertices"] = r.merged_vertices;
  report["unused_vertices"] = r.unused_vertices;
  report["pinched_vertices"] = r.pinched_vertices;
  report["notes"] = r.notes;
  d["load_report"] = report;
  // Invariants (7.1)-(7.5) with orientation in the reference configuration.
  const mesh::Connectivity conn = mesh::Connectivity::from_mesh_data(m);
  mesh::ValidateOptions vo;
  vo.positions = &m.points;
  const mesh::ValidationReport v = mesh::validate(conn, vo);
  py::list violations;
  for (const auto& x : v.violations)
    violations.append(py::dict(py::arg("invariant") = x.invariant, py::arg("message") = x.message));
  d["valid"] = v.ok();
  d["violations"] = violations;
  const bool planar = m.dimension == 2 && !r.surface;
  const mesh::CellQuality q = mesh::cell_quality(m, {}, planar);
  py::dict quality;
  quality["size"] = vector_of(q.size);
  quality["aspect_ratio"] = vector_of(q.aspect_ratio);
  quality["shewchuk"] = vector_of(q.shewchuk);
  quality["min_angle"] = vector_of(q.min_angle);
  quality["max_angle"] = vector_of(q.max_angle);
  std::vector<std::string> shape;
  shape.reserve(q.shape.size());
  for (auto s : q.shape) shape.emplace_back(mesh::to_string(s));
  quality["shape"] = shape;
  d["quality"] = quality;
  return d;
}

/// parse (scene text, or the file at `path` when `text` is empty) + build_scene + run_scene
/// (+ write_outputs when asked); the summary is the JSON text `incise run --summary-json` writes.
py::dict run_scene(const std::string& path, const std::string& text, const std::string& base_dir,
                   bool write_outputs) {
  const auto start = std::chrono::steady_clock::now();
  scene::SceneSpec spec =
      text.empty() ? scene::load_scene(path) : scene::parse_scene(text, path, base_dir);
  scene::BuiltScene built = scene::build_scene(spec);
  scene::SceneRunResult res;
  {
    py::gil_scoped_release release;  // a solve may take seconds; let other Python threads run
    res = scene::run_scene(built);
  }
  const double total =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::vector<std::string> written;
  if (write_outputs) {
    scene::OutputOptions oo;
    oo.total_seconds = total;
    written = scene::write_outputs(built, res, oo);
  }
  py::dict d;
  d["summary_json"] = scene::summary_json(built, res, total, written);
  d["mesh"] = mesh_arrays(built.mesh);
  const int dim = built.mesh.dimension;
  const Eigen::Index n = built.mesh.num_points();
  if (res.u.size() == dim * n) {
    py::array_t<double> u({static_cast<py::ssize_t>(n), static_cast<py::ssize_t>(dim)});
    std::copy(res.u.data(), res.u.data() + res.u.size(), u.mutable_data());
    d["displacement"] = u;
  } else {
    d["displacement"] = py::none();  // the run ended on a different (cut/refined) mesh
  }
  std::vector<double> it, rn, en, sec;
  for (const auto& row : res.trace) {
    it.push_back(static_cast<double>(row.iteration));
    rn.push_back(row.residual_norm);
    en.push_back(row.energy);
    sec.push_back(row.seconds);
  }
  py::dict trace;
  trace["iteration"] = vector_of(it);
  trace["residual_norm"] = vector_of(rn);
  trace["energy"] = vector_of(en);
  trace["seconds"] = vector_of(sec);
  d["trace"] = trace;
  return d;
}

py::dict run_certify(const std::string& data_dir, bool quick, const std::string& filter) {
  certify::CertifySummary s;
  {
    py::gil_scoped_release release;
    s = certify::run_certify(data_dir, quick, filter);
  }
  py::dict d;
  d["summary_json"] = certify::certify_json(s, "python").dump();
  d["html"] = certify::certify_html(s, "python");
  return d;
}

}  // namespace

PYBIND11_MODULE(_incise, m) {
  m.doc() = "incise: FEM of soft tissue that is cut and pierced (docs/python.md)";
  static py::exception<ParseError> parse_error(m, "ParseError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ParseError& e) {
      parse_error(e.what());
    } catch (const ParameterError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const UsageError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  m.def("check_mesh", &check_mesh, py::arg("path"), py::arg("reorient") = false,
        py::arg("merge_duplicates") = false, py::arg("scale") = 1.0,
        "Reads a mesh file (.msh, .mesh, .node/.ele, .off) and returns its arrays, the reader's "
        "report, the ch. 7 invariant check and per-cell quality.");
  m.def("_run_scene", &run_scene, py::arg("path"), py::arg("text"), py::arg("base_dir"),
        py::arg("write_outputs"));
  m.def("_certify", &run_certify, py::arg("data_dir"), py::arg("quick") = true,
        py::arg("filter") = "");
  m.def("environment", &environment_dict, "The machine and build (core/environment.hpp).");
}
