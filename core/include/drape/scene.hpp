// Scenes: what a scene file (JSON, docs/scene_format.md) describes, validated on load, and how it becomes a cooked
// cloth plus simulation parameters. The built-in scenes are the files under scenes/, embedded into the library at
// build time, so `--scene NAME` and `--scene scenes/NAME.json` are the same scene.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "drape/colliders.hpp"
#include "drape/panels.hpp"
#include "drape/scene_hang.hpp"
#include "drape/simulation.hpp"

namespace drape {

enum class ClothType : std::uint8_t { grid, tshirt };

/// Everything a scene file holds (cold tier). Defaults are those of "hang".
struct SceneSpec {
    std::string name = "hang";
    std::string description;
    ClothType cloth = ClothType::grid;
    HangParams grid;      ///< cloth.type = "grid" (n, size, mass, plane, centre, pins, material)
    TShirtParams tshirt;  ///< cloth.type = "tshirt"
    /// Material (N/m; damping as a fraction of critical, like HangParams).
    float stiffness = 1000.0f, shear_ratio = 0.5f, bend_ratio = 0.1f, damping_ratio = 0.05f;
    float seam_stiffness = 1000.0f; ///< N/m, seam springs (tshirt)
    SimulationParams physics;       ///< gravity, drag, integrator, wind, strain limit, colliders (dt: see below)
    std::optional<float> dt;        ///< s; absent = 0.9 x the stability bound
    bool body = false;              ///< add default_body() colliders (tshirt)
};

/// Names of the built-in scenes, in a fixed order: hang, drape, sphere, flag, tshirt.
std::vector<std::string> builtin_scene_names();

/// Parses and validates scene JSON. `source` names the file in messages. Throws InvalidInput naming the source, the
/// field as a JSON path (e.g. "cloth.n") and the allowed range; unknown fields are errors.
SceneSpec parse_scene(const std::string& json_text, const std::string& source);

/// A built-in scene by name, or a scene file by path (anything ending in .json). Throws InvalidInput (unknown name,
/// missing or unreadable file, or any parse error).
SceneSpec load_scene(const std::string& name_or_path);

struct BuiltScene {
    Cloth cloth;
    InitialState initial;
    SimulationParams params; ///< dt filled in (the scene's or the default)
};

/// Cooks a scene. Sizes are checked before anything is allocated.
BuiltScene build_scene(const SceneSpec& spec);

/// Particle count a spec will have, computed without building it (to refuse absurd sizes early).
std::size_t scene_particle_count(const SceneSpec& spec);

} // namespace drape
