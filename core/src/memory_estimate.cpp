#include "drape/memory_estimate.hpp"

#include <sys/resource.h>

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "drape/errors.hpp"

namespace drape {

namespace {

/// Peak bytes per particle while cooking and running a scene: the slope of the peak RSS of `drape run --steps 1`
/// between two sizes (docs/user_guide.md "Memory"), plus 5%. Measured after issue 7 (Edge::scale, bending rows):
/// grids (hang, N = 1000 -> 1414) 676 B per particle with the seeds' springs, 881 B with a fabric (no bend springs,
/// but Q's rows per particle, plain and SIMD-sliced); triangulated cloths (tshirt, 360 -> 720 cells per metre, 101k ->
/// 403k particles) 758 B with springs, 911 B with a fabric (Delaunay temporaries, hinge elements).
constexpr double grid_bytes_per_particle = 710.0;
constexpr double grid_fabric_bytes_per_particle = 925.0;
constexpr double mesh_bytes_per_particle = 800.0;
constexpr double mesh_fabric_bytes_per_particle = 960.0;
constexpr double fixed_bytes = 64.0 * 1024 * 1024;

std::size_t mapped_bytes() {
    std::ifstream in("/proc/self/statm");
    std::size_t pages = 0;
    if (!(in >> pages)) return 0;
    return pages * 4096;
}

} // namespace

std::size_t scene_memory_bytes(const SceneSpec& spec) {
    const bool fabric = spec.model == MaterialModel::fabric;
    const double per_particle = spec.cloth == ClothType::grid
                                    ? (fabric ? grid_fabric_bytes_per_particle : grid_bytes_per_particle)
                                    : (fabric ? mesh_fabric_bytes_per_particle : mesh_bytes_per_particle);
    return static_cast<std::size_t>(fixed_bytes + per_particle * double(scene_particle_count(spec)));
}

std::size_t available_memory_bytes() {
    std::size_t available = std::numeric_limits<std::size_t>::max();
    std::ifstream in("/proc/meminfo");
    std::string key;
    std::size_t kib = 0;
    std::string unit;
    while (in >> key >> kib >> unit)
        if (key == "MemAvailable:") {
            available = kib * 1024;
            break;
        }
    rlimit lim{};
    if (getrlimit(RLIMIT_AS, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY) {
        const std::size_t used = mapped_bytes();
        const std::size_t cap = lim.rlim_cur > used ? std::size_t(lim.rlim_cur - used) : 0;
        available = std::min(available, cap);
    }
    return available;
}

std::string format_bytes(std::size_t bytes) {
    char buf[32];
    const double b = double(bytes);
    if (b >= 1024.0 * 1024 * 1024)
        std::snprintf(buf, sizeof buf, "%.1f GiB", b / (1024.0 * 1024 * 1024));
    else
        std::snprintf(buf, sizeof buf, "%.0f MiB", b / (1024.0 * 1024));
    return buf;
}

void check_scene_memory(const SceneSpec& spec, const std::string& what) {
    const std::size_t need = scene_memory_bytes(spec);
    const std::size_t have = available_memory_bytes();
    if (need > have)
        throw InvalidInput(what + ": the cloth would have " + std::to_string(scene_particle_count(spec)) +
                           " particles and needs about " + format_bytes(need) + " of memory; " + format_bytes(have) +
                           " are available");
}

} // namespace drape
