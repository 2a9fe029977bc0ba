// Scene files (docs/scenes.md): a valid scene parses into the expected spec; each kind of bad
// scene is rejected with a ParseError naming the JSON path and the expected form.

#include <incise/core/error.hpp>
#include <incise/interactive/augmented_cut_session.hpp>
#include <incise/material/material.hpp>
#include <incise/scene/delaunay_scene.hpp>
#include <incise/scene/scene_parser.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <tuple>

#include <incise_test/scene_errors.hpp>
#include "incise_test/seed.hpp"

namespace {

using incise::ParseError;
using incise::scene::parse_scene;
using Json = nlohmann::json;

// The thesis cantilever (§3.3, Table 3.1): l = 1.2 m, h = 0.2 m, d = 0.3 m, E = 1e6 Pa, ν = 0,
// total tip load 3 N.
Json valid_scene() {
  return Json::parse(R"({
    "version": 1,
    "name": "cantilever",
    "mesh": {"type": "box", "nx": 4, "ny": 1, "nz": 1, "lx": 1.2, "ly": 0.2, "lz": 0.3},
    "material": {"model": "linear", "E": 1e6, "nu": 0.0},
    "fixed": [{"type": "plane", "axis": "x", "value": 0.0}],
    "loads": [{"type": "nodal", "region": {"type": "plane", "axis": "x", "value": 1.2},
               "total_force": [0, -3, 0]}],
    "solver": {"method": "cg", "tolerance": 1e-8, "max_iterations": 5000},
    "outputs": {"probes": [{"name": "tip", "region": {"type": "plane", "axis": "x", "value": 1.2}}]}
  })");
}

std::string error_of(const Json& j) {
  return incise::test::scene_parse_error(j.dump(2));
}

TEST(SceneParser, ValidCantileverParses) {
  const auto s = parse_scene(valid_scene().dump(), "scene.json", "");
  EXPECT_EQ(s.name, "cantilever");
  EXPECT_EQ(s.mesh.source, incise::scene::MeshSpec::Source::kBox);
  EXPECT_EQ(s.mesh.nx, 4);
  EXPECT_DOUBLE_EQ(s.mesh.lx, 1.2);
  EXPECT_EQ(s.material.model, "linear");
  EXPECT_DOUBLE_EQ(s.material.parameters.youngs_modulus, 1e6);
  EXPECT_DOUBLE_EQ(s.material.parameters.poisson_ratio, 0.0);
  EXPECT_DOUBLE_EQ(s.material.parameters.density, 1000.0);  // material::Parameters' default
  ASSERT_EQ(s.fixed.size(), 1u);
  EXPECT_EQ(s.fixed[0].axis, 0);
  ASSERT_EQ(s.loads.size(), 1u);
  EXPECT_EQ(s.loads[0].kind, incise::scene::LoadSpec::Kind::kNodal);
  EXPECT_DOUBLE_EQ(s.loads[0].vector[1], -3.0);
  EXPECT_EQ(s.solver.method, incise::scene::SolverSpec::Method::kCG);
  EXPECT_EQ(s.solver.preconditioner, incise::solver::Preconditioner::kNone);
  EXPECT_DOUBLE_EQ(s.solver.tolerance, 1e-8);
  ASSERT_EQ(s.outputs.probes.size(), 1u);
  EXPECT_TRUE(s.outputs.probes[0].use_region);
}

// The box split "kuhn" names the mirrored Kuhn pattern of tetrahedral bisection
// (mesh::CubeSplit::kKuhn, docs/tet_bisection.md); an unknown split names the three.
TEST(SceneParser, KuhnSplitParsesAndUnknownSplitIsRefused) {
  Json j = valid_scene();
  j["mesh"]["split"] = "kuhn";
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").mesh.split, incise::mesh::CubeSplit::kKuhn);
  j["mesh"]["split"] = "seven";
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/mesh/split"), std::string::npos) << e;
  EXPECT_NE(e.find("kuhn"), std::string::npos) << e;
  EXPECT_NE(e.find("five"), std::string::npos) << e;
}

// One bad-scene kind per test: the message must name the path and the expected form.

TEST(SceneParserBad, JsonSyntaxErrorGivesLine) {
  const std::string e = incise::test::scene_parse_error("{\n  \"version\": 1,\n  \"mesh\": {]\n}");
  EXPECT_NE(e.find("scene.json:3: invalid JSON at column"), std::string::npos) << e;
}

