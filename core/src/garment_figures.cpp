// Figures of a sewn symmetric garment (garment_figures.hpp).
#include "drape/garment_figures.hpp"

#include <cmath>
#include <string>

#include "drape/colliders.hpp"
#include "drape/errors.hpp"

namespace drape {

std::vector<std::uint32_t> tshirt_mirror_map(const TShirtParams& params) { return build_tshirt(params).mirror; }

GarmentFigures garment_figures(const Simulation& sim, std::span<const std::uint32_t> mirror, double beyond_distance) {
    GarmentFigures f;
    f.finite = sim.health().finite;
    const auto x = sim.x(), y = sim.y(), z = sim.z();
    const std::array<double, 3> o = sim.cloth().origin;
    const SeamSet& s = sim.cloth().seams;
    for (std::size_t k = 0; k < s.a.size(); ++k) {
        const double dx = x[s.b[k]] - x[s.a[k]], dy = y[s.b[k]] - y[s.a[k]], dz = z[s.b[k]] - z[s.a[k]];
        f.longest_seam = std::max(f.longest_seam, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    const std::size_t counted = std::min(sim.cloth().particle_count, mirror.size());
    for (std::size_t i = 0; i < counted; ++i) {
        const std::size_t j = mirror[i];
        const double dx = (x[i] + o[0]) + (x[j] + o[0]), dy = y[i] - y[j], dz = z[i] - z[j];
        const double e2 = dx * dx + dy * dy + dz * dz, e = std::sqrt(e2);
        f.mirror_rms += e2;
        if (e > beyond_distance) ++f.beyond;
        if (e > f.mirror_error) {
            f.mirror_error = e;
            f.worst = i;
        }
        for (const Collider& c : sim.params().colliders)
            if (c.kind != ColliderKind::plane && is_inside(c, {x[i], y[i], z[i]}, 1e-5f)) {
                ++f.inside;
                break;
            }
    }
    if (counted > 0) f.mirror_rms = std::sqrt(f.mirror_rms / double(counted));
    return f;
}

} // namespace drape
