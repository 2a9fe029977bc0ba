#include <incise/core/error.hpp>
#include <incise/cut/cutter.hpp>
#include <incise/cut/predicates.hpp>
#include <incise/mesh/quality.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <numeric>

namespace incise::cut {

namespace {

/// Half-width of the band around t = 1/2 inside which an edge counts as halved and the
/// lowest node index is marked (§3.2.1). Relative to the edge parameter, far above the
/// ~1e-16 relative error of t = d_p/(d_p − d_q).
constexpr double kHalfTie = 1e-12;
/// Barycentric slack for "w lies in the face / element" tests (dimensionless): points on a
/// shared face or edge must be found in at least one of the incident simplices.
constexpr double kInsideTol = 1e-9;
/// Sweep triangles with area below this fraction of the squared longest side are degenerate.
constexpr double kSweepAreaRelEps = 1e-12;
/// A node within this fraction of the sweep triangle's longest side from the sweep plane is
/// already on the sweep and is not moved (covers nodes snapped by an earlier, coplanar step).
constexpr double kOnSweepRelEps = 1e-12;

bool has(const Tet& t, Index v) {
  return t[0] == v || t[1] == v || t[2] == v || t[3] == v;
}

bool has_duplicate(const Tet& t) {
  for (int i = 0; i < 4; ++i) {
    for (int j = i + 1; j < 4; ++j) {
      if (t[static_cast<size_t>(i)] == t[static_cast<size_t>(j)]) return true;
    }
  }
  return false;
}

Tet substitute(Tet t, Index from, Index to) {
  for (auto& v : t) {
    if (v == from) v = to;
  }
  return t;
}

std::array<Index, 3> sorted_face(const Tet& t, int j, int* parity = nullptr) {
  std::array<Index, 3> f{t[static_cast<size_t>(kTetFace[j][0])],
                         t[static_cast<size_t>(kTetFace[j][1])],
                         t[static_cast<size_t>(kTetFace[j][2])]};
  int p = 0;
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < 2 - pass; ++i) {
      if (f[static_cast<size_t>(i)] > f[static_cast<size_t>(i + 1)]) {
        std::swap(f[static_cast<size_t>(i)], f[static_cast<size_t>(i + 1)]);
        p ^= 1;
      }
    }
  }
  if (parity) *parity = p;
  return f;
}

/// Point of segment pq closest to segment rs: parameters (s along pq, u along rs).
void closest_params(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s, double& sp,
                    double& sr) {
  const Vec3 d1 = q - p, d2 = s - r, w = p - r;
  const double a = d1.dot(d1), b = d1.dot(d2), c = d2.dot(d2), d = d1.dot(w), e = d2.dot(w);
  const double den = a * c - b * b;
  sp = den > 1e-300 ? (b * e - c * d) / den : 0.5;
  sr = den > 1e-300 ? (a * e - b * d) / den : 0.5;
  sp = std::clamp(sp, 0.0, 1.0);
  sr = std::clamp(sr, 0.0, 1.0);
}

/// Whether the fixed nodes seen so far hold a component rigidly: three non-collinear ones
/// (fewer leave a rigid-body rotation free, and the stiffness matrix singular).
class Anchor {
 public:
  void add(const Vec3& p) {
    if (count_ == 0) {
      p0_ = p;
      count_ = 1;
    } else if (count_ == 1 && (p - p0_).norm() > 0) {
      p1_ = p;
      count_ = 2;
    } else if (count_ == 2) {
      const Vec3 a = p1_ - p0_, b = p - p0_;
      // Relative collinearity threshold far above round-off of the cross product.
      if (a.cross(b).norm() > 1e-9 * a.norm() * b.norm()) count_ = 3;
    }
  }
  bool any() const { return count_ > 0; }
  bool anchored() const { return count_ == 3; }

 private:
  Vec3 p0_ = Vec3::Zero(), p1_ = Vec3::Zero();
  int count_ = 0;
};

constexpr bool same_edge_order() {
  for (int k = 0; k < 6; ++k) {
    if (mesh::kTetEdges[static_cast<size_t>(k)][0] != kTetEdge[k][0] ||
        mesh::kTetEdges[static_cast<size_t>(k)][1] != kTetEdge[k][1])
      return false;
  }
  return true;
}
static_assert(same_edge_order(), "mesh::kTetEdges and cut::kTetEdge must list edges alike");

}  // namespace

void CutTotals::add(const CutStepReport& r) {
  faces_selected += r.faces_selected;
  faces_dissected += r.faces_dissected;
  nodes_snapped += r.nodes_snapped;
  snaps_refused += r.snaps_refused;
  snaps_failed += r.snaps_failed;
  snaps_outside_star += r.snaps_outside_star;
  faces_pending = r.faces_pending;
  degenerate_found += r.degenerate_found;
  collapses += r.collapses;
  incollapsible += r.incollapsible;
  new_nodes += static_cast<Index>(r.new_nodes.size());
  free_components += r.free_components;
}

/// Uniform hash grid over elements that have a boundary face (deformed bounding boxes).
/// Entries may be stale (moved or changed elements); queries test every candidate exactly.
struct Cutter::Grid {
  double h = 1.0;
  std::int64_t lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};  ///< occupied cell range
  std::unordered_map<std::int64_t, std::vector<Index>> cells;
  static std::int64_t key(std::int64_t i, std::int64_t j, std::int64_t k) {
    constexpr std::int64_t kOff = 1 << 20;
    return ((i + kOff) << 42) | ((j + kOff) << 21) | (k + kOff);
  }
  std::int64_t coord(double x) const { return static_cast<std::int64_t>(std::floor(x / h)); }
};

Cutter::Cutter(CutMesh& mesh, CutOptions options)
    : mesh_(mesh), options_(options), rng_(options.seed), grid_(std::make_unique<Grid>()) {
  INCISE_CHECK_PARAM(options_.degenerate_aspect_ratio >= 0 && options_.degenerate_aspect_ratio < 1,
                     "degenerate_aspect_ratio must lie in [0,1)");
  INCISE_CHECK_PARAM(options_.large_dihedral_angle > 0 && options_.large_dihedral_angle < 3.15,
                     "large_dihedral_angle must lie in (0, π)");
}

