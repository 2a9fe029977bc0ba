#pragma once
// Helpers for the io tests: temporary files and ParseError expectations.

#include <gtest/gtest.h>
#include <incise/core/error.hpp>
#include <incise/io/read_mesh.hpp>

#include <unistd.h>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace incise::io::test {

/// Directory for test files: /dev/shm when present (the fuzz test rewrites files hundreds of
/// times; on a disk that costs milliseconds each), else the gtest temp directory.
inline std::string temp_dir() {
  static const std::string dir =
      ::access("/dev/shm", W_OK) == 0 ? std::string("/dev/shm/") : ::testing::TempDir();
  return dir;
}

/// Removes every file handed out by write_temp/temp_path (and base.node/base.ele) at exit.
class TempFiles {
 public:
  static TempFiles& instance() {
    static TempFiles t;
    return t;
  }
  void add(const std::string& p) { paths_.push_back(p); }
  ~TempFiles() {
    for (const auto& p : paths_)
      for (const char* ext : {"", ".node", ".ele"}) std::remove((p + ext).c_str());
  }

 private:
  std::vector<std::string> paths_;
};

/// Writes `content` to a fresh file named `name` in the test temp directory; returns its path.
inline std::string write_temp(const std::string& name, const std::string& content) {
  const std::string path = temp_dir() + "incise_io_" + std::to_string(::getpid()) + "_" + name;
  TempFiles::instance().add(path);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << content;
  return path;
}

/// Temp path (not created) for writers.
inline std::string temp_path(const std::string& name) {
  const std::string path = temp_dir() + "incise_io_" + std::to_string(::getpid()) + "_" + name;
  TempFiles::instance().add(path);
  return path;
}

/// Expects read_mesh(path) to throw ParseError at `line` whose message contains `fragment`.
inline void expect_parse_error(const std::string& path, long line, const std::string& fragment,
                               const ReadOptions& options = {}) {
  try {
    (void)read_mesh(path, options);
    ADD_FAILURE() << "no ParseError for " << path;
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file().substr(e.file().size() - 4), path.substr(path.size() - 4));
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(e.message().find(fragment), std::string::npos)
        << "message '" << e.message() << "' lacks '" << fragment << "'";
    // what() is "FILE:LINE: MESSAGE" (one line).
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos);
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type for " << path << ": " << e.what();
  }
}

}  // namespace incise::io::test
