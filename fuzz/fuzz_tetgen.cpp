// libFuzzer harness: io::read_tetgen on arbitrary bytes. The input is split at its first line
// "#@ele" into the .node part and the .ele part (no marker: all .node, an empty .ele); '#'
// starts a TetGen comment, so the marker is a comment wherever else it lands. Expected: a
// ParseError, or a mesh that builds a valid connectivity (fuzz_support.hpp).

#include <incise/io/read_mesh.hpp>

#include <string_view>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string base = incise::fuzz::scratch_path("input");
  const std::string_view in(reinterpret_cast<const char*>(data), size);
  constexpr std::string_view kMarker = "#@ele\n";
  const std::size_t at = in.find(kMarker);
  const std::string_view node = in.substr(0, at);
  const std::string_view ele = at == std::string_view::npos ? "" : in.substr(at + kMarker.size());
  incise::fuzz::write_file(base + ".node", reinterpret_cast<const std::uint8_t*>(node.data()),
                           node.size());
  incise::fuzz::write_file(base + ".ele", reinterpret_cast<const std::uint8_t*>(ele.data()),
                           ele.size());
  incise::fuzz::read_and_check(base,
                               [](const std::string& p) { return incise::io::read_tetgen(p); });
  return 0;
}
