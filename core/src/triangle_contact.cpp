// The deepest point of a cloth triangle inside an analytic collider (triangle_contact.hpp has the method).
#include "drape/triangle_contact.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "closest_points.hpp"
#include "disc_lattice.hpp"

namespace drape {
namespace {

using namespace geom;

/// Signed distance of p to the solid of a sphere, capsule or disc (negative inside), m.
double solid_distance(const Collider& col, V3 p) noexcept {
    const V3 c = v3(col.centre);
    switch (col.kind) {
    case ColliderKind::sphere:
        return norm(p - c) - col.size[0];
    case ColliderKind::capsule: {
        const V3 ab = v3(col.axis) - c;
        const double len2 = dot(ab, ab);
        const double s = len2 > 0.0 ? std::clamp(dot(p - c, ab) / len2, 0.0, 1.0) : 0.0;
        return norm(p - (c + s * ab)) - col.size[0];
    }
    case ColliderKind::disc: {
        const double R = col.size[0], top = col.centre[1], bottom = double(col.centre[1]) - col.size[1];
        const double r = std::sqrt((p.x - c.x) * (p.x - c.x) + (p.z - c.z) * (p.z - c.z)); // not hypot: slow
        const double er = std::max(r - R, 0.0), ey = p.y > top ? p.y - top : (p.y < bottom ? bottom - p.y : 0.0);
        if (er == 0.0 && ey == 0.0) return -std::min({top - p.y, R - r, p.y - bottom});
        return std::sqrt(er * er + ey * ey);
    }
    case ColliderKind::plane:
        return dot(p - c, v3(col.axis));
    case ColliderKind::ellipsoid:
        break; // not a distance: see deepest()
    }
    return 0.0;
}

/// Barycentric coordinates of the point of triangle (a, b, c) closest to segment e0-e1 (exact): the segment's ends
/// against the triangle, the triangle's edges against the segment, and the segment crossing the triangle.
std::array<double, 3> closest_to_segment(V3 e0, V3 e1, V3 a, V3 b, V3 c) noexcept {
    std::array<double, 3> best{1.0, 0.0, 0.0};
    double best_d = std::numeric_limits<double>::max();
    auto point = [&](const std::array<double, 3>& k) { return k[0] * a + k[1] * b + k[2] * c; };
    auto offer = [&](const std::array<double, 3>& k, V3 other) {
        const double d = norm(point(k) - other);
        if (d < best_d) best_d = d, best = k;
    };
    offer(closest_on_triangle(e0, a, b, c), e0);
    offer(closest_on_triangle(e1, a, b, c), e1);
    const V3 corner[3] = {a, b, c};
    for (int k = 0; k < 3; ++k) {
        double s = 0.0, t = 0.0;
        closest_segments(corner[k], corner[(k + 1) % 3], e0, e1, s, t);
        std::array<double, 3> bary{0.0, 0.0, 0.0};
        bary[k] = 1.0 - s;
        bary[(k + 1) % 3] = s;
        offer(bary, e0 + t * (e1 - e0));
    }
    // The segment through the triangle's plane inside the triangle: distance 0 there.
    const V3 n = {(b - a).y * (c - a).z - (b - a).z * (c - a).y, (b - a).z * (c - a).x - (b - a).x * (c - a).z,
                  (b - a).x * (c - a).y - (b - a).y * (c - a).x};
    const double h0 = dot(e0 - a, n), h1 = dot(e1 - a, n);
    if ((h0 < 0.0) != (h1 < 0.0) && h0 != h1) {
        const V3 x = e0 + (h0 / (h0 - h1)) * (e1 - e0);
        const std::array<double, 3> k = closest_on_triangle(x, a, b, c);
        offer(k, x);
    }
    return best;
}

/// The deepest point of triangle (a, b, c) in the collider's solid grown by `grow` (m): whether it is inside
/// (strictly, in double) and its barycentric coordinates.
bool deepest(const Collider& col, float grow, V3 a, V3 b, V3 c, std::array<double, 3>& bary) noexcept {
    if (col.kind == ColliderKind::disc) {
        // The distance to the solid cylinder is at least the height above its top face (and below its bottom face):
        // a triangle with every vertex that high is clear (the usual case for a cloth lying on a table).
        const double top = col.centre[1], bottom = double(col.centre[1]) - col.size[1];
        if (std::min({a.y, b.y, c.y}) - top >= grow || bottom - std::max({a.y, b.y, c.y}) >= grow) return false;
    }
    const V3 centroid = (1.0 / 3.0) * (a + b + c);
    const double radius = std::max({norm(a - centroid), norm(b - centroid), norm(c - centroid)});
    auto at = [&](double s, double w) { return a + s * (b - a) + w * (c - a); };
    switch (col.kind) {
    case ColliderKind::plane: {
        const double da = solid_distance(col, a), db = solid_distance(col, b), dc = solid_distance(col, c);
        const double m = std::min({da, db, dc});
        bary = {m == da ? 1.0 : 0.0, m != da && m == db ? 1.0 : 0.0, m != da && m != db ? 1.0 : 0.0};
        return m < grow;
    }
    case ColliderKind::sphere: {
        const V3 cen = v3(col.centre);
        if (norm(centroid - cen) - col.size[0] - grow > radius) return false;
        bary = closest_on_triangle(cen, a, b, c);
        return norm(at(bary[1], bary[2]) - cen) < double(col.size[0]) + grow;
    }
    case ColliderKind::ellipsoid: {
        // Local frame (q = R^T (p - centre)) scaled by 1 / (semi-axes + grow): the grown ellipsoid is the unit ball.
        const auto& R = col.rotation;
        const double A[3] = {double(col.size[0]) + grow, double(col.size[1]) + grow, double(col.size[2]) + grow};
        if (norm(centroid - v3(col.centre)) - std::max({A[0], A[1], A[2]}) > radius) return false;
        auto scaled = [&](V3 p) {
            const V3 w = p - v3(col.centre);
            return V3{(R[0] * w.x + R[3] * w.y + R[6] * w.z) / A[0], (R[1] * w.x + R[4] * w.y + R[7] * w.z) / A[1],
                      (R[2] * w.x + R[5] * w.y + R[8] * w.z) / A[2]};
        };
        const V3 sa = scaled(a), sb = scaled(b), sc = scaled(c);
        bary = closest_on_triangle({0.0, 0.0, 0.0}, sa, sb, sc);
        return norm(sa + bary[1] * (sb - sa) + bary[2] * (sc - sa)) < 1.0;
    }
    case ColliderKind::capsule: {
        if (solid_distance(col, centroid) - grow > radius) return false;
        bary = closest_to_segment(v3(col.centre), v3(col.axis), a, b, c);
        return solid_distance(col, at(bary[1], bary[2])) < grow;
    }
    case ColliderKind::disc: {
        if (solid_distance(col, centroid) - grow > radius) return false;
        const double R = col.size[0], top = col.centre[1], bottom = double(col.centre[1]) - col.size[1];
        auto within = [&](V3 p) {
            return (p.x - col.centre[0]) * (p.x - col.centre[0]) + (p.z - col.centre[2]) * (p.z - col.centre[2]) <= R * R;
        };
        auto in_band = [&](V3 p) { return p.y >= bottom && p.y <= top; };
        if (within(a) && within(b) && within(c) &&
            ((a.y >= top && b.y >= top && c.y >= top) || (a.y <= bottom && b.y <= bottom && c.y <= bottom))) {
            // Above the top face (or below the bottom) everywhere and within the radius: the distance is the height
            // there, linear, so its minimum is a vertex.
            const double da = solid_distance(col, a), db = solid_distance(col, b), dc = solid_distance(col, c);
            const double m = std::min({da, db, dc});
            bary = {m == da ? 1.0 : 0.0, m != da && m == db ? 1.0 : 0.0, m != da && m != db ? 1.0 : 0.0};
            return m < grow;
        }
        if (in_band(a) && in_band(b) && in_band(c)) {
            // Between the faces everywhere: the distance is the horizontal distance to the axis minus R, so the
            // deepest point is the closest point of the triangle's horizontal projection to the axis.
            auto flat = [](V3 p) { return V3{p.x, 0.0, p.z}; };
            bary = closest_on_triangle({double(col.centre[0]), 0.0, double(col.centre[2])}, flat(a), flat(b), flat(c));
        } else {
            // Across a rim: the lattice minimum, its points closer than the rounded rim's radius (the margin; at
            // least 1 mm), 6 to 48 intervals a side. The true minimum of this convex f is at most a second-order
            // amount deeper (about (spacing / 2)^2 / (2 margin), ~10% of the margin).
            const double spacing = std::max(double(grow), 1e-3);
            const int m = std::clamp(int(std::ceil(2.0 * radius / spacing)), 4, disc_lattice::max_intervals);
            // In float, relative to the disc's top centre (the lattice's many evaluations are the cost here), a row
            // of the lattice per SIMD batch (disc_lattice.hpp, bit for bit its scalar reference).
            const V3 o = v3(col.centre);
            const disc_lattice::Triangle t{float(a.x - o.x), float(a.y - o.y), float(a.z - o.z),
                                           float(b.x - a.x), float(b.y - a.y), float(b.z - a.z),
                                           float(c.x - a.x), float(c.y - a.y), float(c.z - a.z),
                                           col.size[0],      col.size[1]};
            const std::array<int, 2> ij = disc_lattice::minimum(t, m);
            const double s = double(ij[0]) / m, w = double(ij[1]) / m;
            bary = {1.0 - s - w, s, w};
        }
        return solid_distance(col, at(bary[1], bary[2])) < grow;
    }
    }
    return false;
}

} // namespace

float enclosing_radius2(Vec3f a, Vec3f b, Vec3f c) noexcept {
    auto d2 = [](const Vec3f& p, const Vec3f& q) {
        return (p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]);
    };
    const float ab = d2(a, b), bc = d2(b, c), ca = d2(c, a);
    const float longest = std::max({ab, bc, ca});
    if (2.0f * longest >= ab + bc + ca) return 0.25f * longest; // right or obtuse: the longest edge's midpoint
    // Acute: the circumradius, R^2 = a^2 b^2 c^2 / (16 area^2) = ab bc ca / (4 |AB x AC|^2).
    const float ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2], vx = c[0] - a[0], vy = c[1] - a[1],
                vz = c[2] - a[2];
    const float cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
    const float cross2 = cx * cx + cy * cy + cz * cz;
    return cross2 > 0.0f ? std::min(ab * bc * ca / (4.0f * cross2), longest) : 0.25f * longest;
}

