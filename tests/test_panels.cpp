// Garment panels: mask panels (counts per spring kind), the T-shirt, outline panels and sewing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "drape/cloth.hpp"
#include "drape/colliders.hpp"
#include "drape/errors.hpp"
#include "drape/panels.hpp"

namespace drape {
namespace {

MaskPanel full_mask(std::size_t w, std::size_t h) {
    return {std::vector<std::string>(h, std::string(w, '1'))};
}

struct KindCounts {
    std::size_t structural, shear, bend;
};
KindCounts counts(const GarmentAssembly& a) {
    return {a.edge_count(SpringKind::structural), a.edge_count(SpringKind::shear),
            a.edge_count(SpringKind::bend)};
}

double dist(const GarmentAssembly& a, std::uint32_t i, std::uint32_t j) {
    const double dx = double{a.x[i]} - a.x[j], dy = double{a.y[i]} - a.y[j], dz = double{a.z[i]} - a.z[j];
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}

// Triangle normal (not normalised).
std::array<double, 3> tri_normal(const GarmentAssembly& a, std::size_t t) {
    const std::uint32_t i = a.triangles[3 * t], j = a.triangles[3 * t + 1], k = a.triangles[3 * t + 2];
    const double ux = a.x[j] - a.x[i], uy = a.y[j] - a.y[i], uz = a.z[j] - a.z[i];
    const double vx = a.x[k] - a.x[i], vy = a.y[k] - a.y[i], vz = a.z[k] - a.z[i];
    return {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
}

std::array<double, 3> cross(const std::array<float, 3>& u, const std::array<float, 3>& v) {
    return {double{u[1]} * v[2] - double{u[2]} * v[1], double{u[2]} * v[0] - double{u[0]} * v[2],
            double{u[0]} * v[1] - double{u[1]} * v[0]};
}

template <class F> std::string error_of(F&& f) {
    try {
        f();
    } catch (const InvalidInput& e) {
        return e.what();
    }
    return "(no error)";
}

// ---------------------------------------------------------------------------------------------------------------------

TEST(GarmentMask, FullRectangleMatchesTheGridFormula) {
    for (auto [w, h] : {std::pair<std::size_t, std::size_t>{1, 1},
                        {1, 5},
                        {5, 1},
                        {2, 2},
                        {3, 2},
                        {5, 3},
                        {7, 11},
                        {32, 32}}) {
        GarmentAssembly a;
        const MaskPanelBuild b = add_mask_panel(a, full_mask(w, h), 0.01f, 0.001f);
        SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h));
        EXPECT_EQ(a.particle_count(), w * h);
        const KindCounts k = counts(a);
        EXPECT_EQ(k.structural, h * (w - 1) + w * (h - 1));
        EXPECT_EQ(k.shear, 2 * (w - 1) * (h - 1));
        EXPECT_EQ(k.bend, h * (w >= 2 ? w - 2 : 0) + w * (h >= 2 ? h - 2 : 0));
        EXPECT_EQ(a.triangle_count(), 2 * (w - 1) * (h - 1));
        EXPECT_EQ(b.edge_count, a.edges.size());
        if (w >= 2 && h >= 2) {
            EXPECT_EQ(b.boundary_particles.size(), 2 * w + 2 * h - 4);
            EXPECT_EQ(b.boundary_edges.size(), 2 * (w - 1) + 2 * (h - 1));
        } else {
            EXPECT_EQ(b.boundary_particles.size(), w * h); // no triangles: every particle is on the boundary
        }
    }
    // BENCH.md: 5,826 springs at N = 32.
    GarmentAssembly a;
    add_mask_panel(a, full_mask(32, 32), 0.01f, 0.001f);
    EXPECT_EQ(a.edges.size(), 5826u);
}

TEST(GarmentMask, HandCountedSmallMasks) {
    struct Case {
        std::vector<std::string> rows;
        std::size_t particles, structural, shear, bend, triangles, boundary;
    };
    const Case cases[] = {
        // Staircase: (0,0) (0,1) (1,1) (1,2). Shear (0,0)-(1,1) and (0,1)-(1,2); two half-cell triangles.
        {{"110", "011"}, 4, 3, 2, 0, 2, 4},
        // Two particles touching at a corner: no triangle, so no shear spring.
        {{"10", "01"}, 2, 0, 0, 0, 0, 2},
        // A gap: no bend spring across it.
        {{"101"}, 2, 0, 0, 0, 0, 2},
        // A plus: four half cells, one shear each, two bends through the centre; the centre is interior.
        {{"010", "111", "010"}, 5, 4, 4, 2, 4, 4},
        // A ring around a hole: bends only where the middle exists.
        {{"111", "101", "111"}, 8, 8, 4, 4, 4, 8},
        // An L: one half cell (the inner corner) holds a triangle and its shear spring.
        {{"100", "100", "111"}, 5, 4, 1, 2, 1, 5},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.rows[0] + "/" + (c.rows.size() > 1 ? c.rows[1] : ""));
        GarmentAssembly a;
        const MaskPanelBuild b = add_mask_panel(a, {c.rows}, 0.1f, 0.01f);
        EXPECT_EQ(a.particle_count(), c.particles);
        const KindCounts k = counts(a);
        EXPECT_EQ(k.structural, c.structural);
        EXPECT_EQ(k.shear, c.shear);
        EXPECT_EQ(k.bend, c.bend);
        EXPECT_EQ(a.triangle_count(), c.triangles);
        EXPECT_EQ(b.boundary_particles.size(), c.boundary);
    }
}

