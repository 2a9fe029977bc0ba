#include "json_reader.hpp"

#include <incise/scene/scene_parser.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>

namespace incise::scene::detail {

namespace {

std::string fmt(double v) {
  std::ostringstream os;
  os.precision(12);
  os << v;
  return os.str();
}

// Levenshtein distance, for "did you mean" suggestions.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::size_t> prev(b.size() + 1), cur(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) prev[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    cur[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t sub =
          prev[j - 1] + (std::tolower(static_cast<unsigned char>(a[i - 1])) ==
                                 std::tolower(static_cast<unsigned char>(b[j - 1]))
                             ? 0
                             : 1);
      cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
    }
    std::swap(prev, cur);
  }
  return prev[b.size()];
}

std::string escape_pointer_token(const std::string& key) {
  std::string out;
  for (char c : key) {
    if (c == '~')
      out += "~0";
    else if (c == '/')
      out += "~1";
    else
      out += c;
  }
  return out;
}

}  // namespace

bool Range::contains(double v) const {
  if (!std::isfinite(v)) return false;
  if (lo_open ? !(v > lo) : !(v >= lo)) return false;
  if (hi_open ? !(v < hi) : !(v <= hi)) return false;
  return true;
}

std::string Range::describe() const {
  const double inf = std::numeric_limits<double>::infinity();
  if (lo == -inf && hi == inf) return "a finite number";
  if (hi == inf) return std::string("a number ") + (lo_open ? "> " : ">= ") + fmt(lo);
  if (lo == -inf) return std::string("a number ") + (hi_open ? "< " : "<= ") + fmt(hi);
  return std::string("a number in ") + (lo_open ? "(" : "[") + fmt(lo) + ", " + fmt(hi) +
         (hi_open ? ")" : "]");
}

Range positive() {
  return {0.0, std::numeric_limits<double>::infinity(), true, true};
}
Range non_negative() {
  return {0.0, std::numeric_limits<double>::infinity(), false, true};
}
Range any_finite() {
  const double inf = std::numeric_limits<double>::infinity();
  return {-inf, inf, true, true};
}

std::string show(const Json& j) {
  std::string s = j.dump();
  if (s.size() > 60) s = s.substr(0, 57) + "...";
  const char* type = j.is_string()    ? "string "
                     : j.is_object()  ? "object "
                     : j.is_array()   ? "array "
                     : j.is_boolean() ? "boolean "
                     : j.is_null()    ? ""
                                      : "";
  return type + s;
}

std::string child_path(const std::string& parent, const std::string& key) {
  return parent + "/" + escape_pointer_token(key);
}
std::string child_path(const std::string& parent, std::size_t index) {
  return parent + "/" + std::to_string(index);
}

void fail(const std::string& file, const std::string& path, const std::string& msg) {
  throw ParseError(file, 0, (path.empty() ? std::string("/") : path) + ": " + msg);
}

void fail_expected(const std::string& file, const std::string& path, const std::string& expected,
                   const Json& got) {
  fail(file, path, "expected " + expected + ", got " + show(got));
}

JsonObject::JsonObject(const Json& j, std::string path, std::string file, const std::string& what)
    : j_(j), path_(std::move(path)), file_(std::move(file)) {
  if (!j_.is_object()) fail_expected(file_, path_, what, j_);
}

bool JsonObject::has(const std::string& key) const {
  return j_.contains(key);
}

const Json* JsonObject::get(const std::string& key) {
  known_.insert(key);
  auto it = j_.find(key);
  return it == j_.end() ? nullptr : &*it;
}

const Json& JsonObject::require(const std::string& key, const std::string& expected) {
  const Json* v = get(key);
  if (!v) fail(file_, path_, "missing required key \"" + key + "\" (expected " + expected + ")");
  return *v;
}

double as_number(const Json& j, const std::string& file, const std::string& path, const Range& r) {
  if (!j.is_number() || !r.contains(j.get<double>())) fail_expected(file, path, r.describe(), j);
  return j.get<double>();
}

