#include <incise/core/error.hpp>
#include <incise/cut/cut_mesh.hpp>
#include <incise/cut/predicates.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <unordered_set>

namespace incise::cut {

namespace {

/// Sorted triple key of a face and the parity of the sort permutation.
struct FaceKey {
  std::array<Index, 3> n;
  int parity;
};

FaceKey face_key(Index a, Index b, Index c) {
  FaceKey k{{a, b, c}, 0};
  // Bubble sort with swap counting (3 elements).
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < 2 - pass; ++i) {
      if (k.n[static_cast<size_t>(i)] > k.n[static_cast<size_t>(i + 1)]) {
        std::swap(k.n[static_cast<size_t>(i)], k.n[static_cast<size_t>(i + 1)]);
        k.parity ^= 1;
      }
    }
  }
  return k;
}

struct TripleHash {
  size_t operator()(const std::array<Index, 3>& a) const {
    std::uint64_t h = static_cast<std::uint32_t>(a[0]);
    h = h * 0x9E3779B97F4A7C15ULL + static_cast<std::uint32_t>(a[1]);
    h = h * 0x9E3779B97F4A7C15ULL + static_cast<std::uint32_t>(a[2]);
    return static_cast<size_t>(h ^ (h >> 29));
  }
};

Index find_root(std::vector<Index>& parent, Index i) {
  while (parent[static_cast<size_t>(i)] != i) {
    parent[static_cast<size_t>(i)] = parent[static_cast<size_t>(parent[static_cast<size_t>(i)])];
    i = parent[static_cast<size_t>(i)];
  }
  return i;
}

bool contains(const Tet& t, Index v) {
  return t[0] == v || t[1] == v || t[2] == v || t[3] == v;
}

}  // namespace

