// Analytic colliders: projection of points onto inflated surfaces and the collide stage's range kernel.
#include "drape/colliders.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "drape/errors.hpp"
#include "range_check.hpp"

namespace drape {

const char* collider_kind_name(ColliderKind kind) noexcept {
    switch (kind) {
    case ColliderKind::plane:
        return "plane";
    case ColliderKind::sphere:
        return "sphere";
    case ColliderKind::disc:
        return "disc";
    case ColliderKind::capsule:
        return "capsule";
    case ColliderKind::ellipsoid:
        return "ellipsoid";
    }
    return "unknown";
}

namespace {

constexpr float max_extent = 1000.0f; // m: sizes and coordinates

void check_size(const std::string& name, float value) { check_positive(name, value, " m", false, max_extent); }

void check_point(const std::string& name, const Vec3f& p) {
    for (int k = 0; k < 3; ++k)
        if (!(std::abs(p[k]) <= max_extent))
            throw InvalidInput(name + "[" + std::to_string(k) + "] = " + range_number(p[k]) +
                               " m is outside the allowed range [-1000, 1000]");
}

std::string prefix(ColliderKind kind) {
    return std::string(collider_kind_name(kind)) + ".";
}

Collider with_surface(ColliderKind kind, const ColliderSurface& s) {
    Collider c;
    c.kind = kind;
    c.thickness = s.thickness;
    c.friction = s.friction;
    return c;
}

inline float dot3(const Vec3f& a, const Vec3f& b) noexcept {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

// ---------------------------------------------------------------------------------------------------------------------
// Inside tests: branch-free arithmetic on one point, the same expressions in the batch pre-pass and in the
// projection (so a point the pre-pass calls outside is exactly one the projection would leave alone).

inline float capsule_t(const Collider& col, float x, float y, float z) noexcept {
    const float abx = col.axis[0] - col.centre[0], aby = col.axis[1] - col.centre[1],
                abz = col.axis[2] - col.centre[2];
    const float len2 = abx * abx + aby * aby + abz * abz;
    const float t = ((x - col.centre[0]) * abx + (y - col.centre[1]) * aby + (z - col.centre[2]) * abz) /
                    (len2 > 0.0f ? len2 : 1.0f);
    return std::min(std::max(t, 0.0f), 1.0f);
}

// Ellipsoid level f = sum (q_i / A_i)^2 of the inflated ellipsoid (A = semi-axes + thickness); q = R^T (p -
// c).
inline float ellipsoid_level(const Collider& col, float x, float y, float z,
                             Vec3f* out_local = nullptr) noexcept {
    const auto& R = col.rotation;
    const float wx = x - col.centre[0], wy = y - col.centre[1], wz = z - col.centre[2];
    const float qx = R[0] * wx + R[3] * wy + R[6] * wz, qy = R[1] * wx + R[4] * wy + R[7] * wz,
                qz = R[2] * wx + R[5] * wy + R[8] * wz;
    if (out_local) *out_local = {qx, qy, qz};
    const float ax = qx / (col.size[0] + col.thickness), ay = qy / (col.size[1] + col.thickness),
                az = qz / (col.size[2] + col.thickness);
    return ax * ax + ay * ay + az * az;
}

template <ColliderKind K> inline bool inside_kind(const Collider& col, float x, float y, float z) noexcept {
    if constexpr (K == ColliderKind::plane) {
        const float d = (x - col.centre[0]) * col.axis[0] + (y - col.centre[1]) * col.axis[1] +
                        (z - col.centre[2]) * col.axis[2];
        return d < col.thickness;
    } else if constexpr (K == ColliderKind::sphere) {
        const float dx = x - col.centre[0], dy = y - col.centre[1], dz = z - col.centre[2];
        const float r = col.size[0] + col.thickness;
        return dx * dx + dy * dy + dz * dz < r * r;
    } else if constexpr (K == ColliderKind::capsule) {
        const float t = capsule_t(col, x, y, z);
        const float dx = x - (col.centre[0] + t * (col.axis[0] - col.centre[0]));
        const float dy = y - (col.centre[1] + t * (col.axis[1] - col.centre[1]));
        const float dz = z - (col.centre[2] + t * (col.axis[2] - col.centre[2]));
        const float r = col.size[0] + col.thickness;
        return dx * dx + dy * dy + dz * dz < r * r;
    } else if constexpr (K == ColliderKind::disc) {
        const float top = col.centre[1], bottom = col.centre[1] - col.size[1];
        const float dx = x - col.centre[0], dz = z - col.centre[2];
        const float er = std::max(std::sqrt(dx * dx + dz * dz) - col.size[0], 0.0f);
        const float ey = std::max(std::max(y - top, bottom - y), 0.0f);
        // Inside the solid (er = ey = 0) or within thickness of it; bitwise ops keep the loop branch-free.
        return ((er == 0.0f) & (ey == 0.0f)) | (er * er + ey * ey < col.thickness * col.thickness);
    } else {
        return ellipsoid_level(col, x, y, z) < 1.0f;
    }
}

// ---------------------------------------------------------------------------------------------------------------------
// Projections (called only for points inside). Each returns the point on the inflated surface and its normal.

struct Projection {
    Vec3f point, normal;
};

inline Projection project_round(const Vec3f& c, float radius, float x, float y, float z) noexcept {
    const float dx = x - c[0], dy = y - c[1], dz = z - c[2];
    const float d = std::sqrt(dx * dx + dy * dy + dz * dz);
    const Vec3f n = d > 1e-12f ? Vec3f{dx / d, dy / d, dz / d} : Vec3f{0.0f, 1.0f, 0.0f};
    return {{c[0] + n[0] * radius, c[1] + n[1] * radius, c[2] + n[2] * radius}, n};
}

inline Projection project_plane(const Collider& col, float x, float y, float z) noexcept {
    const Vec3f& n = col.axis;
    // The ground (normal exactly +y): set the height exactly, no rounding in x, z.
    if (n[0] == 0.0f && n[2] == 0.0f && n[1] == 1.0f) return {{x, col.centre[1] + col.thickness, z}, n};
    const float d = (x - col.centre[0]) * n[0] + (y - col.centre[1]) * n[1] + (z - col.centre[2]) * n[2];
    const float push = col.thickness - d;
    return {{x + push * n[0], y + push * n[1], z + push * n[2]}, n};
}

// Solid vertical cylinder [0, R] x [top - H, top] in (radius, y), grown by t (rounded rims).
inline Projection project_disc(const Collider& col, float x, float y, float z) noexcept {
    const float R = col.size[0], t = col.thickness;
    const float top = col.centre[1], bottom = col.centre[1] - col.size[1];
    const float dx = x - col.centre[0], dz = z - col.centre[2];
    const float r = std::sqrt(dx * dx + dz * dz);
    const float ux = r > 0.0f ? dx / r : 1.0f, uz = r > 0.0f ? dz / r : 0.0f; // radial direction
    if (r <= R && y <= top && y >= bottom) {
        // Inside the solid: leave through the nearest face.
        const float to_top = top - y, to_side = R - r, to_bottom = y - bottom;
        if (to_top <= to_side && to_top <= to_bottom) return {{x, top + t, z}, {0.0f, 1.0f, 0.0f}};
        if (to_side <= to_bottom)
            return {{col.centre[0] + ux * (R + t), y, col.centre[2] + uz * (R + t)}, {ux, 0.0f, uz}};
        return {{x, bottom - t, z}, {0.0f, -1.0f, 0.0f}};
    }
    // Outside the solid, within t of its closest point (qr, qy).
    const float qr = std::min(r, R), qy = std::clamp(y, bottom, top);
    const float er = r - qr, ey = y - qy;
    if (er == 0.0f) { // straight above or below a face: only y changes
        const float ny = ey > 0.0f ? 1.0f : -1.0f;
        return {{x, qy + ny * t, z}, {0.0f, ny, 0.0f}};
    }
    const float d = std::sqrt(er * er + ey * ey);
    const float nr = er / d, ny = ey / d;
    const float new_r = qr + nr * t;
    return {{col.centre[0] + ux * new_r, qy + ny * t, col.centre[2] + uz * new_r}, {nr * ux, ny, nr * uz}};
}

inline Projection project_ellipsoid(const Collider& col, float x, float y, float z, float* s_warm) noexcept {
    Vec3f q;
    ellipsoid_level(col, x, y, z, &q);
    const auto& R = col.rotation;
    const Vec3f A{col.size[0] + col.thickness, col.size[1] + col.thickness, col.size[2] + col.thickness};
    const Vec3f e = ellipsoid_closest_point(A, q, s_warm);
    Vec3f n{e[0] / (A[0] * A[0]), e[1] / (A[1] * A[1]), e[2] / (A[2] * A[2])};
    const float len = std::sqrt(dot3(n, n));
    n = {n[0] / len, n[1] / len, n[2] / len};
    return {{col.centre[0] + R[0] * e[0] + R[1] * e[1] + R[2] * e[2],
             col.centre[1] + R[3] * e[0] + R[4] * e[1] + R[5] * e[2],
             col.centre[2] + R[6] * e[0] + R[7] * e[1] + R[8] * e[2]},
            {R[0] * n[0] + R[1] * n[1] + R[2] * n[2], R[3] * n[0] + R[4] * n[1] + R[5] * n[2],
             R[6] * n[0] + R[7] * n[1] + R[8] * n[2]}};
}

template <ColliderKind K>
inline Projection project_kind(const Collider& col, float x, float y, float z, float* s_warm = nullptr) noexcept {
    Projection pr;
    if constexpr (K == ColliderKind::plane) pr = project_plane(col, x, y, z);
    if constexpr (K == ColliderKind::sphere)
        pr = project_round(col.centre, col.size[0] + col.thickness, x, y, z);
    if constexpr (K == ColliderKind::capsule) {
        const float t = capsule_t(col, x, y, z);
        const Vec3f c{col.centre[0] + t * (col.axis[0] - col.centre[0]),
                      col.centre[1] + t * (col.axis[1] - col.centre[1]),
                      col.centre[2] + t * (col.axis[2] - col.centre[2])};
        pr = project_round(c, col.size[0] + col.thickness, x, y, z);
    }
    if constexpr (K == ColliderKind::disc) pr = project_disc(col, x, y, z);
    if constexpr (K == ColliderKind::ellipsoid) pr = project_ellipsoid(col, x, y, z, s_warm);
    // Float rounding can leave the projected point a hair inside; step out along the normal until the inside
    // test (the one the kernel uses) agrees, so a point is never found inside the same collider twice.
    float step = 1e-7f; // m
    for (int k = 0; k < 24 && inside_kind<K>(col, pr.point[0], pr.point[1], pr.point[2]); ++k, step *= 2.0f)
        for (int c = 0; c < 3; ++c)
            pr.point[c] += step * pr.normal[c];
    return pr;
}

// Removes the inward normal velocity and applies Coulomb friction to the tangential part.
inline void respond(const Vec3f& n, float mu, float& vx, float& vy, float& vz) noexcept {
    const float vn = vx * n[0] + vy * n[1] + vz * n[2];
    if (!(vn < 0.0f)) return;
    float tx = vx - vn * n[0], ty = vy - vn * n[1], tz = vz - vn * n[2];
    if (mu > 0.0f) {
        const float vt = std::sqrt(tx * tx + ty * ty + tz * tz);
        const float scale = vt > 0.0f ? std::max(0.0f, 1.0f - mu * (-vn) / vt) : 0.0f;
        tx *= scale;
        ty *= scale;
        tz *= scale;
    }
    vx = tx;
    vy = ty;
    vz = tz;
}

// ---------------------------------------------------------------------------------------------------------------------
// Batch kernel: particles in chunks; per chunk and collider, a branch-free pre-pass flags the particles
// inside (a plain loop the compiler can vectorise), then the flagged ones are projected one by one (contacts
// are few).

constexpr std::size_t collide_chunk = 64;

struct SoA {
    float* __restrict x;
    float* __restrict y;
    float* __restrict z;
    float* __restrict vx;
    float* __restrict vy;
    float* __restrict vz;
    const float* __restrict inv_mass;
    /// Positions at the start of the substep (nullptr: not known, every point inside is projected).
    const float* hold_x = nullptr;
    const float* hold_y = nullptr;
    const float* hold_z = nullptr;
};

/// How deep (m) a point must be inside a collider's inflated solid to count as placed or stuck inside it (the two
/// rules below that hold it at rest): a projection onto a tilted plane or a curved surface can land inside by a
/// float rounding (about 1e-7 m at 1 m from the origin), and with no slack such a point was held at rest in every
/// following substep, so a cloth on a 20-degree plane never slid (0.02 m/s after 1 s, frictionless; g sin = 3.36).
constexpr float hold_slack = 1e-5f;

/// The collider with its inflation less hold_slack: its inside test is "inside by more than rounding".
Collider without_slack(const Collider& c) noexcept {
    Collider d = c;
    d.thickness -= hold_slack;
    return d;
}

/// Puts particle i back where it started the substep, at rest.
inline void hold(const SoA& s, std::size_t i) noexcept {
    s.x[i] = s.hold_x[i];
    s.y[i] = s.hold_y[i];
    s.z[i] = s.hold_z[i];
    s.vx[i] = s.vy[i] = s.vz[i] = 0.0f;
}

template <ColliderKind K>
std::size_t collide_chunk_with(const Collider& col, const SoA& s, std::size_t begin,
                               std::size_t end) noexcept {
    std::uint8_t flag[collide_chunk];
    const std::size_t n = end - begin;
    const float* __restrict x = s.x + begin;
    const float* __restrict y = s.y + begin;
    const float* __restrict z = s.z + begin;
    const float* __restrict w = s.inv_mass + begin;
    for (std::size_t k = 0; k < n; ++k)
        flag[k] = static_cast<std::uint8_t>(inside_kind<K>(col, x[k], y[k], z[k]) & (w[k] != 0.0f));
    std::size_t contacts = 0;
    const Collider deep = without_slack(col);
    for (std::size_t k = 0; k < n; ++k) {
        if (!flag[k]) continue;
        const std::size_t i = begin + k;
        if (s.hold_x && inside_kind<K>(deep, s.hold_x[i], s.hold_y[i], s.hold_z[i])) {
            // It started the substep inside this collider (the cloth was placed inside it) and is still inside:
            // projecting it out would teleport it across the solid and stretch its springs (energy from
            // nowhere). It is held at rest until the dynamics carry it out.
            hold(s, i);
            continue;
        }
        const Projection pr = project_kind<K>(col, s.x[i], s.y[i], s.z[i]);
        s.x[i] = pr.point[0];
        s.y[i] = pr.point[1];
        s.z[i] = pr.point[2];
        respond(pr.normal, col.friction, s.vx[i], s.vy[i], s.vz[i]);
        ++contacts;
    }
    return contacts;
}

std::size_t collide_chunk_any(const Collider& col, const SoA& s, std::size_t begin,
                              std::size_t end) noexcept {
    switch (col.kind) {
    case ColliderKind::plane:
        return collide_chunk_with<ColliderKind::plane>(col, s, begin, end);
    case ColliderKind::sphere:
        return collide_chunk_with<ColliderKind::sphere>(col, s, begin, end);
    case ColliderKind::disc:
        return collide_chunk_with<ColliderKind::disc>(col, s, begin, end);
    case ColliderKind::capsule:
        return collide_chunk_with<ColliderKind::capsule>(col, s, begin, end);
    case ColliderKind::ellipsoid:
        return collide_chunk_with<ColliderKind::ellipsoid>(col, s, begin, end);
    }
    return 0;
}

} // namespace

// ---------------------------------------------------------------------------------------------------------------------
// Construction and validation

void check_collider(const Collider& c) {
    const std::string pre = prefix(c.kind);
    check_range(pre + "thickness", c.thickness, 0.0f, 1.0f, " m");
    check_range(pre + "friction", c.friction, 0.0f, 1.0f, "");
    check_point(pre + "centre", c.centre);
    switch (c.kind) {
    case ColliderKind::plane: {
        const float len = std::sqrt(dot3(c.axis, c.axis));
        if (!(std::abs(len - 1.0f) <= 1e-4f))
            throw InvalidInput(pre + "normal has length " + range_number(len) + " (must be 1 within 1e-4)");
        break;
    }
    case ColliderKind::sphere:
        check_size(pre + "radius", c.size[0]);
        break;
    case ColliderKind::disc:
        check_size(pre + "radius", c.size[0]);
        check_size(pre + "height", c.size[1]);
        break;
    case ColliderKind::capsule:
        check_point(pre + "end_b", c.axis);
        check_size(pre + "radius", c.size[0]);
        break;
    case ColliderKind::ellipsoid: {
        static const char* axis_name[3] = {"semi_axes[0]", "semi_axes[1]", "semi_axes[2]"};
        for (int k = 0; k < 3; ++k)
            check_size(pre + axis_name[k], c.size[k]);
        const auto& R = c.rotation;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                // Columns i and j of R: dot = delta_ij.
                const float d = R[i] * R[j] + R[3 + i] * R[3 + j] + R[6 + i] * R[6 + j];
                if (!(std::abs(d - (i == j ? 1.0f : 0.0f)) <= 1e-4f))
                    throw InvalidInput(pre + "rotation is not orthonormal (columns " + std::to_string(i) +
                                       " . " + std::to_string(j) + " = " + range_number(d) + ")");
            }
        const float det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) +
                          R[2] * (R[3] * R[7] - R[4] * R[6]);
        if (!(det > 0.0f))
            throw InvalidInput(pre + "rotation has determinant " + range_number(det) +
                               " (must be +1: no mirroring)");
        break;
    }
    default:
        throw InvalidInput("collider kind " + std::to_string(static_cast<int>(c.kind)) +
                           " is unknown (0..4)");
    }
}

