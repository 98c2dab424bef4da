// drape_implicit convergence: one implicit step from a moving hang, the relative energy error
// (G(x_k) - G*) / |G(x_0) - G*| against iterations k and against wall time, per iteration method.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "commands.hpp"

namespace drape::implicit_bench {

namespace {
struct Variant {
    std::string name;
    ImplicitMethod method;
    float rho;
    bool multilevel;
    bool fas = false;
};
struct Point {
    std::uint32_t k = 0;
    double wall = 0.0, g = 0.0, residual = 0.0;
};
} // namespace

int cmd_convergence(const Options& opt) {
    Report rep;
    rep.command = "convergence";
    rep.threads = opt.threads;
    const std::vector<std::uint32_t> sizes = opt.sizes.empty() ? std::vector<std::uint32_t>{100, 316} : opt.sizes;
    const float rho = opt.rho > 0.0f ? opt.rho : 0.9f;
    const std::vector<Variant> variants = {
        {"Gauss-Seidel VBD", ImplicitMethod::gauss_seidel, 0.0f, true},
        {"Gauss-Seidel VBD + Chebyshev " + std::to_string(rho).substr(0, 4), ImplicitMethod::gauss_seidel, rho, true},
        {"Gauss-Seidel VBD + Chebyshev + FAS", ImplicitMethod::gauss_seidel, rho, true, true},
        {"Gauss-Seidel VBD + Chebyshev, single level", ImplicitMethod::gauss_seidel, rho, false},
        {"Jacobi", ImplicitMethod::jacobi, 0.0f, true},
        {"Jacobi + Chebyshev " + std::to_string(rho).substr(0, 4), ImplicitMethod::jacobi, rho, true},
    };
    const std::vector<std::uint32_t> ks = {1, 2, 3, 5, 7, 10, 15, 20, 30, 50, 70, 100, 150, 200, 300};
    std::string csv_path = opt.csv;
    if (csv_path.empty()) csv_path = (opt.out_dir.empty() ? std::string(".") : opt.out_dir) + "/convergence.csv";
    std::ofstream csv(csv_path);
    if (!csv) {
        std::fprintf(stderr, "drape_implicit: cannot write %s\n", csv_path.c_str());
        return 5;
    }
    csv << "n,h_s,method,iterations,wall_s,objective_J,relative_error,solver_relative_residual\n";
    csv.precision(17);
    const float h = opt.dt;
    for (std::uint32_t n : sizes) {
        BuiltScene scene = hang_scene(n);
        // The moving state: the hang after 0.5 s of falling (implicit steps of h, 100 iterations each).
        Simulation start(scene.cloth, scene.initial,
                         implicit_params(scene.params, h, 100, 0.9f, ImplicitMethod::gauss_seidel, 0.0f));
        start.step(static_cast<std::size_t>(std::llround(0.5 / h)));
        // Every variant steps a fresh simulation restarted from this state (restart(): the same first guess for all).
        const StepProblem prob = step_problem(start, h);
        const std::vector<double> x0 = prediction(prob);
        const double g0 = objective(prob, x0);
        const double g0_ref = reference_objective(prob, x0);
        if (std::isfinite(g0_ref)) {
            char buf[200];
            std::snprintf(buf, sizeof buf, "N = %u: G(x_0) here %.12g J, by implicit_reference.hpp %.12g J", n, g0, g0_ref);
            rep.notes.push_back(buf);
        }
        std::fprintf(stderr, "convergence: N = %u, t = %.3g s, max speed %.3g m/s\n", n, start.time(),
                     static_cast<double>(start.health().max_speed));

        std::vector<std::vector<Point>> curves(variants.size());
        std::vector<double> best_x;
        double best_g = INFINITY;
        for (std::size_t v = 0; v < variants.size(); ++v) {
            for (std::uint32_t k : ks) {
                if (k > opt.kmax) break;
                Simulation sim = restart(start, implicit_params(start.params(), h, k, variants[v].rho, variants[v].method,
                                                                0.0f, variants[v].multilevel, variants[v].fas));
                const auto t0 = std::chrono::steady_clock::now();
                bool ok = true;
                try {
                    sim.step(1);
                } catch (const std::exception& e) {
                    ok = false;
                    rep.notes.push_back("N = " + std::to_string(n) + " " + variants[v].name + " k = " +
                                        std::to_string(k) + ": " + e.what());
                }
                const double wall = seconds_since(t0);
                const std::vector<double> x = positions(sim);
                const double g = ok ? objective(prob, x) : NAN;
                curves[v].push_back({k, wall, g, sim.implicit_stats().relative_residual});
                if (g < best_g) {
                    best_g = g;
                    best_x = x;
                }
            }
        }
        // G*: the Eigen Newton reference from the best iterate, else 1000 Gauss-Seidel + Chebyshev iterations.
        double g_star = best_g;
        std::string star_method;
        if (have_newton_reference() && n <= opt.newton_step_max_n) {
            const NewtonOut r = newton_minimise(prob, best_x, 1e-9, 50);
            const double gr = objective(prob, r.x);
            g_star = std::min(g_star, gr);
            char buf[200];
            std::snprintf(buf, sizeof buf, "Eigen Newton reference from the best iterate: %d iterations, |grad G| = "
                          "%.3g N%s", r.iterations, r.gradient_norm, r.converged ? "" : " (not converged: G* may lie above the minimum, the errors are then understated)");
            star_method = buf;
        } else {
            Simulation sim = restart(start, implicit_params(start.params(), h, 1000, rho, ImplicitMethod::gauss_seidel, 0.0f));
            sim.step(1);
            g_star = std::min(g_star, objective(prob, positions(sim)));
            star_method = std::string("the lowest of 1000 Gauss-Seidel + Chebyshev iterations and every iterate above (") +
                          (have_newton_reference() ? "N above --newton-step-max-n: the Eigen reference's sparse LDLT is too slow here"
                                                   : "the Eigen Newton reference is not compiled in") +
                          "); errors near the end of the curves are understated";
        }
        const double denom = std::fabs(g0 - g_star);
        char buf[400];
        std::snprintf(buf, sizeof buf,
                      "N = %u: one step h = %.4g s from the hang at t = %.3g s; G(x_0) - G* = %.6g J with x_0 the "
                      "inertial prediction; G* = %.12g J by %s",
                      n, h, start.time(), g0 - g_star, g_star, star_method.c_str());
        rep.notes.push_back(buf);

        Table t;
        t.title = "Convergence of one implicit step, N = " + std::to_string(n) + " (" +
                  std::to_string(scene.cloth.particle_count) + " particles): relative energy error (G(x_k) - G*) / "
                  "|G(x_0) - G*| and wall time (ms)";
        t.columns = {"iterations k"};
        for (const Variant& v : variants) {
            t.columns.push_back(v.name + " error");
            t.columns.push_back(v.name + " ms");
        }
        for (std::size_t r = 0; r < curves[0].size(); ++r) {
            std::vector<Cell> row = {num(curves[0][r].k, "%.0f")};
            for (std::size_t v = 0; v < variants.size(); ++v) {
                const Point& p = curves[v][r];
                row.push_back(num((p.g - g_star) / denom, "%.3e"));
                row.push_back(num(p.wall * 1000.0, "%.3g"));
                csv << n << ',' << h << ",\"" << variants[v].name << "\"," << p.k << ',' << p.wall << ',' << p.g << ','
                    << (p.g - g_star) / denom << ',' << p.residual << '\n';
            }
            t.add(std::move(row));
        }
        rep.tables.push_back(std::move(t));
    }
    rep.notes.push_back("CSV: " + csv_path + " (plot: bench/implicit/plot_convergence.py)");
    rep.notes.push_back("Each point is a fresh simulation restarted from the same state (restart()) and stepped once with "
                        "iterations = k (tolerance 0); "
                        "the wall time is that one step's (prediction, k sweeps, velocities). Errors below ~1e-7 are "
                        "at the float32 positions' rounding floor.");
    rep.print(opt.json, opt.json_out);
    return 0;
}

} // namespace drape::implicit_bench
