// The exact reference for one implicit step (implicit_reference.hpp, docs/implicit.md): G, its gradient, its projected
// Hessian and projected Newton with Eigen's sparse LDLT. Plain double loops over the cloth's cold lists (edges,
// bending elements): clarity over speed.
#include "drape/implicit_reference.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCholesky>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <string>

#include "drape/cloth.hpp"
#include "drape/errors.hpp"
#include "implicit_hessian.hpp"

namespace drape {

namespace {

using V3 = std::array<double, 3>;

V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

std::string num(double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%g", v);
    return buf;
}

void check_span(std::span<const float> s, std::size_t n, const char* name, bool may_be_empty) {
    if (may_be_empty && s.empty()) return;
    if (s.size() != n)
        throw InvalidInput(std::string("implicit step: ") + name + " has " + std::to_string(s.size()) +
                           " entries (must be the particle count, " + std::to_string(n) + ")");
    for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(s[i]))
            throw InvalidInput(std::string("implicit step: ") + name + "[" + std::to_string(i) + "] = " + num(s[i]) +
                               " is not finite");
}

void check_positions(const ImplicitProblem& p, std::span<const double> x, const char* what) {
    const std::size_t n = p.cloth->particle_count;
    if (x.size() != 3 * n)
        throw InvalidInput(std::string("implicit step: ") + what + " has " + std::to_string(x.size()) +
                           " entries (must be 3 x the particle count, " + std::to_string(3 * n) + ")");
    for (std::size_t k = 0; k < x.size(); ++k)
        if (!std::isfinite(x[k]))
            throw InvalidInput(std::string("implicit step: ") + what + "[" + std::to_string(k) + "] = " + num(x[k]) +
                               " is not finite");
}

bool fixed(const ImplicitProblem& p, std::size_t i) { return !(p.cloth->inv_mass[i] > 0.0f); }
double mass(const ImplicitProblem& p, std::size_t i) { return 1.0 / double(p.cloth->inv_mass[i]); }
V3 start_position(const ImplicitProblem& p, std::size_t i) { return {p.x0[i], p.y0[i], p.z0[i]}; }

/// Particle i's position in x; a fixed particle's is x^n.
V3 position(const ImplicitProblem& p, std::span<const double> x, std::size_t i) {
    return fixed(p, i) ? start_position(p, i) : V3{x[3 * i], x[3 * i + 1], x[3 * i + 2]};
}

/// The displacement x_i - x_i^n (0 for a fixed particle), formed directly so it keeps its digits.
V3 displacement(const ImplicitProblem& p, std::span<const double> x, std::size_t i) {
    if (fixed(p, i)) return {0.0, 0.0, 0.0};
    return {x[3 * i] - double(p.x0[i]), x[3 * i + 1] - double(p.y0[i]), x[3 * i + 2] - double(p.z0[i])};
}

/// h v + h^2 a: y_i - x_i^n.
V3 predicted_displacement(const ImplicitProblem& p, std::size_t i) {
    const double h = p.h;
    return {h * p.vx[i] + h * h * p.ax[i], h * p.vy[i] + h * h * p.ay[i], h * p.vz[i] + h * h * p.az[i]};
}

struct SpringConstants {
    double k = 0.0, kd = 0.0, rest = 0.0;
};
SpringConstants spring_constants(const Cloth& c, const Edge& e) {
    const SpringMaterial& m = c.material[std::size_t(e.kind)];
    return {double(m.stiffness) * e.scale, double(m.damping) * e.scale, double(e.rest)};
}

/// n_s: the unit spring direction a -> b at the step start, or 0 when the spring has zero length there.
V3 frozen_direction(const ImplicitProblem& p, const Edge& e) {
    const V3 d = sub(start_position(p, e.b), start_position(p, e.a));
    const double len = std::sqrt(dot(d, d));
    if (!(len > 0.0)) return {0.0, 0.0, 0.0};
    return {d[0] / len, d[1] / len, d[2] / len};
}

/// Below this length (relative to the rest length) a spring's direction is undefined: it contributes no gradient and
/// the isotropic block k I to the Hessian.
constexpr double degenerate_length = 1e-12;

/// G(x) and the sum of the magnitudes of its terms (the scale of its rounding error).
double objective_and_magnitude(const ImplicitProblem& p, std::span<const double> x, double& magnitude) {
    const Cloth& c = *p.cloth;
    const std::size_t n = c.particle_count;
    const double h = p.h;
    double sum = 0.0, mag = 0.0;
    auto add = [&](double v) {
        sum += v;
        mag += std::fabs(v);
    };
    for (std::size_t i = 0; i < n; ++i) {
        if (fixed(p, i)) continue;
        const double m = mass(p, i);
        const V3 d = displacement(p, x, i), dy = sub(d, predicted_displacement(p, i));
        add(m / (2.0 * h * h) * dot(dy, dy) + m * p.air_drag / (2.0 * h) * dot(d, d));
        if (!p.fx.empty()) add(-(double(p.fx[i]) * x[3 * i] + double(p.fy[i]) * x[3 * i + 1] + double(p.fz[i]) * x[3 * i + 2]));
    }
    for (const Edge& e : c.edges) {
        const SpringConstants s = spring_constants(c, e);
        const V3 d = sub(position(p, x, e.b), position(p, x, e.a));
        const double stretch = std::sqrt(dot(d, d)) - s.rest;
        const double dd = dot(sub(displacement(p, x, e.b), displacement(p, x, e.a)), frozen_direction(p, e));
        add(0.5 * s.k * stretch * stretch + s.kd / (2.0 * h) * dd * dd);
    }
    const double beta = c.bending.damping;
    for (const BendElement& e : c.bending.elements) {
        V3 q{0.0, 0.0, 0.0}, dq{0.0, 0.0, 0.0};
        for (std::size_t k = 0; k < 4; ++k) {
            if (e.c[k] == 0.0f) continue;
            const V3 xk = position(p, x, e.v[k]), dk = displacement(p, x, e.v[k]);
            for (int a = 0; a < 3; ++a) {
                q[a] += double(e.c[k]) * xk[a];
                dq[a] += double(e.c[k]) * dk[a];
            }
        }
        add(0.5 * double(e.weight) * (dot(q, q) + beta / h * dot(dq, dq)));
    }
    magnitude = mag;
    return sum;
}

void gradient_unchecked(const ImplicitProblem& p, std::span<const double> x, std::span<double> g) {
    const Cloth& c = *p.cloth;
    const std::size_t n = c.particle_count;
    const double h = p.h;
    std::fill(g.begin(), g.end(), 0.0);
    auto add = [&](std::size_t i, const V3& v, double s) {
        if (fixed(p, i)) return;
        for (int a = 0; a < 3; ++a) g[3 * i + a] += s * v[a];
    };
    for (std::size_t i = 0; i < n; ++i) {
        if (fixed(p, i)) continue;
        const double m = mass(p, i);
        const V3 d = displacement(p, x, i), dy = sub(d, predicted_displacement(p, i));
        add(i, dy, m / (h * h));
        add(i, d, m * p.air_drag / h);
        if (!p.fx.empty()) add(i, V3{p.fx[i], p.fy[i], p.fz[i]}, -1.0);
    }
    for (const Edge& e : c.edges) {
        const SpringConstants s = spring_constants(c, e);
        const V3 d = sub(position(p, x, e.b), position(p, x, e.a));
        const double len = std::sqrt(dot(d, d));
        if (len > degenerate_length * s.rest) {
            // dE/dx_b = k (L - l) u, u = d / L; dE/dx_a = -that.
            const double f = s.k * (len - s.rest) / len;
            add(e.b, d, f);
            add(e.a, d, -f);
        }
        const V3 nd = frozen_direction(p, e);
        const double dd = dot(sub(displacement(p, x, e.b), displacement(p, x, e.a)), nd);
        add(e.b, nd, s.kd / h * dd);
        add(e.a, nd, -s.kd / h * dd);
    }
    const double beta = c.bending.damping;
    for (const BendElement& e : c.bending.elements) {
        V3 q{0.0, 0.0, 0.0}, dq{0.0, 0.0, 0.0};
        for (std::size_t k = 0; k < 4; ++k) {
            if (e.c[k] == 0.0f) continue;
            const V3 xk = position(p, x, e.v[k]), dk = displacement(p, x, e.v[k]);
            for (int a = 0; a < 3; ++a) {
                q[a] += double(e.c[k]) * xk[a];
                dq[a] += double(e.c[k]) * dk[a];
            }
        }
        const V3 r{q[0] + beta / h * dq[0], q[1] + beta / h * dq[1], q[2] + beta / h * dq[2]};
        for (std::size_t k = 0; k < 4; ++k)
            if (e.c[k] != 0.0f) add(e.v[k], r, double(e.weight) * e.c[k]);
    }
}

double norm_unchecked(const ImplicitProblem& p, std::span<const double> g) {
    double s = 0.0;
    for (std::size_t i = 0; i < p.cloth->particle_count; ++i)
        if (!fixed(p, i)) s += g[3 * i] * g[3 * i] + g[3 * i + 1] * g[3 * i + 1] + g[3 * i + 2] * g[3 * i + 2];
    return std::sqrt(s);
}

} // namespace

