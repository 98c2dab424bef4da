// The exact reference for one implicit step (implicit_reference.hpp, docs/implicit.md): G's gradient and projected
// Hessian against finite differences (springs model and fabric model with bending, damping on), the projection keeps
// a compressed cloth's Hessian positive semi-definite, projected Newton converges in a handful of iterations with G
// falling every iteration, and repeated large steps from rest find a static equilibrium (force balance).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "drape/errors.hpp"
#include "drape/implicit_reference.hpp"
#include "drape/scene_hang.hpp"
#include "implicit_hessian.hpp"

using namespace drape;

namespace {

constexpr float gravity = -9.81f;

HangParams springs_params(std::uint32_t n) {
    HangParams hp;
    hp.n = n;
    hp.model = MaterialModel::springs;
    hp.damping_ratio = 0.2f;
    return hp;
}

HangParams fabric_params(std::uint32_t n) {
    HangParams hp;
    hp.n = n;
    hp.model = MaterialModel::fabric;
    hp.fabric.density = 0.2f;
    hp.fabric.stretch_u = 6000.0f;
    hp.fabric.stretch_v = 2500.0f;
    hp.fabric.shear = 80.0f;
    hp.fabric.bend_u = 8e-6f;
    hp.fabric.bend_v = 3e-6f;
    hp.fabric.damping = 2e-3f;
    return hp;
}

/// A cloth and one step's state; problem() points into it (do not move a StepData after calling it).
struct StepData {
    SceneBuild scene;
    std::vector<float> x, y, z, vx, vy, vz, ax, ay, az, fx, fy, fz;

    explicit StepData(const HangParams& hp) : scene(build_hang_scene(hp)) {
        const std::size_t n = scene.cloth.particle_count;
        x = scene.initial.x, y = scene.initial.y, z = scene.initial.z;
        vx.assign(n, 0.0f), vy.assign(n, 0.0f), vz.assign(n, 0.0f);
        ax.assign(n, 0.0f), ay.assign(n, gravity), az.assign(n, 0.0f);
    }
    std::size_t count() const { return scene.cloth.particle_count; }
    bool fixed(std::size_t i) const { return !(scene.cloth.inv_mass[i] > 0.0f); }
    ImplicitProblem problem(double h, double air_drag) const {
        ImplicitProblem p;
        p.cloth = &scene.cloth;
        p.h = h;
        p.air_drag = air_drag;
        p.x0 = x, p.y0 = y, p.z0 = z;
        p.vx = vx, p.vy = vy, p.vz = vz;
        p.ax = ax, p.ay = ay, p.az = az;
        p.fx = fx, p.fy = fy, p.fz = fz;
        return p;
    }
    /// Positions at the step start, interleaved, in double.
    std::vector<double> start() const {
        std::vector<double> s(3 * count());
        for (std::size_t i = 0; i < count(); ++i) s[3 * i] = x[i], s[3 * i + 1] = y[i], s[3 * i + 2] = z[i];
        return s;
    }
    /// Ends a step at `next` (interleaved): v = (next - x) / h, x = next (rounded to float, like the simulation's).
    void advance(const std::vector<double>& next, double h) {
        for (std::size_t i = 0; i < count(); ++i) {
            vx[i] = float((next[3 * i] - x[i]) / h), vy[i] = float((next[3 * i + 1] - y[i]) / h),
            vz[i] = float((next[3 * i + 2] - z[i]) / h);
            x[i] = float(next[3 * i]), y[i] = float(next[3 * i + 1]), z[i] = float(next[3 * i + 2]);
        }
    }
};

/// A state for the finite-difference checks: x^n the flat grid jittered, random v^n and constant forces, and the
/// evaluation point x the grid stretched by 10 % with a small jitter, so that every spring is longer than its rest
/// length (there the projected Hessian is the exact one); the test checks that it is.
std::vector<double> stretched_state(StepData& s, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const std::size_t n = s.count();
    const float spacing = 1.0f / float(s.scene.cloth.grid->columns - 1);
    s.fx.resize(n), s.fy.resize(n), s.fz.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        s.x[i] += 0.05f * spacing * u(rng), s.y[i] += 0.05f * spacing * u(rng), s.z[i] += 0.05f * spacing * u(rng);
        s.vx[i] = 0.3f * u(rng), s.vy[i] = 0.3f * u(rng), s.vz[i] = 0.3f * u(rng);
        s.fx[i] = 1e-3f * u(rng), s.fy[i] = 1e-3f * u(rng), s.fz[i] = 1e-3f * u(rng);
    }
    std::vector<double> x(3 * n);
    for (std::size_t i = 0; i < n; ++i) {
        x[3 * i] = 1.1 * s.scene.initial.x[i] + 0.02 * spacing * u(rng);
        x[3 * i + 1] = 0.05 * spacing * u(rng);
        x[3 * i + 2] = 1.1 * s.scene.initial.z[i] + 0.02 * spacing * u(rng);
    }
    for (std::size_t i = 0; i < n; ++i) // fixed particles are held at x (their x^n: a grab moved them there)
        if (s.fixed(i)) {
            s.x[i] = float(x[3 * i]), s.y[i] = float(x[3 * i + 1]), s.z[i] = float(x[3 * i + 2]);
            x[3 * i] = s.x[i], x[3 * i + 1] = s.y[i], x[3 * i + 2] = s.z[i];
        }
    for (const Edge& e : s.scene.cloth.edges) {
        const double dx = x[3 * e.b] - x[3 * e.a], dy = x[3 * e.b + 1] - x[3 * e.a + 1],
                     dz = x[3 * e.b + 2] - x[3 * e.a + 2];
        EXPECT_GT(std::sqrt(dx * dx + dy * dy + dz * dz), 1.01 * e.rest) << "spring " << e.a << "-" << e.b;
    }
    return x;
}

