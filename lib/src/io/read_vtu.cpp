// read_vtu: the VTU files write_vtu writes (ASCII, or raw appended zlib-compressed data with
// UInt64 headers), read back for tests and scripts.
#include <incise/core/error.hpp>
#include <incise/io/write_mesh.hpp>

#include <zlib.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>

namespace incise::io {

namespace {

struct Reader {
  std::string path;
  std::string text;

  [[noreturn]] void fail(std::size_t pos, const std::string& what) const {
    const long line =
        1 + static_cast<long>(std::count(
                text.begin(), text.begin() + static_cast<long>(std::min(pos, text.size())), '\n'));
    throw ParseError(path, line, what);
  }

  /// The value of attribute `name` in the tag text `tag` ("" when absent).
  static std::string attribute(const std::string& tag, const std::string& name) {
    const std::string key = " " + name + "=\"";
    const auto a = tag.find(key);
    if (a == std::string::npos) return "";
    const auto b = a + key.size();
    return tag.substr(b, tag.find('"', b) - b);
  }

  /// Decodes the compressed block at `offset` of the appended data into `bytes` bytes.
  std::string inflate(std::size_t base, std::size_t offset, std::size_t at) const {
    std::size_t p = base + offset;
    auto u64 = [&](std::size_t i) {
      if (p + 8 * (i + 1) > text.size()) fail(at, "truncated appended data: expected a header");
      std::uint64_t v;
      std::memcpy(&v, text.data() + p + 8 * i, 8);
      return v;
    };
    const std::uint64_t blocks = u64(0), block = u64(1), last = u64(2);
    if (blocks > text.size() || block > (std::uint64_t{1} << 30))
      fail(at, "bad compression header");
    std::string out;
    std::size_t data = p + 8 * (3 + blocks);
    for (std::uint64_t b = 0; b < blocks; ++b) {
      const std::uint64_t clen = u64(3 + b);
      const std::uint64_t ulen = (b + 1 == blocks && last != 0) ? last : block;
      if (data + clen > text.size()) fail(at, "truncated appended data: expected a block");
      std::string chunk(ulen, '\0');
      uLongf len = static_cast<uLongf>(ulen);
      if (uncompress(reinterpret_cast<Bytef*>(chunk.data()), &len,
                     reinterpret_cast<const Bytef*>(text.data() + data),
                     static_cast<uLong>(clen)) != Z_OK ||
          len != ulen)
        fail(at, "zlib data that does not inflate to its declared size");
      out += chunk;
      data += clen;
    }
    return out;
  }

  template <class V>
  static std::vector<double> convert(const std::string& bytes) {
    std::vector<double> out(bytes.size() / sizeof(V));
    for (std::size_t i = 0; i < out.size(); ++i) {
      V v;
      std::memcpy(&v, bytes.data() + i * sizeof(V), sizeof(V));
      out[i] = static_cast<double>(v);
    }
    return out;
  }
};

}  // namespace

const DataArray* VtuContents::find(const std::vector<DataArray>& arrays, const std::string& name) {
  for (const auto& a : arrays)
    if (a.name == name) return &a;
  return nullptr;
}

VtuContents read_vtu(const std::string& path) {
  Reader r{path, {}};
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw ParseError(path, 0, "cannot open the file");
    std::ostringstream ss;
    ss << in.rdbuf();
    r.text = ss.str();
  }
  const std::string& t = r.text;
  // The XML part ends where the appended data begins (binary files).
  const auto appended_tag = t.find("<AppendedData");
  std::size_t base = std::string::npos;
  if (appended_tag != std::string::npos) {
    if (Reader::attribute(t.substr(appended_tag, t.find('>', appended_tag) - appended_tag),
                          "encoding") != "raw")
      r.fail(appended_tag, "expected <AppendedData encoding=\"raw\">");
    base = t.find('_', appended_tag);
    if (base == std::string::npos) r.fail(appended_tag, "expected '_' before the appended data");
    ++base;
  }
  const std::string xml = t.substr(0, appended_tag);
  const auto piece = xml.find("<Piece ");
  if (piece == std::string::npos) r.fail(0, "expected a <Piece> of an UnstructuredGrid");
  const std::string piece_tag = xml.substr(piece, xml.find('>', piece) - piece);
  const long long np = std::atoll(Reader::attribute(piece_tag, "NumberOfPoints").c_str());
  const long long nc = std::atoll(Reader::attribute(piece_tag, "NumberOfCells").c_str());
  if (np < 0 || nc < 0) r.fail(piece, "expected non-negative NumberOfPoints and NumberOfCells");

