#pragma once
/// \file cli_util.hpp
/// Small helpers shared by the run / certify / bench subcommands.

#include <incise/core/atomic_file.hpp>
#include <incise/core/error.hpp>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

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

/// Output of a shell command (stdout, trailing newline removed), or "" when it fails.
inline std::string command_output(const std::string& command) {
  std::string result;
  FILE* pipe = popen((command + " 2>/dev/null").c_str(), "r");
  if (!pipe) return result;
  std::array<char, 256> buf{};
  while (fgets(buf.data(), static_cast<int>(buf.size()), pipe)) result += buf.data();
  if (pclose(pipe) != 0) return "";
  while (!result.empty() && (result.back() == '\n' || result.back() == '\r')) result.pop_back();
  return result;
}

/// The source tree: the current directory when it holds reference_data/, else the tree this
/// program was configured from (INCISE_SOURCE_DIR, compile definition).
inline std::string source_root() {
  std::error_code ec;
  if (std::filesystem::is_directory("reference_data", ec)) return ".";
#ifdef INCISE_SOURCE_DIR
  return INCISE_SOURCE_DIR;
#else
  return ".";
#endif
}

/// reference_data folder (see source_root); UsageError when it is not found.
inline std::string find_reference_data() {
  const std::string d = source_root() + "/reference_data";
  std::error_code ec;
  if (!std::filesystem::is_directory(d, ec))
    throw UsageError("cannot find reference_data/ (run from the source tree or pass --data DIR)");
  return d;
}

/// Short commit of the source tree, with "-dirty" when it has uncommitted changes to tracked
/// files; "unknown" outside a git checkout.
inline std::string git_commit() {
  const std::string root = source_root();
  std::string c = command_output("git -C '" + root + "' rev-parse --short=10 HEAD");
  if (c.empty()) return "unknown";
  if (!command_output("git -C '" + root + "' status --porcelain --untracked-files=no").empty())
    c += "-dirty";
  return c;
}

}  // namespace incise::cli
