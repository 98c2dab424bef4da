// Garment panels: mask panels, the T-shirt, outline panels (Bowyer-Watson Delaunay) and sewing.
#include "drape/panels.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <string>
#include <unordered_set>
#include <utility>

#include "drape/errors.hpp"

namespace drape {

namespace {

// Largest particle count of an assembly (cook_cloth refuses 2^31 and more).
constexpr std::size_t assembly_max_particles = (std::size_t{1} << 31) - 1;

template <class T> void check_range(const std::string& name, T value, T lo, T hi, const char* unit) {
    if (!(value >= lo && value <= hi))
        throw InvalidInput(name + " = " + std::to_string(value) + unit + " is outside the allowed range [" +
                           std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

void check_frame(const PanelFrame& f) {
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
void push_particle(GarmentAssembly& a, const PanelFrame& f, double u, double v, double mass) {
    a.x.push_back(static_cast<float>(f.origin[0] + u * f.axis_u[0] + v * f.axis_v[0]));
    a.y.push_back(static_cast<float>(f.origin[1] + u * f.axis_u[1] + v * f.axis_v[1]));
    a.z.push_back(static_cast<float>(f.origin[2] + u * f.axis_u[2] + v * f.axis_v[2]));
    a.mass.push_back(static_cast<float>(mass));
}

std::string describe_char(char ch) {
    const auto uc = static_cast<unsigned char>(ch);
    if (uc >= 32 && uc < 127) return std::string("'") + ch + "'";
    char buf[16];
    std::snprintf(buf, sizeof buf, "byte 0x%02x", uc);
    return buf;
}

std::uint64_t pair_key(std::uint32_t a, std::uint32_t b) noexcept {
    if (a > b) std::swap(a, b);
    return (std::uint64_t{a} << 32) | b;
}

} // namespace

// ---------------------------------------------------------------------------------------------------------------------
// Assembly

std::vector<float> GarmentAssembly::inverse_masses() const {
    std::vector<float> inv(mass.size());
    for (std::size_t i = 0; i < mass.size(); ++i)
        inv[i] = 1.0f / mass[i];
    return inv;
}

InitialState GarmentAssembly::initial_state() const {
    InitialState s;
    s.x = x;
    s.y = y;
    s.z = z;
    s.vx.assign(x.size(), 0.0f);
    s.vy.assign(x.size(), 0.0f);
    s.vz.assign(x.size(), 0.0f);
    return s;
}

std::size_t GarmentAssembly::edge_count(SpringKind kind) const noexcept {
    return static_cast<std::size_t>(
        std::count_if(edges.begin(), edges.end(), [kind](const Edge& e) { return e.kind == kind; }));
}


void add_triangle_springs(GarmentAssembly& io, std::span<const std::uint32_t> triangles) {
    struct HalfEdge {
        std::uint64_t key;
        std::uint32_t opposite;
    };
    std::vector<HalfEdge> half;
    half.reserve(triangles.size());
    for (std::size_t t = 0; t + 2 < triangles.size(); t += 3)
        for (int k = 0; k < 3; ++k) {
            const std::uint32_t a = triangles[t + k], b = triangles[t + (k + 1) % 3], c = triangles[t + (k + 2) % 3];
            half.push_back({pair_key(a, b), c});
        }
    std::sort(half.begin(), half.end(), [](const HalfEdge& l, const HalfEdge& r) {
        return l.key != r.key ? l.key < r.key : l.opposite < r.opposite;
    });
    auto dist = [&](std::uint32_t a, std::uint32_t b) {
        const double dx = double{io.x[a]} - io.x[b], dy = double{io.y[a]} - io.y[b],
                     dz = double{io.z[a]} - io.z[b];
        return static_cast<float>(std::sqrt(dx * dx + dy * dy + dz * dz));
    };
    std::unordered_set<std::uint64_t> joined;
    joined.reserve(half.size());
    std::vector<std::uint64_t> cross;
    for (std::size_t k = 0; k < half.size();) {
        std::size_t m = k;
        while (m < half.size() && half[m].key == half[k].key)
            ++m;
        const auto a = static_cast<std::uint32_t>(half[k].key >> 32);
        const auto b = static_cast<std::uint32_t>(half[k].key & 0xffffffffu);
        io.edges.push_back({a, b, SpringKind::structural, dist(a, b)});
        joined.insert(half[k].key);
        if (m - k == 2 && half[k].opposite != half[k + 1].opposite)
            cross.push_back(pair_key(half[k].opposite, half[k + 1].opposite));
        k = m;
    }
    for (std::uint64_t key : cross) {
        if (!joined.insert(key).second) continue;
        const auto a = static_cast<std::uint32_t>(key >> 32);
        const auto b = static_cast<std::uint32_t>(key & 0xffffffffu);
        io.edges.push_back({a, b, SpringKind::bend, dist(a, b)});
    }
}

// ---------------------------------------------------------------------------------------------------------------------
// Mask panels

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
                              const PanelFrame& frame) {
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
            push_particle(io, frame, c * h, r * h, particle_mass);
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

// ---------------------------------------------------------------------------------------------------------------------
// T-shirt

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
    const float half_span = static_cast<float>(static_cast<double>(g.m) * h);
    PanelFrame front{{half_span, p.shoulder_y, 0.5f * p.gap}, {-1.0f, 0.0f, 0.0f}, {0.0f, -1.0f, 0.0f}};
    PanelFrame back{{-half_span, p.shoulder_y, -0.5f * p.gap}, {1.0f, 0.0f, 0.0f}, {0.0f, -1.0f, 0.0f}};
    out.front = add_mask_panel(out.assembly, out.mask, out.spacing, particle_mass, front);
    out.back = add_mask_panel(out.assembly, out.mask, out.spacing, particle_mass, back);

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
    return out;
}

// ---------------------------------------------------------------------------------------------------------------------
// Bowyer-Watson Delaunay

namespace {

using i64 = std::int64_t;
__extension__ typedef __int128 i128; // GCC/Clang 128-bit integer (exact in-circle test)

constexpr i64 lattice_max = (i64{1} << 28) - 1; // input points snap to [0, 2^28)

struct LatticePoint {
    i64 x, y;
};

// > 0 when (a, b, c) turn counter-clockwise. Exact: coordinates < 2^28, products < 2^56.
inline i64 orient(const LatticePoint& a, const LatticePoint& b, const LatticePoint& c) noexcept {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

// > 0 when d is strictly inside the circumcircle of the counter-clockwise triangle (a, b, c). Exact in 128
// bits: differences < 2^28, lifted terms < 2^57, each product < 2^115.
inline int in_circle(const LatticePoint& a, const LatticePoint& b, const LatticePoint& c,
                     const LatticePoint& d) noexcept {
    const i64 adx = a.x - d.x, ady = a.y - d.y, bdx = b.x - d.x, bdy = b.y - d.y, cdx = c.x - d.x,
              cdy = c.y - d.y;
    const i128 alift = i128{adx} * adx + i128{ady} * ady;
    const i128 blift = i128{bdx} * bdx + i128{bdy} * bdy;
    const i128 clift = i128{cdx} * cdx + i128{cdy} * cdy;
    const i128 det = alift * (i128{bdx} * cdy - i128{cdx} * bdy) +
                     blift * (i128{cdx} * ady - i128{adx} * cdy) +
                     clift * (i128{adx} * bdy - i128{bdx} * ady);
    return det > 0 ? 1 : (det < 0 ? -1 : 0);
}

// Index along a Hilbert curve over a 2^20 x 2^20 grid (insertion order with locality).
std::uint64_t hilbert_index(std::uint32_t x, std::uint32_t y) noexcept {
    constexpr std::uint32_t n = 1u << 20;
    std::uint64_t d = 0;
    for (std::uint32_t s = n / 2; s > 0; s /= 2) {
        const std::uint32_t rx = (x & s) ? 1u : 0u, ry = (y & s) ? 1u : 0u;
        d += std::uint64_t{s} * s * ((3u * rx) ^ ry);
        if (ry == 0) {
            if (rx == 1) {
                x = n - 1 - x;
                y = n - 1 - y;
            }
            std::swap(x, y);
        }
    }
    return d;
}

struct Triangle {
    std::uint32_t v[3];  // counter-clockwise; a ghost triangle has the vertex at infinity in v[2]
    std::int32_t adj[3]; // adj[i]: triangle across the edge opposite v[i] (v[i+1] -> v[i+2])
};

constexpr std::uint32_t dead = std::numeric_limits<std::uint32_t>::max();

// Bowyer-Watson with the super-triangle taken to infinity: one symbolic vertex `inf` and "ghost" triangles
// (a, b, inf) on every convex-hull edge a -> b (the hull lies to its right). A ghost's circumcircle is the
// open half-plane left of a -> b plus the open segment ab (J. R. Shewchuk's lecture notes on Delaunay
// refinement). So the triangulation always covers exactly the convex hull: no sliver is lost to a finite
// super-triangle.
class BowyerWatson {
  public:
    // Starts from the counter-clockwise triangle (p0, p1, p2) and its three ghosts.
    BowyerWatson(std::vector<LatticePoint> points, std::uint32_t p0, std::uint32_t p1, std::uint32_t p2)
        : pts_(std::move(points)), inf_(static_cast<std::uint32_t>(pts_.size())) {
        tris_.push_back({{p0, p1, p2}, {-1, -1, -1}});
        tris_.push_back({{p2, p1, inf_}, {-1, -1, -1}});
        tris_.push_back({{p0, p2, inf_}, {-1, -1, -1}});
        tris_.push_back({{p1, p0, inf_}, {-1, -1, -1}});
        for (std::int32_t t = 0; t < 4; ++t)
            for (std::int32_t u = 0; u < 4; ++u)
                for (int i = 0; i < 3; ++i)
                    if (u != t && has_edge(u, tris_[t].v[(i + 2) % 3], tris_[t].v[(i + 1) % 3]))
                        tris_[t].adj[i] = u;
        stamp_.assign(4, 0);
    }

    void insert(std::uint32_t p) {
        ++round_;
        const std::int32_t start = locate(pts_[p]);
        // Cavity: triangles whose circumcircle strictly contains p, flooded from the one holding p.
        cavity_.clear();
        boundary_.clear();
        cavity_.push_back(start);
        stamp_[start] = in_stamp();
        for (std::size_t k = 0; k < cavity_.size(); ++k) {
            const std::int32_t t = cavity_[k];
            for (int i = 0; i < 3; ++i) {
                const std::int32_t nb = tris_[t].adj[i];
                if (stamp_[nb] == in_stamp()) continue;
                if (stamp_[nb] != out_stamp()) {
                    if (circumcircle_contains(nb, p)) {
                        stamp_[nb] = in_stamp();
                        cavity_.push_back(nb);
                        continue;
                    }
                    stamp_[nb] = out_stamp();
                }
                boundary_.push_back({tris_[t].v[(i + 1) % 3], tris_[t].v[(i + 2) % 3], nb});
            }
        }
        for (std::int32_t t : cavity_) {
            tris_[t].v[0] = dead;
            free_.push_back(t);
        }
        // Fan: one triangle (a, b, p) per boundary edge a -> b (rotated so a vertex at infinity comes last).
        fan_.clear();
        for (const BoundaryEdge& e : boundary_) {
            std::int32_t t;
            if (!free_.empty()) {
                t = free_.back();
                free_.pop_back();
            } else {
                t = static_cast<std::int32_t>(tris_.size());
                tris_.push_back({});
                stamp_.push_back(0);
            }
            if (e.a == inf_)
                tris_[t] = {{e.b, p, inf_}, {-1, -1, -1}};
            else if (e.b == inf_)
                tris_[t] = {{p, e.a, inf_}, {-1, -1, -1}};
            else
                tris_[t] = {{e.a, e.b, p}, {-1, -1, -1}};
            stamp_[t] = 0;
            set_adj(t, e.a, e.b, e.outside);
            set_adj(e.outside, e.b, e.a, t);
            fan_.push_back({e.a, t});
        }
        // The cavity boundary is a simple polygon around p: each of its vertices starts exactly one boundary
        // edge. Edge b -> p of the triangle on a -> b faces edge p -> b of the triangle on b -> c.
        std::sort(fan_.begin(), fan_.end());
        for (std::size_t k = 0; k < fan_.size(); ++k) {
            const std::int32_t t = fan_[k].second;
            const std::uint32_t b = boundary_of(t, p);
            const auto it = std::lower_bound(fan_.begin(), fan_.end(),
                                             std::pair<std::uint32_t, std::int32_t>{b, INT32_MIN});
            set_adj(t, b, p, it->second);
            set_adj(it->second, p, b, t);
        }
        last_ = fan_.front().second;
    }

    // Real triangles (no vertex at infinity), 3 indices each.
    std::vector<std::uint32_t> result() const {
        std::vector<std::uint32_t> out;
        for (const Triangle& t : tris_) {
            if (t.v[0] == dead || t.v[2] == inf_) continue;
            out.insert(out.end(), {t.v[0], t.v[1], t.v[2]});
        }
        return out;
    }

  private:
    struct BoundaryEdge {
        std::uint32_t a, b;
        std::int32_t outside;
    };

    std::uint64_t in_stamp() const noexcept { return 2 * round_; }
    std::uint64_t out_stamp() const noexcept { return 2 * round_ + 1; }
    bool is_ghost(std::int32_t t) const noexcept { return tris_[t].v[2] == inf_; }

    bool has_edge(std::int32_t t, std::uint32_t u, std::uint32_t v) const noexcept {
        for (int i = 0; i < 3; ++i)
            if (tris_[t].v[(i + 1) % 3] == u && tris_[t].v[(i + 2) % 3] == v) return true;
        return false;
    }
    void set_adj(std::int32_t t, std::uint32_t u, std::uint32_t v, std::int32_t nb) noexcept {
        for (int i = 0; i < 3; ++i)
            if (tris_[t].v[(i + 1) % 3] == u && tris_[t].v[(i + 2) % 3] == v) tris_[t].adj[i] = nb;
    }
    // For a fan triangle built on boundary edge a -> b around p: b (the vertex before p in counter-clockwise
    // order).
    std::uint32_t boundary_of(std::int32_t t, std::uint32_t p) const noexcept {
        const Triangle& tri = tris_[t];
        for (int i = 0; i < 3; ++i)
            if (tri.v[(i + 1) % 3] == p) return tri.v[i];
        return dead;
    }

    bool circumcircle_contains(std::int32_t t, std::uint32_t p) const noexcept {
        const Triangle& tri = tris_[t];
        const LatticePoint& q = pts_[p];
        if (tri.v[2] != inf_) return in_circle(pts_[tri.v[0]], pts_[tri.v[1]], pts_[tri.v[2]], q) > 0;
        const LatticePoint& a = pts_[tri.v[0]];
        const LatticePoint& b = pts_[tri.v[1]];
        const i64 o = orient(a, b, q);
        if (o != 0) return o > 0;
        // On the hull edge's line: inside only on the open segment.
        return (q.x - a.x) * (b.x - a.x) + (q.y - a.y) * (b.y - a.y) > 0 &&
               (q.x - b.x) * (a.x - b.x) + (q.y - b.y) * (a.y - b.y) > 0;
    }

    // Visibility walk from the last created triangle to a real triangle containing q (inside or on its
    // boundary), or to the ghost whose half-plane holds q when q is outside the hull. Terminates on a
    // Delaunay triangulation; the first edge tried rotates so the walk never cycles on degenerate layouts.
    std::int32_t locate(const LatticePoint& q) const {
        std::int32_t t = last_;
        if (is_ghost(t)) {
            if (orient(pts_[tris_[t].v[0]], pts_[tris_[t].v[1]], q) > 0) return t;
            t = tris_[t].adj[2];
        }
        for (std::size_t step = 0;; ++step) {
            const Triangle& tri = tris_[t];
            bool moved = false;
            for (int k = 0; k < 3; ++k) {
                const int i = static_cast<int>((k + step) % 3);
                if (orient(pts_[tri.v[(i + 1) % 3]], pts_[tri.v[(i + 2) % 3]], q) < 0) {
                    t = tri.adj[i];
                    moved = true;
                    break;
                }
            }
            if (!moved || is_ghost(t)) return t;
            if (step > 4 * tris_.size() + 16) throw std::logic_error("delaunay: point location failed");
        }
    }

    std::vector<LatticePoint> pts_;
    std::uint32_t inf_;
    std::vector<Triangle> tris_;
    std::vector<std::uint64_t> stamp_;
    std::vector<std::int32_t> free_, cavity_;
    std::vector<BoundaryEdge> boundary_;
    std::vector<std::pair<std::uint32_t, std::int32_t>> fan_;
    std::uint64_t round_ = 0;
    std::int32_t last_ = 0;
};

} // namespace

std::vector<std::uint32_t> delaunay_triangulate(std::span<const double> px, std::span<const double> py,
                                                std::vector<std::uint32_t>* out_duplicate_of) {
    if (px.size() != py.size())
        throw InvalidInput("delaunay: " + std::to_string(px.size()) + " x coordinates but " +
                           std::to_string(py.size()) + " y coordinates");
    const std::size_t n = px.size();
    if (n > (std::size_t{1} << 24))
        throw InvalidInput("delaunay: " + std::to_string(n) + " points (allowed 0..16777216)");
    double min_x = 0, max_x = 0, min_y = 0, max_y = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(px[i]) || !std::isfinite(py[i]))
            throw InvalidInput("delaunay: point " + std::to_string(i) + " has a non-finite coordinate");
        if (i == 0 || px[i] < min_x) min_x = px[i];
        if (i == 0 || px[i] > max_x) max_x = px[i];
        if (i == 0 || py[i] < min_y) min_y = py[i];
        if (i == 0 || py[i] > max_y) max_y = py[i];
    }
    const double extent = std::max(max_x - min_x, max_y - min_y);
    const double scale = extent > 0 ? static_cast<double>(lattice_max) / extent : 0.0;
    std::vector<LatticePoint> lattice(n);
    for (std::size_t i = 0; i < n; ++i)
        lattice[i] = {std::min<i64>(std::llround((px[i] - min_x) * scale), lattice_max),
                      std::min<i64>(std::llround((py[i] - min_y) * scale), lattice_max)};

    // Merge points that share a lattice point (the lowest index stays).
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
        if (lattice[a].x != lattice[b].x) return lattice[a].x < lattice[b].x;
        if (lattice[a].y != lattice[b].y) return lattice[a].y < lattice[b].y;
        return a < b;
    });
    std::vector<std::uint32_t> dup(n);
    std::vector<std::uint32_t> unique;
    for (std::size_t k = 0; k < n; ++k) {
        const std::uint32_t i = order[k];
        if (k > 0 && lattice[i].x == lattice[order[k - 1]].x && lattice[i].y == lattice[order[k - 1]].y) {
            dup[i] = dup[order[k - 1]];
        } else {
            dup[i] = i;
            unique.push_back(i);
        }
    }
    if (out_duplicate_of) *out_duplicate_of = dup;
    if (unique.size() < 3) return {};

