#include <incise/core/error.hpp>
#include <incise/mesh/connectivity.hpp>
#include <incise/mesh/validate.hpp>

#include <algorithm>
#include <numeric>
#include <string>

namespace incise::mesh {

namespace {

std::string handle_text(const char* kind, Index i, std::uint32_t g) {
  return std::string(kind) + " " + std::to_string(i) + " (generation " + std::to_string(g) + ")";
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// construction

Connectivity::Connectivity(int dim, Index num_vertices) : dim_(dim) {
  INCISE_CHECK(dim == 2 || dim == 3, "Connectivity: dimension must be 2 or 3");
  INCISE_CHECK(num_vertices >= 0, "Connectivity: negative vertex count");
  vertex_elements_.resize(static_cast<std::size_t>(num_vertices));
}

Connectivity::Connectivity(const Connectivity& o)
    : dim_(o.dim_),
      elements_(o.elements_),
      faces_(o.faces_),
      free_elements_(o.free_elements_),
      free_faces_(o.free_faces_),
      boundary_(o.boundary_),
      vertex_elements_(o.vertex_elements_),
      num_elements_(o.num_elements_),
      num_faces_(o.num_faces_),
      stamp_(o.stamp_),
      version_(o.version_) {}

Connectivity& Connectivity::operator=(const Connectivity& o) {
  if (this != &o) {
    Connectivity copy(o);
    *this = std::move(copy);
    watchers_.clear();
  }
  return *this;
}

Connectivity Connectivity::from_mesh_data(const MeshData& mesh) {
  const int d = mesh.dimension;
  INCISE_CHECK(d == 2 || d == 3, "from_mesh_data: dimension must be 2 or 3");
  INCISE_CHECK(mesh.cells.rows() == d + 1 || mesh.cells.cols() == 0,
               "from_mesh_data: cells must have dimension+1 rows");
  const Index n = mesh.num_points();
  Connectivity conn(d, n);
  std::vector<Simplex> simplices;
  simplices.reserve(static_cast<std::size_t>(mesh.cells.cols()));
  std::array<Index, 4> seq{};
  for (Eigen::Index c = 0; c < mesh.cells.cols(); ++c) {
    for (int r = 0; r <= d; ++r) {
      seq[static_cast<std::size_t>(r)] = mesh.cells(r, c);
      INCISE_CHECK(seq[static_cast<std::size_t>(r)] >= 0 && seq[static_cast<std::size_t>(r)] < n,
                   "from_mesh_data: cell " + std::to_string(c) + " has vertex index " +
                       std::to_string(seq[static_cast<std::size_t>(r)]) + " outside [0, " +
                       std::to_string(n) + ")");
    }
    simplices.emplace_back(seq.data(), d + 1, +1);
  }
  conn.replace_elements({}, simplices);
  return conn;
}

Index Connectivity::add_vertex() {
  vertex_elements_.emplace_back();
  return static_cast<Index>(vertex_elements_.size()) - 1;
}

void Connectivity::ensure_vertex(Index v) {
  if (v >= num_vertices()) vertex_elements_.resize(static_cast<std::size_t>(v) + 1);
}

// ---------------------------------------------------------------------------------------------
// handles

Index Connectivity::check_element(ElementHandle e) const {
  INCISE_CHECK(e.index >= 0 && e.index < element_capacity() &&
                   elements_[static_cast<std::size_t>(e.index)].alive,
               "dead or invalid " + handle_text("element", e.index, e.generation));
  INCISE_ASSERT(elements_[static_cast<std::size_t>(e.index)].generation == e.generation,
                "stale " + handle_text("element", e.index, e.generation));
  return e.index;
}

Index Connectivity::check_face(FaceHandle f) const {
  INCISE_CHECK(f.index >= 0 && f.index < static_cast<Index>(faces_.size()) &&
                   faces_[static_cast<std::size_t>(f.index)].alive,
               "dead or invalid " + handle_text("face", f.index, f.generation));
  INCISE_ASSERT(faces_[static_cast<std::size_t>(f.index)].generation == f.generation,
                "stale " + handle_text("face", f.index, f.generation));
  return f.index;
}

bool Connectivity::is_alive(ElementHandle e) const {
  return e.index >= 0 && e.index < element_capacity() &&
         elements_[static_cast<std::size_t>(e.index)].alive &&
         elements_[static_cast<std::size_t>(e.index)].generation == e.generation;
}

bool Connectivity::is_alive(FaceHandle f) const {
  return f.index >= 0 && f.index < static_cast<Index>(faces_.size()) &&
         faces_[static_cast<std::size_t>(f.index)].alive &&
         faces_[static_cast<std::size_t>(f.index)].generation == f.generation;
}

const Simplex& Connectivity::simplex(ElementHandle e) const {
  return elements_[static_cast<std::size_t>(check_element(e))].simplex;
}

const Simplex& Connectivity::simplex(FaceHandle f) const {
  return faces_[static_cast<std::size_t>(check_face(f))].simplex;
}

FaceHandle Connectivity::face(ElementHandle e, int i) const {
  const auto& r = elements_[static_cast<std::size_t>(check_element(e))];
  INCISE_CHECK(i >= 0 && i <= dim_, "Connectivity::face: index out of range");
  return face_handle(r.faces[static_cast<std::size_t>(i)]);
}

ElementHandle Connectivity::element(FaceHandle f) const {
  return element_handle(faces_[static_cast<std::size_t>(check_face(f))].element);
}

FaceHandle Connectivity::mate(FaceHandle f) const {
  const Index m = faces_[static_cast<std::size_t>(check_face(f))].mate;
  return m < 0 ? FaceHandle{} : face_handle(m);
}

FaceHandle Connectivity::opposite_face(ElementHandle e, Index v) const {
  const auto& r = elements_[static_cast<std::size_t>(check_element(e))];
  const int i = r.simplex.index(v);
  INCISE_CHECK(i >= 0, "opposite_face: vertex " + std::to_string(v) + " not in element");
  return face_handle(r.faces[static_cast<std::size_t>(i)]);
}

Index Connectivity::opposite_vertex(FaceHandle f) const {
  const auto& fr = faces_[static_cast<std::size_t>(check_face(f))];
  const auto& er = elements_[static_cast<std::size_t>(fr.element)];
  for (int i = 0; i <= dim_; ++i)
    if (er.faces[static_cast<std::size_t>(i)] == f.index) return er.simplex.vertex(i);
  INCISE_CHECK(false, "opposite_vertex: face not listed by its element (invariant 7.2)");
  return -1;
}

std::array<ElementHandle, 4> Connectivity::neighbours(ElementHandle e) const {
  const auto& r = elements_[static_cast<std::size_t>(check_element(e))];
  std::array<ElementHandle, 4> out{};
  for (int i = 0; i <= dim_; ++i) {
    const Index m = faces_[static_cast<std::size_t>(r.faces[static_cast<std::size_t>(i)])].mate;
    if (m >= 0)
      out[static_cast<std::size_t>(i)] =
          element_handle(faces_[static_cast<std::size_t>(m)].element);
  }
  return out;
}

ElementHandle Connectivity::element_at(Index index) const {
  if (index < 0 || index >= element_capacity() || !elements_[static_cast<std::size_t>(index)].alive)
    return {};
  return element_handle(index);
}

std::vector<ElementHandle> Connectivity::elements() const {
  std::vector<ElementHandle> out;
  out.reserve(static_cast<std::size_t>(num_elements_));
  for (Index i = 0; i < element_capacity(); ++i)
    if (elements_[static_cast<std::size_t>(i)].alive) out.push_back(element_handle(i));
  return out;
}

FaceHandle Connectivity::boundary_face(const Simplex& sigma) const {
  const auto it = boundary_.find(sigma);
  return it == boundary_.end() ? FaceHandle{} : face_handle(it->second);
}

std::vector<FaceHandle> Connectivity::boundary() const {
  std::vector<FaceHandle> out;
  out.reserve(boundary_.size());
  for (const auto& kv : boundary_) out.push_back(face_handle(kv.second));
  return out;
}

std::vector<ElementHandle> Connectivity::star(Index v) const {
  std::vector<ElementHandle> out;
  if (v < 0 || v >= num_vertices()) return out;
  const auto& list = vertex_elements_[static_cast<std::size_t>(v)];
  out.reserve(list.size());
  for (Index e : list) out.push_back(element_handle(e));
  return out;
}

ElementHandle Connectivity::find_element(const Simplex& t) const {
  if (t.count() != dim_ + 1 || t.vertex(0) >= num_vertices()) return {};
  for (Index e : vertex_elements_[static_cast<std::size_t>(t.vertex(0))])
    if (elements_[static_cast<std::size_t>(e)].simplex == t) return element_handle(e);
  return {};
}

FaceHandle Connectivity::find_face(const Simplex& s) const {
  if (s.count() != dim_ || s.vertex(0) >= num_vertices()) return {};
  for (Index e : vertex_elements_[static_cast<std::size_t>(s.vertex(0))]) {
    const auto& er = elements_[static_cast<std::size_t>(e)];
    for (int i = 0; i <= dim_; ++i) {
      const Index f = er.faces[static_cast<std::size_t>(i)];
      if (faces_[static_cast<std::size_t>(f)].simplex == s) return face_handle(f);
    }
  }
  return {};
}

Index Connectivity::star_size(Index v) const {
  if (v < 0 || v >= num_vertices()) return 0;
  return static_cast<Index>(vertex_elements_[static_cast<std::size_t>(v)].size());
}

// ---------------------------------------------------------------------------------------------
// cycle-around (§7.2)

// Walks from element e leaving through the face opposite `exit_vertex` (a vertex of e not in
// σ); appends every element entered until the boundary (returns false) or `stop` is re-entered
// (returns true: closed cycle).
bool Connectivity::walk(Index e, Index exit_vertex, const Simplex& sigma, Index stop,
                        std::vector<ElementHandle>& out) const {
  const std::size_t guard = static_cast<std::size_t>(num_elements_) + 1;
  Index x = exit_vertex;
  for (std::size_t steps = 0; steps < guard; ++steps) {
    const auto& er = elements_[static_cast<std::size_t>(e)];
    const Index fi = er.faces[static_cast<std::size_t>(er.simplex.index(x))];
    const auto& fr = faces_[static_cast<std::size_t>(fi)];
    // The exit face contains σ and exactly one other vertex u; u is the next exit vertex.
    Index u = -1;
    for (int i = 0; i < fr.simplex.count(); ++i)
      if (!sigma.contains(fr.simplex.vertex(i))) u = fr.simplex.vertex(i);
    if (fr.mate < 0) return false;
    e = faces_[static_cast<std::size_t>(fr.mate)].element;
    if (e == stop) return true;
    out.push_back(element_handle(e));
    x = u;
  }
  return false;  // only reachable on a corrupt structure (more steps than elements)
}

std::vector<ElementHandle> Connectivity::cycle_around(FaceHandle entry, int j) const {
  const Index fi = check_face(entry);
  INCISE_CHECK(j >= 0 && j < dim_, "cycle_around: j must be in 0..d-1");
  const auto& fr = faces_[static_cast<std::size_t>(fi)];
  const Simplex sigma = fr.simplex.subn(j);
  const Index e0 = fr.element;
  const Index v = fr.simplex.vertex(j);  // vertex of entry not in σ
  const Index w = opposite_vertex(entry);
  // Thesis walk: enter through the face containing v, leave through opposite-face(v).
  std::vector<ElementHandle> forward{element_handle(e0)};
  if (walk(e0, v, sigma, e0, forward)) return forward;  // closed cycle around interior σ
  std::vector<ElementHandle> backward;
  walk(e0, w, sigma, e0, backward);
  std::vector<ElementHandle> out(backward.rbegin(), backward.rend());
  out.insert(out.end(), forward.begin(), forward.end());
  return out;
}

std::vector<ElementHandle> Connectivity::cycle_around(const Simplex& sigma) const {
  INCISE_CHECK(sigma.count() == dim_ - 1,
               "cycle_around: need a (d-2)-simplex (vertex in 2D, edge in 3D)");
  const Index a = sigma.vertex(0);
  if (a < 0 || a >= num_vertices()) return {};
  for (Index e : vertex_elements_[static_cast<std::size_t>(a)]) {
    const auto& er = elements_[static_cast<std::size_t>(e)];
    bool all = true;
    for (int i = 0; i < sigma.count(); ++i) all = all && er.simplex.contains(sigma.vertex(i));
    if (!all) continue;
    // The two vertices p, q of e not in σ; entry = face opposite p (contains σ and q).
    Index p = -1, q = -1;
    for (int i = 0; i <= dim_; ++i) {
      const Index x = er.simplex.vertex(i);
      if (sigma.contains(x)) continue;
      (p < 0 ? p : q) = x;
    }
    const Index fi = er.faces[static_cast<std::size_t>(er.simplex.index(p))];
    const int j = faces_[static_cast<std::size_t>(fi)].simplex.index(q);
    return cycle_around(face_handle(fi), j);
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// record management

Index Connectivity::new_element(const Simplex& s) {
  Index e;
  if (!free_elements_.empty()) {
    e = free_elements_.back();
    free_elements_.pop_back();
  } else {
    e = static_cast<Index>(elements_.size());
    elements_.emplace_back();
  }
  auto& r = elements_[static_cast<std::size_t>(e)];
  r.simplex = s;
  r.alive = true;
  r.faces = {{-1, -1, -1, -1}};
  ++num_elements_;
  return e;
}

Index Connectivity::new_face(const Simplex& s) {
  Index f;
  if (!free_faces_.empty()) {
    f = free_faces_.back();
    free_faces_.pop_back();
  } else {
    f = static_cast<Index>(faces_.size());
    faces_.emplace_back();
  }
  auto& r = faces_[static_cast<std::size_t>(f)];
  r.simplex = s;
  r.alive = true;
  r.element = -1;
  r.mate = -1;
  ++num_faces_;
  return f;
}

void Connectivity::free_element(Index e) {
  auto& r = elements_[static_cast<std::size_t>(e)];
  r.alive = false;
  ++r.generation;
  free_elements_.push_back(e);
  --num_elements_;
}

void Connectivity::free_face(Index f) {
  auto& r = faces_[static_cast<std::size_t>(f)];
  r.alive = false;
  r.mate = -1;
  r.element = -1;
  ++r.generation;
  free_faces_.push_back(f);
  --num_faces_;
}

void Connectivity::incidence_add(Index e) {
  const auto& s = elements_[static_cast<std::size_t>(e)].simplex;
  for (int i = 0; i < s.count(); ++i) {
    ensure_vertex(s.vertex(i));
    vertex_elements_[static_cast<std::size_t>(s.vertex(i))].push_back(e);
  }
}

void Connectivity::incidence_remove(Index e) {
  const auto& s = elements_[static_cast<std::size_t>(e)].simplex;
  for (int i = 0; i < s.count(); ++i) {
    auto& list = vertex_elements_[static_cast<std::size_t>(s.vertex(i))];
    const auto it = std::find(list.begin(), list.end(), e);
    if (it != list.end()) {
      *it = list.back();
      list.pop_back();
    }
  }
}

void Connectivity::touch_boundary(const Simplex& s) {
  if (watchers_.empty()) return;
  const auto it = boundary_.find(s);
  if (it == boundary_.end())
    touched_.push_back({s, -1, 0});
  else
    touched_.push_back({s, it->second, faces_[static_cast<std::size_t>(it->second)].generation});
}

void Connectivity::boundary_insert(const Simplex& s, Index f) {
  touch_boundary(s);
  boundary_[s] = f;
}

void Connectivity::boundary_erase(const Simplex& s) {
  touch_boundary(s);
  boundary_.erase(s);
}

void Connectivity::begin_edit() {
  ++stamp_;
  touched_.clear();
}

void Connectivity::finish_edit(const std::vector<std::pair<ElementHandle, Simplex>>& removed,
                               const std::vector<Index>& added,
                               const std::vector<std::pair<Index, Simplex>>& changed) {
  ++version_;
#if defined(INCISE_PARANOID)
  {
    ValidationReport report;
    if (num_elements_ <= kParanoidFullValidationLimit) {
      report = validate(*this, paranoid_validate_options());
    } else {
      // Large mesh: check the stars of every vertex of a removed, added or changed simplex.
      std::vector<Index> verts;
      auto take = [&](const Simplex& t) {
        for (int i = 0; i < t.count(); ++i) verts.push_back(t.vertex(i));
      };
      for (const auto& r : removed) take(r.second);
      for (Index e : added) take(elements_[static_cast<std::size_t>(e)].simplex);
      for (const auto& c : changed) {
        take(c.second);
        take(elements_[static_cast<std::size_t>(c.first)].simplex);
      }
      std::sort(verts.begin(), verts.end());
      verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
      std::vector<ElementHandle> around;
      for (Index v : verts)
        for (Index e : vertex_elements_[static_cast<std::size_t>(v)])
          around.push_back(element_handle(e));
      report = validate_local(*this, around, verts, paranoid_validate_options());
    }
    if (!report.ok())
      throw UsageError("mesh connectivity invalid after edit " + std::to_string(version_) + ":\n" +
                       report.summary());
  }
#endif
  if (watchers_.empty()) return;
  // Net boundary changes: first recorded state per simplex versus the final state.
  std::stable_sort(
      touched_.begin(), touched_.end(),
      [](const BoundaryTouch& a, const BoundaryTouch& b) { return a.simplex < b.simplex; });
  std::vector<std::pair<FaceHandle, Simplex>> b_removed;
  std::vector<FaceHandle> b_added;
  for (std::size_t i = 0; i < touched_.size(); ++i) {
    if (i > 0 && touched_[i].simplex == touched_[i - 1].simplex) continue;
    const BoundaryTouch& t = touched_[i];
    const auto it = boundary_.find(t.simplex);
    const bool post = it != boundary_.end();
    const bool same = post && t.face == it->second &&
                      faces_[static_cast<std::size_t>(it->second)].generation == t.generation;
    if (t.face >= 0 && !same) b_removed.push_back({FaceHandle{t.face, t.generation}, t.simplex});
    if (post && !same) b_added.push_back(face_handle(it->second));
  }
  touched_.clear();
  for (ConnectivityWatcher* w : watchers_) {
    for (const auto& r : removed) w->element_removed(*this, r.first, r.second);
    for (const auto& r : b_removed) w->boundary_removed(*this, r.first, r.second);
    for (Index e : added) w->element_added(*this, element_handle(e));
    for (const auto& c : changed) w->element_changed(*this, element_handle(c.first), c.second);
    for (FaceHandle f : b_added) w->boundary_added(*this, f);
  }
}

// ---------------------------------------------------------------------------------------------
// replace-elements (§7.3)

std::vector<ElementHandle> Connectivity::replace_elements(const std::vector<ElementHandle>& remove,
                                                          const std::vector<Simplex>& add) {
  begin_edit();
  const int nf = dim_ + 1;

  // --- checks (nothing is modified except per-edit stamps) ---
  for (const ElementHandle& h : remove) {
    const Index e = check_element(h);
    auto& er = elements_[static_cast<std::size_t>(e)];
    INCISE_CHECK(er.stamp != stamp_,
                 "replace_elements: element " + std::to_string(e) + " listed twice for removal");
    er.stamp = stamp_;
  }
  for (const Simplex& t : add) {
    INCISE_CHECK(t.count() == nf, "replace_elements: simplex " + t.to_string() +
                                      " has wrong dimension for a " + std::to_string(dim_) +
                                      "D mesh");
  }

  // oldfacemap: faces of removed elements, sorted by simplex.
  struct OldFace {
    Simplex simplex;
    Index face;
    bool used;
  };
  std::vector<OldFace> old;
  old.reserve(remove.size() * static_cast<std::size_t>(nf));
  for (const ElementHandle& h : remove)
    for (int i = 0; i < nf; ++i) {
      const Index f =
          elements_[static_cast<std::size_t>(h.index)].faces[static_cast<std::size_t>(i)];
      old.push_back({faces_[static_cast<std::size_t>(f)].simplex, f, false});
    }
  std::sort(old.begin(), old.end(),
            [](const OldFace& a, const OldFace& b) { return a.simplex < b.simplex; });

  // newfacemap: one entry per (new simplex, slot); face = reused old face or −1.
  struct NewFace {
    Simplex simplex;
    Index face;
  };
  std::vector<NewFace> fresh;
  fresh.reserve(add.size() * static_cast<std::size_t>(nf));
  for (const Simplex& t : add)
    for (int j = 0; j < nf; ++j) {
      const Simplex s = t.subn(j);
      Index f = -1;
      const auto it =
          std::lower_bound(old.begin(), old.end(), s,
                           [](const OldFace& a, const Simplex& b) { return a.simplex < b; });
      if (it != old.end() && it->simplex == s) {
        f = it->face;
        it->used = true;
      }
      fresh.push_back({s, f});
    }
  std::vector<Index> order(fresh.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](Index a, Index b) {
    return fresh[static_cast<std::size_t>(a)].simplex < fresh[static_cast<std::size_t>(b)].simplex;
  });
  for (std::size_t k = 1; k < order.size(); ++k) {
    const Simplex& a = fresh[static_cast<std::size_t>(order[k - 1])].simplex;
    INCISE_CHECK(!(a == fresh[static_cast<std::size_t>(order[k])].simplex),
                 "replace_elements: face " + a.to_string() +
                     " would be represented twice among the new elements (invariant 7.4)");
  }
  for (const NewFace& nfc : fresh)
    if (nfc.face < 0)
      INCISE_CHECK(boundary_.find(nfc.simplex) == boundary_.end(),
                   "replace_elements: face " + nfc.simplex.to_string() +
                       " is already a boundary face of a kept element (invariant 7.4)");

  // --- mutation ---
  for (const OldFace& o : old)
    if (o.used) faces_[static_cast<std::size_t>(o.face)].stamp = stamp_;  // reused

  // Discarded faces: release their mates to the boundary; unmated ones leave the boundary.
  for (const OldFace& o : old) {
    if (o.used) continue;
    auto& fr = faces_[static_cast<std::size_t>(o.face)];
    const Index g = fr.mate;
    if (g >= 0) {
      auto& gr = faces_[static_cast<std::size_t>(g)];
      const bool g_discarded =
          elements_[static_cast<std::size_t>(gr.element)].stamp == stamp_ && gr.stamp != stamp_;
      if (!g_discarded) {
        gr.mate = -1;
        boundary_insert(gr.simplex, g);
      }
    } else {
      boundary_erase(fr.simplex);
    }
  }

  std::vector<std::pair<ElementHandle, Simplex>> removed;
  removed.reserve(remove.size());
  for (const ElementHandle& h : remove) {
    removed.push_back({h, elements_[static_cast<std::size_t>(h.index)].simplex});
    incidence_remove(h.index);
    free_element(h.index);
  }
  for (const OldFace& o : old)
    if (!o.used) free_face(o.face);

  // Matched pairs (§7.3): σ and −σ both new → create them mated, boundary untouched.
  for (std::size_t k = 1; k < order.size(); ++k) {
    NewFace& a = fresh[static_cast<std::size_t>(order[k - 1])];
    NewFace& b = fresh[static_cast<std::size_t>(order[k])];
    if (a.face < 0 && b.face < 0 && a.simplex.same_vertices(b.simplex)) {
      a.face = new_face(a.simplex);
      b.face = new_face(b.simplex);
      faces_[static_cast<std::size_t>(a.face)].mate = b.face;
      faces_[static_cast<std::size_t>(b.face)].mate = a.face;
    }
  }

  std::vector<Index> added;
  added.reserve(add.size());
  std::vector<ElementHandle> result;
  result.reserve(add.size());
  for (std::size_t t = 0; t < add.size(); ++t) {
    const Index e = new_element(add[t]);
    for (int j = 0; j < nf; ++j) {
      NewFace& nfc = fresh[t * static_cast<std::size_t>(nf) + static_cast<std::size_t>(j)];
      Index f = nfc.face;
      if (f < 0) {
        f = new_face(nfc.simplex);
        const Simplex m = nfc.simplex.mate();
        const auto it = boundary_.find(m);
        if (it != boundary_.end()) {
          const Index g = it->second;
          faces_[static_cast<std::size_t>(f)].mate = g;
          faces_[static_cast<std::size_t>(g)].mate = f;
          boundary_erase(m);
        } else {
          boundary_insert(nfc.simplex, f);
        }
      }
      faces_[static_cast<std::size_t>(f)].element = e;
      elements_[static_cast<std::size_t>(e)].faces[static_cast<std::size_t>(j)] = f;
    }
    incidence_add(e);
    added.push_back(e);
    result.push_back(element_handle(e));
  }
  finish_edit(removed, added, {});
  return result;
}

// ---------------------------------------------------------------------------------------------
// change-elements (§7.3)

void Connectivity::change_elements(const std::vector<ElementChange>& changes) {
  begin_edit();
  const int nf = dim_ + 1;
  struct Plan {
    Index e;
    Simplex old_simplex;
    Simplex new_simplex;
    std::array<Index, 4> new_faces;  // new_faces[j'] = face now at slot j'
  };
  std::vector<Plan> plan;
  plan.reserve(changes.size());
  for (const ElementChange& c : changes) {
    const Index e = check_element(c.element);
    auto& er = elements_[static_cast<std::size_t>(e)];
    INCISE_CHECK(er.stamp != stamp_,
                 "change_elements: element " + std::to_string(e) + " listed twice");
    er.stamp = stamp_;
    const Simplex& t = er.simplex;
    // π applied to the sorted sequence (a0..ad) keeps the sequence's orientation p.
    const Simplex tn(c.new_vertices.data(), nf, t.sign());  // throws if π not injective
    Plan p{e, t, tn, {{-1, -1, -1, -1}}};
    for (int i = 0; i < nf; ++i) {
      const int jn = tn.index(c.new_vertices[static_cast<std::size_t>(i)]);
      p.new_faces[static_cast<std::size_t>(jn)] = er.faces[static_cast<std::size_t>(i)];
    }
    plan.push_back(p);
  }
  std::vector<Simplex> all, moved;  // all new face simplices; those that differ from the old
  all.reserve(plan.size() * static_cast<std::size_t>(nf));
  for (const Plan& p : plan)
    for (int j = 0; j < nf; ++j) {
      all.push_back(p.new_simplex.subn(j));
      if (!(all.back() ==
            faces_[static_cast<std::size_t>(p.new_faces[static_cast<std::size_t>(j)])].simplex))
        moved.push_back(all.back());
    }
  std::sort(all.begin(), all.end());
  for (std::size_t k = 1; k < all.size(); ++k)
    INCISE_CHECK(!(all[k - 1] == all[k]), "change_elements: face " + all[k].to_string() +
                                              " would be represented twice (invariant 7.4)");
  // An unchanged face simplex cannot collide with a kept face (7.4 held before the edit).
  for (const Simplex& s : moved) {
    const auto it = boundary_.find(s);
    INCISE_CHECK(it == boundary_.end() ||
                     elements_[static_cast<std::size_t>(
                                   faces_[static_cast<std::size_t>(it->second)].element)]
                             .stamp == stamp_,
                 "change_elements: face " + s.to_string() +
                     " is already a boundary face of an unchanged element (invariant 7.4)");
  }

  // --- mutation ---
  // Improvement over the thesis' change-elements (which detaches every face and re-inserts it
  // through the boundary map, "spurious updates", §7.5): a face keeps its mate when the mate's
  // new simplex is still the opposite of its own (both unchanged, or both changed consistently,
  // e.g. faces through v when substituting v := w over a whole class), and a boundary face whose
  // simplex does not change stays in the boundary map. Only the remaining faces go through the
  // boundary map.
  for (std::size_t k = 0; k < plan.size(); ++k)
    elements_[static_cast<std::size_t>(plan[k].e)].scratch = static_cast<Index>(k);
  auto new_simplex_of = [&](Index f) {
    const Plan& p = plan[static_cast<std::size_t>(
        elements_[static_cast<std::size_t>(faces_[static_cast<std::size_t>(f)].element)].scratch)];
    for (int j = 0; j < nf; ++j)
      if (p.new_faces[static_cast<std::size_t>(j)] == f) return p.new_simplex.subn(j);
    return Simplex();
  };
  enum Action : char { kKeep, kRelease, kUnmate, kLeaveBoundary };
  std::vector<Action> action(plan.size() * static_cast<std::size_t>(nf), kKeep);
  std::vector<Index> old_mate(action.size(), -1);
  for (std::size_t k = 0; k < plan.size(); ++k)
    for (int j = 0; j < nf; ++j) {
      const std::size_t slot = k * static_cast<std::size_t>(nf) + static_cast<std::size_t>(j);
      const Index f = plan[k].new_faces[static_cast<std::size_t>(j)];
      const FaceRecord& fr = faces_[static_cast<std::size_t>(f)];
      const Simplex sn = plan[k].new_simplex.subn(j);
      const Index g = fr.mate;
      old_mate[slot] = g;
      if (g >= 0) {
        const bool g_changed =
            elements_[static_cast<std::size_t>(faces_[static_cast<std::size_t>(g)].element)]
                .stamp == stamp_;
        if (g_changed)
          action[slot] = new_simplex_of(g) == sn.mate() ? kKeep : kUnmate;
        else
          action[slot] = sn == fr.simplex ? kKeep : kRelease;
      } else {
        action[slot] = sn == fr.simplex ? kKeep : kLeaveBoundary;
      }
    }
  for (std::size_t k = 0; k < plan.size(); ++k)
    for (int j = 0; j < nf; ++j) {
      const std::size_t slot = k * static_cast<std::size_t>(nf) + static_cast<std::size_t>(j);
      const Index f = plan[k].new_faces[static_cast<std::size_t>(j)];
      auto& fr = faces_[static_cast<std::size_t>(f)];
      const Index g = old_mate[slot];
      switch (action[slot]) {
        case kKeep: break;
        case kRelease:
          fr.mate = -1;
          faces_[static_cast<std::size_t>(g)].mate = -1;
          boundary_insert(faces_[static_cast<std::size_t>(g)].simplex, g);
          break;
        case kUnmate:
          fr.mate = -1;
          faces_[static_cast<std::size_t>(g)].mate = -1;
          break;
        case kLeaveBoundary: {
          const auto it = boundary_.find(fr.simplex);
          if (it != boundary_.end() && it->second == f) boundary_erase(fr.simplex);
          break;
        }
      }
    }
  // Relabel elements and faces.
  std::vector<std::pair<Index, Simplex>> changed;
  changed.reserve(plan.size());
  for (const Plan& p : plan) {
    incidence_remove(p.e);
    auto& er = elements_[static_cast<std::size_t>(p.e)];
    er.simplex = p.new_simplex;
    for (int j = 0; j < nf; ++j) {
      const Index f = p.new_faces[static_cast<std::size_t>(j)];
      er.faces[static_cast<std::size_t>(j)] = f;
      faces_[static_cast<std::size_t>(f)].simplex = p.new_simplex.subn(j);
    }
    incidence_add(p.e);
    changed.push_back({p.e, p.old_simplex});
  }
  // Re-attach the detached faces: mate with a boundary face −σ' or enter the boundary map.
  for (std::size_t k = 0; k < plan.size(); ++k)
    for (int j = 0; j < nf; ++j) {
      const std::size_t slot = k * static_cast<std::size_t>(nf) + static_cast<std::size_t>(j);
      if (action[slot] == kKeep) continue;
      const Index f = plan[k].new_faces[static_cast<std::size_t>(j)];
      const Simplex s = faces_[static_cast<std::size_t>(f)].simplex;
      const auto it = boundary_.find(s.mate());
      if (it != boundary_.end()) {
        const Index g = it->second;
        faces_[static_cast<std::size_t>(f)].mate = g;
        faces_[static_cast<std::size_t>(g)].mate = f;
        boundary_erase(s.mate());
      } else {
        boundary_insert(s, f);
      }
    }
  finish_edit({}, {}, changed);
}

void Connectivity::substitute_vertex(const std::vector<ElementHandle>& elements, Index v, Index w) {
  std::vector<ElementChange> changes;
  changes.reserve(elements.size());
  for (const ElementHandle& h : elements) {
    const Simplex& s = simplex(h);
    ElementChange c{h, {{-1, -1, -1, -1}}};
    for (int i = 0; i < s.count(); ++i)
      c.new_vertices[static_cast<std::size_t>(i)] = s.vertex(i) == v ? w : s.vertex(i);
    changes.push_back(c);
  }
  change_elements(changes);
}

// ---------------------------------------------------------------------------------------------
// watchers and export

void Connectivity::add_watcher(ConnectivityWatcher* w) {
  INCISE_CHECK(w != nullptr, "add_watcher: null watcher");
  if (std::find(watchers_.begin(), watchers_.end(), w) == watchers_.end()) watchers_.push_back(w);
  w->init(*this);
}

void Connectivity::remove_watcher(ConnectivityWatcher* w) {
  watchers_.erase(std::remove(watchers_.begin(), watchers_.end(), w), watchers_.end());
}

CellMatrix Connectivity::cells() const {
  CellMatrix c(dim_ + 1, num_elements_);
  Eigen::Index col = 0;
  for (const auto& r : elements_) {
    if (!r.alive) continue;
    for (int i = 0; i <= dim_; ++i) c(i, col) = r.simplex.vertex(i);
    if (r.simplex.sign() < 0) std::swap(c(0, col), c(1, col));
    ++col;
  }
  return c;
}

MeshData Connectivity::to_mesh_data(const Eigen::Matrix3Xd& points) const {
  INCISE_CHECK(points.cols() >= num_vertices(), "to_mesh_data: fewer points than vertices");
  MeshData m;
  m.dimension = dim_;
  m.points = points;
  m.cells = cells();
  return m;
}

}  // namespace incise::mesh