Collider make_plane(Vec3f point, Vec3f normal, ColliderSurface surface) {
    Collider c = with_surface(ColliderKind::plane, surface);
    c.centre = point;
    const float len = std::sqrt(dot3(normal, normal));
    if (!(len > 0.0f) || !std::isfinite(len))
        throw InvalidInput("plane.normal has length " + range_number(len) + " (must be > 0)");
    c.axis = {normal[0] / len, normal[1] / len, normal[2] / len};
    check_collider(c);
    return c;
}

Collider make_ground(float height, ColliderSurface surface) {
    check_range("ground.height", height, -max_extent, max_extent, " m");
    return make_plane({0.0f, height, 0.0f}, {0.0f, 1.0f, 0.0f}, surface);
}

Collider make_sphere(Vec3f centre, float radius, ColliderSurface surface) {
    Collider c = with_surface(ColliderKind::sphere, surface);
    c.centre = centre;
    c.size = {radius, 0.0f, 0.0f};
    check_collider(c);
    return c;
}

Collider make_disc(Vec3f top_centre, float radius, float height, ColliderSurface surface) {
    Collider c = with_surface(ColliderKind::disc, surface);
    c.centre = top_centre;
    c.size = {radius, height, 0.0f};
    check_collider(c);
    return c;
}

