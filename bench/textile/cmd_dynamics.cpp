// drape_textile hang / verlet: resolution convergence of the hang scene with the fabric model, and position Verlet
// against symplectic Euler at rest.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "drape/scene.hpp"
#include "drape/scene_hang.hpp"
#include "drape/stability.hpp"
#include "harness.hpp"
#include "textile_commands.hpp"

namespace drape::textile {

namespace {

HangParams hang_params(std::uint32_t n, const Fabric& fabric) {
    HangParams hp;
    hp.n = n;
    hp.size = 1.0f;
    hp.model = MaterialModel::fabric;
    hp.fabric = fabric;
    hp.pins = GridPins::corners;
    hp.pin_radius = load_scene("hang").grid.pin_radius; // the hang scene's clips (2 cm)
    hp.plane = GridPlane::horizontal;
    return hp;
}

/// Lowest point (min y) and the sag of the top edge's midpoint below the pins (y of the pins = 0), m.
void hang_figures(const Simulation& sim, std::uint32_t n, double& lowest, double& sag) {
    const auto y = sim.y();
    lowest = *std::min_element(y.begin(), y.end());
    const double mid = n % 2 ? y[grid_index(n, n / 2, 0)] : 0.5 * (y[grid_index(n, n / 2 - 1, 0)] + y[grid_index(n, n / 2, 0)]);
    sag = -mid;
}

/// The swing: the cloth's mean z (its centre of mass for equal masses; the pins' axis is along x), m.
double mean_z(const Simulation& sim) {
    double s = 0.0;
    for (float z : sim.z()) s += z;
    return s / double(sim.z().size());
}

double kinetic_energy(const Simulation& sim) {
    double ke = 0.0;
    for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
        const float im = sim.cloth().inv_mass[i];
        if (im == 0.0f) continue;
        const auto v = particle_velocity(sim, i);
        ke += 0.5 / im * (double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]);
    }
    return ke;
}

/// Decay time of the swing from the extrema of a sampled signal about its final value: least-squares fit of
/// ln |extremum - final| against time; extrema below `floor` (m) are left out. Returns 0 with fewer than 3.
double decay_time(const std::vector<double>& t, const std::vector<double>& s, double final_value, double floor,
                  int& used) {
    std::vector<double> tt, la;
    const int w = 3;
    for (std::size_t k = w; k + w < s.size(); ++k) {
        bool mx = true, mn = true;
        for (int d = 1; d <= w; ++d) {
            mx = mx && s[k] >= s[k - d] && s[k] > s[k + d];
            mn = mn && s[k] <= s[k - d] && s[k] < s[k + d];
        }
        const double a = std::fabs(s[k] - final_value);
        if ((mx || mn) && a > floor) {
            tt.push_back(t[k]);
            la.push_back(std::log(a));
        }
    }
    used = static_cast<int>(tt.size());
    if (tt.size() < 3) return 0.0;
    double mt = 0, ml = 0;
    for (std::size_t k = 0; k < tt.size(); ++k) mt += tt[k], ml += la[k];
    mt /= tt.size();
    ml /= tt.size();
    double sxy = 0, sxx = 0;
    for (std::size_t k = 0; k < tt.size(); ++k) sxy += (tt[k] - mt) * (la[k] - ml), sxx += (tt[k] - mt) * (tt[k] - mt);
    const double slope = sxy / sxx;
    return slope < 0.0 ? -1.0 / slope : 0.0;
}

} // namespace

