// Stage 2: spring forces and spring damping, gathered per particle (each particle sums its own springs in a fixed
// order: no atomics, no scatter; each spring is evaluated once from each end).
//
// For a spring from particle i to j with d = x_j - x_i, l = |d|, rest length l0, stiffness k, damping kd:
//   Hooke (000 eq 1.4, 001 eq 1):   F_i = k (d - l0 d / l) = k (1 - l0 / l) d
//   damping (001 eq 2, projected):  F_i = kd ((v_j - v_i) . d) d / l^2
// so F_i = c d with c = k - k l0 / l + kd ((v_j - v_i) . d) / l^2. For Verlet the relative velocity is
// ((d - (p_j - p_i)) / dt) . d = (l^2 - (p_j - p_i) . d) / dt, the 1/dt folded into kd.
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
    fbatch rel;
    if constexpr (I == Integrator::symplectic_euler)
        rel = dot;
    else
        rel = r2 - dot;
    return simd::fma(kd * rel, inv * inv, hooke);
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

/// A neighbour's position difference plus beta times its velocity difference, d + beta (v_j - v_i): what Rayleigh
/// damping adds to a linear force (bending: f = -Q (x + beta v)). d = x_j - x_i, du = u_j - u_i of the integrator's
/// state; `beta` is StepContext::bend_beta. The one place the bending kernels read u, v, w:
///   symplectic Euler: u is the velocity, so d + beta du;
///   position Verlet: u is the previous position, v_j - v_i = (d - du) / dt, so d + (beta / dt) (d - du) with
///   bend_beta = beta / dt.
template <Integrator I> DRAPE_INLINE fbatch damped_difference(fbatch d, fbatch du, fbatch beta) noexcept {
    if constexpr (I == Integrator::symplectic_euler)
        return simd::fma(beta, du, d);
    else
        return simd::fma(beta, d - du, d);
}

/// Bending over Q's SIMD-sliced rows (general path): f_i = sum_j -Q_ij (d_j + beta (v_j - v_i)), gathers of the
/// neighbour state. Padding entries (the particle itself, coefficient 0) contribute exactly 0.
struct CsrBending {
    template <Integrator I>
    DRAPE_INLINE static void accumulate(const StepContext& c, std::size_t p, const SelfBatch& s, Vec3b& f) noexcept {
        using ibatch = xsimd::batch<std::int32_t>;
        const std::size_t slice = p / simd::width;
        const std::size_t begin = c.bend_slice_begin[slice];
        const std::size_t slots = c.bend_slice_slots[slice];
        const fbatch beta(c.bend_beta);
        for (std::size_t slot = 0; slot < slots; ++slot) {
            const std::size_t at = begin + slot * simd::width;
            const ibatch idx = ibatch::load_aligned(reinterpret_cast<const std::int32_t*>(c.bend_neighbour + at));
            const fbatch a = simd::load(c.bend_coefficient + at);
            const fbatch dx = damped_difference<I>(fbatch::gather(c.x, idx) - s.x, fbatch::gather(c.u, idx) - s.u, beta);
            const fbatch dy = damped_difference<I>(fbatch::gather(c.y, idx) - s.y, fbatch::gather(c.v, idx) - s.v, beta);
            const fbatch dz = damped_difference<I>(fbatch::gather(c.z, idx) - s.z, fbatch::gather(c.w, idx) - s.w, beta);
            f.x = simd::fma(a, dx, f.x);
            f.y = simd::fma(a, dy, f.y);
            f.z = simd::fma(a, dz, f.z);
        }
    }
};

/// General path with bending (fabric model on any mesh): springs, then bending.
struct CsrFabric {
    template <Integrator I>
    DRAPE_INLINE static Vec3b accumulate(const StepContext& c, std::size_t p, const SelfBatch& s) noexcept {
        Vec3b f = CsrSprings::accumulate<I>(c, p, s);
        CsrBending::accumulate<I>(c, p, s, f);
        return f;
    }
};

/// The grid stencil's slots (scene_hang.cpp builds them in this order: ascending offset; "up" is row j - 1).
namespace grid_slot {
inline constexpr std::size_t up2 = 0, up_left = 1, up = 2, up_right = 3, left2 = 4, left = 5, right = 6, right2 = 7,
                             down_left = 8, down = 9, down_right = 10, down2 = 11;
}

