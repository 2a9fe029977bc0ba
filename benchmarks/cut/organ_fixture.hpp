#pragma once
/// \file organ_fixture.hpp
/// Private to the organ_bench executable (benchmarks/cut/organ_*.cpp, issue 17): the liver its
/// benchmarks run on and the helpers they share. The command line of each benchmark is documented
/// beside it; BM_LiverScalpelPath's (the executable's main one) at the top of organ_bench.cpp.

#include <incise/io/read_mesh.hpp>
#include <incise/mesh/mesh_data.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/refine_uniform.hpp>

#include <string>

namespace incise::bench::organ {

/// The shipped CGAL liver (reference_data/meshes/liver_coarse.mesh, mm → m; 16,597 tetrahedra) or
/// the same liver refined once by mesh::refine_uniform (Bey 1995, 132,776 tetrahedra); both are
/// read and built once per process, on the first call.
inline const incise::mesh::MeshData& liver(bool refined) {
  static const incise::mesh::MeshData coarse = [] {
    incise::io::ReadOptions o;
    o.scale = 0.001;
    return incise::io::read_mesh(
               std::string(INCISE_SOURCE_DIR) + "/reference_data/meshes/liver_coarse.mesh", o)
        .mesh;
  }();
  static const incise::mesh::MeshData fine = incise::mesh::refine_uniform(coarse);
  return refined ? fine : coarse;
}

/// Median, 95th percentile (nearest rank) and maximum: mesh::summarize.
using incise::mesh::summarize;

}  // namespace incise::bench::organ
