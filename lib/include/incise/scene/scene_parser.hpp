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
/// files, inconsistent combinations (e.g. a dynamic solver without a density), and texts beyond
/// the limits below (refused before the JSON parser runs, so that no text can exhaust memory or
/// stack). The parser has no side effects: it only reads the scene and checks that named input
/// files exist.

#include <incise/scene/scene_spec.hpp>

#include <cstddef>
#include <string>

namespace incise::scene {

/// Largest scene text accepted: 16 MiB (shipped scenes are ~1 KiB; a scene names its mesh by
/// file, so nothing large belongs in it). Memory for parsing is linear in the text size.
inline constexpr std::size_t kMaxSceneBytes = std::size_t{16} << 20;

/// Deepest nesting of arrays and objects accepted: 64 levels (the format needs 6, e.g.
/// /outputs/probes/0/region/min/0).
inline constexpr int kMaxSceneDepth = 64;

/// Parses scene text. `file` names the source in messages; relative file paths in the scene
/// (mesh files) are resolved against `base_dir` ("" = current directory).
/// Throws ParseError on any invalid input; returns a fully validated spec otherwise, with the
/// line of every value (SceneSpec::lines) for the builder's messages.
SceneSpec parse_scene(const std::string& text, const std::string& file,
                      const std::string& base_dir);

/// Reads and parses the scene file at `path` (relative paths inside resolved against its
/// folder). Throws ParseError when the file cannot be read, is larger than kMaxSceneBytes (read
/// no further than that) or is invalid.
SceneSpec load_scene(const std::string& path);

}  // namespace incise::scene
