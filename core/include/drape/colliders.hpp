// Analytic colliders: ground plane, sphere (seed 004), horizontal disc / table (seed 001), capsule, ellipsoid
// and a body made of ellipsoids (seed 004). Pure functions; the collide stage of the substep calls
// collide_range().
//
// Every collider is a solid with a collision margin `thickness` (m): a point is "inside" when it is inside
// the solid or closer than `thickness` to it, and is then projected onto the inflated surface (the solid
// grown by thickness), along that surface's outward normal. Exact distances for plane, sphere, capsule and
// disc (the disc is a solid cylinder; grown by thickness it has rounded rims, which helps cloth drape over
// the edge). For an ellipsoid the inflated surface is the ellipsoid with semi-axes a + t, b + t, c + t (exact
// along the axes, up to ~t^2 / a closer to the true offset surface elsewhere), and the projection is that
// ellipsoid's closest point, found by bisection on the Lagrange parameter (D. Eberly, "Distance from a point
// to an ellipse, an ellipsoid, or a hyperellipsoid"; here safeguarded Newton), then snapped radially onto the
// surface (see ellipsoid_closest_point). Every projected point is then stepped out along the normal by 0.1
// um, doubling, until the kernel's own inside test agrees it is outside, so float rounding never leaves it
// inside and a second pass does not find it again.
//
// Batch kernel: particles in chunks of 64; per chunk and collider a branch-free pre-pass flags the particles
// inside (a plain loop over the SoA arrays), then only the flagged ones are projected.
//
// Velocity response (collide_range): for a point pushed out with normal n, the inward normal velocity v.n < 0
// is removed, and Coulomb friction takes mu |v.n| off the tangential speed (never reversing it); mu = 0 keeps
// the tangential velocity. Points outside are not touched (bitwise), nor are pinned ones (inverse mass 0).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace drape {

enum class ColliderKind : std::uint8_t { plane, sphere, disc, capsule, ellipsoid };
const char* collider_kind_name(ColliderKind kind) noexcept;

using Vec3f = std::array<float, 3>;

/// One analytic collider, a small plain struct (the meaning of the fields depends on `kind`). Build it with
/// the make_* functions, which check every field.
struct Collider {
    ColliderKind kind = ColliderKind::plane;
    float thickness = 0.0f; ///< collision margin, m, >= 0
    float friction = 0.0f;  ///< Coulomb coefficient, 0..1
    /// plane: a point on it; sphere, ellipsoid: centre; disc: centre of the top face; capsule: first end. m
    Vec3f centre{0.0f, 0.0f, 0.0f};
    /// plane: unit normal (out of the solid); capsule: second end (m). Unused otherwise.
    Vec3f axis{0.0f, 1.0f, 0.0f};
    /// sphere, capsule: {radius}; disc: {radius, height (the cylinder reaches from the top down by it)};
    /// ellipsoid: semi-axes along its local x, y, z. m
    Vec3f size{0.0f, 0.0f, 0.0f};
    /// ellipsoid: rotation, row-major, world = R * local (columns are the local axes in world coordinates).
    std::array<float, 9> rotation{1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f};
};

/// Collision margin and friction shared by every kind.
struct ColliderSurface {
    float thickness = 0.005f; ///< m, 0..1
    float friction = 0.3f;    ///< 0..1
};

/// Half-space below the plane through `point` with unit `normal` (normalised here; any length > 0).
Collider make_plane(Vec3f point, Vec3f normal, ColliderSurface surface = {});
/// The ground: the half-space y < height.
Collider make_ground(float height, ColliderSurface surface = {});
/// radius > 0 (m, up to 1000).
Collider make_sphere(Vec3f centre, float radius, ColliderSurface surface = {});
/// A horizontal disc / table: a solid vertical cylinder of `radius` whose top face is centred at `top_centre`
/// and which reaches `height` down (a thin table top: small height). radius > 0, height > 0 (m, up to 1000).
Collider make_disc(Vec3f top_centre, float radius, float height, ColliderSurface surface = {});
/// Points within `radius` of the segment a-b (a may equal b: a sphere). radius > 0.
Collider make_capsule(Vec3f a, Vec3f b, float radius, ColliderSurface surface = {});
/// semi_axes > 0 each (m, up to 1000); `rotation` row-major, orthonormal with determinant +1 (checked to
/// 1e-4).
Collider make_ellipsoid(Vec3f centre, Vec3f semi_axes, ColliderSurface surface = {},
                        const std::array<float, 9>& rotation = {1, 0, 0, 0, 1, 0, 0, 0, 1});
/// Row-major rotation by `angle` radians about the unit `axis` (normalised here).
std::array<float, 9> rotation_about_axis(Vec3f axis, float angle);
/// The collider moved by `offset` (m, added in double before rounding to float): the points of every kind
/// (plane point, centres, both capsule ends) move, directions and sizes do not. Scenes move colliders into
/// the cloth's frame with offset = -Cloth::origin.
Collider translated(const Collider& collider, const std::array<double, 3>& offset);

/// Checks every field of a collider (what the make_* functions check). Throws InvalidInput naming the field
/// and the allowed range.
void check_collider(const Collider& collider);

