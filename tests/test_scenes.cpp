// Scene files: every built-in loads and runs; broken files get their clear error (file, JSON path, range).
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>

#include <sys/stat.h>
#include <unistd.h>

#include "drape/scene.hpp"
#include "scene_test_util.hpp"
#include "test_helpers.hpp"

using namespace drape;
using drape::testing::has;
using drape::testing::scene_error_of;

namespace {

TEST(Scenes, EveryBuiltinLoadsBuildsAndSteps) {
    const std::vector<std::string> names = builtin_scene_names();
    EXPECT_EQ(names, (std::vector<std::string>{"hang", "drape", "sphere", "flag", "tshirt"}));
    for (const std::string& name : names) {
        const SceneSpec spec = load_scene(name);
        EXPECT_EQ(spec.name, name);
        BuiltScene b = build_scene(spec);
        EXPECT_GT(b.cloth.particle_count, 0u) << name;
        EXPECT_GT(b.params.dt, 0.0f) << name;
        Simulation sim(std::move(b.cloth), b.initial, b.params);
        sim.step(200);
        EXPECT_TRUE(sim.health().finite) << name;
    }
}

TEST(Scenes, BuiltinFilesOnDiskAreTheEmbeddedOnes) {
    for (const std::string& name : builtin_scene_names()) {
        const std::string path = std::string(DRAPE_SOURCE_DIR) + "/scenes/" + name + ".json";
        BuiltScene from_file = build_scene(load_scene(path));
        BuiltScene builtin = build_scene(load_scene(name));
        EXPECT_EQ(from_file.cloth.particle_count, builtin.cloth.particle_count) << name;
        EXPECT_EQ(from_file.cloth.spring_count(), builtin.cloth.spring_count()) << name;
        EXPECT_EQ(from_file.params.dt, builtin.params.dt) << name;
        EXPECT_EQ(from_file.params.colliders.size(), builtin.params.colliders.size()) << name;
    }
}

TEST(Scenes, SeedFigures) {
    const BuiltScene drape = build_scene(load_scene("drape"));
    EXPECT_EQ(drape.cloth.particle_count, 1156u); // seed 001: 34 x 34
    EXPECT_EQ(drape.cloth.triangles.size() / 3, 2178u);
    const BuiltScene shirt = build_scene(load_scene("tshirt"));
    EXPECT_NEAR(double(shirt.cloth.particle_count), 1008.0, 30.0); // seed 000
    EXPECT_GT(shirt.cloth.seams.a.size(), 0u);
    EXPECT_GT(shirt.params.colliders.size(), 5u) << "the body of ellipsoids";
}

TEST(Scenes, SeamColourGroupsShareNoParticleAndHoldEverySeamOnce) {
    const BuiltScene shirt = build_scene(load_scene("tshirt"));
    const SeamSet& s = shirt.cloth.seams;
    std::multiset<std::uint32_t> seen(s.groups.edge_index.begin(), s.groups.edge_index.end());
    for (std::uint32_t e = 0; e < shirt.cloth.edges.size(); ++e)
        EXPECT_EQ(seen.count(e), shirt.cloth.edges[e].kind == SpringKind::seam ? 1u : 0u) << e;
    for (std::size_t g = 0; g < s.groups.group_count(); ++g) {
        if (s.groups.is_overflow(g)) continue;
        std::set<std::uint32_t> touched;
        for (std::uint32_t e : s.groups.group(g)) {
            EXPECT_TRUE(touched.insert(shirt.cloth.edges[e].a).second);
            EXPECT_TRUE(touched.insert(shirt.cloth.edges[e].b).second);
        }
    }
    // Seams are not CSR rows: the CSR holds exactly the other springs, both directions.
    EXPECT_EQ(shirt.cloth.graph.entry_count(), 2 * (shirt.cloth.spring_count() - s.a.size()));
}

TEST(Scenes, TShirtClosesItsSeams) {
    BuiltScene b = build_scene(load_scene("tshirt"));
    const float h = 1.0f / 35.0f;
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.step(static_cast<std::size_t>(1.5 / sim.params().dt));
    ASSERT_TRUE(sim.health().finite);
    // Every seam spring is within the strain limit: the two panels are sewn together (the shirt is closed).
    const SeamSet& s = sim.cloth().seams;
    const float limit = 1.0f + sim.params().strain_limit.ratio;
    float worst = 0.0f;
    for (std::size_t k = 0; k < s.a.size(); ++k) {
        const float dx = sim.x()[s.b[k]] - sim.x()[s.a[k]], dy = sim.y()[s.b[k]] - sim.y()[s.a[k]],
                    dz = sim.z()[s.b[k]] - sim.z()[s.a[k]];
        worst = std::max(worst, std::sqrt(dx * dx + dy * dy + dz * dz) / s.rest[k]);
    }
    EXPECT_LE(worst, limit + 1e-3f) << "longest seam " << worst * s.rest[0] << " m, rest " << s.rest[0] << " m, h " << h;
    // And no particle is inside the body.
    for (std::size_t i = 0; i < sim.cloth().particle_count; ++i)
        for (const Collider& c : sim.params().colliders)
            ASSERT_FALSE(is_inside(c, {sim.x()[i], sim.y()[i], sim.z()[i]}, 1e-5f)) << i;
}

struct BadFile {
    const char* name;
    const char* json;
    const char* expect; ///< must appear in the message
};

class BrokenScene : public ::testing::TestWithParam<BadFile> {};

TEST_P(BrokenScene, GivesAClearError) {
    const BadFile& c = GetParam();
    const std::string msg = scene_error_of(c.json);
    ASSERT_FALSE(msg.empty()) << c.name << " was accepted";
    EXPECT_TRUE(has(msg, "test.json")) << msg;
    EXPECT_TRUE(has(msg, c.expect)) << c.name << ": " << msg;
}

// An outline with a spike far narrower than its spacing: the fabric model's needle triangles there were refused as
// "spring 128-180 has stiffness scale 2225.7", naming no field of the file and no place in the outline.
TEST(Scene, OutlineNarrowerThanItsSpacingIsRefusedNamingWhere) {
    const std::string spike = R"({ "cloth": { "type": "outline", "spacing": 0.02, "pins": "top_edge",
        "outline": [[0, 0], [1, 0], [1, 1], [0.5, 1], [0.50001, 1.5], [0.49999, 1], [0, 1]] },
        "material": { "fabric": "wool" } })";
    std::string msg;
    try {
        build_scene(parse_scene(spike, "test.json"));
    } catch (const InvalidInput& e) {
        msg = e.what();
    }
    EXPECT_TRUE(has(msg, "test.json: cloth.outline at cloth.spacing = 0.02 m: near (0.5, 1.")) << msg;
    EXPECT_TRUE(has(msg, "narrower than the spacing")) << msg;
    EXPECT_TRUE(has(msg, "widen the outline there, or lower cloth.spacing")) << msg;
    // The same outline without the spike builds.
    const std::string square = R"({ "cloth": { "type": "outline", "spacing": 0.02, "pins": "top_edge",
        "outline": [[0, 0], [1, 0], [1, 1], [0, 1]] }, "material": { "fabric": "wool" } })";
    EXPECT_NO_THROW(build_scene(parse_scene(square, "test.json")));
}

