#include <incise/core/error.hpp>
#include <incise/mesh/bisection.hpp>

#include <cmath>
#include <string>

namespace incise::mesh {

namespace {

double cross(const Vec2& a, const Vec2& b) {
  return a(0) * b(1) - a(1) * b(0);
}

}  // namespace

BisectionMesh::BisectionMesh(const MeshData& mesh)
    : conn_(Connectivity::from_mesh_data(mesh)), points_(mesh.points) {
  INCISE_CHECK_PARAM(mesh.dimension == 2 && mesh.cells.rows() == 3,
                     "BisectionMesh needs a 2D triangle mesh");
  for (Index c = 0; c < mesh.num_cells(); ++c) {
    const Vec2 a = mesh.points.col(mesh.cells(0, c)).head<2>();
    const Vec2 b = mesh.points.col(mesh.cells(1, c)).head<2>();
    const Vec2 d = mesh.points.col(mesh.cells(2, c)).head<2>();
    INCISE_CHECK_PARAM(cross(b - a, d - a) > 0.0,
                       "triangle " + std::to_string(c) + " has non-positive area");
  }
  for (const ElementHandle e : conn_.elements()) {
    TreeNode n;
    n.simplex = conn_.simplex(e);
    n.element = e;
    if (static_cast<std::size_t>(e.index) >= node_of_slot_.size())
      node_of_slot_.resize(static_cast<std::size_t>(e.index) + 1, -1);
    node_of_slot_[static_cast<std::size_t>(e.index)] = static_cast<int>(tree_.size());
    tree_.push_back(n);
  }
  num_roots_ = static_cast<int>(tree_.size());
  num_start_vertices_ = conn_.num_vertices();
}

std::array<Index, 2> BisectionMesh::parents(Index v) const {
  INCISE_CHECK(v >= 0 && v < conn_.num_vertices(),
               "parents: vertex " + std::to_string(v) + " is out of range");
  if (v < num_start_vertices_) return {{-1, -1}};
  return parents_[static_cast<std::size_t>(v - num_start_vertices_)];
}

int BisectionMesh::node_of(ElementHandle e) const {
  INCISE_CHECK(conn_.is_alive(e), "node_of: element is not alive");
  return node_of_slot_[static_cast<std::size_t>(e.index)];
}

std::array<Index, 2> BisectionMesh::hypotenuse(ElementHandle e) const {
  const Simplex& s = conn_.simplex(e);
  std::array<Index, 2> best{{-1, -1}};
  double longest = -1.0;
  for (int i = 0; i < 3; ++i) {
    const Index p = s.vertex(i), q = s.vertex((i + 1) % 3);
    const double l = (points_.col(p) - points_.col(q)).squaredNorm();
    if (l > longest) {
      longest = l;
      best = {{p, q}};
    }
  }
  return best;
}

std::vector<ElementHandle> BisectionMesh::incident(Index p, Index q) const {
  std::vector<ElementHandle> out;
  for (const ElementHandle e : conn_.star(p))
    if (conn_.simplex(e).contains(q)) out.push_back(e);
  return out;
}

Index BisectionMesh::simple_bisect(Index p, Index q) {
  const std::vector<ElementHandle> f = incident(p, q);
  INCISE_CHECK(!f.empty(), "simple_bisect: (" + std::to_string(p) + ", " + std::to_string(q) +
                               ") is not an edge of the mesh");
  for (const ElementHandle e : f) {
    const auto h = hypotenuse(e);
    INCISE_CHECK((h[0] == p && h[1] == q) || (h[0] == q && h[1] == p),
                 "simple_bisect: (" + std::to_string(p) + ", " + std::to_string(q) +
                     ") is not the hypotenuse of an incident triangle");
  }
  const Index n = conn_.add_vertex();
  points_.conservativeResize(Eigen::NoChange, static_cast<Eigen::Index>(n) + 1);
  points_.col(n) = 0.5 * (points_.col(p) + points_.col(q));
  parents_.resize(static_cast<std::size_t>(n - num_start_vertices_) + 1, {{-1, -1}});
  parents_[static_cast<std::size_t>(n - num_start_vertices_)] = {{p, q}};
  std::vector<Simplex> add;
  std::vector<int> parents;
  for (const ElementHandle e : f) {
    const Simplex& s = conn_.simplex(e);
    add.push_back(s.substituted(p, n));
    add.push_back(s.substituted(q, n));
    parents.push_back(node_of(e));
  }
  const std::vector<ElementHandle> made = conn_.replace_elements(f, add);
  for (std::size_t k = 0; k < made.size(); ++k) {
    const int parent = parents[k / 2];
    TreeNode child;
    child.simplex = add[k];
    child.parent = parent;
    child.depth = tree_[static_cast<std::size_t>(parent)].depth + 1;
    child.element = made[k];
    const int id = static_cast<int>(tree_.size());
    tree_[static_cast<std::size_t>(parent)].children[k % 2] = id;
    tree_.push_back(child);
    if (static_cast<std::size_t>(made[k].index) >= node_of_slot_.size())
      node_of_slot_.resize(static_cast<std::size_t>(made[k].index) + 1, -1);
    node_of_slot_[static_cast<std::size_t>(made[k].index)] = id;
  }
  ++bisections_;
  return n;
}

Index BisectionMesh::bisect(Index p, Index q) {
  return bisect_impl(p, q, 0);
}

Index BisectionMesh::bisect_impl(Index p, Index q, int level) {
  INCISE_CHECK(level <= kMaxRecursion,
               "bisect: recursion deeper than kMaxRecursion (the starting mesh is not compatibly "
               "divisible)");
  INCISE_CHECK(!incident(p, q).empty(), "bisect: (" + std::to_string(p) + ", " + std::to_string(q) +
                                            ") is not an edge of the mesh");
  // Fig. 6.7: while an incident triangle has another hypotenuse, bisect that one first. Each
  // such bisection splits the triangle so that (p, q) becomes a child's hypotenuse.
  for (;;) {
    bool again = false;
    for (const ElementHandle e : incident(p, q)) {
      const auto h = hypotenuse(e);
      if ((h[0] == p && h[1] == q) || (h[0] == q && h[1] == p)) continue;
      bisect_impl(h[0], h[1], level + 1);
      again = true;
      break;
    }
    if (!again) break;
  }
  return simple_bisect(p, q);
}

bool BisectionMesh::contains(const Simplex& t, const Vec2& x) const {
  const Vec2 a = points_.col(t.vertex(0)).head<2>();
  const Vec2 b = points_.col(t.vertex(1)).head<2>();
  const Vec2 c = points_.col(t.vertex(2)).head<2>();
  const double area = cross(b - a, c - a);
  // Barycentric coordinates; the tolerance (relative, 1e-12) keeps points on shared edges and
  // at vertices inside, whichever way the rounding goes.
  const double tol = -1e-12 * std::abs(area);
  const double la = cross(b - x, c - x), lb = cross(c - x, a - x), lc = cross(a - x, b - x);
  if (area > 0) return la >= tol && lb >= tol && lc >= tol;
  return la <= -tol && lb <= -tol && lc <= -tol;
}

ElementHandle BisectionMesh::locate(const Vec2& x) const {
  for (int r = 0; r < num_roots_; ++r) {
    if (!contains(tree_[static_cast<std::size_t>(r)].simplex, x)) continue;
    int n = r;
    while (tree_[static_cast<std::size_t>(n)].children[0] >= 0) {
      const auto& ch = tree_[static_cast<std::size_t>(n)].children;
      n = contains(tree_[static_cast<std::size_t>(ch[0])].simplex, x) ? ch[0] : ch[1];
    }
    return tree_[static_cast<std::size_t>(n)].element;
  }
  return ElementHandle{};
}

int BisectionMesh::refine_around(const Vec2& x, double h) {
  INCISE_CHECK(std::isfinite(h) && h > 0.0, "refine_around: h must be finite and > 0");
  int calls = 0;
  for (;;) {
    const ElementHandle t = locate(x);
    INCISE_CHECK(t.valid(), "refine_around: the point lies outside the mesh");
    const auto hyp = hypotenuse(t);
    if ((points_.col(hyp[0]) - points_.col(hyp[1])).norm() <= h) return calls;
    bisect(hyp[0], hyp[1]);
    ++calls;
  }
}

}  // namespace incise::mesh
