#include <incise/mesh/validate.hpp>

#include <algorithm>
#include <sstream>

namespace incise::mesh {

std::size_t ValidationReport::count(const std::string& invariant) const {
  return static_cast<std::size_t>(
      std::count_if(violations.begin(), violations.end(),
                    [&](const Violation& v) { return v.invariant == invariant; }));
}

std::string ValidationReport::summary(std::size_t max_lines) const {
  std::ostringstream os;
  if (ok()) return "valid";
  os << violations.size() << (truncated ? "+" : "") << " violation(s)";
  for (std::size_t i = 0; i < violations.size() && i < max_lines; ++i)
    os << "\n[" << violations[i].invariant << "] " << violations[i].message;
  if (violations.size() > max_lines) os << "\n...";
  return os.str();
}

/// Read access to the raw records for validate() (friend of Connectivity).
class ValidatorAccess {
 public:
  ValidatorAccess(const Connectivity& c, const ValidateOptions& o, ValidationReport& r)
      : c_(c), o_(o), r_(r) {}

  // validate_local(): see validate.hpp.
  void run_local(std::vector<Index> elems, std::vector<Index> verts) {
    const int nf = c_.dim_ + 1;
    const Index nv = static_cast<Index>(c_.vertex_elements_.size());
    std::sort(elems.begin(), elems.end());
    elems.erase(std::unique(elems.begin(), elems.end()), elems.end());
    // Faces with simplex s found by scanning star(s.vertex(0)).
    auto faces_with = [&](const Simplex& s, std::vector<Index>& out) {
      out.clear();
      const Index v = s.vertex(0);
      if (v < 0 || v >= nv) return;
      for (Index e : c_.vertex_elements_[static_cast<std::size_t>(v)]) {
        if (!live_e(e)) continue;
        for (int i = 0; i < nf; ++i) {
          const Index g = er(e).faces[static_cast<std::size_t>(i)];
          if (live_f(g) && fr(g).simplex == s) out.push_back(g);
        }
      }
    };
    std::vector<Index> found;
    for (Index e : elems) {
      if (!live_e(e)) continue;
      const ER& t = er(e);
      if (t.simplex.count() != nf) {
        add("simplex", el(e, t.simplex) + " does not have d+1 vertices", {e}, {});
        continue;
      }
      for (int i = 0; i < nf; ++i) {
        const Index v = t.simplex.vertex(i);
        verts.push_back(v);
        const bool listed =
            v < nv && std::find(c_.vertex_elements_[static_cast<std::size_t>(v)].begin(),
                                c_.vertex_elements_[static_cast<std::size_t>(v)].end(),
                                e) != c_.vertex_elements_[static_cast<std::size_t>(v)].end();
        if (!listed)
          add("incidence",
              el(e, t.simplex) + " missing from star list of vertex " + std::to_string(v), {e}, {},
              {v});
      }
      if (t.simplex.vertex(0) < nv)
        for (Index e2 : c_.vertex_elements_[static_cast<std::size_t>(t.simplex.vertex(0))])
          if (e2 != e && live_e(e2) && er(e2).simplex == t.simplex)
            add("7.4",
                "elements " + std::to_string(e) + " and " + std::to_string(e2) +
                    " both represent " + t.simplex.to_string(),
                {e, e2}, {});
      for (int i = 0; i < nf; ++i) {
        const Index f = t.faces[static_cast<std::size_t>(i)];
        if (!live_f(f)) {
          add("7.1",
              el(e, t.simplex) + ": faces[" + std::to_string(i) + "] = " + std::to_string(f) +
                  " is not a live face",
              {e}, {f});
          continue;
        }
        const FR& x = fr(f);
        if (!(x.simplex == t.simplex.subn(i)))
          add("7.1",
              el(e, t.simplex) + ": faces[" + std::to_string(i) + "] is " + fa(f, x.simplex) +
                  ", expected " + t.simplex.subn(i).to_string(),
              {e}, {f});
        if (x.element != e)
          add("7.2",
              el(e, t.simplex) + " lists " + fa(f, x.simplex) + " whose element is " +
                  std::to_string(x.element),
              {e, x.element}, {f});
        faces_with(x.simplex, found);
        for (Index g : found)
          if (g != f)
            add("7.4",
                "faces " + std::to_string(f) + " and " + std::to_string(g) + " both represent " +
                    x.simplex.to_string(),
                {e}, {f, g});
        const bool in_map = c_.boundary_.count(x.simplex) != 0;
        if (x.mate >= 0) {
          if (!live_f(x.mate)) {
            add("7.3", fa(f, x.simplex) + ": mate " + std::to_string(x.mate) + " is not live", {e},
                {f, x.mate});
            continue;
          }
          const FR& m = fr(x.mate);
          if (!(m.simplex == x.simplex.mate()))
            add("7.3", fa(f, x.simplex) + ": mate is " + fa(x.mate, m.simplex), {e}, {f, x.mate});
          if (m.mate != f)
            add("mate-symmetry",
                fa(f, x.simplex) + " has mate " + std::to_string(x.mate) + " whose mate is " +
                    std::to_string(m.mate),
                {e}, {f, x.mate});
          if (!live_e(m.element))
            add("7.2",
                fa(x.mate, m.simplex) + ": element " + std::to_string(m.element) + " is not live",
                {m.element}, {x.mate});
          if (in_map)
            add("boundary-map", "boundary map contains mated " + fa(f, x.simplex), {e}, {f});
        } else {
          const auto it = c_.boundary_.find(x.simplex);
          if (it == c_.boundary_.end() || it->second != f)
            add("boundary-map",
                "mateless " + fa(f, x.simplex) + " is not the boundary map's entry for its simplex",
                {e}, {f});
          faces_with(x.simplex.mate(), found);
          if (!found.empty())
            add("7.5",
                fa(f, x.simplex) + " is mateless although " + fa(found[0], fr(found[0]).simplex) +
                    " exists",
                {e}, {f, found[0]});
        }
      }
    }
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    std::vector<Index> star;
    for (Index v : verts) {
      if (v < 0 || v >= nv) continue;
      const auto& list = c_.vertex_elements_[static_cast<std::size_t>(v)];
      star.clear();
      for (Index e : list) {
        if (!live_e(e) || !er(e).simplex.contains(v))
          add("incidence",
              "star list of vertex " + std::to_string(v) + " holds element " + std::to_string(e) +
                  " which is dead or lacks the vertex",
              {e}, {}, {v});
        else
          star.push_back(e);
      }
      if (o_.check_connected_stars && star.size() > 1) {
        std::vector<Index> seen{star[0]}, stack{star[0]};
        while (!stack.empty()) {
          const Index e = stack.back();
          stack.pop_back();
          for (int i = 0; i < nf; ++i) {
            if (er(e).simplex.vertex(i) == v) continue;
            const Index f = er(e).faces[static_cast<std::size_t>(i)];
            if (!live_f(f) || !live_f(fr(f).mate)) continue;
            const Index n = fr(fr(f).mate).element;
            if (std::find(star.begin(), star.end(), n) == star.end() ||
                std::find(seen.begin(), seen.end(), n) != seen.end())
              continue;
            seen.push_back(n);
            stack.push_back(n);
          }
        }
        if (seen.size() != star.size())
          add("connected-star",
              "star of vertex " + std::to_string(v) + " (" + std::to_string(star.size()) +
                  " elements) is not face-connected",
              std::vector<Index>(star), {}, {v});
      }
    }
    if (o_.positions != nullptr) orientation(&elems);
  }

