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

/// The local step of the slice's lanes (all of them computed; the caller writes only the live, movable ones): new
/// positions into out_x/y/z, |g|^2 into g2 (lanes of width floats).
inline void solve_batch(const SweepArgs& a, const VbdSlices& sl, std::size_t slice, float* out_x, float* out_y,
                        float* out_z, float* g2) noexcept {
    using simd::fbatch;
    using simd::fmask;
    using simd::ibatch;
    auto indices = [](const std::uint32_t* p) { return simd::load_indices(p); };
    const VbdGraph& g = *a.graph;
    constexpr std::size_t W = simd::width;
    const ibatch vi = indices(sl.vertex.data() + slice * W);
    const fbatch zero(0.0f), one(1.0f);
    const fbatch xi = simd::gather(a.x, vi), yi = simd::gather(a.y, vi), zi = simd::gather(a.z, vi);
    const fbatch x0i = simd::gather(a.x0, vi), y0i = simd::gather(a.y0, vi), z0i = simd::gather(a.z0, vi);
    const fbatch dxi = xi - x0i, dyi = yi - y0i, dzi = zi - z0i;
    fbatch w = simd::gather(a.inv_mass, vi);
    w = simd::select(w == zero, one, w); // fixed lanes are not written: keep their arithmetic finite
    const fbatch m = one / w;
    const fbatch mi = m * fbatch(a.inv_h2), md = m * fbatch(a.drag_over_h);
    fbatch gx = mi * (xi - simd::gather(a.px, vi)) + md * dxi;
    fbatch gy = mi * (yi - simd::gather(a.py, vi)) + md * dyi;
    fbatch gz = mi * (zi - simd::gather(a.pz, vi)) + md * dzi;
    fbatch hxx = mi + md, hyy = hxx, hzz = hxx, hxy = zero, hxz = zero, hyz = zero;
    fbatch qhxx = hxx, qhyy = hxx, qhzz = hxx, qhxy = zero, qhxz = zero, qhyz = zero;
    fbatch sgx = zero, sgy = zero, sgz = zero;
    const fbatch inv_h(a.inv_h), tiny(1e-24f);
    const std::size_t sb = sl.spring_begin[slice], ss = sl.spring_slots[slice];
    // The line search below reuses each spring's d = x_j - x_i and |d| (the same values it would recompute).
    constexpr std::size_t cached_slots = 16;
    alignas(64) float cache_dx[cached_slots][W], cache_dy[cached_slots][W], cache_dz[cached_slots][W],
        cache_l0[cached_slots][W];
    for (std::size_t s = 0; s < ss; ++s) {
        const std::size_t at = sb + s * W;
        const ibatch j = indices(sl.spring_neighbour.data() + at);
        const fbatch k = simd::load(sl.spring_k.data() + at), l = simd::load(sl.spring_rest.data() + at);
        const fbatch xj = simd::gather(a.x, j), yj = simd::gather(a.y, j), zj = simd::gather(a.z, j);
        const fbatch dx = xj - xi, dy = yj - yi, dz = zj - zi;
        const fbatch len2 = dx * dx + dy * dy + dz * dz;
        if (s < cached_slots) {
            simd::store(cache_dx[s], dx);
            simd::store(cache_dy[s], dy);
            simd::store(cache_dz[s], dz);
            simd::store(cache_l0[s], xsimd::sqrt(len2));
        }
        const fmask stretched = len2 > tiny;
        const fbatch inv_len = one / xsimd::sqrt(simd::select(stretched, len2, one));
        const fbatch len = len2 * inv_len;
        const fbatch ux = dx * inv_len, uy = dy * inv_len, uz = dz * inv_len;
        const fbatch sforce = k * (len - l);
        sgx = sgx - simd::select(stretched, sforce * ux, zero);
        sgy = sgy - simd::select(stretched, sforce * uy, zero);
        sgz = sgz - simd::select(stretched, sforce * uz, zero);
        const fbatch c = k * xsimd::max(zero, one - l * inv_len), cu = k - c;
        hxx = hxx + simd::select(stretched, c + cu * ux * ux, zero);
        hyy = hyy + simd::select(stretched, c + cu * uy * uy, zero);
        hzz = hzz + simd::select(stretched, c + cu * uz * uz, zero);
        hxy = hxy + simd::select(stretched, cu * ux * uy, zero);
        hxz = hxz + simd::select(stretched, cu * ux * uz, zero);
        hyz = hyz + simd::select(stretched, cu * uy * uz, zero);
        const fmask at_rest = (~stretched) & (l == zero);
        hxx = hxx + simd::select(at_rest, k, zero);
        hyy = hyy + simd::select(at_rest, k, zero);
        hzz = hzz + simd::select(at_rest, k, zero);
        const fbatch kd = simd::load(sl.spring_kd.data() + at) * inv_h;
        const fbatch nx = simd::gather(a.x0, j) - x0i, ny = simd::gather(a.y0, j) - y0i,
                     nz = simd::gather(a.z0, j) - z0i;
        const fbatch n2 = nx * nx + ny * ny + nz * nz;
        const fmask damped = (kd > zero) & (n2 > tiny);
        const fbatch inv_n2 = one / simd::select(damped, n2, one);
        const fbatch ddx = (xj - simd::gather(a.x0, j)) - dxi, ddy = (yj - simd::gather(a.y0, j)) - dyi,
                     ddz = (zj - simd::gather(a.z0, j)) - dzi;
        const fbatch p = kd * (ddx * nx + ddy * ny + ddz * nz) * inv_n2;
        gx = gx - simd::select(damped, p * nx, zero);
        gy = gy - simd::select(damped, p * ny, zero);
        gz = gz - simd::select(damped, p * nz, zero);
        const fbatch q = kd * inv_n2;
        qhxx = qhxx + simd::select(damped, q * nx * nx, zero);
        qhyy = qhyy + simd::select(damped, q * ny * ny, zero);
        qhzz = qhzz + simd::select(damped, q * nz * nz, zero);
        qhxy = qhxy + simd::select(damped, q * nx * ny, zero);
        qhxz = qhxz + simd::select(damped, q * nx * nz, zero);
        qhyz = qhyz + simd::select(damped, q * ny * nz, zero);
    }
    if (!g.bend_diag.empty()) {
        const fbatch bh = fbatch(g.bend_beta) * inv_h;
        fbatch bx = zero, by = zero, bz = zero;
        const std::size_t bb = sl.bend_begin[slice], bs = sl.bend_slots[slice];
        for (std::size_t s = 0; s < bs; ++s) {
            const std::size_t at = bb + s * W;
            const ibatch j = indices(sl.bend_neighbour.data() + at);
            const fbatch q = simd::load(sl.bend_q.data() + at);
            const fbatch xj = simd::gather(a.x, j), yj = simd::gather(a.y, j), zj = simd::gather(a.z, j);
            bx = bx + q * ((xj - xi) + bh * ((xj - simd::gather(a.x0, j)) - dxi));
            by = by + q * ((yj - yi) + bh * ((yj - simd::gather(a.y0, j)) - dyi));
            bz = bz + q * ((zj - zi) + bh * ((zj - simd::gather(a.z0, j)) - dzi));
        }
        gx = gx + bx;
        gy = gy + by;
        gz = gz + bz;
        const fbatch d = simd::gather(g.bend_diag.data(), vi) * (one + bh);
        qhxx = qhxx + d;
        qhyy = qhyy + d;
        qhzz = qhzz + d;
    }
    hxx = hxx + (qhxx - (mi + md));
    hyy = hyy + (qhyy - (mi + md));
    hzz = hzz + (qhzz - (mi + md));
    hxy = hxy + qhxy;
    hxz = hxz + qhxz;
    hyz = hyz + qhyz;
    const fbatch qgx = gx, qgy = gy, qgz = gz;
    gx = gx + sgx;
    gy = gy + sgy;
    gz = gz + sgz;
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
            const std::size_t at = sb + s * W;
            fbatch dx, dy, dz, l0;
            if (s < cached_slots) {
                dx = simd::load(cache_dx[s]);
                dy = simd::load(cache_dy[s]);
                dz = simd::load(cache_dz[s]);
                l0 = simd::load(cache_l0[s]);
            } else {
                const ibatch j = indices(sl.spring_neighbour.data() + at);
                dx = simd::gather(a.x, j) - xi;
                dy = simd::gather(a.y, j) - yi;
                dz = simd::gather(a.z, j) - zi;
                l0 = xsimd::sqrt(dx * dx + dy * dy + dz * dz);
            }
            const fbatch l1 = xsimd::sqrt((dx - px) * (dx - px) + (dy - py) * (dy - py) + (dz - pz) * (dz - pz));
            const fbatch sum = l0 + l1;
            const fmask live = sum > zero;
            const fbatch dl = (p2 - fbatch(2.0f) * (dx * px + dy * py + dz * pz)) / simd::select(live, sum, one);
            const fbatch de = fbatch(0.5f) * simd::load(sl.spring_k.data() + at) * dl *
                              (sum - fbatch(2.0f) * simd::load(sl.spring_rest.data() + at));
            e = e + simd::select(live, de, zero);
        }
        return e;
    };
    fmask searching(true);
    for (int halving = 0; halving < 8; ++halving) {
        searching = searching & (change(ddx, ddy, ddz) > zero);
        if (!xsimd::any(searching)) break;
        const fbatch half(0.5f);
        ddx = simd::select(searching, ddx * half, ddx);
        ddy = simd::select(searching, ddy * half, ddy);
        ddz = simd::select(searching, ddz * half, ddz);
        if (halving == 7) {
            ddx = simd::select(searching, zero, ddx);
            ddy = simd::select(searching, zero, ddy);
            ddz = simd::select(searching, zero, ddz);
        }
    }
    (xi + ddx).store_unaligned(out_x);
    (yi + ddy).store_unaligned(out_y);
    (zi + ddz).store_unaligned(out_z);
    (gx * gx + gy * gy + gz * gz).store_unaligned(g2);
}

} // namespace drape::vbd
