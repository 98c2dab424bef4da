// Mask cloths in scene files (cloth.type "mask", docs/scene_format.md "Mask cloths"): panels, masses from density x
// area, seams between boundary edges, pins, the errors of broken files, writing and reading back, and the resolution
// rule that `drape run --size` and the viewer share (set_scene_resolution).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <string>

#include "drape/errors.hpp"
#include "drape/scene.hpp"
#include "scene_test_util.hpp"
#include "drape/scene_write.hpp"

using namespace drape;
using drape::testing::has;
using drape::testing::scene_error_of;

namespace {

/// A springs-model mask scene: two 4 x 5 panels facing each other 5 cm apart (the back one mirrored), sewn along
/// their left and right columns (a tube), the front panel's top row pinned, the back's cell (0, 2) pinned by list,
/// a second, tilted frame with axes of length 2 (normalised when built).
const char* const tube = R"({
  "scene": "tube",
  "cloth": { "type": "mask", "density": 0.2,
    "panels": [
      { "name": "front", "cell_size": 0.05, "origin": [0.1, 1.0, 0.025], "axis_u": [-1, 0, 0], "axis_v": [0, -1, 0],
        "pins": "top_row", "rows": ["0110", "1111", "1111", "1111", "1111"] },
      { "name": "back", "cell_size": 0.05, "origin": [-0.1, 1.0, -0.025], "axis_u": [2, 0, 0], "axis_v": [0, -2, 0],
        "pins": [[0, 2]], "rows": ["0110", "1111", "1111", "1111", "1111"] }
    ],
    "seams": [
      { "a": { "panel": "front", "path": [[1, 0], [4, 0]] }, "b": { "panel": "back", "path": [[1, 3], [4, 3]] } },
      { "a": { "panel": "front", "path": [[1, 3], [4, 3]] }, "b": { "panel": "back", "path": [[1, 0], [4, 0]] },
        "rest_ratio": 0.25 }
    ] },
  "material": { "stiffness": 2000 }
})";

} // namespace

// The boundary rule the parser uses for seams (mask_cell_on_boundary, from the mask alone) is exactly the boundary
// of the triangle mesh add_mask_panel builds, on random masks (holes, pinches, lone particles, three-corner cells).
TEST(SceneMasks, BoundaryRuleMatchesTheMesh) {
    std::mt19937 rng(12345);
    for (int trial = 0; trial < 200; ++trial) {
        const int rows = 1 + int(rng() % 7), columns = 1 + int(rng() % 7);
        MaskPanel mask;
        for (int r = 0; r < rows; ++r) {
            std::string row;
            for (int c = 0; c < columns; ++c)
                row += rng() % 4 == 0 ? '0' : '1';
            mask.rows.push_back(row);
        }
        if (std::none_of(mask.rows.begin(), mask.rows.end(),
                         [](const std::string& r) { return r.find('1') != std::string::npos; }))
            mask.rows[0][0] = '1';
        GarmentAssembly a;
        const MaskPanelBuild b = add_mask_panel(a, mask, 0.1f, 0.001f);
        const std::set<std::uint32_t> boundary(b.boundary_particles.begin(), b.boundary_particles.end());
        for (int r = 0; r < rows; ++r)
            for (int c = 0; c < columns; ++c) {
                const std::int32_t i = b.particle_at(r, c);
                const bool expected = i >= 0 && boundary.count(std::uint32_t(i)) > 0;
                ASSERT_EQ(mask_cell_on_boundary(mask, r, c), expected)
                    << "trial " << trial << " cell (" << r << ", " << c << ") of\n"
                    << [&] {
                           std::string s;
                           for (auto& row : mask.rows)
                               s += row + "\n";
                           return s;
                       }();
            }
    }
}

