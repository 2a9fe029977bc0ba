#pragma once
/// \file scene_spec.hpp
/// The typed form of a scene file (docs/scenes.md). A scene names a mesh, a material, fixed
/// regions, loads, a solver with its tolerance and budgets, optional tools and outputs. The
/// parser (scene_parser.hpp) produces a SceneSpec only when the whole file is valid; the builder
/// (scene_builder.hpp) then constructs only the parts the spec names.
///
/// Units are SI throughout: metres, pascals, newtons, kilograms, seconds. Every enum a scene
/// names by a string has one NameTable (core/name_table.hpp): the scene's own below, those of
/// lower modules with their enums (solver::kPreconditionerNames,
/// linalg::kSchurPreconditionerNames); material models are named by the material registry.

#include <incise/core/name_table.hpp>
#include <incise/core/types.hpp>
#include <incise/interactive/refactorization_policy.hpp>
#include <incise/io/write_mesh.hpp>
#include <incise/linalg/augmented_system.hpp>
#include <incise/material/parameters.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/needle/friction.hpp>
#include <incise/scene/line_index.hpp>
#include <incise/solver/dynamic_relaxation.hpp>
#include <incise/solver/linear_cg.hpp>
#include <incise/solver/nonlinear_cg.hpp>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace incise::scene {

/// A set of mesh nodes (or, for surface loads, of boundary faces whose vertices all lie in it).
struct Region {
  /// How membership is decided.
  enum class Kind {
    kPlane,   ///< |x[axis] − value| ≤ tolerance
    kBox,     ///< lo ≤ x ≤ hi componentwise
    kSphere,  ///< ‖x − center‖ ≤ radius
    kTag      ///< point tag == tag, or vertex of a cell with cell tag == tag
  };
  Kind kind = Kind::kPlane;
  int axis = 0;                ///< plane: 0,1,2 for x,y,z
  double value = 0.0;          ///< plane: coordinate (m)
  double tolerance = 0.0;      ///< plane: half-thickness (m); 0 → 1e-9 × bounding-box size
  Vec3 lo = Vec3::Zero();      ///< box: lower corner (m)
  Vec3 hi = Vec3::Zero();      ///< box: upper corner (m)
  Vec3 center = Vec3::Zero();  ///< sphere: centre (m)
  double radius = 0.0;         ///< sphere: radius (m), > 0
  int tag = 0;                 ///< tag: label from the mesh file
  std::string path;            ///< JSON path of this region in the scene, for messages
};

/// Names of Region::Kind (scene key `type` of a region).
inline constexpr NameTable<Region::Kind, 4> kRegionKindNames{{{
    {Region::Kind::kPlane, "plane"},
    {Region::Kind::kBox, "box"},
    {Region::Kind::kSphere, "sphere"},
    {Region::Kind::kTag, "tag"},
}}};

/// Where the mesh comes from.
struct MeshSpec {
  /// Source of the mesh.
  enum class Source {
    kFile,      ///< a mesh file (Medit .mesh, Gmsh .msh, TetGen .node/.ele, OFF)
    kBox,       ///< mesh::make_box
    kCylinder,  ///< mesh::make_cylinder (structured O-grid along x)
    kSlab2d     ///< mesh::make_right_triangle_slab: the plane-stress slab of thesis §6.5, §6.8
  };
  Source source = Source::kBox;
  std::string file;    ///< kFile: path, resolved relative to the scene file's folder
  double scale = 1.0;  ///< kFile: factor applied to the file's coordinates (e.g. 0.001 for mm)
  int nx = 1, ny = 1, nz = 1;                     ///< kBox: cubes per axis
  double lx = 1, ly = 1, lz = 1;                  ///< kBox: box sizes (m)
  mesh::CubeSplit split = mesh::CubeSplit::kSix;  ///< kBox: cube split
  double radius = 0, length = 0;  ///< kCylinder: radius and length (m); axis along x
  int rings = 1, layers = 1;      ///< kCylinder: rings across the disk, layers along x
  /// kSlab2d: the rectangle [0, width] × [0, height] (m) in the z = 0 plane.
  double width = 0, height = 0;
  /// kSlab2d: starting grid spacing h_start (m), the leg of every right triangle; width and
  /// height must be integer multiples of it. Given as a length (scene key `h_start`) or as the
  /// thesis level k, h_k = 0.1 m · 2⁻ᵏ (key `h_start_level`, mesh::thesis_slab_spacing).
  double h_start = 0;
  int h_start_level = 0;  ///< kSlab2d: k when given as a level, 0 when given as a length
  double thickness = 0;   ///< kSlab2d: plane-stress thickness d (m), > 0 (thesis §6.3)
};

