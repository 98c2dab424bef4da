#include "camera.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace drape::render {

namespace {
constexpr float pi = 3.14159265358979f;
constexpr float max_pitch = 0.5f * pi - 0.01f;
float radians(float deg) {
    return deg * pi / 180.0f;
}
} // namespace

Eigen::Matrix4f look_at(const Eigen::Vector3f& eye, const Eigen::Vector3f& target,
                        const Eigen::Vector3f& up) {
    const Eigen::Vector3f f = (target - eye).normalized();
    const Eigen::Vector3f s = f.cross(up).normalized();
    const Eigen::Vector3f u = s.cross(f);
    Eigen::Matrix4f m = Eigen::Matrix4f::Identity();
    m.block<1, 3>(0, 0) = s.transpose();
    m.block<1, 3>(1, 0) = u.transpose();
    m.block<1, 3>(2, 0) = -f.transpose();
    m(0, 3) = -s.dot(eye);
    m(1, 3) = -u.dot(eye);
    m(2, 3) = f.dot(eye);
    return m;
}

Eigen::Matrix4f perspective(float fov_y_rad, float aspect, float near_plane, float far_plane) {
    const float t = 1.0f / std::tan(0.5f * fov_y_rad);
    Eigen::Matrix4f m = Eigen::Matrix4f::Zero();
    m(0, 0) = t / aspect;
    m(1, 1) = t;
    m(2, 2) = (far_plane + near_plane) / (near_plane - far_plane);
    m(2, 3) = 2.0f * far_plane * near_plane / (near_plane - far_plane);
    m(3, 2) = -1.0f;
    return m;
}

Eigen::Vector3f OrbitCamera::eye() const {
    const float cp = std::cos(pitch);
    return target + distance * Eigen::Vector3f(cp * std::sin(yaw), std::sin(pitch), cp * std::cos(yaw));
}

Eigen::Vector3f OrbitCamera::forward() const {
    return (target - eye()).normalized();
}

Eigen::Vector3f OrbitCamera::right() const {
    return forward().cross(Eigen::Vector3f::UnitY()).normalized();
}

Eigen::Vector3f OrbitCamera::up() const {
    return right().cross(forward());
}

Eigen::Matrix4f OrbitCamera::view() const {
    return look_at(eye(), target, Eigen::Vector3f::UnitY());
}

Eigen::Matrix4f OrbitCamera::projection(float aspect) const {
    const float near_plane = std::max(0.001f, 0.01f * distance);
    const float far_plane = std::max(100.0f, 100.0f * distance);
    return perspective(radians(fov_y_deg), std::max(aspect, 1e-3f), near_plane, far_plane);
}

void OrbitCamera::orbit(float d_yaw, float d_pitch) {
    yaw = std::remainder(yaw + d_yaw, 2.0f * pi);
    pitch = std::clamp(pitch + d_pitch, -max_pitch, max_pitch);
}

float OrbitCamera::visible_height() const {
    return 2.0f * distance * std::tan(0.5f * radians(fov_y_deg));
}

void OrbitCamera::pan(float dx, float dy) {
    target += visible_height() * (dx * right() + dy * up());
}

void OrbitCamera::zoom(float factor) {
    distance = std::clamp(distance * factor, min_distance, max_distance);
}

void OrbitCamera::frame(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float aspect) {
    target = 0.5f * (lo + hi);
    const float radius = 0.5f * (hi - lo).norm();
    const float half_v = 0.5f * radians(fov_y_deg);
    const float half_h = std::atan(std::tan(half_v) * std::max(aspect, 1e-3f));
    const float half = std::min(half_v, half_h);
    distance = std::clamp(radius / std::sin(half), min_distance, max_distance);
}

} // namespace drape::render