TEST(SceneMasks, EdgeCellsFollowThePathsLegs) {
    MaskEdgeSpec e;
    e.path = {{0, 0}, {0, 3}, {2, 5}, {2, 4}};
    const std::vector<std::array<std::uint32_t, 2>> want = {{0, 0}, {0, 1}, {0, 2}, {0, 3}, {1, 4}, {2, 5}, {2, 4}};
    EXPECT_EQ(mask_edge_cells(e), want);
    e.path = {{3, 1}};
    EXPECT_EQ(mask_edge_cells(e).size(), 1u);
}

TEST(SceneMasks, PanelsMassesSeamsAndPins) {
    const SceneSpec spec = parse_scene(tube, "tube.json");
    ASSERT_EQ(spec.cloth, ClothType::mask);
    ASSERT_EQ(spec.masks.panels.size(), 2u);
    EXPECT_EQ(scene_particle_count(spec), 2u * 18u);
    const BuiltScene b = build_scene(spec);
    const Cloth& c = b.cloth;
    ASSERT_EQ(c.particle_count, 36u);
    // Positions: the front's cell (0, 1) at origin + 1 h u; the back's cell (4, 0) at its origin + 4 h v (axes
    // normalised); stored relative to the cloth's origin, the middle of the panels' origins.
    EXPECT_DOUBLE_EQ(c.origin[0], 0.0);
    EXPECT_DOUBLE_EQ(c.origin[1], 1.0);
    EXPECT_DOUBLE_EQ(c.origin[2], 0.0);
    EXPECT_NEAR(b.initial.x[0], 0.1f - 0.05f, 1e-6f);
    EXPECT_NEAR(b.initial.z[0], 0.025f, 1e-6f);
    const std::size_t back_last_row_first = 18 + 14; // back panel: 2 + 4 x 4 particles, row 4 starts at 14
    EXPECT_NEAR(b.initial.x[back_last_row_first], -0.1f, 1e-6f);
    EXPECT_NEAR(b.initial.y[back_last_row_first], -0.2f, 1e-6f);
    // Masses: density x the triangles' area: 3 x 3 full cells below row 1, and above it one full cell and two with
    // three corners (half a cell each) beside the top row's two particles.
    double total = 0.0;
    for (float inv : c.free_inv_mass)
        total += 1.0 / double(inv);
    const double h = 0.05, cells_per_panel = 9.0 + 1.0 + 2 * 0.5; // full cells; the two cells beside the top pair
    EXPECT_NEAR(total, 2.0 * 0.2 * cells_per_panel * h * h, 1e-7);
    // Seams: 4 + 4 pairs, rest = ratio x h.
    std::size_t seams = 0;
    std::set<float> rests;
    for (const Edge& e : c.edges)
        if (e.kind == SpringKind::seam) ++seams, rests.insert(e.rest);
    EXPECT_EQ(seams, 8u);
    EXPECT_EQ(rests, (std::set<float>{0.25f * 0.05f, 0.5f * 0.05f}));
    // Pins: the front's top row (2 particles) and the back's cell (0, 2) (its particle 1).
    std::vector<std::size_t> pinned;
    for (std::size_t i = 0; i < c.particle_count; ++i)
        if (c.inv_mass[i] == 0.0f) pinned.push_back(i);
    EXPECT_EQ(pinned, (std::vector<std::size_t>{0, 1, 19}));
    // It runs.
    Simulation sim(b.cloth, b.initial, b.params);
    sim.step(300);
    EXPECT_TRUE(sim.health().finite);
}

TEST(SceneMasks, FabricMassesComeFromTheFabricsDensity) {
    std::string text = tube;
    text.replace(text.find("\"density\": 0.2,"), 15, "");
    text.replace(text.find("{ \"stiffness\": 2000 }"), 21, "\"denim\"");
    const BuiltScene b = build_scene(parse_scene(text, "tube.json"));
    double total = 0.0;
    for (float inv : b.cloth.free_inv_mass)
        total += 1.0 / double(inv);
    const double denim = double(find_fabric("denim")->density);
    EXPECT_NEAR(total, 2.0 * denim * 11.0 * 0.05 * 0.05, 1e-6 * total);
    // A density beside a fabric is a second answer: refused.
    std::string both = tube;
    both.replace(both.find("{ \"stiffness\": 2000 }"), 21, "\"denim\"");
    EXPECT_TRUE(has(scene_error_of(both), "test.json: cloth.density is a spring-model field")) << scene_error_of(both);
}

