// Scene writer: every scene written and read back is the same scene; a saved state continues bit-identically.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <cmath>
#include <unistd.h>

#include "drape/scene.hpp"
#include "drape/scene_write.hpp"
#include "test_helpers.hpp"

using namespace drape;

namespace {

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

template <class T> bool same_bits(const T& a, const T& b) { return std::memcmp(&a, &b, sizeof(T)) == 0; }

void expect_same_collider(const Collider& a, const Collider& b, const std::string& what) {
    EXPECT_EQ(a.kind, b.kind) << what;
    EXPECT_TRUE(same_bits(a.thickness, b.thickness)) << what;
    EXPECT_TRUE(same_bits(a.friction, b.friction)) << what;
    EXPECT_TRUE(same_bits(a.centre, b.centre)) << what;
    EXPECT_TRUE(same_bits(a.axis, b.axis)) << what;
    EXPECT_TRUE(same_bits(a.size, b.size)) << what;
    EXPECT_TRUE(same_bits(a.rotation, b.rotation)) << what;
}

/// Every field parse_scene sets, compared bit for bit.
void expect_same_spec(const SceneSpec& a, const SceneSpec& b, const std::string& what) {
    EXPECT_EQ(a.name, b.name) << what;
    EXPECT_EQ(a.description, b.description) << what;
    ASSERT_EQ(a.cloth, b.cloth) << what;
    switch (a.cloth) {
    case ClothType::grid:
        EXPECT_EQ(a.grid.n, b.grid.n) << what;
        EXPECT_TRUE(same_bits(a.grid.size, b.grid.size)) << what;
        EXPECT_TRUE(same_bits(a.grid.total_mass, b.grid.total_mass)) << what;
        EXPECT_EQ(a.grid.plane, b.grid.plane) << what;
        EXPECT_EQ(a.grid.pins, b.grid.pins) << what;
        EXPECT_TRUE(same_bits(a.grid.centre, b.grid.centre)) << what;
        EXPECT_TRUE(same_bits(a.grid.pin_radius, b.grid.pin_radius)) << what;
        break;
    case ClothType::tshirt:
        EXPECT_TRUE(same_bits(a.tshirt.cells_per_metre, b.tshirt.cells_per_metre)) << what;
        EXPECT_TRUE(same_bits(a.tshirt.total_mass, b.tshirt.total_mass)) << what;
        EXPECT_TRUE(same_bits(a.tshirt.shoulder_y, b.tshirt.shoulder_y)) << what;
        EXPECT_TRUE(same_bits(a.tshirt.gap, b.tshirt.gap)) << what;
        EXPECT_TRUE(same_bits(a.tshirt.seam_rest_ratio, b.tshirt.seam_rest_ratio)) << what;
        break;
    case ClothType::outline:
        EXPECT_EQ(a.outline.outline.outline, b.outline.outline.outline) << what;
        EXPECT_TRUE(same_bits(a.outline.spacing, b.outline.spacing)) << what;
        EXPECT_TRUE(same_bits(a.outline.density, b.outline.density)) << what;
        EXPECT_EQ(a.outline.plane, b.outline.plane) << what;
        EXPECT_TRUE(same_bits(a.outline.centre, b.outline.centre)) << what;
        EXPECT_EQ(a.outline.pin_top, b.outline.pin_top) << what;
        EXPECT_EQ(a.outline.copy, b.outline.copy) << what;
        EXPECT_TRUE(same_bits(a.outline.gap, b.outline.gap)) << what;
        EXPECT_EQ(a.outline.sew, b.outline.sew) << what;
        EXPECT_TRUE(same_bits(a.outline.seam_rest_ratio, b.outline.seam_rest_ratio)) << what;
        break;
    case ClothType::mask:
        EXPECT_TRUE(same_bits(a.masks.density, b.masks.density)) << what;
        ASSERT_EQ(a.masks.panels.size(), b.masks.panels.size()) << what;
        for (std::size_t k = 0; k < a.masks.panels.size(); ++k) {
            const MaskPanelSpec &p = a.masks.panels[k], &q = b.masks.panels[k];
            EXPECT_EQ(p.name, q.name) << what;
            EXPECT_EQ(p.mask.rows, q.mask.rows) << what;
            EXPECT_TRUE(same_bits(p.cell_size, q.cell_size)) << what;
            EXPECT_TRUE(same_bits(p.origin, q.origin)) << what;
            EXPECT_TRUE(same_bits(p.axis_u, q.axis_u)) << what;
            EXPECT_TRUE(same_bits(p.axis_v, q.axis_v)) << what;
            EXPECT_EQ(p.pins, q.pins) << what;
            EXPECT_EQ(p.pin_cells, q.pin_cells) << what;
        }
        ASSERT_EQ(a.masks.seams.size(), b.masks.seams.size()) << what;
        for (std::size_t k = 0; k < a.masks.seams.size(); ++k) {
            const MaskSeamSpec &p = a.masks.seams[k], &q = b.masks.seams[k];
            EXPECT_TRUE(p.a.panel == q.a.panel && p.a.path == q.a.path && p.b.panel == q.b.panel &&
                        p.b.path == q.b.path)
                << what;
            EXPECT_TRUE(same_bits(p.rest_ratio, q.rest_ratio)) << what;
        }
        break;
    case ClothType::mesh:
        EXPECT_EQ(a.mesh.file, b.mesh.file) << what;
        EXPECT_TRUE(same_bits(a.mesh.density, b.mesh.density)) << what;
        EXPECT_TRUE(same_bits(a.mesh.scale, b.mesh.scale)) << what;
        EXPECT_TRUE(same_bits(a.mesh.centre, b.mesh.centre)) << what;
        EXPECT_EQ(a.mesh.pins, b.mesh.pins) << what;
        EXPECT_EQ(a.mesh.pin_vertices, b.mesh.pin_vertices) << what;
        ASSERT_TRUE(a.mesh.mesh && b.mesh.mesh) << what;
        EXPECT_EQ(a.mesh.mesh->x, b.mesh.mesh->x) << what;
        EXPECT_EQ(a.mesh.mesh->triangles, b.mesh.mesh->triangles) << what;
        break;
    }
    EXPECT_EQ(a.model, b.model) << what;
    EXPECT_EQ(a.fabric.name, b.fabric.name) << what;
    for (auto [x, y] : {std::pair{a.fabric.density, b.fabric.density}, {a.fabric.stretch_u, b.fabric.stretch_u},
                        {a.fabric.stretch_v, b.fabric.stretch_v}, {a.fabric.shear, b.fabric.shear},
                        {a.fabric.bend_u, b.fabric.bend_u}, {a.fabric.bend_v, b.fabric.bend_v},
                        {a.fabric.damping, b.fabric.damping}})
        EXPECT_TRUE(same_bits(x, y)) << what;
    for (auto [x, y] : {std::pair{a.stiffness, b.stiffness}, {a.shear_ratio, b.shear_ratio}, {a.bend_ratio, b.bend_ratio},
                        {a.damping_ratio, b.damping_ratio}, {a.seam_stiffness, b.seam_stiffness}})
        EXPECT_TRUE(same_bits(x, y)) << what;
    const SimulationParams &p = a.physics, &q = b.physics;
    EXPECT_TRUE(same_bits(p.gravity, q.gravity)) << what;
    EXPECT_TRUE(same_bits(p.air_drag, q.air_drag)) << what;
    EXPECT_EQ(p.integrator, q.integrator) << what;
    EXPECT_EQ(p.solver, q.solver) << what;
    EXPECT_EQ(p.implicit.iterations, q.implicit.iterations) << what;
    EXPECT_TRUE(same_bits(p.implicit.tolerance, q.implicit.tolerance)) << what;
    EXPECT_TRUE(same_bits(p.implicit.chebyshev_rho, q.implicit.chebyshev_rho)) << what;
    EXPECT_EQ(p.implicit.method, q.implicit.method) << what;
    EXPECT_EQ(p.implicit.fas, q.implicit.fas) << what;
    EXPECT_EQ(p.implicit.fas_at_rest, q.implicit.fas_at_rest) << what;
    EXPECT_EQ(p.implicit.multilevel, q.implicit.multilevel) << what;
    EXPECT_TRUE(same_bits(p.self_collision.thickness, q.self_collision.thickness)) << what;
    EXPECT_TRUE(same_bits(p.self_collision.friction, q.self_collision.friction)) << what;
    EXPECT_EQ(p.self_collision.substeps, q.self_collision.substeps) << what;
    EXPECT_EQ(p.wind.enabled, q.wind.enabled) << what;
    EXPECT_TRUE(same_bits(p.wind.strength, q.wind.strength)) << what;
    EXPECT_EQ(p.aero.enabled, q.aero.enabled) << what;
    EXPECT_TRUE(same_bits(p.aero.density, q.aero.density)) << what;
    EXPECT_TRUE(same_bits(p.aero.drag_coefficient, q.aero.drag_coefficient)) << what;
    EXPECT_TRUE(same_bits(p.aero.velocity, q.aero.velocity)) << what;
    EXPECT_TRUE(same_bits(p.strain_limit.ratio, q.strain_limit.ratio)) << what;
    EXPECT_EQ(p.strain_limit.passes, q.strain_limit.passes) << what;
    EXPECT_EQ(p.strain_limit.every, q.strain_limit.every) << what;
    ASSERT_EQ(p.colliders.size(), q.colliders.size()) << what;
    for (std::size_t k = 0; k < p.colliders.size(); ++k)
        expect_same_collider(p.colliders[k], q.colliders[k], what + " collider " + std::to_string(k));
    EXPECT_EQ(a.dt.has_value(), b.dt.has_value()) << what;
    if (a.dt && b.dt) {
        EXPECT_TRUE(same_bits(*a.dt, *b.dt)) << what;
    }
    EXPECT_EQ(a.body, b.body) << what;
    ASSERT_EQ(a.state.has_value(), b.state.has_value()) << what;
    if (a.state) {
        EXPECT_EQ(a.state->pinned, b.state->pinned) << what;
        for (auto [u, v] : {std::pair{&a.state->x, &b.state->x}, {&a.state->y, &b.state->y}, {&a.state->z, &b.state->z},
                            {&a.state->vx, &b.state->vx}, {&a.state->vy, &b.state->vy}, {&a.state->vz, &b.state->vz}}) {
            ASSERT_EQ(u->size(), v->size()) << what;
            EXPECT_EQ(std::memcmp(u->data(), v->data(), u->size() * sizeof(float)), 0) << what;
        }
    }
}

/// The built cloths are identical: particles, masses, springs, triangles, initial state, parameters.
void expect_same_build(const BuiltScene& a, const BuiltScene& b, const std::string& what) {
    ASSERT_EQ(a.cloth.particle_count, b.cloth.particle_count) << what;
    const std::size_t n = a.cloth.particle_count;
    EXPECT_EQ(std::memcmp(a.cloth.inv_mass.data(), b.cloth.inv_mass.data(), n * sizeof(float)), 0) << what;
    EXPECT_EQ(a.cloth.free_inv_mass, b.cloth.free_inv_mass) << what;
    ASSERT_EQ(a.cloth.edges.size(), b.cloth.edges.size()) << what;
    for (std::size_t e = 0; e < a.cloth.edges.size(); ++e) {
        const Edge &x = a.cloth.edges[e], &y = b.cloth.edges[e];
        ASSERT_TRUE(x.a == y.a && x.b == y.b && x.kind == y.kind && same_bits(x.rest, y.rest)) << what << " edge " << e;
    }
    for (std::size_t k = 0; k < spring_kind_count; ++k) {
        EXPECT_TRUE(same_bits(a.cloth.material[k].stiffness, b.cloth.material[k].stiffness)) << what;
        EXPECT_TRUE(same_bits(a.cloth.material[k].damping, b.cloth.material[k].damping)) << what;
    }
    EXPECT_EQ(a.cloth.triangles, b.cloth.triangles) << what;
    EXPECT_EQ(a.cloth.grid.has_value(), b.cloth.grid.has_value()) << what;
    EXPECT_EQ(a.initial.x, b.initial.x) << what;
    EXPECT_EQ(a.initial.y, b.initial.y) << what;
    EXPECT_EQ(a.initial.z, b.initial.z) << what;
    EXPECT_EQ(a.initial.vx, b.initial.vx) << what;
    EXPECT_TRUE(same_bits(a.params.dt, b.params.dt)) << what;
    ASSERT_EQ(a.params.colliders.size(), b.params.colliders.size()) << what;
    for (std::size_t k = 0; k < a.params.colliders.size(); ++k)
        expect_same_collider(a.params.colliders[k], b.params.colliders[k], what);
}

/// Every built-in scene and the example scenes.
std::vector<std::pair<std::string, SceneSpec>> all_scenes() {
    std::vector<std::pair<std::string, SceneSpec>> out;
    for (const std::string& name : builtin_scene_names()) out.emplace_back(name, load_scene(name));
    for (const auto& entry : std::filesystem::directory_iterator(std::string(DRAPE_SOURCE_DIR) + "/scenes/examples"))
        if (entry.path().extension() == ".json") out.emplace_back(entry.path().string(), load_scene(entry.path().string()));
    return out;
}

std::filesystem::path temp_dir() {
    const auto dir = std::filesystem::temp_directory_path() / ("drape_scene_write_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    return dir;
}

std::string read_text(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(SceneWrite, EveryScenesRoundTripsToTheSameSpecAndCloth) {
    const auto scenes = all_scenes();
    EXPECT_GE(scenes.size(), builtin_scene_names().size() + 1); // the examples too
    for (const auto& [name, spec] : scenes) {
        const std::string text = scene_to_json(spec, spec.state ? &*spec.state : nullptr); // pile.json has a state
        const SceneSpec back = parse_scene(text, name + " (written)");
        expect_same_spec(spec, back, name);
        expect_same_build(build_scene(spec), build_scene(back), name);
        EXPECT_EQ(scene_to_json(back, back.state ? &*back.state : nullptr), text) << name << ": writing is a fixed point";
    }
}

TEST(SceneWrite, EveryFieldIsWrittenExplicitly) {
    SceneSpec springs = load_scene("hang");
    springs.model = MaterialModel::springs;
    const std::string text = scene_to_json(springs);
    for (const char* field : {"\"scene\"", "\"description\"", "\"type\": \"grid\"", "\"n\": 100", "\"size\"", "\"mass\"",
                              "\"plane\"", "\"centre\"", "\"pins\": \"corners\"", "\"pin_radius\": 0.02",
                              "\"model\": \"springs\"", "\"stiffness\": 1000", "\"shear_ratio\"",
                              "\"bend_ratio\"", "\"damping_ratio\"", "\"seam_stiffness\"", "\"gravity\": [0, -9.81, 0]",
                              "\"drag\": 0.2", "\"integrator\": \"euler\"", "\"wind\"", "\"aero\"", "\"strain_limit\"",
                              "\"colliders\"", "\"body\": false"})
        EXPECT_TRUE(has(text, field)) << field << "\n" << text;
    // The built-in hang is wool: the fabric's every figure in file units, no spring fields, no cloth mass.
    const std::string fabric = scene_to_json(load_scene("hang"));
    for (const char* field : {"\"model\": \"fabric\"", "\"fabric\": \"wool\"", "\"density_gsm\": 168,", "\"stretch_u\"",
                              "\"stretch_v\"", "\"shear\"", "\"bend_u_uNm\"", "\"bend_v_uNm\"", "\"damping\"",
                              "\"seam_stiffness\""})
        EXPECT_TRUE(has(fabric, field)) << field << "\n" << fabric;
    for (const char* field : {"\"mass\"", "\"stiffness\":", "\"shear_ratio\"", "\"damping_ratio\""})
        EXPECT_FALSE(has(fabric, field)) << field << "\n" << fabric;
    EXPECT_FALSE(has(text, "\"state\""));
    EXPECT_FALSE(has(text, "\"dt\"")) << "absent dt stays absent (the default bound)";
    SceneSpec with_dt = load_scene("hang");
    with_dt.dt = 1.25e-5f;
    EXPECT_TRUE(has(scene_to_json(with_dt), "\"dt\": 1.25e-05"));
    // Sewing is on by default (0.5 m/s): only another speed is written, and sewing off (0) is, so it stays off.
    EXPECT_FALSE(has(text, "\"sewing_speed\"")) << text;
    SceneSpec unsewn = load_scene("hang");
    unsewn.physics.sewing_speed = 0.0f;
    const std::string off = scene_to_json(unsewn);
    EXPECT_TRUE(has(off, "\"sewing_speed\": 0")) << off;
    EXPECT_EQ(parse_scene(off, "unsewn.json").physics.sewing_speed, 0.0f);
}

TEST(SceneWrite, ImplicitSolverRoundTrips) {
    SceneSpec s = load_scene("hang");
    s.grid.n = 8;
    s.physics.solver = Solver::implicit;
    s.physics.implicit = {17, 0.003f, 0.85f, ImplicitMethod::jacobi};
    const std::string text = scene_to_json(s);
    for (const char* field : {"\"solver\": \"implicit\"", "\"iterations\": 17", "\"tolerance\": 0.003",
                              "\"chebyshev_rho\": 0.85", "\"method\": \"jacobi\""})
        EXPECT_TRUE(has(text, field)) << field << "\n" << text;
    EXPECT_FALSE(has(text, "\"dt\"")) << "absent dt stays absent (the implicit default, a frame)";
    EXPECT_FALSE(has(text, "\"multilevel\"")) << "the default (on) is left out";
    const SceneSpec back = parse_scene(text, "implicit.json");
    expect_same_spec(s, back, "implicit");
    expect_same_build(build_scene(s), build_scene(back), "implicit");
    s.physics.implicit.multilevel = false;
    const std::string single = scene_to_json(s);
    EXPECT_TRUE(has(single, "\"multilevel\": false")) << single;
    expect_same_spec(s, parse_scene(single, "single.json"), "implicit, single level");
    EXPECT_FALSE(has(text, "\"fas_at_rest\"")) << "the default (off) is left out";
    s.physics.implicit.fas_at_rest = true;
    const std::string at_rest = scene_to_json(s);
    EXPECT_TRUE(has(at_rest, "\"fas_at_rest\": true")) << at_rest;
    expect_same_spec(s, parse_scene(at_rest, "at_rest.json"), "implicit, FAS at rest");
    s.physics.implicit.fas_at_rest = false;
    EXPECT_EQ(build_scene(back).params.dt, implicit_default_dt);
    s.dt = 0.02f;
    expect_same_spec(s, parse_scene(scene_to_json(s), "implicit_dt.json"), "implicit with dt");
    // Self-collision's contact sub-steps: written when not the default (4).
    s.physics.self_collision.thickness = 0.004f;
    EXPECT_FALSE(has(scene_to_json(s), "\"substeps\"")) << "the default is left out";
    s.physics.self_collision.substeps = 2;
    const std::string sub = scene_to_json(s);
    EXPECT_TRUE(has(sub, "\"substeps\": 2")) << sub;
    expect_same_spec(s, parse_scene(sub, "substeps.json"), "implicit with contact sub-steps");
    // The explicit solver is written too (absent reads as explicit, so old files keep their meaning).
    EXPECT_TRUE(has(scene_to_json(load_scene("hang")), "\"solver\": \"explicit\""));
}

TEST(SceneWrite, FloatsReadBackToTheSameBits) {
    SceneSpec s = load_scene("sphere");
    // Awkward floats: values needing 9 digits, tiny ones, negative zero.
    const float awkward[] = {0.1f, 1.0f / 3.0f, 9.81000042f, 999.999939f, 1e-7f, -0.0f, 0.30000001f, 3.4e-5f};
    for (float f : awkward) {
        s.grid.centre = {f, -f, f / 7.0f};
        s.physics.aero.velocity = {f / 11.0f, f / 10.0f, -f / 13.0f};
        const SceneSpec back = parse_scene(scene_to_json(s), "awkward.json");
        EXPECT_TRUE(same_bits(back.grid.centre, s.grid.centre)) << f;
        EXPECT_TRUE(same_bits(back.physics.aero.velocity, s.physics.aero.velocity)) << f;
    }
}

/// Runs `steps`, saves with the state (through a file), reloads, and checks that `more` substeps of both agree bit
/// for bit.
void expect_continues_identically(SceneSpec spec, const std::string& what, std::size_t steps, std::size_t more,
                                  const std::function<void(Simulation&)>& user = {}) {
    BuiltScene b = build_scene(spec);
    Simulation original(std::move(b.cloth), b.initial, b.params);
    original.step(steps);
    if (user) user(original);
    original.step(steps);
    const SceneState state = capture_state(original);
    const std::filesystem::path file = temp_dir() / "continue.json";
    save_scene(file.string(), spec, &state);
    const SceneSpec reloaded = load_scene(file.string());
    ASSERT_TRUE(reloaded.state) << what;
    BuiltScene r = build_scene(reloaded);
    EXPECT_TRUE(same_bits(r.params.dt, original.params().dt)) << what;
    Simulation resumed(std::move(r.cloth), r.initial, r.params);
    EXPECT_EQ(resumed.checksum(), original.checksum()) << what << ": the saved positions";
    for (std::size_t i = 0; i < original.cloth().particle_count; ++i)
        ASSERT_EQ(resumed.is_pinned(i), original.is_pinned(i)) << what << " particle " << i;
    const std::uint64_t before = original.checksum();
    original.step(more);
    resumed.step(more);
    EXPECT_NE(original.checksum(), before) << what << ": the cloth still moves";
    EXPECT_EQ(resumed.checksum(), original.checksum()) << what << ": after " << more << " more substeps";
    EXPECT_TRUE(resumed.health().finite) << what;
}

TEST(SceneWrite, SavedStateContinuesBitIdentically) {
    for (const auto& [name, spec] : all_scenes()) {
        SceneSpec s = spec;
        // The analytic wind depends on the time, which restarts at 0 on load (documented): off here; aero stays.
        s.physics.wind.enabled = false;
        // Under the sanitizers fewer substeps (the same save, load and resume; 77 s of CI's ASan run at 150 + 200).
        if (drape::testing::sanitized)
            expect_continues_identically(s, name, 30, 40);
        else
            expect_continues_identically(s, name, 150, 200);
    }
}

// Self-collision's snapshot of its last run (which decides when the stage runs and each pair's side) is saved with
// the state: a resumed run continues bit-identically; without it the resumed run differs. The scene: a 24 x 24 wool
// cloth folded over itself on the ground (test_self_collision.cpp's pile), 4 mm thickness.
TEST(SceneWrite, SelfCollisionSnapshotIsSavedAndResumed) {
    SceneSpec spec = load_scene("hang");
    const std::uint32_t n = 24;
    spec.grid.n = n;
    spec.grid.size = 0.5f;
    spec.grid.pins = GridPins::none;
    spec.physics.strain_limit.ratio = 0.0f;
    spec.physics.colliders = {make_ground(0.0f, {0.002f, 0.5f})};
    spec.physics.self_collision.thickness = 0.004f;
    spec.physics.self_collision.friction = 0.3f;
    const BuiltScene flat = build_scene(spec);
    SceneState fold;
    fold.origin = flat.cloth.origin;
    drape::testing::fold_over_itself(n, spec.grid.size, fold.x, fold.y, fold.z);
    fold.vx.assign(fold.x.size(), 0.0f);
    fold.vy = fold.vx;
    fold.vz = fold.vx;
    spec.state = fold;
    expect_continues_identically(spec, "folded pile with self-collision", 150, 200);

    BuiltScene b = build_scene(spec);
    Simulation original(std::move(b.cloth), b.initial, b.params);
    original.step(300);
    // A state saved right before a step in which the stage skips (the pile is still moving: most steps run it), and
    // in which the planes of its last run hold some particle.
    SceneState state;
    for (int k = 0; k < 200; ++k) {
        state = capture_state(original);
        const std::size_t runs = original.self_collision_runs();
        original.step(1);
        if (original.self_collision_runs() == runs && !state.sc_planes.index.empty()) break;
        state = SceneState{};
    }
    ASSERT_EQ(state.snapshot_x.size(), original.cloth().particle_count) << "a skipping step, after the stage has run";
    const std::uint64_t after_one = original.checksum();
    original.step(199);
    const std::uint64_t after_200 = original.checksum();
    {
        spec.state = state;
        BuiltScene r = build_scene(parse_scene(scene_to_json(spec, &state), "resume.json")); // through the file format
        Simulation resumed(std::move(r.cloth), r.initial, r.params);
        resumed.step(1);
        EXPECT_EQ(resumed.checksum(), after_one) << "the planes held the same particles";
        resumed.step(199);
        EXPECT_EQ(resumed.checksum(), after_200);
        SceneState no_planes = state;
        no_planes.sc_planes = {};
        spec.state = no_planes;
        BuiltScene q = build_scene(spec);
        Simulation unheld(std::move(q.cloth), q.initial, q.params);
        unheld.step(1);
        EXPECT_NE(unheld.checksum(), after_one) << "without its planes the skipping step holds nothing";
    }
    state.snapshot_x.clear();
    state.snapshot_y.clear();
    state.snapshot_z.clear();
    state.sc_planes = {};
    spec.state = state;
    BuiltScene r = build_scene(spec);
    Simulation resumed(std::move(r.cloth), r.initial, r.params);
    resumed.step(1);
    EXPECT_EQ(resumed.self_collision_runs(), 1u) << "without the snapshot the stage runs at once";
}

TEST(SceneWrite, UserPinsAndUnpinsAreSaved) {
    // hang: unpin an authored corner, pin a middle particle; the reloaded cloth has exactly those pins (no strain
    // limiting here: its colour groups are ordered from the pins at load).
    expect_continues_identically(load_scene("hang"), "hang with user pins", 100, 300, [](Simulation& sim) {
        sim.set_pinned(0, false);
        sim.set_pinned(5050, true);
    });
    BuiltScene b = build_scene(load_scene("hang"));
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.set_pinned(0, false);
    sim.set_pinned(5050, true);
    const SceneState st = capture_state(sim);
    // The 2 cm clips hold 4 particles each at N = 100 (h = 1 cm): the corner, its two neighbours and (1, 1) at 1.41 cm.
    EXPECT_EQ(st.pinned, (std::vector<std::uint32_t>{1, 98, 99, 100, 101, 198, 199, 5050}));
    // Unpinned authored pin gets its mass back: it falls.
    SceneSpec spec = load_scene("hang");
    spec.state = st;
    BuiltScene r = build_scene(spec);
    EXPECT_GT(r.cloth.inv_mass[0], 0.0f);
    EXPECT_EQ(r.cloth.inv_mass[5050], 0.0f);
    EXPECT_EQ(r.cloth.inv_mass[99], 0.0f);
}

TEST(SceneWrite, GrabbedParticleIsSavedUnpinned) {
    BuiltScene b = build_scene(load_scene("hang"));
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.grab(42, {0.0f, 0.5f, 0.0f});
    sim.step(3);
    const SceneState st = capture_state(sim);
    EXPECT_EQ(st.pinned, (std::vector<std::uint32_t>{0, 1, 98, 99, 100, 101, 198, 199})) << "the two clips";
}

TEST(SceneWrite, VerletStateContinuesToWithinRounding) {
    SceneSpec s = load_scene("hang");
    s.physics.integrator = Integrator::verlet;
    BuiltScene b = build_scene(s);
    Simulation original(std::move(b.cloth), b.initial, b.params);
    original.step(200);
    s.state = capture_state(original);
    BuiltScene r = build_scene(parse_scene(scene_to_json(s, &*s.state), "verlet.json"));
    Simulation resumed(std::move(r.cloth), r.initial, r.params);
    original.step(200);
    resumed.step(200);
    double worst = 0.0;
    for (std::size_t i = 0; i < original.cloth().particle_count; ++i)
        worst = std::max(worst, double(std::fabs(original.y()[i] - resumed.y()[i])));
    EXPECT_LT(worst, 1e-4) << "m; x - v dt rounds the previous position";
}

TEST(SceneWrite, StateErrorsAreClear) {
    const std::string base = R"({"cloth": {"n": 2, "mass": 0.001}, "state": )";
    auto error = [&](const std::string& state) -> std::string {
        try {
            build_scene(parse_scene(base + state + "}", "s.json"));
        } catch (const InvalidInput& e) {
            return e.what();
        }
        return "";
    };
    const std::string ok_vel = R"("velocities": [[0,0,0],[0,0,0],[0,0,0],[0,0,0]])";
    const std::string four = R"("positions": [[0,0,0],[1,0,0],[0,0,1],[1,0,1]])";
    EXPECT_EQ(error("{" + four + ", " + ok_vel + R"(, "pinned": [0, 3]})"), "");
    std::string e = error(R"({"positions": [[0,0,0]], "velocities": [[0,0,0]], "pinned": []})");
    EXPECT_TRUE(has(e, "state.positions") && has(e, "1 entries") && has(e, "4 particles")) << e;
    e = error("{" + four + ", " + ok_vel + R"(, "pinned": [4]})");
    EXPECT_TRUE(has(e, "s.json: state.pinned[0]") && has(e, "[0, 4)")) << e;
    e = error(R"({"positions": [[0,0,0],[1,0,0],[0,"x",1],[1,0,1]], )" + ok_vel + R"(, "pinned": []})");
    EXPECT_TRUE(has(e, "state.positions[2][1]") && has(e, "finite")) << e;
    e = error(R"({"positions": [[0,0,0],[1,0,0],[0,0,1],[1,0,1e7]], )" + ok_vel + R"(, "pinned": []})");
    EXPECT_TRUE(has(e, "state.positions[3][2]")) << e;
    e = error("{" + four + R"(, "velocities": [[0,0,0]], "pinned": []})");
    EXPECT_TRUE(has(e, "state.velocities") && has(e, "1 entries")) << e;
    e = error("{" + four + ", " + ok_vel + "}");
    EXPECT_TRUE(has(e, "state.pinned") && has(e, "required")) << e;
    e = error("{" + four + ", " + ok_vel + R"(, "pinned": [], "time": 3})");
    EXPECT_TRUE(has(e, "state.time") && has(e, "not a known field")) << e;
    // Self-collision's planes: only with a snapshot, a particle index in range and ascending, a unit normal.
    const std::string snap = R"(, "self_collision_snapshot": [[0,0,0],[1,0,0],[0,0,1],[1,0,1]])";
    const std::string pre = "{" + four + ", " + ok_vel + R"(, "pinned": [])";
    EXPECT_EQ(error(pre + snap + R"(, "self_collision_planes": [[1, 0, 0, 1, 0, 0], [3, 2, 0, -1, 0, 0]]})"), "");
    const struct {
        std::string state, where, what;
    } bad[] = {
        {pre + R"(, "self_collision_planes": [[1, 0, 0, 1, 0, 0]]})", "state.self_collision_planes",
         "needs self_collision_snapshot"},
        {pre + snap + R"(, "self_collision_planes": [[4, 0, 0, 1, 0, 0]]})", "state.self_collision_planes[0]", "[0, 4)"},
        {pre + snap + R"(, "self_collision_planes": [[2, 0, 0, 1, 0, 0], [1, 0, 0, 1, 0, 0]]})",
         "state.self_collision_planes[1]", "ascending"},
        {pre + snap + R"(, "self_collision_planes": [[1, 0, 0, 2, 0, 0]]})", "state.self_collision_planes[0]",
         "unit normal"},
        {pre + snap + R"(, "self_collision_planes": [[1, 0, 1, 0, 0]]})", "state.self_collision_planes[0]",
         "[particle, partner, nx, ny, nz, c]"},
        {pre + snap + R"(, "self_collision_planes": [[1, 9, 0, 1, 0, 0]]})", "state.self_collision_planes[0]", "[0, 4)"},
        {pre + snap + R"(, "self_collision_planes": [[1, 0, 0, 1, 0, 0.5]]})", "state.self_collision_planes[0]",
         "within 1 mm"},
    };
    for (const auto& b : bad) {
        e = error(b.state);
        EXPECT_TRUE(has(e, b.where) && has(e, b.what)) << e;
    }
}

TEST(SceneWrite, SaveIsAtomicAndFailuresNameThePath) {
    const std::filesystem::path dir = temp_dir();
    const SceneSpec spec = load_scene("drape");
    const std::string file = (dir / "drape_copy.json").string();
    save_scene(file, spec);
    save_scene(file, spec); // over an existing file
    expect_same_spec(spec, load_scene(file), "saved drape");
    for (const auto& entry : std::filesystem::directory_iterator(dir))
        EXPECT_FALSE(has(entry.path().filename().string(), ".tmp-")) << "no temp file left: " << entry.path();
    const std::string missing = (dir / "no_such_dir" / "x.json").string();
    try {
        save_scene(missing, spec);
        ADD_FAILURE() << "wrote into a missing directory";
    } catch (const std::runtime_error& e) {
        EXPECT_TRUE(has(e.what(), missing)) << e.what();
    }
    // A spec the format cannot hold is refused before anything is written.
    SceneSpec rotated = spec;
    rotated.physics.colliders.push_back(make_ellipsoid({0, 0, 0}, {1, 1, 1}, {}, rotation_about_axis({0, 1, 0}, 0.5f)));
    const std::string never = (dir / "never.json").string();
    EXPECT_THROW(save_scene(never, rotated), InvalidInput);
    EXPECT_FALSE(std::filesystem::exists(never));
    // A spec that would not load back (the spring model's node-mass rule) is refused too.
    SceneSpec heavy = spec;
    heavy.model = MaterialModel::springs;
    heavy.grid.total_mass = 1000.0f;
    try {
        save_scene(never, heavy);
        ADD_FAILURE() << "wrote a scene that does not load";
    } catch (const InvalidInput& e) {
        EXPECT_TRUE(has(e.what(), never) && has(e.what(), "would not load back") && has(e.what(), "cloth.mass")) << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(never));
    // A state too large for a scene file (600 x 600 particles, about 27 MiB of text) is refused as what it is, and the
    // file already there is kept (the message read "file is larger than 16 MiB", as if the existing file were).
    {
        SceneSpec big = load_scene("hang");
        big.grid.n = 600;
        SceneState st;
        for (auto* v : {&st.x, &st.y, &st.z, &st.vx, &st.vy, &st.vz})
            v->assign(std::size_t{600} * 600, 0.123456789f);
        const std::string before = read_text(file);
        try {
            save_scene(file, big, &st);
            ADD_FAILURE() << "wrote a scene file over 16 MiB";
        } catch (const InvalidInput& e) {
            EXPECT_TRUE(has(e.what(), file + ": not written: the scene with its state would be")) << e.what();
            EXPECT_TRUE(has(e.what(), "MiB, over the 16 MiB a scene file may hold")) << e.what();
            EXPECT_TRUE(has(e.what(), "save it without the state")) << e.what();
        }
        EXPECT_EQ(read_text(file), before);
    }
    // Saving through a symbolic link writes the file it points to and keeps the link.
    std::filesystem::create_directory(dir / "real");
    const std::filesystem::path real = dir / "real" / "target.json", link = dir / "link.json";
    save_scene(real.string(), load_scene("hang"));
    std::filesystem::create_symlink(real, link);
    save_scene(link.string(), spec);
    EXPECT_TRUE(std::filesystem::is_symlink(link));
    expect_same_spec(spec, load_scene(real.string()), "saved through the link");
    for (const auto& entry : std::filesystem::directory_iterator(dir / "real"))
        EXPECT_FALSE(has(entry.path().filename().string(), ".tmp-")) << "no temp file left: " << entry.path();
    // A mesh scene saved through the link loads through the link: its OBJ path is relative to the link's directory,
    // as load_scene reads it. A dangling link is written through too.
    const SceneSpec disc = load_scene(std::string(DRAPE_SOURCE_DIR) + "/scenes/examples/mesh_disc.json");
    save_scene(link.string(), disc);
    EXPECT_TRUE(std::filesystem::is_symlink(link));
    expect_same_spec(disc, load_scene(link.string()), "mesh scene through the link");
    const std::filesystem::path dangling = dir / "dangling.json", absent = dir / "real" / "absent.json";
    std::filesystem::create_symlink(absent, dangling);
    save_scene(dangling.string(), spec);
    EXPECT_TRUE(std::filesystem::is_symlink(dangling));
    expect_same_spec(spec, load_scene(absent.string()), "written where the dangling link points");
    std::filesystem::remove_all(dir);
}

} // namespace