Cutter::~Cutter() = default;

void Cutter::end_incision() {
  marked_.clear();
  incomplete_.clear();
  pending_.clear();
}

Cutter::EdgeKey Cutter::edge_key(Index a, Index b) const {
  std::uint64_t oa = static_cast<std::uint32_t>(mesh_.origin(a));
  std::uint64_t ob = static_cast<std::uint32_t>(mesh_.origin(b));
  if (oa > ob) std::swap(oa, ob);
  return (oa << 32) | ob;
}

void Cutter::grid_insert(Index e) {
  if (!mesh_.alive(e)) return;
  bool boundary = false;
  for (int j = 0; j < 4 && !boundary; ++j) boundary = mesh_.neighbor(e, j) < 0;
  if (!boundary) return;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (Index v : mesh_.element(e)) {
    lo = lo.cwiseMin(mesh_.deformed(v));
    hi = hi.cwiseMax(mesh_.deformed(v));
  }
  const std::int64_t c0[3] = {grid_->coord(lo.x()), grid_->coord(lo.y()), grid_->coord(lo.z())};
  const std::int64_t c1[3] = {grid_->coord(hi.x()), grid_->coord(hi.y()), grid_->coord(hi.z())};
  const bool empty = grid_->hi[0] < grid_->lo[0];
  for (int d = 0; d < 3; ++d) {
    grid_->lo[d] = empty ? c0[d] : std::min(grid_->lo[d], c0[d]);
    grid_->hi[d] = empty ? c1[d] : std::max(grid_->hi[d], c1[d]);
  }
  for (std::int64_t i = c0[0]; i <= c1[0]; ++i)
    for (std::int64_t j = c0[1]; j <= c1[1]; ++j)
      for (std::int64_t k = c0[2]; k <= c1[2]; ++k) grid_->cells[Grid::key(i, j, k)].push_back(e);
}

void Cutter::collect_seeds(const Vec3 (&tri)[3], std::vector<Index>& seeds) {
  if (grid_version_ != mesh_.positions_version()) {
    // (Re)build: cell size = mean longest edge of the boundary elements.
    grid_->cells.clear();
    grid_->lo[0] = grid_->lo[1] = grid_->lo[2] = 0;
    grid_->hi[0] = grid_->hi[1] = grid_->hi[2] = -1;
    double sum = 0;
    Index count = 0;
    for (Index e = 0; e < mesh_.element_capacity(); ++e) {
      if (!mesh_.alive(e)) continue;
      bool boundary = false;
      for (int j = 0; j < 4 && !boundary; ++j) boundary = mesh_.neighbor(e, j) < 0;
      if (!boundary) continue;
      const Tet& t = mesh_.element(e);
      double m = 0;
      for (const auto& ed : kTetEdge)
        m = std::max(m, (mesh_.deformed(t[static_cast<size_t>(ed[0])]) -
                         mesh_.deformed(t[static_cast<size_t>(ed[1])]))
                            .norm());
      sum += m;
      ++count;
    }
    grid_->h = count > 0 && sum > 0 ? sum / count : 1.0;
    for (Index e = 0; e < mesh_.element_capacity(); ++e) grid_insert(e);
    grid_version_ = mesh_.positions_version();
  }
  const Vec3 n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized();
  const Vec3 lo = tri[0].cwiseMin(tri[1]).cwiseMin(tri[2]);
  const Vec3 hi = tri[0].cwiseMax(tri[1]).cwiseMax(tri[2]);
  const double h = grid_->h;
  const double reach = 0.5 * h * n.cwiseAbs().sum();
  // Enumerate only cells inside both Δ's box and the occupied range of the grid.
  const std::int64_t q0[3] = {std::max(grid_->coord(lo.x()), grid_->lo[0]),
                              std::max(grid_->coord(lo.y()), grid_->lo[1]),
                              std::max(grid_->coord(lo.z()), grid_->lo[2])};
  const std::int64_t q1[3] = {std::min(grid_->coord(hi.x()), grid_->hi[0]),
                              std::min(grid_->coord(hi.y()), grid_->hi[1]),
                              std::min(grid_->coord(hi.z()), grid_->hi[2])};
  for (std::int64_t i = q0[0]; i <= q1[0]; ++i)
    for (std::int64_t j = q0[1]; j <= q1[1]; ++j)
      for (std::int64_t k = q0[2]; k <= q1[2]; ++k) {
        const Vec3 centre((i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h);
        if (std::abs(n.dot(centre - tri[0])) > reach * (1 + 1e-9)) continue;  // plane misses cell
        auto it = grid_->cells.find(Grid::key(i, j, k));
        if (it == grid_->cells.end()) continue;
        for (Index e : it->second) seeds.push_back(e);
      }
}

void Cutter::select_faces(const Vec3 (&tri)[3], CutStepReport& r,
                          std::vector<std::pair<Index, int>>& faces) {
  std::vector<Index> seeds;
  collect_seeds(tri, seeds);
  for (Index e : incomplete_) seeds.push_back(e);
  std::sort(seeds.begin(), seeds.end());
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());

  stamp_.resize(static_cast<size_t>(mesh_.element_capacity()), 0);
  done_.resize(static_cast<size_t>(mesh_.element_capacity()), 0);
  ++stamp_value_;
  std::deque<Index> queue;
  for (Index e : seeds) {
    if (e < mesh_.element_capacity() && mesh_.alive(e) &&
        stamp_[static_cast<size_t>(e)] != stamp_value_) {
      stamp_[static_cast<size_t>(e)] = stamp_value_;
      queue.push_back(e);
    }
  }
  std::unordered_set<EdgeKey> tested;
  std::vector<Index> touched;
  while (!queue.empty()) {
    const Index e = queue.front();
    queue.pop_front();
    const Tet& t = mesh_.element(e);
    const Vec3 p[4] = {mesh_.deformed(t[0]), mesh_.deformed(t[1]), mesh_.deformed(t[2]),
                       mesh_.deformed(t[3])};
    ++r.elements_tested;
    if (!triangle_meets_tetrahedron(tri[0], tri[1], tri[2], p)) continue;
    touched.push_back(e);
    for (const auto& ed : kTetEdge) {
      Index a = t[static_cast<size_t>(ed[0])], b = t[static_cast<size_t>(ed[1])];
      const EdgeKey key = edge_key(a, b);
      if (marked_.count(key) || !tested.insert(key).second) continue;
      if (b < a) std::swap(a, b);  // test from the lower index: one answer per edge
      const SegmentHit hit =
          intersect_segment_triangle(mesh_.deformed(a), mesh_.deformed(b), tri[0], tri[1], tri[2]);
      if (!hit.hit) continue;
      const Index mark = hit.t > 0.5 + kHalfTie ? b : a;  // ties → lowest index
      marked_.emplace(key, mesh_.origin(mark));
      ++r.edges_intersected;
    }
    for (int j = 0; j < 4; ++j) {
      const Index nb = mesh_.neighbor(e, j);
      if (nb >= 0 && stamp_[static_cast<size_t>(nb)] != stamp_value_) {
        stamp_[static_cast<size_t>(nb)] = stamp_value_;
        queue.push_back(nb);
      }
    }
  }

  // Evaluate touched and remembered incomplete tetrahedra (§3.2.1, Fig. 3.1, 3.2).
  std::vector<Index> candidates = touched;
  for (Index e : incomplete_) candidates.push_back(e);
  evaluate(candidates, r, faces);
}

