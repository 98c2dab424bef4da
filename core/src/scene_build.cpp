// Building a scene: cooking a SceneSpec (read by scene.cpp) into a BuiltScene, a cloth plus simulation parameters.
#include "drape/scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <set>

#include "drape/errors.hpp"
#include "drape/level_transfer.hpp"
#include "drape/mirror_symmetry.hpp"
#include "drape/pattern_seams.hpp"
#include "drape/stability.hpp"
#include "drape/triangle_fabric.hpp"

#include "mask_frame.hpp"
#include "scene_json.hpp" // format_number, printable

namespace drape {

namespace {

/// Cooks an assembly (outline and mesh cloths; the T-shirt with the fabric model). Springs model: stiffness per kind as
/// for the other cloths, the damping ratio uses the mean particle mass. Fabric model: triangle_fabric.hpp (membrane
/// springs per edge, hinge bending, seams), the weave's u axis `axis_u`.
void cook_assembly(const SceneSpec& s, const GarmentAssembly& a, const std::vector<float>& inv_mass,
                   const std::vector<float>& free_inv_mass, BuiltScene& out,
                   const std::array<float, 3>& axis_u = {1.0f, 0.0f, 0.0f},
                   WeaveAlignment alignment = WeaveAlignment::aligned) {
    if (s.model == MaterialModel::fabric) {
        out.cloth = cook_triangle_fabric(a, inv_mass, {s.fabric, axis_u, alignment});
    } else {
        double total = 0.0;
        for (float m : a.mass) total += m;
        const float mean_mass = float(total / double(std::max<std::size_t>(1, a.particle_count())));
        std::array<SpringMaterial, spring_kind_count> material{};
        const float ks[4] = {s.stiffness, s.stiffness * s.shear_ratio, s.stiffness * s.bend_ratio, s.seam_stiffness};
        for (int kind = 0; kind < 4; ++kind)
            material[kind] = {ks[kind], s.damping_ratio * 2.0f * std::sqrt(ks[kind] * mean_mass * 0.5f)};
        out.cloth = cook_cloth(inv_mass, a.edges, material);
        out.cloth.triangles = a.triangles;
    }
    out.cloth.free_inv_mass = free_inv_mass;
    out.initial = a.initial_state();
}

/// cloth.type = "mask": the panels (add_mask_panel), masses from the areal density (a third of each triangle's area
/// to its corners; a particle in no triangle gets a third of a half cell, as the T-shirt's), the seams (cell k of
/// edge a to cell k of edge b; a pair already joined or a particle with itself is skipped), the pins.
void build_mask_cloth(const SceneSpec& s, BuiltScene& out) {
    const MaskClothSpec& m = s.masks;
    if (m.panels.empty()) throw InvalidInput(s.source + ": cloth.panels: a mask cloth needs at least one panel");
    // The cloth's origin: the middle of the panels' origins (positions are stored relative to it).
    std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    for (const MaskPanelSpec& p : m.panels)
        for (int k = 0; k < 3; ++k)
            lo[k] = std::min(lo[k], p.origin[k]), hi[k] = std::max(hi[k], p.origin[k]);
    const std::array<double, 3> origin{0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
    const double density = s.model == MaterialModel::fabric ? double(s.fabric.density) : double(m.density);
    GarmentAssembly a;
    std::vector<MaskPanelBuild> panels;
    panels.reserve(m.panels.size());
    for (std::size_t k = 0; k < m.panels.size(); ++k) {
        const MaskPanelSpec& p = m.panels[k];
        const double h = p.cell_size;
        try {
            // (The mass is replaced below; clamped into add_mask_panel's range.)
            panels.push_back(add_mask_panel(a, p.mask, p.cell_size, float(std::clamp(density * h * h, 1e-6, 1.0)),
                                            mask_frame(p, origin)));
        } catch (const InvalidInput& e) {
            throw InvalidInput(s.source + ": cloth.panels[" + std::to_string(k) + "] \"" + printable(p.name, 64) +
                               "\": " + e.what());
        }
    }
    const std::vector<double> lumped = lumped_masses(a.x, a.y, a.z, a.triangles, density);
    for (std::size_t k = 0; k < panels.size(); ++k) {
        const double h = m.panels[k].cell_size, lone = density * h * h / 6.0;
        for (std::uint32_t i = panels[k].first_particle; i < panels[k].first_particle + panels[k].particle_count; ++i)
            a.mass[i] = float(lumped[i] > 0.0 ? lumped[i] : lone);
    }
    std::set<std::pair<std::uint32_t, std::uint32_t>> joined;
    for (const Edge& e : a.edges)
        joined.insert({std::min(e.a, e.b), std::max(e.a, e.b)});
    for (std::size_t k = 0; k < m.seams.size(); ++k) {
        const MaskSeamSpec& seam = m.seams[k];
        const auto ca = mask_edge_cells(seam.a), cb = mask_edge_cells(seam.b);
        if (ca.size() != cb.size() || seam.a.panel >= panels.size() || seam.b.panel >= panels.size())
            throw InvalidInput(s.source + ": cloth.seams[" + std::to_string(k) +
                               "]: edges of unequal length or an unknown panel");
        const float rest =
            seam.rest_ratio * 0.5f * (m.panels[seam.a.panel].cell_size + m.panels[seam.b.panel].cell_size);
        std::size_t itself = 0, before = 0;
        for (std::size_t j = 0; j < ca.size(); ++j) {
            const std::int32_t pa = panels[seam.a.panel].particle_at(ca[j][0], ca[j][1]);
            const std::int32_t pb = panels[seam.b.panel].particle_at(cb[j][0], cb[j][1]);
            if (pa < 0 || pb < 0)
                throw InvalidInput(s.source + ": cloth.seams[" + std::to_string(k) +
                                   "]: a cell of the seam holds no particle");
            const auto lo_i = static_cast<std::uint32_t>(std::min(pa, pb)),
                       hi_i = static_cast<std::uint32_t>(std::max(pa, pb));
            if (lo_i == hi_i) {
                ++itself;
                continue;
            }
            if (!joined.insert({lo_i, hi_i}).second) {
                ++before;
                continue;
            }
            a.edges.push_back({lo_i, hi_i, SpringKind::seam, rest});
        }
        // A seam that joins nothing is a mistake in the file (the same edge twice, or two rows of one panel that its
        // springs already join), not a seam: refused rather than run as if sewn.
        if (itself + before == ca.size())
            throw InvalidInput(s.source + ": cloth.seams[" + std::to_string(k) + "] joins nothing: of its " +
                               std::to_string(ca.size()) + " cell pairs " + std::to_string(itself) +
                               " pair a cell with itself and " + std::to_string(before) +
                               " pair cells already joined (by the panel's springs or an earlier seam); a seam "
                               "sews two different edges, cell k of a to cell k of b");
    }
    // A '1' with no '1' beside, above or below it (or across a corner with a shared neighbour) and no seam would be
    // a loose particle falling on its own: refused, naming the first such cell (a checkerboard mask ran "healthy"
    // with 0 springs).
    std::vector<std::uint32_t> degree(a.particle_count(), 0);
    for (const Edge& e : a.edges)
        ++degree[e.a], ++degree[e.b];
    const std::size_t loose = std::size_t(std::count(degree.begin(), degree.end(), 0u));
    for (std::size_t k = 0; k < panels.size() && loose > 0; ++k)
        for (std::size_t cell = 0; cell < panels[k].cell_particle.size(); ++cell) {
            const std::int32_t i = panels[k].cell_particle[cell];
            if (i < 0 || degree[std::size_t(i)] > 0) continue;
            throw InvalidInput(s.source + ": cloth.panels[" + std::to_string(k) + "] \"" +
                               printable(m.panels[k].name, 64) + "\": the '1' at row " +
                               std::to_string(cell / panels[k].columns) + ", column " +
                               std::to_string(cell % panels[k].columns) +
                               " touches no other '1' (beside, above or below it) and no seam: it would be a loose "
                               "particle falling on its own (" + std::to_string(loose) +
                               (loose == 1 ? " such cell" : " such cells") +
                               " in the cloth); join it to the panel or make it '0'");
        }
    std::vector<float> inv_mass = a.inverse_masses();
    const std::vector<float> free_inv_mass = inv_mass;
    for (std::size_t k = 0; k < panels.size(); ++k) {
        const MaskPanelSpec& p = m.panels[k];
        if (p.pins == MaskPins::top_row) { // the first row holding a particle
            for (std::uint32_t r = 0; r < panels[k].rows; ++r) {
                bool any = false;
                for (std::uint32_t c = 0; c < panels[k].columns; ++c)
                    if (const std::int32_t i = panels[k].particle_at(r, c); i >= 0)
                        inv_mass[std::size_t(i)] = 0.0f, any = true;
                if (any) break;
            }
        } else if (p.pins == MaskPins::list) {
            for (const auto& [r, c] : p.pin_cells)
                if (const std::int32_t i = panels[k].particle_at(r, c); i >= 0) inv_mass[std::size_t(i)] = 0.0f;
        }
    }
    // The fabric's u: the first panel's (mask columns); unaligned when the panels' u axes differ (a warning on load).
    const bool aligned = mask_weave_aligned(m);
    cook_assembly(s, a, inv_mass, free_inv_mass, out, mask_frame(m.panels[0], origin).axis_u,
                  aligned ? WeaveAlignment::aligned : WeaveAlignment::unaligned);
    out.cloth.origin = origin;
}

/// A saved state replaces the initial state and the pins (after dt is chosen, so the default dt is that of the
/// scene's own pins, as when the state was saved).
void apply_state(const SceneState& st, BuiltScene& out) {
    Cloth& c = out.cloth;
    const std::size_t n = c.particle_count;
    if (st.x.size() != n)
        throw InvalidInput("state.positions has " + std::to_string(st.x.size()) + " entries but the cloth has " +
                           std::to_string(n) + " particles");
    if (st.vx.size() != n)
        throw InvalidInput("state.velocities has " + std::to_string(st.vx.size()) + " entries but the cloth has " +
                           std::to_string(n) + " particles");
    for (std::uint32_t i : st.pinned)
        if (i >= n)
            throw InvalidInput("state.pinned names particle " + std::to_string(i) + "; the cloth has " +
                               std::to_string(n) + " particles");
    if (c.free_inv_mass.size() != n) c.free_inv_mass.assign(c.inv_mass.begin(), c.inv_mass.begin() + n);
    for (std::size_t i = 0; i < n; ++i) c.inv_mass[i] = c.free_inv_mass[i];
    for (std::uint32_t i : st.pinned) c.inv_mass[i] = 0.0f;
    // Positions into the cloth's frame: exact when the state was saved from the same frame (the usual case).
    const std::array<double, 3> shift{st.origin[0] - c.origin[0], st.origin[1] - c.origin[1], st.origin[2] - c.origin[2]};
    out.initial.x = st.x;
    out.initial.y = st.y;
    out.initial.z = st.z;
    if (shift != std::array<double, 3>{0.0, 0.0, 0.0})
        for (std::size_t i = 0; i < n; ++i) {
            out.initial.x[i] = static_cast<float>(double(st.x[i]) + shift[0]);
            out.initial.y[i] = static_cast<float>(double(st.y[i]) + shift[1]);
            out.initial.z[i] = static_cast<float>(double(st.z[i]) + shift[2]);
        }
    out.initial.vx = st.vx;
    out.initial.vy = st.vy;
    out.initial.vz = st.vz;
    if (!st.seam_rest.empty() && st.seam_rest.size() != c.seams.a.size())
        throw InvalidInput("state.seam_rest has " + std::to_string(st.seam_rest.size()) + " entries but the cloth has " +
                           std::to_string(c.seams.a.size()) + " seams");
    out.initial.seam_rest = st.seam_rest;
    out.initial.snapshot_x = st.snapshot_x;
    out.initial.snapshot_y = st.snapshot_y;
    out.initial.snapshot_z = st.snapshot_z;
    if (shift != std::array<double, 3>{0.0, 0.0, 0.0})
        for (std::size_t i = 0; i < st.snapshot_x.size(); ++i) {
            out.initial.snapshot_x[i] = static_cast<float>(double(st.snapshot_x[i]) + shift[0]);
            out.initial.snapshot_y[i] = static_cast<float>(double(st.snapshot_y[i]) + shift[1]);
            out.initial.snapshot_z[i] = static_cast<float>(double(st.snapshot_z[i]) + shift[2]);
        }
    out.initial.sc_planes = st.sc_planes;
    if (shift != std::array<double, 3>{0.0, 0.0, 0.0}) {
        SelfCollisionPlanes& pl = out.initial.sc_planes;
        for (std::size_t k = 0; k < pl.index.size(); ++k)
            pl.c[k] = static_cast<float>(double(pl.c[k]) + pl.nx[k] * shift[0] + pl.ny[k] * shift[1] + pl.nz[k] * shift[2]);
    }
}

} // namespace

namespace {

/// Fabric model: an outline narrower than its spacing somewhere (a spike a fraction of the spacing wide) is
/// triangulated there into needles, which the cook refuses (NeedleTriangleError: a membrane spring past
/// membrane_stiffness_ratio_max); this names the place in the outline's coordinates (cu, cv: the outline's centre)
/// rather than two particle numbers.
[[noreturn]] void refuse_outline_needle(const SceneSpec& s, const GarmentAssembly& a, float cu, float cv,
                                        const NeedleTriangleError& e) {
    const bool horizontal = s.outline.plane == GridPlane::horizontal;
    const double u = 0.5 * (double(a.x[e.a]) + a.x[e.b]) + cu,
                 v = (horizontal ? 0.5 * (double(a.z[e.a]) + a.z[e.b]) : -0.5 * (double(a.y[e.a]) + a.y[e.b])) + cv;
    char msg[400];
    std::snprintf(msg, sizeof msg,
                  ": cloth.outline at cloth.spacing = %g m: near (%.4g, %.4g) the outline is narrower than the spacing "
                  "(a spike or a slit): its triangles there are needles whose short edge would be %.0f times as stiff "
                  "as the fabric (at most %.0f); widen the outline there, or lower cloth.spacing",
                  double(s.outline.spacing), u, v, e.ratio, membrane_stiffness_ratio_max);
    throw InvalidInput((s.source.empty() ? std::string("scene") : s.source) + msg);
}

/// The same for an OBJ mesh (fabric model): names the needle's short edge by its OBJ vertices (1-based, as the file
/// numbers them; the first of any welded duplicates) and its middle in the file's units.
[[noreturn]] void refuse_mesh_needle(const SceneSpec& s, const TriangleMesh& mesh, const NeedleTriangleError& e) {
    const auto obj_vertex = [&](std::uint32_t particle) {
        const auto& pv = mesh.particle_of_vertex;
        return std::size_t(std::find(pv.begin(), pv.end(), std::int64_t(particle)) - pv.begin()) + 1;
    };
    char msg[500];
    std::snprintf(msg, sizeof msg,
                  ": cloth.file: the edge from OBJ vertex %zu to vertex %zu (numbered from 1 as in the file's faces; near "
                  "(%.4g, %.4g, %.4g) in the file) is "
                  "the short side of a needle triangle: its membrane spring would be %.0f times as stiff as the fabric "
                  "(at most %.0f); remesh there (collapse the short edge or split the wide triangle)",
                  obj_vertex(e.a), obj_vertex(e.b), 0.5 * (mesh.x[e.a] + mesh.x[e.b]), 0.5 * (mesh.y[e.a] + mesh.y[e.b]),
                  0.5 * (mesh.z[e.a] + mesh.z[e.b]), e.ratio, membrane_stiffness_ratio_max);
    throw InvalidInput((s.source.empty() ? std::string("scene") : s.source) + msg);
}

/// cloth.type = "outline": the panel (and its sewn copy) at the spec's spacing, pinned along the top when asked.
void build_outline_cloth(const SceneSpec& s, BuiltScene& out) {
    const OutlineClothSpec& o = s.outline;
    double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
    for (const auto& v : o.outline.outline)
        for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
    const float cu = float(0.5 * (lo[0] + hi[0])), cv = float(0.5 * (lo[1] + hi[1]));
    // Panel frame: u along +x; v along +z (horizontal) or -y (vertical); the normal u x v is -y or -z.
    PanelFrame frame;
    frame.axis_v = o.plane == GridPlane::horizontal ? std::array{0.0f, 0.0f, 1.0f} : std::array{0.0f, -1.0f, 0.0f};
    const std::array<float, 3> normal = o.plane == GridPlane::horizontal ? std::array{0.0f, -1.0f, 0.0f}
                                                                       : std::array{0.0f, 0.0f, -1.0f};
    const float half_gap = o.copy ? 0.5f * o.gap : 0.0f;
    // Positions relative to o.centre, the frame's origin (Cloth::origin, set below).
    for (int k = 0; k < 3; ++k)
        frame.origin[k] = -cu * frame.axis_u[k] - cv * frame.axis_v[k] - half_gap * normal[k];
    OutlinePanelParams op;
    op.spacing = o.spacing;
    op.areal_density = s.model == MaterialModel::fabric ? s.fabric.density : o.density;
    GarmentAssembly a;
    // Panel errors the file could not be checked for before triangulating (an outline too thin for its
    // spacing) name the file and the fields.
    const auto panel = [&](const PanelFrame& f) {
        try {
            return add_outline_panel(a, o.outline, op, f);
        } catch (const InvalidInput& e) {
            throw InvalidInput((s.source.empty() ? std::string("scene") : s.source) + ": cloth.outline at cloth.spacing = " +
                               format_number(o.spacing) + " m: " + e.what());
        }
    };
    const OutlinePanelBuild front = panel(frame);
    if (o.copy) {
        PanelFrame back = frame;
        for (int k = 0; k < 3; ++k) back.origin[k] += 2.0f * half_gap * normal[k];
        const OutlinePanelBuild rear = panel(back);
        for (const auto& [from, to] : o.sew) {
            const OutlineStretch stretch{from, to, false};
            sew_by_arc_length(a, outline_stretch_particles(front, stretch), outline_stretch_particles(rear, stretch),
                              o.seam_rest_ratio * o.spacing);
        }
    }
    std::vector<float> inv_mass = a.inverse_masses();
    const std::vector<float> free_inv_mass = inv_mass;
    if (o.pin_top) { // the particles along the top (vertical) or the far edge (horizontal: largest z)
        const bool vertical = o.plane == GridPlane::vertical;
        float top = -1e30f;
        for (std::size_t i = 0; i < a.particle_count(); ++i) top = std::max(top, vertical ? a.y[i] : a.z[i]);
        for (std::size_t i = 0; i < a.particle_count(); ++i)
            if ((vertical ? a.y[i] : a.z[i]) >= top - 0.25f * o.spacing) inv_mass[i] = 0.0f;
    }
    try {
        cook_assembly(s, a, inv_mass, free_inv_mass, out);
    } catch (const NeedleTriangleError& e) {
        refuse_outline_needle(s, a, cu, cv, e);
    }
    out.cloth.origin = {double(o.centre[0]), double(o.centre[1]), double(o.centre[2])};
}

/// A cloth of the fabric model that its builder can make at any spacing (an outline) rebuilds itself at
/// 2^level times its spacing for the implicit solver's coarse levels (Cloth::coarsen); `build(level)` makes that copy
/// (nullopt where the builder refuses it: too coarse). Both copies lie where they were built (flat panels), so the
/// maps between them are taken there: the closest point on the other copy's triangles (surface_transfer); the
/// cloth's own built layout is kept for it.
void set_rebuild_coarsen(BuiltScene& out, std::function<std::optional<BuiltScene>(std::uint32_t level)> build) {
    struct Layout {
        std::vector<float> x, y, z;
        std::vector<std::uint32_t> triangles;
    };
    auto fine = std::make_shared<const Layout>(Layout{out.initial.x, out.initial.y, out.initial.z, out.cloth.triangles});
    out.cloth.coarsen = [build = std::move(build), fine](std::uint32_t level) -> std::optional<CoarseCloth> {
        if (level == 0 || level > 16) return std::nullopt;
        const auto attempt = [&](std::uint32_t k) -> std::optional<BuiltScene> {
            try {
                return build(k);
            } catch (const InvalidInput&) { // too coarse for the builder: no such level
                return std::nullopt;
            }
        };
        std::optional<BuiltScene> coarse = attempt(level);
        if (!coarse) return std::nullopt;
        std::optional<BuiltScene> finer;
        if (level > 1 && !(finer = attempt(level - 1))) return std::nullopt;
        const std::vector<float>& fx = finer ? finer->initial.x : fine->x;
        const std::vector<float>& fy = finer ? finer->initial.y : fine->y;
        const std::vector<float>& fz = finer ? finer->initial.z : fine->z;
        const InitialState& c = coarse->initial;
        CoarseCloth copy;
        copy.from_fine = surface_transfer(fine->x, fine->y, fine->z, fine->triangles, c.x, c.y, c.z);
        copy.to_finer = surface_transfer(c.x, c.y, c.z, coarse->cloth.triangles, fx, fy, fz);
        copy.x = c.x;
        copy.y = c.y;
        copy.z = c.z;
        copy.cloth = std::move(coarse->cloth);
        return copy;
    };
}

BuiltScene build_scene_body(const SceneSpec& s) {
    BuiltScene out;
    if (s.cloth == ClothType::grid) {
        HangParams g = s.grid;
        g.stiffness = s.stiffness;
        g.shear_ratio = s.shear_ratio;
        g.bend_ratio = s.bend_ratio;
        g.damping_ratio = s.damping_ratio;
        g.model = s.model;
        g.fabric = s.fabric;
        SceneBuild b = build_hang_scene(g);
        out.cloth = std::move(b.cloth);
        out.initial = std::move(b.initial);
    } else if (s.cloth == ClothType::outline) {
        build_outline_cloth(s, out);
        if (s.model == MaterialModel::fabric) {
            SceneSpec base = s; // what the rebuilds need (not a saved state's arrays)
            base.state.reset();
            set_rebuild_coarsen(out, [base](std::uint32_t k) {
                const SceneSpec& s = base;
                SceneSpec c = s;
                c.outline.spacing = s.outline.spacing * float(1u << k);
                c.outline.seam_rest_ratio = s.outline.seam_rest_ratio / float(1u << k); // the seams' own rest length
                BuiltScene b;
                build_outline_cloth(c, b);
                return std::optional<BuiltScene>(std::move(b));
            });
        }
    } else if (s.cloth == ClothType::mask) {
        build_mask_cloth(s, out);
    } else if (s.cloth == ClothType::mesh) {
        const MeshClothSpec& m = s.mesh;
        if (!m.mesh) throw InvalidInput("mesh cloth: no mesh loaded (cloth.file)");
        GarmentAssembly a;
        // Positions relative to m.centre, the cloth's origin (Cloth::origin, set below).
        add_mesh_panel(a, *m.mesh,
                       {m.scale, {0.0f, 0.0f, 0.0f}, s.model == MaterialModel::fabric ? s.fabric.density : m.density});
        // Sizes float arithmetic can carry: a mesh of 1e30 m gave inf areas (node mass 0, strain inf) and NaN
        // normals with exit 0; two vertices 1e-7 apart gave a spring stiffness scale of 6e6 and a default dt of 0.
        double extent = 0.0, shortest = std::numeric_limits<double>::max();
        for (std::size_t i = 0; i < a.particle_count(); ++i)
            extent = std::max({extent, std::fabs(double(a.x[i])), std::fabs(double(a.y[i])), std::fabs(double(a.z[i]))});
        for (const Edge& e : a.edges) // the triangles' edges (bend springs join opposite vertices, not edges)
            if (e.kind == SpringKind::structural || e.kind == SpringKind::shear) shortest = std::min(shortest, double(e.rest));
        if (!(extent <= 1e4))
            throw InvalidInput(s.source + ": cloth.file: the mesh reaches " + format_number(extent) +
                               " m from its centre after cloth.scale (at most 1e4 m): lower cloth.scale");
        if (shortest != std::numeric_limits<double>::max() && !(shortest >= 1e-5))
            throw InvalidInput(s.source + ": cloth.file: the mesh's shortest edge is " + format_number(shortest) +
                               " m after cloth.scale (at least 1e-5 m): weld vertices that nearly coincide, or raise "
                               "cloth.scale");
        std::vector<float> inv_mass = a.inverse_masses();
        const std::vector<float> free_inv_mass = inv_mass;
        if (m.pins == MeshPins::top) {
            const std::vector<std::uint32_t> top = mesh_top_particles(*m.mesh);
            // A mesh lying flat and level has every vertex at its top: nothing would move.
            if (top.size() == a.particle_count())
                throw InvalidInput(s.source + ": cloth.pins = \"top\" would pin every particle of this mesh (all " +
                                   std::to_string(top.size()) + " are at its top: it lies flat and level); use "
                                   "\"none\", a list of vertex indices, or stand the mesh up");
            for (std::uint32_t i : top) inv_mass[i] = 0.0f;
        }
        for (std::uint32_t v : m.pin_vertices) inv_mass[static_cast<std::size_t>(m.mesh->particle_of_vertex.at(v))] = 0.0f;
        // An OBJ's edges need not follow any weave: the unaligned membrane (triangle_fabric.hpp); u = the file's x.
        try {
            cook_assembly(s, a, inv_mass, free_inv_mass, out, {1.0f, 0.0f, 0.0f}, WeaveAlignment::unaligned);
        } catch (const NeedleTriangleError& e) { // the assembly's particles are the mesh's, in order
            refuse_mesh_needle(s, *m.mesh, e);
        }
        out.cloth.origin = {double(m.centre[0]), double(m.centre[1]), double(m.centre[2])};
    } else if (s.model == MaterialModel::fabric) {
        // Fabric: node masses from the fabric's density and the panels' triangles (TShirtParams::total_mass is not
        // used); a particle in no triangle gets a third of a half cell. Both panels' u is +-x (mask columns). No coarse
        // levels: tried (rebuilt at half the cells per metre), the shirt settled less symmetric at the seed's 35
        // cells/m (docs/implicit.md, "Outline cloths on their coarse levels").
        TShirtBuild t = build_tshirt(s.tshirt);
        GarmentAssembly& a = t.assembly;
        const std::vector<double> m = lumped_masses(a.x, a.y, a.z, a.triangles, s.fabric.density);
        const double lone = double(s.fabric.density) * t.spacing * t.spacing / 6.0;
        for (std::size_t i = 0; i < a.particle_count(); ++i) a.mass[i] = float(m[i] > 0.0 ? m[i] : lone);
        const std::vector<float> inv_mass = a.inverse_masses();
        cook_assembly(s, a, inv_mass, inv_mass, out);
        out.cloth.free_inv_mass.clear();
        if (s.tshirt.mirror_exact) make_mirror_exact(out.cloth, std::move(t.mirror));
    } else {
        const TShirtBuild t = build_tshirt(s.tshirt);
        const GarmentAssembly& a = t.assembly;
        const float mass = s.tshirt.total_mass / static_cast<float>(a.particle_count());
        std::array<SpringMaterial, spring_kind_count> material{};
        const float ks[4] = {s.stiffness, s.stiffness * s.shear_ratio, s.stiffness * s.bend_ratio, s.seam_stiffness};
        for (int kind = 0; kind < 4; ++kind)
            material[kind] = {ks[kind], s.damping_ratio * 2.0f * std::sqrt(ks[kind] * mass * 0.5f)};
        out.cloth = cook_cloth(a.inverse_masses(), a.edges, material);
        out.cloth.triangles = a.triangles;
        if (s.tshirt.mirror_exact) make_mirror_exact(out.cloth, t.mirror);
        out.initial = a.initial_state();
    }
    out.params = s.physics;
    if (s.body) {
        const std::vector<Collider> body = default_body();
        out.params.colliders.insert(out.params.colliders.end(), body.begin(), body.end());
    }
    // The colliders into the cloth's frame (positions relative to Cloth::origin, the cloth's centre).
    const std::array<double, 3>& origin = out.cloth.origin;
    for (Collider& c : out.params.colliders)
        c = translated(c, {-origin[0], -origin[1], -origin[2]});
    // The implicit solver's default step is a frame (any length is stable); the explicit one's 0.9 x the bound.
    out.params.dt = s.dt                                     ? *s.dt
                    : out.params.solver == Solver::implicit ? implicit_default_dt
                                                            : static_cast<float>(default_dt(out.cloth, out.params));
    if (s.state) apply_state(*s.state, out);
    return out;
}
} // namespace

BuiltScene build_scene(const SceneSpec& s) {
    // Every error names the scene: the build's own checks (the fabric's constants, a saved state's size) do not know
    // the file (the fuzzer found "fabric.shear = 40 N/m is too large ..." without it).
    const std::string name = s.source.empty() ? std::string("scene") : s.source;
    try {
        return build_scene_body(s);
    } catch (const InvalidInput& e) {
        const std::string message = e.what();
        if (message.compare(0, name.size() + 2, name + ": ") == 0) throw;
        throw InvalidInput(name + ": " + message);
    }
}

} // namespace drape