TEST(SceneMasks, TankTopExampleIsSewnWithDensityMasses) {
    const SceneSpec spec = load_scene(std::string(DRAPE_SOURCE_DIR) + "/scenes/examples/tank_top.json");
    const BuiltScene b = build_scene(spec);
    EXPECT_EQ(b.cloth.particle_count, 1450u);
    EXPECT_EQ(b.cloth.seams.a.size(), 6u + 6u + 25u + 25u);
    EXPECT_GT(b.params.colliders.size(), 7u); // the body and the ground
    double total = 0.0, area = 0.0;
    for (float inv : b.cloth.free_inv_mass)
        total += 1.0 / double(inv);
    for (const MaskPanelSpec& p : spec.masks.panels) // a cell with 4 corners is two triangles, with 3 one
        for (std::size_t r = 0; r + 1 < p.mask.rows.size(); ++r)
            for (std::size_t c = 0; c + 1 < p.mask.rows[r].size(); ++c) {
                const int corners = (p.mask.rows[r][c] == '1') + (p.mask.rows[r][c + 1] == '1') +
                                    (p.mask.rows[r + 1][c] == '1') + (p.mask.rows[r + 1][c + 1] == '1');
                area += corners == 4 ? 1.0 : corners == 3 ? 0.5 : 0.0;
            }
    area *= 0.02 * 0.02;
    EXPECT_NEAR(total, double(spec.fabric.density) * area, 1e-5 * total);
}

