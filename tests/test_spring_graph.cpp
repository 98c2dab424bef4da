// CSR and SELL spring graph against the grid topology of "hang".
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <set>

#include "drape/scene_hang.hpp"
#include "drape/errors.hpp"
#include "drape/simd.hpp"

using namespace drape;

namespace {

std::array<std::size_t, spring_kind_count> count_by_kind(const Cloth& c) {
    std::array<std::size_t, spring_kind_count> out{};
    for (const Edge& e : c.edges) ++out[static_cast<std::size_t>(e.kind)];
    return out;
}

class SpringGraphGrid : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(SpringGraphGrid, CountsPerKindMatchBenchFormula) {
    const std::uint32_t n = GetParam();
    HangParams hp;
    hp.n = n;
    const Cloth c = build_hang_scene(hp).cloth;
    const auto counts = count_by_kind(c);
    const std::size_t N = n;
    EXPECT_EQ(counts[0], 2 * N * (N - 1)) << "structural";
    EXPECT_EQ(counts[1], 2 * (N - 1) * (N - 1)) << "shear";
    EXPECT_EQ(counts[2], N >= 2 ? 2 * N * (N - 2) : 0) << "bend";
    EXPECT_EQ(c.spring_count(), 2 * N * (N - 1) + 2 * (N - 1) * (N - 1) + 2 * N * (N - 2));
    EXPECT_EQ(c.graph.entry_count(), 2 * c.spring_count());
}

TEST_P(SpringGraphGrid, CsrIsSymmetricSortedAndMatchesEdges) {
    HangParams hp;
    hp.n = GetParam();
    const Cloth c = build_hang_scene(hp).cloth;
    const SpringGraph& g = c.graph;
    std::set<std::pair<std::uint32_t, std::uint32_t>> entries;
    for (std::uint32_t i = 0; i < c.particle_count; ++i) {
        for (std::uint32_t k = g.offsets[i]; k < g.offsets[i + 1]; ++k) {
            if (k > g.offsets[i]) {
                EXPECT_LT(g.neighbour[k - 1], g.neighbour[k]) << "row " << i << " not sorted";
            }
            entries.insert({i, g.neighbour[k]});
            const Edge& e = c.edges[g.edge_index[k]];
            EXPECT_TRUE((e.a == i && e.b == g.neighbour[k]) || (e.b == i && e.a == g.neighbour[k]));
        }
    }
    for (const auto& [i, j] : entries) EXPECT_TRUE(entries.count({j, i})) << i << "-" << j << " has no mirror";
}

TEST_P(SpringGraphGrid, SellSlicesHoldExactlyTheCsrRows) {
    HangParams hp;
    hp.n = GetParam();
    const Cloth c = build_hang_scene(hp).cloth;
    const SpringGraph& g = c.graph;
    constexpr std::size_t W = simd::width;
    for (std::size_t i = 0; i < c.padded_count; ++i) {
        const std::size_t s = i / W, lane = i % W;
        const std::uint32_t len = i < c.particle_count ? g.offsets[i + 1] - g.offsets[i] : 0;
        ASSERT_GE(g.slice_slots[s], len);
        for (std::uint32_t slot = 0; slot < g.slice_slots[s]; ++slot) {
            const std::size_t at = g.slice_begin[s] + slot * W + lane;
            if (slot < len) {
                const std::uint32_t k = g.offsets[i] + slot;
                EXPECT_EQ(g.sell_neighbour[at], g.neighbour[k]);
                const Edge& e = c.edges[g.edge_index[k]];
                EXPECT_EQ(g.sell_rest[at], e.rest);
                EXPECT_EQ(g.sell_stiffness[at], c.material[static_cast<std::size_t>(e.kind)].stiffness);
            } else { // inert padding
                EXPECT_EQ(g.sell_neighbour[at], i);
                EXPECT_EQ(g.sell_stiffness[at], 0.0f);
                EXPECT_EQ(g.sell_damping[at], 0.0f);
            }
        }
    }
}

TEST_P(SpringGraphGrid, GridStencilMatchesCsrRows) {
    HangParams hp;
    hp.n = GetParam();
    const Cloth c = build_hang_scene(hp).cloth;
    ASSERT_TRUE(c.grid.has_value());
    const GridStencil& st = *c.grid;
    // For N >= 4 the slots are in strictly ascending offset; below that two slots can share an offset, but never
    // for the same particle, and the row comparison below still holds.
    if (GetParam() >= 4) {
        for (std::size_t s = 1; s < GridStencil::slot_count; ++s) {
            EXPECT_LT(st.offset[s - 1], st.offset[s]);
        }
    }
    for (std::uint32_t i = 0; i < c.particle_count; ++i) {
        std::vector<std::uint32_t> from_grid;
        for (std::size_t s = 0; s < GridStencil::slot_count; ++s)
            if (st.mask[i] & (1u << s)) from_grid.push_back(static_cast<std::uint32_t>(std::int64_t(i) + st.offset[s]));
        const std::vector<std::uint32_t> from_csr(c.graph.neighbour.begin() + c.graph.offsets[i],
                                                  c.graph.neighbour.begin() + c.graph.offsets[i + 1]);
        EXPECT_EQ(from_grid, from_csr) << "particle " << i;
    }
}

INSTANTIATE_TEST_SUITE_P(Sizes, SpringGraphGrid, ::testing::Values(2u, 3u, 5u, 17u, 32u, 45u));

TEST(SpringGraph, BenchSpringCountAt32) {
    HangParams hp;
    hp.n = 32;
    EXPECT_EQ(build_hang_scene(hp).cloth.spring_count(), 5826u); // BENCH.md
}

TEST(SpringGraph, CookRejectsBadEdges) {
    const std::array<SpringMaterial, spring_kind_count> mat{SpringMaterial{100.0f, 0.0f}};
    const std::vector<float> inv_mass(4, 1.0f);
    auto cook = [&](std::vector<Edge> e) { return cook_cloth(inv_mass, std::move(e), mat); };
    EXPECT_THROW(cook({{0, 4, SpringKind::structural, 1.0f}}), InvalidInput);
    EXPECT_THROW(cook({{2, 2, SpringKind::structural, 1.0f}}), InvalidInput);
    EXPECT_THROW(cook({{0, 1, SpringKind::structural, 0.0f}}), InvalidInput);
    EXPECT_THROW(cook({{0, 1, SpringKind::structural, 1.0f}, {1, 0, SpringKind::shear, 1.0f}}), InvalidInput);
    EXPECT_THROW(cook_cloth(std::vector<float>{1.0f, -1.0f}, {}, mat), InvalidInput);
    EXPECT_NO_THROW(cook({{0, 1, SpringKind::structural, 1.0f}, {3, 2, SpringKind::structural, 1.0f}}));
    try {
        cook({{0, 9, SpringKind::structural, 1.0f}});
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("[0, 3]"), std::string::npos) << e.what();
    }
}

} // namespace
