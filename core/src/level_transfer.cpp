// Transfers between a cloth and its coarser copies (level_transfer.hpp).
#include "drape/level_transfer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "closest_points.hpp"

namespace drape {

std::vector<std::uint32_t> LevelTransfer::nearest() const {
    std::vector<std::uint32_t> out(index.size());
    for (std::size_t k = 0; k < index.size(); ++k) {
        std::size_t best = 0;
        for (std::size_t c = 1; c < width; ++c)
            if (weight[k][c] >= weight[k][best]) best = c;
        out[k] = index[k][best];
    }
    return out;
}

void LevelTransfer::symmetrise(const std::vector<std::uint32_t>& target_twins,
                               const std::vector<std::uint32_t>& source_twins) {
    if (target_twins.size() != size() || source_twins.empty()) return;
    const std::vector<std::array<std::uint32_t, width>> own = index;
    const std::vector<std::array<float, width>> own_weight = weight;
    constexpr std::uint32_t none = 0xFFFFFFFFu; // vbd::mirror_twins: a node without a twin (up to 5 % of them)
    const auto twinned = [&](const std::array<std::uint32_t, width>& i) {
        for (std::size_t c = 0; c < 3; ++c)
            if (i[c] >= source_twins.size() || source_twins[i[c]] == none) return false;
        return true;
    };
    for (std::size_t k = 0; k < size(); ++k) {
        const std::uint32_t twin = target_twins[k];
        // A node or source node without a twin keeps its own map.
        if (twin >= size() || !twinned(own[twin])) continue;
        std::array<std::uint32_t, width> i{};
        std::array<float, width> w{};
        for (std::size_t c = 0; c < 3; ++c) {
            i[c] = own[k][c];
            w[c] = 0.5f * own_weight[k][c];
            i[3 + c] = source_twins[own[twin][c]];
            w[3 + c] = 0.5f * own_weight[twin][c];
        }
        index[k] = i;
        weight[k] = w;
    }
}

LevelTransfer bilinear_transfer(std::uint32_t from_n, std::uint32_t to_n) {
    LevelTransfer t;
    const std::size_t count = std::size_t(to_n) * to_n;
    t.index.resize(count);
    t.weight.resize(count);
    const auto map = [&](std::uint32_t i) { return float(i) * float(from_n - 1) / float(to_n - 1); };
    for (std::uint32_t j = 0; j < to_n; ++j) {
        const float fj = map(j);
        const std::uint32_t j0 = std::min(static_cast<std::uint32_t>(fj), from_n - 2);
        const float v = fj - float(j0);
        for (std::uint32_t i = 0; i < to_n; ++i) {
            const float fi = map(i);
            const std::uint32_t i0 = std::min(static_cast<std::uint32_t>(fi), from_n - 2);
            const float u = fi - float(i0);
            const std::uint32_t k = j0 * from_n + i0;
            const std::size_t target = std::size_t(j) * to_n + i;
            t.index[target] = {k, k + 1, k + from_n, k + from_n + 1, 0, 0};
            t.weight[target] = {(1.0f - u) * (1.0f - v), u * (1.0f - v), (1.0f - u) * v, u * v, 0.0f, 0.0f};
        }
    }
    return t;
}

LevelTransfer surface_transfer(std::span<const float> sx, std::span<const float> sy, std::span<const float> sz,
                               std::span<const std::uint32_t> triangles, std::span<const float> tx,
                               std::span<const float> ty, std::span<const float> tz) {
    using geom::V3;
    const std::size_t tri_count = triangles.size() / 3;
    LevelTransfer t;
    t.index.assign(tx.size(), {});
    t.weight.assign(tx.size(), {});
    if (tri_count == 0) return t;
    const auto at = [&](std::uint32_t i) { return V3{sx[i], sy[i], sz[i]}; };
    // The bucket grid: cells of the mean triangle's longest edge, each triangle in every cell its box touches.
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300}, edge_sum = 0.0;
    for (std::size_t f = 0; f < tri_count; ++f) {
        double longest = 0.0;
        for (int c = 0; c < 3; ++c) {
            const V3 p = at(triangles[3 * f + c]), q = at(triangles[3 * f + (c + 1) % 3]);
            longest = std::max(longest, geom::norm(q - p));
            const double v[3] = {p.x, p.y, p.z};
            for (int d = 0; d < 3; ++d) lo[d] = std::min(lo[d], v[d]), hi[d] = std::max(hi[d], v[d]);
        }
        edge_sum += longest;
    }
    double cell = std::max(edge_sum / double(tri_count), 1e-9);
    std::int64_t dims[3];
    for (;;) { // at most a few cells per triangle (a layout far from flat gets larger cells)
        for (int d = 0; d < 3; ++d) dims[d] = std::clamp<std::int64_t>(std::int64_t((hi[d] - lo[d]) / cell) + 1, 1, 4096);
        if (double(dims[0]) * double(dims[1]) * double(dims[2]) <= 8.0 * double(tri_count) + 64.0) break;
        cell *= 1.5;
    }
    const auto cell_of = [&](double v, int d) {
        return std::clamp<std::int64_t>(std::int64_t(std::floor((v - lo[d]) / cell)), 0, dims[d] - 1);
    };
    const auto key = [&](std::int64_t i, std::int64_t j, std::int64_t k) {
        return std::size_t((k * dims[1] + j) * dims[0] + i);
    };
    std::vector<std::uint32_t> start(std::size_t(dims[0] * dims[1] * dims[2]) + 1, 0), items;
    for (int pass = 0; pass < 2; ++pass) { // counts, then the items (counting sort: triangle order within a cell)
        std::vector<std::uint32_t> fill(pass ? start : std::vector<std::uint32_t>{});
        if (pass) items.resize(start.back());
        for (std::size_t f = 0; f < tri_count; ++f) {
            std::int64_t b0[3], b1[3];
            for (int d = 0; d < 3; ++d) {
                double mn = 1e300, mx = -1e300;
                for (int c = 0; c < 3; ++c) {
                    const V3 p = at(triangles[3 * f + c]);
                    const double v = d == 0 ? p.x : d == 1 ? p.y : p.z;
                    mn = std::min(mn, v), mx = std::max(mx, v);
                }
                b0[d] = cell_of(mn, d), b1[d] = cell_of(mx, d);
            }
            for (std::int64_t k = b0[2]; k <= b1[2]; ++k)
                for (std::int64_t j = b0[1]; j <= b1[1]; ++j)
                    for (std::int64_t i = b0[0]; i <= b1[0]; ++i) {
                        if (pass) items[fill[key(i, j, k)]++] = static_cast<std::uint32_t>(f);
                        else ++start[key(i, j, k) + 1];
                    }
        }
        if (!pass)
            for (std::size_t c = 1; c < start.size(); ++c) start[c] += start[c - 1];
    }
    // Per target point: rings of cells round its cell until the best distance is inside the searched cube.
    const std::int64_t max_ring = std::max({dims[0], dims[1], dims[2]});
    for (std::size_t p = 0; p < tx.size(); ++p) {
        const V3 q{tx[p], ty[p], tz[p]};
        const std::int64_t c0[3] = {cell_of(q.x, 0), cell_of(q.y, 1), cell_of(q.z, 2)};
        double best = std::numeric_limits<double>::infinity();
        std::size_t best_f = 0;
        std::array<double, 3> best_w{1.0, 0.0, 0.0};
        for (std::int64_t r = 0; r <= max_ring; ++r) {
            for (std::int64_t k = c0[2] - r; k <= c0[2] + r; ++k)
                for (std::int64_t j = c0[1] - r; j <= c0[1] + r; ++j)
                    for (std::int64_t i = c0[0] - r; i <= c0[0] + r; ++i) {
                        if (std::max({std::abs(i - c0[0]), std::abs(j - c0[1]), std::abs(k - c0[2])}) != r) continue;
                        if (i < 0 || j < 0 || k < 0 || i >= dims[0] || j >= dims[1] || k >= dims[2]) continue;
                        const std::size_t c = key(i, j, k);
                        for (std::uint32_t e = start[c]; e < start[c + 1]; ++e) {
                            const std::size_t f = items[e];
                            const V3 a = at(triangles[3 * f]), b = at(triangles[3 * f + 1]), d = at(triangles[3 * f + 2]);
                            const std::array<double, 3> w = geom::closest_on_triangle(q, a, b, d);
                            const double dist = geom::norm(q - (w[0] * a + w[1] * b + w[2] * d));
                            if (dist < best || (dist == best && f < best_f)) best = dist, best_f = f, best_w = w;
                        }
                    }
            // Every point outside the searched cube is at least r * cell from q (q lies in the centre cell).
            if (best <= double(r) * cell) break;
        }
        for (int c = 0; c < 3; ++c) {
            t.index[p][c] = triangles[3 * best_f + c];
            t.weight[p][c] = static_cast<float>(best_w[c]);
        }
    }
    return t;
}

} // namespace drape
