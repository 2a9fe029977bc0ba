#include <incise/core/error.hpp>
#include <incise/io/write_mesh.hpp>
#include <incise/mesh/quality.hpp>

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>
#include <set>
#include <type_traits>

#include "writer_support.hpp"

namespace incise::io {

namespace {

using detail::TextWriter;

void check_mesh(const mesh::MeshData& m) {
  INCISE_CHECK(m.dimension == 2 || m.dimension == 3, "writer: dimension must be 2 or 3");
  INCISE_CHECK(m.cells.rows() == m.dimension + 1 || m.cells.cols() == 0,
               "writer: cells must have dimension+1 rows");
  INCISE_CHECK(m.cell_tags.empty() || m.cell_tags.size() == static_cast<std::size_t>(m.num_cells()),
               "writer: cell_tags must be empty or one per cell");
  INCISE_CHECK(
      m.point_tags.empty() || m.point_tags.size() == static_cast<std::size_t>(m.num_points()),
      "writer: point_tags must be empty or one per point");
  INCISE_CHECK(
      m.facet_tags.empty() || m.facet_tags.size() == static_cast<std::size_t>(m.facets.cols()),
      "writer: facet_tags must be empty or one per facet");
  for (Eigen::Index c = 0; c < m.cells.cols(); ++c)
    for (Eigen::Index r = 0; r < m.cells.rows(); ++r)
      INCISE_CHECK(m.cells(r, c) >= 0 && m.cells(r, c) < m.num_points(),
                   "writer: cell vertex index out of range");
}

bool write_facets(const mesh::MeshData& m) {
  return m.dimension == 3 && m.facets.rows() == 3;
}

void check_array(const DataArray& a, Eigen::Index n, const char* what) {
  INCISE_CHECK(a.components >= 1, "write_vtu: components must be >= 1");
  INCISE_CHECK(
      a.values.size() == static_cast<std::size_t>(a.components) * static_cast<std::size_t>(n),
      std::string("write_vtu: ") + what + " array '" + a.name + "' has the wrong length");
  INCISE_CHECK(!a.name.empty() && a.name.find_first_of("\"<>&") == std::string::npos,
               "write_vtu: array names must be non-empty without \" < > &");
  if (a.type == DataArray::Type::kFloat64) return;
  const double lo = a.type == DataArray::Type::kInt32 ? -2147483648.0 : 0.0;
  const double hi = a.type == DataArray::Type::kInt32 ? 2147483647.0 : 255.0;
  for (double v : a.values)
    INCISE_CHECK(v == std::floor(v) && v >= lo && v <= hi,
                 "write_vtu: integer array '" + a.name + "' holds a value outside its type");
}

const char* type_name(DataArray::Type t) {
  switch (t) {
    case DataArray::Type::kInt32: return "Int32";
    case DataArray::Type::kUInt8: return "UInt8";
    default: return "Float64";
  }
}

/// The VTU body: the XML in `xml`, and (binary encoding) the appended block in `appended`.
class VtuBody {
 public:
  explicit VtuBody(VtuEncoding e) : encoding_(e) {}
  TextWriter xml;

  /// One DataArray element. `name` "" for the unnamed Points array. Values are converted to
  /// `type` (Int64 for connectivity and offsets, which DataArray::Type does not offer).
  template <class Value>
  void array(const std::string& name, const char* type, int components,
             const std::vector<Value>& values) {
    xml << "        <DataArray type=\"" << type << "\"";
    if (!name.empty()) xml << " Name=\"" << name << "\"";
    if (components > 1 || name.empty()) xml << " NumberOfComponents=\"" << components << "\"";
    if (encoding_ == VtuEncoding::kAscii) {
      xml << " format=\"ascii\">\n";
      const std::size_t k = static_cast<std::size_t>(components);
      for (std::size_t i = 0; i < values.size(); ++i) {
        if constexpr (std::is_floating_point_v<Value>)
          xml << values[i];
        else
          xml << static_cast<long long>(values[i]);
        xml << ((i + 1) % k == 0 ? '\n' : ' ');
      }
      xml << "        </DataArray>\n";
      return;
    }
    xml << " format=\"appended\" offset=\"" << static_cast<long long>(appended_.size()) << "\"/>\n";
    append_compressed(reinterpret_cast<const unsigned char*>(values.data()),
                      values.size() * sizeof(Value));
  }

