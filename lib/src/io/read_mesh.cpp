#include <incise/core/error.hpp>
#include <incise/io/read_mesh.hpp>

#include <algorithm>
#include <cctype>

namespace incise::io {

namespace {

std::string extension(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string e = path.substr(dot + 1);
  std::transform(e.begin(), e.end(), e.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e;
}

}  // namespace

LoadedMesh read_mesh(const std::string& path, const ReadOptions& options, MeshFormat format) {
  if (format == MeshFormat::kAuto) {
    const std::string e = extension(path);
    if (e == "msh")
      format = MeshFormat::kGmsh;
    else if (e == "mesh")
      format = MeshFormat::kMedit;
    else if (e == "node" || e == "ele")
      format = MeshFormat::kTetGen;
    else if (e == "off")
      format = MeshFormat::kOff;
    else
      throw ParseError(
          path, 0,
          "unknown mesh file extension '" + e + "': expected .msh, .mesh, .node, .ele or .off");
  }
  switch (format) {
    case MeshFormat::kGmsh: return read_gmsh(path, options);
    case MeshFormat::kMedit: return read_medit(path, options);
    case MeshFormat::kTetGen: return read_tetgen(path, options);
    case MeshFormat::kOff: return read_off(path, options);
    case MeshFormat::kAuto: break;
  }
  throw ParseError(path, 0, "no reader for this format");
}

}  // namespace incise::io