int cmd_hang(const Options& opt) {
    const std::string name = opt.fabrics.empty() ? load_scene("hang").fabric.name : opt.fabrics.front();
    const Fabric fabric = textile_fabric(name);
    std::vector<std::uint32_t> sizes = opt.quick ? std::vector<std::uint32_t>{16, 32} : std::vector<std::uint32_t>{32, 64, 128};
    if (opt.fine) sizes.push_back(256);
    if (!opt.sizes.empty()) sizes = opt.sizes;
    const double swing_time = 6.0, settle_drag = 4.0, settle_time = 8.0, scene_drag = 0.2;
    std::printf("Hang scene (1 m cloth, corners held by %.0f mm clips), fabric %s: swing from flat for %.0f s at air drag "
                "%.1f 1/s (the swing, the mean z of the cloth, sampled every 5 ms; decay time from a fit of the log of its "
                "extrema's distance to the settled value), then settled at drag %.0f 1/s (max speed < 0.1 mm/s, or the lowest point still to 1 um per 20 ms (its float32 ulp is 0.12 um), at 5 checks in a row; else %.0f s)\n\n",
                1e3 * hang_params(2, fabric).pin_radius, name.c_str(), swing_time, scene_drag, settle_drag, settle_time);
    std::printf("| N | h (mm) | dt (us) | lowest point (mm) | mid-top-edge sag (mm) | decay time (s) | extrema used "
                "| settled (settle s) | wall s |\n");
    std::printf("|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (std::uint32_t n : sizes) {
        SceneBuild scene = build_hang_scene(hang_params(n, fabric));
        SimulationParams sp;
        sp.air_drag = static_cast<float>(scene_drag);
        sp.dt = static_cast<float>(default_dt(scene.cloth, sp));
        Simulation sim(std::move(scene.cloth), scene.initial, sp);
        const auto t0 = std::chrono::steady_clock::now();
        const auto chunk = std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(0.005 / sp.dt)));
        std::vector<double> ts, swing;
        // --static: the settled shape only (no swing; decay time not measured).
        while (!opt.static_only && sim.time() < swing_time) {
            sim.step(chunk);
            ts.push_back(sim.time());
            swing.push_back(mean_z(sim));
        }
        SimulationParams settle_params = sp;
        settle_params.air_drag = static_cast<float>(settle_drag);
        sim.set_params(settle_params);
        const double swung = sim.time();
        const auto low = [&](const Simulation& s) {
            double lo, sg;
            hang_figures(s, n, lo, sg);
            return lo;
        };
        const SettleStats st = settle(sim, settle_time, 1e-4, 0.02, 5, low, 1e-6);
        double lowest, sag;
        hang_figures(sim, n, lowest, sag);
        int used = 0;
        const double tau = decay_time(ts, swing, mean_z(sim), 1e-3, used);
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("| %u | %.2f | %.2f | %.2f | %.2f | %s | %d | %s (%.1f s) | %.1f |\n", n, 1e3 / (n - 1), sp.dt * 1e6,
                    lowest * 1e3, sag * 1e3, opt.static_only ? "-" : std::to_string(tau).c_str(), used,
                    st.settled ? "yes" : "no", sim.time() - swung, wall);
        std::fflush(stdout);
    }
    return 0;
}

int cmd_verlet(const Options& opt) {
    const std::string name = opt.fabrics.empty() ? "silk" : opt.fabrics.front();
    const Fabric fabric = textile_fabric(name);
    const std::uint32_t n = 32;
    const double drag = 2.0, time = 15.0;
    std::printf("Verlet vs symplectic Euler at rest: hang scene N = %u, fabric %s, air drag %.0f 1/s, %.0f s from "
                "flat, same dt\n\n", n, name.c_str(), drag, time);
    std::printf("| integrator | dt (us) | kinetic energy (J) | max speed (m/s) | lowest point (mm) |\n|---|---:|---:|---:|---:|\n");
    std::vector<float> px[2], py[2], pz[2];
    double ke[2];
    for (int k = 0; k < 2; ++k) {
        SceneBuild scene = build_hang_scene(hang_params(n, fabric));
        SimulationParams sp;
        sp.air_drag = static_cast<float>(drag);
        sp.integrator = k == 0 ? Integrator::symplectic_euler : Integrator::verlet;
        sp.dt = static_cast<float>(default_dt(scene.cloth, sp));
        Simulation sim(std::move(scene.cloth), scene.initial, sp);
        sim.step(static_cast<std::size_t>(std::lround(time / sp.dt)));
        ke[k] = kinetic_energy(sim);
        float vmax = 0.0f;
        for (std::size_t i = 0; i < sim.cloth().particle_count; ++i) {
            const auto v = particle_velocity(sim, i);
            vmax = std::max(vmax, std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]));
        }
        px[k].assign(sim.x().begin(), sim.x().end());
        py[k].assign(sim.y().begin(), sim.y().end());
        pz[k].assign(sim.z().begin(), sim.z().end());
        std::printf("| %s | %.2f | %.3e | %.3e | %.3f |\n", integrator_name(sp.integrator), sp.dt * 1e6, ke[k], vmax,
                    *std::min_element(py[k].begin(), py[k].end()) * 1e3);
    }
    double dmax = 0.0;
    for (std::size_t i = 0; i < px[0].size(); ++i)
        dmax = std::max(dmax, std::hypot(double(px[0][i]) - px[1][i], double(py[0][i]) - py[1][i], double(pz[0][i]) - pz[1][i]));
    std::printf("\nkinetic energy Verlet / Euler = %.2f; max position difference = %.4f mm\n", ke[1] / ke[0], dmax * 1e3);
    return 0;
}

} // namespace drape::textile
