#pragma once
/// \file surface_cutter.hpp
/// Delaunay cutting of a triangle surface in 3D by a line-segment scalpel (thesis §5.3, Figs.
/// 5.9–5.13; the planar scheme of §5.2.2 carried to the surface), with several incisions at once.
///
/// The scalpel is a segment whose ends move at constant velocity between the sampled positions
/// given to move_to; its tail end is the tip. Each movement:
///  0. the live incisions are advanced one after the other (below); then every entering contact
///     of the sweep with a boundary edge (eq. (5.1), sweep.hpp; Fig. 5.12, first case), every
///     crossing of the tip's path with the inside of a triangle (second case) and every contact
///     of the scalpel's side with an exposed interior edge — a ridge it comes down on, meeting
///     neither triangle of the edge before and both after (third case) — starts an incision,
///     earliest first, ties by vertex numbers — unless its edge or triangle is active, the node
///     it snaps to shares a triangle with an active node, or it is within ε_entry of an entry of
///     this movement (restriction 1 of §5.3.2; counted). A
///     boundary edge entry's active node is the edge's end within ε_entry or a new node on it; a
///     tip entry's is a new node inside the triangle; an interior edge entry's is the edge's
///     interior end within ε_entry or a new node splitting the edge. The incision is then
///     advanced over the rest of the movement;
///  1. advancing an incision: the movement is subdivided so that neither scalpel end moves by
///     d_max or more per sub-movement (Fig. 5.11: d_max = the smallest distance from the scalpel
///     to an edge opposite the active node; floored at 10⁻³ h̄, see the .cpp);
///  2. per sub-movement, a sweep that crosses a boundary edge opposite the active node (eq. (5.1))
///     is an exit there; otherwise the scalpel segment is intersected with the active triangles
///     (the star of the active node) and the active node moves to the intersection — in halving
///     steps when a star triangle would fold or flatten (surface.hpp guards); a node held by a
///     star triangle at the 60° crease limit (every step, however small, would sharpen it)
///     slides within that triangle's plane instead (at most 4 slides per movement), with the active
///     triangles legalized by the unfolded criterion and interior nodes closer than ε_edge
///     removed by ear flips (Fig. 5.10) after each step — but not a node next to another active
///     node (restriction 2);
///  3. the incision is split behind the active node as in Fig. 5.5 when the cut edges fail the
///     unfolded empty-circle test (new nodes where the path is closest to the line between the
///     opposite nodes, dilated by δ);
///  4. ε_entry from the entry point: the fix-up of the dent (Fig. 5.6), or for a tip entry an
///     entry node and a constrained edge to the active node, opened into a slit by the first
///     split; exit (Fig. 5.7) when the sweep crosses a boundary edge of the star or the active
///     node comes within ε_exit of one: a node on that edge, the edge to it dissected and
///     contracted; annihilation (Fig. 5.13) when the active node comes within ε_edge of a node
///     next to another active node (not a branch of the same branching): the two incisions join
///     and end; branching (Figs. 5.14, 5.18) when the scalpel meets the active triangles k ≥ 2
///     times (a fold, a pleated star): nodes at the intersections strictly inside distinct
///     triangles not next to another active node (the nearest among them, else no branch), the
///     edges to them dissected one after the other, k incisions — one family, any size, each
///     with its own active node — instead of one, cut over the rest of the movement. An interior
///     edge entry's node branches the same way once the scalpel meets its triangles on both
///     sides of the ridge (the path n1–a–n2 dissected: a slit with two tips, further nodes
///     dissected from it); met on one side only, it goes on as a tip entry.
/// All live active nodes are marked on the Surface, which refuses any change that would put two
/// in one triangle (restriction 3 and "at most one active node per triangle"). A scalpel that no
/// longer meets the active triangles (lifted off the surface, or a jump past the d_max floor)
/// ends the incision where it is (status kLost: the slit stays, the mesh is valid). Not built:
/// a tip or a scalpel side through a node or (tip) an edge exactly. Thresholds
/// are fractions of the starting mesh's mean edge length h̄ (Cutter2DOptions, §5.4 defaults).
/// Entries are found through a uniform 3D grid of cell h̄ over the triangles and boundary edges,
/// kept current by watching the connectivity, so a movement touches only what is near the
/// scalpel and the stars.

#include <incise/core/outcome.hpp>
#include <incise/delaunay/cutter2d.hpp>
#include <incise/delaunay/incision_track.hpp>
#include <incise/delaunay/surface.hpp>
#include <incise/delaunay/sweep.hpp>

#include <functional>
#include <memory>
#include <vector>

