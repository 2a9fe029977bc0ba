#pragma once
/// \file cli_util.hpp
/// Small helpers shared by the subcommands: the exit statuses, the errors that select them, the
/// log (stderr) with its verbosity, option-value checks and the data folder lookup.

#include <incise/core/atomic_file.hpp>
#include <incise/core/error.hpp>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

/// Path from the installed program's folder to the installed data (lib/cli/CMakeLists.txt).
#ifndef INCISE_DATA_FROM_BIN
#define INCISE_DATA_FROM_BIN "../share/incise"
#endif

namespace incise::cli {

/// The exit status of every `incise` command: the one table (docs/cli.md, "Exit status"; tested
/// by the cli_exit_* tests).
enum class Exit : int {
  kOk = 0,                ///< the command did what was asked
  kBadInput = 1,          ///< a file, folder or scene that is unreadable or invalid
  kUsage = 2,             ///< unknown command or option, missing or extra argument, bad value
  kNumericalFailure = 3,  ///< no convergence, inversion, non-finite values, a check out of band
  kInternal = 70,         ///< an unexpected exception (a bug: please report it)
};

/// The process exit code of `e`.
constexpr int exit_code(Exit e) {
  return static_cast<int>(e);
}

/// The exit-status table as printed at the end of every `--help`.
inline const char* exit_status_help() {
  return "exit status: 0 ok, 1 bad input (unreadable or invalid file, folder or scene), 2 usage\n"
         "(unknown option, missing or extra argument, bad option value), 3 numerical failure (no\n"
         "convergence, inversion, non-finite values, a check out of its band), 70 internal error";
}

/// A command line the program cannot run (a bad option value, an extra argument, options that
/// exclude each other): printed as "incise CMD: MESSAGE", exit Exit::kUsage.
class CommandLineError : public std::runtime_error {
 public:
  explicit CommandLineError(const std::string& what) : std::runtime_error(what) {}
};

/// Bad input found by the program itself (a folder that is not one, a file of the wrong kind):
/// exit Exit::kBadInput, like every incise::Error the library throws on a bad file or scene.
class BadInputError : public incise::Error {
 public:
  explicit BadInputError(const std::string& what) : incise::Error(what) {}
};

/// The exit status of an exception a command threw, its one line "PATH: MESSAGE" written to
/// `err` (PATH: "incise run", ...): CommandLineError Exit::kUsage; incise::Error (a bad file,
/// folder or scene: ParseError, ParameterError, the library's UsageError, BadInputError)
/// Exit::kBadInput; any other exception Exit::kInternal, as "PATH: internal error: MESSAGE".
inline int report_exception(const std::exception_ptr& e, const std::string& path,
                            std::ostream& err) {
  try {
    std::rethrow_exception(e);
  } catch (const CommandLineError& x) {
    err << path << ": " << x.what() << "\n";
    return exit_code(Exit::kUsage);
  } catch (const incise::Error& x) {
    err << path << ": " << x.what() << "\n";
    return exit_code(Exit::kBadInput);
  } catch (const std::exception& x) {
    err << path << ": internal error: " << x.what() << "\n";
  } catch (...) {
    err << path << ": internal error: an exception of unknown type\n";
  }
  return exit_code(Exit::kInternal);
}

/// How much goes to stderr besides errors: -q nothing, -v also the details.
enum class Verbosity { kQuiet, kNormal, kVerbose };

/// stderr of a command, by verbosity: errors always; progress and logs (info) unless -q;
/// details only with -v. Results go to stdout, never here.
class Log {
 public:
  Log(std::ostream& err, Verbosity verbosity) : err_(err), verbosity_(verbosity), null_(nullptr) {}
  std::ostream& error() { return err_; }
  std::ostream& info() { return verbosity_ == Verbosity::kQuiet ? null_ : err_; }
  std::ostream& detail() { return verbosity_ == Verbosity::kVerbose ? err_ : null_; }
  Verbosity verbosity() const { return verbosity_; }

