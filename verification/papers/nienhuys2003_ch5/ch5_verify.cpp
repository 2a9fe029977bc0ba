// Thesis ch. 5 reproductions (§5.4): Fig. 5.16 (the 50-triangle start mesh cut by subdivision
// and by Delaunay cutting with ε_edge = h̄/3 and h̄/8: growth +62 / +10 / +12), Fig. 5.17 (minimum
// and maximum angle histograms of the subdivision and the h̄/3 cut), Fig. 5.8 (a regular
// 722-triangle mesh, a curved path, growth +57), and how closely each realized incision follows
// the scalpel path (Hausdorff distance in h̄). The thesis' trajectories are only drawn; ours are
// documented here and in the README. Writes the tables (stdout) and, with INCISE_CH5_SVG=DIR,
// SVG pictures of the cut meshes.
#include <incise/delaunay/cutter2d.hpp>
#include <incise/delaunay/subdivision.hpp>
#include <incise/delaunay/svg.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_test/delaunay_support.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <iostream>

namespace incise::delaunay {
namespace {

using incise::test::components;
using incise::test::cut_along;
using incise::test::valid;

/// Fig. 5.16's trajectory stand-in: a quadratic Bézier from (−0.5, 1.7) via (2.5, 4.2) to
/// (5.5, 2.2) over the 5 × 5 grid of unit squares (h̄ = (2 + √2)/… of the grid's edges), sampled
/// every 0.1 h̄ by the mouse-like movement of cut_along.
std::vector<Vec2> fig_5_16_path() {
  std::vector<Vec2> p;
  const Vec2 a(-0.5, 1.7), c(2.5, 4.2), b(5.5, 2.2);
  for (int i = 0; i <= 40; ++i) {
    const double t = i / 40.0;
    p.push_back((1 - t) * (1 - t) * a + 2 * t * (1 - t) * c + t * t * b);
  }
  return p;
}

/// Fig. 5.8's stand-in: across the 19 × 19 grid, y = 9.5 + 4 sin(π x / 6), x from −1 to 20
/// (strongly curved segments, as in the figure).
std::vector<Vec2> fig_5_8_path() {
  std::vector<Vec2> p;
  for (int i = 0; i <= 210; ++i) {
    const double x = -1 + 0.1 * i;
    p.emplace_back(x, 9.5 + 4 * std::sin(M_PI * x / 6));
  }
  return p;
}

/// Distance from x to the polyline q.
double distance_to(const Vec2& x, const std::vector<Vec2>& q) {
  double d = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i + 1 < q.size(); ++i) {
    const Vec2 e = q[i + 1] - q[i];
    const double l2 = e.squaredNorm();
    const double t = l2 > 0 ? std::clamp((x - q[i]).dot(e) / l2, 0.0, 1.0) : 0.0;
    d = std::min(d, (q[i] + t * e - x).norm());
  }
  return d;
}

/// Symmetric Hausdorff distance of two polylines, by sampling each at 1/50 of its segments.
double hausdorff(const std::vector<Vec2>& a, const std::vector<Vec2>& b) {
  double h = 0;
  for (const auto* pq : {&a, &b}) {
    const auto& p = *pq;
    const auto& q = pq == &a ? b : a;
    for (size_t i = 0; i + 1 < p.size(); ++i)
      for (int k = 0; k <= 50; ++k)
        h = std::max(h, distance_to(p[i] + (p[i + 1] - p[i]) * (k / 50.0), q));
  }
  return h;
}

/// The part of `path` inside the rectangle [0, n]² (clipped at the crossings).
std::vector<Vec2> inside_part(const std::vector<Vec2>& path, double n) {
  auto in = [n](const Vec2& x) { return x.x() >= 0 && x.x() <= n && x.y() >= 0 && x.y() <= n; };
  std::vector<Vec2> out;
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const Vec2 a = path[i], b = path[i + 1];
    for (int k = 0; k <= 100; ++k) {
      const Vec2 x = a + (b - a) * (k / 100.0);
      if (in(x) && (out.empty() || (out.back() - x).norm() > 1e-9)) out.push_back(x);
    }
  }
  return out;
}

