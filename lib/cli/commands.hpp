#pragma once
/// \file commands.hpp
/// Subcommands of the `incise` program. Each takes the arguments after its name and returns
/// the process exit code; each prints to the streams it is given (the library never prints).

#include <iosfwd>
#include <string>
#include <vector>

namespace incise::cli {

using Args = std::vector<std::string>;

/// A subcommand: its name, a one-line summary for `incise --help`, and its entry point.
struct Command {
  const char* name;
  const char* summary;
  int (*run)(const Args& args, std::ostream& out, std::ostream& err);
};

/// `incise mesh check FILE [--vtu OUT] [--reorient] [--merge-duplicates]` (lib/cli/mesh.cpp).
int run_mesh(const Args& args, std::ostream& out, std::ostream& err);

/// `incise run SCENE [--summary-json PATH] [--progress MODE]` (lib/cli/run.cpp).
int run_scene_command(const Args& args, std::ostream& out, std::ostream& err);

/// `incise certify [--quick] [--out DIR] [--filter RE]` (lib/cli/certify.cpp).
int run_certify_command(const Args& args, std::ostream& out, std::ostream& err);

/// `incise bench [--filter RE] [--out DIR] [--bin-dir DIR]` (lib/cli/bench.cpp).
int run_bench_command(const Args& args, std::ostream& out, std::ostream& err);

/// `incise cut MESH SWEEPS [--out OUT.vtu] [...]` (lib/cli/cut.cpp): cut along sweep triangles.
int run_cut(const Args& args, std::ostream& out, std::ostream& err);

}  // namespace incise::cli