TEST(SceneParserBad, DuplicateKey) {
  const std::string e = incise::test::scene_parse_error(
      R"({"version": 1, "material": {"model": "linear", "E": 1, "E": 2}})");
  EXPECT_NE(e.find("/material/E: duplicate key \"E\""), std::string::npos) << e;
}

TEST(SceneParserBad, DuplicateKeyInsideArrayElement) {
  const std::string e = incise::test::scene_parse_error(
      R"({"fixed": [{"type": "box"}, {"type": "tag", "tag": 1, "tag": 2}]})");
  EXPECT_NE(e.find("/fixed/1/tag: duplicate key"), std::string::npos) << e;
}

TEST(SceneParserBad, RootNotAnObject) {
  const std::string e = incise::test::scene_parse_error("[1, 2, 3]");
  EXPECT_NE(e.find("scene.json:1: /: expected a scene object"), std::string::npos) << e;
}

TEST(SceneParserBad, UnknownTopLevelKeyWithSuggestion) {
  Json j = valid_scene();
  j["solvr"] = j["solver"];
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/solvr: unknown key \"solvr\""), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean \"solver\"?"), std::string::npos) << e;
}

TEST(SceneParserBad, UnknownNestedKeyListsAllowedKeys) {
  Json j = valid_scene();
  j["material"]["poisson"] = 0.3;
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/material/poisson: unknown key"), std::string::npos) << e;
  EXPECT_NE(e.find("allowed here: E, allow_inversion, model, nu, rho"), std::string::npos) << e;
}

TEST(SceneParserBad, WrongTypeStringForNumber) {
  Json j = valid_scene();
  j["material"]["nu"] = "0.3";
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/material/nu: expected a finite number, got string \"0.3\""), std::string::npos)
      << e;
}

// Material parameters are judged by material::validate alone; its message is reported at the
// path of the parameter it rejects.
TEST(SceneParserBad, PoissonRatioOutOfRange) {
  Json j = valid_scene();
  j["material"]["nu"] = 0.5;
  const std::string e = error_of(j);  // "scene.json:<line of "nu">: ..."
  EXPECT_EQ(e.substr(e.find(": /")),
            ": /material/nu: material parameter nu (Poisson ratio) = 0.5 is inadmissible: must "
            "satisfy -1 < nu < 0.5");
  EXPECT_EQ(e.rfind("scene.json:", 0), 0u) << e;
}

TEST(SceneParserBad, NonPositiveYoungModulus) {
  Json j = valid_scene();
  j["material"]["E"] = 0;
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/material/E: material parameter E (Young's modulus) = 0 is inadmissible"),
            std::string::npos)
      << e;
}

TEST(SceneParserBad, NegativeGamma) {
  Json j = valid_scene();
  j["material"] = {{"model", "veronda-westmann"}, {"E", 1e4}, {"nu", 0.3}, {"gamma", -1}};
  j["solver"]["method"] = "newton";
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/material/gamma: material parameter gamma (Veronda-Westmann nonlinearity) = "
                   "-1 is inadmissible"),
            std::string::npos)
      << e;
}

TEST(SceneParserBad, NegativeDensity) {
  Json j = valid_scene();
  j["material"]["rho"] = -1;
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/material/rho: material parameter rho (density) = -1 is inadmissible"),
            std::string::npos)
      << e;
}

TEST(SceneParser, VerondaWestmannMaterialHoldsItsParameters) {
  Json j = valid_scene();
  j["material"] = {
      {"model", "veronda-westmann"}, {"E", 1e4}, {"nu", 0.3}, {"gamma", 8}, {"rho", 1070}};
  j["solver"]["method"] = "newton";
  j["solver"]["preconditioner"] = "jacobi";
  const auto s = parse_scene(j.dump(), "scene.json", "");
  EXPECT_EQ(s.material.model, "veronda-westmann");
  EXPECT_DOUBLE_EQ(s.material.parameters.youngs_modulus, 1e4);
  EXPECT_DOUBLE_EQ(s.material.parameters.poisson_ratio, 0.3);
  EXPECT_DOUBLE_EQ(s.material.parameters.gamma, 8.0);
  EXPECT_DOUBLE_EQ(s.material.parameters.density, 1070.0);
  EXPECT_EQ(s.solver.preconditioner, incise::solver::Preconditioner::kJacobi);
}

