/// Thesis §3.3: "a large cut (108 faces dissected) in a generated cube ... which produces 143
/// degenerate elements", with "an element is considered degenerate if its aspect ratio is less
/// than 0.01" (§3.2.3: minimum height over maximum edge). Our diagonal cut gives 2–13 and no
/// setting of the 96-plane sweep more than 60 (README.md). This case tests candidate
/// explanations of the gap in definition and setup that the thesis leaves open, on the §3.3
/// cube (ch3_common.hpp), thesis-faithful snapping (inverting snaps not refused) and no
/// removal unless stated:
///   - the threshold or normalization of the aspect ratio: counts below 0.01 … 0.2;
///   - the configuration in which it is measured: reference X (ours) and deformed x;
///   - counting per sweep-triangle step (a running total of the elements degenerate after each
///     step) instead of once after the cut;
///   - the granularity and planarity of the sweep: 4× finer sweep triangles, and a blade that
///     turns 2° about the vertical per move (an interactive, non-planar sweep);
///   - the cut made while the body relaxes: CG to equilibrium after every sweep triangle (the
///     thesis interleaves relaxation and cutting), with 10× larger dilating loads (the cut then
///     opens between steps); inverting snaps refused here, since the FEM cannot be set up with
///     inverted elements.
/// The mesh stays valid after every step (asserted); no variant reaches the thesis' 143 at
/// any aspect-ratio threshold up to 0.2 (asserted: the gap is not one of these definitions).
/// Prints the table of README.md, "Which definition of degenerate?".
#include <gtest/gtest.h>

#include <incise/mesh/quality.hpp>

#include "ch3_common.hpp"

#include <cmath>
#include <cstdio>
#include <string>

