#include "stage.hpp"

#include <cmath>
#include <vector>

namespace drape::render {

namespace {

const char* const background_vs = R"(#version 450 core
out float v_t;
void main() {
    // One triangle covering the viewport.
    vec2 p = vec2((gl_VertexID << 1) & 2, gl_VertexID & 2) * 2.0 - 1.0;
    v_t = p.y * 0.5 + 0.5;
    gl_Position = vec4(p, 0.0, 1.0);
}
)";

const char* const background_fs = R"(#version 450 core
in float v_t;
out vec4 out_colour;
void main() {
    vec3 bottom = vec3(0.075, 0.082, 0.095);
    vec3 top = vec3(0.235, 0.262, 0.305);
    out_colour = vec4(mix(bottom, top, v_t), 1.0);
}
)";

const char* const grid_vs = R"(#version 450 core
layout(location = 0) in vec4 a_position_weight;  // xyz, line weight (0 minor, 1 major)
uniform mat4 u_view_projection;
out vec3 v_position;
out float v_weight;
void main() {
    v_position = a_position_weight.xyz;
    v_weight = a_position_weight.w;
    gl_Position = u_view_projection * vec4(v_position, 1.0);
}
)";

const char* const grid_fs = R"(#version 450 core
in vec3 v_position;
in float v_weight;
uniform vec3 u_centre;
uniform float u_half_extent;
out vec4 out_colour;
void main() {
    float r = length(v_position.xz - u_centre.xz) / u_half_extent;
    float fade = clamp(1.0 - r * r, 0.0, 1.0);
    vec3 c = mix(vec3(0.36, 0.39, 0.44), vec3(0.58, 0.62, 0.68), v_weight);
    out_colour = vec4(c, fade * mix(0.45, 0.8, v_weight));
}
)";

} // namespace

Stage::Stage(float ground_y, float centre_x, float centre_z, float half_extent, float spacing)
    : ground_y_(ground_y), half_extent_(half_extent), centre_(centre_x, ground_y, centre_z),
      background_(background_vs, background_fs, "background"), grid_(grid_vs, grid_fs, "ground grid") {
    std::vector<float> v;
    const int lines = static_cast<int>(std::floor(half_extent / spacing));
    for (int i = -lines; i <= lines; ++i) {
        const float o = static_cast<float>(i) * spacing;
        const float w = (i % 5 == 0) ? 1.0f : 0.0f;
        const float a = -lines * spacing, b = lines * spacing;
        // Line along z at x = o, and along x at z = o.
        v.insert(v.end(), {centre_x + o, ground_y, centre_z + a, w, centre_x + o, ground_y, centre_z + b, w});
        v.insert(v.end(), {centre_x + a, ground_y, centre_z + o, w, centre_x + b, ground_y, centre_z + o, w});
    }
    vertex_count_ = static_cast<GLsizei>(v.size() / 4);
    glCreateBuffers(1, &buffer_);
    glNamedBufferStorage(buffer_, static_cast<GLsizeiptr>(v.size() * sizeof(float)), v.data(), 0);
    glCreateVertexArrays(1, &vao_);
    glEnableVertexArrayAttrib(vao_, 0);
    glVertexArrayAttribFormat(vao_, 0, 4, GL_FLOAT, GL_FALSE, 0);
    glVertexArrayAttribBinding(vao_, 0, 0);
    glVertexArrayVertexBuffer(vao_, 0, buffer_, 0, 4 * sizeof(float));
    glCreateVertexArrays(1, &empty_vao_);
}

Stage::~Stage() {
    glDeleteVertexArrays(1, &vao_);
    glDeleteVertexArrays(1, &empty_vao_);
    glDeleteBuffers(1, &buffer_);
}

void Stage::draw_background() const {
    glDepthMask(GL_TRUE);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glDisable(GL_DEPTH_TEST);
    glDepthMask(GL_FALSE);
    glUseProgram(background_.id());
    glBindVertexArray(empty_vao_);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    glDepthMask(GL_TRUE);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
}

void Stage::draw_ground(const Eigen::Matrix4f& view_projection, const Eigen::Vector3f& /*eye*/) const {
    glUseProgram(grid_.id());
    glUniformMatrix4fv(grid_.uniform("u_view_projection"), 1, GL_FALSE, view_projection.data());
    glUniform3fv(grid_.uniform("u_centre"), 1, centre_.data());
    glUniform1f(grid_.uniform("u_half_extent"), half_extent_);
    glEnable(GL_BLEND);
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
    glDepthMask(GL_FALSE);
    glBindVertexArray(vao_);
    glDrawArrays(GL_LINES, 0, vertex_count_);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
}

} // namespace drape::render
