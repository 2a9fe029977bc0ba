#pragma once
/// \file scene_errors.hpp
/// The scene parser's error for a scene text, as the scene property tests compare it: one
/// definition for every suite that checks a message (parser, error lines, limits).

#include <incise/core/error.hpp>
#include <incise/scene/scene_parser.hpp>

#include <string>

namespace incise::test {

/// parse_scene(text) as file "scene.json" with no base folder: the ParseError's message
/// ("scene.json:<line>: <path>: expected …"), or "<no error>" when the text parses.
inline std::string scene_parse_error(const std::string& text) {
  try {
    (void)scene::parse_scene(text, "scene.json", "");
  } catch (const ParseError& e) {
    return e.what();
  }
  return "<no error>";
}

}  // namespace incise::test