namespace incise::verify {
namespace {

/// Aspect-ratio thresholds tried: the thesis' 0.01 and up to 20× looser.
constexpr double kThresholds[] = {0.01, 0.02, 0.05, 0.1, 0.2};
constexpr int kNumThresholds = 5;

struct Variant {
  const char* name;
  int moves_per_diagonal_move = 1;  ///< sweep triangles per move of the diagonal blade ÷ 2
  double turn_degrees = 0;          ///< blade rotation about the vertical per move
  bool relax = false;               ///< CG to equilibrium after every sweep triangle
  double load_scale = 1;            ///< factor on the dilating loads
  bool refuse_inverting_snaps = false;
};

struct Counts {
  int faces = 0, snapped = 0;
  int below[kNumThresholds] = {};  ///< reference configuration, after the cut
  int deformed = 0;                ///< AR < 0.01 or inverted in the deformed configuration
  int per_step_total = 0;          ///< Σ over sweep triangles of the count after each one
};

bool degenerate(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double threshold) {
  return mesh::signed_volume(a, b, c, d) <= 0 || mesh::aspect_ratio(a, b, c, d) < threshold;
}

/// Equilibrium of the cube under `scale` × the dilating loads (the state the cut starts from).
Ch3Cube scaled_cube(double scale) {
  Ch3Cube cube;
  if (scale == 1) return cube;
  for (auto& l : cube.loads) l.force *= scale;
  cut::CutMesh cm = cube.make_mesh(false);
  const Solve s = solve(cm, cube.loads);
  EXPECT_TRUE(s.converged);
  cube.deformed = cm.reference_matrix();
  for (Index v = 0; v < cm.num_nodes(); ++v) cube.deformed.col(v) += s.u.segment<3>(3 * v);
  return cube;
}

Counts run_variant(const Variant& var) {
  const Ch3Cube cube = scaled_cube(var.load_scale);
  cut::CutMesh cm = cube.make_mesh(true);
  cut::CutOptions opt;
  opt.remove_degeneracies = false;
  opt.refuse_inverting_snaps = var.refuse_inverting_snaps;
  cut::Cutter cutter(cm, opt);
  const Blade blade = diagonal_blade();
  const int moves = blade.steps * var.moves_per_diagonal_move;
  const Vec3 move = blade.move / var.moves_per_diagonal_move;
  const double turn = var.turn_degrees * 3.14159265358979323846 / 180;
  Vec3 a = blade.a0, b = blade.b0;
  Counts c;
  for (int s = 0; s < moves; ++s) {
    const Vec3 d = b - a;
    const Vec3 d_turned(std::cos(turn) * d.x() - std::sin(turn) * d.y(),
                        std::sin(turn) * d.x() + std::cos(turn) * d.y(), d.z());
    const Vec3 a2 = a + move, b2 = a2 + d_turned;
    for (const auto& tri : {std::array<Vec3, 3>{a, b, b2}, std::array<Vec3, 3>{a, b2, a2}}) {
      const cut::CutStepReport r = cutter.step(tri[0], tri[1], tri[2]);
      c.faces += r.faces_dissected;
      c.snapped += r.nodes_snapped;
      const cut::CutMeshValidation v = cm.validate();
      EXPECT_TRUE(v.ok()) << var.name << ": " << (v.violations.empty() ? "" : v.violations[0]);
      c.per_step_total += cutter.count_degenerate();
      if (var.relax) {
        EXPECT_EQ(v.inverted_reference, 0) << var.name;
        std::vector<Index> map;
        (void)cm.to_mesh_data(false, true, &map);
        const Solve sol = solve(cm, cube.loads);
        EXPECT_TRUE(sol.converged) << var.name;
        Eigen::Matrix3Xd x = cm.deformed_matrix();
        for (Index n = 0; n < cm.num_nodes(); ++n) {
          const Index m = map[static_cast<size_t>(n)];
          if (m >= 0) x.col(n) = cm.reference(n) + sol.u.segment<3>(3 * m);
        }
        cm.set_deformed(x);
      }
    }
    a = a2;
    b = b2;
  }
  for (Index e = 0; e < cm.element_capacity(); ++e) {
    if (!cm.alive(e)) continue;
    const cut::Tet& t = cm.element(e);
    for (int k = 0; k < kNumThresholds; ++k) {
      c.below[k] += degenerate(cm.reference(t[0]), cm.reference(t[1]), cm.reference(t[2]),
                               cm.reference(t[3]), kThresholds[k]);
    }
    c.deformed += degenerate(cm.deformed(t[0]), cm.deformed(t[1]), cm.deformed(t[2]),
                             cm.deformed(t[3]), kThresholds[0]);
  }
  EXPECT_EQ(c.below[0], cutter.count_degenerate()) << var.name;  // the cutter's own definition
  return c;
}

TEST(Nienhuys2003Ch3, DegenerateCountCandidateDefinitions) {
  const Variant variants[] = {
      {"(a) diagonal cut, 6 moves (README)"},
      {"(a) 24 moves (4x finer sweep triangles)", 4},
      {"(a) 24 moves, blade turns 2 deg/move", 4, 2.0},
      {"(b) relaxed after every triangle", 1, 0.0, true, 1.0, true},
      {"(b) relaxed, 10x loads (cut opens)", 1, 0.0, true, 10.0, true},
      {"(b) relaxed, 10x loads, 24 moves", 4, 0.0, true, 10.0, true},
  };
  std::printf("Thesis §3.3: 108 faces dissected, %d degenerate (AR < 0.01)\n", kThesisDegenerate);
  std::printf("%-42s %5s %5s | AR<0.01  0.02  0.05   0.1   0.2 | deformed | per-step total\n",
              "variant", "faces", "snap");
  for (const Variant& var : variants) {
    const Counts c = run_variant(var);
    std::printf("%-42s %5d %5d | %7d %5d %5d %5d %5d | %8d | %14d\n", var.name, c.faces, c.snapped,
                c.below[0], c.below[1], c.below[2], c.below[3], c.below[4], c.deformed,
                c.per_step_total);
    EXPECT_GT(c.faces, 0) << var.name;
    // Not a threshold or normalization matter: even 20× the thesis' threshold stays below 143.
    EXPECT_LT(c.below[kNumThresholds - 1], kThesisDegenerate) << var.name;
  }
}

}  // namespace
}  // namespace incise::verify
