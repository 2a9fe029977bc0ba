/// Thesis §6.8.4–§6.8.5 (Tables 6.4 and 6.5): the standardized insertion of §6.8.1 at several
/// speeds. The slab of §6.8.1 (h_start = h3, h_ref = h6), the needle along y = 0.05 m from
/// x = 0 in +x, advanced by a fixed amount (speed × h_ref) per update to a depth of 70 mm, then
/// settled (settle() until a pass needs no rearrangement). Per speed: updates, solves, CG
/// iterations per solve (mean, max), CPU seconds (reported only), and the final displacement's
/// error against the slowest insertion (mean, max over its nodes, mm). Writes table6_5.csv.

#include <incise/core/timer.hpp>
#include <incise/material/material.hpp>
#include <incise/mesh/slab2d.hpp>
#include <incise/mesh/validate.hpp>
#include <incise/needle/insertion.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#ifndef INCISE_CH6_OUTPUT_DIR
#define INCISE_CH6_OUTPUT_DIR "."
#endif

namespace {

using incise::Vec2;
using incise::VecX;
using incise::needle::NeedleInsertion;
using incise::needle::NeedlePose;
using incise::needle::StepReport;

struct Insertion {
  std::unique_ptr<NeedleInsertion> sim;
  long updates = 0, solves = 0, cg = 0, cg_max = 0;
  double seconds = 0.0;
  bool ok = true;
};

Insertion insert(int k_start, int k_ref, double speed) {
  incise::material::Parameters p;
  p.youngs_modulus = 3.4e4;
  p.poisson_ratio = 0.34;
  incise::needle::InsertionOptions o;
  o.h_ref = incise::mesh::thesis_slab_spacing(k_ref);
  o.epsilon = 0.01;
  Insertion r;
  r.sim = std::make_unique<NeedleInsertion>(
      incise::mesh::make_thesis_slab(k_start), incise::material::Material("linear", p), 0.01,
      std::vector<incise::needle::FixedLine>{{0, 0.1}}, incise::needle::FrictionProfile{}, o);
  const double step = speed * o.h_ref;
  const auto account = [&](const StepReport& rep) {
    ++r.updates;
    r.solves += rep.solves;
    r.cg += rep.cg_iterations;
    r.cg_max = std::max(r.cg_max, rep.max_cg_iterations);
    if (!rep.ok()) r.ok = false;
  };
  incise::Timer timer;
  const int n = static_cast<int>(std::ceil(0.07 / step - 1e-9));
  for (int k = 0; k <= n && r.ok; ++k) {
    const double depth = std::min(0.07, k * step);
    account(r.sim->step(NeedlePose::make(Vec2(depth, 0.05), Vec2(1.0, 0.0), 0.1)));
  }
  for (int k = 0; k < 100 && r.ok; ++k) {
    const StepReport rep = r.sim->settle();
    account(rep);
    if (rep.rearrangements == 0) break;
  }
  r.seconds = timer.seconds();
  return r;
}

/// Mean and max (mm) over the nodes of `ref` of |u_ref − I u| (I: `run`'s field there).
std::pair<double, double> errors(const NeedleInsertion& ref, const NeedleInsertion& run) {
  double sum = 0.0, mx = 0.0;
  const auto& pts = ref.mesh().points();
  const auto& conn = run.mesh().connectivity();
  const auto& sp = run.mesh().points();
  const VecX& u = run.displacement();
  for (Eigen::Index v = 0; v < pts.cols(); ++v) {
    const Vec2 x = pts.col(v).head<2>();
    const auto e = run.mesh().locate(x);
    EXPECT_TRUE(e.valid());
    const auto& t = conn.simplex(e);
    const Vec2 a = sp.col(t.vertex(0)).head<2>(), b = sp.col(t.vertex(1)).head<2>(),
               c = sp.col(t.vertex(2)).head<2>();
    const auto cr = [](const Vec2& p, const Vec2& q) { return p(0) * q(1) - p(1) * q(0); };
    const double area = cr(b - a, c - a);
    const double la = cr(b - x, c - x) / area, lb = cr(c - x, a - x) / area, lc = 1 - la - lb;
    const Vec2 ui = la * u.segment<2>(2 * t.vertex(0)) + lb * u.segment<2>(2 * t.vertex(1)) +
                    lc * u.segment<2>(2 * t.vertex(2));
    const double err = (ref.displacement().segment<2>(2 * v) - ui).norm() * 1e3;
    sum += err;
    mx = std::max(mx, err);
  }
  return {sum / static_cast<double>(pts.cols()), mx};
}

// Thesis Table 6.5 (h_start = h3): speed, CPU s, rearrangements, Hz, CG mean, CG max.
struct ThesisRow {
  double speed, seconds, rearrangements, hz, cg_mean, cg_max;
};
const ThesisRow kThesisH6[] = {
    {3.00, 0.80, 157, 196.25, 11.81, 41}, {1.00, 0.90, 232, 257.78, 11.52, 62},
    {0.30, 0.94, 308, 327.66, 10.87, 70}, {0.10, 1.07, 504, 471.03, 8.14, 61},
    {0.03, 2.24, 1478, 659.82, 5.31, 57}, {0.01, 5.77, 4187, 725.65, 3.87, 51}};
const ThesisRow kThesisH7[] = {
    {3.00, 2.46, 243, 98.78, 12.67, 57},  {1.00, 2.80, 401, 143.21, 10.88, 82},
    {0.30, 3.15, 561, 178.10, 10.03, 66}, {0.10, 3.48, 1000, 287.36, 6.63, 67},
    {0.03, 6.34, 2966, 467.82, 4.18, 53}, {0.01, 15.68, 8505, 542.41, 3.15, 48}};
// Thesis Table 6.4 (h3/h6, against 0.005 h_ref): speed, mean, max error (mm).
const double kThesisT64[6][3] = {{3.00, 0.62, 1.60}, {1.00, 0.68, 1.96}, {0.30, 0.15, 0.34},
                                 {0.10, 0.18, 0.68}, {0.03, 0.36, 1.08}, {0.01, 0.07, 0.27}};

bool slow_run() {
#ifdef INCISE_CH6_SLOW
  return true;
#else
  return false;
#endif
}

TEST(Chapter6, Table6_4And6_5_InsertionSpeed) {
  const int rows = slow_run() ? 6 : 4;  // default: speeds 3 … 0.1 at h6 only (≈ 0.3 s)
  std::ofstream csv(std::string(INCISE_CH6_OUTPUT_DIR) + "/table6_5" + (slow_run() ? "_all" : "") +
                    ".csv");
  csv << "h_start,h_ref,speed,updates,solves,cg_mean,cg_max,seconds,solves_per_second,"
         "thesis_rearrangements,thesis_cg_mean,thesis_cg_max,thesis_hz,mean_error_mm,"
         "max_error_mm,thesis_mean_error_mm,thesis_max_error_mm\n";
  std::vector<long> solves_h6, solves_h7;
  for (const int kr : slow_run() ? std::vector<int>{6, 7} : std::vector<int>{6}) {
    const ThesisRow* thesis = kr == 6 ? kThesisH6 : kThesisH7;
    std::unique_ptr<Insertion> ref;
    std::vector<long>& solves = kr == 6 ? solves_h6 : solves_h7;
    if (slow_run() && kr == 6) ref = std::make_unique<Insertion>(insert(3, kr, 0.005));
    std::vector<Insertion> runs;
    for (int i = 0; i < rows; ++i) {
      runs.push_back(insert(3, kr, thesis[i].speed));
      const Insertion& r = runs.back();
      solves.push_back(r.solves);
      ASSERT_TRUE(r.ok) << "speed " << thesis[i].speed;
      incise::mesh::ValidateOptions vo;
      vo.positions = &r.sim->mesh().points();
      EXPECT_TRUE(incise::mesh::validate(r.sim->mesh().connectivity(), vo).ok());
      std::pair<double, double> e{-1.0, -1.0};
      if (ref) {
        e = errors(*ref->sim, *r.sim);
        // Table 6.4: at ≤ 1 h_ref per update the error build-up stays below the §6.8 accuracy
        // target of ≈ 1 mm (thesis 0.07–0.68 mm mean; ours 0.27–0.50).
        if (thesis[i].speed <= 1.0) {
          EXPECT_LT(e.first, 1.0) << "speed " << thesis[i].speed;
        }
      }
      const double cg_mean = double(r.cg) / double(r.solves);
      std::printf(
          "h3/h%d speed %.2f: updates %ld solves %ld (thesis %.0f) CG mean %.2f (%.2f) "
          "max %ld (%.0f)  %.3f s %.0f solves/s (thesis %.0f Hz)  err %.3f / %.3f mm\n",
          kr, thesis[i].speed, r.updates, r.solves, thesis[i].rearrangements, cg_mean,
          thesis[i].cg_mean, r.cg_max, thesis[i].cg_max, r.seconds, double(r.solves) / r.seconds,
          thesis[i].hz, e.first, e.second);
      csv << "h3,h" << kr << "," << thesis[i].speed << "," << r.updates << "," << r.solves << ","
          << cg_mean << "," << r.cg_max << "," << r.seconds << "," << r.solves / r.seconds << ","
          << thesis[i].rearrangements << "," << thesis[i].cg_mean << "," << thesis[i].cg_max << ","
          << thesis[i].hz << "," << e.first << "," << e.second << ","
          << (kr == 6 ? kThesisT64[i][1] : -1.0) << "," << (kr == 6 ? kThesisT64[i][2] : -1.0)
          << "\n";
    }
    // Table 6.5's trends: slower insertion needs more solves (rearrangements) …
    for (int i = 0; i + 1 < rows; ++i)
      EXPECT_LT(runs[i].solves, runs[i + 1].solves) << "h" << kr << " row " << i;
    // … and fewer CG iterations per solve (coherence between subsequent solutions): the
    // slowest speed run needs fewer per solve than the fastest.
    EXPECT_LT(double(runs[rows - 1].cg) / runs[rows - 1].solves,
              double(runs[0].cg) / runs[0].solves);
  }
  // §6.8.5: "decreasing h_ref by a factor 2 doubles the number of boundary condition
  // rearrangements" (thesis ratios 1.55–2.03; ours 1.85–3.18 — a two-sided band around 2).
  for (std::size_t i = 0; i < solves_h7.size(); ++i) {
    const double ratio = double(solves_h7[i]) / double(solves_h6[i]);
    EXPECT_GE(ratio, 1.5) << "speed row " << i;
    EXPECT_LE(ratio, 3.5) << "speed row " << i;
  }
}

#ifdef INCISE_CH6_SLOW
/// Reference position of the material point at the needle tip (through the deformed triangle
/// containing it); NaN when the tip is outside.
Vec2 tip_reference(const NeedleInsertion& sim) {
  const Eigen::Matrix2Xd x = sim.deformed();
  const auto& conn = sim.mesh().connectivity();
  const Vec2 p = sim.pose().tip;
  const auto cr = [](const Vec2& a, const Vec2& b) { return a(0) * b(1) - a(1) * b(0); };
  for (const auto e : conn.elements()) {
    const auto& t = conn.simplex(e);
    const Vec2 a = x.col(t.vertex(0)), b = x.col(t.vertex(1)), c = x.col(t.vertex(2));
    const double area = cr(b - a, c - a);
    const double la = cr(b - p, c - p) / area, lb = cr(c - p, a - p) / area, lc = 1 - la - lb;
    if (la < -1e-12 || lb < -1e-12 || lc < -1e-12) continue;
    const auto& r = sim.mesh().points();
    return la * r.col(t.vertex(0)).head<2>() + lb * r.col(t.vertex(1)).head<2>() +
           lc * r.col(t.vertex(2)).head<2>();
  }
  return Vec2::Constant(std::nan(""));
}

/// Fig. 6.12: sideways insertion into a slab fixed at the bottom, ν = 0, neo-Hookean (nonlinear
/// CG) against linear (linear CG). The thesis' h values, depth and friction are not stated; ours:
/// h_start = h3, h_ref = h5, the needle along y = 0.05 m from x = 0 in +x to 70 mm, 0.1 h_ref per
/// update (the thesis: 0.01). Reported: the distance between the final tip reference locations
/// (thesis ≈ 8 mm) and the final triangle counts (thesis 625, neo-Hookean).
TEST(Chapter6, Fig6_12_NonlinearSideways) {
  std::vector<Vec2> tips;
  for (const bool nonlinear : {false, true}) {
    incise::material::Parameters p;
    p.youngs_modulus = 3.4e4;
    p.poisson_ratio = 0.0;
    incise::needle::InsertionOptions o;
    o.h_ref = incise::mesh::thesis_slab_spacing(5);
    o.epsilon = 0.01;
    o.relaxation = nonlinear ? incise::needle::Relaxation::kNonlinearCg
                             : incise::needle::Relaxation::kLinearCg;
    NeedleInsertion sim(incise::mesh::make_thesis_slab(3),
                        incise::material::Material(nonlinear ? "neohookean" : "linear", p), 0.01,
                        {{1, 0.0}}, incise::needle::FrictionProfile{}, o);
    const double step = 0.01 * o.h_ref;  // the caption's insertion speed, 0.01 h_ref/update
    const int n = static_cast<int>(std::ceil(0.07 / step - 1e-9));
    incise::Timer timer;
    long solves = 0, cg = 0;
    for (int k = 0; k <= n; ++k) {
      const StepReport rep =
          sim.step(NeedlePose::make(Vec2(std::min(0.07, k * step), 0.05), Vec2(1.0, 0.0), 0.1));
      ASSERT_TRUE(rep.ok()) << (nonlinear ? "neo-Hookean" : "linear") << " step " << k << ": "
                            << rep.brief();
      solves += rep.solves;
      cg += rep.cg_iterations;
    }
    for (int k = 0; k < 100; ++k) {
      const StepReport rep = sim.settle();
      ASSERT_TRUE(rep.ok()) << rep.brief();
      solves += rep.solves;
      if (rep.rearrangements == 0) break;
    }
    tips.push_back(tip_reference(sim));
    double umax = 0.0;
    for (Eigen::Index v = 0; v < sim.displacement().size() / 2; ++v)
      umax = std::max(umax, sim.displacement().segment<2>(2 * v).norm());
    std::printf(
        "%s: tip reference (%.2f, %.2f) mm, max |u| %.2f mm, %d triangles, %ld solves, "
        "%ld CG iterations, %.1f s\n",
        nonlinear ? "neo-Hookean" : "linear", 1e3 * tips.back().x(), 1e3 * tips.back().y(),
        1e3 * umax, sim.mesh().connectivity().num_elements(), solves, cg, timer.seconds());
  }
  ASSERT_TRUE(tips[0].allFinite() && tips[1].allFinite());
  std::printf("distance between the tip reference locations: %.2f mm (thesis: approx. 8 mm)\n",
              1e3 * (tips[0] - tips[1]).norm());
}
#endif

}  // namespace
