// Triangle-level contact with analytic colliders (triangle_contact.hpp, the collide stage's triangle pass): the
// deepest point agrees with dense sampling; cloths of 2 x 2 and 64 x 64 particles dropped on every collider kind end
// with no triangle meeting the collider's solid, under both solvers.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "drape/colliders.hpp"
#include "drape/scene.hpp"
#include "drape/simulation.hpp"
#include "drape/triangle_contact.hpp"

#include "../core/src/disc_lattice.hpp"

namespace drape {
namespace {

std::vector<Collider> kinds(ColliderSurface s) {
    return {
        make_sphere({0.0f, 0.0f, 0.0f}, 0.3f, s),
        make_capsule({-0.3f, 0.0f, 0.1f}, {0.3f, 0.05f, -0.1f}, 0.15f, s),
        make_disc({0.0f, 0.0f, 0.0f}, 0.35f, 0.05f, s),
        make_ellipsoid({0.0f, 0.0f, 0.0f}, {0.4f, 0.1f, 0.2f}, s),
        make_ellipsoid({0.0f, 0.0f, 0.0f}, {0.35f, 0.08f, 0.12f}, s, rotation_about_axis({1, 1, 0}, 0.7f)),
    };
}

// A point p = sum b_i v_i of the triangle, at barycentric (1 - s - w, s, w).
Vec3f at(const Vec3f& a, const Vec3f& b, const Vec3f& c, float s, float w) {
    return {a[0] + s * (b[0] - a[0]) + w * (c[0] - a[0]), a[1] + s * (b[1] - a[1]) + w * (c[1] - a[1]),
            a[2] + s * (b[2] - a[2]) + w * (c[2] - a[2])};
}

// How far inside the inflated solid a point is, by the collider's own projection (0 outside).
float depth_of(const Collider& col, const Vec3f& p) {
    const Contact c = project_point(col, p);
    if (!c.inside) return 0.0f;
    return (c.point[0] - p[0]) * c.normal[0] + (c.point[1] - p[1]) * c.normal[1] + (c.point[2] - p[2]) * c.normal[2];
}

TEST(TriangleContact, DeepestPointAgreesWithDenseSampling) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    int contacts = 0, vertex_free = 0;
    for (const Collider& col : kinds({0.01f, 0.3f})) {
        SCOPED_TRACE(collider_kind_name(col.kind));
        for (int trial = 0; trial < 150; ++trial) {
            const float size = 0.05f + 0.4f * (u(rng) + 1.0f);
            const Vec3f centre{0.4f * u(rng), 0.4f * u(rng), 0.4f * u(rng)};
            Vec3f v[3];
            for (auto& p : v) p = {centre[0] + size * u(rng), centre[1] + size * u(rng), centre[2] + size * u(rng)};
            const TriangleContact tc = triangle_contact(col, v[0], v[1], v[2]);
            // Dense sampling: the deepest sample, and whether any sample is inside.
            constexpr int m = 60;
            float deepest_sample = 0.0f;
            bool sample_inside = false;
            for (int i = 0; i <= m; ++i)
                for (int j = 0; i + j <= m; ++j) {
                    const Vec3f p = at(v[0], v[1], v[2], float(i) / m, float(j) / m);
                    sample_inside = sample_inside || is_inside(col, p);
                    deepest_sample = std::max(deepest_sample, depth_of(col, p));
                }
            // A disc's rim is searched on a lattice (triangle_contact.hpp): exact up to ~10% of the margin.
            const float tolerance =
                col.kind == ColliderKind::disc ? 0.2f * col.thickness + 0.05f * deepest_sample : 1e-5f;
            if (sample_inside && deepest_sample > tolerance) {
                EXPECT_TRUE(tc.inside) << "trial " << trial << ": a sampled point is inside";
            }
            if (!tc.inside) continue;
            ++contacts;
            bool any_vertex = false;
            for (const auto& p : v) any_vertex = any_vertex || is_inside(col, p);
            vertex_free += any_vertex ? 0 : 1;
            EXPECT_TRUE(is_inside(col, tc.point, -1e-5f)) << "trial " << trial;
            EXPECT_NEAR(tc.barycentric[0] + tc.barycentric[1] + tc.barycentric[2], 1.0f, 1e-5f);
            const Vec3f q = at(v[0], v[1], v[2], tc.barycentric[1], tc.barycentric[2]);
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(q[c], tc.point[c], 1e-5f);
            EXPECT_NEAR(tc.depth, depth_of(col, tc.point), 1e-6f);
            // The exact kinds' deepest point is at least as deep as every sample (an ellipsoid's is deepest in its
            // own scaled measure, which is not the projection's depth).
            if (col.kind != ColliderKind::ellipsoid) {
                EXPECT_GE(tc.depth, deepest_sample - tolerance) << "trial " << trial;
            }
            // The pushed point is outside.
            Vec3f pushed = tc.point;
            for (int c = 0; c < 3; ++c) pushed[c] += tc.depth * tc.normal[c];
            EXPECT_FALSE(is_inside(col, pushed, 1e-5f)) << "trial " << trial;
        }
    }
    // The trials reach the cases that matter: contacts, and contacts with every vertex outside.
    EXPECT_GT(contacts, 200);
    EXPECT_GT(vertex_free, 40);
}

TEST(TriangleContact, PlaneIsLeftToTheVerticesButMeetsIsExact) {
    const Collider ground = make_ground(0.0f, {0.01f, 0.3f});
    EXPECT_FALSE(triangle_contact(ground, {0, -1, 0}, {1, -1, 0}, {0, -1, 1}).inside);
    EXPECT_TRUE(triangle_meets_collider(ground, {0, 0.5f, 0}, {1, -0.001f, 0}, {0, 0.5f, 1}));
    EXPECT_FALSE(triangle_meets_collider(ground, {0, 0.5f, 0}, {1, 0.001f, 0}, {0, 0.5f, 1}));
    EXPECT_TRUE(triangle_meets_collider(ground, {0, 0.5f, 0}, {1, 0.005f, 0}, {0, 0.5f, 1}, 0.01f));
}

// A square cloth of n x n particles, 1 m wide, dropped from above onto one collider.
SceneSpec drop_scene(std::uint32_t n, const Collider& col, Solver solver) {
    SceneSpec spec;
    spec.cloth = ClothType::grid;
    spec.grid.n = n;
    spec.grid.size = 1.0f;
    spec.grid.plane = GridPlane::horizontal;
    spec.grid.centre = {0.0f, 0.45f, 0.0f};
    spec.grid.pins = GridPins::none;
    spec.model = MaterialModel::fabric;
    spec.fabric = *find_fabric("wool");
    spec.physics.colliders = {col};
    spec.physics.solver = solver;
    if (solver == Solver::implicit) spec.dt = 1.0f / 60.0f;
    return spec;
}

std::size_t triangles_meeting(const Simulation& sim, const Collider& col) {
    const auto x = sim.x(), y = sim.y(), z = sim.z();
    const auto& tri = sim.cloth().triangles;
    std::size_t count = 0;
    for (std::size_t t = 0; t + 2 < tri.size(); t += 3) {
        const Vec3f a{x[tri[t]], y[tri[t]], z[tri[t]]}, b{x[tri[t + 1]], y[tri[t + 1]], z[tri[t + 1]]},
            c{x[tri[t + 2]], y[tri[t + 2]], z[tri[t + 2]]};
        count += triangle_meets_collider(col, a, b, c) ? 1 : 0;
    }
    return count;
}

struct DropCase {
    std::uint32_t n;
    Solver solver;
};
// Printed by gtest (and in the ctest name): without it the bytes, padding included, would be printed.
void PrintTo(const DropCase& dc, std::ostream* os) {
    *os << "n = " << dc.n << (dc.solver == Solver::implicit ? ", implicit" : ", explicit");
}

class TriangleContactDrop : public ::testing::TestWithParam<DropCase> {};

TEST_P(TriangleContactDrop, NoTriangleEndsInsideAnyColliderKind) {
    const DropCase dc = GetParam();
    for (const Collider& col : kinds({0.005f, 0.4f})) {
        SCOPED_TRACE(collider_kind_name(col.kind));
        BuiltScene built = build_scene(drop_scene(dc.n, col, dc.solver));
        const Collider local = built.params.colliders.at(0); // in the cloth's frame (relative to Cloth::origin)
        const float origin_y = float(built.cloth.origin[1]);
        Simulation sim(std::move(built.cloth), built.initial, built.params);
        const double seconds = 0.6;
        const auto steps = static_cast<std::size_t>(seconds / built.params.dt);
        std::size_t worst = 0;
        for (int k = 0; k < 6; ++k) {
            sim.step(steps / 6);
            worst = std::max(worst, triangles_meeting(sim, local));
        }
        EXPECT_EQ(worst, 0u) << "triangles meeting the solid at some check";
        // The cloth came to the collider and rests on it: it did not fall through (its highest point is above the
        // collider's lowest; all kinds here are centred at y = 0 and reach below it), and it fell (its mean height
        // is below the drop height: a corner of the 2 x 2 cloth tipping over the capsule can stand higher).
        float top = -1e9f;
        double mean = 0.0;
        for (float v : sim.y()) {
            top = std::max(top, origin_y + v);
            mean += origin_y + v;
        }
        mean /= double(sim.y().size());
        EXPECT_GT(top, 0.0f) << "the cloth fell through";
        EXPECT_LT(mean, 0.4) << "the cloth never fell";
    }
}

INSTANTIATE_TEST_SUITE_P(Sizes, TriangleContactDrop,
                         ::testing::Values(DropCase{2, Solver::explicit_euler}, DropCase{2, Solver::implicit},
                                           DropCase{64, Solver::implicit}),
                         [](const auto& info) {
                             std::string name = "n";
                             name += std::to_string(info.param.n);
                             name += info.param.solver == Solver::implicit ? "_implicit" : "_explicit";
                             return name;
                         });

} // namespace
} // namespace drape

