// Atomic file writes (core/atomic_file.hpp): the file appears complete under its name, in a
// folder created for it, or not at all.

#include <incise/core/atomic_file.hpp>
#include <incise/core/error.hpp>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

fs::path fresh_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("incise_atomic_file_test_" + name);
  fs::remove_all(dir);
  return dir;
}

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

TEST(AtomicFile, WritesTheTextInANewFolderAndLeavesNoTemporary) {
  const fs::path dir = fresh_dir("text");
  const fs::path f = dir / "sub" / "a.txt";
  incise::write_file_atomic(f.string(), "one\ntwo\n");
  EXPECT_EQ(read(f), "one\ntwo\n");
  incise::write_file_atomic(f.string(), "three\n");  // replaces the old content
  EXPECT_EQ(read(f), "three\n");
  EXPECT_FALSE(fs::exists(f.string() + ".tmp"));
}

TEST(AtomicFile, WriterGetsTheTemporaryPathAndAFailedWriteKeepsTheOldFile) {
  const fs::path dir = fresh_dir("writer");
  const std::string f = (dir / "b.txt").string();
  incise::write_file_atomic(f, "old");
  std::string seen;
  EXPECT_THROW(incise::write_atomically(f,
                                        [&](const std::string& tmp) {
                                          seen = tmp;
                                          throw incise::Error("writer failed");
                                        }),
               incise::Error);
  EXPECT_EQ(seen, f + ".tmp");
  EXPECT_EQ(read(f), "old");
}

}  // namespace
