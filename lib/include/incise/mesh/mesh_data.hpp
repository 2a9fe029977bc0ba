#pragma once
/// \file mesh_data.hpp
/// Plain simplicial mesh arrays: what readers produce, generators create and writers consume.
/// The connectivity structure of thesis ch. 7 (`Connectivity`) is built from these arrays.

#include <incise/core/types.hpp>

#include <vector>

namespace incise::mesh {

/// Cell index matrix: (dimension+1) rows, one column per cell (triangle or tetrahedron).
using CellMatrix = Eigen::Matrix<Index, Eigen::Dynamic, Eigen::Dynamic>;

/// A simplicial mesh as arrays. `dimension` is 2 for triangle meshes (points in the z = 0
/// plane, or a surface in 3D) and 3 for tetrahedral meshes. Positions are reference positions
/// in metres. Positively oriented cells have positive signed volume (3D) / area (2D, in xy).
struct MeshData {
  int dimension = 3;            ///< 2: triangles, 3: tetrahedra
  Eigen::Matrix3Xd points;      ///< 3 × n_points reference positions (m)
  CellMatrix cells;             ///< (dimension+1) × n_cells vertex indices
  std::vector<int> cell_tags;   ///< per-cell label (physical tag); empty when none
  std::vector<int> point_tags;  ///< per-point label; empty when none
  CellMatrix facets;            ///< dimension × n_facets boundary simplices given by a file
  std::vector<int> facet_tags;  ///< per-facet label; empty when none

  Index num_points() const { return static_cast<Index>(points.cols()); }
  Index num_cells() const { return static_cast<Index>(cells.cols()); }
  int vertices_per_cell() const { return dimension + 1; }
};

}  // namespace incise::mesh
