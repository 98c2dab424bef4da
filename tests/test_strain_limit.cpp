// Provot strain limiting (core/src/strain_limit.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "drape/workers.hpp"
#include "test_helpers.hpp"

using namespace drape;

namespace {

Simulation soft_hang(std::uint32_t n, StrainLimit limit, Integrator integ = Integrator::symplectic_euler) {
    HangParams hp;
    hp.n = n;
    hp.stiffness = 100.0f; // soft: overstretches without limiting
    SceneBuild scene = build_hang_scene(hp);
    SimulationParams p = drape::testing::default_params(scene.cloth, integ);
    p.strain_limit = limit;
    return Simulation(std::move(scene.cloth), scene.initial, p);
}

// After the sweeps, every structural spring is within 1.05 x the limit (the sweeps go on while one is over it), at
// every sample of a 1 s run of a soft "hang" at N = 100 that overstretches by far without limiting.
TEST(StrainLimit, KeepsMaxStrainWithinTheLimitAtN100) {
    Simulation free_cloth = soft_hang(100, {0.0f, 1, 1});
    Simulation limited = soft_hang(100, {0.1f, 4, 1});
    // 0.4 s: the free cloth's first fall, where it overstretches most (measured: free 0.19 / 0.34 / 0.28 at t = 0.14 / 0.24 / 0.34 s, limited <= 0.1023).
    const std::size_t steps = static_cast<std::size_t>(0.4 / limited.params().dt);
    float worst = 0.0f, worst_free = 0.0f;
    for (std::size_t done = 0; done < steps; done += 250) {
        limited.step(250);
        free_cloth.step(250);
        worst = std::max(worst, limited.health().max_structural_strain);
        worst_free = std::max(worst_free, free_cloth.health().max_structural_strain);
    }
    EXPECT_GT(worst_free, 0.12f) << "the test needs a cloth that overstretches";
    EXPECT_LE(worst, 0.1f * 1.05f);
    EXPECT_TRUE(limited.health().finite);
}

TEST(StrainLimit, SweepRunsOutwardFromThePins) {
    Simulation sim = soft_hang(20, {0.1f, 1, 1});
    const ColourGroups& g = sim.strain_limit_groups();
    // Every spring touching a pinned corner is processed before every spring on the far edge (row N - 1).
    std::size_t last_pin_group = 0, first_far_group = g.group_count();
    for (std::size_t k = 0; k < g.group_count(); ++k)
        for (std::uint32_t e : g.group(k)) {
            const Edge& edge = sim.cloth().edges[e];
            if (sim.is_pinned(edge.a) || sim.is_pinned(edge.b)) last_pin_group = std::max(last_pin_group, k);
            if (edge.a >= 19 * 20 || edge.b >= 19 * 20) first_far_group = std::min(first_far_group, k);
        }
    EXPECT_LT(last_pin_group, first_far_group);
    EXPECT_GT(g.group_count(), 19u) << "at least one group per level";
}

TEST(StrainLimit, PinnedEndsStayPut) {
    Simulation sim = soft_hang(40, {0.05f, 4, 1});
    const float x0 = sim.x()[0], x1 = sim.x()[39];
    sim.step(2000);
    EXPECT_EQ(sim.x()[0], x0);
    EXPECT_EQ(sim.y()[0], 0.0f);
    EXPECT_EQ(sim.x()[39], x1);
    EXPECT_EQ(sim.y()[39], 0.0f);
}

TEST(StrainLimit, ColourGroupsShareNoParticleAndCoverEverySpringOnce) {
    Simulation sim = soft_hang(33, {0.1f, 1, 1});
    const ColourGroups& g = sim.strain_limit_groups();
    ASSERT_GT(g.group_count(), 0u);
    std::multiset<std::uint32_t> seen;
    for (std::size_t k = 0; k < g.group_count(); ++k) {
        std::set<std::uint32_t> touched;
        for (std::uint32_t e : g.group(k)) {
            seen.insert(e);
            if (sim.strain_limit_group_serial(k)) continue;
            const Edge& edge = sim.cloth().edges[e];
            EXPECT_TRUE(touched.insert(edge.a).second) << "group " << k << " reuses particle " << edge.a;
            EXPECT_TRUE(touched.insert(edge.b).second) << "group " << k << " reuses particle " << edge.b;
        }
    }
    std::size_t limited = 0;
    for (std::uint32_t e = 0; e < sim.cloth().edges.size(); ++e) {
        const bool bend = sim.cloth().edges[e].kind == SpringKind::bend;
        EXPECT_EQ(seen.count(e), bend ? 0u : 1u) << "edge " << e;
        limited += !bend;
    }
    EXPECT_EQ(seen.size(), limited);
}

TEST(StrainLimit, ThreadCountIndependentAndEqualToSerialTwin) {
    auto run = [](int threads, bool serial) {
        Workers workers(threads);
        return workers.run([&] {
            Simulation sim = soft_hang(120, {0.05f, 3, 1}); // 14,400 particles: groups of several chunks
            serial ? sim.step_serial(300) : sim.step(300);
            return sim.checksum();
        });
    };
    const std::uint64_t one = run(1, false);
    for (int t : {2, 3, 5, 8})
        EXPECT_EQ(one, run(t, false)) << t << " workers";
    EXPECT_EQ(one, run(2, true));
}

TEST(StrainLimit, IntervalStaysStableForBothIntegrators) {
    for (Integrator integ : {Integrator::symplectic_euler, Integrator::verlet}) {
        Simulation sim = soft_hang(60, {0.1f, 4, 8}, integ);
        sim.step(static_cast<std::size_t>(1.0 / sim.params().dt));
        const Health h = sim.health();
        EXPECT_TRUE(h.finite) << integrator_name(integ);
        EXPECT_LT(h.max_structural_strain, 0.15f) << integrator_name(integ);
    }
}

// The stage skips, in its later sweeps, the colour groups in which no particle moved since their last sweep
// (strain_limit_sweep.hpp). This reference sweeps every spring of every group in every pass, with the stage's
// formula written out again here, and must give the same bits: positions (and, in the explicit solver's form,
// velocities) of a cloth whose particles start scattered by up to 30 % of the spacing, so most springs are over the
// limit and the corrections run for many passes. Both forms: the explicit solver's (mass-weighted, shear springs,
// velocities) and the implicit solver's (one-sided from the pins, no shear springs, positions only, compression of
// structural springs bounded too).
TEST(StrainLimit, SkippingUnmovedGroupsKeepsTheBitsOfFullSweeps) {
    for (const bool frame : {false, true}) {
        HangParams hp;
        hp.n = 48;
        SceneBuild scene = build_hang_scene(hp);
        std::mt19937 rng(7);
        std::uniform_real_distribution<float> jitter(-1.0f, 1.0f);
        const float spacing = scene.cloth.edges.front().rest;
        for (std::vector<float>* a : {&scene.initial.x, &scene.initial.y, &scene.initial.z})
            for (float& v : *a) v += 0.3f * spacing * jitter(rng);
        SimulationParams p = drape::testing::default_params(scene.cloth);
        p.strain_limit = {0.05f, 4, 1};
        if (frame) {
            p.solver = Solver::implicit;
            p.dt = 1.0f / 30.0f;
        }
        Simulation sim(std::move(scene.cloth), scene.initial, p);
        const std::size_t n = sim.cloth().particle_count;
        std::vector<float> x(sim.x().begin(), sim.x().end()), y(sim.y().begin(), sim.y().end()),
            z(sim.z().begin(), sim.z().end()), u(n), v(n), w(n), inv_mass(n);
        for (std::size_t i = 0; i < n; ++i) {
            const std::array<float, 3> vel = sim.velocity(i);
            u[i] = vel[0];
            v[i] = vel[1];
            w[i] = vel[2];
            inv_mass[i] = sim.is_pinned(i) ? 0.0f : sim.cloth().inv_mass[i];
        }
        // The implicit form's levels: structural springs away from the pins, breadth first (shear springs do not count).
        const std::vector<Edge>& edges = sim.cloth().edges;
        std::vector<std::uint32_t> level(n, std::numeric_limits<std::uint32_t>::max()), queue;
        for (std::uint32_t i = 0; i < n; ++i)
            if (inv_mass[i] == 0.0f) {
                level[i] = 0;
                queue.push_back(i);
            }
        for (std::size_t head = 0; head < queue.size(); ++head)
            for (const Edge& e : edges) {
                if (e.kind == SpringKind::bend || e.kind == SpringKind::shear || (e.a != queue[head] && e.b != queue[head]))
                    continue;
                const std::uint32_t other = e.a == queue[head] ? e.b : e.a;
                if (level[other] == std::numeric_limits<std::uint32_t>::max()) {
                    level[other] = level[queue[head]] + 1;
                    queue.push_back(other);
                }
            }
        const float stretch = 1.0f + 0.05f, tolerated = 1.0f + 1.05f * 0.05f, vel_scale = 1.0f / p.dt;
        const float squeeze = 1.0f - 0.05f, squeeze_tolerated = 1.0f - 1.05f * 0.05f;
        const ColourGroups& g = sim.strain_limit_groups();
        std::uint32_t passes = 0, corrections = 0;
        for (bool over = true; over && passes < strain_limit_max_passes; ++passes) {
            over = passes < 3; // at least `passes` (4) sweeps
            for (std::size_t k = 0; k < g.group_count(); ++k)
                for (std::uint32_t ei : g.group(k)) {
                    const Edge& e = edges[ei];
                    if (frame && e.kind == SpringKind::shear) continue;
                    const std::uint32_t ia = e.a, ib = e.b;
                    const float dx = x[ib] - x[ia], dy = y[ib] - y[ia], dz = z[ib] - z[ia];
                    const float l2 = dx * dx + dy * dy + dz * dz;
                    float l_max = stretch * e.rest;
                    if (l2 > l_max * l_max) {
                        const float l_tol = tolerated * e.rest;
                        over = over || l2 > l_tol * l_tol;
                    } else { // the frame form also bounds compression: the ends move apart to squeeze x rest
                        const float l_min = squeeze * e.rest;
                        if (!frame || e.kind == SpringKind::seam || !(l2 < l_min * l_min) || l2 == 0.0f) continue;
                        const float l_tol = squeeze_tolerated * e.rest;
                        over = over || l2 < l_tol * l_tol;
                        l_max = l_min;
                    }
                    float wa = inv_mass[ia], wb = inv_mass[ib];
                    const bool one_sided = frame && passes < strain_limit_one_sided_passes;
                    if (one_sided && level[ia] < level[ib] && wb != 0.0f) wa = 0.0f;
                    if (one_sided && level[ib] < level[ia] && wa != 0.0f) wb = 0.0f;
                    if (wa + wb == 0.0f) continue;
                    const float l = std::sqrt(l2);
                    const float c = (l - l_max) / (l * (wa + wb));
                    const float ea = wa * c, eb = wb * c;
                    x[ia] += ea * dx;
                    y[ia] += ea * dy;
                    z[ia] += ea * dz;
                    x[ib] -= eb * dx;
                    y[ib] -= eb * dy;
                    z[ib] -= eb * dz;
                    ++corrections;
                    if (frame) continue;
                    u[ia] += ea * vel_scale * dx;
                    v[ia] += ea * vel_scale * dy;
                    w[ia] += ea * vel_scale * dz;
                    u[ib] -= eb * vel_scale * dx;
                    v[ib] -= eb * vel_scale * dy;
                    w[ib] -= eb * vel_scale * dz;
                }
        }
        EXPECT_GT(passes, 8u) << "the test needs corrections that run for many sweeps (frame form " << frame << ")";
        EXPECT_GT(corrections, n) << "frame form " << frame;
        sim.run_stage(Stage::strain_limit);
        std::size_t differ = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const std::array<float, 3> vel = sim.velocity(i);
            const bool same = sim.x()[i] == x[i] && sim.y()[i] == y[i] && sim.z()[i] == z[i] &&
                              (frame || (vel[0] == u[i] && vel[1] == v[i] && vel[2] == w[i]));
            differ += same ? 0 : 1;
        }
        EXPECT_EQ(differ, 0u) << "particles whose bits differ from full sweeps, frame form " << frame << ", after "
                              << passes << " reference sweeps";
    }
}

} // namespace
