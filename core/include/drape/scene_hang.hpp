// Square grid cloths. Scene "hang" (BENCH.md) is the default: N x N particles, flat and horizontal in the x-z plane
// at y = 0, structural, shear and bend springs, corners (0,0) and (N-1,0) pinned. The same builder makes the other
// grid scenes (drape, sphere, flag: another plane, centre or pin set). Scene builders live once in core and serve
// the app, the tests and the benchmarks.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "drape/cloth.hpp"
#include "drape/fabric.hpp"

namespace drape {

enum class GridPlane : std::uint8_t {
    horizontal, ///< x-z plane at centre.y; row j along +z
    vertical,   ///< x-y plane at centre.z; row 0 on top, row j going down (-y)
};
enum class GridPins : std::uint8_t {
    corners,  ///< (0,0) and (N-1,0): the two corners of row 0
    top_edge, ///< all of row 0
    left_edge, ///< all of column 0 (a flag on its pole)
    none,
};

/// What the user chooses for a grid cloth (cold tier). Ranges are checked by build_hang_scene.
struct HangParams {
    std::uint32_t n = 100;     ///< particles per side, 2..4096
    float size = 1.0f;         ///< side length, m
    float total_mass = 0.1f;   ///< kg, spread evenly
    float stiffness = 1000.0f; ///< structural k, N/m (100..25000, seed 000)
    float shear_ratio = 0.5f;  ///< shear k = ratio * structural k
    float bend_ratio = 0.1f;   ///< bend k = ratio * structural k
    /// Spring damping as a fraction of critical damping of one spring between two particles (0..1):
    /// kd = ratio * 2 sqrt(k m / 2). Keeps the damping meaningful at any resolution.
    float damping_ratio = 0.05f;
    /// Material model: MaterialModel::fabric derives everything from `fabric` (physical units, docs/fabric.md) and
    /// ignores total_mass, stiffness and the ratios above; MaterialModel::springs is the seeds' spring model.
    MaterialModel model = MaterialModel::springs;
    Fabric fabric;
    GridPins pins = GridPins::corners;
    /// Physical pin size, m: each pin holds every particle within this distance of its point (a clip of this
    /// radius; at least the nearest particle), so the strain next to a pin converges with resolution. 0 = one particle.
    float pin_radius = 0.0f;
    GridPlane plane = GridPlane::horizontal;
    /// m, centre of the cloth: the frame's origin (Cloth::origin), positions are stored relative to it
    std::array<float, 3> centre{0.0f, 0.0f, 0.0f};
};

inline constexpr std::uint32_t hang_min_n = 2;
inline constexpr std::uint32_t hang_max_n = 4096;
/// Largest pin radius, m (HangParams::pin_radius).
inline constexpr float hang_max_pin_radius = 1.0f;

struct SceneBuild {
    Cloth cloth;
    InitialState initial;
};

/// The fabric model's spring constants on a square grid (docs/fabric.md "Derived constants on a grid"): structural
/// springs along u and v, both cell diagonals. Per unit width (resolution independent on a square grid): the
/// continuum stiffness is C11 = ks_u + kd, C22 = ks_v + kd, C12 = C66 = kd, so kd = G and ks_u, ks_v give the
/// free-sides tensile stiffnesses E_u = C11 - C12^2 / C22, E_v = C22 - C12^2 / C11. Throws InvalidInput (naming
/// `what` and the fields) when the shear is too large for the stretch (a structural stiffness would be <= 0).
struct GridMembrane {
    float ks_u = 0.0f, ks_v = 0.0f; ///< N/m, a structural spring inside the cloth (a boundary one gets half)
    float kd = 0.0f;                ///< N/m, a diagonal spring
};
GridMembrane grid_membrane(const Fabric& fabric, const std::string& what = "fabric");

/// Builds the hang scene: cooked cloth with the grid stencil, and its initial state, positions relative to
/// params.centre (= cloth.origin). Throws InvalidInput.
SceneBuild build_hang_scene(const HangParams& params);

/// Particle index of grid cell (column i, row j).
constexpr std::uint32_t grid_index(std::uint32_t n, std::uint32_t i, std::uint32_t j) noexcept { return j * n + i; }

} // namespace drape