namespace incise::delaunay {
namespace detail {
class SurfaceGrid;
}

/// Outcome of one surface scalpel movement.
enum class SurfaceMoveStatus {
  kOk,       ///< the active node reached the scalpel (or the scalpel is outside the surface)
  kBlocked,  ///< the active node stopped short (a fold or flat triangle ahead, sub-step cap)
  kLost,     ///< the scalpel left the active triangles other than by an exit: incision ended
};

/// Name of a SurfaceMoveStatus ("ok", "blocked", "lost").
const char* to_string(SurfaceMoveStatus status);

/// Report of one surface movement (counts of this movement).
struct [[nodiscard]] SurfaceMoveReport
    : Outcome<SurfaceMoveStatus, SurfaceMoveStatus::kOk, SurfaceMoveStatus::kOk> {
  CutPhase phase = CutPhase::kOutside;  ///< the phase after the movement
  bool entered = false;                 ///< the scalpel entered the surface (at an edge)
  bool tip_entered = false;             ///< the scalpel's tip pierced a triangle (Fig. 5.12)
  /// The scalpel's side hit an exposed interior edge (a ridge; Fig. 5.12, third case).
  bool edge_entered = false;
  bool fixed_up = false;     ///< the entry fix-up was made
  bool exited = false;       ///< the incision reached the boundary (exit)
  bool annihilated = false;  ///< two incisions met and ended (Fig. 5.13)
  bool branched = false;     ///< an incision branched (Figs. 5.14, 5.18)
  /// The most incisions one branching of this movement made (2 in Fig. 5.14, 3 in Fig. 5.18;
  /// 1 when only the nearest branch could be made; 0 without branching).
  int branch_ways = 0;
  int submovements = 0;           ///< d_max sub-movements (Fig. 5.11)
  int substeps = 0;               ///< moves of the active node
  long flips = 0;                 ///< edge flips
  long topological_refusals = 0;  ///< flips refused as in Fig. 5.9
  int removals = 0;               ///< interior nodes removed
  int splits = 0;                 ///< incision splits (new node pairs)
  int refused = 0;                ///< splits, fix-ups or exits the guards refused
  /// Scalpel–star intersections beyond the first, summed over the sub-movements (not followed,
  /// except those a branching makes branches at).
  int extra_intersections = 0;
  int incisions = 0;    ///< live incisions after the movement
  long restricted = 0;  ///< changes refused: a triangle would get two active nodes (§5.3.2)
  /// Contacts with boundary edges not taken as entries (restriction 1 of §5.3.2: the edge or its
  /// triangle is active — mostly the scalpel at its own incision —, the node it would snap to
  /// shares a triangle with an active node, or it is within ε_entry of an entry of this movement).
  int rejected_entries = 0;
};

/// Delaunay cutter of a triangle surface (see file comment).
class SurfaceCutter {
 public:
  /// Takes the surface to cut; thresholds from `options` (the fields edge, entry, exit,
  /// dilation, max_substeps) times its mean edge length. With short_edge = kAngle (§5.5's
  /// scale-free rule, as in Cutter2D) an interior node v next to the active node a is "too
  /// close" — removed (Fig. 5.10) or, next to another active node, the node of an annihilation
  /// (Fig. 5.13) — when an angle opposite the edge a–v in one of its triangles (in 3D) is below
  /// min_angle, instead of when |a − v| < ε_edge. Throws ParameterError for thresholds ≤ 0 or
  /// non-finite, dilation outside (0, 0.1], max_substeps < 1, or min_angle outside (0, π/3).
  explicit SurfaceCutter(Surface& surface, Cutter2DOptions options = {});
  ~SurfaceCutter();
  SurfaceCutter(const SurfaceCutter&) = delete;
  SurfaceCutter& operator=(const SurfaceCutter&) = delete;

  /// Moves the scalpel to s (m). The first call only places it. Throws ParameterError for a
  /// non-finite position or a zero-length scalpel.
  SurfaceMoveReport move_to(const ScalpelSegment& s);

  /// The most advanced phase over the live incisions (kCutting before kDent before kOutside).
  CutPhase phase() const;
  /// The active node of the oldest live incision, −1 when there is none.
  Index active() const;
  /// The active nodes of the live incisions, oldest first.
  std::vector<Index> active_nodes() const;
  /// Mean edge length h̄ of the starting surface (m).
  double mean_edge() const { return h_; }
  /// The incision nodes of the finished and the live incisions, two lists (sides) per incision
  /// in path order.
  std::vector<std::vector<Index>> incision_sides() const;

