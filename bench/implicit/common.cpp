#include "common.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#if __has_include("drape/implicit_reference.hpp")
#include "drape/implicit_reference.hpp"
#define DRAPE_BENCH_NEWTON 1
#else
#define DRAPE_BENCH_NEWTON 0
#endif

namespace drape::implicit_bench {

BuiltScene hang_scene(std::uint32_t n) {
    SceneSpec spec = load_scene("hang");
    spec.grid.n = n;
    return build_scene(spec);
}

BuiltScene scene_at(const std::string& scene, std::uint32_t n) {
    SceneSpec spec = load_scene(scene);
    set_scene_resolution(spec, n, "--n");
    return build_scene(spec);
}

SimulationParams implicit_params(const SimulationParams& base, float dt, std::uint32_t iterations, float rho,
                                 ImplicitMethod method, float strain_limit, bool multilevel, bool fas) {
    SimulationParams p = base;
    p.solver = Solver::implicit;
    p.integrator = Integrator::symplectic_euler;
    p.dt = dt;
    p.implicit.iterations = iterations;
    p.implicit.tolerance = 0.0f;
    p.implicit.chebyshev_rho = rho;
    p.implicit.method = method;
    p.strain_limit.ratio = strain_limit;
    p.implicit.multilevel = multilevel;
    p.implicit.fas = fas;
    return p;
}

Simulation restart(const Simulation& sim, const SimulationParams& params) {
    const std::size_t n = sim.cloth().particle_count;
    InitialState st;
    st.x.assign(sim.x().begin(), sim.x().end());
    st.y.assign(sim.y().begin(), sim.y().end());
    st.z.assign(sim.z().begin(), sim.z().end());
    st.vx.resize(n);
    st.vy.resize(n);
    st.vz.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::array<float, 3> v = sim.velocity(i);
        st.vx[i] = v[0];
        st.vy[i] = v[1];
        st.vz[i] = v[2];
    }
    return Simulation(sim.cloth(), st, params);
}

std::vector<double> positions(const Simulation& sim) {
    const std::size_t n = sim.cloth().particle_count;
    std::vector<double> x(3 * n);
    for (std::size_t i = 0; i < n; ++i) {
        x[3 * i] = sim.x()[i];
        x[3 * i + 1] = sim.y()[i];
        x[3 * i + 2] = sim.z()[i];
    }
    return x;
}

StepProblem step_problem(const Simulation& sim, double h) {
    const SimulationParams& sp = sim.params();
    if (sp.wind.enabled || sp.aero.enabled)
        throw std::runtime_error("drape_implicit: the objective here covers gravity and air drag only (no wind)");
    StepProblem p;
    p.cloth = &sim.cloth();
    p.h = h;
    p.kr = sp.air_drag;
    p.xn = positions(sim);
    const std::size_t n = sim.cloth().particle_count;
    p.vn.resize(3 * n);
    p.a.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::array<float, 3> v = sim.velocity(i);
        for (int k = 0; k < 3; ++k) {
            p.vn[3 * i + k] = v[k];
            p.a[3 * i + k] = sp.gravity[k];
        }
    }
    return p;
}

std::vector<double> prediction(const StepProblem& p) {
    const std::size_t n = p.cloth->particle_count;
    std::vector<double> y(3 * n);
    for (std::size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const std::size_t j = 3 * i + k;
            y[j] = p.cloth->inv_mass[i] == 0.0f ? p.xn[j] : p.xn[j] + p.h * p.vn[j] + p.h * p.h * p.a[j];
        }
    return y;
}