// Issue 19: the nonlinear-CG variant from the scene (β rule, line search, its tolerance).
TEST(SceneParser, NonlinearCgVariantKeys) {
  Json j = valid_scene();
  j["solver"]["method"] = "nonlinear-cg";
  auto s = parse_scene(j.dump(), "scene.json", "");
  EXPECT_EQ(s.solver.beta, incise::solver::BetaRule::kPolakRibiere);  // the thesis' §4.5 choice
  EXPECT_EQ(s.solver.line_search, incise::solver::LineSearchKind::kSecant);
  EXPECT_EQ(s.solver.line_search_tolerance, 0.1);
  j["solver"]["beta"] = "fletcher-reeves";
  j["solver"]["line_search"] = "newton";
  j["solver"]["line_search_tolerance"] = 0.01;
  s = parse_scene(j.dump(), "scene.json", "");
  EXPECT_EQ(s.solver.beta, incise::solver::BetaRule::kFletcherReeves);
  EXPECT_EQ(s.solver.line_search, incise::solver::LineSearchKind::kNewton);
  EXPECT_EQ(s.solver.line_search_tolerance, 0.01);
}

TEST(SceneParserBad, NonlinearCgVariantKeys) {
  Json j = valid_scene();
  j["solver"]["method"] = "nonlinear-cg";
  j["solver"]["beta"] = "hestenes-stiefel";
  std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/beta"), std::string::npos) << e;
  EXPECT_NE(e.find("fletcher-reeves"), std::string::npos) << e;  // names the choices
  j["solver"].erase("beta");
  for (double bad : {0.0, 1.0, 1.5}) {
    j["solver"]["line_search_tolerance"] = bad;
    e = error_of(j);
    EXPECT_NE(e.find("/solver/line_search_tolerance"), std::string::npos) << bad << ": " << e;
  }
  Json cg = valid_scene();  // method "cg"
  cg["solver"]["line_search"] = "newton";
  e = error_of(cg);
  EXPECT_NE(e.find("only \"nonlinear-cg\" has a beta rule and a line search"), std::string::npos)
      << e;
}

// Issue 19: the assembled K·d of relaxation scenes (`solver.assembled_product`): unset is the
// default (scene::kDefaultAssembledProduct, applied by the builder), an explicit value is kept.
TEST(SceneParser, AssembledProductKey) {
  Json j = valid_scene();
  for (const char* method : {"cg", "nonlinear-cg", "newton", "dynamic-ss22"}) {
    j["solver"]["method"] = method;
    j["material"]["rho"] = 1000;  // dynamic-ss22 needs a density
    EXPECT_FALSE(parse_scene(j.dump(), "scene.json", "").solver.assembled_product.has_value());
    for (bool on : {false, true}) {
      j["solver"]["assembled_product"] = on;
      const auto s = parse_scene(j.dump(), "scene.json", "");
      ASSERT_TRUE(s.solver.assembled_product.has_value()) << method;
      EXPECT_EQ(*s.solver.assembled_product, on) << method;
    }
    j["solver"].erase("assembled_product");
  }
}

// Refused, with the file, line and key, where it does not apply: a material whose K depends on
// u (an explicit false is harmless there), the "augmented" solver, a non-boolean value.
TEST(SceneParserBad, AssembledProductWhereItDoesNotApply) {
  Json j = valid_scene();
  j["material"] = {{"model", "veronda-westmann"}, {"E", 1e4}, {"nu", 0.3}, {"gamma", 8.0}};
  j["solver"]["method"] = "nonlinear-cg";
  j["solver"]["assembled_product"] = true;
  std::string e = error_of(j);
  EXPECT_EQ(e.rfind("scene.json:", 0), 0u) << e;
  EXPECT_NE(e.find(": /solver/assembled_product: the assembled product needs the \"linear\" "
                   "material"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("\"veronda-westmann\""), std::string::npos) << e;
  j["solver"]["assembled_product"] = false;
  EXPECT_EQ(error_of(j), "<no error>");
  Json a = valid_scene();
  a["solver"] = {{"method", "augmented"}, {"assembled_product", true}};
  e = error_of(a);
  EXPECT_NE(e.find(": /solver/assembled_product: not allowed here:"), std::string::npos) << e;
  EXPECT_NE(e.find("the \"augmented\" solver factors K instead"), std::string::npos) << e;
  Json b = valid_scene();
  b["solver"]["assembled_product"] = "yes";
  e = error_of(b);
  EXPECT_NE(e.find(": /solver/assembled_product: "), std::string::npos) << e;
}

TEST(SceneParserBad, MissingRequiredKey) {
  Json j = valid_scene();
  j["material"].erase("E");
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/material: missing required key \"E\" (expected a finite number)"),
            std::string::npos)
      << e;
}

