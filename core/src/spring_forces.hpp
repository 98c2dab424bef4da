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

#include <utility>

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

/// The grid stencil's slots (scene_hang.cpp builds them in this order: ascending offset; "up" is row j - 1).
namespace grid_slot {
inline constexpr std::size_t up2 = 0, up_left = 1, up = 2, up_right = 3, left2 = 4, left = 5, right = 6, right2 = 7,
                             down_left = 8, down = 9, down_right = 10, down2 = 11;
}

/// Regular-grid stencil: neighbours at fixed offsets, contiguous unaligned loads, a per-particle slot mask. Ignores the
/// half-stiffness bits: a grid that has them (GridStencil::half_edges, the fabric model) runs GridFabric.
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

/// acc + a b: one rounding (fma) on every cloth; on a mirror-exact cloth (Cloth::mirror, mirror_symmetry.hpp) the
/// product and the sum rounded apart, so that a term followed by its mirror image cancels exactly: a particle on the
/// centre line sums each neighbour next to its twin, and with fma a pair leaves the product's rounding error behind.
template <bool Exact> DRAPE_INLINE fbatch accumulate_term(fbatch a, fbatch b, fbatch acc) noexcept {
    if constexpr (Exact) return acc + a * b;
    else return simd::fma(a, b, acc);
}

/// General path: SIMD-sliced CSR, gathers of the neighbour state. Inert padding entries contribute exactly 0.
/// Exact: accumulate_term's mirror-exact form.
template <bool Exact> struct CsrSpringsT {
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
            f.x = accumulate_term<Exact>(coef, d.x, f.x);
            f.y = accumulate_term<Exact>(coef, d.y, f.y);
            f.z = accumulate_term<Exact>(coef, d.z, f.z);
        }
        return f;
    }
};
using CsrSprings = CsrSpringsT<false>;

/// A neighbour's position difference plus beta times its velocity difference, d + beta (v_j - v_i): what Rayleigh
/// damping adds to a linear force (bending: f = -Q (x + beta v)). d = x_j - x_i, du = u_j - u_i of the integrator's
/// state; `beta` is StepContext::bend_beta. The one place the bending kernels read u, v, w:
///   symplectic Euler: u is the velocity, so d + beta du;
///   position Verlet: u is the displacement over the last step, v_j - v_i = du / dt, so d + (beta / dt) du with
///   bend_beta = beta / dt: the same operation.
template <Integrator I> DRAPE_INLINE fbatch damped_difference(fbatch d, fbatch du, fbatch beta) noexcept {
    return simd::fma(beta, du, d);
}

/// Bending over Q's SIMD-sliced rows (general path): f_i = sum_j -Q_ij (d_j + beta (v_j - v_i)), gathers of the
/// neighbour state. Padding entries (the particle itself, coefficient 0) contribute exactly 0. Exact: as CsrSpringsT.
template <bool Exact> struct CsrBendingT {
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
            f.x = accumulate_term<Exact>(a, dx, f.x);
            f.y = accumulate_term<Exact>(a, dy, f.y);
            f.z = accumulate_term<Exact>(a, dz, f.z);
        }
    }
};

/// General path with bending (fabric model on any mesh): springs, then bending. Exact: as CsrSpringsT.
template <bool Exact> struct CsrFabricT {
    template <Integrator I>
    DRAPE_INLINE static Vec3b accumulate(const StepContext& c, std::size_t p, const SelfBatch& s) noexcept {
        const Vec3b f = CsrSpringsT<Exact>::template accumulate<I>(c, p, s);
        const fbatch zero(0.0f);
        Vec3b fb{zero, zero, zero}; // its own accumulator, as GridFabric's
        CsrBendingT<Exact>::template accumulate<I>(c, p, s, fb);
        return {f.x + fb.x, f.y + fb.y, f.z + fb.z};
    }
};
using CsrFabric = CsrFabricT<false>;

/// Regular-grid fabric (MaterialModel::fabric on a grid), one pass over the 12 slots in ascending order, each
/// neighbour loaded once:
///   * the 8 membrane springs (structural with the per-particle half-stiffness bits of boundary edges, diagonals)
///     into f, as GridSprings (the 4 bend slots carry no spring);
///   * bending into fb: fb += a_s D_s, D_s = damped_difference of neighbour s and a_s = -Q_ij, its entry of Q's row,
///     from the mask bits (which elements exist, boundary halves) and the three weights (GridBending):
///       row:    a(-2) = -w_u [elem at i-1],  a(-1) = 2 w_u ([elem at i] + [elem at i-1]) + w_t ([cell up-left] +
///               [cell down-left]),  mirrored for +1, +2 (w_u halved on a boundary row);
///       column: the same with w_v, up / down;  diagonals: a = -w_t [its cell];
///   * f + fb.
/// Every a_s is one float rounding of an exact sum (a weight times 1, 2 or 4, plus w_t times 0, 1 or 2), the value
/// Q's assembled row holds; the CSR path (CsrFabric) sums springs, then Q's row into its own accumulator, both by
/// ascending neighbour (= slot order), then adds the two: the grid and CSR fabric kernels agree bit for bit (tested).
struct GridFabric {
    template <std::size_t S>
    DRAPE_INLINE static fbatch bend_coefficient(simd::ubatch mask, fbatch wu, fbatch wv, fbatch wt) noexcept {
        using namespace grid_slot;
        const fbatch one(1.0f), zero(0.0f), two(2.0f);
        auto has = [&](std::uint32_t bit) { return simd::select(simd::test_bits(mask, 1u << bit), one, zero); };
        constexpr std::uint32_t U = GridStencil::bend_u_bit, V = GridStencil::bend_v_bit;
        if constexpr (S == up2) return -(has(V) * wv);
        else if constexpr (S == down2) return -(has(V + 2) * wv);
        else if constexpr (S == left2) return -(has(U) * wu);
        else if constexpr (S == right2) return -(has(U + 2) * wu);
        else if constexpr (S == up) return (two * (has(V + 1) + has(V))) * wv + (has(up_left) + has(up_right)) * wt;
        else if constexpr (S == down) return (two * (has(V + 1) + has(V + 2))) * wv + (has(down_left) + has(down_right)) * wt;
        else if constexpr (S == left) return (two * (has(U + 1) + has(U))) * wu + (has(up_left) + has(down_left)) * wt;
        else if constexpr (S == right) return (two * (has(U + 1) + has(U + 2))) * wu + (has(up_right) + has(down_right)) * wt;
        else return -(has(S) * wt); // a diagonal: its cell's twist element
    }