 private:
  /// One incision: its active node, phase, entry point and node track.
  struct Incision {
    Index active = -1;
    CutPhase phase = CutPhase::kOutside;
    Vec3 entry = Vec3::Zero();
    IncisionTrack<Vec3> track;
    bool tip = false;   ///< entered with the tip through a triangle (Fig. 5.12, second case)
    bool edge = false;  ///< entered through an exposed interior edge (Fig. 5.12, third case)
    double tau = 0;     ///< a branch: the time of its movement from which it is cut
    int family = -1;    ///< the branches of one branching share a number (−1: not a branch)
  };
  /// An entering contact of the sweep with the boundary edge {p, q}.
  struct EntryHit {
    Index p = -1, q = -1;
    SweepHit hit;
  };
  std::vector<EntryHit> find_entries(const ScalpelSegment& from, const ScalpelSegment& to) const;
  std::vector<EntryHit> find_edge_entries(const ScalpelSegment& from,
                                          const ScalpelSegment& to) const;
  /// A crossing of the tip's path with a triangle: time and point.
  struct TipHit {
    double time = 0;
    mesh::ElementHandle triangle;
    Vec3 point = Vec3::Zero();
  };
  std::vector<TipHit> find_tip_entries(const ScalpelSegment& from, const ScalpelSegment& to) const;
  void start(Index a, bool tip, bool edge, double tau, const ScalpelSegment& from,
             const ScalpelSegment& to, SurfaceMoveReport& r);
  void tip_fix_up(SurfaceMoveReport& r);
  void advance(const ScalpelSegment& from, const ScalpelSegment& to, double tau,
               SurfaceMoveReport& r);
  void load(const Incision& i);
  Incision store();
  static void merge(SurfaceMoveReport& r, const SurfaceMoveReport& sub);
  bool is_active(Index v) const;
  bool is_sibling(Index v) const;
  std::vector<Vec3> star_intersections(const ScalpelSegment& s) const;
  bool sweep_exit(const ScalpelSegment& from, const ScalpelSegment& to, Index& p, Index& q,
                  Vec3& x) const;
  bool near_exit(double radius, Index& p, Index& q, Vec3& x) const;
  bool pick_exit_edge(const std::function<double(const Vec3&, const Vec3&, Vec3&)>& key,
                      double limit, Index& p, Index& q, Vec3& x) const;
  double d_max(const ScalpelSegment& s) const;
  void move_active(const Vec3& target, SurfaceMoveReport& r);
  void remove_close_nodes(SurfaceMoveReport& r);
  bool too_short(Index v) const;  ///< the edge active–v is short (ε_edge or the §5.5 angle)
  void fix_up(SurfaceMoveReport& r);
  void split_incision(SurfaceMoveReport& r);
  bool exit_at(Index p, Index q, const Vec3& x, SurfaceMoveReport& r);
  bool annihilate(SurfaceMoveReport& r);
  bool branch(const std::vector<Vec3>& hits, SurfaceMoveReport& r);
  bool edge_branch(const std::vector<Vec3>& hits, SurfaceMoveReport& r);
  /// A branch point: a scalpel intersection strictly inside an active triangle.
  struct BranchPoint {
    mesh::ElementHandle triangle;
    Vec3 point = Vec3::Zero();
  };
  std::vector<BranchPoint> branch_points(const std::vector<Vec3>& hits) const;
  std::vector<Index> branch_nodes(const std::vector<BranchPoint>& at, SurfaceMoveReport& r);
  void dissect_branches(const std::vector<Index>& nodes, std::vector<Index>& holders,
                        std::vector<Index>& tips, SurfaceMoveReport& r);
  void spawn(const std::vector<Index>& tips, SurfaceMoveReport& r);
  bool is_forbidden(Index p, Index q) const;
  void end_incision();

  Surface& mesh_;
  Cutter2DOptions options_;
  std::unique_ptr<detail::SurfaceGrid> grid_;  // triangles and boundary edges by cell
  double h_ = 0, eps_edge_ = 0, eps_entry_ = 0, eps_exit_ = 0, delta_ = 0;
  CutPhase phase_ = CutPhase::kOutside;
  bool placed_ = false;
  ScalpelSegment scalpel_;
  Index active_ = -1;
  Index loaded_ = -1;  // the working incision's active node when it was loaded
  Vec3 entry_ = Vec3::Zero();
  IncisionTrack<Vec3> track_;  // the working incision's node pair, path and sides
  bool tip_ = false;           // the working incision entered with the tip
  bool edge_ = false;          // the working incision entered through an interior edge
  int family_ = -1;            // the working incision's branch family
  int next_family_ = 0;
  double branch_tau_ = 0;  // the current sub-movement's end (a branch made there is cut from it)
  std::vector<Incision> incisions_, finished_;  // live (oldest first) and ended incisions
  std::vector<Incision> spawned_;               // branches of this movement (from the next on)
  struct ForbiddenZone {  // the boundary edges at an exit, closed for entry near it
    std::vector<Edge> edges;
    Vec3 near = Vec3::Zero();
  };
  std::vector<ForbiddenZone> forbidden_;
};

}  // namespace incise::delaunay