/// Names of MeshSpec::Source (scene key `type` of the mesh).
inline constexpr NameTable<MeshSpec::Source, 4> kMeshSourceNames{{{
    {MeshSpec::Source::kFile, "file"},
    {MeshSpec::Source::kBox, "box"},
    {MeshSpec::Source::kCylinder, "cylinder"},
    {MeshSpec::Source::kSlab2d, "slab2d"},
}}};

/// Names of mesh::CubeSplit (scene key `split` of a box mesh; only scenes name the splits).
inline constexpr NameTable<mesh::CubeSplit, 3> kCubeSplitNames{{{
    {mesh::CubeSplit::kSix, "six"},
    {mesh::CubeSplit::kFive, "five"},
    {mesh::CubeSplit::kKuhn, "kuhn"},
}}};

/// Material model and parameters (scene keys `model`, `E`, `nu`, `gamma`, `rho`).
struct MaterialSpec {
  std::string model;  ///< registry name (material::registered_material_names()), e.g. "linear"
  /// E (Pa), ν, γ (Veronda–Westmann, §4.3.4; 0 for the other models), ρ (kg/m³); admissible
  /// as material::validate defines it (checked by the parser and by make_material).
  material::Parameters parameters;
  /// Scene key `allow_inversion` (default false): accept a converged state with inverted
  /// elements (det F ≤ 0) as a success. Only for models whose energy is defined for det F ≤ 0
  /// (material::Material::defined_when_inverted(): "linear", "stvk"); the parser refuses it for
  /// the log models ("neohookean", "veronda-westmann"). Without it such a state is a status
  /// (solver::StopReason::kInverted, scene_runner.hpp).
  bool allow_inversion = false;
};

/// An external load.
struct LoadSpec {
  /// Kind of load.
  enum class Kind {
    kGravity,  ///< body force ρ·g on every element (consistent nodal load ρ g V/4 per vertex)
    kPoint,    ///< force on the node nearest to `at`
    kNodal,    ///< total force split equally over the nodes of `region`
    kSurface   ///< traction (Pa) on boundary faces whose vertices are all in `region`
  };
  Kind kind = Kind::kGravity;
  Vec3 vector = Vec3::Zero();  ///< g (m/s²), force (N), total force (N) or traction (Pa)
  Vec3 at = Vec3::Zero();      ///< kPoint: location (m)
  Region region;               ///< kNodal, kSurface
  std::string path;            ///< JSON path, for messages
};

/// Names of LoadSpec::Kind (scene key `type` of a load).
inline constexpr NameTable<LoadSpec::Kind, 4> kLoadKindNames{{{
    {LoadSpec::Kind::kGravity, "gravity"},
    {LoadSpec::Kind::kPoint, "point"},
    {LoadSpec::Kind::kNodal, "nodal"},
    {LoadSpec::Kind::kSurface, "surface"},
}}};