    // Insertion order: along a Hilbert curve (ties by index: deterministic).
    std::vector<std::uint64_t> key(n);
    for (std::uint32_t i : unique)
        key[i] = hilbert_index(static_cast<std::uint32_t>(lattice[i].x >> 8),
                               static_cast<std::uint32_t>(lattice[i].y >> 8));
    std::sort(unique.begin(), unique.end(),
              [&](std::uint32_t a, std::uint32_t b) { return key[a] != key[b] ? key[a] < key[b] : a < b; });
    std::vector<LatticePoint> pts(unique.size());
    for (std::size_t k = 0; k < unique.size(); ++k)
        pts[k] = lattice[unique[k]];
    // The first triangle: the first two points and the first point after them not collinear with them.
    std::uint32_t third = 2;
    while (third < pts.size() && orient(pts[0], pts[1], pts[third]) == 0)
        ++third;
    if (third == pts.size()) return {}; // all collinear
    const bool ccw = orient(pts[0], pts[1], pts[third]) > 0;
    BowyerWatson bw(pts, 0, ccw ? 1u : third, ccw ? third : 1u);
    for (std::uint32_t k = 1; k < pts.size(); ++k)
        if (k != third && k != 1) bw.insert(k);
    const std::vector<std::uint32_t> lattice_tris = bw.result();
    // Drop slivers thinner than 4 lattice quanta (judged on the input coordinates): nearly collinear hull
    // points give them, and rounding to the lattice may have turned them inside out.
    const double quantum = extent / static_cast<double>(lattice_max);
    std::vector<std::uint32_t> tris;
    tris.reserve(lattice_tris.size());
    for (std::size_t t = 0; t < lattice_tris.size(); t += 3) {
        const std::uint32_t a = unique[lattice_tris[t]], b = unique[lattice_tris[t + 1]],
                            c = unique[lattice_tris[t + 2]];
        const double o = (px[b] - px[a]) * (py[c] - py[a]) - (py[b] - py[a]) * (px[c] - px[a]);
        const double longest =
            std::max({std::hypot(px[b] - px[a], py[b] - py[a]), std::hypot(px[c] - px[b], py[c] - py[b]),
                      std::hypot(px[a] - px[c], py[a] - py[c])});
        if (o <= 4.0 * quantum * longest) continue; // height = o / longest
        tris.insert(tris.end(), {a, b, c});
    }
    return tris;
}

