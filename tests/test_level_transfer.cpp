// The maps between a cloth and its coarser copies (level_transfer.hpp): bilinear on grids, closest point on the other
// copy's triangles on meshes, each against a plain reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "../core/src/closest_points.hpp"
#include "drape/level_transfer.hpp"

namespace drape {
namespace {

// Weights sum to 1, a linear field of grid coordinates is reproduced, corners map onto corners, and the nearest
// source node is the rounded grid coordinate (as the coarse levels' pins were found before).
TEST(LevelTransfer, BilinearReproducesLinearFields) {
    for (auto [from, to] : {std::pair{9u, 5u}, {10u, 5u}, {5u, 9u}, {316u, 158u}, {2u, 7u}}) {
        const LevelTransfer t = bilinear_transfer(from, to);
        ASSERT_EQ(t.size(), std::size_t(to) * to);
        std::vector<float> field(std::size_t(from) * from);
        for (std::uint32_t j = 0; j < from; ++j)
            for (std::uint32_t i = 0; i < from; ++i) field[j * from + i] = 2.0f * float(i) - 3.0f * float(j);
        const std::vector<std::uint32_t> nearest = t.nearest();
        for (std::uint32_t j = 0; j < to; ++j)
            for (std::uint32_t i = 0; i < to; ++i) {
                const std::size_t k = std::size_t(j) * to + i;
                float sum = 0.0f, value = 0.0f;
                for (std::size_t c = 0; c < LevelTransfer::width; ++c) {
                    ASSERT_LT(t.index[k][c], field.size());
                    sum += t.weight[k][c];
                    value += t.weight[k][c] * field[t.index[k][c]];
                }
                const double fi = double(i) * (from - 1) / (to - 1), fj = double(j) * (from - 1) / (to - 1);
                EXPECT_NEAR(sum, 1.0f, 1e-6f);
                EXPECT_NEAR(value, 2.0 * fi - 3.0 * fj, 1e-3 * from) << from << " -> " << to << " at " << i << ", " << j;
                EXPECT_EQ(nearest[k], std::uint32_t(std::lround(fj)) * from + std::uint32_t(std::lround(fi)));
            }
    }
}

// Each target point maps to the closest point of the source triangles: the same distance as a search over every
// triangle, weights summing to 1; on a flat mesh a linear field is reproduced inside it.
TEST(LevelTransfer, SurfaceTransferFindsTheClosestPoint) {
    // A 12 x 9 grid of points jittered in its plane, triangulated, with a gentle fold in z.
    const int nu = 12, nv = 9;
    std::vector<float> sx, sy, sz;
    std::uint32_t seed = 12345;
    auto jitter = [&]() {
        seed = seed * 1664525u + 1013904223u;
        return (float(seed >> 8) / float(1u << 24) - 0.5f) * 0.3f;
    };
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const bool edge = i == 0 || j == 0 || i == nu - 1 || j == nv - 1;
            const float u = 0.1f * (float(i) + (edge ? 0.0f : jitter())), v = 0.1f * (float(j) + (edge ? 0.0f : jitter()));
            sx.push_back(u);
            sy.push_back(v);
            sz.push_back(0.05f * std::sin(3.0f * u));
        }
    std::vector<std::uint32_t> tri;
    for (int j = 0; j + 1 < nv; ++j)
        for (int i = 0; i + 1 < nu; ++i) {
            const std::uint32_t a = j * nu + i, b = a + 1, c = a + nu, d = c + 1;
            tri.insert(tri.end(), {a, b, c, b, d, c});
        }
    // Targets: inside, beside and far off the mesh.
    std::vector<float> tx, ty, tz;
    for (int k = 0; k < 400; ++k) {
        tx.push_back(-0.3f + 1.7f * (0.5f + jitter() / 0.3f));
        ty.push_back(-0.3f + 1.4f * (0.5f + jitter() / 0.3f));
        tz.push_back(0.2f * jitter());
    }
    tx.push_back(50.0f), ty.push_back(-20.0f), tz.push_back(3.0f);
    const LevelTransfer t = surface_transfer(sx, sy, sz, tri, tx, ty, tz);
    ASSERT_EQ(t.size(), tx.size());
    using geom::V3;
    auto at = [&](std::uint32_t i) { return V3{sx[i], sy[i], sz[i]}; };
    for (std::size_t p = 0; p < tx.size(); ++p) {
        const V3 q{tx[p], ty[p], tz[p]};
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t f = 0; f < tri.size() / 3; ++f) {
            const V3 a = at(tri[3 * f]), b = at(tri[3 * f + 1]), c = at(tri[3 * f + 2]);
            const auto w = geom::closest_on_triangle(q, a, b, c);
            best = std::min(best, geom::norm(q - (w[0] * a + w[1] * b + w[2] * c)));
        }
        V3 mapped{0.0, 0.0, 0.0};
        double sum = 0.0;
        for (std::size_t c = 0; c < LevelTransfer::width; ++c) {
            mapped = mapped + double(t.weight[p][c]) * at(t.index[p][c]);
            sum += t.weight[p][c];
        }
        EXPECT_NEAR(sum, 1.0, 1e-6);
        EXPECT_NEAR(geom::norm(q - mapped), best, 1e-5 * (1.0 + best)) << "target " << p;
    }
    // Flat: a linear field of (x, y) at points inside is reproduced.
    std::vector<float> flat(sz.size(), 0.0f), field(sx.size());
    for (std::size_t i = 0; i < sx.size(); ++i) field[i] = 4.0f * sx[i] - 7.0f * sy[i] + 1.0f;
    std::vector<float> ix, iy, iz;
    for (int k = 0; k < 100; ++k) {
        ix.push_back(0.55f + 3.6f * jitter());
        iy.push_back(0.4f + 2.6f * jitter());
        iz.push_back(0.0f);
    }
    const LevelTransfer inside = surface_transfer(sx, sy, flat, tri, ix, iy, iz);
    for (std::size_t p = 0; p < ix.size(); ++p) {
        double value = 0.0;
        for (std::size_t c = 0; c < LevelTransfer::width; ++c)
            value += double(inside.weight[p][c]) * field[inside.index[p][c]];
        EXPECT_NEAR(value, 4.0 * ix[p] - 7.0 * iy[p] + 1.0, 1e-5) << "point " << p;
    }
}