Collider make_capsule(Vec3f a, Vec3f b, float radius, ColliderSurface surface) {
    Collider c = with_surface(ColliderKind::capsule, surface);
    c.centre = a;
    c.axis = b;
    c.size = {radius, 0.0f, 0.0f};
    check_collider(c);
    return c;
}

Collider make_ellipsoid(Vec3f centre, Vec3f semi_axes, ColliderSurface surface,
                        const std::array<float, 9>& rotation) {
    Collider c = with_surface(ColliderKind::ellipsoid, surface);
    c.centre = centre;
    c.size = semi_axes;
    c.rotation = rotation;
    check_collider(c);
    return c;
}

Collider translated(const Collider& collider, const std::array<double, 3>& offset) {
    Collider c = collider;
    for (int k = 0; k < 3; ++k) {
        c.centre[k] = static_cast<float>(double(collider.centre[k]) + offset[k]);
        if (c.kind == ColliderKind::capsule)
            c.axis[k] = static_cast<float>(double(collider.axis[k]) + offset[k]);
    }
    return c;
}

std::array<float, 9> rotation_about_axis(Vec3f axis, float angle) {
    const double len =
        std::sqrt(double{axis[0]} * axis[0] + double{axis[1]} * axis[1] + double{axis[2]} * axis[2]);
    if (!(len > 0.0) || !std::isfinite(len))
        throw InvalidInput("rotation axis has length " + range_number(len) + " (must be > 0)");
    if (!std::isfinite(angle)) throw InvalidInput("rotation angle is not finite");
    const double x = axis[0] / len, y = axis[1] / len, z = axis[2] / len;
    const double c = std::cos(double{angle}), s = std::sin(double{angle}), C = 1.0 - c;
    // Rodrigues' formula.
    const double m[9] = {c + x * x * C,     x * y * C - z * s, x * z * C + y * s,
                         y * x * C + z * s, c + y * y * C,     y * z * C - x * s,
                         z * x * C - y * s, z * y * C + x * s, c + z * z * C};
    std::array<float, 9> out{};
    for (int k = 0; k < 9; ++k)
        out[k] = static_cast<float>(m[k]);
    return out;
}