// ---------------------------------------------------------------------------------------------------------------------
// Outline panels

namespace {

double cross2(double ax, double ay, double bx, double by) noexcept {
    return ax * by - ay * bx;
}

// Sign of the orientation of (a, b, c) with a relative tolerance (0 = collinear).
int orient_sign(const std::array<double, 2>& a, const std::array<double, 2>& b,
                const std::array<double, 2>& c, double tol) noexcept {
    const double o = cross2(b[0] - a[0], b[1] - a[1], c[0] - a[0], c[1] - a[1]);
    return o > tol ? 1 : (o < -tol ? -1 : 0);
}

bool on_segment(const std::array<double, 2>& a, const std::array<double, 2>& b,
                const std::array<double, 2>& p) {
    return std::min(a[0], b[0]) <= p[0] && p[0] <= std::max(a[0], b[0]) && std::min(a[1], b[1]) <= p[1] &&
           p[1] <= std::max(a[1], b[1]);
}

bool segments_touch(const std::array<double, 2>& a, const std::array<double, 2>& b,
                    const std::array<double, 2>& c, const std::array<double, 2>& d, double tol) {
    const int o1 = orient_sign(a, b, c, tol), o2 = orient_sign(a, b, d, tol), o3 = orient_sign(c, d, a, tol),
              o4 = orient_sign(c, d, b, tol);
    if (o1 != o2 && o3 != o4 && o1 != 0 && o2 != 0 && o3 != 0 && o4 != 0) return true;
    return (o1 == 0 && on_segment(a, b, c)) || (o2 == 0 && on_segment(a, b, d)) ||
           (o3 == 0 && on_segment(c, d, a)) || (o4 == 0 && on_segment(c, d, b));
}

double signed_area(const std::vector<std::array<double, 2>>& poly) {
    double s = 0;
    for (std::size_t i = 0, n = poly.size(); i < n; ++i) {
        const auto& a = poly[i];
        const auto& b = poly[(i + 1) % n];
        s += a[0] * b[1] - a[1] * b[0];
    }
    return 0.5 * s;
}

// Even-odd crossing test: strictly-inside for points off the outline.
bool inside_polygon(const std::vector<std::array<double, 2>>& poly, double x, double y) {
    bool in = false;
    for (std::size_t i = 0, n = poly.size(), j = n - 1; i < n; j = i++) {
        const double xi = poly[i][0], yi = poly[i][1], xj = poly[j][0], yj = poly[j][1];
        if ((yi > y) != (yj > y)) {
            const double xc = xi + (y - yi) / (yj - yi) * (xj - xi);
            if (x < xc) in = !in;
        }
    }
    return in;
}

} // namespace

