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
//
// Every element's coefficients sum to 0 (a translation moves no q_e; set_bending checks it), so each row of Q sums
// to 0 and the kernels evaluate f_i = -sum_{j != i} Q_ij ((x_j - x_i) + beta (v_j - v_i)): differences of nearby
// positions, not a cancelling sum of absolute ones (float keeps its digits at any distance from the origin).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "drape/aligned_array.hpp"

namespace drape {

/// One bending element: up to 4 particles with coefficients (unused slots: coefficient 0, index = a used one).
struct BendElement {
    std::array<std::uint32_t, 4> v{};
    std::array<float, 4> c{};
    float weight = 0.0f; ///< w_e, N/m (energy = 1/2 w_e |q_e|^2, q_e in m)
};

/// The grid fabric's bending stencil in closed form (core/src/scene_hang.cpp builds it; the grid kernel evaluates
/// it from the stencil's neighbour loads instead of Q's rows). Weights of the interior elements, N/m; an element
/// along a boundary row (u) or column (v) has half (GridStencil mask bits, cloth.hpp).
struct GridBending {
    float u = 0.0f;     ///< second difference along a row (curvature along u): B_u h^2 / h^4
    float v = 0.0f;     ///< second difference along a column: B_v h^2 / h^4
    float twist = 0.0f; ///< a cell's cross difference: 2 B_t h^2 / h^4
};

/// Bending elements cooked for the kernels (Cloth::bending).
struct BendingSet {
    std::vector<BendElement> elements; ///< as given to set_bending (the reference, health and energy read them)
    float damping = 0.0f;              ///< Rayleigh beta, s
    // Q assembled per particle: off-diagonal entries, rows sorted by neighbour (CSR, in double as summed).
    std::vector<std::uint32_t> offsets;   ///< particle_count + 1
    std::vector<std::uint32_t> neighbour; ///< per entry
    std::vector<double> value;            ///< Q_ij, 1/m * N (N/m); the diagonal Q_ii = -sum of its row's entries
    // The same rows SIMD-sliced (SELL-C, C = simd::width; layout of SpringGraph::sell_*): padding entries point at
    // the particle itself with coefficient 0.
    std::vector<std::uint32_t> slice_begin; ///< slice_count + 1
    std::vector<std::uint32_t> slice_slots; ///< slice_count
    AlignedArray<std::uint32_t> sell_neighbour;
    AlignedArray<float> sell_coefficient; ///< -Q_ij, N/m (f_i = sum_j -Q_ij (d_j), d_j = x_j - x_i + beta (v_j - v_i))
    /// Present when the elements are exactly the grid fabric's stencil (the grid kernel may evaluate them); set_bending
    /// clears it.
    std::optional<GridBending> grid;

    bool empty() const noexcept { return elements.empty(); }
};

struct Cloth;

/// Cooks bending elements into the cloth (Cloth::bending, replacing any): keeps the element list, assembles Q for
/// the kernels; `damping` is Rayleigh beta, s. Throws InvalidInput on an index out of range, a negative or
/// non-finite weight or coefficient, coefficients that do not sum to 0 (to 1e-5 of their magnitudes), or a
/// negative damping.
void set_bending(Cloth& cloth, std::vector<BendElement> elements, float damping);

/// E = 1/2 sum_e w_e |q_e|^2 (J) at positions x, y, z (one entry per particle), in double: the reference.
double bending_energy(std::span<const BendElement> elements, std::span<const float> x, std::span<const float> y,
                      std::span<const float> z);

/// grad E (N, the negative of the bending force) at x, y, z, in double: gx[i] = sum_e w_e c_ei q_e.x, ...
struct BendGradient {
    std::vector<double> gx, gy, gz;
};
BendGradient bending_gradient(std::span<const BendElement> elements, std::span<const float> x,
                              std::span<const float> y, std::span<const float> z);

/// One entry of Q (the Hessian is Q (x) I3: the same Q_ij on the x, y and z blocks), N/m.
struct BendTriplet {
    std::uint32_t row = 0, col = 0;
    double value = 0.0;
};
/// Q = sum_e w_e c_e c_e^T over `particle_count` particles: every non-zero entry once, the diagonal included, sorted
/// by (row, col), in double (for Eigen's setFromTriplets).
std::vector<BendTriplet> bending_hessian(std::span<const BendElement> elements, std::size_t particle_count);

/// The bending elements of a columns x rows grid of spacing h (index = row * columns + column; u along a row, v
/// along a column), rigidities B_u, B_v (N*m) and twist B_t = sqrt(B_u B_v) (docs/fabric.md "Bending energy"): per
/// row, the second difference x_{i-1} - 2 x_i + x_{i+1} at every interior column, weight B_u A / h^4 with A = h^2
/// (h^2 / 2 on the first and last row); per column likewise with B_v; per cell the cross difference
/// x00 - x10 - x01 + x11, weight 2 B_t h^2 / h^4. Order: row elements, column elements, cells.
std::vector<BendElement> grid_bending_elements(std::uint32_t columns, std::uint32_t rows, float h, float bend_u,
                                               float bend_v);
/// The interior weights of those elements (GridBending).
GridBending grid_bending_weights(float h, float bend_u, float bend_v);

/// Gershgorin row sums of Q: sum_j |Q_ij| per particle (stability bound), from the cooked rows.
std::vector<double> bending_row_sums(const BendingSet& bending, std::size_t particle_count);

} // namespace drape
