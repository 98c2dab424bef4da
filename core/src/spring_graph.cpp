// Cooks the spring graph: CSR (both directions, sorted rows) and its SIMD-sliced SELL-C form.
#include "drape/spring_graph.hpp"

#include <algorithm>
#include <limits>

#include "drape/mirror_symmetry.hpp"
#include "drape/simd.hpp"
#include "sell_layout.hpp"

namespace drape {

const char* spring_kind_name(SpringKind kind) noexcept {
    switch (kind) {
    case SpringKind::structural: return "structural";
    case SpringKind::shear: return "shear";
    case SpringKind::bend: return "bend";
    case SpringKind::seam: return "seam";
    }
    return "unknown";
}

SpringGraph build_spring_graph(std::size_t particle_count, std::size_t padded_count, std::span<const Edge> edges,
                               std::span<const std::uint32_t> mirror) {
    SpringGraph g;
    const std::size_t n = particle_count;

    // CSR: count, prefix-sum, fill, then sort each row by neighbour.
    g.offsets.assign(n + 1, 0);
    for (const Edge& e : edges) {
        if (e.kind == SpringKind::seam) continue; // seams are coloured groups, not CSR rows (cloth.hpp)
        ++g.offsets[e.a + 1];
        ++g.offsets[e.b + 1];
    }
    for (std::size_t i = 0; i < n; ++i) g.offsets[i + 1] += g.offsets[i];
    g.neighbour.resize(g.offsets[n]);
    g.edge_index.resize(g.offsets[n]);
    std::vector<std::uint32_t> fill(g.offsets.begin(), g.offsets.end() - 1);
    for (std::uint32_t k = 0; k < edges.size(); ++k) {
        const Edge& e = edges[k];
        if (e.kind == SpringKind::seam) continue;
        g.neighbour[fill[e.a]] = e.b;
        g.edge_index[fill[e.a]++] = k;
        g.neighbour[fill[e.b]] = e.a;
        g.edge_index[fill[e.b]++] = k;
    }
    std::vector<std::pair<std::uint32_t, std::uint32_t>> row;
    for (std::size_t i = 0; i < n; ++i) {
        row.clear();
        for (std::uint32_t k = g.offsets[i]; k < g.offsets[i + 1]; ++k) row.emplace_back(g.neighbour[k], g.edge_index[k]);
        std::sort(row.begin(), row.end());
        for (std::uint32_t k = g.offsets[i], r = 0; k < g.offsets[i + 1]; ++k, ++r) {
            g.neighbour[k] = row[r].first;
            g.edge_index[k] = row[r].second;
        }
    }

    // SELL-C: slices of simd::width consecutive particles, slot-major, padded with inert self-entries.
    constexpr std::size_t C = simd::width;
    const std::size_t slices = padded_count / C;
    const std::size_t total = sell_slices(g.offsets, n, padded_count, g.slice_begin, g.slice_slots);
    // With a mirror map, each particle's slots are filled in mirror order (mirror_symmetry.hpp), else in CSR order.
    const std::vector<std::uint32_t> from =
        mirror.empty() ? std::vector<std::uint32_t>{} : mirror_row_sources(g.offsets, g.neighbour, mirror, mirror);
    g.sell_neighbour.reset(total);
    g.sell_rest.reset(total);
    g.sell_stiffness.reset(total);
    g.sell_damping.reset(total);
    g.sell_edge.assign(total, std::numeric_limits<std::uint32_t>::max());
    for (std::size_t s = 0; s < slices; ++s) {
        for (std::size_t lane = 0; lane < C; ++lane) {
            const std::size_t i = s * C + lane;
            const std::uint32_t len = i < n ? g.offsets[i + 1] - g.offsets[i] : 0;
            for (std::uint32_t slot = 0; slot < g.slice_slots[s]; ++slot) {
                const std::size_t at = g.slice_begin[s] + slot * C + lane;
                if (slot < len) {
                    const std::uint32_t k = from.empty() ? g.offsets[i] + slot : from[g.offsets[i] + slot];
                    g.sell_neighbour[at] = g.neighbour[k];
                    g.sell_edge[at] = g.edge_index[k];
                    g.sell_rest[at] = edges[g.edge_index[k]].rest;
                } else {
                    g.sell_neighbour[at] = static_cast<std::uint32_t>(i); // inert: zero length, zero stiffness
                }
            }
        }
    }
    return g;
}

} // namespace drape
