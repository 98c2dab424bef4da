// Explicit time-step bound (see stability.hpp for the derivation).
#include "drape/stability.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "drape/simulation.hpp"

namespace drape {

StabilityBound stability_bound(const Cloth& cloth, float air_drag) {
    const std::size_t n = cloth.particle_count;
    std::vector<double> sum_k(n, 0.0), sum_kd(n, 0.0);
    StabilityBound b;
    for (const Edge& e : cloth.edges) {
        const SpringMaterial& m = cloth.material[static_cast<std::size_t>(e.kind)];
        sum_k[e.a] += m.stiffness;
        sum_k[e.b] += m.stiffness;
        sum_kd[e.a] += m.damping;
        sum_kd[e.b] += m.damping;
        b.max_stiffness = std::max(b.max_stiffness, double(m.stiffness));
    }
    double min_mass = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double inv_m = cloth.inv_mass[i];
        if (inv_m == 0.0) continue; // pinned: does not move
        b.omega2_max = std::max(b.omega2_max, 2.0 * sum_k[i] * inv_m);
        b.gamma_max = std::max(b.gamma_max, 2.0 * sum_kd[i] * inv_m);
        const double m = 1.0 / inv_m;
        min_mass = min_mass == 0.0 ? m : std::min(min_mass, m);
    }
    b.gamma_max += air_drag;
    b.min_mass = min_mass;
    // Largest dt with w^2 dt^2 + 2 g dt <= 4: the positive root of w^2 dt^2 + 2 g dt - 4 = 0.
    const double w2 = b.omega2_max, g = b.gamma_max;
    if (w2 > 0.0)
        b.dt_max = (-2.0 * g + std::sqrt(4.0 * g * g + 16.0 * w2)) / (2.0 * w2);
    else
        b.dt_max = g > 0.0 ? 2.0 / g : 0.1;
    b.dt_max = std::min(b.dt_max, 0.1);
    return b;
}

double default_dt(const Cloth& cloth, float air_drag) { return 0.9 * stability_bound(cloth, air_drag).dt_max; }

void check_stability(const Cloth& cloth, const SimulationParams& params, const std::string& what) {
    const StabilityBound b = stability_bound(cloth, params.air_drag);
    // Compared in float, the precision dt is stored in: the bound as printed (9 significant digits, see
    // format_dt) and pasted back as dt is accepted.
    if (params.dt <= static_cast<float>(b.dt_max)) return;
    std::ostringstream msg;
    msg.precision(3);
    const double substeps = std::ceil(double(params.dt) / (0.9 * b.dt_max));
    msg << what << " = " << format_dt(params.dt) << " s is above the explicit stability bound " << format_dt(b.dt_max)
        << " s for this cloth (stiffest spring " << b.max_stiffness << " N/m, lightest particle " << b.min_mass
        << " kg); use dt <= " << format_dt(b.dt_max) << " s, e.g. split this step into " << substeps
        << " substeps of " << double(params.dt) / substeps << " s";
    throw InvalidInput(msg.str());
}

std::string format_dt(double dt) {
    // The shortest of 6 to 9 significant digits that reads back as the same float (9 always does).
    const float f = static_cast<float>(dt);
    char buf[32];
    for (int digits = 6; digits <= 9; ++digits) {
        std::snprintf(buf, sizeof buf, "%.*g", digits, double(f));
        if (std::strtof(buf, nullptr) == f) break;
    }
    return buf;
}

} // namespace drape
