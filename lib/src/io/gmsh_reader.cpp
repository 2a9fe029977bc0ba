// Gmsh .msh ASCII reader, versions 2.2 and 4.1 (Gmsh reference manual, "MSH file format").

#include <incise/io/read_mesh.hpp>

#include <map>
#include <sstream>
#include <unordered_map>

#include "text_reader.hpp"

namespace incise::io {

namespace {

using detail::RawMesh;
using detail::TextReader;

constexpr int kPoint = 15, kLine = 1, kTriangle = 2, kTetrahedron = 4;

// Node tag → 0-based index.
class NodeMap {
 public:
  void add(TextReader& r, long long tag, Index index) {
    if (!map_.emplace(tag, index).second) r.fail("duplicate node tag: expected each node once");
  }
  Index find(TextReader& r, long long tag) const {
    const auto it = map_.find(tag);
    if (it == map_.end()) {
      std::ostringstream os;
      os << "node index out of range: node tag " << tag
         << " is not defined in $Nodes; expected a defined node tag";
      r.fail(os.str());
    }
    return it->second;
  }
  void reserve(std::size_t n) { map_.reserve(n); }
  bool empty() const { return map_.empty(); }

 private:
  std::unordered_map<long long, Index> map_;
};

[[noreturn]] void unsupported_type(TextReader& r, long long type) {
  std::ostringstream os;
  os << "unsupported element type " << type
     << ": expected 4 (4-node tetrahedron) or 2 (3-node triangle); points (15) and lines (1) "
        "are ignored";
  r.fail(os.str());
}

int nodes_of_type(TextReader& r, long long type) {
  switch (type) {
    case kPoint: return 1;
    case kLine: return 2;
    case kTriangle: return 3;
    case kTetrahedron: return 4;
    default: unsupported_type(r, type);
  }
}

void add_element(RawMesh& raw, TextReader& r, const NodeMap& nodes, long long type, int tag,
                 const long long* node_tags) {
  if (type == kTetrahedron) {
    for (int i = 0; i < 4; ++i) raw.tets.push_back(nodes.find(r, node_tags[i]));
    raw.tet_tags.push_back(tag);
    raw.tet_lines.push_back(r.line());
  } else if (type == kTriangle) {
    for (int i = 0; i < 3; ++i) raw.tris.push_back(nodes.find(r, node_tags[i]));
    raw.tri_tags.push_back(tag);
    raw.tri_lines.push_back(r.line());
  } else {
    for (int i = 0; i < (type == kLine ? 2 : 1); ++i) nodes.find(r, node_tags[i]);
    ++raw.ignored;
  }
}

void read_point_coordinates(RawMesh& raw, TextReader& r) {
  raw.xyz.push_back(r.real("x coordinate"));
  raw.xyz.push_back(r.real("y coordinate"));
  raw.xyz.push_back(r.real("z coordinate"));
  raw.point_lines.push_back(r.line());
}

void read_physical_names(RawMesh& raw, TextReader& r) {
  const long long n = r.integer("number of physical names", 0);
  for (long long i = 0; i < n; ++i) {
    r.integer("physical dimension", 0, 3);
    const int tag = static_cast<int>(r.integer("physical tag", -(1LL << 31), (1LL << 31) - 1));
    std::string name = r.rest_of_line();
    if (name.size() >= 2 && name.front() == '"' && name.back() == '"')
      name = name.substr(1, name.size() - 2);
    raw.physical_names[tag] = name;
  }
  r.expect("$EndPhysicalNames");
}

// 4.1 $Entities: (dim, tag) → first physical tag (0 when none).
void read_entities(std::map<std::pair<int, long long>, int>& physical, TextReader& r) {
  long long count[4];
  for (long long& c : count) c = r.integer("number of entities", 0);
  for (int dim = 0; dim < 4; ++dim)
    for (long long e = 0; e < count[dim]; ++e) {
      const long long tag = r.integer("entity tag");
      for (int i = 0; i < (dim == 0 ? 3 : 6); ++i) r.real("entity bounding box coordinate");
      const long long nphys = r.integer("number of physical tags", 0, 1 << 20);
      int first = 0;
      for (long long p = 0; p < nphys; ++p) {
        const int t = static_cast<int>(r.integer("physical tag", -(1LL << 31), (1LL << 31) - 1));
        if (p == 0) first = t;
      }
      if (dim > 0) {
        const long long nb = r.integer("number of bounding entities", 0, 1 << 24);
        for (long long b = 0; b < nb; ++b) r.integer("bounding entity tag");
      }
      physical[{dim, tag}] = first;
    }
  r.expect("$EndEntities");
}

void read_nodes_22(RawMesh& raw, NodeMap& nodes, TextReader& r) {
  const long long n = r.integer("number of nodes", 0, (1LL << 31) - 1);
  raw.xyz.reserve(3 * detail::bounded_reserve(n, r.size()));
  nodes.reserve(detail::bounded_reserve(n, r.size()));
  for (long long i = 0; i < n; ++i) {
    const long long tag = r.integer("node tag", 1);
    read_point_coordinates(raw, r);
    r.end_of_line("node tag and 3 coordinates");
    nodes.add(r, tag, static_cast<Index>(i));
  }
  r.expect("$EndNodes");
}

void read_elements_22(RawMesh& raw, const NodeMap& nodes, TextReader& r) {
  const long long n = r.integer("number of elements", 0, (1LL << 31) - 1);
  long long node_tags[4];
  for (long long i = 0; i < n; ++i) {
    r.integer("element tag", 1);
    const long long type = r.integer("element type");
    const int nn = nodes_of_type(r, type);
    const long long ntags = r.integer("number of element tags", 0, 1 << 10);
    int physical = 0;
    for (long long t = 0; t < ntags; ++t) {
      const int v = static_cast<int>(r.integer("element tag", -(1LL << 31), (1LL << 31) - 1));
      if (t == 0) physical = v;
    }
    for (int k = 0; k < nn; ++k) node_tags[k] = r.integer("node tag of element");
    r.end_of_line("the element's node tags");
    add_element(raw, r, nodes, type, physical, node_tags);
  }
  r.expect("$EndElements");
}

void read_nodes_41(RawMesh& raw, NodeMap& nodes, TextReader& r) {
  const long long blocks = r.integer("number of node entity blocks", 0);
  const long long n = r.integer("number of nodes", 0, (1LL << 31) - 1);
  r.integer("minimum node tag");
  r.integer("maximum node tag");
  raw.xyz.reserve(3 * detail::bounded_reserve(n, r.size()));
  nodes.reserve(detail::bounded_reserve(n, r.size()));
  std::vector<long long> tags;
  long long total = 0;
  for (long long b = 0; b < blocks; ++b) {
    const int dim = static_cast<int>(r.integer("entity dimension", 0, 3));
    r.integer("entity tag");
    const bool parametric = r.integer("parametric flag (0 or 1)", 0, 1) == 1;
    const long long count = r.integer("number of nodes in block", 0, n - total);
    tags.clear();
    for (long long i = 0; i < count; ++i) tags.push_back(r.integer("node tag", 1));
    for (long long i = 0; i < count; ++i) {
      read_point_coordinates(raw, r);
      if (parametric)
        for (int p = 0; p < dim; ++p) r.real("parametric coordinate");
      r.end_of_line("node coordinates");
      nodes.add(r, tags[i], static_cast<Index>(total + i));
    }
    total += count;
  }
  if (total != n) {
    std::ostringstream os;
    os << "node count mismatch: header announces " << n << " nodes, blocks hold " << total;
    r.fail(os.str());
  }
  r.expect("$EndNodes");
}

void read_elements_41(RawMesh& raw, const NodeMap& nodes,
                      const std::map<std::pair<int, long long>, int>& physical, TextReader& r) {
  const long long blocks = r.integer("number of element entity blocks", 0);
  const long long n = r.integer("number of elements", 0, (1LL << 31) - 1);
  r.integer("minimum element tag");
  r.integer("maximum element tag");
  long long total = 0;
  long long node_tags[4];
  for (long long b = 0; b < blocks; ++b) {
    const int dim = static_cast<int>(r.integer("entity dimension", 0, 3));
    const long long entity = r.integer("entity tag");
    const long long type = r.integer("element type");
    const int nn = nodes_of_type(r, type);
    const long long count = r.integer("number of elements in block", 0, n - total);
    const auto it = physical.find({dim, entity});
    const int tag = it == physical.end() ? 0 : it->second;
    if (type == kTetrahedron) {
      raw.tets.reserve(raw.tets.size() + 4 * detail::bounded_reserve(count, r.size()));
      raw.tet_lines.reserve(raw.tet_lines.size() + detail::bounded_reserve(count, r.size()));
    }
    for (long long i = 0; i < count; ++i) {
      r.integer("element tag", 1);
      for (int k = 0; k < nn; ++k) node_tags[k] = r.integer("node tag of element");
      r.end_of_line("the element's node tags");
      add_element(raw, r, nodes, type, tag, node_tags);
    }
    total += count;
  }
  if (total != n) {
    std::ostringstream os;
    os << "element count mismatch: header announces " << n << " elements, blocks hold " << total;
    r.fail(os.str());
  }
  r.expect("$EndElements");
}

}  // namespace

LoadedMesh read_gmsh(const std::string& path, const ReadOptions& options) {
  TextReader r = TextReader::open(path, '\0');
  RawMesh raw;
  r.expect("$MeshFormat");
  const std::string version(r.token("format version"));
  int major = 0;
  if (version == "2.2" || version == "2.1" || version == "2" || version == "2.0")
    major = 2;
  else if (version == "4.1")
    major = 4;
  else
    r.fail("unsupported .msh version '" + version + "': expected 2.2 or 4.1");
  if (r.integer("file type", 0, 1) != 0)
    r.fail("binary .msh is not supported: expected file type 0 (ASCII)");
  r.integer("data size", 1, 16);
  r.expect("$EndMeshFormat");
  raw.format = major == 2 ? "gmsh 2.2" : "gmsh 4.1";

  NodeMap nodes;
  bool have_nodes = false, have_elements = false;
  std::map<std::pair<int, long long>, int> physical;
  while (!r.at_end()) {
    const std::string section(r.token("section"));
    if (section.empty() || section[0] != '$')
      r.fail("unexpected '" + section + "': expected a $Section header");
    if (section == "$PhysicalNames") {
      read_physical_names(raw, r);
    } else if (section == "$Entities" && major == 4) {
      read_entities(physical, r);
    } else if (section == "$Nodes") {
      if (have_nodes) r.fail("second $Nodes section: expected one");
      if (major == 2)
        read_nodes_22(raw, nodes, r);
      else
        read_nodes_41(raw, nodes, r);
      have_nodes = true;
    } else if (section == "$Elements") {
      if (!have_nodes) r.fail("$Elements before $Nodes: expected $Nodes first");
      if (have_elements) r.fail("second $Elements section: expected one");
      if (major == 2)
        read_elements_22(raw, nodes, r);
      else
        read_elements_41(raw, nodes, physical, r);
      have_elements = true;
    } else {
      // Unknown or unused section ($NodeData, $Periodic, ...): skip to its end marker.
      const std::string end = "$End" + section.substr(1);
      while (true) {
        const std::string_view t = r.token(end.c_str());
        if (t == end) break;
      }
    }
  }
  if (!have_nodes) r.fail("unexpected end of file: expected a $Nodes section");
  if (!have_elements) r.fail("unexpected end of file: expected an $Elements section");
  if (raw.ignored > 0)
    raw.ignored_notes.push_back(std::to_string(raw.ignored) + " point/line elements ignored");
  return detail::finalize(std::move(raw), path, options);
}

}  // namespace incise::io
