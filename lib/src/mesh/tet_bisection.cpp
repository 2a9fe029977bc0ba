#include <incise/core/error.hpp>
#include <incise/mesh/quality.hpp>
#include <incise/mesh/tet_bisection.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace incise::mesh {

namespace {

using Edge = std::array<Index, 2>;

Edge edge_of(Index p, Index q) {
  return p < q ? Edge{{p, q}} : Edge{{q, p}};
}

bool same_edge(const Edge& e, Index p, Index q) {
  return (e[0] == p && e[1] == q) || (e[0] == q && e[1] == p);
}

/// The strict total order of edges of AMP §2: squared length, then smaller vertex, then larger.
struct EdgeOrder {
  const Eigen::Matrix3Xd& x;
  double len2(Index p, Index q) const { return (x.col(p) - x.col(q)).squaredNorm(); }
  /// True when edge (p, q) is greater than edge (r, s).
  bool greater(Index p, Index q, Index r, Index s) const {
    const double l = len2(p, q), m = len2(r, s);
    if (l != m) return l > m;
    const Edge a = edge_of(p, q), b = edge_of(r, s);
    return a > b;
  }
  /// The maximal edge of triangle (p, q, r).
  Edge face_max(Index p, Index q, Index r) const {
    Edge best = edge_of(p, q);
    if (greater(q, r, best[0], best[1])) best = edge_of(q, r);
    if (greater(p, r, best[0], best[1])) best = edge_of(p, r);
    return best;
  }
};

/// The vertex of e that is not v (pre: v ∈ e).
Index other(const Edge& e, Index v) {
  return e[0] == v ? e[1] : e[0];
}

/// Orientation determinant det(b − a, c − a, d − a) (6 × signed volume).
double orient(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).dot((c - a).cross(d - a));
}

/// Barycentric coordinates of x in tetrahedron (p0, p1, p2, p3) (any orientation; not flat).
std::array<double, 4> barycentric(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3,
                                  const Vec3& x) {
  const double v = orient(p0, p1, p2, p3);
  return {{orient(x, p1, p2, p3) / v, orient(p0, x, p2, p3) / v, orient(p0, p1, x, p3) / v,
           orient(p0, p1, p2, x) / v}};
}

// Barycentric tolerance of locate and of the segment test: points on a shared face or edge
// count as inside whichever way the rounding of the orientation determinants goes (their
// relative error is a few ulps of the terms, far below 1e-12).
constexpr double kBaryTol = 1e-12;

const MeshData& checked(const MeshData& m) {
  INCISE_CHECK_PARAM(m.dimension == 3 && m.cells.rows() == 4,
                     "TetBisectionMesh needs a 3D tetrahedral mesh (dimension 3, 4 x m cells)");
  for (Index c = 0; c < m.num_cells(); ++c) {
    for (int r = 0; r < 4; ++r)
      INCISE_CHECK(m.cells(r, c) >= 0 && m.cells(r, c) < m.num_points(),
                   "TetBisectionMesh: cell " + std::to_string(c) +
                       " has a vertex index out of "
                       "range");
    const double v = signed_volume(m.points.col(m.cells(0, c)), m.points.col(m.cells(1, c)),
                                   m.points.col(m.cells(2, c)), m.points.col(m.cells(3, c)));
    INCISE_CHECK_PARAM(v > 0.0, "TetBisectionMesh: tetrahedron " + std::to_string(c) +
                                    " has non-positive volume " + std::to_string(v) +
                                    " m^3 (cells must be positively oriented)");
  }
  return m;
}

}  // namespace

TetBisectionMesh::Type TetBisectionMesh::type_of(const Marking& m) {
  const Index c = m.v[2], d = m.v[3];
  const bool cd0 = same_edge(m.m0, c, d), cd1 = same_edge(m.m1, c, d);
  if (cd0 && cd1) return Type::kO;
  if (cd0 || cd1) return Type::kM;
  const Index x = other(m.m0, m.v[0]), y = other(m.m1, m.v[1]);
  if (x == y) return m.flag ? Type::kPf : Type::kPu;
  return Type::kA;
}