void Cutter::evaluate(std::vector<Index> candidates, CutStepReport& r,
                      std::vector<std::pair<Index, int>>& faces) {
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  done_.resize(static_cast<size_t>(mesh_.element_capacity()), 0);
  std::vector<std::array<Index, 3>> chosen;
  for (const auto& [e, j] : faces) chosen.push_back(sorted_face(mesh_.element(e), j));
  for (Index e : candidates) {
    if (!mesh_.alive(e)) {
      incomplete_.erase(e);
      continue;
    }
    if (done_[static_cast<size_t>(e)]) {
      incomplete_.erase(e);
      continue;
    }
    const Tet& t = mesh_.element(e);
    int marks = 0;
    for (const auto& ed : kTetEdge) {
      auto it =
          marked_.find(edge_key(t[static_cast<size_t>(ed[0])], t[static_cast<size_t>(ed[1])]));
      if (it == marked_.end()) continue;
      for (int k : {ed[0], ed[1]}) {
        if (mesh_.origin(t[static_cast<size_t>(k)]) == it->second) marks |= 1 << k;
      }
    }
    const int count = __builtin_popcount(static_cast<unsigned>(marks));
    if (count < 3) {
      if (count > 0) incomplete_.insert(e);
      continue;
    }
    int j = 0;
    if (count == 3) {
      while (marks & (1 << j)) ++j;
    } else {
      // All four nodes marked (edges halved, or two sweeps): seeded choice (§3.3).
      ++r.halved_choices;
      std::vector<int> interior;
      for (int k = 0; k < 4; ++k) {
        if (mesh_.neighbor(e, k) >= 0) interior.push_back(k);
      }
      if (interior.empty()) interior = {0, 1, 2, 3};
      j = interior[static_cast<size_t>(rng_() % interior.size())];
    }
    done_[static_cast<size_t>(e)] = 1;
    incomplete_.erase(e);
    if (mesh_.neighbor(e, j) < 0) continue;  // already a boundary (or cut) face
    const auto key = sorted_face(t, j);
    if (std::find(chosen.begin(), chosen.end(), key) != chosen.end()) continue;
    chosen.push_back(key);
    faces.emplace_back(e, j);
  }
}

void Cutter::remark_snapped(const std::vector<Index>& snapped, std::vector<Index>& affected) {
  std::vector<Index> sorted = snapped;
  std::sort(sorted.begin(), sorted.end());
  for (Index v : sorted) {
    for (Index e : mesh_.star(v)) {
      affected.push_back(e);
      const Tet& t = mesh_.element(e);
      for (Index z : t) {
        if (z == v || std::binary_search(sorted.begin(), sorted.end(), z)) continue;
        marked_[edge_key(v, z)] = mesh_.origin(v);
      }
    }
  }
}

