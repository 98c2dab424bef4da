// Greedy edge colouring into conflict-free groups plus a serial overflow group (see colouring.hpp).
#include "drape/colouring.hpp"

#include <algorithm>
#include <bit>
#include <string>

#include "drape/errors.hpp"

namespace drape {

ColourGroups colour_edges(std::span<const Edge> edges, std::size_t particle_count,
                          std::span<const std::uint32_t> subset, std::uint32_t max_colours) {
    if (max_colours < 1 || max_colours > colouring_max_colours)
        throw InvalidInput("max_colours = " + std::to_string(max_colours) +
                           " is outside the allowed range [1, " + std::to_string(colouring_max_colours) +
                           "]");
    if (edges.size() > std::size_t{0xffffffffu})
        throw InvalidInput("colouring: " + std::to_string(edges.size()) + " edges (max 2^32-1)");
    for (std::size_t k = 0; k < edges.size(); ++k) {
        const Edge& e = edges[k];
        if (e.a >= particle_count || e.b >= particle_count)
            throw InvalidInput("colouring: edge " + std::to_string(k) + " (" + std::to_string(e.a) + "-" +
                               std::to_string(e.b) + ") names a particle outside [0, " +
                               std::to_string(particle_count == 0 ? 0 : particle_count - 1) + "]");
        if (e.a == e.b)
            throw InvalidInput("colouring: edge " + std::to_string(k) + " joins particle " +
                               std::to_string(e.a) + " to itself");
    }
    std::vector<std::uint32_t> visit;
    if (subset.empty()) {
        visit.resize(edges.size());
        for (std::size_t k = 0; k < edges.size(); ++k)
            visit[k] = static_cast<std::uint32_t>(k);
    } else {
        std::vector<std::uint8_t> seen(edges.size(), 0);
        for (std::uint32_t k : subset) {
            if (k >= edges.size())
                throw InvalidInput("colouring: subset names edge " + std::to_string(k) + " outside [0, " +
                                   std::to_string(edges.size() == 0 ? 0 : edges.size() - 1) + "]");
            if (seen[k]) throw InvalidInput("colouring: subset names edge " + std::to_string(k) + " twice");
            seen[k] = 1;
        }
        visit.assign(subset.begin(), subset.end());
    }

    // Greedy: smallest colour free at both ends. `colour_of` uses max_colours for the overflow group.
    std::vector<std::uint64_t> used(particle_count, 0);
    std::vector<std::uint32_t> colour_of(visit.size());
    std::vector<std::uint32_t> count(max_colours + 1, 0);
    const std::uint64_t allowed =
        max_colours == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << max_colours) - 1;
    for (std::size_t k = 0; k < visit.size(); ++k) {
        const Edge& e = edges[visit[k]];
        const std::uint64_t free_colours = ~(used[e.a] | used[e.b]) & allowed;
        std::uint32_t c = max_colours;
        if (free_colours != 0) {
            c = static_cast<std::uint32_t>(std::countr_zero(free_colours));
            used[e.a] |= std::uint64_t{1} << c;
            used[e.b] |= std::uint64_t{1} << c;
        }
        colour_of[k] = c;
        ++count[c];
    }
    // Greedy takes the smallest free colour, so the colours in use are 0..colour_count-1 without gaps.
    ColourGroups out;
    while (out.colour_count < max_colours && count[out.colour_count] > 0)
        ++out.colour_count;
    out.overflow_count = count[max_colours];
    out.has_overflow = out.overflow_count > 0;
    const std::uint32_t groups = out.colour_count + (out.has_overflow ? 1u : 0u);
    out.group_offsets.assign(groups + 1, 0);
    for (std::uint32_t g = 0; g < out.colour_count; ++g)
        out.group_offsets[g + 1] = out.group_offsets[g] + count[g];
    if (out.has_overflow) out.group_offsets[groups] = out.group_offsets[groups - 1] + count[max_colours];
    out.edge_index.resize(visit.size());
    std::vector<std::uint32_t> fill(out.group_offsets.begin(), out.group_offsets.end() - 1);
    for (std::size_t k = 0; k < visit.size(); ++k) {
        const std::uint32_t g = colour_of[k] == max_colours ? out.colour_count : colour_of[k];
        out.edge_index[fill[g]++] = visit[k];
    }
    // Sort each group by particle index (memory locality); ties by edge index.
    for (std::uint32_t g = 0; g < groups; ++g)
        std::sort(out.edge_index.begin() + out.group_offsets[g],
                  out.edge_index.begin() + out.group_offsets[g + 1], [&](std::uint32_t l, std::uint32_t r) {
                      const std::uint32_t la = std::min(edges[l].a, edges[l].b),
                                          ra = std::min(edges[r].a, edges[r].b);
                      if (la != ra) return la < ra;
                      const std::uint32_t lb = std::max(edges[l].a, edges[l].b),
                                          rb = std::max(edges[r].a, edges[r].b);
                      return lb != rb ? lb < rb : l < r;
                  });
    if (out.colour_count > 0) {
        out.largest_group = 0;
        out.smallest_group = visit.size();
        for (std::uint32_t g = 0; g < out.colour_count; ++g) {
            out.largest_group = std::max<std::size_t>(out.largest_group, count[g]);
            out.smallest_group = std::min<std::size_t>(out.smallest_group, count[g]);
        }
    }
    return out;
}

} // namespace drape