// The disc's rim lattice (disc_lattice.hpp): the SIMD kernel finds the same lattice point as its scalar reference, bit
// for bit, on triangles across the rim, on the top face, inside and far off, at every lattice size it is used with.
TEST(TriangleContact, DiscLatticeSimdMatchesTheScalarReference) {
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> around(-0.03f, 0.03f), size(0.001f, 0.04f);
    int cases = 0;
    for (int k = 0; k < 3000; ++k) {
        const float R = 0.09f, h = 0.02f;
        // A vertex near the rim (r = R, y = 0) and edges of up to 4 cm in any direction.
        const float angle = 6.2831853f * float(k) / 3000.0f;
        drape::disc_lattice::Triangle t{R * std::cos(angle) + around(rng), 0.3f * around(rng), R * std::sin(angle) + around(rng),
                                 size(rng) * (around(rng) > 0 ? 1.0f : -1.0f), 0.5f * around(rng), around(rng),
                                 around(rng), 0.5f * around(rng), size(rng) * (around(rng) > 0 ? 1.0f : -1.0f), R, h};
        if (k % 7 == 0) t.ay -= 0.03f; // some deep below the top face, inside or beside the cylinder
        for (int m : {4, 5, 13, 16, 17, 31, 48}) {
            const std::array<int, 2> simd = drape::disc_lattice::minimum(t, m),
                                     scalar = drape::disc_lattice::minimum_scalar(t, m);
            ASSERT_EQ(simd, scalar) << "triangle " << k << ", m " << m;
            ++cases;
        }
    }
    EXPECT_EQ(cases, 3000 * 7);
}
