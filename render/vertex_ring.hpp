// The zero-copy vertex path (DESIGN.md "Drawing"): one OpenGL buffer, allocated once with glBufferStorage and
// mapped once, persistently and coherently (GL_MAP_WRITE_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT).
// It holds region_count regions used in turn: while the GPU still reads region n-1 (or n-2), core's output
// stage writes frame n straight into region n through the mapped pointer. Each region is guarded by a fence
// placed after the last draw call that reads it; acquire() waits on that fence before handing the region out
// again, so the CPU never overwrites vertex data the GPU has not consumed. Nothing is copied per frame: no
// glBufferSubData, no staging array, no unmap/remap.
//
//   frame:    n            n+1          n+2          n+3
//   region:   0            1            2            0  <- acquire(0) waits for frame n's fence
#pragma once

#include <array>
#include <cstddef>
#include <span>

#include <glad/gl.h>

namespace drape::render {

class VertexRing {
  public:
    static constexpr std::size_t region_count = 3;

    /// Allocates and maps region_count regions of `region_floats` floats each (region starts 256-byte
    /// aligned). Throws std::runtime_error when the driver refuses the storage or the mapping.
    explicit VertexRing(std::size_t region_floats);
    ~VertexRing();
    VertexRing(const VertexRing&) = delete;
    VertexRing& operator=(const VertexRing&) = delete;

    /// Waits until the GPU is done with the region's previous contents, then returns its mapped floats.
    /// out_wait_ms (optional) receives the time spent waiting.
    std::span<float> acquire(std::size_t region, double* out_wait_ms = nullptr);
    /// Fences the region after the draw calls that read it have been issued.
    void release(std::size_t region);

    GLuint buffer() const noexcept { return buffer_; }
    std::size_t region_floats() const noexcept { return region_floats_; }
    /// Distance between regions, in floats (region_floats rounded up to 256 bytes).
    std::size_t region_stride_floats() const noexcept { return stride_floats_; }
    std::size_t total_bytes() const noexcept { return stride_floats_ * region_count * sizeof(float); }

  private:
    GLuint buffer_ = 0;
    float* mapped_ = nullptr;
    std::size_t region_floats_ = 0;
    std::size_t stride_floats_ = 0;
    std::array<GLsync, region_count> fence_{};
};

} // namespace drape::render