/// Solution method and its stopping rule / budgets.
struct SolverSpec {
  /// Which solver.
  enum class Method {
    kCG,           ///< linear CG on the tangent at u = 0 (thesis §3.1; linear elasticity)
    kNonlinearCG,  ///< nonlinear CG with line search (§2.4.2)
    kNewton,       ///< truncated Newton–Raphson (§2.4.3)
    kDynamicSS22,  ///< explicit dynamic relaxation with the SS22 scheme (§2.5)
    kAugmented     ///< CHOLMOD factorization + augmented system (Yeung et al. 2016)
  };
  /// Interactive cutting run: the configuration each sweep triangle is applied to.
  enum class CutConfiguration {
    kDeformed,  ///< the deformed body X + u of the last solution (the scalpel moves in world
                ///< space, thesis §3.2)
    kReference  ///< the reference configuration (the same cut as the builder's cut-first path)
  };
  /// Interactive cutting run: what one solve follows (one row of the run's steps).
  enum class SolveEvery {
    kSegment,  ///< a path segment (one blade advance): its two sweep triangles cut, one solve
               ///< (interactive::AugmentedCutSession::frame)
    kTriangle  ///< every sweep triangle (AugmentedCutSession::step), two solves per segment
  };
  Method method = Method::kCG;
  /// Stop when ‖r‖₂ ≤ tolerance·‖f_ext‖₂ (§3.1), in (0, 1). In a needle scene: ε of the (6.9)
  /// rule, ‖r‖₂ ≤ ε·√(‖f_ex‖² + ‖f_react‖²) + E·d·H/√n·ε_round (needle::InsertionOptions).
  double tolerance = 1e-8;
  /// Needle scenes only: ε_round of (6.9), in [0, 1) (scene key `tolerance_round`; §6.8.1).
  double tolerance_round = 1e-8;
  int max_iterations = 10000;  ///< iteration (or time-step) budget, ≥ 1
  /// Threads of the element loops of the tetrahedral problem (fem::ElasticProblem::set_threads,
  /// 1 … kMaxThreads; results are bitwise the same for any value); 0 = the default,
  /// default_thread_count() (INCISE_THREADS, else all cores). Scene key `threads`.
  int threads = 0;
  double time_budget = 0.0;  ///< wall-clock budget (s); 0 = unlimited
  /// Linear material, methods "cg", "nonlinear-cg", "newton", "dynamic-ss22" (scene key
  /// `assembled_product`): K·d from the stiffness assembled once in 3×3 node blocks
  /// (fem::ElasticProblem::set_assembled_product) instead of element products; with
  /// "dynamic-ss22" also the gradient recurrence (solver::DynamicRelaxationOptions::
  /// gradient_recurrence: one K·d per step instead of a gradient sweep). Unset: on for the
  /// linear material when the assembled K fits the memory budget (kDefaultAssembledProduct),
  /// off otherwise; an explicit true is refused for another material, the "augmented" solver,
  /// needle scenes (their needle tool has the key) and when it does not fit the budget.
  std::optional<bool> assembled_product;
  /// CG and Newton's inner CG (scene key `preconditioner`).
  solver::Preconditioner preconditioner = solver::Preconditioner::kNone;
  double time_step = 0.0;  ///< dynamic: Δt (s); 0 → 0.9 × critical step 2/√λ_max (§4.1)
  double damping = -1.0;  ///< dynamic: damping η (1/s), ≥ 0; −1 → automatic: 2ζ√θ₁ (§4.1,
                          ///< solver::estimate_dynamic_parameters) or, with spectral_tuning,
                          ///< from the FFT
  bool spectral_tuning = false;  ///< dynamic: estimate damping from an FFT of the trace
  /// dynamic: Π on every energy_every-th step (solver::DynamicRelaxationOptions::energy_every)
  int energy_every = solver::DynamicRelaxationOptions{}.energy_every;
  /// Nonlinear CG only: the β rule (2.48)/(2.49) (scene key `beta`, solver::kBetaRuleNames).
  solver::BetaRule beta = solver::BetaRule::kPolakRibiere;
  /// Nonlinear CG only: the §4.4.2 line search (scene key `line_search`,
  /// solver::kLineSearchNames).
  solver::LineSearchKind line_search = solver::LineSearchKind::kSecant;
  /// Nonlinear CG only: ε_newton of the line search, > 0 and < 1 (scene key
  /// `line_search_tolerance`; NonlinearCgOptions::epsilon_newton, §4.5.1's 0.1).
  double line_search_tolerance = 0.1;
  /// Interactive cutting run ("augmented" with tools) only. Scene key `cut_configuration`.
  CutConfiguration cut_configuration = CutConfiguration::kDeformed;
  /// Interactive cutting run only. Scene key `solve_every` ("segment", the default: the
  /// library session's one-solve frame, measured faster in docs/augmented.md "One solve per
  /// frame"; "triangle": a solve and a row per sweep triangle).
  SolveEvery solve_every = SolveEvery::kSegment;
  /// 3D needle scene with "augmented": needle::InsertionOptions3D::refactor_at_m (≥ 1, default
  /// 600). Otherwise interactive cutting run only: interactive::AugmentedCutOptions::refactor_at_m,
  /// the augmented paper's §3.6 background refactorization — started after a solve once m − |𝓓|
  /// replaced columns (a count) have accumulated; 0 = never. Scene key `refactor_at_m`.
  int refactor_at_m = 0;
  /// Interactive cutting run only, with refactor_at_m = 0: the automatic §3.6 policy of
  /// interactive::AugmentedCutOptions in this mode; nullopt = none (m grows, and the per-step
  /// rows do not depend on when a background job finishes). Scene key `refactorization`:
  /// kNoRefactorizationName or a name of interactive::kRefactorizationModeNames; default the
  /// session's, interactive::kDefaultRefactorizationMode ("continuous").
  std::optional<interactive::RefactorizationMode> refactorization =
      interactive::kDefaultRefactorizationMode;
  /// Interactive cutting run only: linalg::AugmentedOptions::solve_threads, the threads of
  /// step 3's full backward substitution (1 = serial; the result is bit-identical for any
  /// value). Scene key `solve_threads`, 1 … 64.
  int solve_threads = 1;
  /// Interactive cutting run only: how eq. 17 (the Schur system) is solved and preconditioned,
  /// as in linalg::AugmentedOptions. Scene key `schur_preconditioner`: "explicit" (the default)
  /// is linalg::SchurSolver::kDirectCached, the explicit H R⁻¹ J in capacitance form; the
  /// paper's §3.5 choices (linalg::kSchurPreconditionerNames: "hsj", "spai", "none") are
  /// SchurSolver::kGmres with that preconditioner.
  linalg::SchurSolver schur_solver = linalg::SchurSolver::kDirectCached;
  /// Used when schur_solver is kGmres.
  linalg::SchurPreconditioner schur_preconditioner = linalg::SchurPreconditioner::kDiagonal;
};

