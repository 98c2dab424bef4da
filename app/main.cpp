// The `drape` executable: command-line front end.
//   drape run ...   headless run of a scene with machine-readable figures (see run_command.hpp)
//   drape materials the fabric presets in file units (see materials.hpp)
//   drape view ...  the real-time viewer (see view_command.hpp); `drape` with no arguments opens it
// Exit codes (drape::exit_code, docs/user_guide.md): 0 ok, 1 internal error, 2 bad input (one line naming the flag
// or file field and its allowed range), 3 simulation became non-finite, 4 blow-up, 5 an output could not be written.
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <type_traits>
#include <iostream>
#include <sstream>
#include <string>

#include <CLI/CLI.hpp>

#include "drape/errors.hpp"
#include "drape/scene_hang.hpp"
#include "materials.hpp"
#include "run_command.hpp"
#include "view_command.hpp"

namespace {

/// A CLI11 validator whose message states the allowed range (and unit) in one line. Integer options take whole
/// numbers only ("3.5" and "1e3" are refused as not whole); floating-point options refuse NaN and infinities.
template <class T> CLI::Validator in_range(T lo, T hi, const std::string& unit = "") {
    std::ostringstream desc;
    desc << "[" << lo << ", " << hi << "]" << unit;
    const std::string range = desc.str();
    return CLI::Validator(
        [lo, hi, range](std::string& text) -> std::string {
            // Any number first (strtod: also 1e400, inf, nan), then the type's own reading.
            errno = 0;
            char* end = nullptr;
            const double any = std::strtod(text.c_str(), &end);
            const bool numeric = !text.empty() && end == text.c_str() + text.size() && !std::isspace(text[0]);
            if (!numeric) return "'" + text + "' is not a number; allowed range " + range;
            if (std::isnan(any)) return "'" + text + "' is not a number; allowed range " + range;
            if constexpr (std::is_integral_v<T>) {
                if (std::isfinite(any) && any != std::floor(any))
                    return "'" + text + "' must be a whole number in " + range;
                T value{};
                std::istringstream in(text);
                in >> value;
                if (in.fail() || !in.eof()) {
                    if (!(any >= double(lo) && any <= double(hi)))
                        return "value " + text + " is outside the allowed range " + range;
                    return "'" + text + "' must be a whole number written with digits only, in " + range;
                }
                if (text[0] == '-' && lo >= T{0}) return "value " + text + " is outside the allowed range " + range;
                if (!(value >= lo && value <= hi)) return "value " + text + " is outside the allowed range " + range;
            } else {
                if (!(any >= double(lo) && any <= double(hi)))
                    return "value " + text + " is outside the allowed range " + range;
            }
            return {};
        },
        range);
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"drape: a data-oriented, SIMD + multithreaded mass-spring cloth engine"};
    app.require_subcommand(0, 1); // no subcommand: the viewer
    app.set_version_flag("--version", "drape 0.1.0");

