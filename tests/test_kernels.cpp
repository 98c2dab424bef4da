// The SIMD kernels against the plain scalar reference (tests/scalar_reference.cpp), on random perturbed states,
// and the kernel variants (grid stencil / CSR, fused / staged, parallel / serial) against each other.
#include <gtest/gtest.h>

#include <cmath>

#include "scalar_reference.hpp"
#include "test_helpers.hpp"

using namespace drape;
using drape::testing::default_params;
using drape::testing::perturbed_hang;

namespace {

struct KernelCase {
    KernelPath kernel;
    Integrator integrator;
};

class KernelVsReference : public ::testing::TestWithParam<KernelCase> {};

TEST_P(KernelVsReference, SpringForcesMatchScalarReference) {
    const KernelCase kc = GetParam();
    for (std::uint32_t n : {5u, 23u, 40u}) {
        SceneBuild scene = perturbed_hang(n, 0.3f, 0.5f, 1234 + n);
        SimulationParams p = default_params(scene.cloth, kc.integrator, kc.kernel);
        p.fused = false;
        Simulation sim(std::move(scene.cloth), scene.initial, p);
        const reference::State st = reference::read_state(sim);
        const reference::Forces ref = reference::spring_forces(sim.cloth(), st);
        sim.run_stage(Stage::spring_forces);
        const auto out = sim.stage_output();
        double worst = 0.0;
        for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
            const double scale = ref.scale[i] + 1e-30;
            worst = std::max({worst, std::fabs(out.fx[i] - ref.fx[i]) / scale, std::fabs(out.fy[i] - ref.fy[i]) / scale,
                              std::fabs(out.fz[i] - ref.fz[i]) / scale});
        }
        EXPECT_LE(worst, 1e-5) << "n = " << n;
        RecordProperty("worst_relative_error_n" + std::to_string(n), std::to_string(worst));
    }
}

TEST_P(KernelVsReference, ExternalAccelerationMatchesScalarReference) {
    const KernelCase kc = GetParam();
    SceneBuild scene = perturbed_hang(21, 0.3f, 0.5f, 77);
    SimulationParams p = default_params(scene.cloth, kc.integrator, kc.kernel);
    p.wind.enabled = true;
    p.air_drag = 0.7f;
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    sim.step(37); // a non-zero time for the wind field
    const reference::State st = reference::read_state(sim);
    std::vector<double> ax, ay, az;
    reference::external_acceleration(sim.cloth(), p, st, sim.time(), ax, ay, az);
    sim.run_stage(Stage::external_forces);
    const auto out = sim.stage_output();
    for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
        const double scale = 10.0 + std::fabs(ay[i]); // m/s^2: gravity sets the scale
        ASSERT_NEAR(out.ax[i], ax[i], 1e-5 * scale) << i;
        ASSERT_NEAR(out.ay[i], ay[i], 1e-5 * scale) << i;
        ASSERT_NEAR(out.az[i], az[i], 1e-5 * scale) << i;
    }
}

