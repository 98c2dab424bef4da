// The T-shirt sewn shut and mirror-symmetric (issue 9 item 3): seams close to the cloth thickness, nothing inside the
// body, the settled shirt the mirror image of itself within the thickness.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "drape/colliders.hpp"
#include "drape/garment_figures.hpp"
#include "drape/tshirt.hpp"
#include "drape/scene.hpp"
#include "drape/simulation.hpp"
#include "drape/triangle_contact.hpp"
#include "drape/errors.hpp"

using namespace drape;

namespace {

// Fewest triangles of the cloth meeting any body collider (triangle_contact.hpp's exact test).
std::size_t triangles_in_body(const Simulation& sim) {
    const auto x = sim.x(), y = sim.y(), z = sim.z();
    const std::vector<std::uint32_t>& tri = sim.cloth().triangles;
    std::size_t count = 0;
    for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
        const Vec3f a{x[tri[t]], y[tri[t]], z[tri[t]]}, b{x[tri[t + 1]], y[tri[t + 1]], z[tri[t + 1]]},
            c{x[tri[t + 2]], y[tri[t + 2]], z[tri[t + 2]]};
        for (const Collider& col : sim.params().colliders)
            if (col.kind != ColliderKind::plane && triangle_meets_collider(col, a, b, c)) {
                ++count;
                break;
            }
    }
    return count;
}

// The built-in T-shirt (the seed's 1,008 particles): sewn at 0.5 m/s with gravity held off until every seam is
// closed, then dropped onto the body.
TEST(TShirtSewn, ClosesEverySeamSymmetricallyOutsideTheBody) {
    const SceneSpec spec = load_scene("tshirt");
    ASSERT_GT(spec.physics.sewing_speed, 0.0f);
    const std::vector<std::uint32_t> mirror = tshirt_mirror_map(spec.tshirt);
    BuiltScene b = build_scene(spec);
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    const GarmentFigures start = garment_figures(sim, mirror);
    EXPECT_NEAR(start.longest_seam, 0.26, 1e-3) << "the panels start a gap apart";
    EXPECT_LT(start.mirror_error, 1e-6);
    sim.step(static_cast<std::size_t>(2.5 / sim.params().dt));
    const float thickness = 0.005f; // the body's collision margin: the cloth's thickness against it
    const GarmentFigures f = garment_figures(sim, mirror, thickness);
    ASSERT_TRUE(f.finite);
    const float seam_rest = spec.tshirt.seam_rest_ratio / spec.tshirt.cells_per_metre;
    EXPECT_LE(seam_rest, thickness);
    EXPECT_LE(f.longest_seam, (1.0 + spec.physics.strain_limit.ratio) * seam_rest + 1e-5) << "a seam is open";
    // Mirror symmetry. Until the cloth meets the body the two halves differ by float rounding only (3e-7 m); the
    // folds that form under the arms then amplify that difference, and how far depends on the rounding, i.e. on the
    // SIMD width: with AVX-512 the whole shirt ends within 1.2-1.5 mm of its mirror image, with AVX2 one armpit fold
    // (20 of the 1,008 particles) falls the other way and ends up to 2.4 cm from it (docs/garments.md). So: the shirt
    // as a whole within the thickness (root mean square 0.26 mm / 2.5 mm), and at most 3 % of its particles farther.
    EXPECT_LE(f.mirror_rms, thickness) << "the shirt is not its own mirror image (rms)";
    EXPECT_LE(f.beyond, sim.cloth().particle_count * 3 / 100)
        << f.beyond << " particles are farther than the thickness from their twin's mirror image (worst: particle "
        << f.worst << ", " << f.mirror_error << " m)";
    EXPECT_EQ(f.inside, 0u) << "particles inside the body";
    EXPECT_EQ(triangles_in_body(sim), 0u) << "triangles through the body";
    // It hangs from the shoulders: the top row (shoulder line, sleeve tops) rests on the shoulders and arms, above
    // the armpits (y = 0.18), not below them.
    float lowest_top = 1e9f;
    const TShirtBuild t = build_tshirt(spec.tshirt);
    for (const MaskPanelBuild* panel : {&t.front, &t.back})
        for (std::int64_t c = 0; c < panel->columns; ++c)
            if (const std::int32_t i = panel->particle_at(0, c); i >= 0)
                lowest_top = std::min(lowest_top, float(sim.y()[std::size_t(i)] + sim.cloth().origin[1]));
    EXPECT_GT(lowest_top, 0.18f) << "the shirt slid off the shoulders";
}

