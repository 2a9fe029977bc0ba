#pragma once
/// \file cli_util.hpp
/// Small helpers shared by the run / certify / bench subcommands.

#include <incise/core/atomic_file.hpp>
#include <incise/core/error.hpp>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

/// Path from the installed program's folder to the installed data (lib/cli/CMakeLists.txt).
#ifndef INCISE_DATA_FROM_BIN
#define INCISE_DATA_FROM_BIN "../share/incise"
#endif

namespace incise::cli {

/// The value after option args[i] (advances i); UsageError when missing.
inline std::string option_value(const std::vector<std::string>& args, std::size_t& i,
                                const std::string& name) {
  if (i + 1 >= args.size()) throw UsageError(name + " expects a value");
  return args[++i];
}

/// `value` parsed as a finite, normal (not subnormal) number > 0, the whole string consumed;
/// UsageError naming the option and the value otherwise ("abc", "1e999", "1e-320", "2x").
inline double positive_number(const std::string& value, const std::string& name) {
  const char* begin = value.c_str();
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(begin, &end);
  if (value.empty() || end != begin + value.size() || errno == ERANGE || !std::isfinite(v) ||
      !(v >= std::numeric_limits<double>::min()))
    throw UsageError(name + " expects a finite number > 0, got '" + value + "'");
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
/// A folder chosen by 1 or 2 must exist (UsageError naming it); otherwise the first of 3 and 4
/// that exists is returned, canonical. UsageError naming every path tried when none does.
inline std::string find_data_dir(const std::string& option) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const char* expected =
      "the incise data folder: reference_data/ of the source tree or <prefix>/share/incise";
  if (!option.empty()) {
    if (!fs::is_directory(option, ec))
      throw UsageError("--data " + option + ": not a folder (expected " + expected + ")");
    return option;
  }
  const char* env = std::getenv("INCISE_DATA_DIR");
  if (env && *env) {
    if (!fs::is_directory(env, ec))
      throw UsageError("INCISE_DATA_DIR=" + std::string(env) + ": not a folder (expected " +
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
  throw UsageError(std::string("cannot find ") + expected + "; tried " + tried +
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
