#pragma once
/// \file cli_util.hpp
/// Small helpers shared by the run / certify / bench subcommands.

#include <incise/core/error.hpp>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace incise::cli {

/// The value after option args[i] (advances i); UsageError when missing.
inline std::string option_value(const std::vector<std::string>& args, std::size_t& i,
                                const std::string& name) {
  if (i + 1 >= args.size()) throw UsageError(name + " expects a value");
  return args[++i];
}

/// Writes `text` to `path` through a temporary file renamed into place, creating parent
/// folders; a reader never sees a half-written file. Throws Error on failure.
inline void write_file_atomic(const std::string& path, const std::string& text) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  if (!p.parent_path().empty()) fs::create_directories(p.parent_path());
  const std::string tmp = path + ".tmp";
  {
    std::ofstream o(tmp, std::ios::binary);
    o << text;
    if (!o) throw Error("cannot write " + tmp);
  }
  fs::rename(tmp, p);
}

/// Folder of the running executable (from /proc/self/exe), or "" when unknown.
inline std::string executable_dir() {
  std::error_code ec;
  const auto p = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string() : p.parent_path().string();
}

}  // namespace incise::cli
