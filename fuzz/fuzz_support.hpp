#pragma once
// Shared by the libFuzzer harnesses (docs/bad_input.md, "Fuzzing"): the input written to a file
// the public readers can open, and the checks every accepted mesh must pass.

#include <incise/core/error.hpp>
#include <incise/io/read_mesh.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/validate.hpp>

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace incise::fuzz {

/// Path of a per-process scratch file `name` (in /dev/shm when writable: the harnesses rewrite
/// it on every execution).
inline std::string scratch_path(const std::string& name) {
  static const std::string dir = ::access("/dev/shm", W_OK) == 0 ? "/dev/shm/" : "/tmp/";
  return dir + "incise_fuzz_" + std::to_string(::getpid()) + "_" + name;
}

/// Writes bytes [data, data + size) to `path` (truncating it).
inline void write_file(const std::string& path, const std::uint8_t* data, std::size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
}

/// Aborts (a finding) with `what` on stderr.
[[noreturn]] inline void finding(const std::string& what) {
  std::fprintf(stderr, "incise fuzz finding: %s\n", what.c_str());
  std::abort();
}

/// Reads `path` with `read`; a ParseError is the expected refusal. A mesh the reader accepts
/// must build a Connectivity that validate() accepts (read_mesh.hpp's contract); anything else
/// thrown is a finding.
template <class Reader>
void read_and_check(const std::string& path, Reader&& read) {
  io::LoadedMesh loaded;
  try {
    loaded = read(path);
  } catch (const ParseError&) {
    return;
  }
  const mesh::MeshData& m = loaded.mesh;
  mesh::Connectivity conn(m.dimension);
  try {
    conn = mesh::Connectivity::from_mesh_data(m);
  } catch (const std::exception& e) {
    finding(std::string("accepted mesh builds no connectivity: ") + e.what());
  }
  mesh::ValidateOptions vo;
  if (!loaded.report.surface) vo.positions = &m.points;
  const mesh::ValidationReport v = mesh::validate(conn, vo);
  if (!v.ok()) finding("accepted mesh fails validate(): " + v.summary(3));
}

}  // namespace incise::fuzz
