// libFuzzer harness: scene::parse_scene on arbitrary bytes and, when it accepts them,
// scene::build_scene under a memory budget of 8 MiB (so that the harness explores the builder's
// checks, not large meshes). Mesh file paths resolve against reference_data/fuzz/scene (its
// seeds name ../medit/*.mesh). Expected: a spec and a built scene, or a ParseError (scene errors
// name file, line and JSON path); anything else is a finding.

#include <incise/scene/scene_builder.hpp>
#include <incise/scene/scene_parser.hpp>

#include <string>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string base_dir = std::string(INCISE_SOURCE_DIR) + "/reference_data/fuzz/scene";
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    incise::scene::SceneSpec spec = incise::scene::parse_scene(text, "fuzz.json", base_dir);
    spec.limits.memory_mb = 8;
    (void)incise::scene::build_scene(spec);
  } catch (const incise::ParseError&) {
  }
  return 0;
}
