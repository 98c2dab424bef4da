// The fabric material model on triangle meshes: membrane springs (Van Gelder 1998) with the fabric's
// directional tensile stiffness, lumped masses, seams, and hinge bending (Bergou et al. 2006). See
// triangle_fabric.hpp and docs/fabric.md ("Triangle meshes").
#include "drape/triangle_fabric.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "drape/bending.hpp"
#include "drape/errors.hpp"

namespace drape {

namespace {

std::array<double, 3> unit_axis(const std::array<float, 3>& axis) {
    const double l =
        std::sqrt(double(axis[0]) * axis[0] + double(axis[1]) * axis[1] + double(axis[2]) * axis[2]);
    if (!(l > 0.0) || !std::isfinite(l))
        throw InvalidInput("fabric: the weave's u axis must be a non-zero vector");
    return {axis[0] / l, axis[1] / l, axis[2] / l};
}

/// Area of the triangle (a, b, c), in double.
double triangle_area(std::span<const float> x, std::span<const float> y, std::span<const float> z, std::uint32_t a,
                     std::uint32_t b, std::uint32_t c) {
    const double ux = double(x[b]) - x[a], uy = double(y[b]) - y[a], uz = double(z[b]) - z[a];
    const double vx = double(x[c]) - x[a], vy = double(y[c]) - y[a], vz = double(z[c]) - z[a];
    const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
    return 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
}

/// Index of spring (a, b) in `edges` sorted by (a, b) with a < b, or npos.
std::size_t find_edge(std::span<const Edge> edges, std::uint32_t a, std::uint32_t b) {
    if (a > b) std::swap(a, b);
    const auto it =
        std::lower_bound(edges.begin(), edges.end(), std::pair{a, b}, [](const Edge& e, const auto& key) {
            return e.a != key.first ? e.a < key.first : e.b < key.second;
        });
    if (it == edges.end() || it->a != a || it->b != b) return std::size_t(-1);
    return static_cast<std::size_t>(it - edges.begin());
}

} // namespace

double edge_modulus(const Fabric& f, double cos2, WeaveAlignment alignment) {
    cos2 = std::clamp(cos2, 0.0, 1.0);
    const double sin2 = 1.0 - cos2;
    const double eu = f.stretch_u, ev = f.stretch_v;
    if (alignment == WeaveAlignment::unaligned) return eu * cos2 + ev * sin2;
    const double g = std::max(double(f.shear), 1e-3 * std::min(eu, ev));
    return 1.0 / (cos2 * cos2 / eu + sin2 * sin2 / ev + cos2 * sin2 / g);
}

NeedleTriangleError::NeedleTriangleError(std::uint32_t a_, std::uint32_t b_, double ratio_)
    : InvalidInput("membrane spring " + std::to_string(a_) + "-" + std::to_string(b_) + " would be " +
                   std::to_string(static_cast<long long>(std::lround(ratio_))) +
                   " times as stiff as the fabric (at most " +
                   std::to_string(static_cast<long long>(membrane_stiffness_ratio_max)) +
                   "): a needle triangle (a short edge across a wide triangle); remesh there"),
      a(a_), b(b_), ratio(ratio_) {}

std::vector<double> membrane_stiffness(std::span<const float> x, std::span<const float> y,
                                       std::span<const float> z, std::span<const std::uint32_t> triangles,
                                       std::span<const Edge> edges, const Fabric& fabric,
                                       const std::array<float, 3>& axis_u, WeaveAlignment alignment) {
    const std::array<double, 3> u = unit_axis(axis_u);
    if (!(fabric.stretch_u > 0.0f) || !(fabric.stretch_v > 0.0f))
        throw InvalidInput("fabric: stretch_u and stretch_v must be > 0");
    // Edges sorted by (a, b), each remembering its place in `edges`.
    std::vector<std::size_t> order(edges.size());
    for (std::size_t k = 0; k < order.size(); ++k)
        order[k] = k;
    const auto key = [&](std::size_t k) {
        return std::pair{std::min(edges[k].a, edges[k].b), std::max(edges[k].a, edges[k].b)};
    };
    std::sort(order.begin(), order.end(), [&](std::size_t l, std::size_t r) { return key(l) < key(r); });
    const auto slot = [&](std::uint32_t a, std::uint32_t b) -> std::size_t {
        const std::pair want{std::min(a, b), std::max(a, b)};
        const auto it = std::lower_bound(order.begin(), order.end(), want,
                                         [&](std::size_t k, const auto& w) { return key(k) < w; });
        return it != order.end() && key(*it) == want ? *it : std::size_t(-1);
    };
    const auto modulus = [&](std::uint32_t a, std::uint32_t b, double& l2) {
        const double d[3] = {double(x[b]) - x[a], double(y[b]) - y[a], double(z[b]) - z[a]};
        l2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        const double c = (d[0] * u[0] + d[1] * u[1] + d[2] * u[2]);
        return edge_modulus(fabric, l2 > 0.0 ? c * c / l2 : 0.5, alignment);
    };
    std::vector<double> k(edges.size(), 0.0);
    std::vector<char> in_triangle(edges.size(), 0);
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
        const std::uint32_t v[3] = {triangles[t], triangles[t + 1], triangles[t + 2]};
        const double area = triangle_area(x, y, z, v[0], v[1], v[2]);
        for (int s = 0; s < 3; ++s) {
            const std::uint32_t a = v[s], b = v[(s + 1) % 3];
            const std::size_t e = slot(a, b);
            if (e == std::size_t(-1)) continue;
            double l2 = 0.0;
            const double m = modulus(a, b, l2);
            if (l2 > 0.0) k[e] += m * area / l2;
            in_triangle[e] = 1;
        }
    }
    for (std::size_t e = 0; e < edges.size(); ++e)
        if (!in_triangle[e]) {
            double l2 = 0.0;
            k[e] = modulus(edges[e].a, edges[e].b, l2);
        }
    return k;
}

