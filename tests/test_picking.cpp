// Ray-sphere picking (core/src/picking.cpp) without a window: the nearest particle along the ray is hit,
// misses miss, particles behind the camera are never picked, rays unprojected from a real view-projection
// pass through what the camera sees at that pixel, and the drag target keeps the picked depth.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "drape/errors.hpp"
#include "drape/picking.hpp"
#include "drape/workers.hpp"

using namespace drape;

namespace {

struct Points {
    std::vector<float> x, y, z;
    void add(float a, float b, float c) {
        x.push_back(a);
        y.push_back(b);
        z.push_back(c);
    }
};

Ray ray(Eigen::Vector3f o, Eigen::Vector3f d) {
    return {o, d.normalized()};
}

// OpenGL-style look-at and perspective (the same formulas the viewer's camera uses).
Eigen::Matrix4f look_at(const Eigen::Vector3f& eye, const Eigen::Vector3f& target,
                        const Eigen::Vector3f& up) {
    const Eigen::Vector3f f = (target - eye).normalized(), s = f.cross(up).normalized(), u = s.cross(f);
    Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
    m.row(0).head<3>() = s;
    m.row(1).head<3>() = u;
    m.row(2).head<3>() = -f;
    m(0, 3) = -s.dot(eye);
    m(1, 3) = -u.dot(eye);
    m(2, 3) = f.dot(eye);
    return m;
}

Eigen::Matrix4f perspective(float fovy_rad, float aspect, float near, float far) {
    const float t = 1.0f / std::tan(0.5f * fovy_rad);
    Eigen::Matrix4f m = Eigen::Matrix4f::Zero();
    m(0, 0) = t / aspect;
    m(1, 1) = t;
    m(2, 2) = (far + near) / (near - far);
    m(2, 3) = 2.0f * far * near / (near - far);
    m(3, 2) = -1.0f;
    return m;
}

} // namespace

TEST(Picking, NearestHitAlongTheRayWins) {
    Points p;
    p.add(0.0f, 0.0f, -5.0f);  // 0: on the ray, far
    p.add(0.0f, 0.0f, -2.0f);  // 1: on the ray, nearest
    p.add(0.05f, 0.0f, -3.0f); // 2: grazed
    p.add(1.0f, 0.0f, -1.0f);  // 3: off the ray
    const PickHit h = pick_particle(ray({0, 0, 0}, {0, 0, -1}), p.x, p.y, p.z, 0.1f);
    ASSERT_TRUE(h.hit());
    EXPECT_EQ(h.index, 1u);
    EXPECT_NEAR(h.distance, 1.9f, 1e-6f); // surface of the sphere of radius 0.1 around z = -2
}

TEST(Picking, GrazingHitIsFoundAndOffRayIsMissed) {
    Points p;
    p.add(0.09f, 0.0f, -3.0f); // 0.09 m from the ray: inside radius 0.1
    p.add(0.11f, 0.0f, -1.0f); // 0.11 m from the ray: outside
    const PickHit h = pick_particle(ray({0, 0, 0}, {0, 0, -1}), p.x, p.y, p.z, 0.1f);
    ASSERT_TRUE(h.hit());
    EXPECT_EQ(h.index, 0u);
    const PickHit miss = pick_particle(ray({0, 0, 0}, {0, 1, 0}), p.x, p.y, p.z, 0.1f);
    EXPECT_FALSE(miss.hit());
    EXPECT_EQ(miss.index, no_particle);
}

TEST(Picking, ParticlesBehindTheCameraAreNeverPicked) {
    Points p;
    p.add(0.0f, 0.0f, 2.0f); // behind (the ray looks down -z)
    p.add(0.0f, 0.0f, 0.5f); // behind, close
    EXPECT_FALSE(pick_particle(ray({0, 0, 0}, {0, 0, -1}), p.x, p.y, p.z, 0.1f).hit());
    p.add(0.0f, 0.0f, -4.0f); // in front
    const PickHit h = pick_particle(ray({0, 0, 0}, {0, 0, -1}), p.x, p.y, p.z, 0.1f);
    ASSERT_TRUE(h.hit());
    EXPECT_EQ(h.index, 2u);
    // A sphere around the origin itself: the origin is inside it, distance 0.
    Points q;
    q.add(0.0f, 0.0f, 0.05f);
    const PickHit inside = pick_particle(ray({0, 0, 0}, {0, 0, -1}), q.x, q.y, q.z, 0.1f);
    ASSERT_TRUE(inside.hit());
    EXPECT_EQ(inside.distance, 0.0f);
}

TEST(Picking, TiesGoToTheLowerIndexAndResultIsThreadIndependent) {
    // 100,000 random particles (several picking blocks), two exact duplicates at the front.
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    Points p;
    for (int i = 0; i < 100000; ++i)
        p.add(u(rng), u(rng), -3.0f + u(rng));
    p.x[70000] = p.x[90000] = 0.001f;
    p.y[70000] = p.y[90000] = 0.0f;
    p.z[70000] = p.z[90000] = -1.5f;
    const Ray r = ray({0, 0, 0}, {0, 0, -1});
    PickHit one;
    {
        Workers workers(1);
        one = workers.run([&] { return pick_particle(r, p.x, p.y, p.z, 0.01f); });
    }
    ASSERT_TRUE(one.hit());
    EXPECT_EQ(one.index, 70000u);
    for (int t : {2, 3, 5, 8}) {
        Workers workers(t);
        const PickHit h = workers.run([&] { return pick_particle(r, p.x, p.y, p.z, 0.01f); });
        EXPECT_EQ(h.index, one.index);
        EXPECT_EQ(h.distance, one.distance);
    }
    // Brute force agrees.
    std::size_t best = no_particle;
    float best_t = INFINITY;
    for (std::size_t i = 0; i < p.x.size(); ++i) {
        const Eigen::Vector3f c(p.x[i], p.y[i], p.z[i]);
        const float tca = c.dot(r.direction);
        const float d2 = c.squaredNorm() - tca * tca;
        if (d2 > 1e-4f) continue;
        const float t = std::max(0.0f, tca - std::sqrt(1e-4f - d2));
        if (tca + std::sqrt(1e-4f - d2) >= 0.0f && t < best_t) best_t = t, best = i;
    }
    EXPECT_EQ(best, one.index);
}

