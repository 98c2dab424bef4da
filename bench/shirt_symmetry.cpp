// The sewn T-shirt's seams and symmetry over time (the figures of docs/garments.md "Measured"): the built-in tshirt
// scene, stepped for a while, with its longest seam, its largest distance from its own mirror image (and where), the
// particles inside the body and whether the state is finite, twelve times over the run.
//   drape_shirt [field=value ...]: cells_per_metre= (resolution, 10..1000), strain_limit= (ratio, 0 = off),
//   seam_rest= (seam rest length over the spacing), sewing_speed= (m/s), seconds= (run length, default 3),
//   solver=implicit, mirror_exact=0 (TShirtParams::mirror_exact, on by default), self_collision= (thickness in m, 0 = off), early=1 (also after the first 1, 2, 3, 10, 20, 50, 100, 200 and 500 substeps),
//   every_step=1 (after every substep instead, to find where symmetry is first lost)
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "drape/garment_figures.hpp"
#include "drape/scene.hpp"
#include "drape/simulation.hpp"

namespace {

void print(const char* when, const drape::Simulation& sim, const drape::GarmentFigures& f) {
    const std::array<double, 3> o = sim.cloth().origin;
    std::printf("%s: longest seam %.4f m, mirror error %.3g m at particle %zu (%.3f %.3f %.3f), rms %.3g m, %zu beyond "
                "5 mm, inside the body %zu, finite %s, limited stretch %.3f, kinetic energy %.3g J\n",
                when, f.longest_seam, f.mirror_error, f.worst, sim.x()[f.worst] + o[0], sim.y()[f.worst] + o[1],
                sim.z()[f.worst] + o[2], f.mirror_rms, f.beyond, f.inside, f.finite ? "yes" : "no",
                double(sim.health().max_limited_stretch), sim.health().kinetic_energy);
}

} // namespace

int main(int argc, char** argv) try {
    drape::SceneSpec spec = drape::load_scene("tshirt");
    double seconds = 3.0;
    bool early = false, every_step = false;
    for (int k = 1; k < argc; ++k) {
        const std::string a = argv[k];
        const auto eq = a.find('=');
        if (eq == std::string::npos) throw std::runtime_error("expected field=value: " + a);
        const std::string key = a.substr(0, eq), value = a.substr(eq + 1);
        // A number for the numeric fields, the whole value (std::stof alone takes "7x" as 7 and names no field).
        const auto number = [&] {
            std::size_t used = 0;
            float v = 0.0f;
            try {
                v = std::stof(value, &used);
            } catch (const std::exception&) {
                used = 0;
            }
            if (used == 0 || used != value.size() || !std::isfinite(v))
                throw std::runtime_error(key + "=" + value + " is not a number");
            return v;
        };
        if (key == "cells_per_metre") spec.tshirt.cells_per_metre = number();
        else if (key == "strain_limit") spec.physics.strain_limit.ratio = number();
        else if (key == "seam_rest") spec.tshirt.seam_rest_ratio = number();
        else if (key == "sewing_speed") spec.physics.sewing_speed = number();
        else if (key == "seconds") seconds = number();
        else if (key == "solver" && value == "implicit") spec.physics.solver = drape::Solver::implicit;
        else if (key == "early") early = value != "0";
        else if (key == "every_step") every_step = value != "0";
        else if (key == "mirror_exact") spec.tshirt.mirror_exact = value != "0";
        else if (key == "self_collision") spec.physics.self_collision.thickness = number();
        else throw std::runtime_error("unknown field " + a);
    }
    if (!(seconds > 0.0 && seconds <= 1000.0)) throw std::runtime_error("seconds must be in (0, 1000]");
    const std::vector<std::uint32_t> mirror = drape::tshirt_mirror_map(spec.tshirt);
    drape::BuiltScene b = drape::build_scene(spec);
    drape::Simulation sim(std::move(b.cloth), b.initial, b.params);
    std::printf("tshirt: %.0f cells/m, %zu particles, %s solver, dt %g s, strain limit %g\n",
                double(spec.tshirt.cells_per_metre), sim.cloth().particle_count,
                drape::solver_name(sim.params().solver), double(sim.params().dt),
                double(sim.params().strain_limit.ratio));
    print("t = 0", sim, drape::garment_figures(sim, mirror));
    if (early)
        for (std::size_t n : {1, 1, 1, 7, 10, 30, 50, 100, 300}) {
            sim.step(n);
            const std::string when = "substep " + std::to_string(sim.steps_done());
            print(when.c_str(), sim, drape::garment_figures(sim, mirror));
        }
    if (every_step) { // after each substep (each implicit step) until `seconds`: where symmetry is first lost
        const auto steps = static_cast<std::size_t>(seconds / sim.params().dt + 0.5);
        for (std::size_t k = 0; k < steps; ++k) {
            sim.step(1);
            const std::string when = "substep " + std::to_string(sim.steps_done());
            print(when.c_str(), sim, drape::garment_figures(sim, mirror));
        }
        return 0;
    }
    const auto per = static_cast<std::size_t>(seconds / 12.0 / sim.params().dt + 0.5);
    for (int k = 1; k <= 12; ++k) {
        sim.step(per > 0 ? per : 1);
        char when[64];
        std::snprintf(when, sizeof when, "t = %.3f s", sim.time());
        print(when, sim, drape::garment_figures(sim, mirror));
    }
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "drape_shirt: %s\n", e.what());
    return 2;
}