float core_measure(const Collider& col, Vec3f p) noexcept {
    const float t = col.thickness;
    float dx = p[0] - col.centre[0], dy = p[1] - col.centre[1], dz = p[2] - col.centre[2];
    switch (col.kind) {
    case ColliderKind::plane:
        return 0.0f;
    case ColliderKind::capsule: {
        const float ax = col.axis[0] - col.centre[0], ay = col.axis[1] - col.centre[1], az = col.axis[2] - col.centre[2];
        const float len2 = ax * ax + ay * ay + az * az;
        const float u = len2 > 0.0f ? std::clamp((dx * ax + dy * ay + dz * az) / len2, 0.0f, 1.0f) : 0.0f;
        dx -= u * ax, dy -= u * ay, dz -= u * az;
        [[fallthrough]];
    }
    case ColliderKind::sphere:
        return dx * dx + dy * dy + dz * dz;
    case ColliderKind::ellipsoid: {
        const auto& R = col.rotation;
        const float qx = (R[0] * dx + R[3] * dy + R[6] * dz) / (col.size[0] + t),
                    qy = (R[1] * dx + R[4] * dy + R[7] * dz) / (col.size[1] + t),
                    qz = (R[2] * dx + R[5] * dy + R[8] * dz) / (col.size[2] + t);
        return qx * qx + qy * qy + qz * qz;
    }
    case ColliderKind::disc:
        return float(solid_distance(col, v3(p))) - t; // the exact signed distance to the inflated disc
    }
    return 0.0f;
}

