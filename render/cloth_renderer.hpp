// Draws the cloth from the vertex ring (vertex_ring.hpp) that core's output stage (drape/publish.hpp) fills:
// six float attributes, one per plane (x, y, z, nx, ny, nz) plus an optional strain plane (strain colours), a
// static index buffer of the triangles,
// Blinn-Phong shading with a point light, two-sided (back faces get the flipped normal and optionally their
// own colour), and round markers for pinned, grabbed and hovered particles.
//
// Level of detail: a grid cloth finer than lod_max_side x lod_max_side vertices is drawn through a coarser
// index buffer over every k-th row and column (the last row and column always included, so the outline is
// exact). The output stage still publishes every vertex with normals of the full mesh; only the triangles
// drawn are fewer. llvmpipe spends ~70 ns per triangle in its vertex and setup stages on this machine, so at
// 1M particles (2M triangles) the full mesh alone costs ~0.2 s per frame, while a 256 x 256 sampling covers
// the same screen area at about 2 pixels per cell. set_full_detail(true) (--full-mesh) draws every triangle.
//
// Lighting per pixel or per vertex: when the drawn triangles' mean edge is under vertex_lighting_below_px pixels
// on screen, the colour (the same Blinn-Phong, checker and strain colours) is computed at the vertices and
// interpolated. Such triangles shade a few pixels each, so per-pixel lighting adds nothing visible there, while in
// llvmpipe it was most of the drawing: at N = 200 (2.1 px edges) the swap of a frame took 17-18 ms lit per pixel
// and 7-8 ms lit per vertex (docs/viewer.md, "Drawing cost"). Zooming in past the threshold switches back.
//
// The vertex array object is set up once: attribute p reads plane p of region 0; a frame selects its region
// with the base vertex of glDrawElementsBaseVertex (region r starts r * region_stride_floats floats later,
// the same offset for every plane), so nothing is rebound or copied per frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include <Eigen/Core>
#include <glad/gl.h>

#include "shader.hpp"
#include "vertex_ring.hpp"

namespace drape::render {

/// Material and light of the cloth. Colours are sRGB in [0, 1]; the shader lights in linear space.
struct Shading {
    Eigen::Vector3f front_colour{0.78f, 0.20f, 0.17f};
    Eigen::Vector3f back_colour{0.93f, 0.80f, 0.55f};
    bool back_colour_enabled = true; ///< false: back faces use the front colour
    float ambient = 0.10f;           ///< [0, 1], fraction of the base colour lit without the point light
    float diffuse = 0.85f;           ///< kd [0, 1]
    float specular = 0.25f;          ///< ks [0, 1]
    float shininess = 32.0f;         ///< Blinn-Phong exponent [1, 512]
    Eigen::Vector3f light_position{1.1f, 0.7f, 1.3f}; ///< m, world space
    float light_intensity = 1.0f;                     ///< [0, 4]
    bool checker = true; ///< faint checker pattern on grid cloths (shows the shape while it moves)
    /// Colour by per-vertex strain (plane 6 of the region, drape/strain_field.hpp) instead of the material
    /// colours: 0 .. strain_max (0.05 = 5 %) over strain_colour_srgb()'s map; lighting as usual.
    bool strain_colours = false;
    float strain_max = 0.05f;
};

/// The strain colour map at t in [0, 1] (clamped; NaN reads as 1), sRGB: blue, cyan, green, yellow, red. The
/// shader uses the same stops; the viewer draws its colour bar with this.
Eigen::Vector3f strain_colour_srgb(float t);

class ClothRenderer {
  public:
    /// Planes per ring region: publish.hpp's six (x, y, z, nx, ny, nz) and the strain plane.
    static constexpr std::size_t vertex_planes = 7;
    static constexpr std::size_t strain_plane_index = 6;

    /// particle_count vertices laid out as publish.hpp describes (planes of plane_floats floats);
    /// grid_columns > 0 when the cloth is a grid of that many columns (enables the checker pattern).
    /// rest_x/y/z: positions (m) to measure the drawn triangles' mean edge from (the cloth as built).
    ClothRenderer(std::span<const std::uint32_t> triangles, std::size_t particle_count,
                  std::size_t plane_floats, std::uint32_t grid_columns, std::uint32_t grid_rows,
                  bool full_detail, std::span<const float> rest_x, std::span<const float> rest_y,
                  std::span<const float> rest_z);

    static constexpr std::uint32_t lod_max_side = 256;
    /// Lit per vertex below this mean edge on screen, in pixels (per pixel from it up).
    static constexpr float vertex_lighting_below_px = 4.0f;
    ~ClothRenderer();
    ClothRenderer(const ClothRenderer&) = delete;
    ClothRenderer& operator=(const ClothRenderer&) = delete;

    /// Waits for this frame's region to be free and returns it for the output stage to write.
    std::span<float> begin_frame(double* out_wait_ms = nullptr);
    /// The strain plane of a region begin_frame() returned (plane_floats floats).
    std::span<float> strain_plane(std::span<float> region) const noexcept {
        return region.subspan(strain_plane_index * plane_floats_, plane_floats_);
    }
    /// pixels_per_metre: the screen scale at the cloth (framebuffer pixels per metre at the camera's target);
    /// pixel_lighting forces lighting per pixel whatever the triangles' size.
    void draw_cloth(const Eigen::Matrix4f& view_projection, const Eigen::Vector3f& eye, const Shading& shading,
                    float pixels_per_metre, bool pixel_lighting);
    /// Replaces the marker list (only when pins change, not per frame). highlight / hover: particle index or
    /// SIZE_MAX.
    void set_markers(std::span<const std::uint32_t> pinned, std::size_t highlight, std::size_t hover);
    void draw_markers(const Eigen::Matrix4f& view_projection, float pixel_scale);
    /// Fences the region after every draw call that reads it and moves to the next region.
    void end_frame();

    std::size_t particle_count() const noexcept { return particle_count_; }
    /// Triangles drawn per frame (fewer than the cloth has when the level of detail is coarser).
    std::size_t triangle_count() const noexcept { return static_cast<std::size_t>(index_count_) / 3; }
    /// Every lod_stride()-th row and column is drawn (1 = full mesh).
    std::uint32_t lod_stride() const noexcept { return lod_stride_; }
    const VertexRing& ring() const noexcept { return ring_; }
    /// The last draw_cloth(): lit per vertex, and the drawn triangles' mean edge on screen (pixels).
    bool lit_per_vertex() const noexcept { return lit_per_vertex_; }
    float drawn_edge_px() const noexcept { return drawn_edge_px_; }

  private:
    GLint base_vertex() const noexcept { return static_cast<GLint>(region_ * ring_.region_stride_floats()); }

    std::size_t particle_count_;
    std::size_t plane_floats_;
    std::uint32_t grid_columns_;
    std::uint32_t lod_stride_ = 1;
    float drawn_edge_m_ = 0.0f;   ///< mean edge of the drawn triangles as built, m
    float drawn_edge_px_ = 0.0f;  ///< the same on screen at the last draw, pixels
    bool lit_per_vertex_ = false; ///< the last draw's lighting
    VertexRing ring_;
    std::size_t region_ = 0;
    bool frame_open_ = false;
    GLuint vao_ = 0;
    GLuint index_buffer_ = 0;
    GLsizei index_count_ = 0;
    GLuint marker_buffer_ = 0;
    GLsizei pinned_count_ = 0;
    GLsizei highlight_count_ = 0;
    GLsizei hover_count_ = 0;
    Program cloth_program_;
    Program cloth_vertex_lit_program_;
    Program marker_program_;
};

} // namespace drape::render