TEST(GarmentMask, RestLengthsWindingAndFrame) {
    // A tilted frame: u along x, v along (0, -0.6, 0.8) (a panel leaning back).
    const PanelFrame frame{{1.0f, 2.0f, 3.0f}, {1.0f, 0.0f, 0.0f}, {0.0f, -0.6f, 0.8f}};
    GarmentAssembly a;
    const MaskPanel mask{{"0111110", "1111111", "1110111", "0110110"}};
    const MaskPanelBuild b = add_mask_panel(a, mask, 0.05f, 0.002f, frame);
    for (const Edge& e : a.edges) {
        EXPECT_LT(e.a, e.b);
        EXPECT_NEAR(e.rest, dist(a, e.a, e.b), 1e-6);
    }
    const auto n = cross(frame.axis_u, frame.axis_v);
    for (std::size_t t = 0; t < a.triangle_count(); ++t) {
        const auto tn = tri_normal(a, t);
        EXPECT_GT(tn[0] * n[0] + tn[1] * n[1] + tn[2] * n[2], 0.0) << "triangle " << t;
    }
    // Cell (row 1, column 2) sits at origin + 2h u + 1h v.
    const std::int32_t p = b.particle_at(1, 2);
    ASSERT_GE(p, 0);
    EXPECT_NEAR(a.x[p], 1.0f + 0.1f, 1e-6);
    EXPECT_NEAR(a.y[p], 2.0f - 0.03f, 1e-6);
    EXPECT_NEAR(a.z[p], 3.0f + 0.04f, 1e-6);
    EXPECT_EQ(b.particle_at(0, 0), -1);
    EXPECT_EQ(b.particle_at(-1, 0), -1);
    // Every mass as given; the cloth cooks.
    for (float m : a.mass)
        EXPECT_EQ(m, 0.002f);
    std::array<SpringMaterial, spring_kind_count> mat{};
    for (auto& m : mat)
        m = {1000.0f, 0.1f};
    const Cloth c = cook_cloth(a.inverse_masses(), a.edges, mat);
    EXPECT_EQ(c.particle_count, a.particle_count());
}

TEST(GarmentMask, TwoPanelsAppendToOneAssembly) {
    GarmentAssembly a;
    const MaskPanelBuild p1 = add_mask_panel(a, full_mask(3, 3), 0.1f, 0.01f);
    const MaskPanelBuild p2 =
        add_mask_panel(a, full_mask(4, 2), 0.1f, 0.01f, {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}});
    EXPECT_EQ(p1.first_particle, 0u);
    EXPECT_EQ(p2.first_particle, 9u);
    EXPECT_EQ(a.particle_count(), 17u);
    EXPECT_EQ(p2.first_edge, p1.edge_count);
    for (std::size_t e = p2.first_edge; e < p2.first_edge + p2.edge_count; ++e)
        EXPECT_GE(a.edges[e].a, 9u);
    for (std::size_t t = p2.first_triangle * 3; t < a.triangles.size(); ++t)
        EXPECT_GE(a.triangles[t], 9u);
}

