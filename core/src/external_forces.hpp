// Stage 1: external forces, as accelerations of movable particles (pinned particles get none).
//   gravity       a = g
//   air drag      a = -kr v            (F = -m kr v, seed 001 eq 4; 000 eq 1.5 in per-mass form)
//   analytic wind a = s (sin 10t, 0, |sin(z + 10t)|)   (seed 000 listing 3.3, as an acceleration field)
#pragma once

#include "kernel_context.hpp"
#include "drape/simulation.hpp"

namespace drape::kernels {

/// Velocity of a batch: stored (Euler) or the displacement (x - x_prev) / dt (Verlet).
template <Integrator I> DRAPE_INLINE Vec3b velocity(const StepContext& c, const SelfBatch& s) noexcept {
    if constexpr (I == Integrator::symplectic_euler) {
        return {s.u, s.v, s.w};
    } else {
        const fbatch inv_dt(c.inv_dt);
        return {s.u * inv_dt, s.v * inv_dt, s.w * inv_dt};
    }
}

template <Integrator I, bool Wind>
DRAPE_INLINE Vec3b external_acceleration(const StepContext& c, const SelfBatch& s, fmask movable) noexcept {
    const Vec3b vel = velocity<I>(c, s);
    const fbatch drag(c.drag);
    fbatch gx(c.gx), gz(c.gz);
    if constexpr (Wind) {
        gx = gx + fbatch(c.wind_x);
        gz = gz + fbatch(c.wind_strength) * xsimd::abs(xsimd::sin(s.z + fbatch(c.wind_phase)));
    }
    const fbatch zero(0.0f);
    return {simd::select(movable, simd::fnma(drag, vel.x, gx), zero),
            simd::select(movable, simd::fnma(drag, vel.y, fbatch(c.gy)), zero),
            simd::select(movable, simd::fnma(drag, vel.z, gz), zero)};
}

DRAPE_INLINE fmask movable_lanes(const StepContext& c, std::size_t p) noexcept {
    return simd::load(c.inv_mass + p) > fbatch(0.0f);
}

/// Stage pass: external accelerations of particles [begin, end) into the scratch arrays ax, ay, az.
void external_forces_range(const StepContext& c, Integrator integrator, bool wind, std::size_t begin,
                           std::size_t end);

} // namespace drape::kernels