TEST(SceneParserBad, MissingMeshFile) {
  Json j = valid_scene();
  j["mesh"] = {{"type", "file"}, {"path", "no/such/liver.mesh"}};
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/mesh/path: mesh file not found: no/such/liver.mesh"), std::string::npos) << e;
}

TEST(SceneParserBad, UnknownMeshExtension) {
  Json j = valid_scene();
  j["mesh"] = {{"type", "file"}, {"path", "liver.stl"}};
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/mesh/path: expected a mesh file ending in .mesh"), std::string::npos) << e;
}

TEST(SceneParserBad, IntegerExpected) {
  Json j = valid_scene();
  j["mesh"]["nx"] = 2.5;
  EXPECT_NE(error_of(j).find("/mesh/nx: expected an integer in [1, 1000], got 2.5"),
            std::string::npos);
}

TEST(SceneParserBad, UnknownEnumValue) {
  Json j = valid_scene();
  j["solver"]["method"] = "gauss-seidel";
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/method: expected one of \"cg\", \"nonlinear-cg\", \"newton\", "
                   "\"dynamic-ss22\", \"augmented\", got string \"gauss-seidel\""),
            std::string::npos)
      << e;
  // The list is the method's name table.
  EXPECT_NE(e.find("expected " + incise::scene::kMethodNames.one_of() + ", got"), std::string::npos)
      << e;
}

// Every name of a method parses to its value (the name table read both ways).
TEST(SceneParser, EveryMethodNameParsesToItsValue) {
  for (const auto& [method, name] : incise::scene::kMethodNames.entries) {
    SCOPED_TRACE(name);
    Json j = valid_scene();
    j["solver"] = {{"method", name}};
    if (method == incise::scene::SolverSpec::Method::kDynamicSS22) j["material"]["rho"] = 1000;
    const auto s = parse_scene(j.dump(), "scene.json", "");
    EXPECT_EQ(s.solver.method, method);
    EXPECT_STREQ(incise::scene::to_string(s.solver.method), name);
  }
}

TEST(SceneParserBad, DensityZeroWhereAGravityLoadNeedsIt) {
  Json j = valid_scene();
  j["loads"].push_back({{"type", "gravity"}, {"g", {0, 0, -9.8}}});
  j["material"]["rho"] = 0;
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/material/rho: expected a number > 0 (density in kg/m^3), got 0: the gravity "
                   "load at /loads/1 needs a density"),
            std::string::npos)
      << e;
}

TEST(SceneParserBad, VectorWithWrongLength) {
  Json j = valid_scene();
  j["loads"][0]["total_force"] = {0, -3};
  EXPECT_NE(error_of(j).find("/loads/0/total_force: expected an array of 3 finite numbers"),
            std::string::npos);
}

TEST(SceneParserBad, VectorWithNonNumberEntry) {
  Json j = valid_scene();
  j["loads"][0]["total_force"] = {0, "down", 0};
  EXPECT_NE(error_of(j).find("/loads/0/total_force/1: expected a finite number, got string"),
            std::string::npos);
}

TEST(SceneParserBad, BoxRegionInverted) {
  Json j = valid_scene();
  j["fixed"][0] = {{"type", "box"}, {"min", {0, 0, 0}}, {"max", {1, -1, 1}}};
  EXPECT_NE(error_of(j).find("/fixed/0/max: expected max >= min in every coordinate"),
            std::string::npos);
}

TEST(SceneParserBad, NoLoads) {
  Json j = valid_scene();
  j["loads"] = Json::array();
  EXPECT_NE(error_of(j).find("/loads: expected at least one load"), std::string::npos);
}

TEST(SceneParserBad, StaticWithoutFixedRegion) {
  Json j = valid_scene();
  j["fixed"] = Json::array();
  EXPECT_NE(error_of(j).find("/fixed: expected at least one fixed region"), std::string::npos);
}