/// Whether a relaxation scene of the linear material multiplies by the assembled K when the
/// scene does not say (SolverSpec::assembled_product unset): the same default as the 3D
/// needle's (needle::InsertionOptions3D::assembled_product); measured in docs/solvers.md,
/// "Fourth pass".
inline constexpr bool kDefaultAssembledProduct = true;

/// Names of SolverSpec::Method (scene key `method`).
inline constexpr NameTable<SolverSpec::Method, 5> kMethodNames{{{
    {SolverSpec::Method::kCG, "cg"},
    {SolverSpec::Method::kNonlinearCG, "nonlinear-cg"},
    {SolverSpec::Method::kNewton, "newton"},
    {SolverSpec::Method::kDynamicSS22, "dynamic-ss22"},
    {SolverSpec::Method::kAugmented, "augmented"},
}}};

/// Names of SolverSpec::CutConfiguration (scene key `cut_configuration`).
inline constexpr NameTable<SolverSpec::CutConfiguration, 2> kCutConfigurationNames{{{
    {SolverSpec::CutConfiguration::kDeformed, "deformed"},
    {SolverSpec::CutConfiguration::kReference, "reference"},
}}};

/// Names of SolverSpec::SolveEvery (scene key `solve_every`).
inline constexpr NameTable<SolverSpec::SolveEvery, 2> kSolveEveryNames{{{
    {SolverSpec::SolveEvery::kSegment, "segment"},
    {SolverSpec::SolveEvery::kTriangle, "triangle"},
}}};