std::vector<double> lumped_masses(std::span<const float> x, std::span<const float> y,
                                  std::span<const float> z, std::span<const std::uint32_t> triangles,
                                  double density) {
    std::vector<double> m(x.size(), 0.0);
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
        const std::uint32_t a = triangles[t], b = triangles[t + 1], c = triangles[t + 2];
        const double third = density * triangle_area(x, y, z, a, b, c) / 3.0;
        m[a] += third, m[b] += third, m[c] += third;
    }
    return m;
}

Cloth cook_triangle_fabric(const GarmentAssembly& a, std::span<const float> inv_mass,
                           const TriangleFabricOptions& o) {
    const Fabric& f = o.fabric;
    const std::size_t n = a.particle_count();
    // Springs: every triangle edge, the seams, and structural springs of the assembly in no triangle.
    std::vector<Edge> edges;
    edges.reserve(a.triangles.size() + a.edges.size());
    for (std::size_t t = 0; t + 2 < a.triangles.size(); t += 3)
        for (int s = 0; s < 3; ++s) {
            const std::uint32_t p = a.triangles[t + s], q = a.triangles[t + (s + 1) % 3];
            if (p == q || p >= n || q >= n) continue;
            edges.push_back({std::min(p, q), std::max(p, q), SpringKind::structural, 0.0f});
        }
    std::sort(edges.begin(), edges.end(),
              [](const Edge& l, const Edge& r) { return l.a != r.a ? l.a < r.a : l.b < r.b; });
    edges.erase(std::unique(edges.begin(), edges.end(),
                            [](const Edge& l, const Edge& r) { return l.a == r.a && l.b == r.b; }),
                edges.end());
    const std::size_t triangle_edges = edges.size();
    const std::array<double, 3> u = unit_axis(o.axis_u);
    for (Edge& e :
         edges) { // rest length: the assembly's spring on that edge if it has one, else the distance
        const double dx = double(a.x[e.b]) - a.x[e.a], dy = double(a.y[e.b]) - a.y[e.a],
                     dz = double(a.z[e.b]) - a.z[e.a];
        const double l2 = dx * dx + dy * dy + dz * dz;
        e.rest = float(std::sqrt(l2));
        // Weave-aligned meshes: an edge more than ~8 degrees off both u and v is a shear (bias) spring, so
        // health figures and strain limits name warp and weft strain "structural" as on grids.
        const double c = dx * u[0] + dy * u[1] + dz * u[2];
        const double cos2 = l2 > 0.0 ? c * c / l2 : 0.0;
        if (o.alignment == WeaveAlignment::aligned && cos2 > 0.02 && cos2 < 0.98) e.kind = SpringKind::shear;
    }
    for (const Edge& e : a.edges) {
        if (e.kind != SpringKind::seam && e.kind != SpringKind::structural) continue;
        const std::size_t at = find_edge(std::span<const Edge>(edges.data(), triangle_edges), e.a, e.b);
        if (at != std::size_t(-1)) {
            edges[at].rest = e.rest;
            if (e.kind == SpringKind::seam) edges[at].kind = SpringKind::seam; // a seam along a triangle edge
            continue;
        }
        edges.push_back({std::min(e.a, e.b), std::max(e.a, e.b), e.kind, e.rest});
    }
    // Stiffness: each kind's material is a reference (k_ref = the mean of stretch_u and stretch_v, damping
    // Fabric::damping x k_ref) and each spring's Edge::scale its own stiffness over k_ref, so stiffness and
    // damping are k_e and Fabric::damping x k_e. Seams: k_ref, scale 1.
    const double k_ref = 0.5 * (double(f.stretch_u) + f.stretch_v);
    const std::vector<double> k =
        membrane_stiffness(a.x, a.y, a.z, a.triangles, edges, f, o.axis_u, o.alignment);
    std::size_t stiffest = std::size_t(-1);
    for (std::size_t e = 0; e < edges.size(); ++e)
        if (edges[e].kind != SpringKind::seam && (stiffest == std::size_t(-1) || k[e] > k[stiffest])) stiffest = e;
    if (stiffest != std::size_t(-1) && !(k[stiffest] <= membrane_stiffness_ratio_max * k_ref))
        throw NeedleTriangleError(edges[stiffest].a, edges[stiffest].b, k[stiffest] / k_ref);
    for (std::size_t e = 0; e < edges.size(); ++e)
        edges[e].scale = edges[e].kind == SpringKind::seam ? 1.0f : float(k[e] / k_ref);
    std::array<SpringMaterial, spring_kind_count> material{};
    for (SpringKind kind : {SpringKind::structural, SpringKind::shear})
        material[static_cast<std::size_t>(kind)] = {float(k_ref), float(double(f.damping) * k_ref)};
    material[static_cast<std::size_t>(SpringKind::seam)] = {float(k_ref), float(double(f.damping) * k_ref)};
    Cloth cloth = cook_cloth(inv_mass, std::move(edges), material);
    cloth.triangles = a.triangles;
    set_bending(cloth, hinge_bending_elements(a.x, a.y, a.z, a.triangles, f.bend_u, f.bend_v, o.axis_u),
                f.damping);
    return cloth;
}

} // namespace drape
