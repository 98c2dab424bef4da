// Greedy edge colouring: conflict-free groups, every edge exactly once, determinism, overflow.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "drape/colouring.hpp"
#include "drape/errors.hpp"
#include "drape/tshirt.hpp"
#include "drape/scene_hang.hpp"

namespace drape {
namespace {

// Checks the CSR shape, conflict-freeness of the colours and that `expected` edges appear exactly once.
void check_groups(const ColourGroups& g, std::span<const Edge> edges, std::size_t n,
                  const std::vector<std::uint32_t>& expected) {
    ASSERT_EQ(g.group_offsets.size(), g.group_count() + 1);
    EXPECT_EQ(g.group_offsets.front(), 0u);
    EXPECT_EQ(g.group_offsets.back(), g.edge_index.size());
    EXPECT_EQ(g.group_count(), g.colour_count + (g.has_overflow ? 1u : 0u));
    std::vector<std::uint32_t> all(g.edge_index);
    std::sort(all.begin(), all.end());
    std::vector<std::uint32_t> want(expected);
    std::sort(want.begin(), want.end());
    EXPECT_EQ(all, want) << "every edge in exactly one group";
    std::vector<std::uint32_t> last_group(n, UINT32_MAX);
    std::size_t largest = 0, smallest = SIZE_MAX;
    for (std::size_t c = 0; c < g.colour_count; ++c) {
        const auto grp = g.group(c);
        EXPECT_FALSE(grp.empty());
        largest = std::max(largest, grp.size());
        smallest = std::min(smallest, grp.size());
        for (std::uint32_t e : grp) {
            for (std::uint32_t v : {edges[e].a, edges[e].b}) {
                EXPECT_NE(last_group[v], c) << "colour " << c << " has two springs at particle " << v;
                last_group[v] = static_cast<std::uint32_t>(c);
            }
        }
        // Sorted by lower particle index.
        for (std::size_t k = 1; k < grp.size(); ++k)
            EXPECT_LE(std::min(edges[grp[k - 1]].a, edges[grp[k - 1]].b),
                      std::min(edges[grp[k]].a, edges[grp[k]].b));
    }
    if (g.colour_count > 0) {
        EXPECT_EQ(g.largest_group, largest);
        EXPECT_EQ(g.smallest_group, smallest);
    }
    EXPECT_EQ(g.overflow_count, g.has_overflow ? g.group(g.colour_count).size() : 0u);
}

std::vector<std::uint32_t> iota_edges(std::size_t n) {
    std::vector<std::uint32_t> v(n);
    for (std::size_t k = 0; k < n; ++k)
        v[k] = static_cast<std::uint32_t>(k);
    return v;
}

TEST(Colour, HangClothNeedsFewColoursAndNoOverflow) {
    for (std::uint32_t n : {2u, 3u, 32u, 100u}) {
        HangParams p;
        p.n = n;
        const SceneBuild s = build_hang_scene(p);
        const auto& edges = s.cloth.edges;
        const ColourGroups g = colour_edges(edges, s.cloth.particle_count);
        SCOPED_TRACE("N = " + std::to_string(n));
        check_groups(g, edges, s.cloth.particle_count, iota_edges(edges.size()));
        EXPECT_FALSE(g.has_overflow);
        EXPECT_LE(g.colour_count, 23u); // greedy: at most 2 * 12 - 1 for the 12-neighbour grid
        if (n == 100) {
            RecordProperty("colours", static_cast<int>(g.colour_count));
            std::printf("hang N=100: %zu springs, %u colours, largest group %zu, smallest %zu\n",
                        edges.size(), g.colour_count, g.largest_group, g.smallest_group);
        }
        // Deterministic.
        const ColourGroups again = colour_edges(edges, s.cloth.particle_count);
        EXPECT_EQ(again.edge_index, g.edge_index);
        EXPECT_EQ(again.group_offsets, g.group_offsets);
    }
}

TEST(Colour, TShirtSeamsAsASubset) {
    const TShirtBuild t = build_tshirt({});
    const auto& edges = t.assembly.edges;
    const ColourGroups g = colour_edges(edges, t.assembly.particle_count(), t.seam_edges);
    check_groups(g, edges, t.assembly.particle_count(), t.seam_edges);
    // Seams of the T-shirt join distinct particle pairs (each front particle sewn once): one colour suffices.
    EXPECT_EQ(g.colour_count, 1u);
    EXPECT_FALSE(g.has_overflow);
    // All the shirt's springs, for strain limiting.
    const ColourGroups all = colour_edges(edges, t.assembly.particle_count());
    check_groups(all, edges, t.assembly.particle_count(), iota_edges(edges.size()));
    EXPECT_FALSE(all.has_overflow);
}

TEST(Colour, RandomGraphsAndOverflow) {
    for (unsigned seed : {1u, 2u, 3u}) {
        std::mt19937 rng(seed);
        const std::size_t n = 50;
        std::uniform_int_distribution<std::uint32_t> pick(0, n - 1);
        std::vector<Edge> edges;
        for (int k = 0; k < 600; ++k) {
            const std::uint32_t a = pick(rng), b = pick(rng);
            if (a != b) edges.push_back({a, b, SpringKind::seam, 0.01f});
        }
        for (std::uint32_t cap : {1u, 4u, 16u, 64u}) {
            const ColourGroups g = colour_edges(edges, n, {}, cap);
            check_groups(g, edges, n, iota_edges(edges.size()));
            EXPECT_LE(g.colour_count, cap);
            if (cap == 64) {
                EXPECT_FALSE(g.has_overflow); // degree ~24 here: greedy needs < 2 * 24 colours
            }
            if (cap <= 4) {
                EXPECT_TRUE(g.has_overflow);
            }
        }
    }
    // A star: every edge shares particle 0; 8 colours of one edge each, the rest overflows.
    std::vector<Edge> star;
    for (std::uint32_t k = 1; k <= 100; ++k)
        star.push_back({0, k, SpringKind::seam, 0.01f});
    const ColourGroups g = colour_edges(star, 101, {}, 8);
    check_groups(g, star, 101, iota_edges(star.size()));
    EXPECT_EQ(g.colour_count, 8u);
    EXPECT_EQ(g.overflow_count, 92u);
    EXPECT_EQ(g.largest_group, 1u);
    EXPECT_TRUE(g.is_overflow(8));
}

TEST(Colour, RejectsBadInput) {
    const std::vector<Edge> edges{{0, 1, SpringKind::seam, 0.1f}, {1, 2, SpringKind::seam, 0.1f}};
    auto msg = [](auto&& f) -> std::string {
        try {
            f();
        } catch (const InvalidInput& e) {
            return e.what();
        }
        return "";
    };
    EXPECT_NE(msg([&] { colour_edges(edges, 2); }).find("outside [0, 1]"), std::string::npos);
    EXPECT_NE(msg([&] { colour_edges(edges, 3, {}, 0); }).find("max_colours"), std::string::npos);
    EXPECT_NE(msg([&] { colour_edges(edges, 3, {}, 65); }).find("[1, 64]"), std::string::npos);
    const std::vector<std::uint32_t> twice{1, 1}, outside{2};
    EXPECT_NE(msg([&] { colour_edges(edges, 3, twice); }).find("twice"), std::string::npos);
    EXPECT_NE(msg([&] { colour_edges(edges, 3, outside); }).find("subset"), std::string::npos);
    const std::vector<Edge> loop{{1, 1, SpringKind::seam, 0.1f}};
    EXPECT_NE(msg([&] { colour_edges(loop, 3); }).find("itself"), std::string::npos);
    EXPECT_EQ(colour_edges({}, 0).group_count(), 0u);
}

} // namespace
} // namespace drape
