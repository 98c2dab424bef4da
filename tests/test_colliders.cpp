// Analytic colliders: no particle left inside, outside and pinned particles untouched, velocity response,
// validation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "drape/colliders.hpp"
#include "drape/errors.hpp"

namespace drape {
namespace {

constexpr float slack = 1e-5f; // m: float rounding of a projected point

struct Cloud {
    std::vector<float> x, y, z, vx, vy, vz, inv_mass;
    std::size_t size() const { return x.size(); }
};

// Random points in a box around `centre`, random velocities, every 7th pinned.
Cloud random_cloud(unsigned seed, Vec3f centre, float half, std::size_t n = 4000) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    Cloud c;
    for (std::size_t i = 0; i < n; ++i) {
        c.x.push_back(centre[0] + half * u(rng));
        c.y.push_back(centre[1] + half * u(rng));
        c.z.push_back(centre[2] + half * u(rng));
        c.vx.push_back(u(rng));
        c.vy.push_back(u(rng));
        c.vz.push_back(u(rng));
        c.inv_mass.push_back(i % 7 == 3 ? 0.0f : 100.0f);
    }
    return c;
}

std::vector<Collider> sample_colliders(ColliderSurface s) {
    return {
        make_ground(0.1f, s),
        make_plane({0.1f, 0.2f, 0.3f}, {1.0f, 2.0f, -0.5f}, s),
        make_sphere({0.1f, 0.2f, -0.1f}, 0.3f, s),
        make_disc({0.0f, 0.1f, 0.0f}, 0.4f, 0.02f, s),
        make_capsule({-0.3f, 0.0f, 0.1f}, {0.3f, 0.2f, -0.1f}, 0.15f, s),
        make_capsule({0.0f, 0.0f, 0.0f}, {0.0f, 0.0f, 0.0f}, 0.2f, s), // degenerate: a sphere
        make_ellipsoid({0.0f, 0.1f, 0.0f}, {0.4f, 0.1f, 0.2f}, s),
        make_ellipsoid({0.05f, 0.0f, 0.0f}, {0.5f, 0.05f, 0.05f}, s, rotation_about_axis({1, 1, 0}, 0.7f)),
        make_ellipsoid({0.0f, 0.0f, 0.0f}, {0.2f, 0.2f, 0.2f}, s), // a sphere as an ellipsoid
    };
}

TEST(Collider, NoPointLeftInsideOutsidePointsAndPinnedUntouched) {
    for (ColliderSurface s :
         {ColliderSurface{0.0f, 0.0f}, ColliderSurface{0.01f, 0.4f}, ColliderSurface{0.05f, 1.0f}}) {
        unsigned seed = 1;
        for (const Collider& col : sample_colliders(s)) {
            SCOPED_TRACE(std::string(collider_kind_name(col.kind)) + " thickness " +
                         std::to_string(s.thickness));
            const Cloud before = random_cloud(seed++, {0.0f, 0.1f, 0.0f}, 0.6f, 40000);
            Cloud c = before;
            collide_range(col, c.x.data(), c.y.data(), c.z.data(), c.vx.data(), c.vy.data(), c.vz.data(),
                          c.inv_mass.data(), 0, c.size());
            std::size_t inside_before = 0, moved = 0;
            for (std::size_t i = 0; i < c.size(); ++i) {
                const Vec3f p0{before.x[i], before.y[i], before.z[i]};
                const Vec3f p1{c.x[i], c.y[i], c.z[i]};
                const bool was_inside = is_inside(col, p0);
                inside_before += was_inside;
                const bool same = std::memcmp(&p0, &p1, sizeof p0) == 0 && c.vx[i] == before.vx[i] &&
                                  c.vy[i] == before.vy[i] && c.vz[i] == before.vz[i];
                if (before.inv_mass[i] == 0.0f) {
                    EXPECT_TRUE(same) << "pinned particle " << i << " moved";
                    continue;
                }
                if (!was_inside) {
                    EXPECT_TRUE(same) << "outside particle " << i << " was touched";
                }
                EXPECT_FALSE(is_inside(col, p1, slack)) << "particle " << i << " left inside";
                moved += !same;
                // The normal velocity after the response is not inward.
                if (was_inside) {
                    const Contact k = project_point(col, p0);
                    EXPECT_GE(c.vx[i] * k.normal[0] + c.vy[i] * k.normal[1] + c.vz[i] * k.normal[2], -1e-5f);
                }
            }
            EXPECT_GT(inside_before, 20u) << "the test cloud should hit the collider";
            EXPECT_GT(moved, 0u);
        }
    }
}

TEST(Collider, ProjectionIsTheNearestSurfacePointForExactKinds) {
    // Sphere: radial; plane: straight up; disc: through the nearest face.
    const Collider sphere = make_sphere({1, 2, 3}, 0.5f, {0.01f, 0});
    Contact c = project_point(sphere, {1.1f, 2.0f, 3.0f});
    ASSERT_TRUE(c.inside);
    EXPECT_NEAR(c.point[0], 1.51f, 1e-6f);
    EXPECT_NEAR(c.normal[0], 1.0f, 1e-6f);
    const Collider ground = make_ground(-0.5f, {0.002f, 0});
    c = project_point(ground, {0.3f, -0.6f, 0.7f});
    ASSERT_TRUE(c.inside);
    EXPECT_EQ(c.point[0], 0.3f);
    EXPECT_EQ(c.point[1], -0.498f);
    EXPECT_EQ(c.point[2], 0.7f);
    EXPECT_FALSE(project_point(ground, {0.0f, -0.497f, 0.0f}).inside);
    const Collider disc = make_disc({0, 1, 0}, 0.5f, 0.02f, {0.01f, 0});
    c = project_point(disc, {0.2f, 0.995f, 0.0f}); // inside the slab, near the top
    ASSERT_TRUE(c.inside);
    EXPECT_NEAR(c.point[1], 1.01f, 1e-6f);
    EXPECT_EQ(c.normal[1], 1.0f);
    c = project_point(disc, {0.505f, 1.005f, 0.0f}); // near the rim: rounded
    ASSERT_TRUE(c.inside);
    EXPECT_NEAR(std::hypot(c.point[0] - 0.5f, c.point[1] - 1.0f), 0.01f, 1e-6f);
    EXPECT_FALSE(project_point(disc, {0.52f, 1.0f, 0.0f}).inside);
    EXPECT_FALSE(project_point(disc, {0.0f, 0.9f, 0.0f}).inside); // below the thin table
    const Collider cap = make_capsule({0, 0, 0}, {1, 0, 0}, 0.1f, {0.0f, 0});
    c = project_point(cap, {0.5f, 0.05f, 0.0f});
    ASSERT_TRUE(c.inside);
    EXPECT_NEAR(c.point[1], 0.1f, 1e-6f);
    EXPECT_NEAR(c.point[0], 0.5f, 1e-6f);
}

TEST(Collider, EllipsoidClosestPointMatchesBruteForce) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (Vec3f axes : {Vec3f{0.22f, 0.045f, 0.045f}, Vec3f{0.16f, 0.30f, 0.10f}, Vec3f{0.3f, 0.3f, 0.3f}}) {
        // Dense surface samples for the brute-force nearest point.
        std::vector<Vec3f> surface;
        const int m = 400;
        for (int i = 0; i <= m; ++i)
            for (int j = 0; j < 2 * m; ++j) {
                const double th = M_PI * i / m, ph = M_PI * j / m;
                surface.push_back({static_cast<float>(axes[0] * std::sin(th) * std::cos(ph)),
                                   static_cast<float>(axes[1] * std::sin(th) * std::sin(ph)),
                                   static_cast<float>(axes[2] * std::cos(th))});
            }
        for (int k = 0; k < 60; ++k) {
            Vec3f q;
            do {
                q = {static_cast<float>(axes[0] * u(rng)), static_cast<float>(axes[1] * u(rng)),
                     static_cast<float>(axes[2] * u(rng))};
            } while ((q[0] / axes[0]) * (q[0] / axes[0]) + (q[1] / axes[1]) * (q[1] / axes[1]) +
                         (q[2] / axes[2]) * (q[2] / axes[2]) >=
                     1.0f);
            const Vec3f x = ellipsoid_closest_point(axes, q);
            const float f = (x[0] / axes[0]) * (x[0] / axes[0]) + (x[1] / axes[1]) * (x[1] / axes[1]) +
                            (x[2] / axes[2]) * (x[2] / axes[2]);
            EXPECT_GE(f, 1.0f);
            EXPECT_LT(f, 1.0f + 1e-5f);
            const double d = std::hypot(double{x[0]} - q[0], double{x[1]} - q[1], double{x[2]} - q[2]);
            double best = 1e9;
            for (const Vec3f& s : surface)
                best =
                    std::min(best, std::hypot(double{s[0]} - q[0], double{s[1]} - q[1], double{s[2]} - q[2]));
            // The brute force is on a sampled surface: it can only be farther than the true closest point.
            EXPECT_LE(d, best + 1e-5) << "point " << q[0] << " " << q[1] << " " << q[2];
            // Closest-point condition: q - x is along the surface normal at x.
            const double n[3] = {x[0] / (axes[0] * axes[0]), x[1] / (axes[1] * axes[1]),
                                 x[2] / (axes[2] * axes[2])};
            const double r[3] = {double{q[0]} - x[0], double{q[1]} - x[1], double{q[2]} - x[2]};
            const double c[3] = {r[1] * n[2] - r[2] * n[1], r[2] * n[0] - r[0] * n[2],
                                 r[0] * n[1] - r[1] * n[0]};
            const double nn = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            EXPECT_LT(std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / nn, 1e-3 * d + 1e-6);
        }
    }
    // The centre: out along the shortest axis.
    const Vec3f x = ellipsoid_closest_point({0.3f, 0.1f, 0.2f}, {0.0f, 0.0f, 0.0f});
    EXPECT_NEAR(std::abs(x[1]), 0.1f, 1e-6f);
}

