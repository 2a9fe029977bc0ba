// Scene errors name the file, the line and the JSON path of the offending value, then what was
// expected (docs/scenes.md, "Errors"): "scene.json:<line>: <path>: expected ..., got ...". The
// line is that of the value, or for an object member that of its key; for a missing key that of
// the enclosing object. Errors the builder finds after parsing (a region selecting no node) carry
// the line too.

#include <incise/core/error.hpp>
#include <incise/scene/scene_builder.hpp>
#include <incise/scene/scene_parser.hpp>

#include <incise_test/scene_errors.hpp>

#include <gtest/gtest.h>

#include <string>

namespace {

using incise::ParseError;
using incise::scene::build_scene;
using incise::scene::parse_scene;

// A valid scene, one key per line where it matters; line numbers are counted from 1.
const char* const kScene = R"({
  "version": 1,
  "name": "a {[\"quoted\"]} name: with / and ~",
  "mesh": {"type": "box", "nx": 2, "ny": 1, "nz": 1,
           "lx": 1.2, "ly": 0.2, "lz": 0.3},
  "material": {
    "model": "linear",
    "E": 1e6,
    "nu": 0.0
  },
  "fixed": [
    {"type": "plane", "axis": "x", "value": 0.0},
    {"type": "plane",
     "axis": "y", "value": 0.0}
  ],
  "loads": [{"type": "point", "at": [1.2, 0.2, 0.3], "force": [0, -1, 0]}],
  "solver": {"method": "cg"}
}
)";

