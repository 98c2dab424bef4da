// The output stage (core/src/publish.cpp) against a plain scalar reference: positions copied exactly,
// area-weighted normals per vertex from the triangle list (double precision, scatter form), the structural
// strain figure equal to Simulation::health()'s, padding zeroed, and the parallel result bitwise equal to the
// serial twin at 1, 2 and 3 threads. Both paths are covered: the SIMD grid path (scene "hang") and the
// general per-vertex fan path (the same cloth without its grid stencil, and a small irregular mesh).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "drape/errors.hpp"
#include "drape/publish.hpp"
#include "drape/scene_hang.hpp"
#include "drape/simulation.hpp"
#include "drape/workers.hpp"
#include "test_helpers.hpp"

using namespace drape;

namespace {

struct Reference {
    std::vector<double> nx, ny, nz;
    double max_strain = 0.0;
};

/// Scatter form, the textbook way: each triangle adds (b - a) x (c - a) to its three vertices; then
/// normalise.
Reference reference_normals(const Cloth& cloth, const std::vector<float>& x, const std::vector<float>& y,
                            const std::vector<float>& z) {
    const std::size_t n = cloth.particle_count;
    Reference r;
    r.nx.assign(n, 0.0);
    r.ny.assign(n, 0.0);
    r.nz.assign(n, 0.0);
    const auto& t = cloth.triangles;
    for (std::size_t k = 0; k < t.size(); k += 3) {
        const std::uint32_t a = t[k], b = t[k + 1], c = t[k + 2];
        const double ux = double(x[b]) - x[a], uy = double(y[b]) - y[a], uz = double(z[b]) - z[a];
        const double vx = double(x[c]) - x[a], vy = double(y[c]) - y[a], vz = double(z[c]) - z[a];
        const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
        for (std::uint32_t v : {a, b, c}) {
            r.nx[v] += cx;
            r.ny[v] += cy;
            r.nz[v] += cz;
        }
    }
    for (std::size_t i = 0; i < n; ++i) {
        const double len = std::sqrt(r.nx[i] * r.nx[i] + r.ny[i] * r.ny[i] + r.nz[i] * r.nz[i]);
        if (len > 0.0) {
            r.nx[i] /= len;
            r.ny[i] /= len;
            r.nz[i] /= len;
        } else {
            r.nx[i] = 0.0;
            r.ny[i] = 1.0;
            r.nz[i] = 0.0;
        }
    }
    for (const Edge& e : cloth.edges) {
        if (e.kind != SpringKind::structural) continue;
        const double dx = double(x[e.b]) - x[e.a], dy = double(y[e.b]) - y[e.a], dz = double(z[e.b]) - z[e.a];
        r.max_strain =
            std::max(r.max_strain, std::fabs(std::sqrt(dx * dx + dy * dy + dz * dz) - e.rest) / e.rest);
    }
    return r;
}

/// Checks a publish() output against the reference; returns the largest normal error (radians-ish: |n -
/// n_ref|).
double check_output(const Publisher& pub, const Cloth& cloth, const std::vector<float>& out,
                    const std::vector<float>& x, const std::vector<float>& y, const std::vector<float>& z,
                    const PublishStats& stats) {
    const std::size_t n = cloth.particle_count, plane = pub.plane_floats();
    EXPECT_EQ(plane % simd::width, 0u);
    EXPECT_GE(plane, n);
    const Reference ref = reference_normals(cloth, x, y, z);
    double worst = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        // Positions are copied bit for bit.
        EXPECT_EQ(out[0 * plane + i], x[i]) << i;
        EXPECT_EQ(out[1 * plane + i], y[i]) << i;
        EXPECT_EQ(out[2 * plane + i], z[i]) << i;
        const double ex = out[3 * plane + i] - ref.nx[i], ey = out[4 * plane + i] - ref.ny[i],
                     ez = out[5 * plane + i] - ref.nz[i];
        const double err = std::sqrt(ex * ex + ey * ey + ez * ez);
        worst = std::max(worst, err);
        EXPECT_LT(err, 2e-5) << "normal of vertex " << i;
    }
    for (std::size_t i = n; i < plane; ++i)
        for (std::size_t q = 0; q < vertex_plane_count; ++q)
            EXPECT_EQ(out[q * plane + i], 0.0f) << "padding " << i;
    EXPECT_TRUE(stats.finite);
    EXPECT_NEAR(stats.max_structural_strain, ref.max_strain, 1e-5 * std::max(1.0, ref.max_strain));
    return worst;
}

