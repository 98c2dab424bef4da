// Springs as a graph over particles.
//
// Layout (DESIGN.md "Data"): CSR over particles - offsets[n+1] and, per entry, the neighbour, the rest length and
// the kind. Both directions of every spring are stored, rows sorted by neighbour index. Each particle sums its own
// row in that fixed order: no atomics, no scatter, the same result on any thread count.
//
// For SIMD the rows are regrouped SELL-C style (C = SIMD width): particles [s*C, s*C+C) form slice s, whose
// entries are stored slot-major (entry `slot` of all C rows side by side), padded to the longest row of the slice
// with inert entries (neighbour = the particle itself, stiffness 0, damping 0). One slot of a slice is one SIMD
// batch: a contiguous load of neighbour indices and spring constants, gathers of the neighbour state.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/aligned_array.hpp"

namespace drape {

enum class SpringKind : std::uint8_t { structural = 0, shear = 1, bend = 2, seam = 3 };
inline constexpr std::size_t spring_kind_count = 4;
const char* spring_kind_name(SpringKind kind) noexcept;

/// One spring, stored once (a < b).
struct Edge {
    std::uint32_t a = 0, b = 0;
    SpringKind kind = SpringKind::structural;
    float rest = 0.0f; ///< rest length, m
    /// The spring's stiffness and damping are its kind's material times this (1 in the springs model; the fabric model
    /// sets each spring's share of the membrane it represents, e.g. 1/2 on a boundary edge, docs/fabric.md).
    float scale = 1.0f;
};

struct SpringGraph {
    // Plain CSR (both directions, rows sorted by neighbour).
    std::vector<std::uint32_t> offsets;   ///< particle_count + 1
    std::vector<std::uint32_t> neighbour; ///< per entry
    std::vector<std::uint32_t> edge_index; ///< per entry: index into Cloth::edges

    // SIMD-sliced CSR (SELL-C). slice_begin[s] is the first entry of slice s; it has slice_slots[s] slots of
    // simd::width entries each.
    std::vector<std::uint32_t> slice_begin;  ///< slice_count + 1
    std::vector<std::uint32_t> slice_slots;  ///< slice_count
    AlignedArray<std::uint32_t> sell_neighbour;
    AlignedArray<float> sell_rest;      ///< m
    AlignedArray<float> sell_stiffness; ///< N/m: material stiffness x Edge::scale (0 for padding)
    AlignedArray<float> sell_damping;   ///< N*s/m (0 for padding)
    std::vector<std::uint32_t> sell_edge; ///< per SELL entry: edge index, or UINT32_MAX for padding

    std::size_t entry_count() const noexcept { return neighbour.size(); }
    std::size_t sell_entry_count() const noexcept { return sell_neighbour.size(); }
};

/// Builds CSR and SELL from edges over `particle_count` particles (padded to `padded_count`). Seam springs are left
/// out (Cloth::seams handles them). CSR rows are sorted by neighbour; SELL rows follow them, or with a `mirror` map
/// (mirror_symmetry.hpp) mirror_row_order's order, so a particle and its twin sum their springs alike.
SpringGraph build_spring_graph(std::size_t particle_count, std::size_t padded_count, std::span<const Edge> edges,
                               std::span<const std::uint32_t> mirror = {});

} // namespace drape
