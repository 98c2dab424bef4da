// The fabric model on a grid (build_hang_scene with MaterialModel::fabric, docs/fabric.md "Derived constants on a
// grid"): derived spring constants, node masses, the exact membrane response of the per-cell assembly, the
// stability bound with bending and Rayleigh damping, and a healthy hanging run.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "drape/errors.hpp"
#include "drape/health_monitor.hpp"
#include "drape/scene_hang.hpp"
#include "drape/simulation.hpp"
#include "drape/stability.hpp"
#include "scalar_reference.hpp"

using namespace drape;

namespace {

HangParams fabric_params(std::uint32_t n) {
    HangParams hp;
    hp.n = n;
    hp.model = MaterialModel::fabric;
    hp.fabric.density = 0.2f;
    hp.fabric.stretch_u = 6000.0f;
    hp.fabric.stretch_v = 2500.0f;
    hp.fabric.shear = 80.0f;
    hp.fabric.bend_u = 8e-6f;
    hp.fabric.bend_v = 3e-6f;
    hp.fabric.damping = 2e-4f;
    return hp;
}

TEST(FabricGrid, MembraneConstantsGiveTheFreeSidesStretchStiffness) {
    Fabric f;
    f.stretch_u = 6000.0f;
    f.stretch_v = 2500.0f;
    f.shear = 800.0f;
    const GridMembrane m = grid_membrane(f);
    const double c11 = double(m.ks_u) + m.kd, c22 = double(m.ks_v) + m.kd, c12 = m.kd;
    EXPECT_NEAR(c11 - c12 * c12 / c22, f.stretch_u, 1e-5 * f.stretch_u);
    EXPECT_NEAR(c22 - c12 * c12 / c11, f.stretch_v, 1e-5 * f.stretch_v);
    EXPECT_EQ(m.kd, f.shear);
    f.shear = 0.0f; // no shear: the springs are the stretch stiffnesses themselves
    EXPECT_EQ(grid_membrane(f).ks_u, 6000.0f);
    f.shear = 5000.0f; // more shear than the stretch can carry
    try {
        grid_membrane(f, "scene.json: material");
        ADD_FAILURE() << "a shear above the stretch stiffness was accepted";
    } catch (const InvalidInput& e) {
        EXPECT_NE(std::string(e.what()).find("scene.json: material.shear"), std::string::npos) << e.what();
    }
    HangParams hp = fabric_params(8);
    auto error_of = [](const HangParams& bad) -> std::string {
        try {
            build_hang_scene(bad);
        } catch (const InvalidInput& e) {
            return e.what();
        }
        return "accepted";
    };
    hp.fabric.density = 0.0f;
    EXPECT_NE(error_of(hp).find("fabric.density = 0 kg/m^2 is outside the allowed range (0, inf)"),
              std::string::npos)
        << error_of(hp);
    hp.fabric.density = 0.2f;
    hp.fabric.damping = std::numeric_limits<float>::infinity();
    EXPECT_NE(error_of(hp).find("fabric.damping = inf s is outside the allowed range [0, inf)"), std::string::npos)
        << error_of(hp);
}

TEST(FabricGrid, NodeMassesAddUpToDensityTimesArea) {
    const HangParams hp = fabric_params(9);
    const SceneBuild s = build_hang_scene(hp);
    const std::vector<float>& w = s.cloth.free_inv_mass;
    double total = 0.0;
    for (float v : w) total += 1.0 / v;
    EXPECT_NEAR(total, hp.fabric.density * hp.size * hp.size, 1e-6 * total);
    // Corner = 1/4 of an interior node, edge = 1/2.
    EXPECT_FLOAT_EQ(w[grid_index(9, 0, 4)] / w[grid_index(9, 4, 4)], 2.0f);
    EXPECT_FLOAT_EQ(w[grid_index(9, 8, 8)] / w[grid_index(9, 4, 4)], 4.0f);
    EXPECT_TRUE(s.cloth.bending.grid.has_value());
    for (const Edge& e : s.cloth.edges) EXPECT_NE(e.kind, SpringKind::bend) << "the fabric model has no bend springs";
}

/// Net spring force on every particle of an n x n fabric grid in a uniform membrane strain e_uu (with e_vv from the
/// free sides, e_vv = -C12 / C22 e_uu), or the transpose, from the scalar reference. Returns the worst interior /
/// side residual over E eps h and the total force on the far edge over E eps width.
struct StripResult {
    double residual = 0.0, load_ratio = 0.0;
};
StripResult strip(std::uint32_t n, bool along_u) {
    const HangParams hp = fabric_params(n);
    SceneBuild s = build_hang_scene(hp);
    const GridMembrane m = grid_membrane(hp.fabric);
    const double eps = 3e-4, c11 = double(m.ks_u) + m.kd, c22 = double(m.ks_v) + m.kd, c12 = m.kd;
    const double e_uu = along_u ? eps : -c12 / c11 * eps, e_vv = along_u ? -c12 / c22 * eps : eps;
    const double stiffness = along_u ? hp.fabric.stretch_u : hp.fabric.stretch_v;
    reference::State st;
    const double h = hp.size / (n - 1), width = hp.size;
    for (std::uint32_t j = 0; j < n; ++j) // in double: a float grid's rounding would be a strain of 1e-7 / h
        for (std::uint32_t i = 0; i < n; ++i) {
            st.x.push_back((i * h - 0.5 * hp.size) * (1.0 + e_uu));
            st.y.push_back(0.0);
            st.z.push_back((j * h - 0.5 * hp.size) * (1.0 + e_vv));
        }
    st.vx.assign(st.x.size(), 0.0);
    st.vy = st.vz = st.vx;
    const reference::Forces f = reference::spring_forces(s.cloth, st);
    StripResult r;
    double load = 0.0;
    for (std::uint32_t j = 0; j < n; ++j)
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::uint32_t k = grid_index(n, i, j);
            const std::uint32_t along = along_u ? i : j;
            if (along == n - 1) load += along_u ? f.fx[k] : f.fz[k]; // the pulled edge
            if (along == 0 || along == n - 1) continue;
            r.residual = std::max({r.residual, std::fabs(f.fx[k]), std::fabs(f.fy[k]), std::fabs(f.fz[k])});
        }
    r.residual /= stiffness * eps * h;
    r.load_ratio = -load / (stiffness * eps * width); // the springs pull the edge back: tension T = E eps
    return r;
}