Vec3 as_vec3(const Json& j, const std::string& file, const std::string& path) {
  const std::string form = "an array of 3 finite numbers [x, y, z]";
  if (!j.is_array() || j.size() != 3) fail_expected(file, path, form, j);
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    if (!j[i].is_number() || !std::isfinite(j[i].get<double>()))
      fail_expected(file, child_path(path, static_cast<std::size_t>(i)), "a finite number", j[i]);
    v[i] = j[i].get<double>();
  }
  return v;
}

Vec2 as_vec2(const Json& j, const std::string& file, const std::string& path) {
  const std::string form = "an array of 2 finite numbers [x, y]";
  if (!j.is_array() || j.size() != 2) fail_expected(file, path, form, j);
  Vec2 v;
  for (int i = 0; i < 2; ++i) {
    if (!j[i].is_number() || !std::isfinite(j[i].get<double>()))
      fail_expected(file, child_path(path, static_cast<std::size_t>(i)), "a finite number", j[i]);
    v[i] = j[i].get<double>();
  }
  return v;
}

double JsonObject::number(const std::string& key, const Range& r) {
  return as_number(require(key, r.describe()), file_, child_path(path_, key), r);
}

double JsonObject::number(const std::string& key, const Range& r, double fallback) {
  const Json* v = get(key);
  return v ? as_number(*v, file_, child_path(path_, key), r) : fallback;
}

int JsonObject::integer(const std::string& key, int lo, int hi) {
  const std::string form = "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  const Json& v = require(key, form);
  if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi)
    fail_expected(file_, child_path(path_, key), form, v);
  return static_cast<int>(v.get<long long>());
}

int JsonObject::integer(const std::string& key, int lo, int hi, int fallback) {
  return has(key) ? integer(key, lo, hi) : (known_.insert(key), fallback);
}

bool JsonObject::boolean(const std::string& key, bool fallback) {
  const Json* v = get(key);
  if (!v) return fallback;
  if (!v->is_boolean()) fail_expected(file_, child_path(path_, key), "true or false", *v);
  return v->get<bool>();
}

std::string JsonObject::string(const std::string& key) {
  const Json& v = require(key, "a string");
  if (!v.is_string()) fail_expected(file_, child_path(path_, key), "a string", v);
  return v.get<std::string>();
}

std::string JsonObject::string(const std::string& key, const std::string& fallback) {
  return has(key) ? string(key) : (known_.insert(key), fallback);
}

std::string JsonObject::choice(const std::string& key, const std::vector<std::string>& choices) {
  const std::string form = one_of(choices);
  const Json& v = require(key, form);
  if (!v.is_string() ||
      std::find(choices.begin(), choices.end(), v.get<std::string>()) == choices.end())
    fail_expected(file_, child_path(path_, key), form, v);
  return v.get<std::string>();
}

std::string JsonObject::choice(const std::string& key, const std::vector<std::string>& choices,
                               const std::string& fallback) {
  return has(key) ? choice(key, choices) : (known_.insert(key), fallback);
}

Vec3 JsonObject::vec3(const std::string& key) {
  return as_vec3(require(key, "an array of 3 finite numbers [x, y, z]"), file_,
                 child_path(path_, key));
}

Vec3 JsonObject::vec3(const std::string& key, const Vec3& fallback) {
  return has(key) ? vec3(key) : (known_.insert(key), fallback);
}

JsonObject JsonObject::object(const std::string& key, const std::string& what) {
  return JsonObject(require(key, what), child_path(path_, key), file_, what);
}

const Json* JsonObject::array(const std::string& key, const std::string& what, bool optional) {
  const Json* v = optional ? get(key) : &require(key, what);
  if (v && !v->is_array()) fail_expected(file_, child_path(path_, key), what, *v);
  return v;
}

void JsonObject::forbid(const std::string& key, const std::string& reason) {
  forbidden_.insert(key);
  if (has(key)) fail(file_, child_path(path_, key), "not allowed here: " + reason);
}

