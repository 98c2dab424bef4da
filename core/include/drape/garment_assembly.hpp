// Garment assembly (cold tier): panels are appended to a GarmentAssembly, a growing list of particles, springs and
// triangles, so several panels make one cloth. Panels are joined by seam springs (SpringKind::seam): the T-shirt
// builder sews its front and back panels (tshirt.hpp); sew_by_arc_length() (pattern_seams.hpp) sews any two boundary
// polylines. The assembly feeds cook_cloth() unchanged (inverse_masses(), edges) plus initial_state() for the
// simulation.
//
// Frames: a panel is authored in 2D (u, v) coordinates, metres, and placed in 3D by a PanelFrame (an origin and two
// orthonormal in-plane axes), so a panel can stand vertically. Triangles are counter-clockwise seen from the panel
// normal u x v (the cooked cloth's convention).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/cloth.hpp"
#include "drape/spring_graph.hpp"

namespace drape {

/// Particles, springs and triangles of one or more panels (cold tier). Plain vectors, one entry per particle.
struct GarmentAssembly {
    std::vector<float> x, y, z; ///< initial positions, m
    std::vector<float> mass;    ///< kg, > 0
    std::vector<Edge> edges;    ///< every spring once (a < b), rest length = initial distance except seams
    std::vector<std::uint32_t> triangles; ///< 3 particle indices per triangle, CCW seen from the panel normal

    std::size_t particle_count() const noexcept { return mass.size(); }
    std::size_t triangle_count() const noexcept { return triangles.size() / 3; }
    /// 1/mass per particle (nothing pinned), the first argument of cook_cloth().
    std::vector<float> inverse_masses() const;
    /// Positions of the assembly with zero velocity.
    InitialState initial_state() const;
    /// Number of edges of one kind.
    std::size_t edge_count(SpringKind kind) const noexcept;
};

/// Placement of a panel: point (u, v) of the panel goes to origin + u * axis_u + v * axis_v. The axes must be
/// unit length and orthogonal (checked to 1e-4). The default is a vertical panel in the x-y plane, u along +x
/// and v along -y, so mask row 0 is the top (text order) and the normal u x v is -z.
struct PanelFrame {
    std::array<float, 3> origin{0.0f, 0.0f, 0.0f}; ///< m
    std::array<float, 3> axis_u{1.0f, 0.0f, 0.0f};
    std::array<float, 3> axis_v{0.0f, -1.0f, 0.0f};
};

/// Springs of a triangle mesh already in the assembly (seed 001's rule): a structural spring on every edge of
/// `triangles` (assembly particle indices, 3 per triangle); a bend spring joining the two opposite vertices of every
/// edge shared by exactly two triangles (an edge of 3+ triangles, non-manifold, gets none; a pair already joined by
/// these springs, or the same vertex twice, is skipped). Structural springs first, in (a, b) order, then the bend
/// springs; rest lengths = current distances.
void add_triangle_springs(GarmentAssembly& io_assembly, std::span<const std::uint32_t> triangles);

} // namespace drape
