// Property tests of the mesh connectivity of thesis ch. 7: invariants (7.1)–(7.5) after every
// randomized edit, validator sensitivity to deliberate corruption, round trips, cycle-around
// against brute force, dissection (§7.3) against a brute-force class computation, watchers (§7.4).
#include <gtest/gtest.h>
#include <incise/core/error.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/dissect.hpp>
#include <incise/mesh/generators.hpp>
#include <incise/mesh/validate.hpp>
#include <incise_test/seed.hpp>

#include <algorithm>
#include <functional>
#include <iostream>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <vector>

namespace incise::mesh {

/// Test-only access to Connectivity internals (declared a friend in connectivity.hpp, defined
/// only here): used to corrupt valid structures deliberately.
struct ConnectivityTestAccess {
  static auto& elements(Connectivity& c) { return c.elements_; }
  static auto& faces(Connectivity& c) { return c.faces_; }
  static auto& boundary(Connectivity& c) { return c.boundary_; }
  static auto& incidence(Connectivity& c) { return c.vertex_elements_; }
};

namespace {

using TA = ConnectivityTestAccess;

// ---------------------------------------------------------------------------------------------
// meshes

// Planar grid of nx×ny squares in z = 0, each split along a diagonal (alternating, or random
// when rng is given, with interior nodes jittered by up to 0.25 spacing: a small irregular
// "Delaunay-ish" triangulation). Triangles positively oriented (counter-clockwise).
MeshData triangle_grid(int nx, int ny, std::mt19937_64* rng) {
  MeshData m;
  m.dimension = 2;
  const int px = nx + 1, py = ny + 1;
  m.points.resize(3, px * py);
  std::uniform_real_distribution<double> jitter(-0.25, 0.25);
  for (int j = 0; j < py; ++j)
    for (int i = 0; i < px; ++i) {
      Vec3 x(i, j, 0.0);
      if (rng && i > 0 && j > 0 && i < nx && j < ny) x += Vec3(jitter(*rng), jitter(*rng), 0);
      m.points.col(i + px * j) = x;
    }
  m.cells.resize(3, 2 * nx * ny);
  int c = 0;
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const Index a = i + px * j, b = a + 1, d = a + px, e = d + 1;
      const bool forward = rng ? ((*rng)() % 2 == 0) : ((i + j) % 2 == 0);
      const std::array<std::array<Index, 3>, 2> t =
          forward ? std::array<std::array<Index, 3>, 2>{{{a, b, e}, {a, e, d}}}
                  : std::array<std::array<Index, 3>, 2>{{{a, b, d}, {b, e, d}}};
      for (const auto& tri : t) {
        for (int r = 0; r < 3; ++r) m.cells(r, c) = tri[static_cast<std::size_t>(r)];
        ++c;
      }
    }
  return m;
}

struct NamedMesh {
  std::string name;
  MeshData data;
};

std::vector<NamedMesh> test_meshes(std::mt19937_64& rng) {
  std::vector<NamedMesh> out;
  out.push_back({"box3x3x3-six", make_box(3, 3, 3, 1, 1, 1, CubeSplit::kSix)});
  out.push_back({"box3x3x3-five", make_box(3, 3, 3, 1, 1, 1, CubeSplit::kFive)});
  out.push_back({"cylinder-2x2", make_cylinder(1.0, 0.5, 2, 2)});
  out.push_back({"grid8x8", triangle_grid(8, 8, nullptr)});
  out.push_back({"grid7x7-random", triangle_grid(7, 7, &rng)});
  return out;
}

// ---------------------------------------------------------------------------------------------
// helpers

// Canonical description of a mesh: sorted element simplices and sorted boundary simplices.
struct Snapshot {
  std::vector<Simplex> elements;
  std::vector<Simplex> boundary;
  bool operator==(const Snapshot& o) const {
    return elements == o.elements && boundary == o.boundary;
  }
};

Snapshot snapshot(const Connectivity& c) {
  Snapshot s;
  for (ElementHandle e : c.elements()) s.elements.push_back(c.simplex(e));
  for (FaceHandle f : c.boundary()) s.boundary.push_back(c.simplex(f));
  std::sort(s.elements.begin(), s.elements.end());
  std::sort(s.boundary.begin(), s.boundary.end());
  return s;
}

bool element_contains_all(const Simplex& t, const Simplex& s) {
  for (int i = 0; i < s.count(); ++i)
    if (!t.contains(s.vertex(i))) return false;
  return true;
}

bool edge_exists(const Connectivity& c, Index p, Index q) {
  for (ElementHandle e : c.star(p))
    if (c.simplex(e).contains(q)) return true;
  return false;
}

// Bistellar 2 → d flip across the interior face f (2D edge flip, Fig. 7.4; 3D 2-3 flip).
// With A = σ.sup(p) and B = (−σ).sup(q), the new elements are σ.subn(j).sup(q).sup(p): their
// boundary is q*∂σ − p*∂σ = ∂A + ∂B (cone formula ∂(v*τ) = τ − v*∂τ).
bool flip_2_to_d(Connectivity& c, FaceHandle f) {
  const FaceHandle g = c.mate(f);
  if (!g.valid()) return false;
  const Index p = c.opposite_vertex(f), q = c.opposite_vertex(g);
  if (p == q || edge_exists(c, p, q)) return false;
  const Simplex sigma = c.simplex(f);
  std::vector<Simplex> add;
  for (int j = 0; j < sigma.count(); ++j) add.push_back(sigma.subn(j).sup(q).sup(p));
  c.replace_elements({c.element(f), c.element(g)}, add);
  return true;
}

// Bistellar 3 → 2 flip removing the interior edge pq of degree 3 (inverse of the above).
bool flip_3_to_2(Connectivity& c, Index p, Index q) {
  const std::vector<ElementHandle> ring = c.cycle_around(Simplex({p, q}));
  if (ring.size() != 3) return false;
  std::set<Index> others;
  for (ElementHandle e : ring) {
    for (int i = 0; i < 4; ++i) {
      const Index v = c.simplex(e).vertex(i);
      if (v != p && v != q) others.insert(v);
      // the edge must be interior: both faces containing pq mated
      if (v != p && v != q && !c.mate(c.face(e, i)).valid()) return false;
    }
  }
  if (others.size() != 3) return false;
  const std::vector<Index> r(others.begin(), others.end());
  for (ElementHandle e : c.star(r[0]))
    if (c.simplex(e).contains(r[1]) && c.simplex(e).contains(r[2])) return false;  // σ exists
  std::vector<Simplex> have;
  for (ElementHandle e : ring) have.push_back(c.simplex(e));
  std::sort(have.begin(), have.end());
  for (int s : {1, -1}) {
    const Simplex sigma({r[0], r[1], r[2]}, s);
    std::vector<Simplex> expect;
    for (int j = 0; j < 3; ++j) expect.push_back(sigma.subn(j).sup(q).sup(p));
    std::sort(expect.begin(), expect.end());
    if (expect == have) {
      c.replace_elements(ring, {sigma.sup(p), sigma.mate().sup(q)});
      return true;
    }
  }
  ADD_FAILURE() << "ring around interior edge is not a consistently oriented 3-cycle";
  return false;
}

// Watcher mirroring elements and boundary from notifications only (§7.4); counts anomalies:
// an added object already present, a removed/changed one absent or with another simplex.
struct MirrorWatcher : ConnectivityWatcher {
  std::map<ElementHandle, Simplex> elements;
  std::map<FaceHandle, Simplex> boundary;
  std::vector<Index> touched;  // vertices of removed/added/changed simplices since last clear
  int anomalies = 0;
  long events = 0;
  void touch(const Simplex& s) {
    for (int i = 0; i < s.count(); ++i) touched.push_back(s.vertex(i));
  }
  void init(const Connectivity& c) override {
    elements.clear();
    boundary.clear();
    for (ElementHandle e : c.elements()) elements[e] = c.simplex(e);
    for (FaceHandle f : c.boundary()) boundary[f] = c.simplex(f);
  }
  void element_removed(const Connectivity&, ElementHandle e, const Simplex& s) override {
    ++events;
    touch(s);
    const auto it = elements.find(e);
    if (it == elements.end() || it->second != s) ++anomalies;
    if (it != elements.end()) elements.erase(it);
  }
  void boundary_removed(const Connectivity&, FaceHandle f, const Simplex& s) override {
    ++events;
    const auto it = boundary.find(f);
    if (it == boundary.end() || it->second != s) ++anomalies;
    if (it != boundary.end()) boundary.erase(it);
  }
  void element_added(const Connectivity& c, ElementHandle e) override {
    ++events;
    touch(c.simplex(e));
    if (!elements.emplace(e, c.simplex(e)).second) ++anomalies;
  }
  void element_changed(const Connectivity& c, ElementHandle e, const Simplex& old) override {
    ++events;
    touch(old);
    touch(c.simplex(e));
    const auto it = elements.find(e);
    if (it == elements.end() || it->second != old) {
      ++anomalies;
      return;
    }
    it->second = c.simplex(e);
  }
  void boundary_added(const Connectivity& c, FaceHandle f) override {
    ++events;
    if (c.mate(f).valid()) ++anomalies;
    if (!boundary.emplace(f, c.simplex(f)).second) ++anomalies;
  }
};

void expect_mirror_matches(const MirrorWatcher& w, const Connectivity& c) {
  std::map<ElementHandle, Simplex> el;
  for (ElementHandle e : c.elements()) el[e] = c.simplex(e);
  std::map<FaceHandle, Simplex> bd;
  for (FaceHandle f : c.boundary()) bd[f] = c.simplex(f);
  EXPECT_EQ(w.anomalies, 0);
  EXPECT_TRUE(w.elements == el) << "watcher element mirror differs";
  EXPECT_TRUE(w.boundary == bd) << "watcher boundary mirror differs";
}

// Brute-force (v, C)-classes of star(v) (§7.3) from element simplices only: union-find over
// pairs of elements sharing a (d−1)-face that contains v and whose vertex set is not in C.
std::set<std::set<Index>> brute_classes(const Connectivity& c, Index v,
                                        const std::set<std::vector<Index>>& cut_sets) {
  std::vector<ElementHandle> star;
  for (ElementHandle e : c.elements())
    if (c.simplex(e).contains(v)) star.push_back(e);
  std::vector<std::size_t> parent(star.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<std::size_t(std::size_t)> find = [&](std::size_t x) {
    return parent[x] == x ? x : parent[x] = find(parent[x]);
  };
  for (std::size_t a = 0; a < star.size(); ++a)
    for (std::size_t b = a + 1; b < star.size(); ++b) {
      const Simplex& s = c.simplex(star[a]);
      const Simplex& t = c.simplex(star[b]);
      std::vector<Index> shared;
      for (int i = 0; i < s.count(); ++i)
        if (t.contains(s.vertex(i))) shared.push_back(s.vertex(i));
      if (static_cast<int>(shared.size()) != c.dimension()) continue;
      if (cut_sets.count(shared)) continue;
      parent[find(a)] = find(b);
    }
  std::map<std::size_t, std::set<Index>> groups;
  for (std::size_t a = 0; a < star.size(); ++a) groups[find(a)].insert(star[a].index);
  std::set<std::set<Index>> out;
  for (auto& g : groups) out.insert(g.second);
  return out;
}

std::vector<Index> vertex_set(const Simplex& s) {
  return std::vector<Index>(s.vertices().begin(), s.vertices().begin() + s.count());
}

// Reverses a dissection by substituting every new vertex back to its origin.
void undo_dissection(Connectivity& c, const DissectResult& r) {
  std::map<Index, Index> back;
  for (const VertexSplit& s : r.splits) back[s.new_vertex] = s.old_vertex;
  std::set<ElementHandle> touched;
  for (const VertexSplit& s : r.splits) touched.insert(s.elements.begin(), s.elements.end());
  std::vector<ElementChange> changes;
  for (ElementHandle e : touched) {
    const Simplex& t = c.simplex(e);
    ElementChange ch{e, {{-1, -1, -1, -1}}};
    for (int i = 0; i < t.count(); ++i) {
      const auto it = back.find(t.vertex(i));
      ch.new_vertices[static_cast<std::size_t>(i)] = it == back.end() ? t.vertex(i) : it->second;
    }
    changes.push_back(ch);
  }
  c.change_elements(changes);
}

// Dissects along `cut`, checks the classes against brute force, that faces outside C stay
// joined, that element handles survive, validates, then undoes and checks the round trip.
// Returns the number of edits performed (2 when something was split, else 1).
int dissect_and_check(Connectivity& c, Eigen::Matrix3Xd& x, const std::vector<FaceHandle>& cut,
                      bool check_orientation) {
  const Snapshot before = snapshot(c);
  const std::vector<ElementHandle> handles = c.elements();
  std::set<std::vector<Index>> cut_sets;
  std::set<Index> cut_faces, cut_vertices;
  for (FaceHandle f : cut) {
    if (!c.mate(f).valid()) continue;
    cut_sets.insert(vertex_set(c.simplex(f)));
    cut_faces.insert(f.index);
    cut_faces.insert(c.mate(f).index);
    for (Index v : vertex_set(c.simplex(f))) cut_vertices.insert(v);
  }
  std::vector<FaceHandle> joined;  // interior faces outside C
  for (ElementHandle e : handles)
    for (int i = 0; i <= c.dimension(); ++i) {
      const FaceHandle f = c.face(e, i);
      if (c.mate(f).valid() && !cut_faces.count(f.index)) joined.push_back(f);
    }
  std::map<Index, std::set<std::set<Index>>> expected;
  std::size_t expected_new = 0;
  for (Index v : cut_vertices) {
    expected[v] = brute_classes(c, v, cut_sets);
    expected_new += expected[v].size() - 1;
  }

  const DissectResult r = dissect(c, cut);
  extend_positions(x, r);
  EXPECT_EQ(static_cast<std::size_t>(r.num_new_vertices()), expected_new);
  ValidateOptions opt;
  if (check_orientation) opt.positions = &x;
  const ValidationReport rep = validate(c, opt);
  EXPECT_TRUE(rep.ok()) << "after dissect: " << rep.summary();
  for (ElementHandle e : handles) EXPECT_TRUE(c.is_alive(e));  // change-elements keeps identity
  for (FaceHandle f : joined) EXPECT_TRUE(c.mate(f).valid()) << "face outside C came apart";
  // Partition of star(v) (by element slot) into classes equals the brute-force one.
  std::map<Index, std::set<std::set<Index>>> got;
  for (Index v : cut_vertices) {
    std::set<Index> kept;
    for (ElementHandle e : c.star(v)) kept.insert(e.index);
    if (!kept.empty()) got[v].insert(kept);
  }
  for (const VertexSplit& s : r.splits) {
    std::set<Index> cls;
    for (ElementHandle e : s.elements) cls.insert(e.index);
    got[s.old_vertex].insert(cls);
    EXPECT_EQ(c.star_size(s.new_vertex), static_cast<Index>(s.elements.size()));
  }
  for (Index v : cut_vertices) EXPECT_TRUE(got[v] == expected[v]) << "classes of vertex " << v;
  if (r.num_new_vertices() == 0) {
    EXPECT_TRUE(snapshot(c) == before);
    return 1;
  }
  undo_dissection(c, r);
  const ValidationReport rep2 = validate(c);
  EXPECT_TRUE(rep2.ok()) << "after undoing dissection: " << rep2.summary();
  EXPECT_TRUE(snapshot(c) == before) << "dissect + merge did not restore the mesh";
  return 2;
}

void expect_cycle_around_brute_force(const Connectivity& c, const Simplex& sigma) {
  const std::vector<ElementHandle> ring = c.cycle_around(sigma);
  std::set<ElementHandle> got(ring.begin(), ring.end());
  std::set<ElementHandle> want;
  for (ElementHandle e : c.elements())
    if (element_contains_all(c.simplex(e), sigma)) want.insert(e);
  EXPECT_EQ(got.size(), ring.size()) << "element listed twice around " << sigma;
  EXPECT_TRUE(got == want) << "cycle_around " << sigma << " differs from brute force";
  // Rotational order: consecutive elements are neighbours.
  for (std::size_t k = 1; k < ring.size(); ++k) {
    const auto nb = c.neighbours(ring[k - 1]);
    EXPECT_TRUE(std::find(nb.begin(), nb.end(), ring[k]) != nb.end())
        << "ring around " << sigma << " not in rotational order at " << k;
  }
}

// A random (d−2)-simplex of the mesh (edge in 3D, vertex in 2D).
Simplex random_ridge(const Connectivity& c, std::mt19937_64& rng) {
  const std::vector<ElementHandle> el = c.elements();
  const Simplex& t = c.simplex(el[rng() % el.size()]);
  if (c.dimension() == 2) return Simplex({t.vertex(static_cast<int>(rng() % 3))});
  const int a = static_cast<int>(rng() % 4);
  const int b = (a + 1 + static_cast<int>(rng() % 3)) % 4;
  return Simplex({t.vertex(a), t.vertex(b)});
}

// ---------------------------------------------------------------------------------------------
// (b) ≥ 10^4 random edits, validation after every edit

TEST(ConnectivityProperty, RandomEditsKeepInvariants_Eq71to75) {
  INCISE_SEEDED_RNG(rng, 20031107);
  // A quarter in builds with debug checks: paranoid validation after every edit doubles the test's
  // own and makes the sequence quadratic (50 s under ASan).
  const int edits_per_mesh = incise::test::scaled_for_checks(2100, 4);
  long total_edits = 0;
  std::map<std::string, long> kinds;
  for (NamedMesh& nm : test_meshes(rng)) {
    SCOPED_TRACE(nm.name);
    Connectivity c = Connectivity::from_mesh_data(nm.data);
    Eigen::Matrix3Xd x = nm.data.points;
    MirrorWatcher watcher;
    c.add_watcher(&watcher);
    ASSERT_TRUE(validate(c, {}).ok());
    const int d = c.dimension();
    int edits = 0;
    int checks = 0;
    auto check = [&](bool stars) {
      ValidateOptions opt;
      opt.check_connected_stars = stars;
      const ValidationReport rep = validate(c, opt);
      ASSERT_TRUE(rep.ok()) << rep.summary();
      // Every third check: the local check around the edit(s) since the last one (stars of
      // every touched vertex) agrees (thinned out only to keep the ASan run short).
      expect_mirror_matches(watcher, c);
      ASSERT_EQ(c.num_faces(), (d + 1) * c.num_elements());
      if (++checks % 3 != 0) return;
      std::sort(watcher.touched.begin(), watcher.touched.end());
      watcher.touched.erase(std::unique(watcher.touched.begin(), watcher.touched.end()),
                            watcher.touched.end());
      std::vector<ElementHandle> around;
      for (Index v : watcher.touched)
        for (ElementHandle h : c.star(v)) around.push_back(h);
      const ValidationReport local = validate_local(c, around, watcher.touched, opt);
      ASSERT_TRUE(local.ok()) << local.summary();
      watcher.touched.clear();
    };
    int guard = 0;
    while (edits < edits_per_mesh && ++guard < 20 * edits_per_mesh) {
      const std::vector<ElementHandle> el = c.elements();
      const ElementHandle e = el[rng() % el.size()];
      const int op = static_cast<int>(rng() % 10);
      if (op <= 3) {  // 2D edge flip / 3D 2-3 flip
        if (!flip_2_to_d(c, c.face(e, static_cast<int>(rng() % (d + 1))))) continue;
        ++kinds[d == 2 ? "2D edge flip" : "3D 2-3 flip"];
        ++edits;
        check(true);
      } else if (op <= 5 && d == 3) {  // 3-2 flip on a random edge
        const Simplex edge = random_ridge(c, rng);
        if (!flip_3_to_2(c, edge.vertex(0), edge.vertex(1))) continue;
        ++kinds["3D 3-2 flip"];
        ++edits;
        check(true);
      } else if (op <= 6) {  // (c) remove 1–3 elements (or a whole vertex star), re-add
        std::vector<ElementHandle> rem;
        if (rng() % 4 == 0) {
          rem = c.star(c.simplex(e).vertex(0));
        } else {
          std::set<ElementHandle> pick{e};
          const int k = static_cast<int>(rng() % 3);
          for (int i = 0; i < k; ++i) pick.insert(el[rng() % el.size()]);
          rem.assign(pick.begin(), pick.end());
        }
        const Snapshot before = snapshot(c);
        std::vector<Simplex> simplices;
        for (ElementHandle h : rem) simplices.push_back(c.simplex(h));
        c.replace_elements(rem, {});
        for (ElementHandle h : rem) ASSERT_FALSE(c.is_alive(h));
        check(false);  // removal may pinch a star: structural checks only
        std::shuffle(simplices.begin(), simplices.end(), rng);
        const std::vector<ElementHandle> back = c.replace_elements({}, simplices);
        ASSERT_EQ(back.size(), simplices.size());
        check(true);
        ASSERT_TRUE(snapshot(c) == before) << "remove + re-add did not restore the mesh";
        kinds["remove+re-add"] += 2;
        edits += 2;
      } else if (op <= 8) {  // dissection along a random face set, then merge back
        std::vector<FaceHandle> cut;
        const int mode = static_cast<int>(rng() % 3);
        if (mode == 0) {  // a few random faces
          const int k = 1 + static_cast<int>(rng() % 6);
          for (int i = 0; i < k; ++i)
            cut.push_back(c.face(el[rng() % el.size()], static_cast<int>(rng() % (d + 1))));
        } else if (mode == 1) {  // all faces of one element: cuts it out
          for (int i = 0; i <= d; ++i) cut.push_back(c.face(e, i));
        } else {  // random half of the faces containing a vertex
          const Index v = c.simplex(e).vertex(static_cast<int>(rng() % (d + 1)));
          for (ElementHandle h : c.star(v))
            for (int i = 0; i <= d; ++i)
              if (c.simplex(h).vertex(i) != v && rng() % 2) cut.push_back(c.face(h, i));
        }
        const int n = dissect_and_check(c, x, cut, false);
        if (::testing::Test::HasFailure()) return;
        kinds[n == 2 ? "dissect+merge (split)" : "dissect (no split)"] += n;
        edits += n;
        check(true);
      } else {  // vertex substitution: rename v := fresh w over star(v)
        const Index v = c.simplex(e).vertex(static_cast<int>(rng() % (d + 1)));
        const std::vector<ElementHandle> st = c.star(v);
        const Index w = c.add_vertex();
        x.conservativeResize(3, w + 1);
        x.col(w) = x.col(v);
        c.substitute_vertex(st, v, w);
        for (ElementHandle h : st) ASSERT_TRUE(c.is_alive(h) && c.simplex(h).contains(w));
        ASSERT_EQ(c.star_size(v), 0);
        ++kinds["vertex substitution"];
        ++edits;
        check(true);
      }
      if (rng() % 8 == 0) expect_cycle_around_brute_force(c, random_ridge(c, rng));
      if (::testing::Test::HasFailure()) return;
    }
    EXPECT_GE(edits, edits_per_mesh);
    total_edits += edits;
    c.remove_watcher(&watcher);
  }
  std::string summary;
  for (const auto& k : kinds) summary += " " + k.first + "=" + std::to_string(k.second);
  RecordProperty("edits", static_cast<int>(total_edits));
  std::cout << "[ edits    ] " << total_edits << " validated random edits:" << summary << "\n";
  EXPECT_GE(total_edits, incise::test::scaled_for_checks(10000, 4));
}

// ---------------------------------------------------------------------------------------------
// (a) corruption: validate() must name the violated invariant

struct Corruption {
  std::string name;
  std::string invariant;
  std::function<void(Connectivity&)> apply;
};

// First interior face (has a mate) and first boundary face of the structure.
Index first_interior_face(Connectivity& c) {
  for (std::size_t f = 0; f < TA::faces(c).size(); ++f)
    if (TA::faces(c)[f].alive && TA::faces(c)[f].mate >= 0) return static_cast<Index>(f);
  return -1;
}

// Two elements of star(v) that are not face-neighbours, for an interior vertex v.
std::pair<ElementHandle, ElementHandle> separated_pair(const Connectivity& c) {
  for (Index v = 0; v < c.num_vertices(); ++v) {
    const std::vector<ElementHandle> st = c.star(v);
    for (std::size_t a = 0; a < st.size(); ++a)
      for (std::size_t b = a + 1; b < st.size(); ++b) {
        const auto nb = c.neighbours(st[a]);
        if (std::find(nb.begin(), nb.end(), st[b]) == nb.end()) return {st[a], st[b]};
      }
  }
  return {};
}

std::vector<Corruption> corruptions() {
  std::vector<Corruption> list;
  list.push_back({"swap two face slots of an element", "7.1", [](Connectivity& c) {
                    auto& r = TA::elements(c)[0];
                    std::swap(r.faces[0], r.faces[1]);
                  }});
  list.push_back({"face points to an element that does not list it", "7.2", [](Connectivity& c) {
                    auto& f = TA::faces(c)[static_cast<std::size_t>(TA::elements(c)[0].faces[0])];
                    f.element = 1;
                  }});
  list.push_back({"mate with the wrong simplex", "7.3", [](Connectivity& c) {
                    const Index f = first_interior_face(c);
                    auto& fr = TA::faces(c)[static_cast<std::size_t>(f)];
                    const auto& owner = TA::elements(c)[static_cast<std::size_t>(fr.element)];
                    // another face of the same element: simplex is not −σ
                    fr.mate = owner.faces[0] == f ? owner.faces[1] : owner.faces[0];
                  }});
  list.push_back({"one-sided mate", "mate-symmetry", [](Connectivity& c) {
                    // f ↔ g mates; clear g's side only.
                    const Index f = first_interior_face(c);
                    auto& fr = TA::faces(c)[static_cast<std::size_t>(f)];
                    TA::faces(c)[static_cast<std::size_t>(fr.mate)].mate = -1;
                  }});
  list.push_back({"duplicate element record (Figure 7.8 style)", "7.4", [](Connectivity& c) {
                    auto& els = TA::elements(c);
                    auto& fcs = TA::faces(c);
                    auto rec = els[0];
                    const Index e = static_cast<Index>(els.size());
                    for (auto& f : rec.faces) {
                      if (f < 0) continue;
                      auto fr = fcs[static_cast<std::size_t>(f)];
                      fr.element = e;
                      fr.mate = -1;
                      f = static_cast<Index>(fcs.size());
                      fcs.push_back(fr);
                    }
                    els.push_back(rec);
                  }});
  list.push_back(
      {"mated pair both unmated and put on the boundary map", "7.5", [](Connectivity& c) {
         const Index f = first_interior_face(c);
         auto& fr = TA::faces(c)[static_cast<std::size_t>(f)];
         const Index g = fr.mate;
         auto& gr = TA::faces(c)[static_cast<std::size_t>(g)];
         fr.mate = -1;
         gr.mate = -1;
         TA::boundary(c)[fr.simplex] = f;
         TA::boundary(c)[gr.simplex] = g;
       }});
  list.push_back(
      {"boundary map entry points to another boundary face", "boundary-map", [](Connectivity& c) {
         auto& b = TA::boundary(c);
         auto it = b.begin();
         auto jt = std::next(it);
         it->second = jt->second;
       }});
  list.push_back({"vertex missing from incidence list", "incidence", [](Connectivity& c) {
                    auto& inc = TA::incidence(c);
                    for (auto& l : inc)
                      if (!l.empty()) {
                        l.pop_back();
                        return;
                      }
                  }});
  list.push_back({"disconnected star via change_elements", "connected-star", [](Connectivity& c) {
                    const auto pr = separated_pair(c);
                    // substitute a shared vertex of both elements by one fresh vertex w
                    const Simplex& a = c.simplex(pr.first);
                    const Simplex& b = c.simplex(pr.second);
                    Index v = -1;
                    for (int i = 0; i < a.count(); ++i)
                      if (b.contains(a.vertex(i))) v = a.vertex(i);
                    const Index w = c.add_vertex();
                    c.substitute_vertex({pr.first, pr.second}, v, w);
                  }});
  return list;
}

TEST(ConnectivityProperty, ValidatorNamesEachCorruption_Eq71to75) {
  INCISE_SEEDED_RNG(rng, 4242);
  std::set<std::string> caught;
  for (NamedMesh& nm : test_meshes(rng)) {
    for (const Corruption& k : corruptions()) {
      SCOPED_TRACE(nm.name + ": " + k.name);
      Connectivity c = Connectivity::from_mesh_data(nm.data);
      ASSERT_TRUE(validate(c).ok());
      k.apply(c);
      ValidationReport rep;
      ASSERT_NO_THROW(rep = validate(c));
      EXPECT_TRUE(rep.has(k.invariant)) << "expected [" << k.invariant << "], got\n"
                                        << rep.summary();
      if (rep.has(k.invariant)) caught.insert(k.invariant);
      // validate_local over every element (and vertex) names it as well.
      std::vector<Index> all_vertices(static_cast<std::size_t>(c.num_vertices()));
      std::iota(all_vertices.begin(), all_vertices.end(), 0);
      std::vector<ElementHandle> all;
      for (Index i = 0; i < c.element_capacity(); ++i)
        if (c.element_at(i).valid()) all.push_back(c.element_at(i));
      ValidationReport local;
      ASSERT_NO_THROW(local = validate_local(c, all, all_vertices));
      EXPECT_TRUE(local.has(k.invariant))
          << "validate_local: expected [" << k.invariant << "], got\n"
          << local.summary();
    }
  }
  std::string list;
  for (const auto& s : caught) list += " " + s;
  std::cout << "[ caught   ] corruption classes:" << list << "\n";
  EXPECT_GE(caught.size(), 9u);
}

// Figure 7.8: re-adding an existing interior element cannot be caught by replace_elements'
// cheap checks; validate() (or the paranoid build after the edit) reports (7.4).
TEST(ConnectivityProperty, Figure78DuplicateIsCaughtByValidate) {
  Connectivity c = Connectivity::from_mesh_data(make_box(3, 3, 3, 1, 1, 1));
  ElementHandle interior;
  for (ElementHandle e : c.elements()) {
    bool all = true;
    for (ElementHandle n : c.neighbours(e)) all = all && n.valid();
    if (all) interior = e;
  }
  ASSERT_TRUE(interior.valid());
  const Simplex t = c.simplex(interior);
#if defined(INCISE_PARANOID)
  EXPECT_THROW(c.replace_elements({}, {t}), UsageError);
#else
  c.replace_elements({}, {t});
#endif
  const ValidationReport rep = validate(c);
  EXPECT_TRUE(rep.has("7.4")) << rep.summary();
  // Locally, around the re-added element only.
  std::vector<ElementHandle> around;
  for (int i = 0; i < 4; ++i)
    for (ElementHandle h : c.star(t.vertex(i))) around.push_back(h);
  EXPECT_TRUE(validate_local(c, around).has("7.4"));
}

// Above kParanoidFullValidationLimit elements, paranoid builds validate locally after each edit;
// a Figure 7.8 duplicate is still caught. Without INCISE_PARANOID the same local check is run
// explicitly.
TEST(ConnectivityProperty, LocalValidationOnLargeMesh) {
  Connectivity c = Connectivity::from_mesh_data(make_box(9, 9, 9, 1, 1, 1));  // 4,374 tets
  ASSERT_GT(c.num_elements(), kParanoidFullValidationLimit);
  // A legal edit first: remove and re-add one element.
  const ElementHandle e = c.elements()[c.num_elements() / 2];
  const Simplex t = c.simplex(e);
  c.replace_elements({e}, {});
  const ElementHandle back = c.replace_elements({}, {t})[0];
  std::vector<ElementHandle> around;
  for (int i = 0; i < 4; ++i)
    for (ElementHandle h : c.star(t.vertex(i))) around.push_back(h);
  EXPECT_TRUE(validate_local(c, around).ok());
#if defined(INCISE_PARANOID)
  EXPECT_THROW(c.replace_elements({}, {t}), UsageError);
#else
  c.replace_elements({}, {t});
#endif
  around.clear();
  for (int i = 0; i < 4; ++i)
    for (ElementHandle h : c.star(t.vertex(i))) around.push_back(h);
  const ValidationReport rep = validate_local(c, around);
  EXPECT_TRUE(rep.has("7.4")) << rep.summary();
  EXPECT_TRUE(c.is_alive(back));
}

TEST(ConnectivityProperty, OrientationCheckWithPositions) {
  const MeshData m = make_box(2, 2, 2, 1, 1, 1, CubeSplit::kFive);
  Connectivity c = Connectivity::from_mesh_data(m);
  ValidateOptions opt;
  opt.positions = &m.points;
  EXPECT_TRUE(validate(c, opt).ok());
  Eigen::Matrix3Xd mirrored = m.points;
  mirrored.row(0) *= -1.0;  // reflection: every element inverted
  opt.positions = &mirrored;
  const ValidationReport rep = validate(c, opt);
  EXPECT_EQ(rep.count("orientation"), static_cast<std::size_t>(c.num_elements()));
  MeshData g = triangle_grid(4, 3, nullptr);
  Connectivity c2 = Connectivity::from_mesh_data(g);
  opt.positions = &g.points;
  EXPECT_TRUE(validate(c2, opt).ok());
}

// validate() must survive arbitrary garbage in the records (never throw, never crash; ASan).
TEST(ConnectivityProperty, ValidateSurvivesRandomGarbage) {
  INCISE_SEEDED_RNG(rng, 99);
  for (NamedMesh& nm : test_meshes(rng)) {
    const Connectivity pristine = Connectivity::from_mesh_data(nm.data);
    for (int trial = 0; trial < incise::test::scaled(60); ++trial) {
      Connectivity c = pristine;
      auto& els = TA::elements(c);
      auto& fcs = TA::faces(c);
      const int hits = 1 + static_cast<int>(rng() % 4);
      std::uniform_int_distribution<Index> any(-3, static_cast<Index>(fcs.size()) + 3);
      for (int h = 0; h < hits; ++h) {
        switch (rng() % 6) {
          case 0:
            els[rng() % els.size()].faces[rng() % static_cast<unsigned>(c.dimension() + 1)] =
                any(rng);
            break;
          case 1: fcs[rng() % fcs.size()].element = any(rng); break;
          case 2: fcs[rng() % fcs.size()].mate = any(rng); break;
          case 3: fcs[rng() % fcs.size()].alive = false; break;
          case 4: els[rng() % els.size()].alive = false; break;
          default: TA::boundary(c)[Simplex({0, 1, 2})] = any(rng); break;
        }
      }
      ValidationReport rep;
      ASSERT_NO_THROW(rep = validate(c));
      EXPECT_FALSE(rep.ok());
    }
  }
}

// ---------------------------------------------------------------------------------------------
// (c), (d), (e) and API behaviour

TEST(ConnectivityProperty, BuildAndExportRoundTrip) {
  INCISE_SEEDED_RNG(rng, 5);
  for (NamedMesh& nm : test_meshes(rng)) {
    SCOPED_TRACE(nm.name);
    const Connectivity c = Connectivity::from_mesh_data(nm.data);
    EXPECT_EQ(c.num_elements(), nm.data.num_cells());
    ValidateOptions opt;
    opt.positions = &nm.data.points;
    const ValidationReport rep = validate(c, opt);
    EXPECT_TRUE(rep.ok()) << rep.summary();
    const MeshData out = c.to_mesh_data(nm.data.points);
    const Connectivity c2 = Connectivity::from_mesh_data(out);
    EXPECT_TRUE(snapshot(c) == snapshot(c2));
    opt.positions = &out.points;
    EXPECT_TRUE(validate(c2, opt).ok());
    for (ElementHandle e : c.elements()) {
      EXPECT_EQ(c.find_element(c.simplex(e)), e);
      EXPECT_FALSE(c.find_element(c.simplex(e).mate()).valid());
      for (int i = 0; i <= c.dimension(); ++i)
        EXPECT_EQ(c.find_face(c.simplex(e).subn(i)), c.face(e, i));
    }
    // Euler-type count: every face is interior (paired) or on the boundary.
    EXPECT_EQ((c.num_faces() - c.num_boundary_faces()) % 2, 0);
  }
}

TEST(ConnectivityProperty, CycleAroundEqualsBruteForce_Sec72) {
  INCISE_SEEDED_RNG(rng, 6);
  for (NamedMesh& nm : test_meshes(rng)) {
    SCOPED_TRACE(nm.name);
    const Connectivity c = Connectivity::from_mesh_data(nm.data);
    std::set<Simplex> ridges;
    for (ElementHandle e : c.elements()) {
      const Simplex& t = c.simplex(e);
      if (c.dimension() == 2) {
        for (int i = 0; i < 3; ++i) ridges.insert(Simplex({t.vertex(i)}));
      } else {
        for (int i = 0; i < 4; ++i)
          for (int j = i + 1; j < 4; ++j) ridges.insert(Simplex({t.vertex(i), t.vertex(j)}));
      }
    }
    for (const Simplex& s : ridges) expect_cycle_around_brute_force(c, s);
    // The thesis' signature: entry face and index j; interior rings come back to the entry.
    for (ElementHandle e : c.elements())
      for (int i = 0; i <= c.dimension(); ++i) {
        const FaceHandle f = c.face(e, i);
        for (int j = 0; j < c.dimension(); ++j) {
          const Simplex sigma = c.simplex(f).subn(j);
          const auto ring = c.cycle_around(f, j);
          std::size_t brute = 0;
          for (ElementHandle h : c.elements())
            brute += element_contains_all(c.simplex(h), sigma) ? 1 : 0;
          ASSERT_EQ(ring.size(), brute);
        }
      }
  }
}

TEST(ConnectivityProperty, ReplaceElementsReusesFacesAndMatchedPairs_Sec73) {
  // Figure 7.4 edge flip on two triangles: bcd, abd → abc, acd. Faces ab, bc, cd, da survive.
  const Index a = 0, b = 1, cc = 2, d = 3;
  MeshData m;
  m.dimension = 2;
  m.points = Eigen::Matrix3Xd::Zero(3, 4);
  m.cells.resize(3, 2);
  m.cells.col(0) << b, cc, d;
  m.cells.col(1) << a, b, d;
  Connectivity c = Connectivity::from_mesh_data(m);
  ASSERT_TRUE(validate(c).ok());
  std::map<Simplex, FaceHandle> before;
  for (FaceHandle f : c.boundary()) before[c.simplex(f)] = f;
  ASSERT_EQ(before.size(), 4u);
  MirrorWatcher w;
  c.add_watcher(&w);
  const auto els = c.elements();
  const auto added = c.replace_elements(els, {Simplex({a, b, cc}), Simplex({a, cc, d})});
  ASSERT_TRUE(validate(c).ok()) << validate(c).summary();
  for (const auto& kv : before) EXPECT_EQ(c.boundary_face(kv.first), kv.second) << kv.first;
  // The boundary did not change: only element events, no boundary events (matched pair ac).
  EXPECT_EQ(w.events, 4);
  expect_mirror_matches(w, c);
  const FaceHandle ac = c.opposite_face(added[0], b);
  EXPECT_TRUE(c.mate(ac).valid());
  EXPECT_EQ(c.element(c.mate(ac)), added[1]);
}

// change-elements over the whole star of an interior vertex changes no boundary face: the
// watcher hears exactly |star(v)| element changes, and every face keeps its handle and mate.
TEST(ConnectivityProperty, ChangeElementsOnInteriorStarHasNoBoundaryEvents_Sec74) {
  Connectivity c = Connectivity::from_mesh_data(make_box(3, 3, 3, 1, 1, 1));
  const Index v = 1 + 4 * (1 + 4 * 1);  // node (1,1,1): interior
  const std::vector<ElementHandle> st = c.star(v);
  ASSERT_EQ(st.size(), 24u);  // 6-split: 24 tetrahedra around an interior node
  std::map<FaceHandle, FaceHandle> mates;
  for (ElementHandle e : st)
    for (int i = 0; i < 4; ++i) mates[c.face(e, i)] = c.mate(c.face(e, i));
  MirrorWatcher w;
  c.add_watcher(&w);
  const Index nw = c.add_vertex();
  c.substitute_vertex(st, v, nw);
  EXPECT_EQ(w.events, 24);
  expect_mirror_matches(w, c);
  for (const auto& kv : mates) {
    EXPECT_TRUE(c.is_alive(kv.first));
    EXPECT_EQ(c.mate(kv.first), kv.second);
  }
  EXPECT_TRUE(validate(c).ok());
}

TEST(ConnectivityProperty, PreconditionViolationsThrowAndLeaveMeshIntact) {
  Connectivity c = Connectivity::from_mesh_data(make_box(2, 2, 2, 1, 1, 1));
  const Snapshot before = snapshot(c);
  const auto el = c.elements();
  EXPECT_THROW(c.replace_elements({el[0], el[0]}, {}), UsageError);
  EXPECT_THROW(c.replace_elements({}, {Simplex({0, 1, 2})}), UsageError);  // wrong dimension
  // A boundary face of a kept element would be represented twice.
  const FaceHandle bf = c.boundary()[0];
  const Simplex dup = c.simplex(bf).sup(1000);
  EXPECT_THROW(c.replace_elements({}, {dup}), UsageError);
  // Two new elements sharing an equally oriented face.
  EXPECT_THROW(
      c.replace_elements({}, {Simplex({900, 901, 902, 903}), Simplex({900, 901, 902, 904})}),
      UsageError);
  // Non-injective substitution.
  const Simplex t = c.simplex(el[0]);
  EXPECT_THROW(c.change_elements({{el[0], {{t.vertex(0), t.vertex(0), t.vertex(2), t.vertex(3)}}}}),
               UsageError);
  EXPECT_TRUE(snapshot(c) == before);
  EXPECT_TRUE(validate(c).ok());
  // Stale handle: slot reused with a new generation.
  const Simplex s0 = c.simplex(el[0]);
  c.replace_elements({el[0]}, {});
  const auto again = c.replace_elements({}, {s0});
  EXPECT_EQ(again[0].index, el[0].index);
  EXPECT_NE(again[0].generation, el[0].generation);
  EXPECT_FALSE(c.is_alive(el[0]));
  EXPECT_TRUE(c.is_alive(again[0]));
#if INCISE_DEBUG_CHECKS
  EXPECT_THROW((void)c.simplex(el[0]), UsageError);
#endif
  EXPECT_TRUE(snapshot(c) == before);
}

TEST(ConnectivityProperty, DissectAlongGridPlanes_Sec73) {
  // Cuts along (partial) grid planes of a box: the classic crack and a full separation.
  INCISE_SEEDED_RNG(rng, 73);
  for (CubeSplit split : {CubeSplit::kSix, CubeSplit::kFive}) {
    const MeshData m = make_box(4, 3, 3, 4, 3, 3, split);
    for (int trial = 0; trial < 6; ++trial) {
      Connectivity c = Connectivity::from_mesh_data(m);
      Eigen::Matrix3Xd x = m.points;
      const double plane = 1 + static_cast<double>(rng() % 3);
      const double ymax = trial == 0 ? 3.0 : 1.0 + static_cast<double>(rng() % 3);
      std::vector<FaceHandle> cut;
      for (ElementHandle e : c.elements())
        for (int i = 0; i < 4; ++i) {
          const FaceHandle f = c.face(e, i);
          const Simplex& s = c.simplex(f);
          bool on = true;
          for (int k = 0; k < 3; ++k) {
            on = on && x(0, s.vertex(k)) == plane && x(1, s.vertex(k)) <= ymax;
          }
          if (on) cut.push_back(f);
        }
      ASSERT_FALSE(cut.empty());
      const Snapshot before = snapshot(c);
      (void)before;
      dissect_and_check(c, x, cut, true);
      if (trial == 0) {
        // full plane: two pieces, every vertex of the plane duplicated once
        Connectivity c2 = Connectivity::from_mesh_data(m);
        Eigen::Matrix3Xd x2 = m.points;
        std::vector<FaceHandle> cut2;
        for (ElementHandle e : c2.elements())
          for (int i = 0; i < 4; ++i) {
            const FaceHandle f = c2.face(e, i);
            const Simplex& s = c2.simplex(f);
            bool on = true;
            for (int k = 0; k < 3; ++k) on = on && x2(0, s.vertex(k)) == plane;
            if (on) cut2.push_back(f);
          }
        const Index boundary_before = c2.num_boundary_faces();
        const DissectResult r = dissect(c2, cut2);
        extend_positions(x2, r);
        EXPECT_EQ(r.num_new_vertices(), 4 * 4);  // (ny+1)(nz+1) nodes on the plane
        EXPECT_EQ(c2.num_boundary_faces(), boundary_before + static_cast<Index>(cut2.size()));
        ValidateOptions opt;
        opt.positions = &x2;
        EXPECT_TRUE(validate(c2, opt).ok());
      }
    }
  }
}

TEST(ConnectivityProperty, DissectWithEmptyCutDoesNothing_Sec73) {
  Connectivity c = Connectivity::from_mesh_data(triangle_grid(4, 4, nullptr));
  const Snapshot before = snapshot(c);
  const DissectResult r = dissect(c, {});
  EXPECT_EQ(r.num_new_vertices(), 0);
  EXPECT_TRUE(snapshot(c) == before);
}

}  // namespace
}  // namespace incise::mesh