TEST(SceneParserBad, GravityWithoutDensity) {
  Json j = valid_scene();
  j["loads"].push_back({{"type", "gravity"}, {"g", {0, 0, -9.8}}});
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/material: missing required key \"rho\""), std::string::npos) << e;
  EXPECT_NE(e.find("gravity load at /loads/1"), std::string::npos) << e;
}

TEST(SceneParserBad, DynamicWithoutDensity) {
  Json j = valid_scene();
  j["solver"] = {{"method", "dynamic-ss22"}};
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/material: missing required key \"rho\" (expected a number > 0, density in "
                   "kg/m^3): the \"dynamic-ss22\" solver needs a density for the lumped mass"),
            std::string::npos)
      << e;
}

TEST(SceneParserBad, LinearCgWithNonlinearMaterial) {
  Json j = valid_scene();
  j["material"]["model"] = "neohookean";
  EXPECT_NE(error_of(j).find("/solver/method: \"cg\" solves linear elasticity only"),
            std::string::npos);
}

TEST(SceneParserBad, DynamicKeyOnStaticSolver) {
  Json j = valid_scene();
  j["solver"]["time_step"] = 1e-4;
  EXPECT_NE(error_of(j).find("/solver/time_step: not allowed here: only the \"dynamic-ss22\""),
            std::string::npos);
}

TEST(SceneParserBad, GammaOnNonVerondaMaterial) {
  Json j = valid_scene();
  j["material"]["gamma"] = 8;
  EXPECT_NE(error_of(j).find("/material/gamma: not allowed here"), std::string::npos);
}

TEST(SceneParserBad, DuplicateProbeName) {
  Json j = valid_scene();
  j["outputs"]["probes"].push_back({{"name", "tip"}, {"at", {1.2, 0.1, 0.15}}});
  EXPECT_NE(error_of(j).find("/outputs/probes/1/name: duplicate probe name \"tip\""),
            std::string::npos);
}

TEST(SceneParserBad, ProbeWithBothLocationAndRegion) {
  Json j = valid_scene();
  j["outputs"]["probes"][0]["at"] = {1.2, 0.1, 0.15};
  EXPECT_NE(error_of(j).find("/outputs/probes/0: expected exactly one of \"at\""),
            std::string::npos);
}

TEST(SceneParserBad, ScalpelPathTooShort) {
  Json j = valid_scene();
  j["tools"] = {{{"type", "scalpel"}, {"path", {{0, 0, 0}}}, {"blade", {0, 0, 1}}}};
  EXPECT_NE(error_of(j).find("/tools/0/path: expected an array of at least 2 points"),
            std::string::npos);
}

TEST(SceneParserBad, ScalpelSegmentParallelToBlade) {
  Json j = valid_scene();
  j["tools"] = {{{"type", "scalpel"}, {"path", {{0, 0, 0}, {0, 0, 1}}}, {"blade", {0, 0, 1}}}};
  EXPECT_NE(error_of(j).find("/tools/0/path/1: the path segment from point 0"), std::string::npos);
}

TEST(SceneParserBad, UnsupportedVersion) {
  Json j = valid_scene();
  j["version"] = 2;
  EXPECT_NE(error_of(j).find("/version: expected an integer in [1, 1], got 2"), std::string::npos);
}

TEST(SceneParserBad, ToleranceNotBelowOne) {
  Json j = valid_scene();
  j["solver"]["tolerance"] = 1.0;
  EXPECT_NE(error_of(j).find("/solver/tolerance: expected a number in (0, 1), got 1"),
            std::string::npos);
}

TEST(SceneParserBad, VtuEveryWithoutVtu) {
  Json j = valid_scene();
  j["outputs"]["vtu_every"] = 10;
  EXPECT_NE(error_of(j).find("/outputs/vtu_every: not allowed here"), std::string::npos);
}

TEST(SceneParserBad, UnreadableSceneFile) {
  try {
    (void)incise::scene::load_scene("/nonexistent/dir/scene.json");
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/dir/scene.json: cannot open scene file");
  }
}

// Every scene shipped in reference_data/scenes/ must parse.
TEST(SceneParser, ShippedScenesParse) {
  const std::string dir = incise::test::source_path("reference_data/scenes");
  int count = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    SCOPED_TRACE(entry.path().string());
    if (incise::scene::is_delaunay_scene(entry.path().string()))  // thesis ch. 5 (own parser)
      EXPECT_NO_THROW((void)incise::scene::load_delaunay_scene(entry.path().string()));
    else
      EXPECT_NO_THROW((void)incise::scene::load_scene(entry.path().string()));
    ++count;
  }
  EXPECT_GE(count, 1);
}