void check_outline(const OutlinePanel& panel) {
    const auto& o = panel.outline;
    const std::size_t n = o.size();
    if (n < 3 || n > 4096)
        throw InvalidInput("outline has " + std::to_string(n) + " vertices (allowed 3..4096)");
    double extent = 0;
    for (std::size_t i = 0; i < n; ++i) {
        if (!std::isfinite(o[i][0]) || !std::isfinite(o[i][1]))
            throw InvalidInput("outline vertex " + std::to_string(i) + " has a non-finite coordinate");
        extent = std::max({extent, std::abs(o[i][0]), std::abs(o[i][1])});
    }
    if (extent > 1e3)
        throw InvalidInput("outline reaches " + std::to_string(extent) + " m from the origin (max 1000)");
    for (std::size_t i = 0; i < n; ++i) {
        const auto& a = o[i];
        const auto& b = o[(i + 1) % n];
        if (a[0] == b[0] && a[1] == b[1])
            throw InvalidInput("outline vertices " + std::to_string(i) + " and " +
                               std::to_string((i + 1) % n) + " coincide (consecutive vertices must differ)");
    }
    const double area = std::abs(signed_area(o));
    const bool zero_area = !(area > 1e-12 * std::max(extent * extent, 1e-300));
    const double tol = 1e-14 * extent * extent;
    if (zero_area) { // all on one line, or a self-crossing outline whose lobes cancel (a bow tie): told apart below
        std::size_t far = 0;
        double far_d = 0;
        for (std::size_t i = 1; i < n; ++i) {
            const double d = std::hypot(o[i][0] - o[0][0], o[i][1] - o[0][1]);
            if (d > far_d) far_d = d, far = i;
        }
        bool collinear = true;
        for (std::size_t i = 1; i < n && collinear; ++i)
            collinear = orient_sign(o[0], o[far], o[i], 1e-12 * std::max(extent * extent, 1e-300)) == 0;
        if (collinear) throw InvalidInput("outline has zero area (its vertices are collinear)");
    }
    for (std::size_t i = 0; i < n; ++i) {
        const auto& a = o[i];
        const auto& b = o[(i + 1) % n];
        // Adjacent edges must not fold back onto each other.
        const auto& c = o[(i + 2) % n];
        if (orient_sign(a, b, c, tol) == 0 &&
            (c[0] - b[0]) * (a[0] - b[0]) + (c[1] - b[1]) * (a[1] - b[1]) > 0)
            throw InvalidInput("outline is self-intersecting: edges " + std::to_string(i) + " and " +
                               std::to_string((i + 1) % n) + " fold back onto each other (the outline must be a "
                               "simple polygon)");
        for (std::size_t j = i + 2; j < n; ++j) {
            if (i == 0 && j == n - 1) continue; // adjacent through vertex 0
            if (segments_touch(a, b, o[j], o[(j + 1) % n], tol))
                throw InvalidInput("outline is self-intersecting: edge " + std::to_string(i) + " (vertices " +
                                   std::to_string(i) + "-" + std::to_string((i + 1) % n) + ") meets edge " +
                                   std::to_string(j) + " (vertices " + std::to_string(j) + "-" +
                                   std::to_string((j + 1) % n) + "); the outline must be a simple polygon");
        }
    }
    if (zero_area) throw InvalidInput("outline has zero area");
}

