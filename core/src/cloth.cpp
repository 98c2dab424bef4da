// Cooking a cloth: validated edges, CSR/SELL, per-entry materials.
#include "drape/cloth.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "drape/errors.hpp"

namespace drape {

namespace {

void check_material(SpringKind kind, const SpringMaterial& m) {
    if (!(m.stiffness >= 0.0f && m.stiffness <= 1e6f))
        throw InvalidInput(std::string("material.") + spring_kind_name(kind) + ".stiffness = " +
                           std::to_string(m.stiffness) + " N/m is outside the allowed range [0, 1e6]");
    if (!(m.damping >= 0.0f && m.damping <= 1e3f * (1.0f + 1e-6f))) // the fabric's limit, rounded in float, is allowed
        throw InvalidInput(std::string("material.") + spring_kind_name(kind) + ".damping = " +
                           std::to_string(m.damping) + " N*s/m is outside the allowed range [0, 1e3]");
}

} // namespace

Cloth cook_cloth(std::span<const float> inv_mass, std::vector<Edge> edges,
                 const std::array<SpringMaterial, spring_kind_count>& material, std::size_t halo) {
    const std::size_t n = inv_mass.size();
    if (n == 0) throw InvalidInput("cloth has no particles (need at least 1)");
    if (n >= (std::size_t{1} << 31)) throw InvalidInput("cloth has " + std::to_string(n) + " particles (max 2^31-1)");
    for (std::size_t i = 0; i < n; ++i)
        if (!(inv_mass[i] >= 0.0f) || !std::isfinite(inv_mass[i]))
            throw InvalidInput("particle " + std::to_string(i) + " has inverse mass " + std::to_string(inv_mass[i]) +
                               " (must be finite and >= 0; 0 pins it)");
    for (Edge& e : edges) {
        if (e.a >= n || e.b >= n)
            throw InvalidInput("spring " + std::to_string(e.a) + "-" + std::to_string(e.b) +
                               " names a particle outside [0, " + std::to_string(n - 1) + "]");
        if (e.a == e.b) throw InvalidInput("spring joins particle " + std::to_string(e.a) + " to itself");
        if (!(e.rest > 0.0f) || !std::isfinite(e.rest))
            throw InvalidInput("spring " + std::to_string(e.a) + "-" + std::to_string(e.b) + " has rest length " +
                               std::to_string(e.rest) + " m (must be > 0 and finite)");
        if (!(e.scale >= 0.0f && e.scale <= 1e3f))
            throw InvalidInput("spring " + std::to_string(e.a) + "-" + std::to_string(e.b) + " has stiffness scale " +
                               std::to_string(e.scale) + " (must be in [0, 1000])");
        if (e.a > e.b) std::swap(e.a, e.b);
    }
    std::sort(edges.begin(), edges.end(), [](const Edge& l, const Edge& r) {
        return l.a != r.a ? l.a < r.a : l.b < r.b;
    });
    for (std::size_t k = 1; k < edges.size(); ++k)
        if (edges[k].a == edges[k - 1].a && edges[k].b == edges[k - 1].b)
            throw InvalidInput("duplicate spring " + std::to_string(edges[k].a) + "-" + std::to_string(edges[k].b));

    Cloth c;
    c.particle_count = n;
    c.padded_count = pad_to_width(n);
    c.halo = halo;
    c.inv_mass.reset(c.padded_count, halo);
    std::copy(inv_mass.begin(), inv_mass.end(), c.inv_mass.data());
    c.edges = std::move(edges);
    c.graph = build_spring_graph(n, c.padded_count, c.edges);
    std::vector<std::uint32_t> seam_subset;
    for (std::uint32_t k = 0; k < c.edges.size(); ++k)
        if (c.edges[k].kind == SpringKind::seam) seam_subset.push_back(k);
    if (!seam_subset.empty()) {
        SeamSet& s = c.seams;
        s.groups = colour_edges(c.edges, n, seam_subset);
        for (std::uint32_t e : s.groups.edge_index) {
            s.a.push_back(c.edges[e].a);
            s.b.push_back(c.edges[e].b);
            s.rest.push_back(c.edges[e].rest);
            s.kind.push_back(c.edges[e].kind);
            s.scale.push_back(c.edges[e].scale);
            s.particles.push_back(c.edges[e].a);
            s.particles.push_back(c.edges[e].b);
        }
        std::sort(s.particles.begin(), s.particles.end());
        s.particles.erase(std::unique(s.particles.begin(), s.particles.end()), s.particles.end());
    }
    apply_materials(c, material);
    return c;
}

void apply_materials(Cloth& cloth, const std::array<SpringMaterial, spring_kind_count>& material) {
    for (std::size_t k = 0; k < spring_kind_count; ++k) check_material(static_cast<SpringKind>(k), material[k]);
    cloth.material = material;
    SpringGraph& g = cloth.graph;
    for (std::size_t at = 0; at < g.sell_entry_count(); ++at) {
        const std::uint32_t e = g.sell_edge[at];
        if (e == std::numeric_limits<std::uint32_t>::max()) continue;
        const Edge& edge = cloth.edges[e];
        const SpringMaterial& m = material[static_cast<std::size_t>(edge.kind)];
        g.sell_stiffness[at] = m.stiffness * edge.scale;
        g.sell_damping[at] = m.damping * edge.scale;
    }
}

std::optional<GridStructuralRest> uniform_grid_structural(const Cloth& cloth) {
    if (!cloth.grid || cloth.grid->columns == 0 ||
        std::size_t{cloth.grid->columns} * cloth.grid->rows != cloth.particle_count)
        return std::nullopt;
    const std::size_t columns = cloth.grid->columns, rows = cloth.grid->rows;
    GridStructuralRest rest;
    std::size_t east = 0, south = 0;
    for (const Edge& e : cloth.edges) {
        if (e.kind != SpringKind::structural) continue;
        const std::size_t a = std::min(e.a, e.b), b = std::max(e.a, e.b);
        if (b == a + 1 && a % columns + 1 < columns) {
            if (east++ == 0) rest.east = e.rest;
            if (e.rest != rest.east) return std::nullopt;
        } else if (b == a + columns) {
            if (south++ == 0) rest.south = e.rest;
            if (e.rest != rest.south) return std::nullopt;
        } else {
            return std::nullopt;
        }
    }
    if (east != rows * (columns - 1) || south != columns * (rows - 1)) return std::nullopt;
    return rest;
}

std::vector<std::uint32_t> sewn_representatives(const SeamSet& seams, std::size_t particle_count) {
    std::vector<std::uint32_t> rep(particle_count);
    for (std::uint32_t i = 0; i < rep.size(); ++i) rep[i] = i;
    auto root = [&](std::uint32_t i) {
        while (rep[i] != i) i = rep[i] = rep[rep[i]];
        return i;
    };
    for (std::size_t k = 0; k < seams.a.size(); ++k) {
        const std::uint32_t ra = root(seams.a[k]), rb = root(seams.b[k]);
        if (ra != rb) rep[std::max(ra, rb)] = std::min(ra, rb);
    }
    for (std::uint32_t i = 0; i < rep.size(); ++i) rep[i] = root(i);
    return rep;
}

double cloth_spacing(const Cloth& cloth) {
    double structural = 0.0, all = 0.0;
    std::size_t count = 0;
    for (const Edge& e : cloth.edges) {
        all += e.rest;
        if (e.kind == SpringKind::structural) structural += e.rest, ++count;
    }
    if (count) return structural / double(count);
    return cloth.edges.empty() ? 0.0 : all / double(cloth.edges.size());
}

} // namespace drape