MeshData TetBisectionMesh::to_mesh_data() const {
  MeshData m = conn_.to_mesh_data(points_);
  if (root_tags_.empty()) return m;
  // Connectivity::cells() and elements() both list live elements in slot order.
  m.cell_tags.reserve(static_cast<std::size_t>(m.num_cells()));
  for (const ElementHandle e : conn_.elements()) {
    int n = node_of(e);
    while (tree_[static_cast<std::size_t>(n)].parent >= 0)
      n = tree_[static_cast<std::size_t>(n)].parent;
    m.cell_tags.push_back(root_tags_[static_cast<std::size_t>(n)]);
  }
  return m;
}

TetBisectionMesh::TetBisectionMesh(const MeshData& tets)
    : conn_(Connectivity::from_mesh_data(checked(tets))), points_(tets.points) {
  const EdgeOrder order{points_};
  for (const ElementHandle e : conn_.elements()) {
    const Simplex& s = conn_.simplex(e);
    // Refinement edge: the maximal edge (AMP §2).
    Edge r = edge_of(s.vertex(0), s.vertex(1));
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j)
        if (order.greater(s.vertex(i), s.vertex(j), r[0], r[1]))
          r = edge_of(s.vertex(i), s.vertex(j));
    TreeNode n;
    n.simplex = s;
    n.element = e;
    Marking& m = n.marking;
    m.v[0] = r[0];
    m.v[1] = r[1];
    int k = 2;
    for (int i = 0; i < 4; ++i)
      if (s.vertex(i) != r[0] && s.vertex(i) != r[1])
        m.v[static_cast<std::size_t>(k++)] = s.vertex(i);
    m.m0 = order.face_max(m.v[0], m.v[2], m.v[3]);
    m.m1 = order.face_max(m.v[1], m.v[2], m.v[3]);
    set_node(e, static_cast<int>(tree_.size()));
    tree_.push_back(n);
  }
  num_roots_ = static_cast<int>(tree_.size());
  // Roots were made in element order, which is the starting cells' order (from_mesh_data).
  if (tets.cell_tags.size() == static_cast<std::size_t>(tets.num_cells()))
    root_tags_ = tets.cell_tags;
  num_start_vertices_ = conn_.num_vertices();

  // Uniform grid of the roots' bounding boxes, about one cell per root.
  if (num_roots_ > 0) {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (int r = 0; r < num_roots_; ++r)
      for (int i = 0; i < 4; ++i) {
        lo = lo.cwiseMin(points_.col(tree_[static_cast<std::size_t>(r)].simplex.vertex(i)));
        hi = hi.cwiseMax(points_.col(tree_[static_cast<std::size_t>(r)].simplex.vertex(i)));
      }
    const Vec3 ext = (hi - lo).cwiseMax(1e-300);
    const double cell = std::cbrt(ext.prod() / static_cast<double>(num_roots_));
    for (int a = 0; a < 3; ++a) {
      const double n = std::ceil(ext(a) / cell);
      grid_n_[static_cast<std::size_t>(a)] = static_cast<int>(std::clamp(n, 1.0, 512.0));
      grid_cell_(a) = ext(a) / grid_n_[static_cast<std::size_t>(a)];
    }
    grid_lo_ = lo;
    const std::size_t cells = static_cast<std::size_t>(grid_n_[0]) *
                              static_cast<std::size_t>(grid_n_[1]) *
                              static_cast<std::size_t>(grid_n_[2]);
    std::vector<std::array<int, 6>> range(static_cast<std::size_t>(num_roots_));
    grid_start_.assign(cells + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      for (int r = 0; r < num_roots_; ++r) {
        auto& rg = range[static_cast<std::size_t>(r)];
        if (pass == 0) {
          Vec3 blo = points_.col(tree_[static_cast<std::size_t>(r)].simplex.vertex(0)), bhi = blo;
          for (int i = 1; i < 4; ++i) {
            blo = blo.cwiseMin(points_.col(tree_[static_cast<std::size_t>(r)].simplex.vertex(i)));
            bhi = bhi.cwiseMax(points_.col(tree_[static_cast<std::size_t>(r)].simplex.vertex(i)));
          }
          for (int a = 0; a < 3; ++a) {
            const int na = grid_n_[static_cast<std::size_t>(a)];
            // The box grows by 1e-6 of a cell so that points within locate's tolerance of
            // the tetrahedron fall into one of its cells whatever the rounding.
            const double pad = 1e-6 * grid_cell_(a);
            rg[static_cast<std::size_t>(a)] = std::clamp(
                static_cast<int>(std::floor((blo(a) - pad - lo(a)) / grid_cell_(a))), 0, na - 1);
            rg[static_cast<std::size_t>(a + 3)] = std::clamp(
                static_cast<int>(std::floor((bhi(a) + pad - lo(a)) / grid_cell_(a))), 0, na - 1);
          }
        }
        for (int k = rg[2]; k <= rg[5]; ++k)
          for (int j = rg[1]; j <= rg[4]; ++j)
            for (int i = rg[0]; i <= rg[3]; ++i) {
              const std::size_t c = static_cast<std::size_t>(i + grid_n_[0] * (j + grid_n_[1] * k));
              if (pass == 0)
                ++grid_start_[c + 1];
              else
                grid_roots_[static_cast<std::size_t>(grid_start_[c]++)] = r;
            }
      }
      if (pass == 0) {
        for (std::size_t c = 0; c < cells; ++c) grid_start_[c + 1] += grid_start_[c];
        grid_roots_.resize(static_cast<std::size_t>(grid_start_[cells]));
      } else {
        // grid_start_[c] now holds the end of cell c: shift back.
        for (std::size_t c = cells; c > 0; --c) grid_start_[c] = grid_start_[c - 1];
        grid_start_[0] = 0;
      }
    }
  }
}