  /// A DataArray of the caller's, converted to its type.
  void array(const DataArray& a) {
    switch (a.type) {
      case DataArray::Type::kInt32:
        array(a.name, type_name(a.type), a.components,
              std::vector<std::int32_t>(a.values.begin(), a.values.end()));
        return;
      case DataArray::Type::kUInt8:
        array(a.name, type_name(a.type), a.components,
              std::vector<std::uint8_t>(a.values.begin(), a.values.end()));
        return;
      default: array(a.name, type_name(a.type), a.components, a.values);
    }
  }

  bool binary() const { return encoding_ == VtuEncoding::kBinaryZlib; }
  const std::string& appended() const { return appended_; }

 private:
  /// VTK's compressed layout: UInt64 header [blocks, block size, last partial block size (0
  /// when the last block is full), compressed size of each block], then the compressed blocks.
  void append_compressed(const unsigned char* data, std::size_t bytes) {
    constexpr std::size_t kBlock = 32768;
    const std::size_t blocks = (bytes + kBlock - 1) / kBlock;
    std::vector<std::uint64_t> header(3 + blocks);
    header[0] = blocks;
    header[1] = kBlock;
    header[2] = bytes % kBlock;
    std::string body;
    std::vector<unsigned char> out(compressBound(static_cast<uLong>(kBlock)));
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t n = std::min(kBlock, bytes - b * kBlock);
      uLongf len = static_cast<uLongf>(out.size());
      if (compress2(out.data(), &len, data + b * kBlock, static_cast<uLong>(n),
                    Z_DEFAULT_COMPRESSION) != Z_OK)
        throw Error("write_vtu: zlib compression failed");
      header[3 + b] = len;
      body.append(reinterpret_cast<const char*>(out.data()), len);
    }
    appended_.append(reinterpret_cast<const char*>(header.data()),
                     header.size() * sizeof(std::uint64_t));
    appended_ += body;
  }

