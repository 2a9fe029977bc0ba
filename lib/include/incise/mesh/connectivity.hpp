#pragma once
/// \file connectivity.hpp
/// Simplicial mesh connectivity of thesis ch. 7 (§7.2–7.4): Elements, Faces, the boundary map,
/// replace-elements, change-elements, cycle-around and watchers.
///
/// Representation (docs/mesh_connectivity.md). One implementation serves d = 2 (triangles) and
/// d = 3 (tetrahedra): the dimension is a run-time value (fixed at construction) because the
/// `Simplex` type already holds up to 4 vertices and every algorithm of ch. 7 is written for a
/// general d; a template would only duplicate code. Elements (d-simplices) and Faces
/// ((d−1)-simplices) live in two arrays of records addressed by typed handles
/// (`ElementHandle`, `FaceHandle`: slot index + generation counter). Freed slots go to free lists
/// and are reused; their generation is incremented, so a stale handle is detected by
/// INCISE_ASSERT in debug and paranoid builds (always-on checks reject dead slots). The boundary
/// map (7.5) is a hash map from the canonical boundary Simplex to its Face.
///
/// Invariants (checked by `validate()`, validate.hpp):
///  - (7.1) element t: face(t, i).simplex == t.simplex.subn(i), i = 0..d;
///  - (7.2) face f: f ∈ faces(f.element);
///  - (7.3) f.mate is none or f.mate.simplex == −f.simplex (and mates are symmetric);
///  - (7.4) no two Elements and no two Faces represent the same oriented simplex;
///  - (7.5) the boundary map holds exactly the faces σ with −σ ∉ faces(T), i.e. the mateless ones.
///
/// Mates are written only by `replace_elements` and `change_elements` (and the builder, which
/// calls replace_elements). Vertices are non-negative integers; the structure does not store
/// positions (callers keep a 3×n matrix indexed by vertex, §7.4).
///
/// Paranoid builds (INCISE_PARANOID defined) run validate() (structural checks, see
/// `kParanoidChecks` in validate.hpp) after every edit and throw UsageError on a violation.

#include <incise/core/types.hpp>
#include <incise/mesh/mesh_data.hpp>
#include <incise/mesh/simplex.hpp>

#include <array>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

