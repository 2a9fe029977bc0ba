#pragma once
/// \file validate.hpp
/// Checker for the invariants of the mesh connectivity (thesis §7.2–7.3, §7.5: "Conditions
/// (7.1) to (7.5) can be checked automatically in a validation routine").
///
/// validate() never throws or aborts on a corrupt structure: every index read from the records
/// is range-checked first, and each violation is reported with the invariant's name and the
/// objects (element slots, face slots, vertices) involved. Invariant names:
///  - "7.1"  face i of element t is live and represents t.simplex.subn(i);
///  - "7.2"  the element of face f is live and lists f among its faces;
///  - "7.3"  f.mate is none, or a live face with simplex −f.simplex;
///  - "mate-symmetry"  f.mate = g implies g.mate = f;
///  - "7.4"  no two live Elements (Faces) represent the same simplex;
///  - "7.5"  the keys of the boundary map are exactly the face simplices σ with −σ ∉ faces(T);
///  - "boundary-map"  every map entry σ ↦ f has f live, f.simplex = σ and no mate, and every
///            mateless face is in the map under its simplex;
///  - "connected-star"  star(v) is (v, ∅)-connected for every vertex v (§7.3, end);
///  - "orientation"  (optional, with positions) every element has positive signed volume (3D)
///            or area in the xy-plane (2D) in the reference configuration;
///  - "simplex"  an element's simplex has d+1 vertices (well-formed record);
///  - "incidence"  the vertex→element lists (used by star()) agree with the elements;
///  - "counts"  the cached element/face counts agree with the live records.
/// Cost: O((d+1)·#elements) hash-map work plus O(Σ_v |star(v)|) for connected stars.

#include <incise/mesh/connectivity.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace incise::mesh {

/// One violated invariant and the objects involved (slot indices; vertices by number).
struct Violation {
  std::string invariant;        ///< "7.1" … "7.5", "mate-symmetry", "boundary-map", …
  std::string message;          ///< human-readable description naming the objects
  std::vector<Index> elements;  ///< element slots involved
  std::vector<Index> faces;     ///< face slots involved
  std::vector<Index> vertices;  ///< vertices involved
};

/// Result of validate(): every violation found (up to ValidateOptions::max_violations).
struct [[nodiscard]] ValidationReport {
  std::vector<Violation> violations;  ///< empty when the structure is valid
  bool truncated = false;             ///< true when max_violations was reached

  /// True when no invariant is violated.
  bool ok() const { return violations.empty(); }
  /// Number of violations of the named invariant.
  std::size_t count(const std::string& invariant) const;
  /// True when at least one violation of the named invariant was found.
  bool has(const std::string& invariant) const { return count(invariant) > 0; }
  /// One line per violation: "[7.3] face 12 +<1,2,5>: mate 40 has simplex …".
  std::string summary(std::size_t max_lines = 20) const;
};

/// Which checks validate() performs.
struct ValidateOptions {
  bool check_connected_stars = true;  ///< "connected-star" (§7.3); O(Σ|star(v)|)
  bool check_incidence = true;        ///< "incidence": vertex→element lists
  /// If non-null, check "orientation" using these reference positions (3×n, n ≥ vertices).
  const Eigen::Matrix3Xd* positions = nullptr;
  std::size_t max_violations = 100000;  ///< stop collecting after this many
};

/// The checks run after every edit in paranoid builds: all structural invariants, but not
/// connected stars or orientation (legitimate intermediate edits, e.g. removing elements, may
/// pinch a star; orientation needs positions).
inline ValidateOptions paranoid_validate_options() {
  ValidateOptions o;
  o.check_connected_stars = false;
  return o;
}

/// Checks every invariant listed in the file comment; never throws on a corrupt structure.
ValidationReport validate(const Connectivity& conn, const ValidateOptions& options = {});

/// Local validation around an edit: the checks of validate() restricted to `elements` (dead
/// handles are skipped), their faces and those faces' mates, and to the vertices of `elements`
/// plus `vertices` (incidence lists, connected stars). Duplicates (7.4) and the "−σ is a face"
/// test of (7.5) are found by scanning the star of a face's first vertex, so they rely on the
/// incidence lists. Cost O(Σ_v |star(v)|·(d+1)²) over the involved vertices — independent of the
/// mesh size. It cannot see violations away from the given objects; validate() can.
ValidationReport validate_local(const Connectivity& conn,
                                const std::vector<ElementHandle>& elements,
                                const std::vector<Index>& vertices = {},
                                const ValidateOptions& options = {});

/// Paranoid builds run the full validate() after an edit while the mesh has at most this many
/// elements, and validate_local() over the stars of every vertex the edit touched above it.
/// 4,096: unit-test meshes are validated whole after every edit; organ meshes (the 16,597-tet
/// liver) locally, which keeps long random edit sequences on them linear (docs/ci.md).
constexpr Index kParanoidFullValidationLimit = 4096;

}  // namespace incise::mesh
