// libFuzzer harness: io::read_sweep_file on arbitrary bytes. Expected: the events or a
// ParseError; anything else is a finding. Accepted events have finite corners.

#include <incise/io/sweep_file.hpp>

#include <cmath>

#include "fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = incise::fuzz::scratch_path("input.sweep");
  incise::fuzz::write_file(path, data, size);
  try {
    for (const incise::io::SweepEvent& ev : incise::io::read_sweep_file(path))
      for (const incise::Vec3& p : ev.triangle)
        if (!p.allFinite()) incise::fuzz::finding("accepted sweep event with a non-finite corner");
  } catch (const incise::ParseError&) {
  }
  return 0;
}
