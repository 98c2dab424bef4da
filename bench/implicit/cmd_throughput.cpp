// drape_implicit throughput: the implicit solver's cost per iteration in vertex-iterations per second beside the
// explicit substep's particle-substeps per second (same cloth, same run), and thread scaling 1 -> T threads.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "commands.hpp"
#include "drape/workers.hpp"

namespace drape::implicit_bench {

namespace {
struct Rates {
    double step_lo = 0.0, step_hi = 0.0; ///< s per implicit step at k_lo and k_hi iterations
    double per_iteration = 0.0;          ///< s, (step_hi - step_lo) / (k_hi - k_lo)
    double substep = 0.0;                ///< s per explicit substep
};
constexpr std::uint32_t k_lo = 5, k_hi = 25;

/// Best of `repeats` timings of f (wall seconds).
template <class F> double best_of(int repeats, F&& f) {
    double best = INFINITY;
    for (int r = 0; r < repeats; ++r) {
        const auto t0 = std::chrono::steady_clock::now();
        f();
        best = std::min(best, seconds_since(t0));
    }
    return best;
}

Rates measure(const BuiltScene& scene, const Options& opt) {
    Rates r;
    const std::size_t particles = scene.cloth.particle_count;
    // Implicit: from the hang after a few steps (moving), each timing a fresh copy's one step.
    Simulation base(scene.cloth, scene.initial,
                    implicit_params(scene.params, opt.dt, k_lo, opt.rho, ImplicitMethod::gauss_seidel, 0.0f,
                                    opt.multilevel, opt.fas));
    base.step(3);
    const int repeats = particles > 200000 ? 2 : 4;
    for (std::uint32_t k : {k_lo, k_hi}) {
        Simulation sim = restart(base, implicit_params(base.params(), opt.dt, k, opt.rho, ImplicitMethod::gauss_seidel,
                                                       0.0f, opt.multilevel, opt.fas));
        sim.step(1); // warm
        const double t = best_of(repeats, [&] { sim.step(1); });
        (k == k_lo ? r.step_lo : r.step_hi) = t;
    }
    r.per_iteration = (r.step_hi - r.step_lo) / static_cast<double>(k_hi - k_lo);
    // Explicit: substeps at the default dt, batches of about 5e7 particle-substeps.
    Simulation ex(scene.cloth, scene.initial, scene.params);
    const std::size_t batch = std::max<std::size_t>(20, static_cast<std::size_t>(5e7 / static_cast<double>(particles)));
    ex.step(batch / 4); // warm
    r.substep = best_of(3, [&] { ex.step(batch); }) / static_cast<double>(batch);
    return r;
}
} // namespace

int cmd_throughput(const Options& opt) {
    Report rep;
    rep.command = "throughput";
    rep.threads = opt.threads;
    const std::vector<std::uint32_t> sizes = opt.sizes.empty() ? std::vector<std::uint32_t>{316, 1000} : opt.sizes;
    std::vector<int> thread_counts = {1};
    if (opt.threads != 1) thread_counts.push_back(opt.threads);
    Table t;
    t.title = "Implicit iteration cost beside the explicit substep (hang, Gauss-Seidel VBD" +
              std::string(opt.rho > 0.0f ? " + Chebyshev" : "") +
              (opt.multilevel ? ", multilevel guess" : ", single level") + ")";
    t.columns = {"N", "particles", "threads", "implicit step, " + std::to_string(k_lo) + " it (ms)",
                 "implicit step, " + std::to_string(k_hi) + " it (ms)", "per iteration (ms)", "vertex-iterations/s",
                 "explicit substep (ms)", "particle-substeps/s", "substeps per iteration"};
    Table s;
    s.title = "Thread scaling 1 -> " + std::to_string(opt.threads);
    s.columns = {"N", "implicit per-iteration speed-up", "implicit step (" + std::to_string(k_hi) + " it) speed-up",
                 "explicit substep speed-up"};
    for (std::uint32_t n : sizes) {
        const BuiltScene scene = hang_scene(n);
        const double particles = static_cast<double>(scene.cloth.particle_count);
        std::vector<Rates> per_threads;
        for (int threads : thread_counts) {
            std::fprintf(stderr, "throughput: N = %u, %d thread(s)\n", n, threads);
            Workers workers(threads);
            const Rates r = workers.run([&] { return measure(scene, opt); });
            per_threads.push_back(r);
            t.add({num(n, "%.0f"), num(particles, "%.0f"), num(threads, "%.0f"), num(r.step_lo * 1e3, "%.4g"),
                   num(r.step_hi * 1e3, "%.4g"), num(r.per_iteration * 1e3, "%.4g"),
                   num(particles / r.per_iteration, "%.3e"), num(r.substep * 1e3, "%.4g"),
                   num(particles / r.substep, "%.3e"), num(r.per_iteration / r.substep, "%.3g")});
        }
        if (per_threads.size() == 2)
            s.add({num(n, "%.0f"), num(per_threads[0].per_iteration / per_threads[1].per_iteration, "%.3g"),
                   num(per_threads[0].step_hi / per_threads[1].step_hi, "%.3g"),
                   num(per_threads[0].substep / per_threads[1].substep, "%.3g")});
    }
    rep.tables.push_back(std::move(t));
    if (!s.rows.empty()) rep.tables.push_back(std::move(s));
    rep.notes.push_back("Per iteration = (step at " + std::to_string(k_hi) + " iterations - step at " +
                        std::to_string(k_lo) + ") / " + std::to_string(k_hi - k_lo) +
                        " (the step's fixed cost - prediction, velocities - cancels); vertex-iterations/s = particles "
                        "/ per-iteration time. Best of 2-4 timings each; explicit: best of 3 batches of ~5e7 "
                        "particle-substeps at the default dt.");
    rep.print(opt.json, opt.json_out);
    return 0;
}

} // namespace drape::implicit_bench
