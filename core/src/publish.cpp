// Output stage: positions and area-weighted normals into the caller's span (see publish.hpp for the layout
// and the two paths).
#include "drape/publish.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "drape/errors.hpp"
#include "drape/simd.hpp"
#include "for_each_index.hpp"

namespace drape {

namespace {

using simd::fbatch;
using simd::fmask;
constexpr std::size_t W = simd::width;

/// Structural springs per strain chunk on the general path (fixed, so partials combine in a fixed order).
constexpr std::size_t strain_chunk_springs = 8192;

// Grid fan, counter-clockwise seen from +normal around vertex (i, j), with "hang"'s triangulation (cells
// split by the (i+1, j)-(i, j+1) diagonal): neighbours E (i+1, j), NE (i+1, j-1), N (i, j-1), W (i-1, j), SW
// (i-1, j+1), S (i, j+1). Fan triangle t is (vertex, fan[t], fan[t+1 mod 6]).
enum Fan : int { east, north_east, north, west, south_west, south, fan_count };
constexpr std::uint32_t spring_east_bit = 1u << 6;
constexpr std::uint32_t spring_south_bit = 1u << 7;

std::array<std::ptrdiff_t, fan_count> fan_offsets(std::size_t columns) {
    const auto c = static_cast<std::ptrdiff_t>(columns);
    return {1, 1 - c, -c, -1, c - 1, c};
}

/// Bits of the fan triangles and structural springs that exist at grid vertex (i, j).
std::uint32_t grid_vertex_mask(std::size_t i, std::size_t j, std::size_t columns, std::size_t rows) {
    const bool e = i + 1 < columns, w = i >= 1, n = j >= 1, s = j + 1 < rows;
    std::uint32_t m = 0;
    if (e && n) m |= 1u << 0 | 1u << 1; // (E, NE), (NE, N): cell (i, j-1)
    if (n && w) m |= 1u << 2;           // (N, W): second triangle of cell (i-1, j-1)
    if (w && s) m |= 1u << 3 | 1u << 4; // (W, SW), (SW, S): cell (i-1, j)
    if (s && e) m |= 1u << 5;           // (S, E): first triangle of cell (i, j)
    if (e) m |= spring_east_bit;
    if (s) m |= spring_south_bit;
    return m;
}

/// True when `triangles` is exactly the triangulation scene "hang" builds for a columns x rows grid.
bool is_hang_triangulation(const std::vector<std::uint32_t>& triangles, std::size_t columns,
                           std::size_t rows) {
    if (columns < 2 || rows < 2 || triangles.size() != 6 * (columns - 1) * (rows - 1)) return false;
    std::size_t t = 0;
    for (std::size_t j = 0; j + 1 < rows; ++j)
        for (std::size_t i = 0; i + 1 < columns; ++i) {
            const auto a = static_cast<std::uint32_t>(j * columns + i), b = a + 1,
                       c = static_cast<std::uint32_t>(a + columns), d = c + 1;
            const std::uint32_t expect[6] = {a, c, b, b, c, d};
            for (std::uint32_t v : expect)
                if (triangles[t++] != v) return false;
        }
    return true;
}

inline void cross(float ax, float ay, float az, float bx, float by, float bz, float& cx, float& cy,
                  float& cz) noexcept {
    cx = ay * bz - az * by;
    cy = az * bx - ax * bz;
    cz = ax * by - ay * bx;
}

/// Unit normal from an area-weighted sum; a vertex whose triangles all collapsed gets +y.
inline void normalize_or_up(float& nx, float& ny, float& nz) noexcept {
    const float len2 = nx * nx + ny * ny + nz * nz;
    if (len2 > 0.0f) {
        const float inv = 1.0f / std::sqrt(len2);
        nx *= inv;
        ny *= inv;
        nz *= inv;
    } else {
        nx = 0.0f;
        ny = 1.0f;
        nz = 0.0f;
    }
}

/// Stores vertex k (position, unit normal) into the six planes of `out`, each `plane` floats long.
inline void store_vertex(float* out, std::size_t plane, std::size_t k, float px, float py, float pz, float nx, float ny,
                         float nz) noexcept {
    out[0 * plane + k] = px;
    out[1 * plane + k] = py;
    out[2 * plane + k] = pz;
    out[3 * plane + k] = nx;
    out[4 * plane + k] = ny;
    out[5 * plane + k] = nz;
}

inline bool finite3(float a, float b, float c) noexcept {
    return std::isfinite(a) && std::isfinite(b) && std::isfinite(c);
}

inline float spring_strain(float dx, float dy, float dz, float rest) noexcept {
    // Same expression and order as Simulation::health().
    return std::fabs(std::sqrt(dx * dx + dy * dy + dz * dz) - rest) / rest;
}

inline fbatch spring_strain(fbatch dx, fbatch dy, fbatch dz, fbatch rest) noexcept {
    return xsimd::abs(xsimd::sqrt(dx * dx + dy * dy + dz * dz) - rest) / rest;
}

} // namespace

Publisher::Publisher(const Cloth& cloth)
    : particle_count_(cloth.particle_count), plane_floats_(pad_to_width(cloth.particle_count)),
      block_count_((cloth.particle_count + block_particles - 1) / block_particles) {
    const std::size_t n = particle_count_;
    for (std::uint32_t v : cloth.triangles)
        if (v >= n)
            throw InvalidInput("triangle vertex " + std::to_string(v) + " is outside [0, " +
                               std::to_string(n) + ")");
    if (cloth.triangles.size() % 3 != 0)
        throw InvalidInput("triangle list length " + std::to_string(cloth.triangles.size()) +
                           " is not a multiple of 3");

    // Grid path when the cloth is a full grid with hang's triangulation.
    if (cloth.grid && std::size_t{cloth.grid->columns} * cloth.grid->rows == n &&
        is_hang_triangulation(cloth.triangles, cloth.grid->columns, cloth.grid->rows)) {
        grid_columns_ = cloth.grid->columns;
        grid_rows_ = cloth.grid->rows;
        grid_mask_.reset(plane_floats_);
        for (std::size_t j = 0; j < grid_rows_; ++j)
            for (std::size_t i = 0; i < grid_columns_; ++i)
                grid_mask_[j * grid_columns_ + i] = grid_vertex_mask(i, j, grid_columns_, grid_rows_);
        // The fused strain figure covers the structural springs only if they are exactly the grid's east and
        // south neighbours, each direction with one rest length.
        const std::optional<GridStructuralRest> rest = uniform_grid_structural(cloth);
        grid_strain_ = rest.has_value();
        if (rest) {
            rest_east_ = rest->east;
            rest_south_ = rest->south;
        }
    } else {
        // General path: per vertex, the (next, previous) pairs of its triangles, in triangle order.
        fan_offsets_.assign(n + 1, 0);
        for (std::uint32_t v : cloth.triangles)
            ++fan_offsets_[v + 1];
        for (std::size_t i = 0; i < n; ++i)
            fan_offsets_[i + 1] += fan_offsets_[i];
        fan_pairs_.resize(2 * std::size_t{fan_offsets_[n]});
        std::vector<std::uint32_t> fill(fan_offsets_.begin(), fan_offsets_.end() - 1);
        const auto& t = cloth.triangles;
        for (std::size_t k = 0; k + 2 < t.size(); k += 3) {
            const std::uint32_t v[3] = {t[k], t[k + 1], t[k + 2]};
            for (int r = 0; r < 3; ++r) {
                const std::uint32_t slot = fill[v[r]]++;
                fan_pairs_[2 * slot] = v[(r + 1) % 3];
                fan_pairs_[2 * slot + 1] = v[(r + 2) % 3];
            }
        }
    }
    if (!grid_strain_) {
        for (const Edge& e : cloth.edges)
            if (e.kind == SpringKind::structural) structural_.push_back({e.a, e.b, e.rest});
        strain_chunk_count_ = (structural_.size() + strain_chunk_springs - 1) / strain_chunk_springs;
        chunk_strain_.assign(strain_chunk_count_, 0.0f);
    }
    block_strain_.assign(block_count_, 0.0f);
    block_finite_.assign(block_count_, 1);
}

PublishStats Publisher::publish(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                                std::span<float> out) {
    return publish_impl<true>(x, y, z, out);
}

PublishStats Publisher::publish_serial(std::span<const float> x, std::span<const float> y,
                                       std::span<const float> z, std::span<float> out) {
    return publish_impl<false>(x, y, z, out);
}

template <bool Parallel>
PublishStats Publisher::publish_impl(std::span<const float> x, std::span<const float> y,
                                     std::span<const float> z, std::span<float> out) {
    if (x.size() < particle_count_ || y.size() < particle_count_ || z.size() < particle_count_)
        throw InvalidInput("publish: position spans hold fewer than " + std::to_string(particle_count_) +
                           " values");
    if (out.size() < output_floats())
        throw InvalidInput("publish: output span holds " + std::to_string(out.size()) + " floats, needs " +
                           std::to_string(output_floats()));
    const Positions p{x.data(), y.data(), z.data()};
    float* o = out.data();
    auto run_block = [&](std::size_t b) {
        if (grid_path())
            block_grid(b, p, o);
        else
            block_general(b, p, o);
    };
    for_each_index<Parallel>(block_count_, run_block);
    for_each_index<Parallel>(strain_chunk_count_, [&](std::size_t c) { strain_chunk(c, p); });
    // The padding after the last block (only when there are no particles at all).
    for (std::size_t k = block_count_ * block_particles; k < plane_floats_; ++k)
        for (std::size_t plane = 0; plane < vertex_plane_count; ++plane)
            o[plane * plane_floats_ + k] = 0.0f;

    PublishStats stats;
    float strain = 0.0f;
    for (std::size_t b = 0; b < block_count_; ++b) {
        stats.finite = stats.finite && block_finite_[b] != 0;
        strain = std::max(strain, block_strain_[b]);
    }
    for (std::size_t c = 0; c < strain_chunk_count_; ++c)
        strain = std::max(strain, chunk_strain_[c]);
    stats.max_structural_strain = stats.finite ? strain : NAN;
    return stats;
}

// One vertex of the grid path, scalar: the rows at the top and bottom of the cloth (whose fan would read
// outside the arrays) and the padding. Same arithmetic, in the same order, as the SIMD body in block_grid.
void Publisher::grid_vertex_scalar(std::size_t k, Positions p, float* out, float& strain,
                                   bool& finite) const noexcept {
    const std::size_t plane = plane_floats_;
    if (k >= particle_count_) {
        for (std::size_t q = 0; q < vertex_plane_count; ++q)
            out[q * plane + k] = 0.0f;
        return;
    }
    const std::uint32_t mask = grid_mask_[k];
    const float px = p.x[k], py = p.y[k], pz = p.z[k];
    const std::array<std::ptrdiff_t, fan_count> off = fan_offsets(grid_columns_);
    float ex[fan_count], ey[fan_count], ez[fan_count];
    for (int f = 0; f < fan_count; ++f) {
        // Neighbours that do not exist read the vertex itself (a zero edge): always in bounds.
        const auto kk = static_cast<std::ptrdiff_t>(k);
        const std::ptrdiff_t nb = kk + off[f];
        const bool inside = nb >= 0 && nb < static_cast<std::ptrdiff_t>(particle_count_);
        const std::size_t q = inside ? static_cast<std::size_t>(nb) : k;
        ex[f] = p.x[q] - px;
        ey[f] = p.y[q] - py;
        ez[f] = p.z[q] - pz;
    }
    float nx = 0.0f, ny = 0.0f, nz = 0.0f;
    for (int t = 0; t < fan_count; ++t) {
        const int u = (t + 1) % fan_count;
        float cx, cy, cz;
        cross(ex[t], ey[t], ez[t], ex[u], ey[u], ez[u], cx, cy, cz);
        const bool on = (mask >> t) & 1u;
        nx = nx + (on ? cx : 0.0f);
        ny = ny + (on ? cy : 0.0f);
        nz = nz + (on ? cz : 0.0f);
    }
    normalize_or_up(nx, ny, nz);
    if (mask & spring_east_bit)
        strain = std::max(strain, spring_strain(ex[east], ey[east], ez[east], rest_east_));
    if (mask & spring_south_bit)
        strain = std::max(strain, spring_strain(ex[south], ey[south], ez[south], rest_south_));
    finite = finite && finite3(px, py, pz) && finite3(nx, ny, nz);
    store_vertex(out, plane, k, px, py, pz, nx, ny, nz);
}

void Publisher::block_grid(std::size_t block, Positions p, float* out) noexcept {
    const std::size_t begin = block * block_particles;
    const std::size_t end = std::min(begin + block_particles, plane_floats_);
    const std::size_t plane = plane_floats_;
    const std::size_t columns = grid_columns_;
    const std::array<std::ptrdiff_t, fan_count> off = fan_offsets(columns);
    const bool strain_here = grid_strain_;
    float strain = 0.0f;
    bool finite = true;
    fbatch strain_v(0.0f);
    fmask finite_v(true);
    const fbatch zero(0.0f), one(1.0f), rest_e(rest_east_), rest_s(rest_south_);
    for (std::size_t k = begin; k < end; k += W) {
        // SIMD when the whole fan of all W lanes is inside the arrays: k - columns >= 0, k + W - 1 + columns
        // < n.
        if (k < columns || k + W + columns > particle_count_) {
            for (std::size_t l = k; l < k + W; ++l)
                grid_vertex_scalar(l, p, out, strain, finite);
            continue;
        }
        const fbatch px = simd::loadu(p.x + k), py = simd::loadu(p.y + k), pz = simd::loadu(p.z + k);
        const simd::ubatch mask = simd::load(grid_mask_.data() + k);
        fbatch ex[fan_count], ey[fan_count], ez[fan_count];
        for (int f = 0; f < fan_count; ++f) {
            const std::size_t q = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(k) + off[f]);
            ex[f] = simd::loadu(p.x + q) - px;
            ey[f] = simd::loadu(p.y + q) - py;
            ez[f] = simd::loadu(p.z + q) - pz;
        }
        fbatch nx = zero, ny = zero, nz = zero;
        for (int t = 0; t < fan_count; ++t) {
            const int u = (t + 1) % fan_count;
            const fbatch cx = ey[t] * ez[u] - ez[t] * ey[u];
            const fbatch cy = ez[t] * ex[u] - ex[t] * ez[u];
            const fbatch cz = ex[t] * ey[u] - ey[t] * ex[u];
            const fmask on = simd::test_bits(mask, 1u << t);
            nx = nx + simd::select(on, cx, zero);
            ny = ny + simd::select(on, cy, zero);
            nz = nz + simd::select(on, cz, zero);
        }
        const fbatch len2 = nx * nx + ny * ny + nz * nz;
        const fmask has_area = len2 > zero;
        const fbatch inv = one / xsimd::sqrt(simd::select(has_area, len2, one));
        nx = simd::select(has_area, nx * inv, zero);
        ny = simd::select(has_area, ny * inv, one);
        nz = simd::select(has_area, nz * inv, zero);
        if (strain_here) {
            const fbatch se = spring_strain(ex[east], ey[east], ez[east], rest_e);
            const fbatch ss = spring_strain(ex[south], ey[south], ez[south], rest_s);
            strain_v = xsimd::max(strain_v, simd::select(simd::test_bits(mask, spring_east_bit), se, zero));
            strain_v = xsimd::max(strain_v, simd::select(simd::test_bits(mask, spring_south_bit), ss, zero));
        }
        finite_v = finite_v && simd::finite_lanes(px) && simd::finite_lanes(py) && simd::finite_lanes(pz) &&
                   simd::finite_lanes(nx) && simd::finite_lanes(ny) && simd::finite_lanes(nz);
        px.store_unaligned(out + 0 * plane + k);
        py.store_unaligned(out + 1 * plane + k);
        pz.store_unaligned(out + 2 * plane + k);
        nx.store_unaligned(out + 3 * plane + k);
        ny.store_unaligned(out + 4 * plane + k);
        nz.store_unaligned(out + 5 * plane + k);
    }
    alignas(64) float lanes[W];
    strain_v.store_aligned(lanes);
    for (float s : lanes)
        strain = std::max(strain, s);
    block_strain_[block] = strain_here ? strain : 0.0f;
    block_finite_[block] = (finite && xsimd::all(finite_v)) ? 1 : 0;
}

