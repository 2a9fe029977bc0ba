#pragma once
/// \file scene_outputs.hpp
/// The files a scene's `outputs` name (docs/scenes.md), written by the library: the VTU frames
/// during a run (FrameWriter, called from run_scene's observers), then the CSV trace, the final
/// VTU and, on request, the run summary as JSON (write_outputs). Each file is written to a
/// temporary name and renamed into place (core/atomic_file.hpp), parent folders are created;
/// paths are relative to the current directory. Nothing is printed.

#include <incise/io/write_mesh.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/scene/scene_builder.hpp>
#include <incise/scene/scene_runner.hpp>
#include <incise/solver/report.hpp>

#include <string>
#include <vector>

namespace incise::interactive {
class AugmentedCutSession;
}  // namespace incise::interactive

namespace incise::scene {

/// Writes the VTU frames `outputs.vtu_every` asks for (none when it is 0 or `vtu` is empty), in
/// the encoding `outputs.vtu_format`, each followed by the ParaView index `<vtu>.pvd` of the
/// frames so far: `<vtu>_<iteration>.vtu` of the scene's mesh with tet_fields() every vtu_every
/// iterations (pvd time: the simulated time of dynamic relaxation, IterationInfo::time, else the
/// iteration), or in an interactive cutting run `<vtu>_<step>.vtu` of the cut mesh with
/// tet_fields() of cut_session_problem() every vtu_every steps (step 0 = initial solve; pvd time =
/// step); the index is zero-padded to 6 digits (more when max_iterations has more). In a needle
/// scene: `<vtu>_<update>.vtu` of the refined slab (triangles; needle_fields()) every vtu_every
/// updates and at the last planned update, the update zero-padded to max(4, digits of the last
/// update), each frame followed by `<vtu>.pvd`, the ParaView index of the frames so far
/// (timestep = update). A 3D needle scene writes the refined tetrahedral mesh the same way
/// (needle_fields() of 3D) and beside it `<vtu>_needle_<update>.vtu`, the needle surface
/// (needle3d.hpp) as triangles with point array "displacement" and cell array "area" (m²,
/// deformed), indexed by `<vtu>_needle.pvd`.
class FrameWriter {
 public:
  /// Keeps a reference to `scene`, which must outlive the writer.
  explicit FrameWriter(const BuiltScene& scene) : scene_(scene) {}
  /// For run_scene's RunObserver: writes the frame of this iteration when one is due.
  void iteration(const solver::IterationInfo& info);
  /// For run_scene's CutStepObserver: writes the frame of this step when one is due.
  void cut_step(const CutStepRow& row, const interactive::AugmentedCutSession& session);
  /// For run_scene's NeedleUpdateObserver: writes the frame of this update when one is due,
  /// then the .pvd index.
  void needle_update(const NeedleUpdateRow& row, std::size_t total_updates,
                     const needle::NeedleInsertion& insertion);
  /// The same for a 3D needle scene (run_scene's NeedleUpdateObserver3D).
  void needle_update(const NeedleUpdateRow& row, std::size_t total_updates,
                     const needle::NeedleInsertion3D& insertion);
  /// Frames written so far.
  long frames() const { return frames_; }