// A file nested millions of levels deep was refused cleanly but only after using about 1 GB: the reader stops at 256.
TEST(Scene, DeepNestingIsRefusedEarly) {
    const std::size_t depth = 1000000;
    const std::string text = R"({"cloth": )" + std::string(depth, '[') + std::string(depth, ']') + "}";
    const std::string msg = scene_error_of(text);
    EXPECT_TRUE(has(msg, "test.json: arrays and objects nested more than 256 deep (at cloth")) << msg.substr(0, 300);
    EXPECT_TRUE(has(msg, "a scene file nests at most a few levels")) << msg.substr(0, 300);
    EXPECT_LT(msg.size(), 400u);
    // 255 levels are read (and refused for what they hold, not for their depth).
    const std::string ok = scene_error_of(R"({"cloth": )" + std::string(254, '[') + std::string(254, ']') + "}");
    EXPECT_FALSE(has(ok, "nested more than")) << ok.substr(0, 300);
}

TEST(Scene, NulByteIsRefused) {
    const std::string text = std::string("{}") + '\0' + R"({"cloth": {"n": 1e400}})";
    ASSERT_EQ(text.size(), 26u);
    const std::string msg = scene_error_of(text);
    EXPECT_TRUE(has(msg, "byte 2 is a NUL character")) << msg;
}