bool Cutter::snap_node(Index v, const Vec3& o, const Vec3& n, double scale, CutStepReport& r) {
  const Vec3 x = mesh_.deformed(v);
  if (mesh_.fixed(v)) {
    ++r.snaps_fixed;  // fixed nodes are never moved
    return false;
  }
  if (std::abs(n.dot(x - o)) <= kOnSweepRelEps * scale) {
    ++r.nodes_on_sweep;  // already on the sweep plane (e.g. snapped by an earlier step)
    return true;
  }
  Vec3 w = x;
  bool found = false;
  if (mesh_.on_boundary(v)) {
    // Fig. 3.6: project within each incident boundary face onto plane(Δ) ∩ plane(f).
    double best = std::numeric_limits<double>::infinity();
    for (Index e : mesh_.star(v)) {
      const Tet& t = mesh_.element(e);
      const int lv = mesh_.local_index(e, v);
      for (int j = 0; j < 4; ++j) {
        if (j == lv || mesh_.neighbor(e, j) >= 0) continue;
        const Vec3 a = mesh_.deformed(t[static_cast<size_t>(kTetFace[j][0])]);
        const Vec3 b = mesh_.deformed(t[static_cast<size_t>(kTetFace[j][1])]);
        const Vec3 c = mesh_.deformed(t[static_cast<size_t>(kTetFace[j][2])]);
        Vec3 nf = (b - a).cross(c - a);
        const double area2 = nf.norm();
        if (!(area2 > 0)) continue;
        nf /= area2;
        const double nn = n.dot(nf);
        const double det = 1.0 - nn * nn;
        if (det < 1e-12) continue;  // face parallel to the sweep: no intersection line
        const double r1 = n.dot(o - x), r2 = nf.dot(a - x);
        const double alpha = (r1 - nn * r2) / det, beta = (r2 - nn * r1) / det;
        const Vec3 y = x + alpha * n + beta * nf;
        // barycentric in face abc
        const double l0 = (b - y).cross(c - y).dot(nf) / area2;
        const double l1 = (c - y).cross(a - y).dot(nf) / area2;
        const double l2 = 1.0 - l0 - l1;
        if (l0 < -kInsideTol || l1 < -kInsideTol || l2 < -kInsideTol) continue;
        const double d = (y - x).norm();
        if (d < best) {
          best = d;
          w = y;
          found = true;
        }
      }
    }
  } else {
    w = x - n.dot(x - o) * n;
    found = true;
  }
  if (!found) {
    ++r.snaps_failed;
    ++r.snaps_no_projection;
    return false;
  }
  // Map w back to the reference configuration through the incident element containing it.
  Vec3 W;
  bool located = false;
  for (Index e : mesh_.star(v)) {
    const Tet& t = mesh_.element(e);
    const Vec3 p[4] = {mesh_.deformed(t[0]), mesh_.deformed(t[1]), mesh_.deformed(t[2]),
                       mesh_.deformed(t[3])};
    double l[4];
    if (!barycentric(w, p, l)) continue;
    if (l[0] < -kInsideTol || l[1] < -kInsideTol || l[2] < -kInsideTol || l[3] < -kInsideTol)
      continue;
    W = Vec3::Zero();
    for (int k = 0; k < 4; ++k) W += l[k] * mesh_.reference(t[static_cast<size_t>(k)]);
    located = true;
    break;
  }
  if (!located) {
    ++r.snaps_failed;
    ++r.snaps_outside_star;
    return false;
  }
  const Vec3 X_old = mesh_.reference(v);
  mesh_.set_position(v, W, w);
  if (options_.refuse_inverting_snaps) {
    for (Index e : mesh_.star(v)) {
      const Tet& t = mesh_.element(e);
      if (!(mesh_.reference_volume(t) > 0) || !(mesh_.deformed_volume(t) > 0)) {
        mesh_.set_position(v, X_old, x);
        ++r.snaps_refused;
        return false;
      }
    }
  }
  ++r.nodes_snapped;
  r.moved_nodes.push_back(v);
  return true;
}

void Cutter::snap(const Vec3 (&tri)[3], const std::vector<std::pair<Index, int>>& faces,
                  CutStepReport& r) {
  const Vec3 n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalized();
  std::vector<Index> nodes;
  for (const auto& [e, j] : faces)
    for (int k = 0; k < 3; ++k)
      nodes.push_back(mesh_.element(e)[static_cast<size_t>(kTetFace[j][k])]);
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  const double scale =
      std::max({(tri[1] - tri[0]).norm(), (tri[2] - tri[1]).norm(), (tri[0] - tri[2]).norm()});
  for (Index v : nodes) (void)snap_node(v, tri[0], n, scale, r);
}

bool Cutter::is_degenerate(Index e) const {
  const Tet& t = mesh_.element(e);
  const Vec3 &a = mesh_.reference(t[0]), &b = mesh_.reference(t[1]), &c = mesh_.reference(t[2]),
             &d = mesh_.reference(t[3]);
  // The thesis' aspect ratio (mesh/quality.hpp) is unsigned; an inverted element counts as
  // degenerate whatever its shape.
  return mesh::signed_volume(a, b, c, d) < 0 ||
         mesh::aspect_ratio(a, b, c, d) < options_.degenerate_aspect_ratio;
}

Index Cutter::count_degenerate() const {
  Index c = 0;
  for (Index e = 0; e < mesh_.element_capacity(); ++e) {
    if (mesh_.alive(e) && is_degenerate(e)) ++c;
  }
  return c;
}

bool Cutter::apply_local_op(const std::vector<Index>& old_elements,
                            const std::vector<Tet>& new_tets, CutStepReport& r) {
  for (const Tet& t : new_tets) {
    if (has_duplicate(t)) return false;
    if (!(mesh_.reference_volume(t) > 0) || !(mesh_.deformed_volume(t) > 0)) return false;
  }
  // Surrounding elements E: stars of all involved nodes, minus the old ones.
  std::vector<Index> nodes;
  for (Index e : old_elements)
    for (Index v : mesh_.element(e)) nodes.push_back(v);
  for (const Tet& t : new_tets)
    for (Index v : t) nodes.push_back(v);
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  std::vector<Index> around;
  for (Index v : nodes)
    for (Index e : mesh_.star(v)) around.push_back(e);
  std::sort(around.begin(), around.end());
  around.erase(std::unique(around.begin(), around.end()), around.end());
  std::vector<Index> old_sorted = old_elements;
  std::sort(old_sorted.begin(), old_sorted.end());
  std::vector<Tet> after = new_tets;
  for (Index e : around) {
    if (!std::binary_search(old_sorted.begin(), old_sorted.end(), e))
      after.push_back(mesh_.element(e));
  }
  // Each oriented face at most once; each face in at most two elements (manifold, Fig. 3.10).
  std::map<std::array<Index, 3>, std::array<int, 2>> face_count;
  for (const Tet& t : after) {
    for (int j = 0; j < 4; ++j) {
      int parity = 0;
      const auto f = sorted_face(t, j, &parity);
      auto& c = face_count[f];
      if (++c[static_cast<size_t>(parity)] > 1) return false;
    }
  }
  // Star of every involved node still face-connected (dissection precondition, §7.3).
  for (Index v : nodes) {
    std::vector<size_t> in;
    for (size_t i = 0; i < after.size(); ++i) {
      if (has(after[i], v)) in.push_back(i);
    }
    if (in.size() < 2) continue;
    std::vector<Index> parent(in.size());
    std::iota(parent.begin(), parent.end(), 0);
    auto root = [&parent](Index i) {
      while (parent[static_cast<size_t>(i)] != i) i = parent[static_cast<size_t>(i)];
      return i;
    };
    size_t classes = in.size();
    for (size_t a = 0; a < in.size(); ++a) {
      for (size_t b = a + 1; b < in.size(); ++b) {
        int shared = 0;
        for (Index w : after[in[a]]) shared += has(after[in[b]], w) ? 1 : 0;
        if (shared == 3) {
          const Index ra = root(static_cast<Index>(a)), rb = root(static_cast<Index>(b));
          if (ra != rb) {
            parent[static_cast<size_t>(std::max(ra, rb))] = std::min(ra, rb);
            --classes;
          }
        }
      }
    }
    if (classes != 1) return false;
  }
  // Apply through replace-elements (§7.3).
  for (Index e : old_sorted) r.changed_elements.push_back(e);
  const std::vector<Index> added = mesh_.replace(old_sorted, new_tets);
  for (Index e : added) r.changed_elements.push_back(e);
  // Representatives for the component check: a removed element is replaced by a new one in
  // the same place (or by a surviving neighbour when the operation only removed elements).
  Index stand_in = added.empty() ? -1 : added[0];
  for (Index e : around) {
    if (stand_in < 0 && mesh_.alive(e)) stand_in = e;
  }
  for (Index e : old_sorted) {
    if (!mesh_.alive(e) && stand_in >= 0) replaced_[e] = stand_in;
  }
  for (Index v : nodes) {
    if (mesh_.unused(v)) r.removed_nodes.push_back(v);
  }
  return true;
}