  VtuEncoding encoding_;
  std::string appended_;
};

bool little_endian() {
  const std::uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

}  // namespace

void write_vtu(const std::string& path, const mesh::MeshData& m,
               const std::vector<DataArray>& point_data, const std::vector<DataArray>& cell_data,
               VtuEncoding encoding) {
  check_mesh(m);
  for (const auto& a : point_data) check_array(a, m.num_points(), "point");
  for (const auto& a : cell_data) check_array(a, m.num_cells(), "cell");
  INCISE_CHECK(encoding == VtuEncoding::kAscii || little_endian(),
               "write_vtu: binary VTU is written little-endian only");
  const int k = m.dimension + 1;
  VtuBody v(encoding);
  TextWriter& w = v.xml;
  w << "<?xml version=\"1.0\"?>\n"
    << "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\"";
  if (v.binary()) w << " header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\"";
  w << ">\n  <UnstructuredGrid>\n"
    << "    <Piece NumberOfPoints=\"" << static_cast<long long>(m.num_points())
    << "\" NumberOfCells=\"" << static_cast<long long>(m.num_cells()) << "\">\n";
  w << "      <PointData>\n";
  if (!m.point_tags.empty()) v.array("tag", "Int32", 1, m.point_tags);
  for (const auto& a : point_data) v.array(a);
  w << "      </PointData>\n      <CellData>\n";
  if (!m.cell_tags.empty()) v.array("tag", "Int32", 1, m.cell_tags);
  for (const auto& a : cell_data) v.array(a);
  w << "      </CellData>\n      <Points>\n";
  std::vector<double> points(static_cast<std::size_t>(3 * m.num_points()));
  for (Index i = 0; i < m.num_points(); ++i)
    for (int d = 0; d < 3; ++d) points[static_cast<std::size_t>(3 * i + d)] = m.points(d, i);
  v.array("", "Float64", 3, points);
  w << "      </Points>\n      <Cells>\n";
  std::vector<std::int64_t> conn, offsets;
  conn.reserve(static_cast<std::size_t>(k * m.num_cells()));
  for (Index c = 0; c < m.num_cells(); ++c)
    for (int r = 0; r < k; ++r) conn.push_back(m.cells(r, c));
  for (Index c = 0; c < m.num_cells(); ++c) offsets.push_back(static_cast<std::int64_t>(c + 1) * k);
  const std::uint8_t type = m.dimension == 3 ? 10 : 5;  // VTK_TETRA, VTK_TRIANGLE
  v.array("connectivity", "Int64", 1, conn);
  v.array("offsets", "Int64", 1, offsets);
  v.array("types", "UInt8", 1,
          std::vector<std::uint8_t>(static_cast<std::size_t>(m.num_cells()), type));
  w << "      </Cells>\n    </Piece>\n  </UnstructuredGrid>\n";
  if (v.binary()) {
    w << "  <AppendedData encoding=\"raw\">\n   _";
    w << v.appended();
    w << "\n  </AppendedData>\n";
  }
  w << "</VTKFile>\n";
  w.save(path);
}

void write_pvd(const std::string& path, const std::vector<PvdFrame>& frames) {
  TextWriter w;
  w << "<?xml version=\"1.0\"?>\n"
    << "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
    << "  <Collection>\n";
  for (const PvdFrame& f : frames) {
    INCISE_CHECK(!f.file.empty() && f.file.find_first_of("\"<>&") == std::string::npos,
                 "write_pvd: file names must be non-empty without \" < > &");
    w << "    <DataSet timestep=\"" << f.timestep << "\" group=\"\" part=\"0\" file=\"" << f.file
      << "\"/>\n";
  }
  w << "  </Collection>\n</VTKFile>\n";
  w.save(path);
}

void write_gmsh(const std::string& path, const mesh::MeshData& m, int version) {
  check_mesh(m);
  INCISE_CHECK_PARAM(version == 22 || version == 41, "write_gmsh: version must be 22 or 41");
  const int k = m.dimension + 1;
  const int cell_type = m.dimension == 3 ? 4 : 2;
  const bool facets = write_facets(m);
  const Index nf = facets ? static_cast<Index>(m.facets.cols()) : 0;
  auto cell_tag = [&](Index c) { return m.cell_tags.empty() ? 0 : m.cell_tags[c]; };
  auto facet_tag = [&](Index f) { return m.facet_tags.empty() ? 0 : m.facet_tags[f]; };
  TextWriter w;
  if (version == 22) {
    w << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n"
      << static_cast<long long>(m.num_points()) << '\n';
    for (Index i = 0; i < m.num_points(); ++i)
      w << static_cast<long long>(i + 1) << ' ' << m.points(0, i) << ' ' << m.points(1, i) << ' '
        << m.points(2, i) << '\n';
    w << "$EndNodes\n$Elements\n" << static_cast<long long>(m.num_cells() + nf) << '\n';
    long long id = 1;
    for (Index f = 0; f < nf; ++f)
      w << id++ << " 2 2 " << facet_tag(f) << ' ' << facet_tag(f) << ' ' << m.facets(0, f) + 1
        << ' ' << m.facets(1, f) + 1 << ' ' << m.facets(2, f) + 1 << '\n';
    for (Index c = 0; c < m.num_cells(); ++c) {
      w << id++ << ' ' << cell_type << " 2 " << cell_tag(c) << ' ' << cell_tag(c);
      for (int r = 0; r < k; ++r) w << ' ' << m.cells(r, c) + 1;
      w << '\n';
    }
    w << "$EndElements\n";
    w.save(path);
    return;
  }
  // 4.1: one entity per distinct tag; entity e has physical tag `tag` unless tag is 0.
  std::set<int> cell_tags, facet_tags;
  for (Index c = 0; c < m.num_cells(); ++c) cell_tags.insert(cell_tag(c));
  for (Index f = 0; f < nf; ++f) facet_tags.insert(facet_tag(f));
  if (cell_tags.empty()) cell_tags.insert(0);
  std::map<int, int> cell_entity, facet_entity;
  for (int t : cell_tags) cell_entity.emplace(t, static_cast<int>(cell_entity.size()) + 1);
  for (int t : facet_tags) facet_entity.emplace(t, static_cast<int>(facet_entity.size()) + 1);
  const auto bb = mesh::bounding_box(m.points);
  auto box = [&](TextWriter& o) {
    o << bb[0].x() << ' ' << bb[0].y() << ' ' << bb[0].z() << ' ' << bb[1].x() << ' ' << bb[1].y()
      << ' ' << bb[1].z();
  };
  auto phys = [&](TextWriter& o, int tag) {
    if (tag == 0)
      o << " 0";
    else
      o << " 1 " << tag;
  };
  w << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 ";
  const bool volume = m.dimension == 3;
  const std::size_t n_surf = volume ? facet_entity.size() : cell_entity.size();
  w << static_cast<long long>(n_surf) << ' '
    << (volume ? static_cast<long long>(cell_entity.size()) : 0LL) << '\n';
  for (const auto& [tag, e] : (volume ? facet_entity : cell_entity)) {
    w << e << ' ';
    box(w);
    phys(w, tag);
    w << " 0\n";
  }
  if (volume)
    for (const auto& [tag, e] : cell_entity) {
      w << e << ' ';
      box(w);
      phys(w, tag);
      w << " 0\n";
    }
  w << "$EndEntities\n$Nodes\n1 " << static_cast<long long>(m.num_points()) << " 1 "
    << static_cast<long long>(m.num_points()) << '\n'
    << m.dimension << " 1 0 " << static_cast<long long>(m.num_points()) << '\n';
  for (Index i = 0; i < m.num_points(); ++i) w << static_cast<long long>(i + 1) << '\n';
  for (Index i = 0; i < m.num_points(); ++i)
    w << m.points(0, i) << ' ' << m.points(1, i) << ' ' << m.points(2, i) << '\n';
  w << "$EndNodes\n$Elements\n";
  // Blocks: maximal runs of equal tag (facets, then cells), so that the order is preserved.
  struct Block {
    int dim, entity, type;
    Index first, count;
  };
  std::vector<Block> blocks;
  for (Index f = 0; f < nf; ++f) {
    if (f == 0 || facet_tag(f) != facet_tag(f - 1))
      blocks.push_back({2, facet_entity[facet_tag(f)], 2, f, 0});
    ++blocks.back().count;
  }
  const std::size_t first_cell_block = blocks.size();
  for (Index c = 0; c < m.num_cells(); ++c) {
    if (c == 0 || cell_tag(c) != cell_tag(c - 1))
      blocks.push_back({m.dimension, cell_entity[cell_tag(c)], cell_type, c, 0});
    ++blocks.back().count;
  }
  const long long total = nf + m.num_cells();
  w << static_cast<long long>(blocks.size()) << ' ' << total << " 1 " << total << '\n';
  long long id = 1;
  for (std::size_t b = 0; b < blocks.size(); ++b) {
    const Block& bl = blocks[b];
    const bool cells = b >= first_cell_block;
    w << bl.dim << ' ' << bl.entity << ' ' << bl.type << ' ' << bl.count << '\n';
    for (Index i = bl.first; i < bl.first + bl.count; ++i) {
      w << id++;
      for (int r = 0; r < (cells ? k : 3); ++r)
        w << ' ' << (cells ? m.cells(r, i) : m.facets(r, i)) + 1;
      w << '\n';
    }
  }
  w << "$EndElements\n";
  w.save(path);
}

void write_medit(const std::string& path, const mesh::MeshData& m, bool planar2d) {
  check_mesh(m);
  INCISE_CHECK(!planar2d || m.dimension == 2, "write_medit: planar2d needs a triangle mesh");
  TextWriter w;
  w << "MeshVersionFormatted 2\n\nDimension " << (planar2d ? 2 : 3) << "\n\nVertices\n"
    << static_cast<long long>(m.num_points()) << '\n';
  for (Index i = 0; i < m.num_points(); ++i) {
    w << m.points(0, i) << ' ' << m.points(1, i);
    if (!planar2d) w << ' ' << m.points(2, i);
    w << ' ' << (m.point_tags.empty() ? 0 : m.point_tags[i]) << '\n';
  }
  auto block = [&](const char* name, const mesh::CellMatrix& cells, const std::vector<int>& tags) {
    w << '\n' << name << '\n' << static_cast<long long>(cells.cols()) << '\n';
    for (Eigen::Index c = 0; c < cells.cols(); ++c) {
      for (Eigen::Index r = 0; r < cells.rows(); ++r) w << cells(r, c) + 1 << ' ';
      w << (tags.empty() ? 0 : tags[c]) << '\n';
    }
  };
  if (m.dimension == 3) {
    if (write_facets(m) && m.facets.cols() > 0) block("Triangles", m.facets, m.facet_tags);
    block("Tetrahedra", m.cells, m.cell_tags);
  } else {
    block("Triangles", m.cells, m.cell_tags);
  }
  w << "\nEnd\n";
  w.save(path);
}

void write_tetgen(const std::string& base, const mesh::MeshData& m) {
  check_mesh(m);
  INCISE_CHECK(m.dimension == 3, "write_tetgen: tetrahedral meshes only");
  TextWriter node;
  const bool marks = !m.point_tags.empty();
  node << static_cast<long long>(m.num_points()) << " 3 0 " << (marks ? 1 : 0) << '\n';
  for (Index i = 0; i < m.num_points(); ++i) {
    node << static_cast<long long>(i + 1) << ' ' << m.points(0, i) << ' ' << m.points(1, i) << ' '
         << m.points(2, i);
    if (marks) node << ' ' << m.point_tags[i];
    node << '\n';
  }
  TextWriter ele;
  const bool attr = !m.cell_tags.empty();
  ele << static_cast<long long>(m.num_cells()) << " 4 " << (attr ? 1 : 0) << '\n';
  for (Index c = 0; c < m.num_cells(); ++c) {
    ele << static_cast<long long>(c + 1);
    for (int r = 0; r < 4; ++r) ele << ' ' << m.cells(r, c) + 1;
    if (attr) ele << ' ' << m.cell_tags[c];
    ele << '\n';
  }
  node.save(base + ".node");
  ele.save(base + ".ele");
}

void write_off(const std::string& path, const mesh::MeshData& m) {
  check_mesh(m);
  INCISE_CHECK(m.dimension == 2, "write_off: triangle meshes only");
  TextWriter w;
  w << "OFF\n"
    << static_cast<long long>(m.num_points()) << ' ' << static_cast<long long>(m.num_cells())
    << " 0\n";
  for (Index i = 0; i < m.num_points(); ++i)
    w << m.points(0, i) << ' ' << m.points(1, i) << ' ' << m.points(2, i) << '\n';
  for (Index c = 0; c < m.num_cells(); ++c)
    w << "3 " << m.cells(0, c) << ' ' << m.cells(1, c) << ' ' << m.cells(2, c) << '\n';
  w.save(path);
}

std::vector<DataArray> quality_cell_data(const mesh::CellQuality& q) {
  constexpr double kDegrees = 180.0 / 3.14159265358979323846;
  const bool tets = q.dimension == 3;
  std::vector<DataArray> d = {{tets ? "volume" : "area", 1, q.size},
                              {"aspect_ratio", 1, q.aspect_ratio},
                              {"shewchuk_quality", 1, q.shewchuk},
                              {tets ? "min_dihedral_angle_deg" : "min_angle_deg", 1, q.min_angle},
                              {tets ? "max_dihedral_angle_deg" : "max_angle_deg", 1, q.max_angle},
                              {"shape_class", 1, {}, DataArray::Type::kUInt8}};
  for (auto* a : {&d[3], &d[4]})
    for (double& v : a->values) v *= kDegrees;
  for (auto s : q.shape) d[5].values.push_back(static_cast<double>(s));
  return d;
}

}  // namespace incise::io
