// The small parameter struct every kernel takes: raw pointers into the SoA arrays plus per-substep constants.
// Built once per substep by Simulation (substep.cpp); kernels never touch Simulation or Cloth directly.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "drape/cloth.hpp"
#include "drape/simd.hpp"

#define DRAPE_INLINE [[gnu::always_inline]] inline

namespace drape::kernels {

using simd::fbatch;
using simd::fmask;

struct Vec3b {
    fbatch x, y, z;
};

/// One particle batch's own state, loaded once and shared by every stage of the fused pass.
struct SelfBatch {
    fbatch x, y, z; ///< position, m
    fbatch u, v, w; ///< velocity (symplectic Euler) or displacement over the last step, x - x_prev (Verlet)
};

struct StepContext {
    // State read this substep (buffer A) and written (buffer B). Hot arrays carry a halo (see aligned_array.hpp).
    const float* __restrict x;
    const float* __restrict y;
    const float* __restrict z;
    const float* __restrict u;
    const float* __restrict v;
    const float* __restrict w;
    float* __restrict out_x;
    float* __restrict out_y;
    float* __restrict out_z;
    float* __restrict out_u;
    float* __restrict out_v;
    float* __restrict out_w;
    const float* __restrict inv_mass;

    // Regular-grid stencil (grid path).
    const std::uint32_t* __restrict grid_mask;
    std::array<std::ptrdiff_t, GridStencil::slot_count> grid_offset;
    std::array<float, GridStencil::slot_count> grid_k;     ///< N/m
    std::array<float, GridStencil::slot_count> grid_krest; ///< k * l0, N
    std::array<float, GridStencil::slot_count> grid_kd;    ///< N*s/m; for Verlet already divided by dt
    // The grid fabric's bending stencil (GridBending): interior weights, N/m.
    float grid_bend_u, grid_bend_v, grid_twist;

    // SIMD-sliced CSR (general path).
    const std::uint32_t* __restrict slice_begin;
    const std::uint32_t* __restrict slice_slots;
    const std::uint32_t* __restrict sell_neighbour;
    const float* __restrict sell_rest;
    const float* __restrict sell_stiffness;
    const float* __restrict sell_damping;
    bool mirror; ///< the cloth is mirror-exact (Cloth::mirror): the CSR sums use accumulate_term's exact form

    // Bending (bending.hpp): Q's off-diagonal rows, SIMD-sliced; null when the cloth has no bending.
    bool bending;
    float bend_beta; ///< Rayleigh beta, s; for Verlet divided by dt (see damped_difference)
    const std::uint32_t* __restrict bend_slice_begin;
    const std::uint32_t* __restrict bend_slice_slots;
    const std::uint32_t* __restrict bend_neighbour;
    const float* __restrict bend_coefficient; ///< -Q_ij, N/m

    // Per-substep constants.
    float dt;      ///< s
    float dt2;     ///< s^2
    float inv_dt;  ///< 1/s
    float gx, gy, gz; ///< gravity, m/s^2
    float drag;    ///< 1/s
    float wind_x;  ///< strength * sin(10 t), m/s^2 (uniform in space)
    float wind_strength; ///< m/s^2
    float wind_phase;    ///< 10 t + Cloth::origin z (mod 2 pi), rad

    // Forces (N) per particle from the irregular stages (aero_forces, seam_forces); unused when neither runs.
    const float* __restrict extra_fx;
    const float* __restrict extra_fy;
    const float* __restrict extra_fz;

    // Staged-pipeline scratch: spring force (N) and external acceleration (m/s^2).
    float* __restrict fx;
    float* __restrict fy;
    float* __restrict fz;
    float* __restrict ax;
    float* __restrict ay;
    float* __restrict az;
    std::uint8_t* block_ok; ///< per block: 1 when every value written is finite
};

/// Adds the forces of the irregular stages (aerodynamic wind, seams) of batch p to the spring forces.
template <bool Extra> DRAPE_INLINE void add_extra_forces(const StepContext& c, std::size_t p, Vec3b& f) noexcept {
    if constexpr (Extra) {
        f.x = f.x + simd::load(c.extra_fx + p);
        f.y = f.y + simd::load(c.extra_fy + p);
        f.z = f.z + simd::load(c.extra_fz + p);
    }
}

DRAPE_INLINE SelfBatch load_self(const StepContext& c, std::size_t p) noexcept {
    return {simd::load(c.x + p), simd::load(c.y + p), simd::load(c.z + p),
            simd::load(c.u + p), simd::load(c.v + p), simd::load(c.w + p)};
}

} // namespace drape::kernels