void validate_implicit_problem(const ImplicitProblem& p) {
    if (p.cloth == nullptr) throw InvalidInput("implicit step: no cloth");
    if (!(p.h > 0.0) || !std::isfinite(p.h))
        throw InvalidInput("implicit step: h = " + num(p.h) + " s (must be finite and > 0)");
    if (!(p.air_drag >= 0.0) || !std::isfinite(p.air_drag))
        throw InvalidInput("implicit step: air_drag = " + num(p.air_drag) + " 1/s (must be finite and >= 0)");
    const std::size_t n = p.cloth->particle_count;
    check_span(p.x0, n, "x0", false), check_span(p.y0, n, "y0", false), check_span(p.z0, n, "z0", false);
    check_span(p.vx, n, "vx", false), check_span(p.vy, n, "vy", false), check_span(p.vz, n, "vz", false);
    check_span(p.ax, n, "ax", false), check_span(p.ay, n, "ay", false), check_span(p.az, n, "az", false);
    if (p.fx.empty() != p.fy.empty() || p.fx.empty() != p.fz.empty())
        throw InvalidInput("implicit step: fx, fy, fz must all be empty or all have the particle count's entries");
    check_span(p.fx, n, "fx", true), check_span(p.fy, n, "fy", true), check_span(p.fz, n, "fz", true);
}