INSTANTIATE_TEST_SUITE_P(
    Files, BrokenScene,
    ::testing::Values(
        BadFile{"malformed", "{\"scene\": \"x\", ", "malformed JSON"},
        BadFile{"not_object", "[1, 2]", "must be a JSON object"},
        // A repeated key kept only the last value; a NUL byte ended the text (the rest was ignored).
        BadFile{"duplicate_key", R"({"cloth": {"n": 10, "n": 20}})", "cloth.n appears twice in one object"},
        BadFile{"wrong_type", R"({"cloth": {"n": "ten"}})", "cloth.n must be a whole number in [2, 4096]"},
        BadFile{"fraction", R"({"cloth": {"n": 10.5}})", "cloth.n"},
        BadFile{"unknown_field", R"({"cloth": {"n": 10, "colour": 3}})", "cloth.colour is not a known field"},
        BadFile{"unknown_top", R"({"gravity": 3})", "gravity is not a known field"},
        BadFile{"stiffness_range", R"({"material": {"stiffness": 50}})", "[100, 25000] N/m"},
        BadFile{"node_mass", R"({"cloth": {"n": 10, "mass": 1.0}})", "[0.001, 1] g"},
        BadFile{"absurd_size", R"({"cloth": {"n": 100000}})", "cloth.n"},
        BadFile{"absurd_tshirt", R"({"cloth": {"type": "tshirt", "cells_per_metre": 1e9}})", "cells_per_metre"},
        BadFile{"bad_enum", R"({"cloth": {"pins": "left"}})", "cloth.pins"},
        BadFile{"bad_vec", R"({"physics": {"gravity": [0, -9.81]}})", "physics.gravity must be an array of 3"},
        BadFile{"nan_like", R"({"physics": {"drag": -1}})", "physics.drag"},
        BadFile{"dt_range", R"({"physics": {"dt": 5}})", "physics.dt"},
        BadFile{"sewing_speed", R"({"physics": {"sewing_speed": 20}})", "physics.sewing_speed"},
        BadFile{"collider_type", R"({"colliders": [{"type": "cube"}]})", "colliders[0].type"},
        BadFile{"collider_missing_type", R"({"colliders": [{"radius": 1}]})", "colliders[0].type is required"},
        BadFile{"collider_radius", R"({"colliders": [{"type": "sphere", "radius": -1}]})", "colliders[0].radius"},
        BadFile{"collider_unknown", R"({"colliders": [{"type": "sphere", "colour": 1}]})",
                "colliders[0].colour is not a known field"},
        BadFile{"collider_friction", R"({"colliders": [{"type": "ground", "friction": 2}]})", "[0, 1]"},
        BadFile{"strain_passes", R"({"physics": {"strain_limit": {"passes": 0}}})", "physics.strain_limit.passes"},
        BadFile{"wind_type", R"({"physics": {"wind": {"enabled": "yes"}}})", "physics.wind.enabled must be true or false"},
        // The implicit solver's fields.
        BadFile{"solver_name", R"({"physics": {"solver": "newton"}})",
                "physics.solver = \"newton\" is not one of \"explicit\", \"implicit\""},
        BadFile{"implicit_verlet", R"({"physics": {"solver": "implicit", "integrator": "verlet"}})",
                "physics.integrator = \"verlet\" is a choice of the explicit solver only"},
        BadFile{"implicit_iterations", R"({"physics": {"implicit": {"iterations": 0}}})",
                "physics.implicit.iterations = 0 is outside the allowed range [1, 1000]"},
        BadFile{"implicit_iterations_fraction", R"({"physics": {"implicit": {"iterations": 2.5}}})",
                "physics.implicit.iterations must be a whole number in [1, 1000]"},
        BadFile{"implicit_tolerance", R"({"physics": {"implicit": {"tolerance": -0.1}}})",
                "physics.implicit.tolerance = -0.1 is outside the allowed range [0, 1]"},
        BadFile{"implicit_rho_one", R"({"physics": {"implicit": {"chebyshev_rho": 1}}})",
                "physics.implicit.chebyshev_rho = 1 is outside the allowed range [0, 1)"},
        BadFile{"implicit_rho_big", R"({"physics": {"implicit": {"chebyshev_rho": 1.5}}})",
                "physics.implicit.chebyshev_rho = 1.5 is outside the allowed range"},
        BadFile{"implicit_method", R"({"physics": {"implicit": {"method": "sor"}}})",
                "physics.implicit.method = \"sor\" is not one of \"gauss_seidel\", \"jacobi\""},
        BadFile{"implicit_multilevel", R"({"physics": {"implicit": {"multilevel": 1}}})",
                "physics.implicit.multilevel must be true or false"},
        BadFile{"implicit_unknown", R"({"physics": {"implicit": {"sweeps": 3}}})",
                "physics.implicit.sweeps is not a known field"},
        // Self-collision's contact sub-steps.
        BadFile{"self_collision_substeps_zero", R"({"physics": {"self_collision": {"substeps": 0}}})",
                "physics.self_collision.substeps = 0 is outside the allowed range [1, 16]"},
        BadFile{"self_collision_substeps_big", R"({"physics": {"self_collision": {"substeps": 17}}})",
                "physics.self_collision.substeps = 17 is outside the allowed range [1, 16]"},
        BadFile{"self_collision_substeps_fraction", R"({"physics": {"self_collision": {"substeps": 1.5}}})",
                "physics.self_collision.substeps must be a whole number in [1, 16]"},
        // Out-of-range numbers are echoed as the file wrote them: every digit of a huge integer (not
        // 1.84467e+19), and a value just past a bound not rounded onto it ("1.0000001", not "1").
        BadFile{"huge_integer", R"({"physics": {"self_collision": {"substeps": 18446744073709551615}}})",
                "physics.self_collision.substeps = 18446744073709551615 is outside the allowed range [1, 16]"},
        BadFile{"just_past_bound", R"({"physics": {"implicit": {"tolerance": 1.0000001}}})",
                "physics.implicit.tolerance = 1.0000001 is outside the allowed range [0, 1]"},
        BadFile{"huge_gravity", R"({"physics": {"gravity": [0, -123456789012, 0]}})",
                "physics.gravity[1] = -123456789012 is outside the allowed range"},
        // Numbers a double cannot hold, and NaN / Infinity (not JSON): a range error at the field, never an abort.
        BadFile{"overflow_n", R"({"cloth": {"n": 1e400}})",
                "cloth.n = 1e400 is not a finite number; allowed range [2, 4096]"},
        BadFile{"overflow_gravity", R"({"physics": {"gravity": [0, -1e400, 0]}})",
                "physics.gravity[1] = -1e400 is not a finite number; allowed range [-100, 100] m/s^2"},
        BadFile{"nan_literal", R"({"cloth": {"size": NaN}})", "cloth.size = NaN is not a finite number; allowed range [0.01, 100] m"},
        BadFile{"infinity_literal", R"({"material": {"stiffness": -Infinity}})",
                "material.stiffness = -Infinity is not a finite number; allowed range [100, 25000] N/m"},
        BadFile{"overflow_collider", R"({"colliders": [{"type": "sphere", "radius": 1e999}]})",
                "colliders[0].radius = 1e999 is not a finite number"},
        BadFile{"overflow_outline", R"({"cloth": {"type": "outline", "outline": [[0,0],[1,-1e400],[0,1]]}})",
                "cloth.outline[1][1] = -1e400 is not a finite number; allowed range [-100, 100] m"},
        BadFile{"overflow_where_object", R"({"physics": 1e400})", "physics = 1e400 is not a finite number"},
        BadFile{"overflow_unknown_field", R"({"cloth": {"weight": 1e400}})", "cloth.weight is not a known field"},
        BadFile{"overflow_then_syntax", "{\"cloth\": {\"n\": 1e400,\n \"size\": }}", "line 2, column 10"},
        BadFile{"overflow_bool", R"({"body": 1e400})", "body = 1e400 is not a finite number"},
        BadFile{"type_error_in_sew", R"({"cloth": {"type": "outline", "outline": [[0,0],[1,0],[0,1]], "copy": {"sew": [[0, -1]]}}})",
                "cloth.copy.sew[0]"},
        BadFile{"too_many_colliders", R"({"colliders": [{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}]})", "at most 64"}),
    [](const auto& info) { return std::string(info.param.name); });

