#include <incise/core/atomic_file.hpp>
#include <incise/core/error.hpp>
#include <incise/scene/solution_file.hpp>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <vector>

namespace incise::scene {

namespace {
const char* const kHeader = "# incise solution: ";
}

void write_solution(const std::string& path, const VecX& u) {
  INCISE_CHECK_PARAM(u.allFinite(), "write_solution: the solution has non-finite entries");
  std::string text =
      std::string(kHeader) + std::to_string(u.size()) + " values (displacement per DOF, m)\n";
  text.reserve(text.size() + static_cast<std::size_t>(u.size()) * 25);
  char buf[40];
  for (Eigen::Index i = 0; i < u.size(); ++i) {
    // 17 significant digits (printf's %.17g): every double reads back bitwise.
    const auto r = std::to_chars(buf, buf + sizeof buf, u[i], std::chars_format::general, 17);
    text.append(buf, r.ptr);
    text += '\n';
  }
  write_file_atomic(path, text);
}

VecX read_solution(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ParseError(path, 0, "cannot open the solution file");
  std::string line;
  long n_expected = -1;
  if (std::getline(in, line) && line.rfind(kHeader, 0) == 0) {
    const std::string rest = line.substr(std::string(kHeader).size());
    char* end = nullptr;
    errno = 0;
    n_expected = std::strtol(rest.c_str(), &end, 10);
    if (end == rest.c_str() || errno != 0 || n_expected < 0) n_expected = -1;
  }
  if (n_expected < 0)
    throw ParseError(path, 1,
                     std::string("expected the header '") + kHeader +
                         "N values ...' of a file written by incise run --write-solution");
  std::vector<double> v;
  v.reserve(static_cast<std::size_t>(n_expected));
  long line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(line.c_str(), &end);
    if (end == line.c_str() || *end != '\0' || errno == ERANGE || !std::isfinite(x))
      throw ParseError(path, line_no, "expected one finite number, got '" + line + "'");
    v.push_back(x);
  }
  if (static_cast<long>(v.size()) != n_expected)
    throw ParseError(path, line_no,
                     "the header announces " + std::to_string(n_expected) +
                         " values, the file has " + std::to_string(v.size()));
  return Eigen::Map<const VecX>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace incise::scene
