/// Thesis §6.8.3 (Tables 6.2 and 6.3): CG iterations and displacement errors of the static
/// needle load for combinations of h_start (uniform starting mesh) and h_ref (refinement around
/// the needle). The slab of §6.8.1: 0.10 × 0.10 × 0.01 m, E = 34 kPa, ν = 0.34, fixed at
/// x = 0.1 m, ε_round = 1e-8; the load is the friction profile (needle/friction.hpp, our
/// parameters: the thesis gives none) along y = 0.05 m over 70 mm from x = 0 (tip at
/// x = 0.07 m), pointing along +x (the needle drags the material towards the fixed side),
/// lumped onto the mesh nodes of that line as the needle-node thresholds are. The "needle" is
/// mesh edges, so no conformance error enters (§6.8.1).
///
/// Per (h_start, h_ref): bisection refine-around at points every h_ref/4 along the loaded
/// segment until the triangles there are congruent to the uniform h_ref slab's; linear CG from
/// u = 0 stopped by (6.9) with ε = 0.01 (the thesis does not state its ε for Table 6.2) for the
/// iteration counts; discretization errors of the direct (CHOLMOD) solution on the same mesh
/// against a direct solve on the uniform h7 slab, mean and max over the h7 nodes of
/// |u_h7 − I u_h| (I: the coarse field evaluated at the h7 node); and the CG solution's own
/// error against the direct one (the relaxation error at ε = 0.01). Writes table6_2.csv next to
/// the binary and asserts the trends the thesis shows (see README.md).

#include <incise/fem/plane_stress_problem.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/bisection.hpp>
#include <incise/mesh/slab2d.hpp>
#include <incise/mesh/validate.hpp>
#include <incise/needle/friction.hpp>
#include <incise/needle/needle_problem.hpp>
#include <incise/solver/linear_cg.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#ifndef INCISE_CH6_OUTPUT_DIR
#define INCISE_CH6_OUTPUT_DIR "."
#endif