double outline_panel_point_estimate(const OutlinePanel& panel, double h) {
    const auto& poly = panel.outline;
    const std::size_t nv = poly.size();
    if (nv == 0) return 0.0;
    double min_u = poly[0][0], max_u = poly[0][0], min_v = poly[0][1], max_v = poly[0][1];
    double perimeter = 0;
    for (std::size_t i = 0; i < nv; ++i) {
        min_u = std::min(min_u, poly[i][0]);
        max_u = std::max(max_u, poly[i][0]);
        min_v = std::min(min_v, poly[i][1]);
        max_v = std::max(max_v, poly[i][1]);
        const auto& b = poly[(i + 1) % nv];
        perimeter += std::hypot(b[0] - poly[i][0], b[1] - poly[i][1]);
    }
    const double cols_d = std::floor((max_u - min_u) / h) + 1, rows_d = std::floor((max_v - min_v) / h) + 1;
    return cols_d * rows_d + perimeter / h + 2.0 * static_cast<double>(nv);
}

OutlinePanelBuild add_outline_panel(GarmentAssembly& io, const OutlinePanel& panel,
                                    const OutlinePanelParams& p, const PanelFrame& frame) {
    check_outline(panel);
    check_range("outline panel spacing", p.spacing, 1e-4, 10.0, " m");
    check_range("outline panel areal_density", p.areal_density, 1e-4, 100.0, " kg/m^2");
    check_range("outline panel outline_clearance", p.outline_clearance, 0.0, 0.99, "");
    check_range("outline panel max_points", p.max_points, std::size_t{1}, std::size_t{1} << 24, "");
    check_frame(frame);

    const auto& poly = panel.outline;
    const std::size_t nv = poly.size();
    const double h = p.spacing;
    OutlinePanelBuild out;
    out.area = std::abs(signed_area(poly));

    // Bounding box and a size check before anything is allocated.
    double min_u = poly[0][0], max_u = poly[0][0], min_v = poly[0][1], max_v = poly[0][1];
    for (std::size_t i = 0; i < nv; ++i) {
        min_u = std::min(min_u, poly[i][0]);
        max_u = std::max(max_u, poly[i][0]);
        min_v = std::min(min_v, poly[i][1]);
        max_v = std::max(max_v, poly[i][1]);
    }
    const double cols_d = std::floor((max_u - min_u) / h) + 1, rows_d = std::floor((max_v - min_v) / h) + 1;
    const double estimate = outline_panel_point_estimate(panel, h);
    if (estimate > static_cast<double>(p.max_points)) {
        char msg[200];
        std::snprintf(msg, sizeof msg,
                      "outline panel would need up to %.0f points at spacing %g m (at most %zu: max_points); raise "
                      "the spacing",
                      estimate, h, p.max_points);
        throw InvalidInput(msg);
    }
    const std::size_t cols = static_cast<std::size_t>(cols_d), rows = static_cast<std::size_t>(rows_d);

    // Points: outline samples first (in outline order), then the fill, row by row.
    std::vector<double> pu, pv, arc;
    out.outline_vertex_arc.resize(nv);
    double s = 0;
    for (std::size_t i = 0; i < nv; ++i) {
        const auto& a = poly[i];
        const auto& b = poly[(i + 1) % nv];
        const double len = std::hypot(b[0] - a[0], b[1] - a[1]);
        const std::size_t pieces =
            std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(len / h - 1e-9)));
        out.outline_vertex_arc[i] = s;
        for (std::size_t t = 0; t < pieces; ++t) {
            const double f = static_cast<double>(t) / static_cast<double>(pieces);
            pu.push_back(a[0] + f * (b[0] - a[0]));
            pv.push_back(a[1] + f * (b[1] - a[1]));
            arc.push_back(s + f * len);
        }
        s += len;
    }
    out.perimeter = s;
    const std::size_t outline_count = pu.size();

    // Fill points near the outline (closer than clearance * h) are marked and dropped.
    std::vector<std::uint8_t> near(cols * rows, 0);
    const double clearance = p.outline_clearance * h;
    if (clearance > 0)
        for (std::size_t i = 0; i < nv; ++i) {
            const auto& a = poly[i];
            const auto& b = poly[(i + 1) % nv];
            const double dx = b[0] - a[0], dy = b[1] - a[1], len2 = dx * dx + dy * dy;
            const auto lo_c =
                static_cast<std::ptrdiff_t>(std::floor((std::min(a[0], b[0]) - clearance - min_u) / h));
            const auto hi_c =
                static_cast<std::ptrdiff_t>(std::ceil((std::max(a[0], b[0]) + clearance - min_u) / h));
            const auto lo_r =
                static_cast<std::ptrdiff_t>(std::floor((std::min(a[1], b[1]) - clearance - min_v) / h));
            const auto hi_r =
                static_cast<std::ptrdiff_t>(std::ceil((std::max(a[1], b[1]) + clearance - min_v) / h));
            for (std::ptrdiff_t r = std::max<std::ptrdiff_t>(lo_r, 0);
                 r <= std::min<std::ptrdiff_t>(hi_r, static_cast<std::ptrdiff_t>(rows) - 1); ++r)
                for (std::ptrdiff_t c = std::max<std::ptrdiff_t>(lo_c, 0);
                     c <= std::min<std::ptrdiff_t>(hi_c, static_cast<std::ptrdiff_t>(cols) - 1); ++c) {
                    const double x = min_u + static_cast<double>(c) * h,
                                 y = min_v + static_cast<double>(r) * h;
                    const double t = std::clamp(((x - a[0]) * dx + (y - a[1]) * dy) / len2, 0.0, 1.0);
                    const double ex = a[0] + t * dx - x, ey = a[1] + t * dy - y;
                    if (ex * ex + ey * ey < clearance * clearance)
                        near[static_cast<std::size_t>(r) * cols + static_cast<std::size_t>(c)] = 1;
                }
        }
    for (std::size_t r = 0; r < rows; ++r)
        for (std::size_t c = 0; c < cols; ++c) {
            const double x = min_u + static_cast<double>(c) * h, y = min_v + static_cast<double>(r) * h;
            if (near[r * cols + c] || !inside_polygon(poly, x, y)) continue;
            pu.push_back(x);
            pv.push_back(y);
        }
    near = {};

    // Triangulate; keep triangles whose centroid is inside the outline.
    std::vector<std::uint32_t> dup;
    const std::vector<std::uint32_t> tris = delaunay_triangulate(pu, pv, &dup);
    std::vector<std::uint32_t> kept;
    kept.reserve(tris.size());
    for (std::size_t t = 0; t < tris.size(); t += 3) {
        const double cx = (pu[tris[t]] + pu[tris[t + 1]] + pu[tris[t + 2]]) / 3.0;
        const double cy = (pv[tris[t]] + pv[tris[t + 1]] + pv[tris[t + 2]]) / 3.0;
        if (inside_polygon(poly, cx, cy)) kept.insert(kept.end(), {tris[t], tris[t + 1], tris[t + 2]});
    }
    if (kept.empty())
    {
        char msg[200];
        std::snprintf(msg, sizeof msg,
                      "outline panel has no triangle at spacing %g m: the outline is too small or too thin for that "
                      "spacing (use a smaller spacing)",
                      h);
        throw InvalidInput(msg);
    }

    // Particles: the points used by kept triangles, in point order; lumped masses (1/3 of each triangle's
    // area).
    const std::size_t np = pu.size();
    std::vector<double> lumped(np, 0.0);
    for (std::size_t t = 0; t < kept.size(); t += 3) {
        const std::uint32_t a = kept[t], b = kept[t + 1], c = kept[t + 2];
        const double area = 0.5 * cross2(pu[b] - pu[a], pv[b] - pv[a], pu[c] - pu[a], pv[c] - pv[a]);
        for (std::uint32_t v : {a, b, c})
            lumped[v] += area / 3.0;
    }
    std::vector<std::int64_t> particle(np, -1);
    out.first_particle = static_cast<std::uint32_t>(io.particle_count());
    std::size_t used = 0;
    for (std::size_t i = 0; i < np; ++i)
        used += lumped[i] > 0 ? 1 : 0;
    if (io.particle_count() + used > assembly_max_particles)
        throw InvalidInput("garment would have " + std::to_string(io.particle_count() + used) +
                           " particles (max 2^31-1)");
    for (std::size_t i = 0; i < np; ++i) {
        if (!(lumped[i] > 0)) continue;
        particle[i] = static_cast<std::int64_t>(io.particle_count());
        push_particle(io, frame, pu[i], pv[i], lumped[i] * p.areal_density);
    }
    out.particle_count = static_cast<std::uint32_t>(used);
    for (std::size_t i = 0; i < outline_count; ++i) {
        if (dup[i] != i || particle[i] < 0) continue;
        out.outline_particles.push_back(static_cast<std::uint32_t>(particle[i]));
        out.outline_arc.push_back(arc[i]);
    }

    out.first_triangle = io.triangle_count();
    for (std::uint32_t v : kept)
        io.triangles.push_back(static_cast<std::uint32_t>(particle[v]));
    out.triangle_count = kept.size() / 3;

    out.first_edge = io.edges.size();
    add_triangle_springs(io, std::span<const std::uint32_t>(io.triangles).subspan(out.first_triangle * 3));
    out.edge_count = io.edges.size() - out.first_edge;
    return out;
}