TEST(SceneMasks, BrokenFilesGiveClearErrors) {
    const auto scene = [](const std::string& panels, const std::string& seams = "") {
        return "{\"cloth\": {\"type\": \"mask\", \"panels\": [" + panels + "], \"seams\": [" + seams + "]}}";
    };
    const std::string a = R"({"name": "a", "rows": ["111", "111", "111"]})";
    const std::string b = R"({"name": "b", "rows": ["111", "111", "111"], "origin": [0, 0, 0.1]})";
    const auto seam = [](const std::string& pa, const std::string& pb) {
        return R"({"a": {"panel": "a", "path": )" + pa + R"(}, "b": {"panel": "b", "path": )" + pb + "}}";
    };
    const std::pair<std::string, std::string> cases[] = {
        {scene(R"({"name": "a", "rows": ["111", "11"]})"), "test.json: cloth.panels[0].rows[1] has 2 characters but "
                                                           "cloth.panels[0].rows[0] has 3 (a mask is rectangular"},
        {scene(R"({"name": "a", "rows": ["1 1"]})"),
         "cloth.panels[0].rows[0] column 1 holds ' '; only '0' and '1' are allowed"},
        {scene(R"({"name": "a", "rows": ["1\u00e91"]})"), "cloth.panels[0].rows[0] column 1 holds byte 0xc3"},
        {scene(a + R"(, {"name": "b", "rows": ["00"]})"),
         "cloth.panels[1].rows holds no '1': a panel needs at least one particle"},
        {scene(R"({"name": "a", "rows": []})"), "cloth.panels[0].rows must list 1 to 4096 rows"},
        {scene(R"({"name": "a", "rows": [""]})"), "cloth.panels[0].rows[0] has 0 characters; allowed 1 to 4096"},
        {scene(R"({"rows": ["1"]})"), "cloth.panels[0].name is required"},
        {scene(a + ", " + a), "cloth.panels[1].name = \"a\" names an earlier panel too"},
        {scene(R"({"name": "a", "rows": ["1"], "cell_size": 0})"),
         "cloth.panels[0].cell_size = 0 is outside the allowed range [0.001, 1] m"},
        {scene(R"({"name": "a", "rows": ["1"], "axis_v": [1, 0.1, 0]})"),
         "cloth.panels[0].axis_v is not perpendicular to cloth.panels[0].axis_u"},
        {scene(R"({"name": "a", "rows": ["1"], "axis_u": [0, 0, 0]})"), "cloth.panels[0].axis_u has length 0"},
        {scene(R"({"name": "a", "rows": ["10"], "pins": [[0, 1]]})"), "cloth.panels[0].pins[0] = [0, 1] is a '0' cell"},
        {scene(R"({"name": "a", "rows": ["10"], "pins": "bottom"})"),
         "cloth.panels[0].pins = \"bottom\" is not one of \"none\", \"top_row\""},
        {scene(R"({"name": "a", "rows": ["1"], "colour": 1})"), "cloth.panels[0].colour is not a known field"},
        {scene("", ""), "cloth.panels must list 1 to 256 panels"},
        {scene(a + ", " + b, seam("[[0, 0], [0, 2]]", "[[0, 0], [0, 1]]")),
         "cloth.seams[0].b.path has 2 cells but cloth.seams[0].a.path has 3; a seam joins two edges cell to cell, so "
         "they must have equal lengths"},
        {scene(a + ", " + b, seam("[[1, 0], [1, 2]]", "[[0, 0], [0, 2]]")),
         "cloth.seams[0].a.path passes cell [1, 1], inside panel \"a\": an edge runs along the panel's boundary"},
        {scene(a + ", " + b, seam("[[0, 0], [2, 1]]", "[[0, 0], [2, 1]]")),
         "cloth.seams[0].a.path[1] is not on the same row, column or 45-degree diagonal as cloth.seams[0].a.path[0]"},
        {scene(a + ", " + b, seam("[[0, 0], [0, 3]]", "[[0, 0], [0, 2]]")),
         "cloth.seams[0].a.path[1] = [0, 3] is outside the mask (rows [0, 2], columns [0, 2])"},
        {scene(a + ", " + b, seam("[[0, 0], [0, 0]]", "[[0, 0], [0, 2]]")),
         "cloth.seams[0].a.path[1] repeats the cell before it"},
        {scene(a + ", " + b, seam("[[0, 0], [0, 2], [0, 1]]", "[[0, 0], [0, 2], [0, 1]]")),
         "cloth.seams[0].a.path passes cell [0, 1] twice"},
        {scene(a + R"(, {"name": "b", "rows": ["101"]})", seam("[[0, 0]]", "[[0, 0], [0, 2]]")),
         "cloth.seams[0].b.path passes cell [0, 1] of panel \"b\", a '0'"},
        {scene(a, R"({"a": {"panel": "a", "path": [[0, 0]]}, "b": {"panel": "x", "path": [[0, 0]]}})"),
         "cloth.seams[0].b.panel = \"x\" is not a panel of this cloth (\"a\")"},
        {scene(a, R"({"a": {"panel": "a", "path": [[0, 0]]}})"), "cloth.seams[0].b is required"},
        // A name with a control character is shown escaped: the message stays one line.
        {scene(R"({"name": "a\nb", "rows": ["1"]})",
               R"({"a": {"panel": "x", "path": [[0, 0]]}, "b": {"panel": "x", "path": [[0, 0]]}})"),
         "cloth.seams[0].a.panel = \"x\" is not a panel of this cloth (\"a\\u000ab\")"},
        {scene(a + ", " + b, seam("[[0, 0]]", "[[0, 0]]").insert(1, R"("rest_ratio": 3, )")),
         "cloth.seams[0].rest_ratio = 3 is outside the allowed range [0.01, 2]"},
    };
    for (const auto& [text, want] : cases) {
        const std::string msg = scene_error_of(text);
        EXPECT_TRUE(has(msg, want)) << "want: " << want << "\ngot:  " << msg;
        EXPECT_TRUE(has(msg, "test.json: ")) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    }
    // More than 4096 rows: refused before anything is built.
    std::string rows;
    for (int k = 0; k < 4097; ++k)
        rows += std::string(k ? "," : "") + "\"1\"";
    EXPECT_TRUE(has(scene_error_of(scene(R"({"name": "a", "rows": [)" + rows + "]}")),
                    "cloth.panels[0].rows has 4097 entries (at most 4096)"));
}