/// The value of the scene key `schur_preconditioner` that selects linalg::SchurSolver::
/// kDirectCached; its other values are the names in linalg::kSchurPreconditionerNames.
inline constexpr const char* kExplicitSchurName = "explicit";

/// The value of the scene key `refactorization` that selects no automatic §3.6 policy (the
/// default); its other values are the names in interactive::kRefactorizationModeNames.
inline constexpr const char* kNoRefactorizationName = "none";

/// A tool. The scalpel is swept along a path; consecutive blade positions span the sweep
/// triangles of thesis §3.2. The needle (thesis ch. 6: in 2D on a `slab2d` mesh, in 3D (§6.9)
/// on a tetrahedral one) is a rigid segment whose tip follows the path at `speed` × h_ref per
/// update, pointing along the path segment it is on (scene_builder.hpp, needle_updates()).
struct ToolSpec {
  /// Kind of tool.
  enum class Kind {
    kScalpel,  ///< 3D: a blade swept along the path (§3.2)
    kNeedle    ///< a rigid needle inserted along the path (§6.4, §6.7; 3D: §6.9)
  };
  Kind kind = Kind::kScalpel;
  /// Scalpel: blade tip positions (m), ≥ 2. Needle: tip positions (m; on a slab2d z = 0 and the
  /// scene gives [x, y], in 3D [x, y, z]), ≥ 2, consecutive points distinct.
  std::vector<Vec3> path;
  Vec3 blade = Vec3::Zero();  ///< scalpel: vector from tip to the blade's back end (m), non-zero
  std::string path_json;      ///< JSON path, for messages
  /// Needle: length L (m) of the rigid shaft (the base is tip − L·t); default the path's length.
  double length = 0;
  double speed = 0;  ///< needle: tip advance per update, in units of h_ref (> 0)
  /// Needle: refinement size around the tip h_ref (m), ≤ the mesh's h_start; given as a length
  /// (key `h_ref`) or as the thesis level (key `h_ref_level`, h_k = 0.1 m · 2⁻ᵏ).
  double h_ref = 0;
  int h_ref_level = 0;               ///< needle: k when h_ref was given as a level, else 0
  needle::FrictionProfile friction;  ///< needle: shaft friction profile (friction.hpp)
  bool relocate = false;             ///< needle: §6.8.6 relocation of intercepted nodes
  int max_rearrangements = 100;      ///< needle: stick–slip passes per update before a status
  /// 3D needle (tetrahedral mesh) only: radius r (m) of the shaft (needle3d.hpp).
  double radius = 0;
  /// 3D needle only: longest edge (m) along the tip's reference trace (InsertionOptions3D::
  /// h_shaft); default 2·radius, the needle's diameter.
  double h_shaft = 0;
  /// 3D needle only: refinement budget in tetrahedra (InsertionOptions3D::max_elements).
  Index max_elements = 1000000;
  /// 3D needle, linear material only: K·d from the stiffness assembled once per refinement
  /// (InsertionOptions3D::assembled_product; key `assembled_product`). Unset: the library's
  /// default (on; ignored for other materials); an explicit true is refused where it does not
  /// apply (another material, the "augmented" solver).
  std::optional<bool> assembled_product;
  /// 3D needle, solver "cg" only: warm start advanced by the previous update's increment
  /// (InsertionOptions3D::extrapolate; key `extrapolate`, default false).
  bool extrapolate = false;
};