namespace incise::mesh {

/// Stable handle of an Element (a d-simplex of the mesh). Valid until the element is removed by
/// replace_elements; change_elements keeps it valid (element identity is preserved).
struct ElementHandle {
  Index index = -1;              ///< slot in the element array; −1 for "none"
  std::uint32_t generation = 0;  ///< slot generation when the handle was issued
  /// True unless this is the "none" handle (says nothing about staleness).
  bool valid() const { return index >= 0; }
  bool operator==(const ElementHandle& o) const {
    return index == o.index && generation == o.generation;
  }
  bool operator!=(const ElementHandle& o) const { return !(*this == o); }
  bool operator<(const ElementHandle& o) const {
    return index != o.index ? index < o.index : generation < o.generation;
  }
};

/// Stable handle of a Face (a (d−1)-simplex on the boundary of one element). Faces kept by
/// replace_elements (both before and after) and all faces of changed elements keep their handle.
struct FaceHandle {
  Index index = -1;              ///< slot in the face array; −1 for "none"
  std::uint32_t generation = 0;  ///< slot generation when the handle was issued
  /// True unless this is the "none" handle.
  bool valid() const { return index >= 0; }
  bool operator==(const FaceHandle& o) const {
    return index == o.index && generation == o.generation;
  }
  bool operator!=(const FaceHandle& o) const { return !(*this == o); }
  bool operator<(const FaceHandle& o) const {
    return index != o.index ? index < o.index : generation < o.generation;
  }
};

class Connectivity;

/// Observer of connectivity changes (thesis §7.4, Mesh_connectivity_watcher). After every
/// replace_elements / change_elements call, when the structure is consistent again, each
/// registered watcher is told the net changes of that call, in this order: removed elements,
/// removed boundary faces, added elements, changed elements, added boundary faces. A boundary
/// face that leaves and re-enters the boundary map within one call (same handle, same simplex)
/// is not reported. Callbacks must not edit the connectivity.
class ConnectivityWatcher {
 public:
  virtual ~ConnectivityWatcher() = default;
  /// Called by add_watcher with the current state (walk conn.elements(), conn.boundary()).
  virtual void init(const Connectivity& conn) {}
  /// Element `e` (now stale) with simplex `simplex` was removed.
  virtual void element_removed(const Connectivity& conn, ElementHandle e, const Simplex& simplex) {}
  /// Face `f` (possibly stale) with simplex `simplex` left the boundary map.
  virtual void boundary_removed(const Connectivity& conn, FaceHandle f, const Simplex& simplex) {}
  /// Element `e` was added.
  virtual void element_added(const Connectivity& conn, ElementHandle e) {}
  /// Element `e` kept its identity but its simplex changed from `old_simplex` (change_elements).
  virtual void element_changed(const Connectivity& conn, ElementHandle e,
                               const Simplex& old_simplex) {}
  /// Face `f` entered the boundary map (it is mateless now).
  virtual void boundary_added(const Connectivity& conn, FaceHandle f) {}
};

/// One entry of a change_elements call: element `element` gets the vertex substitution π given
/// by `new_vertices[i] = π(element.simplex.vertex(i))`, i = 0..d (canonical order). The new
/// simplex is π applied to the vertex sequence (orientation of the sequence kept), and face
/// opposite vertex a becomes the face opposite π(a) (same Face handle).
struct ElementChange {
  ElementHandle element;              ///< the element to change
  std::array<Index, 4> new_vertices;  ///< π of each canonical vertex; unused entries ignored
};

/// Simplicial mesh connectivity for d = 2 or 3 (see file comment).
class Connectivity {
 public:
  /// Empty connectivity of dimension `dim` ∈ {2, 3} over vertices 0..num_vertices−1 (more can be
  /// added with add_vertex or by using larger vertex numbers in replace_elements).
  explicit Connectivity(int dim, Index num_vertices = 0);

  /// Builds the connectivity of `mesh` (cells as oriented simplices, (dimension+1)×m). Each cell
  /// column (c0,…,cd) becomes +⟨c0,…,cd⟩. Throws UsageError for an invalid cell set (repeated
  /// vertex, index out of range, duplicate face, a face shared by three cells).
  static Connectivity from_mesh_data(const MeshData& mesh);

  /// Copies the structure; the copy has no watchers.
  Connectivity(const Connectivity& o);
  /// Copies the structure; this object's watchers are dropped.
  Connectivity& operator=(const Connectivity& o);
  Connectivity(Connectivity&&) = default;
  Connectivity& operator=(Connectivity&&) = default;

  /// Mesh dimension d (2 or 3).
  int dimension() const { return dim_; }
  /// Number of vertex slots (largest vertex number + 1 ever seen, or as constructed).
  Index num_vertices() const { return static_cast<Index>(vertex_elements_.size()); }
  /// Number of live elements.
  Index num_elements() const { return num_elements_; }
  /// Number of live faces (= (d+1)·num_elements()).
  Index num_faces() const { return num_faces_; }
  /// Number of boundary faces (size of the boundary map).
  Index num_boundary_faces() const { return static_cast<Index>(boundary_.size()); }
  /// Number of edits (replace/change calls) so far; a cheap version stamp for caches.
  std::uint64_t version() const { return version_; }

  /// A new vertex number (num_vertices() before the call) with an empty star.
  Index add_vertex();

  // ---- element and face access (handles must be live; see is_alive) ----

