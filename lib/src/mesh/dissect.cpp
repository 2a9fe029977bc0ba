#include <incise/core/error.hpp>
#include <incise/mesh/dissect.hpp>

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

namespace incise::mesh {

std::vector<Index> DissectResult::origin() const {
  std::vector<Index> o;
  o.reserve(splits.size());
  for (const auto& s : splits) o.push_back(s.old_vertex);
  return o;
}

DissectResult dissect(Connectivity& conn, const std::vector<FaceHandle>& cut) {
  DissectResult result;
  result.first_new_vertex = conn.num_vertices();
  const int d = conn.dimension();

  // C as a set of face slots (mates included); boundary faces cannot separate anything.
  std::unordered_set<Index> in_cut;
  std::vector<Index> vertices;
  for (const FaceHandle& f : cut) {
    INCISE_CHECK(conn.is_alive(f), "dissect: dead face handle in cut set");
    const FaceHandle m = conn.mate(f);
    if (!m.valid()) continue;
    in_cut.insert(f.index);
    in_cut.insert(m.index);
    const Simplex& s = conn.simplex(f);
    for (int i = 0; i < s.count(); ++i) vertices.push_back(s.vertex(i));
  }
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());

  // New vertex arrays per changed element (index in `changes`).
  std::unordered_map<Index, std::size_t> change_of;  // element slot → entry in changes
  std::vector<ElementChange> changes;
  auto substitute = [&](ElementHandle e, Index v, Index w) {
    auto it = change_of.find(e.index);
    if (it == change_of.end()) {
      const Simplex& s = conn.simplex(e);
      ElementChange c{e, {{-1, -1, -1, -1}}};
      for (int i = 0; i <= d; ++i) c.new_vertices[static_cast<std::size_t>(i)] = s.vertex(i);
      it = change_of.emplace(e.index, changes.size()).first;
      changes.push_back(c);
    }
    ElementChange& c = changes[it->second];
    const int i = conn.simplex(e).index(v);
    c.new_vertices[static_cast<std::size_t>(i)] = w;
  };

  Index next_vertex = conn.num_vertices();
  std::vector<ElementHandle> star;
  std::unordered_map<Index, int> cls;  // element slot → class id (−1 unvisited)
  std::vector<ElementHandle> queue;
  for (Index v : vertices) {
    star = conn.star(v);
    std::sort(star.begin(), star.end());
    cls.clear();
    for (const ElementHandle& e : star) cls[e.index] = -1;
    int classes = 0;
    std::vector<std::vector<ElementHandle>> members;
    for (const ElementHandle& start : star) {
      if (cls[start.index] >= 0) continue;
      const int id = classes++;
      members.emplace_back();
      cls[start.index] = id;
      queue.assign(1, start);
      while (!queue.empty()) {
        const ElementHandle e = queue.back();
        queue.pop_back();
        members.back().push_back(e);
        const Simplex& s = conn.simplex(e);
        for (int i = 0; i <= d; ++i) {
          if (s.vertex(i) == v) continue;  // the face opposite v does not contain v
          const FaceHandle f = conn.face(e, i);
          if (in_cut.count(f.index)) continue;  // do not cross C
          const FaceHandle m = conn.mate(f);
          if (!m.valid()) continue;
          const ElementHandle n = conn.element(m);
          const auto it = cls.find(n.index);
          if (it == cls.end() || it->second >= 0) continue;
          it->second = id;
          queue.push_back(n);
        }
      }
    }
    // Class 0 (contains the smallest slot) keeps v; the others get new vertices.
    for (int k = 1; k < classes; ++k) {
      const Index w = next_vertex++;
      auto& m = members[static_cast<std::size_t>(k)];
      std::sort(m.begin(), m.end());
      for (const ElementHandle& e : m) substitute(e, v, w);
      result.splits.push_back({v, w, m});
    }
  }
  while (conn.num_vertices() < next_vertex) conn.add_vertex();
  if (!changes.empty()) conn.change_elements(changes);
  return result;
}

void extend_positions(Eigen::Matrix3Xd& positions, const DissectResult& result) {
  INCISE_CHECK(positions.cols() == result.first_new_vertex,
               "extend_positions: position matrix has " + std::to_string(positions.cols()) +
                   " columns, dissection started at vertex " +
                   std::to_string(result.first_new_vertex));
  const Eigen::Index n = positions.cols();
  positions.conservativeResize(3, n + result.num_new_vertices());
  for (Index k = 0; k < result.num_new_vertices(); ++k)
    positions.col(n + k) = positions.col(result.splits[static_cast<std::size_t>(k)].old_vertex);
}

}  // namespace incise::mesh