namespace {

using incise::Index;
using incise::Vec2;
using incise::VecX;

constexpr double kThickness = 0.01;  // §6.8.1
constexpr double kLineY = 0.05;
constexpr double kTipX = 0.07;  // 70 mm loaded
constexpr double kEpsilon = 0.01;

incise::material::Material material() {
  incise::material::Parameters p;
  p.youngs_modulus = 3.4e4;
  p.poisson_ratio = 0.34;
  return incise::material::Material("linear", p);
}

struct Solution {
  incise::mesh::BisectionMesh mesh;
  VecX u;
  long iterations = 0;
  Index triangles = 0;
};

/// Builds the mesh for (k_start, k_ref), loads it and solves (direct when `direct`).
Solution solve(int k_start, int k_ref, bool direct, double epsilon = kEpsilon) {
  Solution s{incise::mesh::BisectionMesh(incise::mesh::make_thesis_slab(k_start)), VecX(), 0, 0};
  const double h_ref = incise::mesh::thesis_slab_spacing(k_ref);
  if (k_ref > k_start)
    for (double x = 0.0; x <= kTipX + 1e-12; x += h_ref / 4)
      s.mesh.refine_around(Vec2(x, kLineY), std::sqrt(2.0) * h_ref * (1 + 1e-9));
  incise::mesh::ValidateOptions vo;
  vo.positions = &s.mesh.points();
  EXPECT_TRUE(incise::mesh::validate(s.mesh.connectivity(), vo).ok());
  const auto data = s.mesh.to_mesh_data();
  s.triangles = data.num_cells();
  incise::fem::PlaneStressProblem p(data, material(), kThickness);
  std::vector<Index> fixed, line;
  std::vector<double> sl;
  for (Index v = 0; v < data.num_points(); ++v) {
    if (data.points(0, v) > 0.1 - 1e-12) fixed.push_back(v);
    if (std::abs(data.points(1, v) - kLineY) < 1e-12 && data.points(0, v) <= kTipX + 1e-12) {
      line.push_back(v);
      sl.push_back(kTipX - data.points(0, v));
    }
  }
  p.fix_nodes(fixed);
  const std::vector<double> f = incise::needle::FrictionProfile{}.dynamic_thresholds(sl);
  for (std::size_t k = 0; k < line.size(); ++k) p.add_point_load(line[k], Vec2(f[k], 0.0));
  s.u = VecX::Zero(p.size());
  if (direct) {
    incise::needle::NeedleProblem np(p, incise::needle::NeedlePose{}, {}, {});
    const auto d = incise::needle::direct_solve(np, s.u);
    EXPECT_TRUE(d.ok()) << d.brief();
    return s;
  }
  incise::solver::LinearCgOptions o;
  o.stop.rule = incise::solver::ResidualRule::kWithReactions;
  o.stop.epsilon = epsilon;
  o.stop.epsilon_round = 1e-8;                                     // §6.8.1
  o.stop.force_scale = 3.4e4 * kThickness * std::sqrt(2.0) * 0.1;  // E·d·H, H = diagonal
  const auto rep = incise::solver::linear_cg(p, s.u, o);
  EXPECT_TRUE(rep.ok()) << rep.brief();
  s.iterations = rep.iterations;
  return s;
}

/// Mean and max (mm) over the reference nodes of |u_ref − I u|.
std::pair<double, double> errors(const Solution& ref, const Solution& s,
                                 std::vector<double>* per_node = nullptr) {
  double sum = 0.0, mx = 0.0;
  if (per_node) per_node->assign(static_cast<std::size_t>(ref.mesh.points().cols()), 0.0);
  const auto& pts = ref.mesh.points();
  const auto& conn = s.mesh.connectivity();
  const auto& sp = s.mesh.points();
  for (Eigen::Index v = 0; v < pts.cols(); ++v) {
    const Vec2 x = pts.col(v).head<2>();
    const auto e = s.mesh.locate(x);
    EXPECT_TRUE(e.valid());
    const auto& t = conn.simplex(e);
    const Vec2 a = sp.col(t.vertex(0)).head<2>(), b = sp.col(t.vertex(1)).head<2>(),
               c = sp.col(t.vertex(2)).head<2>();
    const auto cr = [](const Vec2& p, const Vec2& q) { return p(0) * q(1) - p(1) * q(0); };
    const double area = cr(b - a, c - a);
    const double la = cr(b - x, c - x) / area, lb = cr(c - x, a - x) / area, lc = 1 - la - lb;
    const Vec2 ui = la * s.u.segment<2>(2 * t.vertex(0)) + lb * s.u.segment<2>(2 * t.vertex(1)) +
                    lc * s.u.segment<2>(2 * t.vertex(2));
    const double err = (ref.u.segment<2>(2 * v) - ui).norm() * 1e3;
    sum += err;
    mx = std::max(mx, err);
    if (per_node) (*per_node)[static_cast<std::size_t>(v)] = err;
  }
  return {sum / static_cast<double>(pts.cols()), mx};
}

/// Fig. 6.10 analogue: the error at every reference (uniform h7) node as a square of side h7,
/// white (0) to red (`scale` mm), y up, with the coarse mesh `s` drawn over it.
void write_error_svg(const std::string& path, const Solution& ref, const std::vector<double>& err,
                     const Solution& s, double scale, const std::string& title) {
  const double px = 4000.0;  // pixels per metre: 400 px for the 0.1 m slab
  const double h = incise::mesh::thesis_slab_spacing(7) * px;
  std::ofstream out(path);
  out << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"420\" height=\"450\">\n"
      << "<text x=\"10\" y=\"20\" font-size=\"13\">" << title << "</text>\n"
      << "<g transform=\"translate(10,440) scale(1,-1)\" shape-rendering=\"crispEdges\">\n";
  const auto& pts = ref.mesh.points();
  for (Eigen::Index v = 0; v < pts.cols(); ++v) {
    const double f = std::min(1.0, err[static_cast<std::size_t>(v)] / scale);
    const int gb = static_cast<int>(std::lround(255 * (1 - f)));
    out << "<rect x=\"" << pts(0, v) * px - h / 2 << "\" y=\"" << pts(1, v) * px - h / 2
        << "\" width=\"" << h << "\" height=\"" << h << "\" fill=\"rgb(255," << gb << "," << gb
        << ")\"/>\n";
  }
  const auto data = s.mesh.to_mesh_data();
  out << "<g stroke=\"black\" stroke-width=\"0.3\" fill=\"none\">\n";
  for (Index c = 0; c < data.num_cells(); ++c) {
    out << "<polygon points=\"";
    for (int i = 0; i < 3; ++i)
      out << data.points(0, data.cells(i, c)) * px << "," << data.points(1, data.cells(i, c)) * px
          << " ";
    out << "\"/>\n";
  }
  out << "</g></g></svg>\n";
}

// Thesis Table 6.2 (CG iterations), rows h_start = h1..h6, columns h_ref = h3..h7 (0: empty).
const int kThesisIterations[6][5] = {{22, 34, 45, 62, 84},  {27, 36, 46, 64, 84},
                                     {46, 49, 58, 73, 93},  {0, 81, 86, 96, 115},
                                     {0, 0, 204, 208, 194}, {0, 0, 0, 278, 285}};
// Thesis Table 6.3 (mean error, mm).
const double kThesisMean[6][5] = {{0.34, 0.33, 0.33, 0.30, 0.28}, {0.26, 0.24, 0.24, 0.21, 0.20},
                                  {0.15, 0.13, 0.13, 0.10, 0.08}, {0, 0.09, 0.08, 0.04, 0.03},
                                  {0, 0, 0.07, 0.03, 0.00},       {0, 0, 0, 0.02, 0.00}};
const double kThesisMax[6][5] = {{1.01, 0.88, 0.88, 0.87, 0.87}, {0.91, 0.68, 0.61, 0.54, 0.53},
                                 {0.66, 0.54, 0.51, 0.29, 0.27}, {0, 0.45, 0.43, 0.19, 0.14},
                                 {0, 0, 0.41, 0.17, 0.06},       {0, 0, 0, 0.16, 0.03}};

TEST(Chapter6, Table6_2And6_3_MeshDensity) {
  const Solution ref = solve(7, 7, true);
  double umax = 0.0;
  for (Eigen::Index v = 0; v < ref.u.size() / 2; ++v)
    umax = std::max(umax, ref.u.segment<2>(2 * v).norm());
  std::printf("h7 reference: max |u| = %.3f mm\n", umax * 1e3);
  std::map<std::pair<int, int>, long> it;
  std::map<std::pair<int, int>, std::pair<double, double>> err, cg_err;
  std::ofstream csv(std::string(INCISE_CH6_OUTPUT_DIR) + "/table6_2.csv");
  csv << "h_start,h_ref,triangles,cg_iterations,thesis_iterations,mean_error_mm,max_error_mm,"
         "thesis_mean_mm,thesis_max_mm,cg_mean_error_mm,cg_max_error_mm\n";
  for (int ks = 1; ks <= 6; ++ks)
    for (int kr = std::max(3, ks); kr <= 7; ++kr) {
      if (ks == 1 && kr < 3) continue;
      const Solution s = solve(ks, kr, false);
      const Solution exact = solve(ks, kr, true);
      it[{ks, kr}] = s.iterations;
      std::vector<double> per_node;
      err[{ks, kr}] = errors(ref, exact, &per_node);
      if (kr == 6 && (ks == 6 || ks == 3)) {
        // Fig. 6.10: top h6/h6, bottom h3/h6; each scaled to its own maximum.
        const std::string name = "fig6_10_h" + std::to_string(ks) + "_h6.svg";
        const double top = err[{ks, kr}].second;
        char title[160];
        std::snprintf(title, sizeof title,
                      "displacement error, h_start = h%d, h_ref = h6 (white 0, red %.3f mm)", ks,
                      top);
        write_error_svg(std::string(INCISE_CH6_OUTPUT_DIR) + "/" + name, ref, per_node, exact, top,
                        title);
        Eigen::Index worst = 0;
        for (std::size_t v = 0; v < per_node.size(); ++v)
          if (per_node[v] > per_node[static_cast<std::size_t>(worst)])
            worst = static_cast<Eigen::Index>(v);
        std::printf("h%d/h6: largest error %.3f mm at (%.1f, %.1f) mm\n", ks, top,
                    1e3 * ref.mesh.points()(0, worst), 1e3 * ref.mesh.points()(1, worst));
      }
      cg_err[{ks, kr}] = errors(exact, s);
      const int c = kr - 3, r = ks - 1;
      csv << "h" << ks << ",h" << kr << "," << s.triangles << "," << s.iterations << ","
          << kThesisIterations[r][c] << "," << err[{ks, kr}].first << "," << err[{ks, kr}].second
          << "," << kThesisMean[r][c] << "," << kThesisMax[r][c] << "," << cg_err[{ks, kr}].first
          << "," << cg_err[{ks, kr}].second << "\n";
      std::printf(
          "h%d/h%d: %6d triangles  CG %4ld (thesis %3d)  err mean %.4f max %.4f mm "
          "(thesis %.2f / %.2f)  CG vs exact %.4f / %.4f mm\n",
          ks, kr, s.triangles, s.iterations, kThesisIterations[r][c], err[{ks, kr}].first,
          err[{ks, kr}].second, kThesisMean[r][c], kThesisMax[r][c], cg_err[{ks, kr}].first,
          cg_err[{ks, kr}].second);
    }
  const auto iters = [&](int ks, int kr) { return it.at(std::make_pair(ks, kr)); };
  const auto mean = [&](int ks, int kr) { return err.at(std::make_pair(ks, kr)).first; };
  const auto maxerr = [&](int ks, int kr) { return err.at(std::make_pair(ks, kr)).second; };
  // Trend 1 (Table 6.2 rows; the thesis' h5 row is the exception, so it is not asserted):
  // refining further around the needle costs iterations.
  for (int ks : {1, 2, 3, 4, 6})
    for (int kr = std::max(3, ks); kr < 7; ++kr)
      EXPECT_LT(iters(ks, kr), iters(ks, kr + 1)) << "row h" << ks << " h_ref h" << kr;
  // Trend 2 (Table 6.2 columns): a finer starting mesh costs iterations ("information travels
  // faster over coarser mesh parts").
  for (int kr = 3; kr <= 7; ++kr)
    for (int ks = 1; ks < std::min(kr, 6); ++ks)
      EXPECT_LE(iters(ks, kr), iters(ks + 1, kr)) << "column h" << kr << " h_start h" << ks;
  // Band (reported as measured, two-sided): ours are 0.44–0.86 of the thesis' counts. Same CG
  // and stopping rule on the same slab; the load values and the thesis' ε are not stated, so
  // the claim is "the same order, somewhat fewer", not equality.
  for (const auto& [key, n] : it) {
    const double thesis = kThesisIterations[key.first - 1][key.second - 3];
    EXPECT_GE(n, 0.4 * thesis) << "h" << key.first << "/h" << key.second;
    EXPECT_LE(n, 1.0 * thesis) << "h" << key.first << "/h" << key.second;
  }
  // Trend 3 (Table 6.3, maximum error): refining around the needle to h7 lowers the maximum
  // error below that of the coarsest h_ref, for h_start = h2…h6 (in our h1 row the maximum sits
  // stays at 0.203–0.204 mm for every h_ref: a difference, README.md).
  for (int ks = 2; ks <= 6; ++ks) {
    const int first = std::max(3, ks);
    EXPECT_LT(maxerr(ks, 7), maxerr(ks, first)) << "row h" << ks;
  }
  // Trend 4 (Table 6.3, mean error columns): a finer starting mesh lowers the mean error.
  for (int kr = 3; kr <= 7; ++kr)
    for (int ks = 1; ks < std::min(kr, 6); ++ks)
      EXPECT_LT(mean(ks + 1, kr), mean(ks, kr)) << "column h" << kr << " h_start h" << ks;
}

// --- Table 6.6: relocation on a tilted line (§6.8.6) -------------------------------------

constexpr double kTiltAngle = 10.0 * 3.14159265358979323846 / 180.0;  // Fig. 6.11: not stated
const Vec2 kTiltEntry(0.0, 0.04);

/// A mesh with its own reference positions (relocated nodes moved) and its solution.
struct Field {
  incise::mesh::MeshData data;
  VecX u;
};

/// Static friction load along the tilted segment from kTiltEntry over 70 mm. Needle nodes are
/// chosen as needle::NeedleInsertion intercepts them (the closer endpoint of every edge that
/// crosses the segment); with `relocate` they are projected orthogonally onto it (§6.8.6).
Field solve_tilted(int k_start, int k_ref, bool relocate) {
  incise::mesh::BisectionMesh mesh(incise::mesh::make_thesis_slab(k_start));
  const Vec2 t(std::cos(kTiltAngle), std::sin(kTiltAngle)), n(-t.y(), t.x());
  const Vec2 tip = kTiltEntry + 0.07 * t;
  const double h_ref = incise::mesh::thesis_slab_spacing(k_ref);
  if (k_ref > k_start)
    for (double d = 0.0; d <= 0.07 + 1e-12; d += h_ref / 4)
      mesh.refine_around(kTiltEntry + d * t, std::sqrt(2.0) * h_ref * (1 + 1e-9));
  Field f{mesh.to_mesh_data(), VecX()};
  auto& pts = f.data.points;
  std::vector<char> is_needle(static_cast<std::size_t>(pts.cols()), 0);
  const auto cr = [](const Vec2& a, const Vec2& b) { return a(0) * b(1) - a(1) * b(0); };
  const Vec2 d = tip - kTiltEntry;
  for (Index c = 0; c < f.data.num_cells(); ++c)
    for (int i = 0; i < 3; ++i) {
      const Index p = f.data.cells(i, c), q = f.data.cells((i + 1) % 3, c);
      const Vec2 a = pts.col(p).head<2>(), e = pts.col(q).head<2>() - a;
      const double den = cr(e, d);
      if (den == 0.0) continue;
      const double alpha = cr(kTiltEntry - a, d) / den, beta = cr(kTiltEntry - a, e) / den;
      if (alpha < 0 || alpha > 1 || beta < 0 || beta > 1) continue;
      is_needle[static_cast<std::size_t>(alpha < 0.5 ? p : q)] = 1;
    }
  std::vector<std::vector<Index>> star(static_cast<std::size_t>(pts.cols()));
  for (Index c = 0; c < f.data.num_cells(); ++c)
    for (int i = 0; i < 3; ++i) star[static_cast<std::size_t>(f.data.cells(i, c))].push_back(c);
  const auto area = [&](Index c) {
    const Vec2 a = pts.col(f.data.cells(0, c)).head<2>(), b = pts.col(f.data.cells(1, c)).head<2>(),
               cc = pts.col(f.data.cells(2, c)).head<2>();
    return 0.5 * cr(b - a, cc - a);
  };
  std::vector<Index> line, fixed;
  std::vector<double> sl;
  int kept = 0;
  for (Index v = 0; v < f.data.num_points(); ++v) {
    if (pts(0, v) > 0.1 - 1e-12) fixed.push_back(v);
    if (!is_needle[static_cast<std::size_t>(v)]) continue;
    const Vec2 x = pts.col(v).head<2>();
    const double sv = (tip - x).dot(t);
    if (sv < 0.0 || sv > 0.07) continue;
    // Relocation keeps boundary nodes on the boundary (the entry at x = 0), and a node whose
    // projection would leave an incident triangle with less than a quarter of its area stays
    // where it is (the flattening of §6.4 / ch. 3: a triangle with all three vertices
    // projected onto the line has none).
    if (relocate && x.x() > 1e-12) {
      std::vector<double> before;
      for (const Index c : star[static_cast<std::size_t>(v)]) before.push_back(area(c));
      pts.col(v).head<2>() = x - (x - tip).dot(n) * n;
      for (std::size_t k = 0; k < before.size(); ++k)
        if (area(star[static_cast<std::size_t>(v)][k]) < 0.25 * before[k]) {
          pts.col(v).head<2>() = x;
          ++kept;
          break;
        }
    }
    line.push_back(v);
    sl.push_back(sv);
  }
  if (relocate)
    std::printf("h%d/h%d: %zu needle nodes, %d not relocated (flattening)\n", k_start, k_ref,
                line.size(), kept);
  incise::fem::PlaneStressProblem p(f.data, material(), kThickness);
  p.fix_nodes(fixed);
  const std::vector<double> load = incise::needle::FrictionProfile{}.dynamic_thresholds(sl);
  for (std::size_t k = 0; k < line.size(); ++k) p.add_point_load(line[k], load[k] * t);
  f.u = VecX::Zero(p.size());
  incise::needle::NeedleProblem np(p, incise::needle::NeedlePose{}, {}, {});
  const auto r = incise::needle::direct_solve(np, f.u);
  EXPECT_TRUE(r.ok()) << r.brief();
  return f;
}

/// `f`'s field at x (brute-force location; its reference positions may be relocated).
Vec2 evaluate(const Field& f, const Vec2& x) {
  const auto cr = [](const Vec2& a, const Vec2& b) { return a(0) * b(1) - a(1) * b(0); };
  for (Index c = 0; c < f.data.num_cells(); ++c) {
    const Index i0 = f.data.cells(0, c), i1 = f.data.cells(1, c), i2 = f.data.cells(2, c);
    const Vec2 a = f.data.points.col(i0).head<2>(), b = f.data.points.col(i1).head<2>(),
               cc = f.data.points.col(i2).head<2>();
    const double area = cr(b - a, cc - a);
    const double la = cr(b - x, cc - x) / area, lb = cr(cc - x, a - x) / area;
    const double lc = 1 - la - lb;
    if (la < -1e-12 || lb < -1e-12 || lc < -1e-12) continue;
    return la * f.u.segment<2>(2 * i0) + lb * f.u.segment<2>(2 * i1) + lc * f.u.segment<2>(2 * i2);
  }
  ADD_FAILURE() << "point outside the mesh";
  return Vec2::Zero();
}

/// Mean and max (mm) over the nodes of `at` of |I_a − I_b|; `a` == nullptr stands for `at`'s
/// own nodal values.
std::pair<double, double> difference(const Field& at, const Field* a, const Field& b) {
  double sum = 0.0, mx = 0.0;
  for (Index v = 0; v < at.data.num_points(); ++v) {
    const Vec2 x = at.data.points.col(v).head<2>();
    const Vec2 ua = a ? evaluate(*a, x) : Vec2(at.u.segment<2>(2 * v));
    const double e = (ua - evaluate(b, x)).norm() * 1e3;
    sum += e;
    mx = std::max(mx, e);
  }
  return {sum / at.data.num_points(), mx};
}

TEST(Chapter6, Table6_6_Relocation) {
  // As the thesis: h_start = h3, h_ref = h6, against the uniform h7 slab (without relocation),
  // sampled at the h7 nodes.
  const Field ref = solve_tilted(7, 7, false);
  const Field with = solve_tilted(3, 6, true), without = solve_tilted(3, 6, false);
  const auto wv = difference(ref, &with, without), dw = difference(ref, nullptr, with),
             dwo = difference(ref, nullptr, without);
  std::printf(
      "Table 6.6 (h3/h6, against uniform h7): with vs without %.3f / %.3f mm (thesis "
      "0.019 / 0.23); with relocation %.3f / %.3f (0.094 / 0.43); without %.3f / %.3f "
      "(0.095 / 0.37)\n",
      wv.first, wv.second, dw.first, dw.second, dwo.first, dwo.second);
  std::ofstream csv(std::string(INCISE_CH6_OUTPUT_DIR) + "/table6_6.csv");
  csv << "quantity,mean_mm,max_mm,thesis_mean_mm,thesis_max_mm\n"
      << "with_vs_without," << wv.first << "," << wv.second << ",0.019,0.23\n"
      << "discretization_with," << dw.first << "," << dw.second << ",0.094,0.43\n"
      << "discretization_without," << dwo.first << "," << dwo.second << ",0.095,0.37\n";
  // The thesis' conclusion: the difference relocation makes is smaller than the discretization
  // error, with or without relocation (mean errors).
  EXPECT_LT(wv.first, dw.first);
  EXPECT_LT(wv.first, dwo.first);
}

#ifdef INCISE_CH6_SLOW
// Thesis Table 6.1: relaxation tolerance ε, average and maximum error (mm) against ε = 1e-8.
const double kThesisT61[6][3] = {{0.3, 0.74, 2.98},       {0.1, 0.061, 0.18},
                                 {0.03, 0.034, 0.083},    {0.01, 0.011, 0.022},
                                 {0.003, 0.0038, 0.0096}, {0.001, 0.0008, 0.0021}};
#endif

#ifdef INCISE_CH6_SLOW
// ≈ 6 s CPU (six CG solves from zero on the 32768-triangle h7 slab): the slow executable only.
TEST(Chapter6, Table6_1_RelaxationTolerance) {
  // h_start = h_ref = h7 (§6.8.2); the reference is the direct solve (the thesis: ε = 1e-8).
  const Solution ref = solve(7, 7, true);
  std::ofstream csv(std::string(INCISE_CH6_OUTPUT_DIR) + "/table6_1.csv");
  csv << "epsilon,cg_iterations,mean_error_mm,max_error_mm,thesis_mean_mm,thesis_max_mm\n";
  std::vector<std::pair<double, double>> e;
  for (const auto& row : kThesisT61) {
    const Solution s = solve(7, 7, false, row[0]);
    e.push_back(errors(ref, s));
    std::printf("eps %.3f: CG %ld  error mean %.4f max %.4f mm (thesis %.4f / %.4f)\n", row[0],
                s.iterations, e.back().first, e.back().second, row[1], row[2]);
    csv << row[0] << "," << s.iterations << "," << e.back().first << "," << e.back().second << ","
        << row[1] << "," << row[2] << "\n";
  }
  // The thesis' trend: a tighter tolerance gives a smaller error, and ε = 0.001 is far below the
  // ≈ 1 mm accuracy target.
  for (std::size_t i = 0; i + 1 < e.size(); ++i) EXPECT_LT(e[i + 1].first, e[i].first) << i;
  EXPECT_LT(e.back().second, 0.1);
  // Band, two-sided: every mean error within a factor 3 of the thesis' (measured 0.68–2.1×).
  // (6.9) is relative, so the errors scale with the displacements, whose magnitude the friction
  // profile was fitted to on Table 6.3 (not on this table); a factor 3 allows for the unknown
  // profile shape.
  for (std::size_t i = 0; i < e.size(); ++i) {
    EXPECT_GE(e[i].first, kThesisT61[i][1] / 3) << "eps " << kThesisT61[i][0];
    EXPECT_LE(e[i].first, kThesisT61[i][1] * 3) << "eps " << kThesisT61[i][0];
  }
}
#endif

}  // namespace