std::vector<double> inertial_prediction(const ImplicitProblem& p) {
    validate_implicit_problem(p);
    const std::size_t n = p.cloth->particle_count;
    std::vector<double> y(3 * n);
    for (std::size_t i = 0; i < n; ++i) {
        const V3 x0 = start_position(p, i);
        const V3 d = fixed(p, i) ? V3{0.0, 0.0, 0.0} : predicted_displacement(p, i);
        for (int a = 0; a < 3; ++a) y[3 * i + a] = x0[a] + d[a];
    }
    return y;
}

double implicit_objective(const ImplicitProblem& p, std::span<const double> x) {
    validate_implicit_problem(p);
    check_positions(p, x, "x");
    double magnitude = 0.0;
    return objective_and_magnitude(p, x, magnitude);
}

void implicit_gradient(const ImplicitProblem& p, std::span<const double> x, std::span<double> g) {
    validate_implicit_problem(p);
    check_positions(p, x, "x");
    if (g.size() != x.size())
        throw InvalidInput("implicit step: the gradient has " + std::to_string(g.size()) + " entries (must be " +
                           std::to_string(x.size()) + ")");
    gradient_unchecked(p, x, g);
}

double movable_norm(const ImplicitProblem& p, std::span<const double> g) {
    validate_implicit_problem(p);
    check_positions(p, g, "gradient");
    return norm_unchecked(p, g);
}