void TetBisectionMesh::set_max_bisections_per_call(long n) {
  INCISE_CHECK(n >= 1, "set_max_bisections_per_call: the limit must be >= 1");
  max_bisections_ = n;
}

void TetBisectionMesh::set_node(ElementHandle e, int node) {
  if (static_cast<std::size_t>(e.index) >= node_of_slot_.size())
    node_of_slot_.resize(static_cast<std::size_t>(e.index) + 1, -1);
  node_of_slot_[static_cast<std::size_t>(e.index)] = node;
}

std::array<Index, 2> TetBisectionMesh::parents(Index v) const {
  INCISE_CHECK(v >= 0 && v < conn_.num_vertices(),
               "parents: vertex " + std::to_string(v) + " is out of range");
  if (v < num_start_vertices_) return {{-1, -1}};
  return parents_[static_cast<std::size_t>(v - num_start_vertices_)];
}

int TetBisectionMesh::node_of(ElementHandle e) const {
  INCISE_CHECK(conn_.is_alive(e), "TetBisectionMesh: element is not alive");
  return node_of_slot_[static_cast<std::size_t>(e.index)];
}

const TetBisectionMesh::Marking& TetBisectionMesh::marking(ElementHandle e) const {
  return tree_[static_cast<std::size_t>(node_of(e))].marking;
}

TetBisectionMesh::Type TetBisectionMesh::type(ElementHandle e) const {
  return type_of(marking(e));
}

std::array<Index, 2> TetBisectionMesh::refinement_edge(ElementHandle e) const {
  const Marking& m = marking(e);
  return {{m.v[0], m.v[1]}};
}

double TetBisectionMesh::longest_edge(ElementHandle e) const {
  const Simplex& s = conn_.simplex(e);
  double l = 0.0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      l = std::max(l, (points_.col(s.vertex(i)) - points_.col(s.vertex(j))).squaredNorm());
  return std::sqrt(l);
}

std::array<long, 6> TetBisectionMesh::similarity_signature(ElementHandle e) const {
  const Simplex& s = conn_.simplex(e);
  std::array<double, 6> l{};
  std::size_t k = 0;
  for (int i = 0; i < 4; ++i)
    for (int j = i + 1; j < 4; ++j)
      l[k++] = (points_.col(s.vertex(i)) - points_.col(s.vertex(j))).squaredNorm();
  std::sort(l.begin(), l.end());
  std::array<long, 6> key{};
  for (std::size_t i = 0; i < 6; ++i) key[i] = std::lround(l[i] / l[5] * 1e9);
  return key;
}

std::vector<ElementHandle> TetBisectionMesh::around_edge(Index p, Index q) const {
  std::vector<ElementHandle> out;
  for (const ElementHandle e : conn_.star(p))
    if (conn_.simplex(e).contains(q)) out.push_back(e);
  return out;
}