 private:
  /// Counts the frame `file` and rewrites `<vtu>.pvd` with it appended at `time`.
  void frame(const std::string& file, double time);
  const BuiltScene& scene_;
  long frames_ = 0;
  std::vector<io::PvdFrame> pvd_;          ///< frames so far, for the .pvd index
  std::vector<io::PvdFrame> surface_pvd_;  ///< 3D needle-surface frames, for their index
};

/// The arrays of a scene's state (docs/mesh_formats.md "Fields"; units SI).
struct FieldArrays {
  std::vector<io::DataArray> point;  ///< see tet_fields()
  std::vector<io::DataArray> cell;   ///< see tet_fields()
};
/// The arrays written for displacement `u` (3 per node, m) of an elastic problem: point data
/// "displacement" (m), "reaction_force" (N: the residual Σq − f_ext at fixed DOFs, the force
/// the supports exert; 0 at free DOFs; only when `gradient`, the problem's gradient at u, is
/// given), "fixed" and "loaded" (UInt8 0/1: a DOF of the node is
/// fixed / carries a nonzero external force); cell data fem::element_fields(): "strain",
/// "second_piola_stress", "cauchy_stress" (6 components xx yy zz xy yz xz; Pa),
/// "von_mises_stress" (Pa), "strain_energy_density" (J/m³) and "inverted" (UInt8). An array
/// with a NaN or infinity (a diverged run) is left out. "displacement" only when the problem's
/// size is not u's. Written for static and dynamic runs, every frame and the final state of an
/// augmented cut run (cut_session_problem) and every 3D needle frame (the insertion's problem,
/// without reactions: evaluating its gradient would add to the flops the run reports).
FieldArrays tet_fields(const fem::ElasticProblem& problem, const VecX& u,
                       const VecX* gradient = nullptr);
/// tet_fields() of the scene's problem with its gradient at u (reactions); "displacement" only
/// for a scene without a problem.
FieldArrays tet_fields(const BuiltScene& scene, const VecX& u);
/// The same arrays, by the same code, for a plane-stress slab at in-plane displacement `u` (2
/// per node, m): "displacement" with 3 components (z = 0), "reaction_force" (z = 0), and the
/// plane-stress fem::element_fields() (in-plane xx, yy, xy; strain zz = E₃₃, the thickness
/// strain; stress zz ≈ 0; yz = xz = 0).
FieldArrays tri_fields(const fem::PlaneStressProblem& problem, const VecX& u,
                       const VecX* gradient = nullptr);

/// The arrays of a 2D needle frame and of a 2D needle scene's final state: tri_fields() of the
/// insertion's problem (without reactions, as in 3D) and the point array "needle_state" (0: no
/// needle node, 1: sticking, 2: slipping; needle::NodeState).
FieldArrays needle_fields(const needle::NeedleInsertion& insertion);
/// The same for a 3D needle insertion on its mesh `mesh` (to_mesh_data() of the insertion's):
/// tet_fields() without reactions, "needle_state" and the cell array needle_cell_data().
FieldArrays needle_fields(const needle::NeedleInsertion3D& insertion, const mesh::MeshData& mesh);
/// The cell array "needle_faces" of a 3D insertion's mesh (cells in to_mesh_data() order): how
/// many of each tetrahedron's faces are needle-surface faces.
io::DataArray needle_cell_data(const needle::NeedleInsertion3D& insertion,
                               const mesh::MeshData& mesh);
/// The needle surface of a 3D insertion as a triangle mesh on all its vertices (reference
/// positions), with point array "displacement" and cell array "area" (m², deformed); written
/// beside every 3D needle frame.
void write_needle_surface_vtu(const std::string& path, const needle::NeedleInsertion3D& insertion,
                              io::VtuEncoding encoding = io::VtuEncoding::kBinaryZlib);

/// Options of write_outputs().
struct OutputOptions {
  std::string summary_json;  ///< path of the summary JSON ("" = none)
  double total_seconds = 0;  ///< wall time of the whole run (s), reported in the summary
  long frames = 0;           ///< VTU frames written during the run (FrameWriter::frames())
};

/// After run_scene(scene, ...): writes the CSV trace (`outputs.csv`: one row per iteration, or
/// per solve of an interactive cutting run, or per update of a needle scene), the final state
/// `<vtu>.vtu` (a needle scene's with needle_fields()) and, when
/// options.summary_json is set, summary_json() there. Returns what was written, in that order:
/// the paths, with "<n> frames <vtu>_<it>.vtu, index <vtu>.pvd" (or "_<step>.vtu, ..."; a
/// needle scene's "_<update>.vtu, ...") after the final VTU when options.frames > 0. The final
/// VTU of a tetrahedral scene holds tet_fields().
/// Throws Error (or std::filesystem::filesystem_error) when a file cannot be written.
std::vector<std::string> write_outputs(const BuiltScene& scene, const SceneRunResult& result,
                                       const OutputOptions& options = {});

/// Per-frame time statistics of an interactive cutting run (issue 17): over the steps after
/// the initial solve, frame = cut + update (column replacements and augmented solve, of which
/// swap is the §3.6 factor swap); nearest-rank median, p95 and max (mesh::summarize).
struct FrameTimes {
  mesh::Stats frame, cut, update, swap;  ///< seconds
};
/// FrameTimes of result.cut_steps (all zero without cut steps).
FrameTimes frame_times(const SceneRunResult& result);

/// The run summary as JSON text (docs/scenes.md, `incise run --summary-json`): scene file, name,
/// method, result and message, iterations, residual, energy, flops, times, mesh size, probes, built
/// and not-built parts, the cut steps of an interactive cutting run, and `outputs` = `written`.
std::string summary_json(const BuiltScene& scene, const SceneRunResult& result,
                         double total_seconds, const std::vector<std::string>& written);

}  // namespace incise::scene
