// Runs a triangle-mesh scene (outline, mesh or tshirt) with the fabric material model and prints its health
// every 0.1 s: the check of docs/fabric.md "Triangle meshes" (healthy, finite, the largest membrane strain).
//   drape_fabric_mesh_run SCENE [seconds] [preset-like fields: density=kg/m2 stretch_u= stretch_v= shear=
//   bend_u= bend_v= damping=; strain_limit= (ratio, 0 = off); cells_per_metre= (tshirt)]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>

#include "drape/scene.hpp"
#include "drape/simulation.hpp"

int main(int argc, char** argv) try {
    if (argc < 2) {
        std::fprintf(stderr, "usage: %s SCENE [seconds] [field=value ...]\n", argv[0]);
        return 2;
    }
    drape::SceneSpec spec = drape::load_scene(argv[1]);
    const double seconds = argc > 2 ? std::atof(argv[2]) : 1.0;
    spec.model = drape::MaterialModel::fabric;
    drape::Fabric& f = spec.fabric;
    for (int k = 3; k < argc; ++k) {
        const std::string a = argv[k];
        const auto eq = a.find('=');
        if (eq == std::string::npos) throw std::runtime_error("expected field=value: " + a);
        const std::string key = a.substr(0, eq);
        const float v = std::stof(a.substr(eq + 1));
        if (key == "density")
            f.density = v;
        else if (key == "stretch_u")
            f.stretch_u = v;
        else if (key == "stretch_v")
            f.stretch_v = v;
        else if (key == "shear")
            f.shear = v;
        else if (key == "bend_u")
            f.bend_u = v;
        else if (key == "bend_v")
            f.bend_v = v;
        else if (key == "damping")
            f.damping = v;
        else if (key == "cells_per_metre") spec.tshirt.cells_per_metre = v; // tshirt resolution
        else if (key == "strain_limit")
            spec.physics.strain_limit.ratio = v; // 0 = off
        else
            throw std::runtime_error("unknown field " + key);
    }
    for (const std::string& w : spec.warnings)
        std::printf("warning: %s\n", w.c_str());
    drape::BuiltScene b = drape::build_scene(spec);
    std::printf(
        "%s: fabric density %.3f kg/m^2, stretch %.0f/%.0f N/m, shear %.1f N/m, bend %.2g/%.2g N*m, damping "
        "%.3g s\n%zu particles, %zu springs, dt %.3g s\n",
        spec.name.c_str(), f.density, f.stretch_u, f.stretch_v, f.shear, f.bend_u, f.bend_v, f.damping,
        b.cloth.particle_count, b.cloth.spring_count(), double(b.params.dt));
    drape::Simulation sim(std::move(b.cloth), b.initial, b.params);
    const auto per = static_cast<std::size_t>(0.1 / sim.params().dt + 0.5);
    float worst = 0.0f;
    for (double t = 0.0; t < seconds - 1e-9; t += 0.1) {
        sim.step(per);
        const drape::Health h = sim.health();
        worst = std::max(worst, h.max_structural_strain);
        std::printf(
            "t = %.2f s: max strain %.4f, kinetic energy %.3g J, max speed %.3g m/s, finite %d, healthy %d\n",
            sim.time(), h.max_structural_strain, h.kinetic_energy, h.max_speed, int(h.finite),
            int(h.monitor.healthy));
    }
    std::printf("largest strain seen at the 0.1 s checks: %.4f\n", worst);
    // Where the largest strain is now: the spring, its kind and stiffness.
    const drape::Cloth& c = sim.cloth();
    std::size_t at = 0;
    double most = -1.0;
    for (std::size_t e = 0; e < c.edges.size(); ++e) {
        const drape::Edge& s = c.edges[e];
        const double dx = sim.x()[s.b] - sim.x()[s.a], dy = sim.y()[s.b] - sim.y()[s.a],
                     dz = sim.z()[s.b] - sim.z()[s.a];
        const double strain = std::sqrt(dx * dx + dy * dy + dz * dz) / s.rest - 1.0;
        if (s.kind == drape::SpringKind::structural && strain > most) most = strain, at = e;
    }
    if (most >= 0.0) {
        const drape::Edge& s = c.edges[at];
        std::printf("now: most strained structural spring %u-%u (rest %.4g m, k %.4g N/m): strain %.4f\n",
                    s.a, s.b, double(s.rest), double(c.material[std::size_t(s.kind)].stiffness * s.scale),
                    most);
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
}
