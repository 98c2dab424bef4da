// drape_textile cusick: the Cusick drape test (ISO 9073-9 / BS 5058 geometry): a 30 cm specimen centred on an 18 cm
// disc, dropped flat from just above it and settled; drape coefficient DC = (shadow - disc) / (specimen - disc) from
// the top-view raster of the settled triangles, folds from the radial profile of the shadow's outline.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "drape/scene_hang.hpp"
#include "drape/stability.hpp"
#include "drape_measure.hpp"
#include "harness.hpp"
#include "textile_commands.hpp"

namespace drape::textile {

namespace {

constexpr double pi = 3.14159265358979323846;
constexpr double disc_radius = 0.09, specimen_side = 0.30;

struct CusickResult {
    std::uint32_t n = 0;
    std::size_t particles = 0;
    double specimen_area = 0.0, shadow = 0.0, dc = 0.0;
    int folds = 0;
    double r_min = 0.0, r_max = 0.0; ///< m, radial profile
    SettleStats settle;
    TopView view;
};

/// The square specimen (side 30 cm; a grid cloth cannot be cut to a circle), centred on the disc.
CusickResult run_cusick(const Fabric& fabric, double spacing, double drag, double max_time) {
    CusickResult r;
    HangParams hp;
    hp.model = MaterialModel::fabric;
    hp.fabric = fabric;
    hp.n = static_cast<std::uint32_t>(std::lround(specimen_side / spacing)) + 1;
    hp.size = static_cast<float>(specimen_side);
    hp.pins = GridPins::none;
    hp.plane = GridPlane::horizontal;
    const ColliderSurface surface{0.001f, 0.6f};
    hp.centre = {0.0f, surface.thickness + 0.002f, 0.0f};
    r.n = hp.n;
    SceneBuild scene = build_hang_scene(hp);
    r.particles = scene.cloth.particle_count;
    r.specimen_area = specimen_side * specimen_side;
    SimulationParams sp;
    sp.air_drag = static_cast<float>(drag);
    const std::array<double, 3> back{-double(hp.centre[0]), -double(hp.centre[1]), -double(hp.centre[2])};
    sp.colliders.push_back(translated(make_disc({0.0f, 0.0f, 0.0f}, float(disc_radius), 0.02f, surface), back));
    sp.colliders.push_back(translated(make_ground(-0.5f, surface), back));
    sp.dt = static_cast<float>(default_dt(scene.cloth, sp));
    std::vector<std::uint32_t> triangles = scene.cloth.triangles;
    Simulation sim(std::move(scene.cloth), scene.initial, sp);
    // Settled: the fastest particle slower than 1 mm/s, or the cloth's mean height still to 0.1 um per 20 ms.
    const auto mean_height = [](const Simulation& s) {
        double y = 0.0;
        for (float v : s.y()) y += v;
        return y / double(s.y().size());
    };
    r.settle = settle(sim, max_time, 1e-3, 0.02, 5, mean_height, 1e-7);
    r.view = rasterise_top(sim.x(), sim.y(), sim.z(), triangles, 0.22, 0.0005);
    r.shadow = r.view.area();
    const double disc = pi * disc_radius * disc_radius;
    r.dc = (r.shadow - disc) / (r.specimen_area - disc);
    const std::vector<double> prof = radial_profile(r.view, 360);
    r.folds = fold_count(prof);
    r.r_min = *std::min_element(prof.begin(), prof.end());
    r.r_max = *std::max_element(prof.begin(), prof.end());
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
    const double drag = 2.0, max_time = 6.0;
    std::printf("Cusick drape test: square specimen %.0f cm (grid cloth), disc radius %.0f mm (collision margin 1 mm, "
                "friction 0.6), dropped from 3 mm above, air drag %.1f 1/s, settled (max speed < 1 mm/s, or the mean height still to 0.1 um per 20 ms, at 5 checks in a row; else 6 s); shadow "
                "rasterised at 0.5 mm; DC = (shadow - disc) / (specimen - disc)\n\n",
                specimen_side * 100.0, disc_radius * 1e3, drag);
    std::printf("| fabric | h (mm) | N | DC | folds | r min (mm) | r max (mm) | sim s | steps | wall s |\n");
    std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (const std::string& name : fabrics)
        for (double h : spacings) {
            const CusickResult r = run_cusick(textile_fabric(name), h, drag, max_time);
            std::printf("| %s | %.1f | %u | %.3f | %d | %.1f | %.1f | %.2f%s | %zu | %.1f |\n", name.c_str(), h * 1e3,
                        r.n, r.dc, r.folds, r.r_min * 1e3, r.r_max * 1e3, r.settle.sim_time,
                        r.settle.settled ? "" : " (not settled)", r.settle.steps, r.settle.wall);
            std::fflush(stdout);
            if (!opt.png_dir.empty() && h == spacings.back()) {
                const std::string path = opt.png_dir + "/cusick_" + name + ".png";
                if (!write_top_view_png(r.view, path, disc_radius, 0.15))
                    std::fprintf(stderr, "drape_textile: cannot write %s\n", path.c_str());
                else
                    std::printf("\n(wrote %s)\n\n", path.c_str());
            }
        }
    return 0;
}

} // namespace drape::textile