struct Histogram {
  std::array<int, 18> min_angle{}, max_angle{};  // 10° bins
  double smallest = 180, largest = 0;
};

Histogram angles(const Triangulation& t) {
  Histogram h;
  for (const auto& e : t.connectivity().elements()) {
    const auto tri = t.triangle(e);
    double lo = 180, hi = 0;
    for (int i = 0; i < 3; ++i) {
      const Vec2 p = t.point(tri[static_cast<size_t>(i)]),
                 q = t.point(tri[static_cast<size_t>((i + 1) % 3)]),
                 w = t.point(tri[static_cast<size_t>((i + 2) % 3)]);
      const Vec2 x = q - p, y = w - p;
      const double a = std::atan2(std::abs(x.x() * y.y() - x.y() * y.x()), x.dot(y)) * 180 / M_PI;
      lo = std::min(lo, a);
      hi = std::max(hi, a);
    }
    ++h.min_angle[static_cast<size_t>(std::min(17, static_cast<int>(lo / 10)))];
    ++h.max_angle[static_cast<size_t>(std::min(17, static_cast<int>(hi / 10)))];
    h.smallest = std::min(h.smallest, lo);
    h.largest = std::max(h.largest, hi);
  }
  return h;
}

void write_svg(const Triangulation& t, const std::vector<Vec2>& path, double n,
               const std::string& name) {
  const char* dir = std::getenv("INCISE_CH5_SVG");
  if (dir == nullptr || *dir == '\0') return;
  std::ofstream f(std::string(dir) + "/" + name + ".svg");
  f << mesh_svg(t, path, SvgFrame{Vec2::Zero(), n, 1.0});  // the square [-1, n + 1]²
}

struct CutResult {
  Index growth = 0;
  double hausdorff_h = 0;  ///< realized incision vs path, in h̄
  Histogram hist;
  int components = 0;
};

/// Mean edge length of a mesh.
double mean_edge(const Triangulation& t) {
  double sum = 0;
  const auto edges = t.edges();
  for (const Edge& e : edges) sum += (t.point(e.first) - t.point(e.second)).norm();
  return sum / static_cast<double>(edges.size());
}

CutResult delaunay_cut(const mesh::MeshData& start, const std::vector<Vec2>& path, double n,
                       double edge, const std::string& svg) {
  Triangulation t(start);
  Cutter2DOptions o;
  o.edge = edge;
  Cutter2D cutter(t, o);
  const Index before = t.num_triangles();
  cut_along(cutter, t, path, 0.1 * cutter.mean_edge());
  CutResult r;
  r.growth = t.num_triangles() - before;
  r.hist = angles(t);
  r.components = components(t);
  // Realized incision: one side's nodes in path order.
  std::vector<Vec2> realized;
  if (!cutter.incision_sides().empty())
    for (const Index v : cutter.incision_sides()[0]) realized.push_back(t.point(v));
  if (realized.size() >= 2)
    r.hausdorff_h = hausdorff(realized, inside_part(path, n)) / cutter.mean_edge();
  write_svg(t, path, n, svg);
  return r;
}

CutResult subdivision(const mesh::MeshData& start, const std::vector<Vec2>& path, double n,
                      const std::string& svg) {
  Triangulation t(start);
  const double h = mean_edge(t);
  const SubdivisionReport s = subdivision_cut(t, path);
  CutResult r;
  r.growth = s.triangles_after - s.triangles_before;
  r.hist = angles(t);
  r.components = components(t);
  std::vector<Vec2> realized;
  for (const Index v : s.chain) realized.push_back(t.point(v));
  r.hausdorff_h = hausdorff(realized, inside_part(path, n)) / h;
  write_svg(t, path, n, svg);
  return r;
}