// symmetrise: on a mirror-symmetric layout whose triangulation is not (every cell cut along the same diagonal), a
// field symmetric across x = 0 maps to a symmetric one and an antisymmetric field to an antisymmetric one; before,
// points on the diagonals mapped differently from their mirror images.
TEST(LevelTransfer, SymmetrisedMapsTreatMirrorImagesAlike) {
    const int n = 9; // source: n x n nodes over [-1, 1]^2, z = 0
    std::vector<float> sx, sy, sz;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            sx.push_back(-1.0f + 2.0f * float(i) / float(n - 1));
            sy.push_back(-1.0f + 2.0f * float(j) / float(n - 1));
            sz.push_back(0.0f);
        }
    std::vector<std::uint32_t> tri;
    for (int j = 0; j + 1 < n; ++j)
        for (int i = 0; i + 1 < n; ++i) {
            const std::uint32_t a = j * n + i, b = a + 1, c = a + n, d = c + 1;
            tri.insert(tri.end(), {a, b, d, a, d, c}); // always the a-d diagonal
        }
    std::vector<std::uint32_t> source_twins(sx.size());
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) source_twins[j * n + i] = j * n + (n - 1 - i);
    // Targets: a 7 x 6 grid of points, many on the source's diagonals, symmetric in x.
    std::vector<float> tx, ty, tz;
    const int m = 7;
    for (int j = 0; j < 6; ++j)
        for (int i = 0; i < m; ++i) {
            tx.push_back(-0.9f + 1.8f * float(i) / float(m - 1));
            ty.push_back(-0.8f + 0.3f * float(j));
            tz.push_back(0.0f);
        }
    std::vector<std::uint32_t> target_twins(tx.size());
    for (int j = 0; j < 6; ++j)
        for (int i = 0; i < m; ++i) target_twins[j * m + i] = j * m + (m - 1 - i);
    std::vector<float> even(sx.size()), odd(sx.size());
    for (std::size_t i = 0; i < sx.size(); ++i) {
        even[i] = sx[i] * sx[i] * (sy[i] + 0.5f); // cross terms: a diagonal matters
        odd[i] = sx[i] * (sy[i] + sy[i] * sy[i]);
    }
    auto apply = [](const LevelTransfer& t, const std::vector<float>& f, std::size_t k) {
        double v = 0.0;
        for (std::size_t c = 0; c < LevelTransfer::width; ++c) v += double(t.weight[k][c]) * f[t.index[k][c]];
        return v;
    };
    LevelTransfer t = surface_transfer(sx, sy, sz, tri, tx, ty, tz);
    double before = 0.0;
    for (std::size_t k = 0; k < tx.size(); ++k)
        before = std::max(before, std::fabs(apply(t, even, k) - apply(t, even, target_twins[k])));
    EXPECT_GT(before, 1e-3) << "the plain map is not symmetric (else this test shows nothing)";
    // Twins missing (vbd::mirror_twins leaves up to 5 % without, as UINT32_MAX): those nodes keep their own maps and
    // no entry points at a missing twin.
    {
        LevelTransfer partial = t;
        std::vector<std::uint32_t> tt = target_twins, st = source_twins;
        tt[3] = 0xFFFFFFFFu;
        st[40] = 0xFFFFFFFFu;
        partial.symmetrise(tt, st);
        for (std::size_t k = 0; k < partial.size(); ++k) {
            float sum = 0.0f;
            for (std::size_t c = 0; c < LevelTransfer::width; ++c) {
                ASSERT_LT(partial.index[k][c], sx.size()) << "target " << k;
                sum += partial.weight[k][c];
            }
            EXPECT_NEAR(sum, 1.0f, 1e-6f);
        }
        EXPECT_EQ(partial.index[3], t.index[3]);
        EXPECT_EQ(partial.weight[3], t.weight[3]);
    }
    t.symmetrise(target_twins, source_twins);
    for (std::size_t k = 0; k < tx.size(); ++k) {
        EXPECT_NEAR(apply(t, even, k), apply(t, even, target_twins[k]), 1e-6) << "target " << k;
        EXPECT_NEAR(apply(t, odd, k), -apply(t, odd, target_twins[k]), 1e-6) << "target " << k;
        float sum = 0.0f;
        for (float w : t.weight[k]) sum += w;
        EXPECT_NEAR(sum, 1.0f, 1e-6f);
    }
}

} // namespace
} // namespace drape
