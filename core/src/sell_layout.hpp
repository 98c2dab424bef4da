// SELL-C slice layout shared by the spring graph and the bending rows: slices of simd::width consecutive particles,
// each as many slots as its longest CSR row (spring_graph.hpp describes the format).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "drape/simd.hpp"

namespace drape {

/// Fills slice_begin (slices + 1 entries, in SELL entries) and slice_slots (per slice) from CSR `offsets` over the
/// `n` real particles of `padded_count`; returns the total number of SELL entries.
inline std::size_t sell_slices(const std::vector<std::uint32_t>& offsets, std::size_t n, std::size_t padded_count,
                               std::vector<std::uint32_t>& slice_begin, std::vector<std::uint32_t>& slice_slots) {
    constexpr std::size_t C = simd::width;
    const std::size_t slices = padded_count / C;
    slice_begin.assign(slices + 1, 0);
    slice_slots.assign(slices, 0);
    for (std::size_t s = 0; s < slices; ++s) {
        std::uint32_t longest = 0;
        for (std::size_t lane = 0; lane < C; ++lane) {
            const std::size_t i = s * C + lane;
            if (i < n) longest = std::max(longest, offsets[i + 1] - offsets[i]);
        }
        slice_slots[s] = longest;
        slice_begin[s + 1] = slice_begin[s] + static_cast<std::uint32_t>(longest * C);
    }
    return slice_begin[slices];
}

} // namespace drape