TEST(GarmentMask, RejectsBadMasksNamingRowAndColumn) {
    GarmentAssembly a;
    EXPECT_NE(error_of([&] { add_mask_panel(a, {{}}, 0.1f, 0.01f); }).find("no rows"), std::string::npos);
    EXPECT_NE(error_of([&] {
                  add_mask_panel(a, {{"111", "11"}}, 0.1f, 0.01f);
              }).find("row 1 has 2 columns"),
              std::string::npos);
    EXPECT_NE(error_of([&] {
                  add_mask_panel(a, {{"111", "111", "1101"}}, 0.1f, 0.01f);
              }).find("row 2 has 4"),
              std::string::npos);
    EXPECT_NE(error_of([&] {
                  add_mask_panel(a, {{"1111", "1111", "111x"}}, 0.1f, 0.01f);
              }).find("row 2, column 3 holds 'x'"),
              std::string::npos);
    EXPECT_NE(error_of([&] {
                  add_mask_panel(a, {{"000", "000"}}, 0.1f, 0.01f);
              }).find("no '1'"),
              std::string::npos);
    EXPECT_NE(error_of([&] { add_mask_panel(a, {{""}}, 0.1f, 0.01f); }).find("row 0 has 0 columns"),
              std::string::npos);
    EXPECT_NE(error_of([&] { add_mask_panel(a, full_mask(4097, 1), 0.1f, 0.01f); }).find("allowed 1..4096"),
              std::string::npos);
    EXPECT_NE(error_of([&] { add_mask_panel(a, full_mask(1, 4097), 0.1f, 0.01f); }).find("4097 rows"),
              std::string::npos);
    EXPECT_NE(error_of([&] { add_mask_panel(a, full_mask(2, 2), 0.0f, 0.01f); }).find("panel spacing"),
              std::string::npos);
    EXPECT_NE(error_of([&] { add_mask_panel(a, full_mask(2, 2), 0.1f, -1.0f); }).find("particle mass"),
              std::string::npos);
    EXPECT_NE(error_of([&] {
                  add_mask_panel(a, full_mask(2, 2), 0.1f, 0.01f, {{0, 0, 0}, {1, 0, 0}, {1, 0, 0}});
              }).find("orthogonal"),
              std::string::npos);
    EXPECT_EQ(a.particle_count(), 0u); // nothing appended on error
}

// ---------------------------------------------------------------------------------------------------------------------
// T-shirt

TEST(GarmentTShirt, SeedResolutionHas1008ParticlesInTwoIdenticalPanels) {
    const TShirtBuild t = build_tshirt({});
    EXPECT_EQ(t.assembly.particle_count(), 1008u);
    EXPECT_EQ(t.front.particle_count, 504u);
    EXPECT_EQ(t.back.particle_count, 504u);
    EXPECT_EQ(t.front.first_particle, 0u);
    EXPECT_EQ(t.back.first_particle, 504u);
    // Identical panels: the same springs (shifted by 504) with the same rest lengths, the same triangles.
    ASSERT_EQ(t.front.edge_count, t.back.edge_count);
    for (std::size_t k = 0; k < t.front.edge_count; ++k) {
        const Edge& f = t.assembly.edges[t.front.first_edge + k];
        const Edge& b = t.assembly.edges[t.back.first_edge + k];
        EXPECT_EQ(f.a + 504, b.a);
        EXPECT_EQ(f.b + 504, b.b);
        EXPECT_EQ(f.kind, b.kind);
        EXPECT_EQ(f.rest, b.rest);
    }
    ASSERT_EQ(t.front.triangle_count, t.back.triangle_count);
    for (std::size_t k = 0; k < 3 * t.front.triangle_count; ++k)
        EXPECT_EQ(t.assembly.triangles[3 * t.front.first_triangle + k] + 504,
                  t.assembly.triangles[3 * t.back.first_triangle + k]);
    // The back is the front turned half a turn about y: (x, y, z) -> (-x, y, -z).
    for (std::uint32_t i = 0; i < 504; ++i) {
        EXPECT_NEAR(t.assembly.x[i + 504], -t.assembly.x[i], 1e-6);
        EXPECT_EQ(t.assembly.y[i + 504], t.assembly.y[i]);
        EXPECT_NEAR(t.assembly.z[i + 504], -t.assembly.z[i], 1e-6);
    }
    // Normals face out: front +z, back -z.
    for (std::size_t k = 0; k < t.assembly.triangle_count(); ++k) {
        const auto n = tri_normal(t.assembly, k);
        EXPECT_GT(k < t.front.triangle_count ? n[2] : -n[2], 0.0);
    }
    // Mask symmetric left-right; sizes: 0.88 m span, 0.68 m tall at h = 1/35 m.
    for (const std::string& row : t.mask.rows)
        EXPECT_TRUE(std::equal(row.begin(), row.end(), row.rbegin()));
    EXPECT_EQ(t.mask.rows.size(), 25u);
    EXPECT_EQ(t.mask.rows[0].size(), 31u);
    float total = 0;
    for (float m : t.assembly.mass)
        total += m;
    EXPECT_NEAR(total, 0.15f, 1e-5f);
    // It cooks (seam rest lengths are positive, no duplicate springs).
    std::array<SpringMaterial, spring_kind_count> mat{};
    for (auto& m : mat)
        m = {1000.0f, 0.1f};
    EXPECT_NO_THROW(cook_cloth(t.assembly.inverse_masses(), t.assembly.edges, mat));
}

