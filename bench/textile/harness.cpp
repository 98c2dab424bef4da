// Textile test harness: clamp, load and settle grid cloths with the fabric model (see harness.hpp).
#include "harness.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "drape/scene_hang.hpp"
#include "drape/stability.hpp"
#include "elastica.hpp"

namespace drape::textile {

namespace {
constexpr double g0 = 9.81;
}

Fabric textile_fabric(const std::string& name) {
    const std::optional<Fabric> f = find_fabric(name);
    if (!f) throw std::invalid_argument("unknown fabric preset " + name + " (drape materials lists them)");
    return *f;
}

std::array<float, 3> particle_velocity(const Simulation& sim, std::size_t i) { return sim.velocity(i); }

SettleStats settle(Simulation& sim, double max_time, double speed_tol, double check_every, int checks_needed,
                   const std::function<double(const Simulation&)>& probe, double probe_tol) {
    SettleStats st;
    st.dt = sim.params().dt;
    const auto chunk = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(check_every / st.dt)));
    const auto t0 = std::chrono::steady_clock::now();
    int quiet = 0;
    double last = probe ? probe(sim) : 0.0;
    while (st.sim_time < max_time) {
        sim.step(chunk);
        st.steps += chunk;
        st.sim_time = sim.time();
        float vmax = 0.0f;
        for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
            const auto v = particle_velocity(sim, i);
            vmax = std::max(vmax, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
        }
        st.max_speed = vmax;
        bool still = vmax < speed_tol;
        if (probe) {
            const double now = probe(sim);
            still = still || std::fabs(now - last) < probe_tol;
            last = now;
        }
        quiet = still ? quiet + 1 : 0;
        if (quiet >= checks_needed) {
            st.settled = true;
            break;
        }
    }
    st.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return st;
}

CantileverResult run_cantilever(const CantileverCase& c) {
    const double h = c.spacing;
    const int k = c.clamp_rows - 1;
    const auto cells = static_cast<std::uint32_t>(std::max(1L, std::lround(c.overhang / h - 0.5)));
    if (k < 1) throw std::invalid_argument("cantilever: clamp_rows >= 2");
    const double l = (cells + 0.5) * h;
    CantileverResult r;
    r.overhang = l;
    const double B = c.along_v ? c.fabric.bend_v : c.fabric.bend_u, rho = c.fabric.density;
    r.c_input = bending_length(B, rho, g0);

    HangParams hp;
    hp.model = MaterialModel::fabric;
    hp.fabric = c.fabric;
    hp.n = cells + static_cast<std::uint32_t>(k) + 1;
    hp.size = static_cast<float>((hp.n - 1) * h);
    hp.pins = GridPins::none;
    hp.plane = GridPlane::horizontal;
    r.n = hp.n;
    SceneBuild scene = build_hang_scene(hp);
    r.particles = scene.cloth.particle_count;

    SimulationParams sp;
    const double w1 = 3.516 * std::sqrt(B / (rho * std::pow(l, 4))); // first cantilever mode, rad/s
    sp.air_drag = static_cast<float>(c.drag >= 0.0 ? c.drag : std::min(100.0, 2.0 * w1));
    sp.dt = static_cast<float>(default_dt(scene.cloth, sp));
    Simulation sim(std::move(scene.cloth), scene.initial, sp);
    const std::uint32_t n = hp.n;
    auto at = [&](std::uint32_t along, std::uint32_t across) {
        return c.along_v ? grid_index(n, across, along) : grid_index(n, along, across);
    };
    for (std::uint32_t a = 0; a <= static_cast<std::uint32_t>(k); ++a)
        for (std::uint32_t b = 0; b < n; ++b) sim.set_pinned(at(a, b), true);
    const auto tip_height = [&](const Simulation& s) {
        double y = 0.0;
        for (std::uint32_t b = 0; b < n; ++b) y += s.y()[at(n - 1, b)];
        return y / n;
    };
    r.settle = settle(sim, c.max_time, 1e-4, 0.01, 5, tip_height, 1e-6 * l);

    // Column (row) means along the strip: position along it and height.
    auto mean_at = [&](std::uint32_t a, double& along, double& up) {
        along = up = 0.0;
        for (std::uint32_t b = 0; b < n; ++b) {
            const std::size_t i = at(a, b);
            along += c.along_v ? sim.z()[i] : sim.x()[i];
            up += sim.y()[i];
        }
        along /= n;
        up /= n;
    };
    double a0, y0, a1, y1; // the clamp line: midpoint of the last held segment
    mean_at(static_cast<std::uint32_t>(k - 1), a0, y0);
    mean_at(static_cast<std::uint32_t>(k), a1, y1);
    a0 = 0.5 * (a0 + a1);
    y0 = 0.5 * (y0 + y1);
    const ElasticaShape ref = solve_elastica(l, r.c_input);
    r.ref_tip_x = ref.tip_x();
    r.ref_tip_y = ref.tip_y();
    r.theta_reference = ref.chord_angle();
    for (std::uint32_t a = static_cast<std::uint32_t>(k); a < n; ++a) {
        double along, up, rx, ry;
        mean_at(a, along, up);
        ref.at((a - k + 0.5) * h, rx, ry);
        r.shape_error = std::max(r.shape_error, std::hypot(along - a0 - rx, up - y0 - ry) / l);
        if (a == n - 1) {
            r.tip_x = along - a0;
            r.tip_y = up - y0;
        }
    }
    r.theta = std::atan2(-r.tip_y, r.tip_x);
    r.c_peirce = peirce_bending_length(l, r.theta);
    r.c_elastica = r.theta > 0.0 ? elastica_bending_length(l, r.theta) : 0.0;
    const double theta_last = std::atan2(-(r.tip_y - (y1 - y0)), r.tip_x - (a1 - a0));
    r.c_last_row = theta_last > 0.0 ? elastica_bending_length(cells * h, theta_last) : 0.0;
    return r;
}

