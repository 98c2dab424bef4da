#include "obj_export.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "drape/errors.hpp"

namespace drape::app {

ObjExporter::ObjExporter(const Cloth& cloth, std::string directory)
    : directory_(std::move(directory)), publisher_(std::make_unique<Publisher>(cloth)),
      planes_(publisher_->output_floats()), triangles_(cloth.triangles) {
    std::error_code ec;
    std::filesystem::create_directories(directory_, ec);
    if (ec || !std::filesystem::is_directory(directory_))
        throw WriteError("--export-obj: cannot create directory '" + directory_ + "': " + ec.message());
}

std::string ObjExporter::write(const Simulation& sim, std::size_t index) {
    publisher_->publish(sim.x(), sim.y(), sim.z(), planes_);
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05zu.obj", index);
    const std::string path = (std::filesystem::path(directory_) / name).string();
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) throw WriteError("--export-obj: cannot write '" + path + "' (" + std::strerror(errno) + ")");
    const std::size_t n = publisher_->particle_count(), stride = publisher_->plane_floats();
    const float* p = planes_.data();
    std::fprintf(f, "# drape frame %zu, t = %.6f s, %zu vertices, %zu triangles\n", index, sim.time(), n,
                 triangles_.size() / 3);
    for (std::size_t i = 0; i < n; ++i) std::fprintf(f, "v %.6g %.6g %.6g\n", p[i], p[stride + i], p[2 * stride + i]);
    for (std::size_t i = 0; i < n; ++i)
        std::fprintf(f, "vn %.5g %.5g %.5g\n", p[3 * stride + i], p[4 * stride + i], p[5 * stride + i]);
    for (std::size_t t = 0; t + 2 < triangles_.size(); t += 3) {
        const unsigned a = triangles_[t] + 1, b = triangles_[t + 1] + 1, c = triangles_[t + 2] + 1;
        std::fprintf(f, "f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c);
    }
    const bool ok = std::ferror(f) == 0;
    if (std::fclose(f) != 0 || !ok) throw WriteError("--export-obj: error writing '" + path + "' (disk full?)");
    return path;
}

} // namespace drape::app
