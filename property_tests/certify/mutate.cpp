// incise_mutate SPEC SOURCE OUTPUT: writes SOURCE with the one mutation SPEC describes to OUTPUT
// (the certify mutation test, docs/certify.md). SPEC (mutations/<id>.mutation): '#' comment
// lines, a line "file: <path in the source tree>", then
//   <<<<<<< find
//   exact lines of SOURCE
//   =======
//   their replacement
//   >>>>>>> replace
// The find text must occur exactly once in SOURCE; otherwise nothing is written and the exit
// status is 1 with the reason (the library changed under the mutation: update the spec).
// OUTPUT is rewritten only when its content changes, so a rebuild recompiles only real changes.

#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

namespace {

bool read_file(const std::string& path, std::string& out) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  std::ostringstream os;
  os << in.rdbuf();
  out = os.str();
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 4) {
    std::cerr << "usage: incise_mutate SPEC SOURCE OUTPUT\n";
    return 2;
  }
  const std::string spec_path = argv[1], source_path = argv[2], output_path = argv[3];
  std::string spec, source;
  if (!read_file(spec_path, spec)) {
    std::cerr << "incise_mutate: cannot read " << spec_path << "\n";
    return 1;
  }
  if (!read_file(source_path, source)) {
    std::cerr << "incise_mutate: cannot read " << source_path << "\n";
    return 1;
  }
  enum class Part { kHeader, kFind, kReplace, kDone } part = Part::kHeader;
  std::string find, replace;
  std::istringstream lines(spec);
  std::string line;
  while (std::getline(lines, line)) {
    if (part == Part::kHeader && line == "<<<<<<< find") {
      part = Part::kFind;
    } else if (part == Part::kFind && line == "=======") {
      part = Part::kReplace;
    } else if (part == Part::kReplace && line == ">>>>>>> replace") {
      part = Part::kDone;
    } else if (part == Part::kFind) {
      find += line + "\n";
    } else if (part == Part::kReplace) {
      replace += line + "\n";
    }
  }
  if (part != Part::kDone || find.empty()) {
    std::cerr << spec_path << ": expected a find block and a replace block\n";
    return 1;
  }
  const std::size_t at = source.find(find);
  if (at == std::string::npos || source.find(find, at + 1) != std::string::npos) {
    std::cerr << spec_path << ": the find text occurs "
              << (at == std::string::npos ? "nowhere" : "more than once") << " in " << source_path
              << "; the library changed under this mutation, update the spec\n";
    return 1;
  }
  const std::string mutated = source.substr(0, at) + replace + source.substr(at + find.size());
  std::string old;
  if (read_file(output_path, old) && old == mutated) return 0;
  std::ofstream out(output_path, std::ios::binary);
  out << mutated;
  if (!out) {
    std::cerr << "incise_mutate: cannot write " << output_path << "\n";
    return 1;
  }
  return 0;
}
