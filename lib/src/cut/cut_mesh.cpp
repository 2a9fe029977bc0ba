#include <incise/core/error.hpp>
#include <incise/cut/cut_mesh.hpp>
#include <incise/cut/predicates.hpp>
#include <incise/mesh/dissect.hpp>
#include <incise/mesh/validate.hpp>

#include <algorithm>

namespace incise::cut {

namespace {

mesh::Simplex to_simplex(const Tet& t) {
  return mesh::Simplex(t.data(), 4, +1);
}

Tet to_tet(const mesh::Simplex& s) {
  Tet t{s.vertex(0), s.vertex(1), s.vertex(2), s.vertex(3)};
  if (s.sign() < 0) std::swap(t[0], t[1]);
  return t;
}

mesh::Connectivity checked_connectivity(const mesh::MeshData& data) {
  INCISE_CHECK_PARAM(data.dimension == 3 && data.cells.rows() == 4,
                     "CutMesh needs a tetrahedral mesh (dimension 3, 4 nodes per cell)");
  mesh::Connectivity conn = mesh::Connectivity::from_mesh_data(data);
  while (conn.num_vertices() < data.num_points()) (void)conn.add_vertex();
  return conn;
}

}  // namespace

CutMesh::CutMesh(const mesh::MeshData& data) : conn_(checked_connectivity(data)) {
  const Index n = data.num_points();
  INCISE_CHECK_PARAM(conn_.num_vertices() == n, "cells refer to nodes beyond the point list");
  ref_.resize(static_cast<size_t>(n));
  for (Index i = 0; i < n; ++i) ref_[static_cast<size_t>(i)] = data.points.col(i);
  def_ = ref_;
  fixed_.assign(static_cast<size_t>(n), 0);
  origin_.resize(static_cast<size_t>(n));
  for (Index i = 0; i < n; ++i) origin_[static_cast<size_t>(i)] = i;
  for (Index e = 0; e < element_capacity(); ++e) refresh(e);
  if (!data.cell_tags.empty()) {
    INCISE_CHECK_PARAM(static_cast<Index>(data.cell_tags.size()) == data.num_cells() &&
                           element_capacity() == data.num_cells(),
                       "cell_tags must hold one tag per cell");
    tags_ = data.cell_tags;  // from_mesh_data puts cell c in slot c
  }
}

void CutMesh::refresh(Index e) {
  if (static_cast<Index>(tets_.size()) < element_capacity())
    tets_.resize(static_cast<size_t>(element_capacity()), Tet{-1, -1, -1, -1});
  const mesh::ElementHandle h = conn_.element_at(e);
  tets_[static_cast<size_t>(e)] = h.valid() ? to_tet(conn_.simplex(h)) : Tet{-1, -1, -1, -1};
}

void CutMesh::set_position(Index v, const Vec3& X, const Vec3& x) {
  ref_[static_cast<size_t>(v)] = X;
  def_[static_cast<size_t>(v)] = x;
}

void CutMesh::set_deformed(const Eigen::Matrix3Xd& x) {
  INCISE_CHECK(x.cols() == num_nodes(), "deformed positions need one column per node");
  for (Index i = 0; i < num_nodes(); ++i) def_[static_cast<size_t>(i)] = x.col(i);
  ++positions_version_;
}

Eigen::Matrix3Xd CutMesh::reference_matrix() const {
  Eigen::Matrix3Xd m(3, num_nodes());
  for (Index i = 0; i < num_nodes(); ++i) m.col(i) = reference(i);
  return m;
}

Eigen::Matrix3Xd CutMesh::deformed_matrix() const {
  Eigen::Matrix3Xd m(3, num_nodes());
  for (Index i = 0; i < num_nodes(); ++i) m.col(i) = deformed(i);
  return m;
}

std::vector<Index> CutMesh::star(Index v) const {
  std::vector<Index> out;
  for (const auto& h : conn_.star(v)) out.push_back(h.index);
  return out;
}

Index CutMesh::neighbor(Index e, int j) const {
  const mesh::ElementHandle h = conn_.element_at(e);
  const mesh::FaceHandle m = conn_.mate(conn_.opposite_face(h, element(e)[static_cast<size_t>(j)]));
  return m.valid() ? conn_.element(m).index : -1;
}

int CutMesh::local_index(Index e, Index v) const {
  const Tet& t = element(e);
  for (int k = 0; k < 4; ++k) {
    if (t[static_cast<size_t>(k)] == v) return k;
  }
  return -1;
}

bool CutMesh::on_boundary(Index v) const {
  for (const auto& h : conn_.star(v)) {
    const Tet& t = element(h.index);
    for (Index w : t) {
      if (w != v && !conn_.mate(conn_.opposite_face(h, w)).valid()) return true;
    }
  }
  return false;
}

Index CutMesh::add_node(const Vec3& X, const Vec3& x, bool is_fixed, Index origin_node) {
  const Index v = conn_.add_vertex();
  INCISE_ASSERT(v == num_nodes(), "connectivity and node arrays out of step");
  ref_.push_back(X);
  def_.push_back(x);
  fixed_.push_back(is_fixed ? 1 : 0);
  origin_.push_back(origin_node);
  return v;
}

std::vector<Index> CutMesh::replace(const std::vector<Index>& remove, const std::vector<Tet>& add) {
  std::vector<mesh::ElementHandle> old;
  old.reserve(remove.size());
  for (Index e : remove) {
    INCISE_CHECK(alive(e), "replace: element " + std::to_string(e) + " is not alive");
    old.push_back(conn_.element_at(e));
  }
  std::vector<mesh::Simplex> simplices;
  simplices.reserve(add.size());
  for (const Tet& t : add) simplices.push_back(to_simplex(t));
  std::vector<Tet> removed;
  for (Index e : remove) removed.push_back(element(e));
  std::vector<int> removed_tags;
  for (Index e : remove) removed_tags.push_back(tag(e));
  const auto added = conn_.replace_elements(old, simplices);
  for (Index e : remove) refresh(e);
  if (!tags_.empty()) {
    if (static_cast<Index>(tags_.size()) < element_capacity())
      tags_.resize(static_cast<size_t>(element_capacity()), 0);
    for (std::size_t a = 0; a < added.size(); ++a) {
      int best = -1, best_tag = 0;
      for (std::size_t r = 0; r < removed.size(); ++r) {
        int shared = 0;
        for (Index v : add[a]) shared += std::count(removed[r].begin(), removed[r].end(), v) > 0;
        if (shared > best) best = shared, best_tag = removed_tags[r];
      }
      tags_[static_cast<size_t>(added[a].index)] = best_tag;
    }
  }
  std::vector<Index> out;
  out.reserve(added.size());
  for (const auto& h : added) {
    refresh(h.index);
    out.push_back(h.index);
  }
  return out;
}

double CutMesh::reference_volume(const Tet& t) const {
  return signed_volume(reference(t[0]), reference(t[1]), reference(t[2]), reference(t[3]));
}

double CutMesh::deformed_volume(const Tet& t) const {
  return signed_volume(deformed(t[0]), deformed(t[1]), deformed(t[2]), deformed(t[3]));
}

Index CutMesh::dissect(const std::vector<std::pair<Index, int>>& faces, std::vector<Index>& changed,
                       std::vector<Index>& new_nodes) {
  std::vector<mesh::FaceHandle> handles;
  handles.reserve(faces.size());
  for (const auto& [e, j] : faces) {
    INCISE_CHECK(alive(e) && j >= 0 && j < 4, "dissect: bad face");
    handles.push_back(face_handle(e, j));
  }
  return dissect(handles, changed, new_nodes);
}

Index CutMesh::dissect(const std::vector<mesh::FaceHandle>& faces, std::vector<Index>& changed,
                       std::vector<Index>& new_nodes) {
  std::vector<mesh::FaceHandle> cut;
  cut.reserve(faces.size());
  for (const auto& f : faces) {
    if (conn_.is_alive(f) && conn_.mate(f).valid()) cut.push_back(f);
  }
  const mesh::DissectResult result = mesh::dissect(conn_, cut);
  for (const auto& split : result.splits) {
    const Index v = split.old_vertex;
    INCISE_ASSERT(split.new_vertex == num_nodes(), "dissect appended vertices out of order");
    ref_.push_back(reference(v));
    def_.push_back(deformed(v));
    fixed_.push_back(fixed_[static_cast<size_t>(v)]);
    origin_.push_back(origin(v));
    new_nodes.push_back(split.new_vertex);
    for (const auto& h : split.elements) {
      refresh(h.index);
      changed.push_back(h.index);
    }
  }
  Index on_boundary_count = 0;
  for (const auto& f : cut) {
    if (!conn_.mate(f).valid()) ++on_boundary_count;
  }
  std::sort(changed.begin(), changed.end());
  changed.erase(std::unique(changed.begin(), changed.end()), changed.end());
  return on_boundary_count;
}

CutMeshValidation CutMesh::validate() const {
  CutMeshValidation r;
  auto violate = [&r](std::string msg) {
    if (r.violations.size() < 50) r.violations.push_back(std::move(msg));
    ++r.violation_count;
  };
  mesh::ValidateOptions opt;
  opt.positions = nullptr;  // orientation is counted below, in both configurations
  const mesh::ValidationReport rep = mesh::validate(conn_, opt);
  for (const auto& v : rep.violations) violate("[" + v.invariant + "] " + v.message);
  if (conn_.num_vertices() != num_nodes()) violate("[nodes] connectivity/node count mismatch");
  for (Index v = 0; v < num_nodes(); ++v) {
    if (!ref_[static_cast<size_t>(v)].allFinite() || !def_[static_cast<size_t>(v)].allFinite())
      violate("[positions] node " + std::to_string(v) + ": non-finite position");
  }
  for (Index e = 0; e < element_capacity(); ++e) {
    const mesh::ElementHandle h = conn_.element_at(e);
    if (!h.valid()) continue;
    const Tet& t = element(e);
    if (to_simplex(t) != conn_.simplex(h))
      violate("[cache] element " + std::to_string(e) + ": node cache differs from simplex");
    if (!(reference_volume(t) > 0)) ++r.inverted_reference;
    if (!(deformed_volume(t) > 0)) ++r.inverted_deformed;
  }
  return r;
}

CutMeshValidation CutMesh::validate_local(const std::vector<Index>& elements) const {
  CutMeshValidation r;
  auto violate = [&r](std::string msg) {
    if (r.violations.size() < 50) r.violations.push_back(std::move(msg));
    ++r.violation_count;
  };
  std::vector<Index> nodes;
  for (Index e : elements) {
    if (!alive(e)) continue;
    const mesh::ElementHandle h = conn_.element_at(e);
    const Tet& t = element(e);
    const std::string name = "element " + std::to_string(e);
    if (to_simplex(t) != conn_.simplex(h)) violate("[cache] " + name + ": node cache differs");
    if (!(reference_volume(t) > 0)) ++r.inverted_reference;
    if (!(deformed_volume(t) > 0)) ++r.inverted_deformed;
    for (int i = 0; i < 4; ++i) {
      const mesh::FaceHandle f = conn_.face(h, i);
      if (!conn_.is_alive(f) || conn_.simplex(f) != conn_.simplex(h).subn(i)) {
        violate("[7.1] " + name + " face " + std::to_string(i));
        continue;
      }
      const mesh::FaceHandle m = conn_.mate(f);
      if (m.valid()) {
        if (!conn_.is_alive(m) || conn_.simplex(m) != conn_.simplex(f).mate() || conn_.mate(m) != f)
          violate("[7.3] " + name + " face " + std::to_string(i) + ": bad mate");
      } else if (conn_.boundary_face(conn_.simplex(f)) != f) {
        violate("[7.5] " + name + " face " + std::to_string(i) + ": not in the boundary map");
      }
    }
    for (Index v : t) {
      nodes.push_back(v);
      if (!reference(v).allFinite() || !deformed(v).allFinite())
        violate("[positions] node " + std::to_string(v) + ": non-finite position");
    }
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  for (Index v : nodes) {
    const std::vector<Index> s = star(v);
    if (s.empty()) continue;
    // Face-connectedness of star(v) through faces containing v (§7.3).
    std::vector<Index> stack{s[0]};
    std::vector<Index> seen{s[0]};
    while (!stack.empty()) {
      const Index e = stack.back();
      stack.pop_back();
      const int lv = local_index(e, v);
      if (lv < 0) {
        violate("[incidence] star(" + std::to_string(v) + ") lists element " + std::to_string(e) +
                " without it");
        break;
      }
      for (int j = 0; j < 4; ++j) {
        if (j == lv) continue;
        const Index nb = neighbor(e, j);
        if (nb >= 0 && std::find(seen.begin(), seen.end(), nb) == seen.end()) {
          seen.push_back(nb);
          stack.push_back(nb);
        }
      }
    }
    if (seen.size() != s.size())
      violate("[connected-star] star(" + std::to_string(v) + ") is not face-connected");
  }
  return r;
}

mesh::MeshData CutMesh::to_mesh_data(bool deformed_positions, bool compact,
                                     std::vector<Index>* node_map) const {
  mesh::MeshData d;
  d.dimension = 3;
  std::vector<Index> map(static_cast<size_t>(num_nodes()), -1);
  Index count = 0;
  for (Index v = 0; v < num_nodes(); ++v) {
    if (!compact || !unused(v)) map[static_cast<size_t>(v)] = count++;
  }
  d.points.resize(3, count);
  for (Index v = 0; v < num_nodes(); ++v) {
    const Index m = map[static_cast<size_t>(v)];
    if (m >= 0) d.points.col(m) = deformed_positions ? deformed(v) : reference(v);
  }
  d.cells.resize(4, num_elements());
  Index c = 0;
  for (Index e = 0; e < element_capacity(); ++e) {
    if (!alive(e)) continue;
    for (int k = 0; k < 4; ++k)
      d.cells(k, c) = map[static_cast<size_t>(element(e)[static_cast<size_t>(k)])];
    if (has_tags()) d.cell_tags.push_back(tag(e));
    ++c;
  }
  if (node_map) *node_map = std::move(map);
  return d;
}

}  // namespace incise::cut
