#include "text_reader.hpp"

#include <incise/mesh/quality.hpp>
#include <incise/mesh/repair.hpp>
#include <incise/mesh/tet_faces.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

namespace incise::io::detail {

TextReader::TextReader(std::string file, std::string text, char comment)
    : file_(std::move(file)), text_(std::move(text)), comment_(comment) {}

TextReader TextReader::open(const std::string& path, char comment) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ParseError(path, 0, "cannot open file for reading");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw ParseError(path, 0, "read error");
  return TextReader(path, ss.str(), comment);
}

void TextReader::skip_space() {
  const std::size_t n = text_.size();
  while (pos_ < n) {
    const char c = text_[pos_];
    if (c == '\n') {
      ++line_;
      ++pos_;
    } else if (c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v') {
      ++pos_;
    } else if (comment_ != '\0' && c == comment_) {
      while (pos_ < n && text_[pos_] != '\n') ++pos_;
    } else {
      return;
    }
  }
}

bool TextReader::at_end() {
  skip_space();
  return pos_ >= text_.size();
}

std::string_view TextReader::token(const char* what) {
  skip_space();
  if (pos_ >= text_.size())  // reported at the line of the last token read
    fail(std::string("unexpected end of file: expected ") + what);
  token_line_ = line_;
  const std::size_t start = pos_;
  const std::size_t n = text_.size();
  while (pos_ < n) {
    const char c = text_[pos_];
    if (c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v' ||
        (comment_ != '\0' && c == comment_))
      break;
    ++pos_;
  }
  return std::string_view(text_).substr(start, pos_ - start);
}

std::string_view TextReader::peek() {
  const std::size_t p = pos_;
  const long l = line_, tl = token_line_;
  std::string_view t;
  if (!at_end()) t = token("token");
  pos_ = p;
  line_ = l;
  token_line_ = tl;
  return t;
}

namespace {
std::string quoted(std::string_view t) {
  std::string s(t.substr(0, 40));
  if (t.size() > 40) s += "...";
  return "'" + s + "'";
}
}  // namespace

double TextReader::real(const char* what) {
  std::string_view t = token(what);
  std::string_view body = t;
  if (!body.empty() && body.front() == '+') body.remove_prefix(1);
  double v = 0;
  const auto [ptr, ec] = std::from_chars(body.data(), body.data() + body.size(), v);
  if (ec == std::errc::result_out_of_range)
    fail(std::string("number out of range: expected ") + what + ", got " + quoted(t));
  if (ec != std::errc() || ptr != body.data() + body.size() || body.empty())
    fail(std::string("bad number: expected ") + what + ", got " + quoted(t));
  if (!std::isfinite(v))
    fail(std::string("non-finite value: expected a finite ") + what + ", got " + quoted(t));
  return v;
}

long long TextReader::integer(const char* what, long long lo, long long hi) {
  std::string_view t = token(what);
  std::string_view body = t;
  if (!body.empty() && body.front() == '+') body.remove_prefix(1);
  long long v = 0;
  const auto [ptr, ec] = std::from_chars(body.data(), body.data() + body.size(), v);
  if (ec == std::errc::result_out_of_range)
    fail(std::string("integer out of range: expected ") + what + ", got " + quoted(t));
  if (ec != std::errc() || ptr != body.data() + body.size() || body.empty())
    fail(std::string("bad integer: expected ") + what + ", got " + quoted(t));
  if (v < lo || v > hi) {
    std::ostringstream os;
    os << "value out of range: expected " << what << " in [" << lo << ", " << hi << "], got " << v;
    fail(os.str());
  }
  return v;
}

void TextReader::end_of_line(const char* after) {
  const std::size_t n = text_.size();
  while (pos_ < n && (text_[pos_] == ' ' || text_[pos_] == '\t' || text_[pos_] == '\r')) ++pos_;
  if (pos_ >= n || text_[pos_] == '\n' || (comment_ != '\0' && text_[pos_] == comment_)) return;
  std::size_t e = pos_;
  while (e < n && text_[e] != '\n') ++e;
  fail(std::string("unexpected extra data: expected end of line after ") + after + ", got " +
       quoted(std::string_view(text_).substr(pos_, e - pos_)));
}

