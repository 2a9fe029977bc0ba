/// \file cutter_components.cpp
/// The component check after every cut (thesis §3.3: "the mesh is checked for its connectivity
/// after every cut, and all unfixed components are fixed on an arbitrary face"): a local search
/// from the two sides of every separated face, falling back to the O(n) search; components
/// without three non-collinear fixed nodes are fixed on a face or reported (FreeComponentPolicy).

#include "cutter_internal.hpp"

#include <algorithm>
#include <deque>
#include <unordered_map>

namespace incise::cut {

namespace {

/// Whether the fixed nodes seen so far hold a component rigidly: three non-collinear ones
/// (fewer leave a rigid-body rotation free, and the stiffness matrix singular).
class Anchor {
 public:
  void add(const Vec3& p) {
    if (count_ == 0) {
      p0_ = p;
      count_ = 1;
    } else if (count_ == 1 && (p - p0_).norm() > 0) {
      p1_ = p;
      count_ = 2;
    } else if (count_ == 2) {
      const Vec3 a = p1_ - p0_, b = p - p0_;
      // Relative collinearity threshold far above round-off of the cross product.
      if (a.cross(b).norm() > 1e-9 * a.norm() * b.norm()) count_ = 3;
    }
  }
  bool any() const { return count_ > 0; }
  bool anchored() const { return count_ == 3; }

