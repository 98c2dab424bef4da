// The T-shirt (seed 000): two identical mask panels sewn along the shoulders, the sides and under the sleeves.
#include "drape/tshirt.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "panel_build.hpp"

namespace drape {

using namespace panel_build;

namespace {

// Pattern dimensions, m (see TShirtParams). At 35 cells per metre they give 504 particles per panel.
constexpr double tshirt_half_span = 0.44;    // centre to cuff
constexpr double tshirt_half_body = 0.24;    // centre to side
constexpr double tshirt_height = 0.68;       // shoulder line to hem
constexpr double tshirt_sleeve_depth = 0.18; // shoulder line to the underside of a sleeve
constexpr double tshirt_neck_half_width = 0.10;
constexpr double tshirt_neck_depth = 0.08;

struct TShirtGrid {
    std::int64_t m, b, rows, s; // centre column, body half width (cells), row count, last sleeve row
    double neck_w, neck_d;      // neck semi-axes, cells
};

TShirtGrid tshirt_grid(double r) {
    auto cells = [r](double metres) { return static_cast<std::int64_t>(std::floor(metres * r + 0.5)); };
    return {cells(tshirt_half_span),    cells(tshirt_half_body),    cells(tshirt_height) + 1,
            cells(tshirt_sleeve_depth), tshirt_neck_half_width * r, tshirt_neck_depth * r};
}

} // namespace

MaskPanel tshirt_mask(float cells_per_metre) {
    check_range("tshirt resolution (cells_per_metre)", cells_per_metre, 10.0f, 1000.0f, " cells/m");
    const TShirtGrid g = tshirt_grid(cells_per_metre);
    MaskPanel mask;
    const std::int64_t width = 2 * g.m + 1;
    mask.rows.assign(static_cast<std::size_t>(g.rows), std::string(static_cast<std::size_t>(width), '0'));
    for (std::int64_t j = 0; j < g.rows; ++j)
        for (std::int64_t c = 0; c < width; ++c) {
            const std::int64_t x = c - g.m;
            const bool body = std::abs(x) <= g.b;
            const bool sleeve = j <= g.s;
            const double nx = static_cast<double>(x) / g.neck_w, ny = static_cast<double>(j) / g.neck_d;
            const bool neck = nx * nx + ny * ny < 1.0;
            if ((body || sleeve) && !neck)
                mask.rows[static_cast<std::size_t>(j)][static_cast<std::size_t>(c)] = '1';
        }
    return mask;
}

TShirtBuild build_tshirt(const TShirtParams& p) {
    check_range("tshirt resolution (cells_per_metre)", p.cells_per_metre, 10.0f, 1000.0f, " cells/m");
    check_range("tshirt total mass", p.total_mass, 0.001f, 10.0f, " kg");
    check_range("tshirt shoulder_y", p.shoulder_y, -10.0f, 10.0f, " m");
    check_range("tshirt gap", p.gap, 0.001f, 2.0f, " m");
    check_range("tshirt seam_rest_ratio", p.seam_rest_ratio, 0.01f, 2.0f, "");

    TShirtBuild out;
    out.mask = tshirt_mask(p.cells_per_metre);
    const TShirtGrid g = tshirt_grid(p.cells_per_metre);
    const double h = 1.0 / p.cells_per_metre;
    out.spacing = static_cast<float>(h);
    std::size_t per_panel = 0;
    for (const std::string& row : out.mask.rows)
        per_panel += static_cast<std::size_t>(std::count(row.begin(), row.end(), '1'));
    const float particle_mass = static_cast<float>(p.total_mass / (2.0 * static_cast<double>(per_panel)));

    // Front: normal +z, columns run along -x. Back: normal -z, columns along +x. Column c of the front and
    // column 2m - c of the back sit at the same x.
    // mirror_exact: both frames' origins on the centre line x = 0, at the centre column m, so the halves are exact
    // mirror images; otherwise at the first column (half_span rounded to float: the halves differ by an ulp).
    const float half_span = p.mirror_exact ? 0.0f : static_cast<float>(static_cast<double>(g.m) * h);
    const auto m = p.mirror_exact ? static_cast<std::uint32_t>(g.m) : 0u;
    PanelFrame front{{half_span, p.shoulder_y, 0.5f * p.gap}, {-1.0f, 0.0f, 0.0f}, {0.0f, -1.0f, 0.0f}};
    PanelFrame back{{-half_span, p.shoulder_y, -0.5f * p.gap}, {1.0f, 0.0f, 0.0f}, {0.0f, -1.0f, 0.0f}};
    out.front = add_mask_panel(out.assembly, out.mask, out.spacing, particle_mass, front, m);
    out.back = add_mask_panel(out.assembly, out.mask, out.spacing, particle_mass, back, m);

    const float seam_rest = static_cast<float>(p.seam_rest_ratio * h);
    const std::int64_t width = 2 * g.m + 1, last_row = g.rows - 1;
    for (std::int64_t j = 0; j < g.rows; ++j) {
        std::int64_t first = -1, last = -1;
        for (std::int64_t c = 0; c < width; ++c)
            if (out.front.particle_at(j, c) >= 0) {
                if (first < 0) first = c;
                last = c;
            }
        for (std::int64_t c = 0; c < width; ++c) {
            const std::int32_t f = out.front.particle_at(j, c);
            if (f < 0) continue;
            SeamPart part;
            if (j == 0)
                part = SeamPart::shoulder; // the whole top row: shoulders and sleeve tops, up to the neck
            else if (j < last_row && out.front.particle_at(j + 1, c) < 0)
                part = SeamPart::underarm; // underside of a sleeve, out to the cuff
            else if ((c == first || c == last) && c != 0 && c != width - 1)
                part = SeamPart::side; // outermost particle of a body row, down to the hem
            else
                continue;
            const std::int32_t b = out.back.particle_at(j, 2 * g.m - c);
            if (b < 0) throw std::logic_error("tshirt mask is not symmetric");
            out.seam_edges.push_back(static_cast<std::uint32_t>(out.assembly.edges.size()));
            out.seam_part.push_back(part);
            out.assembly.edges.push_back({static_cast<std::uint32_t>(std::min(f, b)),
                                          static_cast<std::uint32_t>(std::max(f, b)), SpringKind::seam,
                                          seam_rest});
        }
    }
    out.mirror.assign(out.assembly.particle_count(), 0);
    for (const MaskPanelBuild* panel : {&out.front, &out.back})
        for (std::int64_t r = 0; r < panel->rows; ++r)
            for (std::int64_t c = 0; c < panel->columns; ++c) {
                const std::int32_t i = panel->particle_at(r, c), j = panel->particle_at(r, panel->columns - 1 - c);
                if (i < 0) continue;
                if (j < 0) throw std::logic_error("tshirt mask is not symmetric");
                out.mirror[static_cast<std::size_t>(i)] = static_cast<std::uint32_t>(j);
            }
    return out;
}

} // namespace drape
