// Medit / INRIA .mesh ASCII reader (Frey, "MEDIT: an interactive mesh visualization software",
// INRIA RT-0253, 2001, appendix: the .mesh keywords).

#include <incise/io/read_mesh.hpp>

#include <algorithm>
#include <cctype>
#include <sstream>

#include "text_reader.hpp"

namespace incise::io {

namespace {

using detail::RawMesh;
using detail::TextReader;

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

void read_simplices(RawMesh& raw, TextReader& r, int k, Index num_points) {
  const long long n =
      r.integer(k == 4 ? "number of tetrahedra" : "number of triangles", 0, (1LL << 31) - 1);
  std::vector<Index>& v = k == 4 ? raw.tets : raw.tris;
  std::vector<int>& tags = k == 4 ? raw.tet_tags : raw.tri_tags;
  std::vector<long>& lines = k == 4 ? raw.tet_lines : raw.tri_lines;
  const std::size_t reserve = detail::bounded_reserve(n, r.size());
  v.reserve(v.size() + k * reserve);
  tags.reserve(tags.size() + reserve);
  lines.reserve(lines.size() + reserve);
  for (long long i = 0; i < n; ++i) {
    for (int j = 0; j < k; ++j)
      v.push_back(static_cast<Index>(r.integer("vertex index (1-based)", 1, num_points) - 1));
    tags.push_back(static_cast<int>(r.integer("reference", -(1LL << 31), (1LL << 31) - 1)));
    lines.push_back(r.line());
  }
}

}  // namespace

LoadedMesh read_medit(const std::string& path, const ReadOptions& options) {
  TextReader r = TextReader::open(path, '#');
  RawMesh raw;
  int version = 0, dim = 3;
  bool have_vertices = false;
  while (!r.at_end()) {
    const std::string_view word = r.token("keyword");
    const std::string kw = lower(word);
    if (kw == "end") break;
    if (kw == "meshversionformatted") {
      version = static_cast<int>(r.integer("mesh version (1 to 4)", 1, 4));
    } else if (kw == "dimension") {
      dim = static_cast<int>(r.integer("dimension (2 or 3)", 2, 3));
    } else if (kw == "vertices") {
      if (have_vertices) r.fail("second Vertices section: expected one");
      const long long n = r.integer("number of vertices", 0, (1LL << 31) - 1);
      const std::size_t reserve = detail::bounded_reserve(n, r.size());
      raw.xyz.reserve(3 * reserve);
      raw.point_lines.reserve(reserve);
      raw.point_tags.reserve(reserve);
      for (long long i = 0; i < n; ++i) {
        raw.xyz.push_back(r.real("x coordinate"));
        raw.xyz.push_back(r.real("y coordinate"));
        raw.xyz.push_back(dim == 3 ? r.real("z coordinate") : 0.0);
        raw.point_tags.push_back(
            static_cast<int>(r.integer("vertex reference", -(1LL << 31), (1LL << 31) - 1)));
        raw.point_lines.push_back(r.line());
      }
      have_vertices = true;
    } else if (kw == "triangles" || kw == "tetrahedra") {
      if (!have_vertices) r.fail("'" + std::string(word) + "' before Vertices: expected Vertices");
      read_simplices(raw, r, kw == "tetrahedra" ? 4 : 3,
                     static_cast<Index>(raw.point_lines.size()));
    } else {
      // Sections that are skipped: entries per record.
      int width = -1;
      if (kw == "edges")
        width = 3;
      else if (kw == "corners" || kw == "requiredvertices" || kw == "ridges" ||
               kw == "requirededges" || kw == "requiredtriangles" || kw == "requiredtetrahedra")
        width = 1;
      else if (kw == "normals" || kw == "tangents")
        width = dim;
      else if (kw == "normalatvertices" || kw == "tangentatvertices" || kw == "tangentatedges")
        width = 2;
      else if (kw == "normalattrianglevertices")
        width = 3;
      if (width < 0) {
        if (kw == "quadrilaterals" || kw == "hexahedra" || kw == "prisms" || kw == "pyramids" ||
            kw == "trianglesp2" || kw == "tetrahedrap2" || kw == "edgesp2")
          r.fail("unsupported element type '" + std::string(word) +
                 "': expected Triangles or Tetrahedra");
        r.fail("unknown keyword '" + std::string(word) + "': expected a Medit section keyword");
      }
      const long long n = r.integer("number of records", 0, (1LL << 31) - 1);
      for (long long i = 0; i < n * width; ++i) r.real("record value");
      if (kw == "edges") raw.ignored += static_cast<Index>(n);
    }
  }
  if (version == 0) r.fail("expected MeshVersionFormatted");
  if (!have_vertices) r.fail("unexpected end of file: expected a Vertices section");
  raw.format = "medit " + std::to_string(version);
  if (raw.ignored > 0) raw.ignored_notes.push_back(std::to_string(raw.ignored) + " edges ignored");
  return detail::finalize(std::move(raw), path, options);
}

}  // namespace incise::io
