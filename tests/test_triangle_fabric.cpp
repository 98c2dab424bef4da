// The fabric model on triangle meshes: the directional tensile stiffness, the membrane springs (a strip under
// a known tension stretches by T / E at three spacings, both weave directions; the shear stiffness the
// springs give), lumped masses, and the cooked cloth (per-spring materials, seams, no bend springs).
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include "drape/bending.hpp"
#include "drape/errors.hpp"
#include "drape/outline_panel.hpp"
#include "drape/pattern_seams.hpp"
#include "drape/scene.hpp"
#include "drape/simulation.hpp"
#include "drape/triangle_fabric.hpp"
#include "drape/workers.hpp"
#include "test_helpers.hpp"

namespace drape {
namespace {

Fabric test_fabric() {
    Fabric f;
    f.density = 0.2f;
    f.stretch_u = 5000.0f;
    f.stretch_v = 2000.0f;
    f.shear = 40.0f;
    f.bend_u = 8e-6f;
    f.bend_v = 4e-6f;
    f.damping = 0.002f;
    return f;
}

/// A w x h rectangle cut from an outline (add_outline_panel): filled u-v grid, outline samples, Delaunay.
GarmentAssembly rectangle(double w, double h, double spacing) {
    OutlinePanel p{{{0.0, 0.0}, {w, 0.0}, {w, h}, {0.0, h}}};
    GarmentAssembly a;
    OutlinePanelParams op;
    op.spacing = spacing;
    add_outline_panel(a, p, op); // default frame: u along +x, v along -y, in z = 0
    return a;
}

/// The unique edges of the triangles.
std::vector<Edge> triangle_edges(const GarmentAssembly& a) {
    std::vector<Edge> e;
    for (std::size_t t = 0; t < a.triangles.size(); t += 3)
        for (int s = 0; s < 3; ++s) {
            const std::uint32_t p = a.triangles[t + s], q = a.triangles[t + (s + 1) % 3];
            e.push_back({std::min(p, q), std::max(p, q), SpringKind::structural, 0.0f});
        }
    std::sort(e.begin(), e.end(),
              [](const Edge& l, const Edge& r) { return l.a != r.a ? l.a < r.a : l.b < r.b; });
    e.erase(std::unique(e.begin(), e.end(),
                        [](const Edge& l, const Edge& r) { return l.a == r.a && l.b == r.b; }),
            e.end());
    return e;
}

TEST(TriangleFabric, EdgeModulus) {
    const Fabric f = test_fabric();
    EXPECT_NEAR(edge_modulus(f, 1.0, WeaveAlignment::aligned), 5000.0, 1e-9);
    EXPECT_NEAR(edge_modulus(f, 0.0, WeaveAlignment::aligned), 2000.0, 1e-9);
    // 45 degrees: 1 / E = (1/Eu + 1/Ev + 1/G) / 4, close to 4 G for a fabric.
    EXPECT_NEAR(edge_modulus(f, 0.5, WeaveAlignment::aligned), 4.0 / (1 / 5000.0 + 1 / 2000.0 + 1 / 40.0),
                1e-9);
    EXPECT_NEAR(edge_modulus(f, 0.5, WeaveAlignment::unaligned), 3500.0, 1e-9);
    EXPECT_NEAR(edge_modulus(f, 0.25, WeaveAlignment::unaligned), 2750.0, 1e-9);
}

/// The unique-edge list of a mesh given as positions and triangles, as an assembly (for the generators
/// below).
GarmentAssembly mesh_assembly(std::vector<float> x, std::vector<float> y, std::vector<std::uint32_t> tri) {
    GarmentAssembly a;
    a.x = std::move(x);
    a.y = std::move(y);
    a.z.assign(a.x.size(), 0.0f);
    a.mass.assign(a.x.size(), 1.0f);
    a.triangles = std::move(tri);
    return a;
}

/// A w x h grid in the x-y plane (v along -y, as panels), every cell split along the same diagonal: the usual
/// OBJ export of a subdivided plane.
GarmentAssembly one_diagonal_grid(double w, double h, double s) {
    const auto nx = static_cast<std::uint32_t>(std::lround(w / s)) + 1,
               ny = static_cast<std::uint32_t>(std::lround(h / s)) + 1;
    std::vector<float> x, y;
    std::vector<std::uint32_t> tri;
    for (std::uint32_t r = 0; r < ny; ++r)
        for (std::uint32_t c = 0; c < nx; ++c)
            x.push_back(float(c * s)), y.push_back(-float(r * s));
    for (std::uint32_t r = 0; r + 1 < ny; ++r)
        for (std::uint32_t c = 0; c + 1 < nx; ++c) {
            const std::uint32_t a = r * nx + c, b = a + 1, d = a + nx, e = d + 1;
            tri.insert(tri.end(), {a, b, d, b, e, d});
        }
    return mesh_assembly(std::move(x), std::move(y), std::move(tri));
}

/// A w x h panel of (nearly) equilateral triangles of side about s, rows along u, fitted to the rectangle
/// exactly.
GarmentAssembly equilateral(double w, double h, double s) {
    const auto nx = static_cast<std::uint32_t>(std::lround(w / s)) + 1;
    const auto ny = static_cast<std::uint32_t>(std::lround(h / (s * std::sqrt(3.0) / 2.0))) + 1;
    const double sx = w / (nx - 1), sy = h / (ny - 1);
    std::vector<float> x, y;
    std::vector<std::uint32_t> tri;
    // Odd rows are shifted by half a cell, and get one more point so both ends stay on the rectangle's sides.
    std::vector<std::uint32_t> first(ny + 1, 0);
    for (std::uint32_t r = 0; r < ny; ++r) {
        first[r] = static_cast<std::uint32_t>(x.size());
        if (r % 2 == 0)
            for (std::uint32_t c = 0; c < nx; ++c)
                x.push_back(float(c * sx)), y.push_back(-float(r * sy));
        else {
            x.push_back(0.0f), y.push_back(-float(r * sy));
            for (std::uint32_t c = 0; c + 1 < nx; ++c)
                x.push_back(float((c + 0.5) * sx)), y.push_back(-float(r * sy));
            x.push_back(float(w)), y.push_back(-float(r * sy));
        }
    }
    first[ny] = static_cast<std::uint32_t>(x.size());
    for (std::uint32_t r = 0; r + 1 < ny;
         ++r) { // zip the two rows: always advance along the row whose next point is nearer
        std::uint32_t i = first[r], j = first[r + 1];
        const std::uint32_t ie = first[r + 1], je = first[r + 2];
        while (i + 1 < ie || j + 1 < je) {
            const bool step_i = j + 1 >= je || (i + 1 < ie && x[i + 1] <= x[j + 1]);
            if (step_i)
                tri.insert(tri.end(), {i, i + 1, j}), ++i;
            else
                tri.insert(tri.end(), {i, j + 1, j}), ++j;
        }
    }
    return mesh_assembly(std::move(x), std::move(y), std::move(tri));
}

/// Static linear solve: a strip of length L along u (along_u) or v, one end clamped, tension T (N/m) on the
/// other end spread over its nodes by their share of the end's length. Returns the strain (mean end
/// displacement / L). `make(w, h)` gives the strip's mesh (u along x, v along -y).
template <class Make>
double strip_strain(Make&& make, bool along_u, const Fabric& f, WeaveAlignment alignment, double T) {
    const double L = 0.3, W = 0.1;
    GarmentAssembly a = make(along_u ? L : W, along_u ? W : L);
    const std::vector<Edge> edges = triangle_edges(a);
    const std::vector<double> k =
        membrane_stiffness(a.x, a.y, a.z, a.triangles, edges, f, {1, 0, 0}, alignment);
    // Pull along the strip's axis: coordinate s (x for u; -y for v, the panel's v axis) and the cross
    // coordinate.
    const std::size_t n = a.particle_count();
    std::vector<double> s(n), c(n);
    for (std::size_t i = 0; i < n; ++i) {
        s[i] = along_u ? a.x[i] : -double(a.y[i]);
        c[i] = along_u ? -double(a.y[i]) : a.x[i];
    }
    const double s0 = *std::min_element(s.begin(), s.end()), s1 = *std::max_element(s.begin(), s.end());
    const double tol = 1e-6;
    // Unknowns: 2 per free node (s, c displacements); clamped nodes at s0 are dropped.
    std::vector<int> id(n, -1);
    int m = 0;
    for (std::size_t i = 0; i < n; ++i)
        if (s[i] > s0 + tol) id[i] = m++;
    std::vector<Eigen::Triplet<double>> trip;
    for (std::size_t e = 0; e < edges.size(); ++e) {
        const std::uint32_t p = edges[e].a, q = edges[e].b;
        double d[2] = {s[q] - s[p], c[q] - c[p]};
        const double l = std::hypot(d[0], d[1]);
        d[0] /= l, d[1] /= l;
        for (int r = 0; r < 2; ++r)
            for (int t = 0; t < 2; ++t) {
                const double v = k[e] * d[r] * d[t];
                if (id[p] >= 0) trip.emplace_back(2 * id[p] + r, 2 * id[p] + t, v);
                if (id[q] >= 0) trip.emplace_back(2 * id[q] + r, 2 * id[q] + t, v);
                if (id[p] >= 0 && id[q] >= 0) {
                    trip.emplace_back(2 * id[p] + r, 2 * id[q] + t, -v);
                    trip.emplace_back(2 * id[q] + r, 2 * id[p] + t, -v);
                }
            }
    }
    Eigen::SparseMatrix<double> K(2 * m, 2 * m);
    K.setFromTriplets(trip.begin(), trip.end());
    // The loaded end: its nodes sorted across the strip, each taking half of each neighbouring gap.
    std::vector<std::size_t> end;
    for (std::size_t i = 0; i < n; ++i)
        if (s[i] > s1 - tol) end.push_back(i);
    std::sort(end.begin(), end.end(), [&](std::size_t l, std::size_t r) { return c[l] < c[r]; });
    Eigen::VectorXd F = Eigen::VectorXd::Zero(2 * m);
    for (std::size_t j = 0; j < end.size(); ++j) {
        const double lo = j > 0 ? 0.5 * (c[end[j]] - c[end[j - 1]]) : 0.0;
        const double hi = j + 1 < end.size() ? 0.5 * (c[end[j + 1]] - c[end[j]]) : 0.0;
        F[2 * id[end[j]]] = T * (lo + hi);
    }
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(K);
    EXPECT_EQ(solver.info(), Eigen::Success);
    const Eigen::VectorXd u = solver.solve(F);
    double mean = 0.0;
    for (std::size_t i : end)
        mean += u[2 * id[i]];
    return mean / double(end.size()) / (s1 - s0);
}

TEST(TriangleFabric, StripUnderTensionStretchesByTOverE) {
    // Weave-aligned panels (outline panels: a u-v grid fill and outline samples, Delaunay), orthotropic
    // fabric.
    const double T = 10.0; // N/m
    const Fabric f = test_fabric();
    for (const bool along_u : {true, false})
        for (const double h : {0.02, 0.01, 0.005}) {
            const double E = along_u ? f.stretch_u : f.stretch_v;
            const double ratio = strip_strain([&](double w, double l) { return rectangle(w, l, h); }, along_u,
                                              f, WeaveAlignment::aligned, T) /
                                 (T / E);
            std::printf("outline strip (aligned), along %s, h = %.3f m: strain / (T/E) = %.4f\n",
                        along_u ? "u" : "v", h, ratio);
            EXPECT_NEAR(ratio, 1.0, 0.03) << (along_u ? "u" : "v") << ", h = " << h;
        }
}

TEST(TriangleFabric, UnalignedMeshesUnderTension) {
    // OBJ-like meshes (the unaligned rule) of an isotropic fabric: a one-diagonal grid and an equilateral
    // mesh.
    const double T = 10.0;
    Fabric f = test_fabric();
    f.stretch_v = f.stretch_u;
    for (const bool along_u : {true, false})
        for (const double h : {0.02, 0.01, 0.005}) {
            const double grid = strip_strain([&](double w, double l) { return one_diagonal_grid(w, l, h); },
                                             along_u, f, WeaveAlignment::unaligned, T) /
                                (T / f.stretch_u);
            const double tri = strip_strain([&](double w, double l) { return equilateral(w, l, h); }, along_u,
                                            f, WeaveAlignment::unaligned, T) /
                               (T / f.stretch_u);
            std::printf(
                "unaligned, along %s, h = %.3f m: strain / (T/E): one-diagonal grid %.4f, equilateral %.4f\n",
                along_u ? "u" : "v", h, grid, tri);
            EXPECT_NEAR(grid, 1.0, 0.03) << (along_u ? "u" : "v") << ", h = " << h;
            EXPECT_NEAR(tri, 1.0, 0.05) << (along_u ? "u" : "v") << ", h = " << h;
        }
}

/// The membrane's homogenised in-plane stiffness (Voigt: e_uu, e_vv, shear angle): every spring stretched by
/// an affine strain, linearised; energy = 1/2 A e^T C e.
Eigen::Matrix3d homogenised(const GarmentAssembly& a, WeaveAlignment alignment, double& area) {
    const std::vector<Edge> edges = triangle_edges(a);
    const Fabric f = test_fabric();
    const std::vector<double> k =
        membrane_stiffness(a.x, a.y, a.z, a.triangles, edges, f, {1, 0, 0}, alignment);
    area = 0.0;
    for (std::size_t t = 0; t < a.triangles.size(); t += 3) {
        const std::uint32_t i = a.triangles[t], j = a.triangles[t + 1], l = a.triangles[t + 2];
        area += 0.5 * std::fabs((double(a.x[j]) - a.x[i]) * (double(a.y[l]) - a.y[i]) -
                                (double(a.x[l]) - a.x[i]) * (double(a.y[j]) - a.y[i]));
    }
    // Energy of strain (euu, evv, gamma): panel u = x, v = -y.
    const auto energy = [&](const Eigen::Vector3d& e) {
        double sum = 0.0;
        for (std::size_t q = 0; q < edges.size(); ++q) {
            const double du = double(a.x[edges[q].b]) - a.x[edges[q].a],
                         dv = -(double(a.y[edges[q].b]) - a.y[edges[q].a]);
            const double l = std::hypot(du, dv);
            const double dl = (e[0] * du * du + e[1] * dv * dv + e[2] * du * dv) / l; // l d^T eps d
            sum += 0.5 * k[q] * dl * dl;
        }
        return sum;
    };
    Eigen::Matrix3d C;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const Eigen::Vector3d ei = Eigen::Vector3d::Unit(i), ej = Eigen::Vector3d::Unit(j);
            C(i, j) = (energy(ei + ej) - energy(ei) - energy(ej)) / area;
        }
    return C;
}

TEST(TriangleFabric, ShearStiffnessOfTheSprings) {
    // Weave-aligned panels: the diagonal springs carry Fabric::shear (Kilby's off-axis modulus); the tensile
    // stiffnesses along u and v with every other strain free are stretch_u and stretch_v.
    double area = 0.0;
    const Eigen::Matrix3d C = homogenised(rectangle(0.2, 0.2, 0.01), WeaveAlignment::aligned, area);
    const Eigen::Matrix3d S = C.inverse();
    std::printf("aligned: E_u = %.1f, E_v = %.1f, G = %.2f N/m (fabric 5000, 2000, 40)\n", 1 / S(0, 0),
                1 / S(1, 1), 1 / S(2, 2));
    EXPECT_NEAR(1 / S(0, 0), 5000.0, 0.02 * 5000.0);
    EXPECT_NEAR(1 / S(1, 1), 2000.0, 0.02 * 2000.0);
    EXPECT_NEAR(1 / S(2, 2), 40.0, 0.1 * 40.0);
    // Unaligned (OBJ) meshes: shear is what the triangles give (far above a fabric's): on an equilateral mesh
    // of an isotropic fabric the springs are an isotropic membrane with Poisson ratio 1/3, G = 3 E / 8.
    const Eigen::Matrix3d Su =
        homogenised(equilateral(0.2, 0.2, 0.01), WeaveAlignment::unaligned, area).inverse();
    std::printf("unaligned, equilateral: E_u = %.1f, E_v = %.1f, G = %.1f N/m (stretch_v = %.0f)\n",
                1 / Su(0, 0), 1 / Su(1, 1), 1 / Su(2, 2), 2000.0);
    EXPECT_GT(1 / Su(2, 2), 10 * 40.0);
}

TEST(TriangleFabric, LumpedMassesAddUpToDensityTimesArea) {
    const GarmentAssembly a = rectangle(0.3, 0.2, 0.013);
    const std::vector<double> m = lumped_masses(a.x, a.y, a.z, a.triangles, 0.2);
    double total = 0.0;
    for (double v : m) {
        EXPECT_GT(v, 0.0);
        total += v;
    }
    EXPECT_NEAR(total, 0.2 * 0.3 * 0.2, 1e-6 * 0.012);
}

// A needle (short edge 2-3 across two wide triangles): the cook refuses it naming that edge and its k_e / k_ref (the
// callers translate the particles into the user's terms); 40 times wider it cooks.
TEST(TriangleFabric, NeedleIsRefusedNamingItsShortEdge) {
    const Fabric f = test_fabric();
    const auto needle = [](float width) {
        // particles 0 and 1 the far corners, 2 and 3 the short edge's ends
        return mesh_assembly({0.0f, 0.0f, 0.5f * width, -0.5f * width}, {1.0f, -1.0f, 0.0f, 0.0f}, {0, 2, 3, 3, 2, 1});
    };
    const GarmentAssembly a = needle(4e-4f);
    const std::vector<float> inv(a.particle_count(), 1.0f);
    const std::vector<Edge> edges{{2, 3, SpringKind::structural, 0.0f}};
    const double k_ref = 0.5 * (double(f.stretch_u) + f.stretch_v);
    const double expected = membrane_stiffness(a.x, a.y, a.z, a.triangles, edges, f, {1, 0, 0}, WeaveAlignment::aligned)[0] / k_ref;
    ASSERT_GT(expected, membrane_stiffness_ratio_max);
    try {
        cook_triangle_fabric(a, inv, {f, {1, 0, 0}, WeaveAlignment::aligned});
        ADD_FAILURE() << "a needle cooked";
    } catch (const NeedleTriangleError& e) {
        EXPECT_EQ(e.a, 2u);
        EXPECT_EQ(e.b, 3u);
        EXPECT_NEAR(e.ratio, expected, 1e-9 * expected);
        EXPECT_NE(std::string(e.what()).find("membrane spring 2-3 would be"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("as stiff as the fabric (at most 1000)"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(cook_triangle_fabric(needle(1.6e-2f), inv, {f, {1, 0, 0}, WeaveAlignment::aligned}));
}

TEST(TriangleFabric, CookedClothHasPerSpringMaterialsAndNoBendSprings) {
    GarmentAssembly a = rectangle(0.1, 0.1, 0.02);
    const std::size_t panel = a.particle_count();
    ASSERT_GT(a.edge_count(SpringKind::bend), 0u); // the outline panel's own cross springs
    OutlinePanel p{{{0.0, 0.0}, {0.1, 0.0}, {0.1, 0.1}, {0.0, 0.1}}};
    OutlinePanelParams op;
    op.spacing = 0.02;
    PanelFrame back;
    back.origin = {0.0f, 0.0f, -0.05f};
    add_outline_panel(a, p, op, back);
    const std::vector<std::uint32_t> seams =
        sew_by_arc_length(a, std::vector<std::uint32_t>{0, 1},
                          std::vector<std::uint32_t>{std::uint32_t(panel), std::uint32_t(panel + 1)}, 0.01f);
    ASSERT_FALSE(seams.empty());
    const std::vector<double> mass = lumped_masses(a.x, a.y, a.z, a.triangles, 0.2);
    std::vector<float> inv(mass.size());
    for (std::size_t i = 0; i < mass.size(); ++i)
        inv[i] = float(1.0 / mass[i]);
    const Fabric f = test_fabric();
    const Cloth c = cook_triangle_fabric(a, inv, {f, {1, 0, 0}, WeaveAlignment::aligned});
    EXPECT_EQ(c.edges.size(), triangle_edges(a).size() + seams.size());
    std::size_t seam_count = 0;
    for (std::size_t e = 0; e < c.edges.size(); ++e) {
        EXPECT_NE(c.edges[e].kind, SpringKind::bend);
        if (c.edges[e].kind == SpringKind::shear) { // off the weave: neither along u (x) nor v (y)
            const double dx = std::fabs(a.x[c.edges[e].b] - a.x[c.edges[e].a]),
                         dy = std::fabs(a.y[c.edges[e].b] - a.y[c.edges[e].a]);
            EXPECT_GT(std::min(dx, dy), 0.1 * std::max(dx, dy));
        }
        const SpringMaterial& kind = c.material[static_cast<std::size_t>(c.edges[e].kind)];
        const float k = kind.stiffness * c.edges[e].scale, kd = kind.damping * c.edges[e].scale;
        EXPECT_GT(k, 0.0f);
        EXPECT_FLOAT_EQ(kd, f.damping * k);
        if (c.edges[e].kind == SpringKind::seam) {
            ++seam_count;
            EXPECT_FLOAT_EQ(k, 3500.0f);
        }
    }
    EXPECT_EQ(seam_count, seams.size());
    EXPECT_EQ(c.triangles, a.triangles);
    // Each spring's stiffness is the membrane's for its edge.
    const std::vector<double> expected =
        membrane_stiffness(a.x, a.y, a.z, a.triangles, c.edges, f, {1, 0, 0}, WeaveAlignment::aligned);
    for (std::size_t e = 0; e < c.edges.size(); ++e)
        if (c.edges[e].kind != SpringKind::seam) {
            EXPECT_NEAR(c.material[static_cast<std::size_t>(c.edges[e].kind)].stiffness * c.edges[e].scale,
                        expected[e], 1e-5 * expected[e]);
        }
}

TEST(TriangleFabric, ScenesCookWithTheFabricModel) {
    for (const char* name : {"tshirt", DRAPE_SOURCE_DIR "/scenes/examples/bag.json",
                             DRAPE_SOURCE_DIR "/scenes/examples/mesh_disc.json"}) {
        SceneSpec spec = load_scene(name);
        spec.model = MaterialModel::springs; // the scenes' own material is a fabric preset
        const BuiltScene springs = build_scene(spec);
        spec.model = MaterialModel::fabric;
        spec.fabric = test_fabric();
        const BuiltScene b = build_scene(spec);
        EXPECT_EQ(b.cloth.particle_count, springs.cloth.particle_count) << name;
        for (const Edge& e : springs.cloth.edges)
            EXPECT_EQ(e.scale, 1.0f) << name;
        EXPECT_TRUE(springs.cloth.bending.empty()) << name;
        EXPECT_FALSE(b.cloth.bending.empty()) << name;
        for (const Edge& e : b.cloth.edges)
            EXPECT_NE(e.kind, SpringKind::bend) << name;
        EXPECT_EQ(b.cloth.triangles, springs.cloth.triangles) << name;
        // Node masses: the fabric's density times the area, whatever the scene's own mass figures.
        double mass = 0.0, area = 0.0;
        const auto& t = b.cloth.triangles;
        const InitialState& x = b.initial;
        for (std::size_t k = 0; k < t.size(); k += 3) {
            const std::uint32_t i = t[k], j = t[k + 1], l = t[k + 2];
            const double ux = x.x[j] - x.x[i], uy = x.y[j] - x.y[i], uz = x.z[j] - x.z[i];
            const double vx = x.x[l] - x.x[i], vy = x.y[l] - x.y[i], vz = x.z[l] - x.z[i];
            area += 0.5 * std::sqrt(std::pow(uy * vz - uz * vy, 2) + std::pow(uz * vx - ux * vz, 2) +
                                    std::pow(ux * vy - uy * vx, 2));
        }
        for (std::size_t i = 0; i < b.cloth.particle_count; ++i) {
            const float inv = b.cloth.free_inv_mass.empty() ? b.cloth.inv_mass[i] : b.cloth.free_inv_mass[i];
            mass += 1.0 / inv;
        }
        EXPECT_NEAR(mass, test_fabric().density * area, 0.01 * mass) << name;
        EXPECT_GT(b.params.dt, 0.0f) << name;
    }
}

TEST(TriangleFabric, TShirtWithTheFabricModelStaysHealthy) {
    // The seams start 0.26 m long and close the shirt in the first 0.1 s; without a strain limit the
    // membrane's own stiffness and a little Rayleigh damping keep warp and weft strain small.
    SceneSpec spec = load_scene("tshirt");
    spec.model = MaterialModel::fabric;
    spec.fabric = test_fabric();
    spec.fabric.damping = 1e-5f;
    spec.physics.strain_limit.ratio = 0.0f;
    BuiltScene b = build_scene(spec);
    Simulation sim(std::move(b.cloth), b.initial, b.params);
    sim.step(static_cast<std::size_t>(0.1 / sim.params().dt));
    const Health h = sim.health();
    EXPECT_TRUE(h.finite);
    EXPECT_TRUE(h.monitor.healthy);
    EXPECT_LT(h.max_structural_strain, 0.03f); // warp and weft springs (measured 0.017)
}

// Hinge bending through Q's rows, per-spring stiffness and seams: the same bits at every worker count and
// serially.
TEST(TriangleFabric, FabricTShirtIndependentOfWorkerCount) {
    const auto run = [](int workers, bool serial) {
        Workers arena(workers);
        return arena.run([serial] {
            SceneSpec spec = load_scene("tshirt");
            spec.tshirt.cells_per_metre = 80; // ~5,100 particles: several blocks
            spec.model = MaterialModel::fabric;
            spec.fabric = test_fabric();
            spec.fabric.damping = 1e-5f;
            // Without the scene's strain limit: at 80 cells/m it blows up while the seams close (docs/fabric.md).
            spec.physics.strain_limit.ratio = 0.0f;
            BuiltScene b = build_scene(spec);
            Simulation sim(std::move(b.cloth), b.initial, b.params);
            const std::size_t steps = drape::testing::sanitized ? 50 : 150; // ASan: 31 s with 150
            if (serial)
                sim.step_serial(steps);
            else
                sim.step(steps);
            EXPECT_TRUE(sim.health().finite);
            return sim.checksum();
        });
    };
    const std::uint64_t one = run(1, false);
    for (int w : {3, 8})
        EXPECT_EQ(one, run(w, false)) << w << " workers";
    EXPECT_EQ(one, run(1, true)) << "serial";
}

} // namespace
} // namespace drape
