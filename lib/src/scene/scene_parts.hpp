#pragma once
// Parts of the scene parser shared with the Delaunay scene parser (private to the scene module).
#include <incise/scene/scene_spec.hpp>

#include <string>

#include "json_reader.hpp"

namespace incise::scene::detail {

/// The `material` object (docs/scenes.md): model, E, nu, gamma, rho, allow_inversion, each
/// checked as material::validate defines it. `rho_reason` is non-empty when the scene needs a
/// density: then "rho" is required and must be > 0.
MaterialSpec parse_material(JsonObject o, const std::string& rho_reason);

}  // namespace incise::scene::detail