TEST(GarmentTShirt, SeamsOnlyOnShouldersSidesAndUnderarms) {
    const TShirtBuild t = build_tshirt({});
    const std::size_t rows = t.front.rows, cols = t.front.columns;
    const std::int64_t m = static_cast<std::int64_t>(cols / 2);
    std::set<std::uint32_t> front_boundary(t.front.boundary_particles.begin(),
                                           t.front.boundary_particles.end());
    std::set<std::uint32_t> back_boundary(t.back.boundary_particles.begin(), t.back.boundary_particles.end());
    // Cell of a front particle.
    std::vector<std::pair<std::int64_t, std::int64_t>> cell(t.assembly.particle_count(), {-1, -1});
    for (std::size_t r = 0; r < rows; ++r)
        for (std::size_t c = 0; c < cols; ++c) {
            const std::int32_t f = t.front.particle_at(r, c);
            if (f >= 0) cell[f] = {r, c};
        }
    ASSERT_EQ(t.seam_edges.size(), t.seam_part.size());
    std::set<std::uint32_t> sewn_front;
    std::size_t parts[3] = {0, 0, 0};
    for (std::size_t k = 0; k < t.seam_edges.size(); ++k) {
        const Edge& e = t.assembly.edges[t.seam_edges[k]];
        EXPECT_EQ(e.kind, SpringKind::seam);
        EXPECT_NEAR(e.rest, 0.5f * t.spacing, 1e-7);
        const std::uint32_t f = e.a, b = e.b; // front indices are below back indices
        ASSERT_LT(f, 504u);
        ASSERT_GE(b, 504u);
        EXPECT_TRUE(front_boundary.count(f)) << "front particle " << f << " is not on the boundary";
        EXPECT_TRUE(back_boundary.count(b)) << "back particle " << b << " is not on the boundary";
        EXPECT_NEAR(t.assembly.x[f], t.assembly.x[b], 1e-6f); // the same (x, y) on both panels
        EXPECT_EQ(t.assembly.y[f], t.assembly.y[b]);
        EXPECT_NEAR(t.assembly.z[f] - t.assembly.z[b], 0.26f, 1e-6);
        EXPECT_TRUE(sewn_front.insert(f).second) << "front particle sewn twice";
        const auto [r, c] = cell[f];
        ++parts[static_cast<int>(t.seam_part[k])];
        switch (t.seam_part[k]) {
        case SeamPart::shoulder:
            EXPECT_EQ(r, 0);
            break;
        case SeamPart::underarm:
            EXPECT_GT(r, 0);
            EXPECT_GT(std::abs(c - m), static_cast<std::int64_t>(0.24 * 35 + 0.5)); // under a sleeve
            EXPECT_EQ(t.front.particle_at(r + 1, c), -1);
            break;
        case SeamPart::side:
            EXPECT_EQ(std::abs(c - m), static_cast<std::int64_t>(0.24 * 35 + 0.5)); // the body's side column
            break;
        }
    }
    EXPECT_GT(parts[0], 0u);
    EXPECT_GT(parts[1], 0u);
    EXPECT_GT(parts[2], 0u);
    // A boundary particle is sewn unless it is on the neck (below row 0 near the centre; the neck is 0.20 m
    // wide and 0.08 m deep), the hem (last row) between the two side seams, or a cuff (first or last column)
    // between the shoulder and the underarm.
    const std::int64_t body = static_cast<std::int64_t>(0.24 * 35 + 0.5);
    std::size_t open[3] = {0, 0, 0};
    for (std::uint32_t f : t.front.boundary_particles) {
        const auto [r, c] = cell[f];
        const bool neck = r > 0 && r <= 3 && std::abs(c - m) <= 4;
        const bool hem = r == static_cast<std::int64_t>(rows) - 1 && std::abs(c - m) < body;
        const bool cuff = (c == 0 || c == static_cast<std::int64_t>(cols) - 1) && r > 0 &&
                          t.front.particle_at(r + 1, c) >= 0;
        EXPECT_EQ(sewn_front.count(f) == 1, !(neck || hem || cuff)) << "row " << r << " column " << c;
        open[0] += neck;
        open[1] += hem;
        open[2] += cuff;
    }
    EXPECT_GT(open[0], 0u);
    EXPECT_EQ(open[1], static_cast<std::size_t>(2 * body - 1));
    EXPECT_EQ(open[2], 2u * 5u); // sleeve rows 1..5 at each cuff
}