// kScene with `from` replaced by `to` (once; `from` must occur).
std::string edited(const std::string& from, const std::string& to) {
  std::string s = kScene;
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

// The builder's error for `spec`: its line and message ("<no error>" when it builds).
struct BuildError {
  long line = -1;
  std::string what = "<no error>";
};

BuildError build_error(const incise::scene::SceneSpec& spec) {
  try {
    (void)build_scene(spec);
  } catch (const ParseError& e) {
    return {e.line(), e.what()};
  }
  return {};
}

// kScene with an outputs object holding one probe (`probe`, the text of its JSON object).
std::string with_probe(const std::string& probe) {
  return edited(
      "  \"solver\": {\"method\": \"cg\"}\n",
      "  \"solver\": {\"method\": \"cg\"},\n  \"outputs\": {\"probes\": [\n    " + probe + "]}\n");
}

// Line of the value at `pointer` in the spec's index; -1 when the index has no such value.
long line_at(const incise::scene::SceneSpec& s, const std::string& pointer) {
  return s.lines.contains(pointer) ? s.lines.line(pointer) : -1;
}

TEST(SceneErrorLines, ValidSceneRecordsTheLineOfEveryValue) {
  const auto s = parse_scene(kScene, "scene.json", "");
  EXPECT_EQ(line_at(s, ""), 1);
  EXPECT_EQ(line_at(s, "/name"), 3);  // a string holding braces, quotes and ": " is skipped whole
  EXPECT_EQ(line_at(s, "/mesh/nx"), 4);
  EXPECT_EQ(line_at(s, "/mesh/lz"), 5);
  EXPECT_EQ(line_at(s, "/material"), 6);  // an object member: the line of its key
  EXPECT_EQ(line_at(s, "/material/nu"), 9);
  EXPECT_EQ(line_at(s, "/fixed/1"), 13);  // an array element: the line where it begins
  EXPECT_EQ(line_at(s, "/fixed/1/axis"), 14);
  EXPECT_EQ(line_at(s, "/loads/0/at/2"), 16);
  EXPECT_EQ(line_at(s, "/solver/method"), 17);
}

TEST(SceneErrorLines, OutOfRangeValueNamesItsLine) {
  EXPECT_EQ(incise::test::scene_parse_error(edited("\"nx\": 2", "\"nx\": 0")),
            "scene.json:4: /mesh/nx: expected an integer in [1, 1000], got 0");
}

// material::validate judges the parameters; the parser names the line of the rejected one.
TEST(SceneErrorLines, InadmissibleMaterialParameterNamesItsLine) {
  EXPECT_EQ(incise::test::scene_parse_error(edited("\"nu\": 0.0", "\"nu\": 0.5")),
            "scene.json:9: /material/nu: material parameter nu (Poisson ratio) = 0.5 is "
            "inadmissible: must satisfy -1 < nu < 0.5");
  EXPECT_EQ(incise::test::scene_parse_error(edited("\"E\": 1e6", "\"E\": -2")),
            "scene.json:8: /material/E: material parameter E (Young's modulus) = -2 is "
            "inadmissible: must be finite and > 0 Pa");
}

TEST(SceneErrorLines, WrongTypeInANestedArrayNamesItsLine) {
  EXPECT_EQ(incise::test::scene_parse_error(edited("\"axis\": \"y\"", "\"axis\": 1")),
            "scene.json:14: /fixed/1/axis: expected one of \"x\", \"y\", \"z\", got 1");
}

TEST(SceneErrorLines, UnknownKeyNamesTheLineOfTheKey) {
  const std::string e =
      incise::test::scene_parse_error(edited("\"E\": 1e6,", "\"E\": 1e6, \"poisson\": 0.3,"));
  EXPECT_EQ(e.rfind("scene.json:8: /material/poisson: unknown key \"poisson\"", 0), 0u) << e;
}

TEST(SceneErrorLines, KeyHoldingColonAndSlashIsFoundByItsEscapedPointer) {
  // The JSON pointer escapes "/" as "~1"; the message's path is itself followed by ": ".
  const std::string e = incise::test::scene_parse_error(
      edited("\"version\": 1,", "\"version\": 1,\n  \"a: b/c\": 2,"));
  EXPECT_EQ(e.rfind("scene.json:3: /a: b~1c: unknown key \"a: b/c\"", 0), 0u) << e;
}

TEST(SceneErrorLines, MissingKeyNamesTheEnclosingObject) {
  const std::string e = incise::test::scene_parse_error(edited("    \"E\": 1e6,\n", ""));
  EXPECT_EQ(e.rfind("scene.json:6: /material: missing required key \"E\"", 0), 0u) << e;
}

TEST(SceneErrorLines, RootNotAnObjectIsLineOfTheRoot) {
  EXPECT_EQ(incise::test::scene_parse_error("\n\n  [1, 2]\n")
                .rfind("scene.json:3: /: expected a scene object", 0),
            0u);
}

TEST(SceneErrorLines, SyntaxErrorKeepsItsOwnLineAndColumn) {
  const std::string e = incise::test::scene_parse_error(edited("\"nu\": 0.0", "\"nu\": 0.0,"));
  EXPECT_EQ(e.rfind("scene.json:10: invalid JSON at column", 0), 0u) << e;
}

TEST(SceneErrorLines, BuilderErrorNamesTheLineOfTheRegion) {
  const auto spec = parse_scene(
      edited("\"axis\": \"y\", \"value\": 0.0", "\"axis\": \"y\", \"value\": 5"), "scene.json", "");
  const BuildError e = build_error(spec);
  EXPECT_EQ(e.line, 13);
  EXPECT_EQ(e.what.rfind("scene.json:13: /fixed/1: region selects no node", 0), 0u) << e.what;
}

// Issue 18: degenerate generated geometry is the generator's refusal (mesh::GeneratorError) at
// the JSON path and line of the parameter, before anything is allocated.
TEST(SceneErrorLines, DegenerateGeneratedGeometryNamesTheParameterAndItsLine) {
  EXPECT_EQ(build_error(parse_scene(edited("\"lx\": 1.2", "\"lx\": 1e300"), "scene.json", "")).what,
            "scene.json:5: /mesh/lx: make_box: cell size lx / nx = 1e+300 / 2 = 5e+299 m is "
            "outside [1e-100, 1e+100] m (cell volumes would not be representable)");
  const std::string cylinder = edited(
      "\"mesh\": {\"type\": \"box\", \"nx\": 2, \"ny\": 1, \"nz\": 1,\n           \"lx\": 1.2, "
      "\"ly\": 0.2, \"lz\": 0.3},",
      "\"mesh\": {\"type\": \"cylinder\", \"radius\": 0.1,\n  \"length\": 1e-320, \"rings\": 2, "
      "\"layers\": 2},");
  const BuildError e = build_error(parse_scene(cylinder, "scene.json", ""));
  EXPECT_EQ(e.line, 5);
  EXPECT_EQ(e.what.rfind("scene.json:5: /mesh/length: make_cylinder: cell size length / layers", 0),
            0u)
      << e.what;
}

// Issue 18: the build's memory estimate is checked against the budget before the mesh exists.
TEST(SceneErrorLines, MeshBeyondTheMemoryBudgetIsRefusedWithEstimateAndBudget) {
  const std::string big =
      edited("\"nx\": 2, \"ny\": 1, \"nz\": 1", "\"nx\": 100, \"ny\": 10, \"nz\": 10");
  const auto with_limit = [&](const std::string& scene, const std::string& limit) {
    std::string t = scene;
    t.replace(t.find("  \"version\": 1,"), 15,
              "  \"version\": 1, \"limits\": {\"memory_mb\": " + limit + "},");
    return t;
  };
  const BuildError e = build_error(parse_scene(with_limit(big, "1"), "scene.json", ""));
  EXPECT_EQ(e.line, 4);
  EXPECT_EQ(
      e.what.rfind("scene.json:4: /mesh: the mesh and its elastic problem need an estimated ", 0),
      0u)
      << e.what;
  EXPECT_NE(e.what.find("(60000 tetrahedra, 12221 nodes), more than the memory budget of 1 MiB "
                        "(limits.memory_mb = 1)"),
            std::string::npos)
      << e.what;
  EXPECT_EQ(build_error(parse_scene(with_limit(big, "64"), "scene.json", "")).line, -1);  // builds
  EXPECT_EQ(incise::test::scene_parse_error(with_limit(kScene, "0")),
            "scene.json:2: /limits/memory_mb: expected an integer in [1, 2147483647], got 0");
  // The issue's 1000^3 box against the default budget (half the physical memory: smaller on any
  // machine with less than 2.4 TB): 6e9 cells × 184 B (4 indices, element reference and cell of
  // the problem) + 1.003e9 nodes × 99 B (coordinates, 3 DOFs × (load, mass, flag)) = 1.148e6 MiB.
  const BuildError d = build_error(parse_scene(
      edited("\"nx\": 2, \"ny\": 1, \"nz\": 1", "\"nx\": 1000, \"ny\": 1000, \"nz\": 1000"),
      "scene.json", ""));
  EXPECT_NE(d.what.find("/mesh: the mesh and its elastic problem need an estimated 1.148e+06 MiB "
                        "(6000000000 tetrahedra, 1003003001 nodes), more than the memory budget "
                        "of "),
            std::string::npos)
      << d.what;
  EXPECT_NE(d.what.find("(by default half the physical memory; set \"limits\": {\"memory_mb\": "
                        "N} or incise run --memory-mb N)"),
            std::string::npos)
      << d.what;
}

TEST(SceneErrorLines, ProbeNameOutsideTheCsvAlphabetNamesItsLine) {
  // docs/scenes.md, outputs: probe names become CSV column names.
  const std::string text = with_probe("{\"name\": \"tip probe\", \"at\": [1.2, 0.2, 0.3]}");
  EXPECT_EQ(incise::test::scene_parse_error(text).rfind(
                "scene.json:19: /outputs/probes/0/name: expected a name of "
                "letters, digits, '_', '.', '-', got string \"tip probe\"",
                0),
            0u)
      << incise::test::scene_parse_error(text);
}

TEST(SceneErrorLines, ProbeOutsideTheMeshNamesTheLineOfItsLocation) {
  const std::string text = with_probe("{\"name\": \"far\",\n     \"at\": [5, 0, 0]}");
  const BuildError e = build_error(parse_scene(text, "scene.json", ""));
  EXPECT_EQ(e.line, 20);
  EXPECT_EQ(e.what.rfind("scene.json:20: /outputs/probes/0/at: probe location", 0), 0u) << e.what;
}

TEST(SceneErrorLines, SpecMadeInCodeHasNoLine) {
  auto spec = parse_scene(kScene, "scene.json", "");
  spec.lines = {};
  spec.fixed[1].value = 5.0;
  const BuildError e = build_error(spec);
  EXPECT_EQ(e.line, 0);
  EXPECT_EQ(e.what.rfind("scene.json: /fixed/1: region selects no node", 0), 0u) << e.what;
}

}  // namespace