TEST(FabricGrid, UniformStrainIsInEquilibriumWithTensionEtimesStrain) {
    // Per-cell assembly (half stiffness on boundary edges) makes the uniform free-sides strain an exact equilibrium
    // of a strip of any width: every particle but the pulled edges carries no net force, and the edge carries
    // T = E eps per unit width (linear in eps; eps = 3e-4 leaves O(eps) nonlinearity, and the float rest lengths
    // (h = 1/2^k exact, the diagonals rounded) 1e-7 / eps).
    for (std::uint32_t n : {5u, 9u, 33u})
        for (bool along_u : {true, false}) {
            const StripResult r = strip(n, along_u);
            EXPECT_LE(r.residual, 2e-3) << "n " << n << " along u " << along_u;
            EXPECT_NEAR(r.load_ratio, 1.0, 2e-3) << "n " << n << " along u " << along_u;
            RecordProperty("tension_ratio_n" + std::to_string(n) + (along_u ? "_u" : "_v"), std::to_string(r.load_ratio));
        }
}

/// Largest eigenvalue of M^-1 K at rest (springs linearised: k n n^T; bending: Q), movable particles, by power
/// iteration on the symmetric M^-1/2 K M^-1/2.
double omega2_max(const SceneBuild& s) {
    const Cloth& c = s.cloth;
    const std::size_t n = c.particle_count;
    const std::vector<BendTriplet> q = bending_hessian(c.bending.elements, n);
    std::vector<double> v(3 * n), out(3 * n);
    for (std::size_t i = 0; i < 3 * n; ++i) v[i] = std::sin(1.0 + 7.3 * i);
    double lambda = 0.0;
    for (int it = 0; it < 3000; ++it) {
        double norm = 0.0;
        for (double x : v) norm += x * x;
        norm = std::sqrt(norm);
        for (double& x : v) x /= norm;
        std::vector<double> u(3 * n); // M^-1/2 v
        for (std::size_t i = 0; i < n; ++i)
            for (int a = 0; a < 3; ++a) u[3 * i + a] = v[3 * i + a] * std::sqrt(double(c.inv_mass[i]));
        std::fill(out.begin(), out.end(), 0.0);
        for (const Edge& e : c.edges) {
            const double k = double(c.material[std::size_t(e.kind)].stiffness) * e.scale;
            const double d[3] = {double(s.initial.x[e.b]) - s.initial.x[e.a], double(s.initial.y[e.b]) - s.initial.y[e.a],
                                 double(s.initial.z[e.b]) - s.initial.z[e.a]};
            const double l = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            double proj = 0.0;
            for (int a = 0; a < 3; ++a) proj += d[a] / l * (u[3 * e.a + a] - u[3 * e.b + a]);
            for (int a = 0; a < 3; ++a) {
                out[3 * e.a + a] += k * proj * d[a] / l;
                out[3 * e.b + a] -= k * proj * d[a] / l;
            }
        }
        for (const BendTriplet& t : q)
            for (int a = 0; a < 3; ++a) out[3 * t.row + a] += t.value * u[3 * t.col + a];
        double dot = 0.0;
        for (std::size_t i = 0; i < n; ++i)
            for (int a = 0; a < 3; ++a) {
                out[3 * i + a] *= std::sqrt(double(c.inv_mass[i]));
                dot += out[3 * i + a] * v[3 * i + a];
            }
        lambda = dot;
        v = out;
    }
    return lambda;
}