  VtuContents out;
  std::vector<double> points, conn, types;
  const auto sec_point = xml.find("<PointData"), sec_cell = xml.find("<CellData"),
             sec_points = xml.find("<Points>"), sec_cells = xml.find("<Cells>");
  for (auto a = xml.find("<DataArray", piece); a != std::string::npos;
       a = xml.find("<DataArray", a + 1)) {
    const auto close = xml.find('>', a);
    if (close == std::string::npos) r.fail(a, "unterminated <DataArray");
    const std::string tag = xml.substr(a, close - a);
    DataArray d;
    d.name = Reader::attribute(tag, "Name");
    const std::string nc_text = Reader::attribute(tag, "NumberOfComponents");
    d.components = nc_text.empty() ? 1 : std::atoi(nc_text.c_str());
    const std::string type = Reader::attribute(tag, "type");
    const std::string format = Reader::attribute(tag, "format");
    if (format == "appended") {
      if (base == std::string::npos) r.fail(a, "appended array without <AppendedData>");
      const std::string bytes = r.inflate(
          base, static_cast<std::size_t>(std::atoll(Reader::attribute(tag, "offset").c_str())), a);
      if (type == "Float64")
        d.values = Reader::convert<double>(bytes);
      else if (type == "Int64")
        d.values = Reader::convert<std::int64_t>(bytes);
      else if (type == "Int32")
        d.values = Reader::convert<std::int32_t>(bytes);
      else if (type == "UInt8")
        d.values = Reader::convert<std::uint8_t>(bytes);
      else
        r.fail(a, "unsupported type '" + type + "': expected Float64, Int64, Int32 or UInt8");
    } else if (format == "ascii") {
      const auto end = xml.find("</DataArray>", close);
      if (end == std::string::npos) r.fail(a, "expected </DataArray>");
      std::istringstream in(xml.substr(close + 1, end - close - 1));
      for (double v; in >> v;) d.values.push_back(v);
      if (!in.eof()) r.fail(a, "bad number in ascii array '" + d.name + "'");
    } else {
      r.fail(a, "format '" + format + "': expected ascii or appended");
    }
    if (type == "Int32") d.type = DataArray::Type::kInt32;
    if (type == "UInt8") d.type = DataArray::Type::kUInt8;
    if (a > sec_cells) {
      if (d.name == "connectivity") conn = d.values;
      if (d.name == "types") types = d.values;
    } else if (a > sec_points) {
      points = d.values;
    } else if (a > sec_cell && sec_cell != std::string::npos) {
      if (d.values.size() != static_cast<std::size_t>(nc * d.components))
        r.fail(a, "cell array '" + d.name + "' length does not match NumberOfCells");
      if (d.name == "tag")
        out.mesh.cell_tags.assign(d.values.begin(), d.values.end());
      else
        out.cell_data.push_back(std::move(d));
    } else if (a > sec_point && sec_point != std::string::npos) {
      if (d.values.size() != static_cast<std::size_t>(np * d.components))
        r.fail(a, "point array '" + d.name + "' length does not match NumberOfPoints");
      if (d.name == "tag")
        out.mesh.point_tags.assign(d.values.begin(), d.values.end());
      else
        out.point_data.push_back(std::move(d));
    }
  }
  if (points.size() != static_cast<std::size_t>(3 * np))
    r.fail(sec_points, "expected 3 coordinates per point");
  if (types.size() != static_cast<std::size_t>(nc)) r.fail(sec_cells, "expected a type per cell");
  const bool tets = nc == 0 || types[0] == 10;
  const int k = tets ? 4 : 3;
  for (double ty : types)
    if (ty != (tets ? 10 : 5)) r.fail(sec_cells, "expected only tetrahedra or only triangles");
  if (conn.size() != static_cast<std::size_t>(k * nc))
    r.fail(sec_cells, "connectivity length does not match the cells");
  out.mesh.dimension = tets ? 3 : 2;
  out.mesh.points = Eigen::Map<const Eigen::Matrix3Xd>(points.data(), 3, np);
  out.mesh.cells.resize(k, nc);
  for (long long c = 0; c < nc; ++c)
    for (int j = 0; j < k; ++j) {
      const double v = conn[static_cast<std::size_t>(c * k + j)];
      if (v < 0 || v >= static_cast<double>(np)) r.fail(sec_cells, "vertex index out of range");
      out.mesh.cells(j, c) = static_cast<Index>(v);
    }
  return out;
}

}  // namespace incise::io
