// Hostile scene texts (issue 18): nesting deeper than kMaxSceneDepth and texts longer than
// kMaxSceneBytes are refused before the JSON parser recurses or the text is kept, with the file
// and the line; numbers beyond the doubles and duplicate keys name their line and JSON path; the
// line index stays linear in the text size. Inputs are the issue's (nesting 1e4, 3e4 and 1e5
// deep); the tests assert the errors only (no clock, no memory probe): before the limits the 1e5
// case crashed and the others took 0.2 and 1.8 GB.

#include <incise/core/error.hpp>
#include <incise/scene/line_index.hpp>
#include <incise/scene/scene_parser.hpp>

#include <gtest/gtest.h>

#include <incise_test/scene_errors.hpp>
#include "incise_test/seed.hpp"

#include <cstdio>
#include <fstream>
#include <string>

#include <unistd.h>

namespace {

using incise::ParseError;
using incise::scene::kMaxSceneBytes;
using incise::scene::kMaxSceneDepth;
using incise::scene::LineIndex;
using incise::scene::parse_scene;

std::string nested_arrays(std::size_t depth, const std::string& sep = "") {
  std::string s;
  for (std::size_t i = 0; i < depth; ++i) s += "[" + sep;
  for (std::size_t i = 0; i < depth; ++i) s += "]";
  return s;
}

TEST(SceneLimits, NestingOfTheIssueIsRefusedAtTheFirstLevelBeyondTheLimit) {
  const std::string expected =
      "scene.json:1: arrays and objects nested deeper than 64 levels (a scene needs at most 6";
  for (std::size_t depth : {10000u, 30000u, 100000u}) {
    EXPECT_EQ(incise::test::scene_parse_error(nested_arrays(depth)).rfind(expected, 0), 0u)
        << depth;
    // Nested objects inside a valid key.
    std::string s = "{\"version\": 1, \"description\": ";
    for (std::size_t i = 0; i < depth; ++i) s += "{\"a\":";
    s += "0";
    for (std::size_t i = 0; i < depth; ++i) s += "}";
    EXPECT_EQ(incise::test::scene_parse_error(s + "}").rfind(expected, 0), 0u) << depth;
  }
}

TEST(SceneLimits, TheDepthLimitCountsBracketsOutsideStringsAndNamesTheLine) {
  // One bracket per line: level 65 opens on line 65.
  const std::string deep = nested_arrays(kMaxSceneDepth + 1, "\n");
  EXPECT_EQ(incise::test::scene_parse_error(deep).rfind(
                "scene.json:65: arrays and objects nested deeper", 0),
            0u)
      << incise::test::scene_parse_error(deep);
  // 64 levels pass the limit (and fail later: the root is no object).
  EXPECT_EQ(incise::test::scene_parse_error(nested_arrays(kMaxSceneDepth))
                .rfind("scene.json:1: /: expected a scene", 0),
            0u);
  // Brackets inside strings, also after an escaped quote, are text: the scene gets as far as
  // its first missing key.
  const std::string in_string = "{\"name\": \"\\\"" + std::string(1000, '[') + "\"}";
  EXPECT_EQ(incise::test::scene_parse_error(in_string).rfind(
                "scene.json:1: /: missing required key \"mesh\"", 0),
            0u)
      << incise::test::scene_parse_error(in_string);
}

TEST(SceneLimits, OversizedTextAndFileAreRefusedWithTheLimit) {
  // A valid JSON object padded with spaces to one byte over the limit.
  const std::string big = "{" + std::string(kMaxSceneBytes - 1, ' ') + "}";
  const std::string e = incise::test::scene_parse_error(big);
  EXPECT_EQ(
      e.rfind("scene.json: scene text of 16777217 bytes is larger than the limit of 16 MiB", 0), 0u)
      << e.substr(0, 200);
  const std::string path =
      ::testing::TempDir() + "incise_big_scene_" + std::to_string(::getpid()) + ".json";
  {
    std::ofstream out(path, std::ios::binary);
    out << big;
  }
  try {
    (void)incise::scene::load_scene(path);
    ADD_FAILURE() << "accepted";
  } catch (const ParseError& err) {
    EXPECT_EQ(err.message().rfind("scene file is larger than the limit of 16 MiB", 0), 0u)
        << err.what();
  }
  std::remove(path.c_str());
  // An endless file is read no further than the limit; a directory opens but cannot be read.
  EXPECT_THROW((void)incise::scene::load_scene("/dev/zero"), ParseError);
  try {
    (void)incise::scene::load_scene(::testing::TempDir());
    ADD_FAILURE() << "accepted a directory";
  } catch (const ParseError& err) {
    EXPECT_EQ(err.message(), "error while reading scene file");
  }
}

TEST(SceneLimits, NumberBeyondTheDoublesNamesItsLineAndPath) {
  const std::string text =
      "{\"version\": 1,\n \"mesh\": {\"type\": \"box\",\n  \"lx\": 1e400}}";  // issue input
  EXPECT_EQ(incise::test::scene_parse_error(text),
            "scene.json:3: /mesh/lx: number 1e400 is out of range: expected a finite number "
            "(magnitude below 1.8e308)");
  EXPECT_EQ(incise::test::scene_parse_error("{\"loads\": [0,\n -1e999]}"),
            "scene.json:2: /loads/1: number -1e999 is out of range: expected a finite number "
            "(magnitude below 1.8e308)");
  // Beyond the doubles as an integer, too; an underflow is a finite 0 (then out of range).
  EXPECT_EQ(incise::test::scene_parse_error("[" + std::string(400, '9') + "]")
                .rfind("scene.json:1: /0: number 999", 0),
            0u);
  EXPECT_NE(incise::test::scene_parse_error(
                R"({"mesh": {"type": "box", "nx": 1, "ny": 1, "nz": 1, "lx": 1e-400}})")
                .find("/mesh/lx: expected a number > 0, got 0"),
            std::string::npos);
}

TEST(SceneLimits, DuplicateKeyNamesTheLineOfTheRepeat) {
  EXPECT_EQ(incise::test::scene_parse_error("{\"version\": 1,\n\n \"version\": 1}"),
            "scene.json:3: /version: duplicate key \"version\" (each key may appear once per "
            "object)");
  EXPECT_EQ(incise::test::scene_parse_error("{\"fixed\": [{},\n {\"a/b\": 1,\n  \"a/b\": 2}]}"),
            "scene.json:3: /fixed/1/a~1b: duplicate key \"a/b\" (each key may appear once per "
            "object)");
}

// Fuzzer finding (fuzz_scene): nlohmann takes a NUL byte for the end of the text and dropped
// the rest; the line index then met a second root value and failed a UsageError check. The
// crash input is kept in property_tests/scene/data/.
TEST(SceneLimits, NulByteIsRefusedWithItsLineAndColumn) {
  EXPECT_EQ(incise::test::scene_parse_error(std::string("{\"version\": 1}\n  \0{\"mesh\": 1}", 28)),
            "scene.json:2: invalid JSON at column 3: NUL byte (expected JSON text)");
  const std::string crash =
      incise::test::source_path("property_tests/scene/data/fuzz_crash_nul_after_root.json");
  try {
    (void)incise::scene::load_scene(crash);
    ADD_FAILURE() << "accepted";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(e.message(), "invalid JSON at column 86: NUL byte (expected JSON text)");
  }
}

TEST(SceneLimits, LineIndexIsLinearInTheTextSize) {
  // 60 levels of objects under 100 KB keys (6 MB of keys), then 10^6 array elements: an index
  // holding each value's JSON pointer would need 10^6 × 6 MB; the tree index holds the keys once.
  const std::string key(100000, 'k');
  std::string s;
  for (int i = 0; i < 60; ++i) s += "{\"" + key + "\":\n";
  s += "[";
  for (int i = 0; i < 1000000; ++i) s += i ? ",0" : "0";
  s += "]";
  for (int i = 0; i < 60; ++i) s += "}";
  ASSERT_LT(s.size(), kMaxSceneBytes);
  const std::string e =
      incise::test::scene_parse_error(s);  // parsed and indexed; then the scene lacks its keys
  EXPECT_EQ(e.rfind("scene.json:1: /: missing required key \"mesh\"", 0), 0u) << e.substr(0, 100);
}

TEST(SceneLimits, LineIndexFindsValuesAndFallsBackToTheNearestAncestor) {
  LineIndex lines;
  EXPECT_EQ(lines.line("/a"), 0);  // empty index
  const std::string a = "a", slash = "b/~c";
  const LineIndex::Id root = lines.add(LineIndex::kNone, 1);
  const LineIndex::Id arr = lines.add(root, 2, &a);
  lines.add(arr, 3);
  const LineIndex::Id obj = lines.add(arr, 4);
  lines.add(obj, 5, &slash);
  EXPECT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines.line(""), 1);
  EXPECT_EQ(lines.line("/a"), 2);
  EXPECT_EQ(lines.line("/a/0"), 3);
  EXPECT_EQ(lines.line("/a/1/b~1~0c"), 5);  // RFC 6901 escapes
  EXPECT_FALSE(lines.contains("/a/01"));    // no leading zeros
  EXPECT_FALSE(lines.contains("/a/2"));
  EXPECT_EQ(lines.line("/a/2/x"), 2);  // nearest ancestor
  EXPECT_EQ(lines.line("/zzz"), 1);
  EXPECT_EQ(lines.find("/a/1"), obj);
}

}  // namespace