bool Cutter::try_recipe(Index e, CutStepReport& r) {
  const Tet t = mesh_.element(e);
  std::array<Vec3, 4> X{mesh_.reference(t[0]), mesh_.reference(t[1]), mesh_.reference(t[2]),
                        mesh_.reference(t[3])};
  // §3.2.3 classification by the mesh module (mesh/quality.hpp; its kTetEdges order is
  // kTetEdge's). try_recipe is only called for degenerate elements, so every element is
  // classified here (infinite aspect-ratio threshold; an inverted element is degenerate too).
  const mesh::ShapeInfo info = mesh::classify_tetrahedron(
      X[0], X[1], X[2], X[3],
      {std::numeric_limits<double>::infinity(), options_.large_dihedral_angle});
  const std::array<double, 6> angle = mesh::dihedral_angles(X[0], X[1], X[2], X[3]);
  std::array<int, 6> large{};  // large-angle edges by decreasing angle
  int num_large = 0;
  for (int k = 0; k < 6; ++k) {
    if (info.large_angle_edge[static_cast<size_t>(k)]) large[static_cast<size_t>(num_large++)] = k;
  }
  for (int i = 1; i < num_large; ++i) {  // insertion sort by decreasing angle (≤ 6 entries)
    for (int j = i; j > 0 && angle[static_cast<size_t>(large[static_cast<size_t>(j)])] >
                                 angle[static_cast<size_t>(large[static_cast<size_t>(j - 1)])];
         --j)
      std::swap(large[static_cast<size_t>(j)], large[static_cast<size_t>(j - 1)]);
  }
  int shortest_edge = 0;
  for (int k = 1; k < 6; ++k) {
    if ((X[static_cast<size_t>(kTetEdge[k][0])] - X[static_cast<size_t>(kTetEdge[k][1])]).norm() <
        (X[static_cast<size_t>(kTetEdge[shortest_edge][0])] -
         X[static_cast<size_t>(kTetEdge[shortest_edge][1])])
            .norm())
      shortest_edge = k;
  }

  auto edge_star = [&](Index a, Index b) {
    std::vector<Index> out;
    for (Index f : mesh_.star(a)) {
      if (has(mesh_.element(f), b)) out.push_back(f);
    }
    return out;
  };
  // Collapse u into v: u disappears, elements containing both vanish.
  auto collapse = [&](Index u, Index v) {
    if (mesh_.fixed(u) && !mesh_.fixed(v)) return false;
    std::vector<Index> old = mesh_.star(u);
    std::vector<Tet> nt;
    for (Index f : old) {
      if (!has(mesh_.element(f), v)) nt.push_back(substitute(mesh_.element(f), u, v));
    }
    return apply_local_op(old, nt, r);
  };
  auto needle = [&]() {
    const Index a = t[static_cast<size_t>(kTetEdge[shortest_edge][0])];
    const Index b = t[static_cast<size_t>(kTetEdge[shortest_edge][1])];
    // Prefer keeping boundary nodes (a flat surface keeps its shape).
    const bool ab = mesh_.on_boundary(a), bb = mesh_.on_boundary(b);
    if (ab && !bb) return collapse(b, a) || collapse(a, b);
    return collapse(a, b) || collapse(b, a);
  };
  // The large angle lies at edge k; a spindle's fourth node lies near the *opposite* edge ab
  // (thesis §3.2.3: "the edge opposite the large angle is split"). Split ab at the node p of
  // edge k nearest to line ab and collapse the split node into p.
  auto spindle = [&](int k) {
    Index a = -1, b = -1;
    for (int j = 0; j < 4; ++j) {
      if (j == kTetEdge[k][0] || j == kTetEdge[k][1]) continue;
      (a < 0 ? a : b) = t[static_cast<size_t>(j)];
    }
    const Index others[2] = {t[static_cast<size_t>(kTetEdge[k][0])],
                             t[static_cast<size_t>(kTetEdge[k][1])]};
    const Vec3 d = (mesh_.reference(b) - mesh_.reference(a)).normalized();
    auto dist = [&](Index v) {
      const Vec3 w = mesh_.reference(v) - mesh_.reference(a);
      return (w - w.dot(d) * d).norm();
    };
    const Index p = dist(others[0]) <= dist(others[1]) ? others[0] : others[1];
    std::vector<Index> old = edge_star(a, b);
    std::vector<Tet> nt;
    for (Index f : old) {
      for (Index q : {a, b}) {
        const Tet u = substitute(mesh_.element(f), q, p);
        if (!has_duplicate(u)) nt.push_back(u);
      }
    }
    return apply_local_op(old, nt, r);
  };
  // Split both crossing edges, collapse the short edge between the new nodes (sliver).
  auto sliver = [&](int k1, int k2) {
    const Index a = t[static_cast<size_t>(kTetEdge[k1][0])],
                b = t[static_cast<size_t>(kTetEdge[k1][1])];
    const Index c = t[static_cast<size_t>(kTetEdge[k2][0])],
                d = t[static_cast<size_t>(kTetEdge[k2][1])];
    if (a == c || a == d || b == c || b == d) return false;
    double s1 = 0.5, s2 = 0.5;
    closest_params(mesh_.reference(a), mesh_.reference(b), mesh_.reference(c), mesh_.reference(d),
                   s1, s2);
    s1 = std::clamp(s1, 0.05, 0.95);
    s2 = std::clamp(s2, 0.05, 0.95);
    const Vec3 Xm = 0.5 * ((1 - s1) * mesh_.reference(a) + s1 * mesh_.reference(b) +
                           (1 - s2) * mesh_.reference(c) + s2 * mesh_.reference(d));
    const Vec3 xm = 0.5 * ((1 - s1) * mesh_.deformed(a) + s1 * mesh_.deformed(b) +
                           (1 - s2) * mesh_.deformed(c) + s2 * mesh_.deformed(d));
    const bool fix = (mesh_.fixed(a) && mesh_.fixed(b)) || (mesh_.fixed(c) && mesh_.fixed(d));
    std::vector<Index> old = edge_star(a, b);
    for (Index f : edge_star(c, d)) old.push_back(f);
    std::sort(old.begin(), old.end());
    old.erase(std::unique(old.begin(), old.end()), old.end());
    const Index m = mesh_.add_node(Xm, xm, fix, mesh_.num_nodes());
    std::vector<Tet> nt;
    for (Index f : old) {
      std::vector<Tet> pieces{mesh_.element(f)};
      if (has(pieces[0], a) && has(pieces[0], b))
        pieces = {substitute(pieces[0], a, m), substitute(pieces[0], b, m)};
      std::vector<Tet> out;
      for (const Tet& q : pieces) {
        if (has(q, c) && has(q, d)) {
          out.push_back(substitute(q, c, m));
          out.push_back(substitute(q, d, m));
        } else {
          out.push_back(q);
        }
      }
      for (const Tet& q : out) {
        if (!has_duplicate(q)) nt.push_back(q);
      }
    }
    if (apply_local_op(old, nt, r)) {
      r.new_nodes.push_back(m);
      return true;
    }
    r.removed_nodes.push_back(m);  // created for the attempt, left unused
    return false;
  };
  // Split the face opposite the apex, collapse the new node into the apex (cap).
  auto cap = [&](int apex) {
    const Index d = t[static_cast<size_t>(apex)];
    Index f3[3];
    for (int k = 0; k < 3; ++k) f3[k] = t[static_cast<size_t>(kTetFace[apex][k])];
    std::vector<Index> old;
    for (Index f : mesh_.star(f3[0])) {
      if (has(mesh_.element(f), f3[1]) && has(mesh_.element(f), f3[2])) old.push_back(f);
    }
    std::vector<Tet> nt;
    for (Index f : old) {
      for (Index q : f3) {
        const Tet u = substitute(mesh_.element(f), q, d);
        if (!has_duplicate(u)) nt.push_back(u);
      }
    }
    return apply_local_op(old, nt, r);
  };

  bool ok = false;
  switch (info.shape) {
    case mesh::ShapeClass::kGood:
    case mesh::ShapeClass::kNeedle: break;
    case mesh::ShapeClass::kSpindle: ok = spindle(large[0]); break;
    case mesh::ShapeClass::kSliver: {
      const int k1 = large[0], k2 = large[1];
      ok = sliver(k1, k2) || spindle(k1) || spindle(k2);
      break;
    }
    case mesh::ShapeClass::kCap:
    case mesh::ShapeClass::kFlat: {  // ≥ 3 large angles: the three largest define the cap
      // Apex: the node near the opposite face's interior, common to the three largest-angle
      // edges (the large angles of a cap are at the edges from the apex; Fig. 3.8).
      int apex = -1;
      for (int j = 0; j < 4 && apex < 0; ++j) {
        bool on_all = true;
        for (int q = 0; q < 3; ++q)
          on_all = on_all && (kTetEdge[large[static_cast<size_t>(q)]][0] == j ||
                              kTetEdge[large[static_cast<size_t>(q)]][1] == j);
        if (on_all) apex = j;
      }
      ok = (apex >= 0 && cap(apex)) || spindle(large[0]);
      break;
    }
  }
  if (!ok) ok = needle();
  if (ok) ++r.collapses;
  return ok;
}