void TextReader::skip_line() {
  const std::size_t n = text_.size();
  while (pos_ < n && text_[pos_] != '\n') ++pos_;
}

std::string TextReader::rest_of_line() {
  const std::size_t n = text_.size();
  std::size_t e = pos_;
  while (e < n && text_[e] != '\n') ++e;
  std::string s = text_.substr(pos_, e - pos_);
  pos_ = e;
  const auto first = s.find_first_not_of(" \t\r");
  const auto last = s.find_last_not_of(" \t\r");
  return first == std::string::npos ? std::string() : s.substr(first, last - first + 1);
}

void TextReader::expect(const char* word) {
  const std::string_view t = token(word);
  if (t != word) fail(std::string("expected ") + word + ", got " + quoted(t));
}

void TextReader::fail(const std::string& message) const {
  throw ParseError(file_, token_line_, message);
}

std::size_t bounded_reserve(long long count, std::size_t text_size) {
  if (count <= 0) return 0;
  return static_cast<std::size_t>(
      std::min<long long>(count, static_cast<long long>(text_size / 2 + 1)));
}

namespace {

// Sorted vertex key of a cell (k ≤ 4 entries, unused entries −1).
using Key = std::array<Index, 4>;

Key sorted_key(const Index* v, int k) {
  Key key{-1, -1, -1, -1};
  for (int i = 0; i < k; ++i) key[i] = v[i];
  for (int i = 1; i < k; ++i)
    for (int j = i; j > 0 && key[j - 1] > key[j]; --j) std::swap(key[j - 1], key[j]);
  return key;
}

// "line 12" or "lines 12, 40, ..." (at most `max` numbers).
std::string line_list(const std::vector<long>& lines, std::size_t max) {
  std::ostringstream os;
  os << (lines.size() == 1 ? "line " : "lines ");
  for (std::size_t i = 0; i < lines.size() && i < max; ++i) os << (i ? ", " : "") << lines[i];
  if (lines.size() > max) os << ", ...";
  return os.str();
}

// Checks one family of cells (k vertices each): repeated vertex (error), duplicate cells (error
// when `duplicates` is null, else collected as (index of first, index of repeat)).
void check_cells(const std::string& file, const std::vector<Index>& v, int k,
                 const std::vector<long>& lines, const char* what,
                 std::vector<std::pair<std::size_t, std::size_t>>* duplicates) {
  const std::size_t n = lines.size();
  for (std::size_t c = 0; c < n; ++c) {
    const Key key = sorted_key(&v[c * k], k);
    for (int i = 1; i < k; ++i)
      if (key[i] == key[i - 1]) {
        std::ostringstream os;
        os << "degenerate " << what << ": vertex " << key[i] + 1 << " (1-based) repeated; expected "
           << k << " distinct vertices";
        throw ParseError(file, lines[c], os.str());
      }
  }
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::vector<Key> keys(n);
  for (std::size_t c = 0; c < n; ++c) keys[c] = sorted_key(&v[c * k], k);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return keys[a] != keys[b] ? keys[a] < keys[b] : a < b;
  });
  for (std::size_t i = 1; i < n; ++i)
    if (keys[order[i]] == keys[order[i - 1]]) {
      if (duplicates != nullptr) {
        duplicates->push_back({order[i - 1], order[i]});
        continue;
      }
      std::ostringstream os;
      os << "duplicate " << what << ": same vertices as the " << what << " at line "
         << lines[order[i - 1]] << "; expected each " << what << " once";
      throw ParseError(file, lines[order[i]], os.str());
    }
}

// Number of duplicate facet pairs whose orientations are opposite (even vs odd permutation).
Index count_opposite(const std::vector<Index>& tris,
                     const std::vector<std::pair<std::size_t, std::size_t>>& dups) {
  auto parity = [&](std::size_t f) {
    // Number of inversions of (a, b, c) modulo 2.
    const Index a = tris[3 * f], b = tris[3 * f + 1], c = tris[3 * f + 2];
    return ((a > b) + (a > c) + (b > c)) % 2;
  };
  Index n = 0;
  for (const auto& [f0, f1] : dups) n += parity(f0) != parity(f1) ? 1 : 0;
  return n;
}

void count_labels(const std::vector<int>& tags, std::map<int, Index>& out) {
  for (int t : tags) ++out[t];
}

