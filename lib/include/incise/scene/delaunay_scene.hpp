#pragma once
/// \file delaunay_scene.hpp
/// Delaunay cutting scenes (thesis ch. 5; docs/scenes.md, "Delaunay cutting scenes"): a 2D
/// triangle mesh cut by a point scalpel (delaunay::Cutter2D, §5.2.2, or the subdivision cutter
/// of Fig. 5.16), a triangle surface in 3D cut by a line-segment scalpel (delaunay::
/// SurfaceCutter, §5.3), or a pre-stretched plane-stress sheet cut while it deforms
/// (interactive::DelaunayCutSession, §5.5). A scene file is a Delaunay scene when its first tool
/// has type "scalpel2d" or "surface_scalpel" (is_delaunay_scene); `incise run` then parses,
/// runs and writes it here instead of through scene_parser/scene_builder/scene_runner.
///
/// Movements: the scalpel samples are joined by straight movements of at most `step` · h̄
/// (delaunay::movement_points / movement_segments), h̄ the start mesh's mean edge length; each
/// movement is one `move_to` and one CSV row. The subdivision cutter cuts the whole path at once
/// (one movement). Thresholds are fractions of h̄ (§5.4 defaults ε_edge = h̄/3, ε_entry = ε_exit =
/// h̄/6) or, for ε_edge, the §5.5 angle rule.
#include <incise/core/environment.hpp>
#include <incise/delaunay/cutter2d.hpp>
#include <incise/delaunay/sweep.hpp>
#include <incise/scene/line_index.hpp>
#include <incise/scene/scene_spec.hpp>

#include <functional>
#include <string>
#include <vector>

