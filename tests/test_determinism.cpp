// Results are bitwise identical for every thread count (DESIGN.md invariant): the checksum of the positions after
// 500 substeps at 1, 2, 3 and 4 threads, with and without wind, both integrators and both kernels.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include "drape/scene.hpp"
#include "test_helpers.hpp"

using namespace drape;

namespace {

std::uint64_t checksum_after(std::size_t threads, std::uint32_t n, bool wind, Integrator integ, KernelPath kernel,
                             std::size_t steps = 500) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    HangParams hp;
    hp.n = n;
    SceneBuild scene = build_hang_scene(hp);
    SimulationParams p = drape::testing::default_params(scene.cloth, integ, kernel);
    p.wind.enabled = wind;
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    sim.step(steps);
    EXPECT_TRUE(sim.health().finite);
    return sim.checksum();
}

struct DetCase {
    bool wind;
    Integrator integ;
    KernelPath kernel;
};

class Determinism : public ::testing::TestWithParam<DetCase> {};

TEST_P(Determinism, ChecksumIndependentOfThreadCount) {
    const DetCase c = GetParam();
    // N = 100: 10,000 particles = 10 blocks, so two or more threads really split the cloth.
    const std::uint64_t one = checksum_after(1, 100, c.wind, c.integ, c.kernel);
    for (std::size_t t : {2u, 3u, 4u})
        EXPECT_EQ(one, checksum_after(t, 100, c.wind, c.integ, c.kernel)) << t << " threads";
    std::printf("[ checksum ] N=100 500 substeps %s%s %s: %016llx (1, 2, 3, 4 threads)\n", integrator_name(c.integ),
                c.wind ? " wind" : "", kernel_path_name(c.kernel), static_cast<unsigned long long>(one));
}

INSTANTIATE_TEST_SUITE_P(Variants, Determinism,
                         ::testing::Values(DetCase{false, Integrator::symplectic_euler, KernelPath::grid},
                                           DetCase{true, Integrator::symplectic_euler, KernelPath::grid},
                                           DetCase{false, Integrator::verlet, KernelPath::grid},
                                           DetCase{true, Integrator::verlet, KernelPath::grid},
                                           DetCase{true, Integrator::symplectic_euler, KernelPath::csr}),
                         [](const auto& info) {
                             return std::string(integrator_name(info.param.integ)) + (info.param.wind ? "_wind_" : "_") +
                                    kernel_path_name(info.param.kernel);
                         });

TEST(Determinism, OddSizeWithPartialBatch) {
    const std::uint64_t one = checksum_after(1, 77, true, Integrator::symplectic_euler, KernelPath::grid, 200);
    EXPECT_EQ(one, checksum_after(2, 77, true, Integrator::symplectic_euler, KernelPath::grid, 200));
    EXPECT_EQ(one, checksum_after(3, 77, true, Integrator::symplectic_euler, KernelPath::grid, 200));
}

TEST(Determinism, RunsAreRepeatable) {
    EXPECT_EQ(checksum_after(2, 64, true, Integrator::verlet, KernelPath::grid, 100),
              checksum_after(2, 64, true, Integrator::verlet, KernelPath::grid, 100));
}

TEST(Determinism, WindChangesTheResult) { // the wind cases above really differ from the calm ones
    EXPECT_NE(checksum_after(2, 40, true, Integrator::symplectic_euler, KernelPath::grid, 100),
              checksum_after(2, 40, false, Integrator::symplectic_euler, KernelPath::grid, 100));
}

} // namespace

namespace {

// The irregular stages (aero per triangle, seams in colour groups, strain limiting, collisions with the body) keep
// results independent of the thread count: the T-shirt with aerodynamic wind at 1, 2 and 3 threads.
TEST(Determinism, GarmentStagesIndependentOfThreadCount) {
    auto run = [](std::size_t threads) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        SceneSpec spec = load_scene("tshirt");
        spec.tshirt.cells_per_metre = 90; // ~6,500 particles: several blocks and chunks
        spec.physics.aero.enabled = true;
        BuiltScene b = build_scene(spec);
        Simulation sim(std::move(b.cloth), b.initial, b.params);
        sim.step(300);
        EXPECT_TRUE(sim.health().finite);
        return sim.checksum();
    };
    const std::uint64_t one = run(1);
    EXPECT_EQ(one, run(2));
    EXPECT_EQ(one, run(3));
    std::printf("[ checksum ] tshirt (90 cells/m) + aero, 300 substeps: %016llx (1, 2, 3 threads)\n",
                static_cast<unsigned long long>(one));
}

} // namespace