std::vector<Collider> default_body(ColliderSurface s) {
    return {
        make_ellipsoid({0.0f, 0.0f, 0.0f}, {0.16f, 0.30f, 0.10f}, s),      // torso
        make_ellipsoid({0.0f, -0.30f, 0.0f}, {0.17f, 0.15f, 0.11f}, s),    // hips
        make_ellipsoid({0.0f, 0.22f, 0.0f}, {0.19f, 0.06f, 0.08f}, s),     // shoulders
        make_ellipsoid({0.0f, 0.34f, 0.0f}, {0.05f, 0.07f, 0.05f}, s),     // neck
        make_ellipsoid({0.0f, 0.48f, 0.0f}, {0.08f, 0.11f, 0.09f}, s),     // head
        make_ellipsoid({-0.40f, 0.22f, 0.0f}, {0.22f, 0.045f, 0.045f}, s), // right arm (x < 0)
        make_ellipsoid({0.40f, 0.22f, 0.0f}, {0.22f, 0.045f, 0.045f}, s),  // left arm (x > 0)
    };
}

// ---------------------------------------------------------------------------------------------------------------------
// Projection

Vec3f ellipsoid_closest_point(Vec3f semi_axes, Vec3f q_in, float* s_warm) noexcept {
    double a[3], a2[3], q[3];
    for (int k = 0; k < 3; ++k) {
        a[k] = semi_axes[k];
        a2[k] = a[k] * a[k];
        q[k] = q_in[k];
        // On a symmetry plane the closest point is not unique and the root sits at the pole: nudge off it.
        if (std::abs(q[k]) < 1e-9 * a[k]) q[k] = q[k] < 0.0 ? -1e-9 * a[k] : 1e-9 * a[k];
    }
    // The closest point is x_i = a_i^2 q_i / (a_i^2 + s) at the root of S(s) = sum (a_i q_i / (a_i^2 + s))^2 = 1
    // (s > -min a_i^2; inside, S(0) < 1 and the root lies in (-min a_i^2, 0)). Newton runs on h(s) = S^(-1/2) - 1,
    // not on S - 1: h is the power mean of exponent -2 of the a_i^2 + s (weights (a_i q_i)^2), so it is increasing
    // and concave, and linear where one axis dominates (exactly so on a sphere), where S - 1 is a steep convex
    // curve. From s = 0 (h > 0) the first step lands left of the root (concavity) and later steps climb to it
    // monotonically; a step leaving the bracket is replaced by bisection. Convergence is quadratic, so a Newton step
    // under 1e-6 min a^2 leaves ~1e-12 of it (far below float rounding of x; tested against the exact root). On the
    // implicit T-shirt at 70 cells/m, Newton on S - 1 to a 1e-14 step took 6 iterations in most calls (5 to 7), this
    // with a 1e-8 stop 4 (3 to 5); the shirt's 3 s ran 0.91x the wall (docs/collisions.md, "Ellipsoid projection").
    const double amin2 = std::min({a2[0], a2[1], a2[2]});
    double lo = -amin2, hi = 0.0, s = 0.0;
    // A warm start (a nearby point's root): Newton from either side of the root ends climbing to it (a step from
    // the right lands left of it, by concavity), so any start in the bracket converges as from 0, in fewer steps.
    if (s_warm && *s_warm > lo && *s_warm < hi) s = *s_warm;
    for (int it = 0; it < 100; ++it) {
        double S = 0.0, dS = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double den = 1.0 / (a2[k] + s);
            const double r = a[k] * q[k] * den;
            S += r * r;
            dS -= 2.0 * r * r * den;
        }
        if (S > 1.0)
            lo = s;
        else
            hi = s;
        if (S == 1.0) break;
        // h = S^(-1/2) - 1, h' = -S^(-3/2) S' / 2: the step -h / h' = 2 S (1 - sqrt S) / S'.
        const double root_S = std::sqrt(S);
        double next = s + 2.0 * S * (1.0 - root_S) / dS;
        const bool newton = next > lo && next < hi;
        if (!newton) next = 0.5 * (lo + hi);
        const bool done = std::abs(next - s) <= (newton ? 1e-6 : 1e-14) * amin2;
        s = next;
        if (done) break;
    }
    if (s_warm) *s_warm = static_cast<float>(s);
    double x[3];
    for (int k = 0; k < 3; ++k) {
        x[k] = a2[k] * q[k] / (a2[k] + s);
        // A point on a symmetry plane whose closest point stayed on it (the nudge alone moved it off, by ~1e-9 a):
        // exactly on the plane, so a mirror-symmetric cloth stays so (mirror_symmetry.hpp).
        if (q_in[k] == 0.0f && std::abs(x[k]) <= 1e-6 * a[k]) x[k] = 0.0;
    }
    // Radial snap onto the surface, then out by a few float ulps until the float point is not inside.
    double g = 0.0;
    for (int k = 0; k < 3; ++k)
        g += (x[k] / a[k]) * (x[k] / a[k]);
    const double scale = 1.0 / std::sqrt(g);
    Vec3f out{static_cast<float>(x[0] * scale), static_cast<float>(x[1] * scale),
              static_cast<float>(x[2] * scale)};
    for (int it = 0; it < 8; ++it) {
        const float f = (out[0] / semi_axes[0]) * (out[0] / semi_axes[0]) +
                        (out[1] / semi_axes[1]) * (out[1] / semi_axes[1]) +
                        (out[2] / semi_axes[2]) * (out[2] / semi_axes[2]);
        if (f >= 1.0f) break;
        for (float& v : out)
            v *= 1.0f + 2e-7f;
    }
    return out;
}

