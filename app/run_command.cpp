// `drape run`: builds a scene, steps it, prints the figures of BENCH.md "Output".
#include "run_command.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <thread>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "drape/fabric.hpp"
#include "drape/memory_estimate.hpp"
#include "materials.hpp"
#include "drape/scene.hpp"
#include "obj_export.hpp"
#include "drape/simulation.hpp"
#include "drape/stability.hpp"
#include "drape/workers.hpp"

namespace drape::app {

namespace {

/// ", Chebyshev rho R" for the text summary, with what the cloth's sweeps ran with where that differs (few sweeps,
/// colliders).
std::string chebyshev_text(const SimulationParams& sp) {
    if (sp.implicit.chebyshev_rho <= 0.0f) return "";
    const float used = chebyshev_rho_used(sp);
    std::string t = ", Chebyshev rho " + format_dt(sp.implicit.chebyshev_rho);
    if (used != sp.implicit.chebyshev_rho)
        t += used > 0.0f ? " (" + format_dt(used) + " at " + std::to_string(sp.implicit.iterations) + " sweeps)"
                         : sp.colliders.empty() ? " (off below " + std::to_string(chebyshev_min_iterations) + " sweeps)"
                                                : std::string(" (off with colliders)");
    return t;
}

using clock_type = std::chrono::steady_clock;

std::string hex64(std::uint64_t v) {
    char buf[19];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(v));
    return buf;
}

/// Progress on stderr, only when it is a terminal and the run has lasted over 2 s.
class Progress {
  public:
    Progress(std::uint64_t total, const char* unit) : total_(total), unit_(unit), tty_(isatty(STDERR_FILENO) != 0) {
        // DRAPE_PROGRESS_AFTER: seconds before the first report (default 2; tests use 0).
        if (const char* after = std::getenv("DRAPE_PROGRESS_AFTER")) delay_ = std::atof(after);
    }
    void update(std::uint64_t done) {
        if (!tty_) return;
        const double elapsed = std::chrono::duration<double>(clock_type::now() - start_).count();
        if (elapsed < delay_ || (shown_ && elapsed - last_ < 0.25)) return;
        last_ = elapsed;
        const double left = done ? elapsed * double(total_ - done) / double(done) : 0.0;
        std::fprintf(stderr, "\rdrape: %s %llu/%llu (%3.0f%%), %.1f s elapsed, ~%.1f s left   ", unit_,
                     static_cast<unsigned long long>(done), static_cast<unsigned long long>(total_),
                     100.0 * double(done) / double(total_), elapsed, left);
        shown_ = true;
    }
    /// Erases the progress line (carriage return, clear to end of line), so that what follows starts on a clean line.
    void clear() {
        if (shown_) std::fprintf(stderr, "\r\033[K");
        shown_ = false;
    }
    ~Progress() { clear(); }

  private:
    std::uint64_t total_;
    const char* unit_;
    bool tty_;
    bool shown_ = false;
    double last_ = 0.0;
    double delay_ = 2.0;
    clock_type::time_point start_ = clock_type::now();
};

} // namespace

