// Vertex block descent's local step for simd::width vertices of one colour at once (one SIMD lane each): the same
// operations in the same order as the scalar solve_vertex (vbd.hpp), lane by lane, so both give the same bits
// (tests/test_implicit.cpp checks it). Springs and bending rows come SIMD-sliced per colour (VbdSlices): slot s of a
// slice holds the s-th spring (bending entry) of each of its vertices, padded with inert entries (the vertex itself,
// k = kd = rest = 0; q = 0) that add exactly nothing.
#pragma once

#include <cstdint>

#include "drape/aligned_array.hpp"
#include "drape/simd.hpp"
#include "vbd.hpp"

namespace drape::vbd {

/// The colours' vertices in SIMD slices (cooked by Solver::cook).
struct VbdSlices {
    std::vector<std::uint32_t> colour_slices; ///< per colour: its first slice (colour_count + 1)
    std::vector<std::uint32_t> lanes;         ///< per slice: vertices in it (<= width; the rest are inert)
    AlignedArray<std::uint32_t> vertex;       ///< per slice x lane (inert lanes: the slice's first vertex)
    std::vector<std::uint32_t> spring_begin, spring_slots, bend_begin, bend_slots; ///< per slice
    AlignedArray<std::uint32_t> spring_neighbour, spring_edge; ///< per slot x lane (padding: UINT32_MAX edge)
    AlignedArray<float> spring_k, spring_kd, spring_rest;
    AlignedArray<std::uint32_t> bend_neighbour;
    AlignedArray<float> bend_q;
};

/// Spring damping's coefficient q = (kd / h) / |n|^2 of one slot (0 where kd = 0 or n, the spring at the start of the
/// step, has no length), and its Hessian block q n n^T added to an accumulator (DampingHessian, vbd.hpp): both depend only on the state at the
/// start of the step, so a grid cloth computes them once per step (GridLayout::cook_damping) and its sweeps read
/// them; the other sources compute them in the sweep with these same operations (the same bits).
inline simd::fbatch damping_q(simd::fbatch kd, simd::fbatch inv_h, simd::fbatch nx, simd::fbatch ny,
                              simd::fbatch nz) noexcept {
    const simd::fbatch zero(0.0f), one(1.0f), k = kd * inv_h;
    const simd::fbatch n2 = simd::fma(nz, nz, simd::fma(ny, ny, nx * nx));
    const simd::fmask damped = (k > zero) & (n2 > simd::fbatch(1e-24f));
    return simd::select(damped, k / simd::select(damped, n2, one), zero);
}
/// The local step of simd::width vertices at once, one per lane, from a source of their state and their springs and
/// bending rows (slot by slot; padded slots add exactly nothing). Writes the new positions and |g|^2 per lane
/// (GradientOnly: the gradient of G at the iterate instead of the new position, as solve_vertex<true>). `hess`
/// (optional, 6 batches): the local Hessians the step solved with, as solve_vertex's.
/// Sources: SliceSource below (a colour's slice, neighbours gathered) and GridSource (vbd_grid.hpp: a grid cloth in
/// colour sub-grids, neighbours loaded contiguously). The operations and their order are those of the scalar
/// solve_vertex (vbd.hpp), so every source gives its bits.
template <bool GradientOnly = false, bool Exact = false, class Src>
inline void solve_lanes(const Src& src, const SweepArgs& a, simd::fbatch& out_x, simd::fbatch& out_y,
                        simd::fbatch& out_z, simd::fbatch& out_g2, simd::fbatch* hess = nullptr) noexcept {
    using simd::fbatch;
    using simd::fmask;
    constexpr std::size_t W = simd::width;
    const VbdGraph& g = *a.graph;
    const fbatch zero(0.0f), one(1.0f);
    const fbatch xi = src.own(a.x), yi = src.own(a.y), zi = src.own(a.z);
    const fbatch x0i = src.own(a.x0), y0i = src.own(a.y0), z0i = src.own(a.z0);
    const fbatch dxi = xi - x0i, dyi = yi - y0i, dzi = zi - z0i;
    fbatch w = src.own(a.inv_mass);
    w = simd::select(w == zero, one, w); // fixed lanes are not written: keep their arithmetic finite
    const fbatch m = one / w;
    const fbatch mi = m * fbatch(a.inv_h2), md = m * fbatch(a.drag_over_h);
    fbatch gx = simd::fma(mi, xi - src.own(a.px), md * dxi);
    fbatch gy = simd::fma(mi, yi - src.own(a.py), md * dyi);
    fbatch gz = simd::fma(mi, zi - src.own(a.pz), md * dzi);
    const fbatch base = mi + md;
    fbatch hxx = base, hyy = hxx, hzz = hxx, hxy = zero, hxz = zero, hyz = zero;
    DampingHessian<simd::fbatch> dh; // the springs' damping, summed from zero (cooked per step by a grid source)
    if constexpr (Src::cooked_damping) dh = src.damping_hessian();
    fbatch sgx = zero, sgy = zero, sgz = zero;
    const fbatch inv_h(a.inv_h), tiny(1e-24f);
    const std::size_t ss = src.springs();
    // The line search below reuses each spring's d = x_j - x_i and |d| (the same values it would recompute).
    constexpr std::size_t cached_slots = 16;
    alignas(64) float cache_dx[cached_slots][W], cache_dy[cached_slots][W], cache_dz[cached_slots][W],
        cache_l0[cached_slots][W];
    for (std::size_t s = 0; s < ss; ++s) {
        const fbatch k = src.spring_k(s), l = src.spring_rest(s);
        fbatch xj, yj, zj;
        src.spring_pos(s, a.x, a.y, a.z, xj, yj, zj);
        const fbatch dx = xj - xi, dy = yj - yi, dz = zj - zi;
        const fbatch len2 = simd::fma(dz, dz, simd::fma(dy, dy, dx * dx));
        // 1/|d| to ~23 bits without a division (rsqrt14 and a Newton step: the divider is this kernel's bottleneck;
        // docs/implicit.md "Fused and division-free sweeps"); |d| = |d|^2 / |d|.
        const fmask stretched = len2 > tiny;
        const fbatch inv_len = simd::rsqrt(simd::select(stretched, len2, one));
        const fbatch l0 = len2 * inv_len;
        if (s < cached_slots) {
            simd::store(cache_dx[s], dx);
            simd::store(cache_dy[s], dy);
            simd::store(cache_dz[s], dz);
            simd::store(cache_l0[s], l0);
        }
        const fbatch ux = dx * inv_len, uy = dy * inv_len, uz = dz * inv_len;
        const fbatch sforce = simd::select(stretched, k * (l0 - l), zero);
        sgx = accumulate_neg<Exact>(sforce, ux, sgx);
        sgy = accumulate_neg<Exact>(sforce, uy, sgy);
        sgz = accumulate_neg<Exact>(sforce, uz, sgz);
        const fbatch c = k * xsimd::max(zero, simd::fnma(l, inv_len, one));
        // A zero-length spring at its rest: Hessian k I.
        const fbatch cm = simd::select(stretched, c, simd::select(l == zero, k, zero));
        const fbatch cu = simd::select(stretched, k - c, zero);
        add_isotropic_outer<Exact>(cm, cu, ux, uy, uz, hxx, hyy, hzz, hxy, hxz, hyz);
        fbatch x0j, y0j, z0j;
        src.spring_pos(s, a.x0, a.y0, a.z0, x0j, y0j, z0j);
        const fbatch nx = x0j - x0i, ny = y0j - y0i, nz = z0j - z0i;
        fbatch q;
        if constexpr (Src::cooked_damping) {
            q = src.damping_q(s);
        } else {
            q = damping_q(src.spring_kd(s), inv_h, nx, ny, nz);
            dh.template add<Exact>(q, nx, ny, nz);
        }
        const fbatch p = q * simd::fma(dz - nz, nz, simd::fma(dy - ny, ny, (dx - nx) * nx));
        gx = accumulate_neg<Exact>(p, nx, gx);
        gy = accumulate_neg<Exact>(p, ny, gy);
        gz = accumulate_neg<Exact>(p, nz, gz);
    }
    fbatch qhxx = base + dh.xx, qhyy = base + dh.yy, qhzz = base + dh.zz, qhxy = dh.xy, qhxz = dh.xz, qhyz = dh.yz;
    if (!g.bend_diag.empty()) {
        const fbatch bh = fbatch(g.bend_beta) * inv_h;
        fbatch bx = zero, by = zero, bz = zero;
        const std::size_t bs = src.bends();
        for (std::size_t s = 0; s < bs; ++s) {
            const fbatch q = src.bend_q(s);
            fbatch xj, yj, zj, x0j, y0j, z0j;
            src.bend_pos(s, a.x, a.y, a.z, xj, yj, zj);
            src.bend_pos(s, a.x0, a.y0, a.z0, x0j, y0j, z0j);
            bx = accumulate<Exact>(q, simd::fma(bh, (xj - x0j) - dxi, xj - xi), bx);
            by = accumulate<Exact>(q, simd::fma(bh, (yj - y0j) - dyi, yj - yi), by);
            bz = accumulate<Exact>(q, simd::fma(bh, (zj - z0j) - dzi, zj - zi), bz);
        }
        gx = gx + bx;
        gy = gy + by;
        gz = gz + bz;
        const fbatch d = src.bend_diag() * (one + bh);
        qhxx = qhxx + d;
        qhyy = qhyy + d;
        qhzz = qhzz + d;
    }
    if (a.fr_k != nullptr) { // friction, as solve_vertex
        const fbatch nx = src.own(a.fr_nx), ny = src.own(a.fr_ny), nz = src.own(a.fr_nz);
        const fbatch dn = simd::fma(dzi, nz, simd::fma(dyi, ny, dxi * nx));
        const fbatch ux = simd::fnma(dn, nx, dxi), uy = simd::fnma(dn, ny, dyi), uz = simd::fnma(dn, nz, dzi);
        const fbatch s = xsimd::sqrt(simd::fma(uz, uz, simd::fma(uy, uy, ux * ux)));
        const fbatch wf = friction_weight(src.own(a.fr_k), s, fbatch(a.fr_eps));
        gx = accumulate<Exact>(wf, ux, gx);
        gy = accumulate<Exact>(wf, uy, gy);
        gz = accumulate<Exact>(wf, uz, gz);
        add_isotropic_outer<Exact>(wf, -wf, nx, ny, nz, qhxx, qhyy, qhzz, qhxy, qhxz, qhyz);
    }
    hxx = hxx + (qhxx - base);
    hyy = hyy + (qhyy - base);
    hzz = hzz + (qhzz - base);
    hxy = hxy + qhxy;
    hxz = hxz + qhxz;
    hyz = hyz + qhyz;
    const fbatch qgx = gx, qgy = gy, qgz = gz;
    gx = gx + sgx;
    gy = gy + sgy;
    gz = gz + sgz;
    if constexpr (GradientOnly) { // the gradient of G at the iterate (solve_vertex<true>), no step
        out_x = gx;
        out_y = gy;
        out_z = gz;
        out_g2 = gx * gx + gy * gy + gz * gz;
        return;
    }
    if (hess != nullptr) write_hessian(hess, hxx, hyy, hzz, hxy, hxz, hyz);
    const fbatch c00 = hyy * hzz - hyz * hyz, c01 = hxz * hyz - hxy * hzz, c02 = hxy * hyz - hxz * hyy;
    const fbatch c11 = hxx * hzz - hxz * hxz, c12 = hxy * hxz - hxx * hyz, c22 = hxx * hyy - hxy * hxy;
    const fbatch det = hxx * c00 + hxy * c01 + hxz * c02;
    const fbatch inv_det = one / det;
    fbatch ddx = -((c00 * gx + c01 * gy + c02 * gz) * inv_det);
    fbatch ddy = -((c01 * gx + c11 * gy + c12 * gz) * inv_det);
    fbatch ddz = -((c02 * gx + c12 * gy + c22 * gz) * inv_det);
    auto change = [&](fbatch px, fbatch py, fbatch pz) {
        fbatch e = qgx * px + qgy * py + qgz * pz + fbatch(0.5f) * (qhxx * px * px + qhyy * py * py + qhzz * pz * pz) +
                   qhxy * px * py + qhxz * px * pz + qhyz * py * pz;
        const fbatch p2 = px * px + py * py + pz * pz;
        for (std::size_t s = 0; s < ss; ++s) {
            fbatch dx, dy, dz, l0;
            if (s < cached_slots) {
                dx = simd::load(cache_dx[s]);
                dy = simd::load(cache_dy[s]);
                dz = simd::load(cache_dz[s]);
                l0 = simd::load(cache_l0[s]);
            } else {
                fbatch xj, yj, zj;
                src.spring_pos(s, a.x, a.y, a.z, xj, yj, zj);
                dx = xj - xi;
                dy = yj - yi;
                dz = zj - zi;
                const fbatch len2 = simd::fma(dz, dz, simd::fma(dy, dy, dx * dx));
                l0 = len2 * simd::rsqrt(simd::select(len2 > tiny, len2, one));
            }
            const fbatch ex = dx - px, ey = dy - py, ez = dz - pz;
            const fbatch l1 = xsimd::sqrt(simd::fma(ez, ez, simd::fma(ey, ey, ex * ex)));
            const fbatch sum = l0 + l1;
            const fmask live = sum > zero;
            const fbatch two(2.0f);
            const fbatch dl =
                simd::fnma(two, simd::fma(dz, pz, simd::fma(dy, py, dx * px)), p2) / simd::select(live, sum, one);
            const fbatch de = fbatch(0.5f) * src.spring_k(s) * dl * simd::fnma(two, src.spring_rest(s), sum);
            e = e + simd::select(live, de, zero);
        }
        return e;
    };
    // As the scalar solve_vertex: a step that is not finite is no step (lanes outside the cloth too: their Hessian is
    // 0), a change that is not finite counts as a rise.
    const fbatch sum_dd = ddx + ddy + ddz;
    const fmask finite = (sum_dd - sum_dd) == zero;
    ddx = simd::select(finite, ddx, zero);
    ddy = simd::select(finite, ddy, zero);
    ddz = simd::select(finite, ddz, zero);
    fmask searching(true);
    for (int halving = 0; halving < vbd_line_search_halvings; ++halving) {
        searching = searching & !(change(ddx, ddy, ddz) <= zero);
        if (!xsimd::any(searching)) break;
        const fbatch half(0.5f);
        ddx = simd::select(searching, ddx * half, ddx);
        ddy = simd::select(searching, ddy * half, ddy);
        ddz = simd::select(searching, ddz * half, ddz);
        if (halving == vbd_line_search_halvings - 1) {
            ddx = simd::select(searching, zero, ddx);
            ddy = simd::select(searching, zero, ddy);
            ddz = simd::select(searching, zero, ddz);
        }
    }
    out_x = xi + ddx;
    out_y = yi + ddy;
    out_z = zi + ddz;
    out_g2 = gx * gx + gy * gy + gz * gz;
}


/// A slice of a colour's vertices (VbdSlices): own state and neighbours gathered by index.
struct SliceSource {
    static constexpr bool cooked_damping = false;
    const VbdSlices& sl;
    const VbdGraph& graph;
    simd::ibatch vi;
    std::size_t sb, ss, bb, bs;
    SliceSource(const VbdSlices& slices, const VbdGraph& g, std::size_t slice) noexcept
        : sl(slices), graph(g), vi(simd::load_indices(slices.vertex.data() + slice * simd::width)),
          sb(slices.spring_begin[slice]), ss(slices.spring_slots[slice]), bb(slices.bend_begin[slice]),
          bs(slices.bend_slots[slice]) {}
    simd::fbatch own(const float* f) const noexcept { return simd::gather(f, vi); }
    std::size_t springs() const noexcept { return ss; }
    std::size_t bends() const noexcept { return bs; }
    simd::fbatch spring_k(std::size_t s) const noexcept { return simd::load(sl.spring_k.data() + sb + s * simd::width); }
    simd::fbatch spring_kd(std::size_t s) const noexcept { return simd::load(sl.spring_kd.data() + sb + s * simd::width); }
    simd::fbatch spring_rest(std::size_t s) const noexcept {
        return simd::load(sl.spring_rest.data() + sb + s * simd::width);
    }
    void spring_pos(std::size_t s, const float* x, const float* y, const float* z, simd::fbatch& ox, simd::fbatch& oy,
                    simd::fbatch& oz) const noexcept {
        gather3(sl.spring_neighbour.data() + sb + s * simd::width, x, y, z, ox, oy, oz);
    }
    simd::fbatch bend_q(std::size_t s) const noexcept { return simd::load(sl.bend_q.data() + bb + s * simd::width); }
    void bend_pos(std::size_t s, const float* x, const float* y, const float* z, simd::fbatch& ox, simd::fbatch& oy,
                  simd::fbatch& oz) const noexcept {
        gather3(sl.bend_neighbour.data() + bb + s * simd::width, x, y, z, ox, oy, oz);
    }
    simd::fbatch bend_diag() const noexcept { return simd::gather(graph.bend_diag.data(), vi); }
    static void gather3(const std::uint32_t* index, const float* x, const float* y, const float* z, simd::fbatch& ox,
                        simd::fbatch& oy, simd::fbatch& oz) noexcept {
        const simd::ibatch j = simd::load_indices(index);
        ox = simd::gather(x, j);
        oy = simd::gather(y, j);
        oz = simd::gather(z, j);
    }
};

/// The local step of the slice's lanes (all of them computed; the caller writes only the live, movable ones): new
/// positions into out_x/y/z, |g|^2 into g2 (lanes of width floats).
/// `hess` (optional): the lanes' local Hessians, hess[c * width + lane] for component c (xx yy zz xy xz yz).
template <bool Exact = false>
inline void solve_batch(const SweepArgs& a, const VbdSlices& sl, std::size_t slice, float* out_x, float* out_y,
                        float* out_z, float* g2, float* hess = nullptr) noexcept {
    simd::fbatch ox, oy, oz, og, h[6];
    solve_lanes<false, Exact>(SliceSource(sl, *a.graph, slice), a, ox, oy, oz, og, hess != nullptr ? h : nullptr);
    ox.store_unaligned(out_x);
    oy.store_unaligned(out_y);
    oz.store_unaligned(out_z);
    og.store_unaligned(g2);
    if (hess != nullptr)
        for (std::size_t c = 0; c < 6; ++c) h[c].store_unaligned(hess + c * simd::width);
}

} // namespace drape::vbd
