// incise — command-line entry point. Parses the command line with CLI11 (Debian libcli11-dev),
// runs the selected subcommand (commands.hpp) and maps what it throws to the one exit-status
// table (cli_util.hpp Exit, docs/cli.md): CLI11 parse errors 2, and what a command throws by
// report_exception (CommandLineError 2, incise::Error 1, any other exception 70).

#include <incise/core/error.hpp>
#include <incise/linalg/blas_threads.hpp>

#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>
#include <regex>

#include "cli_util.hpp"
#include "commands.hpp"

namespace incise::cli {

void add_vtu_format_option(CLI::App* app, io::VtuEncoding* encoding) {
  app->add_option_function<std::string>(
         "--vtu-format",
         [encoding](const std::string& s) { *encoding = *io::kVtuEncodingNames.find(s); },
         "VTU encoding: binary (raw appended, zlib-compressed; the default) or ascii (text)")
      ->check(CLI::IsMember(io::kVtuEncodingNames.names()))
      ->type_name("FORMAT");
}

namespace {

std::string version_line() {
  return std::string("incise ") + build_version() + " (commit " + build_commit() + ")";
}

/// "incise run", "incise mesh check": the deepest command CLI11 selected.
const CLI::App* selected(const CLI::App& root, std::string& path) {
  const CLI::App* app = &root;
  path = "incise";
  for (auto subs = app->get_subcommands(); !subs.empty(); subs = app->get_subcommands()) {
    app = subs.front();
    path += " " + app->get_name();
  }
  return app;
}

/// A CLI11 parse error as one line: "incise CMD: MESSAGE (see incise CMD --help)". CLI11's
/// "--opt: 1 required TEXT missing" reads "--opt expects a value", "X is required" "missing X".
std::string parse_error_line(const CLI::App& root, const CLI::ParseError& e) {
  std::string path;
  selected(root, path);
  std::string what = e.what();
  std::smatch m;
  if (std::regex_match(what, m, std::regex("(\\S+): [0-9]+ required \\S+ missing")))
    what = m[1].str() + " expects a value";
  else if (std::regex_match(what, m, std::regex("(\\S+) is required")))
    what = "missing " + m[1].str();
  return path + ": " + what + " (see " + path + " --help)";
}

int run_command(const Command& c, const std::string& path, Log& log) {
  Context context{std::cout, log, c.app->remaining()};
  try {
    // Stop the BLAS workers OpenBLAS started (and left spinning) at load; incise raises the
    // count per call site (blas_threads.hpp, docs/solvers.md "BLAS threads").
    incise::linalg::park_blas_threads();
    return c.run(context);
  } catch (...) {
    return report_exception(std::current_exception(), path, log.error());
  }
}

int run_main(int argc, char** argv) {
  CLI::App app(
      "incise: FEM soft-tissue simulation, cutting and needle insertion (thesis-based; "
      "docs/cli.md)",
      "incise");
  // Set before the subcommands are added: they inherit these.
  app.set_help_flag("-h,--help", "print this help and exit");
  app.allow_extras();
  app.footer(exit_status_help());
  app.get_formatter()->column_width(34);

  std::vector<Command> commands;
  CLI::App* version = app.add_subcommand("version",
                                         "print the version and the commit it was "
                                         "built from");
  commands.push_back({version, [](Context& c) {
                        reject_extras(c.extras, "version", [](const std::string& a) {
                          return "unexpected argument '" + a + "'";
                        });
                        c.out << version_line() << "\n";
                        return exit_code(Exit::kOk);
                      }});
  CLI::App* mesh = app.add_subcommand("mesh",
                                      "mesh tools: mesh check FILE loads a mesh, reports "
                                      "its quality and validates (7.1)-(7.5)");
  commands.push_back(add_mesh_check_command(*mesh));
  commands.push_back(add_run_command(app));
  commands.push_back(add_certify_command(app));
  commands.push_back(add_bench_command(app));
  commands.push_back(add_cut_command(app));

  // --version on the program and every subcommand; -q / -v on every command.
  bool quiet = false, verbose = false;
  app.set_version_flag("--version", version_line(), "print the version and exit");
  mesh->set_version_flag("--version", version_line(), "print the version and exit");
  for (const Command& c : commands) {
    c.app->set_version_flag("--version", version_line(), "print the version and exit");
    c.app->add_flag("-q,--quiet", quiet, "nothing on stderr but errors (no progress, no logs)");
    c.app->add_flag("-v,--verbose", verbose, "more detail on stderr (and in some reports)");
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << parse_error_line(app, e) << "\n";
    return exit_code(Exit::kUsage);
  }

  std::string path;
  const CLI::App* leaf = selected(app, path);
  if (quiet && verbose) {
    std::cerr << path << ": -q and -v exclude each other (see " << path << " --help)\n";
    return exit_code(Exit::kUsage);
  }
  Log log(std::cerr, quiet     ? Verbosity::kQuiet
                     : verbose ? Verbosity::kVerbose
                               : Verbosity::kNormal);
  // An argument left over by a group before its subcommand (`incise --frob run ...`) is an
  // error too: the groups allow extras only so that this program words the message.
  std::string group = "incise";
  for (const CLI::App* a = &app; a != leaf; a = a->get_subcommands().front()) {
    const std::vector<std::string> extras = a->remaining();
    if (!extras.empty()) {
      std::cerr << group << ": unknown option '" << extras.front() << "' (see " << group
                << " --help)\n";
      return exit_code(Exit::kUsage);
    }
    group += " " + a->get_subcommands().front()->get_name();
  }
  for (const Command& c : commands)
    if (c.app == leaf) return run_command(c, path, log);

  // No command selected: `incise`, `incise frob`, `incise mesh`, `incise mesh frob`.
  const std::vector<std::string> extras = leaf->remaining();
  if (!extras.empty())
    std::cerr << path << ": unknown " << (leaf == &app ? "command" : "subcommand") << " '"
              << extras.front() << "'\n";
  std::cerr << app.help();
  return exit_code(Exit::kUsage);
}

}  // namespace
}  // namespace incise::cli

int main(int argc, char** argv) {
  try {
    return incise::cli::run_main(argc, argv);
  } catch (...) {
    return incise::cli::report_exception(std::current_exception(), "incise", std::cerr);
  }
}