struct Model {
    const char* name;
    HangParams params;
};
std::vector<Model> models(std::uint32_t n) { return {{"springs", springs_params(n)}, {"fabric", fabric_params(n)}}; }

/// For the derivative checks also a fabric whose bending and Rayleigh damping are as large as the membrane's forces
/// (on the others they are below the checks' resolution, 1e-6 of the largest entry).
std::vector<Model> derivative_models(std::uint32_t n) {
    std::vector<Model> m = models(n);
    HangParams stiff = fabric_params(n);
    stiff.fabric.stretch_u = 200.0f, stiff.fabric.stretch_v = 150.0f, stiff.fabric.shear = 20.0f;
    stiff.fabric.bend_u = 4e-3f, stiff.fabric.bend_v = 2e-3f, stiff.fabric.damping = 0.05f;
    m.push_back({"fabric, stiff bending", stiff});
    return m;
}

TEST(ImplicitReference, GradientMatchesCentralDifferencesOfTheObjective) {
    for (const Model& m : derivative_models(6)) {
        SCOPED_TRACE(m.name);
        StepData s(m.params);
        std::vector<double> x = stretched_state(s, 3);
        const ImplicitProblem p = s.problem(1.0 / 30.0, 0.3);
        if (m.params.model == MaterialModel::fabric) { // bending and its damping are on
            ASSERT_FALSE(s.scene.cloth.bending.empty());
            ASSERT_GT(s.scene.cloth.bending.damping, 0.0f);
        }
        ASSERT_GT(s.scene.cloth.material[std::size_t(SpringKind::structural)].damping, 0.0f);
        std::vector<double> g(x.size());
        implicit_gradient(p, x, g);
        const double e = 1e-6; // m
        double worst = 0.0, scale = 0.0;
        for (std::size_t k = 0; k < x.size(); ++k) {
            if (s.fixed(k / 3)) {
                EXPECT_EQ(g[k], 0.0) << "fixed particle " << k / 3;
                continue;
            }
            const double keep = x[k];
            x[k] = keep + e;
            const double plus = implicit_objective(p, x);
            x[k] = keep - e;
            const double minus = implicit_objective(p, x);
            x[k] = keep;
            worst = std::max(worst, std::fabs((plus - minus) / (2.0 * e) - g[k]));
            scale = std::max(scale, std::fabs(g[k]));
        }
        ASSERT_GT(scale, 0.1); // N: the stretched springs pull
        EXPECT_LE(worst, 1e-6 * scale) << "largest |g| " << scale;
    }
}

