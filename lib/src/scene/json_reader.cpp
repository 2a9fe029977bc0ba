#include "json_reader.hpp"

#include <algorithm>
#include <cmath>
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

// Tracks the JSON pointer of the value being parsed, to name duplicate keys.
struct Frame {
  bool is_array = false;
  long index = -1;
  std::string key;
  std::set<std::string> keys;
};

std::string frames_path(const std::vector<Frame>& st, std::size_t upto) {
  std::string p;
  for (std::size_t i = 0; i < upto; ++i) {
    p += st[i].is_array ? child_path("", static_cast<std::size_t>(st[i].index))
                        : child_path("", st[i].key);
  }
  return p;
}

}  // namespace

Json parse_strict(const std::string& text, const std::string& file) {
  std::vector<Frame> st;
  auto element_started = [&st]() {
    if (!st.empty() && st.back().is_array) ++st.back().index;
  };
  Json::parser_callback_t cb = [&](int, Json::parse_event_t ev, Json& parsed) -> bool {
    switch (ev) {
      case Json::parse_event_t::object_start:
        element_started();
        st.push_back(Frame{});
        break;
      case Json::parse_event_t::array_start:
        element_started();
        st.push_back(Frame{true, -1, {}, {}});
        break;
      case Json::parse_event_t::object_end:
      case Json::parse_event_t::array_end:
        if (!st.empty()) st.pop_back();
        break;
      case Json::parse_event_t::key: {
        const std::string k = parsed.get<std::string>();
        if (!st.back().keys.insert(k).second)
          fail(file, frames_path(st, st.size() - 1) + child_path("", k),
               "duplicate key \"" + k + "\" (each key may appear once per object)");
        st.back().key = k;
        break;
      }
      case Json::parse_event_t::value: element_started(); break;
    }
    return true;
  };
  try {
    return Json::parse(text, cb, /*allow_exceptions=*/true, /*ignore_comments=*/false);
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
  }
}

std::map<std::string, long> value_lines(const std::string& text) {
  struct Level {
    bool is_array;
    std::string path;
    std::size_t count = 0;  // elements begun (arrays)
    bool want_key = true;   // objects: the next string is a key
    std::string key;        // objects: the current member's key
    long key_line = 0;      // objects: the line of that key
  };
  std::map<std::string, long> lines;
  std::vector<Level> st;
  long line = 1;
  // A value begins at the current position: record its pointer and line.
  auto begin_value = [&]() -> std::string {
    if (st.empty()) {
      lines.emplace("", line);
      return "";
    }
    Level& l = st.back();
    const std::string p = l.is_array ? child_path(l.path, l.count++) : child_path(l.path, l.key);
    lines.emplace(p, l.is_array ? line : l.key_line);
    return p;
  };
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
    } else if (c == '{' || c == '[') {
      const std::string p = begin_value();
      st.push_back(Level{c == '[', p, 0, true, {}, 0});
    } else if (c == '}' || c == ']') {
      if (!st.empty()) st.pop_back();
    } else if (c == ',') {
      if (!st.empty() && !st.back().is_array) st.back().want_key = true;
    } else if (c == '"') {
      std::size_t end = i + 1;  // the closing quote (no raw newline can occur in a string)
      while (end < text.size() && text[end] != '"') end += text[end] == '\\' ? 2 : 1;
      if (!st.empty() && !st.back().is_array && st.back().want_key) {
        st.back().key = Json::parse(text.substr(i, end - i + 1)).get<std::string>();
        st.back().key_line = line;
        st.back().want_key = false;
      } else {
        begin_value();
      }
      i = end;
    } else if (c == '-' || (c >= '0' && c <= '9') || c == 't' || c == 'f' || c == 'n') {
      begin_value();  // number or literal: skip to its end
      while (i + 1 < text.size() &&
             std::string(",]} \t\r\n").find(text[i + 1]) == std::string::npos)
        ++i;
    }
  }
  return lines;
}

long line_of(const std::map<std::string, long>& lines, const std::string& path) {
  std::string p = path;
  while (true) {
    const auto it = lines.find(p);
    if (it != lines.end()) return it->second;
    if (p.empty()) return 0;
    p.erase(p.rfind('/') == std::string::npos ? 0 : p.rfind('/'));
  }
}

ParseError with_line(const ParseError& e, const std::string& file,
                     const std::map<std::string, long>& lines) {
  if (e.line() > 0 || e.file() != file || e.message().empty() || e.message()[0] != '/') return e;
  // The path is the longest prefix followed by ": " that names a value (a key may hold ": ").
  const std::string& m = e.message();
  std::string path;
  for (std::size_t at = m.find(": "); at != std::string::npos; at = m.find(": ", at + 1)) {
    const std::string candidate = m.substr(0, at);
    if (path.empty() || lines.count(candidate)) path = candidate;
  }
  const std::string key = path == "/" ? "" : path;  // fail() writes the root as "/"
  return ParseError(file, line_of(lines, key), m);
}

}  // namespace incise::scene::detail
