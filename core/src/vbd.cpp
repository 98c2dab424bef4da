// Cooking for vertex block descent: per-vertex springs (CSR), bending rows in float, and a greedy vertex colouring.
#include "vbd.hpp"

#include <algorithm>
#include <numeric>

namespace drape::vbd {

void refresh_materials(VbdGraph& g, const Cloth& cloth) {
    for (std::size_t e = 0; e < g.spring_edge.size(); ++e) {
        const Edge& edge = cloth.edges[g.spring_edge[e]];
        const SpringMaterial& m = cloth.material[static_cast<std::size_t>(edge.kind)];
        g.spring_k[e] = m.stiffness * edge.scale;
        g.spring_kd[e] = m.damping * edge.scale;
    }
}

VbdGraph cook(const Cloth& cloth) {
    const std::size_t n = cloth.particle_count;
    VbdGraph g;
    g.particle_count = n;

    // Springs: both directions of every edge, rows sorted by neighbour.
    g.spring_offsets.assign(n + 1, 0);
    for (const Edge& e : cloth.edges) {
        ++g.spring_offsets[e.a + 1];
        ++g.spring_offsets[e.b + 1];
    }
    std::partial_sum(g.spring_offsets.begin(), g.spring_offsets.end(), g.spring_offsets.begin());
    const std::size_t entries = g.spring_offsets[n];
    g.spring_neighbour.resize(entries);
    g.spring_edge.resize(entries);
    std::vector<std::uint32_t> fill(g.spring_offsets.begin(), g.spring_offsets.end() - 1);
    for (std::uint32_t k = 0; k < cloth.edges.size(); ++k) {
        const Edge& e = cloth.edges[k];
        g.spring_neighbour[fill[e.a]] = e.b;
        g.spring_edge[fill[e.a]++] = k;
        g.spring_neighbour[fill[e.b]] = e.a;
        g.spring_edge[fill[e.b]++] = k;
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> row;
    for (std::size_t i = 0; i < n; ++i) {
        const std::uint32_t b = g.spring_offsets[i], end = g.spring_offsets[i + 1];
        row.clear();
        for (std::uint32_t e = b; e < end; ++e) row.emplace_back(g.spring_neighbour[e], g.spring_edge[e]);
        std::sort(row.begin(), row.end());
        for (std::uint32_t e = b; e < end; ++e) {
            g.spring_neighbour[e] = row[e - b].first;
            g.spring_edge[e] = row[e - b].second;
        }
    }
    g.spring_k.resize(entries);
    g.spring_kd.resize(entries);
    g.spring_rest.resize(entries);
    for (std::size_t e = 0; e < entries; ++e) g.spring_rest[e] = cloth.edges[g.spring_edge[e]].rest;
    refresh_materials(g, cloth);

    // Bending rows from the cooked Q (double) into float.
    const BendingSet& bend = cloth.bending;
    if (!bend.empty()) {
        g.bend_offsets = bend.offsets;
        g.bend_neighbour = bend.neighbour;
        g.bend_q.resize(bend.value.size());
        g.bend_diag.assign(n, 0.0f);
        for (std::size_t i = 0; i < n; ++i) {
            double diag = 0.0;
            for (std::uint32_t e = bend.offsets[i]; e < bend.offsets[i + 1]; ++e) {
                g.bend_q[e] = static_cast<float>(bend.value[e]);
                diag -= bend.value[e];
            }
            g.bend_diag[i] = static_cast<float>(diag);
        }
        g.bend_beta = bend.damping;
    }

    // Greedy colouring in index order: each vertex takes the smallest colour none of its coupled neighbours
    // (springs or bending) has yet.
    std::vector<std::uint32_t> colour(n, UINT32_MAX);
    std::vector<std::uint32_t> stamp; // stamp[c] == i + 1: colour c is taken by a neighbour of i
    std::uint32_t colours = 0;
    for (std::uint32_t i = 0; i < n; ++i) {
        auto mark = [&](std::uint32_t j) {
            const std::uint32_t c = colour[j];
            if (c == UINT32_MAX) return;
            if (c >= stamp.size()) stamp.resize(c + 1, 0);
            stamp[c] = i + 1;
        };
        for (std::uint32_t e = g.spring_offsets[i]; e < g.spring_offsets[i + 1]; ++e) mark(g.spring_neighbour[e]);
        if (!bend.empty())
            for (std::uint32_t e = bend.offsets[i]; e < bend.offsets[i + 1]; ++e) mark(bend.neighbour[e]);
        std::uint32_t c = 0;
        while (c < stamp.size() && stamp[c] == i + 1) ++c;
        colour[i] = c;
        colours = std::max(colours, c + 1);
    }
    g.colour_offsets.assign(colours + 1, 0);
    for (std::uint32_t c : colour) ++g.colour_offsets[c + 1];
    std::partial_sum(g.colour_offsets.begin(), g.colour_offsets.end(), g.colour_offsets.begin());
    g.colour_vertex.resize(n);
    fill.assign(g.colour_offsets.begin(), g.colour_offsets.end() - 1);
    for (std::uint32_t i = 0; i < n; ++i) g.colour_vertex[fill[colour[i]]++] = i;
    return g;
}

} // namespace drape::vbd