// cut_configuration (docs/scenes.md, interactive cutting run): only for "augmented" with tools.
Json augmented_cut_scene() {
  Json j = valid_scene();
  j["solver"] = Json::parse(R"({"method": "augmented", "cut_configuration": "reference"})");
  j["tools"] = Json::parse(
      R"([{"type": "scalpel", "path": [[0.6, -0.1, 0.4], [0.6, 0.3, 0.4]], "blade": [0, 0, -0.2]}])");
  return j;
}

TEST(SceneParser, CutConfigurationParses) {
  using incise::scene::SolverSpec;
  const auto s = parse_scene(augmented_cut_scene().dump(), "scene.json", "");
  EXPECT_EQ(s.solver.cut_configuration, SolverSpec::CutConfiguration::kReference);
  Json j = augmented_cut_scene();
  j["solver"].erase("cut_configuration");
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.cut_configuration,
            SolverSpec::CutConfiguration::kDeformed);  // default
}

TEST(SceneParserBad, CutConfigurationOnANonAugmentedSolver) {
  Json j = augmented_cut_scene();
  j["solver"]["method"] = "cg";
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/cut_configuration: not allowed here: only the \"augmented\" method"),
            std::string::npos)
      << e;
}

TEST(SceneParserBad, CutConfigurationWithoutTool) {
  Json j = augmented_cut_scene();
  j.erase("tools");
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/cut_configuration: not allowed here: the scene names no tool"),
            std::string::npos)
      << e;
}

TEST(SceneParserBad, CutConfigurationUnknownValue) {
  Json j = augmented_cut_scene();
  j["solver"]["cut_configuration"] = "world";
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/cut_configuration"), std::string::npos) << e;
  EXPECT_NE(e.find("\"deformed\""), std::string::npos) << e;
}

// solve_every (docs/scenes.md, interactive cutting run): "segment" (default) or "triangle",
// only for "augmented" with tools.
TEST(SceneParser, SolveEveryParses) {
  using incise::scene::SolverSpec;
  Json j = augmented_cut_scene();
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.solve_every,
            SolverSpec::SolveEvery::kSegment);  // default
  j["solver"]["solve_every"] = "triangle";
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.solve_every,
            SolverSpec::SolveEvery::kTriangle);
  j["solver"]["solve_every"] = "segment";
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.solve_every,
            SolverSpec::SolveEvery::kSegment);
}

TEST(SceneParserBad, SolveEveryUnknownValueOtherMethodOrNoTool) {
  Json j = augmented_cut_scene();
  j["solver"]["solve_every"] = "frame";
  std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/solve_every"), std::string::npos) << e;
  EXPECT_NE(e.find("\"segment\""), std::string::npos) << e;
  EXPECT_NE(e.find("\"triangle\""), std::string::npos) << e;
  j["solver"]["solve_every"] = "triangle";
  j["solver"]["method"] = "cg";
  j["solver"].erase("cut_configuration");
  e = error_of(j);
  EXPECT_NE(e.find("/solver/solve_every: not allowed here: only the \"augmented\" method"),
            std::string::npos)
      << e;
  j = augmented_cut_scene();
  j["solver"].erase("cut_configuration");
  j["solver"]["solve_every"] = "triangle";
  j.erase("tools");
  e = error_of(j);
  EXPECT_NE(e.find("/solver/solve_every: not allowed here: the scene names no tool"),
            std::string::npos)
      << e;
}

// refactor_at_m (docs/scenes.md, interactive cutting run; augmented paper §3.6).
TEST(SceneParser, RefactorAtMParses) {
  Json j = augmented_cut_scene();
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.refactor_at_m, 0);  // default: never
  j["solver"]["refactor_at_m"] = 300;
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.refactor_at_m, 300);
}

// refactorization (docs/scenes.md; interactive/refactorization_policy.hpp): by default the
// library session's mode (continuous, issue 17); "none" turns it off.
TEST(SceneParser, RefactorizationParses) {
  Json j = augmented_cut_scene();
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.refactorization,
            incise::interactive::RefactorizationMode::kContinuous);
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.refactorization,
            incise::interactive::AugmentedCutOptions{}.refactorization_mode);
  j["solver"]["refactorization"] = "none";
  EXPECT_FALSE(parse_scene(j.dump(), "scene.json", "").solver.refactorization.has_value());
  j["solver"]["refactorization"] = "break-even";
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.refactorization,
            incise::interactive::RefactorizationMode::kBreakEven);
  j["solver"]["refactorization"] = "continuous";
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.refactorization,
            incise::interactive::RefactorizationMode::kContinuous);
}

