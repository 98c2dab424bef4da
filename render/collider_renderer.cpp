#include "collider_renderer.hpp"

#include <cmath>
#include <vector>

#include <Eigen/Geometry>

namespace drape::render {

namespace {

const char* const collider_vs = R"(#version 450 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_view_projection;
out vec3 v_position;
out vec3 v_normal;
void main() {
    v_position = a_position;
    v_normal = a_normal;
    gl_Position = u_view_projection * vec4(a_position, 1.0);
}
)";

const char* const collider_fs = R"(#version 450 core
in vec3 v_position;
in vec3 v_normal;
uniform vec3 u_eye;
uniform vec3 u_light_position;
out vec4 out_colour;
void main() {
    vec3 n = normalize(v_normal);
    vec3 l = normalize(u_light_position - v_position);
    vec3 v = normalize(u_eye - v_position);
    vec3 h = normalize(l + v);
    vec3 base = vec3(0.42, 0.45, 0.50);  // linear grey-blue: reads as "solid, not cloth"
    float ndl = max(dot(n, l), 0.0);
    float spec = ndl > 0.0 ? pow(max(dot(n, h), 0.0), 48.0) : 0.0;
    vec3 c = 0.18 * base + 0.8 * ndl * base + vec3(0.25 * spec);
    out_colour = vec4(pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2)), 1.0);
}
)";

constexpr float pi = 3.14159265358979f;

struct Mesh {
    std::vector<float> v; // x y z nx ny nz per vertex, triangles
    void add(const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
        v.insert(v.end(), {p.x(), p.y(), p.z(), n.x(), n.y(), n.z()});
    }
};

Eigen::Vector3f vec(const Vec3f& a) {
    return {a[0], a[1], a[2]};
}

/// Unit sphere point and normal at (theta from +y, phi around y).
Eigen::Vector3f sphere_dir(float theta, float phi) {
    return {std::sin(theta) * std::cos(phi), std::cos(theta), std::sin(theta) * std::sin(phi)};
}

/// Ellipsoid x = c + R diag(s) u for unit u; its normal is R diag(1/s) u (normalised).
void add_ellipsoid(Mesh& m, const Eigen::Vector3f& c, const Eigen::Vector3f& s, const Eigen::Matrix3f& r) {
    constexpr int rings = 24, segments = 40;
    auto point = [&](int i, int j, Eigen::Vector3f& p, Eigen::Vector3f& n) {
        const Eigen::Vector3f u = sphere_dir(pi * float(i) / rings, 2.0f * pi * float(j) / segments);
        p = c + r * u.cwiseProduct(s);
        n = (r * u.cwiseQuotient(s)).normalized();
    };
    for (int i = 0; i < rings; ++i)
        for (int j = 0; j < segments; ++j) {
            Eigen::Vector3f p[4], n[4];
            point(i, j, p[0], n[0]);
            point(i + 1, j, p[1], n[1]);
            point(i + 1, j + 1, p[2], n[2]);
            point(i, j + 1, p[3], n[3]);
            for (int k : {0, 1, 2, 0, 2, 3})
                m.add(p[k], n[k]);
        }
}

/// Solid cylinder of `radius` from top centre `top` down by `height`, with caps.
void add_disc(Mesh& m, const Eigen::Vector3f& top, float radius, float height) {
    constexpr int segments = 64;
    const Eigen::Vector3f down(0.0f, -height, 0.0f), up = Eigen::Vector3f::UnitY();
    for (int j = 0; j < segments; ++j) {
        const float a0 = 2.0f * pi * float(j) / segments, a1 = 2.0f * pi * float(j + 1) / segments;
        const Eigen::Vector3f d0(std::cos(a0), 0.0f, std::sin(a0)), d1(std::cos(a1), 0.0f, std::sin(a1));
        const Eigen::Vector3f t0 = top + radius * d0, t1 = top + radius * d1;
        // Top cap, side, bottom cap.
        m.add(top, up), m.add(t1, up), m.add(t0, up);
        m.add(t0, d0), m.add(t1, d1), m.add(t1 + down, d1);
        m.add(t0, d0), m.add(t1 + down, d1), m.add(t0 + down, d0);
        m.add(top + down, -up), m.add(t0 + down, -up), m.add(t1 + down, -up);
    }
}