/// Names of ToolSpec::Kind (scene key `type` of a tool).
inline constexpr NameTable<ToolSpec::Kind, 2> kToolKindNames{{{
    {ToolSpec::Kind::kScalpel, "scalpel"},
    {ToolSpec::Kind::kNeedle, "needle"},
}}};

/// A quantity recorded during and after the run.
struct ProbeSpec {
  /// What the probe measures.
  enum class Quantity {
    kDisplacement  ///< displacement u (m)
  };
  std::string name;  ///< unique, [A-Za-z0-9_.-]+
  Quantity quantity = Quantity::kDisplacement;
  bool use_region = false;        ///< false: node nearest to `at`; true: average over region
  Vec3 at = Vec3::Zero();         ///< location (m)
  Region region;                  ///< averaging region
  std::optional<Vec3> reference;  ///< optional expected value (m), reported with the error
  /// Optional one-line context printed with the probe (e.g. what the source reports for the
  /// same quantity on the same mesh, so an error against `reference` is read correctly).
  std::string note;
};

/// Names of ProbeSpec::Quantity (scene key `quantity` of a probe).
inline constexpr NameTable<ProbeSpec::Quantity, 1> kProbeQuantityNames{{{
    {ProbeSpec::Quantity::kDisplacement, "displacement"},
}}};

/// Files the run writes.
struct OutputSpec {
  std::string vtu;    ///< VTU file stem ("" = none); written every `vtu_every` iterations
  int vtu_every = 0;  ///< 0: final state only
  /// `vtu_format`: "binary" (default: raw appended, zlib-compressed) or "ascii".
  io::VtuEncoding vtu_format = io::VtuEncoding::kBinaryZlib;
  std::string csv;  ///< CSV trace of iteration, residual, probes ("" = none)
  std::vector<ProbeSpec> probes;
};

/// Resource limits of building a scene (scene key `limits`).
struct LimitsSpec {
  /// Memory budget of the build (MiB), scene key `memory_mb`: a build whose estimate (mesh
  /// arrays and elastic problem, scene_builder.hpp) is larger is refused before it allocates.
  /// 0: the default, incise::default_memory_budget_bytes() (core/memory_budget.hpp).
  std::int64_t memory_mb = 0;
};

/// A whole scene.
struct SceneSpec {
  std::string file;         ///< the scene file the spec came from ("<memory>" if parsed from text)
  std::string name;         ///< short title
  std::string description;  ///< free text
  MeshSpec mesh;
  MaterialSpec material;
  std::vector<Region> fixed;
  std::vector<LoadSpec> loads;
  SolverSpec solver;
  std::vector<ToolSpec> tools;
  OutputSpec outputs;
  LimitsSpec limits;
  /// The scene's needle (the one tool of a needle scene, 2D or 3D), nullptr otherwise.
  const ToolSpec* needle() const {
    return tools.size() == 1 && tools[0].kind == ToolSpec::Kind::kNeedle ? &tools[0] : nullptr;
  }
  /// Line (1-based) in `file` of each JSON value by JSON pointer ("/fixed/0"; an object member:
  /// the line of its key), so that errors found later (the builder's) can name it; empty for
  /// specs made in code.
  LineIndex lines;
};

/// Names used in scene files (from the tables above).
inline const char* to_string(SolverSpec::Method m) {
  return kMethodNames.name(m);
}
inline const char* to_string(SolverSpec::CutConfiguration c) {
  return kCutConfigurationNames.name(c);
}
inline const char* to_string(SolverSpec::SolveEvery s) {
  return kSolveEveryNames.name(s);
}
inline const char* to_string(Region::Kind k) {
  return kRegionKindNames.name(k);
}
inline const char* to_string(LoadSpec::Kind k) {
  return kLoadKindNames.name(k);
}

}  // namespace incise::scene