  void run() {
    elements();
    faces();
    duplicates_and_boundary();
    if (o_.check_incidence) incidence();
    if (o_.check_connected_stars) connected_stars();
    if (o_.positions != nullptr) orientation(nullptr);
    counts();
  }

 private:
  using ER = Connectivity::ElementRecord;
  using FR = Connectivity::FaceRecord;

  bool full() const { return r_.violations.size() >= o_.max_violations; }
  void add(const char* inv, const std::string& msg, std::vector<Index> e, std::vector<Index> f,
           std::vector<Index> v = {}) {
    if (full()) {
      r_.truncated = true;
      return;
    }
    r_.violations.push_back({inv, msg, std::move(e), std::move(f), std::move(v)});
  }
  Index ne() const { return static_cast<Index>(c_.elements_.size()); }
  Index nfc() const { return static_cast<Index>(c_.faces_.size()); }
  bool live_e(Index e) const {
    return e >= 0 && e < ne() && c_.elements_[static_cast<std::size_t>(e)].alive;
  }
  bool live_f(Index f) const {
    return f >= 0 && f < nfc() && c_.faces_[static_cast<std::size_t>(f)].alive;
  }
  const ER& er(Index e) const { return c_.elements_[static_cast<std::size_t>(e)]; }
  const FR& fr(Index f) const { return c_.faces_[static_cast<std::size_t>(f)]; }
  static std::string el(Index e, const Simplex& s) {
    return "element " + std::to_string(e) + " " + s.to_string();
  }
  static std::string fa(Index f, const Simplex& s) {
    return "face " + std::to_string(f) + " " + s.to_string();
  }

