// Output stage: the per-frame vertex data for drawing, written straight into a span the caller hands over.
//
// The viewer hands over one region of a persistent, coherent mapped OpenGL buffer, so this stage is the only
// writer of vertex data and nothing is copied afterwards (no staging array, no glBufferSubData). It runs once
// per drawn frame, not per substep.
//
// Output layout: six planes of plane_floats() floats each, in the order of VertexPlane:
//
//     [ x ... | y ... | z ... | nx ... | ny ... | nz ... ]      plane_floats() = cloth.padded_count (whole
//     SIMD
//                                                                batches, so each plane starts 64-byte
//                                                                aligned when the span does)
//
// Planar (structure-of-arrays) rather than interleaved xyz-nxnynz: the solver's state is SoA, so positions
// are streamed plane to plane with full SIMD loads and stores, and normals are computed 16 vertices at a time
// and stored the same way without a transpose. The GPU reads six float attributes, one per plane
// (render/cloth_renderer.cpp).
//
// Normals are area-weighted: n_i = normalize(sum over triangles t touching i of (b - a) x (c - a)), the cross
// product being twice the triangle's area times its unit normal. Each vertex gathers its own triangles (no
// scatter, no atomics), so the output does not depend on the thread count. Two paths:
//   grid    - the cloth is a full regular grid triangulated as scene "hang" does: each vertex's six fan
//   neighbours
//             sit at fixed index offsets (+1, -N+1, -N, -1, +N-1, +N), 16 vertices per SIMD batch with
//             unaligned loads and a per-vertex mask of the triangles that exist;
//   general - any triangle mesh: a per-vertex fan list (CSR of (next, previous) vertex pairs) cooked once,
//   scalar.
// While the positions are in registers the stage also computes the largest structural strain |l - l0| / l0
// (the figure Simulation::health() reports, here at no extra memory traffic) and checks that every position
// is finite.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/aligned_array.hpp"
#include "drape/cloth.hpp"

namespace drape {

/// The planes of the output, in memory order.
enum class VertexPlane : std::uint8_t { x, y, z, nx, ny, nz, count };
inline constexpr std::size_t vertex_plane_count = static_cast<std::size_t>(VertexPlane::count);

/// Figures the output stage computes on the way.
struct PublishStats {
    float max_structural_strain = 0.0f; ///< max |l - l0| / l0 over structural springs (same as Health)
    bool finite = true;                 ///< every published position and normal is finite
};

/// Cooked once per cloth (like the cloth itself); publish() then never allocates.
class Publisher {
  public:
    /// Cooks the per-vertex fan lists or the grid masks from cloth.triangles, and the structural springs for
    /// the strain figure. Throws InvalidInput when a triangle index is out of range.
    explicit Publisher(const Cloth& cloth);

    std::size_t particle_count() const noexcept { return particle_count_; }
    /// Floats per plane (the cloth's padded particle count).
    std::size_t plane_floats() const noexcept { return plane_floats_; }
    /// Floats the output span must hold: vertex_plane_count * plane_floats().
    std::size_t output_floats() const noexcept { return vertex_plane_count * plane_floats_; }
    /// True when the SIMD regular-grid path runs (else the general per-vertex fan path).
    bool grid_path() const noexcept { return grid_columns_ != 0; }

    /// Writes positions and area-weighted unit normals of particle_count() vertices into out (layout above;
    /// padding entries are written as zero). x, y, z hold particle_count() current positions (m). Parallel
    /// with oneTBB over fixed blocks of block_particles vertices; the output is bitwise the same for any
    /// thread count. Throws InvalidInput when a span is too short.
    PublishStats publish(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                         std::span<float> out);
    /// The serial twin of publish() (same per-vertex arithmetic, one thread).
    PublishStats publish_serial(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                                std::span<float> out);

  private:
    struct Positions {
        const float* x;
        const float* y;
        const float* z;
    };
    template <bool Parallel>
    PublishStats publish_impl(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                              std::span<float> out);
    void block_grid(std::size_t block, Positions p, float* out) noexcept;
    void block_general(std::size_t block, Positions p, float* out) noexcept;
    void strain_chunk(std::size_t chunk, Positions p) noexcept;
    void grid_vertex_scalar(std::size_t k, Positions p, float* out, float& strain,
                            bool& finite) const noexcept;

    std::size_t particle_count_ = 0;
    std::size_t plane_floats_ = 0;
    std::size_t block_count_ = 0;

    // Grid path (grid_columns_ != 0).
    std::size_t grid_columns_ = 0;
    std::size_t grid_rows_ = 0;
    float rest_east_ = 0.0f;   ///< m, structural spring to the next column
    float rest_south_ = 0.0f;  ///< m, structural spring to the next row
    bool grid_strain_ = false; ///< the grid pass also yields the strain figure (else structural_ is scanned)
    /// Per vertex: bit t (0..5) set when fan triangle t exists; bit 6: spring east; bit 7: spring south.
    AlignedArray<std::uint32_t> grid_mask_;

    // General path.
    std::vector<std::uint32_t> fan_offsets_; ///< particle_count + 1
    std::vector<std::uint32_t>
        fan_pairs_; ///< per fan entry: next, previous (counter-clockwise around the vertex)
    struct StructuralSpring {
        std::uint32_t a, b;
        float rest;
    };
    std::vector<StructuralSpring> structural_; ///< for the strain figure when the grid path does not cover it
    std::size_t strain_chunk_count_ = 0;

    // Per-block partials, combined in block order (sized once here, never per frame).
    std::vector<float> block_strain_;
    std::vector<std::uint8_t> block_finite_;
    std::vector<float> chunk_strain_;
};

} // namespace drape