Index TetBisectionMesh::bisect(ElementHandle e) {
  INCISE_CHECK(conn_.is_alive(e), "TetBisectionMesh::bisect: element is not alive");
  const auto r = refinement_edge(e);
  return bisect_edge(r[0], r[1], 0, bisections_);
}

Index TetBisectionMesh::bisect_edge(Index p, Index q, int level, long budget_start) {
  INCISE_CHECK(level <= kMaxRecursion,
               "TetBisectionMesh: conforming closure deeper than kMaxRecursion = " +
                   std::to_string(kMaxRecursion) + " levels (work limit)");
  // The edges whose bisect_edge calls are waiting for this one (the recursion stack).
  struct StackGuard {
    std::vector<Edge>& s;
    StackGuard(std::vector<Edge>& st, Edge e) : s(st) { s.push_back(e); }
    ~StackGuard() { s.pop_back(); }
  } guard(pending_, edge_of(p, q));
  for (;;) {
    INCISE_CHECK(bisections_ - budget_start < max_bisections_,
                 "TetBisectionMesh: more than " + std::to_string(max_bisections_) +
                     " simple bisections in one call (work limit; is h far below the mesh "
                     "size?)");
    const std::vector<ElementHandle> around = around_edge(p, q);
    INCISE_CHECK(!around.empty(), "TetBisectionMesh: (" + std::to_string(p) + ", " +
                                      std::to_string(q) + ") is not an edge of the mesh");
    // AMP §3 / Fig. 6.7: a tetrahedron around (p, q) with another refinement edge is bisected
    // first; (p, q) then lies in one of its children. Repeat until all agree. When that
    // refinement edge is itself waiting for (p, q) (a cycle of the marks, see file comment),
    // (p, q) is split at once in every tetrahedron around it.
    bool again = false, cycle = false;
    for (const ElementHandle t : around) {
      const Marking& m = marking(t);
      if (same_edge(Edge{{m.v[0], m.v[1]}}, p, q)) continue;
      const Edge r = edge_of(m.v[0], m.v[1]);
      if (std::find(pending_.begin(), pending_.end(), r) != pending_.end()) {
        cycle = true;
        break;
      }
      bisect_edge(m.v[0], m.v[1], level + 1, budget_start);
      again = true;
      break;
    }
    if (cycle) ++forced_;
    if (!again) return simple_bisect(p, q, around);
  }
}

namespace {

/// The marked edge of face {x, y, z} of a tetrahedron with marking m (file comment).
Edge face_mark_of(const TetBisectionMesh::Marking& m, Index x, Index y, Index z) {
  auto has = [&](Index v) { return x == v || y == v || z == v; };
  if (has(m.v[0]) && has(m.v[1])) return edge_of(m.v[0], m.v[1]);
  return has(m.v[0]) ? m.m0 : m.m1;
}

}  // namespace