namespace incise::scene {

/// The start mesh of a Delaunay scene (scene key `mesh`).
struct DelaunayMeshSpec {
  /// Where it comes from.
  enum class Source {
    kRectangle,  ///< mesh::make_rectangle: nx × ny squares of lx × ly, alternating diagonals
    kFile,       ///< io::read_mesh: a triangle mesh (OFF, Medit, Gmsh)
    kSurface     ///< delaunay::make_surface: a generated surface (cylinder patch, bell, fold)
  };
  Source source = Source::kRectangle;
  int nx = 1, ny = 1;     ///< kRectangle: squares per axis; kSurface: grid n × m (ny = m)
  double lx = 1, ly = 1;  ///< kRectangle: sizes (m)
  std::string file;       ///< kFile: resolved path
  double scale = 1.0;     ///< kFile: coordinate factor
  std::string shape;      ///< kSurface: "cylinder", "bell" or "fold"
};

/// Names of DelaunayMeshSpec::Source (scene key `type` of the mesh).
inline constexpr NameTable<DelaunayMeshSpec::Source, 3> kDelaunayMeshSourceNames{{{
    {DelaunayMeshSpec::Source::kRectangle, "rectangle"},
    {DelaunayMeshSpec::Source::kFile, "file"},
    {DelaunayMeshSpec::Source::kSurface, "surface"},
}}};

/// Which cutter a 2D scalpel drives (scene key `cutter`).
enum class DelaunayCutterKind {
  kDelaunay,    ///< delaunay::Cutter2D (§5.2.2)
  kSubdivision  ///< delaunay::subdivision_cut (Fig. 5.16 top)
};

/// Names of DelaunayCutterKind.
inline constexpr NameTable<DelaunayCutterKind, 2> kDelaunayCutterNames{{{
    {DelaunayCutterKind::kDelaunay, "delaunay"},
    {DelaunayCutterKind::kSubdivision, "subdivision"},
}}};

/// Names of delaunay::ShortEdgeRule (scene key `short_edge`).
inline constexpr NameTable<delaunay::ShortEdgeRule, 2> kShortEdgeRuleNames{{{
    {delaunay::ShortEdgeRule::kDistance, "distance"},
    {delaunay::ShortEdgeRule::kAngle, "angle"},
}}};

/// The pre-stretched sheet of a deforming cut (scene key `sheet`, §5.5;
/// interactive::DelaunayCutSession): material in plane stress, held lines, one loaded line.
struct SheetSpec {
  MaterialSpec material;
  double thickness = 0;          ///< m, > 0
  std::vector<Vec2> fixed;       ///< (axis, value) of each held line
  Vec2 loaded = Vec2::Zero();    ///< (axis, value) of the loaded line
  Vec2 traction = Vec2::Zero();  ///< N/m² on the loaded line's boundary edges
  double tolerance = 1e-8;       ///< CG: ‖r‖ ≤ tolerance ‖f_ext‖ (6.8)
  long max_iterations = 20000;   ///< CG steps per solve
};

/// A whole Delaunay scene.
struct DelaunaySceneSpec {
  std::string file;  ///< the scene file
  std::string name, description;
  DelaunayMeshSpec mesh;
  bool surface = false;  ///< the tool is a "surface_scalpel" (§5.3); else "scalpel2d" (§5.2)
  DelaunayCutterKind cutter = DelaunayCutterKind::kDelaunay;
  std::vector<Vec2> path;                       ///< scalpel2d: samples (m), ≥ 2
  std::vector<delaunay::ScalpelSegment> blade;  ///< surface_scalpel: samples (m), ≥ 2
  double step = 0.1;                            ///< movement length / h̄, > 0
  delaunay::Cutter2DOptions options;            ///< thresholds (fractions of h̄) and rule
  bool has_sheet = false;                       ///< a deforming cut (§5.5)
  SheetSpec sheet;
  std::string csv, vtu, svg;  ///< outputs ("" = none)
  int vtu_every = 1;          ///< a VTU frame every this many movements (and the last)
  LineIndex lines;            ///< line of each JSON value, for messages
};

/// True when the file at `path` is a JSON object whose first tool has type "scalpel2d" or
/// "surface_scalpel". Never throws: an unreadable or invalid file is false (load_scene reports).
bool is_delaunay_scene(const std::string& path);

/// Parses a Delaunay scene; errors as parse_scene's (ParseError "<file>:<line>: <path>: ...").
/// Also checks the start mesh: a surface must be an oriented 2-manifold with boundary, a 2D mesh
/// planar and counter-clockwise (reported at /mesh).
DelaunaySceneSpec parse_delaunay_scene(const std::string& text, const std::string& file,
                                       const std::string& base_dir);

/// Reads and parses the scene at `path` (limits as load_scene).
DelaunaySceneSpec load_delaunay_scene(const std::string& path);

/// One movement of a Delaunay run (a CSV row).
struct DelaunayMovementRow {
  long movement = 0;       ///< 0-based
  Index triangles = 0;     ///< live triangles after the movement
  Index vertices = 0;      ///< vertices of live triangles
  long flips = 0;          ///< edge flips
  int removals = 0;        ///< interior nodes removed (Fig. 5.10)
  int splits = 0;          ///< incision splits (Fig. 5.5)
  bool entered = false;    ///< an incision started (any entry of Fig. 5.12)
  bool exited = false;     ///< an incision reached the boundary (Fig. 5.7)
  int incisions = 0;       ///< live incisions after the movement (0 or 1 in 2D)
  std::string status;      ///< "ok", "blocked", "lost"; a sheet's failed solve: its reason
  double min_angle = 0;    ///< smallest angle of the mesh (degrees)
  double max_angle = 0;    ///< largest angle (degrees)
  long cg_iterations = 0;  ///< sheet: CG steps of the solve
  double residual = 0;     ///< sheet: final ‖r‖ (N)
  double opening = 0;      ///< sheet: largest distance of the deformed incision sides (m)
};

/// Outcome of run_delaunay_scene().
struct DelaunayRunResult {
  RunEnvironment environment;
  std::vector<DelaunayMovementRow> rows;
  Index triangles_before = 0, triangles_after = 0;
  int components = 0;           ///< connected pieces of the final mesh
  long entries = 0, exits = 0;  ///< movements with an entry, an exit
  long blocked = 0, lost = 0;   ///< movements with those statuses
  /// "ok"; for a sheet whose solve failed, the solver::StopReason name (the run stops there)
  std::string status = "ok";
  std::string message;               ///< what failed ("" when ok)
  double seconds = 0;                ///< wall time of the movements (s)
  std::vector<std::string> written;  ///< files written, in order
  bool ok() const { return status == "ok"; }
};

/// Called after every movement with the row and the number of movements planned.
using DelaunayObserver = std::function<void(const DelaunayMovementRow&, std::size_t total)>;

/// Builds the start mesh, moves the scalpel through every planned movement and writes the files
/// the scene's outputs name: the CSV (one row per movement), VTU frames `<vtu>_<movement>.vtu`
/// (zero-padded to max(4, digits)) every vtu_every movements and at the last, indexed by
/// `<vtu>.pvd` (timestep = movement), the final `<vtu>.vtu`, the SVG of a 2D final mesh with the
/// path (delaunay::mesh_svg), and `summary_json` when non-empty. Numerical failure (a sheet's
/// solve) is result.status, never thrown; files that cannot be written throw.
DelaunayRunResult run_delaunay_scene(const DelaunaySceneSpec& spec, const std::string& summary_json,
                                     const DelaunayObserver& observer = {});

}  // namespace incise::scene
