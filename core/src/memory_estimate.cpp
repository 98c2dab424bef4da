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

/// Peak bytes per particle while cooking and running a scene (measured: peak RSS of `drape run --steps 1` against the
/// particle count; see docs/user_guide.md "Memory"). Grids: 588 B per particle between N = 1000 and 2000, plus 5%.
/// Triangulated cloths (tshirt, outline) cook through a Delaunay triangulation with more temporaries: 631 - 636 B per
/// particle they get, which scene_particle_count over-counts by up to 3%; 700 keeps about 10% of margin.
constexpr double grid_bytes_per_particle = 620.0;
constexpr double mesh_bytes_per_particle = 700.0;
constexpr double fixed_bytes = 64.0 * 1024 * 1024;

std::size_t mapped_bytes() {
    std::ifstream in("/proc/self/statm");
    std::size_t pages = 0;
    if (!(in >> pages)) return 0;
    return pages * 4096;
}

} // namespace

std::size_t scene_memory_bytes(const SceneSpec& spec) {
    const double per_particle = spec.cloth == ClothType::grid ? grid_bytes_per_particle : mesh_bytes_per_particle;
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
