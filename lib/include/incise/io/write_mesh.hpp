#pragma once
/// \file write_mesh.hpp
/// Writers: VTU (ParaView XML unstructured grid; raw binary zlib-compressed appended data by
/// default, ASCII on request) with point and cell data arrays, and the readable formats (Gmsh
/// 2.2/4.1, Medit, TetGen, OFF) so that every reader has a round-trip test. Text formats write
/// doubles in the shortest form that reads back exactly; binary VTU stores the doubles' bytes.
/// Throws incise::Error when the file cannot be written and UsageError on inconsistent input.

#include <incise/core/name_table.hpp>
#include <incise/mesh/mesh_data.hpp>
#include <incise/mesh/quality.hpp>

#include <string>
#include <vector>

namespace incise::io {

/// A named data array: `components` values per point or per cell, stored point/cell-major
/// (values[i*components + c]). Length must be components × (number of points or cells).
/// `type` is the VTK type written; the values of an integer type must be integers in its range.
struct DataArray {
  /// The VTK element type of the array in the file.
  enum class Type { kFloat64, kInt32, kUInt8 };
  std::string name;
  int components = 1;
  std::vector<double> values;
  Type type = Type::kFloat64;
};

/// How write_vtu stores its arrays.
enum class VtuEncoding {
  /// Default: every array in one `<AppendedData encoding="raw">` block, zlib-compressed
  /// (`compressor="vtkZLibDataCompressor"`, `header_type="UInt64"`, blocks of 32768 bytes
  /// before compression), little-endian. Exact: the doubles' bytes are stored.
  kBinaryZlib,
  /// Every array as text (`format="ascii"`), doubles in the shortest exact form.
  kAscii,
};

/// Names of the encodings (scene key `outputs.vtu_format`, docs/scenes.md).
inline constexpr NameTable<VtuEncoding, 2> kVtuEncodingNames{{{
    {VtuEncoding::kBinaryZlib, "binary"},
    {VtuEncoding::kAscii, "ascii"},
}}};
/// Name from kVtuEncodingNames.
inline const char* to_string(VtuEncoding e) {
  return kVtuEncodingNames.name(e);
}

/// Writes `m` as a VTU file (VTK XML UnstructuredGrid, docs/mesh_formats.md). Cells are
/// VTK_TETRA (10) or VTK_TRIANGLE (5), connectivity and offsets Int64. Cell tags, when
/// present, are written as the Int32 cell array "tag" and point tags as point array "tag";
/// `point_data` and `cell_data` follow with their own types.
void write_vtu(const std::string& path, const mesh::MeshData& m,
               const std::vector<DataArray>& point_data = {},
               const std::vector<DataArray>& cell_data = {},
               VtuEncoding encoding = VtuEncoding::kBinaryZlib);

/// What read_vtu() returns: the mesh (points, cells, the "tag" arrays as cell_tags and
/// point_tags) and the other arrays in file order, as doubles with the type they had.
struct VtuContents {
  mesh::MeshData mesh;
  std::vector<DataArray> point_data;
  std::vector<DataArray> cell_data;
  /// The array called `name` in `arrays`, or nullptr.
  static const DataArray* find(const std::vector<DataArray>& arrays, const std::string& name);
};

/// Reads a VTU file as write_vtu writes it (either encoding; one piece of tetrahedra or
/// triangles), for round-trip tests and scripts; VTK's own reader is the reference
/// (test io_vtk_readback). Throws ParseError naming the file and what was expected.
VtuContents read_vtu(const std::string& path);

/// One dataset of a ParaView collection (write_pvd): a file and its time.
struct PvdFrame {
  double timestep = 0;  ///< the DataSet's `timestep` attribute (ParaView's animation time)
  std::string file;     ///< the dataset's path as written into the index (relative to it)
};

/// Writes a ParaView collection index (.pvd, VTK XML "Collection") listing `frames` in order,
/// so that ParaView opens the files as one time series. Throws UsageError for a file name that
/// is empty or holds one of " < > &, incise::Error when the file cannot be written.
void write_pvd(const std::string& path, const std::vector<PvdFrame>& frames);

/// Gmsh ASCII writer, version 2.2 or 4.1 (`version` = 22 or 41). Cells are written as
/// tetrahedra (or triangles), facets as triangles; tags become physical tags (4.1: one entity
/// per distinct tag, with $Entities). Nodes are numbered from 1.
void write_gmsh(const std::string& path, const mesh::MeshData& m, int version = 41);

/// Medit .mesh writer (MeshVersionFormatted 2, Dimension 3 — or 2 for planar triangle meshes
/// when `planar2d`), 1-based, tags as references (0 when absent).
void write_medit(const std::string& path, const mesh::MeshData& m, bool planar2d = false);

/// TetGen writer: `base`.node and `base`.ele (1-based, region attribute = cell tag when
/// present, boundary marker = point tag when present). Tetrahedral meshes only.
void write_tetgen(const std::string& base, const mesh::MeshData& m);

/// OFF writer for triangle meshes (dimension 2).
void write_off(const std::string& path, const mesh::MeshData& m);

/// The per-cell quality arrays `incise mesh check --vtu` writes (mesh::cell_quality), named
/// for what they hold: tetrahedra "volume" (signed, m³), "aspect_ratio" (§3.2.3),
/// "shewchuk_quality", "min_dihedral_angle_deg", "max_dihedral_angle_deg" (degrees), and
/// "shape_class" (UInt8: 0 good, 1 needle, 2 spindle, 3 sliver, 4 cap, 5 flat — the order of
/// mesh::ShapeClass, names mesh::to_string); triangles "area" (m²) and "min_angle_deg",
/// "max_angle_deg" instead.
std::vector<DataArray> quality_cell_data(const mesh::CellQuality& q);

}  // namespace incise::io
