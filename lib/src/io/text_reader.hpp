#pragma once
// Private to the io module: a whitespace-token scanner over a whole file held in memory, that
// knows the line of every token and turns every malformed token into a ParseError naming the
// file, the line and what was expected; and RawMesh, what format readers collect before the
// common checks of finalize().

#include <incise/core/error.hpp>
#include <incise/io/read_mesh.hpp>

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace incise::io::detail {

/// Token scanner. `comment` (e.g. '#') starts a comment running to the end of the line; '\0'
/// disables comments.
class TextReader {
 public:
  TextReader(std::string file, std::string text, char comment);

  /// Reads a whole file; throws ParseError(path, 0, "cannot open file") when unreadable.
  static TextReader open(const std::string& path, char comment);

  const std::string& file() const { return file_; }
  /// Line of the most recently read token (1-based).
  long line() const { return token_line_; }
  /// Size of the text in bytes.
  std::size_t size() const { return text_.size(); }

  /// True when only whitespace and comments remain.
  bool at_end();
  /// Next token; at end of file throws "unexpected end of file: expected <what>".
  std::string_view token(const char* what);
  /// Next token without consuming it; empty at end of file.
  std::string_view peek();
  /// Next token parsed as a finite double ("expected <what>" on failure, NaN/inf rejected).
  double real(const char* what);
  /// Next token parsed as an integer in [lo, hi].
  long long integer(const char* what, long long lo = -(1LL << 62), long long hi = (1LL << 62));
  /// Skips blanks; the next character must be a newline, a comment or the end of file.
  void end_of_line(const char* after);
  /// Skips the rest of the current line (after the last token).
  void skip_line();
  /// The rest of the current line, trimmed, consumed.
  std::string rest_of_line();
  /// Expects the exact keyword `word` as next token.
  void expect(const char* word);

  /// Throws ParseError at the line of the last token.
  [[noreturn]] void fail(const std::string& message) const;

 private:
  void skip_space();
  std::string file_;
  std::string text_;
  char comment_;
  std::size_t pos_ = 0;
  long line_ = 1;        // line at pos_
  long token_line_ = 1;  // line of the last token
};

/// Bounded reserve size for a count read from a file (never trust it for allocation).
std::size_t bounded_reserve(long long count, std::size_t text_size);

/// Cells and points as collected by a format reader (0-based indices, already range checked).
struct RawMesh {
  std::string format;
  std::vector<double> xyz;        // 3 per point
  std::vector<long> point_lines;  // source line per point
  std::vector<int> point_tags;    // empty when the format has none
  std::vector<Index> tets;        // 4 per tetrahedron
  std::vector<int> tet_tags;      // empty when none
  std::vector<long> tet_lines;    // source line per tetrahedron
  std::vector<Index> tris;        // 3 per triangle
  std::vector<int> tri_tags;      // empty when none
  std::vector<long> tri_lines;    // source line per triangle
  Index ignored = 0;              // skipped lower-dimensional records
  std::vector<std::string> ignored_notes;
  std::map<int, std::string> physical_names;
};

/// Common checks and conversion to MeshData (see read_mesh.hpp): repeated vertices in a cell,
/// duplicate vertices (reported or merged), duplicate cells, degenerate and inverted cells
/// (reoriented when asked), unused vertices, labels.
LoadedMesh finalize(RawMesh&& raw, const std::string& file, const ReadOptions& options);

}  // namespace incise::io::detail