Contact project_point(const Collider& col, Vec3f p, float* s_warm) noexcept {
    Contact out{false, p, {}};
    auto run = [&]<ColliderKind K>() {
        if (!inside_kind<K>(col, p[0], p[1], p[2])) return;
        const Projection pr = project_kind<K>(col, p[0], p[1], p[2], s_warm);
        out = {true, pr.point, pr.normal};
    };
    switch (col.kind) {
    case ColliderKind::plane:
        run.operator()<ColliderKind::plane>();
        break;
    case ColliderKind::sphere:
        run.operator()<ColliderKind::sphere>();
        break;
    case ColliderKind::disc:
        run.operator()<ColliderKind::disc>();
        break;
    case ColliderKind::capsule:
        run.operator()<ColliderKind::capsule>();
        break;
    case ColliderKind::ellipsoid:
        run.operator()<ColliderKind::ellipsoid>();
        break;
    }
    return out;
}

namespace {

// The bisection of segment_entry's kinds without a closed form: p0 + lo (p1 - p0) outside, p0 + hi (p1 - p0) inside.
Contact entry_by_bisection(const Collider& c, Vec3f p0, Vec3f p1) noexcept {
    float lo = 0.0f, hi = 1.0f;
    for (int it = 0; it < 20; ++it) {
        const float mid = 0.5f * (lo + hi);
        const Vec3f q{p0[0] + mid * (p1[0] - p0[0]), p0[1] + mid * (p1[1] - p0[1]), p0[2] + mid * (p1[2] - p0[2])};
        (is_inside(c, q) ? hi : lo) = mid;
    }
    return project_point(c, {p0[0] + hi * (p1[0] - p0[0]), p0[1] + hi * (p1[1] - p0[1]), p0[2] + hi * (p1[2] - p0[2])});
}

} // namespace

