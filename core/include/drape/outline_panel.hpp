// Panels from an outline polygon (seed 004 section 1): the bounding box is filled with evenly spaced points, the
// points outside are dropped, the rest (plus points sampled along the outline) are triangulated with Bowyer-Watson
// Delaunay (delaunay.hpp); a stretch spring on every triangle edge and a bending "cross" spring across every shared
// edge (seed 001).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "drape/garment_assembly.hpp"

namespace drape {

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

} // namespace drape
