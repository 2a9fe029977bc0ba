#include <incise/scene/scene_parser.hpp>

#include <incise/core/error.hpp>
#include <incise/core/parallel.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/slab2d.hpp>
#include <incise/needle/insertion3d.hpp>

#include <filesystem>
#include <limits>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "json_reader.hpp"
#include "scene_parts.hpp"

namespace incise::scene {

namespace {

using detail::fail;
using detail::Json;
using detail::JsonObject;
using detail::Range;

// Per-axis bound for generated meshes; their size is bounded by the builder's memory budget
// (1000³ cubes are 6e9 tets, refused under any budget below 1.1 TB).
constexpr int kMaxCells = 1000;
constexpr int kMaxIterations = 100000000;
// Needle scenes: the thesis' levels h_k = 0.1 m·2⁻ᵏ (mesh::thesis_slab_spacing), at most 10
// bisection levels between h_start and h_ref (the thesis spans 6, h1 → h7), and at most 10⁶
// updates (the slowest §6.8 insertion, 0.01 h_ref at h7, has 9,000).
constexpr int kMinSlabLevel = 1, kMaxSlabLevel = 7;
constexpr double kMaxRefinementRatio = 1024;
constexpr double kMaxNeedleUpdates = 1e6;

const std::vector<std::string> kMeshExtensions = {".mesh", ".msh", ".node", ".off"};

// `a <what> object {"type": "a"|"b", ...}`: the expected form of an object whose `type` is a
// name from `table`.
template <class Table>
std::string typed_object(const std::string& what, const Table& table) {
  std::string s = "a " + what + " object {\"type\": ";
  const std::vector<std::string> names = table.names();
  for (std::size_t i = 0; i < names.size(); ++i) s += (i ? "|\"" : "\"") + names[i] + "\"";
  return s + ", ...}";
}

Region parse_region(const Json& j, const std::string& path, const std::string& file) {
  JsonObject o(j, path, file, typed_object("region", kRegionKindNames));
  Region r;
  r.path = path;
  r.kind = o.choice("type", kRegionKindNames);
  if (r.kind == Region::Kind::kPlane) {
    const std::string axis = o.choice("axis", {"x", "y", "z"});
    r.axis = axis[0] - 'x';
    r.value = o.number("value", detail::any_finite());
    r.tolerance = o.number("tolerance", detail::non_negative(), 0.0);
  } else if (r.kind == Region::Kind::kBox) {
    r.lo = o.vec3("min");
    r.hi = o.vec3("max");
    for (int a = 0; a < 3; ++a) {
      if (!(r.lo[a] <= r.hi[a]))
        fail(file, detail::child_path(path, "max"),
             "expected max >= min in every coordinate (coordinate " + std::to_string(a) +
                 " has max " + std::to_string(r.hi[a]) + " < min " + std::to_string(r.lo[a]) + ")");
    }
  } else if (r.kind == Region::Kind::kSphere) {
    r.center = o.vec3("center");
    r.radius = o.number("radius", detail::positive());
  } else {
    r.tag = o.integer("tag", std::numeric_limits<int>::min(), std::numeric_limits<int>::max());
  }
  o.finish();
  return r;
}

// A grid spacing given as a length (key `key`, m, > 0) or as the thesis level k (key
// `key_level`, h_k = 0.1 m·2⁻ᵏ): exactly one of the two. Returns the length; `level` is k or 0.
double length_or_level(JsonObject& o, const std::string& key, int& level) {
  const std::string level_key = key + "_level";
  const bool has_length = o.has(key), has_level = o.has(level_key);
  if (has_length == has_level)
    fail(o.file(), o.path(),
         "expected exactly one of \"" + key + "\" (a length in m) or \"" + level_key +
             "\" (the thesis level k: h_k = 0.1 m * 2^-k, k in [" + std::to_string(kMinSlabLevel) +
             ", " + std::to_string(kMaxSlabLevel) + "])");
  if (has_length) {
    level = 0;
    o.get(level_key);
    return o.number(key, detail::positive());
  }
  o.get(key);
  level = o.integer(level_key, kMinSlabLevel, kMaxSlabLevel);
  return mesh::thesis_slab_spacing(level);
}

MeshSpec parse_mesh(JsonObject o, const std::string& file, const std::string& base_dir) {
  MeshSpec m;
  m.source = o.choice("type", kMeshSourceNames);
  if (m.source == MeshSpec::Source::kFile) {
    const std::string rel = o.string("path");
    const std::string p = detail::child_path(o.path(), "path");
    std::filesystem::path fp(rel);
    if (fp.is_relative() && !base_dir.empty()) fp = std::filesystem::path(base_dir) / fp;
    std::string ext = fp.extension().string();
    if (std::find(kMeshExtensions.begin(), kMeshExtensions.end(), ext) == kMeshExtensions.end())
      fail(file, p,
           "expected a mesh file ending in .mesh (Medit), .msh (Gmsh), .node (TetGen) or .off, "
           "got \"" +
               rel + "\"");
    std::error_code ec;
    if (!std::filesystem::is_regular_file(fp, ec))
      fail(file, p, "mesh file not found: " + fp.lexically_normal().string());
    m.file = fp.lexically_normal().string();
    m.scale = o.number("scale", detail::positive(), 1.0);
  } else if (m.source == MeshSpec::Source::kBox) {
    m.nx = o.integer("nx", 1, kMaxCells);
    m.ny = o.integer("ny", 1, kMaxCells);
    m.nz = o.integer("nz", 1, kMaxCells);
    m.lx = o.number("lx", detail::positive());
    m.ly = o.number("ly", detail::positive());
    m.lz = o.number("lz", detail::positive());
    m.split = o.choice("split", kCubeSplitNames, mesh::CubeSplit::kSix);
  } else if (m.source == MeshSpec::Source::kCylinder) {
    m.radius = o.number("radius", detail::positive());
    m.length = o.number("length", detail::positive());
    m.rings = o.integer("rings", 1, kMaxCells);
    m.layers = o.integer("layers", 1, kMaxCells);
  } else {
    m.width = o.number("width", detail::positive());
    m.height = o.number("height", detail::positive());
    m.h_start = length_or_level(o, "h_start", m.h_start_level);
    m.thickness = o.number("thickness", detail::positive());
  }
  o.finish();
  return m;
}

// material::validate(p), its ParameterError reported at the JSON path of the inadmissible
// parameter. validate judges each parameter on its own, so that parameter is the first whose
// value alone (the others at their admissible defaults) is rejected; a rule between parameters
// would be reported at the material object.
void validate_material(const JsonObject& o, const material::Parameters& p) {
  try {
    material::validate(p);
  } catch (const ParameterError& e) {
    using P = material::Parameters;
    const std::pair<const char*, double P::*> keys[] = {{"E", &P::youngs_modulus},
                                                        {"nu", &P::poisson_ratio},
                                                        {"gamma", &P::gamma},
                                                        {"rho", &P::density}};
    for (const auto& [key, member] : keys) {
      P alone;
      alone.*member = p.*member;
      try {
        material::validate(alone);
      } catch (const ParameterError&) {
        fail(o.file(), detail::child_path(o.path(), key), e.what());
      }
    }
    fail(o.file(), o.path(), e.what());
  }
}

}  // namespace

namespace detail {

// `rho_reason` is non-empty when the scene needs a density (gravity, dynamic solver): then
// "rho" is required and must be > 0.
MaterialSpec parse_material(JsonObject o, const std::string& rho_reason) {
  MaterialSpec m;
  m.model = o.choice("model", material::registered_material_names());
  material::Parameters& p = m.parameters;
  p.youngs_modulus = o.number("E", detail::any_finite());
  p.poisson_ratio = o.number("nu", detail::any_finite());
  if (m.model == material::VerondaWestmann::kName) {
    p.gamma = o.number("gamma", detail::any_finite());
  } else {
    o.forbid("gamma", "only the \"veronda-westmann\" model has the nonlinearity gamma (§4.3.4)");
  }
  if (!rho_reason.empty() && !o.has("rho"))
    fail(o.file(), o.path(),
         "missing required key \"rho\" (expected a number > 0, density in kg/m^3): " + rho_reason);
  p.density = o.number("rho", detail::any_finite(), p.density);
  validate_material(o, p);
  if (material::Material(m.model, p).defined_when_inverted())
    m.allow_inversion = o.boolean("allow_inversion", false);
  else
    o.forbid("allow_inversion", "material \"" + m.model +
                                    "\" has no energy for det F <= 0 (its log J term), so an "
                                    "inverted element is never a solution; only \"linear\" and "
                                    "\"stvk\" may allow inversion");
  if (!rho_reason.empty() && !(p.density > 0))
    fail(o.file(), detail::child_path(o.path(), "rho"),
         "expected a number > 0 (density in kg/m^3), got " + detail::show(*o.get("rho")) + ": " +
             rho_reason);
  o.finish();
  return m;
}

}  // namespace detail

namespace {

LoadSpec parse_load(const Json& j, const std::string& path, const std::string& file) {
  JsonObject o(j, path, file, typed_object("load", kLoadKindNames));
  LoadSpec l;
  l.path = path;
  l.kind = o.choice("type", kLoadKindNames);
  if (l.kind == LoadSpec::Kind::kGravity) {
    l.vector = o.vec3("g");
  } else if (l.kind == LoadSpec::Kind::kPoint) {
    l.at = o.vec3("at");
    l.vector = o.vec3("force");
  } else if (l.kind == LoadSpec::Kind::kNodal) {
    l.region = parse_region(o.require("region", "a region object"),
                            detail::child_path(path, "region"), file);
    l.vector = o.vec3("total_force");
  } else {
    l.region = parse_region(o.require("region", "a region object"),
                            detail::child_path(path, "region"), file);
    l.vector = o.vec3("traction");
  }
  o.finish();
  return l;
}

// `slab`: a needle scene (thesis ch. 6: a slab2d mesh, or a tetrahedral mesh with a needle):
// linear or nonlinear CG on the projected problem (6.7) of §6.6, stopped by (6.9) with ε_round,
// plain CG; `needle3d` (a tetrahedral needle scene) also the augmented solver
// (needle::SolvePath3D::kAugmented), whose only key is refactor_at_m.
SolverSpec parse_solver(JsonObject o, bool slab, bool needle3d) {
  SolverSpec s;
  s.method = o.choice("method", kMethodNames);
  const bool needle_augmented = needle3d && s.method == SolverSpec::Method::kAugmented;
  if (slab && !needle_augmented && s.method != SolverSpec::Method::kCG &&
      s.method != SolverSpec::Method::kNonlinearCG)
    fail(o.file(), detail::child_path(o.path(), "method"),
         std::string(needle3d ? "a 3D needle scene is solved by \"cg\", \"nonlinear-cg\" or "
                                "\"augmented\""
                              : "a slab2d needle scene is solved by \"cg\" or \"nonlinear-cg\"") +
             " on the projected problem (6.7) of thesis §6.6, got \"" + to_string(s.method) + "\"");
  if (needle_augmented) {
    const std::string why =
        "the augmented needle solve is exact (GMRES on eq. 17 of Yeung et al. 2016 to 1e-12), "
        "not stopped by (6.9)";
    for (const char* key : {"tolerance", "tolerance_round", "max_iterations", "preconditioner"})
      o.forbid(key, why);
    o.forbid("threads",
             "a needle scene rebuilds its problem at every update with the default thread count");
    for (const char* key :
         {"cut_configuration", "solve_every", "solve_threads", "schur_preconditioner"})
      o.forbid(key, "it belongs to the interactive cutting run's augmented solver");
    o.forbid("assembled_product",
             "the augmented needle solve factors K; the needle tool's own assembled_product "
             "(/tools/0/assembled_product) is for its CG path");
    s.refactor_at_m = o.integer("refactor_at_m", 1, std::numeric_limits<int>::max(),
                                needle::InsertionOptions3D{}.refactor_at_m);
    o.finish();
    return s;
  }
  s.tolerance = o.number("tolerance", Range{0.0, 1.0, true, true}, 1e-8);
  s.max_iterations = o.integer("max_iterations", 1, kMaxIterations, 10000);
  if (slab) {
    o.forbid("threads",
             "a needle scene rebuilds its problem at every update with the default thread count "
             "(3D: INCISE_THREADS, else all cores; plane-stress loops: one thread)");
  } else {
    s.threads = o.integer("threads", 1, kMaxThreads, 0);
  }
  if (slab) {
    o.forbid("time_budget",
             "a needle run has no wall-clock budget (max_iterations caps each solve)");
    s.tolerance_round = o.number("tolerance_round", Range{0.0, 1.0, false, true}, 1e-8);
  } else {
    s.time_budget = o.number("time_budget", detail::non_negative(), 0.0);
    o.forbid("tolerance_round",
             "only a needle scene (a \"slab2d\" mesh, or a needle tool) has the rounding term "
             "epsilon_round of the "
             "(6.9) stopping rule; this scene stops by (6.8), ||r|| <= tol ||f_ext||");
  }
  const bool dynamic = s.method == SolverSpec::Method::kDynamicSS22;
  if (slab) {
    o.forbid("assembled_product",
             needle3d ? "a 3D needle scene sets it on its needle (/tools/0/assembled_product): "
                        "the needle rebuilds its problem at every refinement"
                      : "a slab2d needle scene solves the plane-stress problem (6.7) matrix-free");
  } else if (s.method == SolverSpec::Method::kAugmented) {
    o.forbid("assembled_product",
             "the assembled product speeds up the K·d of \"cg\", \"nonlinear-cg\", \"newton\" "
             "and \"dynamic-ss22\"; the \"augmented\" solver factors K instead");
  } else if (o.has("assembled_product")) {
    s.assembled_product = o.boolean("assembled_product", kDefaultAssembledProduct);
  } else {
    (void)o.get("assembled_product");  // known (listed as allowed); unset: the default
  }
  if (slab && s.method != SolverSpec::Method::kCG) {
    o.forbid("preconditioner",
             "in a needle scene only \"cg\" takes a preconditioner (\"jacobi\": the diagonal of "
             "the projected problem (6.7), needle::NeedleProblemT::hessian_diagonal)");
  } else if (s.method == SolverSpec::Method::kCG || s.method == SolverSpec::Method::kNewton) {
    s.preconditioner =
        o.choice("preconditioner", solver::kPreconditionerNames, solver::Preconditioner::kNone);
  } else {
    o.forbid("preconditioner", "only \"cg\" and \"newton\" take a preconditioner");
  }
  if (s.method == SolverSpec::Method::kNonlinearCG && !slab) {
    s.beta = o.choice("beta", solver::kBetaRuleNames, solver::BetaRule::kPolakRibiere);
    s.line_search =
        o.choice("line_search", solver::kLineSearchNames, solver::LineSearchKind::kSecant);
    s.line_search_tolerance = o.number("line_search_tolerance", Range{0.0, 1.0, true, true}, 0.1);
  } else {
    const std::string why = slab ? "a needle scene's nonlinear CG uses its fixed settings"
                                 : "only \"nonlinear-cg\" has a beta rule and a line search";
    o.forbid("beta", why);
    o.forbid("line_search", why);
    o.forbid("line_search_tolerance", why);
  }
  if (dynamic) {
    s.time_step = o.number("time_step", detail::non_negative(), 0.0);
    s.damping = o.number("damping", detail::non_negative(), -1.0);
    s.spectral_tuning = o.boolean("spectral_tuning", false);
    s.energy_every = o.integer("energy_every", 1, std::numeric_limits<int>::max(), s.energy_every);
  } else {
    const std::string why = "only the \"dynamic-ss22\" method integrates in time";
    o.forbid("time_step", why);
    o.forbid("damping", why);
    o.forbid("spectral_tuning", why);
    o.forbid("energy_every", why);
  }
  if (s.method == SolverSpec::Method::kAugmented) {
    s.cut_configuration = o.choice("cut_configuration", kCutConfigurationNames,
                                   SolverSpec::CutConfiguration::kDeformed);
    s.solve_every = o.choice("solve_every", kSolveEveryNames, SolverSpec::SolveEvery::kSegment);
    s.refactor_at_m = o.integer("refactor_at_m", 0, std::numeric_limits<int>::max(), 0);
    std::vector<std::string> refactorization_names = {kNoRefactorizationName};
    for (const std::string& n : interactive::kRefactorizationModeNames.names())
      refactorization_names.push_back(n);
    const std::string refactorization =
        o.choice("refactorization", refactorization_names,
                 std::string(interactive::to_string(interactive::kDefaultRefactorizationMode)));
    s.refactorization = refactorization == kNoRefactorizationName
                            ? std::nullopt
                            : interactive::kRefactorizationModeNames.find(refactorization);
    s.solve_threads = o.integer("solve_threads", 1, 64, 1);
    std::vector<std::string> schur_names = {kExplicitSchurName};
    for (const std::string& n : linalg::kSchurPreconditionerNames.names()) schur_names.push_back(n);
    const std::string schur = o.choice("schur_preconditioner", schur_names, kExplicitSchurName);
    if (schur != kExplicitSchurName) {
      s.schur_solver = linalg::SchurSolver::kGmres;
      s.schur_preconditioner = *linalg::kSchurPreconditionerNames.find(schur);
    }
  } else {
    o.forbid("cut_configuration",
             "only the \"augmented\" method solves between sweep triangles (the others cut "
             "first, in the reference configuration)");
    o.forbid("solve_every",
             "only the \"augmented\" method solves between sweep triangles (the others cut "
             "first, then solve once)");
    o.forbid("refactor_at_m",
             "only the \"augmented\" method has a factorization to refactor (§3.6 of Yeung et "
             "al. 2016)");
    o.forbid("refactorization",
             "only the \"augmented\" method has a factorization to refactor (§3.6 of Yeung et "
             "al. 2016)");
    o.forbid("solve_threads",
             "only the \"augmented\" method has step-3 triangular solves to split (Yeung et al. "
             "2016 §3.2)");
    o.forbid("schur_preconditioner",
             "only the \"augmented\" method solves a Schur system (Yeung et al. 2016 eq. 17)");
  }
  o.finish();
  return s;
}

// The needle of a needle scene (docs/scenes.md, "Needle scenes"): on a slab2d (`slab`) a line
// in the plane, on a tetrahedral mesh a shaft of radius r (§6.9). The checks that need the
// mesh (h_ref ≤ h_start, the path entering the body) are parse_root's (2D) and the builder's
// (3D).
void parse_needle(JsonObject& o, ToolSpec& t, bool slab) {
  const std::string& file = o.file();
  const std::string& path = t.path_json;
  const std::string form = slab ? "an array of at least 2 points [[x, y], ...] (the tip's path)"
                                : "an array of at least 2 points [[x, y, z], ...] (the tip's path)";
  const Json* p = o.array("path", form, false);
  if (p->size() < 2) detail::fail_expected(file, detail::child_path(path, "path"), form, *p);
  double total = 0.0;
  for (std::size_t i = 0; i < p->size(); ++i) {
    const std::string at = detail::child_path(path + "/path", i);
    if (slab) {
      const Vec2 x = detail::as_vec2((*p)[i], file, at);
      t.path.push_back(Vec3(x[0], x[1], 0.0));
    } else {
      t.path.push_back(detail::as_vec3((*p)[i], file, at));
    }
    if (i == 0) continue;
    const double seg = (t.path[i] - t.path[i - 1]).stableNorm();
    if (!(seg > 0.0))
      fail(file, detail::child_path(path + "/path", i),
           "the needle path segment from point " + std::to_string(i - 1) +
               " has zero length (expected consecutive points to differ: the needle's direction "
               "is that of the segment its tip is on)");
    total += seg;
  }
  t.length = o.number("length", detail::positive(), total);
  t.speed = o.number("speed", detail::positive());
  t.h_ref = length_or_level(o, "h_ref", t.h_ref_level);
  if (slab) {
    const std::string why =
        "a needle in a slab2d scene is a line in the plane (thesis §6.4); "
        "radius, h_shaft and max_elements belong to the 3D needle (§6.9)";
    o.forbid("radius", why);
    o.forbid("h_shaft", why);
    o.forbid("max_elements", why);
    o.forbid("assembled_product", why);
    o.forbid("extrapolate", why);
  } else {
    t.radius = o.number("radius", detail::positive());
    t.h_shaft = o.number("h_shaft", detail::positive(), 2.0 * t.radius);
    t.max_elements = o.integer("max_elements", 1, std::numeric_limits<Index>::max(), 1000000);
    if (o.has("assembled_product")) t.assembled_product = o.boolean("assembled_product", true);
    t.extrapolate = o.boolean("extrapolate", false);
  }
  if (o.has("friction")) {
    JsonObject f = o.object("friction",
                            "a friction object {\"shaft_density\": N/m, \"tip_density\": N/m, "
                            "\"bulge_length\": m, \"static_factor\": ...}");
    const needle::FrictionProfile d;
    t.friction.shaft_density = f.number("shaft_density", detail::non_negative(), d.shaft_density);
    t.friction.tip_density = f.number("tip_density", detail::non_negative(), d.tip_density);
    t.friction.bulge_length = f.number("bulge_length", detail::positive(), d.bulge_length);
    t.friction.static_factor =
        f.number("static_factor", Range{1.0, std::numeric_limits<double>::infinity(), false, true},
                 d.static_factor);
    f.finish();
  } else {
    o.get("friction");
  }
  t.relocate = o.boolean("relocate", false);
  t.max_rearrangements = o.integer("max_rearrangements", 0, 100000, 100);
}

ToolSpec parse_tool(const Json& j, const std::string& path, const std::string& file, bool slab) {
  JsonObject o(j, path, file, typed_object("tool", kToolKindNames));
  ToolSpec t;
  t.path_json = path;
  t.kind = o.choice("type", kToolKindNames);
  if (t.kind == ToolSpec::Kind::kNeedle) {
    parse_needle(o, t, slab);
    o.finish();
    return t;
  }
  const Json* p = o.array("path", "an array of at least 2 points [[x, y, z], ...]", false);
  if (p->size() < 2)
    detail::fail_expected(file, detail::child_path(path, "path"),
                          "an array of at least 2 points [[x, y, z], ...]", *p);
  for (std::size_t i = 0; i < p->size(); ++i)
    t.path.push_back(detail::as_vec3((*p)[i], file, detail::child_path(path + "/path", i)));
  t.blade = o.vec3("blade");
  if (t.blade.norm() == 0.0)
    fail(file, detail::child_path(path, "blade"),
         "expected a non-zero vector from the blade tip to its back end, got [0, 0, 0]");
  for (std::size_t i = 0; i + 1 < t.path.size(); ++i) {
    const Vec3 seg = t.path[i + 1] - t.path[i];
    // Relative threshold: a sweep quad thinner than 1e-12 of its sides has no usable area.
    if (seg.cross(t.blade).norm() <= 1e-12 * seg.norm() * t.blade.norm() || seg.norm() == 0.0)
      fail(file, detail::child_path(path + "/path", i + 1),
           "the path segment from point " + std::to_string(i) +
               " is empty or parallel to the blade, so its sweep triangles have no area");
  }
  o.finish();
  return t;
}

OutputSpec parse_outputs(JsonObject o) {
  OutputSpec out;
  out.vtu = o.string("vtu", "");
  if (!out.vtu.empty()) {
    out.vtu_every = o.integer("vtu_every", 0, kMaxIterations, 0);
    out.vtu_format = o.choice("vtu_format", io::kVtuEncodingNames, io::VtuEncoding::kBinaryZlib);
  } else {
    o.forbid("vtu_every", "set \"vtu\" (the output file stem) first");
    o.forbid("vtu_format", "set \"vtu\" (the output file stem) first");
  }
  out.csv = o.string("csv", "");
  const std::string file = o.file();
  if (const Json* probes = o.array("probes", "an array of probe objects", true)) {
    std::set<std::string> names;
    const std::regex name_re("[A-Za-z0-9_.-]+");
    for (std::size_t i = 0; i < probes->size(); ++i) {
      const std::string pp = detail::child_path(o.path() + "/probes", i);
      JsonObject po((*probes)[i], pp, file,
                    "a probe object {\"name\": ..., \"at\": [x, y, z] or \"region\": {...}}");
      ProbeSpec pr;
      pr.name = po.string("name");
      if (!std::regex_match(pr.name, name_re))
        detail::fail_expected(file, pp + "/name", "a name of letters, digits, '_', '.', '-'",
                              Json(pr.name));
      if (!names.insert(pr.name).second)
        fail(file, pp + "/name", "duplicate probe name \"" + pr.name + "\"");
      pr.quantity = po.choice("quantity", kProbeQuantityNames, ProbeSpec::Quantity::kDisplacement);
      const bool has_at = po.has("at"), has_region = po.has("region");
      if (has_at == has_region)
        fail(file, pp,
             "expected exactly one of \"at\" (nearest node) or \"region\" (average over nodes)");
      if (has_at) {
        pr.at = po.vec3("at");
        po.forbid("region", "");
      } else {
        pr.use_region = true;
        pr.region = parse_region(*po.get("region"), pp + "/region", file);
        po.forbid("at", "");
      }
      if (po.has("reference")) pr.reference = po.vec3("reference");
      po.get("reference");
      pr.note = po.string("note", "");
      po.finish();
      out.probes.push_back(std::move(pr));
    }
  }
  o.finish();
  return out;
}

// --- needle scenes (slab2d mesh + needle tool) ------------------------------------------------

const char* mesh_kind(const MeshSpec& m) {
  return m.source == MeshSpec::Source::kSlab2d ? "a 2D (plane-stress triangle)"
                                               : "a tetrahedral (3D)";
}

// A scalpel needs a tetrahedral mesh (a needle goes into either).
void check_tool_dimension(const ToolSpec& t, const MeshSpec& m, const std::string& file) {
  const bool slab = m.source == MeshSpec::Source::kSlab2d;
  const std::string at = detail::child_path(t.path_json, "type");
  const std::string got = std::string(mesh_kind(m)) + " mesh of type \"" +
                          kMeshSourceNames.name(m.source) + "\" at /mesh";
  if (t.kind == ToolSpec::Kind::kScalpel && slab)
    fail(file, at,
         "a scalpel cuts tetrahedral meshes (thesis ch. 3): it needs a \"box\", \"cylinder\" or "
         "\"file\" mesh, got " +
             got + "; a slab2d scene takes a \"needle\"");
}

// A fixed region of a slab2d scene: a line x = value or y = value (needle::FixedLine).
void check_slab_fixed_line(const Region& r, const Json& j, const std::string& file) {
  if (r.kind != Region::Kind::kPlane || r.axis == 2)
    fail(file, r.path,
         "a slab2d scene is held on straight lines: expected a region {\"type\": \"plane\", "
         "\"axis\": \"x\"|\"y\", \"value\": ...}, got " +
             detail::show(j));
  if (j.contains("tolerance"))
    fail(file, r.path + "/tolerance",
         "not allowed here: a slab2d scene holds the nodes within 1e-9 m of the line "
         "(needle::FixedLine), also those that refinement creates on it");
}

// Fraction interval [t0, t1] of the segment a → b inside the closed rectangle [0, w] × [0, h]
// (Liang–Barsky); false when it misses it.
bool clip_to_rectangle(const Vec3& a, const Vec3& b, double w, double h, double& t0, double& t1) {
  t0 = 0.0;
  t1 = 1.0;
  const double d[2] = {b[0] - a[0], b[1] - a[1]};
  const double lo[2] = {0.0, 0.0}, hi[2] = {w, h};
  for (int k = 0; k < 2; ++k) {
    if (d[k] == 0.0) {
      if (a[k] < lo[k] || a[k] > hi[k]) return false;
      continue;
    }
    double ta = (lo[k] - a[k]) / d[k], tb = (hi[k] - a[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

// The needle against the slab: one needle, h_ref ≤ h_start, the path entering the body, a
// bounded number of updates.
void check_needle(const SceneSpec& s, const std::string& file) {
  if (s.tools.empty())
    fail(file, "/tools",
         "a slab2d mesh is driven by a needle: expected \"tools\": [{\"type\": \"needle\", "
         "...}] (exactly one)");
  if (s.tools.size() != 1)
    fail(file, "/tools/1",
         "a slab2d scene has exactly one needle (needle::NeedleInsertion drives one), got " +
             std::to_string(s.tools.size()) + " tools");
  const ToolSpec& t = s.tools[0];
  const MeshSpec& m = s.mesh;
  const std::string href = t.path_json + (t.h_ref_level ? "/h_ref_level" : "/h_ref");
  std::ostringstream os;
  os.precision(6);
  // 1e-9 relative: a level and the same length written out are equal.
  if (t.h_ref > m.h_start * (1 + 1e-9)) {
    os << "h_ref = " << t.h_ref << " m is larger than the mesh's h_start = " << m.h_start
       << " m (/mesh): refinement only makes triangles smaller (thesis §6.7); expected h_ref <= "
          "h_start";
    fail(file, href, os.str());
  }
  if (m.h_start / t.h_ref > kMaxRefinementRatio * (1 + 1e-9)) {
    os << "h_start / h_ref = " << m.h_start / t.h_ref
       << " is more than 1024 (10 bisection levels; the thesis spans 64, h1 to h7): expected "
          "h_ref >= h_start / 1024";
    fail(file, href, os.str());
  }
  bool enters = false;
  double total = 0.0;
  for (std::size_t i = 0; i + 1 < t.path.size(); ++i) {
    total += (t.path[i + 1] - t.path[i]).stableNorm();
    double t0 = 0, t1 = 0;
    if (!clip_to_rectangle(t.path[i], t.path[i + 1], m.width, m.height, t0, t1) || !(t1 > t0))
      continue;
    const Vec3 mid = t.path[i] + 0.5 * (t0 + t1) * (t.path[i + 1] - t.path[i]);
    enters = enters || (mid[0] > 0 && mid[0] < m.width && mid[1] > 0 && mid[1] < m.height);
  }
  if (!enters) {
    os << "the needle's path never enters the body: expected a path through the interior of the "
          "slab [0, "
       << m.width << "] x [0, " << m.height << "] m (/mesh)";
    fail(file, t.path_json + "/path", os.str());
  }
  const double updates = total / (t.speed * t.h_ref);
  if (!(updates <= kMaxNeedleUpdates)) {
    os << "the path of " << total << " m at " << t.speed << " h_ref per update (h_ref = " << t.h_ref
       << " m) takes " << updates << " updates, more than the limit of 1e6";
    fail(file, t.path_json + "/speed", os.str());
  }
}

// Whether the scene's "tools" array names a needle (read before the tools are parsed: the
// solver and loads of a needle scene follow other rules).
bool names_needle(const Json& root) {
  if (!root.is_object() || !root.contains("tools") || !root["tools"].is_array()) return false;
  for (const Json& t : root["tools"])
    if (t.is_object() && t.contains("type") && t["type"] == "needle") return true;
  return false;
}

// A fixed region of a 3D needle scene: a plane or a box (needle::FixedBox).
void check_needle3d_fixed(const Region& r, const Json& j, const std::string& file) {
  if (r.kind != Region::Kind::kPlane && r.kind != Region::Kind::kBox)
    fail(file, r.path,
         "a 3D needle scene is held on planes and boxes (needle::FixedBox, also the nodes "
         "refinement creates there): expected a region of type \"plane\" or \"box\", got " +
             detail::show(j));
}

// The 3D needle: one needle, a bounded number of updates. Whether the path enters the body
// and fits the refinement budget needs the mesh (scene_builder.cpp).
void check_needle3d(const SceneSpec& s, const std::string& file) {
  if (s.tools.size() != 1)
    fail(file, "/tools/1",
         "a needle scene has exactly one tool, the needle (needle::NeedleInsertion3D drives one), "
         "got " +
             std::to_string(s.tools.size()) + " tools");
  const ToolSpec& t = s.tools[0];
  if (t.assembled_product.value_or(false) && s.material.model != "linear")
    fail(file, t.path_json + "/assembled_product",
         "the assembled product needs the \"linear\" material (its stiffness does not change "
         "with u), got \"" +
             s.material.model + "\"");
  if (t.assembled_product.value_or(false) && s.solver.method == SolverSpec::Method::kAugmented)
    fail(file, t.path_json + "/assembled_product",
         "the assembled product speeds up CG's K·d; the \"augmented\" solver factors K instead");
  if (t.extrapolate && s.solver.method != SolverSpec::Method::kCG)
    fail(file, t.path_json + "/extrapolate",
         "the extrapolated warm start is for solver \"cg\" only (nonlinear CG starts from the "
         "previous solution)");
  double total = 0.0;
  for (std::size_t i = 0; i + 1 < t.path.size(); ++i)
    total += (t.path[i + 1] - t.path[i]).stableNorm();
  const double updates = total / (t.speed * t.h_ref);
  if (!(updates <= kMaxNeedleUpdates)) {
    std::ostringstream os;
    os << "the path of " << total << " m at " << t.speed << " h_ref per update (h_ref = " << t.h_ref
       << " m) takes " << updates << " updates, more than the limit of 1e6";
    fail(file, t.path_json + "/speed", os.str());
  }
}

SceneSpec parse_root(const Json& root_json, const std::string& file, const std::string& base_dir) {
  JsonObject root(root_json, "", file, "a scene object {\"mesh\": ..., \"material\": ..., ...}");
  SceneSpec s;
  s.file = file;
  root.integer("version", 1, 1, 1);
  s.name = root.string("name", "");
  s.description = root.string("description", "");
  s.mesh = parse_mesh(root.object("mesh", typed_object("mesh", kMeshSourceNames)), file, base_dir);
  // A slab2d mesh is the 2D (plane-stress) body of a needle insertion (thesis ch. 6); every
  // other mesh is tetrahedral.
  const bool slab = s.mesh.source == MeshSpec::Source::kSlab2d;
  // A tetrahedral mesh with a needle tool is a 3D needle scene (thesis §6.9).
  const bool needle3d = !slab && names_needle(root_json);
  const bool needle_scene = slab || needle3d;
  s.solver = parse_solver(root.object("solver", "a solver object {\"method\": ...}"), needle_scene,
                          needle3d);
  const bool dynamic = s.solver.method == SolverSpec::Method::kDynamicSS22;
  const Json* solver_json = root.get("solver");

  std::string rho_reason;
  if (needle_scene) {
    root.forbid("loads",
                "a needle scene is loaded by its needle only (the needle insertion applies no "
                "other force); remove \"loads\"");
  } else {
    const Json* loads = root.array("loads", "an array of load objects", false);
    if (loads->empty())
      fail(file, "/loads",
           "expected at least one load (the stopping rule ||r|| <= tol ||f_ext|| needs f_ext != "
           "0)");
    for (std::size_t i = 0; i < loads->size(); ++i) {
      s.loads.push_back(parse_load((*loads)[i], detail::child_path("/loads", i), file));
      if (s.loads.back().kind == LoadSpec::Kind::kGravity && rho_reason.empty())
        rho_reason = "the gravity load at " + s.loads.back().path + " needs a density";
    }
  }
  if (dynamic && rho_reason.empty())
    rho_reason = "the \"dynamic-ss22\" solver needs a density for the lumped mass";
  s.material = detail::parse_material(root.object("material", "a material object {\"model\": ...}"),
                                      rho_reason);
  if (s.solver.method == SolverSpec::Method::kCG &&
      s.material.model != material::LinearElastic::kName)
    fail(file, "/solver/method",
         "\"cg\" solves linear elasticity only (thesis §3.1); material \"" + s.material.model +
             "\" needs \"nonlinear-cg\", \"newton\" or \"dynamic-ss22\"");
  if (s.solver.method == SolverSpec::Method::kAugmented &&
      s.material.model != material::LinearElastic::kName)
    fail(file, "/solver/method",
         "\"augmented\" factorizes the constant linear stiffness; material \"" + s.material.model +
             "\" is nonlinear");
  if (s.solver.assembled_product.value_or(false) &&
      s.material.model != material::LinearElastic::kName)
    fail(file, "/solver/assembled_product",
         "the assembled product needs the \"linear\" material (its stiffness K does not change "
         "with u; fem::ElasticProblem::set_assembled_product), got \"" +
             s.material.model + "\": its K·d stays matrix-free");

  const Json* fixed = root.array("fixed", "an array of region objects", false);
  for (std::size_t i = 0; i < fixed->size(); ++i) {
    s.fixed.push_back(parse_region((*fixed)[i], detail::child_path("/fixed", i), file));
    if (slab) check_slab_fixed_line(s.fixed.back(), (*fixed)[i], file);
    if (needle3d) check_needle3d_fixed(s.fixed.back(), (*fixed)[i], file);
  }
  if (s.fixed.empty() && !dynamic)
    fail(file, "/fixed",
         "expected at least one fixed region: a static problem without constraints has a "
         "singular stiffness (rigid motions)");

  if (const Json* tools = root.array("tools", "an array of tool objects", true)) {
    for (std::size_t i = 0; i < tools->size(); ++i) {
      s.tools.push_back(parse_tool((*tools)[i], detail::child_path("/tools", i), file, slab));
      check_tool_dimension(s.tools.back(), s.mesh, file);
    }
  }
  if (slab) check_needle(s, file);
  if (needle3d) check_needle3d(s, file);
  // Keys of the interactive cutting run (augmented solver with a tool) in a scene without one.
  if (s.tools.empty() && solver_json && solver_json->is_object()) {
    const std::pair<const char*, const char*> cut_only_keys[] = {
        {"cut_configuration", ""},
        {"solve_every", ""},
        {"refactor_at_m", ", so the augmented run solves once and never refactors"},
        {"refactorization", ", so the augmented run solves once and never refactors"},
        {"solve_threads",
         ", so the augmented run is one direct CHOLMOD solve without the augmented steps"},
        {"schur_preconditioner",
         ", so the augmented run is one direct CHOLMOD solve without a Schur system"}};
    for (const auto& [key, why] : cut_only_keys) {
      if (solver_json->contains(key))
        fail(file, std::string("/solver/") + key,
             std::string("not allowed here: the scene names no tool") + why +
                 " (add a scalpel under /tools)");
    }
  }
  if (root.has("outputs")) {
    s.outputs = parse_outputs(root.object("outputs", "an outputs object"));
    if (needle_scene && !s.outputs.probes.empty())
      fail(file, "/outputs/probes",
           "not allowed here: a needle scene refines its mesh at every update, so a probe has no "
           "fixed node; its per-update CSV records the tip, the needle nodes and the needle force");
  } else {
    root.get("outputs");
  }
  if (root.has("limits")) {
    JsonObject limits = root.object("limits", "a limits object {\"memory_mb\": N}");
    s.limits.memory_mb = limits.integer("memory_mb", 1, std::numeric_limits<int>::max(), 0);
    limits.finish();
  } else {
    root.get("limits");
  }
  root.finish();
  return s;
}

}  // namespace

SceneSpec parse_scene(const std::string& text, const std::string& file,
                      const std::string& base_dir) {
  detail::ParsedJson parsed = detail::parse_strict(text, file);
  try {
    SceneSpec s = parse_root(parsed.value, file, base_dir);
    s.lines = std::move(parsed.lines);
    return s;
  } catch (const ParseError& e) {
    throw detail::with_line(e, file, parsed.lines);  // "<file>:<line>: <path>: ..."
  }
}

SceneSpec load_scene(const std::string& path) {
  const std::string text = detail::read_scene_file(path);
  const std::string base = std::filesystem::path(path).parent_path().string();
  return parse_scene(text, path, base);
}

}  // namespace incise::scene
