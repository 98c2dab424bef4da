// Mouse picking (seed 004, section 3): a ray from the camera through the cursor, tested against every
// particle as a small sphere; the nearest hit along the ray wins. The grabbed particle then follows the
// cursor at the depth it was picked at (a plane facing the camera). Pure geometry on spans of positions: no
// window, unit-tested in tests/test_picking.cpp.
//
// Conventions are OpenGL's: normalized device coordinates in [-1, 1], y up, z = -1 on the near plane and +1
// on the far plane; the inverse view-projection matrix maps clip space back to world space (m).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include <Eigen/Core>

namespace drape {

/// A half-line: origin + t * direction for t >= 0. direction has unit length.
struct Ray {
    Eigen::Vector3f origin = Eigen::Vector3f::Zero();
    Eigen::Vector3f direction = Eigen::Vector3f::UnitZ();
};

/// Normalized device coordinates of a window position in pixels (origin top-left, y down, as GLFW reports the
/// cursor); width and height in the same units.
Eigen::Vector2f window_to_ndc(double px, double py, double width, double height) noexcept;

/// The ray through NDC point (ndc_x, ndc_y): from its point on the near plane towards its point on the far
/// plane. Works for perspective and orthographic projections.
Ray ray_from_ndc(const Eigen::Matrix4f& inverse_view_projection, float ndc_x, float ndc_y);

inline constexpr std::size_t no_particle = std::numeric_limits<std::size_t>::max();

struct PickHit {
    std::size_t index = no_particle; ///< particle hit, or no_particle
    float distance =
        std::numeric_limits<float>::infinity(); ///< m along the ray to the sphere's surface (0 inside)
    bool hit() const noexcept { return index != no_particle; }
};

/// Tests every particle as a sphere of `radius` (m) around its position; returns the hit nearest the ray
/// origin (ties: the lower index). Spheres entirely behind the origin are missed. Parallel over fixed blocks
/// with oneTBB; the result does not depend on the thread count.
PickHit pick_particle(const Ray& ray, std::span<const float> x, std::span<const float> y,
                      std::span<const float> z, float radius);

/// Depth of `point` along the camera's unit viewing direction `forward`, measured from `eye` (m).
float view_depth(const Eigen::Vector3f& point, const Eigen::Vector3f& eye,
                 const Eigen::Vector3f& forward) noexcept;

/// Where the ray meets the plane facing the camera at view depth `depth` from `eye`: the drag target of a
/// grabbed particle that keeps its depth. Falls back to the ray origin + depth * direction when the ray runs
/// parallel to the plane.
Eigen::Vector3f point_at_depth(const Ray& ray, const Eigen::Vector3f& eye, const Eigen::Vector3f& forward,
                               float depth) noexcept;

} // namespace drape
