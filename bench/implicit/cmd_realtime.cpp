// drape_implicit realtime: the real-time factor at quality on the hang scene (issue 8 "Figures"), implicit against
// explicit side by side in one run.
#include <cmath>
#include <cstdio>
#include <optional>

#include "commands.hpp"

namespace drape::implicit_bench {

namespace {

struct RunFigures {
    std::string solver;
    double dt = 0.0;
    std::uint32_t iterations = 0;
    double simulated = 0.0; ///< s timed
    double wall = 0.0;      ///< s
    bool full = false;      ///< the whole duration ran
    float strain = NAN;     ///< max structural strain at the end of the timed run (full runs only)
    float strain_run = NAN; ///< the largest at the ends of the run's chunks of ~0.05 s (full runs only)
    bool finite = true;
    double relative_residual = NAN; ///< implicit: the last step's
    double settled_at = 0.0;        ///< s of simulated time of the settled shape (0: none)
    std::vector<double> settled;
    std::string failure;
};

/// Runs `sim` to `duration` (timed) and on to `settle_time`, within a wall budget (explicit) or not (implicit).
RunFigures run(Simulation& sim, const Options& opt, bool budgeted) {
    RunFigures f;
    f.dt = sim.params().dt;
    const std::size_t total = static_cast<std::size_t>(std::llround(opt.duration.value_or(2.0) / f.dt));
    // Chunks of about 0.05 s simulated, so that an over-budget explicit run stops early.
    const std::size_t chunk = std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(opt.explicit_short / f.dt)));
    std::size_t done = 0;
    try {
        float most = 0.0f;
        while (done < total) {
            const std::size_t k = std::min(chunk, total - done);
            const auto t0 = std::chrono::steady_clock::now();
            sim.step(k);
            f.wall += seconds_since(t0); // the strain samples below are not timed
            done += k;
            if (budgeted && f.wall / static_cast<double>(done) * static_cast<double>(total) > opt.explicit_budget) break;
            most = std::max(most, sim.health().max_structural_strain);
        }
        f.simulated = static_cast<double>(done) * f.dt;
        f.full = done == total;
        const Health h = sim.health();
        f.finite = h.finite;
        if (f.full) f.strain = h.max_structural_strain, f.strain_run = most;
        if (sim.params().solver == Solver::implicit) f.relative_residual = sim.implicit_stats().relative_residual;
        if (!f.full || !f.finite || opt.settle_time <= 0.0) return f;
        const std::size_t settle = static_cast<std::size_t>(std::llround(opt.settle_time / f.dt));
        const double per_step = f.wall / static_cast<double>(done);
        if (settle > total && (!budgeted || per_step * static_cast<double>(settle) <= opt.explicit_settle_budget)) {
            if (opt.settle_drag > 0.0) {
                SimulationParams p = sim.params();
                p.air_drag = static_cast<float>(opt.settle_drag);
                sim.set_params(p);
            }
            sim.step(settle - total);
        }
        if (settle <= total || !budgeted || per_step * static_cast<double>(settle) <= opt.explicit_settle_budget) {
            f.settled_at = sim.time();
            f.settled = positions(sim);
        }
    } catch (const std::exception& e) {
        f.finite = false;
        f.failure = e.what();
        f.simulated = static_cast<double>(done) * f.dt;
    }
    return f;
}

} // namespace