void JsonObject::finish() const {
  for (auto it = j_.begin(); it != j_.end(); ++it) {
    if (known_.count(it.key()) || forbidden_.count(it.key())) continue;
    std::string msg = "unknown key \"" + it.key() + "\"; allowed here: ";
    std::string best;
    std::size_t best_d = 3;  // suggest only close matches (≤ 2 edits)
    bool first = true;
    for (const auto& k : known_) {
      msg += (first ? "" : ", ") + k;
      first = false;
      const std::size_t d = edit_distance(it.key(), k);
      if (d < best_d) best_d = d, best = k;
    }
    if (!best.empty()) msg += " (did you mean \"" + best + "\"?)";
    fail(file_, child_path(path_, it.key()), msg);
  }
}

namespace {

std::string mib(std::size_t bytes) {
  std::ostringstream os;
  os.precision(3);
  os << static_cast<double>(bytes) / (1024.0 * 1024.0) << " MiB";
  return os.str();
}

// Refuses arrays and objects nested deeper than kMaxSceneDepth, at the line of the first
// bracket beyond it, counting the brackets outside strings only; and NUL bytes, which nlohmann
// takes for the end of the text (the rest would be dropped silently). Runs on any text, before
// the JSON parser has checked the syntax.
void prescan(const std::string& text, const std::string& file) {
  int depth = 0;
  long line = 1;
  std::size_t line_start = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') ++line, line_start = i + 1;
    if (c == '\0')
      throw ParseError(file, line,
                       "invalid JSON at column " + std::to_string(i - line_start + 1) +
                           ": NUL byte (expected JSON text)");
    if (in_string) {
      if (c == '\\' && i + 1 < text.size() && text[i + 1] != '\n')
        ++i;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > kMaxSceneDepth)
        throw ParseError(file, line,
                         "arrays and objects nested deeper than " + std::to_string(kMaxSceneDepth) +
                             " levels (a scene needs at most 6; docs/scenes.md, Limits)");
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
}

// One open array or object of the line-index scan.
struct Level {
  LineIndex::Id id = LineIndex::kNone;
  bool is_array = false;
  std::size_t count = 0;         // arrays: elements begun
  bool want_key = true;          // objects: the next string is a key
  std::string key;               // objects: the current member's key
  long key_line = 0;             // objects: the line of that key
  std::set<std::string> keys{};  // objects: the keys seen so far
};

// JSON pointer of the value the innermost level is at (its current element or member).
std::string current_path(const std::vector<Level>& st) {
  std::string p;
  for (const Level& l : st)
    p += l.is_array ? child_path("", l.count == 0 ? 0 : l.count - 1) : child_path("", l.key);
  return p;
}

// Builds the line index of `text` (valid JSON up to the first number nlohmann refused, if any)
// in one pass; refuses duplicate keys and numbers beyond the finite doubles at their line.
LineIndex index_lines(const std::string& text, const std::string& file) {
  LineIndex lines;
  std::vector<Level> st;
  long line = 1;
  // A value begins at the current position: add it to the index.
  auto begin_value = [&]() -> LineIndex::Id {
    if (st.empty()) return lines.empty() ? lines.add(LineIndex::kNone, line) : LineIndex::kNone;
    Level& l = st.back();
    if (l.is_array) {
      ++l.count;
      return lines.add(l.id, line);
    }
    return lines.add(l.id, l.key_line, &l.key);
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
    } else if (c == '{' || c == '[') {
      Level l;
      l.id = begin_value();
      l.is_array = c == '[';
      st.push_back(std::move(l));
    } else if (c == '}' || c == ']') {
      if (!st.empty()) st.pop_back();
      if (st.empty()) break;  // the end of the root value (nothing but blanks follows)
    } else if (c == ',') {
      if (!st.empty() && !st.back().is_array) st.back().want_key = true;
    } else if (c == '"') {
      std::size_t end = i + 1;  // the closing quote (no raw newline can occur in a string)
      while (end < text.size() && text[end] != '"') end += text[end] == '\\' ? 2 : 1;
      if (!st.empty() && !st.back().is_array && st.back().want_key) {
        Level& l = st.back();
        l.key = Json::parse(text.substr(i, end - i + 1)).get<std::string>();
        l.key_line = line;
        l.want_key = false;
        if (!l.keys.insert(l.key).second)
          throw ParseError(file, line,
                           current_path(st) + ": duplicate key \"" + l.key +
                               "\" (each key may appear once per object)");
      } else {
        begin_value();
      }
      i = end;
    } else if (c == '-' || (c >= '0' && c <= '9') || c == 't' || c == 'f' || c == 'n') {
      begin_value();  // number or literal: skip to its end
      const std::size_t start = i;
      while (i + 1 < text.size() &&
             std::string(",]} \t\r\n").find(text[i + 1]) == std::string::npos)
        ++i;
      if (c != 't' && c != 'f' && c != 'n') {
        const std::string number = text.substr(start, i + 1 - start);
        if (!std::isfinite(std::strtod(number.c_str(), nullptr))) {
          const std::string path = current_path(st);
          throw ParseError(file, line,
                           (path.empty() ? std::string("/") : path) + ": number " +
                               (number.size() > 40 ? number.substr(0, 37) + "..." : number) +
                               " is out of range: expected a finite number (magnitude below "
                               "1.8e308)");
        }
      }
    }
  }
  return lines;
}

}  // namespace

