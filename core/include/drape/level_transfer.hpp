// The implicit solver's coarse levels (docs/implicit.md, "Multilevel initial guess"): a cloth that can rebuild itself
// at a coarser spacing (Cloth::coarsen) hands the solver each coarser copy with two linear maps, one from the cloth's
// particles onto the copy's nodes and one from the copy onto the next finer copy (or onto the cloth). Grids map
// bilinearly by grid coordinates; meshes (outline cloths) by the barycentric coordinates of the closest point on the
// other copy's triangles, both taken in the flat layout the two were built in. Cooked once, outside any step.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/cloth.hpp"

namespace drape {

/// A linear map between two discretisations of one cloth: target node k gets
/// sum over c < width of weight[k][c] * source[index[k][c]] (unused entries weigh 0 and point at node 0).
struct LevelTransfer {
    static constexpr std::size_t width = 6; ///< bilinear: 4; a triangle: 3; a triangle and its mirror image: 6
    std::vector<std::array<std::uint32_t, width>> index;
    std::vector<std::array<float, width>> weight;
    std::size_t size() const noexcept { return index.size(); }
    /// Per target node: the source node of its largest weight (the later one on a tie): the source node nearest it.
    std::vector<std::uint32_t> nearest() const;
    /// For a mirror-symmetric pair of layouts (each node's mirror twin, vbd::mirror_twins, in the target and in the
    /// source): each target node's map becomes the mean of its own and its twin's mirrored, so that mirror images
    /// map alike (a triangulation is not mirror symmetric: a point on a cell's diagonal took that diagonal's ends).
    /// Needs at most 3 entries per node; does nothing when either twin list is empty; a node whose twin, or one of
    /// whose twin's source nodes, has no twin (UINT32_MAX) keeps its own map.
    void symmetrise(const std::vector<std::uint32_t>& target_twins, const std::vector<std::uint32_t>& source_twins);
};

/// A coarser copy of a cloth: the same material, pins and placement at about twice the spacing of the next finer.
struct CoarseCloth {
    Cloth cloth;
    LevelTransfer from_fine; ///< onto this copy's nodes, from the cloth's own particles
    LevelTransfer to_finer;  ///< onto the next finer copy's nodes (the cloth's own particles for the first), from this
    std::vector<float> x, y, z; ///< where the copy was built (a mesh's layout: its mirror twins are found there)
};

/// Square grids, node (i, j) of a to_n x to_n grid sampled bilinearly at (i, j) (from_n - 1) / (to_n - 1) on a
/// from_n x from_n grid spanning the same square (from_n, to_n >= 2).
LevelTransfer bilinear_transfer(std::uint32_t from_n, std::uint32_t to_n);

/// Meshes: each target point mapped to the closest point of the source triangles (3 indices each), its barycentric
/// coordinates as weights. A bucket grid of the triangles' boxes finds it; ties go to the lower triangle index. Source
/// and target are positions of one layout (a panel lying flat where both copies were built).
LevelTransfer surface_transfer(std::span<const float> sx, std::span<const float> sy, std::span<const float> sz,
                               std::span<const std::uint32_t> triangles, std::span<const float> tx,
                               std::span<const float> ty, std::span<const float> tz);

} // namespace drape