double objective(const StepProblem& p, const std::vector<double>& x) {
    const Cloth& c = *p.cloth;
    const std::size_t n = c.particle_count;
    const double h = p.h;
    double g = 0.0;
    // Inertia and air drag (movable particles).
    for (std::size_t i = 0; i < n; ++i) {
        if (c.inv_mass[i] == 0.0f) continue;
        const double m = 1.0 / static_cast<double>(c.inv_mass[i]);
        double in = 0.0, dr = 0.0;
        for (int k = 0; k < 3; ++k) {
            const std::size_t j = 3 * i + k;
            const double y = p.xn[j] + h * p.vn[j] + h * h * p.a[j];
            in += (x[j] - y) * (x[j] - y);
            dr += (x[j] - p.xn[j]) * (x[j] - p.xn[j]);
        }
        g += m / (2.0 * h * h) * in + m * p.kr / (2.0 * h) * dr;
    }
    // Springs and their damping along the step-start direction.
    for (const Edge& e : c.edges) {
        const SpringMaterial& mat = c.material[static_cast<std::size_t>(e.kind)];
        const double k = static_cast<double>(mat.stiffness) * e.scale, kd = static_cast<double>(mat.damping) * e.scale;
        double d[3], dn[3];
        for (int q = 0; q < 3; ++q) {
            d[q] = x[3 * e.b + q] - x[3 * e.a + q];
            dn[q] = p.xn[3 * e.b + q] - p.xn[3 * e.a + q];
        }
        const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        g += 0.5 * k * (len - e.rest) * (len - e.rest);
        const double ln = std::sqrt(dn[0] * dn[0] + dn[1] * dn[1] + dn[2] * dn[2]);
        if (ln > 0.0 && kd > 0.0) {
            const double s = ((d[0] - dn[0]) * dn[0] + (d[1] - dn[1]) * dn[1] + (d[2] - dn[2]) * dn[2]) / ln;
            g += kd / (2.0 * h) * s * s;
        }
    }
    // Bending and its Rayleigh damping.
    const double beta = c.bending.damping;
    for (const BendElement& e : c.bending.elements) {
        double q[3] = {0, 0, 0}, qn[3] = {0, 0, 0};
        for (int s = 0; s < 4; ++s)
            for (int k = 0; k < 3; ++k) {
                q[k] += static_cast<double>(e.c[s]) * x[3 * e.v[s] + k];
                qn[k] += static_cast<double>(e.c[s]) * p.xn[3 * e.v[s] + k];
            }
        const double q2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
        const double dq2 = (q[0] - qn[0]) * (q[0] - qn[0]) + (q[1] - qn[1]) * (q[1] - qn[1]) + (q[2] - qn[2]) * (q[2] - qn[2]);
        g += 0.5 * e.weight * q2 + beta / (2.0 * h) * e.weight * dq2;
    }
    return g;
}