  /// True when `e` refers to a live element of the current generation.
  bool is_alive(ElementHandle e) const;
  /// True when `f` refers to a live face of the current generation.
  bool is_alive(FaceHandle f) const;
  /// The d-simplex represented by element e.
  const Simplex& simplex(ElementHandle e) const;
  /// The (d−1)-simplex represented by face f.
  const Simplex& simplex(FaceHandle f) const;
  /// Face i of element e; its simplex is simplex(e).subn(i) — invariant (7.1).
  FaceHandle face(ElementHandle e, int i) const;
  /// The element owning face f — invariant (7.2).
  ElementHandle element(FaceHandle f) const;
  /// The mate of f (the face −σ of the neighbouring element) or the none-handle on the boundary.
  FaceHandle mate(FaceHandle f) const;
  /// Face of e opposite vertex v (`e.opposite-face(v)`, §7.2). Pre: v ∈ simplex(e).
  FaceHandle opposite_face(ElementHandle e, Index v) const;
  /// Vertex of element(f) not in f (`e.opposite-vertex(f)`, §7.2).
  Index opposite_vertex(FaceHandle f) const;
  /// The d+1 neighbours of e: entry i is the element across face i, or none on the boundary.
  std::array<ElementHandle, 4> neighbours(ElementHandle e) const;
  /// Handle of the live element in slot `index`, or none when the slot is free.
  ElementHandle element_at(Index index) const;
  /// Number of element slots (live and free); iterate 0..element_capacity()−1 with element_at.
  Index element_capacity() const { return static_cast<Index>(elements_.size()); }
  /// All live elements in slot order (the column order of to_mesh_data()).
  std::vector<ElementHandle> elements() const;
  /// Face on the boundary map with simplex σ, or none (`mesh.boundary[σ]`).
  FaceHandle boundary_face(const Simplex& sigma) const;
  /// All boundary faces (the values of the boundary map), in unspecified order.
  std::vector<FaceHandle> boundary() const;

  /// The element representing the d-simplex t (orientation must match), or none. Scans
  /// star(t.vertex(0)): O(|star|).
  ElementHandle find_element(const Simplex& t) const;
  /// The face representing the (d−1)-simplex s (orientation must match), or none. Scans
  /// star(s.vertex(0)): O(|star|·(d+1)).
  FaceHandle find_face(const Simplex& s) const;

  /// star(v) = elements containing vertex v (§7.3), from the vertex→element incidence lists
  /// that every edit maintains (cost O(|star(v)|)). Order unspecified. Empty for unknown v.
  std::vector<ElementHandle> star(Index v) const;
  /// |star(v)| in O(1).
  Index star_size(Index v) const;

  /// cycle-around of §7.2: all elements containing σ = simplex(entry).subn(j) — around an edge
  /// in 3D, around a vertex in 2D — in rotational order (consecutive elements share a face that
  /// contains σ). If σ is interior the list starts at element(entry) and follows the thesis'
  /// walk; if the walk meets the boundary, the other direction is walked too and the list runs
  /// from one boundary face to the other. Cost O(|result|). Pre: 0 ≤ j < d.
  std::vector<ElementHandle> cycle_around(FaceHandle entry, int j) const;
  /// cycle_around for a (d−2)-simplex given by its vertices (edge {a,b} in 3D, vertex {a} in 2D;
  /// orientation ignored). Uses star of the first vertex to find an entry. Empty when no
  /// element contains σ.
  std::vector<ElementHandle> cycle_around(const Simplex& sigma) const;

  // ---- edits (the only writers of mates) ----

  /// replace-elements of §7.3 with face reuse and the matched-pair improvement: removes the
  /// elements `remove` and adds one element per simplex of `add` (each a d-simplex, the face
  /// order of (7.1) is derived from it). Faces whose simplex occurs both among the removed and
  /// the added elements keep their Face handle and mate; new interior face pairs between added
  /// elements are created already mated, without touching the boundary map. Returns the handles
  /// of the new elements in the order of `add`. Throws UsageError, before changing anything, on
  /// a dead or repeated handle in `remove`, a simplex of wrong dimension, or a face simplex that
  /// would be represented twice (among the new faces, or already a boundary face of a kept
  /// element). Other misuse (e.g. re-adding an existing interior element, Figure 7.8) is not
  /// detected here but by validate() — after every edit in paranoid builds.
  std::vector<ElementHandle> replace_elements(const std::vector<ElementHandle>& remove,
                                              const std::vector<Simplex>& add);