Index TetBisectionMesh::simple_bisect(Index p, Index q, const std::vector<ElementHandle>& around) {
  const Index n = conn_.add_vertex();
  points_.conservativeResize(Eigen::NoChange, static_cast<Eigen::Index>(n) + 1);
  points_.col(n) = 0.5 * (points_.col(p) + points_.col(q));
  parents_.resize(static_cast<std::size_t>(n - num_start_vertices_) + 1, {{-1, -1}});
  parents_[static_cast<std::size_t>(n - num_start_vertices_)] = {{std::min(p, q), std::max(p, q)}};

  std::vector<Simplex> add;
  std::vector<Marking> marks;
  std::vector<int> parent_nodes;
  add.reserve(2 * around.size());
  marks.reserve(2 * around.size());
  for (const ElementHandle t : around) {
    const Marking& pm = marking(t);
    const Simplex& s = conn_.simplex(t);
    // a, b: the split edge; c, d: the other two vertices.
    const Index a = p, b = q;
    Index c = -1, d = -1;
    for (int i = 0; i < 4; ++i)
      if (s.vertex(i) != a && s.vertex(i) != b) (c < 0 ? c : d) = s.vertex(i);
    const Edge mark_acd = face_mark_of(pm, a, c, d), mark_bcd = face_mark_of(pm, b, c, d);
    // AMP §3 when (a, b) is the refinement edge; otherwise (a split forced by a cycle) the same
    // rule as for an unflagged non-planar parent: children unflagged, new face marks cd.
    const bool regular = same_edge(Edge{{pm.v[0], pm.v[1]}}, a, b);
    const Type ty = regular ? type_of(pm) : Type::kO;
    // Mark of the new face c d n: cd, or for a flagged planar parent the edge from n to the
    // vertex that both children's refinement edges share.
    Edge new_face = edge_of(c, d);
    if (ty == Type::kPf) new_face = edge_of(n, other(mark_acd, a));
    // Mark of a face of a child, given as its vertex set {x, y, z}.
    auto face_mark = [&](Index x, Index y, Index z) -> Edge {
      auto has = [&](Index v) { return x == v || y == v || z == v; };
      if (!has(n)) return has(a) ? mark_acd : mark_bcd;  // inherited face acd or bcd
      if (has(a) || has(b)) {                            // half of a cut face: edge opposite n
        const Index end = has(a) ? a : b;
        const Index w = has(c) ? c : d;
        return edge_of(end, w);
      }
      return new_face;  // c d n
    };
    for (int k = 0; k < 2; ++k) {
      const Index keep = k == 0 ? a : b;
      const Edge ref = k == 0 ? mark_acd : mark_bcd;
      Marking cm;
      cm.v[0] = ref[0];
      cm.v[1] = ref[1];
      int slot = 2;
      for (const Index v : {keep, c, d, n})
        if (v != ref[0] && v != ref[1]) cm.v[static_cast<std::size_t>(slot++)] = v;
      cm.m0 = face_mark(cm.v[0], cm.v[2], cm.v[3]);
      cm.m1 = face_mark(cm.v[1], cm.v[2], cm.v[3]);
      cm.flag = ty == Type::kPu;
      add.push_back(s.substituted(keep == a ? b : a, n));
      marks.push_back(cm);
    }
    parent_nodes.push_back(node_of(t));
  }
  const std::vector<ElementHandle> made = conn_.replace_elements(around, add);
  for (std::size_t k = 0; k < made.size(); ++k) {
    const int parent = parent_nodes[k / 2];
    TreeNode child;
    child.simplex = add[k];
    child.marking = marks[k];
    child.parent = parent;
    child.depth = tree_[static_cast<std::size_t>(parent)].depth + 1;
    child.element = made[k];
    const int id = static_cast<int>(tree_.size());
    tree_[static_cast<std::size_t>(parent)].children[k % 2] = id;
    tree_.push_back(child);
    set_node(made[k], id);
  }
  ++bisections_;
  return n;
}

double TetBisectionMesh::min_barycentric(const Simplex& t, const Vec3& x) const {
  const auto l = barycentric(points_.col(t.vertex(0)), points_.col(t.vertex(1)),
                             points_.col(t.vertex(2)), points_.col(t.vertex(3)), x);
  return std::min(std::min(l[0], l[1]), std::min(l[2], l[3]));
}

bool TetBisectionMesh::meets_segment(const Simplex& t, const Vec3& a, const Vec3& b) const {
  const Vec3 p0 = points_.col(t.vertex(0)), p1 = points_.col(t.vertex(1)),
             p2 = points_.col(t.vertex(2)), p3 = points_.col(t.vertex(3));
  const auto la = barycentric(p0, p1, p2, p3, a), lb = barycentric(p0, p1, p2, p3, b);
  // Barycentric coordinates are affine along the segment: clip s ∈ [0, 1] by λ_i(s) ≥ −tol.
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 4; ++i) {
    const double f0 = la[static_cast<std::size_t>(i)] + kBaryTol;
    const double f1 = lb[static_cast<std::size_t>(i)] + kBaryTol;
    if (f0 < 0.0 && f1 < 0.0) return false;
    if (f0 < 0.0) lo = std::max(lo, f0 / (f0 - f1));
    if (f1 < 0.0) hi = std::min(hi, f0 / (f0 - f1));
  }
  return lo <= hi;
}

