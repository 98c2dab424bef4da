// Helpers shared by the panel builders (mask_panel.cpp, tshirt.cpp, outline_panel.cpp, garment_assembly.cpp,
// pattern_seams.cpp): the panel frame's check, placing a particle, and an order-free key for a particle pair (the range
// check is range_check.hpp's, shared with colliders and grid scenes). Internal to core.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>

#include "drape/errors.hpp"
#include "drape/garment_assembly.hpp"
#include "range_check.hpp"

namespace drape::panel_build {

// Largest particle count of an assembly (cook_cloth refuses 2^31 and more).
inline constexpr std::size_t assembly_max_particles = (std::size_t{1} << 31) - 1;

inline void check_frame(const PanelFrame& f) {
    auto dot = [](const std::array<float, 3>& a, const std::array<float, 3>& b) {
        return double{a[0]} * b[0] + double{a[1]} * b[1] + double{a[2]} * b[2];
    };
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(f.origin[k]) || !std::isfinite(f.axis_u[k]) || !std::isfinite(f.axis_v[k]))
            throw InvalidInput("panel frame has a non-finite origin or axis component");
    const double lu = std::sqrt(dot(f.axis_u, f.axis_u)), lv = std::sqrt(dot(f.axis_v, f.axis_v));
    if (std::abs(lu - 1.0) > 1e-4)
        throw InvalidInput("panel frame axis_u has length " + std::to_string(lu) +
                           " (must be 1 within 1e-4)");
    if (std::abs(lv - 1.0) > 1e-4)
        throw InvalidInput("panel frame axis_v has length " + std::to_string(lv) +
                           " (must be 1 within 1e-4)");
    const double d = dot(f.axis_u, f.axis_v);
    if (std::abs(d) > 1e-4)
        throw InvalidInput("panel frame axes are not orthogonal: axis_u . axis_v = " + std::to_string(d) +
                           " (must be 0 within 1e-4)");
}

// Appends a particle at panel point (u, v).
inline void push_particle(GarmentAssembly& a, const PanelFrame& f, double u, double v, double mass) {
    a.x.push_back(static_cast<float>(f.origin[0] + u * f.axis_u[0] + v * f.axis_v[0]));
    a.y.push_back(static_cast<float>(f.origin[1] + u * f.axis_u[1] + v * f.axis_v[1]));
    a.z.push_back(static_cast<float>(f.origin[2] + u * f.axis_u[2] + v * f.axis_v[2]));
    a.mass.push_back(static_cast<float>(mass));
}

inline std::string describe_char(char ch) {
    const auto uc = static_cast<unsigned char>(ch);
    if (uc >= 32 && uc < 127) return std::string("'") + ch + "'";
    char buf[16];
    std::snprintf(buf, sizeof buf, "byte 0x%02x", uc);
    return buf;
}

inline std::uint64_t pair_key(std::uint32_t a, std::uint32_t b) noexcept {
    if (a > b) std::swap(a, b);
    return (std::uint64_t{a} << 32) | b;
}


} // namespace drape::panel_build