int run_command(const RunOptions& o) {
    // Exactly this many worker threads build and step the cloth (also above the core count): a task_arena.
    Workers workers(o.threads);
    const int hardware = Workers::hardware();
    const int threads = workers.workers();

    // The scene, with the flags the user gave overriding its values.
    SceneSpec spec;
    try {
        spec = load_scene(o.scene);
    } catch (const InvalidInput& e) {
        throw InvalidInput(std::string("--scene: ") + e.what());
    }
    for (const std::string& w : spec.warnings) std::cerr << "drape run: warning: " << w << "\n";
    // --size: particles per side of a grid, cells per metre of a T-shirt or an outline (spacing 1 / size); refused
    // for a mesh or a mask cloth (set_scene_resolution, the viewer's rule too).
    if (o.size) set_scene_resolution(spec, *o.size, "--size");
    if (o.material) apply_material_flag(spec, *o.material);
    // --stiffness and --damping are the spring model's: refused (not silently dropped) for a fabric.
    for (const auto& [given, flag] : {std::pair{o.stiffness.has_value(), "--stiffness"}, {o.damping.has_value(), "--damping"}})
        if (given && spec.model == MaterialModel::fabric)
            throw InvalidInput(std::string(flag) + ": a spring-model flag, but the material is the fabric '" +
                               spec.fabric.name + "'" + (o.material ? " (--material)" : " (the scene's)") +
                               "; add --material springs for the seeds' spring model");
    if (o.stiffness) spec.stiffness = *o.stiffness;
    if (o.damping) spec.damping_ratio = *o.damping;
    if (o.export_obj && o.export_obj->empty())
        throw InvalidInput("--export-obj: an empty path; give the directory to write the frames into");
    if (o.drag) spec.physics.air_drag = *o.drag;
    apply_solver_flags(spec, {.solver = o.solver,
                              .iterations = o.iterations,
                              .tolerance = o.tolerance,
                              .integrator = o.integrator,
                              .strain_limit = o.strain_limit,
                              .fas = o.fas,
                              .single_level = o.single_level,
                              .fas_at_rest = o.fas_at_rest});
    const bool implicit = spec.physics.solver == Solver::implicit;
    if (o.wind) spec.physics.wind.enabled = true;
    if (o.aero) spec.physics.aero.enabled = true;
    if (o.wind_strength) spec.physics.wind.strength = *o.wind_strength;
    if (o.strain_passes) spec.physics.strain_limit.passes = *o.strain_passes;
    if (o.strain_every) spec.physics.strain_limit.every = *o.strain_every;
    if (o.self_collision) spec.physics.self_collision.thickness = *o.self_collision;
    if (o.self_collision_substeps) spec.physics.self_collision.substeps = *o.self_collision_substeps;
    // Flags that would change nothing in this run are refused, as the implicit solver's flags are with the explicit
    // one (an adversarial sweep found them accepted and echoed in the JSON while ignored).
    if (o.self_collision_substeps && !implicit)
        throw InvalidInput("--self-collision-substeps: a flag of the implicit solver's self-collision, but the solver "
                           "is explicit; add --solver implicit");
    if (o.self_collision_substeps && !(spec.physics.self_collision.thickness > 0.0f))
        throw InvalidInput("--self-collision-substeps: self-collision is off; turn it on with --self-collision H (or "
                           "the scene's physics.self_collision.thickness)");
    if ((o.strain_passes || o.strain_every) && !(spec.physics.strain_limit.ratio > 0.0f))
        throw InvalidInput(std::string(o.strain_passes ? "--strain-passes" : "--strain-every") +
                           ": strain limiting is off; turn it on with --strain-limit R (or the scene's "
                           "physics.strain_limit.ratio)");
    if (o.wind_strength && !spec.physics.wind.enabled)
        throw InvalidInput("--wind-strength: the wind is off; turn it on with --wind (or the scene's physics.wind)");
    if (implicit && (o.kernel != "auto" || o.staged))
        throw InvalidInput(std::string(o.staged ? "--staged" : "--kernel " + o.kernel) +
                           ": a choice of the explicit solver's spring pass, but the solver is implicit (its sweeps "
                           "solve every energy per vertex); drop it, or use --solver explicit");
    spec.physics.kernel = o.kernel == "grid" ? KernelPath::grid : o.kernel == "csr" ? KernelPath::csr : KernelPath::automatic;
    spec.physics.fused = !o.staged;
    if (o.dt) spec.dt = static_cast<float>(*o.dt);
    const std::string size_flag = o.size ? "--size " + std::to_string(*o.size) : "--scene " + o.scene;
    const std::size_t expected = scene_particle_count(spec);
    if (expected > (std::size_t{1} << 24))
        throw InvalidInput(size_flag + ": the cloth would have " + std::to_string(expected) +
                           " particles (at most 16,777,216)");
    check_scene_memory(spec, size_flag); // refused at once, with the figure, instead of failing half-way

    BuiltScene scene = workers.run([&] { return build_scene(spec); });
    SimulationParams sp = scene.params;
    const StabilityBound bound = stability_bound(scene.cloth, sp);
    const bool dt_default = !spec.dt.has_value();
    // A dt above the bound: the message names where it came from (the flag, or the scene file's field). The implicit
    // solver takes any step from 1e-4 s up to 0.1 s.
    if (!dt_default && !implicit) check_stability(scene.cloth, sp, o.dt ? std::string("--dt") : spec.source + ": physics.dt");
    if (!dt_default && implicit && !(sp.dt >= implicit_min_dt))
        throw InvalidInput((o.dt ? std::string("--dt") : spec.source + ": physics.dt") + ": " + format_dt(sp.dt) +
                           " s is below the implicit solver's shortest step, 1e-4 s (a step's motion under gravity "
                           "would be lost to the rounding of positions); use --solver explicit for steps that short");

    auto g = [](double v) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.4g", v);
        return std::string(buf);
    };
    // A default dt below the smallest a run takes: strong damping, or a near-degenerate spring (a sliver triangle, two
    // vertices almost on top of each other), sets the explicit bound. (A sweep found a 100 x 100 grid of a light
    // fabric with damping 0.1 s blamed on its mesh.)
    if (dt_default && !implicit && !(sp.dt >= 1e-9f)) {
        double shortest = std::numeric_limits<double>::max();
        for (const Edge& e : scene.cloth.edges) shortest = std::min(shortest, double(e.rest));
        // A spring far shorter than the cloth's spacing makes both its stiffness and its damping rate huge: the
        // mesh is the cause. On an even mesh, what sets the bound is named (the damping with its range).
        const double spacing = cloth_spacing(scene.cloth);
        const std::string why =
            shortest < 0.1 * spacing
                ? "its shortest spring is " + g(shortest) + " m long against a mean of " + g(spacing) +
                      " m (a near-degenerate triangle or two vertices almost on top of each other): remesh the cloth"
                : explicit_bound_cause(bound) +
                      (damping_sets_explicit_bound(bound)
                           ? " (material.damping: [0, " + g(fabric_range_damping.hi) + "] s)"
                           : std::string(" (its shortest spring is ") + g(shortest) + " m long)");
        throw InvalidInput(spec.source + ": the default dt (0.9 x the explicit stability bound " + g(bound.dt_max) +
                           " s) is " + g(sp.dt) + " s, below the smallest dt (1e-9 s): " + why +
                           "; or use --solver implicit, which takes steps of up to 0.1 s at any stiffness and damping");
    }
    std::uint64_t steps = 1000;
    if (o.steps) steps = *o.steps;
    if (o.sim_seconds) {
        const double want = std::ceil(*o.sim_seconds / double(sp.dt)); // as a double: it may be past 2^64
        if (!(want <= 1e9))
            throw InvalidInput("--sim-seconds " + g(*o.sim_seconds) + " at dt = " + g(sp.dt) + " s needs " + g(want) +
                               (implicit ? " steps" : " substeps") + " (max 1e9)");
        steps = static_cast<std::uint64_t>(want);
    }

    std::optional<Simulation> built;
    workers.run([&] { built.emplace(std::move(scene.cloth), scene.initial, sp); });
    Simulation& sim = *built;
    // --fas changes the coarse levels' solve; a cloth without coarse levels (a T-shirt, mask or OBJ mesh, the springs
    // model, a small grid) would run exactly as without it.
    for (const auto& [given, flag] : {std::pair{o.fas, "--fas"}, {o.fas_at_rest, "--fas-at-rest"}})
        if (given && sim.implicit_levels() == 1)
            throw InvalidInput(std::string(flag) + ": the coarse correction of the multilevel guess, but this cloth "
                               "has no coarse levels (only square grids of the fabric model, 10 x 10 and up, and "
                               "outline cloths of the fabric model have them); drop " + flag);
    // FAS at rest never acts where its measured faults are (implicit_step.cpp, fas_at_rest): say so, not accept it.
    if (o.fas_at_rest) {
        if (const char* why = fas_at_rest_excluded_by(sim.params()))
            throw InvalidInput(std::string("--fas-at-rest: FAS at rest never acts with colliders, self-collision, "
                                           "wind or aerodynamic wind (docs/implicit.md, \"FAS at rest\"), and this "
                                           "scene has ") + why + "; drop --fas-at-rest");
    }
    const std::string long_run =
        implicit ? std::string() : long_explicit_run_warning(bound, double(sp.dt), steps, sim.cloth().particle_count);
    for (const std::string& w : {single_level_implicit_warning(sim), self_collision_thickness_warning(sim),
                                 started_inside_warning(sim), long_run})
        if (!w.empty()) std::cerr << "drape run: warning: " << w << "\n";
    const std::size_t particles = sim.cloth().particle_count;
    std::unique_ptr<ObjExporter> exporter;
    std::size_t frames_written = 0;
    if (o.export_obj) {
        exporter = std::make_unique<ObjExporter>(sim.cloth(), *o.export_obj, o.export_overwrite);
        workers.run([&] { exporter->write(sim, frames_written++); });
    }

    std::string error, blow_up;
    Progress progress(steps, implicit ? "step" : "substep");
    const auto start = clock_type::now();
    try {
        // Chunks of ~1e7 particle-substeps (an implicit step: ~1e6 particle-steps, each many sweeps) keep progress
        // reports cheap and responsive.
        const std::uint64_t chunk =
            exporter ? o.export_every : std::max<std::uint64_t>(1, (implicit ? 1'000'000 : 10'000'000) / particles);
        workers.run([&] {
            for (std::uint64_t done = 0; done < steps;) {
                const std::uint64_t n = std::min(chunk, steps - done);
                sim.step(n);
                done += n;
                progress.update(done);
                if (done == steps) sim.check_health_now(); // "healthy" is about the end state (checks come every few steps)
                if (exporter && (done % o.export_every == 0 || done == steps)) exporter->write(sim, frames_written++);
            }
        });
    } catch (const BlowUpError& e) {
        blow_up = e.what(); // the health monitor: finite, but not healthy (exit code 4)
    } catch (const SimulationError& e) {
        error = e.what();
    }
    progress.clear();
    const double wall = std::chrono::duration<double>(clock_type::now() - start).count();
    const Health health = workers.run([&] { return sim.health(); });
    const std::uint64_t done = sim.steps_done();
    const double rate = wall > 0.0 ? double(particles) * double(done) / wall : 0.0;
    const double real_time = wall > 0.0 ? sim.time() / wall : 0.0; // simulated seconds per wall second

    nlohmann::ordered_json j;
    j["scene"] = spec.name;
    j["cloth"] = spec.cloth == ClothType::grid     ? "grid"
                 : spec.cloth == ClothType::tshirt ? "tshirt"
                 : spec.cloth == ClothType::mesh   ? "mesh"
                 : spec.cloth == ClothType::mask   ? "mask"
                                                   : "outline";
    if (spec.cloth == ClothType::grid)
        j["n"] = spec.grid.n;
    else if (spec.cloth == ClothType::tshirt) {
        j["cells_per_metre"] = spec.tshirt.cells_per_metre;
        j["mirror_exact"] = !sim.cloth().mirror.empty();
    }
    else if (spec.cloth == ClothType::outline)
        j["spacing"] = spec.outline.spacing;
    else if (spec.cloth == ClothType::mask)
        j["panels"] = spec.masks.panels.size();
    j["particles"] = particles;
    j["springs"] = sim.cloth().spring_count();
    j["threads"] = threads;
    j["hardware_threads"] = hardware;
    j["solver"] = solver_name(sp.solver);
    j["substeps"] = done; // explicit substeps or implicit steps (also "steps")
    j["steps"] = done;
    j["dt"] = sp.dt;
    j["dt_max"] = bound.dt_max; // the explicit stability bound (the implicit step may exceed it)
    j["dt_source"] = !dt_default ? (o.dt ? "--dt" : "scene: physics.dt")
                     : implicit  ? "default: a frame (1/30 s)"
                                 : "default: 0.9 x stability bound";
    j["sim_seconds"] = sim.time();
    j["real_time_factor"] = real_time;
    j["integrator"] = integrator_name(sp.integrator);
    if (implicit) {
        const ImplicitStats& st = sim.implicit_stats();
        j["implicit"] = {{"iterations", st.iterations}, // the last step's
                         {"relative_residual", st.relative_residual},
                         {"max_iterations", sp.implicit.iterations},
                         {"tolerance", sp.implicit.tolerance},
                         {"chebyshev_rho", sp.implicit.chebyshev_rho},
                         {"chebyshev_rho_used", chebyshev_rho_used(sp)}, // the cloth's own sweeps
                         {"fas", sp.implicit.fas},
                         {"fas_at_rest", sp.implicit.fas_at_rest},
                         {"fas_last_step", st.fas}, // the last step's coarse levels solved with FAS
                         // the cloth strained past 30 % with the last step's residual above 0.1 (the stderr warning)
                         {"unconverged", implicit_unconverged(sim, health.max_structural_strain)},
                         {"multilevel", sp.implicit.multilevel}, // the setting (physics.implicit.multilevel)
                         // grids this cloth has: 1 = no coarse levels (a T-shirt, mask, OBJ or springs cloth, or a grid
                         // under 10 x 10), so the setting has nothing to act on (an adversarial sweep read
                         // "multilevel": true beside "levels": 1 as a contradiction)
                         {"levels_available", sim.implicit_levels()},
                         // grids the last step solved: 1 + coarse levels; 1 also when the setting is off or contact
                         // sub-steps ran single level (self_collision.substepped)
                         {"levels", st.levels},
                         // steps whose strain limit could not hold the stretch, solved again as sub-steps
                         {"strain_substepped", sim.strain_substepped()},
                         {"method", sp.implicit.method == ImplicitMethod::jacobi ? "jacobi" : "gauss_seidel"}};
    }
    j["kernel"] = kernel_path_name(sim.kernel());
    j["fused"] = sp.fused;
    if (spec.model == MaterialModel::springs) j["stiffness"] = spec.stiffness;
    j["material"] = material_report(spec, sim.cloth());
    j["wind"] = sp.wind.enabled;
    j["aero"] = sp.aero.enabled;
    j["strain_limit"] = sp.strain_limit.ratio;
    j["strain_passes"] = sp.strain_limit.passes;
    j["strain_every"] = sp.strain_limit.every;
    j["colliders"] = sp.colliders.size();
    j["self_collision"] = {{"thickness", sp.self_collision.thickness}, {"friction", sp.self_collision.friction},
                           {"contacts", sim.self_contacts()}, {"runs", sim.self_collision_runs()},
                           {"parts", sim.self_collision_parts()}, {"resolves", sim.self_collision_resolves()},
                           {"substeps", sp.self_collision.substeps},
                           {"substepped", sim.self_collision_substepped()}};
    j["seam_springs"] = sim.cloth().seams.a.size();
    j["seam_colours"] = sim.cloth().seams.groups.colour_count;
    if (exporter) j["obj_frames"] = frames_written;
    j["wall_seconds"] = wall;
    j["particle_substeps_per_second"] = rate;
    j["stages"] = sim.stage_names();
    j["max_strain"] = health.max_structural_strain;
    j["kinetic_energy"] = health.kinetic_energy;
    j["max_speed"] = health.max_speed;
    j["finite"] = health.finite && error.empty();
    j["healthy"] = health.finite && error.empty() && blow_up.empty();
    const std::string overstretched = overstretched_warning(sim, health.max_structural_strain);
    j["overstretched"] = !overstretched.empty(); // the stderr warning below
    if (!blow_up.empty()) j["health_error"] = blow_up;
    j["health"] = {{"checked", health.monitor.checked},
                   {"substep", health.monitor.substep},
                   {"kinetic_energy", health.monitor.kinetic_energy},
                   {"energy_bound", health.monitor.energy_bound},
                   {"max_strain", health.monitor.max_strain},
                   {"strain_bound", health.monitor.strain_bound},
                   {"max_speed", health.monitor.max_speed},
                   {"speed_bound", health.monitor.speed_bound}};
    if (sp.strain_limit.ratio > 0.0f) {
        // What the strain limit achieved: the largest stretch of the springs it limits, honoured within 10 %.
        j["strain_limit_max_stretch"] = health.max_limited_stretch;
        j["strain_limit_honoured"] = health.max_limited_stretch <= 1.1f * sp.strain_limit.ratio;
    }
    j["checksum"] = hex64(sim.checksum());
    j["origin"] = sim.origin(); // m: positions are stored relative to it (the cloth's centre)
    if (!error.empty()) j["error"] = error;

    if (o.json) {
        std::cout << j.dump() << std::endl;
    } else {
        std::printf("drape run: scene %s, %zu particles, %zu springs, %d thread(s), kernel %s%s\n",
                    spec.name.c_str(), particles, sim.cloth().spring_count(), threads,
                    kernel_path_name(sim.kernel()), sp.fused ? " (fused)" : " (staged)");
        if (implicit) {
            const ImplicitStats& st = sim.implicit_stats();
            std::printf("  solver implicit (backward Euler, %s%s), dt %s s (%s; %.3g x the explicit bound %s s), "
                        "%llu steps = %.4g s simulated\n",
                        sp.implicit.method == ImplicitMethod::jacobi ? "Jacobi" : "vertex block descent",
                        chebyshev_text(sp).c_str(),
                        format_dt(sp.dt).c_str(), dt_default ? "default: a frame" : o.dt ? "--dt" : "scene's physics.dt",
                        double(sp.dt) / bound.dt_max, format_dt(bound.dt_max).c_str(),
                        static_cast<unsigned long long>(done), sim.time());
            std::printf("  last step: %u iterations (at most %u%s), relative residual %.3g\n", st.iterations,
                        sp.implicit.iterations,
                        sp.implicit.tolerance > 0.0f ? (", tolerance " + format_dt(sp.implicit.tolerance)).c_str() : "",
                        st.relative_residual);
        } else {
            std::printf("  solver explicit, integrator %s, dt %s s (%s; bound %s s), %llu substeps = %.4g s simulated\n",
                        integrator_name(sp.integrator), format_dt(sp.dt).c_str(),
                        dt_default ? "default" : o.dt ? "--dt" : "scene's physics.dt", format_dt(bound.dt_max).c_str(),
                        static_cast<unsigned long long>(done), sim.time());
        }
        const DerivedMaterial d = derive_material(sim.cloth());
        if (spec.model == MaterialModel::fabric)
            std::printf("  material: fabric '%s' (%.4g g/m^2); derived node mass %.4g g, spring k structural "
                        "%.4g-%.4g, shear %.4g-%.4g N/m\n",
                        spec.fabric.name.c_str(), double(spec.fabric.density) * fabric_gsm_per_kg_m2,
                        d.node_mass_g_mean, double(d.spring_min[0]), double(d.spring_max[0]),
                        double(d.spring_min[1]), double(d.spring_max[1]));
        else
            std::printf("  material: springs, node mass %.4g g, spring k structural %.4g, shear %.4g, bend %.4g N/m\n",
                        d.node_mass_g_mean, double(d.stiffness[0]), double(d.stiffness[1]), double(d.stiffness[2]));
        std::printf("  wall %.3f s, %.4g particle-%s/s, %.3gx real time\n", wall, rate, implicit ? "steps" : "substeps",
                    real_time);
        std::printf("  max structural strain %.4f, kinetic energy %.4g J, finite %s, checksum %s\n",
                    double(health.max_structural_strain), health.kinetic_energy,
                    (health.finite && error.empty()) ? "yes" : "no", hex64(sim.checksum()).c_str());
        if (health.monitor.checked)
            std::printf("  healthy %s (last check at substep %zu: kinetic energy %.4g J of %.4g, strain %.4g of %.4g, "
                        "speed %.4g of %.4g m/s)\n",
                        blow_up.empty() && error.empty() ? "yes" : "no", health.monitor.substep,
                        health.monitor.kinetic_energy, health.monitor.energy_bound, double(health.monitor.max_strain),
                        double(health.monitor.strain_bound), double(health.monitor.max_speed),
                        double(health.monitor.speed_bound));
        else // stopped before the monitor's first check: its figures would read 0 of 0
            std::printf("  healthy %s (the health monitor had not checked yet: it checks every %zu substeps)\n",
                        blow_up.empty() && error.empty() ? "yes" : "no", HealthMonitor::check_every);
    }
    if (!blow_up.empty()) {
        std::cerr << "drape run: " << blow_up << std::endl;
        return exit_code::blow_up;
    }
    if (!error.empty()) {
        std::cerr << "drape run: " << error << std::endl;
        return exit_code::non_finite;
    }
    if (implicit_unconverged(sim, health.max_structural_strain))
        std::cerr << "drape run: warning: " << unconverged_implicit_warning(sim, health.max_structural_strain, false)
                  << std::endl;
    if (!overstretched.empty()) std::cerr << "drape run: warning: " << overstretched << std::endl;
    if (sp.strain_limit.ratio > 0.0f && !(health.max_limited_stretch <= 1.1f * sp.strain_limit.ratio)) {
        // With the implicit solver at few sweeps the step itself is far from its solution (an adversarial sweep: the
        // bag at 1 sweep per 0.1 s step was told to lower the stiffness).
        const bool few_sweeps = implicit && sim.implicit_stats().relative_residual > unconverged_residual;
        std::cerr << "drape run: warning: strain limit " << sp.strain_limit.ratio << " not honoured: max stretch "
                  << health.max_limited_stretch
                  << " over the limited springs (structural, shear and seams; max_strain is the structural ones') "
                     "(more than 1.1 x the limit) after up to "
                  << strain_limit_max_passes << " sweeps per substep; "
                  << (few_sweeps ? "the implicit step's sweeps are far from converged (relative residual " +
                                       g(sim.implicit_stats().relative_residual) + "): raise --iterations (now " +
                                       std::to_string(sp.implicit.iterations) +
                                       ", allowed [1, 1000]) or shorten --dt, or raise the ratio"
                                 : std::string("raise the ratio or lower the stiffness"))
                  << std::endl;
    }
    return exit_code::ok;
}

} // namespace drape::app
