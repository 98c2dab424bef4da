// Output stage, optional part: per-vertex strain for the viewer's strain colouring.
//
//     s_i = max over the structural springs (i, j) of |l_ij - l0_ij| / l0_ij      (dimensionless; 0.05 = 5 %)
//
// the same per-spring figure as Simulation::health() and PublishStats::max_structural_strain, but kept per
// vertex (max, not mean: one overstretched spring is what a user looks for). Written into one float plane
// of plane_floats() values (padding zero), e.g. the seventh plane of the viewer's mapped vertex region
// after publish.hpp's six, so the renderer maps it to a colour in the shader. Runs once per drawn frame,
// only while strain colouring is on.
//
// Two paths, chosen when cooked (like publish.hpp):
//   grid    - a full regular grid whose structural springs are exactly its east/south neighbours with one
//             rest length per direction (scene "hang"): neighbours at fixed offsets +1, -1, +N, -N, 16
//             vertices per SIMD batch with unaligned loads and a per-vertex mask of the springs that exist;
//             the first and last grid row (whose neighbours would fall outside the arrays) run the scalar
//             twin of the same arithmetic;
//   general - any cloth: a per-vertex CSR of its structural springs (neighbour, rest length), filtered from
//             Cloth::graph once, scalar.
// Every vertex gathers its own springs (no scatter), the maximum is exact whatever the order, and blocks
// are fixed (block_particles), so the output is bitwise the same at any thread count. Cooked once;
// compute() allocates nothing.
//
// On the way compute() also counts the vertices in a histogram of strain_bins bins, four per octave from
// 2^-14 (0.006 %) up (the float's exponent and two leading mantissa bits: no log; bins 14 % to 25 %
// wide), per block, summed in
// block order. quantile() reads it: the viewer's automatic colour scale follows the 99th percentile, so one
// overstretched spring at a grabbed particle does not turn the rest of the cloth blue.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/aligned_array.hpp"
#include "drape/cloth.hpp"

namespace drape {

class StrainField {
  public:
    /// Cooks the grid masks or the structural CSR from `cloth` (structural springs only; seams, shear and
    /// bend springs are left out).
    explicit StrainField(const Cloth& cloth);

    std::size_t particle_count() const noexcept { return particle_count_; }
    /// Floats compute() writes (the cloth's padded particle count, as Publisher::plane_floats()).
    std::size_t plane_floats() const noexcept { return plane_floats_; }
    /// True when the SIMD regular-grid path runs.
    bool grid_path() const noexcept { return columns_ != 0; }

    /// Writes s_i for every vertex into out[0, particle_count()) and zero into the padding up to
    /// plane_floats(); returns max_i s_i (0 for a cloth without structural springs). Parallel with oneTBB
    /// over fixed blocks; bitwise the same for any thread count. Throws InvalidInput when a span is short.
    float compute(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                  std::span<float> out);
    /// The serial twin of compute().
    float compute_serial(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                         std::span<float> out);

    static constexpr std::size_t strain_bins = 80;
    /// Bin of a strain value (0 for anything below 2^-14, the last bin for anything above ~2^5.75 and NaN).
    static std::size_t bin_of(float strain) noexcept;
    /// Upper edge of a bin (strain, dimensionless).
    static float bin_upper(std::size_t bin) noexcept;
    /// Vertices per bin over the whole cloth, from the last compute().
    std::span<const std::uint32_t> histogram() const noexcept { return histogram_; }
    /// The upper edge of the bin holding the q-quantile (0 < q <= 1) of the last compute()'s strains: at
    /// least a fraction q of the vertices has a strain at most this (within one bin, 14 % to 25 % wide).
    float quantile(double q) const noexcept;

  private:
    struct Positions {
        const float* x;
        const float* y;
        const float* z;
    };
    template <bool Parallel>
    float compute_impl(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                       std::span<float> out);
    void block_grid(std::size_t block, Positions p, float* out) noexcept;
    void block_general(std::size_t block, Positions p, float* out) noexcept;
    float grid_vertex_scalar(std::size_t k, Positions p) const noexcept;

    std::size_t particle_count_ = 0;
    std::size_t plane_floats_ = 0;
    std::size_t block_count_ = 0;

    // Grid path (columns_ != 0).
    std::size_t columns_ = 0;
    float rest_east_ = 0.0f;  ///< m, structural spring to the next column (and from the previous one)
    float rest_south_ = 0.0f; ///< m, structural spring to the next row (and from the previous one)
    /// Per vertex: bit 0 east, 1 west, 2 south, 3 north spring exists.
    AlignedArray<std::uint32_t> grid_mask_;

    // General path: structural springs per vertex (both directions).
    std::vector<std::uint32_t> offsets_; ///< particle_count + 1
    std::vector<std::uint32_t> neighbour_;
    std::vector<float> rest_; ///< m

    std::vector<float> block_max_; ///< per-block partials, combined in block order (sized once)
    std::vector<std::uint32_t> block_histogram_; ///< block_count x strain_bins (sized once)
    std::vector<std::uint32_t> histogram_;       ///< strain_bins
};

} // namespace drape
