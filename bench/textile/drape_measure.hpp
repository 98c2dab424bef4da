// Top-view measurements of a draped cloth (Cusick drape test): the shadow of its triangles rasterised onto the
// horizontal plane (x-z), its area, the radial profile of its outline and the fold count, and a top-view picture.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace drape::textile {

/// A square top-view raster centred on the disc axis (x = z = 0): per pixel the highest cloth point above it.
struct TopView {
    int size = 0;          ///< pixels per side
    double extent = 0.0;   ///< half width, m (pixel centres from -extent to +extent)
    double pixel = 0.0;    ///< m per pixel
    std::vector<float> top; ///< highest y per pixel, -inf where no cloth
    bool covered(int px, int pz) const;
    double area() const;   ///< covered area, m^2
};

/// Rasterises the triangles (indices into x, y, z; positions in m, disc axis at x = z = 0) seen from above.
TopView rasterise_top(std::span<const float> x, std::span<const float> y, std::span<const float> z,
                      std::span<const std::uint32_t> triangles, double extent, double pixel);

/// Outline radius of the shadow against angle: per angular bin the largest radius covered, m.
std::vector<double> radial_profile(const TopView& view, int bins = 360);

/// Folds (nodes) of a radial profile: upward crossings of its mean with a hysteresis of `band` (m) either side,
/// after a circular moving average over `smooth` bins.
int fold_count(const std::vector<double>& profile, double band = 0.003, int smooth = 5);

/// Writes the top view as a PNG: cloth shaded by height (light = high), the disc outline in red, the circle of the
/// flat specimen's radius in grey. Returns false when the file cannot be written.
bool write_top_view_png(const TopView& view, const std::string& path, double disc_radius, double specimen_radius);

} // namespace drape::textile