TEST(SceneParserBad, RefactorizationUnknownName) {
  Json j = augmented_cut_scene();
  j["solver"]["refactorization"] = "always";
  const std::string e = error_of(j);
  EXPECT_NE(e.find("scene.json:"), std::string::npos) << e;
  EXPECT_NE(e.find("/solver/refactorization"), std::string::npos) << e;
  EXPECT_NE(e.find("\"none\", \"break-even\", \"continuous\""), std::string::npos) << e;
}

TEST(SceneParserBad, RefactorizationWithoutTool) {
  Json j = augmented_cut_scene();
  j["solver"].erase("cut_configuration");
  j["solver"]["refactorization"] = "continuous";
  j.erase("tools");
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/refactorization: not allowed here: the scene names no tool"),
            std::string::npos)
      << e;
}

TEST(SceneParserBad, RefactorAtMNegative) {
  Json j = augmented_cut_scene();
  j["solver"]["refactor_at_m"] = -5;
  const std::string e = error_of(j);
  EXPECT_NE(e.find("scene.json:"), std::string::npos) << e;
  EXPECT_NE(e.find("/solver/refactor_at_m: expected an integer in [0, "), std::string::npos) << e;
  EXPECT_NE(e.find("got -5"), std::string::npos) << e;
}

TEST(SceneParserBad, RefactorAtMNotAnInteger) {
  Json j = augmented_cut_scene();
  j["solver"]["refactor_at_m"] = 12.5;
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/refactor_at_m: expected an integer in [0, "), std::string::npos) << e;
}

TEST(SceneParserBad, RefactorAtMOnANonAugmentedSolver) {
  Json j = augmented_cut_scene();
  j["solver"].erase("cut_configuration");
  j["solver"]["method"] = "cg";
  j["solver"]["refactor_at_m"] = 100;
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/refactor_at_m: not allowed here: only the \"augmented\" method"),
            std::string::npos)
      << e;
}

// threads (docs/scenes.md: the element loops' thread count, fem::ElasticProblem::set_threads).
TEST(SceneParser, ThreadsParses) {
  Json j = valid_scene();
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.threads, 0);  // default: 0 = all cores
  j["solver"]["threads"] = 3;
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.threads, 3);
}

TEST(SceneParserBad, ThreadsOutOfRange) {
  for (const Json& bad : {Json(0), Json(257), Json(1.5), Json("2")}) {
    Json j = valid_scene();
    j["solver"]["threads"] = bad;
    const std::string e = error_of(j);
    EXPECT_NE(e.find("/solver/threads: expected an integer in [1, 256]"), std::string::npos) << e;
  }
}

// solve_threads (docs/scenes.md, interactive cutting run; AugmentedOptions::solve_threads).
TEST(SceneParser, SolveThreadsParses) {
  Json j = augmented_cut_scene();
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.solve_threads, 1);  // default: serial
  j["solver"]["solve_threads"] = 2;
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.solve_threads, 2);
}

TEST(SceneParserBad, SolveThreadsOutOfRange) {
  for (const Json& bad : {Json(0), Json(65), Json(1.5), Json("2")}) {
    Json j = augmented_cut_scene();
    j["solver"]["solve_threads"] = bad;
    const std::string e = error_of(j);
    EXPECT_NE(e.find("/solver/solve_threads: expected an integer in [1, 64]"), std::string::npos)
        << e;
  }
}

TEST(SceneParserBad, SolveThreadsOnANonAugmentedSolverOrWithoutTool) {
  Json j = augmented_cut_scene();
  j["solver"].erase("cut_configuration");
  j["solver"]["method"] = "cg";
  j["solver"]["solve_threads"] = 2;
  std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/solve_threads: not allowed here: only the \"augmented\" method"),
            std::string::npos)
      << e;
  j = augmented_cut_scene();
  j["solver"].erase("cut_configuration");
  j["solver"]["solve_threads"] = 2;
  j.erase("tools");
  e = error_of(j);
  EXPECT_NE(e.find("/solver/solve_threads: not allowed here: the scene names no tool"),
            std::string::npos)
      << e;
}

