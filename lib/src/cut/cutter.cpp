/// \file cutter.cpp
/// Cutter, the driver of the thesis' §3.2 pipeline ("Cuts"): one sweep triangle Δⱼ per step —
/// face selection (§3.2.1, cutter_select.cpp), node snapping (§3.2.2, cutter_snap.cpp),
/// dissection by node substitution (§7.3, CutMesh::dissect), degeneracy removal (§3.2.3,
/// cutter_degeneracy.cpp and cutter_recipes.cpp) and the component check after every cut
/// (§3.3, cutter_components.cpp).

#include <incise/core/error.hpp>

#include "cutter_internal.hpp"

#include <algorithm>
#include <cmath>

namespace incise::cut {

const char* to_string(CutStatus status) {
  switch (status) {
    case CutStatus::kOk: return "ok";
    case CutStatus::kDegenerateSweep: return "degenerate_sweep";
  }
  return "unknown";
}

namespace {

/// Sweep triangles with area below this fraction of the squared longest side are degenerate.
constexpr double kSweepAreaRelEps = 1e-12;

}  // namespace

void CutTotals::add(const CutStepReport& r) {
  faces_selected += r.faces_selected;
  faces_dissected += r.faces_dissected;
  nodes_snapped += r.nodes_snapped;
  snaps_refused += r.snaps_refused;
  snaps_failed += r.snaps_failed;
  snaps_outside_star += r.snaps_outside_star;
  faces_pending = r.faces_pending;
  degenerate_found += r.degenerate_found;
  collapses += r.collapses;
  incollapsible += r.incollapsible;
  new_nodes += static_cast<Index>(r.new_nodes.size());
  free_components += r.free_components;
}

Cutter::Cutter(CutMesh& mesh, CutOptions options)
    : mesh_(mesh), options_(options), rng_(options.seed), grid_(std::make_unique<Grid>()) {
  INCISE_CHECK_PARAM(options_.degenerate_aspect_ratio >= 0 && options_.degenerate_aspect_ratio < 1,
                     "degenerate_aspect_ratio must lie in [0,1)");
  INCISE_CHECK_PARAM(options_.large_dihedral_angle > 0 && options_.large_dihedral_angle < 3.15,
                     "large_dihedral_angle must lie in (0, π)");
  INCISE_CHECK_PARAM(options_.search_grid_slack >= 0 && std::isfinite(options_.search_grid_slack),
                     "search_grid_slack must be finite and >= 0");
}

Cutter::~Cutter() = default;

void Cutter::end_incision() {
  marked_.clear();
  incomplete_.clear();
  pending_.clear();
}

Cutter::EdgeKey Cutter::edge_key(Index a, Index b) const {
  std::uint64_t oa = static_cast<std::uint32_t>(mesh_.origin(a));
  std::uint64_t ob = static_cast<std::uint32_t>(mesh_.origin(b));
  if (oa > ob) std::swap(oa, ob);
  return (oa << 32) | ob;
}

void Cutter::grid_after_edit(const CutStepReport& r) {
  // Keep the search grid current around the edit: changed elements, and the stars of moved
  // and new nodes, anchored at their positions now (the invariant of Grid).
  if (grid_version_ == ~std::uint64_t{0}) return;  // not built yet: the build sees the edit
  if (grid_version_ != mesh_.positions_version()) grid_sync_nodes();  // (outside a step)
  std::vector<Index> regrid = r.changed_elements;
  grid_->anchor.resize(static_cast<size_t>(mesh_.num_nodes()));
  for (const auto* list : {&r.moved_nodes, &r.new_nodes})
    for (Index v : *list) {
      grid_->anchor[static_cast<size_t>(v)] = mesh_.deformed(v);
      for (Index e : mesh_.star(v)) regrid.push_back(e);
    }
  std::sort(regrid.begin(), regrid.end());
  regrid.erase(std::unique(regrid.begin(), regrid.end()), regrid.end());
  for (Index e : regrid) grid_insert(e);
  grid_reentries_ += static_cast<std::int64_t>(regrid.size());
}

CutStepReport Cutter::step(const Vec3& a, const Vec3& b, const Vec3& c) {
  CutStepReport r;
  INCISE_CHECK_PARAM(a.allFinite() && b.allFinite() && c.allFinite(),
                     "sweep triangle has non-finite coordinates");
  const Vec3 tri[3] = {a, b, c};
  const double longest =
      std::max({(b - a).squaredNorm(), (c - b).squaredNorm(), (a - c).squaredNorm()});
  if (!((b - a).cross(c - a).norm() > kSweepAreaRelEps * longest) || !(longest > 0)) {
    r.status = CutStatus::kDegenerateSweep;
    return r;
  }
  std::vector<std::pair<Index, int>> faces;
  select_faces(tri, r, faces);
  if (!faces.empty()) {
    if (options_.snap_nodes) {
      snap(tri, faces, r);
      // The sweep now passes through every snapped node: move the marks of the incident
      // edges there and select the faces this completes (see docs/cutting.md, "lag").
      std::vector<Index> affected;
      if (options_.remark_snapped_nodes) remark_snapped(r.moved_nodes, affected);
      const size_t before = faces.size();
      evaluate(affected, r, faces);
      if (faces.size() > before) {
        const std::vector<std::pair<Index, int>> extra(faces.begin() + static_cast<long>(before),
                                                       faces.end());
        snap(tri, extra, r);
      }
    }
    r.faces_selected = static_cast<Index>(faces.size());
    std::vector<Index> changed;
    std::vector<mesh::FaceHandle> cut = pending_;
    for (const auto& [e, j] : faces) cut.push_back(mesh_.face_handle(e, j));
    std::vector<std::pair<Index, Index>>& sides = separated_pairs_;
    sides.clear();  // element pairs across the cut faces (+ neighbours of cut-free elements)
    replaced_.clear();
    {
      const auto& conn = mesh_.connectivity();
      for (const auto& f : cut) {
        if (conn.is_alive(f) && conn.mate(f).valid())
          sides.emplace_back(conn.element(f).index, conn.element(conn.mate(f)).index);
      }
    }
    r.faces_dissected = mesh_.dissect(cut, changed, r.new_nodes);
    pending_.clear();
    for (const auto& f : cut) {
      const auto& conn = mesh_.connectivity();
      if (conn.is_alive(f) && conn.mate(f).valid()) pending_.push_back(f);
    }
    r.changed_elements.insert(r.changed_elements.end(), changed.begin(), changed.end());
    if (options_.remove_degeneracies) {
      std::vector<Index> region;
      std::vector<Index> nodes = r.moved_nodes;
      nodes.insert(nodes.end(), r.new_nodes.begin(), r.new_nodes.end());
      for (const auto& [e, j] : faces)
        for (Index v : mesh_.element(e)) nodes.push_back(v);
      for (Index v : nodes)
        for (Index e : mesh_.star(v)) region.push_back(e);
      std::sort(region.begin(), region.end());
      region.erase(std::unique(region.begin(), region.end()), region.end());
      remove_degeneracies(std::move(region), r);
    }
    if (options_.check_components && (r.faces_dissected > 0 || r.incollapsible > 0)) {
      // Only a separated face pair or a cut-free element can disconnect the mesh; if both
      // sides of every separated pair (the neighbours of every removed element) still reach
      // each other, the components are unchanged.
      if (!local_component_check(sides, r)) {
        r.full_component_check = true;
        check_components(r);
      }
    }
  }
  grid_after_edit(r);
  std::sort(r.changed_elements.begin(), r.changed_elements.end());
  r.changed_elements.erase(std::unique(r.changed_elements.begin(), r.changed_elements.end()),
                           r.changed_elements.end());
  std::sort(r.removed_nodes.begin(), r.removed_nodes.end());
  r.removed_nodes.erase(std::unique(r.removed_nodes.begin(), r.removed_nodes.end()),
                        r.removed_nodes.end());
  r.incomplete_elements = static_cast<Index>(incomplete_.size());
  r.faces_pending = static_cast<Index>(pending_.size());
  return r;
}

}  // namespace incise::cut
