#pragma once
/// \file slab2d.hpp
/// The 2D slabs of thesis §6.5 and §6.8: rectangles meshed with regularly arranged
/// right-angled (right isosceles) triangles, the starting meshes of edge bisection
/// (mesh/bisection.hpp).

#include <incise/mesh/mesh_data.hpp>

namespace incise::mesh {

/// The thesis' grid spacing h_k = 0.1 m · 2⁻ᵏ (§6.8, h1 … h7). Throws ParameterError unless
/// 1 ≤ k ≤ 7.
double thesis_slab_spacing(int k);

/// Rectangle [0, lx]×[0, ly] (m, z = 0 plane) of squares of side h, each split along its
/// diagonal into two right isosceles triangles, the diagonals alternating ("union jack",
/// make_rectangle's GridDiagonal::kAlternating), counter-clockwise. Every triangle's
/// hypotenuse is shared with the other triangle of its square or lies on the boundary, so the
/// mesh is compatibly divisible for bisect(). Throws ParameterError when lx, ly or h is not
/// finite and > 0, or lx/h, ly/h is not an integer to 1e-9 relative.
MeshData make_right_triangle_slab(double lx, double ly, double h);

/// The thesis' square slab 0.1 × 0.1 m at spacing h_k (make_right_triangle_slab(0.1, 0.1,
/// thesis_slab_spacing(k))): 2·4ᵏ triangles.
MeshData make_thesis_slab(int k);

}  // namespace incise::mesh