TensionResult run_tension(const TensionCase& c) {
    const double h = c.spacing, L = c.length;
    const auto cells = static_cast<std::uint32_t>(std::lround(L / h));
    if (cells < 1 || std::fabs(cells * h - L) > 1e-9) throw std::invalid_argument("tension: L / h");
    TensionResult r;
    const double S = c.along_v ? c.fabric.stretch_v : c.fabric.stretch_u;
    r.tension = c.strain * S;

    HangParams hp;
    hp.model = MaterialModel::fabric;
    hp.fabric = c.fabric;
    hp.n = cells + 1;
    hp.size = static_cast<float>(L);
    hp.pins = GridPins::none;
    hp.plane = GridPlane::horizontal;
    r.n = hp.n;
    const std::uint32_t n = hp.n;
    SceneBuild scene = build_hang_scene(hp);
    auto at = [&](std::uint32_t along, std::uint32_t across) {
        return c.along_v ? grid_index(n, across, along) : grid_index(n, along, across);
    };
    // The load: the end row's particles get extra mass m = T * (their share of the width) / g under gravity along
    // the strip (x for u, z for v): a uniform traction T on the end, half shares at the corners.
    Cloth& cloth = scene.cloth;
    if (cloth.free_inv_mass.empty()) cloth.free_inv_mass.assign(cloth.inv_mass.data(), cloth.inv_mass.data() + cloth.particle_count);
    for (std::uint32_t b = 0; b < n; ++b) {
        const std::size_t i = at(n - 1, b);
        const double share = (b == 0 || b == n - 1) ? 0.5 * h : h;
        const double m = 1.0 / cloth.inv_mass[i] + r.tension * share / g0;
        cloth.inv_mass[i] = static_cast<float>(1.0 / m);
        cloth.free_inv_mass[i] = cloth.inv_mass[i];
    }
    // Expected elongation: the tension between rows a and a+1 is g * (mass beyond) / width, each segment stretches
    // by h * tension / S (uniform across the width).
    double beyond = 0.0, elongation = 0.0;
    for (std::uint32_t a = n - 1; a >= 1; --a) {
        for (std::uint32_t b = 0; b < n; ++b) beyond += 1.0 / cloth.inv_mass[at(a, b)];
        elongation += h * (g0 * beyond / L) / S;
    }
    r.expected_strain = elongation / L;

    SimulationParams sp;
    sp.gravity = c.along_v ? std::array<float, 3>{0.0f, 0.0f, float(g0)} : std::array<float, 3>{float(g0), 0.0f, 0.0f};
    const double w = std::sqrt(g0 / (L * c.strain)); // the end row on the strip as a spring, rad/s
    sp.air_drag = static_cast<float>(std::min(100.0, 2.0 * w));
    sp.dt = static_cast<float>(default_dt(cloth, sp));
    std::vector<float> start(n);
    for (std::uint32_t b = 0; b < n; ++b) start[b] = c.along_v ? scene.initial.z[at(n - 1, b)] : scene.initial.x[at(n - 1, b)];
    Simulation sim(std::move(scene.cloth), scene.initial, sp);
    for (std::uint32_t b = 0; b < n; ++b) sim.set_pinned(at(0, b), true);
    const auto end_position = [&](const Simulation& s) {
        double p = 0.0;
        for (std::uint32_t b = 0; b < n; ++b) p += c.along_v ? s.z()[at(n - 1, b)] : s.x()[at(n - 1, b)];
        return p / n;
    };
    r.settle = settle(sim, c.max_time, 1e-5, 0.01, 5, end_position, 1e-6 * L * c.strain);
    double moved = 0.0;
    for (std::uint32_t b = 0; b < n; ++b) {
        const std::size_t i = at(n - 1, b);
        moved += (c.along_v ? sim.z()[i] : sim.x()[i]) - start[b];
    }
    r.measured_strain = moved / n / L;
    const std::size_t first = at(n - 1, 0), last = at(n - 1, n - 1);
    const double width = c.along_v ? sim.x()[last] - sim.x()[first] : sim.z()[last] - sim.z()[first];
    r.lateral_strain = width / L - 1.0;
    return r;
}

} // namespace drape::textile
