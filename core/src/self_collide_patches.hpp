// Self-collision's patches (self_collide_patches.cpp): cooked once from the cloth's triangles.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>

#include "drape/simulation.hpp"

namespace drape {

/// Triangles per patch, at most.
inline constexpr std::uint32_t self_collision_patch_max = 32;

/// Triangles per patch for thickness h on a cloth of mean edge L: a patch about as wide as a contact reaches, 2 h + L
/// (its grown box then overlaps only the patches it touches and theirs on a flat cloth), but small, since the patch
/// pairs that are not skipped are searched pair by pair: 2 ((2 h + L) / L)^2, between 8 and
/// self_collision_patch_max (docs/self_collision.md, "Broad phase", for the measurements behind it).
inline std::uint32_t self_collision_patch_target(float h, float edge) {
    if (!(edge > 0.0f)) return self_collision_patch_max;
    const float side = (2.0f * h + edge) / edge;
    return std::uint32_t(std::clamp(2.0f * side * side + 0.5f, 8.0f, float(self_collision_patch_max)));
}

/// Cuts the triangles into connected patches of at most `target` triangles (breadth first over triangles sharing a
/// particle), gives each particle and each edge (2 per edge in `edges`) to one patch, and lists the patches that
/// touch (share a particle). `vertex_tri_offsets` / `vertex_tris`: each particle's triangles, ascending (CSR).
SelfCollisionPatches cook_self_collision_patches(std::span<const std::uint32_t> triangles, std::size_t particles,
                                                 std::span<const std::uint32_t> edges,
                                                 std::span<const std::uint32_t> vertex_tri_offsets,
                                                 std::span<const std::uint32_t> vertex_tris, std::uint32_t target);

} // namespace drape