// Without sewing the seams snap shut in the first substep: strain limiting pulls the 26 cm seams to their rest
// length at once, the panels' edges fly at tens of m/s. Sewing closes them at the set speed.
TEST(TShirtSewn, SewingClosesTheSeamsGentlyAndSnappingWideSeamsIsRefused) {
    auto fastest = [](float sewing_speed) {
        SceneSpec spec = load_scene("tshirt");
        spec.physics.sewing_speed = sewing_speed;
        BuiltScene b = build_scene(spec);
        Simulation sim(std::move(b.cloth), b.initial, b.params);
        float v = 0.0f;
        for (int k = 0; k < 20; ++k) {
            sim.step(static_cast<std::size_t>(0.01 / sim.params().dt));
            v = std::max(v, sim.health().max_speed);
        }
        return v;
    };
    const float sewn = fastest(0.5f);
    std::printf("fastest particle in the first 0.2 s: %.2f m/s sewn at 0.5 m/s\n", sewn);
    EXPECT_LT(sewn, 2.0f) << "sewing at 0.5 m/s moved a particle at " << sewn << " m/s";
    // Snapped shut (sewing speed 0), the 26 cm seams flung the panels at 15 m/s (docs/garments.md): refused, with the
    // remedy named.
    try {
        fastest(0.0f);
        ADD_FAILURE() << "a T-shirt whose seams start 26 cm open was accepted without sewing";
    } catch (const InvalidInput& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("sewing speed is 0"), std::string::npos) << what;
        EXPECT_NE(what.find("physics.sewing_speed, allowed (0, 10] m/s"), std::string::npos) << what;
    }
}

// Every seam that starts open is sewn by default, however narrow the gap: snapped shut, a seam a few millimetres
// open flings its particles at gap / dt (the canvas bag's 5 mm: 182 m/s in the first substep); one that starts short
// of its rest length is let out the same way. With sewing off (speed 0) a seam must start at its rest length, to
// within SimulationParams::unsewn_gap_ratio of the spacing; such seams run.
TEST(TShirtSewn, SeamsOffTheirRestLengthAreSewnByDefaultAndRefusedUnsewn) {
    // A 1 m square of cotton shirting (5 cm spacing) sewn to its copy along two sides; its seams' rest length is half
    // the spacing (copy.seam_rest_ratio 0.5), so a gap of 0.025 m is closed and 0.028 m is 3 mm open.
    auto square = [](double gap, const char* physics) {
        char text[512];
        std::snprintf(text, sizeof text,
                      R"({"cloth": {"type": "outline", "outline": [[0, 0], [1, 0], [1, 1], [0, 1]], "spacing": 0.05,
                          "copy": {"gap": %g, "sew": [[0, 3], [3, 0]]}}, "material": "cotton_shirting"%s})",
                      gap, physics);
        return build_scene(parse_scene(text, "square.json"));
    };
    auto fastest_after_one_substep = [](BuiltScene b) {
        Simulation sim(std::move(b.cloth), b.initial, b.params);
        sim.step(1);
        return sim.health().max_speed;
    };
    // With sewing off: the refusal's message (empty if the cloth was accepted).
    auto refusal_unsewn = [&](double gap) {
        try {
            fastest_after_one_substep(square(gap, R"(, "physics": {"sewing_speed": 0})"));
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_EQ(SimulationParams{}.sewing_speed, 0.5f);
    const float sewn = fastest_after_one_substep(square(0.028, ""));
    std::printf("seams 3 mm open: fastest particle after one substep %.3g m/s, sewn by default\n", sewn);
    EXPECT_LT(sewn, 1.0f) << "a seam 3 mm open was snapped shut instead of sewn";
    const std::string open = refusal_unsewn(0.028);
    EXPECT_NE(open.find("a seam is 0.003 m open"), std::string::npos) << "seams 3 mm open with sewing off: " << open;
    EXPECT_NE(open.find("sewing speed is 0"), std::string::npos) << open;
    EXPECT_NE(open.find("leave it out for the default 0.5"), std::string::npos) << open;
    // Panels placed closer than the seams' rest length (0.01 m: 15 mm short) were pushed apart at 110 m/s in the first
    // substep; the seams are let out to their rest length at the sewing speed instead.
    const float let_out = fastest_after_one_substep(square(0.01, ""));
    std::printf("seams 15 mm short: fastest particle after one substep %.3g m/s, let out by default\n", let_out);
    EXPECT_LT(let_out, 1.0f) << "a seam 15 mm short of its rest length pushed the panels apart at once";
    const std::string short_seams = refusal_unsewn(0.01);
    EXPECT_NE(short_seams.find("a seam is 0.015 m shorter than its rest length"), std::string::npos)
        << "seams 15 mm short with sewing off: " << short_seams;
    const float closed = fastest_after_one_substep(square(0.025, R"(, "physics": {"sewing_speed": 0})"));
    EXPECT_LT(closed, 0.01f) << "closed seams with sewing off moved the cloth";
}

// A seam between two pinned particles never closes: sewn, the seams beside it stretched the cloth between the pins
// without bound (the canvas bag's panels placed 2 m apart, pinned along their top edges: strain 16.7 in 100 implicit
// steps, reported healthy). Refused past 1.5 spacings off its rest; the bag as shipped (its top corners 5 mm off) runs.
TEST(TShirtSewn, ASeamBetweenPinsHeldApartIsRefused) {
    SceneSpec spec = load_scene(std::string(DRAPE_SOURCE_DIR) + "/scenes/examples/bag.json");
    {
        BuiltScene b = build_scene(spec);
        Simulation sim(std::move(b.cloth), b.initial, b.params);
        sim.step(10);
        EXPECT_TRUE(sim.health().finite);
    }
    for (float gap : {0.5f, 2.0f}) {
        spec.outline.gap = gap;
        BuiltScene b = build_scene(spec);
        try {
            Simulation sim(std::move(b.cloth), b.initial, b.params);
            ADD_FAILURE() << "panels " << gap << " m apart with pinned seam ends accepted";
        } catch (const InvalidInput& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("a seam joins two pinned particles"), std::string::npos) << what;
            EXPECT_NE(what.find("unpin one panel's edge (cloth.pins)"), std::string::npos) << what;
        }
    }
    spec.outline.pin_top = false; // unpinned, the panels 2 m apart are sewn together
    BuiltScene b = build_scene(spec);
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.step(10);
    EXPECT_TRUE(sim.health().finite);
}

