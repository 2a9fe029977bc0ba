// libFuzzer harness: io::read_medit on arbitrary bytes (a .mesh file). Expected: a ParseError, or a
// mesh that builds a valid connectivity (fuzz_support.hpp); anything else is a finding.

#include <incise/io/read_mesh.hpp>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = incise::fuzz::scratch_path("input.mesh");
  incise::fuzz::write_file(path, data, size);
  incise::fuzz::read_and_check(path,
                               [](const std::string& p) { return incise::io::read_medit(p); });
  return 0;
}