// Face j (opposite vertex j) of cell c of `cells` (k = 4: kTetFace; k = 3: the edge
// (v_{j+1}, v_{j+2})): its sorted vertices (unused entries -1) and the parity of the sort.
// Two cells on opposite sides of a face give it opposite parities (thesis invariant 7.4).
struct OrientedFace {
  std::array<Index, 3> key;
  int parity;
  Index cell;
};

OrientedFace oriented_face(const mesh::CellMatrix& cells, Index c, int j) {
  const int k = static_cast<int>(cells.rows());
  std::array<Index, 3> v{-1, -1, -1};
  for (int r = 0; r < k - 1; ++r) v[r] = cells(k == 4 ? mesh::kTetFace[j][r] : (j + 1 + r) % 3, c);
  int parity = 0;  // of the bubble sort below: one swap per inversion
  for (int pass = 0; pass < k - 2; ++pass)
    for (int a = 0; a + 1 < k - 1 - pass; ++a)
      if (v[a] > v[a + 1]) std::swap(v[a], v[a + 1]), parity ^= 1;
  return {v, parity, c};
}

// Surfaces in 3D: flips triangles so that each edge shared by two triangles is traversed in
// opposite directions, orienting every connected part like its first triangle. Returns the
// flipped cells.
std::vector<Index> orient_surface(mesh::CellMatrix& tris) {
  const Index n = static_cast<Index>(tris.cols());
  std::vector<OrientedFace> edges;
  edges.reserve(3 * static_cast<std::size_t>(n));
  for (Index c = 0; c < n; ++c)
    for (int j = 0; j < 3; ++j) edges.push_back(oriented_face(tris, c, j));
  std::sort(edges.begin(), edges.end(),
            [](const OrientedFace& a, const OrientedFace& b) { return a.key < b.key; });
  // Neighbours across manifold edges (exactly two triangles), with "same direction" flags.
  std::vector<std::vector<std::pair<Index, int>>> next(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t e = i;
    while (e < edges.size() && edges[e].key == edges[i].key) ++e;
    if (e - i == 2 && edges[i].cell != edges[i + 1].cell) {
      const int same = edges[i].parity == edges[i + 1].parity ? 1 : 0;
      next[static_cast<std::size_t>(edges[i].cell)].push_back({edges[i + 1].cell, same});
      next[static_cast<std::size_t>(edges[i + 1].cell)].push_back({edges[i].cell, same});
    }
    i = e;
  }
  std::vector<int> state(static_cast<std::size_t>(n), -1);  // -1 unseen, 0 kept, 1 flipped
  std::vector<Index> flipped, queue;
  for (Index s = 0; s < n; ++s) {
    if (state[static_cast<std::size_t>(s)] >= 0) continue;
    state[static_cast<std::size_t>(s)] = 0;
    queue.assign(1, s);
    while (!queue.empty()) {
      const Index c = queue.back();
      queue.pop_back();
      for (const auto& [d, same] : next[static_cast<std::size_t>(c)]) {
        if (state[static_cast<std::size_t>(d)] >= 0) continue;
        // d must be flipped relative to its file orientation iff it then disagrees with c.
        state[static_cast<std::size_t>(d)] = state[static_cast<std::size_t>(c)] ^ same;
        queue.push_back(d);
      }
    }
  }
  for (Index c = 0; c < n; ++c)
    if (state[static_cast<std::size_t>(c)] == 1) {
      std::swap(tris(1, c), tris(2, c));
      flipped.push_back(c);
    }
  return flipped;
}