  // (7.1) and the well-formedness of element simplices.
  void elements() {
    const int nf = c_.dim_ + 1;
    for (Index e = 0; e < ne(); ++e) {
      const ER& t = er(e);
      if (!t.alive) continue;
      if (t.simplex.count() != nf) {
        add("simplex",
            el(e, t.simplex) + " does not have d+1 = " + std::to_string(nf) + " vertices", {e}, {});
        continue;
      }
      for (int i = 0; i < nf; ++i) {
        const Index f = t.faces[static_cast<std::size_t>(i)];
        if (!live_f(f)) {
          add("7.1",
              el(e, t.simplex) + ": faces[" + std::to_string(i) + "] = " + std::to_string(f) +
                  " is not a live face",
              {e}, {f});
          continue;
        }
        const Simplex want = t.simplex.subn(i);
        if (!(fr(f).simplex == want))
          add("7.1",
              el(e, t.simplex) + ": faces[" + std::to_string(i) + "] is " + fa(f, fr(f).simplex) +
                  ", expected subn(" + std::to_string(i) + ") = " + want.to_string(),
              {e}, {f});
        // (7.2) seen from the element: the face must point back.
        if (fr(f).element != e)
          add("7.2",
              el(e, t.simplex) + " lists " + fa(f, fr(f).simplex) + " whose element is " +
                  std::to_string(fr(f).element),
              {e, fr(f).element}, {f});
      }
    }
  }

  // (7.2), (7.3), mate symmetry.
  void faces() {
    const int nf = c_.dim_ + 1;
    for (Index f = 0; f < nfc(); ++f) {
      const FR& x = fr(f);
      if (!x.alive) continue;
      if (!live_e(x.element)) {
        add("7.2", fa(f, x.simplex) + ": element " + std::to_string(x.element) + " is not live",
            {x.element}, {f});
      } else {
        bool listed = false;
        for (int i = 0; i < nf && i < 4; ++i)
          listed = listed || er(x.element).faces[static_cast<std::size_t>(i)] == f;
        if (!listed)
          add("7.2",
              fa(f, x.simplex) + " is not among the faces of its " +
                  el(x.element, er(x.element).simplex),
              {x.element}, {f});
      }
      if (x.mate < 0) continue;
      if (!live_f(x.mate)) {
        add("7.3", fa(f, x.simplex) + ": mate " + std::to_string(x.mate) + " is not a live face",
            {}, {f, x.mate});
        continue;
      }
      const FR& m = fr(x.mate);
      if (!(m.simplex == x.simplex.mate()))
        add("7.3",
            fa(f, x.simplex) + ": mate is " + fa(x.mate, m.simplex) + ", expected " +
                x.simplex.mate().to_string(),
            {}, {f, x.mate});
      if (m.mate != f)
        add("mate-symmetry",
            fa(f, x.simplex) + " has mate " + std::to_string(x.mate) + " whose mate is " +
                std::to_string(m.mate),
            {}, {f, x.mate});
    }
  }

