// The collide stage in the pipeline: cloth dropped onto each collider; no particle is inside any collider after any
// substep (core/src/collide.cpp; the geometry itself is tested in test_colliders.cpp).
#include <gtest/gtest.h>

#include "test_helpers.hpp"

using namespace drape;

namespace {

struct DropCase {
    const char* name;
    Collider collider;
    Integrator integ;
};

class CollideDrop : public ::testing::TestWithParam<DropCase> {};

TEST_P(CollideDrop, NoParticleInsideAfterAnySubstep) {
    const DropCase& c = GetParam();
    HangParams hp;
    hp.n = drape::testing::sanitized ? 28 : 40; // ASan: 14-36 s a collider with 40 (every particle every substep)
    hp.size = 1.2f;
    hp.pins = GridPins::none;
    SceneBuild scene = build_hang_scene(hp);
    for (float& y : scene.initial.y) y = 0.5f; // start above the collider
    SimulationParams p = drape::testing::default_params(scene.cloth, c.integ);
    p.colliders = {c.collider, make_ground(-0.6f)};
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    const std::size_t steps = static_cast<std::size_t>(1.2 / p.dt); // falls 0.5 m in ~0.32 s, then drapes
    std::size_t contacts = 0;
    for (std::size_t n = 0; n < steps; ++n) {
        sim.step(1);
        for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
            const Vec3f q{sim.x()[i], sim.y()[i], sim.z()[i]};
            for (const Collider& col : p.colliders)
                ASSERT_FALSE(is_inside(col, q, 1e-5f)) << c.name << ": particle " << i << " inside after substep " << n;
        }
    }
    for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
        const Vec3f q{sim.x()[i], sim.y()[i], sim.z()[i]};
        contacts += is_inside(c.collider, q, -2e-3f); // within 2 mm of the surface: resting on it
    }
    EXPECT_GT(contacts, 10u) << c.name << ": the cloth should rest on the collider";
    EXPECT_TRUE(sim.health().finite);
}

INSTANTIATE_TEST_SUITE_P(
    Colliders, CollideDrop,
    ::testing::Values(DropCase{"sphere", make_sphere({0.0f, 0.0f, 0.0f}, 0.3f), Integrator::symplectic_euler},
                      DropCase{"sphere_verlet", make_sphere({0.0f, 0.0f, 0.0f}, 0.3f), Integrator::verlet},
                      DropCase{"disc", make_disc({0.0f, 0.0f, 0.0f}, 0.3f, 0.05f), Integrator::symplectic_euler},
                      DropCase{"capsule", make_capsule({-0.3f, 0.0f, 0.0f}, {0.3f, 0.0f, 0.0f}, 0.15f),
                               Integrator::symplectic_euler},
                      DropCase{"ellipsoid", make_ellipsoid({0.0f, 0.0f, 0.0f}, {0.35f, 0.2f, 0.25f}),
                               Integrator::verlet},
                      DropCase{"ground", make_ground(-0.2f), Integrator::symplectic_euler}),
    [](const auto& info) { return std::string(info.param.name); });

} // namespace