float clearance_from_measure(const Collider& col, float m) noexcept {
    const float t = col.thickness;
    switch (col.kind) {
    case ColliderKind::plane:
        return std::numeric_limits<float>::max();
    case ColliderKind::sphere:
    case ColliderKind::capsule:
        return std::sqrt(m) - (col.size[0] + t);
    case ColliderKind::ellipsoid: // scaling by 1 / A stretches no distance by more than 1 / min A
        return (std::min({col.size[0], col.size[1], col.size[2]}) + t) * (std::sqrt(m) - 1.0f);
    case ColliderKind::disc:
        return m;
    }
    return 0.0f;
}

bool triangle_clear_of(const Collider& col, float m0, float m1, float m2, float radius2) noexcept {
    const float t = col.thickness;
    switch (col.kind) {
    case ColliderKind::plane:
        return true;
    case ColliderKind::sphere:
    case ColliderKind::capsule: {
        const float rho = col.size[0] + t;
        return std::min({m0, m1, m2}) - radius2 >= rho * rho;
    }
    case ColliderKind::ellipsoid: {
        // Scaled by 1 / A (A = semi-axes + t) the inflated ellipsoid is the unit ball and no length grows by more
        // than 1 / min A.
        const float amin = std::min({col.size[0], col.size[1], col.size[2]}) + t;
        return std::min({m0, m1, m2}) - radius2 / (amin * amin) >= 1.0f;
    }
    case ColliderKind::disc: {
        const float far = std::max({m0, m1, m2});
        return far > 0.0f && far * far >= 4.0f * radius2; // the diameter bounds every edge
    }
    }
    return false;
}

TriangleContact triangle_contact(const Collider& col, Vec3f a, Vec3f b, Vec3f c) noexcept {
    TriangleContact out;
    if (col.kind == ColliderKind::plane) return out; // linear: the vertices decide
    std::array<double, 3> bary{};
    if (!deepest(col, col.thickness, v3(a), v3(b), v3(c), bary)) return out;
    const Vec3f q{float(bary[0] * a[0] + bary[1] * b[0] + bary[2] * c[0]),
                  float(bary[0] * a[1] + bary[1] * b[1] + bary[2] * c[1]),
                  float(bary[0] * a[2] + bary[1] * b[2] + bary[2] * c[2])};
    const Contact pr = project_point(col, q);
    if (!pr.inside) return out; // inside in double, on the surface in float
    out.inside = true;
    out.barycentric = {float(bary[0]), float(bary[1]), float(bary[2])};
    out.point = q;
    out.surface = pr.point;
    out.normal = pr.normal;
    out.depth = (pr.point[0] - q[0]) * pr.normal[0] + (pr.point[1] - q[1]) * pr.normal[1] +
                (pr.point[2] - q[2]) * pr.normal[2];
    return out;
}

bool triangle_meets_collider(const Collider& col, Vec3f a, Vec3f b, Vec3f c, float margin) noexcept {
    std::array<double, 3> bary{};
    return deepest(col, margin, v3(a), v3(b), v3(c), bary);
}

} // namespace drape