 private:
  std::ostream& err_;
  Verbosity verbosity_;
  std::ostream null_;  // no buffer: writes are dropped
};

/// Arguments CLI11 did not take (unknown options, surplus positionals) are usage errors:
/// CommandLineError "unknown option 'X' (see incise CMD --help)" for one starting with '-',
/// else `surplus(X)` (e.g. "more than one FILE given").
template <class Surplus>
void reject_extras(const std::vector<std::string>& extras, const std::string& command,
                   Surplus surplus) {
  for (const std::string& a : extras)
    if (a.size() > 1 && a[0] == '-')
      throw CommandLineError("unknown option '" + a + "' (see incise " + command + " --help)");
  if (!extras.empty()) throw CommandLineError(surplus(extras.front()));
}

/// `value` parsed as a finite, normal (not subnormal) number > 0, the whole string consumed;
/// CommandLineError naming the option and the value otherwise ("abc", "1e999", "1e-320", "2x").
inline double positive_number(const std::string& value, const std::string& name) {
  const char* begin = value.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(begin, &end);
  if (value.empty() || end != begin + value.size() || errno == ERANGE || !std::isfinite(v) ||
      !(v >= std::numeric_limits<double>::min()))
    throw CommandLineError(name + " expects a finite number > 0, got '" + value + "'");
  return v;
}

/// Atomic file writes (core/atomic_file.hpp), for the subcommands.
using incise::write_file_atomic;

/// Folder of the running executable (from /proc/self/exe), or "" when unknown.
inline std::string executable_dir() {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : p.parent_path().string();
}

/// The data folder (the source tree's reference_data/, or <prefix>/share/incise when
/// installed), looked up in this order (docs/install.md, "Where incise finds its data"):
///   1. `option` (the --data DIR option) when not empty;
///   2. the environment variable INCISE_DATA_DIR when set and not empty;
///   3. <folder of the program>/reference_data: in a build tree, a link to the source tree's
///      reference_data made by lib/cli/CMakeLists.txt;
///   4. <folder of the program>/INCISE_DATA_FROM_BIN (compile definition, default
///      ../share/incise): an installed program, <prefix>/bin/incise → <prefix>/share/incise.
/// A folder chosen by 1 or 2 must exist (BadInputError naming it); otherwise the first of 3 and
/// 4 that exists is returned, canonical. BadInputError naming every path tried when none does.
inline std::string find_data_dir(const std::string& option) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const char* expected =
      "the incise data folder: reference_data/ of the source tree or <prefix>/share/incise";
  if (!option.empty()) {
    if (!fs::is_directory(option, ec))
      throw BadInputError("--data " + option + ": not a folder (expected " + expected + ")");
    return option;
  }
  const char* env = std::getenv("INCISE_DATA_DIR");
  if (env && *env) {
    if (!fs::is_directory(env, ec))
      throw BadInputError("INCISE_DATA_DIR=" + std::string(env) + ": not a folder (expected " +
                          expected + ")");
    return env;
  }
  std::string tried = "--data (not given), INCISE_DATA_DIR (not set)";
  const std::string exe = executable_dir();
  if (exe.empty()) {
    tried += ", the program's folder (/proc/self/exe unreadable)";
  } else {
    const fs::path candidates[] = {fs::path(exe) / "reference_data",
                                   fs::path(exe) / INCISE_DATA_FROM_BIN};
    for (const fs::path& c : candidates) {
      const fs::path p = c.lexically_normal();
      if (fs::is_directory(p, ec)) {
        const fs::path canonical = fs::canonical(p, ec);
        return ec ? p.string() : canonical.string();
      }
      tried += ", " + p.string();
    }
  }
  throw BadInputError(std::string("cannot find ") + expected + "; tried " + tried +
                      " (pass --data DIR or set INCISE_DATA_DIR)");
}

/// The project version (CMakeLists.txt project(VERSION)).
const char* build_version();

/// Short commit of the source tree this program was built from, with "-dirty" when it had
/// uncommitted changes to tracked files at build time; "unknown" when it was not built from a
/// git checkout (lib/cli/build_info.cmake, regenerated on every build).
const char* build_commit();

/// build_commit() (the name the subcommands use).
inline std::string git_commit() {
  return build_commit();
}

}  // namespace incise::cli