Contact segment_entry(const Collider& c, Vec3f p0, Vec3f p1) noexcept {
    if (c.kind != ColliderKind::sphere && c.kind != ColliderKind::ellipsoid) return entry_by_bisection(c, p0, p1);
    // u = S R^T (p - centre) with S = diag(1 / A_i), A the inflated semi-axes (a sphere: R = I, A_i = radius).
    const bool sphere = c.kind == ColliderKind::sphere;
    double A[3], u0[3], du[3];
    for (int k = 0; k < 3; ++k)
        A[k] = double(sphere ? c.size[0] : c.size[k]) + c.thickness;
    static constexpr std::array<float, 9> identity{1.0f, 0.0f, 0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f};
    const auto& R = sphere ? identity : c.rotation;
    for (int k = 0; k < 3; ++k) {
        double a = 0.0, b = 0.0;
        for (int j = 0; j < 3; ++j) {
            a += R[3 * j + k] * (double(p0[j]) - c.centre[j]);
            b += R[3 * j + k] * (double(p1[j]) - c.centre[j]);
        }
        u0[k] = a / A[k];
        du[k] = b / A[k] - u0[k];
    }
    const double qa = du[0] * du[0] + du[1] * du[1] + du[2] * du[2];
    const double qb = u0[0] * du[0] + u0[1] * du[1] + u0[2] * du[2]; // half the linear coefficient
    const double qc = u0[0] * u0[0] + u0[1] * u0[1] + u0[2] * u0[2] - 1.0;
    const double disc = qb * qb - qa * qc;
    // Entering: qc >= 0 (p0 outside) and moving inwards (qb < 0); the smaller root, in the cancellation-free form.
    // Float inside tests disagreeing with these double ones by a rounding fall back to the projection of p1.
    if (!(qc >= 0.0) || !(qb < 0.0) || !(disc >= 0.0) || !(qa > 0.0)) return project_point(c, p1);
    const double t = std::min(qc / (-qb + std::sqrt(disc)), 1.0);
    double n[3], len = 0.0;
    for (int k = 0; k < 3; ++k) {
        n[k] = (u0[k] + t * du[k]) / A[k]; // gradient of |u|^2 / 2 in the local frame
        len += n[k] * n[k];
    }
    len = std::sqrt(len);
    Contact out{true, {}, {}};
    for (int k = 0; k < 3; ++k) {
        out.point[k] = static_cast<float>(double(p0[k]) + t * (double(p1[k]) - p0[k]));
        double w = 0.0;
        for (int j = 0; j < 3; ++j)
            w += R[3 * k + j] * n[j];
        out.normal[k] = static_cast<float>(w / len);
    }
    return out;
}

