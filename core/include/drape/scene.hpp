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

enum class ClothType : std::uint8_t { grid, tshirt, outline };

/// cloth.type = "outline": a panel cut from an outline polygon (seed 004: filled, Delaunay-triangulated), optionally
/// with an identical second panel `gap` behind it, sewn to it along outline stretches (a bag, a pillow).
struct OutlineClothSpec {
    OutlinePanel outline;            ///< vertices in panel coordinates (u, v), m
    float spacing = 0.03f;           ///< m
    float density = 0.15f;           ///< kg/m^2
    GridPlane plane = GridPlane::horizontal;
    std::array<float, 3> centre{0.0f, 0.0f, 0.0f}; ///< where the outline's bounding-box centre goes, m
    bool pin_top = false;            ///< pin the particles along the top (vertical plane) / far edge
    bool copy = false;               ///< add the second panel
    float gap = 0.1f;                ///< m between the panels
    std::vector<std::array<std::uint32_t, 2>> sew; ///< outline stretches (from vertex, to vertex) sewn together
    float seam_rest_ratio = 0.5f;    ///< seam rest length / spacing
};

/// Everything a scene file holds (cold tier). Defaults are those of "hang".
struct SceneSpec {
    std::string name = "hang";
    std::string source;   ///< where it was read from, for messages: a file path or "built-in scene 'hang'"
    std::string description;
    ClothType cloth = ClothType::grid;
    HangParams grid;      ///< cloth.type = "grid" (n, size, mass, plane, centre, pins, material)
    TShirtParams tshirt;  ///< cloth.type = "tshirt"
    OutlineClothSpec outline; ///< cloth.type = "outline"
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
