// Closest points between triangles, segments and points (Ericson, "Real-Time Collision Detection", 2005), in
// double: shared by the triangle contact with colliders (triangle_contact.cpp) and self-collision
// (self_collide.cpp). Internal to drape_core (and its tests).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "drape/colliders.hpp"

namespace drape::geom {

struct V3 {
    double x, y, z;
};
inline V3 operator-(V3 a, V3 b) noexcept { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator+(V3 a, V3 b) noexcept { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator*(double s, V3 a) noexcept { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(V3 a, V3 b) noexcept { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline double norm(V3 a) noexcept { return std::sqrt(dot(a, a)); }
inline V3 v3(const Vec3f& p) noexcept { return {p[0], p[1], p[2]}; }

/// Barycentric coordinates of the point of triangle (a, b, c) closest to p (Ericson, "Real-Time Collision
/// Detection", 2005, section 5.1.5: the Voronoi regions of the vertices, then the edges, then the face).
inline std::array<double, 3> closest_on_triangle(V3 p, V3 a, V3 b, V3 c) noexcept {
    const V3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = dot(ab, ap), d2 = dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) return {1.0, 0.0, 0.0};
    const V3 bp = p - b;
    const double d3 = dot(ab, bp), d4 = dot(ac, bp);
    if (d3 >= 0.0 && d4 <= d3) return {0.0, 1.0, 0.0};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
        const double v = d1 / (d1 - d3);
        return {1.0 - v, v, 0.0};
    }
    const V3 cp = p - c;
    const double d5 = dot(ab, cp), d6 = dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) return {0.0, 0.0, 1.0};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        const double w = d2 / (d2 - d6);
        return {1.0 - w, 0.0, w};
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return {0.0, 1.0 - w, w};
    }
    const double denom = va + vb + vc;
    if (!(denom > 0.0)) return {1.0, 0.0, 0.0}; // a degenerate triangle: its first vertex
    const double v = vb / denom, w = vc / denom;
    return {1.0 - v - w, v, w};
}

/// Closest points of segments p1-q1 and p2-q2 (Ericson 2005, 5.1.9): parameters s on the first, t on the second.
inline void closest_segments(V3 p1, V3 q1, V3 p2, V3 q2, double& s, double& t) noexcept {
    const V3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
    const double a = dot(d1, d1), e = dot(d2, d2), f = dot(d2, r);
    constexpr double eps = 1e-30;
    if (a <= eps && e <= eps) {
        s = t = 0.0;
        return;
    }
    if (a <= eps) {
        s = 0.0;
        t = std::clamp(f / e, 0.0, 1.0);
        return;
    }
    const double c = dot(d1, r);
    if (e <= eps) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
        return;
    }
    const double b = dot(d1, d2), denom = a * e - b * b;
    s = denom > 0.0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
    t = (b * s + f) / e;
    if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
    } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
    }
}

} // namespace drape::geom