  // (7.4), (7.5), boundary map. Sorting instead of hashing: in the order of Simplex::operator<
  // equal simplices are adjacent and σ, −σ are neighbours within the run of equal vertex sets.
  void duplicates_and_boundary() {
    std::vector<std::pair<Simplex, Index>> es;
    es.reserve(static_cast<std::size_t>(c_.num_elements_));
    for (Index e = 0; e < ne(); ++e)
      if (er(e).alive) es.emplace_back(er(e).simplex, e);
    std::sort(es.begin(), es.end());
    for (std::size_t i = 1; i < es.size(); ++i)
      if (es[i].first == es[i - 1].first)
        add("7.4",
            "elements " + std::to_string(es[i - 1].second) + " and " +
                std::to_string(es[i].second) + " both represent " + es[i].first.to_string(),
            {es[i - 1].second, es[i].second}, {});

    std::vector<std::pair<Simplex, Index>> fs;
    fs.reserve(static_cast<std::size_t>(c_.num_faces_));
    for (Index f = 0; f < nfc(); ++f)
      if (fr(f).alive) fs.emplace_back(fr(f).simplex, f);
    std::sort(fs.begin(), fs.end());
    for (std::size_t i = 1; i < fs.size(); ++i)
      if (fs[i].first == fs[i - 1].first)
        add("7.4",
            "faces " + std::to_string(fs[i - 1].second) + " and " + std::to_string(fs[i].second) +
                " both represent " + fs[i].first.to_string(),
            {}, {fs[i - 1].second, fs[i].second});
    // (7.5): keys of the map == { σ ∈ faces(T) : −σ ∉ faces(T) }.
    for (std::size_t lo = 0; lo < fs.size();) {
      std::size_t hi = lo + 1;
      while (hi < fs.size() && fs[hi].first.same_vertices(fs[lo].first)) ++hi;
      bool has_neg = false, has_pos = false;
      for (std::size_t i = lo; i < hi; ++i) (fs[i].first.sign() > 0 ? has_pos : has_neg) = true;
      for (std::size_t i = lo; i < hi; ++i) {
        const Simplex& s = fs[i].first;
        const bool is_boundary = s.sign() > 0 ? !has_neg : !has_pos;
        const bool in_map = c_.boundary_.count(s) != 0;
        if (is_boundary && !in_map)
          add("7.5",
              fa(fs[i].second, s) + " is on the boundary of T (" + s.mate().to_string() +
                  " is no face) but not in the boundary map",
              {}, {fs[i].second});
        if (!is_boundary && in_map)
          add("7.5",
              "boundary map contains " + s.to_string() + " although " + s.mate().to_string() +
                  " is a face of the mesh",
              {}, {fs[i].second});
      }
      lo = hi;
    }
    for (const auto& kv : c_.boundary_) {
      const auto it = std::lower_bound(fs.begin(), fs.end(), std::make_pair(kv.first, Index(-1)));
      if (it == fs.end() || !(it->first == kv.first))
        add("7.5", "boundary map key " + kv.first.to_string() + " is not a face of the mesh", {},
            {kv.second});
      // boundary-map: the entry's value is a live mateless face with that simplex.
      const Index f = kv.second;
      if (!live_f(f)) {
        add("boundary-map",
            "boundary map " + kv.first.to_string() + " -> " + std::to_string(f) +
                " which is not a live face",
            {}, {f});
        continue;
      }
      if (!(fr(f).simplex == kv.first))
        add("boundary-map",
            "boundary map " + kv.first.to_string() + " -> " + fa(f, fr(f).simplex) +
                " (simplex differs)",
            {}, {f});
      if (fr(f).mate >= 0)
        add("boundary-map",
            "boundary map " + kv.first.to_string() + " -> " + fa(f, fr(f).simplex) +
                " which has mate " + std::to_string(fr(f).mate),
            {}, {f, fr(f).mate});
    }
    for (Index f = 0; f < nfc(); ++f) {
      if (!fr(f).alive || fr(f).mate >= 0) continue;
      const auto it = c_.boundary_.find(fr(f).simplex);
      if (it == c_.boundary_.end() || it->second != f)
        add("boundary-map",
            "mateless " + fa(f, fr(f).simplex) + " is not the boundary map's entry for its simplex",
            {}, {f});
    }
  }