std::vector<std::uint32_t> outline_stretch_particles(const OutlinePanelBuild& build,
                                                     const OutlineStretch& stretch) {
    const std::size_t nv = build.outline_vertex_arc.size();
    if (stretch.from_vertex >= nv || stretch.to_vertex >= nv)
        throw InvalidInput("outline stretch " + std::to_string(stretch.from_vertex) + " -> " +
                           std::to_string(stretch.to_vertex) + " names a vertex outside [0, " +
                           std::to_string(nv == 0 ? 0 : nv - 1) + "]");
    const double s0 = build.outline_vertex_arc[stretch.from_vertex],
                 s1 = build.outline_vertex_arc[stretch.to_vertex];
    const double length = stretch.from_vertex == stretch.to_vertex
                              ? build.perimeter
                              : (s1 >= s0 ? s1 - s0 : build.perimeter - s0 + s1);
    std::vector<std::pair<double, std::uint32_t>> on;
    for (std::size_t k = 0; k < build.outline_particles.size(); ++k) {
        double d = build.outline_arc[k] - s0;
        if (d < 0) d += build.perimeter;
        const bool whole = stretch.from_vertex == stretch.to_vertex;
        if (whole ? d < length : d <= length) on.push_back({d, build.outline_particles[k]});
    }
    std::sort(on.begin(), on.end());
    std::vector<std::uint32_t> out;
    out.reserve(on.size());
    for (const auto& e : on)
        out.push_back(e.second);
    if (stretch.reversed) std::reverse(out.begin(), out.end());
    return out;
}

