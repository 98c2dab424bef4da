// Exact mirror symmetry of a cloth (mirror_symmetry.hpp).
#include "drape/mirror_symmetry.hpp"

#include <algorithm>
#include <array>
#include <string>
#include <utility>

#include "drape/bending.hpp"
#include "drape/cloth.hpp"
#include "drape/errors.hpp"

namespace drape {

void check_mirror_map(std::span<const std::uint32_t> twin, std::size_t particle_count) {
    if (twin.size() != particle_count)
        throw InvalidInput("mirror map has " + std::to_string(twin.size()) + " entries for " +
                           std::to_string(particle_count) + " particles (need one per particle)");
    for (std::size_t i = 0; i < twin.size(); ++i) {
        if (twin[i] >= particle_count)
            throw InvalidInput("mirror map: particle " + std::to_string(i) + "'s twin " + std::to_string(twin[i]) +
                               " is outside [0, " + std::to_string(particle_count - 1) + "]");
        if (twin[twin[i]] != i)
            throw InvalidInput("mirror map: particle " + std::to_string(i) + "'s twin is " + std::to_string(twin[i]) +
                               ", whose twin is " + std::to_string(twin[twin[i]]) + " (must be " + std::to_string(i) +
                               ")");
    }
}

namespace {

std::uint32_t position_of(std::span<const std::uint32_t> sorted_row, std::uint32_t j, std::uint32_t i) {
    const auto it = std::lower_bound(sorted_row.begin(), sorted_row.end(), j);
    if (it == sorted_row.end() || *it != j)
        throw InvalidInput("mirror map: particle " + std::to_string(i) + "'s row has no neighbour " + std::to_string(j) +
                           " where its twin's row has that particle's twin (the cloth is not its own mirror image)");
    return static_cast<std::uint32_t>(it - sorted_row.begin());
}

} // namespace

std::vector<std::uint32_t> mirror_row_order(std::uint32_t i, std::uint32_t t, std::span<const std::uint32_t> row,
                                            std::span<const std::uint32_t> partner_row,
                                            std::span<const std::uint32_t> entry_twin) {
    std::vector<std::uint32_t> order;
    order.reserve(row.size());
    if (row.size() != partner_row.size())
        throw InvalidInput("mirror map: particle " + std::to_string(i) + " has " + std::to_string(row.size()) +
                           " entries, its twin " + std::to_string(t) + " " + std::to_string(partner_row.size()) +
                           " (the cloth is not its own mirror image)");
    if (i < t) {
        for (std::uint32_t k = 0; k < row.size(); ++k) order.push_back(k);
    } else if (i > t) {
        for (const std::uint32_t e : partner_row) order.push_back(position_of(row, entry_twin[e], i));
    } else {
        for (std::uint32_t k = 0; k < row.size(); ++k) {
            const std::uint32_t e = row[k];
            if (entry_twin[e] == e) {
                order.push_back(k);
            } else if (e < entry_twin[e]) {
                order.push_back(k);
                order.push_back(position_of(row, entry_twin[e], i));
            }
        }
    }
    return order;
}

std::vector<std::uint32_t> mirror_row_sources(std::span<const std::uint32_t> offsets,
                                              std::span<const std::uint32_t> entries,
                                              std::span<const std::uint32_t> twin,
                                              std::span<const std::uint32_t> entry_twin) {
    std::vector<std::uint32_t> from(entries.size());
    const auto row = [&](std::size_t p) { return entries.subspan(offsets[p], offsets[p + 1] - offsets[p]); };
    for (std::size_t i = 0; i + 1 < offsets.size(); ++i) {
        const std::vector<std::uint32_t> order =
            mirror_row_order(std::uint32_t(i), twin[i], row(i), row(twin[i]), entry_twin);
        for (std::size_t k = 0; k < order.size(); ++k) from[offsets[i] + k] = offsets[i] + order[k];
    }
    return from;
}

std::vector<std::uint32_t> mirror_triangle_map(std::span<const std::uint32_t> triangles,
                                               std::span<const std::uint32_t> twin) {
    const std::size_t count = triangles.size() / 3;
    using Key = std::array<std::uint32_t, 3>;
    auto key = [](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        Key k{a, b, c};
        std::sort(k.begin(), k.end());
        return k;
    };
    std::vector<std::pair<Key, std::uint32_t>> sorted(count);
    for (std::uint32_t t = 0; t < count; ++t)
        sorted[t] = {key(triangles[3 * t], triangles[3 * t + 1], triangles[3 * t + 2]), t};
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::uint32_t> map(count);
    for (std::uint32_t t = 0; t < count; ++t) {
        const Key k = key(twin[triangles[3 * t]], twin[triangles[3 * t + 1]], twin[triangles[3 * t + 2]]);
        const auto it = std::lower_bound(sorted.begin(), sorted.end(), std::pair{k, std::uint32_t{0}});
        if (it == sorted.end() || it->first != k)
            throw InvalidInput("mirror map: triangle " + std::to_string(t) + " (" + std::to_string(triangles[3 * t]) +
                               ", " + std::to_string(triangles[3 * t + 1]) + ", " +
                               std::to_string(triangles[3 * t + 2]) + ") has no mirror image");
        map[t] = it->second;
    }
    return map;
}

std::vector<std::uint32_t> mirror_edge_map(std::span<const Edge> edges, std::span<const std::uint32_t> twin) {
    std::vector<std::pair<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t>> sorted(edges.size());
    for (std::size_t k = 0; k < edges.size(); ++k)
        sorted[k] = {{std::min(edges[k].a, edges[k].b), std::max(edges[k].a, edges[k].b)}, std::uint32_t(k)};
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::uint32_t> map(edges.size());
    for (std::size_t k = 0; k < edges.size(); ++k) {
        const std::uint32_t ta = twin[edges[k].a], tb = twin[edges[k].b];
        const std::pair key{std::min(ta, tb), std::max(ta, tb)};
        const auto it = std::lower_bound(sorted.begin(), sorted.end(), std::pair{key, std::uint32_t{0}});
        if (it == sorted.end() || it->first != key)
            throw InvalidInput("mirror map: spring " + std::to_string(edges[k].a) + "-" + std::to_string(edges[k].b) +
                               " has no mirror image " + std::to_string(key.first) + "-" + std::to_string(key.second));
        map[k] = it->second;
    }
    return map;
}

void make_mirror_exact(Cloth& cloth, std::vector<std::uint32_t> twin) {
    const std::size_t n = cloth.particle_count;
    check_mirror_map(twin, n);
    for (std::size_t i = 0; i < n; ++i) {
        if (twin[i] >= i) continue;
        cloth.inv_mass[i] = cloth.inv_mass[twin[i]];
        if (!cloth.free_inv_mass.empty()) cloth.free_inv_mass[i] = cloth.free_inv_mass[twin[i]];
    }
    // Springs: each takes its mirror image's figures where that comes first.
    std::vector<Edge>& edges = cloth.edges;
    const std::vector<std::uint32_t> edge_twin = mirror_edge_map(edges, twin);
    for (std::size_t k = 0; k < edges.size(); ++k) {
        const std::size_t m = edge_twin[k];
        if (m >= k) continue;
        edges[k].rest = edges[m].rest;
        edges[k].scale = edges[m].scale;
        edges[k].kind = edges[m].kind;
    }
    SeamSet& seams = cloth.seams;
    for (std::size_t k = 0; k < seams.groups.edge_index.size(); ++k) {
        const Edge& e = edges[seams.groups.edge_index[k]];
        seams.rest[k] = e.rest;
        seams.scale[k] = e.scale;
    }
    cloth.mirror = std::move(twin);
    cloth.mirror_triangle.clear();
    cloth.mirror_corners.clear();
    if (!cloth.triangles.empty()) {
        cloth.mirror_triangle = mirror_triangle_map(cloth.triangles, cloth.mirror);
        cloth.mirror_corners = cloth.triangles;
        for (std::size_t t = 0; t < cloth.mirror_triangle.size(); ++t) {
            const std::uint32_t m = cloth.mirror_triangle[t];
            if (m >= t) continue;
            for (int c = 0; c < 3; ++c) cloth.mirror_corners[3 * t + c] = cloth.mirror[cloth.triangles[3 * m + c]];
        }
    }
    cloth.graph = build_spring_graph(n, cloth.padded_count, cloth.edges, cloth.mirror);
    apply_materials(cloth, cloth.material);
    if (!cloth.bending.elements.empty()) {
        std::vector<BendElement> elements = std::move(cloth.bending.elements);
        set_bending(cloth, std::move(elements), cloth.bending.damping);
    }
}

} // namespace drape