/// The default body for the T-shirt (TShirtParams in tshirt.hpp), in the same frame: y up, facing +z, origin
/// at the torso centre. Ellipsoids (centre; semi-axes), m:
///   torso     (0, 0, 0);        (0.16, 0.30, 0.10)
///   hips      (0, -0.30, 0);    (0.17, 0.15, 0.11)
///   shoulders (0, 0.22, 0);     (0.19, 0.06, 0.08) - its girth (~0.92 m) fits inside the shirt tube (2 x 0.48 m)
///   neck      (0, 0.34, 0);     (0.05, 0.07, 0.05)
///   head      (0, 0.48, 0);     (0.08, 0.11, 0.09)
///   arms      (+-0.40, 0.22, 0); (0.22, 0.045, 0.045) - horizontal, a T-pose matching the T-shirt's flat
///   sleeves.
/// The shirt's shoulder line (y = 0.33) sits on the shoulders (top 0.28 + thickness), its sleeves (y
/// 0.15..0.33) around the arms (y 0.175..0.265), its panels 0.13 m in front of and behind the centre, clear
/// of every part.
std::vector<Collider> default_body(ColliderSurface surface = {0.005f, 0.5f});

/// Result of projecting one point.
struct Contact {
    bool inside = false; ///< the point was inside the solid or closer than thickness to it
    Vec3f point{};       ///< where it goes: on the inflated surface (the input point when not inside), m
    Vec3f normal{};      ///< outward unit normal of the inflated surface at `point` (valid when inside)
};

/// Projects one point out of one collider (the collider must be valid: check_collider). `s_warm` (optional, read
/// and written by ellipsoids only): ellipsoid_closest_point's warm start, for a caller that projects nearby points
/// in turn.
Contact project_point(const Collider& collider, Vec3f p, float* s_warm = nullptr) noexcept;

/// Closest point of the ellipsoid with semi-axes `a` (> 0, local frame, centred at 0) to a point `q` inside
/// it: x_i = a_i^2 q_i / (a_i^2 + s) where s in (-min a_i^2, 0] solves sum (a_i q_i / (a_i^2 + s))^2 = 1,
/// found in double by Newton's method kept inside a shrinking bracket (a step leaving it is replaced by
/// bisection, which keeps it robust near the medial axis, where the root approaches the pole). The result is
/// then scaled radially onto the surface so that sum (x_i / a_i)^2 >= 1 holds in float. Points on a symmetry
/// plane are nudged off it by 1e-9 a_i (the closest point there is not unique). `s_warm` (optional): Newton starts
/// from *s_warm where it lies in (-min a_i^2, 0), else from 0, and *s_warm receives the root found, a start for a
/// nearby point. Either start ends at a Newton step under 1e-6 min a_i^2, which quadratic convergence leaves ~1e-12
/// min a_i^2 from the root, far below float rounding of x; the two results may still differ in the last bit.
/// Exposed for the tests.
Vec3f ellipsoid_closest_point(Vec3f semi_axes, Vec3f q, float* s_warm = nullptr) noexcept;

/// The collide stage over particles [begin, end) of structure-of-arrays state: positions (m) and velocities
/// (m/s) in place; particles with inv_mass 0 are skipped. One collider, or several in order (a body): with
/// several, the pass over them repeats (up to 4 times) while a particle of the chunk was still inside one of
/// them (overlapping colliders can push a point from one into another). With `hold_x/y/z` (the positions at the
/// start of the substep), a point is held there at rest instead of projected when (a) it started the substep inside
/// the collider it is found in (a cloth placed inside a solid: projecting would teleport it across the solid and
/// stretch its springs), or (b) it is still inside one after the last pass (overlapping colliders whose projections
/// disagree). The stage then never adds energy: it only removes velocity, and a held point is at rest where it was.
/// Results per particle do not depend on begin/end or chunking.
void collide_range(const Collider& collider, float* x, float* y, float* z, float* vx, float* vy, float* vz,
                   const float* inv_mass, std::size_t begin, std::size_t end) noexcept;
void collide_range(std::span<const Collider> colliders, float* x, float* y, float* z, float* vx, float* vy,
                   float* vz, const float* inv_mass, std::size_t begin, std::size_t end,
                   const float* hold_x = nullptr, const float* hold_y = nullptr,
                   const float* hold_z = nullptr) noexcept;

/// Where the segment from `p0` (outside the collider) to `p1` (inside it) first enters it, and the outward unit normal
/// there: the implicit solver's contact (vbd::contact_project) keeps a point on the tangent plane at that entry.
/// Spheres and ellipsoids solve the quadratic |u0 + t (u1 - u0)|^2 = 1 in double (u: the point in the frame where the
/// inflated surface is the unit sphere) and take the normal from the gradient there; planes, capsules and discs bisect
/// the segment (20 halvings) and project the last inside point. With p0 not outside or p1 not inside, the result is
/// the projection of p1.
Contact segment_entry(const Collider& collider, Vec3f p0, Vec3f p1) noexcept;

/// Whether a point is inside a collider (inside the solid or closer than thickness to it), with `slack` (m)
/// taken off the margin to allow for float rounding of a projected point: what the tests check after
/// collide_range.
bool is_inside(const Collider& collider, Vec3f p, float slack = 0.0f) noexcept;

} // namespace drape