TEST(Scenes, MissingFileAndUnknownNameAreClear) {
    try {
        load_scene("/nonexistent/dir/scene.json");
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_TRUE(has(e.what(), "/nonexistent/dir/scene.json")) << e.what();
        EXPECT_TRUE(has(e.what(), "does not exist")) << e.what();
    }
    try {
        load_scene("hangg");
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_TRUE(has(e.what(), "unknown scene 'hangg'")) << e.what();
        EXPECT_TRUE(has(e.what(), "hang, drape, sphere, flag, tshirt")) << e.what();
    }
}

TEST(Scenes, MinimalFileGetsTheHangDefaults) {
    const SceneSpec s = parse_scene("{}", "test.json");
    EXPECT_EQ(s.grid.n, 100u);
    EXPECT_EQ(s.physics.strain_limit.ratio, 0.0f);
    EXPECT_TRUE(s.physics.colliders.empty());
}

} // namespace

namespace {

TEST(Scenes, ImplicitSolverFieldsAndItsDefaultStep) {
    // Absent: the explicit solver, its dt 0.9 x the stability bound.
    const SceneSpec plain = parse_scene(R"({"cloth": {"n": 16}})", "test.json");
    EXPECT_EQ(plain.physics.solver, Solver::explicit_euler);
    const BuiltScene explicit_scene = build_scene(plain);
    EXPECT_LT(explicit_scene.params.dt, 0.01f);
    // Implicit without a dt: one frame, 1/30 s; with one: the file's.
    const SceneSpec s = parse_scene(R"({"cloth": {"n": 16}, "physics": {"solver": "implicit",
        "implicit": {"iterations": 12, "tolerance": 0.01, "chebyshev_rho": 0.5, "method": "jacobi"}}})", "test.json");
    EXPECT_EQ(s.physics.solver, Solver::implicit);
    EXPECT_EQ(s.physics.implicit.iterations, 12u);
    EXPECT_EQ(s.physics.implicit.tolerance, 0.01f);
    EXPECT_EQ(s.physics.implicit.chebyshev_rho, 0.5f);
    EXPECT_EQ(s.physics.implicit.method, ImplicitMethod::jacobi);
    EXPECT_FALSE(s.dt.has_value());
    const BuiltScene b = build_scene(s);
    EXPECT_EQ(b.params.dt, implicit_default_dt);
    EXPECT_EQ(b.params.solver, Solver::implicit);
    const SceneSpec fixed = parse_scene(R"({"cloth": {"n": 16}, "physics": {"solver": "implicit", "dt": 0.05}})", "t.json");
    EXPECT_EQ(build_scene(fixed).params.dt, 0.05f);
    // It runs: a step of a frame, far above the explicit bound.
    Simulation sim(b.cloth, b.initial, b.params);
    sim.step(2);
    EXPECT_TRUE(sim.health().finite);
    EXPECT_GT(sim.implicit_stats().iterations, 0u);
}

