// Seams between pattern pieces (cold tier): two boundary polylines joined by seam springs (SpringKind::seam).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "drape/garment_assembly.hpp"

namespace drape {

/// Sews two polylines of particles: each polyline is parameterised by its normalised arc length (0 at its
/// first particle, 1 at its last, from the assembly's positions); every particle of `a` is joined to the
/// particle of `b` nearest in that parameter and every particle of `b` not yet joined to the nearest of `a`.
/// Appends seam springs (SpringKind::seam, rest `seam_rest` m, > 0), skipping pairs already joined and self
/// pairs, and returns the indices of the new edges in io_assembly.edges. Each polyline needs >= 1 particle,
/// indices in range. Throws InvalidInput.
std::vector<std::uint32_t> sew_by_arc_length(GarmentAssembly& io_assembly, std::span<const std::uint32_t> a,
                                             std::span<const std::uint32_t> b, float seam_rest);

} // namespace drape
