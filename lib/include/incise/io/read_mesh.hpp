#pragma once
/// \file read_mesh.hpp
/// Mesh readers: Gmsh `.msh` 2.2 and 4.1 ASCII, Medit `.mesh`, TetGen `.node`/`.ele`, OFF
/// triangle surfaces. Every reader produces a MeshData plus a LoadReport of what it found.
///
/// Bad input throws incise::ParseError(file, line, "expected ...") — truncated files, bad
/// numbers, NaN/inf coordinates, indices out of range, unsupported element types, repeated
/// vertices in a cell, duplicate cells, degenerate (zero-volume) cells, inverted cells and
/// inconsistently oriented surfaces (unless ReadOptions::reorient), faces shared by more than two
/// cells or by two on the same side (thesis invariant 7.4), data after the declared records.
/// Nothing in a file can crash the reader, and every mesh it returns builds a
/// mesh::Connectivity. The accepted
/// syntax of each format, the checks and the options are documented in docs/mesh_formats.md.

#include <incise/mesh/mesh_data.hpp>

#include <map>
#include <string>
#include <vector>

namespace incise::io {

/// File formats known to read_mesh.
enum class MeshFormat {
  kAuto,    ///< by extension: .msh, .mesh, .node/.ele, .off
  kGmsh,    ///< Gmsh .msh, ASCII versions 2.2 and 4.1
  kMedit,   ///< Medit/INRIA .mesh (ASCII)
  kTetGen,  ///< TetGen .node + .ele (same base name)
  kOff      ///< Object File Format, triangle faces only
};

/// Options of every reader.
struct ReadOptions {
  /// Flip inverted cells (negative signed volume, or negative xy area for planar triangle
  /// meshes) by swapping their last two vertices, and count them in LoadReport::reoriented;
  /// orient each connected part of a surface in 3D like its first triangle (flips counted too).
  /// When false an inverted cell, or two neighbouring surface triangles traversing their common
  /// edge in the same direction, is a ParseError.
  bool reorient = false;
  /// A cell is degenerate (ParseError) when |6√2·V| ≤ tol·ℓ_max³ (tetrahedra) or
  /// |4/√3·A| ≤ tol·ℓ_max² (triangles), i.e. its volume relative to the regular cell with the
  /// same longest edge is at most tol. Default: round-off level flatness.
  double degenerate_tolerance = 1e-12;
  /// Merge vertices with bitwise identical coordinates (first occurrence kept; cells are
  /// renumbered; unused vertices are kept). When false duplicates are only reported.
  bool merge_duplicate_vertices = false;
  /// Split pinched vertices (star not face-connected, thesis §7.3) with
  /// mesh::split_pinched_vertices and report them; when false they are left for validate()
  /// to reject ("connected-star"). On by default: the data structure of ch. 7 cannot represent
  /// them, and real meshes have them (the liver has two).
  bool split_pinched_vertices = true;
  /// Factor applied to every coordinate after reading (e.g. 0.001 for files in millimetres;
  /// incise works in metres). Must be positive and finite.
  double scale = 1.0;
};

/// What a reader found in a file.
struct LoadReport {
  std::string file;            ///< path as given
  std::string format;          ///< e.g. "gmsh 4.1", "medit 1", "tetgen", "off"
  Index num_points = 0;        ///< vertices in the returned mesh
  Index num_cells = 0;         ///< tetrahedra (dimension 3) or triangles (dimension 2)
  Index num_facets = 0;        ///< boundary triangles given by the file (dimension 3 only)
  Index ignored_elements = 0;  ///< points, lines, edges and other lower-dimensional records
  bool surface = false;        ///< dimension-2 mesh not contained in the plane z = const
  Index reoriented = 0;        ///< cells flipped: inverted, or surface triangles (reorient option)
  Index duplicate_vertices = 0;  ///< vertices whose coordinates equal an earlier vertex's
  Index merged_vertices = 0;     ///< of those, merged (merge_duplicate_vertices option)
  Index unused_vertices = 0;     ///< vertices referenced by no cell
  Index pinched_vertices = 0;    ///< vertices split because their star was not connected
  Index added_vertices = 0;      ///< new vertices appended by that split
  /// Facets (boundary triangles of a tetrahedral file) whose vertex set repeats an earlier
  /// facet's; kept as listed (CGAL's Medit output lists each facet once per incident side).
  Index duplicate_facets = 0;
  Index opposite_facets = 0;         ///< of those, with the opposite orientation of the earlier one
  std::map<int, Index> cell_labels;  ///< cell tag → number of cells
  std::map<int, Index> facet_labels;          ///< facet tag → number of facets
  std::map<int, Index> point_labels;          ///< point tag → number of points
  std::map<int, std::string> physical_names;  ///< Gmsh $PhysicalNames (tag → name)
  /// Human-readable findings, one sentence each (duplicates, unused vertices, reorientations
  /// with the first few cell numbers, ignored records).
  std::vector<std::string> notes;
};

/// A mesh and what its reader found.
struct LoadedMesh {
  mesh::MeshData mesh;
  LoadReport report;
};

/// Reads a mesh, choosing the reader by `format` (or by extension for kAuto: .msh → Gmsh,
/// .mesh → Medit, .node/.ele → TetGen (both files must exist), .off → OFF). Throws
/// ParseError for unreadable or malformed files and for unknown extensions.
LoadedMesh read_mesh(const std::string& path, const ReadOptions& options = {},
                     MeshFormat format = MeshFormat::kAuto);

/// Gmsh .msh ASCII 2.2 or 4.1: $MeshFormat, optional $PhysicalNames and $Entities (4.1),
/// $Nodes, $Elements; other sections are skipped. Tetrahedra (type 4) become cells and
/// triangles (type 2) facets; a file without tetrahedra gives a triangle mesh. Points (15) and
/// lines (1) are ignored; any other element type is an error. Cell tags are physical tags
/// (2.2: first tag; 4.1: first physical tag of the element's entity; 0 when none).
LoadedMesh read_gmsh(const std::string& path, const ReadOptions& options = {});

/// Medit .mesh ASCII (MeshVersionFormatted 1|2, Dimension 2|3, Vertices, Triangles,
/// Tetrahedra, plus Edges, Corners, Ridges, Required*, Normals, Tangents… which are skipped);
/// 1-based indices, last integer of each record is its reference (label).
LoadedMesh read_medit(const std::string& path, const ReadOptions& options = {});

/// TetGen .node + .ele pair; `path` may name either file or the common base. Indices may start
/// at 0 or 1 (taken from the first .node record); the first .ele attribute (region) is the
/// cell tag, the .node boundary marker the point tag. Only 4-node tetrahedra are accepted.
LoadedMesh read_tetgen(const std::string& path, const ReadOptions& options = {});

/// OFF (Object File Format) surface: "OFF", counts, vertices, faces "3 i j k [colour]".
/// Faces with other than 3 vertices and data after the declared faces are errors. Result has
/// dimension 2.
LoadedMesh read_off(const std::string& path, const ReadOptions& options = {});

}  // namespace incise::io