double max_distance(const std::vector<double>& a, const std::vector<double>& b) {
    double m = 0.0;
    for (std::size_t i = 0; i + 2 < a.size(); i += 3) {
        const double dx = a[i] - b[i], dy = a[i + 1] - b[i + 1], dz = a[i + 2] - b[i + 2];
        m = std::max(m, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    return m;
}

double rms_distance(const std::vector<double>& a, const std::vector<double>& b) {
    double s = 0.0;
    for (std::size_t i = 0; i + 2 < a.size(); i += 3) {
        const double dx = a[i] - b[i], dy = a[i + 1] - b[i + 1], dz = a[i + 2] - b[i + 2];
        s += dx * dx + dy * dy + dz * dz;
    }
    return a.size() < 3 ? 0.0 : std::sqrt(s / double(a.size() / 3));
}

double mean_offset(const std::vector<double>& a, const std::vector<double>& b) {
    double d[3] = {0.0, 0.0, 0.0};
    for (std::size_t i = 0; i + 2 < a.size(); i += 3)
        for (int k = 0; k < 3; ++k) d[k] += a[i + k] - b[i + k];
    const double n = a.size() < 3 ? 1.0 : double(a.size() / 3);
    return std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / n;
}

bool have_newton_reference() { return DRAPE_BENCH_NEWTON != 0; }

#if DRAPE_BENCH_NEWTON
namespace {
struct FloatProblem {
    std::vector<float> x, y, z, vx, vy, vz, ax, ay, az;
    ImplicitProblem problem;
};
void fill(FloatProblem& f, const StepProblem& p) {
    const std::size_t n = p.cloth->particle_count;
    for (std::vector<float>* v : {&f.x, &f.y, &f.z, &f.vx, &f.vy, &f.vz, &f.ax, &f.ay, &f.az}) v->resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        f.x[i] = static_cast<float>(p.xn[3 * i]);
        f.y[i] = static_cast<float>(p.xn[3 * i + 1]);
        f.z[i] = static_cast<float>(p.xn[3 * i + 2]);
        f.vx[i] = static_cast<float>(p.vn[3 * i]);
        f.vy[i] = static_cast<float>(p.vn[3 * i + 1]);
        f.vz[i] = static_cast<float>(p.vn[3 * i + 2]);
        f.ax[i] = static_cast<float>(p.a[3 * i]);
        f.ay[i] = static_cast<float>(p.a[3 * i + 1]);
        f.az[i] = static_cast<float>(p.a[3 * i + 2]);
    }
    f.problem.cloth = p.cloth;
    f.problem.h = p.h;
    f.problem.air_drag = p.kr;
    f.problem.x0 = f.x;
    f.problem.y0 = f.y;
    f.problem.z0 = f.z;
    f.problem.vx = f.vx;
    f.problem.vy = f.vy;
    f.problem.vz = f.vz;
    f.problem.ax = f.ax;
    f.problem.ay = f.ay;
    f.problem.az = f.az;
}
} // namespace
#endif

double reference_objective(const StepProblem& p, const std::vector<double>& x) {
#if DRAPE_BENCH_NEWTON
    FloatProblem f;
    fill(f, p);
    return implicit_objective(f.problem, x);
#else
    (void)p, (void)x;
    return NAN;
#endif
}

NewtonOut newton_minimise(const StepProblem& p, const std::vector<double>& start, double tolerance,
                          int max_iterations) {
    NewtonOut out;
#if DRAPE_BENCH_NEWTON
    FloatProblem f;
    fill(f, p);
    const NewtonResult r = newton_reference(f.problem, start, tolerance, max_iterations);
    out.x = r.x;
    out.objective = r.objective;
    out.gradient_norm = r.gradient_norm;
    out.iterations = r.iterations;
    out.converged = r.converged;
#else
    (void)p, (void)start, (void)tolerance, (void)max_iterations;
#endif
    return out;
}

namespace {
/// Steps `sim` `per_check` steps at a time while more() until a check moves no particle more than 10 um; x ends as
/// the positions, and the last check's largest motion (m) is returned.
template <class More> double step_until_still(Simulation& sim, std::size_t per_check, std::vector<double>& x, More more) {
    x = positions(sim);
    double moved = 0.0;
    while (more()) {
        sim.step(per_check);
        std::vector<double> xn = positions(sim);
        moved = max_distance(xn, x);
        x = std::move(xn);
        if (moved < 1e-5) break;
    }
    return moved;
}
} // namespace

Equilibrium reference_equilibrium(const Simulation& settled, const Options& opt, std::uint32_t n) {
    Equilibrium eq;
#if !DRAPE_BENCH_NEWTON
    (void)n;
#endif
#if DRAPE_BENCH_NEWTON
    if (n <= opt.newton_max_n) {
        // The static problem as a sequence of backward-Euler steps from rest with a long step (h = 10 s: G is then
        // the potential energy plus a weak proximal term), each solved by Newton to 1e-10 of the weight's norm, the
        // state stored in float between steps (as the simulation holds it), until a step moves nothing by 0.1 um
        // (tests/test_implicit_reference.cpp, LargeStepsFromRestReachAStaticEquilibrium).
        const Cloth& cloth = settled.cloth();
        const std::size_t np = cloth.particle_count;
        std::vector<double> x = positions(settled);
        auto problem_at = [&](const std::vector<double>& at, double h) {
            StepProblem sp;
            sp.cloth = &cloth;
            sp.h = h;
            sp.kr = 0.0;
            sp.xn = at;
            sp.vn.assign(3 * np, 0.0);
            sp.a.resize(3 * np);
            for (std::size_t i = 0; i < np; ++i)
                for (int k = 0; k < 3; ++k) sp.a[3 * i + k] = settled.params().gravity[k];
            return sp;
        };
        double weight2 = 0.0;
        const double g_norm = std::sqrt(double(settled.params().gravity[0]) * settled.params().gravity[0] +
                                        double(settled.params().gravity[1]) * settled.params().gravity[1] +
                                        double(settled.params().gravity[2]) * settled.params().gravity[2]);
        for (std::size_t i = 0; i < np; ++i)
            if (cloth.inv_mass[i] != 0.0f) weight2 += std::pow(g_norm / cloth.inv_mass[i], 2);
        const double tolerance = 1e-10 * std::sqrt(weight2);
        int steps = 0, newton_total = 0;
        double moved = 1.0;
        bool all_converged = true;
        for (; steps < 40 && moved > 1e-7 && newton_total < opt.newton_iterations; ++steps) {
            FloatProblem f;
            fill(f, problem_at(x, 10.0));
            std::vector<double> xs(3 * np);
            for (std::size_t i = 0; i < np; ++i) {
                xs[3 * i] = f.x[i];
                xs[3 * i + 1] = f.y[i];
                xs[3 * i + 2] = f.z[i];
            }
            const NewtonResult r = newton_reference(f.problem, xs, tolerance, std::min(100, opt.newton_iterations - newton_total));
            newton_total += r.iterations;
            all_converged = all_converged && r.converged;
            moved = max_distance(r.x, xs);
            x = r.x;
        }
        // Static residual: worst |f_elastic + m g| / m g over the movable particles (G's gradient at x = x^n, v = 0
        // and h = 1e6 s is grad E - m g; inertia and damping vanish).
        FloatProblem f;
        fill(f, problem_at(x, 1e6));
        std::vector<double> g(3 * np);
        implicit_gradient(f.problem, x, g);
        double worst = 0.0;
        for (std::size_t i = 0; i < np; ++i) {
            if (cloth.inv_mass[i] == 0.0f) continue;
            const double w = g_norm / cloth.inv_mass[i];
            worst = std::max(worst, std::sqrt(g[3 * i] * g[3 * i] + g[3 * i + 1] * g[3 * i + 1] + g[3 * i + 2] * g[3 * i + 2]) / w);
        }
        eq.x = x;
        eq.residual = worst;
        char buf[300];
        std::snprintf(buf, sizeof buf,
                      "Eigen Newton reference from the settled shape (static: %d steps of h = 10 s from rest, %d "
                      "Newton iterations%s; the last step moved %.2g m; worst |f_elastic + m g| / m g = %.2g)",
                      steps, newton_total, all_converged ? "" : ", some not converged", moved, worst);
        eq.method = buf;
        return eq;
    }
#endif
    // A long implicit run from the settled shape, h = 0.1 s, many iterations, with the air drag raised to
    // opt.ref_drag (near critical for the hanging cloth's swing, sqrt(g / 1 m) ~ 3 rad/s; the static equilibrium does
    // not depend on drag) so that the swing dies out, until a step moves no particle more than 10 um.
    SimulationParams p = implicit_params(settled.params(), 0.1f, opt.ref_iterations, opt.rho,
                                         ImplicitMethod::gauss_seidel, 0.0f, true);
    p.air_drag = static_cast<float>(opt.ref_drag);
    Simulation sim = restart(settled, p);
    int steps = 0;
    const double moved = step_until_still(sim, 1, eq.x, [&] {
        if (steps == opt.ref_steps) return false;
        ++steps;
        return true;
    });
    eq.residual = moved;
    char buf[300];
    std::snprintf(buf, sizeof buf,
                  "long implicit run (h = 0.1 s, %u Gauss-Seidel iterations + Chebyshev, air drag %.3g/s, %d steps from "
                  "the settled shape; the last step moved %.2g m%s)%s",
                  opt.ref_iterations, opt.ref_drag, steps, moved, moved < 1e-5 ? "" : ": not settled",
                  have_newton_reference() ? "" : " - the Eigen Newton reference is not compiled in");
    eq.method = buf;
    return eq;
}

Equilibrium explicit_equilibrium(const Simulation& settled, const SimulationParams& explicit_params, const Options& opt) {
    SimulationParams p = explicit_params;
    p.solver = Solver::explicit_euler;
    p.air_drag = static_cast<float>(opt.ref_drag);
    const std::size_t n = settled.cloth().particle_count;
    InitialState st; // the settled shape, at rest
    st.x.assign(settled.x().begin(), settled.x().end());
    st.y.assign(settled.y().begin(), settled.y().end());
    st.z.assign(settled.z().begin(), settled.z().end());
    st.vx.assign(n, 0.0f);
    st.vy.assign(n, 0.0f);
    st.vz.assign(n, 0.0f);
    Simulation sim(settled.cloth(), st, p);
    const std::size_t window = std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(0.1 / double(p.dt))));
    Equilibrium eq;
    const double moved = step_until_still(sim, window, eq.x, [&] { return sim.time() < opt.ref_seconds; });
    eq.residual = moved;
    char buf[300];
    std::snprintf(buf, sizeof buf,
                  "explicit run (%s, dt = %.3g s, air drag %.3g/s, %.3g s from the settled shape at rest; the last "
                  "0.1 s moved %.2g m%s)",
                  integrator_name(p.integrator), double(p.dt), opt.ref_drag, sim.time(), moved,
                  moved < 1e-5 ? "" : ": not settled");
    eq.method = buf;
    return eq;
}

