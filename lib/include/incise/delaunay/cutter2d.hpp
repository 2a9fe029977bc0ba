#pragma once
/// \file cutter2d.hpp
/// Delaunay cutting of a planar triangle mesh by a point scalpel (thesis §5.2.2, Figs. 5.4–5.7).
///
/// The scalpel is a sequence of positions (move_to). While it is inside the mesh it is attached
/// to the active node a, a boundary node whose two boundary edges — the cut edges — form the
/// incision. Each movement:
///  1. moves a towards the scalpel in sub-steps; a sub-step goes at most half-way to the first
///     position where a triangle of a's star would become flat, and after it the edges around a
///     are legalized (empty-circle flips, Fig. 5.3). An interior edge that a approaches is
///     flipped before a reaches it (points of a chord lie inside the circumcircle), so the star
///     never inverts (nor gets flatter than 2·area = 10⁻⁸ · longest edge²: the movement stops as
///     blocked instead); interior nodes closer to a than ε_edge are removed by ear flips
///     (Fig. 5.10);
///  2. records the scalpel path and splits the incision (Fig. 5.5): when the incision, seen as one
///     edge from its last node pair c₁, c₂ (midpoint c) to a, fails the empty-circle criterion in
///     the quadrilateral a o₁ c o₂, new nodes c₁′, c₂′ are inserted where o₁o₂ meets the path,
///     dilated by δ towards o₁ and o₂ so the two sides stay apart;
///  3. predicts the exit (Fig. 5.7): when the movement extrapolated from a meets a boundary edge
///     within ε_exit — or the movement itself reaches one — a node is inserted there, the edge to
///     it is made, dissected and contracted: the incision reaches the boundary and the mesh is
///     separated there. The boundary edges at the exit are forbidden for entry until the scalpel
///     is 2 ε_exit away.
/// Entry (Fig. 5.6): a movement from outside that crosses a boundary edge attaches the scalpel to
/// the edge's end within ε_entry, or to a new node inserted at the crossing. The active node makes
/// a dent until it is ε_entry from the entry point; then the dent is filled with two triangles
/// and the incision starts (fix-up). A scalpel that leaves before the fix-up leaves the dent.
///
/// Boundary edges are found through a uniform grid of cell h̄ kept current by watching the
/// connectivity, so a movement's cost does not grow with the mesh (benchmarks/delaunay).
/// Thresholds are fractions of the mean edge length h̄ of the starting mesh (§5.4 defaults:
/// ε_edge = h̄/3, ε_entry = ε_exit = h̄/6). Every change goes through Triangulation (one
/// replace_elements each, §7.3); triangles stay strictly counter-clockwise by exact predicates.
/// What cannot be done (a blocked movement, a refused split or exit) is reported in the
/// movement's report and leaves a valid mesh.

#include <incise/core/outcome.hpp>
#include <incise/delaunay/incision_track.hpp>
#include <incise/delaunay/triangulation.hpp>

#include <memory>
#include <string>
#include <vector>

