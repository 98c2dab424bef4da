// Figures of a sewn, left-right symmetric garment (docs/garments.md): how far its seams are from closed, how far it is
// from its own mirror image, how many particles are inside the body. The T-shirt tests and `drape_shirt`
// (bench/shirt_symmetry.cpp) measure with them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "drape/tshirt.hpp"
#include "drape/simulation.hpp"

namespace drape {

/// For each particle of the T-shirt built from `params`, the particle that is its mirror image (x -> -x): column c
/// <-> columns - 1 - c of the same panel and row (TShirtBuild::mirror).
std::vector<std::uint32_t> tshirt_mirror_map(const TShirtParams& params);

struct GarmentFigures {
    double longest_seam = 0.0; ///< m, the longest seam spring
    double mirror_error = 0.0; ///< m, max over particles i of |p_i - mirror(p_mirror(i))| (world x -> -x)
    double mirror_rms = 0.0;   ///< m, the root mean square of that distance over the particles
    std::size_t beyond = 0;    ///< particles whose mirror error exceeds `beyond_distance` (garment_figures' argument)
    std::size_t worst = 0;     ///< the particle of the largest mirror error
    std::size_t inside = 0;    ///< particles inside a collider other than a plane (the body)
    bool finite = false;       ///< every value of the state finite (Simulation::health)
};

/// The figures of the simulation's current state; `mirror` from tshirt_mirror_map (one entry per particle);
/// `beyond_distance` (m) the mirror error that GarmentFigures::beyond counts particles above.
GarmentFigures garment_figures(const Simulation& sim, std::span<const std::uint32_t> mirror,
                               double beyond_distance = 0.005);

} // namespace drape