CutMesh::CutMesh(const mesh::MeshData& data) {
  INCISE_CHECK_PARAM(data.dimension == 3 && data.cells.rows() == 4,
                     "CutMesh needs a tetrahedral mesh (dimension 3, 4 nodes per cell)");
  const Index n = data.num_points();
  ref_.resize(static_cast<size_t>(n));
  for (Index i = 0; i < n; ++i) ref_[static_cast<size_t>(i)] = data.points.col(i);
  def_ = ref_;
  fixed_.assign(static_cast<size_t>(n), 0);
  origin_.resize(static_cast<size_t>(n));
  std::iota(origin_.begin(), origin_.end(), 0);
  star_.resize(static_cast<size_t>(n));
  tets_.reserve(static_cast<size_t>(data.num_cells()));
  for (Index c = 0; c < data.num_cells(); ++c) {
    Tet t;
    for (int k = 0; k < 4; ++k) {
      t[static_cast<size_t>(k)] = data.cells(k, c);
      INCISE_CHECK_PARAM(t[static_cast<size_t>(k)] >= 0 && t[static_cast<size_t>(k)] < n,
                         "cell " + std::to_string(c) + " refers to a missing node");
    }
    add_element(t);
  }
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

Index CutMesh::neighbor(Index e, int j) const {
  const Tet& t = element(e);
  const Index a = t[static_cast<size_t>(kTetFace[j][0])];
  const Index b = t[static_cast<size_t>(kTetFace[j][1])];
  const Index c = t[static_cast<size_t>(kTetFace[j][2])];
  for (Index f : star(a)) {
    if (f != e && contains(element(f), b) && contains(element(f), c)) return f;
  }
  return -1;
}

int CutMesh::local_index(Index e, Index v) const {
  const Tet& t = element(e);
  for (int k = 0; k < 4; ++k) {
    if (t[static_cast<size_t>(k)] == v) return k;
  }
  return -1;
}

bool CutMesh::on_boundary(Index v) const {
  for (Index e : star(v)) {
    const int lv = local_index(e, v);
    for (int j = 0; j < 4; ++j) {
      if (j != lv && neighbor(e, j) < 0) return true;
    }
  }
  return false;
}

Index CutMesh::add_node(const Vec3& X, const Vec3& x, bool is_fixed, Index origin_node) {
  ref_.push_back(X);
  def_.push_back(x);
  fixed_.push_back(is_fixed ? 1 : 0);
  origin_.push_back(origin_node);
  star_.emplace_back();
  return num_nodes() - 1;
}

void CutMesh::star_remove(Index v, Index e) {
  auto& s = star_[static_cast<size_t>(v)];
  auto it = std::find(s.begin(), s.end(), e);
  if (it != s.end()) {
    *it = s.back();
    s.pop_back();
  }
}

void CutMesh::set_element(Index e, const Tet& t) {
  INCISE_CHECK(e >= 0 && e < element_capacity() && alive(e), "set_element on a dead handle");
  for (Index v : tets_[static_cast<size_t>(e)]) star_remove(v, e);
  tets_[static_cast<size_t>(e)] = t;
  for (Index v : t) star_[static_cast<size_t>(v)].push_back(e);
}

Index CutMesh::add_element(const Tet& t) {
  Index e;
  if (!free_.empty()) {
    e = free_.back();
    free_.pop_back();
    tets_[static_cast<size_t>(e)] = t;
    alive_[static_cast<size_t>(e)] = 1;
  } else {
    e = element_capacity();
    tets_.push_back(t);
    alive_.push_back(1);
  }
  for (Index v : t) star_[static_cast<size_t>(v)].push_back(e);
  ++live_elements_;
  return e;
}

void CutMesh::remove_element(Index e) {
  INCISE_CHECK(e >= 0 && e < element_capacity() && alive(e), "remove_element on a dead handle");
  for (Index v : tets_[static_cast<size_t>(e)]) star_remove(v, e);
  alive_[static_cast<size_t>(e)] = 0;
  free_.push_back(e);
  --live_elements_;
}

double CutMesh::reference_volume(const Tet& t) const {
  return signed_volume(reference(t[0]), reference(t[1]), reference(t[2]), reference(t[3]));
}

double CutMesh::deformed_volume(const Tet& t) const {
  return signed_volume(deformed(t[0]), deformed(t[1]), deformed(t[2]), deformed(t[3]));
}

Index CutMesh::dissect(const std::vector<std::pair<Index, int>>& faces, std::vector<Index>& changed,
                       std::vector<Index>& new_nodes) {
  // Faces are identified by (element, local face): local positions survive substitution.
  std::unordered_set<std::int64_t> cut;
  std::vector<Index> nodes;
  auto key = [](Index e, int j) { return static_cast<std::int64_t>(e) * 4 + j; };
  for (const auto& [e, j] : faces) {
    INCISE_CHECK(alive(e) && j >= 0 && j < 4, "dissect: bad face handle");
    cut.insert(key(e, j));
    const Index n = neighbor(e, j);
    if (n >= 0) {
      const Tet& t = element(e);
      // local face of n opposite the node of n not in this face
      for (int k = 0; k < 4; ++k) {
        const Index w = element(n)[static_cast<size_t>(k)];
        if (!contains(t, w) || w == t[static_cast<size_t>(j)]) {
          cut.insert(key(n, k));
          break;
        }
      }
    }
    for (int k = 0; k < 3; ++k) nodes.push_back(element(e)[static_cast<size_t>(kTetFace[j][k])]);
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());

  for (Index v : nodes) {
    std::vector<Index> s = star(v);
    std::sort(s.begin(), s.end());
    const Index m = static_cast<Index>(s.size());
    std::vector<Index> parent(static_cast<size_t>(m));
    std::iota(parent.begin(), parent.end(), 0);
    auto pos = [&](Index e) {
      return static_cast<Index>(std::lower_bound(s.begin(), s.end(), e) - s.begin());
    };
    for (Index i = 0; i < m; ++i) {
      const Index e = s[static_cast<size_t>(i)];
      const int lv = local_index(e, v);
      for (int j = 0; j < 4; ++j) {
        if (j == lv || cut.count(key(e, j))) continue;
        const Index n = neighbor(e, j);
        if (n < 0) continue;
        const Index pi = find_root(parent, i);
        const Index pn = find_root(parent, pos(n));
        if (pi != pn) parent[static_cast<size_t>(std::max(pi, pn))] = std::min(pi, pn);
      }
    }
    // Class of the lowest handle (root 0 after min-union) keeps v; others get copies.
    std::unordered_map<Index, Index> copy_of_root;
    for (Index i = 0; i < m; ++i) {
      const Index r = find_root(parent, i);
      if (r == find_root(parent, 0)) continue;
      auto it = copy_of_root.find(r);
      if (it == copy_of_root.end()) {
        const Index w = add_node(reference(v), deformed(v), fixed(v), origin(v));
        new_nodes.push_back(w);
        it = copy_of_root.emplace(r, w).first;
      }
      const Index e = s[static_cast<size_t>(i)];
      Tet t = element(e);
      t[static_cast<size_t>(local_index(e, v))] = it->second;
      set_element(e, t);
      changed.push_back(e);
    }
  }
  Index on_boundary_count = 0;
  for (const auto& [e, j] : faces) {
    if (neighbor(e, j) < 0) ++on_boundary_count;
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
  const Index n = num_nodes();
  for (Index v = 0; v < n; ++v) {
    if (!ref_[static_cast<size_t>(v)].allFinite() || !def_[static_cast<size_t>(v)].allFinite())
      violate("node " + std::to_string(v) + ": non-finite position");
    const auto& s = star(v);
    for (Index e : s) {
      if (e < 0 || e >= element_capacity() || !alive(e) || !contains(element(e), v))
        violate("star(" + std::to_string(v) + ") lists element " + std::to_string(e) +
                " that does not contain it");
    }
    std::vector<Index> sorted = s;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
      violate("star(" + std::to_string(v) + ") has a duplicate element");
  }
  std::unordered_map<std::array<Index, 3>, std::vector<std::pair<Index, int>>, TripleHash> faces;
  faces.reserve(static_cast<size_t>(num_elements()) * 3);
  for (Index e = 0; e < element_capacity(); ++e) {
    if (!alive(e)) continue;
    const Tet& t = element(e);
    bool ok = true;
    for (int k = 0; k < 4; ++k) {
      const Index v = t[static_cast<size_t>(k)];
      if (v < 0 || v >= n) {
        violate("element " + std::to_string(e) + " refers to missing node");
        ok = false;
        continue;
      }
      if (std::count(star(v).begin(), star(v).end(), e) != 1)
        violate("element " + std::to_string(e) + " missing from star(" + std::to_string(v) + ")");
      for (int l = k + 1; l < 4; ++l) {
        if (t[static_cast<size_t>(l)] == v) {
          violate("element " + std::to_string(e) + " repeats node " + std::to_string(v));
          ok = false;
        }
      }
    }
    if (!ok) continue;
    if (!(reference_volume(t) > 0)) ++r.inverted_reference;
    if (!(deformed_volume(t) > 0)) ++r.inverted_deformed;
    for (int j = 0; j < 4; ++j) {
      const FaceKey k =
          face_key(t[static_cast<size_t>(kTetFace[j][0])], t[static_cast<size_t>(kTetFace[j][1])],
                   t[static_cast<size_t>(kTetFace[j][2])]);
      faces[k.n].emplace_back(e, k.parity);
    }
  }
  for (const auto& [k, list] : faces) {
    const std::string name =
        std::to_string(k[0]) + "," + std::to_string(k[1]) + "," + std::to_string(k[2]);
    if (list.size() > 2) {
      violate("face {" + name + "} in " + std::to_string(list.size()) + " elements (manifold)");
    } else if (list.size() == 2 && list[0].second == list[1].second) {
      violate("face {" + name + "} has the same orientation in elements " +
              std::to_string(list[0].first) + " and " + std::to_string(list[1].first) + " (7.3)");
    }
  }
  // Star connectivity (precondition of dissection, §7.3).
  for (Index v = 0; v < n; ++v) {
    const auto& s = star(v);
    if (s.size() < 2) continue;
    std::vector<Index> sorted = s;
    std::sort(sorted.begin(), sorted.end());
    const Index m = static_cast<Index>(sorted.size());
    std::vector<Index> parent(static_cast<size_t>(m));
    std::iota(parent.begin(), parent.end(), 0);
    Index classes = m;
    for (Index i = 0; i < m; ++i) {
      const Index e = sorted[static_cast<size_t>(i)];
      const int lv = local_index(e, v);
      for (int j = 0; j < 4; ++j) {
        if (j == lv) continue;
        const Index nb = neighbor(e, j);
        if (nb < 0) continue;
        auto it = std::lower_bound(sorted.begin(), sorted.end(), nb);
        if (it == sorted.end() || *it != nb) continue;
        const Index a = find_root(parent, i);
        const Index b = find_root(parent, static_cast<Index>(it - sorted.begin()));
        if (a != b) {
          parent[static_cast<size_t>(std::max(a, b))] = std::min(a, b);
          --classes;
        }
      }
    }
    if (classes != 1)
      violate("star(" + std::to_string(v) + ") is not face-connected (" + std::to_string(classes) +
              " parts; §7.3 precondition)");
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
    ++c;
  }
  if (node_map) *node_map = std::move(map);
  return d;
}

}  // namespace incise::cut
