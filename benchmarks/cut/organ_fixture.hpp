#pragma once
/// \file organ_fixture.hpp
/// Private to the organ_bench executable (benchmarks/cut/organ_*.cpp, issue 17): the liver its
/// benchmarks run on and the helpers they share. The command line of each benchmark is documented
/// beside it; BM_LiverScalpelPath's (the executable's main one) at the top of organ_bench.cpp.

#include <benchmark/benchmark.h>
#include <incise/fixtures/organ_path.hpp>
#include <incise/interactive/refactorization_policy.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/mesh_data.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/refine_uniform.hpp>

#include <cstdint>
#include <string>

namespace incise::bench::organ {

/// The shipped CGAL liver (reference_data/meshes/liver_coarse.mesh scaled by 0.001; 16,597
/// tetrahedra) or the same liver refined once by mesh::refine_uniform (Bey 1995, 132,776
/// tetrahedra); both are read and built once per process, on the first call.
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

/// The scene of the liver path benchmarks (BM_LiverScalpelPath, BM_LiverCutOnly,
/// BM_LiverStrategies) from their first three arguments — refined liver (0/1), blade advance per
/// frame (0.1 mm units), frames — with the liver's scripted path (fixtures/organ_path.hpp) and
/// material. Bound as `const auto& [refined, advance, frames, body, path, material] =
/// LiverPath(state);`.
struct LiverPath {
  explicit LiverPath(const benchmark::State& state)
      : refined(state.range(0) != 0),
        advance(1e-4 * static_cast<double>(state.range(1))),
        frames(static_cast<int>(state.range(2))),
        body(liver(refined)),
        path(incise::fixtures::organ_path(body)),
        material(incise::fixtures::organ_material()) {}
  bool refined;
  double advance;  ///< m per frame
  int frames;
  const incise::mesh::MeshData& body;
  incise::fixtures::OrganPath path;
  incise::material::Material material;
};

/// The automatic §3.6 policy's mode argument: 0 continuous (the default), otherwise break-even
/// (interactive/refactorization_policy.hpp).
inline incise::interactive::RefactorizationMode refactorization_mode(std::int64_t arg) {
  return arg == 0 ? incise::interactive::RefactorizationMode::kContinuous
                  : incise::interactive::RefactorizationMode::kBreakEven;
}

}  // namespace incise::bench::organ
