#pragma once
/// \file cutter.hpp
/// Cutting a tetrahedral mesh along its faces from a scalpel sweep (thesis §3.2): one sweep
/// triangle at a time, face selection (§3.2.1), node snapping (§3.2.2), dissection by node
/// substitution (§7.3) and degeneracy removal (§3.2.3), followed by a component check.

#include <incise/core/outcome.hpp>
#include <incise/cut/cut_mesh.hpp>

#include <cstdint>
#include <memory>
#include <random>
#include <unordered_map>
#include <unordered_set>
#include <vector>

namespace incise::cut {

/// What to do with a connected component that is not anchored after a cut (§3.3: the thesis
/// looks for components without fixed nodes; we also count components whose fixed nodes are
/// all collinear — one or two nodes, or a line — since a rigid rotation is then still free
/// and the stiffness matrix singular).
enum class FreeComponentPolicy {
  kFixOnFace,  ///< fix the nodes of one boundary face of it (the thesis' choice)
  kReport      ///< leave it free, report it
};

/// Options of the cutter. Defaults are the thesis' values (§3.3).
struct CutOptions {
  bool snap_nodes = true;  ///< §3.2.2 node snapping
  /// After snapping, move the marks of the edges at each snapped node to it and re-evaluate
  /// (docs/cutting.md, "lag"); false = the thesis' order (select, then snap) only.
  bool remark_snapped_nodes = true;
  bool refuse_inverting_snaps = true;     ///< refuse a snap that inverts an element (§3.4)
  bool remove_degeneracies = true;        ///< §3.2.3
  double degenerate_aspect_ratio = 0.01;  ///< aspect ratio below which an element is flat
  double large_dihedral_angle = 0.99 * 3.14159265358979323846;  ///< "large" angle (rad)
  int max_degeneracy_passes = 20;  ///< bound on removal passes (thesis: while list shrinks)
  bool check_components = true;    ///< search components without fixed nodes after a cut
  FreeComponentPolicy free_components = FreeComponentPolicy::kFixOnFace;
  /// How far (a fraction of the search grid's cell size) a node may move from the position its
  /// elements were entered into the boundary search grid at before they are entered again
  /// (§3.2.1 entry search; issue 17: the grid is updated, not rebuilt). Queries are widened by
  /// the drift, so any value ≥ 0 finds the same elements; 0 re-enters every element whose node
  /// moved at all (the grid of the current positions), larger values re-enter fewer elements
  /// per solve and widen the queries more.
  double search_grid_slack = 0.25;
  std::uint64_t seed = 20031107;  ///< seeds the all-edges-halved face choice (§3.3)
};

/// Outcome class of one sweep-triangle step.
enum class CutStatus {
  kOk,              ///< processed (possibly with nothing selected)
  kDegenerateSweep  ///< the sweep triangle has (near) zero area; nothing was done
};

/// Name of a CutStatus ("ok", "degenerate_sweep").
const char* to_string(CutStatus status);

/// Report of one step (one sweep triangle), for the caller and for warm-starting solvers.
/// status kDegenerateSweep: nothing was done.
struct [[nodiscard]] CutStepReport : Outcome<CutStatus, CutStatus::kOk, CutStatus::kOk> {
  Index elements_tested = 0;    ///< elements visited by the outward search
  Index edges_intersected = 0;  ///< new sweep/edge intersections recorded
  Index faces_selected = 0;     ///< faces chosen by §3.2.1 this step
  Index faces_dissected = 0;    ///< faces that ended on the boundary this step (new or pending)
  Index faces_pending = 0;      ///< selected faces still joined (Fig. 7.7), retried in later steps
  Index halved_choices = 0;     ///< tetrahedra with four marked nodes (seeded choice)
  Index incomplete_elements = 0;  ///< remembered incomplete tetrahedra after the step
  Index nodes_snapped = 0;        ///< nodes moved onto the sweep (§3.2.2)
  Index snaps_refused = 0;        ///< snaps refused because an element would invert
  Index snaps_failed = 0;         ///< snaps_no_projection + snaps_outside_star
  Index snaps_no_projection = 0;  ///< boundary node: no incident boundary face admits one
  Index snaps_outside_star = 0;   ///< the projection lies in no element incident with the node
  Index nodes_on_sweep = 0;       ///< nodes already on the sweep plane, left in place
  Index snaps_fixed = 0;          ///< nodes of selected faces left in place because fixed
  Index degenerate_found = 0;     ///< flat elements found in the first removal pass
  Index collapses = 0;            ///< edge collapses performed (§3.2.3)
  Index incollapsible = 0;        ///< degenerate elements cut free and removed
  Index removal_passes = 0;       ///< removal passes made
  Index free_components = 0;      ///< components found without three non-collinear fixed nodes
  Index components_fixed = 0;     ///< of those, fixed on a face (policy kFixOnFace)
  /// True when the O(n) component search ran (the two sides of a separated face, or the
  /// neighbours of a cut-free element, did not meet in the local search); otherwise the
  /// local search proved that nothing was split.
  bool full_component_check = false;
  std::vector<Index> new_nodes;         ///< nodes created (copies and split nodes)
  std::vector<Index> moved_nodes;       ///< existing nodes whose positions changed
  std::vector<Index> changed_elements;  ///< element handles changed, added or removed
  std::vector<Index> removed_nodes;     ///< nodes that became unused (collapses, cut-free)
  std::vector<Index> fixed_nodes;       ///< nodes newly fixed by FreeComponentPolicy::kFixOnFace
};

/// Totals over several steps (sums of the counts of CutStepReport; faces_pending is the
/// value after the last step).
struct CutTotals {
  /// Sums of the CutStepReport fields of the same names (new_nodes: list sizes).
  Index faces_selected = 0, faces_dissected = 0, nodes_snapped = 0, snaps_refused = 0,
        snaps_failed = 0, snaps_outside_star = 0, faces_pending = 0, degenerate_found = 0,
        collapses = 0, incollapsible = 0, new_nodes = 0, free_components = 0;
  /// Adds the counts of one step.
  void add(const CutStepReport& r);
};

/// Processes a scalpel sweep, one triangle at a time, on a CutMesh it does not own.
/// State kept between steps of one incision (§3.2.1): the first intersection of every
/// mesh edge (keyed by the original nodes, so it survives dissection copies) and the
/// incomplete tetrahedra. Call `end_incision()` to forget it.
class Cutter {
 public:
  /// Cuts `mesh` (not owned; must outlive the cutter). Throws ParameterError for options out
  /// of range (aspect ratio threshold outside [0,1), large angle outside (0,π)).
  Cutter(CutMesh& mesh, CutOptions options = {});
  ~Cutter();  ///< Out of line: Grid is an incomplete type here.
  Cutter(const Cutter&) = delete;
  Cutter& operator=(const Cutter&) = delete;

