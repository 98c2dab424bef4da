// Mesh cloths (cloth.type = "mesh"): an OBJ file becomes particles, springs and triangles; broken files are clear
// errors. The asset tests/data/disc.obj is written by tests/data/make_disc_obj.py.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <unistd.h>

#include "drape/scene.hpp"
#include "drape/scene_write.hpp"

using namespace drape;

namespace {

const std::string source_dir = DRAPE_SOURCE_DIR;
const std::string disc_obj = source_dir + "/tests/data/disc.obj";
const std::string disc_scene = source_dir + "/scenes/examples/mesh_disc.json";

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// The OBJ read independently of drape (plain text: "v x y z", "f a b c" with 1-based indices).
struct PlainObj {
    std::vector<std::array<double, 3>> v;
    std::vector<std::array<std::size_t, 3>> f;
};
PlainObj read_plain(const std::string& path) {
    PlainObj o;
    std::ifstream in(path);
    std::string line;
    while (std::getline(in, line)) {
        std::istringstream s(line);
        std::string tag;
        s >> tag;
        if (tag == "v") {
            std::array<double, 3> p{};
            s >> p[0] >> p[1] >> p[2];
            o.v.push_back(p);
        } else if (tag == "f") {
            std::array<std::size_t, 3> t{};
            s >> t[0] >> t[1] >> t[2];
            o.f.push_back({t[0] - 1, t[1] - 1, t[2] - 1});
        }
    }
    return o;
}

std::filesystem::path temp_dir() {
    const auto dir = std::filesystem::temp_directory_path() / ("drape_mesh_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    return dir;
}

std::string write_file(const std::string& name, const std::string& text) {
    const std::string path = (temp_dir() / name).string();
    std::ofstream(path) << text;
    return path;
}

/// A scene whose cloth is the mesh at `obj` (path relative to the scene file, which goes beside it).
std::string mesh_scene(const std::string& obj, const std::string& extra = "") {
    return R"({"cloth": {"type": "mesh", "file": ")" + obj + R"(", "density": 0.2)" + extra + "}}";
}

std::string load_error(const std::string& scene_path) {
    try {
        build_scene(load_scene(scene_path));
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "";
}

TEST(MeshCloth, DiscSceneMatchesItsObjFile) {
    const PlainObj obj = read_plain(disc_obj);
    ASSERT_EQ(obj.v.size(), 469u);
    ASSERT_EQ(obj.f.size(), 864u);
    SceneSpec spec = load_scene(disc_scene);
    ASSERT_EQ(spec.cloth, ClothType::mesh);
    EXPECT_TRUE(spec.warnings.empty());
    // The seeds' spring model on this mesh (the scene's own fabric: tests/test_triangle_fabric.cpp).
    spec.model = MaterialModel::springs;
    const BuiltScene b = build_scene(spec);
    EXPECT_EQ(b.cloth.particle_count, obj.v.size()) << "one particle per OBJ vertex";
    EXPECT_EQ(b.cloth.triangles.size(), 3 * obj.f.size());

    // Mass = density x area (area from the file, here independently).
    double area = 0.0;
    for (const auto& t : obj.f) {
        const auto &a = obj.v[t[0]], &p = obj.v[t[1]], &c = obj.v[t[2]];
        const double u[3] = {p[0] - a[0], p[1] - a[1], p[2] - a[2]}, w[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        const double x = u[1] * w[2] - u[2] * w[1], y = u[2] * w[0] - u[0] * w[2], z = u[0] * w[1] - u[1] * w[0];
        area += 0.5 * std::sqrt(x * x + y * y + z * z);
    }
    double mass = 0.0;
    for (std::size_t i = 0; i < b.cloth.particle_count; ++i) {
        ASSERT_GT(b.cloth.inv_mass[i], 0.0f) << "pins none";
        mass += 1.0 / b.cloth.inv_mass[i];
    }
    EXPECT_NEAR(mass, double(spec.mesh.density) * area, 1e-6 * mass);
    EXPECT_NEAR(area, 0.28, 0.01) << "a 12-ring polygon of radius 0.3: just under pi 0.09 = 0.283";

    // Structural springs = the unique edges of the OBJ, with their lengths; bend springs = its interior edges.
    std::map<std::pair<std::size_t, std::size_t>, int> edges;
    for (const auto& t : obj.f)
        for (int k = 0; k < 3; ++k) ++edges[std::minmax(t[k], t[(k + 1) % 3])];
    std::size_t interior = 0;
    for (const auto& [e, count] : edges) interior += count == 2 ? 1 : 0;
    std::set<std::pair<std::size_t, std::size_t>> structural;
    std::size_t bend = 0, other = 0;
    for (const Edge& e : b.cloth.edges) {
        if (e.kind == SpringKind::structural) {
            structural.insert({e.a, e.b});
            const auto &p = obj.v[e.a], &q = obj.v[e.b];
            const double len = std::sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
            EXPECT_NEAR(e.rest, len, 1e-6);
        } else if (e.kind == SpringKind::bend) {
            ++bend;
        } else {
            ++other;
        }
    }
    std::set<std::pair<std::size_t, std::size_t>> expected;
    for (const auto& [e, count] : edges) expected.insert(e);
    EXPECT_EQ(structural, expected);
    EXPECT_EQ(structural.size(), obj.v.size() + obj.f.size() - 1) << "Euler: V - E + F = 1 for a disc";
    EXPECT_EQ(bend, interior) << "one bend spring across each interior edge";
    EXPECT_EQ(other, 0u) << "no shear or seam springs on a mesh";

    // Placed: the bounding-box centre at cloth.centre, which is the cloth's origin (positions are stored relative
    // to it).
    float lo[3] = {1e9f, 1e9f, 1e9f}, hi[3] = {-1e9f, -1e9f, -1e9f};
    for (std::size_t i = 0; i < b.cloth.particle_count; ++i) {
        const float p[3] = {b.initial.x[i], b.initial.y[i], b.initial.z[i]};
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    }
    for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(b.cloth.origin[k], double(spec.mesh.centre[k])) << k;
        EXPECT_NEAR(b.cloth.origin[k] + 0.5 * (lo[k] + hi[k]), spec.mesh.centre[k], 1e-6) << k;
    }
}

TEST(MeshCloth, DiscDropsOntoTheSphereAndStaysHealthy) {
    BuiltScene b = build_scene(load_scene(disc_scene));
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    const std::size_t substeps = static_cast<std::size_t>(2.0 / sim.params().dt); // 2 s
    sim.step(substeps);
    const Health h = sim.health();
    EXPECT_TRUE(h.finite);
    EXPECT_LT(h.max_structural_strain, 0.15f) << "strain limit 0.1 holds (approximately)";
    EXPECT_LT(h.kinetic_energy, 1e-3) << "J: settling, not exploding";
    // Draped over the sphere: the centre rests on top, the rim hangs below it.
    const Collider& sphere = sim.params().colliders[0];
    float centre_y = 0.0f, lowest = 1e9f;
    for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
        EXPECT_FALSE(is_inside(sphere, {sim.x()[i], sim.y()[i], sim.z()[i]}, 1e-4f)) << i;
        lowest = std::min(lowest, sim.y()[i]);
    }
    centre_y = float(sim.origin()[1] + sim.y()[0]); // OBJ vertex 0 is the disc's centre (world y)
    EXPECT_NEAR(centre_y, 0.205f, 0.01f);
    EXPECT_LT(sim.origin()[1] + lowest, 0.1) << "the rim drapes down (world y)";
}

TEST(MeshCloth, QuadsAreTriangulatedAndTopPinsHold) {
    // A vertical 5 x 5 quad grid, 0.1 m cells, in the x-y plane; faces are quads (and one pentagon row is not needed).
    std::string obj = "# quads\n";
    for (int r = 0; r < 5; ++r)
        for (int c = 0; c < 5; ++c) obj += "v " + std::to_string(0.1 * c) + " " + std::to_string(-0.1 * r) + " 0\n";
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) {
            const int a = r * 5 + c + 1;
            obj += "f " + std::to_string(a) + " " + std::to_string(a + 5) + " " + std::to_string(a + 6) + " " +
                   std::to_string(a + 1) + "\n";
        }
    write_file("quads.obj", obj);
    const std::string scene = write_file("quads.json", mesh_scene("quads.obj", R"(, "pins": "top", "centre": [0, 1, 0])"));
    BuiltScene b = build_scene(load_scene(scene));
    EXPECT_EQ(b.cloth.particle_count, 25u);
    EXPECT_EQ(b.cloth.triangles.size(), 3u * 32u) << "16 quads, 2 triangles each";
    std::vector<std::uint32_t> pinned;
    for (std::uint32_t i = 0; i < 25; ++i)
        if (b.cloth.inv_mass[i] == 0.0f) pinned.push_back(i);
    EXPECT_EQ(pinned, (std::vector<std::uint32_t>{0, 1, 2, 3, 4})) << "the top row";
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.step(5000);
    EXPECT_TRUE(sim.health().finite);
    const float oy = float(sim.origin()[1]);
    EXPECT_FLOAT_EQ(oy + sim.y()[0], 1.2f) << "pinned top row stays (centre 1 + half height 0.2)";
    EXPECT_LT(oy + sim.y()[24], 0.8f) << "the rest hangs, stretched a little";
    EXPECT_GT(oy + sim.y()[24], 0.7f);
}

TEST(MeshCloth, PinListWeldsDegenerateAndNonManifold) {
    // Vertices 1-4: a square of two triangles (1 2 3, and 1 5 4 with vertex 5 a duplicate of 3: welded); a
    // degenerate triangle (3 5 4 after welding: a repeated vertex) and a zero-area one (1 2 6, vertex 6 on the line
    // 1-2); 3 2 1 repeats 1 2 3; two fins, 1 2 7 and 2 1 9, make edge 1-2 shared by three triangles (non-manifold);
    // vertices 6 and 8 are in no kept face.
    const std::string obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 1 1 0\nv 0.5 0 0\nv 0.5 0 1\nv 9 9 9\n"
                            "v 0.5 0 -1\nf 1 2 3\nf 1 5 4\nf 3 5 4\nf 1 2 6\nf 1 2 7\nf 3 2 1\nf 2 1 9\n";
    write_file("odd.obj", obj);
    const std::string scene = write_file("odd.json", mesh_scene("odd.obj", R"(, "pins": [3, 4])"));
    const SceneSpec spec = load_scene(scene);
    const TriangleMesh& m = *spec.mesh.mesh;
    EXPECT_EQ(m.obj_vertices(), 9u);
    EXPECT_EQ(m.particle_count(), 6u) << "1 2 3 4 7 9; 5 welded to 3; 6 and 8 unused";
    EXPECT_EQ(m.welded, 1u);
    EXPECT_EQ(m.degenerate, 2u);
    EXPECT_EQ(m.repeated, 1u) << "3 2 1 repeats 1 2 3";
    EXPECT_EQ(m.unused, 2u);
    EXPECT_EQ(m.triangle_count(), 4u);
    ASSERT_EQ(spec.warnings.size(), 1u);
    EXPECT_TRUE(has(spec.warnings[0], "odd.obj") && has(spec.warnings[0], "2 degenerate triangles dropped") &&
                has(spec.warnings[0], "1 vertices welded"))
        << spec.warnings[0];
    // OBJ vertices 3 and 4 (0-based) -> particles of "v 0 1 0" and the welded "v 1 1 0".
    const BuiltScene b = build_scene(spec);
    EXPECT_EQ(b.cloth.inv_mass[m.particle_of_vertex[3]], 0.0f);
    EXPECT_EQ(b.cloth.inv_mass[m.particle_of_vertex[4]], 0.0f);
    EXPECT_EQ(m.particle_of_vertex[4], m.particle_of_vertex[2]);
    std::size_t bend = 0;
    for (const Edge& e : b.cloth.edges) bend += e.kind == SpringKind::bend ? 1 : 0;
    // Edges: 0-1 (3 triangles: no bend), 1-2, 0-2 (shared by 2: bend 1-3), 0-3, 2-3, 0-4, 1-4, 0-5, 1-5.
    EXPECT_EQ(b.cloth.edges.size() - bend, 9u);
    EXPECT_EQ(bend, 1u) << "only the manifold interior edge 0-2 gets a bend spring";
    const std::string never_used = write_file("odd2.json", mesh_scene("odd.obj", R"(, "pins": [7])"));
    const std::string e = load_error(never_used);
    EXPECT_TRUE(has(e, "cloth.pins[0]") && has(e, "in no triangle")) << e;
    const std::string out_of_range = write_file("odd3.json", mesh_scene("odd.obj", R"(, "pins": [9])"));
    EXPECT_TRUE(has(load_error(out_of_range), "cloth.pins[0] must be an OBJ vertex index in [0, 8]"))
        << load_error(out_of_range);
}

TEST(MeshCloth, BrokenObjFilesGiveOneClearLine) {
    struct Case {
        const char* name;
        std::string text;
        std::vector<std::string> message;
    };
    const std::vector<Case> cases = {
        {"garbage.obj", "this is not an obj file\n\x01\x02\x03 v\n", {"no triangle", "no faces"}},
        {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n", {"line 5", "face vertex index 9", "[1, 3]"}},
        {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", {"line 4", "index 0"}},
        {"noface.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", {"no triangle", "no faces"}},
        {"nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", {"line 2", "'nan'", "not a finite number"}},
        {"inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1e400 0\nf 1 2 3\n", {"line 3", "not a finite number"}},
        {"short.obj", "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", {"line 1", "3 coordinates"}},
        {"word.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", {"line 4", "'x' is not a vertex index"}},
        {"flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", {"no triangle left", "1 degenerate"}},
        {"relative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", {"line 4", "-4", "before the first vertex"}},
    };
    for (const Case& c : cases) {
        write_file(c.name, c.text);
        const std::string scene = write_file(std::string(c.name) + ".json", mesh_scene(c.name));
        const std::string e = load_error(scene);
        EXPECT_TRUE(has(e, scene + ": cloth.file \"" + c.name + "\":")) << c.name << ": " << e;
        for (const std::string& part : c.message) EXPECT_TRUE(has(e, part)) << c.name << ": " << e;
        EXPECT_FALSE(has(e, "\n")) << c.name << ": one line: " << e;
    }
    const std::string missing = write_file("missing.json", mesh_scene("no_such.obj"));
    EXPECT_TRUE(has(load_error(missing), "no_such.obj: cannot open the OBJ file")) << load_error(missing);
    const std::string dir = write_file("dir.json", mesh_scene("."));
    EXPECT_TRUE(has(load_error(dir), "is not a regular file")) << load_error(dir);
    const std::string nofile = write_file("nofile.json", R"({"cloth": {"type": "mesh"}})");
    EXPECT_TRUE(has(load_error(nofile), "cloth.file is required")) << load_error(nofile);
    write_file("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string bad_pins = write_file("bad_pins.json", mesh_scene("tri.obj", R"(, "pins": "corners")"));
    EXPECT_TRUE(has(load_error(bad_pins), "cloth.pins = \"corners\" is not one of \"none\", \"top\"")) << load_error(bad_pins);
    const std::string bad_scale = write_file("bad_scale.json", mesh_scene("tri.obj", R"(, "scale": 0)"));
    EXPECT_TRUE(has(load_error(bad_scale), "cloth.scale")) << load_error(bad_scale);
    // "top" on a mesh lying flat and level would pin every vertex (nothing would move).
    write_file("flat.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
    const std::string flat = write_file("flat.json", mesh_scene("flat.obj", R"(, "pins": "top")"));
    EXPECT_TRUE(has(load_error(flat), "cloth.pins = \"top\" would pin every particle of this mesh (all 3")) << load_error(flat);
}

// A needle (a short edge across wide triangles) in an OBJ cloth of the fabric model: its membrane spring would be far
// stiffer than the fabric; the refusal names the OBJ vertices (as the file numbers them) and the place in file units,
// not two particle numbers. An unused first vertex makes particle and vertex numbers differ.
TEST(MeshCloth, FabricNeedleIsRefusedNamingItsObjVertices) {
    const auto obj = [](const char* width) {
        return std::string("v 5 5 5\nv 0 0 0\nv ") + width + " 0 0\nv 0.0002 1 0\nv 0.0002 -1 0\nf 2 3 4\nf 3 2 5\n";
    };
    const auto scene = [](const char* file) {
        return std::string(R"({"cloth": {"type": "mesh", "file": ")") + file +
               R"("}, "material": {"fabric": "denim"}})";
    };
    write_file("needle.obj", obj("0.0004"));
    const std::string needle = write_file("needle.json", scene("needle.obj"));
    const std::string e = load_error(needle);
    EXPECT_TRUE(has(e, needle + ": cloth.file: the edge from OBJ vertex 2 to vertex 3 (numbered from 1 as in the "
                               "file's faces; near (0.0002, 0, 0) in the file) is the short side of a needle triangle")) << e;
    EXPECT_TRUE(has(e, "times as stiff as the fabric (at most 1000); remesh there")) << e;
    EXPECT_FALSE(has(e, "\n")) << e;
    // Twenty times wider, the edge's spring is 400 times softer: the same file builds.
    write_file("wide.obj", obj("0.008"));
    const std::string wide = write_file("wide.json", scene("wide.obj"));
    EXPECT_EQ(load_error(wide), "");
}

TEST(MeshCloth, ParseObjMeshDirectly) {
    // Polygons (a pentagon) are triangulated by tinyobjloader; negative (relative) indices work; materials ignored.
    const TriangleMesh m = parse_obj_mesh("mtllib none.mtl\nusemtl cloth\nv 0 0 0\nv 1 0 0\nv 1.5 1 0\nv 0.5 1.5 0\n"
                                          "v -0.5 1 0\nf -5 -4 -3 -2 -1\n",
                                          "pentagon");
    EXPECT_EQ(m.particle_count(), 5u);
    EXPECT_EQ(m.triangle_count(), 3u);
    EXPECT_GT(m.area(), 1.0);
    EXPECT_EQ(m.cleaning_note(), "");
}

TEST(MeshCloth, ByteOrderMarkIsNotPartOfTheFirstLine) {
    const TriangleMesh m = parse_obj_mesh("\xEF\xBB\xBFv 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nf 1 2 3\n", "bom.obj");
    ASSERT_EQ(m.particle_count(), 3u); // vertex 4 is in no triangle
    EXPECT_EQ(m.x[0], 0.0);
    EXPECT_EQ(m.x[1], 1.0);
    EXPECT_EQ(m.z[2], 1.0);
    EXPECT_NEAR(m.area(), 0.5, 1e-12);
}

TEST(MeshCloth, TooManyVerticesAreRefusedBeforeParsing) {
    // The limit is 16,777,216; a test file that size would be 134 MB, so the same check runs with a limit of 3.
    const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    EXPECT_EQ(parse_obj_mesh(tri, "three.obj", 3).particle_count(), 3u);
    try {
        parse_obj_mesh("v 0 0 1\n" + tri, "four.obj", 3);
        ADD_FAILURE() << "four vertices accepted with a limit of 3";
    } catch (const InvalidInput& e) {
        EXPECT_EQ(std::string(e.what()), "four.obj: line 4: more than 3 vertices (a mesh cloth has at most 3 particles)");
    }
    EXPECT_EQ(mesh_max_vertices, 16777216u);
}

TEST(MeshCloth, ScaleAndCentreAndSaveReload) {
    write_file("tri2.obj", "v 10 10 10\nv 12 10 10\nv 10 12 10\nf 1 2 3\n");
    const std::string scene =
        write_file("scaled.json", mesh_scene("tri2.obj", R"(, "scale": 0.5, "centre": [1, 2, 3], "pins": [0])"));
    const SceneSpec spec = load_scene(scene);
    const BuiltScene b = build_scene(spec);
    const auto& o = b.cloth.origin; // world = origin + stored
    EXPECT_FLOAT_EQ(float(o[0] + b.initial.x[0]), 0.5f);
    EXPECT_FLOAT_EQ(float(o[1] + b.initial.y[0]), 1.5f);
    EXPECT_FLOAT_EQ(float(o[2] + b.initial.z[0]), 3.0f);
    EXPECT_FLOAT_EQ(float(o[0] + b.initial.x[1]), 1.5f);
    double mass = 0.0;
    for (std::size_t i = 1; i < 3; ++i) mass += 1.0 / b.cloth.inv_mass[i];
    EXPECT_NEAR(mass, 0.2 * 0.5 * 2.0 / 3.0, 1e-7) << "density 0.2 x area 0.5 (scaled), 2 of 3 vertices free";
    // Saved into another directory, the OBJ path is written relative to the new file and still resolves.
    const std::filesystem::path other = temp_dir() / "elsewhere";
    std::filesystem::create_directories(other);
    const std::string saved = (other / "copy.json").string();
    save_scene(saved, spec);
    std::ifstream in(saved);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_TRUE(has(text, "\"file\": \"../tri2.obj\"")) << text;
    const SceneSpec back = load_scene(saved);
    EXPECT_EQ(back.mesh.file, spec.mesh.file);
    EXPECT_EQ(back.mesh.pin_vertices, spec.mesh.pin_vertices);
    EXPECT_EQ(build_scene(back).initial.x, b.initial.x);
}

} // namespace