std::vector<float> positions(const Simulation& sim, int axis) {
    const std::span<const float> s = axis == 0 ? sim.x() : axis == 1 ? sim.y() : sim.z();
    return {s.begin(), s.end()};
}

} // namespace

class PublishGrid : public ::testing::TestWithParam<std::uint32_t> {};

// Scene "hang", perturbed and then stepped so the cloth is really bent: grid path vs the reference.
TEST_P(PublishGrid, MatchesScalarReferenceOnPerturbedCloth) {
    const std::uint32_t n = GetParam();
    SceneBuild scene = drape::testing::perturbed_hang(n, 0.3f, 0.5f, 1234u + n);
    const SimulationParams params = drape::testing::default_params(scene.cloth);
    Simulation sim(std::move(scene.cloth), scene.initial, params);
    sim.step(50);
    Publisher pub(sim.cloth());
    EXPECT_TRUE(pub.grid_path());
    std::vector<float> out(pub.output_floats(), -7.0f); // garbage the stage must overwrite
    const PublishStats stats = pub.publish(sim.x(), sim.y(), sim.z(), out);
    const std::vector<float> x = positions(sim, 0), y = positions(sim, 1), z = positions(sim, 2);
    const double worst = check_output(pub, sim.cloth(), out, x, y, z, stats);
    // The fused strain figure is the one health() reports, to the bit.
    EXPECT_EQ(stats.max_structural_strain, sim.health().max_structural_strain);
    std::printf("[ publish ] grid N=%u: worst normal error %.3g, max strain %.4f\n", n, worst,
                double(stats.max_structural_strain));
}

// 2: every vertex on the border; 5 and 33: partial SIMD batches and rows shorter/longer than a batch; 40:
// 1600 particles over two blocks with the SIMD body in use; 77: odd size, several blocks.
INSTANTIATE_TEST_SUITE_P(Sizes, PublishGrid, ::testing::Values(2u, 3u, 5u, 17u, 33u, 40u, 77u));

TEST(Publish, GeneralPathMatchesReferenceAndGridPath) {
    SceneBuild scene = drape::testing::perturbed_hang(45, 0.4f, 0.0f, 99u);
    Cloth grid_cloth = scene.cloth;
    Cloth general_cloth = scene.cloth;
    general_cloth.grid.reset(); // same mesh, no stencil: the general fan path
    Publisher grid_pub(grid_cloth), general_pub(general_cloth);
    ASSERT_TRUE(grid_pub.grid_path());
    ASSERT_FALSE(general_pub.grid_path());
    const auto& s = scene.initial;
    std::vector<float> a(grid_pub.output_floats()), b(general_pub.output_floats());
    const PublishStats sa = grid_pub.publish(s.x, s.y, s.z, a);
    const PublishStats sb = general_pub.publish(s.x, s.y, s.z, b);
    check_output(grid_pub, grid_cloth, a, s.x, s.y, s.z, sa);
    check_output(general_pub, general_cloth, b, s.x, s.y, s.z, sb);
    EXPECT_EQ(sa.max_structural_strain, sb.max_structural_strain);
    for (std::size_t i = 0; i < a.size(); ++i)
        EXPECT_NEAR(a[i], b[i], 2e-5f) << i;
}

// A small irregular mesh: a fan of 5 triangles around vertex 0, bent out of plane, plus a detached triangle.
TEST(Publish, IrregularMesh) {
    Cloth cloth;
    cloth.particle_count = 9;
    cloth.padded_count = pad_to_width(9);
    cloth.triangles = {0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5, 0, 5, 1, 6, 7, 8};
    cloth.edges = {{0, 1, SpringKind::structural, 1.0f}, {6, 7, SpringKind::structural, 1.0f}};
    const std::vector<float> x = {0.0f, 1.0f, 0.3f, -0.8f, -0.8f, 0.3f, 2.0f, 3.0f, 2.0f};
    const std::vector<float> y = {0.2f, 0.0f, 0.1f, -0.1f, 0.0f, 0.05f, 0.0f, 0.0f, 0.0f};
    const std::vector<float> z = {0.0f, 0.0f, 0.9f, 0.6f, -0.6f, -0.9f, 0.0f, 0.0f, 1.0f};
    Publisher pub(cloth);
    EXPECT_FALSE(pub.grid_path());
    std::vector<float> out(pub.output_floats(), 3.0f);
    const PublishStats stats = pub.publish(x, y, z, out);
    check_output(pub, cloth, out, x, y, z, stats);
    // Triangle (6, 7, 8): (1,0,0) x (0,0,1) = (0,-1,0), so vertex 8's normal is -y.
    const std::size_t plane = pub.plane_floats();
    EXPECT_NEAR(out[4 * plane + 8], -1.0f, 1e-6f);
    EXPECT_NEAR(stats.max_structural_strain, std::hypot(1.0, 0.2) - 1.0, 1e-6);
}

