// Outline panels (seed 004 section 1): a polygon filled with points, Delaunay-triangulated, and its outline kept
// as particles for sewing.
#include "drape/outline_panel.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "drape/delaunay.hpp"
#include "panel_build.hpp"

namespace drape {

using namespace panel_build;

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

} // namespace drape
