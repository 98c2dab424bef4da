// Mask panels (seed 000 section 1.4): a 0/1 mask on a square grid turned into particles, springs and triangles.
#include "drape/mask_panel.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "panel_build.hpp"

namespace drape {

using namespace panel_build;

std::int32_t MaskPanelBuild::particle_at(std::int64_t row, std::int64_t column) const noexcept {
    if (row < 0 || column < 0 || row >= rows || column >= columns) return -1;
    return cell_particle[static_cast<std::size_t>(row) * columns + static_cast<std::size_t>(column)];
}

void check_mask(const MaskPanel& mask) {
    if (mask.rows.empty())
        throw InvalidInput("mask has no rows (need 1.." + std::to_string(mask_max_side) + ")");
    if (mask.rows.size() > mask_max_side)
        throw InvalidInput("mask has " + std::to_string(mask.rows.size()) + " rows (allowed 1.." +
                           std::to_string(mask_max_side) + ")");
    const std::size_t width = mask.rows[0].size();
    if (width == 0 || width > mask_max_side)
        throw InvalidInput("mask row 0 has " + std::to_string(width) + " columns (allowed 1.." +
                           std::to_string(mask_max_side) + ")");
    std::size_t ones = 0;
    for (std::size_t r = 0; r < mask.rows.size(); ++r) {
        const std::string& row = mask.rows[r];
        if (row.size() != width)
            throw InvalidInput("mask row " + std::to_string(r) + " has " + std::to_string(row.size()) +
                               " columns but row 0 has " + std::to_string(width) +
                               " (a mask is rectangular)");
        for (std::size_t c = 0; c < width; ++c) {
            if (row[c] == '1')
                ++ones;
            else if (row[c] != '0')
                throw InvalidInput("mask row " + std::to_string(r) + ", column " + std::to_string(c) +
                                   " holds " + describe_char(row[c]) + " (only '0' and '1' are allowed)");
        }
    }
    if (ones == 0) throw InvalidInput("mask has no '1' (need at least one particle)");
}

MaskPanelBuild add_mask_panel(GarmentAssembly& io, const MaskPanel& mask, float spacing, float particle_mass,
                              const PanelFrame& frame, std::uint32_t origin_column) {
    check_mask(mask);
    check_range("panel spacing", spacing, 1e-4f, 10.0f, " m");
    check_range("particle mass", particle_mass, 1e-9f, 10.0f, " kg");
    check_frame(frame);

    MaskPanelBuild out;
    const std::uint32_t rows = static_cast<std::uint32_t>(mask.rows.size());
    const std::uint32_t cols = static_cast<std::uint32_t>(mask.rows[0].size());
    out.rows = rows;
    out.columns = cols;
    out.first_particle = static_cast<std::uint32_t>(io.particle_count());
    out.cell_particle.assign(std::size_t{rows} * cols, -1);

    std::size_t count = 0;
    for (const std::string& row : mask.rows)
        count += static_cast<std::size_t>(std::count(row.begin(), row.end(), '1'));
    if (io.particle_count() + count > assembly_max_particles)
        throw InvalidInput("garment would have " + std::to_string(io.particle_count() + count) +
                           " particles (max 2^31-1)");

    // Particles, row-major.
    const double h = spacing;
    std::uint32_t next = out.first_particle;
    for (std::uint32_t r = 0; r < rows; ++r)
        for (std::uint32_t c = 0; c < cols; ++c) {
            if (mask.rows[r][c] != '1') continue;
            out.cell_particle[std::size_t{r} * cols + c] = static_cast<std::int32_t>(next++);
            push_particle(io, frame, (double(c) - double(origin_column)) * h, r * h, particle_mass);
        }
    out.particle_count = static_cast<std::uint32_t>(count);

    auto at = [&](std::int64_t r, std::int64_t c) { return out.particle_at(r, c); };
    const float rest_structural = spacing;
    const float rest_shear = static_cast<float>(h * std::sqrt(2.0));
    const float rest_bend = static_cast<float>(2.0 * h);

    // Springs. Row-major particle numbering makes every pair below (a, b) with a < b.
    out.first_edge = io.edges.size();
    auto push_edge = [&](std::int32_t a, std::int32_t b, SpringKind kind, float rest) {
        io.edges.push_back({static_cast<std::uint32_t>(a), static_cast<std::uint32_t>(b), kind, rest});
    };
    for (std::int64_t r = 0; r < rows; ++r)
        for (std::int64_t c = 0; c < cols; ++c) {
            const std::int32_t p = at(r, c);
            const std::int32_t right = at(r, c + 1), down = at(r + 1, c), diag = at(r + 1, c + 1);
            if (p >= 0) {
                if (right >= 0) push_edge(p, right, SpringKind::structural, rest_structural);
                if (down >= 0) push_edge(p, down, SpringKind::structural, rest_structural);
                // Shear (r,c)-(r+1,c+1) needs a triangle on that diagonal: (r,c+1) or (r+1,c) present.
                if (diag >= 0 && (right >= 0 || down >= 0)) push_edge(p, diag, SpringKind::shear, rest_shear);
                // Bend needs the middle particle.
                if (right >= 0 && at(r, c + 2) >= 0) push_edge(p, at(r, c + 2), SpringKind::bend, rest_bend);
                if (down >= 0 && at(r + 2, c) >= 0) push_edge(p, at(r + 2, c), SpringKind::bend, rest_bend);
            }
            // Shear (r,c+1)-(r+1,c) needs (r,c) or (r+1,c+1) present.
            if (right >= 0 && down >= 0 && (p >= 0 || diag >= 0))
                push_edge(right, down, SpringKind::shear, rest_shear);
        }
    out.edge_count = io.edges.size() - out.first_edge;

    // Triangles, counter-clockwise seen from axis_u x axis_v. Corners: a = (r,c), b = (r,c+1), d = (r+1,c),
    // e = (r+1,c+1); b - a = u h, d - a = v h.
    out.first_triangle = io.triangle_count();
    auto push_tri = [&](std::int32_t p, std::int32_t q, std::int32_t s) {
        io.triangles.insert(io.triangles.end(), {static_cast<std::uint32_t>(p), static_cast<std::uint32_t>(q),
                                                 static_cast<std::uint32_t>(s)});
    };
    std::vector<std::uint8_t> in_triangle(count, 0);
    for (std::int64_t r = 0; r + 1 < rows; ++r)
        for (std::int64_t c = 0; c + 1 < cols; ++c) {
            const std::int32_t a = at(r, c), b = at(r, c + 1), d = at(r + 1, c), e = at(r + 1, c + 1);
            const int present = (a >= 0) + (b >= 0) + (d >= 0) + (e >= 0);
            if (present < 3) continue;
            const std::size_t before = io.triangles.size();
            if (present == 4) {
                // Diagonals mirrored about the mask's centre column, so a mask symmetric left-right gives a
                // mesh symmetric left-right (a garment on a symmetric body settles symmetric): b-d left of the
                // centre, a-e right of it (a cell straddling the centre of an even-width mask takes b-d).
                if (2 * c + 1 <= static_cast<std::int64_t>(cols) - 1) {
                    push_tri(a, b, d); // (b-a) x (d-a) = u x v
                    push_tri(b, e, d);
                } else {
                    push_tri(a, b, e);
                    push_tri(a, e, d);
                }
            } else if (a < 0) {
                push_tri(b, e, d);
            } else if (b < 0) {
                push_tri(a, e, d);
            } else if (d < 0) {
                push_tri(a, b, e);
            } else {
                push_tri(a, b, d);
            }
            for (std::size_t k = before; k < io.triangles.size(); ++k)
                in_triangle[io.triangles[k] - out.first_particle] = 1;
        }
    out.triangle_count = io.triangle_count() - out.first_triangle;

    // Boundary: triangle edges used once, plus particles in no triangle.
    std::vector<std::uint64_t> tri_edges;
    tri_edges.reserve(out.triangle_count * 3);
    for (std::size_t t = out.first_triangle; t < out.first_triangle + out.triangle_count; ++t)
        for (int k = 0; k < 3; ++k)
            tri_edges.push_back(pair_key(io.triangles[3 * t + k], io.triangles[3 * t + (k + 1) % 3]));
    std::sort(tri_edges.begin(), tri_edges.end());
    for (std::size_t k = 0; k < tri_edges.size();) {
        std::size_t m = k;
        while (m < tri_edges.size() && tri_edges[m] == tri_edges[k])
            ++m;
        if (m - k == 1) {
            const auto a = static_cast<std::uint32_t>(tri_edges[k] >> 32);
            const auto b = static_cast<std::uint32_t>(tri_edges[k] & 0xffffffffu);
            out.boundary_edges.push_back({a, b});
            out.boundary_particles.push_back(a);
            out.boundary_particles.push_back(b);
        }
        k = m;
    }
    for (std::size_t i = 0; i < count; ++i)
        if (!in_triangle[i])
            out.boundary_particles.push_back(out.first_particle + static_cast<std::uint32_t>(i));
    std::sort(out.boundary_particles.begin(), out.boundary_particles.end());
    out.boundary_particles.erase(std::unique(out.boundary_particles.begin(), out.boundary_particles.end()),
                                 out.boundary_particles.end());
    return out;
}

} // namespace drape