// The schedule itself: a seam's current rest length is its start length minus speed x t, down to its rest; the
// health figures measure a seam against it (a seam on schedule is not "stretched").
TEST(TShirtSewn, SeamRestFollowsTheScheduleAndBadSpeedsAreRefused) {
    SceneSpec spec = load_scene("tshirt");
    spec.physics.strain_limit.ratio = 0.0f;
    BuiltScene b = build_scene(spec);
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.step(static_cast<std::size_t>(0.2 / sim.params().dt));
    // 0.2 s at 0.5 m/s: the 0.26 m seams have rest 0.16 m; the panels follow the schedule within a few mm.
    const SeamSet& s = sim.cloth().seams;
    for (std::size_t k = 0; k < s.a.size(); ++k) {
        const float dx = sim.x()[s.b[k]] - sim.x()[s.a[k]], dy = sim.y()[s.b[k]] - sim.y()[s.a[k]],
                    dz = sim.z()[s.b[k]] - sim.z()[s.a[k]];
        EXPECT_NEAR(std::sqrt(dx * dx + dy * dy + dz * dz), 0.26 - 0.5 * sim.time(), 0.01) << "seam " << k;
    }
    EXPECT_LT(sim.health().max_limited_stretch, 0.1f);
    EXPECT_FALSE(sim.seams_being_sewn().empty());
    SimulationParams p = sim.params();
    {   // Sewing switched off mid-run with the seams still 16 cm open: they would snap shut. Refused, nothing changed.
        SimulationParams off = p;
        off.sewing_speed = 0.0f;
        try {
            sim.set_params(off);
            ADD_FAILURE() << "sewing switched off with seams 16 cm open";
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find("would snap shut"), std::string::npos) << e.what();
        }
        EXPECT_EQ(sim.params().sewing_speed, 0.5f);
        sim.step(1);
        EXPECT_FALSE(sim.seams_being_sewn().empty());
    }
    for (float bad : {-0.1f, 10.5f, std::nanf("")}) {
        p.sewing_speed = bad;
        try {
            sim.set_params(p);
            ADD_FAILURE() << "sewing speed " << bad << " accepted";
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find("sewing speed"), std::string::npos) << e.what();
            EXPECT_NE(std::string(e.what()).find("[0, 10] m/s"), std::string::npos) << e.what();
        }
    }
}

