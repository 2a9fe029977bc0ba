#pragma once
// Strict, path-aware access to a JSON object (private to the scene module).
//
// JsonObject wraps one object at a JSON pointer path. Every accessor marks its key as known;
// finish() rejects any key that was never asked for, listing the known keys and suggesting the
// closest one. Every failure throws incise::ParseError("<file>", 0, "<path>: <message>").

#include <incise/core/error.hpp>
#include <incise/core/name_table.hpp>
#include <incise/core/types.hpp>
#include <incise/scene/line_index.hpp>

#include <nlohmann/json.hpp>

#include <optional>
#include <set>
#include <string>
#include <vector>

namespace incise::scene::detail {

using Json = nlohmann::json;

/// Admissible interval of a number; open or closed at either end, infinite when unbounded.
struct Range {
  double lo;
  double hi;
  bool lo_open;
  bool hi_open;
  bool contains(double v) const;
  std::string describe() const;  ///< "a number in (-1, 0.5)", "a number > 0", ...
};

Range positive();      ///< (0, ∞)
Range non_negative();  ///< [0, ∞)
Range any_finite();    ///< (−∞, ∞)

/// Short rendering of a JSON value for messages (strings quoted, long values cut).
std::string show(const Json& j);

/// JSON pointer path of key/index below `parent` ("" is the root).
std::string child_path(const std::string& parent, const std::string& key);
std::string child_path(const std::string& parent, std::size_t index);

/// Throws ParseError(file, 0, path + ": " + message).
[[noreturn]] void fail(const std::string& file, const std::string& path, const std::string& msg);

/// Throws "<path>: expected <expected>, got <shown value>".
[[noreturn]] void fail_expected(const std::string& file, const std::string& path,
                                const std::string& expected, const Json& got);

class JsonObject {
 public:
  /// Throws unless `j` is an object. `what` describes the expected object in messages.
  JsonObject(const Json& j, std::string path, std::string file, const std::string& what);

  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  bool has(const std::string& key) const;
  /// Marks key as known and returns it, or nullptr when absent.
  const Json* get(const std::string& key);
  /// Like get() but throws "missing required key" with the expected form.
  const Json& require(const std::string& key, const std::string& expected);

  double number(const std::string& key, const Range& r);
  double number(const std::string& key, const Range& r, double fallback);
  int integer(const std::string& key, int lo, int hi);
  int integer(const std::string& key, int lo, int hi, int fallback);
  bool boolean(const std::string& key, bool fallback);
  std::string string(const std::string& key);
  std::string string(const std::string& key, const std::string& fallback);
  /// A string from a fixed list of choices.
  std::string choice(const std::string& key, const std::vector<std::string>& choices);
  std::string choice(const std::string& key, const std::vector<std::string>& choices,
                     const std::string& fallback);
  /// A name from `table`, as its enum value.
  template <class Enum, std::size_t N>
  Enum choice(const std::string& key, const NameTable<Enum, N>& table) {
    return *table.find(choice(key, table.names()));
  }
  template <class Enum, std::size_t N>
  Enum choice(const std::string& key, const NameTable<Enum, N>& table, Enum fallback) {
    return has(key) ? choice(key, table) : (known_.insert(key), fallback);
  }
  Vec3 vec3(const std::string& key);
  Vec3 vec3(const std::string& key, const Vec3& fallback);
  /// A nested object (required).
  JsonObject object(const std::string& key, const std::string& what);
  /// An array (required unless `optional`); returns nullptr when optional and absent.
  const Json* array(const std::string& key, const std::string& what, bool optional);

  /// Rejects a key present but not allowed in this context, with the reason.
  void forbid(const std::string& key, const std::string& reason);

  /// Throws for the first key that no accessor asked for.
  void finish() const;

 private:
  const Json& j_;
  std::string path_;
  std::string file_;
  std::set<std::string> known_;
  std::set<std::string> forbidden_;  ///< known but not allowed in this context
};

/// Value-level checks for elements of arrays.
double as_number(const Json& j, const std::string& file, const std::string& path, const Range& r);
Vec3 as_vec3(const Json& j, const std::string& file, const std::string& path);
Vec2 as_vec2(const Json& j, const std::string& file, const std::string& path);  ///< [x, y]

/// A JSON text parsed by parse_strict: its value and the line of each of its values.
struct ParsedJson {
  Json value;
  LineIndex lines;
};

/// Parses a scene's JSON text strictly, in memory linear in its size and stack bounded by
/// kMaxSceneDepth (scene_parser.hpp). Refused with ParseError(file, line, ...): a text longer
/// than kMaxSceneBytes; arrays and objects nested deeper than kMaxSceneDepth (found by a scan of
/// the brackets outside strings before the JSON parser recurses); syntax errors (with column);
/// duplicate keys (at the repeated key, with its JSON path); numbers beyond the finite doubles
/// (at the number, with its path).
ParsedJson parse_strict(const std::string& text, const std::string& file);

/// The text of the scene file `path`, read no further than kMaxSceneBytes + 1 bytes (the file
/// may be a pipe, or endless like /dev/zero). Throws ParseError(path, 0, ...) when it cannot be
/// opened or read, or is larger than kMaxSceneBytes ("scene file is larger than the limit of
/// 16 MiB (...)"). Shared by load_scene and load_delaunay_scene.
std::string read_scene_file(const std::string& path);

/// `e` with the line of the JSON path its message starts with ("<path>: ...", as fail() writes
/// it) when `e` names `file` without a line; otherwise `e` unchanged.
ParseError with_line(const ParseError& e, const std::string& file, const LineIndex& lines);

}  // namespace incise::scene::detail
