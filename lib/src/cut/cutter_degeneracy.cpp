/// \file cutter_degeneracy.cpp
/// Degeneracy removal (thesis §3.2.3): elements with aspect ratio below the threshold (or
/// inverted) are collected, every one is given to its collapse recipe (cutter_recipes.cpp), and
/// passes repeat while the list shrinks; what remains is incollapsible and is cut free and
/// removed, as the thesis did.

#include <incise/mesh/quality.hpp>

#include "cutter_internal.hpp"

#include <algorithm>

namespace incise::cut {

bool Cutter::is_degenerate(Index e) const {
  const Tet& t = mesh_.element(e);
  const Vec3 &a = mesh_.reference(t[0]), &b = mesh_.reference(t[1]), &c = mesh_.reference(t[2]),
             &d = mesh_.reference(t[3]);
  // The thesis' aspect ratio (mesh/quality.hpp) is unsigned; an inverted element counts as
  // degenerate whatever its shape.
  return mesh::signed_volume(a, b, c, d) < 0 ||
         mesh::aspect_ratio(a, b, c, d) < options_.degenerate_aspect_ratio;
}

Index Cutter::count_degenerate() const {
  Index c = 0;
  for (Index e = 0; e < mesh_.element_capacity(); ++e) {
    if (mesh_.alive(e) && is_degenerate(e)) ++c;
  }
  return c;
}

void Cutter::cut_free(Index e, CutStepReport& r) {
  std::vector<std::pair<Index, int>> faces;
  std::vector<Index> around;
  for (int j = 0; j < 4; ++j) {
    const Index nb = mesh_.neighbor(e, j);
    if (nb >= 0) {
      faces.emplace_back(e, j);
      around.push_back(nb);
    }
  }
  // Removing e may disconnect its neighbours from each other: check them afterwards.
  for (size_t k = 1; k < around.size(); ++k) separated_pairs_.emplace_back(around[0], around[k]);
  if (!around.empty()) replaced_[e] = around[0];
  if (!faces.empty()) {
    std::vector<Index> changed;
    (void)mesh_.dissect(faces, changed, r.new_nodes);
    for (Index c : changed) r.changed_elements.push_back(c);
  }
  const Tet t = mesh_.element(e);
  (void)mesh_.replace({e}, {});
  r.changed_elements.push_back(e);
  for (Index v : t) {
    if (mesh_.unused(v)) r.removed_nodes.push_back(v);
  }
}

void Cutter::remove_degeneracies(std::vector<Index> region, CutStepReport& r) {
  auto degenerate_in = [&](const std::vector<Index>& reg) {
    std::vector<Index> out;
    for (Index e : reg) {
      if (e < mesh_.element_capacity() && mesh_.alive(e) && is_degenerate(e)) out.push_back(e);
    }
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  };
  auto grow = [&](std::vector<Index>& reg) {
    std::vector<Index> nodes;
    for (Index e : reg)
      if (e < mesh_.element_capacity() && mesh_.alive(e))
        for (Index v : mesh_.element(e)) nodes.push_back(v);
    for (Index e : r.changed_elements)
      if (mesh_.alive(e))
        for (Index v : mesh_.element(e)) nodes.push_back(v);
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    reg.clear();
    for (Index v : nodes)
      for (Index e : mesh_.star(v)) reg.push_back(e);
    std::sort(reg.begin(), reg.end());
    reg.erase(std::unique(reg.begin(), reg.end()), reg.end());
  };
  std::vector<Index> list = degenerate_in(region);
  r.degenerate_found += static_cast<Index>(list.size());
  for (int pass = 0; pass < options_.max_degeneracy_passes && !list.empty(); ++pass) {
    ++r.removal_passes;
    for (Index e : list) {
      if (mesh_.alive(e) && is_degenerate(e)) (void)try_recipe(e, r);
    }
    grow(region);
    std::vector<Index> next = degenerate_in(region);
    const bool shorter = next.size() < list.size();
    list = std::move(next);
    if (!shorter) break;
  }
  for (Index e : list) {
    if (mesh_.alive(e) && is_degenerate(e)) {
      cut_free(e, r);
      ++r.incollapsible;
    }
  }
}

void Cutter::remove_degeneracies_everywhere(CutStepReport& report) {
  std::vector<Index> all;
  for (Index e = 0; e < mesh_.element_capacity(); ++e) {
    if (mesh_.alive(e)) all.push_back(e);
  }
  remove_degeneracies(std::move(all), report);
  grid_after_edit(report);
}

}  // namespace incise::cut