// Issue 9: "a grabbed T-shirt hem dragged 30 cm and released stays on the body". The front hem is dragged 0.28 m
// forward and 0.1 m down over 0.5 s, then released. (With the strain limit at 10 % the knit could not give: the limit
// fought the grab until the health monitor stopped the run at 101 % strain; jersey is limited at 30 % now.)
// 4 s in Release: Release only (scripts/test.sh; its code paths - sewing, the body, a grab - run in the tests above).
TEST(TShirtSewn, HemDraggedThirtyCentimetresAndReleasedStaysOn) {
    const SceneSpec spec = load_scene("tshirt");
    BuiltScene b = build_scene(spec);
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    const float dt = sim.params().dt;
    sim.step(static_cast<std::size_t>(1.5 / dt));
    const TShirtBuild t = build_tshirt(spec.tshirt);
    struct TopRow {
        float lowest = 1e9f, cuff = 1e9f; // lowest top-row particle (y), the cuff nearest the body (|x|)
        std::size_t in_body = 0;
    };
    auto top_row = [&](const char* when) {
        TopRow r;
        for (const MaskPanelBuild* panel : {&t.front, &t.back})
            for (std::int64_t c = 0; c < panel->columns; ++c)
                if (const std::int32_t i = panel->particle_at(0, c); i >= 0) {
                    r.lowest = std::min(r.lowest, float(sim.y()[std::size_t(i)] + sim.cloth().origin[1]));
                    if (c == 0 || c == panel->columns - 1)
                        r.cuff = std::min(r.cuff, std::fabs(float(sim.x()[std::size_t(i)] + sim.cloth().origin[0])));
                }
        r.in_body = triangles_in_body(sim);
        std::printf("%s: lowest top-row particle y = %.3f m, the cuffs at |x| >= %.3f m, triangles in the body %zu\n",
                    when, r.lowest, r.cuff, r.in_body);
        return r;
    };
    const TopRow settled = top_row("settled");
    const std::size_t hem = std::size_t(t.front.particle_at(t.front.rows - 1, t.front.columns / 2));
    const std::array<float, 3> p0{sim.x()[hem], sim.y()[hem], sim.z()[hem]};
    sim.grab(hem, p0);
    const int moves = 50; // 0.5 s: 0.28 m forward and 0.1 m down, 0.30 m in all
    for (int k = 1; k <= moves; ++k) {
        const float s = float(k) / moves;
        sim.move_grab({p0[0], p0[1] - 0.1f * s, p0[2] + 0.28f * s});
        sim.step(static_cast<std::size_t>(0.01 / dt));
    }
    EXPECT_GT(sim.z()[hem], p0[2] + 0.25f) << "the hem was not dragged";
    const TopRow dragged = top_row("dragged");
    sim.release_grab();
    sim.step(static_cast<std::size_t>(1.5 / dt));
    const TopRow after = top_row("1.5 s after release");
    ASSERT_TRUE(sim.health().finite);
    for (const TopRow* r : {&settled, &dragged, &after}) {
        EXPECT_GT(r->lowest, 0.18f) << "the shoulder line slid below the armpits";
        EXPECT_GT(r->cuff, 0.38f) << "a sleeve rode up the arm";
        EXPECT_EQ(r->in_body, 0u) << "triangles through the body";
    }
    EXPECT_LT(sim.z()[hem], p0[2] + 0.1f) << "the hem did not fall back";
}

// The hand pushes the front hem into the body: 0.28 m back and 0.1 m down over 0.5 s, a path through the hips. The
// grabbed particle stops at the body's surface and slides on it (docs/collisions.md, "The hand and the colliders"):
// at no step is it inside a body collider, no triangle ends in the body, the strain limit holds, and the shirt stays
// on. Before, the particle went into the hips with the hand and the body pushed its neighbours out against the limit
// (measured with this test and the old grab: the hand inside the hips in 23, 30 and 25 of the 50 steps at 35, 30 and
// 50 cells/m, limited stretch 0.315, 0.616 and 0.758, the hem through the hips to the full 0.28 m). Both solvers: the
// implicit one needs its triangle contact terms on with self-collision (without them the hem slid under the hips and
// 26 triangles crossed the body during the push). DRAPE_CPM=C gives the figures of docs/collisions.md ("The hand and
// the colliders").
class HemPushed : public ::testing::TestWithParam<Solver> {};