void Publisher::block_general(std::size_t block, Positions p, float* out) noexcept {
    const std::size_t begin = block * block_particles;
    const std::size_t end = std::min(begin + block_particles, plane_floats_);
    const std::size_t real_end = std::min(end, particle_count_);
    const std::size_t plane = plane_floats_;
    bool finite = true;
    for (std::size_t k = begin; k < real_end; ++k) {
        const float px = p.x[k], py = p.y[k], pz = p.z[k];
        float nx = 0.0f, ny = 0.0f, nz = 0.0f;
        for (std::uint32_t e = fan_offsets_[k]; e < fan_offsets_[k + 1]; ++e) {
            const std::uint32_t a = fan_pairs_[2 * std::size_t{e}], b = fan_pairs_[2 * std::size_t{e} + 1];
            float cx, cy, cz;
            cross(p.x[a] - px, p.y[a] - py, p.z[a] - pz, p.x[b] - px, p.y[b] - py, p.z[b] - pz, cx, cy, cz);
            nx = nx + cx;
            ny = ny + cy;
            nz = nz + cz;
        }
        normalize_or_up(nx, ny, nz);
        finite = finite && finite3(px, py, pz) && finite3(nx, ny, nz);
        store_vertex(out, plane, k, px, py, pz, nx, ny, nz);
    }
    for (std::size_t k = real_end; k < end; ++k)
        for (std::size_t q = 0; q < vertex_plane_count; ++q)
            out[q * plane + k] = 0.0f;
    block_strain_[block] = 0.0f;
    block_finite_[block] = finite ? 1 : 0;
}

void Publisher::strain_chunk(std::size_t chunk, Positions p) noexcept {
    const std::size_t begin = chunk * strain_chunk_springs;
    const std::size_t end = std::min(begin + strain_chunk_springs, structural_.size());
    float strain = 0.0f;
    for (std::size_t s = begin; s < end; ++s) {
        const StructuralSpring& e = structural_[s];
        const float v = spring_strain(p.x[e.b] - p.x[e.a], p.y[e.b] - p.y[e.a], p.z[e.b] - p.z[e.a], e.rest);
        if (!(v <= strain)) strain = v;
    }
    chunk_strain_[chunk] = strain;
}

} // namespace drape
