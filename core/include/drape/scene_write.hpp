// Writing scenes: a SceneSpec (and optionally the state of a running simulation) as a scene file that parse_scene
// reads back to the same spec (docs/scene_format.md). Every field is written explicitly; numbers are written so that
// they read back to the same float bits (shortest form that round-trips, else max_digits10 digits).
#pragma once

#include <string>

#include "drape/scene.hpp" // SceneSpec, SceneState
#include "drape/simulation.hpp"

namespace drape {

// SceneState (positions, velocities and pinned particles to save with a scene) is declared in scene.hpp, beside the
// SceneSpec that holds it.

/// The scene as JSON text in the format parse_scene reads (docs/scene_format.md), every field written explicitly;
/// with a state, a "state" section so build_scene starts from it. A mesh cloth's file is written as its absolute
/// path (save_scene writes it relative to the saved file). Throws InvalidInput for what the format cannot express
/// (a rotated ellipsoid collider, a state whose arrays differ in length).
std::string scene_to_json(const SceneSpec& spec, const SceneState* state = nullptr);

/// Writes scene_to_json to path atomically (temp file + rename). Before writing, the text is read back with
/// parse_scene, so a file that would not load is never written (InvalidInput with parse_scene's message); a text
/// over scene_file_max_bytes (a large cloth's state) is refused first, saying so. Throws std::runtime_error naming
/// the path on failure.
void save_scene(const std::string& path, const SceneSpec& spec, const SceneState* state = nullptr);

/// The current state of a simulation, for save_scene: positions, velocities (Simulation::velocity) and the pinned
/// particles. A particle being grabbed is saved unpinned (a grab is a transient user action). Reloaded, a symplectic
/// Euler run continues bit-identically (time restarts at 0: the analytic wind's phase and strain_limit.every count
/// from the reload); a Verlet run stores x - v dt as its previous position, equal to within float rounding.
SceneState capture_state(const Simulation& sim);

} // namespace drape