TEST(ImplicitReference, HessianMatchesFiniteDifferencesOfTheGradient) {
    for (const Model& m : derivative_models(5)) {
        SCOPED_TRACE(m.name);
        StepData s(m.params);
        std::vector<double> x = stretched_state(s, 8);
        const ImplicitProblem p = s.problem(1.0 / 60.0, 0.2);
        const Eigen::MatrixXd H(implicit_hessian(p, x));
        const std::size_t dim = x.size();
        ASSERT_EQ(std::size_t(H.rows()), dim);
        EXPECT_LE((H - H.transpose()).cwiseAbs().maxCoeff(), 1e-12 * H.cwiseAbs().maxCoeff());
        const double e = 1e-6;
        std::vector<double> gp(dim), gm(dim);
        double worst = 0.0;
        for (std::size_t c = 0; c < dim; ++c) {
            if (s.fixed(c / 3)) { // identity row and column
                for (std::size_t r = 0; r < dim; ++r) {
                    EXPECT_EQ(H(Eigen::Index(r), Eigen::Index(c)), r == c ? 1.0 : 0.0);
                    EXPECT_EQ(H(Eigen::Index(c), Eigen::Index(r)), r == c ? 1.0 : 0.0);
                }
                continue;
            }
            const double keep = x[c];
            x[c] = keep + e;
            implicit_gradient(p, x, gp);
            x[c] = keep - e;
            implicit_gradient(p, x, gm);
            x[c] = keep;
            for (std::size_t r = 0; r < dim; ++r)
                if (!s.fixed(r / 3))
                    worst = std::max(worst, std::fabs((gp[r] - gm[r]) / (2.0 * e) - H(Eigen::Index(r), Eigen::Index(c))));
        }
        const double scale = H.cwiseAbs().maxCoeff();
        EXPECT_LE(worst, 1e-6 * scale) << "largest |H_ij| " << scale;
    }
}

TEST(ImplicitReference, ProjectedHessianOfACompressedClothIsPositiveSemiDefinite) {
    for (const Model& m : models(5)) {
        SCOPED_TRACE(m.name);
        StepData s(m.params);
        std::vector<double> x = s.start();
        std::mt19937 rng(4);
        std::uniform_real_distribution<double> u(-1.0, 1.0);
        for (std::size_t i = 0; i < s.count(); ++i) // squeezed to 80 %, crumpled out of plane
            if (!s.fixed(i)) x[3 * i] *= 0.8, x[3 * i + 1] = 0.03 * u(rng), x[3 * i + 2] *= 0.8;
        const double h = 1.0 / 30.0;
        const ImplicitProblem p = s.problem(h, 0.0);
        Eigen::MatrixXd H(implicit_hessian(p, x));
        for (std::size_t i = 0; i < s.count(); ++i) // take away the inertia: the elastic part alone
            for (int a = 0; a < 3; ++a)
                H(Eigen::Index(3 * i + a), Eigen::Index(3 * i + a)) -=
                    s.fixed(i) ? 1.0 : 1.0 / (double(s.scene.cloth.inv_mass[i]) * h * h);
        const Eigen::VectorXd eig = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H).eigenvalues();
        EXPECT_GE(eig.minCoeff(), -1e-9 * eig.maxCoeff()) << "largest " << eig.maxCoeff();
    }
}

double weight_norm(const StepData& s) {
    double w = 0.0;
    for (std::size_t i = 0; i < s.count(); ++i)
        if (!s.fixed(i)) w += std::pow(double(gravity) / s.scene.cloth.inv_mass[i], 2);
    return std::sqrt(w);
}

TEST(ImplicitReference, NewtonConvergesInAHandfulOfIterationsAndGFallsEveryIteration) {
    for (const Model& m : models(16)) {
        SCOPED_TRACE(m.name);
        StepData s(m.params);
        const double h = 1.0 / 30.0, tolerance = 1e-9 * weight_norm(s);
        for (int step = 0; step < 3; ++step) {
            const ImplicitProblem p = s.problem(h, 0.2);
            const NewtonResult r = newton_reference(p, {}, tolerance, 20);
            EXPECT_TRUE(r.converged) << "step " << step << ": |g| " << r.gradient_norm << " N after " << r.iterations;
            EXPECT_LE(r.iterations, 10) << "step " << step;
            EXPECT_EQ(r.cg_fallbacks, 0);
            ASSERT_EQ(r.objective_history.size(), std::size_t(r.iterations) + 1);
            for (int k = 1; k <= r.iterations; ++k) // G falls (down to its rounding, ~1e-13 of its terms)
                EXPECT_LE(r.objective_history[k], r.objective_history[k - 1] + 1e-12 * std::fabs(r.objective_history[0]))
                    << "step " << step << " iteration " << k;
            std::vector<double> g(r.x.size());
            implicit_gradient(p, r.x, g);
            EXPECT_NEAR(movable_norm(p, g), r.gradient_norm, 1e-12 * weight_norm(s));
            std::printf("[ %s ] step %d: %d iterations (%d projected), |g| %.3g -> %.3g N (weight %.3g N)\n", m.name,
                        step, r.iterations, r.projected_iterations, r.gradient_history.front(), r.gradient_norm,
                        weight_norm(s));
            s.advance(r.x, h);
        }
        EXPECT_LT(*std::min_element(s.y.begin(), s.y.end()), -0.01f); // it fell
    }
}