/// Regular-grid fabric (MaterialModel::fabric on a grid): the 8 membrane springs (structural with the per-particle
/// half-stiffness bits of boundary edges, diagonals) in ascending slot order, as the CSR row sums them, then the
/// bending stencil in closed form from the same 12 neighbour loads (the 4 bend slots carry no spring):
///   along the row, q_{i-1} = D_-2 - 2 D_-1, q_i = D_-1 + D_+1, q_{i+1} = D_+2 - 2 D_+1 (D_k = damped_difference of
///   neighbour k), f += w_u (2 q_i - q_{i-1} - q_{i+1}) over the elements that exist (mask bits), w_u halved on a
///   boundary row; the same along the column; each existing cell's cross difference q_c with the particle's
///   coefficient s_c = +-1 gives f -= w_t s_c q_c.
/// This is f_i = -sum_j Q_ij D_j summed in another order than the CSR path: equal within float rounding, not bitwise.
struct GridFabric {
    template <Integrator I>
    DRAPE_INLINE static Vec3b accumulate(const StepContext& c, std::size_t p, const SelfBatch& s) noexcept {
        const simd::ubatch mask = simd::load(c.grid_mask + p);
        const fbatch zero(0.0f), one(1.0f), half(0.5f), two(2.0f);
        const fbatch beta(c.bend_beta);
        Vec3b f{zero, zero, zero};
        Vec3b D[GridStencil::slot_count];
#pragma GCC unroll 12
        for (std::size_t slot = 0; slot < GridStencil::slot_count; ++slot) {
            const std::ptrdiff_t q = static_cast<std::ptrdiff_t>(p) + c.grid_offset[slot];
            const fbatch xj = simd::loadu(c.x + q), yj = simd::loadu(c.y + q), zj = simd::loadu(c.z + q);
            const fbatch uj = simd::loadu(c.u + q), vj = simd::loadu(c.v + q), wj = simd::loadu(c.w + q);
            const bool spring = slot != grid_slot::up2 && slot != grid_slot::left2 && slot != grid_slot::right2 &&
                                slot != grid_slot::down2;
            const bool structural = slot == grid_slot::up || slot == grid_slot::left || slot == grid_slot::right ||
                                    slot == grid_slot::down;
            if (spring) {
                Vec3b d;
                fbatch coef = spring_coefficient<I>(s, xj, yj, zj, uj, vj, wj, fbatch(c.grid_k[slot]),
                                                    fbatch(c.grid_krest[slot]), fbatch(c.grid_kd[slot]), d);
                // Half stiffness (a boundary edge): the coefficient is linear in k, k l0 and kd, and halving is exact
                // in float, so halving it gives the bits of the CSR path's halved constants.
                if (structural)
                    coef = coef * simd::select(simd::test_bits(mask, 1u << (GridStencil::half_bit + slot)), half, one);
                coef = simd::select(simd::test_bits(mask, 1u << slot), coef, zero);
                f.x = simd::fma(coef, d.x, f.x);
                f.y = simd::fma(coef, d.y, f.y);
                f.z = simd::fma(coef, d.z, f.z);
            }
            D[slot].x = damped_difference<I>(xj - s.x, uj - s.u, beta);
            D[slot].y = damped_difference<I>(yj - s.y, vj - s.v, beta);
            D[slot].z = damped_difference<I>(zj - s.z, wj - s.w, beta);
        }
        using namespace grid_slot;
        auto exists = [&](std::uint32_t bit) { return simd::test_bits(mask, 1u << bit); };
        // Second differences along the row (slots left2, left, right, right2) and the column (up2, up, down, down2).
        const fbatch wu = simd::select(exists(GridStencil::edge_row_bit), half, one) * fbatch(c.grid_bend_u);
        const fbatch wv = simd::select(exists(GridStencil::edge_column_bit), half, one) * fbatch(c.grid_bend_v);
        const fmask ul = exists(GridStencil::bend_u_bit), u0 = exists(GridStencil::bend_u_bit + 1),
                    ur = exists(GridStencil::bend_u_bit + 2);
        const fmask vu = exists(GridStencil::bend_v_bit), v0 = exists(GridStencil::bend_v_bit + 1),
                    vd = exists(GridStencil::bend_v_bit + 2);
        const fmask c_ul = exists(up_left), c_ur = exists(up_right), c_dl = exists(down_left),
                    c_dr = exists(down_right);
        const fbatch wt(c.grid_twist);
        auto component = [&](fbatch Vec3b::*m) {
            auto at = [&](std::size_t slot) { return D[slot].*m; };
            // Row: 2 q_i - q_{i-1} - q_{i+1}, each where it exists.
            fbatch row = simd::select(u0, two * (at(left) + at(right)), zero);
            row = row - simd::select(ul, simd::fnma(two, at(left), at(left2)), zero);
            row = row - simd::select(ur, simd::fnma(two, at(right), at(right2)), zero);
            fbatch col = simd::select(v0, two * (at(up) + at(down)), zero);
            col = col - simd::select(vu, simd::fnma(two, at(up), at(up2)), zero);
            col = col - simd::select(vd, simd::fnma(two, at(down), at(down2)), zero);
            // Twist: -q(up-left cell) + q(up-right) + q(down-left) - q(down-right).
            fbatch tw = zero;
            tw = tw - simd::select(c_ul, at(up_left) - at(up) - at(left), zero);
            tw = tw + simd::select(c_ur, at(up) - at(up_right) + at(right), zero);
            tw = tw + simd::select(c_dl, at(left) - at(down_left) + at(down), zero);
            tw = tw - simd::select(c_dr, at(down_right) - at(right) - at(down), zero);
            return simd::fma(wu, row, simd::fma(wv, col, wt * tw));
        };
        f.x = f.x + component(&Vec3b::x);
        f.y = f.y + component(&Vec3b::y);
        f.z = f.z + component(&Vec3b::z);
        return f;
    }
};

/// Stage pass: spring forces of particles [begin, end) into the scratch arrays fx, fy, fz.
/// With `seams`, adds the seam forces written by the seam_forces stage (as the fused pass does); with c.bending,
/// the bending forces (GridFabric / CsrFabric).
void spring_forces_range(const StepContext& c, Integrator integrator, KernelPath path, bool seams, std::size_t begin,
                         std::size_t end);

} // namespace drape::kernels
