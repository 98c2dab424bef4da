// Per-vertex structural strain for the viewer's colouring (see strain_field.hpp for the two paths).
#include "drape/strain_field.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "drape/errors.hpp"
#include "drape/simd.hpp"
#include "for_each_index.hpp"

namespace drape {

namespace {

using simd::fbatch;
using simd::fmask;
constexpr std::size_t W = simd::width;

constexpr std::uint32_t east_bit = 1u << 0, west_bit = 1u << 1, south_bit = 1u << 2, north_bit = 1u << 3;

inline float spring_strain(float dx, float dy, float dz, float rest) noexcept {
    // Same expression and order as Simulation::health() and the output stage.
    return std::fabs(std::sqrt(dx * dx + dy * dy + dz * dz) - rest) / rest;
}

inline fbatch spring_strain(fbatch dx, fbatch dy, fbatch dz, fbatch rest) noexcept {
    return xsimd::abs(xsimd::sqrt(dx * dx + dy * dy + dz * dz) - rest) / rest;
}

constexpr std::uint32_t histogram_shift = 21;                     // keep sign, exponent, 2 mantissa bits
constexpr std::uint32_t histogram_base = (127u - 14u) << 2;        // 2^-14 >> 21

/// Bins of W strains at once: the arithmetic of bin_of on integer lanes.
inline simd::ubatch bins_of(fbatch strain) noexcept {
    const simd::ubatch bits = xsimd::bitwise_cast<simd::ubatch>(strain) & simd::ubatch(0x7fffffffu);
    const simd::ubatch key = xsimd::max(bits >> histogram_shift, simd::ubatch(histogram_base));
    return xsimd::min(key - simd::ubatch(histogram_base),
                      simd::ubatch(static_cast<std::uint32_t>(StrainField::strain_bins - 1)));
}

/// Four interleaved counters per bin: consecutive vertices usually share a bin, and one counter would make
/// every increment wait for the previous one.
struct LocalHistogram {
    std::uint32_t count[4][StrainField::strain_bins];
    LocalHistogram() noexcept { std::memset(count, 0, sizeof count); }
    void add(std::size_t lane, std::size_t bin) noexcept { ++count[lane & 3][bin]; }
    void store(std::uint32_t* out) const noexcept {
        for (std::size_t b = 0; b < StrainField::strain_bins; ++b)
            out[b] = count[0][b] + count[1][b] + count[2][b] + count[3][b];
    }
};

/// std::max's choice (the first argument unless the second is larger), spelled out so both paths agree.
inline float larger(float a, float b) noexcept { return a < b ? b : a; }

} // namespace

StrainField::StrainField(const Cloth& cloth)
    : particle_count_(cloth.particle_count), plane_floats_(pad_to_width(cloth.particle_count)),
      block_count_((pad_to_width(cloth.particle_count) + block_particles - 1) / block_particles) {
    const std::size_t n = particle_count_;
    // Grid path when every structural spring is an east or south grid neighbour, each direction with one
    // rest length, and every such neighbour pair has its spring.
    if (const std::optional<GridStructuralRest> rest = uniform_grid_structural(cloth)) {
        const std::size_t columns = cloth.grid->columns, rows = cloth.grid->rows;
        rest_east_ = rest->east;
        rest_south_ = rest->south;
        columns_ = columns;
        grid_mask_.reset(plane_floats_);
        for (std::size_t k = 0; k < plane_floats_; ++k) {
            std::uint32_t m = 0;
            if (k < n) {
                const std::size_t i = k % columns, j = k / columns;
                if (i + 1 < columns) m |= east_bit;
                if (i >= 1) m |= west_bit;
                if (j + 1 < rows) m |= south_bit;
                if (j >= 1) m |= north_bit;
            }
            grid_mask_[k] = m;
        }
    }
    if (!grid_path()) {
        // General path: the cloth's CSR rows (both directions, sorted by neighbour), structural entries only.
        const SpringGraph& g = cloth.graph;
        offsets_.assign(n + 1, 0);
        if (g.offsets.size() == n + 1) {
            for (std::size_t i = 0; i < n; ++i) {
                for (std::uint32_t e = g.offsets[i]; e < g.offsets[i + 1]; ++e) {
                    const Edge& edge = cloth.edges[g.edge_index[e]];
                    if (edge.kind != SpringKind::structural) continue;
                    neighbour_.push_back(g.neighbour[e]);
                    rest_.push_back(edge.rest);
                }
                offsets_[i + 1] = static_cast<std::uint32_t>(neighbour_.size());
            }
        }
    }
    block_max_.assign(block_count_, 0.0f);
    block_histogram_.assign(block_count_ * strain_bins, 0);
    histogram_.assign(strain_bins, 0);
}

std::size_t StrainField::bin_of(float strain) noexcept {
    std::uint32_t bits;
    std::memcpy(&bits, &strain, sizeof bits);
    const std::uint32_t key = (bits & 0x7fffffffu) >> histogram_shift; // |strain|; NaN and inf: top bin
    return key <= histogram_base ? 0 : std::min<std::size_t>(key - histogram_base, strain_bins - 1);
}

float StrainField::bin_upper(std::size_t bin) noexcept {
    const std::uint32_t bits = static_cast<std::uint32_t>(histogram_base + bin + 1) << histogram_shift;
    float v;
    std::memcpy(&v, &bits, sizeof v);
    return v;
}

float StrainField::quantile(double q) const noexcept {
    std::uint64_t total = 0;
    for (std::uint32_t c : histogram_)
        total += c;
    if (total == 0) return 0.0f;
    const double want = std::clamp(q, 0.0, 1.0) * double(total);
    std::uint64_t seen = 0;
    for (std::size_t b = 0; b < strain_bins; ++b) {
        seen += histogram_[b];
        if (double(seen) >= want && seen > 0) return bin_upper(b);
    }
    return bin_upper(strain_bins - 1);
}

float StrainField::compute(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                           std::span<float> out) {
    return compute_impl<true>(x, y, z, out);
}

float StrainField::compute_serial(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                                  std::span<float> out) {
    return compute_impl<false>(x, y, z, out);
}

template <bool Parallel>
float StrainField::compute_impl(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                                std::span<float> out) {
    if (x.size() < particle_count_ || y.size() < particle_count_ || z.size() < particle_count_)
        throw InvalidInput("strain field: position spans hold fewer than " + std::to_string(particle_count_) +
                           " values");
    if (out.size() < plane_floats_)
        throw InvalidInput("strain field: output span holds " + std::to_string(out.size()) + " floats, needs " +
                           std::to_string(plane_floats_));
    const Positions p{x.data(), y.data(), z.data()};
    float* o = out.data();
    auto run_block = [&](std::size_t b) {
        if (grid_path())
            block_grid(b, p, o);
        else
            block_general(b, p, o);
    };
    for_each_index<Parallel>(block_count_, run_block);
    float result = 0.0f;
    std::fill(histogram_.begin(), histogram_.end(), 0u);
    for (std::size_t b = 0; b < block_count_; ++b) {
        result = larger(result, block_max_[b]);
        const std::uint32_t* h = block_histogram_.data() + b * strain_bins;
        for (std::size_t i = 0; i < strain_bins; ++i)
            histogram_[i] += h[i];
    }
    return result;
}

// One vertex of the grid path, scalar (first and last rows, padding): the arithmetic of the SIMD body.
float StrainField::grid_vertex_scalar(std::size_t k, Positions p) const noexcept {
    if (k >= particle_count_) return 0.0f;
    const std::uint32_t mask = grid_mask_[k];
    const float px = p.x[k], py = p.y[k], pz = p.z[k];
    float s = 0.0f;
    auto side = [&](std::uint32_t bit, std::size_t q, float rest) {
        if (mask & bit) s = larger(s, spring_strain(p.x[q] - px, p.y[q] - py, p.z[q] - pz, rest));
    };
    side(east_bit, k + 1, rest_east_);
    side(west_bit, k - 1, rest_east_);
    side(south_bit, k + columns_, rest_south_);
    side(north_bit, k - columns_, rest_south_);
    return s;
}

void StrainField::block_grid(std::size_t block, Positions p, float* out) noexcept {
    const std::size_t begin = block * block_particles;
    const std::size_t end = std::min(begin + block_particles, plane_floats_);
    const std::size_t columns = columns_;
    float block_max = 0.0f;
    fbatch max_v(0.0f);
    const fbatch zero(0.0f), rest_e(rest_east_), rest_s(rest_south_);
    LocalHistogram histogram;
    alignas(64) float lanes[W];
    alignas(64) std::uint32_t lane_bins[W];
    for (std::size_t k = begin; k < end; k += W) {
        // SIMD when every lane's four neighbours are inside the arrays.
        if (k < columns || k + W + columns > particle_count_) {
            for (std::size_t l = k; l < k + W; ++l) {
                const float s = grid_vertex_scalar(l, p);
                out[l] = s;
                block_max = larger(block_max, s);
                if (l < particle_count_) histogram.add(l, bin_of(s));
            }
            continue;
        }
        const fbatch px = simd::loadu(p.x + k), py = simd::loadu(p.y + k), pz = simd::loadu(p.z + k);
        const simd::ubatch mask = simd::load(grid_mask_.data() + k);
        fbatch s = zero;
        auto side = [&](std::uint32_t bit, std::size_t q, fbatch rest) {
            const fbatch v = spring_strain(simd::loadu(p.x + q) - px, simd::loadu(p.y + q) - py,
                                           simd::loadu(p.z + q) - pz, rest);
            // Lane-wise larger(s, v) where the spring exists: select(s < v, v, s).
            s = simd::select(simd::test_bits(mask, bit) && (s < v), v, s);
        };
        side(east_bit, k + 1, rest_e);
        side(west_bit, k - 1, rest_e);
        side(south_bit, k + columns, rest_s);
        side(north_bit, k - columns, rest_s);
        s.store_unaligned(out + k);
        max_v = simd::select(max_v < s, s, max_v);
        bins_of(s).store_aligned(lane_bins); // every lane is a real vertex here (k + W <= count - columns)
        for (std::size_t l = 0; l < W; ++l)
            histogram.add(l, lane_bins[l]);
    }
    histogram.store(block_histogram_.data() + block * strain_bins);
    max_v.store_aligned(lanes);
    for (float v : lanes)
        block_max = larger(block_max, v);
    block_max_[block] = block_max;
}

void StrainField::block_general(std::size_t block, Positions p, float* out) noexcept {
    const std::size_t begin = block * block_particles;
    const std::size_t end = std::min(begin + block_particles, plane_floats_);
    const std::size_t real_end = std::min(end, particle_count_);
    float block_max = 0.0f;
    LocalHistogram histogram;
    for (std::size_t k = begin; k < real_end; ++k) {
        const float px = p.x[k], py = p.y[k], pz = p.z[k];
        float s = 0.0f;
        for (std::uint32_t e = offsets_[k]; e < offsets_[k + 1]; ++e) {
            const std::uint32_t q = neighbour_[e];
            s = larger(s, spring_strain(p.x[q] - px, p.y[q] - py, p.z[q] - pz, rest_[e]));
        }
        out[k] = s;
        block_max = larger(block_max, s);
        histogram.add(k, bin_of(s));
    }
    histogram.store(block_histogram_.data() + block * strain_bins);
    for (std::size_t k = real_end; k < end; ++k)
        out[k] = 0.0f;
    block_max_[block] = block_max;
}

} // namespace drape
