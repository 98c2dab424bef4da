// drape_implicit rest: does the implicit solver bring a hanging cloth to rest? The hang with strong air drag
// (--ref-drag, default 5/s: the swing decays as e^-5t) stepped for --duration seconds (default 8) with the multilevel
// guess (without and with the full approximation scheme's coarse correction, ImplicitParams::fas) and without it;
// once a second: the largest motion of a particle over the last step, the mean height and the
// last step's relative residual. An exact backward Euler solve stops moving; what moves is the solver's error.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "commands.hpp"

namespace drape::implicit_bench {

int cmd_rest(const Options& opt) {
    Report rep;
    rep.command = "rest";
    rep.threads = opt.threads;
    const std::vector<std::uint32_t> sizes = opt.sizes.empty() ? std::vector<std::uint32_t>{32, 100} : opt.sizes;
    const double duration = opt.duration.value_or(8.0);
    Table t;
    t.title = "Coming to rest: " + opt.scene + ", h = " + std::to_string(opt.dt).substr(0, 7) + " s, " +
              std::to_string(opt.iterations) + " iterations, Chebyshev " + std::to_string(opt.rho).substr(0, 4) +
              ", air drag " + std::to_string(opt.ref_drag).substr(0, 4) + "/s";
    t.columns = {"N", "guess", "t (s)", "max motion in the step (mm)", "mean height (m)", "relative residual"};
    for (std::uint32_t n : sizes) {
        bool coarse_grid = true;
        // multilevel, multilevel + FAS, single level, and the explicit solver (symplectic Euler at its default dt,
        // the same drag: the equilibrium the implicit runs should come to; --explicit-rest)
        for (int variant = 0; variant < 4; ++variant) {
            const bool multilevel = variant < 2, fas = variant == 1, explicit_run = variant == 3;
            if (!coarse_grid && variant < 3) continue; // the first run was single level already
            if (explicit_run && !opt.explicit_rest) break;
            const BuiltScene scene = scene_at(opt.scene, n);
            SimulationParams p = explicit_run ? scene.params
                                              : implicit_params(scene.params, opt.dt, opt.iterations, opt.rho,
                                                                ImplicitMethod::gauss_seidel, opt.strain_limit,
                                                                multilevel, fas);
            if (explicit_run) p.integrator = Integrator::symplectic_euler;
            else p.implicit.fas_at_rest = opt.fas_at_rest;
            p.air_drag = static_cast<float>(opt.ref_drag);
            Simulation sim(scene.cloth, scene.initial, p);
            const std::size_t count = sim.cloth().particle_count;
            std::vector<float> px(count), py(count), pz(count);
            const double dt = explicit_run ? double(sim.params().dt) : double(opt.dt);
            const long steps = std::lround(duration / dt), per_second = std::max(1L, std::lround(1.0 / dt));
            std::string guess = explicit_run ? "explicit (euler)"
                                : fas        ? "multilevel + FAS"
                                : multilevel ? (opt.fas_at_rest ? "multilevel (FAS at rest)" : "multilevel")
                                             : "single level";
            std::fprintf(stderr, "rest: N = %u, %s\n", n, guess.c_str());
            for (long s = 1; s <= steps; ++s) {
                const bool report = s % per_second == 0 || s == steps;
                if (report) {
                    std::copy(sim.x().begin(), sim.x().end(), px.begin());
                    std::copy(sim.y().begin(), sim.y().end(), py.begin());
                    std::copy(sim.z().begin(), sim.z().end(), pz.begin());
                }
                try {
                    sim.step(1);
                } catch (const std::exception& e) {
                    t.add({num(n), txt(guess), num(double(s) * dt, "%.2f"), txt("stopped"), txt("-"),
                           txt(e.what())});
                    break;
                }
                if (s == 1 && multilevel && !explicit_run && sim.implicit_stats().levels == 1) {
                    guess = "single level (no coarse grid)";
                    coarse_grid = false;
                }
                if (!report) continue;
                double motion = 0.0, height = 0.0;
                for (std::size_t i = 0; i < count; ++i) {
                    const double dx = sim.x()[i] - px[i], dy = sim.y()[i] - py[i], dz = sim.z()[i] - pz[i];
                    motion = std::max(motion, std::sqrt(dx * dx + dy * dy + dz * dz));
                    height += sim.y()[i];
                }
                t.add({num(n), txt(guess), num(double(s) * dt, "%.2f"),
                       explicit_run ? txt("-") : num(motion * 1e3, "%.3g"), num(height / double(count), "%.5f"),
                       explicit_run ? txt("-") : num(sim.implicit_stats().relative_residual, "%.3g")});
            }
        }
    }
    rep.tables.push_back(std::move(t));
    rep.notes.push_back("Each row: the step ending at t. Mean height: the mean y of the particles (the cloth hangs "
                        "from y = 0). The hang's scene (scenes/hang.json) at N x N, its air drag replaced by "
                        "--ref-drag; --strain-limit as given (default off). --scene S: that scene at resolution N (grids: "
                        "N x N; outlines: N cells per metre). --explicit-rest adds the explicit solver's run (its motion "
                        "column is not comparable: a substep, not a frame).");
    rep.print(opt.json, opt.json_out);
    return 0;
}

} // namespace drape::implicit_bench
