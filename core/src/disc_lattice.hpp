// The disc's rim case of the triangle contact's deepest point (triangle_contact.cpp): the signed distance to the solid
// cylinder at every point of a lattice on the triangle, the first smallest taken. A scalar reference and the SIMD
// kernel that triangle_contact uses; the same float operations in the same order (the build has -ffp-contract=off),
// so the same values and the same lattice point, bit for bit (tests/test_triangle_contact.cpp). Internal to drape_core
// (and its tests).
#pragma once

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

#include "drape/simd.hpp"

namespace drape::disc_lattice {

/// A triangle relative to the disc's top centre (a, and the edges u = b - a, v = c - a), the disc's radius R and
/// height h, m.
struct Triangle {
    float ax, ay, az, ux, uy, uz, vx, vy, vz, R, h;
};

/// The most intervals per side (the lattice then has (m + 1)(m + 2) / 2 points).
inline constexpr int max_intervals = 48;

/// Signed distance to the solid cylinder (minus the depth inside) at barycentric (1 - fs - fw, fs, fw).
inline float value(const Triangle& t, float fs, float fw) noexcept {
    const float px = t.ax + fs * t.ux + fw * t.vx, py = t.ay + fs * t.uy + fw * t.vy, pz = t.az + fs * t.uz + fw * t.vz;
    const float r = std::sqrt(px * px + pz * pz);
    const float er = r - t.R, ey = std::max(py, -t.h - py); // > 0 outside the faces
    if (er <= 0.0f && ey <= 0.0f) return std::max(er, ey);  // inside: minus the depth
    const float pr = std::max(er, 0.0f), py2 = std::max(ey, 0.0f);
    return std::sqrt(pr * pr + py2 * py2);
}

/// The lattice coordinate j / m as the lattice takes it (rounded to float from double).
inline float coordinate(int j, int m) noexcept { return float(double(j) / m); }

/// Scalar reference: {i, j} of the first lattice point (i outer, j inner, j <= m - i) with the smallest value.
inline std::array<int, 2> minimum_scalar(const Triangle& t, int m) noexcept {
    std::array<int, 2> best{0, 0};
    float fbest = std::numeric_limits<float>::max();
    for (int i = 0; i <= m; ++i)
        for (int j = 0; j <= m - i; ++j) {
            const float v = value(t, coordinate(i, m), coordinate(j, m));
            if (v < fbest) fbest = v, best = {i, j};
        }
    return best;
}

/// The same, simd::width points of a row at once (m <= max_intervals).
inline std::array<int, 2> minimum(const Triangle& t, int m) noexcept {
    assert(m >= 1 && m <= max_intervals);
    using simd::fbatch;
    constexpr std::size_t W = simd::width;
    alignas(64) float coord[max_intervals + 1 + W];
    for (int j = 0; j <= m; ++j) coord[j] = coordinate(j, m);
    std::fill(coord + m + 1, coord + m + 1 + W, 0.0f);
    alignas(64) float row[max_intervals + 1 + W];
    const fbatch vx(t.vx), vy(t.vy), vz(t.vz), R(t.R), minus_h(-t.h), zero(0.0f);
    std::array<int, 2> best{0, 0};
    float fbest = std::numeric_limits<float>::max();
    for (int i = 0; i <= m; ++i) {
        const float fs = coord[i];
        // The row's start a + fs u, as value() forms it: (a + fs u) + fw v.
        const fbatch sx(t.ax + fs * t.ux), sy(t.ay + fs * t.uy), sz(t.az + fs * t.uz);
        const int count = m - i + 1;
        for (int j0 = 0; j0 < count; j0 += int(W)) {
            const fbatch fw = simd::loadu(coord + j0);
            const fbatch px = sx + fw * vx, py = sy + fw * vy, pz = sz + fw * vz;
            const fbatch r = xsimd::sqrt(px * px + pz * pz);
            // std::max(a, b) is a < b ? b : a, which max_ps(b, a) is (NaN and signed zeros included): operands swapped.
            const fbatch er = r - R, ey = xsimd::max(minus_h - py, py);
            const fbatch pr = xsimd::max(zero, er), py2 = xsimd::max(zero, ey);
            const fbatch outside = xsimd::sqrt(pr * pr + py2 * py2);
            const fbatch v = xsimd::select((er <= zero) && (ey <= zero), xsimd::max(ey, er), outside);
            v.store_unaligned(row + j0);
        }
        for (int j = 0; j < count; ++j)
            if (row[j] < fbest) fbest = row[j], best = {i, j};
    }
    return best;
}

} // namespace drape::disc_lattice