TEST(FabricGrid, DefaultDtIsStableAndTheBoundIsNotLoose) {
    HangParams hp = fabric_params(16);
    hp.fabric.damping = 0.0f; // the undamped critical step is 2 / omega_max
    SceneBuild s = build_hang_scene(hp);
    const double w2 = omega2_max(s);
    const StabilityBound b = stability_bound(s.cloth, 0.0f);
    const double dt_critical = 2.0 / std::sqrt(w2);
    EXPECT_GE(b.omega2_max, w2 * (1.0 - 1e-6)) << "Gershgorin must bound the spectrum";
    EXPECT_LE(b.dt_max, dt_critical);
    EXPECT_GE(b.dt_max, dt_critical / 3.0) << "the bound should not be far below the true critical step";
    RecordProperty("dt_bound_over_critical", std::to_string(b.dt_max / dt_critical));
    // 20 % above the true critical step the run blows up: the 2000-substep run below can fail.
    auto run = [&](double dt, std::size_t steps, float damping) {
        HangParams p2 = hp;
        p2.fabric.damping = damping;
        SceneBuild sc = build_hang_scene(p2);
        SimulationParams p;
        p.air_drag = 0.0f;
        p.dt = static_cast<float>(dt);
        Simulation sim(std::move(sc.cloth), sc.initial, p);
        sim.step(steps);
        return sim.health().finite;
    };
    EXPECT_ANY_THROW(run(1.2 * dt_critical, 2000, 0.0f) ? throw SimulationError("still finite") : void());
    // The default dt (0.9 x the bound) holds for 2000 substeps, with and without Rayleigh damping.
    EXPECT_TRUE(run(0.9 * b.dt_max, 2000, 0.0f));
    HangParams damped = fabric_params(16);
    SceneBuild sd = build_hang_scene(damped);
    EXPECT_TRUE(run(default_dt(sd.cloth, 0.0f), 2000, damped.fabric.damping));
    EXPECT_LT(default_dt(sd.cloth, 0.0f), 0.9 * b.dt_max) << "Rayleigh damping lowers the bound";
}