namespace {
/// The root s of sum (a_i q_i / (a_i^2 + s))^2 = 1 by 200 bisections in long double, and the closest point it gives
/// after the same radial snap as ellipsoid_closest_point.
struct ExactEllipsoidRoot {
    long double s;
    Vec3f x;
};
ExactEllipsoidRoot exact_ellipsoid_root(Vec3f axes, Vec3f q) {
    const long double a[3] = {axes[0], axes[1], axes[2]};
    const long double amin = std::min({a[0], a[1], a[2]});
    long double lo = -amin * amin, hi = 0.0L;
    for (int it = 0; it < 200; ++it) {
        const long double s = 0.5L * (lo + hi);
        long double S = 0.0L;
        for (int c = 0; c < 3; ++c) {
            const long double r = a[c] * q[c] / (a[c] * a[c] + s);
            S += r * r;
        }
        (S > 1.0L ? lo : hi) = s;
    }
    const long double s = 0.5L * (lo + hi);
    long double x[3], gx = 0.0L;
    for (int c = 0; c < 3; ++c) {
        x[c] = a[c] * a[c] * q[c] / (a[c] * a[c] + s);
        gx += (x[c] / a[c]) * (x[c] / a[c]);
    }
    return {s, {float(x[0] / std::sqrt(gx)), float(x[1] / std::sqrt(gx)), float(x[2] / std::sqrt(gx))}};
}

/// Calls f(axes, q) for points from the centre to 1e-6 under the surface (a direction, then a radius fraction
/// 1 - 10^depth of the way to the surface along it; a quarter uniform), on the three body shapes and a sphere.
template <class F> void for_points_inside_ellipsoids(F&& f) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-1.0, 1.0), depth(-6.0, 0.0);
    for (Vec3f axes : {Vec3f{0.22f, 0.045f, 0.045f}, Vec3f{0.16f, 0.30f, 0.10f}, Vec3f{0.19f, 0.06f, 0.08f},
                       Vec3f{0.3f, 0.3f, 0.3f}}) {
        const double a[3] = {axes[0], axes[1], axes[2]};
        for (int k = 0; k < 2000; ++k) {
            double d[3] = {u(rng), u(rng), u(rng)};
            const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (len < 1e-3) continue;
            const double frac = k % 4 == 0 ? 0.5 * (u(rng) + 1.0) : 1.0 - std::pow(10.0, depth(rng));
            double g = 0.0;
            for (int c = 0; c < 3; ++c)
                g += (d[c] / len / a[c]) * (d[c] / len / a[c]);
            const Vec3f q{float(frac * d[0] / len / std::sqrt(g)), float(frac * d[1] / len / std::sqrt(g)),
                          float(frac * d[2] / len / std::sqrt(g))};
            if ((q[0] / axes[0]) * (q[0] / axes[0]) + (q[1] / axes[1]) * (q[1] / axes[1]) +
                    (q[2] / axes[2]) * (q[2] / axes[2]) >= 1.0f ||
                std::min({std::abs(q[0]), std::abs(q[1]), std::abs(q[2])}) < 1e-6f)
                continue;
            f(axes, q);
        }
    }
}
} // namespace

