// TetGen .node / .ele reader (TetGen 1.6 user manual, §5.2.1 and §5.2.4).

#include <incise/io/read_mesh.hpp>

#include <cmath>
#include <sstream>

#include "text_reader.hpp"

namespace incise::io {

namespace {

using detail::RawMesh;
using detail::TextReader;

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

LoadedMesh read_tetgen(const std::string& path, const ReadOptions& options) {
  std::string base = path;
  if (ends_with(base, ".node") || ends_with(base, ".ele")) base = base.substr(0, base.rfind('.'));
  RawMesh raw;
  raw.format = "tetgen";
  long long first = 0;
  {
    TextReader r = TextReader::open(base + ".node", '#');
    const long long n = r.integer("number of points", 0, (1LL << 31) - 1);
    r.integer("dimension (3)", 3, 3);
    const long long nattr = r.integer("number of point attributes", 0, 1 << 16);
    const long long nmark = r.integer("number of boundary markers (0 or 1)", 0, 1);
    r.end_of_line("the .node header");
    const std::size_t reserve = detail::bounded_reserve(n, r.size());
    raw.xyz.reserve(3 * reserve);
    raw.point_lines.reserve(reserve);
    for (long long i = 0; i < n; ++i) {
      if (i == 0) {
        first = r.integer("first point number (0 or 1)", 0, 1);
      } else {
        r.integer("point number", first + i, first + i);
      }
      raw.xyz.push_back(r.real("x coordinate"));
      raw.xyz.push_back(r.real("y coordinate"));
      raw.xyz.push_back(r.real("z coordinate"));
      raw.point_lines.push_back(r.line());
      for (long long a = 0; a < nattr; ++a) r.real("point attribute");
      if (nmark == 1)
        raw.point_tags.push_back(
            static_cast<int>(r.integer("boundary marker", -(1LL << 31), (1LL << 31) - 1)));
      r.end_of_line("the point record");
    }
    if (!r.at_end()) {
      r.token("end of file");
      r.fail("unexpected extra data after the last point: expected end of file");
    }
  }
  {
    const Index np = static_cast<Index>(raw.point_lines.size());
    TextReader r = TextReader::open(base + ".ele", '#');
    const long long n = r.integer("number of tetrahedra", 0, (1LL << 31) - 1);
    const long long per = r.integer("nodes per tetrahedron", 1, 1 << 10);
    if (per != 4)
      r.fail("unsupported element type: " + std::to_string(per) +
             "-node tetrahedra; expected 4 nodes per tetrahedron");
    const long long nattr = r.integer("number of tetrahedron attributes", 0, 1 << 16);
    r.end_of_line("the .ele header");
    const std::size_t reserve = detail::bounded_reserve(n, r.size());
    raw.tets.reserve(4 * reserve);
    raw.tet_lines.reserve(reserve);
    for (long long i = 0; i < n; ++i) {
      r.integer("tetrahedron number");
      for (int k = 0; k < 4; ++k)
        raw.tets.push_back(
            static_cast<Index>(r.integer("vertex index", first, first + np - 1) - first));
      raw.tet_lines.push_back(r.line());
      for (long long a = 0; a < nattr; ++a) {
        const double v = r.real("region attribute");
        if (a == 0) {
          if (std::abs(v) > 2147483647.0) r.fail("region attribute out of range: expected an int");
          raw.tet_tags.push_back(static_cast<int>(std::lround(v)));
        }
      }
      r.end_of_line("the tetrahedron record");
    }
    if (!r.at_end()) {
      r.token("end of file");
      r.fail("unexpected extra data after the last tetrahedron: expected end of file");
    }
  }
  return detail::finalize(std::move(raw), base + ".ele", options);
}

}  // namespace incise::io
