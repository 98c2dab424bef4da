// The strain-colouring stage (core/src/strain_field.cpp) against a plain scalar reference: every structural
// spring of the edge list evaluated once and scattered (max) to its two ends, in float with the same
// expression, so the stage must match it to the bit on both paths (SIMD grid, general CSR); its maximum is
// health()'s max structural strain; the parallel result equals the serial twin at 1, 2, 3, 5 and 8 workers;
// compute() allocates nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "drape/errors.hpp"
#include "drape/publish.hpp"
#include "drape/strain_field.hpp"
#include "drape/workers.hpp"
#include "test_helpers.hpp"

using namespace drape;

namespace {

/// Scatter form over the edge list: s_i = max over structural springs touching i of |l - l0| / l0.
std::vector<float> reference_strain(const Cloth& cloth, std::span<const float> x, std::span<const float> y,
                                    std::span<const float> z) {
    std::vector<float> s(cloth.particle_count, 0.0f);
    for (const Edge& e : cloth.edges) {
        if (e.kind != SpringKind::structural) continue;
        const float dx = x[e.b] - x[e.a], dy = y[e.b] - y[e.a], dz = z[e.b] - z[e.a];
        const float v = std::fabs(std::sqrt(dx * dx + dy * dy + dz * dz) - e.rest) / e.rest;
        s[e.a] = std::max(s[e.a], v);
        s[e.b] = std::max(s[e.b], v);
    }
    return s;
}

void expect_matches_reference(StrainField& field, const Cloth& cloth, std::span<const float> x,
                              std::span<const float> y, std::span<const float> z) {
    std::vector<float> out(field.plane_floats(), -7.0f); // garbage the stage must overwrite
    const float top = field.compute(x, y, z, out);
    const std::vector<float> ref = reference_strain(cloth, x, y, z);
    float ref_top = 0.0f;
    for (std::size_t i = 0; i < cloth.particle_count; ++i) {
        EXPECT_EQ(out[i], ref[i]) << "vertex " << i;
        ref_top = std::max(ref_top, ref[i]);
    }
    for (std::size_t i = cloth.particle_count; i < field.plane_floats(); ++i)
        EXPECT_EQ(out[i], 0.0f) << "padding " << i;
    EXPECT_EQ(top, ref_top);
}

} // namespace

class StrainFieldGrid : public ::testing::TestWithParam<std::uint32_t> {};

// Scene "hang", perturbed and stepped (really stretched and bent): grid path and general path vs the
// reference, and the maximum is the figure health() and the output stage report.
TEST_P(StrainFieldGrid, MatchesScalarReferenceOnBothPaths) {
    const std::uint32_t n = GetParam();
    SceneBuild scene = drape::testing::perturbed_hang(n, 0.3f, 0.5f, 4321u + n);
    const SimulationParams params = drape::testing::default_params(scene.cloth);
    Simulation sim(std::move(scene.cloth), scene.initial, params);
    sim.step(50);
    StrainField grid(sim.cloth());
    EXPECT_EQ(grid.grid_path(), n >= 2);
    expect_matches_reference(grid, sim.cloth(), sim.x(), sim.y(), sim.z());

    Cloth general_cloth = sim.cloth();
    general_cloth.grid.reset();
    StrainField general(general_cloth);
    EXPECT_FALSE(general.grid_path());
    expect_matches_reference(general, general_cloth, sim.x(), sim.y(), sim.z());

    std::vector<float> out(grid.plane_floats());
    const float top = grid.compute(sim.x(), sim.y(), sim.z(), out);
    EXPECT_EQ(top, sim.health().max_structural_strain);
    Publisher pub(sim.cloth());
    std::vector<float> planes(pub.output_floats());
    EXPECT_EQ(top, pub.publish(sim.x(), sim.y(), sim.z(), planes).max_structural_strain);
    EXPECT_GT(top, 0.0f); // the perturbation stretched something: the test compares real values
}

// 2: every vertex on the border; 5, 17, 33: partial SIMD batches, rows shorter and longer than a batch; 40:
// two blocks; 77: odd size, several blocks with the SIMD body in use.
INSTANTIATE_TEST_SUITE_P(Sizes, StrainFieldGrid, ::testing::Values(2u, 3u, 5u, 17u, 33u, 40u, 77u));

TEST(StrainField, KnownStretchOfOneSpring) {
    // A 3 x 3 grid at rest, then vertex 4 (the centre) moved 0.1 spacing east: its east spring is 0.9 of
    // rest, its west spring 1.1 (up to float rounding), its north and south springs sqrt(1.01).
    HangParams hp;
    hp.n = 3;
    SceneBuild scene = build_hang_scene(hp);
    InitialState s = scene.initial;
    const float h = s.x[1] - s.x[0];
    s.x[4] += 0.1f * h;
    StrainField field(scene.cloth);
    ASSERT_TRUE(field.grid_path());
    std::vector<float> out(field.plane_floats());
    field.compute(s.x, s.y, s.z, out);
    EXPECT_NEAR(out[4], 0.1f, 1e-5f);
    EXPECT_NEAR(out[3], 0.1f, 1e-5f);                       // west neighbour: its east spring is the 1.1 one
    EXPECT_NEAR(out[1], std::sqrt(1.01f) - 1.0f, 1e-5f);    // north neighbour
    EXPECT_NEAR(out[0], 0.0f, 1e-6f);                       // a corner away from the moved vertex
}