bool is_inside(const Collider& col, Vec3f p, float slack) noexcept {
    if (slack != 0.0f) { // a copy with the margin less the slack (it may go negative: a point on the surface is then
                         // outside); without slack the collider itself (no copy: the implicit sweeps call this ~20
                         // times a point in contact)
        Collider c = col;
        c.thickness = col.thickness - slack;
        return is_inside(c, p, 0.0f);
    }
    const Collider& c = col;
    switch (col.kind) {
    case ColliderKind::plane:
        return inside_kind<ColliderKind::plane>(c, p[0], p[1], p[2]);
    case ColliderKind::sphere:
        return std::hypot(p[0] - c.centre[0], p[1] - c.centre[1], p[2] - c.centre[2]) <
               c.size[0] + c.thickness;
    case ColliderKind::capsule: {
        const float t = capsule_t(c, p[0], p[1], p[2]);
        return std::hypot(p[0] - (c.centre[0] + t * (c.axis[0] - c.centre[0])),
                          p[1] - (c.centre[1] + t * (c.axis[1] - c.centre[1])),
                          p[2] - (c.centre[2] + t * (c.axis[2] - c.centre[2]))) < c.size[0] + c.thickness;
    }
    case ColliderKind::ellipsoid: {
        // Beyond the bounding sphere (with 0.1 % to spare for rounding) the level is surely >= 1: skip the rotation
        // and the divisions (the implicit sweeps ask this of every point and every part of a body, every sweep).
        const float dx = p[0] - c.centre[0], dy = p[1] - c.centre[1], dz = p[2] - c.centre[2];
        const float r = 1.001f * (std::max({c.size[0], c.size[1], c.size[2]}) + c.thickness);
        if (dx * dx + dy * dy + dz * dz > r * r) return false;
        return ellipsoid_level(c, p[0], p[1], p[2]) < 1.0f;
    }
    case ColliderKind::disc: {
        // Signed distance to the solid cylinder (negative inside: minus the depth below the nearest face).
        const float R = col.size[0], top = col.centre[1], bottom = col.centre[1] - col.size[1];
        const float dx = p[0] - col.centre[0], dz = p[2] - col.centre[2];
        const float r = std::sqrt(dx * dx + dz * dz);
        const float er = std::max(r - R, 0.0f),
                    ey = p[1] > top ? p[1] - top : (p[1] < bottom ? bottom - p[1] : 0.0f);
        const float sd = (er == 0.0f && ey == 0.0f) ? -std::min({top - p[1], R - r, p[1] - bottom})
                                                    : std::sqrt(er * er + ey * ey);
        return sd < c.thickness;
    }
    }
    return false;
}

