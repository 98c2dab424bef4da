// Scene "hang" (BENCH.md).
#include "drape/scene_hang.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "drape/bending.hpp"
#include "drape/errors.hpp"
#include "drape/level_transfer.hpp"
#include "range_check.hpp"

namespace drape {

GridMembrane grid_membrane(const Fabric& f, const std::string& what) {
    check_positive(what + ".stretch_u", f.stretch_u, " N/m", false);
    check_positive(what + ".stretch_v", f.stretch_v, " N/m", false);
    check_positive(what + ".shear", f.shear, " N/m", true);
    // C11 = a = E_u + G^2 / b and C22 = b = E_v + G^2 / a (C12 = G): the fixed point in closed form. From the two,
    // E_u b = E_v a, so b = (E_v / E_u) a and a^2 - E_u a - E_u G^2 / E_v = 0.
    const double eu = f.stretch_u, ev = f.stretch_v, g = f.shear;
    const double a = 0.5 * eu * (1.0 + std::sqrt(1.0 + 4.0 * g * g / (eu * ev))), b = ev / eu * a;
    GridMembrane m{static_cast<float>(a - g), static_cast<float>(b - g), f.shear};
    if (!(m.ks_u > 0.0f) || !(m.ks_v > 0.0f))
        throw InvalidInput(what + ".shear = " + std::to_string(f.shear) + " N/m is too large for " + what +
                           ".stretch_u = " + std::to_string(f.stretch_u) + " and " + what + ".stretch_v = " +
                           std::to_string(f.stretch_v) + " N/m on a grid (a structural spring would have stiffness <= " +
                           "0); keep the shear below about the smaller stretch stiffness");
    return m;
}

SceneBuild build_hang_scene(const HangParams& p) {
    check_range("size (particles per side)", p.n, hang_min_n, hang_max_n, "");
    check_range("cloth size", p.size, 0.01f, 100.0f, " m");
    const bool fabric = p.model == MaterialModel::fabric;
    if (!fabric) { // the fabric model derives mass and springs from p.fabric and ignores these
        check_range("total mass", p.total_mass, 1e-6f, 1e3f, " kg");
        check_range("stiffness", p.stiffness, 100.0f, 25000.0f, " N/m");
        check_range("shear ratio", p.shear_ratio, 0.0f, 1.0f, "");
        check_range("bend ratio", p.bend_ratio, 0.0f, 1.0f, "");
        check_range("damping ratio", p.damping_ratio, 0.0f, 1.0f, "");
    } else {
        check_positive("fabric.density", p.fabric.density, " kg/m^2", false);
        check_positive("fabric.bend_u", p.fabric.bend_u, " N*m", true);
        check_positive("fabric.bend_v", p.fabric.bend_v, " N*m", true);
        check_positive("fabric.damping", p.fabric.damping, " s", true);
    }
    const GridMembrane membrane = fabric ? grid_membrane(p.fabric) : GridMembrane{};

    const std::uint32_t n = p.n;
    const std::size_t count = std::size_t{n} * n;
    const float h = p.size / static_cast<float>(n - 1);
    const float mass = p.total_mass / static_cast<float>(count);
    // Inverse mass of each particle when free. Fabric: density x a quarter of each adjacent cell's area (an edge
    // particle has two cells, a corner one).
    std::vector<float> free_inv_mass(count, 1.0f / mass);
    if (fabric)
        for (std::uint32_t j = 0; j < n; ++j)
            for (std::uint32_t i = 0; i < n; ++i) {
                const int cells = (i > 0 && i + 1 < n ? 2 : 1) * (j > 0 && j + 1 < n ? 2 : 1);
                free_inv_mass[grid_index(n, i, j)] =
                    static_cast<float>(1.0 / (double(p.fabric.density) * 0.25 * cells * double(h) * h));
            }

    // Particles: column i along x; row j along +z (horizontal) or down -y (vertical); centred on
    // params.centre, which is the frame's origin (Cloth::origin): the stored positions are relative to it,
    // exact at any centre.
    SceneBuild out;
    InitialState& s = out.initial;
    s.x.resize(count);
    s.y.assign(count, 0.0f);
    s.z.resize(count);
    s.vx.assign(count, 0.0f);
    s.vy.assign(count, 0.0f);
    s.vz.assign(count, 0.0f);
    std::vector<float> inv_mass = free_inv_mass;
    for (float c : p.centre)
        if (!(std::fabs(c) <= 1000.0f))
            throw InvalidInput("cloth centre coordinate " + std::to_string(c) + " m is outside [-1000, 1000]");
    for (std::uint32_t j = 0; j < n; ++j)
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::uint32_t k = grid_index(n, i, j);
            const float u = -0.5f * p.size + static_cast<float>(i) * h, v = -0.5f * p.size + static_cast<float>(j) * h;
            s.x[k] = u;
            if (p.plane == GridPlane::horizontal) {
                s.y[k] = 0.0f;
                s.z[k] = v;
            } else {
                s.y[k] = -v;
                s.z[k] = 0.0f;
            }
        }
    check_range("pin radius", p.pin_radius, 0.0f, hang_max_pin_radius, " m");
    if (p.pins == GridPins::corners) {
        // A clip of radius pin_radius at each corner: every particle within it (always the corner itself), so the
        // pinned area, and with it the strain next to the pin, is the same at every resolution.
        const auto clip = [&](std::uint32_t ci) {
            const double r = double(p.pin_radius), hh = double(h);
            const auto reach = static_cast<std::uint32_t>(std::min<double>(n - 1, std::floor(r / hh)));
            for (std::uint32_t dj = 0; dj <= reach; ++dj)
                for (std::uint32_t di = 0; di <= reach; ++di) {
                    if (std::hypot(double(di) * hh, double(dj) * hh) > r * (1.0 + 1e-6)) continue;
                    const std::uint32_t i = ci == 0 ? di : ci - di;
                    inv_mass[grid_index(n, i, dj)] = 0.0f;
                }
        };
        clip(0);
        clip(n - 1);
    } else if (p.pins == GridPins::top_edge) {
        for (std::uint32_t i = 0; i < n; ++i) inv_mass[grid_index(n, i, 0)] = 0.0f;
    } else if (p.pins == GridPins::left_edge) {
        for (std::uint32_t j = 0; j < n; ++j) inv_mass[grid_index(n, 0, j)] = 0.0f;
    }