TEST_P(KernelVsReference, WholeSubstepMatchesScalarReference) {
    const KernelCase kc = GetParam();
    SceneBuild scene = perturbed_hang(31, 0.3f, 0.5f, 99);
    SimulationParams p = default_params(scene.cloth, kc.integrator, kc.kernel);
    p.wind.enabled = true;
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    sim.step(3);
    const reference::State before = reference::read_state(sim);
    const reference::Forces f = reference::spring_forces(sim.cloth(), before);
    const reference::State ref = reference::step_euler(sim.cloth(), p, before, sim.time());
    sim.step(1);
    const reference::State got = reference::read_state(sim);
    const double dt = p.dt;
    double worst_v = 0.0, worst_x = 0.0;
    for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
        // Scale of the velocity change: dt * (|spring terms| / m + |external|), plus |v| for rounding of v itself.
        const double dv_scale = dt * (sim.cloth().inv_mass[i] * f.scale[i] + 20.0) +
                                std::fabs(before.vx[i]) + std::fabs(before.vy[i]) + std::fabs(before.vz[i]) + 1e-12;
        worst_v = std::max({worst_v, std::fabs(got.vx[i] - ref.vx[i]) / dv_scale,
                            std::fabs(got.vy[i] - ref.vy[i]) / dv_scale, std::fabs(got.vz[i] - ref.vz[i]) / dv_scale});
        // Positions: the step's displacement sets the scale (|x| itself would hide errors).
        const double dx_scale = dt * dv_scale + 1e-7 * (std::fabs(before.x[i]) + std::fabs(before.z[i]) + 1.0);
        worst_x = std::max({worst_x, std::fabs(got.x[i] - ref.x[i]) / dx_scale,
                            std::fabs(got.y[i] - ref.y[i]) / dx_scale, std::fabs(got.z[i] - ref.z[i]) / dx_scale});
    }
    // Verlet stores the displacement x - x_prev (v dt): its velocity carries one more rounding (the division by dt).
    const double tol = 1e-5;
    EXPECT_LE(worst_v, tol);
    EXPECT_LE(worst_x, tol);
}

INSTANTIATE_TEST_SUITE_P(Paths, KernelVsReference,
                         ::testing::Values(KernelCase{KernelPath::grid, Integrator::symplectic_euler},
                                           KernelCase{KernelPath::csr, Integrator::symplectic_euler},
                                           KernelCase{KernelPath::grid, Integrator::verlet},
                                           KernelCase{KernelPath::csr, Integrator::verlet}),
                         [](const auto& info) {
                             return std::string(kernel_path_name(info.param.kernel)) + "_" +
                                    integrator_name(info.param.integrator);
                         });

/// Runs `steps` substeps of a perturbed 37x37 hang (odd size: a partial last SIMD batch) and returns the checksum.
std::uint64_t run_variant(KernelPath kernel, bool fused, bool serial, Integrator integ, bool wind, int steps = 60) {
    SceneBuild scene = perturbed_hang(37, 0.2f, 0.3f, 5);
    SimulationParams p = default_params(scene.cloth, integ, kernel);
    p.fused = fused;
    p.wind.enabled = wind;
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    serial ? sim.step_serial(steps) : sim.step(steps);
    return sim.checksum();
}

// The grid stencil sums the same terms in the same order as the sorted CSR row with the same operations, so the two
// paths agree bit for bit (a stronger form of "within float rounding").
TEST(KernelVariants, GridStencilEqualsCsrBitwise) {
    for (Integrator integ : {Integrator::symplectic_euler, Integrator::verlet})
        for (bool wind : {false, true})
            EXPECT_EQ(run_variant(KernelPath::grid, true, false, integ, wind),
                      run_variant(KernelPath::csr, true, false, integ, wind))
                << integrator_name(integ) << " wind " << wind;
}

TEST(KernelVariants, FusedEqualsStagedBitwise) {
    for (KernelPath k : {KernelPath::grid, KernelPath::csr})
        for (Integrator integ : {Integrator::symplectic_euler, Integrator::verlet})
            EXPECT_EQ(run_variant(k, true, false, integ, true), run_variant(k, false, false, integ, true))
                << kernel_path_name(k) << " " << integrator_name(integ);
}

TEST(KernelVariants, ParallelEqualsSerialTwinBitwise) {
    for (KernelPath k : {KernelPath::grid, KernelPath::csr})
        for (bool fused : {true, false})
            EXPECT_EQ(run_variant(k, fused, false, Integrator::symplectic_euler, true),
                      run_variant(k, fused, true, Integrator::symplectic_euler, true));
}

TEST(KernelVariants, StateChangesAtAll) { // guards the tests above against comparing two frozen states
    SceneBuild scene = perturbed_hang(37, 0.2f, 0.3f, 5);
    const SimulationParams p = default_params(scene.cloth);
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    const std::uint64_t before = sim.checksum();
    sim.step(1);
    EXPECT_NE(before, sim.checksum());
}

// ---- The fabric model (MaterialModel::fabric): membrane springs with per-edge stiffness, bending, Rayleigh damping.

