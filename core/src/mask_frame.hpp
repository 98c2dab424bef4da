// Mask panels' frames: shared by reading a scene (scene.cpp: the warning when the panels' weave directions differ)
// and building it (scene_build.cpp). Internal to core.
#pragma once

#include <array>
#include <cmath>

#include "drape/scene.hpp"

namespace drape {

/// A mask panel's frame: the file's axes normalised, the origin relative to the cloth's origin.
inline PanelFrame mask_frame(const MaskPanelSpec& p, const std::array<double, 3>& cloth_origin) {
    PanelFrame f;
    const auto unit = [](const std::array<float, 3>& a) {
        const double len = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
        return std::array<float, 3>{float(a[0] / len), float(a[1] / len), float(a[2] / len)};
    };
    f.axis_u = unit(p.axis_u);
    f.axis_v = unit(p.axis_v);
    for (int k = 0; k < 3; ++k)
        f.origin[k] = static_cast<float>(p.origin[k] - cloth_origin[k]);
    return f;
}

/// Whether every mask panel's u axis is that of the first (or its opposite): the fabric's weave then has one
/// direction in the cloth (WeaveAlignment::aligned along it).
inline bool mask_weave_aligned(const MaskClothSpec& m) {
    if (m.panels.empty()) return true;
    const PanelFrame f0 = mask_frame(m.panels[0], {0.0, 0.0, 0.0});
    for (const MaskPanelSpec& p : m.panels) {
        const PanelFrame f = mask_frame(p, {0.0, 0.0, 0.0});
        const double d = double(f.axis_u[0]) * f0.axis_u[0] + double(f.axis_u[1]) * f0.axis_u[1] +
                         double(f.axis_u[2]) * f0.axis_u[2];
        if (std::fabs(d) < 0.9999) return false;
    }
    return true;
}

} // namespace drape
