#pragma once
/// \file delaunay_cut_session.hpp
/// Delaunay cutting of a deforming plane-stress sheet (thesis §5.5, "future work": intersect the
/// scalpel with the deformed mesh and map the point back to the reference element). The sheet is
/// a delaunay::Triangulation in the reference configuration, cut by delaunay::Cutter2D; after
/// every movement the plane-stress problem (fem::PlaneStressProblem, §6.3) is rebuilt on the
/// current mesh and solved by linear CG (solver/linear_cg.hpp) warm-started from the previous
/// displacement, so an incision across a stretched sheet opens.
///
/// World → reference: a scalpel position inside the deformed sheet is mapped through the
/// deformed triangle that contains it (barycentric coordinates, exact for linear elements); a
/// position outside is moved by the displacement of the nearest deformed vertex. New nodes start
/// from the mean displacement of their neighbours (a warm start only: the solve decides).
/// Boundary conditions are given by lines, re-applied to the current nodes after every change
/// (nodes the cutter puts on a fixed line are fixed too).

#include <incise/core/outcome.hpp>
#include <incise/delaunay/cutter2d.hpp>
#include <incise/delaunay/triangulation.hpp>
#include <incise/material/material.hpp>
#include <incise/solver/report.hpp>

#include <memory>
#include <vector>

namespace incise::interactive {

/// A line {x : x[axis] = value} of the sheet (axis 0 or 1), within 1e-9 of the sheet's size.
struct SheetLine {
  int axis = 0;
  double value = 0.0;
};

/// Options of a DelaunayCutSession.
struct DelaunayCutSessionOptions {
  delaunay::Cutter2DOptions cutter;  ///< the cutter's thresholds (§5.4 defaults)
  double tolerance = 1e-8;           ///< CG: ‖r‖ ≤ tolerance · ‖f_ext‖ (6.8)
  long max_iterations = 20000;       ///< CG steps per solve
};

/// Outcome of one movement of a DelaunayCutSession: the solve's status (ok = converged).
struct [[nodiscard]] DelaunayCutStepReport
    : Outcome<solver::StopReason, solver::StopReason::kConverged,
              solver::StopReason::kMaxIterations> {
  delaunay::CutMove2DReport cut;        ///< what the cutter did
  Vec2 reference_point = Vec2::Zero();  ///< the scalpel mapped to the reference configuration
  long cg_iterations = 0;               ///< CG steps of this movement's solve
  double residual_norm = 0.0;           ///< final ‖r‖ (N)
};

/// A plane-stress sheet, a Delaunay cutter on it and its static solution (see file comment).
class DelaunayCutSession {
 public:
  /// Sheet `mesh` (2D, counter-clockwise), `material` in plane stress of thickness `thickness`
  /// (m); nodes on `fixed` lines held; `traction` (N/m², reference) on the boundary edges of
  /// `loaded`. Solves the uncut sheet: initial_report(). Throws ParameterError for a bad mesh,
  /// material, thickness or line axis.
  DelaunayCutSession(const mesh::MeshData& mesh, const material::Material& material,
                     double thickness, std::vector<SheetLine> fixed, SheetLine loaded,
                     const Vec2& traction, DelaunayCutSessionOptions options = {});
  ~DelaunayCutSession();
  DelaunayCutSession(const DelaunayCutSession&) = delete;
  DelaunayCutSession& operator=(const DelaunayCutSession&) = delete;

  /// The solve of the uncut sheet.
  const DelaunayCutStepReport& initial_report() const { return initial_; }
  /// Moves the scalpel to world point x (m), cuts, re-solves.
  DelaunayCutStepReport move_to(const Vec2& x);

  /// The sheet in the reference configuration.
  const delaunay::Triangulation& mesh() const { return *mesh_; }
  /// The cutter (phase, incision nodes).
  const delaunay::Cutter2D& cutter() const { return *cutter_; }
  /// Displacement of vertex v (m); zero for vertices without triangles.
  Vec2 displacement(Index v) const;
  /// Deformed position of vertex v (m).
  Vec2 deformed(Index v) const { return mesh_->point(v) + displacement(v); }

 private:
  Vec2 to_reference(const Vec2& x) const;
  DelaunayCutStepReport solve();

  material::Material material_;
  double thickness_;
  std::vector<SheetLine> fixed_;
  SheetLine loaded_;
  Vec2 traction_;
  DelaunayCutSessionOptions options_;
  double line_tolerance_ = 0;
  std::unique_ptr<delaunay::Triangulation> mesh_;
  std::unique_ptr<delaunay::Cutter2D> cutter_;
  std::vector<Vec2> u_;  // per vertex
  DelaunayCutStepReport initial_;
};

}  // namespace incise::interactive
