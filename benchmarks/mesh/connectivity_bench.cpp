// Benchmarks of the mesh connectivity of thesis ch. 7 on a ≥100k-tetrahedron box
// (make_box(30, 30, 20), 6-tetrahedron split: 108,000 tetrahedra, 20,181 vertices).
// Each edit benchmark performs an edit and its inverse, so the mesh is the same at every
// iteration; items_per_second counts single replace/change calls (or traversals).
#include <benchmark/benchmark.h>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/dissect.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/validate.hpp>
#include <incise_bench/context.hpp>

#include <random>
#include <vector>

namespace {

using namespace incise;
using namespace incise::mesh;

const MeshData& box() {
  static const MeshData m = make_box(30, 30, 20, 3.0, 3.0, 2.0, CubeSplit::kSix);
  return m;
}

void add_size_counters(benchmark::State& state, const Connectivity& c) {
  state.counters["tets"] = static_cast<double>(c.num_elements());
  state.counters["vertices"] = static_cast<double>(c.num_vertices());
}

void BM_BuildFromMeshData(benchmark::State& state) {
  for (auto _ : state) {
    Connectivity c = Connectivity::from_mesh_data(box());
    benchmark::DoNotOptimize(c.num_boundary_faces());
  }
  state.counters["tets"] = static_cast<double>(box().num_cells());
  state.SetItemsProcessed(state.iterations() * box().num_cells());
}
BENCHMARK(BM_BuildFromMeshData)->Unit(benchmark::kMillisecond);

// replace_elements: a 2-3 flip across an interior face followed by the 3-2 flip back.
void BM_ReplaceElements_Flip23and32(benchmark::State& state) {
  Connectivity c = Connectivity::from_mesh_data(box());
  struct Site {
    ElementHandle a, b;
    Simplex sigma;
    Index p, q;
  };
  std::vector<Site> sites;
  std::mt19937_64 rng(1);
  const std::vector<ElementHandle> el = c.elements();
  while (sites.size() < 4096) {
    const ElementHandle e = el[rng() % el.size()];
    const FaceHandle f = c.face(e, static_cast<int>(rng() % 4));
    const FaceHandle g = c.mate(f);
    if (!g.valid()) continue;
    const Index p = c.opposite_vertex(f), q = c.opposite_vertex(g);
    bool edge = false;
    for (ElementHandle h : c.star(p)) edge = edge || c.simplex(h).contains(q);
    if (edge) continue;
    bool used = false;  // sites must not share elements
    for (const Site& s : sites)
      used = used || s.a == e || s.b == c.element(g) || s.a == c.element(g) || s.b == e;
    if (used) continue;
    sites.push_back({e, c.element(g), c.simplex(f), p, q});
  }
  std::size_t k = 0;
  std::vector<Simplex> three(3);
  for (auto _ : state) {
    Site& s = sites[k++ % sites.size()];
    for (int j = 0; j < 3; ++j)
      three[static_cast<std::size_t>(j)] = s.sigma.subn(j).sup(s.q).sup(s.p);
    const std::vector<ElementHandle> t = c.replace_elements({s.a, s.b}, three);
    const std::vector<ElementHandle> back =
        c.replace_elements(t, {s.sigma.sup(s.p), s.sigma.mate().sup(s.q)});
    s.a = back[0];
    s.b = back[1];
  }
  add_size_counters(state, c);
  state.SetItemsProcessed(state.iterations() * 2);
}
BENCHMARK(BM_ReplaceElements_Flip23and32)->Unit(benchmark::kMicrosecond);

// replace_elements: remove one element and add it again (two calls).
void BM_ReplaceElements_RemoveReadd(benchmark::State& state) {
  Connectivity c = Connectivity::from_mesh_data(box());
  std::vector<ElementHandle> el = c.elements();
  std::mt19937_64 rng(2);
  std::shuffle(el.begin(), el.end(), rng);
  std::size_t k = 0;
  for (auto _ : state) {
    ElementHandle& e = el[k++ % el.size()];
    const Simplex s = c.simplex(e);
    c.replace_elements({e}, {});
    e = c.replace_elements({}, {s})[0];
  }
  add_size_counters(state, c);
  state.SetItemsProcessed(state.iterations() * 2);
}
BENCHMARK(BM_ReplaceElements_RemoveReadd)->Unit(benchmark::kMicrosecond);

// change_elements: substitute an interior vertex v := w over star(v) (24 tetrahedra in the
// 6-split box) and back (two calls).
void BM_ChangeElements_VertexStar(benchmark::State& state) {
  Connectivity c = Connectivity::from_mesh_data(box());
  std::vector<Index> interior;
  for (int k = 1; k < 20; ++k)
    for (int j = 1; j < 30; ++j)
      for (int i = 1; i < 30; ++i) interior.push_back(i + 31 * (j + 31 * k));
  std::mt19937_64 rng(3);
  std::shuffle(interior.begin(), interior.end(), rng);
  const Index w = c.add_vertex();
  std::size_t k = 0;
  double touched = 0;
  for (auto _ : state) {
    const Index v = interior[k++ % interior.size()];
    const std::vector<ElementHandle> st = c.star(v);
    c.substitute_vertex(st, v, w);
    c.substitute_vertex(st, w, v);
    touched += static_cast<double>(st.size());
  }
  add_size_counters(state, c);
  state.counters["elements_per_call"] = touched / static_cast<double>(state.iterations());
  state.SetItemsProcessed(state.iterations() * 2);
}
BENCHMARK(BM_ChangeElements_VertexStar)->Unit(benchmark::kMicrosecond);

// cycle_around a random edge (given by its vertices: includes finding an entry in star(a)).
void BM_CycleAround_Edge(benchmark::State& state) {
  const Connectivity c = Connectivity::from_mesh_data(box());
  std::vector<Simplex> edges;
  std::mt19937_64 rng(4);
  const std::vector<ElementHandle> el = c.elements();
  for (int n = 0; n < 8192; ++n) {
    const Simplex& t = c.simplex(el[rng() % el.size()]);
    const int a = static_cast<int>(rng() % 4), b = (a + 1 + static_cast<int>(rng() % 3)) % 4;
    edges.push_back(Simplex({t.vertex(a), t.vertex(b)}));
  }
  std::size_t k = 0;
  double found = 0;
  for (auto _ : state) {
    const std::vector<ElementHandle> ring = c.cycle_around(edges[k++ % edges.size()]);
    found += static_cast<double>(ring.size());
  }
  add_size_counters(state, c);
  state.counters["elements_per_ring"] = found / static_cast<double>(state.iterations());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_CycleAround_Edge)->Unit(benchmark::kNanosecond);

// cycle_around in the thesis' form: entry face and index j.
void BM_CycleAround_EntryFace(benchmark::State& state) {
  const Connectivity c = Connectivity::from_mesh_data(box());
  std::vector<std::pair<FaceHandle, int>> entries;
  std::mt19937_64 rng(5);
  const std::vector<ElementHandle> el = c.elements();
  for (int n = 0; n < 8192; ++n)
    entries.push_back(
        {c.face(el[rng() % el.size()], static_cast<int>(rng() % 4)), static_cast<int>(rng() % 3)});
  std::size_t k = 0;
  for (auto _ : state) {
    const auto& en = entries[k++ % entries.size()];
    benchmark::DoNotOptimize(c.cycle_around(en.first, en.second));
  }
  add_size_counters(state, c);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_CycleAround_EntryFace)->Unit(benchmark::kNanosecond);

// validate(): all invariants (7.1)–(7.5), mates, boundary map, incidence, connected stars.
void BM_Validate_Full(benchmark::State& state) {
  const Connectivity c = Connectivity::from_mesh_data(box());
  for (auto _ : state) {
    const ValidationReport r = validate(c);
    benchmark::DoNotOptimize(r.violations.size());
  }
  add_size_counters(state, c);
  state.SetItemsProcessed(state.iterations() * c.num_elements());
}
BENCHMARK(BM_Validate_Full)->Unit(benchmark::kMillisecond);

// validate() with the structural checks run after every edit in paranoid builds.
void BM_Validate_Paranoid(benchmark::State& state) {
  const Connectivity c = Connectivity::from_mesh_data(box());
  for (auto _ : state) {
    const ValidationReport r = validate(c, paranoid_validate_options());
    benchmark::DoNotOptimize(r.violations.size());
  }
  add_size_counters(state, c);
  state.SetItemsProcessed(state.iterations() * c.num_elements());
}
BENCHMARK(BM_Validate_Paranoid)->Unit(benchmark::kMillisecond);

// dissect along the full grid plane x = 1.5 (a 30×20 square, 1200 face pairs) and merge back.
void BM_Dissect_Plane(benchmark::State& state) {
  Connectivity c = Connectivity::from_mesh_data(box());
  const Eigen::Matrix3Xd& x = box().points;
  std::vector<FaceHandle> cut;
  for (ElementHandle e : c.elements())
    for (int i = 0; i < 4; ++i) {
      const FaceHandle f = c.face(e, i);
      const Simplex& s = c.simplex(f);
      bool on = true;
      for (int k = 0; k < 3; ++k) on = on && x(0, s.vertex(k)) == 1.5;
      if (on) cut.push_back(f);
    }
  double new_vertices = 0;
  for (auto _ : state) {
    const DissectResult r = dissect(c, cut);
    state.PauseTiming();
    new_vertices = r.num_new_vertices();
    std::vector<ElementChange> undo;
    std::vector<Index> back(static_cast<std::size_t>(c.num_vertices()), -1);
    for (const VertexSplit& s : r.splits)
      back[static_cast<std::size_t>(s.new_vertex)] = s.old_vertex;
    std::vector<char> seen(static_cast<std::size_t>(c.element_capacity()), 0);
    for (const VertexSplit& s : r.splits)
      for (ElementHandle e : s.elements) {
        if (seen[static_cast<std::size_t>(e.index)]++) continue;
        const Simplex& t = c.simplex(e);
        ElementChange ch{e, {{-1, -1, -1, -1}}};
        for (int i = 0; i < 4; ++i) {
          const Index o = back[static_cast<std::size_t>(t.vertex(i))];
          ch.new_vertices[static_cast<std::size_t>(i)] = o >= 0 ? o : t.vertex(i);
        }
        undo.push_back(ch);
      }
    c.change_elements(undo);
    state.ResumeTiming();
  }
  add_size_counters(state, c);
  state.counters["cut_faces"] = static_cast<double>(cut.size());
  state.counters["new_vertices"] = new_vertices;
}
BENCHMARK(BM_Dissect_Plane)->Unit(benchmark::kMillisecond);

}  // namespace

INCISE_BENCHMARK_MAIN();