// ---------------------------------------------------------------------------------------------------------------------
// The collide stage

void collide_range(const Collider& col, float* x, float* y, float* z, float* vx, float* vy, float* vz,
                   const float* inv_mass, std::size_t begin, std::size_t end) noexcept {
    const SoA s{x, y, z, vx, vy, vz, inv_mass};
    for (std::size_t c = begin; c < end; c += collide_chunk)
        collide_chunk_any(col, s, c, std::min(end, c + collide_chunk));
}

namespace {

bool inside_kernel(const Collider& col, float x, float y, float z) noexcept {
    switch (col.kind) {
    case ColliderKind::plane: return inside_kind<ColliderKind::plane>(col, x, y, z);
    case ColliderKind::sphere: return inside_kind<ColliderKind::sphere>(col, x, y, z);
    case ColliderKind::disc: return inside_kind<ColliderKind::disc>(col, x, y, z);
    case ColliderKind::capsule: return inside_kind<ColliderKind::capsule>(col, x, y, z);
    case ColliderKind::ellipsoid: return inside_kind<ColliderKind::ellipsoid>(col, x, y, z);
    }
    return false;
}

} // namespace

void collide_range(std::span<const Collider> colliders, float* x, float* y, float* z, float* vx, float* vy,
                   float* vz, const float* inv_mass, std::size_t begin, std::size_t end, const float* hold_x,
                   const float* hold_y, const float* hold_z) noexcept {
    // Per chunk: passes over the colliders in order until a pass finds no contact (at most 4). A particle's
    // own sequence of projections is the same as if it were processed alone: further passes leave a clean
    // particle alone.
    constexpr int max_passes = 4;
    const SoA s{x, y, z, vx, vy, vz, inv_mass, hold_x, hold_y, hold_z};
    for (std::size_t c = begin; c < end; c += collide_chunk) {
        const std::size_t c_end = std::min(end, c + collide_chunk);
        std::size_t contacts = 0;
        for (int pass = 0; pass < max_passes; ++pass) {
            contacts = 0;
            for (const Collider& col : colliders)
                contacts += collide_chunk_any(col, s, c, c_end);
            if (contacts == 0) break;
        }
        if (contacts == 0 || hold_x == nullptr) continue;
        // Overlapping colliders whose projections disagree (each pushes the point into the other): the point is
        // held where it started the substep, at rest, instead of jumping between their surfaces every substep.
        for (std::size_t i = c; i < c_end; ++i) {
            if (inv_mass[i] == 0.0f) continue;
            bool inside = false;
            for (const Collider& col : colliders)
                inside = inside || inside_kernel(without_slack(col), x[i], y[i], z[i]);
            if (inside) hold(s, i);
        }
    }
}

} // namespace drape
