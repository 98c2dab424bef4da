// Bending energy (cooked tier): a true bending model with small-angle stiffness, in physical units.
//
// Every bending element e is a small linear stencil of particle positions: a vector q_e = sum_k c_ek x_k (k over at
// most 4 particles) that vanishes on the flat rest shape and measures curvature (a second difference along a grid
// row or column, a grid cell's cross difference for twist, or a Bergou-Wardetzky-Harmon-Zorin-Grinspun 2006 hinge
// on a triangle mesh). The energy is quadratic:
//   E = 1/2 sum_e w_e |q_e|^2,     grad_i E = sum_e w_e c_ei q_e,     Hessian = Q (x) I3, Q = sum_e w_e c_e c_e^T,
// so forces are linear in positions and the Hessian is constant (the implicit solver reuses it). With Rayleigh
// damping beta (Fabric::damping) the force is f = -Q (x + beta v). docs/fabric.md derives w_e from the fabric's
// bending rigidity and the mesh.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace drape {

/// One bending element: up to 4 particles with coefficients (unused slots: coefficient 0, index = a used one).
struct BendElement {
    std::array<std::uint32_t, 4> v{};
    std::array<float, 4> c{};
    float weight = 0.0f; ///< w_e, N/m (energy = 1/2 w_e |q_e|^2, q_e in m)
};

struct Cloth;

/// Cooks bending elements into the cloth (Cloth::bending, replacing any): keeps the element list, assembles Q for
/// the kernels; `damping` is Rayleigh beta, s. Throws InvalidInput on an index out of range or a negative weight.
void set_bending(Cloth& cloth, std::vector<BendElement> elements, float damping);

/// Bending elements of a triangle mesh: the quadratic bending model of Bergou, Wardetzky, Harmon, Zorin and Grinspun
/// 2006 ("A Quadratic Bending Model for Inextensible Surfaces", SGP 2006; Wardetzky et al. 2007, "Discrete quadratic
/// curvature energies", CAGD 24). One element per interior edge (an edge of exactly two triangles; an edge of one
/// triangle or of three or more gets none): its two ends x0, x1 and the two opposite vertices x2, x3, coefficients
/// the cotangent stencil K = (c03 + c04, c01 + c02, -c01 - c03, -c02 - c04) of the rest shape (c0j the cotangent of
/// the rest angle between edge e0 = x1 - x0 and e1 = x2 - x0, e2 = x3 - x0, e3 = x2 - x1, e4 = x3 - x1; c03, c04
/// with -e0), weight w = B / (A0 + A1) (A0, A1 the rest areas of the two triangles): with E = 1/2 w |q|^2 a flat mesh
/// bent into a cylinder of radius R then stores B / (2 R^2) per unit area (measured: docs/fabric.md; Bergou's
/// 3 / (A0 + A1) is for their normalisation of the energy, 3x this one). B is the bending rigidity across the edge: bending that
/// edge curves the surface along p, the in-plane direction perpendicular to it, and B = bend_u cos^2 + bend_v sin^2
/// with cos^2 = (p . axis_u)^2 (axis_u: the weave's u direction, unit, in the same frame as the positions).
/// The model assumes a flat rest shape: on a curved rest mesh q_e is not 0 at rest, so the energy pulls the mesh
/// towards flat (hinge_rest_angle_max measures how curved a mesh is). Skips hinges whose two opposite vertices
/// coincide or whose triangles have zero area. Positions: one entry per particle, m.
std::vector<BendElement> hinge_bending_elements(std::span<const float> x, std::span<const float> y,
                                                std::span<const float> z, std::span<const std::uint32_t> triangles,
                                                float bend_u, float bend_v, const std::array<float, 3>& axis_u);

/// Largest angle between the normals of two triangles sharing an interior edge, radians (0 for a flat mesh): how far
/// a rest mesh is from the flat rest shape hinge_bending_elements assumes.
double hinge_rest_angle_max(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                            std::span<const std::uint32_t> triangles);

/// E = 1/2 sum_e w_e |q_e|^2 (J) at positions x, y, z (one entry per particle), in double: the reference.
double bending_energy(std::span<const BendElement> elements, std::span<const float> x, std::span<const float> y,
                      std::span<const float> z);

} // namespace drape
