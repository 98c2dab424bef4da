// Contact of cloth triangles with analytic colliders (docs/collisions.md).
//
// The collide stage projects particles out of every collider (colliders.hpp). That alone lets a triangle pass
// through a collider whose vertices all lie outside it: a 2 x 2 cloth falls through a sphere, a coarse sleeve cuts
// through an arm. This module finds, for one triangle and one collider, the triangle's deepest point inside the
// collider's inflated solid (the solid grown by its thickness), so the stage can push the whole triangle out there.
//
// Every inflated solid is convex, so "how deep is a point" is a convex function f on the triangle and its minimum is
// found without sampling:
//   - sphere: f = |p - c| - (r + t); the minimum is the triangle's closest point to c (exact, Ericson 2005 5.1.5);
//   - ellipsoid: in its frame scaled by 1 / (semi-axes + t) the inflated ellipsoid is the unit ball and the triangle
//     stays a triangle (an affine map), so the deepest point (in that scaled measure) is again a closest point to the
//     centre (exact);
//   - capsule: the triangle's closest point to the axis segment (exact: the segment's ends against the triangle,
//     the triangle's edges against the segment, the segment through the triangle);
//   - disc (a solid cylinder): exact where the triangle lies in one region of the distance - above the top face
//     within the radius (linear: a vertex), or between the faces (the horizontal distance to the axis: a closest
//     point in 2D); a triangle across a rim is searched on a lattice with points about one margin apart, which
//     finds the deepest point to a second-order error, ~10% of the margin;
//   - plane: f is linear, its minimum is at a vertex, which the particle pass already keeps out: never a contact.
// Cheap rejections first: f is 1-Lipschitz for the signed distances, so a triangle whose centroid is farther from the
// surface than the triangle's radius cannot touch; an ellipsoid is bounded by the sphere of its largest semi-axis.
// A contact is then the collider's own projection of the deepest point (project_point: the surface point, its
// outward normal), so a triangle and a particle at the same place get the same answer.
#pragma once

#include <array>

#include "drape/colliders.hpp"

namespace drape {

/// The deepest point of a triangle inside one collider's inflated solid.
struct TriangleContact {
    bool inside = false;                ///< some point of the triangle is inside the inflated solid
    std::array<float, 3> barycentric{}; ///< the deepest point = b0 a + b1 b + b2 c
    Vec3f point{};                      ///< that point, m
    Vec3f surface{};                    ///< where the collider's projection puts it (on the inflated surface), m
    Vec3f normal{};                     ///< outward unit normal there
    float depth = 0.0f;                 ///< (surface - point) . normal, m, > 0 when inside
};

/// The deepest point of triangle (a, b, c) in the collider (grown by its thickness), and its projection. The
/// collider must be valid (check_collider). A plane collider never reports a triangle contact (its vertices decide).
TriangleContact triangle_contact(const Collider& collider, Vec3f a, Vec3f b, Vec3f c) noexcept;

/// Squared radius of the smallest ball holding triangle (a, b, c): (longest edge / 2)^2 for a right or obtuse
/// triangle, else the circumradius squared.
float enclosing_radius2(Vec3f a, Vec3f b, Vec3f c) noexcept;

/// What triangle_clear_of needs of one vertex, computed once per particle and collider: the squared distance to the
/// core (sphere: the centre; capsule: the axis segment), the squared level sum (q_i / A_i)^2 (ellipsoid), or
/// the signed distance to the inflated solid (disc; plane: unused).
float core_measure(const Collider& collider, Vec3f p) noexcept;
/// A lower bound on the distance from a point with this core_measure to the collider's inflated solid (m; <= 0 inside
/// it): exact for sphere, capsule and disc; for an ellipsoid with inflated semi-axes A, min A (sqrt(measure) - 1). The
/// distance is 1-Lipschitz, so no point of a triangle whose vertex has bound c is within c - (longest edge) of the
/// solid: the triangle pass rejects most triangles with it before any search.
float clearance_from_measure(const Collider& collider, float measure) noexcept;

/// True when a triangle whose vertices have core measures m0, m1, m2 and which lies inside a ball of squared radius
/// `radius2` (enclosing_radius2) provably has no point inside the collider's inflated solid. A sphere, capsule or
/// (scaled) ellipsoid is a core K (centre, axis segment, centre) grown by a radius rho; the point p* of the triangle
/// nearest K is a convex combination sum l_i v_i, and for the point k of K nearest p*, |p* - k|^2 =
/// sum l_i |v_i - k|^2 - sum l_i |v_i - p*|^2 >= min_i dist(v_i, K)^2 - radius2 (the spread of points about their
/// mean is at most about any centre). So a triangle is clear when min_i dist(v_i, K)^2 - radius2 >= rho^2: cloth
/// resting on a sphere of radius R needs its vertices only ~L^2 / (8 R) off the surface to be skipped. A disc, whose
/// core is the solid cylinder, uses the 1-Lipschitz bound (clear when a vertex is farther than the triangle's
/// diameter). A plane is always clear (its vertices decide).
bool triangle_clear_of(const Collider& collider, float m0, float m1, float m2, float radius2) noexcept;

/// Whether triangle (a, b, c) meets the collider's solid grown by `margin` (m; 0 = the solid itself, negative = shrunk)
/// - the tests' check that no triangle passes into a collider. Every kind, the plane included (its vertices).
bool triangle_meets_collider(const Collider& collider, Vec3f a, Vec3f b, Vec3f c, float margin = 0.0f) noexcept;

} // namespace drape
