// Garment panels (cold tier): pattern pieces turned into particles, springs and triangles.
//
// Two ways to author a panel, both from the seeds:
//   - a 0/1 mask on a square grid (seed 000 section 1.4): '1' = a particle at that grid point. Springs join
//   grid
//     neighbours by the offsets of the hang scene (structural, shear, bend);
//   - an outline polygon (seed 004 section 1): its bounding box is filled with evenly spaced points, the
//   points
//     outside are dropped, the rest (plus points sampled along the outline) are triangulated with
//     Bowyer-Watson Delaunay; a stretch spring on every triangle edge and a bending "cross" spring across
//     every shared edge (seed 001).
// Panels are appended to a GarmentAssembly, a growing list of particles, springs and triangles, so several
// panels make one cloth. Panels are joined by seam springs (SpringKind::seam): the T-shirt builder sews its
// front and back panels; sew_by_arc_length() sews any two boundary polylines. The assembly feeds cook_cloth()
// unchanged (inverse_masses(), edges) plus initial_state() for the simulation.
//
// Frames: a panel is authored in 2D (u, v) coordinates, metres, and placed in 3D by a PanelFrame (an origin
// and two orthonormal in-plane axes), so a panel can stand vertically. Triangles are counter-clockwise seen
// from the panel normal u x v (the cooked cloth's convention).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
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

// ---------------------------------------------------------------------------------------------------------------------
// Mask panels (seed 000 section 1.4)

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
/// Throws InvalidInput.
MaskPanelBuild add_mask_panel(GarmentAssembly& io_assembly, const MaskPanel& mask, float spacing,
                              float particle_mass, const PanelFrame& frame = {});

// ---------------------------------------------------------------------------------------------------------------------
// T-shirt (seed 000): two identical mask panels sewn along shoulders, sides and under the sleeves.

/// What the user chooses for the T-shirt (cold tier). Ranges are checked by build_tshirt.
///
/// Frame (the body frame of default_body() in colliders.hpp): y up, the wearer faces +z, origin at the torso
/// centre. The flat shirt pattern (per panel, metres, each rounded to whole cells): a body 0.48 wide and 0.68
/// tall (hem at shoulder_y - 0.68), two short sleeves 0.20 long and 0.18 deep along the shoulder line (a T
/// shape 0.88 wide: the arms of default_body() are in a T-pose to match), and an elliptical neck opening 0.20
/// wide and 0.08 deep. Mask cell (row, column) is the point x = (column - m) h, y = shoulder_y - row h, with
/// h = 1 / cells_per_metre and m the centre column. The front panel lies in the plane z = +gap / 2 with
/// normal +z, the back panel in z = -gap / 2 with normal -z; both come from the same mask (identical panels;
/// the back's columns run the other way, so its normal faces out too).
struct TShirtParams {
    /// Grid resolution, cells per metre (10..1000). 35 is the seed's resolution: 2 x 504 = 1,008 particles;
    /// 360 gives about 101k particles (the count grows as about 0.78 r^2).
    float cells_per_metre = 35.0f;
    float total_mass = 0.15f; ///< kg (0.001..10), spread evenly over both panels
    float shoulder_y = 0.33f; ///< height of the shoulder line (top row), m, in the body frame (-10..10)
    /// Distance between the panels, m (0.001..2). The default clears default_body() (torso 0.20 m deep, hips
    /// 0.22 m) by 2 cm on each side, so the shirt starts outside the body and its seams close it.
    float gap = 0.26f;
    /// Rest length of a seam spring as a fraction of the grid spacing (0.01..2; cook_cloth refuses 0). The
    /// seams start `gap` long and pull the panels together to this length: a closed seam leaves a gap this wide
    /// (0.5 h here; the built-in scene uses 0.05 h and sews the seams shut at SimulationParams::sewing_speed).
    float seam_rest_ratio = 0.5f;
};

/// Which part of the pattern a sewn front particle lies on.
enum class SeamPart : std::uint8_t { shoulder, side, underarm };

struct TShirtBuild {
    GarmentAssembly assembly;
    MaskPanel mask;                        ///< the panel mask at this resolution
    MaskPanelBuild front, back;            ///< where each panel landed (front first)
    float spacing = 0.0f;                  ///< h, m
    std::vector<std::uint32_t> seam_edges; ///< indices into assembly.edges of the seam springs
    std::vector<SeamPart> seam_part;       ///< per seam edge, the part of the pattern it closes
};

/// The T-shirt mask at `cells_per_metre` (10..1000), symmetric left-right. Throws InvalidInput.
MaskPanel tshirt_mask(float cells_per_metre);

/// Builds the two panels and the seams: one seam spring (SpringKind::seam, rest seam_rest_ratio * h) joins
/// every front particle on the shoulder line (top row, including the sleeve tops), the sides of the body
/// (outermost particle of each row below the sleeves, down to the hem) and the underside of the sleeves (the
/// bottom row of each sleeve, out to the cuff) to the back particle at the same (x, y). Not sewn: the neck
/// opening, the hem (waist) and the sleeve openings (cuffs), except their end particles where they meet a
/// seam. Throws InvalidInput.
TShirtBuild build_tshirt(const TShirtParams& params);

// ---------------------------------------------------------------------------------------------------------------------
// Panels from an outline polygon (seed 004 section 1)

/// A simple polygon, counter-clockwise or clockwise, vertices in panel coordinates (u, v), m. Not closed (the
/// last vertex joins the first). 3..4096 vertices, no repeated consecutive vertices, no self-intersections.
struct OutlinePanel {
    std::vector<std::array<double, 2>> outline;
};

