// OBJ frames written by `drape run --export-obj` read back with tinyobjloader (Debian's libtinyobjloader-dev), the
// loader many tools use: vertex and face counts, positions equal to the simulation's, unit normals.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include <tiny_obj_loader.h>

#include "drape/scene.hpp"
#include "obj_export.hpp"

using namespace drape;

TEST(ObjExport, FrameReadsBackWithTinyObjLoader) {
    for (const char* name : {"hang", "tshirt"}) {
        BuiltScene b = build_scene(load_scene(name));
        Simulation sim(std::move(b.cloth), b.initial, b.params);
        sim.step(300);
        const auto dir = std::filesystem::temp_directory_path() / ("drape_obj_test_" + std::string(name));
        std::filesystem::remove_all(dir);
        app::ObjExporter exporter(sim.cloth(), dir.string());
        const std::string path = exporter.write(sim, 7);
        EXPECT_EQ(std::filesystem::path(path).filename(), "frame_00007.obj");

        tinyobj::ObjReader reader;
        ASSERT_TRUE(reader.ParseFromFile(path)) << reader.Error();
        const tinyobj::attrib_t& at = reader.GetAttrib();
        const std::size_t n = sim.cloth().particle_count;
        ASSERT_EQ(at.vertices.size(), 3 * n);
        ASSERT_EQ(at.normals.size(), 3 * n);
        ASSERT_EQ(reader.GetShapes().size(), 1u);
        EXPECT_EQ(reader.GetShapes()[0].mesh.indices.size(), sim.cloth().triangles.size());
        for (std::size_t i = 0; i < n; ++i) {
            EXPECT_NEAR(at.vertices[3 * i], sim.x()[i], 1e-5f * (1.0f + std::fabs(sim.x()[i])));
            EXPECT_NEAR(at.vertices[3 * i + 1], sim.y()[i], 1e-5f * (1.0f + std::fabs(sim.y()[i])));
            const float len = std::hypot(at.normals[3 * i], at.normals[3 * i + 1], at.normals[3 * i + 2]);
            EXPECT_NEAR(len, 1.0f, 1e-3f) << name << " vertex " << i;
        }
        for (std::size_t k = 0; k < 30; ++k) { // faces refer to the right vertices (OBJ is 1-based)
            EXPECT_EQ(std::uint32_t(reader.GetShapes()[0].mesh.indices[k].vertex_index), sim.cloth().triangles[k]);
        }
        std::filesystem::remove_all(dir);
    }
}

TEST(ObjExport, UnwritableDirectoryIsAClearError) {
    BuiltScene b = build_scene(load_scene("flag"));
    // An output that cannot be written is WriteError (exit code 5), naming the flag and the path.
    try {
        app::ObjExporter exporter(b.cloth, "/proc/drape_cannot_write_here");
        FAIL() << "an exporter into /proc was created";
    } catch (const WriteError& e) {
        EXPECT_NE(std::string(e.what()).find("--export-obj: cannot create directory '/proc/drape_cannot_write_here'"),
                  std::string::npos)
            << e.what();
    }
}