namespace {
/// `bend`: bending_hessian of the cloth's elements (constant: Newton computes it once).
Eigen::SparseMatrix<double> hessian_unchecked(const ImplicitProblem& p, std::span<const double> x, bool projected,
                                              const std::vector<BendTriplet>& bend) {
    const Cloth& c = *p.cloth;
    const std::size_t n = c.particle_count;
    const double h = p.h;
    using T = Eigen::Triplet<double>;
    std::vector<T> t;
    t.reserve(3 * n + 36 * c.edges.size() + 3 * 16 * c.bending.elements.size());
    for (std::size_t i = 0; i < n; ++i) {
        const double d = fixed(p, i) ? 1.0 : mass(p, i) * (1.0 / (h * h) + p.air_drag / h);
        for (int a = 0; a < 3; ++a) t.emplace_back(int(3 * i + a), int(3 * i + a), d);
    }
    for (const Edge& e : c.edges) {
        const SpringConstants s = spring_constants(c, e);
        const V3 d = sub(position(p, x, e.b), position(p, x, e.a));
        const double len = std::sqrt(dot(d, d));
        double block[3][3];
        const V3 nd = frozen_direction(p, e);
        if (len > degenerate_length * s.rest) {
            const V3 u{d[0] / len, d[1] / len, d[2] / len};
            const double transverse = projected ? std::max(0.0, 1.0 - s.rest / len) // a compressed spring's is 0
                                                : 1.0 - s.rest / len;
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b)
                    block[a][b] = s.k * (transverse * ((a == b ? 1.0 : 0.0) - u[a] * u[b]) + u[a] * u[b]);
        } else {
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) block[a][b] = a == b ? s.k : 0.0;
        }
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) block[a][b] += s.kd / h * nd[a] * nd[b];
        const bool ma = !fixed(p, e.a), mb = !fixed(p, e.b);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                const double v = block[a][b]; // zeros too: the pattern stays the same at every x
                if (ma) t.emplace_back(int(3 * e.a + a), int(3 * e.a + b), v);
                if (mb) t.emplace_back(int(3 * e.b + a), int(3 * e.b + b), v);
                if (ma && mb) {
                    t.emplace_back(int(3 * e.a + a), int(3 * e.b + b), -v);
                    t.emplace_back(int(3 * e.b + a), int(3 * e.a + b), -v);
                }
            }
    }
    const double bend_scale = 1.0 + double(c.bending.damping) / h;
    for (const BendTriplet& q : bend) {
        if (fixed(p, q.row) || fixed(p, q.col)) continue;
        for (int a = 0; a < 3; ++a) t.emplace_back(int(3 * q.row + a), int(3 * q.col + a), bend_scale * q.value);
    }
    Eigen::SparseMatrix<double> hm(int(3 * n), int(3 * n));
    hm.setFromTriplets(t.begin(), t.end());
    return hm;
}
} // namespace

Eigen::SparseMatrix<double> implicit_hessian(const ImplicitProblem& p, std::span<const double> x) {
    validate_implicit_problem(p);
    check_positions(p, x, "x");
    return hessian_unchecked(p, x, true, bending_hessian(p.cloth->bending.elements, p.cloth->particle_count));
}

