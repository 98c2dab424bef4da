// Analytic colliders: projection of points onto inflated surfaces and the collide stage's range kernel.
#include "drape/colliders.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "drape/errors.hpp"

namespace drape {

const char* collider_kind_name(ColliderKind kind) noexcept {
    switch (kind) {
    case ColliderKind::plane: return "plane";
    case ColliderKind::sphere: return "sphere";
    case ColliderKind::disc: return "disc";
    case ColliderKind::capsule: return "capsule";
    case ColliderKind::ellipsoid: return "ellipsoid";
    }
    return "unknown";
}

namespace {

constexpr float max_extent = 1000.0f; // m: sizes and coordinates

void check_range(const std::string& name, float value, float lo, float hi, const char* unit) {
    if (!(value >= lo && value <= hi))
        throw InvalidInput(name + " = " + std::to_string(value) + unit + " is outside the allowed range [" +
                           std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

void check_positive(const std::string& name, float value, const char* unit) {
    if (!(value > 0.0f && value <= max_extent))
        throw InvalidInput(name + " = " + std::to_string(value) + unit + " is outside the allowed range (0, " +
                           std::to_string(max_extent) + "]");
}

void check_point(const std::string& name, const Vec3f& p) {
    for (int k = 0; k < 3; ++k)
        if (!(std::abs(p[k]) <= max_extent))
            throw InvalidInput(name + "[" + std::to_string(k) + "] = " + std::to_string(p[k]) +
                               " m is outside the allowed range [-1000, 1000]");
}

std::string prefix(ColliderKind kind) { return std::string(collider_kind_name(kind)) + "."; }

Collider with_surface(ColliderKind kind, const ColliderSurface& s) {
    Collider c;
    c.kind = kind;
    c.thickness = s.thickness;
    c.friction = s.friction;
    return c;
}

inline float dot3(const Vec3f& a, const Vec3f& b) noexcept { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Pushes p out of a sphere of radius `radius` (already inflated) around c.
inline Contact project_round(const Vec3f& c, float radius, const Vec3f& p) noexcept {
    Contact out;
    out.point = p;
    const float dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
    const float d2 = dx * dx + dy * dy + dz * dz;
    if (!(d2 < radius * radius)) return out;
    out.inside = true;
    const float d = std::sqrt(d2);
    out.normal = d > 1e-12f ? Vec3f{dx / d, dy / d, dz / d} : Vec3f{0.0f, 1.0f, 0.0f};
    out.point = {c[0] + out.normal[0] * radius, c[1] + out.normal[1] * radius, c[2] + out.normal[2] * radius};
    return out;
}

inline Vec3f capsule_closest(const Collider& col, const Vec3f& p) noexcept {
    const Vec3f& a = col.centre;
    const Vec3f& b = col.axis;
    const Vec3f ab{b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const Vec3f ap{p[0] - a[0], p[1] - a[1], p[2] - a[2]};
    const float len2 = dot3(ab, ab);
    const float t = len2 > 0.0f ? std::clamp(dot3(ap, ab) / len2, 0.0f, 1.0f) : 0.0f;
    return {a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]};
}

Contact project_plane(const Collider& col, const Vec3f& p) noexcept {
    Contact out;
    out.point = p;
    const Vec3f& n = col.axis;
    const float d = (p[0] - col.centre[0]) * n[0] + (p[1] - col.centre[1]) * n[1] + (p[2] - col.centre[2]) * n[2];
    if (!(d < col.thickness)) return out;
    out.inside = true;
    out.normal = n;
    const float push = col.thickness - d;
    out.point = {p[0] + push * n[0], p[1] + push * n[1], p[2] + push * n[2]};
    // The ground (normal exactly +y): set the height exactly, no rounding in x, z.
    if (n[0] == 0.0f && n[2] == 0.0f && n[1] == 1.0f) out.point = {p[0], col.centre[1] + col.thickness, p[2]};
    return out;
}

// Solid vertical cylinder [0, R] x [top - H, top] in (radius, y), grown by t (rounded rims).
Contact project_disc(const Collider& col, const Vec3f& p) noexcept {
    Contact out;
    out.point = p;
    const float R = col.size[0], t = col.thickness;
    const float top = col.centre[1], bottom = col.centre[1] - col.size[1];
    const float dx = p[0] - col.centre[0], dz = p[2] - col.centre[2];
    const float r = std::sqrt(dx * dx + dz * dz);
    // Quick reject: outside the grown bounding cylinder.
    if (!(r < R + t) || !(p[1] < top + t) || !(p[1] > bottom - t)) return out;
    const float ux = r > 0.0f ? dx / r : 1.0f, uz = r > 0.0f ? dz / r : 0.0f; // radial direction
    if (r <= R && p[1] <= top && p[1] >= bottom) {
        // Inside the solid: leave through the nearest face.
        const float to_top = top - p[1], to_side = R - r, to_bottom = p[1] - bottom;
        out.inside = true;
        if (to_top <= to_side && to_top <= to_bottom) {
            out.normal = {0.0f, 1.0f, 0.0f};
            out.point = {p[0], top + t, p[2]};
        } else if (to_side <= to_bottom) {
            out.normal = {ux, 0.0f, uz};
            out.point = {col.centre[0] + ux * (R + t), p[1], col.centre[2] + uz * (R + t)};
        } else {
            out.normal = {0.0f, -1.0f, 0.0f};
            out.point = {p[0], bottom - t, p[2]};
        }
        return out;
    }
    // Outside the solid: within t of its closest point?
    const float qr = std::min(r, R), qy = std::clamp(p[1], bottom, top);
    const float er = r - qr, ey = p[1] - qy;
    const float d2 = er * er + ey * ey;
    if (!(d2 < t * t)) return out;
    out.inside = true;
    if (er == 0.0f) { // straight above or below a face: only y changes
        const float ny = ey > 0.0f ? 1.0f : -1.0f;
        out.normal = {0.0f, ny, 0.0f};
        out.point = {p[0], qy + ny * t, p[2]};
        return out;
    }
    const float d = std::sqrt(d2);
    const float nr = er / d, ny = ey / d;
    out.normal = {nr * ux, ny, nr * uz};
    const float new_r = qr + nr * t;
    out.point = {col.centre[0] + ux * new_r, qy + ny * t, col.centre[2] + uz * new_r};
    return out;
}

Contact project_ellipsoid(const Collider& col, const Vec3f& p) noexcept {
    Contact out;
    out.point = p;
    const auto& R = col.rotation;
    const float wx = p[0] - col.centre[0], wy = p[1] - col.centre[1], wz = p[2] - col.centre[2];
    // local = R^T world
    const Vec3f q{R[0] * wx + R[3] * wy + R[6] * wz, R[1] * wx + R[4] * wy + R[7] * wz,
                  R[2] * wx + R[5] * wy + R[8] * wz};
    const Vec3f A{col.size[0] + col.thickness, col.size[1] + col.thickness, col.size[2] + col.thickness};
    const float f = (q[0] / A[0]) * (q[0] / A[0]) + (q[1] / A[1]) * (q[1] / A[1]) + (q[2] / A[2]) * (q[2] / A[2]);
    if (!(f < 1.0f)) return out;
    out.inside = true;
    const Vec3f x = ellipsoid_closest_point(A, q);
    Vec3f n{x[0] / (A[0] * A[0]), x[1] / (A[1] * A[1]), x[2] / (A[2] * A[2])};
    const float len = std::sqrt(dot3(n, n));
    n = {n[0] / len, n[1] / len, n[2] / len};
    out.normal = {R[0] * n[0] + R[1] * n[1] + R[2] * n[2], R[3] * n[0] + R[4] * n[1] + R[5] * n[2],
                  R[6] * n[0] + R[7] * n[1] + R[8] * n[2]};
    out.point = {col.centre[0] + R[0] * x[0] + R[1] * x[1] + R[2] * x[2],
                 col.centre[1] + R[3] * x[0] + R[4] * x[1] + R[5] * x[2],
                 col.centre[2] + R[6] * x[0] + R[7] * x[1] + R[8] * x[2]};
    return out;
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

// One collider over a range; the kind is a template parameter so each loop body is branch-free in the kind.
template <ColliderKind K> inline Contact project_kind(const Collider& col, const Vec3f& p) noexcept {
    if constexpr (K == ColliderKind::plane) return project_plane(col, p);
    if constexpr (K == ColliderKind::sphere) return project_round(col.centre, col.size[0] + col.thickness, p);
    if constexpr (K == ColliderKind::capsule) return project_round(capsule_closest(col, p), col.size[0] + col.thickness, p);
    if constexpr (K == ColliderKind::disc) return project_disc(col, p);
    if constexpr (K == ColliderKind::ellipsoid) return project_ellipsoid(col, p);
}

template <ColliderKind K>
void collide_loop(const Collider& col, float* __restrict x, float* __restrict y, float* __restrict z,
                  float* __restrict vx, float* __restrict vy, float* __restrict vz, const float* __restrict inv_mass,
                  std::size_t begin, std::size_t end) noexcept {
    for (std::size_t i = begin; i < end; ++i) {
        if (inv_mass[i] == 0.0f) continue;
        const Contact c = project_kind<K>(col, {x[i], y[i], z[i]});
        if (!c.inside) continue;
        x[i] = c.point[0];
        y[i] = c.point[1];
        z[i] = c.point[2];
        respond(c.normal, col.friction, vx[i], vy[i], vz[i]);
    }
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
            throw InvalidInput(pre + "normal has length " + std::to_string(len) + " (must be 1 within 1e-4)");
        break;
    }
    case ColliderKind::sphere: check_positive(pre + "radius", c.size[0], " m"); break;
    case ColliderKind::disc:
        check_positive(pre + "radius", c.size[0], " m");
        check_positive(pre + "height", c.size[1], " m");
        break;
    case ColliderKind::capsule:
        check_point(pre + "end_b", c.axis);
        check_positive(pre + "radius", c.size[0], " m");
        break;
    case ColliderKind::ellipsoid: {
        static const char* axis_name[3] = {"semi_axes[0]", "semi_axes[1]", "semi_axes[2]"};
        for (int k = 0; k < 3; ++k) check_positive(pre + axis_name[k], c.size[k], " m");
        const auto& R = c.rotation;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                // Columns i and j of R: dot = delta_ij.
                const float d = R[i] * R[j] + R[3 + i] * R[3 + j] + R[6 + i] * R[6 + j];
                if (!(std::abs(d - (i == j ? 1.0f : 0.0f)) <= 1e-4f))
                    throw InvalidInput(pre + "rotation is not orthonormal (columns " + std::to_string(i) + " . " +
                                       std::to_string(j) + " = " + std::to_string(d) + ")");
            }
        const float det = R[0] * (R[4] * R[8] - R[5] * R[7]) - R[1] * (R[3] * R[8] - R[5] * R[6]) +
                          R[2] * (R[3] * R[7] - R[4] * R[6]);
        if (!(det > 0.0f))
            throw InvalidInput(pre + "rotation has determinant " + std::to_string(det) + " (must be +1: no mirroring)");
        break;
    }
    default: throw InvalidInput("collider kind " + std::to_string(static_cast<int>(c.kind)) + " is unknown (0..4)");
    }
}

Collider make_plane(Vec3f point, Vec3f normal, ColliderSurface surface) {
    Collider c = with_surface(ColliderKind::plane, surface);
    c.centre = point;
    const float len = std::sqrt(dot3(normal, normal));
    if (!(len > 0.0f) || !std::isfinite(len)) throw InvalidInput("plane.normal has length " + std::to_string(len) + " (must be > 0)");
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

Collider make_ellipsoid(Vec3f centre, Vec3f semi_axes, ColliderSurface surface, const std::array<float, 9>& rotation) {
    Collider c = with_surface(ColliderKind::ellipsoid, surface);
    c.centre = centre;
    c.size = semi_axes;
    c.rotation = rotation;
    check_collider(c);
    return c;
}

std::array<float, 9> rotation_about_axis(Vec3f axis, float angle) {
    const double len = std::sqrt(double{axis[0]} * axis[0] + double{axis[1]} * axis[1] + double{axis[2]} * axis[2]);
    if (!(len > 0.0) || !std::isfinite(len))
        throw InvalidInput("rotation axis has length " + std::to_string(len) + " (must be > 0)");
    if (!std::isfinite(angle)) throw InvalidInput("rotation angle is not finite");
    const double x = axis[0] / len, y = axis[1] / len, z = axis[2] / len;
    const double c = std::cos(double{angle}), s = std::sin(double{angle}), C = 1.0 - c;
    // Rodrigues' formula.
    const double m[9] = {c + x * x * C,     x * y * C - z * s, x * z * C + y * s, y * x * C + z * s, c + y * y * C,
                         y * z * C - x * s, z * x * C - y * s, z * y * C + x * s, c + z * z * C};
    std::array<float, 9> out{};
    for (int k = 0; k < 9; ++k) out[k] = static_cast<float>(m[k]);
    return out;
}

std::vector<Collider> default_body(ColliderSurface s) {
    return {
        make_ellipsoid({0.0f, 0.0f, 0.0f}, {0.16f, 0.30f, 0.10f}, s),     // torso
        make_ellipsoid({0.0f, -0.30f, 0.0f}, {0.17f, 0.15f, 0.11f}, s),   // hips
        make_ellipsoid({0.0f, 0.22f, 0.0f}, {0.21f, 0.07f, 0.09f}, s),    // shoulders
        make_ellipsoid({0.0f, 0.34f, 0.0f}, {0.05f, 0.07f, 0.05f}, s),    // neck
        make_ellipsoid({0.0f, 0.48f, 0.0f}, {0.08f, 0.11f, 0.09f}, s),    // head
        make_ellipsoid({-0.40f, 0.22f, 0.0f}, {0.22f, 0.045f, 0.045f}, s), // right arm (x < 0)
        make_ellipsoid({0.40f, 0.22f, 0.0f}, {0.22f, 0.045f, 0.045f}, s),  // left arm (x > 0)
    };
}

// ---------------------------------------------------------------------------------------------------------------------
// Projection

Vec3f ellipsoid_closest_point(Vec3f semi_axes, Vec3f q_in) noexcept {
    double a[3], q[3];
    for (int k = 0; k < 3; ++k) {
        a[k] = semi_axes[k];
        q[k] = q_in[k];
        // On a symmetry plane the closest point is not unique and the root sits at the pole: nudge off it.
        if (std::abs(q[k]) < 1e-9 * a[k]) q[k] = q[k] < 0.0 ? -1e-9 * a[k] : 1e-9 * a[k];
    }
    const double amin2 = std::min({a[0] * a[0], a[1] * a[1], a[2] * a[2]});
    auto F = [&](double s) {
        double sum = 0.0;
        for (int k = 0; k < 3; ++k) {
            const double r = a[k] * q[k] / (a[k] * a[k] + s);
            sum += r * r;
        }
        return sum - 1.0;
    };
    // Inside: F(0) < 0 and F -> +inf at s -> -amin^2 (F decreases in s). Outside (not expected): F(0) >= 0, s = 0.
    double lo = -amin2, hi = 0.0;
    if (F(0.0) < 0.0)
        for (int it = 0; it < 64; ++it) {
            const double mid = 0.5 * (lo + hi);
            if (mid <= lo || mid >= hi) break;
            if (F(mid) > 0.0)
                lo = mid;
            else
                hi = mid;
        }
    double x[3];
    for (int k = 0; k < 3; ++k) x[k] = a[k] * a[k] * q[k] / (a[k] * a[k] + hi);
    // Radial snap onto the surface, then out by a few float ulps until the float point is not inside.
    double g = 0.0;
    for (int k = 0; k < 3; ++k) g += (x[k] / a[k]) * (x[k] / a[k]);
    const double scale = 1.0 / std::sqrt(g);
    Vec3f out{static_cast<float>(x[0] * scale), static_cast<float>(x[1] * scale), static_cast<float>(x[2] * scale)};
    for (int it = 0; it < 8; ++it) {
        const float f = (out[0] / semi_axes[0]) * (out[0] / semi_axes[0]) +
                        (out[1] / semi_axes[1]) * (out[1] / semi_axes[1]) +
                        (out[2] / semi_axes[2]) * (out[2] / semi_axes[2]);
        if (f >= 1.0f) break;
        for (float& v : out) v *= 1.0f + 2e-7f;
    }
    return out;
}

Contact project_point(const Collider& col, Vec3f p) noexcept {
    switch (col.kind) {
    case ColliderKind::plane: return project_kind<ColliderKind::plane>(col, p);
    case ColliderKind::sphere: return project_kind<ColliderKind::sphere>(col, p);
    case ColliderKind::disc: return project_kind<ColliderKind::disc>(col, p);
    case ColliderKind::capsule: return project_kind<ColliderKind::capsule>(col, p);
    case ColliderKind::ellipsoid: return project_kind<ColliderKind::ellipsoid>(col, p);
    }
    return Contact{false, p, {}};
}

bool is_inside(const Collider& col, Vec3f p, float slack) noexcept {
    Collider c = col;
    c.thickness = col.thickness - slack; // may go negative: a point on the surface is then outside
    switch (col.kind) {
    case ColliderKind::ellipsoid: {
        const Vec3f A{col.size[0] + c.thickness, col.size[1] + c.thickness, col.size[2] + c.thickness};
        const auto& R = col.rotation;
        const float wx = p[0] - col.centre[0], wy = p[1] - col.centre[1], wz = p[2] - col.centre[2];
        const Vec3f q{R[0] * wx + R[3] * wy + R[6] * wz, R[1] * wx + R[4] * wy + R[7] * wz,
                      R[2] * wx + R[5] * wy + R[8] * wz};
        return (q[0] / A[0]) * (q[0] / A[0]) + (q[1] / A[1]) * (q[1] / A[1]) + (q[2] / A[2]) * (q[2] / A[2]) < 1.0f;
    }
    case ColliderKind::disc: {
        // Distance to the solid cylinder < thickness (or inside it).
        const float R = col.size[0], top = col.centre[1], bottom = col.centre[1] - col.size[1];
        const float dx = p[0] - col.centre[0], dz = p[2] - col.centre[2];
        const float r = std::sqrt(dx * dx + dz * dz);
        const float er = std::max(r - R, 0.0f), ey = p[1] > top ? p[1] - top : (p[1] < bottom ? bottom - p[1] : 0.0f);
        // Signed distance to the solid: negative inside (depth below the nearest face).
        const float sd = (er == 0.0f && ey == 0.0f) ? -std::min({top - p[1], R - r, p[1] - bottom})
                                                    : std::sqrt(er * er + ey * ey);
        return sd < c.thickness;
    }
    default: return project_point(c, p).inside;
    }
}

// ---------------------------------------------------------------------------------------------------------------------
// The collide stage

void collide_range(const Collider& col, float* x, float* y, float* z, float* vx, float* vy, float* vz,
                   const float* inv_mass, std::size_t begin, std::size_t end) noexcept {
    switch (col.kind) {
    case ColliderKind::plane: collide_loop<ColliderKind::plane>(col, x, y, z, vx, vy, vz, inv_mass, begin, end); break;
    case ColliderKind::sphere: collide_loop<ColliderKind::sphere>(col, x, y, z, vx, vy, vz, inv_mass, begin, end); break;
    case ColliderKind::disc: collide_loop<ColliderKind::disc>(col, x, y, z, vx, vy, vz, inv_mass, begin, end); break;
    case ColliderKind::capsule:
        collide_loop<ColliderKind::capsule>(col, x, y, z, vx, vy, vz, inv_mass, begin, end);
        break;
    case ColliderKind::ellipsoid:
        collide_loop<ColliderKind::ellipsoid>(col, x, y, z, vx, vy, vz, inv_mass, begin, end);
        break;
    }
}

void collide_range(std::span<const Collider> colliders, float* x, float* y, float* z, float* vx, float* vy, float* vz,
                   const float* inv_mass, std::size_t begin, std::size_t end) noexcept {
    constexpr int max_passes = 4;
    for (std::size_t i = begin; i < end; ++i) {
        if (inv_mass[i] == 0.0f) continue;
        for (int pass = 0; pass < max_passes; ++pass) {
            bool any = false;
            for (const Collider& col : colliders) {
                const Contact c = project_point(col, {x[i], y[i], z[i]});
                if (!c.inside) continue;
                any = true;
                x[i] = c.point[0];
                y[i] = c.point[1];
                z[i] = c.point[2];
                respond(c.normal, col.friction, vx[i], vy[i], vz[i]);
            }
            if (!any) break;
        }
    }
}

} // namespace drape
