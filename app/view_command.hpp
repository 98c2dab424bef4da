// `drape view`: the real-time viewer (and `drape` with no arguments). Options and entry point; the viewer
// itself is in view_app.hpp (window, input, frame loop), view_ui.cpp (panels) and view_session.hpp
// (simulation and settings).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace drape::app {

struct ViewOptions {
    std::string scene = "hang";        ///< built-in scene name or scene file (.json)
    std::optional<std::string> material; ///< a fabric preset or "springs" instead of the scene's material
    std::optional<std::uint32_t> size; ///< particles per side (grid scenes) or cells per metre (T-shirt);
                                       ///< empty: the scene's own, 64 for "hang"
    int threads = 0;             ///< 0 = all hardware threads
    std::optional<int> substeps; ///< per frame; empty = automatic (real time up to a cost cap)
    std::optional<std::string> solver;       ///< explicit | implicit (empty: the scene's)
    std::optional<std::uint32_t> iterations; ///< implicit: the most iterations per step
    std::optional<float> tolerance;          ///< implicit: relative residual that ends a step early
    bool single_level = false;               ///< implicit: no multilevel guess (--single-level)
    std::optional<float> strain_limit;       ///< largest stretch of the limited springs (0 = off; empty: the scene's)
    std::optional<double> dt;                ///< the implicit step, or the explicit substep (empty: automatic)
    int width = 1280;            ///< window, screen coordinates
    int height = 800;
    bool vsync = true;
    std::uint64_t frames = 0; ///< 0 = until the window is closed
    std::string screenshot;   ///< PNG written from the last frame
    bool stats_json = false;  ///< one JSON object on stdout at exit
    bool ui = true;           ///< panels and overlay
    bool full_mesh = false;   ///< draw every triangle (no level of detail for fine grids)
    bool pixel_lighting = false; ///< light every pixel (default: per vertex where triangles are under 4 px)
    bool overlap = true; ///< simulate the next frame while this one is drawn (--no-overlap: one after the other)
    /// With the overlap: a step longer than a frame does not hold the frame; frames in between blend the last two
    /// states (FrameInterpolator; --no-interpolate: every frame waits for its step)
    bool interpolate = true;
    /// Frames per second drawn while a step spans frames: each drawn frame costs the simulation CPU (llvmpipe draws
    /// on the same cores), so the frames beside a step are paced to this rate (--blend-fps)
    int blend_fps = 30;
    std::optional<float> camera_yaw_deg; ///< camera around the vertical, degrees: 0 from +z (the front), 180 the back
    // Hidden automation hooks (documentation screenshots, tests).
    bool panels_open = false; ///< every panel section expanded
    bool demo_grab = false;   ///< grab the free corner half-way through --frames and drag it
    bool start_paused = false;
    bool key_help = false; ///< the F1 key help open
    bool strain_colours = false; ///< start with strain colours on
    std::string record;          ///< record from the first frame: a directory (PNG frames) or a .mp4 file
    std::string save_obj;        ///< export the last frame as this OBJ file at exit
    std::string save_scene;      ///< save the scene and its state as this scene file at exit
};

/// Opens the viewer and runs it until the window closes or `frames` frames are drawn. Returns the exit code
/// (drape::exit_code): 0 ok, 1 internal (no OpenGL 4.5, ...), 2 bad input or no display (the message says to use
/// xvfb-run), 3 the simulation became non-finite, 4 the cloth exploded (BlowUpError), 5 a screenshot could not be
/// written. A simulation failure is also printed on stderr.
int view_command(const ViewOptions& options);

} // namespace drape::app
