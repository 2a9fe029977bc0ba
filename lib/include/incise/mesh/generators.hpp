#pragma once
/// \file generators.hpp
/// Deterministic mesh generators (structured boxes, beams, bricks, cylinders, planar grids).
///
/// Admissible parameters, checked before anything is allocated (GeneratorError otherwise):
/// counts ≥ 1; lengths positive and finite; every cell size (length / count along an axis, for
/// the cylinder radius / rings and length / layers) in [kMinCellSize, kMaxCellSize], so that cell
/// edges, their cubes and cell volumes are normal doubles (the degenerate-cell tests and the
/// element kernels use them); node and cell counts that an Index can number. The counts of a
/// box or cylinder are available before building it (box_size, cylinder_size), for memory
/// budgets.

#include <incise/core/error.hpp>
#include <incise/mesh/mesh_data.hpp>

#include <cstdint>
#include <string>

namespace incise::mesh {

/// Smallest and largest admissible cell size of the generators (m): their cubes, 1e-300 and
/// 1e300, and the smallest cell volumes (≈ 0.1 × 1e-300) are normal doubles.
inline constexpr double kMinCellSize = 1e-100;
inline constexpr double kMaxCellSize = 1e100;

/// A generator parameter outside its admissible range. parameter() names it as the generator's
/// signature does ("nx", "lx", "length", "rings", ...); empty when the error is about several
/// (too many cells for an Index).
class GeneratorError : public ParameterError {
 public:
  GeneratorError(std::string parameter, const std::string& what)
      : ParameterError(what), parameter_(std::move(parameter)) {}
  const std::string& parameter() const { return parameter_; }