// Refuses a (d-1)-face shared by more than two cells and two cells on the same side of a face
// (the same oriented face twice: overlapping cells, or a surface whose neighbouring triangles
// disagree in orientation), naming the lines of the cells and of the face's vertices.
void check_faces(const std::string& file, const mesh::CellMatrix& cells,
                 const std::vector<long>& cell_lines, const std::vector<long>& point_lines,
                 bool surface, bool reoriented) {
  const int k = static_cast<int>(cells.rows());
  const char* what = k == 4 ? "tetrahedra" : "triangles";
  std::vector<OrientedFace> faces;
  faces.reserve(static_cast<std::size_t>(k) * static_cast<std::size_t>(cells.cols()));
  for (Index c = 0; c < cells.cols(); ++c)
    for (int j = 0; j < k; ++j) faces.push_back(oriented_face(cells, c, j));
  std::sort(faces.begin(), faces.end(), [](const OrientedFace& a, const OrientedFace& b) {
    return a.key != b.key ? a.key < b.key : a.cell < b.cell;
  });
  auto vertex_lines = [&](const std::array<Index, 3>& key) {
    std::ostringstream os;
    os << "vertices at lines " << point_lines[static_cast<std::size_t>(key[0])];
    for (int r = 1; r < k - 1; ++r) os << ", " << point_lines[static_cast<std::size_t>(key[r])];
    return os.str();
  };
  auto line = [&](Index c) { return cell_lines[static_cast<std::size_t>(c)]; };
  for (std::size_t i = 0; i < faces.size();) {
    std::size_t e = i;
    while (e < faces.size() && faces[e].key == faces[i].key) ++e;
    const OrientedFace& a = faces[i];
    std::ostringstream os;
    if (e - i > 2) {
      os << (k == 4 ? "face" : "edge") << " (" << vertex_lines(a.key) << ") shared by " << e - i
         << " " << what << " (lines " << line(a.cell) << ", " << line(faces[i + 1].cell) << ", "
         << line(faces[i + 2].cell) << (e - i > 3 ? ", ..." : "")
         << "): expected a manifold mesh, each " << (k == 4 ? "face" : "edge") << " in at most two "
         << what;
      throw ParseError(file, line(faces[i + 2].cell), os.str());
    }
    if (e - i == 2 && a.parity == faces[i + 1].parity) {
      const OrientedFace& b = faces[i + 1];
      os << what << " at lines " << line(a.cell) << " and " << line(b.cell);
      if (surface) {
        os << " traverse their common edge (" << vertex_lines(a.key) << ") in the same direction: "
           << (reoriented ? "the surface is not orientable"
                          : "the surface is not consistently oriented (the reorient option "
                            "orients each connected part like its first triangle)");
      } else {
        os << " lie on the same side of their common " << (k == 4 ? "face" : "edge") << " ("
           << vertex_lines(a.key) << "): they overlap; expected the two cells of a "
           << (k == 4 ? "face" : "edge") << " on opposite sides";
      }
      throw ParseError(file, line(b.cell), os.str());
    }
    i = e;
  }
}

}  // namespace