    drape::app::RunOptions run;
    CLI::App* cmd = app.add_subcommand("run", "Headless run of a scene; prints its figures (use --json for one "
                                              "machine-readable object).");
    cmd->add_option("--scene", run.scene,
                    "Built-in scene (hang, drape, sphere, flag, tshirt) or a scene file (.json, docs/scene_format.md)")
        ->capture_default_str();
    cmd->add_option("--size", run.size,
                    "Grid scenes: particles per side N (N x N); tshirt and outline cloths: cells per metre (an outline's spacing 1 / N m) [default: the scene's]")
        ->check(in_range<std::uint32_t>(drape::hang_min_n, drape::hang_max_n));
    cmd->add_option("--threads", run.threads, "Worker threads (default: all hardware threads)")
        ->check(in_range<int>(1, 256));
    auto* steps = cmd->add_option("--steps", run.steps,
                                  "Steps of size dt to run (explicit substeps or implicit steps) [default 1000]")
                      ->check(in_range<std::uint64_t>(1, 1'000'000'000));
    auto* secs = cmd->add_option("--sim-seconds", run.sim_seconds, "Simulated seconds to run (instead of --steps)")
                     ->check(in_range<double>(1e-6, 1e4, " s"));
    steps->excludes(secs);
    cmd->add_option("--dt", run.dt,
                    "Explicit substep or implicit step in seconds (default: explicit 0.9 x the stability bound, "
                    "above it refused; implicit a frame, 1/30 s, any step from 1e-4 s up to 0.1 s)")
        ->check(in_range<double>(1e-9, 0.1, " s"));
    cmd->add_option("--integrator", run.integrator,
                    "Time integrator of the explicit solver: euler or verlet [default: the scene's]")
        ->check(CLI::IsMember({"euler", "verlet"}));
    cmd->add_option("--solver", run.solver,
                    "explicit (the seeds' substeps below the stability bound) or implicit (backward Euler by vertex "
                    "block descent, steps as long as a frame) [default: the scene's]")
        ->check(CLI::IsMember({"explicit", "implicit"}));
    cmd->add_option("--iterations", run.iterations,
                    "Implicit solver: iterations (sweeps) per step, the most with --tolerance [scene's, 30]")
        ->check(in_range<std::uint32_t>(1, drape::implicit_max_iterations));
    cmd->add_option("--tolerance", run.tolerance,
                    "Implicit solver: stop a step once its residual is below this fraction of the first sweep's "
                    "(0 = always run --iterations) [scene's, 0]")
        ->check(in_range<float>(0.0f, 1.0f));
    cmd->add_flag("--fas", run.fas,
                  "Implicit solver, grid and outline cloths of the fabric model: the coarse levels of the multilevel guess "
                  "solve with the "
                  "cloth's own force residual (full approximation scheme): a cloth comes to rest at its own equilibrium "
                  "[scene's, off]");
    cmd->add_flag("--single-level", run.single_level,
                  "Implicit solver: no multilevel guess, every step solved on the cloth's own grid only (against "
                  "colliders the guess leaves the cloth touching them to these sweeps anyway: docs/implicit.md); a "
                  "hanging cloth does not come to rest without it [scene's, multilevel on]");
    cmd->add_flag("--fas-at-rest", run.fas_at_rest,
                  "Implicit solver, with the multilevel guess: once the cloth's rms speed has stayed below g dt / 2 for "
                  "10 steps its coarse levels solve as with --fas (until it exceeds 2 g dt), so it comes to rest at its "
                  "own equilibrium; never with colliders, self-collision, wind or a grab; at N >= 200 it needs more than "
                  "10 sweeps [scene's, off]");
    cmd->add_option("--material", run.material,
                    "Material: a fabric preset (silk, cotton_shirting, jersey, linen, wool, denim, ...; see drape "
                    "materials), switching the cloth to the fabric model, or springs (the seeds' spring model with "
                    "the scene's spring fields) [default: the scene's]");
    cmd->add_option("--stiffness", run.stiffness,
                    "Spring model: structural spring stiffness k in N/m (shear and bend follow the scene's ratios) "
                    "[scene: 1000]")
        ->check(in_range<float>(100.0f, 25000.0f, " N/m"));
    cmd->add_option("--damping", run.damping, "Spring model: spring damping as a fraction of critical damping [scene's]")
        ->check(in_range<float>(0.0f, 1.0f));
    cmd->add_option("--drag", run.drag, "Air drag kr in 1/s (F = -m kr v) [scene's]")
        ->check(in_range<float>(0.0f, 100.0f, " 1/s"));
    cmd->add_flag("--wind", run.wind, "Enable seed 000's analytic wind field");
    cmd->add_flag("--aero", run.aero,
                  "Enable seed 004's aerodynamic wind per triangle (density, drag coefficient and wind velocity from "
                  "the scene; defaults 1.2 kg/m^3, 1.0, (0, 0, 5) m/s)");
    cmd->add_option("--wind-strength", run.wind_strength, "Wind amplitude in m/s^2 [scene's, 2]")
        ->check(in_range<float>(0.0f, 100.0f, " m/s^2"));
    cmd->add_option("--kernel", run.kernel, "Spring kernel: grid stencil, general CSR, or auto")
        ->check(CLI::IsMember({"auto", "grid", "csr"}))
        ->capture_default_str();
    cmd->add_option("--strain-limit", run.strain_limit,
                    "Provot strain limiting: largest stretch of structural, shear and seam springs (0.1 = 10%; 0 = off)")
        ->check(in_range<float>(0.0f, 10.0f));
    cmd->add_option("--strain-passes", run.strain_passes, "Least strain-limiting sweeps over all colour groups (more, up to 100, while a spring is over 1.05 x the limit) [scene's, 4]")
        ->check(in_range<std::uint32_t>(1, 100));
    cmd->add_option("--strain-every", run.strain_every, "Run strain limiting after every K-th substep [scene's, 1]")
        ->check(in_range<std::uint32_t>(1, 1000));
    cmd->add_option("--self-collision", run.self_collision,
                    "Self-collision thickness in m: 0 = off, or 0.0005 to 0.05 (docs/self_collision.md) [scene's, 0]")
        ->check(in_range<float>(0.0f, 0.05f, " m (0 = off; on: at least 0.0005)"))
        ->check(CLI::Validator(
            [](std::string& text) -> std::string {
                const double t = std::strtod(text.c_str(), nullptr);
                return t > 0.0 && t < 0.0005 ? "'" + text + "' is below 0.0005 m; allowed 0 (off) or [0.0005, 0.05] m"
                                             : std::string();
            },
            ""));
    cmd->add_option("--self-collision-substeps", run.self_collision_substeps,
                    "Implicit solver: a step in which cloth touches cloth is solved again from its start as K "
                    "sub-steps (1 = never; docs/self_collision.md) [scene's, 4]")
        ->check(in_range<std::uint32_t>(1, drape::self_collision_max_substeps));
    auto* obj = cmd->add_option("--export-obj", run.export_obj,
                                "Write OBJ frames (vertices, normals, faces) into this directory");
    cmd->add_option("--every", run.export_every, "Substeps between exported OBJ frames")
        ->check(in_range<std::uint32_t>(1, 1'000'000'000))
        ->needs(obj)
        ->capture_default_str();
    cmd->add_flag("--overwrite", run.export_overwrite,
                  "Remove the frame_*.obj files already in the --export-obj directory first (without it such a "
                  "directory is refused)")
        ->needs(obj);
    cmd->add_flag("--staged", run.staged, "Run each stage as its own pass instead of the fused pass");
    cmd->add_flag("--json", run.json, "Print exactly one JSON object on stdout");

    bool materials_json = false;
    CLI::App* materials_cmd = app.add_subcommand("materials", "List the fabric presets with their figures in file "
                                                              "units (g/m^2, N/m, micro-N*m, s) and sources.");
    materials_cmd->add_flag("--json", materials_json, "Print one JSON array (each preset with its source)");

    drape::app::ViewOptions view;
    CLI::App* view_cmd = app.add_subcommand("view", "Real-time viewer: drag the cloth, pin particles, edit fabric, "
                                                    "physics and lighting in panels (the default with no arguments). "
                                                    "Press F1 in the window for keys.");
    view_cmd->add_option("--scene", view.scene,
                         "Built-in scene (hang, drape, sphere, flag, tshirt) or a scene file (.json)")
        ->capture_default_str();
    view_cmd->add_option("--material", view.material,
                         "A fabric preset (see drape materials) or springs, instead of the scene's material");
    view_cmd->add_option("--size", view.size,
                         "Grid scenes: particles per side N (N x N) [the built-in hang: 64, scene files and others: their own]; tshirt and "
                         "outline cloths: cells per metre [10, 1000] (an outline's spacing 1 / N m)")
        ->check(in_range<std::uint32_t>(2, 2048));
    view_cmd->add_option("--threads", view.threads, "Worker threads (default: all hardware threads)")
        ->check(in_range<int>(1, 256));
    view_cmd->add_option("--substeps", view.substeps,
                         "Substeps per frame (default: automatic, 1/60 s simulated per frame within a cost cap)")
        ->check(in_range<int>(1, 1000));
    view_cmd->add_option("--solver", view.solver,
                         "explicit or implicit (one implicit step per frame, iterations within a time budget) "
                         "[default: the scene's]")
        ->check(CLI::IsMember({"explicit", "implicit"}));
    view_cmd->add_option("--iterations", view.iterations,
                         "Implicit solver: the most iterations per step (the frame budget may run fewer) [scene's, 30]")
        ->check(in_range<std::uint32_t>(1, drape::implicit_max_iterations));
    view_cmd->add_option("--tolerance", view.tolerance,
                         "Implicit solver: stop a step once its residual is below this fraction of the first sweep's")
        ->check(in_range<float>(0.0f, 1.0f));
    view_cmd->add_flag("--single-level", view.single_level,
                       "Implicit solver: no multilevel guess, every step solved on the cloth's own grid only "
                       "(docs/implicit.md) [scene's, multilevel on]");
    view_cmd->add_option("--strain-limit", view.strain_limit,
                         "Strain limiting: largest stretch of structural and seam springs, and with the explicit solver "
                         "shear springs (0.1 = 10%; 0 = off) [scene's]")
        ->check(in_range<float>(0.0f, 10.0f));
    view_cmd->add_option("--dt", view.dt,
                         "Implicit solver: the step in seconds [1/60 s, a frame at 60 FPS]; explicit: the substep, "
                         "at most the stability bound [default 0.9 x the bound]")
        ->check(in_range<double>(1e-4, 0.1, " s"));
    view_cmd->add_option("--width", view.width, "Window width in pixels")
        ->check(in_range<int>(320, 7680))
        ->capture_default_str();
    view_cmd->add_option("--height", view.height, "Window height in pixels")
        ->check(in_range<int>(240, 4320))
        ->capture_default_str();
    bool no_vsync = false;
    view_cmd->add_flag("--no-vsync", no_vsync, "Do not wait for the display's refresh (measure the real frame rate)");
    view_cmd->add_option("--frames", view.frames, "Draw this many frames, then exit (default: until the window closes)")
        ->check(in_range<std::uint64_t>(1, 100'000'000));
    view_cmd->add_option("--screenshot", view.screenshot, "Save the last frame as this PNG file")
        ->check(CLI::Validator(
            [](std::string& path) -> std::string {
                if (path.size() < 5 || path.substr(path.size() - 4) != ".png")
                    return "'" + path + "' must be a file name ending in .png";
                return {};
            },
            "FILE.png"));
    view_cmd->add_flag("--stats-json", view.stats_json,
                       "At exit, print one JSON object: fps (median), frame_ms {sim, publish, draw}, particles, ...");
    bool no_ui = false;
    view_cmd->add_flag("--no-ui", no_ui, "Hide the panels and the stats overlay (Tab toggles them)");
    view_cmd->add_flag("--full-mesh", view.full_mesh,
                       "Draw every triangle (default: grids finer than 256 x 256 are drawn at a coarser level of detail)");
    view_cmd->add_flag("--pixel-lighting", view.pixel_lighting,
                       "Light every pixel (default: triangles under 4 pixels across on screen are lit at their "
                       "vertices)");
    bool no_overlap = false;
    view_cmd->add_flag("--no-overlap", no_overlap,
                       "Simulate and draw one after the other (default: the next frame simulates on its own thread "
                       "while this one is drawn)");
    bool no_interpolate = false;
    view_cmd->add_flag("--no-interpolate", no_interpolate,
                       "Every frame waits for its step (default: when a step takes longer than a frame, the frames "
                       "in between blend the last two states, one step behind the simulation)");
    view_cmd
        ->add_option("--blend-fps", view.blend_fps,
                     "Frames per second drawn while a step takes longer than a frame (the frames beside the step are "
                     "paced to it, leaving the cores to the simulation)")
        ->check(in_range<int>(10, 240, " frames/s"));
    view_cmd->add_option("--camera-yaw", view.camera_yaw_deg,
                         "Camera angle around the vertical, degrees: 0 looks from +z (a garment's front), 90 from +x, "
                         "180 from behind [default: the scene's view, front-right]")
        ->check(in_range<float>(-360.0f, 360.0f, " degrees")) // CLI::Range let NaN through
        ->option_text("DEG:[-360, 360]");
    // Hidden automation hooks (documentation screenshots and tests).
    view_cmd->add_flag("--panels-open", view.panels_open, "Expand every panel")->group("");
    view_cmd->add_flag("--demo-grab", view.demo_grab, "Grab and drag the free corner half-way through --frames")
        ->group("");
    view_cmd->add_flag("--paused", view.start_paused, "Start paused")->group("");
    view_cmd->add_flag("--key-help", view.key_help, "Open the F1 key help")->group("");
    view_cmd->add_flag("--strain-colours", view.strain_colours, "Start with strain colours on (C toggles them)")
        ->group("");
    view_cmd->add_option("--record", view.record,
                         "Record from the first frame: a directory (PNG frames) or FILE.mp4 (needs ffmpeg)")
        ->group("");
    view_cmd->add_option("--save-obj", view.save_obj, "At exit, export the last frame as this OBJ file")->group("");
    view_cmd->add_option("--save-scene", view.save_scene, "At exit, save the scene and its state to this file")
        ->group("");

    auto is_command = [&](const std::string& name) {
        for (const CLI::App* sub : app.get_subcommands({}))
            if (sub->check_name(name)) return true;
        return false;
    };
    if (argc > 1 && argv[1][0] != '-' && !is_command(argv[1])) {
        std::string known;
        for (const CLI::App* sub : app.get_subcommands({})) known += (known.empty() ? "" : ", ") + sub->get_name();
        std::fprintf(stderr, "drape: unknown command '%s' (commands: %s; see drape --help)\n", argv[1], known.c_str());
        return 2;
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        // A flag given twice reads "--size: At Most 1 required but received 2" in CLI11's words: say it in ours.
        std::string what = e.what();
        const std::string twice = ": At Most 1 required but received ";
        if (const std::size_t at = what.find(twice); at != std::string::npos)
            what = what.substr(0, at) + " given " + what.substr(at + twice.size()) + " times; give it once";
        std::fprintf(stderr, "drape: %s (see drape %s--help)\n", what.c_str(),
                     cmd->parsed() ? "run " : view_cmd->parsed() ? "view " : "");
        return 2;
    }

    try {
        if (cmd->parsed()) return drape::app::run_command(run);
        if (materials_cmd->parsed()) return drape::app::materials_command(materials_json);
        // `drape view`, or `drape` alone: the viewer.
        view.vsync = !no_vsync;
        view.ui = !no_ui;
        view.overlap = !no_overlap;
        view.interpolate = !no_interpolate;
#ifdef DRAPE_WITH_VIEWER
        return drape::app::view_command(view);
#else
        std::fprintf(stderr, "drape: this build has no viewer (configure with -DDRAPE_BUILD_RENDER=ON)\n");
        return 2;
#endif
    } catch (const drape::InvalidInput& e) {
        std::fprintf(stderr, "drape: %s\n", e.what());
        return drape::exit_code::bad_input;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "drape: out of memory building the scene; choose a smaller --size\n");
        return drape::exit_code::bad_input;
    } catch (const drape::WriteError& e) {
        std::fprintf(stderr, "drape: %s\n", e.what());
        return drape::exit_code::write_failed;
    } catch (const std::exception& e) { // a bug: said plainly, never an abort
        std::fprintf(stderr, "drape: internal error: %s\n", e.what());
        return drape::exit_code::internal;
    } catch (...) {
        std::fprintf(stderr, "drape: internal error: an unknown exception\n");
        return drape::exit_code::internal;
    }
    return drape::exit_code::ok;
}