int cmd_realtime(const Options& opt) {
    Report rep;
    rep.command = "realtime";
    rep.threads = opt.threads;
    Table t;
    char title[200];
    std::snprintf(title, sizeof title,
                  "Real-time factor on the hang scene (wool, 2 cm clips): %g s timed; settled shape at %g s%s",
                  opt.duration.value_or(2.0), opt.settle_time,
                  opt.settle_drag > 0.0 ? (" (air drag " + std::to_string(opt.settle_drag).substr(0, 4) + "/s after the timed run)").c_str() : "");
    t.title = title;
    t.columns = {"N",          "particles",      "solver",       "dt (s)",      "iterations", "strain limit",
                 "timed (s)",  "wall (s)",       "real-time x",  "max strain at t_end", "max strain over the run", "finite",
                 "last rel. residual", "settled at (s)", "distance to reference (mm)", "rms distance (mm)", "mean offset (mm)", "quality"};
    std::vector<std::uint32_t> sizes = opt.sizes.empty() ? std::vector<std::uint32_t>{100, 316, 1000} : opt.sizes;
    for (std::uint32_t n : sizes) {
        BuiltScene scene = hang_scene(n);
        const std::size_t particles = scene.cloth.particle_count;
        std::fprintf(stderr, "realtime: N = %u (%zu particles): implicit...\n", n, particles);
        SimulationParams ip = implicit_params(scene.params, opt.dt, opt.iterations, opt.rho, ImplicitMethod::gauss_seidel,
                                              opt.strain_limit, opt.multilevel, opt.fas);
        ip.implicit.fas_at_rest = opt.fas_at_rest;
        Simulation im(scene.cloth, scene.initial, ip);
        RunFigures fi = run(im, opt, false);
        std::string plan; // particles x sweeps per step of each level, the cloth first
        for (const ImplicitLevelPlan& l : im.implicit_level_plan())
            plan += (plan.empty() ? "" : ", ") + std::to_string(l.particles) + " x " + std::to_string(l.sweeps);
        std::fprintf(stderr, "realtime: N = %u: levels (particles x sweeps per step) %s\n", n, plan.c_str());
        fi.solver = !opt.multilevel ? "implicit (single level)"
                    : opt.fas       ? "implicit (multilevel, FAS)"
                    : opt.fas_at_rest ? "implicit (multilevel, FAS at rest)"
                                      : "implicit (multilevel)";
        fi.iterations = opt.iterations;
        std::fprintf(stderr, "realtime: N = %u: explicit...\n", n);
        Simulation ex(scene.cloth, scene.initial, scene.params);
        RunFigures fe = run(ex, opt, true);
        fe.solver = "explicit (" + std::string(integrator_name(scene.params.integrator)) + ")";
        // The reference equilibrium nearest each run's settled shape (a hanging cloth has many: folds).
        std::optional<Equilibrium> eq_i, eq_e;
        std::fprintf(stderr, "realtime: N = %u: reference equilibria...\n", n);
        const auto t_ref = std::chrono::steady_clock::now();
        const bool newton = have_newton_reference() && n <= opt.newton_max_n;
        if (opt.explicit_reference) {
            // Explicit Euler from each run's settled shape (one that did not settle shares the other's): a hanging
            // cloth has many equilibria, and a run still moving at the settle time (slow folds) is measured against
            // where it was going.
            if (!fi.settled.empty()) eq_i = explicit_equilibrium(im, scene.params, opt);
            if (!fe.settled.empty()) eq_e = explicit_equilibrium(ex, scene.params, opt);
            if (!eq_i) eq_i = eq_e;
            if (!eq_e) eq_e = eq_i;
            if (eq_i) rep.notes.push_back("N = " + std::to_string(n) + ": reference equilibrium by " + eq_i->method);
            if (eq_e && !fi.settled.empty() && !fe.settled.empty())
                rep.notes.push_back("N = " + std::to_string(n) + " explicit: its own reference equilibrium by " +
                                    eq_e->method);
        } else if (!newton) {
            // One long implicit run from the implicit (else explicit) settled shape, for both.
            if (!fi.settled.empty()) eq_i = reference_equilibrium(im, opt, n);
            else if (!fe.settled.empty()) eq_i = reference_equilibrium(ex, opt, n);
            eq_e = eq_i;
            if (eq_i) rep.notes.push_back("N = " + std::to_string(n) + ": reference equilibrium by " + eq_i->method);
        } else {
            if (!fe.settled.empty()) {
                eq_e = reference_equilibrium(ex, opt, n);
                rep.notes.push_back("N = " + std::to_string(n) + " explicit: reference equilibrium by " + eq_e->method);
            }
            if (!fi.settled.empty()) {
                eq_i = reference_equilibrium(im, opt, n);
                rep.notes.push_back("N = " + std::to_string(n) + " implicit: reference equilibrium by " + eq_i->method);
                // A shape too far from any equilibrium for Newton to reach one: measure against the explicit run's.
                if (eq_i->residual > 1e-3 && eq_e && eq_e->residual <= 1e-3) {
                    eq_i = eq_e;
                    rep.notes.push_back("N = " + std::to_string(n) + " implicit: that Newton run did not converge; "
                                        "its shape is measured against the explicit run's reference equilibrium");
                } else if (eq_e && eq_e->residual > 1e-3 && eq_i->residual <= 1e-3) {
                    eq_e = eq_i;
                    rep.notes.push_back("N = " + std::to_string(n) + " explicit: that Newton run did not converge; "
                                        "its shape is measured against the implicit run's reference equilibrium");
                }
            }
        }
        std::fprintf(stderr, "realtime: N = %u: reference(s) in %.3g s\n", n, seconds_since(t_ref));
        for (const RunFigures* f : {&fi, &fe}) {
            const bool implicit = f == &fi;
            const std::optional<Equilibrium>& eq = implicit ? eq_i : eq_e;
            const double dist = eq && !f->settled.empty() ? max_distance(f->settled, eq->x) : NAN;
            const double rms = eq && !f->settled.empty() ? rms_distance(f->settled, eq->x) : NAN;
            const double offset = eq && !f->settled.empty() ? mean_offset(f->settled, eq->x) : NAN;
            std::string quality;
            if (!f->full) quality = "n/a (short run)";
            else if (!f->finite) quality = "no (not finite)";
            else {
                const bool strain_ok = f->strain <= 0.10f && f->strain_run <= 0.10f;
                const bool shape_ok = std::isfinite(dist) && dist <= 0.01;
                quality = strain_ok && shape_ok ? "yes" : !strain_ok ? "no (strain)" : std::isfinite(dist) ? "no (shape)"
                                                                                                            : "shape not measured";
            }
            char rtf[64];
            std::snprintf(rtf, sizeof rtf, f->full ? "%.3g" : "%.3g (from %.3g s)", f->simulated / f->wall, f->simulated);
            t.add({num(n, "%.0f"), num(static_cast<double>(particles), "%.0f"), txt(f->solver), num(f->dt, "%.4g"),
                   implicit ? num(f->iterations, "%.0f") : txt("-"),
                   implicit && opt.strain_limit > 0.0f ? num(opt.strain_limit, "%.3g") : txt("off"),
                   num(f->simulated, "%.3g"), num(f->wall, "%.3g"),
                   f->full ? num(f->simulated / f->wall, "%.3g") : txt(rtf),
                   f->full ? num(f->strain, "%.4f") : txt("-"), f->full ? num(f->strain_run, "%.4f") : txt("-"),
                   txt(f->finite ? "yes" : "no"),
                   implicit ? num(f->relative_residual, "%.2e") : txt("-"),
                   f->settled_at > 0.0 ? num(f->settled_at, "%.3g") : txt("-"),
                   std::isfinite(dist) ? num(dist * 1000.0, "%.3g") : txt("-"),
                   std::isfinite(rms) ? num(rms * 1000.0, "%.3g") : txt("-"),
                   std::isfinite(offset) ? num(offset * 1000.0, "%.3g") : txt("-"), txt(quality)});
            if (!f->failure.empty())
                rep.notes.push_back("N = " + std::to_string(n) + " " + f->solver + ": " + f->failure);
        }
    }
    rep.tables.push_back(std::move(t));
    rep.notes.push_back("Quality: max structural strain (stretch or compression) at the end of the timed run and over "
                        "it (sampled every ~0.05 s simulated, not timed) <= 0.10, finite, and the settled shape within "
                        "10 mm (max over particles) of the reference equilibrium. An explicit run whose "
                        "projected wall time exceeds the budget (--explicit-budget) is timed over a short interval "
                        "only: its real-time factor is labelled '(from T s)' and its strain and shape are not measured.");
    rep.print(opt.json, opt.json_out);
    return 0;
}

} // namespace drape::implicit_bench
