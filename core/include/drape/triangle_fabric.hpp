// The fabric material model on triangle meshes (outline panels, OBJ meshes, the T-shirt's mask panels): every
// per-element constant derived from a Fabric (physical units) and the mesh's rest triangles. docs/fabric.md,
// section "Triangle meshes", derives the formulas.
//   - Membrane: one spring per triangle edge, k_e = sum over the edge's triangles T of E_e A_T / l_e^2 (Van
//   Gelder
//     1998, "Approximate simulation of elastic membranes by triangulated spring meshes", J. Graphics Tools
//     3(2)), with E_e the fabric's tensile stiffness along the edge (edge_modulus); damping kd =
//     Fabric::damping x k.
//   - Bending: the hinge elements of Bergou et al. 2006 (hinge_bending_elements in bending.hpp), no bend
//   springs.
//   - Mass: areal density x triangle area, a third to each corner (lumped_masses).
//   - Seams (SpringKind::seam): as stiff as one membrane edge of the fabric across one cell, k = (stretch_u +
//     stretch_v) / 2 (a strip of fabric as wide as it is long), damping Fabric::damping x k.
// Each kind's material holds k_ref = (stretch_u + stretch_v) / 2 (damping Fabric::damping x k_ref) and each
// spring's Edge::scale is k_e / k_ref (seams 1): changing a kind's material later scales all its springs
// together.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/cloth.hpp"
#include "drape/errors.hpp"
#include "drape/fabric.hpp"
#include "drape/garment_assembly.hpp"

namespace drape {

/// How a mesh's edges sit relative to the fabric's weave.
enum class WeaveAlignment : std::uint8_t {
    /// Cut on the weave's grid (mask panels; outline panels, whose fill is a u-v grid): edges along u, along
    /// v and
    /// along cell diagonals. An edge's modulus is the fabric's off-axis tensile stiffness (Kilby 1963), so
    /// edges on
    /// the diagonals carry the shear stiffness.
    aligned,
    /// Edges in any direction (OBJ meshes): E = stretch_u cos^2 + stretch_v sin^2. Shear is what the
    /// triangles'
    /// springs give (about E / 6 to 3 E / 8), not Fabric::shear: soft shear and stiff tension cannot both
    /// come from
    /// edge springs whose directions do not follow the weave.
    unaligned,
};

/// Tensile stiffness per unit width, N/m, of `fabric` along a direction whose angle t to u has cos^2 t =
/// cos2:
///   aligned:   1 / E = cos^4 / stretch_u + sin^4 / stretch_v + cos^2 sin^2 / shear   (off-axis modulus,
///   Poisson 0;
///              shear floored at 1e-3 min(stretch_u, stretch_v))
///   unaligned: E = stretch_u cos^2 + stretch_v sin^2.
double edge_modulus(const Fabric& fabric, double cos2, WeaveAlignment alignment);

/// Membrane spring stiffness (N/m) of each edge in `edges` (a < b or b < a) from the rest triangles:
/// k_e = sum_T E_e A_T / l_e^2 over the triangles T that have edge e, E_e = edge_modulus at
/// cos^2 = (d_e . u)^2, d_e the unit edge direction, u = axis_u normalised. An edge in no triangle gets E_e (a strip of
/// fabric as wide as it is long). Positions one entry per particle, m.
std::vector<double> membrane_stiffness(std::span<const float> x, std::span<const float> y,
                                       std::span<const float> z, std::span<const std::uint32_t> triangles,
                                       std::span<const Edge> edges, const Fabric& fabric,
                                       const std::array<float, 3>& axis_u, WeaveAlignment alignment);

/// Node masses, kg: density (kg/m^2) x the area of each triangle, a third to each of its corners. A particle
/// in no triangle gets 0 (the caller decides).
std::vector<double> lumped_masses(std::span<const float> x, std::span<const float> y,
                                  std::span<const float> z, std::span<const std::uint32_t> triangles,
                                  double density);

/// The most a membrane spring may be stiffer than the fabric, k_e / k_ref (k_ref = (stretch_u + stretch_v) / 2; the
/// cook's limit on Edge::scale): past it an edge is the short side of a needle triangle (k = E A / l^2 grows as the
/// edge shortens across a wide triangle), whose spring would need a time step sqrt(1000) ~ 30 times smaller.
inline constexpr double membrane_stiffness_ratio_max = 1e3;

/// cook_triangle_fabric's refusal of a needle: the stiffest membrane edge, particles (a, b) of the assembly (a < b),
/// and its k_e / k_ref. what() names the two particles; a caller that knows where they came from (an outline, an
/// OBJ file) catches it and names the place in the user's terms.
class NeedleTriangleError : public InvalidInput {
  public:
    NeedleTriangleError(std::uint32_t a, std::uint32_t b, double ratio);
    std::uint32_t a, b;
    double ratio;
};

struct TriangleFabricOptions {
    Fabric fabric;
    std::array<float, 3> axis_u{1.0f, 0.0f, 0.0f}; ///< the weave's u direction in the assembly's frame
    WeaveAlignment alignment = WeaveAlignment::aligned;
};

/// Cooks an assembly with the fabric model: springs on every triangle edge (membrane stiffness per edge; kind
/// SpringKind::structural, or SpringKind::shear on a weave-aligned mesh for an edge more than ~8 degrees off
/// both u and v, cos^2 in (0.02, 0.98): the kind only names it for health figures and strain limits), the
/// assembly's seam springs (seam stiffness above), no other springs of the assembly (its structural springs
/// in no triangle excepted: kept, k = E_e); per-spring stiffness as Edge::scale (above); Cloth::triangles;
/// hinge bending (set_bending, damping Fabric::damping). Rest lengths: the assembly's. Masses are the
/// caller's (inv_mass, 1/kg, 0 = pinned). Throws NeedleTriangleError where a membrane edge's k_e / k_ref passes
/// membrane_stiffness_ratio_max, InvalidInput for any other bad input.
Cloth cook_triangle_fabric(const GarmentAssembly& assembly, std::span<const float> inv_mass,
                           const TriangleFabricOptions& options);

} // namespace drape
