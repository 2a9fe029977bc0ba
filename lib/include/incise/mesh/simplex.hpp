#pragma once
/// \file simplex.hpp
/// Canonical oriented abstract simplex (thesis §7.1–7.2).
///
/// An oriented k-simplex p⟨a0,…,ak⟩ is the class of even permutations of its vertex sequence
/// (p = +1) or of odd ones (p = −1). Vertices are totally ordered (here: non-negative integers),
/// so every oriented simplex has the canonical representative (−1)^s sort(a0,…,ak), where s is
/// the number of swaps made while sorting (§7.2). A `Simplex` stores exactly that: the sorted
/// vertices a0 < … < ak and the sign p. Two `Simplex` objects are equal iff they denote the same
/// oriented simplex, so they serve as keys in ordered and hashed maps.
///
/// Sub-simplices follow the boundary operator of §7.1:
///   subsimplex_{aj} ⟨a0,…,ak⟩ = (−1)^j ⟨a0,…,âj,…,ak⟩,
/// hence `subn(j)` of p⟨a0,…,ak⟩ (canonical, sorted) is p·(−1)^j ⟨a0,…,âj,…,ak⟩. With this rule
/// the faces t.subn(0..d) of an element t listed in the order of invariant (7.1) carry the
/// induced (outward) orientation: for a positively oriented tetrahedron (signed volume > 0 of the
/// sequence a0,a1,a2,a3 when p = +1) each face, read as a vertex sequence, has its right-hand
/// normal pointing out of the tetrahedron; likewise in 2D each edge runs counter-clockwise
/// around a positively oriented triangle. The two faces shared by neighbouring elements are
/// mates: σ and −σ (§7.1, "neighbors").
///
/// 0-simplices (single vertices) exist in two orientations (§7.1); their sign is the one given.

#include <incise/core/types.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <iosfwd>
#include <string>

namespace incise::mesh {

/// Canonical oriented simplex of dimension 0..3 (1..4 vertices), thesis §7.2. Value type,
/// 20 bytes, trivially copyable. A default-constructed Simplex is empty (count 0).
class Simplex {
 public:
  /// Maximum number of vertices (a tetrahedron).
  static constexpr int kMaxCount = 4;

  /// The empty simplex (count() == 0, dimension() == −1); only useful as a placeholder.
  Simplex() = default;

  /// The oriented simplex sign·⟨seq[0],…,seq[count−1]⟩, canonicalised by sorting while
  /// counting swaps (§7.2). Pre: 1 ≤ count ≤ 4, vertices ≥ 0 and pairwise distinct, sign = ±1;
  /// throws UsageError otherwise.
  Simplex(const Index* seq, int count, int sign = +1);

  /// Convenience: Simplex({a, b, c, d}, sign).
  Simplex(std::initializer_list<Index> seq, int sign = +1);

  /// Number of vertices k + 1 (`σ.count()` of §7.2).
  int count() const { return count_; }
  /// Dimension k (`σ.dimension()`); −1 for the empty simplex.
  int dimension() const { return count_ - 1; }
  /// Sign p ∈ {−1, +1} of the canonical representative (`σ.sign()`).
  int sign() const { return sign_; }
  /// j-th vertex aj in increasing order (`σ.vertex(j)`). Pre: 0 ≤ j < count().
  Index vertex(int j) const { return v_[static_cast<std::size_t>(j)]; }
  /// Position j with vertex(j) == v (`σ.index(v)`), or −1 when v is not a vertex.
  int index(Index v) const;
  /// True when v is one of the vertices.
  bool contains(Index v) const { return index(v) >= 0; }
  /// The sorted vertex array (entries ≥ count() are −1).
  const std::array<Index, kMaxCount>& vertices() const { return v_; }

  /// The j-th sub-simplex p·(−1)^j ⟨a0,…,âj,…,ak⟩ (`σ.subn(j)`, §7.2). Face j of an element is
  /// its subn(j) — invariant (7.1). Pre: count() ≥ 2, 0 ≤ j < count().
  Simplex subn(int j) const;
  /// subsimplex_v σ = subn(index(v)) (`σ.subv(v)`). Pre: v is a vertex, count() ≥ 2.
  Simplex subv(Index v) const;
  /// The opposite orientation −σ (`σ.mate()`).
  Simplex mate() const;
  /// σ with vertex v replaced by w in the vertex sequence, orientation of the sequence kept
  /// (`σ.substituted(v, w)`). Returns σ unchanged when v is not a vertex. Pre: w ∉ σ (unless
  /// w == v); throws UsageError otherwise.
  Simplex substituted(Index v, Index w) const;
  /// p·⟨v, a0,…,ak⟩, the (k+1)-simplex containing v and σ with σ = sup(v).subv(v)
  /// (`σ.sup(v)`). Pre: v ∉ σ, count() ≤ 3.
  Simplex sup(Index v) const;

  /// Equality of oriented simplices (same vertices and same sign).
  bool operator==(const Simplex& o) const {
    return count_ == o.count_ && sign_ == o.sign_ && v_[0] == o.v_[0] && v_[1] == o.v_[1] &&
           v_[2] == o.v_[2] && v_[3] == o.v_[3];
  }
  bool operator!=(const Simplex& o) const { return !(*this == o); }
  /// True when both have the same vertex set (orientation ignored).
  bool same_vertices(const Simplex& o) const {
    return count_ == o.count_ && v_[0] == o.v_[0] && v_[1] == o.v_[1] && v_[2] == o.v_[2] &&
           v_[3] == o.v_[3];
  }
  /// Total order (`compare` of §7.2): by count, then lexicographically by vertices, then by
  /// sign (−1 before +1), so σ and −σ are adjacent in sorted sequences.
  bool operator<(const Simplex& o) const {
    if (count_ != o.count_) return count_ < o.count_;
    for (std::size_t i = 0; i < static_cast<std::size_t>(kMaxCount); ++i)
      if (v_[i] != o.v_[i]) return v_[i] < o.v_[i];  // unused entries are −1 in both
    return sign_ < o.sign_;
  }

  /// 64-bit hash of (vertices, sign); used by std::hash<Simplex>.
  std::size_t hash() const;

  /// Human-readable form, e.g. "+<0,3,5,7>" or "-<2,9>".
  std::string to_string() const;

 private:
  std::array<Index, kMaxCount> v_{{-1, -1, -1, -1}};
  std::int8_t count_ = 0;
  std::int8_t sign_ = 1;
};

/// Streams Simplex::to_string().
std::ostream& operator<<(std::ostream& os, const Simplex& s);

}  // namespace incise::mesh

namespace std {
/// Hash of a canonical oriented simplex (vertices and sign).
template <>
struct hash<incise::mesh::Simplex> {
  std::size_t operator()(const incise::mesh::Simplex& s) const noexcept { return s.hash(); }
};
}  // namespace std
