// Stage 2: spring forces and spring damping, gathered per particle (each particle sums its own springs in a fixed
// order: no atomics, no scatter; each spring is evaluated once from each end).
//
// For a spring from particle i to j with d = x_j - x_i, l = |d|, rest length l0, stiffness k, damping kd:
//   Hooke (000 eq 1.4, 001 eq 1):   F_i = k (d - l0 d / l) = k (1 - l0 / l) d
//   damping (001 eq 2, projected):  F_i = kd ((v_j - v_i) . d) d / l^2
// so F_i = c d with c = k - k l0 / l + kd ((v_j - v_i) . d) / l^2. For Verlet u, v, w hold the displacement over
// the last step, so the relative velocity is (u_j - u_i) / dt: the same dot product, the 1/dt folded into kd.
// ~27 SIMD operations per spring end; a zero-length spring gives zero force (l^2 clamped, d = 0).
#pragma once

#include "kernel_context.hpp"
#include "drape/simulation.hpp"

namespace drape::kernels {

/// Smallest squared length used in 1/l: keeps coincident particles finite (d = 0 there, so the force is 0).
inline constexpr float min_length2 = 1e-24f;

/// Coefficient c of one spring end (F_i = c d) and d itself.
template <Integrator I>
DRAPE_INLINE fbatch spring_coefficient(const SelfBatch& s, fbatch xj, fbatch yj, fbatch zj, fbatch uj, fbatch vj,
                                       fbatch wj, fbatch k, fbatch krest, fbatch kd, Vec3b& d) noexcept {
    d.x = xj - s.x;
    d.y = yj - s.y;
    d.z = zj - s.z;
    const fbatch r2 = simd::fma(d.z, d.z, simd::fma(d.y, d.y, d.x * d.x));
    const fbatch inv = simd::rsqrt(xsimd::max(r2, fbatch(min_length2)));
    const fbatch hooke = simd::fnma(krest, inv, k);
    const fbatch du = uj - s.u, dv = vj - s.v, dw = wj - s.w;
    const fbatch dot = simd::fma(dw, d.z, simd::fma(dv, d.y, du * d.x));
    return simd::fma(kd * dot, inv * inv, hooke);
}

/// Regular-grid stencil: neighbours at fixed offsets, contiguous unaligned loads, a per-particle slot mask.
struct GridSprings {
    template <Integrator I>
    DRAPE_INLINE static Vec3b accumulate(const StepContext& c, std::size_t p, const SelfBatch& s) noexcept {
        const simd::ubatch mask = simd::load(c.grid_mask + p);
        const fbatch zero(0.0f);
        Vec3b f{zero, zero, zero};
#pragma GCC unroll 12
        for (std::size_t slot = 0; slot < GridStencil::slot_count; ++slot) {
            const std::ptrdiff_t q = static_cast<std::ptrdiff_t>(p) + c.grid_offset[slot];
            Vec3b d;
            fbatch coef = spring_coefficient<I>(s, simd::loadu(c.x + q), simd::loadu(c.y + q), simd::loadu(c.z + q),
                                                simd::loadu(c.u + q), simd::loadu(c.v + q), simd::loadu(c.w + q),
                                                fbatch(c.grid_k[slot]), fbatch(c.grid_krest[slot]),
                                                fbatch(c.grid_kd[slot]), d);
            coef = simd::select(simd::test_bits(mask, 1u << slot), coef, zero);
            f.x = simd::fma(coef, d.x, f.x);
            f.y = simd::fma(coef, d.y, f.y);
            f.z = simd::fma(coef, d.z, f.z);
        }
        return f;
    }
};

/// General path: SIMD-sliced CSR, gathers of the neighbour state. Inert padding entries contribute exactly 0.
struct CsrSprings {
    template <Integrator I>
    DRAPE_INLINE static Vec3b accumulate(const StepContext& c, std::size_t p, const SelfBatch& s) noexcept {
        using ibatch = xsimd::batch<std::int32_t>;
        const std::size_t slice = p / simd::width;
        const std::size_t begin = c.slice_begin[slice];
        const std::size_t slots = c.slice_slots[slice];
        const fbatch zero(0.0f);
        const fbatch kd_scale(I == Integrator::verlet ? c.inv_dt : 1.0f);
        Vec3b f{zero, zero, zero};
        for (std::size_t slot = 0; slot < slots; ++slot) {
            const std::size_t at = begin + slot * simd::width;
            const ibatch idx = ibatch::load_aligned(reinterpret_cast<const std::int32_t*>(c.sell_neighbour + at));
            const fbatch k = simd::load(c.sell_stiffness + at);
            fbatch kd = simd::load(c.sell_damping + at);
            if constexpr (I == Integrator::verlet) kd = kd * kd_scale;
            Vec3b d;
            const fbatch coef = spring_coefficient<I>(
                s, fbatch::gather(c.x, idx), fbatch::gather(c.y, idx), fbatch::gather(c.z, idx),
                fbatch::gather(c.u, idx), fbatch::gather(c.v, idx), fbatch::gather(c.w, idx), k,
                k * simd::load(c.sell_rest + at), kd, d);
            f.x = simd::fma(coef, d.x, f.x);
            f.y = simd::fma(coef, d.y, f.y);
            f.z = simd::fma(coef, d.z, f.z);
        }
        return f;
    }
};

/// Stage pass: spring forces of particles [begin, end) into the scratch arrays fx, fy, fz.
/// With `seams`, adds the seam forces written by the seam_forces stage (as the fused pass does).
void spring_forces_range(const StepContext& c, Integrator integrator, KernelPath path, bool seams, std::size_t begin,
                         std::size_t end);

} // namespace drape::kernels