namespace incise::delaunay {
namespace detail {
class BoundaryGrid;
}

/// When an interior node next to the active node is "too close" and removed.
enum class ShortEdgeRule {
  kDistance,  ///< §5.2.2/§5.4: closer than ε_edge = edge · h̄
  kAngle,  ///< §5.5 in retrospect, scale-free: an angle opposite the edge a–v is below min_angle
};

/// Options of a Cutter2D; thresholds are fractions of the starting mesh's mean edge length.
struct Cutter2DOptions {
  ShortEdgeRule short_edge = ShortEdgeRule::kDistance;  ///< which rule removes close nodes
  double edge = 1.0 / 3.0;  ///< ε_edge / h̄: interior nodes nearer to the active node are removed
  double min_angle = 0.35;  ///< rad (≈ 20°), kAngle: the smallest admissible angle opposite a–v
  double entry = 1.0 / 6.0;  ///< ε_entry / h̄: snap-to-node distance and fix-up distance at entry
  double exit = 1.0 / 6.0;   ///< ε_exit / h̄: distance of a predicted exit
  double dilation = 1e-3;    ///< δ / h̄: how far new incision nodes are moved off the path
  int max_substeps = 200;    ///< sub-steps of one movement before it is reported as blocked
};

/// Outcome of one scalpel movement.
enum class CutMoveStatus {
  kOk,       ///< the active node reached the scalpel (or the scalpel is outside the mesh)
  kBlocked,  ///< the active node stopped short (sub-step cap, or an edge it cannot cross)
};

/// Name of a CutMoveStatus ("ok", "blocked").
const char* to_string(CutMoveStatus status);

/// What the cutter's state is.
enum class CutPhase {
  kOutside,  ///< not in the mesh
  kDent,     ///< entered, incision not yet fixed up (Fig. 5.6)
  kCutting,  ///< an incision ends at the active node
};

/// Report of one movement (counts of this movement).
struct [[nodiscard]] CutMove2DReport
    : Outcome<CutMoveStatus, CutMoveStatus::kOk, CutMoveStatus::kOk> {
  CutPhase phase = CutPhase::kOutside;  ///< the phase after the movement
  bool entered = false;                 ///< the scalpel entered the mesh
  bool fixed_up = false;                ///< the entry fix-up was made
  bool exited = false;                  ///< the incision reached the boundary (exit)
  int substeps = 0;                     ///< sub-steps of the active node
  long flips = 0;                       ///< edge flips
  int removals = 0;                     ///< interior nodes removed
  int splits = 0;                       ///< incision splits (new node pairs)
  int refused = 0;                      ///< splits or exits that would have inverted a triangle
};

/// Delaunay cutter of a planar triangulation (see file comment).
class Cutter2D {
 public:
  /// Takes the mesh to cut; thresholds from `options` times its mean edge length. Throws
  /// ParameterError for thresholds ≤ 0 or non-finite, min_angle outside (0, π/3), dilation
  /// outside (0, 0.1], max_substeps < 1.
  explicit Cutter2D(Triangulation& mesh, Cutter2DOptions options = {});
  ~Cutter2D();
  Cutter2D(const Cutter2D&) = delete;
  Cutter2D& operator=(const Cutter2D&) = delete;

  /// Moves the scalpel to x (m). The first call only places it. Throws ParameterError for a
  /// non-finite x or a coordinate beyond 1e60 m (the predicates' exact range).
  CutMove2DReport move_to(const Vec2& x);

  /// Current phase.
  CutPhase phase() const { return phase_; }
  /// The active node, −1 outside.
  Index active() const { return active_; }
  /// Mean edge length h̄ of the starting mesh (m).
  double mean_edge() const { return h_; }
  /// The incision nodes of the current and finished incisions, in path order per side.
  const std::vector<std::vector<Index>>& incision_sides() const { return track_.sides; }

 private:
  bool locate_entry(const Vec2& from, const Vec2& to, Index& p, Index& q, double& t) const;
  bool move_keeping_shape(const Vec2& x);
  void move_active(const Vec2& target, CutMove2DReport& r);
  void remove_close_nodes(CutMove2DReport& r);
  void legalize_around(Index v, CutMove2DReport& r);
  void fix_up(CutMove2DReport& r);
  void split_incision(CutMove2DReport& r);
  Index boundary_node_at(Index p, Index q, const Vec2& x, double snap);
  bool exit_at(Index p, Index q, const Vec2& x, CutMove2DReport& r);
  bool boundary_hit(const Vec2& from, const Vec2& to, Index& p, Index& q, double& t) const;
  bool is_incision_node(Index v) const;
  bool too_short(Index v) const;

  Triangulation& mesh_;
  Cutter2DOptions options_;
  std::unique_ptr<detail::BoundaryGrid> grid_;  // boundary edges by cell (watches the mesh)
  double h_ = 0, eps_edge_ = 0, eps_entry_ = 0, eps_exit_ = 0, delta_ = 0;
  CutPhase phase_ = CutPhase::kOutside;
  bool placed_ = false;
  Vec2 scalpel_ = Vec2::Zero();
  Index active_ = -1;
  Vec2 entry_ = Vec2::Zero();
  Index dent_left_ = -1, dent_right_ = -1;  // boundary neighbours of a at entry
  IncisionTrack<Vec2> track_;               // last node pair, path since it, all sides
  std::vector<Edge> forbidden_;
  Vec2 forbidden_near_ = Vec2::Zero();
};

}  // namespace incise::delaunay