TEST(Scenes, OutlinePanelsSewnIntoABag) {
    const std::string path = std::string(DRAPE_SOURCE_DIR) + "/scenes/examples/bag.json";
    BuiltScene b = build_scene(load_scene(path));
    EXPECT_GT(b.cloth.particle_count, 1000u);
    EXPECT_GT(b.cloth.seams.a.size(), 40u);
    std::size_t pinned = 0;
    for (std::size_t i = 0; i < b.cloth.particle_count; ++i) pinned += b.cloth.inv_mass[i] == 0.0f;
    EXPECT_GT(pinned, 10u) << "the top edge of both panels";
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.step(drape::testing::sanitized ? 500 : 2000); // ASan: 43 s with 2000
    const Health h = sim.health();
    EXPECT_TRUE(h.finite);
    EXPECT_LT(h.max_structural_strain, 0.1f + 1e-3f);
}

TEST(Scenes, BrokenOutlinesGiveClearErrors) {
    // A bow tie's two lobes cancel (zero signed area): it is self-intersecting, not collinear.
    const std::string bow_tie = R"({"cloth": {"type": "outline", "outline": [[0,0],[1,1],[1,0],[0,1]]}})";
    EXPECT_TRUE(has(scene_error_of(bow_tie), "cloth.outline: outline is self-intersecting: edge 0 (vertices 0-1) meets edge 2"))
        << scene_error_of(bow_tie);
    EXPECT_FALSE(has(scene_error_of(bow_tie), "collinear")) << scene_error_of(bow_tie);
    const std::string line = R"({"cloth": {"type": "outline", "outline": [[0,0],[1,0],[2,0]]}})";
    EXPECT_TRUE(has(scene_error_of(line), "collinear")) << scene_error_of(line);
    const std::string two = R"({"cloth": {"type": "outline", "outline": [[0,0],[1,1]]}})";
    EXPECT_TRUE(has(scene_error_of(two), "3 to 4096")) << scene_error_of(two);
    const std::string sew = R"({"cloth": {"type": "outline", "outline": [[0,0],[1,0],[0,1]], "copy": {"sew": [[0, 7]]}}})";
    EXPECT_TRUE(has(scene_error_of(sew), "cloth.copy.sew[0]")) << scene_error_of(sew);
    // [k, k] was read as the whole outline (24 seams on a square, as [[3, 0], [0, 3]]): refused.
    const std::string same = R"({"cloth": {"type": "outline", "outline": [[0,0],[1,0],[0,1]], "copy": {"sew": [[1, 1]]}}})";
    EXPECT_TRUE(has(scene_error_of(same), "cloth.copy.sew[0] = [1, 1]: from and to must be different vertices"))
        << scene_error_of(same);
    // A stretch sewn twice (given twice, or overlapping another) sewed its particles again, joining nothing new.
    const std::string twice =
        R"({"cloth": {"type": "outline", "outline": [[0,0],[1,0],[1,1],[0,1]], "copy": {"sew": [[0, 2], [1, 3]]}}})";
    EXPECT_TRUE(has(scene_error_of(twice), "cloth.copy.sew[1] = [1, 3] sews outline edge 1 (vertices 1-2) that "
                                           "cloth.copy.sew[0] sews already"))
        << scene_error_of(twice);
    const std::string loop =
        R"({"cloth": {"type": "outline", "outline": [[0,0],[1,0],[1,1],[0,1]], "copy": {"sew": [[0, 2], [2, 0]]}}})";
    EXPECT_EQ(scene_error_of(loop), "");
    const std::string huge = R"({"cloth": {"type": "outline", "outline": [[0,0],[100,0],[0,100]], "spacing": 0.001}})";
    EXPECT_TRUE(has(scene_error_of(huge), "test.json: cloth.spacing = 0.001 m gives this outline up to")) << scene_error_of(huge);
    EXPECT_TRUE(has(scene_error_of(huge), "at most 4000000")) << scene_error_of(huge);
    // Too thin for its spacing: found only when triangulating (build_scene), still naming the file and the fields.
    const SceneSpec thin =
        parse_scene(R"({"cloth": {"type": "outline", "outline": [[0,0],[1,0],[1,1e-9]], "spacing": 0.3}})", "thin.json");
    try {
        build_scene(thin);
        FAIL() << "a sliver outline built";
    } catch (const InvalidInput& e) {
        EXPECT_TRUE(has(e.what(), "thin.json: cloth.outline at cloth.spacing = 0.3 m: ")) << e.what();
        EXPECT_TRUE(has(e.what(), "too small or too thin")) << e.what();
    }
}

