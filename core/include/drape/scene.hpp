// Scenes: what a scene file (JSON, docs/scene_format.md) describes, validated on load, and how it becomes a cooked
// cloth plus simulation parameters. The built-in scenes are the files under scenes/, embedded into the library at
// build time, so `--scene NAME` and `--scene scenes/NAME.json` are the same scene.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drape/colliders.hpp"
#include "drape/mesh_cloth.hpp"
#include "drape/mask_panel.hpp"
#include "drape/outline_panel.hpp"
#include "drape/tshirt.hpp"
#include "drape/scene_hang.hpp"
#include "drape/simulation.hpp"

namespace drape {

enum class ClothType : std::uint8_t { grid, tshirt, outline, mesh, mask };

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

/// cloth.type = "mesh": an arbitrary triangle mesh read from an OBJ file (core/include/drape/mesh_cloth.hpp). The
/// file is read by parse_scene (so a broken file is an input error at load time); building scales the mesh about
/// its bounding-box centre and moves that centre to `centre`.
enum class MeshPins : std::uint8_t { none, top, list };
struct MeshClothSpec {
    std::string file;              ///< the OBJ file, resolved (absolute, normalised); the scene file may give it relative
    float density = 0.15f;         ///< kg/m^2; a particle gets 1/3 of its triangles' area times it
    float scale = 1.0f;            ///< applied about the bounding-box centre
    std::array<float, 3> centre{0.0f, 0.0f, 0.0f}; ///< where the mesh's bounding-box centre goes, m
    MeshPins pins = MeshPins::none;
    std::vector<std::uint32_t> pin_vertices; ///< pins = list: OBJ vertex indices (0-based)
    std::shared_ptr<const TriangleMesh> mesh; ///< what the file holds (cleaned), shared between copies of the spec
};

/// cloth.type = "mask": one or more named panels drawn as 0/1 masks (seed 000 section 1.4, the T-shirt's way), each
/// placed by its own frame, sewn together along named edges (docs/scene_format.md "Mask cloths").
enum class MaskPins : std::uint8_t { none, top_row, list };
struct MaskPanelSpec {
    std::string name;                            ///< unique within the cloth; seams name panels by it
    MaskPanel mask;                              ///< rows of '0'/'1', checked on load
    float cell_size = 0.02f;                     ///< h, m: cell (row, column) sits at (u, v) = (column h, row h)
    std::array<double, 3> origin{0.0, 0.0, 0.0}; ///< where cell (0, 0) goes, m
    /// The in-plane axes as the file gives them (any length, orthogonal); normalised when built.
    std::array<float, 3> axis_u{1.0f, 0.0f, 0.0f};
    std::array<float, 3> axis_v{0.0f, -1.0f, 0.0f};
    MaskPins pins = MaskPins::none;
    std::vector<std::array<std::uint32_t, 2>> pin_cells; ///< pins = list: (row, column) of '1' cells
};
/// An edge of a mask panel: a polyline of cells (row, column) along the panel's boundary, each leg from one corner
/// to the next along a row, a column or a 45-degree diagonal; its particles are every cell on the legs, in order.
struct MaskEdgeSpec {
    std::uint32_t panel = 0; ///< index into MaskClothSpec::panels
    std::vector<std::array<std::uint32_t, 2>> path;
};
/// A seam: the k-th particle of edge a joined to the k-th of edge b by a seam spring (both edges have as many
/// particles), rest length rest_ratio x the mean of the two panels' cell sizes.
struct MaskSeamSpec {
    MaskEdgeSpec a, b;
    float rest_ratio = 0.5f;
};
struct MaskClothSpec {
    std::vector<MaskPanelSpec> panels;
    std::vector<MaskSeamSpec> seams;
    float density = 0.15f; ///< kg/m^2 (springs model; a fabric's is its own): mass = density x triangle area
};

/// The particles of a mask edge, in path order (the cells on each leg, corners once). Cells are not checked here.
std::vector<std::array<std::uint32_t, 2>> mask_edge_cells(const MaskEdgeSpec& edge);

/// Whether mask cell (row, column) holds a particle on the boundary of its panel's triangle mesh (add_mask_panel's
/// triangles): on an edge of exactly one triangle, or in no triangle. False for a '0' cell or one outside the mask.
bool mask_cell_on_boundary(const MaskPanel& mask, std::int64_t row, std::int64_t column);

/// A simulation state saved with a scene (the "state" section): positions (m) and velocities (m/s) per particle, and
/// the pinned particles. build_scene starts from it: its pins replace the scene's own.
struct SceneState {
    /// The frame the positions are stored in (Cloth::origin of the saved simulation), m: world position =
    /// origin + (x, y, z). Kept separately so that a cloth far from 0 keeps its float precision in the file.
    std::array<double, 3> origin{0.0, 0.0, 0.0};
    std::vector<float> x, y, z, vx, vy, vz;
    std::vector<std::uint32_t> pinned;
    /// Seams being sewn when the state was saved: their current rest lengths, m (InitialState::seam_rest); empty
    /// when no seam is still closing.
    std::vector<float> seam_rest;
    /// Self-collision's snapshot of its last run ("self_collision_snapshot", InitialState::snapshot_x); empty = none.
    std::vector<float> snapshot_x, snapshot_y, snapshot_z;
    /// And its contact planes ("self_collision_planes", InitialState::sc_planes); empty = none.
    SelfCollisionPlanes sc_planes;
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
    MeshClothSpec mesh;       ///< cloth.type = "mesh"
    MaskClothSpec masks;      ///< cloth.type = "mask"
    /// The material: a fabric in physical units (docs/fabric.md; "material": "denim" or an object of fabric fields)
    /// or the seeds' springs (the fields below). Grid cloths pass both to HangParams.
    MaterialModel model = MaterialModel::springs;
    Fabric fabric;
    /// Spring-model material (N/m; damping as a fraction of critical, like HangParams).
    float stiffness = 1000.0f, shear_ratio = 0.5f, bend_ratio = 0.1f, damping_ratio = 0.05f;
    float seam_stiffness = 1000.0f; ///< N/m, seam springs (tshirt)
    SimulationParams physics;       ///< gravity, drag, integrator, wind, strain limit, colliders (dt: see below)
    std::optional<float> dt;        ///< s; absent = 0.9 x the stability bound
    bool body = false;              ///< add default_body() colliders (tshirt)
    std::optional<SceneState> state; ///< the "state" section: where the simulation starts (absent = the cloth at rest)
    /// Notes from loading that are not errors (e.g. degenerate triangles dropped from a mesh); the caller shows them.
    std::vector<std::string> warnings;
};

/// Names of the built-in scenes, in a fixed order: hang, drape, sphere, flag, tshirt.
std::vector<std::string> builtin_scene_names();

/// The largest scene file load_scene and parse_scene read (and save_scene writes), bytes: 16 MiB.
inline constexpr std::size_t scene_file_max_bytes = std::size_t{16} << 20;

/// Parses and validates scene JSON. `source` names the file in messages. Throws InvalidInput naming the source, the
/// field as a JSON path (e.g. "cloth.n") and the allowed range; unknown fields are errors. Relative file names in the
/// scene (cloth.file) are resolved against `base_dir` (empty: the current directory); a mesh cloth's OBJ is read here.
SceneSpec parse_scene(const std::string& json_text, const std::string& source, const std::string& base_dir = "");

/// A built-in scene by name, or a scene file by path (anything ending in .json). Throws InvalidInput (unknown name,
/// missing or unreadable file, or any parse error).
SceneSpec load_scene(const std::string& name_or_path);

struct BuiltScene {
    Cloth cloth;
    InitialState initial;
    SimulationParams params; ///< dt filled in (the scene's or the default)
};

/// Cooks a scene. Sizes are checked before anything is allocated. With a state, the initial state is the saved one
/// and its pins replace the scene's (the default dt is still that of the scene's own pins, as when it was saved);
/// throws InvalidInput when the state's counts do not match the cloth (naming state.positions and both counts).
BuiltScene build_scene(const SceneSpec& spec);

/// Particle count a spec will have, computed without building it (to refuse absurd sizes early).
std::size_t scene_particle_count(const SceneSpec& spec);

/// The resolution `drape run --size` and the viewer's resolution slider set: particles per side of a grid; cells per
/// metre of a T-shirt or an outline (an outline's spacing is 1 / cells per metre: round(1 / spacing)); none for a mesh
/// or a mask cloth (their resolution is the OBJ's, the masks' cells).
std::optional<std::uint32_t> scene_resolution(const SceneSpec& spec);

/// Sets that resolution: grid n (2..4096), T-shirt cells_per_metre (10..1000), outline spacing = 1 / size m (size
/// 10..1000, and the outline's point limit). Throws InvalidInput starting with `flag` and naming the allowed range,
/// or saying why it does not apply (a mesh, a mask cloth).
void set_scene_resolution(SceneSpec& spec, std::uint32_t size, const std::string& flag = "--size");

} // namespace drape