// The Newton iteration stops early (a step under 1e-6 min a^2: quadratic convergence leaves ~1e-12 of the root),
// so it is checked against the root itself (exact_ellipsoid_root).
TEST(Collider, EllipsoidClosestPointMatchesTheExactRootToFloatRounding) {
    for_points_inside_ellipsoids([](Vec3f axes, Vec3f q) {
        const Vec3f want = exact_ellipsoid_root(axes, q).x;
        const Vec3f got = ellipsoid_closest_point(axes, q);
        const float amax = std::max({axes[0], axes[1], axes[2]});
        for (int c = 0; c < 3; ++c)
            ASSERT_NEAR(got[c], want[c], 4e-7 * amax) << "axes " << axes[0] << " " << axes[1] << " " << axes[2]
                                                      << ", point " << q[0] << " " << q[1] << " " << q[2]
                                                      << ", component " << c;
    });
}

// The warm start (the implicit solver's triangle terms pass each triangle's root from one corner's projection to
// the next): from the root itself, from 1 % and 50 % off it, from anywhere in the bracket and from outside it (then
// ignored), the same closest point as the exact root's, and the root handed back.
TEST(Collider, EllipsoidClosestPointFromAnyWarmStartFindsTheSameRoot) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.2, 0.2);
    for_points_inside_ellipsoids([&](Vec3f axes, Vec3f q) {
        const ExactEllipsoidRoot exact = exact_ellipsoid_root(axes, q);
        const float amin = std::min({axes[0], axes[1], axes[2]});
        const float amax = std::max({axes[0], axes[1], axes[2]});
        const float amin2 = amin * amin;
        const float root = float(exact.s);
        for (float start : {root, 1.01f * root, 0.99f * root, 1.5f * root, 0.5f * root, float(u(rng)) * amin2,
                            -2.0f * amin2, 0.1f * amin2, 0.0f}) {
            float s = start;
            const Vec3f got = ellipsoid_closest_point(axes, q, &s);
            for (int c = 0; c < 3; ++c)
                ASSERT_NEAR(got[c], exact.x[c], 4e-7 * amax)
                    << "axes " << axes[0] << " " << axes[1] << " " << axes[2] << ", point " << q[0] << " " << q[1]
                    << " " << q[2] << ", component " << c << ", start " << start;
            ASSERT_NEAR(s, root, 1e-5f * amin2) << "start " << start;
        }
    });
}