/// A soft, stiff-bending fabric, so that at N ~ 20-40 the bending forces are as large as the membrane's (with a real
/// fabric they are 1e-6 of it and an error in them would hide in the springs' rounding).
HangParams fabric_hang() {
    HangParams hp;
    hp.model = MaterialModel::fabric;
    hp.fabric.density = 0.2f;
    hp.fabric.stretch_u = 20.0f;
    hp.fabric.stretch_v = 30.0f;
    hp.fabric.shear = 2.0f;
    hp.fabric.bend_u = 2e-3f;
    hp.fabric.bend_v = 1e-3f;
    hp.fabric.damping = 0.02f;
    return hp;
}

class FabricVsReference : public ::testing::TestWithParam<KernelCase> {};

TEST_P(FabricVsReference, ForcesMatchScalarReference) {
    const KernelCase kc = GetParam();
    for (std::uint32_t n : {5u, 23u, 40u}) {
        SceneBuild scene = perturbed_hang(n, 0.3f, 0.5f, 4321 + n, fabric_hang());
        SimulationParams p = default_params(scene.cloth, kc.integrator, kc.kernel);
        p.fused = false;
        Simulation sim(std::move(scene.cloth), scene.initial, p);
        ASSERT_EQ(sim.kernel(), kc.kernel);
        const reference::State st = reference::read_state(sim);
        const reference::Forces ref = reference::spring_forces(sim.cloth(), st);
        Cloth no_bending = sim.cloth();
        no_bending.bending = BendingSet{};
        const reference::Forces springs_only = reference::spring_forces(no_bending, st);
        sim.run_stage(Stage::spring_forces);
        const auto out = sim.stage_output();
        double worst = 0.0, bending_share = 0.0;
        for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
            const double scale = ref.scale[i] + 1e-30;
            worst = std::max({worst, std::fabs(out.fx[i] - ref.fx[i]) / scale, std::fabs(out.fy[i] - ref.fy[i]) / scale,
                              std::fabs(out.fz[i] - ref.fz[i]) / scale});
            bending_share = std::max({bending_share, std::fabs(springs_only.fx[i] - ref.fx[i]) / scale,
                                      std::fabs(springs_only.fy[i] - ref.fy[i]) / scale});
        }
        // Verlet's velocity difference is (u_j - u_i) / dt of the stored displacements: no digits lost (with x_prev
        // stored it lost those of x - x_prev, which beta / dt ~ 300 amplified: 2.7e-5 measured then).
        EXPECT_LE(worst, 1e-5) << "n = " << n;
        if (n > 5) {
            EXPECT_GE(bending_share, 1e3 * 1e-5) << "n = " << n << ": bending must matter in this test";
        }
        RecordProperty("worst_relative_error_n" + std::to_string(n), std::to_string(worst));
    }
}

TEST_P(FabricVsReference, WholeSubstepMatchesScalarReference) {
    const KernelCase kc = GetParam();
    SceneBuild scene = perturbed_hang(31, 0.3f, 0.5f, 98, fabric_hang());
    SimulationParams p = default_params(scene.cloth, kc.integrator, kc.kernel);
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    sim.step(3);
    const reference::State before = reference::read_state(sim);
    const reference::Forces f = reference::spring_forces(sim.cloth(), before);
    const reference::State ref = reference::step_euler(sim.cloth(), p, before, sim.time());
    sim.step(1);
    const reference::State got = reference::read_state(sim);
    const double dt = p.dt;
    double worst_v = 0.0, worst_x = 0.0;
    for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
        const double dv_scale = dt * (sim.cloth().inv_mass[i] * f.scale[i] + 20.0) + std::fabs(before.vx[i]) +
                                std::fabs(before.vy[i]) + std::fabs(before.vz[i]) + 1e-12;
        worst_v = std::max({worst_v, std::fabs(got.vx[i] - ref.vx[i]) / dv_scale,
                            std::fabs(got.vy[i] - ref.vy[i]) / dv_scale, std::fabs(got.vz[i] - ref.vz[i]) / dv_scale});
        // Positions: the step's displacement sets the scale, after one float rounding of the new position itself (this
        // soft fabric's substep, 7e-5 s, moves a particle by a few ulps of its coordinate).
        const double dx_scale = dt * dv_scale;
        auto err = [&](double g, double r) { return std::max(0.0, std::fabs(g - r) - 1.2e-7 * std::fabs(r)) / dx_scale; };
        worst_x = std::max({worst_x, err(got.x[i], ref.x[i]), err(got.y[i], ref.y[i]), err(got.z[i], ref.z[i])});
    }
    // Both integrators to 1e-5 (Verlet's stored displacement keeps its digits; with x_prev stored it needed 1e-3).
    EXPECT_LE(worst_v, 1e-5);
    EXPECT_LE(worst_x, 1e-5);
}