void Cutter::cut_free(Index e, CutStepReport& r) {
  std::vector<std::pair<Index, int>> faces;
  std::vector<Index> around;
  for (int j = 0; j < 4; ++j) {
    const Index nb = mesh_.neighbor(e, j);
    if (nb >= 0) {
      faces.emplace_back(e, j);
      around.push_back(nb);
    }
  }
  // Removing e may disconnect its neighbours from each other: check them afterwards.
  for (size_t k = 1; k < around.size(); ++k) separated_pairs_.emplace_back(around[0], around[k]);
  if (!around.empty()) replaced_[e] = around[0];
  if (!faces.empty()) {
    std::vector<Index> changed;
    (void)mesh_.dissect(faces, changed, r.new_nodes);
    for (Index c : changed) r.changed_elements.push_back(c);
  }
  const Tet t = mesh_.element(e);
  (void)mesh_.replace({e}, {});
  r.changed_elements.push_back(e);
  for (Index v : t) {
    if (mesh_.unused(v)) r.removed_nodes.push_back(v);
  }
}

void Cutter::remove_degeneracies(std::vector<Index> region, CutStepReport& r) {
  auto degenerate_in = [&](const std::vector<Index>& reg) {
    std::vector<Index> out;
    for (Index e : reg) {
      if (e < mesh_.element_capacity() && mesh_.alive(e) && is_degenerate(e)) out.push_back(e);
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  };
  auto grow = [&](std::vector<Index>& reg) {
    std::vector<Index> nodes;
    for (Index e : reg)
      if (e < mesh_.element_capacity() && mesh_.alive(e))
        for (Index v : mesh_.element(e)) nodes.push_back(v);
    for (Index e : r.changed_elements)
      if (mesh_.alive(e))
        for (Index v : mesh_.element(e)) nodes.push_back(v);
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    reg.clear();
    for (Index v : nodes)
      for (Index e : mesh_.star(v)) reg.push_back(e);
    std::sort(reg.begin(), reg.end());
    reg.erase(std::unique(reg.begin(), reg.end()), reg.end());
  };
  std::vector<Index> list = degenerate_in(region);
  r.degenerate_found += static_cast<Index>(list.size());
  for (int pass = 0; pass < options_.max_degeneracy_passes && !list.empty(); ++pass) {
    ++r.removal_passes;
    for (Index e : list) {
      if (mesh_.alive(e) && is_degenerate(e)) (void)try_recipe(e, r);
    }
    grow(region);
    std::vector<Index> next = degenerate_in(region);
    const bool shorter = next.size() < list.size();
    list = std::move(next);
    if (!shorter) break;
  }
  for (Index e : list) {
    if (mesh_.alive(e) && is_degenerate(e)) {
      cut_free(e, r);
      ++r.incollapsible;
    }
  }
}

void Cutter::remove_degeneracies_everywhere(CutStepReport& report) {
  std::vector<Index> all;
  for (Index e = 0; e < mesh_.element_capacity(); ++e) {
    if (mesh_.alive(e)) all.push_back(e);
  }
  remove_degeneracies(std::move(all), report);
}

bool Cutter::local_component_check(const std::vector<std::pair<Index, Index>>& sides,
                                   CutStepReport& r) {
  // Seeds: the elements on both sides of every face separated in this step (and the
  // neighbours of removed elements). Each seed starts a breadth-first group; the open groups
  // are expanded one element each in turn, and groups that touch are merged. Expansion stops
  // when at most one open group is left. A group whose frontier empties is a whole component
  // S: without fixed nodes it is a new free component (the fixed nodes of the old component
  // all lie elsewhere); with fixed nodes the rest may have lost them (or S holds fewer than
  // three non-collinear ones), so the caller falls back to the O(n) search (return false). Groups
  // near one cut front merge after exploring a neighbourhood of the front, so the usual cost does
  // not depend on the mesh size.
  struct Group {
    std::deque<Index> frontier;
    std::vector<Index> members;
    bool closed = false;
  };
  std::vector<Group> groups;
  std::vector<int> parent;
  std::unordered_map<Index, int> owner;
  auto find = [&parent](int g) {
    while (parent[static_cast<size_t>(g)] != g) g = parent[static_cast<size_t>(g)];
    return g;
  };
  auto resolve = [this](Index e) {
    for (int hops = 0; hops < 64 && !mesh_.alive(e); ++hops) {
      auto it = replaced_.find(e);
      if (it == replaced_.end()) return Index{-1};
      e = it->second;
    }
    return mesh_.alive(e) ? e : Index{-1};
  };
  for (const auto& pair : sides) {
    for (Index raw : {pair.first, pair.second}) {
      const Index e = resolve(raw);
      if (e < 0) return false;
      if (owner.count(e)) continue;
      owner.emplace(e, static_cast<int>(groups.size()));
      parent.push_back(static_cast<int>(groups.size()));
      groups.emplace_back();
      groups.back().frontier.push_back(e);
      groups.back().members.push_back(e);
    }
  }
  std::vector<std::vector<Index>> free_parts;
  auto open_roots = [&]() {
    std::vector<int> roots;
    for (int g = 0; g < static_cast<int>(groups.size()); ++g) {
      if (find(g) == g && !groups[static_cast<size_t>(g)].closed) roots.push_back(g);
    }
    return roots;
  };
  for (std::vector<int> roots = open_roots(); roots.size() > 1; roots = open_roots()) {
    for (int g0 : roots) {
      const int g = find(g0);
      Group& grp = groups[static_cast<size_t>(g)];
      if (g != g0 || grp.closed) continue;
      if (grp.frontier.empty()) {
        Anchor anchor;
        for (Index e : grp.members)
          for (Index v : mesh_.element(e))
            if (mesh_.fixed(v)) anchor.add(mesh_.reference(v));
        // Fixed nodes in S: the rest may have lost its anchor, or S may be anchored by fewer
        // than three non-collinear nodes; the O(n) search decides both.
        if (anchor.any()) return false;
        grp.closed = true;
        free_parts.push_back(grp.members);
        continue;
      }
      const Index e = grp.frontier.front();
      grp.frontier.pop_front();
      for (int j = 0; j < 4; ++j) {
        const Index nb = mesh_.neighbor(e, j);
        if (nb < 0) continue;
        auto it = owner.find(nb);
        if (it == owner.end()) {
          owner.emplace(nb, g);
          Group& mine = groups[static_cast<size_t>(find(g))];
          mine.members.push_back(nb);
          mine.frontier.push_back(nb);
          continue;
        }
        const int h = find(it->second), mine_root = find(g);
        if (h == mine_root) continue;
        if (groups[static_cast<size_t>(h)].closed) return false;  // impossible when valid
        // Merge the smaller group into the larger.
        int big = h, small = mine_root;
        if (groups[static_cast<size_t>(big)].members.size() <
            groups[static_cast<size_t>(small)].members.size())
          std::swap(big, small);
        Group& B = groups[static_cast<size_t>(big)];
        Group& S = groups[static_cast<size_t>(small)];
        B.members.insert(B.members.end(), S.members.begin(), S.members.end());
        B.frontier.insert(B.frontier.end(), S.frontier.begin(), S.frontier.end());
        S.members.clear();
        S.frontier.clear();
        parent[static_cast<size_t>(small)] = big;
      }
    }
  }
  for (auto& part : free_parts) {
    ++r.free_components;
    if (options_.free_components != FreeComponentPolicy::kFixOnFace) continue;
    std::sort(part.begin(), part.end());
    for (Index e : part) {
      int j = 0;
      while (j < 4 && mesh_.neighbor(e, j) >= 0) ++j;
      if (j == 4) continue;
      for (int k = 0; k < 3; ++k) {
        const Index v = mesh_.element(e)[static_cast<size_t>(kTetFace[j][k])];
        if (!mesh_.fixed(v)) r.fixed_nodes.push_back(v);
        mesh_.set_fixed(v, true);
      }
      ++r.components_fixed;
      break;
    }
  }
  return true;
}

void Cutter::check_components(CutStepReport& r) {
  const Index cap = mesh_.element_capacity();
  std::vector<Index> comp(static_cast<size_t>(cap), -1);
  Index ncomp = 0;
  std::vector<Index> stack;
  for (Index s = 0; s < cap; ++s) {
    if (!mesh_.alive(s) || comp[static_cast<size_t>(s)] >= 0) continue;
    Anchor anchor;
    Index face_e = -1;
    int face_j = -1;
    comp[static_cast<size_t>(s)] = ncomp;
    stack.assign(1, s);
    while (!stack.empty()) {
      const Index e = stack.back();
      stack.pop_back();
      for (Index v : mesh_.element(e))
        if (mesh_.fixed(v)) anchor.add(mesh_.reference(v));
      for (int j = 0; j < 4; ++j) {
        const Index nb = mesh_.neighbor(e, j);
        if (nb < 0) {
          if (face_e < 0 || e < face_e) {
            face_e = e;
            face_j = j;
          }
        } else if (comp[static_cast<size_t>(nb)] < 0) {
          comp[static_cast<size_t>(nb)] = ncomp;
          stack.push_back(nb);
        }
      }
    }
    ++ncomp;
    if (anchor.anchored()) continue;
    ++r.free_components;
    if (options_.free_components == FreeComponentPolicy::kFixOnFace && face_e >= 0) {
      for (int k = 0; k < 3; ++k) {
        const Index v = mesh_.element(face_e)[static_cast<size_t>(kTetFace[face_j][k])];
        if (!mesh_.fixed(v)) r.fixed_nodes.push_back(v);
        mesh_.set_fixed(v, true);
      }
      ++r.components_fixed;
    }
  }
}

CutStepReport Cutter::step(const Vec3& a, const Vec3& b, const Vec3& c) {
  CutStepReport r;
  INCISE_CHECK_PARAM(a.allFinite() && b.allFinite() && c.allFinite(),
                     "sweep triangle has non-finite coordinates");
  const Vec3 tri[3] = {a, b, c};
  const double longest =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  if (!((b - a).cross(c - a).norm() > kSweepAreaRelEps * longest) || !(longest > 0)) {
    r.status = CutStatus::kDegenerateSweep;
    return r;
  }
  std::vector<std::pair<Index, int>> faces;
  select_faces(tri, r, faces);
  if (!faces.empty()) {
    if (options_.snap_nodes) {
      snap(tri, faces, r);
      // The sweep now passes through every snapped node: move the marks of the incident
      // edges there and select the faces this completes (see docs/cutting.md, "lag").
      std::vector<Index> affected;
      if (options_.remark_snapped_nodes) remark_snapped(r.moved_nodes, affected);
      const size_t before = faces.size();
      evaluate(affected, r, faces);
      if (faces.size() > before) {
        const std::vector<std::pair<Index, int>> extra(faces.begin() + static_cast<long>(before),
                                                       faces.end());
        snap(tri, extra, r);
      }
    }
    r.faces_selected = static_cast<Index>(faces.size());
    std::vector<Index> changed;
    std::vector<mesh::FaceHandle> cut = pending_;
    for (const auto& [e, j] : faces) cut.push_back(mesh_.face_handle(e, j));
    std::vector<std::pair<Index, Index>>& sides = separated_pairs_;
    sides.clear();  // element pairs across the cut faces (+ neighbours of cut-free elements)
    replaced_.clear();
    {
      const auto& conn = mesh_.connectivity();
      for (const auto& f : cut) {
        if (conn.is_alive(f) && conn.mate(f).valid())
          sides.emplace_back(conn.element(f).index, conn.element(conn.mate(f)).index);
      }
    }
    r.faces_dissected = mesh_.dissect(cut, changed, r.new_nodes);
    pending_.clear();
    for (const auto& f : cut) {
      const auto& conn = mesh_.connectivity();
      if (conn.is_alive(f) && conn.mate(f).valid()) pending_.push_back(f);
    }
    r.changed_elements.insert(r.changed_elements.end(), changed.begin(), changed.end());
    if (options_.remove_degeneracies) {
      std::vector<Index> region;
      std::vector<Index> nodes = r.moved_nodes;
      nodes.insert(nodes.end(), r.new_nodes.begin(), r.new_nodes.end());
      for (const auto& [e, j] : faces)
        for (Index v : mesh_.element(e)) nodes.push_back(v);
      for (Index v : nodes)
        for (Index e : mesh_.star(v)) region.push_back(e);
      std::sort(region.begin(), region.end());
      region.erase(std::unique(region.begin(), region.end()), region.end());
      remove_degeneracies(std::move(region), r);
    }
    if (options_.check_components && (r.faces_dissected > 0 || r.incollapsible > 0)) {
      // Only a separated face pair or a cut-free element can disconnect the mesh; if both
      // sides of every separated pair (the neighbours of every removed element) still reach
      // each other, the components are unchanged.
      if (!local_component_check(sides, r)) {
        r.full_component_check = true;
        check_components(r);
      }
    }
  }
  // Keep the search grid current around the edit.
  std::vector<Index> regrid = r.changed_elements;
  for (Index v : r.moved_nodes)
    for (Index e : mesh_.star(v)) regrid.push_back(e);
  std::sort(regrid.begin(), regrid.end());
  regrid.erase(std::unique(regrid.begin(), regrid.end()), regrid.end());
  for (Index e : regrid) grid_insert(e);
  std::sort(r.changed_elements.begin(), r.changed_elements.end());
  r.changed_elements.erase(std::unique(r.changed_elements.begin(), r.changed_elements.end()),
                           r.changed_elements.end());
  std::sort(r.removed_nodes.begin(), r.removed_nodes.end());
  r.removed_nodes.erase(std::unique(r.removed_nodes.begin(), r.removed_nodes.end()),
                        r.removed_nodes.end());
  r.incomplete_elements = static_cast<Index>(incomplete_.size());
  r.faces_pending = static_cast<Index>(pending_.size());
  return r;
}

}  // namespace incise::cut