  /// Processes sweep triangle (a, b, c), given in the deformed configuration (m).
  /// Post: the mesh satisfies CutMesh::validate() (given it did before).
  CutStepReport step(const Vec3& a, const Vec3& b, const Vec3& c);

  /// Forgets remembered intersections and incomplete tetrahedra (a new incision begins).
  void end_incision();

  /// Runs degeneracy removal over the whole mesh (used when snapping and removal are
  /// separated, e.g. the §3.3 comparison); counts go into `report`.
  void remove_degeneracies_everywhere(CutStepReport& report);

  /// Counts live elements with aspect ratio below the option's threshold (O(n)).
  Index count_degenerate() const;

  /// The options in use.
  const CutOptions& options() const { return options_; }
  /// How many times the boundary search grid (deformed bounding boxes, §3.2.1 entry search)
  /// was built from the whole mesh: once, at the first step. Afterwards it is updated: the
  /// elements changed by a cut, and those around nodes that moved more than
  /// CutOptions::search_grid_slack cells since their elements were entered, are entered again.
  std::int64_t grid_builds() const { return grid_builds_; }
  /// Element entries made by those updates (changed elements and moved nodes' stars) so far.
  std::int64_t grid_reentries() const { return grid_reentries_; }

 private:
  struct Grid;
  using EdgeKey = std::uint64_t;

  void collect_seeds(const Vec3 (&tri)[3], std::vector<Index>& seeds);
  void grid_insert(Index e);
  void grid_sync_nodes();
  void grid_after_edit(const CutStepReport& r);
  void select_faces(const Vec3 (&tri)[3], CutStepReport& r,
                    std::vector<std::pair<Index, int>>& faces);
  void evaluate(std::vector<Index> candidates, CutStepReport& r,
                std::vector<std::pair<Index, int>>& faces);
  void remark_snapped(const std::vector<Index>& snapped, std::vector<Index>& affected);
  void snap(const Vec3 (&tri)[3], const std::vector<std::pair<Index, int>>& faces,
            CutStepReport& r);
  bool snap_node(Index v, const Vec3& origin, const Vec3& normal, double scale, CutStepReport& r);
  void remove_degeneracies(std::vector<Index> region, CutStepReport& r);
  bool try_recipe(Index e, CutStepReport& r);
  bool apply_local_op(const std::vector<Index>& old_elements, const std::vector<Tet>& new_tets,
                      CutStepReport& r);
  void cut_free(Index e, CutStepReport& r);
  void check_components(CutStepReport& r);
  bool local_component_check(const std::vector<std::pair<Index, Index>>& sides, CutStepReport& r);
  bool is_degenerate(Index e) const;
  EdgeKey edge_key(Index a, Index b) const;

  CutMesh& mesh_;
  CutOptions options_;
  std::mt19937_64 rng_;
  std::unique_ptr<Grid> grid_;
  std::uint64_t grid_version_ = ~std::uint64_t{0};  // CutMesh::positions_version() synced
  std::int64_t grid_builds_ = 0, grid_reentries_ = 0;
  /// First intersection of each edge (keyed by original nodes) → original of marked node.
  std::unordered_map<EdgeKey, Index> marked_;
  std::unordered_set<Index> incomplete_;
  /// Selected faces not yet separated by dissection (their vertices' stars were not split,
  /// Fig. 7.7); the cut surface C accumulates, so they are dissected again with later faces.
  std::vector<mesh::FaceHandle> pending_;
  /// Element pairs that were adjacent before this step's separations (component check).
  std::vector<std::pair<Index, Index>> separated_pairs_;
  /// Removed element → an element now occupying its place (this step only).
  std::unordered_map<Index, Index> replaced_;
  std::vector<char> done_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t stamp_value_ = 0;
};

}  // namespace incise::cut
