#pragma once
/// \file sweep_file.hpp
/// Scalpel sweep files (thesis §3.2: a cut is a sequence of sweep triangles, each the area the
/// blade sweeps in one step): the input of `incise cut`, and of any caller that scripts a cut.
///
/// Format (text): one event per line. Nine numbers "ax ay az bx by bz cx cy cz" are one sweep
/// triangle (its three corners, in the mesh file's units); the word `end` ends the current
/// incision (Cutter::end_incision). `#` starts a comment running to the end of the line; blank
/// lines are skipped.

#include <incise/core/types.hpp>

#include <array>
#include <string>
#include <vector>

namespace incise::io {

/// One event of a sweep file.
struct SweepEvent {
  bool end_incision = false;  ///< the line was `end`; `triangle` is unused
  std::array<Vec3, 3> triangle{Vec3::Zero(), Vec3::Zero(),
                               Vec3::Zero()};  ///< corners (file units × scale)
  long line = 0;                               ///< 1-based line in the file
};

/// Reads a sweep file, multiplying every coordinate by `scale` (> 0 and finite). Throws
/// ParseError naming the file, the line and what was expected for anything but the format above
/// (fewer or more than nine numbers on a line, a non-finite number, an unknown word) and for an
/// unreadable file; ParameterError for a bad scale.
std::vector<SweepEvent> read_sweep_file(const std::string& path, double scale = 1.0);

}  // namespace incise::io