TEST(Picking, EmptyAndNonFiniteInputs) {
    Points p;
    EXPECT_FALSE(pick_particle(ray({0, 0, 0}, {0, 0, -1}), p.x, p.y, p.z, 0.1f).hit());
    p.add(NAN, 0.0f, -1.0f);
    p.add(0.0f, 0.0f, -3.0f);
    const PickHit h = pick_particle(ray({0, 0, 0}, {0, 0, -1}), p.x, p.y, p.z, 0.1f);
    ASSERT_TRUE(h.hit());
    EXPECT_EQ(h.index, 1u); // the NaN particle is skipped, never picked
    EXPECT_THROW(pick_particle(ray({0, 0, 0}, {0, 0, -1}), p.x, p.y, p.z, 0.0f), InvalidInput);
}

TEST(Picking, UnprojectedRayPassesThroughWhatThePixelShows) {
    const Eigen::Vector3f eye(1.5f, 1.0f, 2.5f), target(0.0f, -0.4f, 0.0f);
    const Eigen::Matrix4f view = look_at(eye, target, Eigen::Vector3f::UnitY());
    const Eigen::Matrix4f proj = perspective(0.8f, 1.6f, 0.01f, 100.0f);
    const Eigen::Matrix4f vp = proj * view;
    const Eigen::Matrix4f inv = vp.inverse();

    // The centre pixel looks at the target.
    const Eigen::Vector2f centre = window_to_ndc(640.0, 400.0, 1280.0, 800.0);
    EXPECT_NEAR(centre.x(), 0.0f, 1e-6f);
    EXPECT_NEAR(centre.y(), 0.0f, 1e-6f);
    const Ray rc = ray_from_ndc(inv, centre.x(), centre.y());
    EXPECT_NEAR(rc.direction.norm(), 1.0f, 1e-5f);
    EXPECT_LT((rc.direction - (target - eye).normalized()).norm(), 1e-4f);
    // Top-left pixel -> NDC (-1, 1).
    const Eigen::Vector2f tl = window_to_ndc(0.0, 0.0, 1280.0, 800.0);
    EXPECT_EQ(tl.x(), -1.0f);
    EXPECT_EQ(tl.y(), 1.0f);

    // A particle projected to a pixel is picked by the ray through that pixel, and the particle next to it is
    // not.
    Points p;
    p.add(0.3f, -0.7f, 0.2f);
    p.add(0.3f, -0.7f, 0.5f);
    const Eigen::Vector4f clip = vp * Eigen::Vector4f(p.x[0], p.y[0], p.z[0], 1.0f);
    const Eigen::Vector2f ndc = clip.head<2>() / clip.w();
    const double px = (ndc.x() + 1.0) * 0.5 * 1280.0, py = (1.0 - ndc.y()) * 0.5 * 800.0;
    const Eigen::Vector2f back = window_to_ndc(px, py, 1280.0, 800.0);
    const Ray r = ray_from_ndc(inv, back.x(), back.y());
    const PickHit h = pick_particle(r, p.x, p.y, p.z, 0.02f);
    ASSERT_TRUE(h.hit());
    EXPECT_EQ(h.index, 0u);
    const float dist = (Eigen::Vector3f(p.x[0], p.y[0], p.z[0]) - r.origin).norm();
    EXPECT_NEAR(h.distance, dist - 0.02f, 1e-3f);
}

TEST(Picking, DragTargetKeepsThePickedDepth) {
    const Eigen::Vector3f eye(0.0f, 0.0f, 3.0f), forward(0.0f, 0.0f, -1.0f);
    const Eigen::Vector3f picked(0.2f, -0.1f, 0.5f);
    const float depth = view_depth(picked, eye, forward);
    EXPECT_NEAR(depth, 2.5f, 1e-6f);
    // A ray from the eye towards (1, 1, 0): the target lies on it, at the same depth.
    const Ray r = ray(eye, Eigen::Vector3f(1.0f, 1.0f, 0.0f) - eye);
    const Eigen::Vector3f t = point_at_depth(r, eye, forward, depth);
    EXPECT_NEAR(view_depth(t, eye, forward), depth, 1e-5f);
    EXPECT_LT(((t - r.origin).normalized() - r.direction).norm(), 1e-5f);
    EXPECT_NEAR(t.z(), 0.5f, 1e-5f);
    // The ray through the picked point itself returns the picked point.
    const Ray through = ray(eye, picked - eye);
    EXPECT_LT((point_at_depth(through, eye, forward, depth) - picked).norm(), 1e-5f);
}

TEST(Picking, SingularMatrixIsRejected) {
    EXPECT_THROW(ray_from_ndc(Eigen::Matrix4f::Zero(), 0.0f, 0.0f), InvalidInput);
}
