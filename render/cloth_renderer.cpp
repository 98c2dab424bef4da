#include "cloth_renderer.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <initializer_list>
#include <stdexcept>
#include <string>
#include <vector>

namespace drape::render {

namespace {

// The cloth's shaders are put together from the pieces below (cloth_source): one copy of the vertex inputs, the
// material's uniforms and the lighting, shared by the per-pixel and the per-vertex programs.

// Vertex shader inputs: the ring's planes and the grid's shape.
const char* const cloth_inputs = R"(
layout(location = 0) in float px;
layout(location = 1) in float py;
layout(location = 2) in float pz;
layout(location = 3) in float nx;
layout(location = 4) in float ny;
layout(location = 5) in float nz;
layout(location = 6) in float strain;  // plane 6: per-vertex strain (drape/strain_field.hpp), when written
uniform mat4 u_view_projection;
uniform int u_base_vertex;  // gl_VertexID includes the base vertex
uniform int u_columns;      // > 0: grid cloth, index = row * columns + column
vec2 grid_coordinates() {   // (column, row) / (columns - 1) of a grid cloth's vertex, else 0
    int k = gl_VertexID - u_base_vertex;
    return u_columns > 0 ? vec2(k % u_columns, k / u_columns) / float(max(u_columns - 1, 1)) : vec2(0.0);
}
)";

// The material, the light and the colour of a lit point (either stage).
const char* const cloth_shading = R"(
uniform vec3 u_eye;
uniform vec3 u_light_position;
uniform float u_light_intensity;
uniform vec3 u_front;       // linear RGB
uniform vec3 u_back;        // linear RGB
uniform float u_ambient;
uniform float u_diffuse;
uniform float u_specular;
uniform float u_shininess;
uniform float u_checker;    // 0 = off, else the darkening of every other square
uniform float u_strain_max; // > 0: colour by strain, 0 .. u_strain_max over the colour map below
const vec3 strain_stops[5] = vec3[5](STRAIN_STOPS);  // sRGB, the same as strain_colour_srgb()
vec3 strain_colour(float t) {
    float u = clamp(t, 0.0, 1.0) * 4.0;
    int i = min(int(u), 3);
    return pow(mix(strain_stops[i], strain_stops[i + 1], u - float(i)), vec3(2.2));  // to linear
}
// The base colour's factor of the checker pattern at grid coordinates g (1 on light squares).
float checker(vec2 g) {
    vec2 cell = floor(g * 16.0 - 1e-4);
    return 1.0 - u_checker * mod(cell.x + cell.y, 2.0);
}
// The base colour of one side (u_front or u_back) at a point of strain s and grid coordinates g: the strain map when
// strain colours are on, else the side's colour times the checker (1 when the checker is off).
vec3 surface_colour(vec3 side, float s, vec2 g) {
    return u_strain_max > 0.0 ? strain_colour(s / u_strain_max) : side * checker(g);
}
// Blinn-Phong at point p with unit normal n (facing the side lit) and linear base colour; sRGB out.
vec3 shade(vec3 p, vec3 n, vec3 base) {
    vec3 l = normalize(u_light_position - p);
    vec3 v = normalize(u_eye - p);
    vec3 h = normalize(l + v);
    float ndl = max(dot(n, l), 0.0);
    float spec = ndl > 0.0 ? pow(max(dot(n, h), 0.0), u_shininess) : 0.0;
    vec3 c = u_ambient * base + u_light_intensity * (u_diffuse * ndl * base + vec3(u_specular * spec));
    return pow(clamp(c, 0.0, 1.0), vec3(1.0 / 2.2));
}
)";

// Lit per pixel: the vertex shader passes position, normal, grid coordinates and strain on.
const char* const cloth_vs_main = R"(
out vec3 v_position;
out vec3 v_normal;
out vec2 v_grid;
out float v_strain;
void main() {
    v_position = vec3(px, py, pz);
    v_strain = strain;
    v_normal = vec3(nx, ny, nz);
    v_grid = grid_coordinates();
    gl_Position = u_view_projection * vec4(v_position, 1.0);
}
)";

const char* const cloth_fs_main = R"(
in vec3 v_position;
in vec3 v_normal;
in vec2 v_grid;
in float v_strain;
out vec4 out_colour;
void main() {
    // Two-sided lighting: the back face is lit with the flipped normal.
    vec3 n = gl_FrontFacing ? normalize(v_normal) : -normalize(v_normal);
    vec3 base = surface_colour(gl_FrontFacing ? u_front : u_back, v_strain, v_grid);
    out_colour = vec4(shade(v_position, n, base), 1.0);
}
)";

