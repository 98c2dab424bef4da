// What the cloth is drawn on: a vertical background gradient and a ground grid (lines every `spacing` m, a
// brighter line every 5th, fading with distance). Static geometry, uploaded once.
#pragma once

#include <Eigen/Core>
#include <glad/gl.h>

#include "shader.hpp"

namespace drape::render {

class Stage {
  public:
    /// Ground grid in the plane y = ground_y, centred on (centre_x, centre_z), half_extent m to each side.
    Stage(float ground_y, float centre_x, float centre_z, float half_extent, float spacing);
    ~Stage();
    Stage(const Stage&) = delete;
    Stage& operator=(const Stage&) = delete;

    /// Clears colour and depth and draws the gradient (no depth writes).
    void draw_background() const;
    void draw_ground(const Eigen::Matrix4f& view_projection, const Eigen::Vector3f& eye) const;
    float ground_y() const noexcept { return ground_y_; }

  private:
    float ground_y_;
    float half_extent_;
    Eigen::Vector3f centre_;
    GLuint vao_ = 0;
    GLuint buffer_ = 0;
    GLsizei vertex_count_ = 0;
    GLuint empty_vao_ = 0;
    Program background_;
    Program grid_;
};

} // namespace drape::render