void print_histograms(const char* name, const Histogram& h) {
  std::cout << name << " min-angle bins (10°):";
  for (int c : h.min_angle) std::cout << " " << c;
  std::cout << "\n" << name << " max-angle bins (10°):";
  for (int c : h.max_angle) std::cout << " " << c;
  std::cout << "\n";
}

TEST(Chapter5, Fig5_16And5_17SubdivisionVersusDelaunayCutOnThe50TriangleMesh) {
  const mesh::MeshData start = mesh::make_rectangle(5, 5, 5, 5);
  ASSERT_EQ(start.num_cells(), 50);
  const auto path = fig_5_16_path();
  const CutResult sub = subdivision(start, path, 5, "fig5_16_subdivision");
  const CutResult d3 = delaunay_cut(start, path, 5, 1.0 / 3.0, "fig5_16_delaunay_h3");
  const CutResult d8 = delaunay_cut(start, path, 5, 1.0 / 8.0, "fig5_16_delaunay_h8");
  std::cout
      << std::fixed << std::setprecision(3)
      << "Fig. 5.16   cutter              growth (thesis)   Hausdorff/h̄   min angle   max angle\n"
      << "            subdivision         +" << sub.growth << " (+62)        " << sub.hausdorff_h
      << "        " << sub.hist.smallest << "    " << sub.hist.largest << "\n"
      << "            Delaunay h̄/3        +" << d3.growth << " (+10)        " << d3.hausdorff_h
      << "        " << d3.hist.smallest << "    " << d3.hist.largest << "\n"
      << "            Delaunay h̄/8        +" << d8.growth << " (+12)        " << d8.hausdorff_h
      << "        " << d8.hist.smallest << "    " << d8.hist.largest << "\n";
  print_histograms("subdivision", sub.hist);
  print_histograms("Delaunay h/3", d3.hist);
  // What the thesis finds, asserted as orderings: the Delaunay cut grows the mesh far less
  // (thesis 6×: asserted ≥ 2×), keeps angles less extreme (Fig. 5.17: its smallest angle is
  // larger and its largest angle smaller than the subdivision's), and the subdivision follows
  // the path more closely. Every cut separates nothing here (the path crosses the whole mesh, so
  // two components each).
  EXPECT_GE(sub.growth, 2 * d3.growth);
  EXPECT_GE(sub.growth, 2 * d8.growth);
  EXPECT_GT(d3.hist.smallest, sub.hist.smallest);
  EXPECT_LT(d3.hist.largest, sub.hist.largest);
  EXPECT_LT(sub.hausdorff_h, d3.hausdorff_h);
  EXPECT_EQ(sub.components, 2);
  EXPECT_EQ(d3.components, 2);
  EXPECT_EQ(d8.components, 2);
}

TEST(Chapter5, Fig5_8CurvedCutOnThe722TriangleMesh) {
  const mesh::MeshData start = mesh::make_rectangle(19, 19, 19, 19);
  ASSERT_EQ(start.num_cells(), 722);
  const auto path = fig_5_8_path();
  const CutResult d3 = delaunay_cut(start, path, 19, 1.0 / 3.0, "fig5_8_delaunay_h3");
  const CutResult sub = subdivision(start, path, 19, "fig5_8_subdivision");
  std::cout << std::fixed << std::setprecision(3) << "Fig. 5.8    Delaunay h̄/3 growth +"
            << d3.growth << " (thesis +57), Hausdorff " << d3.hausdorff_h << " h̄, angles "
            << d3.hist.smallest << "–" << d3.hist.largest << "; subdivision +" << sub.growth
            << ", Hausdorff " << sub.hausdorff_h << " h̄\n";
  EXPECT_EQ(d3.components, 2);
  EXPECT_GE(sub.growth, 2 * d3.growth);
  // "strongly curved path segments are cut short": the Delaunay incision deviates from the
  // path by less than two mean edge lengths (the cut-short arcs) — measured, see README.
  EXPECT_LT(d3.hausdorff_h, 2.0);
}

}  // namespace
}  // namespace incise::delaunay
