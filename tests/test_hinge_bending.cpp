// Hinge bending elements on triangle meshes (Bergou et al. 2006): zero on the flat rest mesh and under rigid
// motions, the cylinder energy B / (2 R^2) x area converging with spacing (grid-triangulated panels and
// Delaunay discs), the orthotropic rigidity by bending direction, and the energy's gradient and Hessian
// against finite differences.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "drape/bending.hpp"
#include "drape/errors.hpp"
#include "drape/outline_panel.hpp"

namespace drape {
namespace {

struct Mesh {
    std::vector<float> x, y, z;
    std::vector<std::uint32_t> tri;
    double area() const {
        double a = 0.0;
        for (std::size_t t = 0; t < tri.size(); t += 3) {
            const std::uint32_t i = tri[t], j = tri[t + 1], k = tri[t + 2];
            const double ux = x[j] - x[i], uy = y[j] - y[i], uz = z[j] - z[i];
            const double vx = x[k] - x[i], vy = y[k] - y[i], vz = z[k] - z[i];
            const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
            a += 0.5 * std::sqrt(cx * cx + cy * cy + cz * cz);
        }
        return a;
    }
};

/// A w x h panel in the x-y plane at spacing s, each cell split along its (r, c+1)-(r+1, c) diagonal (as mask
/// panels).
Mesh grid_panel(double w, double h, double s) {
    const auto nx = static_cast<std::uint32_t>(std::lround(w / s)) + 1,
               ny = static_cast<std::uint32_t>(std::lround(h / s)) + 1;
    Mesh m;
    for (std::uint32_t r = 0; r < ny; ++r)
        for (std::uint32_t c = 0; c < nx; ++c) {
            m.x.push_back(float(c * s - 0.5 * w));
            m.y.push_back(float(r * s - 0.5 * h));
            m.z.push_back(0.0f);
        }
    for (std::uint32_t r = 0; r + 1 < ny; ++r)
        for (std::uint32_t c = 0; c + 1 < nx; ++c) {
            const std::uint32_t a = r * nx + c, b = a + 1, d = a + nx, e = d + 1;
            m.tri.insert(m.tri.end(), {a, b, d, b, e, d});
        }
    return m;
}

/// A w x h panel of equilateral triangles of side s (rows s sqrt(3) / 2 apart, every other row shifted by s /
/// 2).
Mesh equilateral_panel(double w, double h, double s) {
    const double dy = s * std::sqrt(3.0) / 2.0;
    const auto nx = static_cast<std::uint32_t>(std::lround(w / s)) + 1,
               ny = static_cast<std::uint32_t>(std::lround(h / dy)) + 1;
    Mesh m;
    for (std::uint32_t r = 0; r < ny; ++r)
        for (std::uint32_t c = 0; c < nx; ++c) {
            m.x.push_back(float(c * s + (r % 2 ? 0.5 * s : 0.0) - 0.5 * w));
            m.y.push_back(float(r * dy - 0.5 * h));
            m.z.push_back(0.0f);
        }
    for (std::uint32_t r = 0; r + 1 < ny; ++r)
        for (std::uint32_t c = 0; c + 1 < nx; ++c) {
            const std::uint32_t a = r * nx + c, b = a + 1, d = a + nx, e = d + 1;
            if (r % 2 == 0)
                m.tri.insert(m.tri.end(), {a, b, d, b, e, d});
            else
                m.tri.insert(m.tri.end(), {a, e, d, a, b, e});
        }
    return m;
}

/// A disc of radius r cut from an outline (add_outline_panel: a filled grid plus outline samples, Delaunay).
Mesh delaunay_disc(double r, double s) {
    OutlinePanel p;
    const int n = static_cast<int>(std::ceil(2 * std::numbers::pi * r / s));
    for (int k = 0; k < n; ++k) {
        const double a = 2 * std::numbers::pi * k / n;
        p.outline.push_back({r * std::cos(a), r * std::sin(a)});
    }
    GarmentAssembly g;
    OutlinePanelParams op;
    op.spacing = s;
    add_outline_panel(g, p, op);
    return {g.x, g.y, g.z, g.triangles};
}

/// E = 1/2 sum w |sum c x|^2, in double, straight from the elements.
double energy(const std::vector<BendElement>& el, const Mesh& m) {
    double e = 0.0;
    for (const BendElement& b : el) {
        double q[3] = {0, 0, 0};
        for (int k = 0; k < 4; ++k) {
            q[0] += double(b.c[k]) * m.x[b.v[k]];
            q[1] += double(b.c[k]) * m.y[b.v[k]];
            q[2] += double(b.c[k]) * m.z[b.v[k]];
        }
        e += 0.5 * b.weight * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    }
    return e;
}

/// Wraps the flat mesh (z = 0) onto a cylinder of radius R whose axis is along y (axis_y) or x, tangent at z
/// = 0.
Mesh wrap(const Mesh& flat, double R, bool axis_y) {
    Mesh m = flat;
    for (std::size_t i = 0; i < m.x.size(); ++i) {
        const double s = axis_y ? flat.x[i] : flat.y[i];
        const double a = s / R;
        (axis_y ? m.x[i] : m.y[i]) = float(R * std::sin(a));
        m.z[i] = float(R * (1.0 - std::cos(a)));
    }
    return m;
}

constexpr std::array<float, 3> ux{1.0f, 0.0f, 0.0f};

TEST(HingeBending, OneElementPerInteriorEdge) {
    const Mesh m = grid_panel(0.1, 0.06, 0.01); // 11 x 7 points, 60 cells
    const std::size_t nx = 11, ny = 7;
    const std::size_t edges = ny * (nx - 1) + nx * (ny - 1) + (nx - 1) * (ny - 1);
    const std::size_t boundary = 2 * (nx - 1) + 2 * (ny - 1);
    EXPECT_EQ(hinge_bending_elements(m.x, m.y, m.z, m.tri, 1e-6f, 1e-6f, ux).size(), edges - boundary);
    // A non-manifold edge (a third triangle on an interior edge) gets none: the fan edge 0-12 of the first
    // cell.
    Mesh n = m;
    n.x.push_back(0.0f), n.y.push_back(0.0f), n.z.push_back(0.05f);
    const std::uint32_t top = static_cast<std::uint32_t>(n.x.size() - 1);
    n.tri.insert(n.tri.end(), {1, 11, top}); // edge 1-11 is the first cell's diagonal (interior)
    EXPECT_EQ(hinge_bending_elements(n.x, n.y, n.z, n.tri, 1e-6f, 1e-6f, ux).size(), edges - boundary - 1);
}

TEST(HingeBending, ZeroOnTheFlatMeshAndUnderRigidMotions) {
    const Mesh m = delaunay_disc(0.1, 0.01);
    const float B = 5e-6f;
    const auto el = hinge_bending_elements(m.x, m.y, m.z, m.tri, B, B, ux);
    ASSERT_GT(el.size(), 500u);
    const double bent = energy(el, wrap(m, 0.1, true));
    ASSERT_GT(bent, 0.0);
    EXPECT_LT(energy(el, m), 1e-9 * bent);
    // A rotation about an oblique axis and a translation of about 1 m.
    const double c = std::cos(0.7), s = std::sin(0.7);
    Mesh r = m;
    for (std::size_t i = 0; i < m.x.size(); ++i) {
        const double x = m.x[i], y = m.y[i], z = m.z[i];
        const double x1 = c * x - s * y, y1 = s * x + c * y;   // about z
        const double y2 = c * y1 - s * z, z2 = s * y1 + c * z; // about x
        r.x[i] = float(x1 + 0.6), r.y[i] = float(y2 - 0.8), r.z[i] = float(z2 + 0.3);
    }
    EXPECT_LT(energy(el, r), 1e-6 * bent);
}

/// Relative error of the cylinder energy against B / (2 R^2) x area.
double cylinder_error(const Mesh& m, float B, double R) {
    const auto el = hinge_bending_elements(m.x, m.y, m.z, m.tri, B, B, ux);
    const double exact = B / (2.0 * R * R) * m.area();
    return energy(el, wrap(m, R, true)) / exact - 1.0;
}

TEST(HingeBending, CylinderEnergyConvergesOnAGridPanel) {
    const float B = 5e-6f;
    const double R = 0.15;
    double previous = 1.0;
    for (double s : {0.02, 0.01, 0.005}) {
        const double err = cylinder_error(grid_panel(0.2, 0.2, s), B, R);
        EXPECT_LT(std::fabs(err), 0.12)
            << "spacing " << s; // the boundary edges have no hinge: O(h / size) low
        EXPECT_LT(std::fabs(err), std::fabs(previous))
            << "spacing " << s << ": the error must fall with spacing";
        previous = err;
        std::printf("grid panel 0.2 m, h = %.3f m: E / (B A / 2 R^2) - 1 = %+.4f\n", s, err);
    }
    EXPECT_LT(std::fabs(previous), 0.03);
}

TEST(HingeBending, CylinderEnergyConvergesOnADelaunayDisc) {
    const float B = 5e-6f;
    const double R = 0.15;
    double previous = 1.0;
    for (double s : {0.02, 0.01, 0.005}) {
        const double err = cylinder_error(delaunay_disc(0.1, s), B, R);
        EXPECT_LT(std::fabs(err), 0.06) << "spacing " << s;
        EXPECT_LT(std::fabs(err), std::fabs(previous)) << "spacing " << s;
        previous = err;
        std::printf("Delaunay disc r = 0.1 m, h = %.3f m: E / (B A / 2 R^2) - 1 = %+.4f\n", s, err);
    }
    EXPECT_LT(std::fabs(previous), 0.03);
}

TEST(HingeBending, CylinderEnergyConvergesOnAnEquilateralMesh) {
    const float B = 5e-6f;
    const double R = 0.15;
    double previous = 1.0;
    for (double s : {0.02, 0.01, 0.005}) {
        const double err = cylinder_error(equilateral_panel(0.2, 0.2, s), B, R);
        EXPECT_LT(std::fabs(err), 0.08) << "spacing " << s;
        EXPECT_LT(std::fabs(err), std::fabs(previous)) << "spacing " << s;
        previous = err;
        std::printf("equilateral panel 0.2 m, h = %.3f m: E / (B A / 2 R^2) - 1 = %+.4f\n", s, err);
    }
    EXPECT_LT(std::fabs(previous), 0.03);
}

TEST(HingeBending, OrthotropicRigidityFollowsTheBendingDirection) {
    // Bending along u (cylinder axis along v) costs bend_u, along v costs bend_v.
    const Mesh m = grid_panel(0.2, 0.2, 0.005);
    const float bu = 8e-6f, bv = 2e-6f;
    const auto el = hinge_bending_elements(m.x, m.y, m.z, m.tri, bu, bv, ux);
    const double R = 0.15, area = m.area();
    const double along_u = energy(el, wrap(m, R, true)) / (bu / (2 * R * R) * area);
    const double along_v = energy(el, wrap(m, R, false)) / (bv / (2 * R * R) * area);
    std::printf("bend_u = 4 bend_v: along u E / (B_u A / 2R^2) = %.4f, along v E / (B_v A / 2R^2) = %.4f\n",
                along_u, along_v);
    EXPECT_NEAR(along_u, 1.0, 0.05);
    EXPECT_NEAR(along_v, 1.0, 0.05);
}

TEST(HingeBending, GradientAndHessianMatchFiniteDifferences) {
    const Mesh flat = delaunay_disc(0.05, 0.01);
    const auto el = hinge_bending_elements(flat.x, flat.y, flat.z, flat.tri, 3e-6f, 7e-6f, ux);
    Mesh m = wrap(flat, 0.08, true);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> d(-0.002f, 0.002f);
    for (std::size_t i = 0; i < m.x.size(); ++i)
        m.x[i] += d(rng), m.y[i] += d(rng), m.z[i] += d(rng);
    // Analytic gradient: grad_i E = sum_e w_e c_ei q_e; Hessian block (i, j) = sum_e w_e c_ei c_ej I3.
    const std::size_t n = m.x.size();
    std::vector<double> g(3 * n, 0.0);
    for (const BendElement& b : el) {
        double q[3] = {0, 0, 0};
        for (int k = 0; k < 4; ++k)
            q[0] += b.c[k] * double(m.x[b.v[k]]), q[1] += b.c[k] * double(m.y[b.v[k]]),
                q[2] += b.c[k] * double(m.z[b.v[k]]);
        for (int k = 0; k < 4; ++k)
            for (int a = 0; a < 3; ++a)
                g[3 * b.v[k] + a] += double(b.weight) * b.c[k] * q[a];
    }
    // Energy and gradient in double at perturbed double positions (the float mesh would round the step away).
    std::vector<double> X(3 * n);
    for (std::size_t i = 0; i < n; ++i)
        X[3 * i] = m.x[i], X[3 * i + 1] = m.y[i], X[3 * i + 2] = m.z[i];
    const auto E = [&](const std::vector<double>& p) {
        double e = 0.0;
        for (const BendElement& b : el) {
            double q[3] = {0, 0, 0};
            for (int k = 0; k < 4; ++k)
                for (int a = 0; a < 3; ++a)
                    q[a] += b.c[k] * p[3 * b.v[k] + a];
            e += 0.5 * b.weight * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        }
        return e;
    };
    const auto grad = [&](const std::vector<double>& p, std::size_t i) {
        double gi = 0.0;
        for (const BendElement& b : el)
            for (int k = 0; k < 4; ++k)
                if (3 * b.v[k] + 0 <= i && i < 3 * b.v[k] + 3) {
                    const int a = int(i - 3 * b.v[k]);
                    double q = 0.0;
                    for (int j = 0; j < 4; ++j)
                        q += b.c[j] * p[3 * b.v[j] + a];
                    gi += b.weight * b.c[k] * q;
                }
        return gi;
    };
    double gmax = 0.0;
    for (double v : g)
        gmax = std::max(gmax, std::fabs(v));
    ASSERT_GT(gmax, 0.0);
    const double h = 1e-5;
    for (std::size_t i = 0; i < 3 * n; i += 7) {
        std::vector<double> p = X, q = X;
        p[i] += h, q[i] -= h;
        EXPECT_NEAR((E(p) - E(q)) / (2 * h), g[i], 1e-6 * gmax) << "coordinate " << i;
        // Hessian column i by differences of the gradient, against the constant Q.
        for (std::size_t j : {i, (i + 3) % (3 * n), (i + 1) % (3 * n)}) {
            const double fd = (grad(p, j) - grad(q, j)) / (2 * h);
            double exact = 0.0;
            if (j % 3 == i % 3)
                for (const BendElement& b : el)
                    for (int k = 0; k < 4; ++k)
                        for (int l = 0; l < 4; ++l)
                            if (3 * b.v[k] + j % 3 == j && 3 * b.v[l] + i % 3 == i)
                                exact += b.weight * b.c[k] * b.c[l];
            EXPECT_NEAR(fd, exact, 1e-6 * std::max(1.0, std::fabs(exact))) << i << ", " << j;
        }
    }
}

TEST(HingeBending, CurvedRestMeshesAreMeasured) {
    const Mesh m = grid_panel(0.1, 0.1, 0.01);
    EXPECT_LT(hinge_rest_angle_max(m.x, m.y, m.z, m.tri), 1e-6);
    const Mesh c = wrap(m, 0.05, true);
    // Neighbouring normals on a cylinder of radius R at spacing h differ by about h / R (0.2 rad).
    const double worst = hinge_rest_angle_max(c.x, c.y, c.z, c.tri);
    EXPECT_GT(worst, 0.1);
    EXPECT_LT(worst, 0.3);
}

TEST(HingeBending, BadInputIsRefused) {
    const Mesh m = grid_panel(0.02, 0.02, 0.01);
    EXPECT_THROW(hinge_bending_elements(m.x, m.y, m.z, m.tri, -1.0f, 1e-6f, ux), InvalidInput);
    EXPECT_THROW(hinge_bending_elements(m.x, m.y, m.z, m.tri, 1e-6f, 1e-6f, {0.0f, 0.0f, 0.0f}),
                 InvalidInput);
    std::vector<std::uint32_t> bad = m.tri;
    bad[4] = 99;
    EXPECT_THROW(hinge_bending_elements(m.x, m.y, m.z, bad, 1e-6f, 1e-6f, ux), InvalidInput);
}

} // namespace
} // namespace drape
