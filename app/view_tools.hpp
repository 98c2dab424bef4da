// State of the viewer's tools (app/view_tools.cpp): strain colours and their colour bar, and the File panel
// (save the scene, export the frame as OBJ, record PNG frames or a video). Held by the Viewer; no OpenGL.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "drape/strain_field.hpp"
#include "frame_recorder.hpp"

namespace drape::app {

/// Colour bar range the user can set, percent strain.
inline constexpr float view_min_strain_scale_pct = 0.1f;
inline constexpr float view_max_strain_scale_pct = 200.0f;

/// The auto colour-bar maximum for a frame's strain (its 99th percentile): the next of 1, 1.5, 2, 3, 5, 7.5 x 10^k
/// (fraction, at least view_min_strain_scale_pct %), so the scale stays put while the strain moves within a
/// step.
float nice_strain_scale(float max_strain);

struct ToolsState {
    // Strain colours (render::Shading::strain_colours switches them; these pick the scale).
    bool strain_auto = true;          ///< colour bar maximum follows the cloth (nice_strain_scale)
    float strain_manual_pct = 5.0f;   ///< colour bar maximum when not automatic, %
    float strain_frame_max = 0.0f;    ///< largest per-vertex strain of the last frame (fraction)
    int strain_lower_frames = 0;      ///< frames the auto scale has wanted to shrink (hysteresis)
    std::unique_ptr<StrainField> strain_field;
    std::uint64_t strain_generation = UINT64_MAX; ///< session generation strain_field was cooked for

    // File panel.
    // Text fields (ImGui edits fixed buffers in place).
    char scene_path[512] = "saved_scene.json";
    bool save_state = true; ///< save positions, velocities and pins with the scene
    char obj_path[512] = "frame.obj";
    char record_path[512] = "recording"; ///< a directory (PNG frames) or a .mp4 file
    std::unique_ptr<FrameRecorder> recorder;
    std::vector<float> obj_scratch;
    bool write_failed = false; ///< a save, export or recording failed (automation exits write_failed)
};

} // namespace drape::app
