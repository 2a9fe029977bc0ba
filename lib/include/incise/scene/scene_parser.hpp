#pragma once
/// \file scene_parser.hpp
/// Strict reader of scene files (format: docs/scenes.md).
///
/// Every problem throws incise::ParseError whose message names the file, the line (of the
/// offending value; of its key for an object member; of the enclosing object for a missing key),
/// the JSON path and the expected form, e.g.
/// `cantilever.json:6: /material/nu: expected a number in (-1, 0.5), got 0.7`.
/// Rejected: JSON syntax errors (with line and column), unknown keys (with a suggestion when a
/// known key is close), wrong types, missing required keys, out-of-range values, missing mesh
/// files, inconsistent combinations (e.g. a dynamic solver without a density). The parser has
/// no side effects: it only reads the scene and checks that named input files exist.

#include <incise/scene/scene_spec.hpp>

#include <string>

namespace incise::scene {

/// Parses scene text. `file` names the source in messages; relative file paths in the scene
/// (mesh files) are resolved against `base_dir` ("" = current directory).
/// Throws ParseError on any invalid input; returns a fully validated spec otherwise, with the
/// line of every value (SceneSpec::lines) for the builder's messages.
SceneSpec parse_scene(const std::string& text, const std::string& file,
                      const std::string& base_dir);

/// Reads and parses the scene file at `path` (relative paths inside resolved against its
/// folder). Throws ParseError when the file cannot be read or is invalid.
SceneSpec load_scene(const std::string& path);

}  // namespace incise::scene