TEST_P(HemPushed, IntoTheBodyStopsAtItsSurface) {
    SceneSpec spec = load_scene("tshirt");
    if (const char* c = std::getenv("DRAPE_CPM")) spec.tshirt.cells_per_metre = float(std::atof(c)); // figures in docs
    spec.physics.solver = GetParam();
    ASSERT_GT(spec.physics.self_collision.thickness, 0.0f);
    BuiltScene b = build_scene(spec);
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    const float dt = sim.params().dt;
    sim.step(static_cast<std::size_t>(1.5 / dt));
    const TShirtBuild t = build_tshirt(spec.tshirt);
    const std::size_t hem = std::size_t(t.front.particle_at(t.front.rows - 1, t.front.columns / 2));
    const std::array<float, 3> p0{sim.x()[hem], sim.y()[hem], sim.z()[hem]};
    sim.grab(hem, p0);
    std::size_t hand_inside = 0;
    float stretch = 0.0f;
    const int moves = 50;
    for (int k = 1; k <= moves; ++k) {
        const float s = float(k) / moves;
        sim.move_grab({p0[0], p0[1] - 0.1f * s, p0[2] - 0.28f * s});
        sim.step(std::max<std::size_t>(1, static_cast<std::size_t>(0.01 / dt + 0.5)));
        for (const Collider& c : sim.params().colliders)
            if (c.kind == ColliderKind::ellipsoid && is_inside(c, {sim.x()[hem], sim.y()[hem], sim.z()[hem]}, 1e-4f))
                ++hand_inside;
        stretch = std::max(stretch, sim.health().max_limited_stretch);
    }
    const std::size_t pushed_in_body = triangles_in_body(sim);
    const float hem_z = sim.z()[hem];
    sim.release_grab();
    sim.step(static_cast<std::size_t>(1.0 / dt));
    stretch = std::max(stretch, sim.health().max_limited_stretch);
    const GarmentFigures f = garment_figures(sim, tshirt_mirror_map(spec.tshirt), 0.005f);
    std::printf("pushed into the body: hand inside %zu of %d steps, hem moved back %.3f m, triangles in the body %zu "
                "(pushed) %zu (1 s after), largest limited stretch %.3f, particles inside %zu\n",
                hand_inside, moves, double(p0[2] - hem_z), pushed_in_body, triangles_in_body(sim), double(stretch),
                f.inside);
    ASSERT_TRUE(sim.health().finite);
    EXPECT_EQ(hand_inside, 0u) << "the hand pushed its particle into the body";
    EXPECT_GT(p0[2] - hem_z, 0.02f) << "the hem was not pushed against the body";
    EXPECT_EQ(pushed_in_body, 0u) << "triangles through the body during the push";
    EXPECT_EQ(triangles_in_body(sim), 0u) << "triangles through the body after release";
    EXPECT_EQ(f.inside, 0u) << "particles inside the body";
    EXPECT_LE(stretch, 1.1f * sim.params().strain_limit.ratio) << "the strain limit was not honoured";
}

INSTANTIATE_TEST_SUITE_P(TShirtSewn, HemPushed, ::testing::Values(Solver::explicit_euler, Solver::implicit),
                         [](const auto& info) {
                             return std::string(info.param == Solver::implicit ? "implicit" : "explicit");
                         });

// A saved state's seam_rest (state.seam_rest) must lie within 1.5 times the cloth's spacing of its seam's length: found by an
// adversarial sweep, 1e-30 m (the seam snapped shut) and 100 m (pushed the panels apart) were taken and the run
// stopped blaming "the state was changed from outside the simulation". The T-shirt's seams start 0.26 m open.
TEST(TShirtSewn, SavedSeamRestOffItsSeamIsRefused) {
    SceneSpec spec = load_scene("tshirt");
    const BuiltScene b = build_scene(spec);
    const std::size_t seams = b.cloth.seams.a.size();
    auto start = [&](float rest0) {
        InitialState st = b.initial;
        st.seam_rest.assign(seams, 0.26f); // on schedule: sewing starts from the positions
        st.seam_rest[0] = rest0;
        Simulation sim(b.cloth, st, b.params);
    };
    EXPECT_NO_THROW(start(0.26f));
    for (const auto& [rest0, what] : {std::pair{0.1f, "shorter than that seam"}, std::pair{100.0f, "longer than"}}) {
        try {
            start(rest0);
            ADD_FAILURE() << "seam_rest[0] = " << rest0 << " m accepted";
        } catch (const InvalidInput& e) {
            EXPECT_NE(std::string(e.what()).find(std::string("initial state seam_rest[0] = ")), std::string::npos)
                << e.what();
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    }
}

} // namespace
