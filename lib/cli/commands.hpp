#pragma once
/// \file commands.hpp
/// Subcommands of the `incise` program, parsed by CLI11 (main.cpp). Each `add_*` function
/// registers one command's options on a CLI11 App and returns the command: its App and the
/// action main.cpp runs after parsing. An action prints results to Context::out (stdout) and
/// progress, logs and errors through Context::log (stderr), and returns an exit status
/// (cli_util.hpp Exit); it throws CommandLineError on a bad command line, incise::Error on bad
/// input (the library never prints).

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

#include <incise/io/write_mesh.hpp>

#include "cli_util.hpp"

namespace CLI {
class App;
}  // namespace CLI

namespace incise::cli {

/// What a command's action gets.
struct Context {
  std::ostream& out;                ///< results (stdout)
  Log& log;                         ///< progress, logs, errors (stderr), by -q / -v
  std::vector<std::string> extras;  ///< arguments CLI11 did not take (reject_extras)
};

/// A registered command: its CLI11 App (owned by the parent App) and its action.
struct Command {
  CLI::App* app = nullptr;
  std::function<int(Context&)> run;
};

/// Adds `--vtu-format binary|ascii` (io::kVtuEncodingNames; default binary: raw appended,
/// zlib-compressed) to `app`, writing the choice to `*encoding` (main.cpp).
void add_vtu_format_option(CLI::App* app, io::VtuEncoding* encoding);

/// `incise mesh check FILE [--json] [--vtu OUT] ...` on `mesh` (lib/cli/mesh.cpp).
Command add_mesh_check_command(CLI::App& mesh);

/// `incise run SCENE [--summary-json PATH] [--progress MODE] ...` (lib/cli/run.cpp).
Command add_run_command(CLI::App& root);

/// `incise certify [--quick] [--out DIR] [--filter RE] [--junit FILE] ...` (lib/cli/certify.cpp).
Command add_certify_command(CLI::App& root);

/// `incise bench [--filter RE] [--out DIR] ... | --compare A B` (lib/cli/bench.cpp).
Command add_bench_command(CLI::App& root);

/// `incise cut MESH SWEEPS [--out OUT.vtu] ...` (lib/cli/cut.cpp): cut along sweep triangles.
Command add_cut_command(CLI::App& root);

}  // namespace incise::cli
