// No allocation inside a step (DESIGN.md invariant): a counting global operator new, armed around step().
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include <tbb/global_control.h>

#include "test_helpers.hpp"

// The replacement operator new allocates with malloc, so its operator delete frees with free (g++ cannot see they pair).
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"

namespace {
std::atomic<bool> counting{false};
std::atomic<std::size_t> allocations{0};
} // namespace

void* operator new(std::size_t size) {
    if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
    if (void* p = std::malloc(size ? size : 1)) return p;
    throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

using namespace drape;

namespace {

struct AllocCase {
    KernelPath kernel;
    bool fused;
    Integrator integ;
    bool wind;
};

class NoAllocation : public ::testing::TestWithParam<AllocCase> {};

TEST_P(NoAllocation, StepDoesNotAllocate) {
    const AllocCase c = GetParam();
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    HangParams hp;
    hp.n = 100;
    SceneBuild scene = build_hang_scene(hp);
    SimulationParams p = drape::testing::default_params(scene.cloth, c.integ, c.kernel);
    p.fused = c.fused;
    p.wind.enabled = c.wind;
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    sim.step(5); // warm-up: the thread pool starts here
    sim.grab(5000, {0.0f, 0.1f, 0.0f});
    allocations = 0;
    counting = true;
    sim.step(200);
    sim.step_serial(5);
    sim.move_grab({0.0f, 0.2f, 0.0f});
    sim.step(5);
    counting = false;
    EXPECT_EQ(allocations.load(), 0u);
    // The counter works: an allocation while armed is seen.
    counting = true;
    auto* probe = new std::vector<int>(10);
    counting = false;
    delete probe;
    EXPECT_GE(allocations.load(), 1u);
}

INSTANTIATE_TEST_SUITE_P(Variants, NoAllocation,
                         ::testing::Values(AllocCase{KernelPath::grid, true, Integrator::symplectic_euler, false},
                                           AllocCase{KernelPath::grid, true, Integrator::verlet, true},
                                           AllocCase{KernelPath::csr, true, Integrator::symplectic_euler, true},
                                           AllocCase{KernelPath::grid, false, Integrator::symplectic_euler, true}));

} // namespace