// segment_entry: spheres and ellipsoids by their quadratic, checked against a 60-halving bisection in double of the
// same inside test, and the normal against the one projecting a point just inside gives.
TEST(Collider, SegmentEntryIsTheFirstCrossing) {
    const ColliderSurface s{0.004f, 0.3f};
    const std::vector<Collider> round = {
        make_sphere({0.1f, 0.2f, -0.1f}, 0.25f, s),
        make_ellipsoid({0.0f, 0.1f, 0.0f}, {0.16f, 0.30f, 0.10f}, s),
        make_ellipsoid({-0.2f, 0.0f, 0.3f}, {0.22f, 0.045f, 0.07f}, s, rotation_about_axis({1.0f, 2.0f, 0.5f}, 0.7f)),
    };
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (const Collider& c : round) {
        int checked = 0;
        for (int k = 0; k < 200000 && checked < 300; ++k) {
            const float reach = 0.3f; // p1 in the box around the collider, p0 a sweep's move or a long one away
            const Vec3f p1{c.centre[0] + reach * u(rng), c.centre[1] + reach * u(rng), c.centre[2] + reach * u(rng)};
            const float step = k % 2 ? 0.01f : 0.3f;
            const Vec3f p0{p1[0] + step * u(rng), p1[1] + step * u(rng), p1[2] + step * u(rng)};
            if (is_inside(c, p0) || !is_inside(c, p1)) continue;
            ++checked;
            const Contact e = segment_entry(c, p0, p1);
            ASSERT_TRUE(e.inside);
            double lo = 0.0, hi = 1.0;
            for (int it = 0; it < 60; ++it) {
                const double mid = 0.5 * (lo + hi);
                const Vec3f q{static_cast<float>(p0[0] + mid * (double(p1[0]) - p0[0])),
                              static_cast<float>(p0[1] + mid * (double(p1[1]) - p0[1])),
                              static_cast<float>(p0[2] + mid * (double(p1[2]) - p0[2]))};
                (is_inside(c, q) ? hi : lo) = mid;
            }
            for (int j = 0; j < 3; ++j)
                EXPECT_NEAR(e.point[j], p0[j] + hi * (double(p1[j]) - p0[j]), 2e-6) << collider_kind_name(c.kind);
            const Contact proj = project_point(c, {static_cast<float>(p0[0] + hi * (double(p1[0]) - p0[0])),
                                                   static_cast<float>(p0[1] + hi * (double(p1[1]) - p0[1])),
                                                   static_cast<float>(p0[2] + hi * (double(p1[2]) - p0[2]))});
            if (!proj.inside) continue; // the bisection's last point rounded onto the surface
            for (int j = 0; j < 3; ++j)
                EXPECT_NEAR(e.normal[j], proj.normal[j], 1e-3) << collider_kind_name(c.kind);
        }
        EXPECT_EQ(checked, 300) << collider_kind_name(c.kind);
    }
    // Not entering (p0 inside as well): the projection of p1.
    const Collider& c = round[0];
    const Contact e = segment_entry(c, c.centre, {c.centre[0] + 0.01f, c.centre[1], c.centre[2]});
    const Contact p = project_point(c, {c.centre[0] + 0.01f, c.centre[1], c.centre[2]});
    EXPECT_EQ(e.point, p.point);
    EXPECT_EQ(e.normal, p.normal);
}