 private:
  std::string parameter_;
};

/// Node and cell counts of a generated mesh (64-bit: computed before the Index range is checked).
struct MeshSize {
  std::int64_t points = 0;
  std::int64_t cells = 0;
};

/// How each cube of a structured box is split into tetrahedra.
enum class CubeSplit {
  kSix,   ///< Kuhn/Freudenthal split: 6 tetrahedra around the main diagonal of every cube;
          ///< conforming with identical cubes, all tetrahedra positively oriented.
  kFive,  ///< 5-tetrahedron split (one central tetrahedron) with alternating mirror parity so
          ///< that neighbouring cubes conform.
  kKuhn   ///< reflected Kuhn split: the kSix split of cube (i,j,k) mirrored in x when i is odd,
          ///< in y when j is odd, in z when k is odd, so all main diagonals meet at the corners
          ///< of even parity — the mesh of Maubach's uniform bisection of a Kuhn cube (the
          ///< thesis' level-k cube meshes of §6.9); conforming, all tetrahedra positive.
};

/// Box [0,lx]×[0,ly]×[0,lz] divided into nx×ny×nz cubes (cells), each split into tetrahedra.
/// Node (i,j,k) has index i + (nx+1)*(j + (ny+1)*k). Throws GeneratorError for inadmissible
/// parameters (file comment). Example: the thesis' cantilever (Table 3.1) is
/// make_box(16,4,4, 1.2,0.2,0.3) and finer.
MeshData make_box(int nx, int ny, int nz, double lx, double ly, double lz,
                  CubeSplit split = CubeSplit::kSix);

/// Counts of make_box(nx, ny, nz, lx, ly, lz, split) without building it: (nx+1)(ny+1)(nz+1)
/// points, 6 or 5 cells per cube. Throws GeneratorError as make_box does, except for counts
/// beyond the Index range (which make_box refuses).
MeshSize box_size(int nx, int ny, int nz, double lx, double ly, double lz,
                  CubeSplit split = CubeSplit::kSix);

/// Kuhn cube for tetrahedral bisection (tet_bisection.hpp, thesis §6.9 Fig. 6.13): the cube
/// [0, side]³ divided into n×n×n cubes, each split into 6 tetrahedra around a main diagonal,
/// mirrored from cube to cube (CubeSplit::kKuhn): make_box(n, n, n, side, side, side,
/// CubeSplit::kKuhn), 6n³ tetrahedra (24,576 for n = 16) and (n+1)³ nodes. Throws
/// GeneratorError for inadmissible parameters (file comment).
MeshData make_kuhn_cube(int n, double side);

/// Elongated beam of Yeung, Crouch & Pothen 2016, §4 item (1): nodes on a regular 5×5×h grid
/// (h = 4…1024 in the paper; the largest, h = 1024, has 25,600 nodes and 81,840 elements), i.e.
/// make_box(4, 4, h−1, 4s, 4s, (h−1)s, CubeSplit::kFive) with grid spacing s (m). The paper's
/// element count 81,840 = 4·4·1023·5 shows the 5-tetrahedron split; the paper gives no physical
/// size, so the spacing is a parameter (default 1). The beam axis is z. Requires h ≥ 2 and an
/// admissible spacing (GeneratorError).
MeshData make_beam(int h, double spacing = 1.0);

/// Brick 1×1×2 (x, y, z) of Yeung, Crouch & Pothen 2016, §4 item (2): make_box(n, n, 2n, 1, 1, 2,
/// CubeSplit::kFive). The paper's largest brick (18,081 nodes, 80,000 elements) is n = 20 and
/// its 9,537-node brick is n = 16; the 5-split also reproduces their Fig. 8 (surface node degrees
/// 13 and 5). Requires n ≥ 1.
MeshData make_brick(int n);

/// Cylinder of length `length` along x and radius `radius` (m), built as a structured O-grid:
/// the cross-section disk is `rings` concentric rings (ring k has 6k nodes at radius k·r/rings,
/// triangulated ring to ring by angle order, 6·rings² triangles), extruded in `layers` equal
/// layers; each triangular prism is split into 3 tetrahedra by the smallest-global-index rule of
/// Dompierre et al. (1999), which makes neighbouring prisms conform. Cells: 18·rings²·layers;
/// nodes: (1 + 3·rings·(rings+1))·(layers+1). All cells positively oriented. The volume is that
/// of the inscribed polygonal prism (slightly less than πr²L). Throws GeneratorError for
/// inadmissible parameters (file comment; the cell sizes are radius / rings and length / layers).
MeshData make_cylinder(double length, double radius, int rings, int layers);

/// Counts of make_cylinder(length, radius, rings, layers) without building it. Throws
/// GeneratorError as make_cylinder does, except for counts beyond the Index range.
MeshSize cylinder_size(double length, double radius, int rings, int layers);

/// Coarse cylinder like the thesis' §4.2 small mesh (Table 4.2: length 0.1 m, radius 0.03 m,
/// 1230 elements, 308 nodes, Delaunay): make_cylinder(0.1, 0.03, 3, 8) with 1296 tetrahedra and
/// 333 nodes (structured, not Delaunay; quality in docs/mesh_formats.md and its test).
MeshData make_thesis_cylinder_small();

/// Fine cylinder like the thesis' §4.2 large mesh (Table 4.2: 9300 elements, 1911 nodes):
/// make_cylinder(0.1, 0.03, 5, 21) with 9450 tetrahedra and 2002 nodes.
MeshData make_thesis_cylinder_large();

/// Diagonal of each square of a planar triangle grid.
enum class GridDiagonal {
  kForward,     ///< "/" : from (i,j) to (i+1,j+1)
  kBackward,    ///< "\": from (i+1,j) to (i,j+1)
  kAlternating  ///< "/" when i+j is even, "\" otherwise (union-jack-like pattern)
};

/// Planar triangle mesh (dimension 2) of the rectangle [0,lx]×[0,ly] in the z = 0 plane: nx×ny
/// squares each split into 2 triangles along `diagonal`. Node (i,j) has index i + (nx+1)·j;
/// triangles are counter-clockwise (positive signed xy area). Throws GeneratorError for
/// inadmissible parameters (file comment).
MeshData make_rectangle(int nx, int ny, double lx, double ly,
                        GridDiagonal diagonal = GridDiagonal::kForward);

}  // namespace incise::mesh
