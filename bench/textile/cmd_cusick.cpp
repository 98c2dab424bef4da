// drape_textile cusick: the Cusick drape test (ISO 9073-9 / BS 5058 geometry): a 30 cm specimen centred on an 18 cm
// disc, dropped flat from just above it and settled; drape coefficient DC = (shadow - disc) / (specimen - disc) from
// the top-view raster of the settled triangles, folds from the radial profile of the shadow's outline. The specimen
// is the standard's 30 cm circle (an outline cloth through build_scene, the triangle-mesh fabric model), or with
// --square a 30 cm square grid cloth (the grid fabric model).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "drape/scene.hpp"
#include "drape/scene_hang.hpp"
#include "drape/stability.hpp"
#include "drape/triangle_fabric.hpp"
#include "drape_measure.hpp"
#include "harness.hpp"
#include "textile_commands.hpp"

namespace drape::textile {

namespace {

constexpr double pi = 3.14159265358979323846;
constexpr double disc_radius = 0.09, specimen_side = 0.30, specimen_radius = 0.15;
constexpr double drop_height = 0.002; ///< m above the disc's collision margin

/// A specimen's energies in one configuration (J): the hinge bending energy and the part of it not along each
/// hinge's current normal (the quadratic model's q_e also sees non-affine in-plane motion); the membrane springs'
/// energy along u or v and on the other edges (diagonals, cut edges), each split by the sign of the strain; m g y
/// over the free particles (g = 9.81 m/s^2, y in the cloth's frame).
struct Energies {
    double bending = 0.0, in_plane = 0.0;
    double membrane[2][2] = {{0.0, 0.0}, {0.0, 0.0}}; ///< [along u or v, other edges][tension, compression]
    double gravity = 0.0;
    double membrane_total() const { return membrane[0][0] + membrane[0][1] + membrane[1][0] + membrane[1][1]; }
};

struct CusickResult {
    std::uint32_t n = 0;
    std::size_t particles = 0;
    double specimen_area = 0.0, shadow = 0.0, dc = 0.0;
    int folds = 0;
    double r_min = 0.0, r_max = 0.0; ///< m, radial profile
    SettleStats settle;
    TopView view;
    Energies energies; ///< of the settled specimen, with --energies
};

/// The preset `name` with the command line's diagnostic overrides (--shear, --stretch-scale, then each --set in
/// order), checked by validate_fabric.
Fabric overridden_fabric(const std::string& name, const Options& opt) {
    Fabric fabric = textile_fabric(name);
    if (opt.shear > 0.0) fabric.shear = static_cast<float>(opt.shear);
    fabric.stretch_u = static_cast<float>(fabric.stretch_u * opt.stretch_scale);
    fabric.stretch_v = static_cast<float>(fabric.stretch_v * opt.stretch_scale);
    for (const auto& [key, value] : opt.set) {
        float* field = key == "density"     ? &fabric.density
                       : key == "stretch_u" ? &fabric.stretch_u
                       : key == "stretch_v" ? &fabric.stretch_v
                       : key == "shear"     ? &fabric.shear
                       : key == "bend_u"    ? &fabric.bend_u
                       : key == "bend_v"    ? &fabric.bend_v
                                            : &fabric.damping;
        *field = static_cast<float>(value);
    }
    validate_fabric(fabric, "drape_textile cusick " + name + " with --shear, --stretch-scale or --set (in SI units)");
    return fabric;
}

/// The meshes of the ensemble this run measures: all `samples`, or with --sample only that one.
int first_sample(const Options& opt) { return opt.sample >= 0 ? opt.sample : 0; }
int end_sample(const Options& opt) { return opt.sample >= 0 ? opt.sample + 1 : opt.samples; }

/// How a specimen falls and settles: air drag (1/s), the settling time limit (s), and whether to print its energies.
struct Drop {
    double drag = 2.0, max_time = 6.0;
    bool energies = false;
    /// Clamped between two discs as the standard's tester holds it: every particle within the disc's radius of its
    /// axis pinned where it starts (3 mm above the disc); otherwise the specimen rests on the disc by friction.
    bool clamp = false;
    /// A diagnostic: the hinges whose edge's middle lies within 2 cm past the disc's rim (flat) weigh this much more.
    double rim_bend = 1.0;
};

Energies energies_of(const Cloth& c, std::span<const float> X, std::span<const float> Y, std::span<const float> Z) {
    Energies out;
    for (const BendElement& e : c.bending.elements) {
        double q[3] = {0.0, 0.0, 0.0}, p[4][3];
        for (int k = 0; k < 4; ++k) {
            p[k][0] = X[e.v[k]], p[k][1] = Y[e.v[k]], p[k][2] = Z[e.v[k]];
            for (int d = 0; d < 3; ++d) q[d] += double(e.c[k]) * p[k][d];
        }
        const auto cross = [](const double* a, const double* b, double* o) {
            o[0] = a[1] * b[2] - a[2] * b[1], o[1] = a[2] * b[0] - a[0] * b[2], o[2] = a[0] * b[1] - a[1] * b[0];
        };
        double e0[3], e1[3], e2[3], n0[3], n1[3], n[3];
        for (int d = 0; d < 3; ++d) e0[d] = p[1][d] - p[0][d], e1[d] = p[2][d] - p[0][d], e2[d] = p[3][d] - p[0][d];
        cross(e0, e1, n0);
        cross(e0, e2, n1); // the opposite vertices lie on opposite sides: n1 points against n0 when flat
        const double l0 = std::sqrt(n0[0] * n0[0] + n0[1] * n0[1] + n0[2] * n0[2]),
                     l1 = std::sqrt(n1[0] * n1[0] + n1[1] * n1[1] + n1[2] * n1[2]);
        for (int d = 0; d < 3; ++d) n[d] = n0[d] / l0 - n1[d] / l1;
        const double ln = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        const double qq = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
        const double qn = ln > 0.0 ? (q[0] * n[0] + q[1] * n[1] + q[2] * n[2]) / ln : 0.0;
        out.bending += 0.5 * e.weight * qq;
        out.in_plane += 0.5 * e.weight * (qq - qn * qn);
    }
    for (const Edge& e : c.edges) {
        if (e.kind != SpringKind::structural && e.kind != SpringKind::shear) continue;
        const double dx = X[e.b] - X[e.a], dy = Y[e.b] - Y[e.a], dz = Z[e.b] - Z[e.a];
        const double stretch = std::sqrt(dx * dx + dy * dy + dz * dz) - e.rest;
        const double k = double(c.material[static_cast<std::size_t>(e.kind)].stiffness) * e.scale;
        out.membrane[e.kind == SpringKind::shear ? 1 : 0][stretch < 0.0 ? 1 : 0] += 0.5 * k * stretch * stretch;
    }
    for (std::size_t i = 0; i < X.size(); ++i) {
        const float inv = c.free_inv_mass.empty() ? c.inv_mass[i] : c.free_inv_mass[i];
        if (inv > 0.0f) out.gravity += 9.81 * Y[i] / inv;
    }
    return out;
}

/// Where on the flat specimen an energy sits: the hinge bending and membrane energies of `energies_of` summed over
/// rings of the flat circle (a hinge by the middle of its edge, a spring by its middle), bounded by `ring_edges` (m).
inline constexpr std::array<double, 6> ring_edges{0.09, 0.11, 0.13, 0.14, 0.145, 0.151};
struct RingEnergies {
    std::array<double, 5> bending{}, membrane{};
};
RingEnergies ring_energies(const Cloth& c, std::span<const float> fx, std::span<const float> fz,
                           std::span<const float> X, std::span<const float> Y, std::span<const float> Z) {
    RingEnergies out;
    const auto ring = [](double r) {
        for (std::size_t k = 0; k + 1 < ring_edges.size(); ++k)
            if (r >= ring_edges[k] && r < ring_edges[k + 1]) return int(k);
        return -1;
    };
    for (const BendElement& e : c.bending.elements) {
        const int k = ring(std::hypot(0.5 * (double(fx[e.v[0]]) + fx[e.v[1]]), 0.5 * (double(fz[e.v[0]]) + fz[e.v[1]])));
        if (k < 0) continue;
        double q[3] = {0.0, 0.0, 0.0};
        for (int j = 0; j < 4; ++j)
            q[0] += double(e.c[j]) * X[e.v[j]], q[1] += double(e.c[j]) * Y[e.v[j]], q[2] += double(e.c[j]) * Z[e.v[j]];
        out.bending[k] += 0.5 * e.weight * (q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    }
    for (const Edge& e : c.edges) {
        if (e.kind != SpringKind::structural && e.kind != SpringKind::shear) continue;
        const int k = ring(std::hypot(0.5 * (double(fx[e.a]) + fx[e.b]), 0.5 * (double(fz[e.a]) + fz[e.b])));
        if (k < 0) continue;
        const double dx = X[e.b] - X[e.a], dy = Y[e.b] - Y[e.a], dz = Z[e.b] - Z[e.a];
        const double stretch = std::sqrt(dx * dx + dy * dy + dz * dz) - e.rest;
        out.membrane[k] += 0.5 * double(c.material[static_cast<std::size_t>(e.kind)].stiffness) * e.scale * stretch * stretch;
    }
    return out;
}

/// --energies: a settled specimen's energies as a row of the table printed after the drops.
std::string energies_row(const std::string& fabric, double h, int sample, const Energies& e) {
    char row[400];
    std::snprintf(row, sizeof row, "| %s | %.1f | %d | %.4g | %.2g | %.3g | %.3g | %.3g | %.3g | %.5g |\n",
                  fabric.c_str(), h * 1e3, sample, e.bending, e.in_plane, e.membrane[0][0], e.membrane[0][1],
                  e.membrane[1][0], e.membrane[1][1], e.gravity);
    return row;
}

/// Settles a built specimen on the disc and measures it. `sp` holds the colliders in the cloth's frame and dt.
void settle_and_measure(Cloth cloth, const InitialState& initial, const SimulationParams& sp, const Drop& drop,
                        CusickResult& r) {
    r.particles = cloth.particle_count;
    std::vector<std::uint32_t> triangles = cloth.triangles;
    const std::array<double, 3> origin = cloth.origin;
    if (drop.clamp)
        for (std::size_t i = 0; i < cloth.particle_count; ++i)
            if (std::hypot(double(initial.x[i]) + origin[0], double(initial.z[i]) + origin[2]) <= disc_radius)
                cloth.inv_mass[i] = 0.0f;
    SimulationParams params = sp;
    if (drop.rim_bend != 1.0) {
        std::vector<BendElement> elements = cloth.bending.elements;
        for (BendElement& e : elements) {
            const double r = std::hypot(0.5 * (double(initial.x[e.v[0]]) + initial.x[e.v[1]]) + origin[0],
                                        0.5 * (double(initial.z[e.v[0]]) + initial.z[e.v[1]]) + origin[2]);
            if (r >= disc_radius && r < disc_radius + 0.02) e.weight = static_cast<float>(e.weight * drop.rim_bend);
        }
        set_bending(cloth, std::move(elements), cloth.bending.damping);
        params.dt = static_cast<float>(default_dt(cloth, params));
    }
    Simulation sim(std::move(cloth), initial, params);
    // Settled: the fastest particle slower than 1 mm/s, or the cloth's mean height still to 0.1 um per 20 ms.
    const auto mean_height = [](const Simulation& s) {
        double y = 0.0;
        for (float v : s.y()) y += v;
        return y / double(s.y().size());
    };
    r.settle = settle(sim, drop.max_time, 1e-3, 0.02, 5, mean_height, 1e-7);
    if (drop.energies) r.energies = energies_of(sim.cloth(), sim.x(), sim.y(), sim.z());
    // The raster is centred on the disc axis: positions back into the world frame (x, z only; y is shading).
    std::vector<float> x(sim.x().begin(), sim.x().end()), z(sim.z().begin(), sim.z().end());
    for (float& v : x) v = static_cast<float>(double(v) + origin[0]);
    for (float& v : z) v = static_cast<float>(double(v) + origin[2]);
    r.view = rasterise_top(x, sim.y(), z, triangles, 0.22, 0.0005);
    r.shadow = r.view.area();
    const double disc = pi * disc_radius * disc_radius;
    r.dc = (r.shadow - disc) / (r.specimen_area - disc);
    const std::vector<double> prof = radial_profile(r.view, 360);
    r.folds = fold_count(prof);
    r.r_min = *std::min_element(prof.begin(), prof.end());
    r.r_max = *std::max_element(prof.begin(), prof.end());
}

/// The disc and the ground, world frame (disc top at y = 0, axis x = z = 0).
std::vector<Collider> cusick_colliders(const ColliderSurface& surface) {
    return {make_disc({0.0f, 0.0f, 0.0f}, float(disc_radius), 0.02f, surface), make_ground(-0.5f, surface)};
}

/// The square specimen (side 30 cm, a grid cloth), centred on the disc.
CusickResult run_cusick_square(const Fabric& fabric, double spacing, const Drop& drop) {
    CusickResult r;
    HangParams hp;
    hp.model = MaterialModel::fabric;
    hp.fabric = fabric;
    hp.n = static_cast<std::uint32_t>(std::lround(specimen_side / spacing)) + 1;
    hp.size = static_cast<float>(specimen_side);
    hp.pins = GridPins::none;
    hp.plane = GridPlane::horizontal;
    const ColliderSurface surface{0.001f, 0.6f};
    hp.centre = {0.0f, surface.thickness + float(drop_height), 0.0f};
    r.n = hp.n;
    SceneBuild scene = build_hang_scene(hp);
    r.specimen_area = specimen_side * specimen_side;
    SimulationParams sp;
    sp.air_drag = static_cast<float>(drop.drag);
    const std::array<double, 3> back{-double(hp.centre[0]), -double(hp.centre[1]), -double(hp.centre[2])};
    for (const Collider& c : cusick_colliders(surface)) sp.colliders.push_back(translated(c, back));
    sp.dt = static_cast<float>(default_dt(scene.cloth, sp));
    settle_and_measure(std::move(scene.cloth), scene.initial, sp, drop, r);
    return r;
}

/// A scene of the fabric model named for the test; the caller fills in the cloth.
SceneSpec cusick_spec(ClothType cloth, const Fabric& fabric) {
    SceneSpec spec;
    spec.name = "cusick";
    spec.source = "drape_textile cusick";
    spec.cloth = cloth;
    spec.model = MaterialModel::fabric;
    spec.fabric = fabric;
    return spec;
}

/// Vertices of the circular specimen's polygon at spacing h: about one per h of perimeter (the outline is sampled
/// at spacing <= h anyway, so more vertices would only add short edges), at least 32.
std::uint32_t circle_vertices(double spacing) {
    return std::max<std::uint32_t>(32, static_cast<std::uint32_t>(std::ceil(2.0 * pi * specimen_radius / spacing)));
}

/// The standard's circular specimen (radius 15 cm) as an outline cloth (a regular polygon, circle_vertices(h)
/// vertices on the circle), horizontal, built by build_scene with the fabric model, centred on the disc. Its
/// specimen area is the polygon's (what the cloth covers flat; within 0.3 % of pi r^2 at 20 mm). With `square`, the
/// 30 cm square as an outline (4 vertices): the square grid specimen's shape with the circle's mesh model.
/// `phase` in [0, 1) turns the circle's polygon by that fraction of the angle between its vertices (the same circle,
/// another mesh of it: the u-v fill lattice and the outline samples fall differently); 0 for the square.
BuiltScene build_outline_specimen(const Fabric& fabric, double spacing, const Drop& drop, bool square, double phase,
                                  CusickResult& r) {
    SceneSpec spec = cusick_spec(ClothType::outline, fabric);
    OutlineClothSpec& o = spec.outline;
    const std::uint32_t nv = square ? 4 : circle_vertices(spacing);
    const double half = 0.5 * specimen_side;
    if (square)
        o.outline.outline = {{-half, -half}, {half, -half}, {half, half}, {-half, half}};
    else
        for (std::uint32_t k = 0; k < nv; ++k) {
            const double a = 2.0 * pi * (double(k) + phase) / double(nv);
            o.outline.outline.push_back({specimen_radius * std::cos(a), specimen_radius * std::sin(a)});
        }
    o.spacing = static_cast<float>(spacing);
    o.plane = GridPlane::horizontal;
    const ColliderSurface surface{0.001f, 0.6f};
    o.centre = {0.0f, surface.thickness + float(drop_height), 0.0f};
    spec.physics.air_drag = static_cast<float>(drop.drag);
    spec.physics.colliders = cusick_colliders(surface);
    BuiltScene scene = build_scene(spec); // colliders into the cloth's frame, dt = 0.9 x the stability bound
    r.n = nv;
    r.specimen_area = square ? specimen_side * specimen_side
                             : 0.5 * double(nv) * specimen_radius * specimen_radius * std::sin(2.0 * pi / double(nv));
    return scene;
}

CusickResult run_cusick_outline(const Fabric& fabric, double spacing, const Drop& drop, bool square, double phase) {
    CusickResult r;
    BuiltScene scene = build_outline_specimen(fabric, spacing, drop, square, phase, r);
    settle_and_measure(std::move(scene.cloth), scene.initial, scene.params, drop, r);
    return r;
}

/// --skirt N: one fixed, smooth skirt with N folds, the same surface on every mesh of the circle (no simulation): flat
/// within the disc's radius; beyond it, at distance rho from the rim along the flat cloth, the cloth turns down by
/// phi(rho) = 1.2 (1 - exp(-rho / L)) rad (L = 3 cm) and waves up and down by a (rho / L)^2 / (1 + (rho / L)^2)
/// cos(N theta) (a = 1.5 cm). Its energies on meshes of spacing h say whether the discrete model itself (not the
/// drop) makes a coarse skirt cheaper: for a smooth surface they should converge as h falls. `smooth`: phi(rho) =
/// 1.2 (1 - exp(-(rho / L)^2)) instead, so the curvature starts from 0 at the rim instead of jumping to 40 1/m.
void skirt_shape(std::span<float> x, std::span<float> y, std::span<float> z, int folds, bool smooth) {
    constexpr double length = 0.03, amplitude = 0.015, turn = 1.2;
    for (std::size_t i = 0; i < x.size(); ++i) {
        const double r = std::hypot(double(x[i]), double(z[i])), theta = std::atan2(double(z[i]), double(x[i]));
        const double rho = std::max(0.0, r - disc_radius);
        if (rho == 0.0) continue;
        // s = int_0^rho cos phi, t = int_0^rho sin phi (midpoint rule, 0.05 mm steps)
        const int steps = std::max(1, static_cast<int>(std::ceil(rho / 5e-5)));
        double s = 0.0, t = 0.0;
        for (int k = 0; k < steps; ++k) {
            const double w = (k + 0.5) * rho / steps / length;
            const double phi = turn * (1.0 - std::exp(smooth ? -w * w : -w));
            s += std::cos(phi) * rho / steps;
            t += std::sin(phi) * rho / steps;
        }
        const double q = (rho / length) * (rho / length);
        const double radius = disc_radius + s;
        x[i] = static_cast<float>(radius * std::cos(theta));
        z[i] = static_cast<float>(radius * std::sin(theta));
        y[i] = static_cast<float>(-t + amplitude * q / (1.0 + q) * std::cos(folds * theta));
    }
}

/// The standard's circular specimen as a mask cloth: the cells (row, column) of a u-v grid of spacing h whose centre
/// lies within the 15 cm radius, horizontal, centred on the disc; triangles, springs and bending as any mask panel
/// (the triangle-mesh fabric model, weave-aligned). Its edge is a staircase of grid-aligned triangles instead of the
/// outline cloth's band of cut triangles; its specimen area is its triangles' (within O(h) of pi r^2). `phase` in
/// [0, 1) moves the circle's centre off the cell lattice by (phase, frac(3 phase)) cells (another mesh of the same
/// circle; the specimen stays centred on the disc).
CusickResult run_cusick_mask_circle(const Fabric& fabric, double spacing, const Drop& drop, double phase) {
    CusickResult r;
    SceneSpec spec = cusick_spec(ClothType::mask, fabric);
    const auto cells = static_cast<std::uint32_t>(std::floor(2.0 * specimen_radius / spacing)) + 2;
    const double mid_u = 0.5 * double(cells - 2) + phase;
    const double mid_v = 0.5 * double(cells - 2) + (3.0 * phase - std::floor(3.0 * phase));
    MaskPanelSpec panel;
    panel.name = "specimen";
    panel.cell_size = static_cast<float>(spacing);
    for (std::uint32_t row = 0; row < cells; ++row) {
        std::string line(cells, '0');
        for (std::uint32_t c = 0; c < cells; ++c)
            if (std::hypot((double(c) - mid_u) * spacing, (double(row) - mid_v) * spacing) <= specimen_radius + 1e-9)
                line[c] = '1';
        panel.mask.rows.push_back(line);
    }
    const ColliderSurface surface{0.001f, 0.6f};
    // u along +x, v along -z: the panel's normal u x v points up; the circle's centre on the disc axis.
    panel.axis_u = {1.0f, 0.0f, 0.0f};
    panel.axis_v = {0.0f, 0.0f, -1.0f};
    panel.origin = {-mid_u * spacing, double(surface.thickness) + drop_height, mid_v * spacing};
    spec.masks.panels.push_back(panel);
    spec.physics.air_drag = static_cast<float>(drop.drag);
    spec.physics.colliders = cusick_colliders(surface);
    BuiltScene scene = build_scene(spec);
    r.n = cells;
    // The flat specimen's area: its triangles' (lumped masses at unit density sum to it).
    r.specimen_area = 0.0;
    for (double a : lumped_masses(scene.initial.x, scene.initial.y, scene.initial.z, scene.cloth.triangles, 1.0))
        r.specimen_area += a;
    settle_and_measure(std::move(scene.cloth), scene.initial, scene.params, drop, r);
    return r;
}

} // namespace

int cmd_cusick(const Options& opt) {
    std::vector<std::string> fabrics = opt.fabrics;
    if (fabrics.empty())
        for (const FabricPreset& p : fabric_presets()) fabrics.push_back(p.fabric.name);
    std::vector<double> spacings = opt.quick ? std::vector<double>{0.02, 0.01} : std::vector<double>{0.02, 0.01, 0.005};
    if (opt.fine) spacings.push_back(0.0025);
    if (!opt.spacings.empty()) spacings = opt.spacings;
    const Drop drop{opt.drag > 0.0 ? opt.drag : 2.0, opt.max_time > 0.0 ? opt.max_time : 6.0, opt.energies, opt.clamp,
                    opt.rim_bend};
    const auto print_overrides = [&] {
        if (opt.shear > 0.0) std::printf("Every fabric's shear stiffness replaced by %g N/m (--shear)\n\n", opt.shear);
        if (opt.stretch_scale != 1.0)
            std::printf("Every fabric's stretch stiffness (u and v) times %g (--stretch-scale)\n\n", opt.stretch_scale);
        for (const auto& [key, value] : opt.set)
            std::printf("Every fabric's %s set to %g (--set, after --shear and --stretch-scale)\n\n", key.c_str(), value);
    };
    if (opt.skirt > 0) {
        print_overrides();
        std::printf("Energies of one fixed skirt with %d folds (--skirt%s; no simulation) on meshes of the circle; "
                    "bending and membrane energy also by ring of the flat circle, in mm from its centre\n\n",
                    opt.skirt, opt.skirt_smooth ? " --skirt-smooth" : "");
        std::printf("| fabric | h (mm) | sample | particles | bending (J) | of it in-plane | membrane (J) | m g y (J) | "
                    "bending 90-110 / 110-130 / 130-140 / 140-145 / 145-150 | membrane, same rings |\n");
        std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---|---|\n");
        for (const std::string& name : fabrics)
            for (double h : spacings)
                for (int k = first_sample(opt); k < end_sample(opt); ++k) {
                    CusickResult r;
                    const BuiltScene scene =
                        build_outline_specimen(overridden_fabric(name, opt), h, drop, false, double(k) / opt.samples, r);
                    std::vector<float> x = scene.initial.x, y = scene.initial.y, z = scene.initial.z;
                    skirt_shape(x, y, z, opt.skirt, opt.skirt_smooth);
                    const Energies e = energies_of(scene.cloth, x, y, z);
                    const RingEnergies ring = ring_energies(scene.cloth, scene.initial.x, scene.initial.z, x, y, z);
                    std::printf("| %s | %.1f | %d | %zu | %.4g | %.2g | %.4g | %.5g | %.3g / %.3g / %.3g / %.3g / %.3g | "
                                "%.3g / %.3g / %.3g / %.3g / %.3g |\n",
                                name.c_str(), h * 1e3, k, scene.cloth.particle_count, e.bending, e.in_plane,
                                e.membrane_total(), e.gravity, ring.bending[0], ring.bending[1], ring.bending[2],
                                ring.bending[3], ring.bending[4], ring.membrane[0], ring.membrane[1], ring.membrane[2],
                                ring.membrane[3], ring.membrane[4]);
                    std::fflush(stdout);
                }
        return 0;
    }
    const bool square = opt.square;
    if (square)
        std::printf("Cusick drape test: square specimen %.0f cm (grid cloth, N x N particles)", specimen_side * 100.0);
    else if (opt.mask_circle)
        std::printf("Cusick drape test: circular specimen, diameter %.0f cm, as a mask cloth (the u-v grid cells "
                    "within the circle, triangle-mesh fabric model)", specimen_radius * 200.0);
    else if (opt.square_outline)
        std::printf("Cusick drape test: square specimen %.0f cm as an outline cloth (triangle-mesh fabric model)",
                    specimen_side * 100.0);
    else
        std::printf("Cusick drape test: circular specimen, diameter %.0f cm (outline cloth: a regular polygon of "
                    "ceil(2 pi r / h) >= 32 vertices, triangle-mesh fabric model)", specimen_radius * 200.0);
    std::printf(", disc radius %.0f mm (collision margin 1 mm, friction 0.6), dropped from %.0f mm above, air drag "
                "%.1f 1/s, settled (max speed < 1 mm/s, or the mean height still to 0.1 um per 20 ms, at 5 checks in "
                "a row; else %.0f s); shadow rasterised at 0.5 mm; DC = (shadow - disc) / (specimen - disc)\n\n",
                disc_radius * 1e3, (drop_height + 0.001) * 1e3, drop.drag, drop.max_time);
    print_overrides();
    if (drop.rim_bend != 1.0)
        std::printf("The hinges within 2 cm past the disc's rim weigh %g times as much (--rim-bend)\n\n", drop.rim_bend);
    if (drop.clamp)
        std::printf("Clamped between discs (--clamp): the particles within %.0f mm of the axis pinned where they start\n\n",
                    disc_radius * 1e3);
    const int samples = opt.samples; // [1, 64], checked by main
    if (samples > 1)
        std::printf("%d meshes of each specimen (sample k: %s k / %d); the summary gives their mean DC and its "
                    "sample standard deviation\n\n",
                    samples,
                    opt.mask_circle ? "the circle's centre moved off the cell lattice by (k, frac(3 k)) cells x"
                                    : "the polygon turned by the angle between two of its vertices x",
                    samples);
    std::printf("| fabric | h (mm) |%s %s | DC | folds | r min (mm) | r max (mm) | sim s | steps | wall s |\n",
                samples > 1 ? " sample |" : "", square ? "N" : "particles");
    std::printf("|---|---:|%s---:|---:|---:|---:|---:|---:|---:|---:|\n", samples > 1 ? "---:|" : "");
    struct Summary {
        std::string fabric;
        double h = 0.0;
        std::vector<double> dc; ///< one per sample
        std::string folds;
    };
    std::vector<Summary> summary;
    std::string energy_rows; // --energies: printed after the drops, a table of its own
    for (const std::string& name : fabrics)
        for (double h : spacings) {
            const Fabric fabric = overridden_fabric(name, opt);
            Summary sum{name, h, {}, ""};
            for (int k = first_sample(opt); k < end_sample(opt); ++k) {
                const double phase = double(k) / double(samples);
                const CusickResult r =
                    square            ? run_cusick_square(fabric, h, drop)
                    : opt.mask_circle ? run_cusick_mask_circle(fabric, h, drop, phase)
                                      : run_cusick_outline(fabric, h, drop, opt.square_outline, phase);
                char sample[32] = "";
                if (samples > 1) std::snprintf(sample, sizeof sample, " %d |", k);
                std::printf("| %s | %.1f |%s %zu | %.3f | %d | %.1f | %.1f | %.2f%s | %zu | %.1f |\n", name.c_str(),
                            h * 1e3, sample, square ? std::size_t(r.n) : r.particles, r.dc, r.folds, r.r_min * 1e3,
                            r.r_max * 1e3, r.settle.sim_time, r.settle.settled ? "" : " (not settled)", r.settle.steps,
                            r.settle.wall);
                std::fflush(stdout);
                if (drop.energies) energy_rows += energies_row(name, h, k, r.energies);
                sum.dc.push_back(r.dc);
                sum.folds += (k ? " / " : "") + std::to_string(r.folds);
                if (!opt.png_dir.empty() && h == spacings.back() && k == first_sample(opt)) {
                    const std::string path = opt.png_dir + (square                ? "/cusick_"
                                                            : opt.square_outline ? "/cusick_square_outline_"
                                                            : opt.mask_circle    ? "/cusick_mask_circle_"
                                                                                 : "/cusick_circle_") +
                                             name + ".png";
                    if (!write_top_view_png(r.view, path, disc_radius, specimen_radius))
                        std::fprintf(stderr, "drape_textile: cannot write %s\n", path.c_str());
                    else
                        std::printf("\n(wrote %s)\n\n", path.c_str());
                }
            }
            summary.push_back(sum);
        }
    if (drop.energies)
        std::printf("\nEnergies of each settled specimen (J; --energies): hinge bending and the part of it not along the "
                    "hinges' normals; membrane springs along u or v and on the other edges, by sign of strain; m g y\n\n"
                    "| fabric | h (mm) | sample | bending | of it in-plane | u/v tension | u/v compression | other "
                    "tension | other compression | m g y |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n%s",
                    energy_rows.c_str());
    if (samples > 1 && opt.sample < 0) {
        std::printf("\n| fabric | h (mm) | DC mean | DC sd | DC min - max | folds |\n|---|---:|---:|---:|---|---|\n");
        for (const Summary& m : summary) {
            const double n = double(m.dc.size());
            double mean = 0.0, ss = 0.0;
            for (double d : m.dc) mean += d / n;
            for (double d : m.dc) ss += (d - mean) * (d - mean);
            const auto [lo, hi] = std::minmax_element(m.dc.begin(), m.dc.end());
            std::printf("| %s | %.1f | %.3f | %.3f | %.3f - %.3f | %s |\n", m.fabric.c_str(), m.h * 1e3, mean,
                        std::sqrt(ss / (n - 1.0)), *lo, *hi, m.folds.c_str());
        }
    }
    return 0;
}

} // namespace drape::textile
