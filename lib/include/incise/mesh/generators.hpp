#pragma once
/// \file generators.hpp
/// Deterministic mesh generators (structured boxes, beams, bricks, cylinders, planar grids).

#include <incise/mesh/mesh_data.hpp>

namespace incise::mesh {

/// How each cube of a structured box is split into tetrahedra.
enum class CubeSplit {
  kSix,  ///< Kuhn/Freudenthal split: 6 tetrahedra around the main diagonal of every cube;
         ///< conforming with identical cubes, all tetrahedra positively oriented.
  kFive  ///< 5-tetrahedron split (one central tetrahedron) with alternating mirror parity so
         ///< that neighbouring cubes conform.
};

/// Box [0,lx]×[0,ly]×[0,lz] divided into nx×ny×nz cubes (cells), each split into tetrahedra.
/// Node (i,j,k) has index i + (nx+1)*(j + (ny+1)*k). Throws ParameterError for n < 1 or l ≤ 0.
/// Example: the thesis' cantilever (Table 3.1) is make_box(16,4,4, 1.2,0.2,0.3) and finer.
MeshData make_box(int nx, int ny, int nz, double lx, double ly, double lz,
                  CubeSplit split = CubeSplit::kSix);

}  // namespace incise::mesh