// A seam that joins nothing (an edge sewn to itself, or two rows of one panel its springs join already) ran as if
// sewn, silently.
TEST(SceneMasks, SeamsThatJoinNothingAreRefused) {
    const auto build_error = [](const std::string& pa, const std::string& pb, const std::string& second = "a") {
        const std::string text = R"({"cloth": {"type": "mask", "panels": [{"name": "a", "rows": ["111", "111"]},
            {"name": "b", "rows": ["111", "111"], "origin": [0, 0, 0.1]}],
            "seams": [{"a": {"panel": "a", "path": )" + pa + R"(}, "b": {"panel": ")" + second +
                                 R"(", "path": )" + pb + "}}]}}";
        try {
            build_scene(parse_scene(text, "test.json"));
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    std::string msg = build_error("[[0, 0], [0, 2]]", "[[0, 0], [0, 2]]");
    EXPECT_TRUE(has(msg, "test.json: cloth.seams[0] joins nothing: of its 3 cell pairs 3 pair a cell with itself and "
                         "0 pair cells already joined")) << msg;
    msg = build_error("[[0, 0], [0, 2]]", "[[1, 0], [1, 2]]"); // the structural springs between rows 0 and 1
    EXPECT_TRUE(has(msg, "of its 3 cell pairs 0 pair a cell with itself and 3 pair cells already joined")) << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
    // One new pair is enough; a seam to the other panel is a seam.
    EXPECT_EQ(build_error("[[0, 0], [0, 2]]", "[[1, 2], [1, 0]]"), ""); // (0, 0) to (1, 2), (0, 2) to (1, 0)
    EXPECT_EQ(build_error("[[0, 0], [0, 2]]", "[[0, 0], [0, 2]]", "b"), "");
}