    // The stencil: 12 slots in ascending index offset (the order of a sorted CSR row).
    GridStencil g;
    g.columns = n;
    g.rows = n;
    struct Slot {
        int di, dj;
        SpringKind kind;
    };
    const int N = static_cast<int>(n);
    const Slot slots[GridStencil::slot_count] = {
        {0, -2, SpringKind::bend},        {-1, -1, SpringKind::shear},     {0, -1, SpringKind::structural},
        {1, -1, SpringKind::shear},       {-2, 0, SpringKind::bend},       {-1, 0, SpringKind::structural},
        {1, 0, SpringKind::structural},   {2, 0, SpringKind::bend},        {-1, 1, SpringKind::shear},
        {0, 1, SpringKind::structural},   {1, 1, SpringKind::shear},       {0, 2, SpringKind::bend},
    };
    for (std::size_t s2 = 0; s2 < GridStencil::slot_count; ++s2) {
        g.offset[s2] = slots[s2].dj * N + slots[s2].di;
        g.kind[s2] = slots[s2].kind;
        g.rest[s2] = h * std::sqrt(static_cast<float>(slots[s2].di * slots[s2].di + slots[s2].dj * slots[s2].dj));
    }
    // Fabric: structural springs along v (slots +-N) are ks_v / ks_u of the structural material (ks_u); no bend
    // springs (the bending energy replaces them).
    if (fabric)
        for (std::size_t s2 = 0; s2 < GridStencil::slot_count; ++s2)
            if (slots[s2].kind == SpringKind::structural && slots[s2].di == 0) g.scale[s2] = membrane.ks_v / membrane.ks_u;
    // Edges, each once (from the lower index: the forward slots), with the same rest lengths as the stencil.
    std::vector<Edge> edges;
    edges.reserve(static_cast<std::size_t>(6) * count);
    g.mask.reset(pad_to_width(count));
    for (std::uint32_t j = 0; j < n; ++j)
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::uint32_t k = grid_index(n, i, j);
            const bool edge_row = j == 0 || j + 1 == n, edge_column = i == 0 || i + 1 == n;
            std::uint32_t bits = 0;
            for (std::size_t s2 = 0; s2 < GridStencil::slot_count; ++s2) {
                const int ni = static_cast<int>(i) + slots[s2].di, nj = static_cast<int>(j) + slots[s2].dj;
                if (ni < 0 || nj < 0 || ni >= N || nj >= N) continue;
                if (fabric && slots[s2].kind == SpringKind::bend) continue; // no bend springs: bending replaces them
                bits |= 1u << s2;
                // Fabric: assembled per cell, a structural edge on the boundary (one adjacent cell) gets half.
                const bool half = fabric && slots[s2].kind == SpringKind::structural &&
                                  (slots[s2].dj == 0 ? edge_row : edge_column);
                if (half) {
                    bits |= 1u << (GridStencil::half_bit + s2);
                    g.half_edges = true;
                }
                if (g.offset[s2] > 0)
                    edges.push_back({k, static_cast<std::uint32_t>(static_cast<int>(k) + g.offset[s2]), slots[s2].kind,
                                     g.rest[s2], half ? 0.5f * g.scale[s2] : g.scale[s2]});
            }
            if (fabric) {
                const std::uint32_t ui = i, vj = j, last = n - 1;
                if (ui >= 2) bits |= 1u << GridStencil::bend_u_bit;
                if (ui >= 1 && ui + 1 <= last) bits |= 1u << (GridStencil::bend_u_bit + 1);
                if (ui + 2 <= last) bits |= 1u << (GridStencil::bend_u_bit + 2);
                if (vj >= 2) bits |= 1u << GridStencil::bend_v_bit;
                if (vj >= 1 && vj + 1 <= last) bits |= 1u << (GridStencil::bend_v_bit + 1);
                if (vj + 2 <= last) bits |= 1u << (GridStencil::bend_v_bit + 2);
                if (edge_row) bits |= 1u << GridStencil::edge_row_bit;
                if (edge_column) bits |= 1u << GridStencil::edge_column_bit;
            }
            g.mask[k] = bits;
        }

    std::array<SpringMaterial, spring_kind_count> material{};
    if (fabric) { // Rayleigh damping: every spring's kd = beta k (Edge::scale scales both)
        const float beta = p.fabric.damping;
        material[static_cast<std::size_t>(SpringKind::structural)] = {membrane.ks_u, beta * membrane.ks_u};
        material[static_cast<std::size_t>(SpringKind::shear)] = {membrane.kd, beta * membrane.kd};
    } else {
        const float ks[3] = {p.stiffness, p.stiffness * p.shear_ratio, p.stiffness * p.bend_ratio};
        for (int kind = 0; kind < 3; ++kind)
            material[kind] = {ks[kind], p.damping_ratio * 2.0f * std::sqrt(ks[kind] * mass * 0.5f)};
    }

    // Halo: the stencil reaches two rows (2N) away; one extra batch keeps unaligned loads in bounds.
    const std::size_t halo = 2 * std::size_t{n} + 2 + simd::width;
    out.cloth = cook_cloth(inv_mass, std::move(edges), material, halo);
    out.cloth.grid = std::move(g);
    out.cloth.free_inv_mass = std::move(free_inv_mass);
    if (fabric) {
        set_bending(out.cloth, grid_bending_elements(n, n, h, p.fabric.bend_u, p.fabric.bend_v), p.fabric.damping);
        out.cloth.bending.grid = grid_bending_weights(h, p.fabric.bend_u, p.fabric.bend_v);
        // The same fabric, pins and placement on a coarser grid (the implicit solver's coarse levels): each level
        // (n + 1) / 2 of the next finer one's n per side, the first from N >= 10, none below 5 per side.
        out.cloth.coarsen = [p](std::uint32_t level) -> std::optional<CoarseCloth> {
            constexpr std::uint32_t coarsest_side = 5;
            if (level == 0 || p.n < 2 * coarsest_side) return std::nullopt;
            std::uint32_t finer = p.n, coarse = p.n;
            for (std::uint32_t k = 0; k < level && coarse >= coarsest_side; ++k) finer = coarse, coarse = (coarse + 1) / 2;
            if (coarse < coarsest_side) return std::nullopt;
            HangParams q = p;
            q.n = coarse;
            CoarseCloth c;
            c.cloth = build_hang_scene(q).cloth;
            c.from_fine = bilinear_transfer(p.n, coarse);
            c.to_finer = bilinear_transfer(coarse, finer);
            return c;
        };
    }
    out.cloth.origin = {double(p.centre[0]), double(p.centre[1]), double(p.centre[2])};
    // Triangles: two per grid cell, counter-clockwise seen from +y (horizontal) or +z (vertical).
    auto& tri = out.cloth.triangles;
    tri.reserve(static_cast<std::size_t>(6) * (n - 1) * (n - 1));
    for (std::uint32_t j = 0; j + 1 < n; ++j)
        for (std::uint32_t i = 0; i + 1 < n; ++i) {
            const std::uint32_t a = grid_index(n, i, j), b = grid_index(n, i + 1, j), c = grid_index(n, i, j + 1),
                                d = grid_index(n, i + 1, j + 1);
            tri.insert(tri.end(), {a, c, b, b, c, d});
        }
    return out;
}

} // namespace drape