TEST(Collider, VelocityResponseAndFriction) {
    const Collider frictionless = make_ground(0.0f, {0.01f, 0.0f});
    float x = 0.1f, y = -0.02f, z = 0.0f, vx = 2.0f, vy = -3.0f, vz = 0.5f, w = 1.0f;
    collide_range(frictionless, &x, &y, &z, &vx, &vy, &vz, &w, 0, 1);
    EXPECT_EQ(y, 0.01f);
    EXPECT_EQ(x, 0.1f);
    EXPECT_EQ(vx, 2.0f); // tangential kept
    EXPECT_EQ(vz, 0.5f);
    EXPECT_EQ(vy, 0.0f); // inward normal removed
    // Coulomb: tangential speed reduced by mu |vn|, never reversed.
    const Collider sticky = make_ground(0.0f, {0.01f, 0.5f});
    x = 0.0f, y = 0.0f, z = 0.0f, vx = 2.0f, vy = -1.0f, vz = 0.0f;
    collide_range(sticky, &x, &y, &z, &vx, &vy, &vz, &w, 0, 1);
    EXPECT_NEAR(vx, 1.5f, 1e-6f);
    EXPECT_EQ(vy, 0.0f);
    vx = 0.1f, vy = -1.0f, y = 0.0f;
    collide_range(sticky, &x, &y, &z, &vx, &vy, &vz, &w, 0, 1);
    EXPECT_EQ(vx, 0.0f);
    // Moving away: velocity untouched, position still pushed out.
    vx = 1.0f, vy = 2.0f, y = 0.0f;
    collide_range(sticky, &x, &y, &z, &vx, &vy, &vz, &w, 0, 1);
    EXPECT_EQ(y, 0.01f);
    EXPECT_EQ(vx, 1.0f);
    EXPECT_EQ(vy, 2.0f);
    // Frictionless sphere: tangential velocity kept exactly in direction and size.
    const Collider ball = make_sphere({0, 0, 0}, 1.0f, {0.0f, 0.0f});
    x = 0.0f, y = 0.9f, z = 0.0f, vx = 0.7f, vy = -2.0f, vz = -0.3f;
    collide_range(ball, &x, &y, &z, &vx, &vy, &vz, &w, 0, 1);
    EXPECT_EQ(vx, 0.7f);
    EXPECT_EQ(vz, -0.3f);
    EXPECT_EQ(vy, 0.0f);
}