// schur_preconditioner (docs/scenes.md, interactive cutting run; eq. 17 of Yeung et al. 2016).
TEST(SceneParser, SchurPreconditionerParses) {
  using incise::linalg::SchurPreconditioner;
  using incise::linalg::SchurSolver;
  Json j = augmented_cut_scene();
  EXPECT_EQ(parse_scene(j.dump(), "scene.json", "").solver.schur_solver,
            SchurSolver::kDirectCached);  // default "explicit"
  const std::tuple<const char*, SchurSolver, SchurPreconditioner> cases[] = {
      {"explicit", SchurSolver::kDirectCached, SchurPreconditioner::kDiagonal},
      {"hsj", SchurSolver::kGmres, SchurPreconditioner::kDiagonal},
      {"spai", SchurSolver::kGmres, SchurPreconditioner::kTridiagonalSpai},
      {"none", SchurSolver::kGmres, SchurPreconditioner::kNone}};
  for (const auto& [name, schur_solver, preconditioner] : cases) {
    SCOPED_TRACE(name);
    j["solver"]["schur_preconditioner"] = name;
    const auto s = parse_scene(j.dump(), "scene.json", "");
    EXPECT_EQ(s.solver.schur_solver, schur_solver);
    EXPECT_EQ(s.solver.schur_preconditioner, preconditioner);
  }
}

TEST(SceneParserBad, SchurPreconditionerUnknownOrMisplaced) {
  Json j = augmented_cut_scene();
  j["solver"]["schur_preconditioner"] = "jacobi";
  std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/schur_preconditioner: expected one of \"explicit\", \"hsj\", "
                   "\"spai\", \"none\", got string \"jacobi\""),
            std::string::npos)
      << e;
  j = augmented_cut_scene();
  j["solver"].erase("cut_configuration");
  j["solver"]["method"] = "cg";
  j["solver"]["schur_preconditioner"] = "hsj";
  e = error_of(j);
  EXPECT_NE(e.find("/solver/schur_preconditioner: not allowed here: only the \"augmented\" method"),
            std::string::npos)
      << e;
  j = augmented_cut_scene();
  j["solver"].erase("cut_configuration");
  j["solver"]["schur_preconditioner"] = "hsj";
  j.erase("tools");
  e = error_of(j);
  EXPECT_NE(e.find("/solver/schur_preconditioner: not allowed here: the scene names no tool"),
            std::string::npos)
      << e;
}

TEST(SceneParserBad, RefactorAtMWithoutTool) {
  Json j = augmented_cut_scene();
  j["solver"].erase("cut_configuration");
  j["solver"]["refactor_at_m"] = 100;
  j.erase("tools");
  const std::string e = error_of(j);
  EXPECT_NE(e.find("/solver/refactor_at_m: not allowed here: the scene names no tool"),
            std::string::npos)
      << e;
}

// docs/scenes.md lists every value of every enum a scene names, as the tables name them.
TEST(SceneDocs, NameEveryValueOfEverySceneEnum) {
  std::ifstream in(incise::test::source_path("docs/scenes.md"));
  ASSERT_TRUE(in);
  std::ostringstream os;
  os << in.rdbuf();
  const std::string doc = os.str();
  std::vector<std::string> names = {incise::scene::kExplicitSchurName,
                                    incise::scene::kNoRefactorizationName};
  auto add = [&names](const auto& table) {
    for (const std::string& n : table.names()) names.push_back(n);
  };
  add(incise::scene::kMeshSourceNames);
  add(incise::scene::kCubeSplitNames);
  add(incise::scene::kRegionKindNames);
  add(incise::scene::kLoadKindNames);
  add(incise::scene::kMethodNames);
  add(incise::scene::kCutConfigurationNames);
  add(incise::scene::kToolKindNames);
  add(incise::scene::kProbeQuantityNames);
  add(incise::solver::kPreconditionerNames);
  add(incise::linalg::kSchurPreconditionerNames);
  add(incise::interactive::kRefactorizationModeNames);
  for (const std::string& n : incise::material::registered_material_names()) names.push_back(n);
  for (const std::string& n : names)
    EXPECT_NE(doc.find("`\"" + n + "\"`"), std::string::npos)
        << "docs/scenes.md lacks `\"" << n << "\"`";
}

}  // namespace
