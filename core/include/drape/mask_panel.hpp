// Mask panels (seed 000 section 1.4): a pattern piece as a 0/1 mask on a square grid; '1' = a particle at that grid
// point. Springs join grid neighbours by the offsets of the hang scene (structural, shear, bend).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "drape/garment_assembly.hpp"

namespace drape {

/// A pattern piece as rows of '0'/'1' characters: '1' = a particle. Row r, column c is the grid point
/// (u, v) = (c h, r h) of the panel's frame.
struct MaskPanel {
    std::vector<std::string> rows;
};

inline constexpr std::size_t mask_max_side = 4096; ///< rows and columns of a mask, 1..4096

/// Where a mask panel's particles and springs landed in the assembly.
struct MaskPanelBuild {
    std::uint32_t columns = 0, rows = 0; ///< mask size
    std::uint32_t first_particle = 0;    ///< assembly index of the panel's first particle (row-major order)
    std::uint32_t particle_count = 0;
    std::size_t first_edge = 0, edge_count = 0; ///< its springs: assembly.edges[first_edge, +edge_count)
    std::size_t first_triangle = 0, triangle_count = 0; ///< its triangles, counted in triangles (not indices)
    /// Per mask cell (row * columns + column): assembly particle index, or -1 where the mask has '0'.
    std::vector<std::int32_t> cell_particle;
    /// Particles on the panel's boundary, ascending: on a boundary edge, or in no triangle at all.
    std::vector<std::uint32_t> boundary_particles;
    /// Boundary edges of the panel's triangle mesh (edges of exactly one triangle), as particle pairs (a <
    /// b), sorted.
    std::vector<std::array<std::uint32_t, 2>> boundary_edges;

    /// Assembly index of mask cell (row, column), -1 if absent or outside the mask.
    std::int32_t particle_at(std::int64_t row, std::int64_t column) const noexcept;
};

/// Checks a mask: 1..4096 rows of equal length 1..4096, only '0' and '1', at least one '1'. Throws
/// InvalidInput naming the row and column of the first problem.
void check_mask(const MaskPanel& mask);

/// Appends a mask panel to `io_assembly`. Particles at grid spacing `spacing` (m, 1e-4..10) placed by
/// `frame`, each of mass `particle_mass` (kg, 1e-9..10), numbered row-major. Springs only between present
/// particles, by the grid offsets of the hang scene, rest length = grid distance (h, h sqrt 2, 2h):
///   structural (r,c)-(r,c+1), (r,c)-(r+1,c);
///   shear (r,c)-(r+1,c+1), (r,c+1)-(r+1,c) - only where the half cell across that diagonal holds a triangle,
///   i.e.
///         one of the other two corners of the cell is present (no springs between particles touching at a
///         corner);
///   bend (r,c)-(r,c+2), (r,c)-(r+2,c) - only where the middle particle is present (no springs across a gap).
/// For a full W x H rectangle that is H(W-1) + W(H-1) structural, 2(W-1)(H-1) shear and H(W-2) + W(H-2) bend
/// springs (BENCH.md with W = H = N). Triangles: a cell with all four corners gives two, split along a diagonal
/// mirrored about the mask's centre column - (r,c+1)-(r+1,c) (the hang scene's) left of it, (r,c)-(r+1,c+1) right of
/// it - so a mask symmetric left-right gives a mesh symmetric left-right; a cell with three corners gives the one
/// triangle of those three.
/// `origin_column`: the mask column the frame's origin sits at (0: the first); a particle's u is
/// (column - origin_column) x spacing, so a panel whose origin is its centre column lies exactly mirror-symmetric
/// about it (the T-shirt's).
/// Throws InvalidInput.
MaskPanelBuild add_mask_panel(GarmentAssembly& io_assembly, const MaskPanel& mask, float spacing,
                              float particle_mass, const PanelFrame& frame = {}, std::uint32_t origin_column = 0);

} // namespace drape
