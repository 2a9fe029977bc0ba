// incise — command-line entry point. Dispatches to subcommands (see commands.hpp).

#include <incise/core/error.hpp>
#include <incise/linalg/blas_threads.hpp>

#include <exception>
#include <iostream>

#include "cli_util.hpp"
#include "commands.hpp"

namespace incise::cli {
namespace {

int version(const Args&, std::ostream& out, std::ostream&) {
  out << "incise " << build_version() << " (commit " << build_commit() << ")\n";
  return 0;
}

// Registered subcommands. Add one line per subcommand family (declared in commands.hpp).
const Command kCommands[] = {
    {"version", "print the version and the commit it was built from", &version},
    {"mesh", "mesh check FILE [--vtu OUT]: load, report quality, validate (7.1)-(7.5)", &run_mesh},
    {"run", "run SCENE [--summary-json PATH] [--progress MODE]: run a scene file (docs/scenes.md)",
     &run_scene_command},
    {"certify",
     "certify [--quick] [--out DIR] [--filter RE] [--data DIR]: run the verification "
     "catalogue, write a report",
     &run_certify_command},
    {"bench",
     "bench [--filter RE] [--out DIR] | --compare A B: run benchmarks, update the dashboard",
     &run_bench_command},
    {"cut", "cut MESH SWEEPS [--out OUT.vtu]: cut along sweep triangles (docs/cutting.md)",
     &run_cut},
};

void usage(std::ostream& os) {
  os << "usage: incise <command> [args...]\n\ncommands:\n";
  for (const auto& c : kCommands) os << "  " << c.name << "\t" << c.summary << "\n";
}

}  // namespace
}  // namespace incise::cli

int main(int argc, char** argv) {
  using namespace incise::cli;
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    usage(argc < 2 ? std::cerr : std::cout);
    return argc < 2 ? 2 : 0;
  }
  const std::string name = argv[1];
  const Args args(argv + 2, argv + argc);
  for (const auto& c : kCommands) {
    if (name == c.name) {
      try {
        // Stop the BLAS workers OpenBLAS started (and left spinning) at load; incise raises
        // the count per call site (blas_threads.hpp, docs/solvers.md "BLAS threads").
        incise::linalg::park_blas_threads();
        return c.run(args, std::cout, std::cerr);
      } catch (const incise::Error& e) {
        std::cerr << "incise " << name << ": " << e.what() << "\n";
        return 1;
      } catch (const std::exception& e) {
        std::cerr << "incise " << name << ": internal error: " << e.what() << "\n";
        return 70;
      }
    }
  }
  std::cerr << "incise: unknown command '" << name << "'\n";
  usage(std::cerr);
  return 2;
}
