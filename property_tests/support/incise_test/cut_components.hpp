#pragma once
/// \file cut_components.hpp
/// The O(n) component search of the cut tests (cut robustness, the issue 17 organ path): one
/// definition, independent of the Cutter's own (local and global) searches.

#include <incise/cut/cut_mesh.hpp>

#include <vector>

namespace incise::test {

/// Whether every face-connected component of `m` holds a fixed node (after a cut with
/// cut::FreeComponentPolicy::kFixOnFace no part may be left free).
inline bool every_component_fixed(const cut::CutMesh& m) {
  std::vector<char> seen(static_cast<size_t>(m.element_capacity()), 0);
  for (Index s = 0; s < m.element_capacity(); ++s) {
    if (!m.alive(s) || seen[static_cast<size_t>(s)]) continue;
    bool fixed = false;
    std::vector<Index> stack{s};
    seen[static_cast<size_t>(s)] = 1;
    while (!stack.empty()) {
      const Index e = stack.back();
      stack.pop_back();
      for (Index v : m.element(e)) fixed = fixed || m.fixed(v);
      for (int j = 0; j < 4; ++j) {
        const Index n = m.neighbor(e, j);
        if (n >= 0 && !seen[static_cast<size_t>(n)]) {
          seen[static_cast<size_t>(n)] = 1;
          stack.push_back(n);
        }
      }
    }
    if (!fixed) return false;
  }
  return true;
}

}  // namespace incise::test
