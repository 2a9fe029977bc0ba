/// Thesis §3.3: "In these generated cubes the frequency of degeneracies strongly correlates
/// with the angle of the cut." Our large diagonal cut gives 2–13 degenerate elements against
/// the thesis' 143 (README.md); this case tests whether any cut orientation or position comes
/// near. Deterministic grid over the cut plane: azimuth θ of the blade in the xy plane, tilt φ
/// of the sweep from the vertical, offset δ of the plane from the cube centre (fractions of the
/// cell size h = 1/8). For every setting the cut is made four ways — (a) thesis-faithful
/// snapping without removal, (b) inverting snaps refused without removal, (c) = (b) + removal,
/// (d) = (a) + removal — and the warm-restarted CG is run where possible (§3.3 setup, see
/// ch3_common.hpp). Label `slow` (≈ 30 s CPU in Release); prints the table and the ranges.
/// The CG of (b) — reported, never asserted — stops at kReportedCgCap = 30,000 iterations: the
/// largest count that converges is 24,173, and the 4 settings that reach any cap (they did not
/// converge within 100,000 either) cost 44 % of the case's CPU time (56 → 32 s). (c) and (d),
/// whose convergence is asserted, keep ch3_common.hpp's budget of 100,000.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "ch3_common.hpp"

namespace incise::verify {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr long kReportedCgCap = 30000;  // CG budget of (b), see above

/// Blade for the plane through the cube centre shifted by `offset` (m) along the horizontal
/// normal, containing the horizontal direction t = (cos θ, sin θ, 0) and the descent direction
/// tilted by φ from the vertical; from z = 1.25 (above the top face) down by 0.85 in height
/// (to z = 0.4, as the diagonal cut), in 6 moves.
Blade plane_blade(double theta, double phi, double offset) {
  const Vec3 t(std::cos(theta), std::sin(theta), 0.0);
  const Vec3 nh(-std::sin(theta), std::cos(theta), 0.0);
  const Vec3 down = -std::cos(phi) * Vec3::UnitZ() + std::sin(phi) * nh;
  const Vec3 p0 = Vec3(0.5, 0.5, 1.25) + offset * nh - (0.4 * std::tan(phi)) * nh;
  Blade b;
  b.steps = 6;
  b.a0 = p0 - 0.95 * t;
  b.b0 = p0 + 0.95 * t;
  b.move = (0.85 / std::cos(phi) / b.steps) * down;
  return b;
}

std::string iterations(const CutOutcome& o) {
  return o.solve.attempted ? std::to_string(o.solve.iterations) : std::string("n/a");
}

TEST(Nienhuys2003Ch3Slow, DegeneraciesAgainstTheAngleOfTheCut) {
  const Ch3Cube cube;
  ASSERT_TRUE(cube.converged);
  const double h = 1.0 / 8;
  std::printf(
      "theta  phi  delta/h | (a) faces degen inv | (b) faces degen CG | (c) coll incoll CG | "
      "(d) coll incoll CG\n");
  int max_degen_a = 0, max_degen_b = 0, max_coll_d = 0, max_incoll = 0, settings = 0;
  long max_cg_b = 0, min_cg_b = 1L << 40;
  int min_degen_a = 1 << 30, max_faces = 0, min_faces = 1 << 30;
  std::string best;
  for (double theta_deg : {0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0, 31.6}) {
    for (double phi_deg : {0.0, 15.0, 30.0, 45.0}) {
      for (double off : {0.0, 0.25, 0.5}) {
        const Blade blade = plane_blade(theta_deg * kPi / 180, phi_deg * kPi / 180, off * h);
        cut::CutOptions faithful, refused;
        faithful.remove_degeneracies = false;
        faithful.refuse_inverting_snaps = false;
        refused.remove_degeneracies = false;
        cut::CutOptions faithful_rm = faithful, refused_rm = refused;
        faithful_rm.remove_degeneracies = true;
        refused_rm.remove_degeneracies = true;
        const CutOutcome a = run_cut(cube, blade, faithful, false);
        const CutOutcome b = run_cut(cube, blade, refused, true, kReportedCgCap);
        const CutOutcome c = run_cut(cube, blade, refused_rm);
        const CutOutcome d = run_cut(cube, blade, faithful_rm);
        std::printf("%5.1f %4.0f %7.2f | %9d %5d %3d | %9d %5d %5s | %4d %6d %5s | %4d %6d %5s\n",
                    theta_deg, phi_deg, off, a.totals.faces_dissected, a.degenerate_after,
                    a.inverted, b.totals.faces_dissected, b.degenerate_after, iterations(b).c_str(),
                    c.totals.collapses, c.totals.incollapsible, iterations(c).c_str(),
                    d.totals.collapses, d.totals.incollapsible, iterations(d).c_str());
        ++settings;
        if (a.degenerate_after > max_degen_a) {
          max_degen_a = a.degenerate_after;
          char buf[96];
          std::snprintf(buf, sizeof buf, "theta %.1f phi %.0f delta %.2f h", theta_deg, phi_deg,
                        off);
          best = buf;
        }
        min_degen_a = std::min<int>(min_degen_a, a.degenerate_after);
        max_degen_b = std::max<int>(max_degen_b, b.degenerate_after);
        max_coll_d = std::max<int>(max_coll_d, d.totals.collapses);
        max_incoll =
            std::max<int>(max_incoll, std::max(c.totals.incollapsible, d.totals.incollapsible));
        max_faces = std::max<int>(max_faces, a.totals.faces_dissected);
        min_faces = std::min<int>(min_faces, a.totals.faces_dissected);
        if (b.solve.attempted) {
          max_cg_b = std::max(max_cg_b, b.solve.iterations);
          min_cg_b = std::min(min_cg_b, b.solve.iterations);
        }
        // Degeneracy removal leaves nothing below the threshold (§3.2.3), in every setting.
        EXPECT_EQ(c.degenerate_after, 0);
        EXPECT_EQ(d.degenerate_after, 0);
        EXPECT_EQ(b.inverted, 0);
        // README: with removal the warm-restarted CG converges in every setting (111–473
        // iterations), while without it some settings exhaust the iteration budget.
        const std::string setting = "theta " + std::to_string(theta_deg) + " phi " +
                                    std::to_string(phi_deg) + " delta/h " + std::to_string(off);
        EXPECT_TRUE(c.solve.converged) << setting;
        if (d.solve.attempted) {
          EXPECT_TRUE(d.solve.converged) << setting;
        }
      }
    }
  }
  std::printf(
      "%d settings. Ranges: faces dissected (a) %d..%d (thesis 108); degenerate (a) %d..%d "
      "(thesis 143; max at %s), (b) ..%d; collapses (d) ..%d (thesis 99); incollapsible ..%d "
      "(thesis 13); CG without removal (b) %ld..%ld (thesis 2439)\n",
      settings, min_faces, max_faces, min_degen_a, max_degen_a, best.c_str(), max_degen_b,
      max_coll_d, max_incoll, min_cg_b, max_cg_b);
}

}  // namespace
}  // namespace incise::verify
