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

/// E = 1/2 sum_e w_e |q_e|^2 (J) at positions x, y, z (one entry per particle), in double: the reference.
double bending_energy(std::span<const BendElement> elements, std::span<const float> x, std::span<const float> y,
                      std::span<const float> z);

} // namespace drape