// Lit per vertex, for cloths whose drawn triangles are a few pixels across (ClothRenderer::draw_cloth): the same
// colour computed at the vertices for both sides and interpolated; the fragment shader only picks the side.
// llvmpipe's cost of a fragment grows with what its shader computes, and small triangles shade many fragments each
// (docs/viewer.md, "Drawing cost").
const char* const cloth_vertex_lit_vs_main = R"(
out vec3 v_front_colour;
out vec3 v_back_colour;
void main() {
    vec3 p = vec3(px, py, pz);
    vec3 n = normalize(vec3(nx, ny, nz));
    vec2 g = grid_coordinates();
    v_front_colour = shade(p, n, surface_colour(u_front, strain, g));
    v_back_colour = shade(p, -n, surface_colour(u_back, strain, g));
    gl_Position = u_view_projection * vec4(p, 1.0);
}
)";

const char* const cloth_vertex_lit_fs_main = R"(
in vec3 v_front_colour;
in vec3 v_back_colour;
out vec4 out_colour;
void main() {
    out_colour = vec4(gl_FrontFacing ? v_front_colour : v_back_colour, 1.0);
}
)";

const char* const marker_vs = R"(#version 450 core
layout(location = 0) in float px;
layout(location = 1) in float py;
layout(location = 2) in float pz;
uniform mat4 u_view_projection;
uniform float u_size;
void main() {
    gl_Position = u_view_projection * vec4(px, py, pz, 1.0);
    gl_Position.z -= 0.002 * gl_Position.w;  // drawn just in front of the cloth it sits on
    gl_PointSize = u_size;
}
)";

const char* const marker_fs = R"(#version 450 core
uniform vec3 u_colour;
out vec4 out_colour;
void main() {
    vec2 d = gl_PointCoord * 2.0 - 1.0;
    float r = dot(d, d);
    if (r > 1.0) discard;
    out_colour = vec4(r > 0.55 ? vec3(0.05) : u_colour, 1.0);  // dark rim, bright centre
}
)";

/// Index buffer over every `stride`-th row and column of a columns x rows grid (last ones included), with the
/// same triangulation as scene "hang" (cells split by the (i+1, j)-(i, j+1) diagonal, counter-clockwise from
/// +normal).
std::vector<std::uint32_t> lod_triangles(std::uint32_t columns, std::uint32_t rows, std::uint32_t stride) {
    auto samples = [stride](std::uint32_t count) {
        std::vector<std::uint32_t> v;
        for (std::uint32_t i = 0; i + 1 < count; i += stride)
            v.push_back(i);
        v.push_back(count - 1);
        return v;
    };
    const std::vector<std::uint32_t> cs = samples(columns), rs = samples(rows);
    std::vector<std::uint32_t> t;
    t.reserve(6 * (cs.size() - 1) * (rs.size() - 1));
    for (std::size_t j = 0; j + 1 < rs.size(); ++j)
        for (std::size_t i = 0; i + 1 < cs.size(); ++i) {
            const std::uint32_t a = rs[j] * columns + cs[i], b = rs[j] * columns + cs[i + 1],
                                c = rs[j + 1] * columns + cs[i], d = rs[j + 1] * columns + cs[i + 1];
            t.insert(t.end(), {a, c, b, b, c, d});
        }
    return t;
}

/// The strain colour map's stops (sRGB, evenly spaced over 0 .. 1): blue, cyan, green, yellow, red.
constexpr float strain_stops[5][3] = {
    {0.18f, 0.26f, 0.72f}, {0.20f, 0.68f, 0.92f}, {0.30f, 0.80f, 0.32f}, {0.98f, 0.84f, 0.18f}, {0.86f, 0.13f, 0.10f}};

/// A cloth shader's source: the version line, then the pieces in order, with the colour map's stops written in (one
/// source for the shaders and the colour bar).
std::string cloth_source(std::initializer_list<const char*> pieces) {
    std::string s = "#version 450 core\n";
    for (const char* p : pieces)
        s += p;
    std::string stops;
    for (int i = 0; i < 5; ++i) {
        char v[80];
        std::snprintf(v, sizeof v, "%svec3(%.4f, %.4f, %.4f)", i ? ", " : "", double(strain_stops[i][0]),
                      double(strain_stops[i][1]), double(strain_stops[i][2]));
        stops += v;
    }
    if (const std::size_t at = s.find("STRAIN_STOPS"); at != std::string::npos) s.replace(at, 12, stops);
    return s;
}

/// Mean length (m) of the triangles' edges at the given positions (each edge counted once per triangle); 0 when
/// there are none or the positions are not given.
float mean_edge_length(std::span<const std::uint32_t> triangles, std::span<const float> x, std::span<const float> y,
                       std::span<const float> z) {
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
        for (int e = 0; e < 3; ++e) {
            const std::uint32_t a = triangles[t + e], b = triangles[t + (e + 1) % 3];
            if (a >= x.size() || b >= x.size() || a >= y.size() || b >= y.size() || a >= z.size() || b >= z.size())
                continue;
            const double dx = x[a] - x[b], dy = y[a] - y[b], dz = z[a] - z[b];
            sum += std::sqrt(dx * dx + dy * dy + dz * dz);
            ++count;
        }
    return count ? static_cast<float>(sum / double(count)) : 0.0f;
}

