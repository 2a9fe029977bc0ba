#include <incise/core/atomic_file.hpp>
#include <incise/core/error.hpp>

#include <filesystem>
#include <fstream>

namespace incise {

void write_atomically(const std::string& path,
                      const std::function<void(const std::string& tmp_path)>& write) {
  namespace fs = std::filesystem;
  const fs::path p(path);
  if (!p.parent_path().empty()) fs::create_directories(p.parent_path());
  const std::string tmp = path + ".tmp";
  write(tmp);
  fs::rename(tmp, p);
}

void write_file_atomic(const std::string& path, const std::string& text) {
  write_atomically(path, [&text](const std::string& tmp) {
    std::ofstream o(tmp, std::ios::binary);
    o << text;
    if (!o) throw Error("cannot write " + tmp);
  });
}

}  // namespace incise
