#include "vertex_ring.hpp"

#include <chrono>
#include <stdexcept>
#include <string>

namespace drape::render {

namespace {
constexpr GLbitfield map_flags = GL_MAP_WRITE_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
constexpr std::size_t region_alignment_floats = 256 / sizeof(float);
} // namespace

VertexRing::VertexRing(std::size_t region_floats)
    : region_floats_(region_floats), stride_floats_((region_floats + region_alignment_floats - 1) /
                                                    region_alignment_floats * region_alignment_floats) {
    if (stride_floats_ == 0) stride_floats_ = region_alignment_floats;
    glCreateBuffers(1, &buffer_);
    glGetError();
    glNamedBufferStorage(buffer_, static_cast<GLsizeiptr>(total_bytes()), nullptr, map_flags);
    if (const GLenum e = glGetError(); e != GL_NO_ERROR) {
        glDeleteBuffers(1, &buffer_);
        throw std::runtime_error("glBufferStorage of " + std::to_string(total_bytes()) +
                                 " bytes for the vertex ring failed (GL error " + std::to_string(e) + ")");
    }
    mapped_ = static_cast<float*>(
        glMapNamedBufferRange(buffer_, 0, static_cast<GLsizeiptr>(total_bytes()), map_flags));
    if (!mapped_) {
        glDeleteBuffers(1, &buffer_);
        throw std::runtime_error("cannot map the vertex ring persistently (glMapBufferRange returned null)");
    }
}

VertexRing::~VertexRing() {
    for (GLsync& f : fence_) {
        if (!f) continue;
        glClientWaitSync(f, GL_SYNC_FLUSH_COMMANDS_BIT, 1'000'000'000);
        glDeleteSync(f);
        f = nullptr;
    }
    if (buffer_) {
        glUnmapNamedBuffer(buffer_);
        glDeleteBuffers(1, &buffer_);
    }
}

std::span<float> VertexRing::acquire(std::size_t region, double* out_wait_ms) {
    const auto start = std::chrono::steady_clock::now();
    GLsync& f = fence_[region];
    if (f) {
        // Flush on the first wait so the fence is sure to be signalled eventually; then wait in 1 s slices.
        GLbitfield flags = GL_SYNC_FLUSH_COMMANDS_BIT;
        for (;;) {
            const GLenum r = glClientWaitSync(f, flags, 1'000'000'000);
            if (r == GL_ALREADY_SIGNALED || r == GL_CONDITION_SATISFIED) break;
            if (r == GL_WAIT_FAILED) throw std::runtime_error("glClientWaitSync failed on the vertex ring");
            flags = 0;
        }
        glDeleteSync(f);
        f = nullptr;
    }
    if (out_wait_ms)
        *out_wait_ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    return {mapped_ + region * stride_floats_, region_floats_};
}

void VertexRing::release(std::size_t region) {
    GLsync& f = fence_[region];
    if (f) glDeleteSync(f);
    f = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
}

} // namespace drape::render