TEST(Publish, VertexInNoTriangleGetsUpNormal) {
    Cloth cloth;
    cloth.particle_count = 4;
    cloth.padded_count = pad_to_width(4);
    cloth.triangles = {0, 1, 2};
    std::vector<float> x = {0, 1, 0, 5}, y = {0, 0, 0, 5}, z = {0, 0, 1, 5};
    Publisher pub(cloth);
    std::vector<float> out(pub.output_floats());
    const PublishStats stats = pub.publish(x, y, z, out);
    const std::size_t plane = pub.plane_floats();
    EXPECT_EQ(out[3 * plane + 3], 0.0f);
    EXPECT_EQ(out[4 * plane + 3], 1.0f);
    EXPECT_EQ(out[5 * plane + 3], 0.0f);
    EXPECT_EQ(stats.max_structural_strain, 0.0f);
    // Triangle (0, 1, 2): (1,0,0) x (0,0,1) = (0,-1,0).
    EXPECT_EQ(out[4 * plane + 0], -1.0f);
}

TEST(Publish, ParallelEqualsSerialBitwiseAtAnyThreadCount) {
    SceneBuild scene = drape::testing::perturbed_hang(100, 0.5f, 0.0f, 7u);
    Cloth general = scene.cloth;
    general.grid.reset();
    for (const Cloth* cloth : {&scene.cloth, &general}) {
        Publisher pub(*cloth);
        const auto& s = scene.initial;
        std::vector<float> serial(pub.output_floats());
        const PublishStats ss = pub.publish_serial(s.x, s.y, s.z, serial);
        for (int threads : {1, 2, 3, 5, 8}) {
            Workers workers(threads);
            std::vector<float> par(pub.output_floats(), 1.0f);
            const PublishStats sp = workers.run([&] { return pub.publish(s.x, s.y, s.z, par); });
            EXPECT_EQ(0, std::memcmp(par.data(), serial.data(), par.size() * sizeof(float)))
                << threads << " threads, " << (pub.grid_path() ? "grid" : "general") << " path";
            EXPECT_EQ(sp.max_structural_strain, ss.max_structural_strain);
        }
    }
}

TEST(Publish, ReportsNonFinitePositions) {
    SceneBuild scene = build_hang_scene({});
    Publisher pub(scene.cloth);
    auto s = scene.initial;
    s.y[5000] = std::numeric_limits<float>::quiet_NaN();
    std::vector<float> out(pub.output_floats());
    EXPECT_FALSE(pub.publish(s.x, s.y, s.z, out).finite);
    s.y[5000] = 0.0f;
    s.x[0] = std::numeric_limits<float>::infinity(); // a border vertex: the scalar part of the grid path
    EXPECT_FALSE(pub.publish(s.x, s.y, s.z, out).finite);
}

TEST(Publish, RejectsShortSpans) {
    SceneBuild scene = build_hang_scene({});
    Publisher pub(scene.cloth);
    const auto& s = scene.initial;
    std::vector<float> out(pub.output_floats() - 1);
    EXPECT_THROW(pub.publish(s.x, s.y, s.z, out), InvalidInput);
    std::vector<float> ok(pub.output_floats());
    EXPECT_THROW(pub.publish(std::span<const float>(s.x.data(), 10), s.y, s.z, ok), InvalidInput);
    Cloth bad;
    bad.particle_count = 3;
    bad.padded_count = pad_to_width(3);
    bad.triangles = {0, 1, 3};
    EXPECT_THROW(Publisher{bad}, InvalidInput);
}