TEST(Collider, DefaultBodyLeavesNoPointInside) {
    const auto body = default_body();
    ASSERT_EQ(body.size(), 7u);
    // Points in a shell around the body (the way cloth meets it) and deep inside.
    Cloud c = random_cloud(5, {0.0f, 0.0f, 0.0f}, 0.65f, 50000);
    const Cloud before = c;
    collide_range(std::span<const Collider>(body), c.x.data(), c.y.data(), c.z.data(), c.vx.data(),
                  c.vy.data(), c.vz.data(), c.inv_mass.data(), 0, c.size());
    std::size_t inside_before = 0, inside_after = 0;
    for (std::size_t i = 0; i < c.size(); ++i) {
        bool was = false, is = false;
        for (const Collider& col : body) {
            was = was || is_inside(col, {before.x[i], before.y[i], before.z[i]});
            is = is || is_inside(col, {c.x[i], c.y[i], c.z[i]}, slack);
        }
        if (before.inv_mass[i] == 0.0f) continue;
        inside_before += was;
        inside_after += is;
        if (!was) {
            EXPECT_EQ(c.x[i], before.x[i]);
        }
    }
    std::printf("default body: %zu of %zu random points inside before, %zu after\n", inside_before, c.size(),
                inside_after);
    EXPECT_GT(inside_before, 500u);
    EXPECT_EQ(inside_after, 0u);
}

TEST(Collider, RejectsBadParametersNamingTheField) {
    auto msg = [](auto&& f) -> std::string {
        try {
            f();
        } catch (const InvalidInput& e) {
            return e.what();
        }
        return "";
    };
    EXPECT_NE(msg([] {
                  make_sphere({0, 0, 0}, 0.0f);
              }).find("sphere.radius = 0 m is outside the allowed range (0, 1000]"),
              std::string::npos);
    EXPECT_NE(msg([] { make_sphere({0, 0, 0}, 2000.0f); }).find("(0, 1000]"), std::string::npos);
    EXPECT_NE(msg([] { make_sphere({0, 0, 0}, NAN); }).find("sphere.radius = nan m"), std::string::npos);
    EXPECT_NE(msg([] {
                  make_sphere({0, 0, 0}, 1.0f, {-0.1f, 0.2f});
              }).find("sphere.thickness"),
              std::string::npos);
    EXPECT_NE(msg([] {
                  make_sphere({0, 0, 0}, 1.0f, {0.1f, 1.5f});
              }).find("[0, 1]"),
              std::string::npos);
    EXPECT_NE(msg([] { make_disc({0, 0, 0}, 1.0f, 0.0f); }).find("disc.height"), std::string::npos);
    EXPECT_NE(msg([] {
                  make_capsule({0, 0, 0}, {1, 0, 0}, -1.0f);
              }).find("capsule.radius"),
              std::string::npos);
    EXPECT_NE(msg([] {
                  make_ellipsoid({0, 0, 0}, {1, 0, 1});
              }).find("ellipsoid.semi_axes[1]"),
              std::string::npos);
    EXPECT_NE(msg([] {
                  make_ellipsoid({0, 0, 0}, {1, 1, 1}, {}, {1, 0, 0, 0, 1, 0, 0, 0, -1});
              }).find("determinant"),
              std::string::npos);
    EXPECT_NE(msg([] {
                  make_ellipsoid({0, 0, 0}, {1, 1, 1}, {}, {1, 0, 0, 0, 2, 0, 0, 0, 1});
              }).find("orthonormal"),
              std::string::npos);
    EXPECT_NE(msg([] { make_plane({0, 0, 0}, {0, 0, 0}); }).find("plane.normal"), std::string::npos);
    EXPECT_NE(msg([] { make_sphere({NAN, 0, 0}, 1.0f); }).find("sphere.centre[0]"), std::string::npos);
    EXPECT_NE(msg([] { make_ground(NAN); }).find("ground.height"), std::string::npos);
}

} // namespace
} // namespace drape
