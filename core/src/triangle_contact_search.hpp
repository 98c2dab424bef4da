// The triangle pass's search (docs/collisions.md, "Cheap rejections first"), shared by the collide stage's
// pass (collide.cpp) and the implicit solver's triangle contact terms (implicit_triangle_contact.cpp): per
// particle a lower bound of its distance to the colliders, then per triangle its deepest contact over them
// after the cheap rejections.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include "drape/colliders.hpp"
#include "drape/triangle_contact.hpp"

namespace drape::detail {

/// m: a projected particle's float rounding; a vertex deeper than this inside a collider was held there.
inline constexpr float triangle_inside_slack = 1e-5f;

/// Particles [begin, end) of n: clear[i], a lower bound of the distance to the nearest collider other than a
/// plane, and measure[k * n + i], the core measure for collider k (triangle_contact.hpp).
inline void triangle_contact_bounds(std::span<const Collider> colliders, std::size_t n, const float* x,
                                    const float* y, const float* z, float* clear, float* measure,
                                    std::size_t begin, std::size_t end) noexcept {
    for (std::size_t i = begin; i < end; ++i)
        clear[i] = std::numeric_limits<float>::max();
    for (std::size_t k = 0; k < colliders.size(); ++k) {
        const Collider& col = colliders[k];
        if (col.kind == ColliderKind::plane) continue;
        float* m = measure + k * n;
        for (std::size_t i = begin; i < end; ++i) {
            m[i] = core_measure(col, {x[i], y[i], z[i]});
            clear[i] = std::min(clear[i], clearance_from_measure(col, m[i]));
        }
    }
}

/// The deepest contact of triangle v (its three particles) over the colliders, with that collider's friction
/// in mu and its index in `which` (optional); false when the triangle is rejected or clear. A triangle with a
/// vertex held inside a collider (deeper than triangle_inside_slack, plus `grown`: colliders grown by that
/// much beyond their own thickness) is left alone, as the particle pass leaves the vertex.
inline bool deepest_triangle_contact(std::span<const Collider> colliders, std::size_t n,
                                     const std::uint32_t v[3], const float* x, const float* y, const float* z,
                                     const float* clear, const float* measure, TriangleContact& best,
                                     float& mu, float grown = 0.0f, std::size_t* which = nullptr) noexcept {
    if (std::min({clear[v[0]], clear[v[1]], clear[v[2]]}) < -(grown + triangle_inside_slack)) return false;
    // Rejected when a vertex is farther from every collider than the longest edge is long (the distance is
    // 1-Lipschitz: triangle_contact.hpp), then collider by collider the same way.
    auto len2 = [&](std::uint32_t p, std::uint32_t q) {
        const float ex = x[p] - x[q], ey = y[p] - y[q], ez = z[p] - z[q];
        return ex * ex + ey * ey + ez * ez;
    };
    const float far = std::max({clear[v[0]], clear[v[1]], clear[v[2]]});
    const float longest2 = std::max({len2(v[0], v[1]), len2(v[1], v[2]), len2(v[2], v[0])});
    if (far > 0.0f && far * far >= longest2) return false;
    const Vec3f p[3] = {
        {x[v[0]], y[v[0]], z[v[0]]}, {x[v[1]], y[v[1]], z[v[1]]}, {x[v[2]], y[v[2]], z[v[2]]}};
    const float radius2 = enclosing_radius2(p[0], p[1], p[2]);
    best = TriangleContact{};
    mu = 0.0f;
    for (std::size_t k = 0; k < colliders.size(); ++k) {
        const Collider& col = colliders[k];
        const float* m = measure + k * n;
        if (triangle_clear_of(col, m[v[0]], m[v[1]], m[v[2]], radius2)) continue;
        const TriangleContact c = triangle_contact(col, p[0], p[1], p[2]);
        if (c.inside && (!best.inside || c.depth > best.depth)) {
            best = c;
            mu = col.friction;
            if (which) *which = k;
        }
    }
    return best.inside;
}

} // namespace drape::detail