Eigen::Vector3f to_linear(const Eigen::Vector3f& srgb) {
    return {std::pow(srgb.x(), 2.2f), std::pow(srgb.y(), 2.2f), std::pow(srgb.z(), 2.2f)};
}

} // namespace

Eigen::Vector3f strain_colour_srgb(float t) {
    const float u = std::clamp(std::isfinite(t) ? t : 1.0f, 0.0f, 1.0f) * 4.0f;
    const int i = std::min(static_cast<int>(u), 3);
    const float f = u - float(i);
    Eigen::Vector3f c;
    for (int k = 0; k < 3; ++k)
        c[k] = strain_stops[i][k] + f * (strain_stops[i + 1][k] - strain_stops[i][k]);
    return c;
}

ClothRenderer::ClothRenderer(std::span<const std::uint32_t> triangles, std::size_t particle_count,
                             std::size_t plane_floats, std::uint32_t grid_columns, std::uint32_t grid_rows,
                             bool full_detail, std::span<const float> rest_x, std::span<const float> rest_y,
                             std::span<const float> rest_z)
    : particle_count_(particle_count), plane_floats_(plane_floats), grid_columns_(grid_columns),
      ring_(vertex_planes * plane_floats), cloth_program_(cloth_source({cloth_inputs, cloth_vs_main}).c_str(),
                     cloth_source({cloth_shading, cloth_fs_main}).c_str(), "cloth"),
      cloth_vertex_lit_program_(cloth_source({cloth_inputs, cloth_shading, cloth_vertex_lit_vs_main}).c_str(),
                                cloth_source({cloth_vertex_lit_fs_main}).c_str(), "cloth (lit per vertex)"),
      marker_program_(marker_vs, marker_fs, "marker") {
    std::vector<std::uint32_t> coarse;
    const std::uint32_t side = std::max(grid_columns, grid_rows);
    if (!full_detail && grid_columns > 1 && grid_rows > 1 && side > lod_max_side &&
        std::size_t{grid_columns} * grid_rows == particle_count) {
        lod_stride_ = (side - 1 + lod_max_side - 2) / (lod_max_side - 1);
        coarse = lod_triangles(grid_columns, grid_rows, lod_stride_);
        triangles = coarse;
    }
    drawn_edge_m_ = mean_edge_length(triangles, rest_x, rest_y, rest_z);
    if (triangles.size() > static_cast<std::size_t>(INT32_MAX))
        throw std::runtime_error("too many triangle indices for one draw call");
    index_count_ = static_cast<GLsizei>(triangles.size());
    // Static index buffer: written once here, never again.
    glCreateBuffers(1, &index_buffer_);
    glNamedBufferStorage(index_buffer_,
                         static_cast<GLsizeiptr>(std::max<std::size_t>(1, triangles.size()) * 4),
                         triangles.empty() ? nullptr : triangles.data(), 0);
    glCreateBuffers(1, &marker_buffer_);
    glNamedBufferData(marker_buffer_, 64, nullptr, GL_DYNAMIC_DRAW);

    glCreateVertexArrays(1, &vao_);
    for (GLuint p = 0; p < vertex_planes; ++p) {
        glEnableVertexArrayAttrib(vao_, p);
        glVertexArrayAttribFormat(vao_, p, 1, GL_FLOAT, GL_FALSE, 0);
        glVertexArrayAttribBinding(vao_, p, p);
        glVertexArrayVertexBuffer(vao_, p, ring_.buffer(),
                                  static_cast<GLintptr>(p * plane_floats_ * sizeof(float)), sizeof(float));
    }
    glVertexArrayElementBuffer(vao_, index_buffer_);
}

ClothRenderer::~ClothRenderer() {
    if (vao_) glDeleteVertexArrays(1, &vao_);
    if (index_buffer_) glDeleteBuffers(1, &index_buffer_);
    if (marker_buffer_) glDeleteBuffers(1, &marker_buffer_);
}

std::span<float> ClothRenderer::begin_frame(double* out_wait_ms) {
    frame_open_ = true;
    return ring_.acquire(region_, out_wait_ms);
}