TEST(StrainField, ParallelEqualsSerialBitwiseAtAnyWorkerCount) {
    SceneBuild scene = drape::testing::perturbed_hang(150, 0.5f, 0.0f, 17u);
    Cloth general = scene.cloth;
    general.grid.reset();
    for (const Cloth* cloth : {&scene.cloth, &general}) {
        StrainField field(*cloth);
        const auto& s = scene.initial;
        std::vector<float> serial(field.plane_floats());
        const float serial_top = field.compute_serial(s.x, s.y, s.z, serial);
        for (int workers : {1, 2, 3, 5, 8}) {
            Workers arena(workers);
            std::vector<float> par(field.plane_floats(), 1.0f);
            const float top = arena.run([&] { return field.compute(s.x, s.y, s.z, par); });
            EXPECT_EQ(0, std::memcmp(par.data(), serial.data(), par.size() * sizeof(float)))
                << workers << " workers, " << (field.grid_path() ? "grid" : "general") << " path";
            EXPECT_EQ(top, serial_top);
        }
    }
}

TEST(StrainField, ClothWithoutStructuralSpringsIsZero) {
    Cloth cloth;
    cloth.particle_count = 4;
    cloth.padded_count = pad_to_width(4);
    cloth.triangles = {0, 1, 2};
    std::vector<float> x = {0, 1, 0, 5}, y = {0, 0, 0, 5}, z = {0, 0, 1, 5};
    StrainField field(cloth);
    EXPECT_FALSE(field.grid_path());
    std::vector<float> out(field.plane_floats(), 9.0f);
    EXPECT_EQ(field.compute(x, y, z, out), 0.0f);
    for (float v : out)
        EXPECT_EQ(v, 0.0f);
}

TEST(StrainField, RejectsShortSpans) {
    SceneBuild scene = build_hang_scene({});
    StrainField field(scene.cloth);
    const auto& s = scene.initial;
    std::vector<float> out(field.plane_floats() - 1);
    EXPECT_THROW(field.compute(s.x, s.y, s.z, out), InvalidInput);
    std::vector<float> ok(field.plane_floats());
    EXPECT_THROW(field.compute(std::span<const float>(s.x.data(), 10), s.y, s.z, ok), InvalidInput);
}

TEST(StrainField, HistogramCountsEveryVertexAndGivesQuantiles) {
    // Bins: four per octave from 2^-14; exact bin edges land in the bin below.
    EXPECT_EQ(StrainField::bin_of(0.0f), 0u);
    EXPECT_EQ(StrainField::bin_of(std::ldexp(1.0f, -20)), 0u);
    EXPECT_EQ(StrainField::bin_of(std::numeric_limits<float>::quiet_NaN()), StrainField::strain_bins - 1);
    EXPECT_EQ(StrainField::bin_of(1e30f), StrainField::strain_bins - 1);
    for (float v : {1e-4f, 0.003f, 0.05f, 0.5f, 2.0f}) {
        const std::size_t b = StrainField::bin_of(v);
        EXPECT_LT(v, StrainField::bin_upper(b)) << v;
        EXPECT_GE(v, StrainField::bin_upper(b - 1)) << v;
        // Linear within an octave (1, 1.25, 1.5, 1.75, 2): each bin 14 % to 25 % wide.
        const float ratio = StrainField::bin_upper(b) / StrainField::bin_upper(b - 1);
        EXPECT_GE(ratio, 1.14f) << v;
        EXPECT_LE(ratio, 1.25f) << v;
    }
    // A stepped cloth: the histogram holds every vertex on both paths, the same counts at any worker count,
    // and its quantiles bracket the reference's sorted strains.
    SceneBuild scene = drape::testing::perturbed_hang(90, 0.4f, 0.0f, 3u);
    Cloth general = scene.cloth;
    general.grid.reset();
    const auto& s = scene.initial;
    std::vector<float> ref = reference_strain(scene.cloth, s.x, s.y, s.z);
    std::sort(ref.begin(), ref.end());
    std::vector<std::uint32_t> first;
    for (const Cloth* cloth : {&scene.cloth, &general}) {
        StrainField field(*cloth);
        std::vector<float> out(field.plane_floats());
        for (int workers : {1, 3}) {
            Workers arena(workers);
            arena.run([&] { return field.compute(s.x, s.y, s.z, out); });
            const auto h = field.histogram();
            std::uint64_t total = 0;
            for (std::uint32_t c : h)
                total += c;
            EXPECT_EQ(total, cloth->particle_count);
            if (first.empty()) first.assign(h.begin(), h.end());
            EXPECT_TRUE(std::equal(h.begin(), h.end(), first.begin())) << workers << " workers";
            for (double q : {0.5, 0.9, 0.99, 1.0}) {
                const float v = field.quantile(q);
                const std::size_t rank = static_cast<std::size_t>(std::ceil(q * double(ref.size()))) - 1;
                EXPECT_LT(ref[rank], v) << q; // the q-quantile lies in the bin v closes
                EXPECT_GE(ref[rank], v / 1.25f) << q;
            }
        }
    }
}