 private:
  Vec3 p0_ = Vec3::Zero(), p1_ = Vec3::Zero();
  int count_ = 0;
};

}  // namespace

bool Cutter::local_component_check(const std::vector<std::pair<Index, Index>>& sides,
                                   CutStepReport& r) {
  // Seeds: the elements on both sides of every face separated in this step (and the
  // neighbours of removed elements). Each seed starts a breadth-first group; the open groups
  // are expanded one element each in turn, and groups that touch are merged. Expansion stops
  // when at most one open group is left. A group whose frontier empties is a whole component
  // S: without fixed nodes it is a new free component (the fixed nodes of the old component
  // all lie elsewhere); with fixed nodes the rest may have lost them (or S holds fewer than
  // three non-collinear ones), so the caller falls back to the O(n) search (return false). Groups
  // near one cut front merge after exploring a neighbourhood of the front, so the usual cost does
  // not depend on the mesh size.
  struct Group {
    std::deque<Index> frontier;
    std::vector<Index> members;
    bool closed = false;
  };
  std::vector<Group> groups;
  std::vector<int> parent;
  std::unordered_map<Index, int> owner;
  auto find = [&parent](int g) {
    while (parent[static_cast<size_t>(g)] != g) g = parent[static_cast<size_t>(g)];
    return g;
  };
  // The live element standing in for a seed: itself, or the stand-in recorded when it was
  // removed (replaced_, followed over a bounded chain). kGone: removed with no stand-in, which
  // happens only when nothing it touched survived (cut_free of an element without neighbours,
  // a local operation that removed a whole isolated cluster), so it separates nothing and is
  // skipped (before issue 17 it sent every such step to the O(n) search: 5 of 30 frames of the
  // refined liver path, ≈ 100 ms each). kUnknown (chain too long) still falls back.
  constexpr Index kGone = -1, kUnknown = -2;
  auto resolve = [this](Index e) {
    for (int hops = 0; hops < 64 && !mesh_.alive(e); ++hops) {
      auto it = replaced_.find(e);
      if (it == replaced_.end()) return kGone;
      e = it->second;
    }
    return mesh_.alive(e) ? e : kUnknown;
  };
  for (const auto& pair : sides) {
    for (Index raw : {pair.first, pair.second}) {
      const Index e = resolve(raw);
      if (e == kGone) continue;
      if (e < 0) return false;
      if (owner.count(e)) continue;
      owner.emplace(e, static_cast<int>(groups.size()));
      parent.push_back(static_cast<int>(groups.size()));
      groups.emplace_back();
      groups.back().frontier.push_back(e);
      groups.back().members.push_back(e);
    }
  }
  std::vector<std::vector<Index>> free_parts;
  auto open_roots = [&]() {
    std::vector<int> roots;
    for (int g = 0; g < static_cast<int>(groups.size()); ++g) {
      if (find(g) == g && !groups[static_cast<size_t>(g)].closed) roots.push_back(g);
    }
    return roots;
  };
  for (std::vector<int> roots = open_roots(); roots.size() > 1; roots = open_roots()) {
    for (int g0 : roots) {
      const int g = find(g0);
      Group& grp = groups[static_cast<size_t>(g)];
      if (g != g0 || grp.closed) continue;
      if (grp.frontier.empty()) {
        Anchor anchor;
        for (Index e : grp.members)
          for (Index v : mesh_.element(e))
            if (mesh_.fixed(v)) anchor.add(mesh_.reference(v));
        // Fixed nodes in S: the rest may have lost its anchor, or S may be anchored by fewer
        // than three non-collinear nodes; the O(n) search decides both.
        if (anchor.any()) return false;
        grp.closed = true;
        free_parts.push_back(grp.members);
        continue;
      }
      const Index e = grp.frontier.front();
      grp.frontier.pop_front();
      for (int j = 0; j < 4; ++j) {
        const Index nb = mesh_.neighbor(e, j);
        if (nb < 0) continue;
        auto it = owner.find(nb);
        if (it == owner.end()) {
          owner.emplace(nb, g);
          Group& mine = groups[static_cast<size_t>(find(g))];
          mine.members.push_back(nb);
          mine.frontier.push_back(nb);
          continue;
        }
        const int h = find(it->second), mine_root = find(g);
        if (h == mine_root) continue;
        if (groups[static_cast<size_t>(h)].closed) return false;  // impossible when valid
        // Merge the smaller group into the larger.
        int big = h, small = mine_root;
        if (groups[static_cast<size_t>(big)].members.size() <
            groups[static_cast<size_t>(small)].members.size())
          std::swap(big, small);
        Group& B = groups[static_cast<size_t>(big)];
        Group& S = groups[static_cast<size_t>(small)];
        B.members.insert(B.members.end(), S.members.begin(), S.members.end());
        B.frontier.insert(B.frontier.end(), S.frontier.begin(), S.frontier.end());
        S.members.clear();
        S.frontier.clear();
        parent[static_cast<size_t>(small)] = big;
      }
    }
  }
  for (auto& part : free_parts) {
    ++r.free_components;
    if (options_.free_components != FreeComponentPolicy::kFixOnFace) continue;
    std::sort(part.begin(), part.end());
    for (Index e : part) {
      int j = 0;
      while (j < 4 && mesh_.neighbor(e, j) >= 0) ++j;
      if (j == 4) continue;
      for (int k = 0; k < 3; ++k) {
        const Index v = mesh_.element(e)[static_cast<size_t>(mesh::kTetFace[j][k])];
        if (!mesh_.fixed(v)) r.fixed_nodes.push_back(v);
        mesh_.set_fixed(v, true);
      }
      ++r.components_fixed;
      break;
    }
  }
  return true;
}

void Cutter::check_components(CutStepReport& r) {
  const Index cap = mesh_.element_capacity();
  std::vector<Index> comp(static_cast<size_t>(cap), -1);
  Index ncomp = 0;
  std::vector<Index> stack;
  for (Index s = 0; s < cap; ++s) {
    if (!mesh_.alive(s) || comp[static_cast<size_t>(s)] >= 0) continue;
    Anchor anchor;
    Index face_e = -1;
    int face_j = -1;
    comp[static_cast<size_t>(s)] = ncomp;
    stack.assign(1, s);
    while (!stack.empty()) {
      const Index e = stack.back();
      stack.pop_back();
      for (Index v : mesh_.element(e))
        if (mesh_.fixed(v)) anchor.add(mesh_.reference(v));
      for (int j = 0; j < 4; ++j) {
        const Index nb = mesh_.neighbor(e, j);
        if (nb < 0) {
          if (face_e < 0 || e < face_e) {
            face_e = e;
            face_j = j;
          }
        } else if (comp[static_cast<size_t>(nb)] < 0) {
          comp[static_cast<size_t>(nb)] = ncomp;
          stack.push_back(nb);
        }
      }
    }
    ++ncomp;
    if (anchor.anchored()) continue;
    ++r.free_components;
    if (options_.free_components == FreeComponentPolicy::kFixOnFace && face_e >= 0) {
      for (int k = 0; k < 3; ++k) {
        const Index v = mesh_.element(face_e)[static_cast<size_t>(mesh::kTetFace[face_j][k])];
        if (!mesh_.fixed(v)) r.fixed_nodes.push_back(v);
        mesh_.set_fixed(v, true);
      }
      ++r.components_fixed;
    }
  }
}

}  // namespace incise::cut