// A '1' touching no other '1' and no seam was a loose particle: a checkerboard mask ran "healthy" with 0 springs.
TEST(SceneMasks, LooseCellsAreRefusedNamingTheFirst) {
    const auto build_error = [](const std::string& rows, const std::string& seams = "") {
        const std::string text = R"({"cloth": {"type": "mask", "panels": [{"name": "a", "rows": )" + rows +
                                 R"(}, {"name": "b", "rows": ["11", "11"], "origin": [0, 0, 0.1]}], "seams": [)" + seams +
                                 "]}}";
        try {
            build_scene(parse_scene(text, "test.json"));
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string();
    };
    std::string msg = build_error(R"(["101", "010", "101"])");
    EXPECT_TRUE(has(msg, "test.json: cloth.panels[0] \"a\": the '1' at row 0, column 0 touches no other '1'")) << msg;
    EXPECT_TRUE(has(msg, "(5 such cells in the cloth)")) << msg;
    msg = build_error(R"(["110", "010", "001"])");
    EXPECT_TRUE(has(msg, "the '1' at row 2, column 2") && has(msg, "(1 such cell in the cloth)")) << msg;
    // Joined across a cell's corner with a shared neighbour, or sewn: accepted.
    EXPECT_EQ(build_error(R"(["110", "011"])"), "");
    EXPECT_EQ(build_error(R"(["11", "11", "00", "01"])",
                          R"({"a": {"panel": "a", "path": [[3, 1]]}, "b": {"panel": "b", "path": [[0, 0]]}})"),
              "");
}

// load -> save -> load gives the same cloth: particles, positions, masses, pins, springs (kind, ends, rest).
TEST(SceneMasks, RoundTripThroughSceneFiles) {
    for (const std::string& source : {std::string(tube), std::string("tank_top")}) {
        const SceneSpec first = source == "tank_top"
                                    ? load_scene(std::string(DRAPE_SOURCE_DIR) + "/scenes/examples/tank_top.json")
                                    : parse_scene(source, "tube.json");
        const std::string text = scene_to_json(first);
        const SceneSpec second = parse_scene(text, "saved.json");
        EXPECT_EQ(scene_to_json(second), text);
        const BuiltScene a = build_scene(first), b = build_scene(second);
        ASSERT_EQ(a.cloth.particle_count, b.cloth.particle_count);
        EXPECT_EQ(a.cloth.origin, b.cloth.origin);
        EXPECT_EQ(a.initial.x, b.initial.x);
        EXPECT_EQ(a.initial.y, b.initial.y);
        EXPECT_EQ(a.initial.z, b.initial.z);
        EXPECT_EQ(a.cloth.free_inv_mass, b.cloth.free_inv_mass);
        for (std::size_t i = 0; i < a.cloth.particle_count; ++i)
            ASSERT_EQ(a.cloth.inv_mass[i], b.cloth.inv_mass[i]) << i;
        ASSERT_EQ(a.cloth.edges.size(), b.cloth.edges.size());
        for (std::size_t k = 0; k < a.cloth.edges.size(); ++k) {
            const Edge& ea = a.cloth.edges[k];
            const Edge& eb = b.cloth.edges[k];
            ASSERT_TRUE(ea.a == eb.a && ea.b == eb.b && ea.kind == eb.kind && ea.rest == eb.rest &&
                        ea.scale == eb.scale)
                << k;
        }
        EXPECT_EQ(a.cloth.triangles, b.cloth.triangles);
        EXPECT_EQ(a.params.dt, b.params.dt);
    }
}

// --size (and the viewer's resolution slider) through one rule: grid n, T-shirt and outline cells per metre,
// refused for a mesh or a mask cloth.
TEST(SceneMasks, ResolutionRule) {
    SceneSpec outline = parse_scene(
        R"({"cloth": {"type": "outline", "outline": [[0,0],[0.3,0],[0,0.3]], "spacing": 0.025}})", "o.json");
    EXPECT_EQ(scene_resolution(outline), 40u);
    const std::size_t before = build_scene(outline).cloth.particle_count;
    set_scene_resolution(outline, 80);
    EXPECT_EQ(outline.outline.spacing, 1.0f / 80.0f);
    EXPECT_EQ(scene_resolution(outline), 80u);
    EXPECT_GT(build_scene(outline).cloth.particle_count, 3 * before);
    try {
        set_scene_resolution(outline, 5, "--size");
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_TRUE(
            has(e.what(), "--size: value 5 is outside the allowed range [10, 1000] (cells per metre of the outline"))
            << e.what();
    }
    SceneSpec big =
        parse_scene(R"({"cloth": {"type": "outline", "outline": [[0,0],[50,0],[0,50]], "spacing": 0.1}})", "big.json");
    try {
        set_scene_resolution(big, 1000, "--size");
        FAIL();
    } catch (const InvalidInput& e) {
        EXPECT_TRUE(has(e.what(), "points per panel; at most 4000000")) << e.what();
    }
    EXPECT_EQ(big.outline.spacing, 0.1f); // unchanged when refused
    SceneSpec mask = parse_scene(tube, "tube.json");
    EXPECT_FALSE(scene_resolution(mask).has_value());
    EXPECT_THROW(set_scene_resolution(mask, 50), InvalidInput);
    SceneSpec grid = load_scene("hang");
    set_scene_resolution(grid, 40);
    EXPECT_EQ(grid.grid.n, 40u);
    EXPECT_THROW(set_scene_resolution(grid, 5000), InvalidInput);
}