LoadedMesh finalize(RawMesh&& raw, const std::string& file, const ReadOptions& options) {
  LoadedMesh out;
  LoadReport& rep = out.report;
  rep.file = file;
  rep.format = raw.format;
  rep.physical_names = raw.physical_names;
  rep.ignored_elements = raw.ignored;
  for (const auto& s : raw.ignored_notes) rep.notes.push_back(s);

  const Index np = static_cast<Index>(raw.point_lines.size());
  INCISE_CHECK_PARAM(options.scale > 0 && std::isfinite(options.scale),
                     "ReadOptions::scale must be positive and finite");
  if (options.scale != 1.0)
    for (std::size_t i = 0; i < raw.xyz.size(); ++i) {
      const double x = raw.xyz[i];
      raw.xyz[i] *= options.scale;
      if (!std::isfinite(raw.xyz[i])) {
        std::ostringstream os;
        os << "coordinate " << x << " times the scale " << options.scale
           << " is not finite: expected coordinates within the doubles after scaling";
        throw ParseError(file, raw.point_lines[i / 3], os.str());
      }
    }
  const bool volume = !raw.tets.empty();
  if (!volume && raw.tris.empty())
    throw ParseError(file, 0, "no tetrahedra or triangles found: expected a simplicial mesh");

  // Duplicate vertices: bitwise-equal coordinates (sort by coordinates).
  std::vector<Index> remap(np);
  std::iota(remap.begin(), remap.end(), 0);
  {
    std::vector<Index> order(np);
    std::iota(order.begin(), order.end(), 0);
    auto xyz = [&](Index i) {
      return std::array<double, 3>{raw.xyz[3 * i], raw.xyz[3 * i + 1], raw.xyz[3 * i + 2]};
    };
    std::sort(order.begin(), order.end(), [&](Index a, Index b) {
      const auto pa = xyz(a), pb = xyz(b);
      return pa != pb ? pa < pb : a < b;
    });
    std::vector<long> dup_lines;
    for (Index i = 1; i < np; ++i)
      if (xyz(order[i]) == xyz(order[i - 1])) {
        remap[order[i]] = remap[order[i - 1]];
        ++rep.duplicate_vertices;
        dup_lines.push_back(raw.point_lines[order[i]]);
      }
    if (rep.duplicate_vertices > 0) {
      std::sort(dup_lines.begin(), dup_lines.end());
      std::ostringstream os;
      os << rep.duplicate_vertices << " vertices repeat the coordinates of an earlier vertex ("
         << line_list(dup_lines, 5) << ")"
         << (options.merge_duplicate_vertices ? "; merged" : "; kept (merge option off)");
      rep.notes.push_back(os.str());
    }
    if (options.merge_duplicate_vertices && rep.duplicate_vertices > 0) {
      for (Index& v : raw.tets) v = remap[v];
      for (Index& v : raw.tris) v = remap[v];
      rep.merged_vertices = rep.duplicate_vertices;
    }
  }

  if (volume) {
    check_cells(file, raw.tets, 4, raw.tet_lines, "tetrahedron", nullptr);
    std::vector<std::pair<std::size_t, std::size_t>> dups;
    check_cells(file, raw.tris, 3, raw.tri_lines, "facet", &dups);
    rep.duplicate_facets = static_cast<Index>(dups.size());
    if (!dups.empty()) {
      rep.opposite_facets = count_opposite(raw.tris, dups);
      std::ostringstream os;
      os << dups.size() << " boundary facets repeat an earlier facet's vertices ("
         << rep.opposite_facets << " with opposite orientation; e.g. line "
         << raw.tri_lines[dups.front().second] << " repeats line "
         << raw.tri_lines[dups.front().first] << "); kept as listed";
      rep.notes.push_back(os.str());
    }
  } else {
    check_cells(file, raw.tris, 3, raw.tri_lines, "triangle", nullptr);
  }

  mesh::MeshData& m = out.mesh;
  m.dimension = volume ? 3 : 2;
  m.points = Eigen::Map<const Eigen::Matrix3Xd>(raw.xyz.data(), 3, np);
  m.point_tags = std::move(raw.point_tags);
  const int k = volume ? 4 : 3;
  std::vector<Index>& cells = volume ? raw.tets : raw.tris;
  const std::vector<long>& lines = volume ? raw.tet_lines : raw.tri_lines;
  const Index nc = static_cast<Index>(lines.size());
  m.cells = Eigen::Map<const mesh::CellMatrix>(cells.data(), k, nc);
  m.cell_tags = volume ? std::move(raw.tet_tags) : std::move(raw.tri_tags);
  if (volume) {
    m.facets = Eigen::Map<const mesh::CellMatrix>(raw.tris.data(), 3,
                                                  static_cast<Index>(raw.tri_lines.size()));
    m.facet_tags = std::move(raw.tri_tags);
  } else {
    m.facets.resize(2, 0);
  }

  // Planarity of triangle meshes: all z equal.
  bool planar = true;
  if (!volume)
    for (Index i = 1; i < np && planar; ++i) planar = m.points(2, i) == m.points(2, 0);
  rep.surface = !volume && !planar;

  // Geometry: degenerate and inverted cells.
  std::vector<long> flipped_lines;
  const double tol = options.degenerate_tolerance;
  for (Index c = 0; c < nc; ++c) {
    std::array<Vec3, 4> p;
    double lmax2 = 0;
    for (int r = 0; r < k; ++r) p[r] = m.points.col(m.cells(r, c));
    for (int i = 0; i < k; ++i)
      for (int j = i + 1; j < k; ++j) lmax2 = std::max(lmax2, (p[i] - p[j]).squaredNorm());
    const double lmax = std::sqrt(lmax2);
    double size = 0, normalized = 0;
    if (volume) {
      size = mesh::signed_volume(p[0], p[1], p[2], p[3]);
      normalized = 6.0 * std::sqrt(2.0) * size / (lmax2 * lmax);
    } else {
      size =
          planar ? mesh::signed_area_xy(p[0], p[1], p[2]) : mesh::triangle_area(p[0], p[1], p[2]);
      normalized = 4.0 / std::sqrt(3.0) * size / lmax2;
    }
    if (!(std::abs(normalized) > tol)) {
      std::ostringstream os;
      os << "degenerate " << (volume ? "tetrahedron" : "triangle");
      if (std::isfinite(size) && std::isfinite(normalized))
        os << " (signed " << (volume ? "volume " : "area ") << size << ", " << normalized
           << " of the regular cell with its longest edge): expected a non-flat cell";
      else {  // never print NaN: the products of the coordinates left the doubles
        double largest = 0;
        for (int r = 0; r < k; ++r) largest = std::max(largest, p[r].cwiseAbs().maxCoeff());
        os << ": its " << (volume ? "volume" : "area") << " overflows or underflows the doubles"
           << " (largest coordinate magnitude " << largest << "): expected coordinates whose "
           << (volume ? "cubes" : "squares") << " stay within the doubles (check the scale)";
      }
      throw ParseError(file, lines[c], os.str());
    }
    if (size < 0) {
      if (!options.reorient) {
        std::ostringstream os;
        os << "inverted " << (volume ? "tetrahedron" : "triangle") << " (signed "
           << (volume ? "volume " : "area ") << size
           << "): expected positive orientation (the reorient option flips such cells)";
        throw ParseError(file, lines[c], os.str());
      }
      std::swap(m.cells(k - 2, c), m.cells(k - 1, c));
      flipped_lines.push_back(lines[c]);
    }
  }
  rep.reoriented = static_cast<Index>(flipped_lines.size());
  if (rep.reoriented > 0) {
    std::ostringstream os;
    os << rep.reoriented << " of " << nc << " cells were inverted and have been reoriented ("
       << line_list(flipped_lines, 5) << ")";
    rep.notes.push_back(os.str());
  }

  // Surfaces in 3D have no signed area: their orientation is that of their neighbours.
  if (rep.surface && options.reorient) {
    const std::vector<Index> flipped = orient_surface(m.cells);
    if (!flipped.empty()) {
      std::vector<long> l;
      for (Index c : flipped) l.push_back(lines[static_cast<std::size_t>(c)]);
      std::ostringstream os;
      os << flipped.size() << " of " << nc
         << " surface triangles were flipped to agree with their neighbours (" << line_list(l, 5)
         << ")";
      rep.notes.push_back(os.str());
      rep.reoriented += static_cast<Index>(flipped.size());
    }
  }
  check_faces(file, m.cells, lines, raw.point_lines, rep.surface, options.reorient);

  if (options.split_pinched_vertices) {
    const mesh::PinchSplit split = mesh::split_pinched_vertices(m);
    rep.pinched_vertices = static_cast<Index>(split.pinched.size());
    rep.added_vertices = static_cast<Index>(split.origin.size());
    if (!split.pinched.empty()) {
      std::ostringstream os;
      os << rep.pinched_vertices << " pinched vertices (star not face-connected, thesis §7.3) "
         << "split into " << rep.added_vertices << " new vertices appended from " << split.first_new
         << " (vertex ";
      std::vector<long> l;
      for (Index v : split.pinched) l.push_back(raw.point_lines[v]);
      os << line_list(l, 5) << ")";
      rep.notes.push_back(os.str());
    }
  }

  // Unused vertices.
  std::vector<char> used(m.num_points(), 0);
  for (Index c = 0; c < nc; ++c)
    for (int r = 0; r < k; ++r) used[m.cells(r, c)] = 1;
  for (Index i = 0; i < m.num_points(); ++i) rep.unused_vertices += used[i] ? 0 : 1;
  if (rep.unused_vertices > 0) {
    std::ostringstream os;
    os << rep.unused_vertices << " vertices are used by no cell";
    if (rep.merged_vertices > 0) os << " (including " << rep.merged_vertices << " merged ones)";
    rep.notes.push_back(os.str());
  }

  rep.num_points = m.num_points();
  rep.num_cells = nc;
  rep.num_facets = volume ? static_cast<Index>(m.facets.cols()) : 0;
  count_labels(m.cell_tags, rep.cell_labels);
  count_labels(m.facet_tags, rep.facet_labels);
  count_labels(m.point_tags, rep.point_labels);
  return out;
}

}  // namespace incise::io::detail