NewtonResult newton_reference(const ImplicitProblem& p, std::span<const double> start, double tolerance,
                              int max_iterations) {
    validate_implicit_problem(p);
    if (!(tolerance >= 0.0) || !std::isfinite(tolerance))
        throw InvalidInput("implicit step: Newton tolerance = " + num(tolerance) + " N (must be finite and >= 0)");
    if (max_iterations < 0)
        throw InvalidInput("implicit step: Newton max_iterations = " + std::to_string(max_iterations) +
                           " (must be >= 0)");
    const std::size_t n = p.cloth->particle_count;
    NewtonResult r;
    if (start.empty()) {
        r.x = inertial_prediction(p);
    } else {
        check_positions(p, start, "start");
        r.x.assign(start.begin(), start.end());
    }
    for (std::size_t i = 0; i < n; ++i)
        if (fixed(p, i)) r.x[3 * i] = p.x0[i], r.x[3 * i + 1] = p.y0[i], r.x[3 * i + 2] = p.z0[i];

    const int dim = int(3 * n);
    Eigen::VectorXd g(dim), gt(dim), step(dim);
    std::vector<double> xt(3 * n);
    double magnitude = 0.0;
    double G = objective_and_magnitude(p, r.x, magnitude);
    gradient_unchecked(p, r.x, {g.data(), 3 * n});
    double gnorm = norm_unchecked(p, {g.data(), 3 * n});
    r.objective_history.push_back(G);
    r.gradient_history.push_back(gnorm);

    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
    const std::vector<BendTriplet> bend = bending_hessian(p.cloth->bending.elements, n);
    while (r.iterations < max_iterations && !(gnorm <= tolerance)) {
        // The exact Hessian when it is positive definite (every pivot of its LDL^T > 0): quadratic convergence; the
        // projected one otherwise (positive definite with the inertia term, so p is a descent direction).
        Eigen::SparseMatrix<double> H = hessian_unchecked(p, r.x, false, bend);
        if (r.iterations == 0)
            ldlt.analyzePattern(H); // the pattern is the cloth's (every spring and element), whatever x is
        ldlt.factorize(H);
        if (!(ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() > 0.0)) {
            ++r.projected_iterations;
            H = hessian_unchecked(p, r.x, true, bend);
            ldlt.factorize(H);
        }
        bool solved = false;
        if (ldlt.info() == Eigen::Success) {
            step = ldlt.solve(-g);
            solved = ldlt.info() == Eigen::Success && step.allFinite();
        }
        if (!solved) {
            ++r.cg_fallbacks;
            Eigen::ConjugateGradient<Eigen::SparseMatrix<double>, Eigen::Lower | Eigen::Upper> cg;
            cg.setTolerance(1e-12);
            cg.setMaxIterations(std::max(100, 10 * dim));
            cg.compute(H);
            step = cg.solve(-g);
        }
        double slope = g.dot(step);
        if (!step.allFinite() || !(slope < 0.0)) { // no descent direction: steepest descent
            step = -g;
            slope = -g.squaredNorm();
        }
        // Backtracking (Armijo). G is a sum of terms of total magnitude `magnitude`; a decrease below its rounding
        // (~1e3 eps x magnitude) cannot be seen, and there a step is accepted when it reduces |grad G| instead.
        const double rounding = 1e3 * DBL_EPSILON * magnitude;
        double alpha = 1.0, Gt = 0.0, mt = 0.0;
        bool accepted = false;
        for (int halving = 0; halving < 60 && !accepted; ++halving, alpha *= 0.5) {
            for (int k = 0; k < dim; ++k) xt[std::size_t(k)] = r.x[std::size_t(k)] + alpha * step[k];
            Gt = objective_and_magnitude(p, xt, mt);
            if (-alpha * slope <= rounding) { // G cannot see the decrease (Armijo would pass or fail on noise)
                gradient_unchecked(p, xt, {gt.data(), 3 * n});
                if (std::isfinite(Gt) && norm_unchecked(p, {gt.data(), 3 * n}) < gnorm) accepted = true;
                else break; // below the rounding floor and no better: nothing left to gain
            } else if (std::isfinite(Gt) && Gt <= G + 1e-4 * alpha * slope) {
                accepted = true;
            }
            if (accepted) break;
        }
        if (!accepted) break;
        r.x.swap(xt);
        G = Gt;
        magnitude = mt;
        gradient_unchecked(p, r.x, {g.data(), 3 * n});
        gnorm = norm_unchecked(p, {g.data(), 3 * n});
        ++r.iterations;
        r.objective_history.push_back(G);
        r.gradient_history.push_back(gnorm);
    }
    r.objective = G;
    r.gradient_norm = gnorm;
    r.converged = gnorm <= tolerance;
    return r;
}

} // namespace drape