void ClothRenderer::draw_cloth(const Eigen::Matrix4f& view_projection, const Eigen::Vector3f& eye,
                               const Shading& s, float pixels_per_metre, bool pixel_lighting) {
    drawn_edge_px_ = drawn_edge_m_ * pixels_per_metre;
    lit_per_vertex_ = !pixel_lighting && drawn_edge_px_ < vertex_lighting_below_px;
    const Program& program = lit_per_vertex_ ? cloth_vertex_lit_program_ : cloth_program_;
    glUseProgram(program.id());
    glUniformMatrix4fv(program.uniform("u_view_projection"), 1, GL_FALSE, view_projection.data());
    glUniform1i(program.uniform("u_base_vertex"), base_vertex());
    glUniform1i(program.uniform("u_columns"), static_cast<GLint>(grid_columns_));
    glUniform3fv(program.uniform("u_eye"), 1, eye.data());
    glUniform3fv(program.uniform("u_light_position"), 1, s.light_position.data());
    glUniform1f(program.uniform("u_light_intensity"), s.light_intensity);
    const Eigen::Vector3f front = to_linear(s.front_colour);
    const Eigen::Vector3f back = s.back_colour_enabled ? to_linear(s.back_colour) : front;
    glUniform3fv(program.uniform("u_front"), 1, front.data());
    glUniform3fv(program.uniform("u_back"), 1, back.data());
    glUniform1f(program.uniform("u_ambient"), s.ambient);
    glUniform1f(program.uniform("u_diffuse"), s.diffuse);
    glUniform1f(program.uniform("u_specular"), s.specular);
    glUniform1f(program.uniform("u_shininess"), s.shininess);
    glUniform1f(program.uniform("u_checker"), (s.checker && grid_columns_ > 1) ? 0.12f : 0.0f);
    // Strain colours read plane 6, which the caller wrote this frame (strain_plane()) only while they are on.
    glUniform1f(program.uniform("u_strain_max"), s.strain_colours ? std::max(s.strain_max, 1e-6f) : 0.0f);
    glBindVertexArray(vao_);
    glVertexArrayElementBuffer(vao_, index_buffer_);
    glDisable(GL_CULL_FACE);
    glDrawElementsBaseVertex(GL_TRIANGLES, index_count_, GL_UNSIGNED_INT, nullptr, base_vertex());
}

void ClothRenderer::set_markers(std::span<const std::uint32_t> pinned, std::size_t highlight,
                                std::size_t hover) {
    std::vector<std::uint32_t> list(pinned.begin(), pinned.end());
    pinned_count_ = static_cast<GLsizei>(list.size());
    highlight_count_ = highlight < particle_count_ ? 1 : 0;
    hover_count_ = hover < particle_count_ && hover != highlight ? 1 : 0;
    if (highlight_count_) list.push_back(static_cast<std::uint32_t>(highlight));
    if (hover_count_) list.push_back(static_cast<std::uint32_t>(hover));
    // Changes only when the user pins, grabs or hovers: a small upload then, never per frame.
    glNamedBufferData(marker_buffer_, static_cast<GLsizeiptr>(std::max<std::size_t>(1, list.size()) * 4),
                      list.empty() ? nullptr : list.data(), GL_DYNAMIC_DRAW);
}

void ClothRenderer::draw_markers(const Eigen::Matrix4f& view_projection, float pixel_scale) {
    if (pinned_count_ + highlight_count_ + hover_count_ == 0) return;
    glUseProgram(marker_program_.id());
    glUniformMatrix4fv(marker_program_.uniform("u_view_projection"), 1, GL_FALSE, view_projection.data());
    glBindVertexArray(vao_);
    glVertexArrayElementBuffer(vao_, marker_buffer_);
    glEnable(GL_PROGRAM_POINT_SIZE);
    const GLint size = marker_program_.uniform("u_size"), colour = marker_program_.uniform("u_colour");
    GLsizei first = 0;
    auto draw = [&](GLsizei count, float px, float r, float g, float b) {
        if (count == 0) return;
        glUniform1f(size, px * pixel_scale);
        glUniform3f(colour, r, g, b);
        glDrawElementsBaseVertex(GL_POINTS, count, GL_UNSIGNED_INT,
                                 reinterpret_cast<const void*>(static_cast<std::uintptr_t>(first) * 4),
                                 base_vertex());
        first += count;
    };
    draw(pinned_count_, 10.0f, 1.0f, 0.82f, 0.15f); // pinned: amber
    // The grabbed and hovered particles are shown even behind a fold, like a cursor.
    glDisable(GL_DEPTH_TEST);
    draw(highlight_count_, 14.0f, 0.2f, 0.9f, 1.0f); // grabbed: cyan
    draw(hover_count_, 9.0f, 0.95f, 0.95f, 0.95f);   // under the cursor: white
    glEnable(GL_DEPTH_TEST);
    glVertexArrayElementBuffer(vao_, index_buffer_);
}

void ClothRenderer::end_frame() {
    if (!frame_open_) return;
    ring_.release(region_);
    region_ = (region_ + 1) % VertexRing::region_count;
    frame_open_ = false;
}

} // namespace drape::render
