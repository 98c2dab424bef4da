// Explicit time-step bound (see stability.hpp for the derivation).
#include "drape/stability.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <iterator>
#include <vector>

#include "drape/simulation.hpp"

namespace drape {

namespace {

/// Rest length of spring a-b, or 0 when there is none (edges are sorted by (a, b) with a < b: cook_cloth).
double rest_length(const Cloth& cloth, std::uint32_t a, std::uint32_t b) {
    if (a > b) std::swap(a, b);
    const auto it = std::lower_bound(cloth.edges.begin(), cloth.edges.end(), Edge{a, b, SpringKind::structural, 0.0f},
                                     [](const Edge& l, const Edge& r) { return l.a != r.a ? l.a < r.a : l.b < r.b; });
    return it != cloth.edges.end() && it->a == a && it->b == b ? double(it->rest) : 0.0;
}

struct AeroTerms {
    std::vector<double> gamma;  ///< per particle, rho C_d A_i |v_rel|max / m_i, 1/s
    std::vector<double> omega2; ///< per particle, 3/4 rho C_d |v_rel|max^2 (sum of its triangles' longest edges) / m_i
};

/// The linearised aerodynamic terms per particle (stability.hpp).
AeroTerms aero_terms(const Cloth& cloth, const AeroWind& aero) {
    const std::size_t n = cloth.particle_count;
    std::vector<double> area(n, 0.0), edges(n, 0.0);
    for (std::size_t t = 0; t + 2 < cloth.triangles.size(); t += 3) {
        const std::uint32_t v[3] = {cloth.triangles[t], cloth.triangles[t + 1], cloth.triangles[t + 2]};
        const double l0 = rest_length(cloth, v[0], v[1]), l1 = rest_length(cloth, v[1], v[2]),
                     l2 = rest_length(cloth, v[2], v[0]);
        double a = 0.0;
        if (l0 > 0.0 && l1 > 0.0 && l2 > 0.0) { // Heron, in the stable form
            double e[3] = {l0, l1, l2};
            std::sort(e, e + 3, [](double p, double q) { return p > q; });
            const double q = (e[0] + (e[1] + e[2])) * (e[2] - (e[0] - e[1])) * (e[2] + (e[0] - e[1])) *
                             (e[0] + (e[1] - e[2]));
            a = 0.25 * std::sqrt(std::max(q, 0.0));
        } else { // an edge without a spring: at most half the product of the two others
            double l[3] = {l0, l1, l2};
            std::sort(std::begin(l), std::end(l));
            a = 0.5 * l[1] * l[2];
        }
        const double longest = std::max({l0, l1, l2});
        for (std::uint32_t i : v)
            if (i < n) {
                area[i] += a / 3.0;
                edges[i] += longest;
            }
    }
    const double wind = std::sqrt(double(aero.velocity[0]) * aero.velocity[0] +
                                  double(aero.velocity[1]) * aero.velocity[1] +
                                  double(aero.velocity[2]) * aero.velocity[2]);
    const double rho_cd = double(aero.density) * aero.drag_coefficient, speed = wind + aero_speed_margin;
    AeroTerms out{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
    for (std::size_t i = 0; i < n; ++i) {
        out.gamma[i] = rho_cd * speed * area[i] * cloth.inv_mass[i];
        out.omega2[i] = 0.75 * rho_cd * speed * speed * edges[i] * cloth.inv_mass[i];
    }
    return out;
}

} // namespace

StabilityBound stability_bound(const Cloth& cloth, float air_drag) { return stability_bound(cloth, air_drag, nullptr); }

StabilityBound stability_bound(const Cloth& cloth, const SimulationParams& params) {
    return stability_bound(cloth, params.air_drag, params.aero.enabled ? &params.aero : nullptr);
}

StabilityBound stability_bound(const Cloth& cloth, float air_drag, const AeroWind* aero) {
    const std::size_t n = cloth.particle_count;
    std::vector<double> sum_k(n, 0.0), sum_kd(n, 0.0);
    const AeroTerms aero_t = aero ? aero_terms(cloth, *aero)
                                  : AeroTerms{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)};
    StabilityBound b;
    for (const Edge& e : cloth.edges) {
        const SpringMaterial& m = cloth.material[static_cast<std::size_t>(e.kind)];
        const double k = double(m.stiffness) * e.scale, kd = double(m.damping) * e.scale;
        sum_k[e.a] += k;
        sum_k[e.b] += k;
        sum_kd[e.a] += kd;
        sum_kd[e.b] += kd;
        b.max_stiffness = std::max(b.max_stiffness, k);
    }
    // Bending: K gets Q (x) I3, Gershgorin row sum sum_j |Q_ij|; Rayleigh damping beta Q adds beta times that.
    const std::vector<double> q_rows = bending_row_sums(cloth.bending, n);
    const double beta = cloth.bending.damping;
    double min_mass = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double inv_m = cloth.inv_mass[i];
        if (inv_m == 0.0) continue; // pinned: does not move
        b.omega2_max = std::max(b.omega2_max, (2.0 * sum_k[i] + q_rows[i]) * inv_m + aero_t.omega2[i]);
        b.gamma_max = std::max(b.gamma_max, (2.0 * sum_kd[i] + beta * q_rows[i]) * inv_m + aero_t.gamma[i]);
        b.aero_gamma_max = std::max(b.aero_gamma_max, aero_t.gamma[i]);
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
double default_dt(const Cloth& cloth, const SimulationParams& params) {
    return 0.9 * stability_bound(cloth, params).dt_max;
}

void check_stability(const Cloth& cloth, const SimulationParams& params, const std::string& what) {
    const StabilityBound b = stability_bound(cloth, params);
    // Compared in float, the precision dt is stored in: the bound as printed (9 significant digits, see
    // format_dt) and pasted back as dt is accepted.
    if (params.dt <= static_cast<float>(b.dt_max)) return;
    std::ostringstream msg;
    msg.precision(3);
    const double substeps = std::ceil(double(params.dt) / (0.9 * b.dt_max));
    msg << what << " = " << format_dt(params.dt) << " s is above the explicit stability bound " << format_dt(b.dt_max)
        << " s for this cloth (stiffest spring " << b.max_stiffness << " N/m, lightest particle " << b.min_mass
        << " kg" << (b.aero_gamma_max > 0.0 ? ", aerodynamic drag included" : "") << "); use dt <= "
        << format_dt(b.dt_max) << " s, e.g. split this step into " << substeps << " substeps of "
        << double(params.dt) / substeps << " s";
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
