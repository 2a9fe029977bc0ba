#include "incise_test/seed.hpp"

#include <cstdlib>

namespace incise::test {

std::uint64_t seed(std::uint64_t default_seed) {
  if (const char* s = std::getenv("INCISE_SEED"); s != nullptr && *s != '\0')
    return std::strtoull(s, nullptr, 10);
  return default_seed;
}

std::string source_path(const std::string& relative) {
  const char* root = std::getenv("INCISE_SOURCE_DIR");
  std::string base = (root != nullptr && *root != '\0') ? root : INCISE_DEFAULT_SOURCE_DIR;
  return base + "/" + relative;
}

bool env_set(const char* name) {
  return std::getenv(name) != nullptr;
}

int scaled(int n) {
  double scale = 1.0;
  if (const char* s = std::getenv("INCISE_TEST_SCALE"); s != nullptr && *s != '\0')
    scale = std::strtod(s, nullptr);
  const int r = static_cast<int>(n * scale);
  return r < 1 ? 1 : r;
}

}  // namespace incise::test
