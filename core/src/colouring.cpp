// Greedy edge colouring into conflict-free groups plus a serial overflow group (see colouring.hpp).
#include "drape/colouring.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <string>

#include "drape/errors.hpp"

namespace drape {

ColourGroups colour_edges(std::span<const Edge> edges, std::size_t particle_count,
                          std::span<const std::uint32_t> subset, std::uint32_t max_colours,
                          std::span<const std::uint32_t> edge_twin) {
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
    if (!edge_twin.empty() && edge_twin.size() != edges.size())
        throw InvalidInput("colouring: mirror map has " + std::to_string(edge_twin.size()) + " entries for " +
                           std::to_string(edges.size()) + " edges (need one per edge)");
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

    // With a mirror map: position in `visit` of each edge's mirror image (the unit an edge is coloured with).
    constexpr std::uint32_t none = 0xffffffffu;
    std::vector<std::uint32_t> partner(edge_twin.empty() ? 0 : visit.size(), none);
    if (!edge_twin.empty()) {
        std::vector<std::uint32_t> position(edges.size(), none);
        for (std::size_t k = 0; k < visit.size(); ++k) position[visit[k]] = static_cast<std::uint32_t>(k);
        for (std::size_t k = 0; k < visit.size(); ++k) {
            const std::uint32_t m = edge_twin[visit[k]];
            if (m >= edges.size() || position[m] == none || edge_twin[m] != visit[k])
                throw InvalidInput("colouring: edge " + std::to_string(visit[k]) + "'s mirror image " +
                                   std::to_string(m) + " is not among the edges coloured (or is not its mirror image)");
            partner[k] = position[m];
        }
    }

    // Greedy: smallest colour free at both ends (with a mirror map: at the ends of the edge and of its mirror
    // image, coloured together). `colour_of` uses max_colours for the overflow group.
    std::vector<std::uint64_t> used(particle_count, 0);
    std::vector<std::uint32_t> colour_of(visit.size());
    std::vector<std::uint32_t> count(max_colours + 1, 0);
    const std::uint64_t allowed =
        max_colours == 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << max_colours) - 1;
    for (std::size_t k = 0; k < visit.size(); ++k) {
        const bool paired = !partner.empty() && partner[k] != k;
        if (paired && partner[k] < k) continue; // coloured with its mirror image
        const Edge& e = edges[visit[k]];
        std::array<std::uint32_t, 4> ends{e.a, e.b, e.a, e.b};
        if (paired) ends[2] = edges[visit[partner[k]]].a, ends[3] = edges[visit[partner[k]]].b;
        std::uint64_t taken = 0;
        for (std::uint32_t i : ends) taken |= used[i];
        const std::uint64_t free_colours = ~taken & allowed;
        std::uint32_t c = max_colours;
        if (free_colours != 0) {
            c = static_cast<std::uint32_t>(std::countr_zero(free_colours));
            for (std::uint32_t i : ends) used[i] |= std::uint64_t{1} << c;
        }
        colour_of[k] = c;
        ++count[c];
        if (paired) colour_of[partner[k]] = c, ++count[c];
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
        if (!partner.empty() && partner[k] < k) continue; // placed right after its mirror image
        const std::uint32_t g = colour_of[k] == max_colours ? out.colour_count : colour_of[k];
        out.edge_index[fill[g]++] = visit[k];
        if (!partner.empty() && partner[k] != k) out.edge_index[fill[g]++] = visit[partner[k]];
    }
    // Sort each group by particle index (memory locality); ties by edge index. With a mirror map the groups keep
    // the visiting order, each edge's mirror image next to it.
    for (std::uint32_t g = 0; g < groups && edge_twin.empty(); ++g)
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