  // Vertex→element lists agree with the element simplices.
  void incidence() {
    const Index nv = static_cast<Index>(c_.vertex_elements_.size());
    std::vector<Index> expected(static_cast<std::size_t>(nv), 0);
    for (Index e = 0; e < ne(); ++e) {
      if (!er(e).alive) continue;
      const Simplex& s = er(e).simplex;
      for (int i = 0; i < s.count(); ++i) {
        const Index v = s.vertex(i);
        if (v >= nv) {
          add("incidence", el(e, s) + " uses vertex " + std::to_string(v) + " >= num_vertices", {e},
              {}, {v});
          continue;
        }
        ++expected[static_cast<std::size_t>(v)];
        const auto& list = c_.vertex_elements_[static_cast<std::size_t>(v)];
        if (std::find(list.begin(), list.end(), e) == list.end())
          add("incidence", el(e, s) + " missing from star list of vertex " + std::to_string(v), {e},
              {}, {v});
      }
    }
    for (Index v = 0; v < nv; ++v) {
      const auto& list = c_.vertex_elements_[static_cast<std::size_t>(v)];
      if (static_cast<Index>(list.size()) != expected[static_cast<std::size_t>(v)])
        add("incidence",
            "star list of vertex " + std::to_string(v) + " has " + std::to_string(list.size()) +
                " entries, expected " + std::to_string(expected[static_cast<std::size_t>(v)]),
            {}, {}, {v});
    }
  }

  // star(v) is (v, ∅)-connected: one breadth-first search per vertex over faces containing v.
  void connected_stars() {
    // Gather stars from the records themselves (independent of the incidence lists), as CSR.
    const Index nv = static_cast<Index>(c_.vertex_elements_.size());
    std::vector<Index> start(static_cast<std::size_t>(nv) + 1, 0);
    for (Index e = 0; e < ne(); ++e) {
      if (!er(e).alive) continue;
      const Simplex& s = er(e).simplex;
      for (int i = 0; i < s.count(); ++i)
        if (s.vertex(i) >= 0 && s.vertex(i) < nv)
          ++start[static_cast<std::size_t>(s.vertex(i)) + 1];
    }
    for (Index v = 0; v < nv; ++v)
      start[static_cast<std::size_t>(v) + 1] += start[static_cast<std::size_t>(v)];
    std::vector<Index> fill(start.begin(), start.end() - 1);
    std::vector<Index> members(static_cast<std::size_t>(start.back()));
    for (Index e = 0; e < ne(); ++e) {
      if (!er(e).alive) continue;
      const Simplex& s = er(e).simplex;
      for (int i = 0; i < s.count(); ++i)
        if (s.vertex(i) >= 0 && s.vertex(i) < nv)
          members[static_cast<std::size_t>(fill[static_cast<std::size_t>(s.vertex(i))]++)] = e;
    }
    std::vector<std::uint32_t> mark(static_cast<std::size_t>(ne()), 0);
    std::uint32_t stamp = 0;
    std::vector<Index> queue;
    for (Index v = 0; v < nv; ++v) {
      const auto first = members.begin() + start[static_cast<std::size_t>(v)];
      const auto last = members.begin() + start[static_cast<std::size_t>(v) + 1];
      if (last - first <= 1) continue;
      ++stamp;
      for (auto it = first; it != last; ++it)
        mark[static_cast<std::size_t>(*it)] = stamp;  // member of star(v)
      const std::uint32_t seen = ++stamp;
      std::size_t components = 0;
      for (auto it = first; it != last; ++it) {
        const Index root = *it;
        if (mark[static_cast<std::size_t>(root)] == seen) continue;
        ++components;
        queue.assign(1, root);
        mark[static_cast<std::size_t>(root)] = seen;
        while (!queue.empty()) {
          const Index e = queue.back();
          queue.pop_back();
          const ER& t = er(e);
          for (int i = 0; i < t.simplex.count(); ++i) {
            if (t.simplex.vertex(i) == v) continue;  // face opposite v does not contain v
            const Index f = t.faces[static_cast<std::size_t>(i)];
            if (!live_f(f) || !live_f(fr(f).mate)) continue;
            const Index n = fr(fr(f).mate).element;
            if (!live_e(n) || mark[static_cast<std::size_t>(n)] != seen - 1) continue;
            mark[static_cast<std::size_t>(n)] = seen;
            queue.push_back(n);
          }
        }
      }
      if (components > 1) {
        std::vector<Index> elems(first, last);
        add("connected-star",
            "star of vertex " + std::to_string(v) + " (" + std::to_string(elems.size()) +
                " elements) falls into " + std::to_string(components) +
                " face-connected components",
            std::move(elems), {}, {v});
      }
    }
  }