  /// change-elements of §7.3: applies a vertex substitution to each listed element keeping the
  /// Element and Face handles (face opposite a becomes the face opposite π(a)); mates and the
  /// boundary map are recomputed for the faces of changed elements. Throws UsageError, before
  /// changing anything, on a dead or repeated handle, a non-injective π, or a resulting face
  /// simplex represented twice.
  void change_elements(const std::vector<ElementChange>& changes);

  /// Convenience: substitute vertex v := w in each element of `elements` (thesis Figure 7.5).
  void substitute_vertex(const std::vector<ElementHandle>& elements, Index v, Index w);

  // ---- watchers (§7.4) ----

  /// Registers `w` (not owned; must outlive its registration) and calls w->init(*this).
  void add_watcher(ConnectivityWatcher* w);
  /// Unregisters `w` (no-op when absent).
  void remove_watcher(ConnectivityWatcher* w);

  // ---- export ----

  /// Cells of the live elements in slot order, (d+1)×m: sorted vertices, with the first two
  /// swapped when the sign is −1, so every column denotes the element's oriented simplex.
  CellMatrix cells() const;
  /// MeshData with `points` (3×n, n ≥ num_vertices()) and cells(); tags are not kept.
  MeshData to_mesh_data(const Eigen::Matrix3Xd& points) const;

 private:
  struct ElementRecord {
    Simplex simplex;
    std::array<Index, 4> faces{{-1, -1, -1, -1}};
    std::uint32_t generation = 0;
    std::uint32_t stamp = 0;
    Index scratch = -1;  // per-edit work slot (change_elements: plan index)
    bool alive = false;
  };
  struct FaceRecord {
    Simplex simplex;
    Index element = -1;
    Index mate = -1;
    std::uint32_t generation = 0;
    std::uint32_t stamp = 0;
    bool alive = false;
  };
  struct BoundaryTouch {
    Simplex simplex;
    Index face;  // face in the map before the edit, −1 when absent
    std::uint32_t generation;
  };

  friend struct ConnectivityTestAccess;  // defined only in property_tests (corruption tests)
  friend class ValidatorAccess;          // validate.cpp reads raw records

  Index check_element(ElementHandle e) const;
  Index check_face(FaceHandle f) const;
  ElementHandle element_handle(Index i) const { return {i, elements_[i].generation}; }
  FaceHandle face_handle(Index i) const { return {i, faces_[i].generation}; }
  Index new_element(const Simplex& s);
  Index new_face(const Simplex& s);
  void free_element(Index e);
  void free_face(Index f);
  void ensure_vertex(Index v);
  void incidence_add(Index e);
  void incidence_remove(Index e);
  void touch_boundary(const Simplex& s);
  void boundary_insert(const Simplex& s, Index f);
  void boundary_erase(const Simplex& s);
  void begin_edit();
  void finish_edit(const std::vector<std::pair<ElementHandle, Simplex>>& removed,
                   const std::vector<Index>& added,
                   const std::vector<std::pair<Index, Simplex>>& changed);
  bool walk(Index e, Index exit_vertex, const Simplex& sigma, Index stop,
            std::vector<ElementHandle>& out) const;

  int dim_;
  std::vector<ElementRecord> elements_;
  std::vector<FaceRecord> faces_;
  std::vector<Index> free_elements_;
  std::vector<Index> free_faces_;
  std::unordered_map<Simplex, Index> boundary_;
  std::vector<std::vector<Index>> vertex_elements_;
  Index num_elements_ = 0;
  Index num_faces_ = 0;
  std::uint32_t stamp_ = 0;
  std::uint64_t version_ = 0;
  std::vector<ConnectivityWatcher*> watchers_;
  std::vector<BoundaryTouch> touched_;
};

}  // namespace incise::mesh
