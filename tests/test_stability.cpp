// The explicit time-step bound, bad parameters, and the non-finite stop.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "test_helpers.hpp"

using namespace drape;

namespace {

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

SceneBuild hang(std::uint32_t n, float stiffness = 1000.0f) {
    HangParams hp;
    hp.n = n;
    hp.stiffness = stiffness;
    return build_hang_scene(hp);
}

TEST(Stability, DtAboveTheBoundIsRefusedWithBoundAndSubsteps) {
    SceneBuild scene = hang(64);
    const StabilityBound b = stability_bound(scene.cloth, 0.2f);
    SimulationParams p;
    p.dt = static_cast<float>(3.0 * b.dt_max);
    try {
        Simulation sim(std::move(scene.cloth), scene.initial, p);
        FAIL() << "an unstable dt was accepted";
    } catch (const InvalidInput& e) {
        const std::string msg = e.what();
        EXPECT_TRUE(contains(msg, "stability bound")) << msg;
        EXPECT_TRUE(contains(msg, "substeps")) << msg;
        EXPECT_TRUE(contains(msg, "dt")) << msg;
    }
}

TEST(Stability, BoundScalesLikeSqrtMassOverStiffness) {
    const double soft = stability_bound(hang(64, 400.0f).cloth, 0.0f).dt_max;
    const double stiff = stability_bound(hang(64, 1600.0f).cloth, 0.0f).dt_max;
    EXPECT_NEAR(soft / stiff, 2.0, 0.1); // 4x stiffness -> half the step (damping shifts it slightly)
    const double coarse = stability_bound(hang(32).cloth, 0.0f).dt_max;
    const double fine = stability_bound(hang(64).cloth, 0.0f).dt_max;
    EXPECT_GT(coarse / fine, 1.8); // 4x lighter particles -> about half the step
}

TEST(Stability, RunsAtTheBoundStayFiniteAndBounded) {
    // 0.98 x the bound for 5000 substeps, perturbed start: the bound is safe, not just conservative on paper.
    SceneBuild scene = drape::testing::perturbed_hang(24, 0.2f, 0.5f, 3);
    SimulationParams p;
    p.dt = static_cast<float>(0.98 * stability_bound(scene.cloth, p.air_drag).dt_max);
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    sim.step(5000);
    const Health h = sim.health();
    EXPECT_TRUE(h.finite);
    EXPECT_LT(h.max_structural_strain, 5.0f);
}

TEST(Stability, NonFiniteStateStopsWithStepAndParticle) {
    SceneBuild scene = hang(20);
    scene.initial.vx[57] = 3e38f; // overflows within a few substeps
    SimulationParams p = drape::testing::default_params(scene.cloth);
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    try {
        sim.step(100);
        FAIL() << "an overflowing state was not detected";
    } catch (const SimulationError& e) {
        const std::string msg = e.what();
        EXPECT_TRUE(contains(msg, "substep")) << msg;
        EXPECT_TRUE(contains(msg, "particle")) << msg;
    }
    EXPECT_TRUE(sim.health().finite) << "the state stays at the last finite step";
}

TEST(Stability, SetParamsAndSetMaterialRefuseUnstableChanges) {
    SceneBuild scene = hang(32);
    SimulationParams p = drape::testing::default_params(scene.cloth);
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    SimulationParams bigger = p;
    bigger.dt = p.dt * 4.0f;
    EXPECT_THROW(sim.set_params(bigger), InvalidInput);
    EXPECT_EQ(sim.params().dt, p.dt);
    const SpringMaterial before = sim.cloth().material[0];
    EXPECT_THROW(sim.set_material(SpringKind::structural, {before.stiffness * 20.0f, before.damping}), InvalidInput);
    EXPECT_EQ(sim.cloth().material[0].stiffness, before.stiffness) << "a refused change leaves the material as it was";
    EXPECT_NO_THROW(sim.set_material(SpringKind::structural, {before.stiffness * 0.5f, before.damping}));
    sim.step(10);
    EXPECT_TRUE(sim.health().finite);
}

TEST(Stability, BadParametersNameTheFieldAndRange) {
    SceneBuild scene = hang(8);
    const SimulationParams good = drape::testing::default_params(scene.cloth);
    auto message = [&](SimulationParams p) -> std::string {
        try {
            validate_params(p);
        } catch (const InvalidInput& e) {
            return e.what();
        }
        return "";
    };
    SimulationParams p = good;
    p.dt = -1.0f;
    EXPECT_TRUE(contains(message(p), "dt")) << message(p);
    p = good;
    p.dt = std::nanf("");
    EXPECT_TRUE(contains(message(p), "(0, 0.1] s")) << message(p);
    p = good;
    p.air_drag = -0.1f;
    EXPECT_TRUE(contains(message(p), "air drag")) << message(p);
    p = good;
    p.gravity[1] = INFINITY;
    EXPECT_TRUE(contains(message(p), "gravity[1]")) << message(p);
    p = good;
    p.wind.strength = 1000.0f;
    EXPECT_TRUE(contains(message(p), "[0, 100]")) << message(p);
    EXPECT_EQ(message(good), "");
}

TEST(Stability, HangBuilderRejectsOutOfRangeValues) {
    HangParams hp;
    hp.n = 1;
    EXPECT_THROW(build_hang_scene(hp), InvalidInput);
    hp.n = 5000;
    EXPECT_THROW(build_hang_scene(hp), InvalidInput);
    hp.n = 10;
    hp.stiffness = 50.0f;
    try {
        build_hang_scene(hp);
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_TRUE(contains(e.what(), "stiffness")) << e.what();
        EXPECT_TRUE(contains(e.what(), "25000")) << e.what();
    }
}

} // namespace