INSTANTIATE_TEST_SUITE_P(Paths, FabricVsReference,
                         ::testing::Values(KernelCase{KernelPath::grid, Integrator::symplectic_euler},
                                           KernelCase{KernelPath::csr, Integrator::symplectic_euler},
                                           KernelCase{KernelPath::grid, Integrator::verlet},
                                           KernelCase{KernelPath::csr, Integrator::verlet}),
                         [](const auto& info) {
                             return std::string(kernel_path_name(info.param.kernel)) + "_" +
                                    integrator_name(info.param.integrator);
                         });

Simulation fabric_run(KernelPath kernel, bool fused, bool serial, Integrator integ, int steps = 60) {
    SceneBuild scene = perturbed_hang(37, 0.2f, 0.3f, 6, fabric_hang());
    SimulationParams p = default_params(scene.cloth, integ, kernel);
    p.fused = fused;
    p.wind.enabled = true;
    Simulation sim(std::move(scene.cloth), scene.initial, p);
    serial ? sim.step_serial(steps) : sim.step(steps);
    return sim;
}

// The grid stencil computes each entry of Q's row from the mask (one rounding of an exact sum, as the assembled row
// holds it) and sums springs, then bending, in ascending neighbour order like the CSR path: bit for bit equal.
TEST(FabricVariants, GridStencilEqualsCsrBitwise) {
    for (Integrator integ : {Integrator::symplectic_euler, Integrator::verlet}) {
        const Simulation grid = fabric_run(KernelPath::grid, true, false, integ);
        EXPECT_EQ(grid.checksum(), fabric_run(KernelPath::csr, true, false, integ).checksum()) << integrator_name(integ);
        EXPECT_NE(grid.checksum(), fabric_run(KernelPath::grid, true, false, integ, 59).checksum());
    }
}

// A fabric grid without its bending runs the springs kernel, which honours the boundary halves (Edge::scale 1/2).
TEST(FabricVariants, MembraneAloneGridEqualsCsrBitwise) {
    auto run = [](KernelPath kernel) {
        SceneBuild scene = perturbed_hang(37, 0.2f, 0.3f, 6, fabric_hang());
        set_bending(scene.cloth, {}, 0.0f);
        const SimulationParams p = default_params(scene.cloth, Integrator::symplectic_euler, kernel);
        Simulation sim(std::move(scene.cloth), scene.initial, p);
        sim.step(60);
        return sim.checksum();
    };
    EXPECT_EQ(run(KernelPath::grid), run(KernelPath::csr));
}

TEST(FabricVariants, FusedEqualsStagedAndParallelEqualsSerialBitwise) {
    for (KernelPath k : {KernelPath::grid, KernelPath::csr})
        for (Integrator integ : {Integrator::symplectic_euler, Integrator::verlet}) {
            const std::uint64_t fused = fabric_run(k, true, false, integ).checksum();
            EXPECT_EQ(fused, fabric_run(k, false, false, integ).checksum())
                << kernel_path_name(k) << " " << integrator_name(integ);
            EXPECT_EQ(fused, fabric_run(k, true, true, integ).checksum())
                << kernel_path_name(k) << " " << integrator_name(integ);
        }
}

} // namespace