std::vector<std::uint32_t> sew_by_arc_length(GarmentAssembly& io, std::span<const std::uint32_t> a,
                                             std::span<const std::uint32_t> b, float seam_rest) {
    if (!(seam_rest > 0.0f) || !std::isfinite(seam_rest))
        throw InvalidInput("seam rest length = " + std::to_string(seam_rest) + " m (must be > 0 and finite)");
    if (a.empty() || b.empty()) throw InvalidInput("sewing needs at least one particle on each side");
    const std::size_t n = io.particle_count();
    for (std::span<const std::uint32_t> side : {a, b})
        for (std::uint32_t i : side)
            if (i >= n)
                throw InvalidInput("sewing names particle " + std::to_string(i) + " outside [0, " +
                                   std::to_string(n == 0 ? 0 : n - 1) + "]");
    // Normalised arc length along each polyline, from the assembly's positions.
    auto param = [&](std::span<const std::uint32_t> line) {
        std::vector<double> t(line.size(), 0.0);
        for (std::size_t k = 1; k < line.size(); ++k) {
            const double dx = double{io.x[line[k]]} - io.x[line[k - 1]],
                         dy = double{io.y[line[k]]} - io.y[line[k - 1]],
                         dz = double{io.z[line[k]]} - io.z[line[k - 1]];
            t[k] = t[k - 1] + std::sqrt(dx * dx + dy * dy + dz * dz);
        }
        if (t.back() > 0)
            for (double& v : t)
                v /= t.back();
        return t;
    };
    const std::vector<double> ta = param(a), tb = param(b);
    // Nearest entry of sorted `t` to `value` (the lower index on a tie).
    auto nearest = [](const std::vector<double>& t, double value) {
        const auto it = std::lower_bound(t.begin(), t.end(), value);
        std::size_t k = static_cast<std::size_t>(it - t.begin());
        if (k == t.size()) return t.size() - 1;
        if (k > 0 && value - t[k - 1] <= t[k] - value) return k - 1;
        return k;
    };
    std::unordered_set<std::uint64_t> joined;
    joined.reserve(io.edges.size() + a.size() + b.size());
    for (const Edge& e : io.edges)
        joined.insert(pair_key(e.a, e.b));
    std::vector<std::uint32_t> added;
    auto join = [&](std::uint32_t p, std::uint32_t q) {
        if (p == q || !joined.insert(pair_key(p, q)).second) return;
        added.push_back(static_cast<std::uint32_t>(io.edges.size()));
        io.edges.push_back({std::min(p, q), std::max(p, q), SpringKind::seam, seam_rest});
    };
    std::vector<std::uint8_t> b_joined(b.size(), 0);
    for (std::size_t k = 0; k < a.size(); ++k) {
        const std::size_t m = nearest(tb, ta[k]);
        b_joined[m] = 1;
        join(a[k], b[m]);
    }
    for (std::size_t m = 0; m < b.size(); ++m)
        if (!b_joined[m]) join(a[nearest(ta, tb[m])], b[m]);
    return added;
}

} // namespace drape
