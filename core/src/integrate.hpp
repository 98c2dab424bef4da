// Stage 3: integration, then pins. a = f / m + a_ext for movable particles, 0 for pinned ones (inverse mass 0).
//   symplectic Euler (001 eqs 9-10): v' = v + a dt, x' = x + v' dt
//   position Verlet  (000 eq 1.12):  x' = 2x - x_prev + a dt^2   (no spurious 1/2), stored as the displacement
//                    d = x - x_prev: d' = d + a dt^2, x' = x + d'. The same numbers in exact arithmetic; in float32
//                    d keeps its digits where x - x_prev (a difference of two nearby positions) lost them, so a cloth
//                    at rest settles (x - x_prev of a 1 m cloth at rest was ~1e-7 m of rounding noise per step).
// Writes the other state buffer and reports whether every value written is finite.
#pragma once

#include "kernel_context.hpp"
#include "drape/simulation.hpp"

namespace drape::kernels {

/// Integrates one batch and stores it into the out_* arrays. Returns the lanes whose new values are all finite.
template <Integrator I>
DRAPE_INLINE fmask integrate_batch(const StepContext& c, std::size_t p, const SelfBatch& s, const Vec3b& f,
                                   const Vec3b& a_ext) noexcept {
    const fbatch inv_m = simd::load(c.inv_mass + p);
    const fmask movable = inv_m > fbatch(0.0f);
    const fbatch ax = simd::fma(inv_m, f.x, a_ext.x);
    const fbatch ay = simd::fma(inv_m, f.y, a_ext.y);
    const fbatch az = simd::fma(inv_m, f.z, a_ext.z);
    fbatch nx, ny, nz, nu, nv, nw;
    if constexpr (I == Integrator::symplectic_euler) {
        const fbatch dt(c.dt), zero(0.0f);
        nu = simd::select(movable, simd::fma(ax, dt, s.u), zero);
        nv = simd::select(movable, simd::fma(ay, dt, s.v), zero);
        nw = simd::select(movable, simd::fma(az, dt, s.w), zero);
        nx = simd::select(movable, simd::fma(nu, dt, s.x), s.x);
        ny = simd::select(movable, simd::fma(nv, dt, s.y), s.y);
        nz = simd::select(movable, simd::fma(nw, dt, s.z), s.z);
    } else {
        const fbatch dt2(c.dt2), zero(0.0f);
        nu = simd::select(movable, simd::fma(ax, dt2, s.u), zero); // a pinned particle: displacement 0
        nv = simd::select(movable, simd::fma(ay, dt2, s.v), zero);
        nw = simd::select(movable, simd::fma(az, dt2, s.w), zero);
        nx = simd::select(movable, s.x + nu, s.x);
        ny = simd::select(movable, s.y + nv, s.y);
        nz = simd::select(movable, s.z + nw, s.z);
    }
    simd::store(c.out_x + p, nx);
    simd::store(c.out_y + p, ny);
    simd::store(c.out_z + p, nz);
    simd::store(c.out_u + p, nu);
    simd::store(c.out_v + p, nv);
    simd::store(c.out_w + p, nw);
    // x - x is 0 for finite x and NaN for inf/NaN; summing first checks six values with one compare.
    const fbatch probe = (nx - nx) + (ny - ny) + (nz - nz) + (nu - nu) + (nv - nv) + (nw - nw);
    return probe == fbatch(0.0f);
}

/// Stage pass: integrates particles [begin, end) from scratch fx..fz, ax..az; one block per call.
void integrate_range(const StepContext& c, Integrator integrator, std::size_t begin, std::size_t end,
                     std::size_t block);

} // namespace drape::kernels
