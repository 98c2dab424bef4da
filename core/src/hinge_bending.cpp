// Bending elements of a triangle mesh: the quadratic (isometric) bending model of Bergou, Wardetzky, Harmon,
// Zorin and Grinspun 2006. See bending.hpp for the formulas and docs/fabric.md ("Triangle meshes") for the
// derivation of the weight and the orthotropic rigidity.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "drape/bending.hpp"
#include "drape/errors.hpp"

namespace drape {

namespace {

using Vec = std::array<double, 3>;

Vec sub(const Vec& a, const Vec& b) {
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
double dot(const Vec& a, const Vec& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
Vec cross(const Vec& a, const Vec& b) {
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double norm(const Vec& a) {
    return std::sqrt(dot(a, a));
}

/// One side of an edge: the triangle and its vertex opposite the edge.
struct HalfEdge {
    std::uint32_t a, b;  ///< edge ends, a < b
    std::uint32_t first; ///< the triangle's vertex that comes first in its own winding, of a and b
    std::uint32_t opposite;
    std::uint32_t triangle;
};

/// Every interior edge (exactly two triangles) as a pair of half edges, in (a, b) order.
template <class F>
void for_each_hinge(std::span<const std::uint32_t> triangles, std::size_t particles, F&& f) {
    if (triangles.size() % 3 != 0)
        throw InvalidInput("hinge bending: the triangle list has " + std::to_string(triangles.size()) +
                           " indices (not a multiple of 3)");
    std::vector<HalfEdge> half;
    half.reserve(triangles.size());
    for (std::size_t t = 0; t < triangles.size() / 3; ++t) {
        const std::uint32_t* v = &triangles[3 * t];
        for (int k = 0; k < 3; ++k) {
            if (v[k] >= particles)
                throw InvalidInput("hinge bending: triangle " + std::to_string(t) + " names particle " +
                                   std::to_string(v[k]) + " (the mesh has " + std::to_string(particles) +
                                   ")");
            const std::uint32_t p = v[k], q = v[(k + 1) % 3], o = v[(k + 2) % 3];
            if (p == q) continue;
            half.push_back({std::min(p, q), std::max(p, q), p, o, static_cast<std::uint32_t>(t)});
        }
    }
    std::sort(half.begin(), half.end(), [](const HalfEdge& l, const HalfEdge& r) {
        return l.a != r.a ? l.a < r.a : l.b != r.b ? l.b < r.b : l.triangle < r.triangle;
    });
    for (std::size_t i = 0; i < half.size();) {
        std::size_t j = i + 1;
        while (j < half.size() && half[j].a == half[i].a && half[j].b == half[i].b)
            ++j;
        if (j - i == 2 && half[i].opposite != half[i + 1].opposite) f(half[i], half[i + 1]);
        i = j;
    }
}

} // namespace

std::vector<BendElement> hinge_bending_elements(std::span<const float> x, std::span<const float> y,
                                                std::span<const float> z,
                                                std::span<const std::uint32_t> triangles, float bend_u,
                                                float bend_v, const std::array<float, 3>& axis_u) {
    if (x.size() != y.size() || x.size() != z.size())
        throw InvalidInput("hinge bending: position arrays of different lengths");
    if (!(bend_u >= 0.0f) || !(bend_v >= 0.0f) || !std::isfinite(bend_u) || !std::isfinite(bend_v))
        throw InvalidInput("hinge bending: bending rigidity must be finite and >= 0");
    Vec u{axis_u[0], axis_u[1], axis_u[2]};
    const double lu = norm(u);
    if (!(lu > 0.0) || !std::isfinite(lu))
        throw InvalidInput("hinge bending: the u axis must be a non-zero vector");
    u = {u[0] / lu, u[1] / lu, u[2] / lu};
    const auto pos = [&](std::uint32_t i) { return Vec{x[i], y[i], z[i]}; };
    // cot of the angle between a and b
    const auto cot = [](const Vec& a, const Vec& b) { return dot(a, b) / norm(cross(a, b)); };

    std::vector<BendElement> out;
    for_each_hinge(triangles, x.size(), [&](const HalfEdge& h0, const HalfEdge& h1) {
        const std::uint32_t i0 = h0.a, i1 = h0.b, i2 = h0.opposite, i3 = h1.opposite;
        const Vec x0 = pos(i0), x1 = pos(i1), x2 = pos(i2), x3 = pos(i3);
        const Vec e0 = sub(x1, x0), e1 = sub(x2, x0), e2 = sub(x3, x0), e3 = sub(x2, x1), e4 = sub(x3, x1);
        const Vec n0 = cross(e0, e1),
                  n1 = cross(e0, e2); // x2 and x3 lie on opposite sides: n1 ~ -n0 when flat
        const double a0 = 0.5 * norm(n0), a1 = 0.5 * norm(n1);
        if (!(a0 > 0.0) || !(a1 > 0.0)) return;
        const Vec me0{-e0[0], -e0[1], -e0[2]};
        const double c01 = cot(e0, e1), c02 = cot(e0, e2), c03 = cot(me0, e3), c04 = cot(me0, e4);
        // Direction of bending: in the rest plane, perpendicular to the edge (normal n0 - n1, the two
        // triangles' normals made to agree).
        const Vec n = sub(n0, n1);
        Vec p = cross(n, e0);
        const double lp = norm(p);
        double cos2 = 0.5;
        if (lp > 0.0) {
            const double c = dot(p, u) / lp;
            cos2 = std::min(1.0, c * c);
        }
        const double bend = double(bend_u) * cos2 + double(bend_v) * (1.0 - cos2);
        BendElement e;
        e.v = {i0, i1, i2, i3};
        e.c = {float(c03 + c04), float(c01 + c02), float(-c01 - c03), float(-c02 - c04)};
        e.weight = float(bend / (a0 + a1));
        if (!std::isfinite(e.weight) || !std::isfinite(e.c[0]) || !std::isfinite(e.c[1]) ||
            !std::isfinite(e.c[2]) || !std::isfinite(e.c[3]))
            return;
        out.push_back(e);
    });
    return out;
}

double hinge_rest_angle_max(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                            std::span<const std::uint32_t> triangles) {
    const auto pos = [&](std::uint32_t i) { return Vec{x[i], y[i], z[i]}; };
    double worst = 0.0;
    for_each_hinge(triangles, x.size(), [&](const HalfEdge& h0, const HalfEdge& h1) {
        const Vec x0 = pos(h0.a), x1 = pos(h0.b);
        const Vec e0 = sub(x1, x0);
        const Vec n0 = cross(e0, sub(pos(h0.opposite), x0)), n1 = cross(e0, sub(pos(h1.opposite), x0));
        const double l0 = norm(n0), l1 = norm(n1);
        if (!(l0 > 0.0) || !(l1 > 0.0)) return;
        // Flat: x2 and x3 on opposite sides, so n0 and n1 point opposite ways.
        const double c = std::clamp(-dot(n0, n1) / (l0 * l1), -1.0, 1.0);
        worst = std::max(worst, std::acos(c));
    });
    return worst;
}

} // namespace drape
