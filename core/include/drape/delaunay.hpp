// Bowyer-Watson Delaunay triangulation of 2D points (the outline panels' mesher).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace drape {

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
