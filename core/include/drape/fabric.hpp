// Fabric: a cloth material in physical, resolution-independent units (cold tier).
//
// A user names a fabric (a preset such as "denim", or its own figures); the engine derives every per-element
// constant (spring stiffness, node mass, bending coefficients, damping) from it and the mesh - grid spacing, triangle
// areas - so the same fabric behaves the same at every resolution. The formulas are in docs/fabric.md.
//
// The seeds' plain spring model (per-node mass, per-spring stiffness in N/m, bend springs between particles two
// apart, damping as a ratio of critical) stays selectable as MaterialModel::springs.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace drape {

/// Which material model a cloth uses.
enum class MaterialModel : std::uint8_t {
    fabric,  ///< physical units (Fabric): membrane springs derived from stretch and shear, a true bending energy
    springs, ///< the seeds' springs: structural, shear and bend springs with per-spring stiffness
};
const char* material_model_name(MaterialModel model) noexcept;

/// A fabric in physical units. u is the warp (a grid's columns, a panel's u axis), v the weft.
struct Fabric {
    std::string name = "custom"; ///< preset name, or "custom"
    float density = 0.15f;       ///< areal density, kg/m^2 (files and panels show g/m^2)
    /// Tensile stiffness per unit width, N/m: the tension (force per unit width) over the strain of a strip pulled
    /// along u (warp) or v (weft) with its sides free - what a strip tensile test (e.g. KES-F EMT/LT) measures.
    float stretch_u = 5000.0f, stretch_v = 5000.0f;
    float shear = 50.0f; ///< in-plane shear stiffness G, N/m (shear force per unit width over the shear angle, rad)
    /// Bending rigidity per unit width, N*m (fabrics: micro-newton-metres): moment per unit width over curvature,
    /// for curvature along u (warp) and along v (weft) - what a Peirce cantilever (ASTM D1388) or KES-F B measures.
    float bend_u = 5e-6f, bend_v = 5e-6f;
    /// Rayleigh stiffness-proportional damping, s: every elastic force f = -K x gets a damping force -beta K v.
    /// Resolution-independent (a mode's damping ratio is beta w / 2 for its w, whatever the mesh).
    float damping = 0.0f;
};

/// A fabric preset and where its figures come from (docs/fabric.md cites each).
struct FabricPreset {
    Fabric fabric;
    std::string description; ///< e.g. "cotton shirting, plain weave, 120 g/m^2"
    std::string source;      ///< the published measurement it is taken from
};

/// Every preset, in a fixed order (the viewer's list).
const std::vector<FabricPreset>& fabric_presets();
/// A preset by name (case-sensitive), or nullopt.
std::optional<Fabric> find_fabric(const std::string& name);
/// The preset names, comma-separated, in the order of fabric_presets() (for messages: "silk, cotton_shirting, ...").
std::string fabric_preset_names();

// File and panel units: areal density in g/m^2, stiffness in N/m, bending rigidity in micro-newton-metres, damping in
// s. Fabric holds SI (kg/m^2, N*m); multiply by these to get file units.
inline constexpr double fabric_gsm_per_kg_m2 = 1000.0;
inline constexpr double fabric_uNm_per_Nm = 1e6;

/// Allowed range of one fabric field, in file units, wide enough for every real fabric (tulle to canvas).
struct FabricRange {
    double lo, hi;
    const char* unit;
};
inline constexpr FabricRange fabric_range_density_gsm{5.0, 2000.0, "g/m^2"};
inline constexpr FabricRange fabric_range_stretch{10.0, 1e6, "N/m"};
inline constexpr FabricRange fabric_range_shear{0.01, 1e5, "N/m"};
inline constexpr FabricRange fabric_range_bend_uNm{0.0, 1e4, "micro-N*m"};
inline constexpr FabricRange fabric_range_damping{0.0, 0.1, "s"};

/// Checks every field's range; throws InvalidInput naming `what` (e.g. "scene.json: material") and the field
/// ("scene.json: material.bend_u_uNm = ... micro-N*m is outside the allowed range [0, 10000] micro-N*m").
void validate_fabric(const Fabric& fabric, const std::string& what);

} // namespace drape