TEST(FabricGrid, GridKernelOnlyForTheGridsOwnBending) {
    SceneBuild s = build_hang_scene(fabric_params(6));
    SimulationParams p;
    p.dt = static_cast<float>(default_dt(s.cloth, p.air_drag));
    EXPECT_EQ(Simulation(s.cloth, s.initial, p).kernel(), KernelPath::grid);
    // Other elements on the same grid (here: the rows only): the grid kernel's closed form no longer applies.
    std::vector<BendElement> rows = s.cloth.bending.elements;
    rows.resize(4 * 6);
    set_bending(s.cloth, rows, 0.0f);
    EXPECT_FALSE(s.cloth.bending.grid.has_value());
    EXPECT_EQ(Simulation(s.cloth, s.initial, p).kernel(), KernelPath::csr);
    p.kernel = KernelPath::grid;
    EXPECT_THROW(Simulation(s.cloth, s.initial, p), InvalidInput);
}

TEST(FabricGrid, HealthMonitorCountsTheBendingEnergy) {
    // A cloth started bent into a cylinder, at rest, without gravity: at the first check the energy bound is
    // energy_factor x (elastic energy at the start + the floor), and the elastic energy includes the bending energy.
    auto bound = [](bool bending) {
        HangParams hp = fabric_params(24);
        hp.fabric.bend_u = hp.fabric.bend_v = 1e-3f; // a bending energy far above the floor
        hp.pins = GridPins::none;
        SceneBuild s = build_hang_scene(hp);
        const double R = 0.3;
        for (std::size_t i = 0; i < s.initial.x.size(); ++i) {
            const double u = s.initial.x[i];
            s.initial.x[i] = float(R * std::sin(u / R));
            s.initial.y[i] = float(R * (1.0 - std::cos(u / R)));
        }
        const double e_bend =
            bending_energy(s.cloth.bending.elements, s.initial.x, s.initial.y, s.initial.z);
        if (!bending) set_bending(s.cloth, {}, 0.0f);
        SimulationParams p;
        p.gravity = {0.0f, 0.0f, 0.0f};
        p.dt = static_cast<float>(default_dt(s.cloth, p.air_drag));
        Simulation sim(std::move(s.cloth), s.initial, p);
        sim.step(HealthMonitor::check_every);
        return std::pair{sim.health().monitor.energy_bound, e_bend};
    };
    const auto [with, e_bend] = bound(true);
    const auto [without, unused] = bound(false);
    ASSERT_GT(e_bend, 1e-4);
    EXPECT_NEAR(with - without, HealthMonitor::energy_factor * e_bend, 1e-6 * with);
}

TEST(FabricGrid, HangsOneSecondHealthyAtN64) {
    HangParams hp = fabric_params(64);
    hp.fabric.damping = 1e-4f;
    SceneBuild s = build_hang_scene(hp);
    SimulationParams p;
    p.dt = static_cast<float>(default_dt(s.cloth, p.air_drag));
    Simulation sim(std::move(s.cloth), s.initial, p);
    const std::size_t steps = static_cast<std::size_t>(std::ceil(1.0 / p.dt));
    EXPECT_NO_THROW(sim.step(steps));
    const Health h = sim.health();
    EXPECT_TRUE(h.finite);
    EXPECT_TRUE(h.monitor.healthy);
    EXPECT_GT(h.monitor.substep, 0u);
    // It hangs: the free corners have fallen.
    EXPECT_LT(sim.y()[grid_index(64, 0, 63)], -0.1f);
}

} // namespace