    template <Integrator I, std::size_t S>
    DRAPE_INLINE static void slot(const StepContext& c, std::size_t p, const SelfBatch& s, simd::ubatch mask,
                                  fbatch wu, fbatch wv, fbatch wt, Vec3b& f, Vec3b& fb) noexcept {
        using namespace grid_slot;
        const fbatch zero(0.0f), one(1.0f), half(0.5f);
        const std::ptrdiff_t q = static_cast<std::ptrdiff_t>(p) + c.grid_offset[S];
        const fbatch xj = simd::loadu(c.x + q), yj = simd::loadu(c.y + q), zj = simd::loadu(c.z + q);
        const fbatch uj = simd::loadu(c.u + q), vj = simd::loadu(c.v + q), wj = simd::loadu(c.w + q);
        if constexpr (S != up2 && S != left2 && S != right2 && S != down2) {
            Vec3b d;
            fbatch coef = spring_coefficient<I>(s, xj, yj, zj, uj, vj, wj, fbatch(c.grid_k[S]), fbatch(c.grid_krest[S]),
                                                fbatch(c.grid_kd[S]), d);
            // Half stiffness (a boundary edge): the coefficient is linear in k, k l0 and kd, and halving is exact in
            // float, so halving it gives the bits of the CSR path's halved constants.
            if constexpr (S == up || S == left || S == right || S == down)
                coef = coef * simd::select(simd::test_bits(mask, 1u << (GridStencil::half_bit + S)), half, one);
            coef = simd::select(simd::test_bits(mask, 1u << S), coef, zero);
            f.x = simd::fma(coef, d.x, f.x);
            f.y = simd::fma(coef, d.y, f.y);
            f.z = simd::fma(coef, d.z, f.z);
        }
        const fbatch a = bend_coefficient<S>(mask, wu, wv, wt), beta(c.bend_beta);
        fb.x = simd::fma(a, damped_difference<I>(xj - s.x, uj - s.u, beta), fb.x);
        fb.y = simd::fma(a, damped_difference<I>(yj - s.y, vj - s.v, beta), fb.y);
        fb.z = simd::fma(a, damped_difference<I>(zj - s.z, wj - s.w, beta), fb.z);
    }

    template <Integrator I, std::size_t... S>
    DRAPE_INLINE static Vec3b slots(const StepContext& c, std::size_t p, const SelfBatch& s,
                                    std::index_sequence<S...>) noexcept {
        const simd::ubatch mask = simd::load(c.grid_mask + p);
        const fbatch zero(0.0f), one(1.0f), half(0.5f);
        const fbatch wu = simd::select(simd::test_bits(mask, 1u << GridStencil::edge_row_bit), half, one) *
                          fbatch(c.grid_bend_u);
        const fbatch wv = simd::select(simd::test_bits(mask, 1u << GridStencil::edge_column_bit), half, one) *
                          fbatch(c.grid_bend_v);
        const fbatch wt(c.grid_twist);
        Vec3b f{zero, zero, zero}, fb{zero, zero, zero};
        (slot<I, S>(c, p, s, mask, wu, wv, wt, f, fb), ...);
        return {f.x + fb.x, f.y + fb.y, f.z + fb.z};
    }

    template <Integrator I>
    DRAPE_INLINE static Vec3b accumulate(const StepContext& c, std::size_t p, const SelfBatch& s) noexcept {
        return slots<I>(c, p, s, std::make_index_sequence<GridStencil::slot_count>{});
    }
};

/// Stage pass: spring forces of particles [begin, end) into the scratch arrays fx, fy, fz.
/// With `seams`, adds the seam forces written by the seam_forces stage (as the fused pass does); with c.bending,
/// the bending forces (GridFabric / CsrFabric).
void spring_forces_range(const StepContext& c, Integrator integrator, KernelPath path, bool seams, std::size_t begin,
                         std::size_t end);

} // namespace drape::kernels
