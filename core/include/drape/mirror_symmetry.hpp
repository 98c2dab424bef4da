// Exact left-right mirror symmetry of a cloth whose mesh is its own mirror image (the T-shirt: docs/garments.md,
// "Mirror-exact sums"). A particle's forces are sums over its springs and bending stencil; taken in index order,
// the sum at particle i and at its mirror twin add the same terms in a different order, so the two halves part by
// float rounding, and a buckling fold amplifies that into centimetres. Here the sums at twin(i) add the mirror
// images of i's terms in the same order (and a particle on the centre line adds each term next to its mirror image),
// and every cooked constant of a twin equals its partner's, so a mirror-symmetric state stays mirror-symmetric bit
// for bit through the stages that read these rows.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "drape/spring_graph.hpp"

namespace drape {

struct Cloth;

/// Checks that `twin` is a mirror map of `particle_count` particles: one entry per particle, each < particle_count,
/// twin[twin[i]] == i. Throws InvalidInput naming the first particle that breaks it.
void check_mirror_map(std::span<const std::uint32_t> twin, std::size_t particle_count);

/// The order to take particle i's row in: `row` is i's entries (sorted), `partner_row` those of its twin `t` (sorted),
/// `entry_twin` the entries' mirror map (the particle map for neighbours, mirror_triangle_map's for triangles).
/// Returns the positions in `row` to visit, first to last: for i < t the row as it is; for i > t the twins of
/// partner_row's entries, in partner_row's order; for a particle on the centre line (t == i) each entry e with
/// e < entry_twin[e] followed by its twin (an entry that is its own twin alone). Throws InvalidInput if the rows are
/// not mirror images of each other.
std::vector<std::uint32_t> mirror_row_order(std::uint32_t i, std::uint32_t t, std::span<const std::uint32_t> row,
                                            std::span<const std::uint32_t> partner_row,
                                            std::span<const std::uint32_t> entry_twin);

/// mirror_row_order over a whole CSR table (`offsets`, n + 1 entries; `entries`, each row sorted; `twin`, the
/// particles' mirror map): for each slot of `entries`, the slot whose entry goes there when every row is put in mirror
/// order. Apply it to `entries` and to every column stored beside it.
std::vector<std::uint32_t> mirror_row_sources(std::span<const std::uint32_t> offsets,
                                              std::span<const std::uint32_t> entries,
                                              std::span<const std::uint32_t> twin,
                                              std::span<const std::uint32_t> entry_twin);

/// `values` put in the order of a mirror_row_sources permutation: result[k] = values[from[k]]. For the columns stored
/// beside a CSR table's entries.
template <class T> std::vector<T> gather(const std::vector<T>& values, std::span<const std::uint32_t> from) {
    std::vector<T> out(from.size());
    for (std::size_t k = 0; k < from.size(); ++k) out[k] = values[from[k]];
    return out;
}

/// For each triangle (3 corners each) of `triangles`, the index of its mirror image (the triangle whose corners are
/// the twins of its corners). Throws InvalidInput naming a triangle that has none.
std::vector<std::uint32_t> mirror_triangle_map(std::span<const std::uint32_t> triangles,
                                               std::span<const std::uint32_t> twin);

/// For each spring of `edges`, the index of its mirror image (the spring joining the twins of its ends, in either
/// order; a spring across the mirror line or along it is its own). Throws InvalidInput naming a spring that has none.
std::vector<std::uint32_t> mirror_edge_map(std::span<const Edge> edges, std::span<const std::uint32_t> twin);

/// Makes `cloth` mirror-exact about the map `twin` (check_mirror_map): every pair's inverse masses, every mirror
/// pair of springs' rest lengths and stiffness scales, and every bending coefficient set to the lower-indexed
/// partner's; the SELL rows of the springs and of bending reordered by mirror_row_order. Stores the map in
/// Cloth::mirror, and with triangles Cloth::mirror_triangle (mirror_triangle_map) and Cloth::mirror_corners: the
/// triangles' corners with a triangle after its twin listed as the twins of the twin's corners in the same order (its
/// winding reversed), which the collide stage's triangle pass reads. Throws InvalidInput if the cloth's springs or bending stencils are not mirror images.
void make_mirror_exact(Cloth& cloth, std::vector<std::uint32_t> twin);

} // namespace drape
