// Draws a scene's analytic colliders (drape/colliders.hpp) as lit solid meshes: spheres, ellipsoids (the
// body), discs (tables), capsules. Planes are shown by the ground grid (stage.hpp). Meshes are built once per
// scene and uploaded to a static buffer; colliders do not move.
#pragma once

#include <span>

#include <Eigen/Core>
#include <glad/gl.h>

#include "drape/colliders.hpp"
#include "shader.hpp"

namespace drape::render {

class ColliderRenderer {
  public:
    explicit ColliderRenderer(std::span<const Collider> colliders);
    ~ColliderRenderer();
    ColliderRenderer(const ColliderRenderer&) = delete;
    ColliderRenderer& operator=(const ColliderRenderer&) = delete;

    void draw(const Eigen::Matrix4f& view_projection, const Eigen::Vector3f& eye,
              const Eigen::Vector3f& light_position) const;
    bool empty() const noexcept { return vertex_count_ == 0; }

  private:
    GLuint vao_ = 0;
    GLuint buffer_ = 0;
    GLsizei vertex_count_ = 0;
    Program program_;
};

} // namespace drape::render