double load_average() {
    std::ifstream f("/proc/loadavg");
    double l = -1.0;
    if (f) f >> l;
    return l;
}

Cell num(double v, const char* fmt) {
    if (!std::isfinite(v)) return {std::isnan(v) ? "nan" : "inf", false};
    char buf[64];
    std::snprintf(buf, sizeof buf, fmt, v);
    return {buf, true};
}
Cell txt(const std::string& s) { return {s, false}; }

namespace {
std::string json_string(const std::string& s) {
    std::string o = "\"";
    for (char c : s) {
        if (c == '"' || c == '\\') o += '\\';
        if (c == '\n') {
            o += "\\n";
            continue;
        }
        o += c;
    }
    return o + "\"";
}
} // namespace

void Report::write_json(std::FILE* f) const {
    std::fprintf(f, "{\"command\": %s, \"threads\": %d, \"load\": %.2f, \"tables\": [", json_string(command).c_str(),
                threads, load_average());
    for (std::size_t t = 0; t < tables.size(); ++t) {
        const Table& tb = tables[t];
        std::fprintf(f, "%s\n {\"title\": %s, \"rows\": [", t ? "," : "", json_string(tb.title).c_str());
        for (std::size_t r = 0; r < tb.rows.size(); ++r) {
            std::fprintf(f, "%s\n  {", r ? "," : "");
            for (std::size_t c = 0; c < tb.columns.size() && c < tb.rows[r].size(); ++c) {
                const Cell& cell = tb.rows[r][c];
                std::fprintf(f, "%s%s: %s", c ? ", " : "", json_string(tb.columns[c]).c_str(),
                            cell.number ? cell.text.c_str() : json_string(cell.text).c_str());
            }
            std::fprintf(f, "}");
        }
        std::fprintf(f, "]}");
    }
    std::fprintf(f, "],\n \"notes\": [");
    for (std::size_t k = 0; k < notes.size(); ++k) std::fprintf(f, "%s%s", k ? ", " : "", json_string(notes[k]).c_str());
    std::fprintf(f, "]}\n");
}

void Report::print(bool json, const std::string& json_file) const {
    if (!json_file.empty()) {
        std::FILE* f = std::fopen(json_file.c_str(), "w");
        if (!f) throw std::runtime_error("cannot write " + json_file);
        write_json(f);
        std::fclose(f);
    }
    if (json) {
        write_json(stdout);
        return;
    }
    for (const Table& tb : tables) {
        std::printf("%s\n\n|", tb.title.c_str());
        for (const std::string& c : tb.columns) std::printf(" %s |", c.c_str());
        std::printf("\n|");
        for (std::size_t c = 0; c < tb.columns.size(); ++c) std::printf("---|");
        std::printf("\n");
        for (const auto& row : tb.rows) {
            std::printf("|");
            for (const Cell& cell : row) std::printf(" %s |", cell.text.c_str());
            std::printf("\n");
        }
        std::printf("\n");
    }
    for (const std::string& n : notes) std::printf("%s\n", n.c_str());
    std::printf("\n%d threads; load average %.2f (1 min, /proc/loadavg) at the end of the run\n", threads,
                load_average());
}

} // namespace drape::implicit_bench