TEST(ImplicitReference, LargeStepsFromRestReachAStaticEquilibrium) {
    for (const Model& m : models(10)) {
        SCOPED_TRACE(m.name);
        StepData s(m.params);
        // A long step: what is left of the inertia and damping terms at the last step, (m/h^2 + kd/h)(x - x^n), with
        // x - x^n at the float rounding of the stored state (~4e-8 m), is small against the weight.
        const double h = 10.0, tolerance = 1e-10 * weight_norm(s);
        NewtonResult r;
        double moved = 1.0;
        int steps = 0, newton_iterations = 0;
        for (; steps < 20 && moved > 1e-7; ++steps) { // quasi-static: every step starts at rest
            std::fill(s.vx.begin(), s.vx.end(), 0.0f), std::fill(s.vy.begin(), s.vy.end(), 0.0f),
                std::fill(s.vz.begin(), s.vz.end(), 0.0f);
            const std::vector<double> x0 = s.start();
            r = newton_reference(s.problem(h, 0.0), x0, tolerance, 100);
            ASSERT_TRUE(r.converged) << "step " << steps << ": |g| " << r.gradient_norm;
            newton_iterations += r.iterations;
            moved = 0.0;
            for (std::size_t k = 0; k < x0.size(); ++k) moved = std::max(moved, std::fabs(r.x[k] - x0[k]));
            s.advance(r.x, h);
        }
        EXPECT_LE(moved, 1e-7) << steps << " steps";
        // The static residual at the last solution: the elastic force (G's gradient with no acceleration, x^n at the
        // solution and h so long that inertia and damping vanish) against the weight, per movable particle.
        StepData rest(m.params);
        rest.x = s.x, rest.y = s.y, rest.z = s.z;
        std::fill(rest.ay.begin(), rest.ay.end(), 0.0f);
        std::vector<double> g(r.x.size());
        implicit_gradient(rest.problem(1e6, 0.0), r.x, g);
        double worst = 0.0;
        for (std::size_t i = 0; i < s.count(); ++i) {
            if (s.fixed(i)) continue;
            const double weight = double(gravity) / s.scene.cloth.inv_mass[i];
            worst = std::max(worst, std::hypot(g[3 * i], g[3 * i + 1] - weight, g[3 * i + 2]) / std::fabs(weight));
        }
        std::printf("[ %s ] %d steps of %.0f s (%d Newton iterations), last moved %.3g m, worst |f_elastic + m g| / m g "
                    "= %.3g, lowest y %.3f m\n",
                    m.name, steps, h, newton_iterations, moved, worst, *std::min_element(s.y.begin(), s.y.end()));
        EXPECT_LE(worst, 1e-5);
        EXPECT_LT(*std::min_element(s.y.begin(), s.y.end()), -0.5f); // it hangs
    }
}

TEST(ImplicitReference, BadInputIsOneClearError) {
    StepData s(springs_params(4));
    const std::vector<double> x = s.start();
    auto message = [&](ImplicitProblem p, std::span<const double> at) {
        try {
            implicit_objective(p, at);
        } catch (const InvalidInput& e) {
            return std::string(e.what());
        }
        return std::string("(accepted)");
    };
    ImplicitProblem p = s.problem(0.0, 0.0);
    EXPECT_NE(message(p, x).find("h = 0 s (must be finite and > 0)"), std::string::npos) << message(p, x);
    p.h = 0.01, p.air_drag = -1.0;
    EXPECT_NE(message(p, x).find("air_drag"), std::string::npos);
    p.air_drag = 0.0, p.vy = p.vy.first(3);
    EXPECT_NE(message(p, x).find("vy has 3 entries (must be the particle count, 16)"), std::string::npos) << message(p, x);
    p = s.problem(0.01, 0.0);
    EXPECT_NE(message(p, std::span<const double>(x).first(5)).find("x has 5 entries"), std::string::npos);
    std::vector<double> bad = x;
    bad[7] = std::nan("");
    EXPECT_NE(message(p, bad).find("x[7] = nan is not finite"), std::string::npos) << message(p, bad);
    s.fx.assign(16, 0.0f); // fx without fy, fz
    EXPECT_NE(message(s.problem(0.01, 0.0), x).find("fx, fy, fz"), std::string::npos);
    s.fx.clear();
    EXPECT_EQ(message(s.problem(0.01, 0.0), x), "(accepted)");
    EXPECT_THROW(newton_reference(s.problem(0.01, 0.0), {}, -1.0, 10), InvalidInput);
    EXPECT_THROW(newton_reference(s.problem(0.01, 0.0), {}, 1e-6, -1), InvalidInput);
    EXPECT_THROW(newton_reference(s.problem(0.01, 0.0), std::span<const double>(x).first(3), 1e-6, 10), InvalidInput);
}

} // namespace