TEST(GarmentTShirt, HighResolutionReaches100kParticles) {
    TShirtParams p;
    p.cells_per_metre = 360.0f;
    const TShirtBuild t = build_tshirt(p);
    EXPECT_GT(t.assembly.particle_count(), 100'000u);
    EXPECT_LT(t.assembly.particle_count(), 110'000u);
    EXPECT_EQ(t.front.particle_count, t.back.particle_count);
    std::array<SpringMaterial, spring_kind_count> mat{};
    for (auto& m : mat)
        m = {1000.0f, 0.01f};
    const Cloth c = cook_cloth(t.assembly.inverse_masses(), t.assembly.edges, mat);
    EXPECT_EQ(c.particle_count, t.assembly.particle_count());
}

TEST(GarmentTShirt, StartsOutsideTheDefaultBody) {
    const TShirtBuild t = build_tshirt({});
    const auto body = default_body();
    for (std::size_t i = 0; i < t.assembly.particle_count(); ++i)
        for (const Collider& c : body)
            EXPECT_FALSE(is_inside(c, {t.assembly.x[i], t.assembly.y[i], t.assembly.z[i]}))
                << "particle " << i;
    // The shoulder line is above the shoulders, the hem below the torso's middle.
    EXPECT_NEAR(*std::max_element(t.assembly.y.begin(), t.assembly.y.end()), 0.33f, 1e-6f);
    EXPECT_LT(*std::min_element(t.assembly.y.begin(), t.assembly.y.end()), -0.3f);
}

TEST(GarmentTShirt, RejectsParametersOutOfRange) {
    TShirtParams p;
    p.cells_per_metre = 5.0f;
    EXPECT_NE(error_of([&] { build_tshirt(p); }).find("cells_per_metre"), std::string::npos);
    p = {};
    p.gap = 0.0f;
    EXPECT_NE(error_of([&] { build_tshirt(p); }).find("tshirt gap"), std::string::npos);
    p = {};
    p.seam_rest_ratio = 0.0f;
    EXPECT_NE(error_of([&] { build_tshirt(p); }).find("seam_rest_ratio"), std::string::npos);
    p = {};
    p.total_mass = 100.0f;
    EXPECT_NE(error_of([&] { build_tshirt(p); }).find("total mass"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------------------------------
// Outline panels and sewing

double assembly_area(const GarmentAssembly& a, std::size_t first, std::size_t count) {
    double s = 0;
    for (std::size_t t = first; t < first + count; ++t) {
        const auto n = tri_normal(a, t);
        s += 0.5 * std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return s;
}

TEST(GarmentOutline, SquarePanelCoversItsOutline) {
    GarmentAssembly a;
    const OutlinePanel square{{{0, 0}, {1, 0}, {1, 1}, {0, 1}}};
    OutlinePanelParams p;
    p.spacing = 0.05;
    const OutlinePanelBuild b = add_outline_panel(a, square, p);
    EXPECT_NEAR(b.area, 1.0, 1e-12);
    EXPECT_NEAR(assembly_area(a, 0, a.triangle_count()), 1.0, 1e-6);
    EXPECT_NEAR(b.perimeter, 4.0, 1e-12);
    EXPECT_EQ(b.outline_particles.size(), 80u); // 20 samples per side
    // Fill points: 21x21 grid minus its outline ring (too close to the outline) -> 19 x 19.
    EXPECT_EQ(b.particle_count, 80u + 19u * 19u);
    double mass = 0;
    for (float m : a.mass)
        mass += m;
    EXPECT_NEAR(mass, 0.15, 1e-5);
    // Springs: structural = distinct triangle edges = V + T - 1 (Euler, one face), bend = interior edges.
    const std::size_t V = a.particle_count(), T = a.triangle_count();
    EXPECT_EQ(a.edge_count(SpringKind::structural), V + T - 1);
    EXPECT_LE(a.edge_count(SpringKind::bend), V + T - 1 - b.outline_particles.size());
    EXPECT_GT(a.edge_count(SpringKind::bend), 0u);
    for (const Edge& e : a.edges)
        EXPECT_NEAR(e.rest, dist(a, e.a, e.b), 1e-6);
    // Counter-clockwise seen from u x v = -z with the default frame.
    for (std::size_t t = 0; t < T; ++t)
        EXPECT_LT(tri_normal(a, t)[2], 0.0);
    std::array<SpringMaterial, spring_kind_count> mat{};
    for (auto& m : mat)
        m = {1000.0f, 0.1f};
    EXPECT_NO_THROW(cook_cloth(a.inverse_masses(), a.edges, mat));
}

TEST(GarmentOutline, NonConvexPanelsCoverTheirOutlineWithinSamplingTolerance) {
    const OutlinePanel shapes[] = {
        {{{0, 0}, {0.6, 0}, {0.6, 0.2}, {0.2, 0.2}, {0.2, 0.8}, {0, 0.8}}}, // L, CCW
        {{{0, 0}, {0, 0.5}, {0.5, 0.5}, {0.5, 0}}},                         // square, CW
        {{{0, 0}, {0.5, 0.1}, {1.0, 0}, {0.9, 0.5}, {1.0, 1.0}, {0.5, 0.9}, {0, 1}, {0.1, 0.5}}}, // star-ish
        {{{-0.25, 0},
          {0.25, 0},
          {0.25, 0.5},
          {0.42, 0.45},
          {0.36, 0.6},
          {0.1, 0.7},
          {-0.1, 0.7},
          {-0.36, 0.6},
          {-0.42, 0.45},
          {-0.25, 0.5}}}, // a T-shirt-like front
    };
    for (const OutlinePanel& shape : shapes) {
        for (double h : {0.05, 0.02, 0.0137}) {
            GarmentAssembly a;
            OutlinePanelParams p;
            p.spacing = h;
            const OutlinePanelBuild b = add_outline_panel(a, shape, p);
            const double area = assembly_area(a, 0, a.triangle_count());
            SCOPED_TRACE("h = " + std::to_string(h) + ", polygon area " + std::to_string(b.area));
            // The outline samples (spacing <= h) and the fill's clearance of h/2 make every outline piece a
            // Delaunay edge, so the kept triangles tile the polygon: the areas agree to float rounding of the
            // positions.
            EXPECT_NEAR(area, b.area, 1e-6 * b.area);
            EXPECT_EQ(b.outline_vertex_arc.size(), shape.outline.size());
        }
    }
}

TEST(GarmentOutline, RejectsBadOutlines) {
    GarmentAssembly a;
    OutlinePanelParams p;
    EXPECT_NE(error_of([&] {
                  add_outline_panel(a, {{{0, 0}, {1, 0}}}, p);
              }).find("2 vertices"),
              std::string::npos);
    EXPECT_NE(error_of([&] {
                  add_outline_panel(a, {{{0, 0}, {1, 0}, {1, 0}, {0, 1}}}, p);
              }).find("coincide"),
              std::string::npos);
    EXPECT_NE(error_of([&] {
                  add_outline_panel(a, {{{0, 0}, {3, 0}, {3, 1}, {1, -1}, {0, 2}}}, p);
              }).find("intersect"),
              std::string::npos);
    EXPECT_NE(error_of([&] {
                  add_outline_panel(a, {{{0, 0}, {1, 0}, {2, 0}}}, p);
              }).find("zero area"),
              std::string::npos);
    EXPECT_NE(error_of([&] {
                  add_outline_panel(a, {{{0, 0}, {NAN, 0}, {0, 1}}}, p);
              }).find("vertex 1"),
              std::string::npos);
    p.spacing = 1e-4;
    EXPECT_NE(error_of([&] {
                  add_outline_panel(a, {{{0, 0}, {1, 0}, {1, 1}, {0, 1}}}, p);
              }).find("max_points"),
              std::string::npos);
    EXPECT_EQ(a.particle_count(), 0u);
}

TEST(GarmentSewing, TwoPanelsSewnAlongMatchingEdgesByArcLength) {
    // Two 0.4 x 0.6 rectangles facing each other 0.1 m apart; sew their right edges (vertex 1 -> 2 on both).
    const OutlinePanel rect{{{0, 0}, {0.4, 0}, {0.4, 0.6}, {0, 0.6}}};
    OutlinePanelParams p;
    p.spacing = 0.05;
    GarmentAssembly a;
    const OutlinePanelBuild front = add_outline_panel(a, rect, p, {{0, 0, 0.05f}, {1, 0, 0}, {0, 1, 0}});
    p.spacing = 0.04; // a different sampling on the back: pairing by arc length still works
    const OutlinePanelBuild back = add_outline_panel(a, rect, p, {{0, 0, -0.05f}, {1, 0, 0}, {0, 1, 0}});
    const auto fa = outline_stretch_particles(front, {1, 2, false});
    const auto ba = outline_stretch_particles(back, {1, 2, false});
    ASSERT_EQ(fa.size(), 13u); // 0.6 / 0.05 + 1
    ASSERT_EQ(ba.size(), 16u); // 0.6 / 0.04 = 15 pieces + 1
    for (std::uint32_t i : fa)
        EXPECT_NEAR(a.x[i], 0.4f, 1e-6f);
    for (std::size_t k = 1; k < fa.size(); ++k)
        EXPECT_GT(a.y[fa[k]], a.y[fa[k - 1]]);
    const std::size_t before = a.edges.size();
    const auto seams = sew_by_arc_length(a, fa, ba, 0.005f);
    EXPECT_EQ(a.edges.size(), before + seams.size());
    EXPECT_GE(seams.size(), ba.size());
    EXPECT_LE(seams.size(), fa.size() + ba.size());
    std::set<std::uint32_t> touched;
    for (std::uint32_t k : seams) {
        const Edge& e = a.edges[k];
        EXPECT_EQ(e.kind, SpringKind::seam);
        EXPECT_EQ(e.rest, 0.005f);
        touched.insert(e.a);
        touched.insert(e.b);
        // Paired by arc length: both ends at nearly the same height (within one sample spacing).
        EXPECT_LT(std::abs(a.y[e.a] - a.y[e.b]), 0.05f);
        EXPECT_NEAR(std::abs(a.z[e.a] - a.z[e.b]), 0.1f, 1e-6f);
    }
    EXPECT_EQ(touched.size(), fa.size() + ba.size()); // every particle of both stretches is sewn
    // Reversed stretch runs the other way; the whole loop lists every outline particle once.
    const auto rev = outline_stretch_particles(front, {1, 2, true});
    EXPECT_TRUE(std::equal(rev.begin(), rev.end(), fa.rbegin()));
    EXPECT_EQ(outline_stretch_particles(front, {0, 0, false}).size(), front.outline_particles.size());
    // Wrapping stretch 3 -> 0 (the left edge): 13 particles at u = 0.
    const auto left = outline_stretch_particles(front, {3, 0, false});
    EXPECT_EQ(left.size(), 13u);
    for (std::uint32_t i : left)
        EXPECT_NEAR(a.x[i], 0.0f, 1e-6f);
    // Sewing the same stretches again adds nothing (pairs already joined).
    EXPECT_TRUE(sew_by_arc_length(a, fa, ba, 0.005f).empty());
    std::array<SpringMaterial, spring_kind_count> mat{};
    for (auto& m : mat)
        m = {1000.0f, 0.1f};
    EXPECT_NO_THROW(cook_cloth(a.inverse_masses(), a.edges, mat));
    EXPECT_NE(error_of([&] { sew_by_arc_length(a, fa, ba, 0.0f); }).find("seam rest"), std::string::npos);
    EXPECT_NE(error_of([&] {
                  outline_stretch_particles(front, {0, 4, false});
              }).find("outside [0, 3]"),
              std::string::npos);
}

} // namespace
} // namespace drape