TEST(Scenes, FourHundredDigitIntegerIsARangeError) {
    const std::string text = "{\"cloth\": {\"n\": 1" + std::string(400, '0') + "}}";
    const std::string msg = scene_error_of(text);
    EXPECT_TRUE(has(msg, "test.json: cloth.n = 1000000000")) << msg;
    EXPECT_TRUE(has(msg, "... is not a finite number; allowed range [2, 4096]")) << msg;
}

// Every parse error names the file; whatever nlohmann throws becomes InvalidInput (never an abort).
TEST(Scenes, OnlyInvalidInputEscapesTheParser) {
    const char* cases[] = {"", " ", "nul", "{\"cloth\": {\"n\": 1e400", "[[[[[[[[[[", "{\"cloth\": {\"n\": 18446744073709551616}}",
                           "{\"cloth\": {\"n\": -9223372036854775809}}", "\xff\xfe", "{\"scene\": \"\\ud800\"}",
                           "{\"cloth\": {\"type\": \"outline\", \"outline\": [[0,0],[1,0],[0,1]], \"copy\": {\"sew\": [[0, 1e400]]}}}"};
    for (const char* c : cases) {
        const std::string msg = scene_error_of(c);
        EXPECT_TRUE(has(msg, "test.json: ")) << "'" << c << "': " << msg;
    }
}