std::vector<int> TetBisectionMesh::roots_near(const Vec3& lo, const Vec3& hi) const {
  std::vector<int> out;
  if (num_roots_ == 0) return out;
  std::array<int, 6> rg{};
  for (int a = 0; a < 3; ++a) {
    const int na = grid_n_[static_cast<std::size_t>(a)];
    const double flo = std::floor((lo(a) - grid_lo_(a)) / grid_cell_(a));
    const double fhi = std::floor((hi(a) - grid_lo_(a)) / grid_cell_(a));
    // A query outside the grid by less than a cell is clamped in (the candidates' own test
    // decides); farther out nothing is near.
    if (!(fhi >= -1.0 && flo <= na)) return out;
    rg[static_cast<std::size_t>(a)] = static_cast<int>(std::clamp(flo, 0.0, na - 1.0));
    rg[static_cast<std::size_t>(a + 3)] = static_cast<int>(std::clamp(fhi, 0.0, na - 1.0));
  }
  for (int k = rg[2]; k <= rg[5]; ++k)
    for (int j = rg[1]; j <= rg[4]; ++j)
      for (int i = rg[0]; i <= rg[3]; ++i) {
        const std::size_t c = static_cast<std::size_t>(i + grid_n_[0] * (j + grid_n_[1] * k));
        for (int s = grid_start_[c]; s < grid_start_[c + 1]; ++s)
          out.push_back(grid_roots_[static_cast<std::size_t>(s)]);
      }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

ElementHandle TetBisectionMesh::locate(const Vec3& x) const {
  if (!x.allFinite()) return ElementHandle{};
  for (const int r : roots_near(x, x)) {
    if (min_barycentric(tree_[static_cast<std::size_t>(r)].simplex, x) < -kBaryTol) continue;
    int n = r;
    while (tree_[static_cast<std::size_t>(n)].children[0] >= 0) {
      const auto& ch = tree_[static_cast<std::size_t>(n)].children;
      // The two halves share the cutting plane: take the one x is deeper inside.
      const double l0 = min_barycentric(tree_[static_cast<std::size_t>(ch[0])].simplex, x);
      const double l1 = min_barycentric(tree_[static_cast<std::size_t>(ch[1])].simplex, x);
      n = l0 >= l1 ? ch[0] : ch[1];
    }
    return tree_[static_cast<std::size_t>(n)].element;
  }
  return ElementHandle{};
}

std::vector<ElementHandle> TetBisectionMesh::elements_meeting_segment(const Vec3& a,
                                                                      const Vec3& b) const {
  std::vector<ElementHandle> out;
  if (!a.allFinite() || !b.allFinite()) return out;
  std::vector<int> stack;
  for (const int r : roots_near(a.cwiseMin(b), a.cwiseMax(b))) {
    stack.push_back(r);
    while (!stack.empty()) {
      const int n = stack.back();
      stack.pop_back();
      const TreeNode& node = tree_[static_cast<std::size_t>(n)];
      if (!meets_segment(node.simplex, a, b)) continue;
      if (node.children[0] < 0) {
        out.push_back(node.element);
      } else {
        stack.push_back(node.children[0]);
        stack.push_back(node.children[1]);
      }
    }
  }
  return out;
}

int TetBisectionMesh::refine_around(const Vec3& x, double h) {
  INCISE_CHECK(std::isfinite(h) && h > 0.0, "refine_around: h must be finite and > 0");
  INCISE_CHECK(x.allFinite(), "refine_around: the point is not finite");
  const long start = bisections_;
  int calls = 0;
  for (;;) {
    const ElementHandle t = locate(x);
    INCISE_CHECK(t.valid(), "refine_around: the point lies outside the mesh");
    if (longest_edge(t) <= h) return calls;
    const auto r = refinement_edge(t);
    bisect_edge(r[0], r[1], 0, start);
    ++calls;
  }
}

int TetBisectionMesh::refine_along_segment(const Vec3& a, const Vec3& b, double h) {
  INCISE_CHECK(std::isfinite(h) && h > 0.0, "refine_along_segment: h must be finite and > 0");
  INCISE_CHECK(a.allFinite() && b.allFinite(), "refine_along_segment: an end is not finite");
  const long start = bisections_;
  int calls = 0;
  for (;;) {
    bool any = false;
    for (const ElementHandle t : elements_meeting_segment(a, b)) {
      // Earlier bisections of this pass may have removed t (closure).
      if (!conn_.is_alive(t) || longest_edge(t) <= h) continue;
      const auto r = refinement_edge(t);
      bisect_edge(r[0], r[1], 0, start);
      ++calls;
      any = true;
    }
    if (!any) return calls;
  }
}

}  // namespace incise::mesh
