// Precision far from the origin: positions are stored as float32 relative to the cloth's centre
// (Cloth::origin, in double), so a cloth 1000 m away behaves bitwise as the same cloth at the origin,
// colliders included, and the OBJ export adds the origin back. Before, a 1 cm cloth at (1000, 1000, 1000) m
// ended with max strain 0.30 against 0.007 at the origin (float32 spacing at 1000 m is 61 um, 9 % of this
// cloth's 0.67 mm springs).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "drape/scene.hpp"
#include "drape/simulation.hpp"
#include "obj_export.hpp"

using namespace drape;

namespace {

const std::string far_scene = std::string(DRAPE_SOURCE_DIR) + "/scenes/examples/far_from_origin.json";

Simulation simulate(const SceneSpec& spec, double seconds) {
    BuiltScene b = build_scene(spec);
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.step(static_cast<std::size_t>(std::ceil(seconds / double(sim.params().dt))));
    return sim;
}

TEST(FarFromOrigin, SmallClothAt1000mBehavesAsAtTheOrigin) {
    const SceneSpec far = load_scene(far_scene);
    ASSERT_EQ(far.grid.centre, (std::array<float, 3>{1000.0f, 1000.0f, 1000.0f}));
    SceneSpec near = far;
    near.grid.centre = {0.0f, 0.0f, 0.0f};
    for (Integrator integ : {Integrator::symplectic_euler, Integrator::verlet}) {
        SceneSpec f = far, n = near;
        f.physics.integrator = n.physics.integrator = integ;
        const Simulation a = simulate(f, 1.0), b = simulate(n, 1.0);
        EXPECT_EQ(a.origin(), (std::array<double, 3>{1000.0, 1000.0, 1000.0}));
        EXPECT_EQ(b.origin(), (std::array<double, 3>{0.0, 0.0, 0.0}));
        const Health ha = a.health(), hb = b.health();
        EXPECT_TRUE(ha.finite);
        EXPECT_LT(hb.max_structural_strain, 0.05f) << "the cloth at the origin hangs calmly";
        EXPECT_NEAR(ha.max_structural_strain, hb.max_structural_strain, 1e-6f) << integrator_name(integ);
        EXPECT_NEAR(ha.kinetic_energy, hb.kinetic_energy, 1e-9 + 1e-6 * hb.kinetic_energy);
        // The shape relative to the centre: the same to 1 nm (in fact the same bits).
        double worst = 0.0;
        for (std::size_t i = 0; i < a.cloth().particle_count; ++i)
            worst =
                std::max({worst, std::fabs(double(a.x()[i]) - b.x()[i]),
                          std::fabs(double(a.y()[i]) - b.y()[i]), std::fabs(double(a.z()[i]) - b.z()[i])});
        EXPECT_LT(worst, 1e-9) << integrator_name(integ);
        EXPECT_EQ(a.checksum(), b.checksum()) << integrator_name(integ);
    }
}

TEST(FarFromOrigin, AbsoluteFloatStorageWouldLoseIt) {
    // The test above can fail: the same cloth stored in absolute float32 coordinates (origin 0, positions at
    // 1000 m) is far from the calm cloth at the origin.
    BuiltScene b = build_scene(load_scene(far_scene));
    for (std::size_t i = 0; i < b.initial.x.size(); ++i) {
        b.initial.x[i] += 1000.0f;
        b.initial.y[i] += 1000.0f;
        b.initial.z[i] += 1000.0f;
    }
    b.cloth.origin = {0.0, 0.0, 0.0};
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.step(static_cast<std::size_t>(std::ceil(0.5 / double(sim.params().dt))));
    EXPECT_GT(sim.health().max_structural_strain, 0.1f);
}

TEST(FarFromOrigin, CollidersFarAwayStillCollide) {
    // The sphere scene moved by (1000, 1000, 1000) m (every coordinate exact in float32): the cloth drapes
    // over the sphere exactly as at the origin.
    SceneSpec far = load_scene("sphere");
    far.grid.n = 20;
    far.grid.centre = {1000.0f, 1000.0f, 1000.0f};
    far.physics.colliders = {make_sphere({1000.0f, 999.5f, 1000.0f}, 0.3f, {0.005f, 0.4f}),
                             make_ground(999.0f, {0.005f, 0.6f})};
    SceneSpec near = far;
    near.grid.centre = {0.0f, 0.0f, 0.0f};
    near.physics.colliders = {make_sphere({0.0f, -0.5f, 0.0f}, 0.3f, {0.005f, 0.4f}),
                              make_ground(-1.0f, {0.005f, 0.6f})};
    const Simulation a = simulate(far, 1.0), b = simulate(near, 1.0);
    EXPECT_EQ(a.checksum(), b.checksum());
    EXPECT_NEAR(a.health().max_structural_strain, b.health().max_structural_strain, 1e-6f);
    // It rests on the sphere: the middle particle sits on the sphere's top (relative y -0.5 + 0.3 + margin)
    // and the cloth has not fallen to the ground (relative y -1).
    const std::size_t mid = grid_index(20, 10, 10);
    EXPECT_NEAR(double(a.y()[mid]) + a.origin()[1], 999.805, 0.01);
    float lowest = INFINITY;
    for (float y : a.y())
        lowest = std::min(lowest, y);
    EXPECT_GT(lowest, -0.99f);
    // Without the colliders it would have fallen through.
    SceneSpec free = far;
    free.physics.colliders.clear();
    const Simulation c = simulate(free, 1.0);
    EXPECT_LT(double(c.y()[mid]) + c.origin()[1], 996.0);
}

TEST(FarFromOrigin, OutlineClothFarAwayToo) {
    // The bag (outline panels sewn, aero, strain limiting, a ground) at (1000, 1000, 1000) m and near the
    // origin, the ground 1 m below the cloth's centre in both (every coordinate exact in float32): the same
    // bits.
    SceneSpec near = load_scene(std::string(DRAPE_SOURCE_DIR) + "/scenes/examples/bag.json");
    ASSERT_EQ(near.physics.colliders.size(), 1u);
    SceneSpec far = near;
    near.outline.centre = {0.0f, 0.75f, 0.0f};
    near.physics.colliders = {make_ground(-0.25f, {0.005f, 0.6f})};
    far.outline.centre = {1000.0f, 1000.0f, 1000.0f};
    far.physics.colliders = {make_ground(999.0f, {0.005f, 0.6f})};
    BuiltScene a = build_scene(far), b = build_scene(near);
    Simulation sa(std::move(a.cloth), a.initial, a.params), sb(std::move(b.cloth), b.initial, b.params);
    const std::uint64_t start = sa.checksum();
    sa.step(300);
    sb.step(300);
    EXPECT_EQ(sa.origin(), (std::array<double, 3>{1000.0, 1000.0, 1000.0}));
    EXPECT_EQ(sa.checksum(), sb.checksum());
    EXPECT_NE(sa.checksum(), start) << "300 substeps moved the bag";
}

TEST(FarFromOrigin, ObjExportAddsTheOriginBackInDouble) {
    BuiltScene b = build_scene(load_scene(far_scene));
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.step(200);
    const auto dir = std::filesystem::temp_directory_path() / "drape_obj_far_test";
    std::filesystem::remove_all(dir);
    app::ObjExporter exporter(sim.cloth(), dir.string());
    std::ifstream in(exporter.write(sim, 0));
    std::string line;
    std::size_t i = 0;
    while (std::getline(in, line))
        if (line.rfind("v ", 0) == 0) {
            double x, y, z;
            ASSERT_EQ(std::sscanf(line.c_str(), "v %lf %lf %lf", &x, &y, &z), 3) << line;
            EXPECT_NEAR(x, 1000.0 + double(sim.x()[i]), 1e-8);
            EXPECT_NEAR(y, 1000.0 + double(sim.y()[i]), 1e-8);
            EXPECT_NEAR(z, 1000.0 + double(sim.z()[i]), 1e-8);
            ++i;
        }
    EXPECT_EQ(i, sim.cloth().particle_count);
    std::filesystem::remove_all(dir);
}

TEST(FarFromOrigin, WindFieldKeepsItsWorldPhase) {
    // Seed 000's wind depends on the world z (sin(z + 10 t)): a cloth centred at z = 0.5 m (its frame) moves
    // as the same cloth stored in world coordinates (origin 0), to float rounding (which grows over 2,000
    // substeps of a swinging cloth: ~0.1 mm of its 0.77 m motion).
    SceneSpec spec = load_scene("hang");
    // The seeds' springs (per-spring damping): the lightly damped wool flaps chaotically in this gale, where float
    // rounding alone grows to centimetres (0.13 m measured) and would hide the phase.
    spec.model = MaterialModel::springs;
    spec.grid.n = 16;
    spec.grid.centre = {0.0f, 0.0f, 0.5f};
    spec.physics.wind = {true, 20.0f};
    BuiltScene framed = build_scene(spec), world = build_scene(spec);
    for (float& z : world.initial.z)
        z += 0.5f;
    world.cloth.origin = {0.0, 0.0, 0.0};
    Simulation a(std::move(framed.cloth), framed.initial, framed.params);
    Simulation b(std::move(world.cloth), world.initial, world.params);
    a.step(2000);
    b.step(2000);
    double worst = 0.0, moved = 0.0;
    for (std::size_t i = 0; i < a.cloth().particle_count; ++i) {
        worst = std::max(worst, std::fabs(double(a.z()[i]) + 0.5 - double(b.z()[i])));
        moved = std::max(moved, std::fabs(double(b.z()[i]) - double(world.initial.z[i])));
    }
    EXPECT_LT(worst, 1e-3);
    EXPECT_GT(moved, 1e-3) << "the wind really moved the cloth along z";
    // With the phase ignored (the cloth's frame at z = 0), the result differs by far more.
    SceneSpec at_zero = spec;
    at_zero.grid.centre = {0.0f, 0.0f, 0.0f};
    BuiltScene z0 = build_scene(at_zero);
    Simulation c(std::move(z0.cloth), z0.initial, z0.params);
    c.step(2000);
    double apart = 0.0;
    for (std::size_t i = 0; i < c.cloth().particle_count; ++i)
        apart = std::max(apart, std::fabs(double(a.z()[i]) - double(c.z()[i])));
    std::printf("wind phase: framed vs world %.3g m, moved %.3g m, phase ignored %.3g m\n", worst, moved,
                apart);
    EXPECT_GT(apart, 30 * worst);
}

TEST(FarFromOrigin, ScenesAreBuiltInTheClothsFrame) {
    // The colliders move into the cloth's frame with it.
    SceneSpec s = load_scene("sphere");
    s.grid.n = 10;
    const BuiltScene b = build_scene(s);
    EXPECT_EQ(b.cloth.origin[1], double(s.grid.centre[1]));
    EXPECT_FLOAT_EQ(b.params.colliders[0].centre[1], float(0.0 - double(s.grid.centre[1])));
    float mean_y = 0.0f;
    for (float y : b.initial.y)
        mean_y += y;
    EXPECT_EQ(mean_y, 0.0f) << "a flat cloth at its own centre";
}

} // namespace

// The example with the implicit solver: a flat, light (1 g), stiff (1000 N/m) cloth has no out-of-plane stiffness in
// its local Hessians while the energy grows like the fourth power of a move across it, so its first local steps need
// many halvings. With 8 every one was dropped: the cloth never moved (kinetic energy exactly 0, residual 1, at any
// iteration count). It now swings down about its pinned corners.
TEST(FarFromOrigin, TheExampleMovesWithTheImplicitSolver) {
    SceneSpec spec = load_scene(far_scene);
    spec.physics.solver = Solver::implicit;
    spec.dt = 1.0f / 30.0f;
    BuiltScene b = build_scene(spec);
    Simulation sim(b.cloth, b.initial, b.params);
    sim.step(3); // 0.1 s
    double lowest = 0.0;
    for (std::size_t i = 0; i < b.cloth.particle_count; ++i) lowest = std::min(lowest, double(sim.y()[i] - b.initial.y[i]));
    EXPECT_LT(lowest, -1e-3) << "m: the lowest particle's fall after 0.1 s"; // a 1 cm cloth swinging about its pins
    EXPECT_TRUE(sim.health().finite);
}
