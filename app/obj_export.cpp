#include "obj_export.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "drape/errors.hpp"

namespace drape::app {

namespace {

/// frame_<5 or more digits>.obj: the names ObjExporter writes.
bool is_frame_name(const std::string& name) {
    if (name.size() < 15 || name.rfind("frame_", 0) != 0 || name.compare(name.size() - 4, 4, ".obj") != 0) return false;
    for (std::size_t i = 6; i + 4 < name.size(); ++i)
        if (name[i] < '0' || name[i] > '9') return false;
    return true;
}

} // namespace

ObjExporter::ObjExporter(const Cloth& cloth, std::string directory, bool overwrite)
    : directory_(std::move(directory)), publisher_(std::make_unique<Publisher>(cloth)),
      planes_(publisher_->output_floats()) {
    std::error_code ec;
    std::filesystem::create_directories(directory_, ec);
    if (ec || !std::filesystem::is_directory(directory_))
        throw WriteError("--export-obj: cannot create directory '" + directory_ + "': " + ec.message());
    // Frames already there (an earlier export, or the user's own files of that name) would be overwritten in part,
    // leaving a sequence that mixes two runs: refused unless --overwrite, which removes them all first.
    std::vector<std::filesystem::path> frames;
    for (const auto& entry : std::filesystem::directory_iterator(directory_, ec))
        if (is_frame_name(entry.path().filename().string())) frames.push_back(entry.path());
    if (ec) throw WriteError("--export-obj: cannot read directory '" + directory_ + "': " + ec.message());
    if (frames.empty()) return;
    std::sort(frames.begin(), frames.end());
    if (!overwrite)
        throw InvalidInput("--export-obj: '" + directory_ + "' already holds " + std::to_string(frames.size()) +
                           " frame_*.obj file" + (frames.size() == 1 ? "" : "s") + " (" +
                           frames.front().filename().string() +
                           (frames.size() == 1 ? "" : " ... " + frames.back().filename().string()) +
                           "); choose an empty or new directory, or add --overwrite to remove them first");
    for (const auto& f : frames)
        if (!std::filesystem::remove(f, ec) || ec)
            throw WriteError("--export-obj --overwrite: cannot remove '" + f.string() + "': " + ec.message());
}

std::string ObjExporter::write(const Simulation& sim, std::size_t index) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05zu.obj", index);
    const std::string path = (std::filesystem::path(directory_) / name).string();
    try {
        write_obj_file(path, sim, *publisher_, planes_, index);
    } catch (const WriteError& e) {
        throw WriteError(std::string("--export-obj: ") + e.what());
    }
    return path;
}

void write_obj_file(const std::string& path, const Simulation& sim, Publisher& publisher,
                    std::vector<float>& scratch, std::size_t frame_index) {
    if (scratch.size() < publisher.output_floats()) scratch.resize(publisher.output_floats());
    publisher.publish(sim.x(), sim.y(), sim.z(), scratch);
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) throw WriteError("cannot write '" + path + "' (" + std::strerror(errno) + ")");
    const std::vector<std::uint32_t>& triangles = sim.cloth().triangles;
    const std::size_t n = publisher.particle_count(), stride = publisher.plane_floats();
    const float* p = scratch.data();
    std::fprintf(f, "# drape frame %zu, t = %.6f s, %zu vertices, %zu triangles\n", frame_index, sim.time(), n,
                 triangles.size() / 3);
    // World positions: the simulation's origin added back in double, with digits enough for the float32
    // relative position when the origin is away from zero (1000 m + 1 nm).
    const std::array<double, 3>& o = sim.origin();
    const bool shifted = o[0] != 0.0 || o[1] != 0.0 || o[2] != 0.0;
    for (std::size_t i = 0; i < n; ++i)
        if (shifted)
            std::fprintf(f, "v %.12g %.12g %.12g\n", o[0] + double(p[i]), o[1] + double(p[stride + i]),
                         o[2] + double(p[2 * stride + i]));
        else
            std::fprintf(f, "v %.6g %.6g %.6g\n", p[i], p[stride + i], p[2 * stride + i]);
    for (std::size_t i = 0; i < n; ++i)
        std::fprintf(f, "vn %.5g %.5g %.5g\n", p[3 * stride + i], p[4 * stride + i], p[5 * stride + i]);
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3) {
        const unsigned a = triangles[t] + 1, b = triangles[t + 1] + 1, c = triangles[t + 2] + 1;
        std::fprintf(f, "f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c);
    }
    const bool ok = std::ferror(f) == 0;
    if (std::fclose(f) != 0 || !ok) throw WriteError("error writing '" + path + "' (disk full?)");
}

} // namespace drape::app