// One line of reasonable length whatever the file holds: keys and values with control characters are escaped, a
// syntax error 5,000 arrays deep names a shortened path (the fuzzer's first find: a 10,939-character message).
TEST(Scenes, MessagesStayOneShortLine) {
    const std::string deep = "{\"cloth\": " + std::string(5000, '[') + "-";
    const std::string long_key = "{\"cloth\": {\"" + std::string(100000, 'k') + "\": 1}}";
    for (const std::string& text : {deep, long_key, std::string("{\"cloth\": {\"a\\nb\": 1}}"),
                                    std::string("{\"cloth\": {\"pins\": \"x\\u000dy\"}}"),
                                    std::string("{\"cloth\": {\"n\": 10\n\n  \"size\": 1}}")}) {
        const std::string msg = scene_error_of(text);
        EXPECT_TRUE(has(msg, "test.json: ")) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\r'), std::string::npos) << msg;
        EXPECT_LT(msg.size(), 1000u) << msg.substr(0, 300);
    }
    EXPECT_TRUE(has(scene_error_of("{\"cloth\": {\"a\\nb\": 1}}"), "cloth.a\\u000ab is not a known field"))
        << scene_error_of("{\"cloth\": {\"a\\nb\": 1}}");
    // 5000 levels stop at the depth limit; 200 reach the syntax error, whose path is cut in the middle.
    EXPECT_TRUE(has(scene_error_of(deep), "nested more than 256 deep (at cloth[0][0][0]")) << scene_error_of(deep);
    const std::string malformed = "{\"cloth\": " + std::string(200, '[') + "-";
    EXPECT_TRUE(has(scene_error_of(malformed), "malformed JSON (near cloth[0][0][0]")) << scene_error_of(malformed);
    EXPECT_LT(scene_error_of(malformed).size(), 1000u);
}

// The scene path is checked before it is opened: a FIFO would block the open forever, a directory "opens".
TEST(Scenes, ScenePathMustBeARegularFile) {
    const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("drape_scene_path_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir / "d.json");
    const std::string fifo = (dir / "f.json").string();
    ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
    auto message = [](const std::string& path) {
        try {
            load_scene(path);
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    EXPECT_TRUE(has(message(fifo), "is not a regular file (a FIFO)")) << message(fifo);
    EXPECT_TRUE(has(message((dir / "d.json").string()), "is a directory")) << message((dir / "d.json").string());
    EXPECT_TRUE(has(message((dir / "none.json").string()), "does not exist"));
    {
        std::ofstream big(dir / "big.json");
        big << std::string((16u << 20) + 1, ' ');
    }
    EXPECT_TRUE(has(message((dir / "big.json").string()), "scene files are limited to 16 MiB"));
    std::filesystem::remove_all(dir);
}

} // namespace
