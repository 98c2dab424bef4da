// Orbit camera: rotates around a target point (yaw about +y, pitch above the horizon), pans the target in the
// view plane and zooms by changing the distance. Matrices follow OpenGL conventions (right-handed world, y
// up, clip depth -1..1), the same ones core's picking (drape/picking.hpp) unprojects with.
#pragma once

#include <Eigen/Core>

namespace drape::render {

struct OrbitCamera {
    Eigen::Vector3f target = Eigen::Vector3f::Zero(); ///< m, the point orbited
    float yaw = 0.0f;                                 ///< rad about +y; 0 looks from +z towards -z
    float pitch = 0.0f;                               ///< rad above the horizon, clamped to +-(pi/2 - 0.01)
    float distance = 3.0f;   ///< m from the target, clamped to [min_distance, max_distance]
    float fov_y_deg = 45.0f; ///< vertical field of view, degrees, [20, 90]

    static constexpr float min_distance = 0.02f;
    static constexpr float max_distance = 500.0f;

    Eigen::Vector3f eye() const;
    /// Unit viewing direction (eye towards target).
    Eigen::Vector3f forward() const;
    Eigen::Vector3f right() const;
    Eigen::Vector3f up() const;

    Eigen::Matrix4f view() const;
    /// Perspective for a viewport of width/height `aspect`; near and far planes follow the distance.
    Eigen::Matrix4f projection(float aspect) const;

    /// Height of the view at the target's distance, m (the viewport's height in metres there).
    float visible_height() const;
    /// Adds to yaw and pitch (rad).
    void orbit(float d_yaw, float d_pitch);
    /// Moves the target in the view plane by fractions of the visible height at the target (dx right, dy up).
    void pan(float dx, float dy);
    /// Multiplies the distance by `factor` (< 1 moves closer).
    void zoom(float factor);
    /// Places the target at the centre of the box [lo, hi] and backs off until the whole box is in view for
    /// the given aspect, keeping yaw, pitch and field of view.
    void frame(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, float aspect);
};

/// OpenGL gluLookAt / gluPerspective equivalents.
Eigen::Matrix4f look_at(const Eigen::Vector3f& eye, const Eigen::Vector3f& target, const Eigen::Vector3f& up);
Eigen::Matrix4f perspective(float fov_y_rad, float aspect, float near_plane, float far_plane);

} // namespace drape::render