struct OutlinePanelParams {
    double spacing = 0.02; ///< h: grid spacing of the fill and the outline sampling, m (1e-4..10)
    double areal_density =
        0.15; ///< kg/m^2 (1e-4..100); a particle's mass is 1/3 of its triangles' area times it
    /// Fill points closer than this fraction of h to the outline are dropped (0..0.99): avoids slivers
    /// against the outline samples.
    double outline_clearance = 0.5;
    std::size_t max_points = 4'000'000; ///< refuse bigger panels before allocating (1..16M)
};

/// Where an outline panel's particles landed, and its outline as particles for sewing.
struct OutlinePanelBuild {
    std::uint32_t first_particle = 0, particle_count = 0;
    std::size_t first_edge = 0, edge_count = 0;
    std::size_t first_triangle = 0, triangle_count = 0;
    /// Outline particles in outline order (starting at outline vertex 0): assembly index and arc length from
    /// vertex 0 along the outline, m. Outline samples in no kept triangle were dropped and are not listed.
    std::vector<std::uint32_t> outline_particles;
    std::vector<double> outline_arc;        ///< m, ascending, one per outline particle
    std::vector<double> outline_vertex_arc; ///< arc length of each outline vertex from vertex 0, m
    double perimeter = 0.0;                 ///< m
    double area = 0.0;                      ///< polygon area, m^2 (positive)
};

/// Checks an outline (vertex count, finite, distinct consecutive vertices, non-zero area, simple). Throws
/// InvalidInput naming the vertex or edges at fault.
void check_outline(const OutlinePanel& panel);

/// Upper bound on the points (fill grid cells of the bounding box, outline samples, vertices) an outline panel at
/// spacing h allocates before it is triangulated; add_outline_panel refuses a panel above params.max_points.
double outline_panel_point_estimate(const OutlinePanel& panel, double spacing);

/// Appends a panel cut from an outline: fill points at spacing h strictly inside the polygon (and at least
/// outline_clearance * h from it), the outline vertices, and points along each outline edge at spacing <= h;
/// Bowyer- Watson Delaunay over them; triangles whose centroid is outside the polygon are dropped, and then
/// any particle in no triangle. A structural spring on every triangle edge; a bend spring between the
/// opposite vertices of every two triangles sharing an edge (unless that pair is already joined). Rest
/// lengths = initial distances. Throws InvalidInput.
OutlinePanelBuild add_outline_panel(GarmentAssembly& io_assembly, const OutlinePanel& panel,
                                    const OutlinePanelParams& params, const PanelFrame& frame = {});

/// A stretch of an outline for sewing: from outline vertex `from_vertex` to vertex `to_vertex` along the
/// outline's own order (wrapping past the last vertex; from == to means the whole loop). `reversed` lists its
/// particles from `to_vertex` back to `from_vertex`, so the stretch can be paired against one that runs the
/// other way.
struct OutlineStretch {
    std::uint32_t from_vertex = 0, to_vertex = 1;
    bool reversed = false;
};

/// The panel's outline particles on a stretch, in stretch order (both end vertices included if kept).
/// Throws InvalidInput on a vertex index out of range.
std::vector<std::uint32_t> outline_stretch_particles(const OutlinePanelBuild& build,
                                                     const OutlineStretch& stretch);

/// Sews two polylines of particles: each polyline is parameterised by its normalised arc length (0 at its
/// first particle, 1 at its last, from the assembly's positions); every particle of `a` is joined to the
/// particle of `b` nearest in that parameter and every particle of `b` not yet joined to the nearest of `a`.
/// Appends seam springs (SpringKind::seam, rest `seam_rest` m, > 0), skipping pairs already joined and self
/// pairs, and returns the indices of the new edges in io_assembly.edges. Each polyline needs >= 1 particle,
/// indices in range. Throws InvalidInput.
std::vector<std::uint32_t> sew_by_arc_length(GarmentAssembly& io_assembly, std::span<const std::uint32_t> a,
                                             std::span<const std::uint32_t> b, float seam_rest);

// ---------------------------------------------------------------------------------------------------------------------
// Bowyer-Watson Delaunay triangulation

/// Delaunay triangulation of 2D points by Bowyer-Watson: start from a super-triangle, then insert one point
/// at a time - remove the triangles whose circumcircle strictly contains it (the cavity) and join the
/// cavity's boundary to it (a fan). The super-triangle is taken to infinity (one symbolic vertex and "ghost"
/// triangles on the hull edges), so the result covers exactly the convex hull. Points are snapped to a 2^28
/// integer lattice over their bounding box so the orientation and in-circle predicates are exact (128-bit
/// integers): co-circular points (every grid square) are handled deterministically - a point exactly on a
/// circumcircle does not break that triangle. Points are inserted in Hilbert-curve order (fast point location
/// by walking). Points that snap to the same lattice point are merged: out_duplicate_of (if given) receives,
/// per point, the index of the point it was merged into, or its own index. Returns 3 point indices per
/// triangle, counter-clockwise. Slivers thinner than 4 lattice quanta (~1.5e-8 of the bounding box; only
/// nearly collinear hull points make them) are left out. Fewer than 3 distinct points or all collinear: no
/// triangles. Throws InvalidInput on a non-finite coordinate or more than 16M points.
std::vector<std::uint32_t> delaunay_triangulate(std::span<const double> px, std::span<const double> py,
                                                std::vector<std::uint32_t>* out_duplicate_of = nullptr);

} // namespace drape