std::string read_scene_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ParseError(path, 0, "cannot open scene file");
  std::string text;
  char buf[1 << 16];
  while (text.size() <= kMaxSceneBytes && in.read(buf, sizeof buf).gcount() > 0)
    text.append(buf, static_cast<std::size_t>(in.gcount()));
  if (in.bad()) throw ParseError(path, 0, "error while reading scene file");
  if (text.size() > kMaxSceneBytes)
    throw ParseError(path, 0,
                     "scene file is larger than the limit of " + mib(kMaxSceneBytes) + " (" +
                         std::to_string(kMaxSceneBytes) + " bytes; docs/scenes.md, Limits)");
  return text;
}

ParsedJson parse_strict(const std::string& text, const std::string& file) {
  if (text.size() > kMaxSceneBytes)
    throw ParseError(file, 0,
                     "scene text of " + std::to_string(text.size()) +
                         " bytes is larger than the limit of " + mib(kMaxSceneBytes) + " (" +
                         std::to_string(kMaxSceneBytes) + " bytes; docs/scenes.md, Limits)");
  prescan(text, file);
  ParsedJson out;
  try {
    out.value = Json::parse(text, nullptr, /*allow_exceptions=*/true, /*ignore_comments=*/false);
  } catch (const Json::parse_error& e) {
    // Translate the byte offset into line and column.
    const std::size_t byte = std::min<std::size_t>(e.byte, text.size());
    long line = 1;
    std::size_t line_start = 0;
    for (std::size_t i = 0; i + 1 < byte; ++i) {
      if (text[i] == '\n') ++line, line_start = i + 1;
    }
    std::string what = e.what();
    const auto colon = what.find(": ", what.find("parse error"));
    if (colon != std::string::npos) what = what.substr(colon + 2);
    throw ParseError(file, line,
                     "invalid JSON at column " + std::to_string(byte - line_start) + ": " + what);
  } catch (const Json::out_of_range&) {
    // A number beyond the doubles (nlohmann error 406): the scan below names it and its line.
    (void)index_lines(text, file);
    throw ParseError(file, 0, "a number is out of range: expected finite numbers");
  }
  out.lines = index_lines(text, file);
  return out;
}

ParseError with_line(const ParseError& e, const std::string& file, const LineIndex& lines) {
  if (e.line() > 0 || e.file() != file || e.message().empty() || e.message()[0] != '/') return e;
  // The path is the longest prefix followed by ": " that names a value (a key may hold ": ").
  const std::string& m = e.message();
  std::string path;
  for (std::size_t at = m.find(": "); at != std::string::npos; at = m.find(": ", at + 1)) {
    const std::string candidate = m.substr(0, at);
    if (path.empty() || lines.contains(candidate)) path = candidate;
  }
  const std::string key = path == "/" ? "" : path;  // fail() writes the root as "/"
  return ParseError(file, lines.line(key), m);
}

}  // namespace incise::scene::detail
