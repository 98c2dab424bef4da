// Greedy edge colouring: springs split into groups in which no two springs share a particle (DESIGN.md
// "Data").
//
// A group can be processed in parallel (and in SIMD lanes) with plain writes to both ends of each spring;
// groups run one after another in a fixed order, so results do not depend on the thread count. Used for the
// seam springs and for strain limiting ("colour once, use the colours twice").
//
// Algorithm: edges are visited in the given order; each takes the smallest colour not yet used by either end
// (one 64-bit mask of used colours per particle). Greedy needs at most 2D - 1 colours for a graph of maximum
// degree D (23 for the 12-neighbour grid cloth). Colours are capped at max_colours; an edge that finds none
// free goes to a final "overflow" group, processed serially (its springs may share particles). Each group is
// sorted by (lower particle index, higher particle index) for memory locality. Deterministic: the same input
// gives the same groups.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/spring_graph.hpp"

namespace drape {

inline constexpr std::uint32_t colouring_max_colours = 64; ///< hard cap (one 64-bit mask per particle)

/// Colour groups as CSR: group g holds edge_index[group_offsets[g] .. group_offsets[g+1]). Groups
/// 0..colour_count-1 are conflict-free colours (none empty); if has_overflow, group colour_count is the
/// serial overflow group.
struct ColourGroups {
    std::vector<std::uint32_t> group_offsets; ///< group_count() + 1 entries
    std::vector<std::uint32_t> edge_index;    ///< indices into the edge list that was coloured
    std::uint32_t colour_count = 0;           ///< conflict-free groups
    bool has_overflow = false;
    // Statistics (over the colour groups, not the overflow group; 0 when there is no colour).
    std::size_t largest_group = 0;
    std::size_t smallest_group = 0;
    std::size_t overflow_count = 0; ///< edges in the overflow group

    std::size_t group_count() const noexcept { return group_offsets.empty() ? 0 : group_offsets.size() - 1; }
    std::span<const std::uint32_t> group(std::size_t g) const noexcept {
        return {edge_index.data() + group_offsets[g], group_offsets[g + 1] - group_offsets[g]};
    }
    bool is_overflow(std::size_t g) const noexcept { return has_overflow && g == colour_count; }
};

/// Colours `edges` over `particle_count` particles: every edge in exactly one group. `subset`, when not
/// empty, lists the edges to colour (indices into `edges`, in visiting order; e.g. only the seam springs of a
/// cloth); otherwise all edges are coloured in order. max_colours: 1..64. Throws InvalidInput on an edge
/// naming a particle out of range, a self loop, a subset index out of range or repeated, or max_colours out
/// of range.
///
/// `edge_twin`, when not empty, is a mirror map of the edges (one entry per edge, mirror_edge_map in
/// mirror_symmetry.hpp): each edge is coloured together with its mirror image (same group, placed right after it;
/// groups then keep the visiting order), so a sweep over the groups treats the two halves of a mirror-symmetric cloth
/// alike. An edge and its mirror image that meet at a particle on the mirror line share a group anyway (the only two
/// edges of a conflict-free group that share a particle): the caller solves them together. Throws InvalidInput if an
/// edge's mirror image is not among the edges coloured.
ColourGroups colour_edges(std::span<const Edge> edges, std::size_t particle_count,
                          std::span<const std::uint32_t> subset = {},
                          std::uint32_t max_colours = colouring_max_colours,
                          std::span<const std::uint32_t> edge_twin = {});

} // namespace drape