  // Orientation of all elements (only == nullptr) or of the listed ones.
  void orientation(const std::vector<Index>* only) {
    const Eigen::Matrix3Xd& x = *o_.positions;
    const std::size_t n = only ? only->size() : static_cast<std::size_t>(ne());
    for (std::size_t k = 0; k < n; ++k) {
      const Index e = only ? (*only)[k] : static_cast<Index>(k);
      if (!live_e(e)) continue;
      const Simplex& s = er(e).simplex;
      bool in_range = s.count() == c_.dim_ + 1;
      for (int i = 0; i < s.count(); ++i) in_range = in_range && s.vertex(i) < x.cols();
      if (!in_range) {
        add("orientation", el(e, s) + " has a vertex without a position", {e}, {});
        continue;
      }
      double det;
      const Vec3 a = x.col(s.vertex(0));
      if (c_.dim_ == 3) {
        det = (x.col(s.vertex(1)) - a).dot((x.col(s.vertex(2)) - a).cross(x.col(s.vertex(3)) - a));
      } else {
        const Vec3 u = x.col(s.vertex(1)) - a, w = x.col(s.vertex(2)) - a;
        det = u.x() * w.y() - u.y() * w.x();
      }
      det *= s.sign();
      if (!(det > 0.0)) {
        std::ostringstream os;
        os << el(e, s) << " has non-positive signed " << (c_.dim_ == 3 ? "volume" : "area") << " ("
           << det / (c_.dim_ == 3 ? 6.0 : 2.0) << ")";
        add("orientation", os.str(), {e}, {});
      }
    }
  }

  void counts() {
    Index live_e_count = 0, live_f_count = 0;
    for (Index e = 0; e < ne(); ++e) live_e_count += er(e).alive ? 1 : 0;
    for (Index f = 0; f < nfc(); ++f) live_f_count += fr(f).alive ? 1 : 0;
    if (live_e_count != c_.num_elements_ || live_f_count != c_.num_faces_ ||
        live_f_count != live_e_count * (c_.dim_ + 1))
      add("counts",
          "live elements " + std::to_string(live_e_count) + " (cached " +
              std::to_string(c_.num_elements_) + "), live faces " + std::to_string(live_f_count) +
              " (cached " + std::to_string(c_.num_faces_) + ")",
          {}, {});
  }

  const Connectivity& c_;
  const ValidateOptions& o_;
  ValidationReport& r_;
};

ValidationReport validate(const Connectivity& conn, const ValidateOptions& options) {
  ValidationReport report;
  ValidatorAccess(conn, options, report).run();
  return report;
}

ValidationReport validate_local(const Connectivity& conn,
                                const std::vector<ElementHandle>& elements,
                                const std::vector<Index>& vertices,
                                const ValidateOptions& options) {
  ValidationReport report;
  std::vector<Index> elems;
  elems.reserve(elements.size());
  for (const ElementHandle& h : elements)
    if (conn.is_alive(h)) elems.push_back(h.index);
  ValidatorAccess(conn, options, report).run_local(std::move(elems), vertices);
  return report;
}

}  // namespace incise::mesh
