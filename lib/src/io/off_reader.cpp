// OFF (Object File Format) triangle surface reader.

#include <incise/io/read_mesh.hpp>

#include <string>

#include "text_reader.hpp"

namespace incise::io {

LoadedMesh read_off(const std::string& path, const ReadOptions& options) {
  detail::TextReader r = detail::TextReader::open(path, '#');
  detail::RawMesh raw;
  raw.format = "off";
  r.expect("OFF");
  const long long nv = r.integer("number of vertices", 0, (1LL << 31) - 1);
  const long long nf = r.integer("number of faces", 0, (1LL << 31) - 1);
  r.integer("number of edges", 0);
  r.end_of_line("the vertex, face and edge counts");
  raw.xyz.reserve(3 * detail::bounded_reserve(nv, r.size()));
  for (long long i = 0; i < nv; ++i) {
    raw.xyz.push_back(r.real("x coordinate"));
    raw.xyz.push_back(r.real("y coordinate"));
    raw.xyz.push_back(r.real("z coordinate"));
    raw.point_lines.push_back(r.line());
    r.end_of_line("3 vertex coordinates");
  }
  raw.tris.reserve(3 * detail::bounded_reserve(nf, r.size()));
  for (long long f = 0; f < nf; ++f) {
    const long long k = r.integer("number of face vertices (3)", 0, 1 << 20);
    if (k != 3)
      r.fail("unsupported face with " + std::to_string(k) + " vertices: expected triangles (3)");
    for (int j = 0; j < 3; ++j)
      raw.tris.push_back(static_cast<Index>(r.integer("vertex index (0-based)", 0, nv - 1)));
    raw.tri_lines.push_back(r.line());
    r.skip_line();  // optional colour
  }
  if (!r.at_end()) {
    const std::string extra(r.token("end of file").substr(0, 40));
    r.fail("unexpected data after the " + std::to_string(nf) +
           " faces the header declares: expected end of file, got '" + extra +
           "' (is the face count too small?)");
  }
  return detail::finalize(std::move(raw), path, options);
}

}  // namespace incise::io
