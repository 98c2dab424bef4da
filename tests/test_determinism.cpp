// Results are bitwise identical for every number of worker threads (DESIGN.md invariant). Each run happens
// inside a drape::Workers arena of exactly that many workers (1, 2, 3, 5 and 8: more than the cores of a
// small machine, so the workers really interleave), and every result equals the serial twin
// (Simulation::step_serial).
//
// Covered: every built-in scene (hang, drape, sphere, flag, tshirt) at a small size, with what the scene has
// (strain limiting, analytic and aerodynamic wind, seams, colliders in contact from the first substep), for
// both integrators, both spring kernels (grid scenes; the T-shirt has CSR only) and every solver in
// `solvers()`.
#include <gtest/gtest.h>

#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include "drape/scene.hpp"
#include "drape/workers.hpp"
#include "test_helpers.hpp"

using namespace drape;

namespace {

/// Release: 1, 2, 3, 5 and 8 workers. ASan (test_helpers.hpp): 1, 3 and 8 (one, an odd split, more workers than
/// blocks of some scenes): the sanitizers look for memory errors, which each split shows; Release compares the bits.
const std::vector<int> worker_counts =
    drape::testing::sanitized ? std::vector<int>{1, 3, 8} : std::vector<int>{1, 2, 3, 5, 8};

std::string worker_list() {
    std::string out;
    for (int w : worker_counts) out += (out.empty() ? "" : ", ") + std::to_string(w);
    return out + " workers";
}

/// Substeps of the N = 100 hang per run: ASan a quarter (its CSR variant took 64 s there with 200).
const std::size_t hang_steps = drape::testing::sanitized ? 50 : 200;

/// A way of advancing the cloth. drape has one solver today (explicit, with the integrator as a sub-choice);
/// a second one (e.g. implicit) is added here with whatever it needs set on the scene, and every scene,
/// integrator and kernel below is then checked with it too.
struct Solver {
    const char* name;
    std::function<void(SceneSpec&)> configure;
    std::size_t steps; ///< steps per run (an implicit step is a frame: 40 substeps ~ 8 implicit steps of work)
};
std::vector<Solver> solvers() {
    // ASan (test_helpers.hpp): half the explicit substeps, 3 implicit steps.
    return {{"explicit", [](SceneSpec&) {}, drape::testing::sanitized ? 20u : 40u},
            {"implicit",
             [](SceneSpec& s) {
                 s.physics.solver = drape::Solver::implicit;
                 s.physics.implicit.iterations = 12;
                 s.dt = 1.0f / 30.0f;
             },
             drape::testing::sanitized ? 3u : 8u}};
}

/// A built-in scene made small (a few thousand particles: several 1024-particle blocks, several collide and
/// strain chunks), with the cloth moved into contact with its colliders so the collide stage works from the
/// first substep.
SceneSpec small_scene(const std::string& name) {
    SceneSpec s = load_scene(name);
    if (s.cloth == ClothType::grid) s.grid.n = 72; // 5,184 particles = 6 blocks
    if (s.cloth == ClothType::tshirt) s.tshirt.cells_per_metre = 60;
    if (name == "drape") s.grid.centre[1] = 0.002f; // inside the disc's 4 mm margin
    if (name == "sphere") s.grid.centre[1] = 0.3f;  // the middle of the cloth inside the sphere's 5 mm margin
    if (name == "hang") s.physics.wind.enabled = true; // the analytic wind field on the plain scene too
    return s;
}

struct RunSpec {
    SceneSpec spec;
    Integrator integrator;
    KernelPath kernel;
    std::size_t steps;
};

/// Checksum after `r.steps` substeps with `workers` worker threads (0: the serial twin, step_serial).
std::uint64_t checksum(const RunSpec& r, int workers) {
    Workers arena(workers == 0 ? 1 : workers);
    return arena.run([&] {
        SceneSpec spec = r.spec;
        spec.physics.integrator = r.integrator;
        spec.physics.kernel = r.kernel;
        BuiltScene b = build_scene(spec);
        Simulation sim(std::move(b.cloth), b.initial, b.params);
        workers == 0 ? sim.step_serial(r.steps) : sim.step(r.steps);
        EXPECT_TRUE(sim.health().finite) << r.spec.name;
        return sim.checksum();
    });
}

class SceneDeterminism : public ::testing::TestWithParam<std::string> {};

TEST_P(SceneDeterminism, SameBitsAtEveryWorkerCountAndSerially) {
    for (const Solver& solver : solvers())
        for (Integrator integ : {Integrator::symplectic_euler, Integrator::verlet}) {
            SceneSpec spec = small_scene(GetParam());
            solver.configure(spec);
            if (spec.physics.solver == drape::Solver::implicit && integ == Integrator::verlet) continue;
            std::vector<KernelPath> kernels{KernelPath::csr};
            if (spec.cloth == ClothType::grid) kernels.push_back(KernelPath::grid);
            for (KernelPath kernel : kernels) {
                const RunSpec r{spec, integ, kernel, solver.steps};
                const std::uint64_t serial = checksum(r, 0);
                for (int w : worker_counts)
                    EXPECT_EQ(serial, checksum(r, w))
                        << GetParam() << ", " << solver.name << ", " << integrator_name(integ) << ", "
                        << kernel_path_name(kernel) << ": " << w << " workers";
                std::printf("[ checksum ] %s %s %s %s, %zu steps: %016llx (serial; %s)\n", GetParam().c_str(),
                            solver.name, integrator_name(integ), kernel_path_name(kernel), r.steps,
                            static_cast<unsigned long long>(serial), worker_list().c_str());
            }
        }
}

INSTANTIATE_TEST_SUITE_P(BuiltIn, SceneDeterminism, ::testing::ValuesIn(builtin_scene_names()),
                         [](const auto& info) { return info.param; });

TEST(SceneDeterminism, ScenesUseTheStagesTheyClaim) {
    // The scenes above really run what they are chosen for (otherwise their checks would prove less).
    auto stages = [](const std::string& name) {
        SceneSpec spec = small_scene(name);
        BuiltScene b = build_scene(spec);
        Simulation sim(std::move(b.cloth), b.initial, b.params);
        std::string all;
        for (const std::string& s : sim.stage_names())
            all += s + " ";
        return all;
    };
    EXPECT_NE(stages("drape").find("strain_limit"), std::string::npos);
    EXPECT_NE(stages("drape").find("collide"), std::string::npos);
    EXPECT_NE(stages("sphere").find("collide"), std::string::npos);
    EXPECT_NE(stages("flag").find("aero_forces"), std::string::npos);
    EXPECT_NE(stages("tshirt").find("seam_forces"), std::string::npos);
    EXPECT_NE(stages("tshirt").find("collide"), std::string::npos);
    // Contact from the first substep: a collider moves some particle of the drape and sphere scenes at once.
    for (const char* name : {"drape", "sphere"}) {
        SceneSpec spec = small_scene(name);
        BuiltScene b = build_scene(spec);
        SceneSpec free = spec;
        free.physics.colliders.clear();
        BuiltScene f = build_scene(free);
        Simulation with(std::move(b.cloth), b.initial, b.params),
            without(std::move(f.cloth), f.initial, f.params);
        with.step(1);
        without.step(1);
        EXPECT_NE(with.checksum(), without.checksum()) << name;
    }
}

// Hang variants at a larger size (10 blocks): wind on and off, both integrators, both kernels.
std::uint64_t hang_checksum(int workers, std::uint32_t n, bool wind, Integrator integ, KernelPath kernel,
                            std::size_t steps = 200, MaterialModel model = MaterialModel::springs) {
    Workers arena(workers);
    return arena.run([&] {
        HangParams hp;
        hp.n = n;
        hp.model = model;
        hp.fabric.damping = 1e-4f; // Rayleigh damping of springs and bending
        SceneBuild scene = build_hang_scene(hp);
        SimulationParams p = drape::testing::default_params(scene.cloth, integ, kernel);
        p.wind.enabled = wind;
        Simulation sim(std::move(scene.cloth), scene.initial, p);
        sim.step(steps);
        EXPECT_TRUE(sim.health().finite);
        return sim.checksum();
    });
}

struct DetCase {
    bool wind;
    Integrator integ;
    KernelPath kernel;
};

class Determinism : public ::testing::TestWithParam<DetCase> {};

TEST_P(Determinism, ChecksumIndependentOfWorkerCount) {
    const DetCase c = GetParam();
    // N = 100: 10,000 particles = 10 blocks, so every worker count really splits the cloth.
    const std::uint64_t one = hang_checksum(1, 100, c.wind, c.integ, c.kernel, hang_steps);
    for (int w : worker_counts) {
        if (w == 1) continue;
        EXPECT_EQ(one, hang_checksum(w, 100, c.wind, c.integ, c.kernel, hang_steps)) << w << " workers";
    }
    std::printf("[ checksum ] N=100 %zu substeps %s%s %s: %016llx (%s)\n", hang_steps, integrator_name(c.integ),
                c.wind ? " wind" : "", kernel_path_name(c.kernel), static_cast<unsigned long long>(one),
                worker_list().c_str());
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

// The fabric model (per-edge stiffness, bending from the grid stencil or Q's rows, Rayleigh damping), at 10 blocks.
TEST(Determinism, FabricModelIndependentOfWorkerCount) {
    const std::size_t steps = drape::testing::sanitized ? 50 : 200;
    for (KernelPath kernel : {KernelPath::grid, KernelPath::csr})
        for (Integrator integ : {Integrator::symplectic_euler, Integrator::verlet}) {
            const std::uint64_t one = hang_checksum(1, 100, true, integ, kernel, steps, MaterialModel::fabric);
            for (int w : {3, 8})
                EXPECT_EQ(one, hang_checksum(w, 100, true, integ, kernel, steps, MaterialModel::fabric))
                    << kernel_path_name(kernel) << " " << integrator_name(integ) << ": " << w << " workers";
            if (kernel == KernelPath::grid && integ == Integrator::symplectic_euler) {
                EXPECT_NE(one, hang_checksum(1, 100, true, integ, kernel, steps)) << "the fabric model differs from springs";
            }
            std::printf("[ checksum ] fabric N=100 %zu substeps %s wind %s: %016llx (1, 3, 8 workers)\n", steps,
                        integrator_name(integ), kernel_path_name(kernel), static_cast<unsigned long long>(one));
        }
}

TEST(Determinism, OddSizeWithPartialBatch) {
    const std::uint64_t one = hang_checksum(1, 77, true, Integrator::symplectic_euler, KernelPath::grid);
    for (int w : {2, 3, 5})
        EXPECT_EQ(one, hang_checksum(w, 77, true, Integrator::symplectic_euler, KernelPath::grid));
}

TEST(Determinism, RunsAreRepeatable) {
    EXPECT_EQ(hang_checksum(2, 64, true, Integrator::verlet, KernelPath::grid, 100),
              hang_checksum(2, 64, true, Integrator::verlet, KernelPath::grid, 100));
}

TEST(Determinism, WindChangesTheResult) { // the wind cases above really differ from the calm ones
    EXPECT_NE(hang_checksum(2, 40, true, Integrator::symplectic_euler, KernelPath::grid, 100),
              hang_checksum(2, 40, false, Integrator::symplectic_euler, KernelPath::grid, 100));
}

// The irregular stages (aero per triangle, seams in colour groups, strain limiting, collisions with the body)
// at a larger T-shirt with aerodynamic wind, over more substeps.
TEST(Determinism, GarmentStagesIndependentOfWorkerCount) {
    const std::size_t steps = drape::testing::sanitized ? 60 : 200; // ASan: 49 s with 200
    auto run = [steps](int workers) {
        Workers arena(workers);
        return arena.run([steps] {
            SceneSpec spec = load_scene("tshirt");
            spec.tshirt.cells_per_metre = 80; // ~5,100 particles: several blocks and chunks
            spec.physics.aero.enabled = true;
            BuiltScene b = build_scene(spec);
            Simulation sim(std::move(b.cloth), b.initial, b.params);
            sim.step(steps);
            EXPECT_TRUE(sim.health().finite);
            return sim.checksum();
        });
    };
    const std::uint64_t one = run(1);
    for (int w : {3, 8})
        EXPECT_EQ(one, run(w)) << w << " workers";
    std::printf("[ checksum ] tshirt (80 cells/m) + aero, %zu substeps: %016llx (1, 3, 8 workers)\n", steps,
                static_cast<unsigned long long>(one));
}

} // namespace
