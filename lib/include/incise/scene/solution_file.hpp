#pragma once
/// \file solution_file.hpp
/// A solution written by `incise run --write-solution FILE` and read back by `--reference FILE`
/// (issue 19: the relative energy-norm error per iteration against an earlier run). Text: a
/// first line `# incise solution: N values (displacement per DOF, m)`, then N lines, one value
/// each, printed with 17 significant digits (so reading gives the doubles back exactly).

#include <incise/core/types.hpp>

#include <string>

namespace incise::scene {

/// Writes u to `path` atomically (core/atomic_file.hpp). Throws ParameterError for a
/// non-finite entry (a non-finite solution is not a reference), Error when the file cannot be
/// written.
void write_solution(const std::string& path, const VecX& u);

/// Reads a file written by write_solution(). Throws ParseError(path, line, what) for a missing
/// file (line 0: the message is then "FILE: ..."), a wrong first line, a line that is not one
/// finite number, or a count that differs from the header's.
VecX read_solution(const std::string& path);

}  // namespace incise::scene