/// Capsule: a cylinder between a and b plus a sphere at each end (simple, overlapping).
void add_capsule(Mesh& m, const Eigen::Vector3f& a, const Eigen::Vector3f& b, float radius) {
    add_ellipsoid(m, a, Eigen::Vector3f::Constant(radius), Eigen::Matrix3f::Identity());
    add_ellipsoid(m, b, Eigen::Vector3f::Constant(radius), Eigen::Matrix3f::Identity());
    const Eigen::Vector3f axis = b - a;
    const float len = axis.norm();
    if (len < 1e-6f) return;
    const Eigen::Vector3f w = axis / len;
    const Eigen::Vector3f u =
        (std::fabs(w.x()) < 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitY()).cross(w).normalized();
    const Eigen::Vector3f v = w.cross(u);
    constexpr int segments = 40;
    for (int j = 0; j < segments; ++j) {
        const float a0 = 2.0f * pi * float(j) / segments, a1 = 2.0f * pi * float(j + 1) / segments;
        const Eigen::Vector3f d0 = std::cos(a0) * u + std::sin(a0) * v,
                              d1 = std::cos(a1) * u + std::sin(a1) * v;
        m.add(a + radius * d0, d0), m.add(b + radius * d0, d0), m.add(b + radius * d1, d1);
        m.add(a + radius * d0, d0), m.add(b + radius * d1, d1), m.add(a + radius * d1, d1);
    }
}

} // namespace

ColliderRenderer::ColliderRenderer(std::span<const Collider> colliders)
    : program_(collider_vs, collider_fs, "collider") {
    Mesh m;
    for (const Collider& c : colliders) {
        switch (c.kind) {
        case ColliderKind::sphere:
            add_ellipsoid(m, vec(c.centre), Eigen::Vector3f::Constant(c.size[0]),
                          Eigen::Matrix3f::Identity());
            break;
        case ColliderKind::ellipsoid: {
            Eigen::Matrix3f r;
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    r(i, j) = c.rotation[static_cast<std::size_t>(3 * i + j)];
            add_ellipsoid(m, vec(c.centre), vec(c.size), r);
            break;
        }
        case ColliderKind::disc:
            add_disc(m, vec(c.centre), c.size[0], c.size[1]);
            break;
        case ColliderKind::capsule:
            add_capsule(m, vec(c.centre), vec(c.axis), c.size[0]);
            break;
        case ColliderKind::plane: // the ground grid shows it
            break;
        }
    }
    vertex_count_ = static_cast<GLsizei>(m.v.size() / 6);
    glCreateBuffers(1, &buffer_);
    glNamedBufferStorage(buffer_,
                         static_cast<GLsizeiptr>(std::max<std::size_t>(1, m.v.size()) * sizeof(float)),
                         m.v.empty() ? nullptr : m.v.data(), 0);
    glCreateVertexArrays(1, &vao_);
    for (GLuint a = 0; a < 2; ++a) {
        glEnableVertexArrayAttrib(vao_, a);
        glVertexArrayAttribFormat(vao_, a, 3, GL_FLOAT, GL_FALSE, a * 3 * sizeof(float));
        glVertexArrayAttribBinding(vao_, a, 0);
    }
    glVertexArrayVertexBuffer(vao_, 0, buffer_, 0, 6 * sizeof(float));
}

ColliderRenderer::~ColliderRenderer() {
    glDeleteVertexArrays(1, &vao_);
    glDeleteBuffers(1, &buffer_);
}

void ColliderRenderer::draw(const Eigen::Matrix4f& view_projection, const Eigen::Vector3f& eye,
                            const Eigen::Vector3f& light_position) const {
    if (vertex_count_ == 0) return;
    glUseProgram(program_.id());
    glUniformMatrix4fv(program_.uniform("u_view_projection"), 1, GL_FALSE, view_projection.data());
    glUniform3fv(program_.uniform("u_eye"), 1, eye.data());
    glUniform3fv(program_.uniform("u_light_position"), 1, light_position.data());
    glBindVertexArray(vao_);
    glEnable(GL_DEPTH_TEST);
    glDrawArrays(GL_TRIANGLES, 0, vertex_count_);
}

} // namespace drape::render
