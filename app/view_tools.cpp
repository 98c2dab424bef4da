// The viewer's tools (state in view_tools.hpp): strain colours (Fabric panel controls, key C, the colour bar),
// and the File panel: export the current frame as OBJ, record a PNG sequence or a video (key V), save the
// scene. Hooks in the frame loop (view_app.cpp): publish_strain() right after the output stage,
// record_frame() after the panels are drawn and before the swap, finish_tools() at exit.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include <glad/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>

#include "drape/errors.hpp"
#include "drape/scene_write.hpp"
#include "obj_export.hpp"
#include "screenshot.hpp"
#include "view_app.hpp"

namespace drape::app {

float nice_strain_scale(float max_strain) {
    const float floor_scale = view_min_strain_scale_pct / 100.0f;
    if (!(max_strain > floor_scale)) return floor_scale;
    const float decade = std::pow(10.0f, std::floor(std::log10(max_strain)));
    for (float m : {1.0f, 1.5f, 2.0f, 3.0f, 5.0f, 7.5f, 10.0f})
        if (max_strain <= m * decade * 1.0001f) return m * decade;
    return 10.0f * decade;
}

// ---- Strain colours -------------------------------------------------------------------------------------

void Viewer::publish_strain(std::span<float> region) {
    if (!shading_.strain_colours) return;
    ToolsState& t = tools_;
    if (!t.strain_field || t.strain_generation != session_->generation()) {
        // Cooked once per cloth (a CSR filter over the springs), never per frame.
        t.strain_field = std::make_unique<StrainField>(session_->sim().cloth());
        t.strain_generation = session_->generation();
    }
    const Simulation& sim = session_->sim();
    t.strain_frame_max = session_->in_workers(
        [&] { return t.strain_field->compute(sim.x(), sim.y(), sim.z(), renderer_->strain_plane(region)); });
    if (!t.strain_auto) {
        shading_.strain_max = t.strain_manual_pct / 100.0f;
        return;
    }
    // Auto scale: the 99th percentile of the vertices' strains (a few overstretched springs at a grabbed
    // particle show red without washing out the rest), rounded up to 1, 1.5, 2, 3, 5, 7.5 x 10^k; it grows at once and
    // shrinks only after a second of frames that all wanted a smaller one.
    // (The histogram's bin edge can lie above the largest value: never beyond the frame's maximum.)
    const float want = nice_strain_scale(std::min(t.strain_field->quantile(0.99), t.strain_frame_max));
    if (want >= shading_.strain_max) {
        shading_.strain_max = want;
        t.strain_lower_frames = 0;
    } else if (++t.strain_lower_frames > 60) {
        shading_.strain_max = want;
        t.strain_lower_frames = 0;
    }
}

void Viewer::ui_strain_controls() {
    ImGui::Checkbox("strain colours (C)", &shading_.strain_colours);
    ImGui::SameLine();
    ImGui::TextDisabled("(?)");
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("Colour each vertex by the largest stretch |l - l0| / l0 of its structural springs,\n"
                          "blue (0) to red (the colour bar's maximum).");
    if (!shading_.strain_colours) return;
    ImGui::Checkbox("auto scale", &tools_.strain_auto);
    if (!tools_.strain_auto) {
        ImGui::SameLine();
        ImGui::PushItemWidth(112.0f);
        ImGui::SliderFloat("##strain max", &tools_.strain_manual_pct, view_min_strain_scale_pct,
                           view_max_strain_scale_pct, "max %.1f %%",
                           ImGuiSliderFlags_AlwaysClamp | ImGuiSliderFlags_Logarithmic);
        ImGui::PopItemWidth();
    }
}

void Viewer::ui_tool_overlays() {
    const ImGuiIO& io = ImGui::GetIO();
    if (tools_.recorder && show_ui_) {
        // A recording badge under the stats overlay (Tab hides it with the panels, for a clean recording).
        ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - 8.0f, 150.0f), ImGuiCond_Always, ImVec2(1.0f, 0.0f));
        ImGui::SetNextWindowBgAlpha(0.62f);
        ImGui::Begin("recording", nullptr,
                     ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoNav |
                         ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoInputs);
        ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "REC  %zu frames  (V stops)",
                           tools_.recorder->frames_written());
        ImGui::End();
    }
    if (!shading_.strain_colours) return;
    // Bottom right, above the status line (messages sit at the bottom, centred on the free area).
    ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - 8.0f, io.DisplaySize.y - 52.0f), ImGuiCond_Always,
                            ImVec2(1.0f, 1.0f));
    ImGui::SetNextWindowBgAlpha(0.7f);
    ImGui::Begin("strain", nullptr,
                 ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoNav |
                     ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoInputs);
    const float scale_pct = 100.0f * shading_.strain_max;
    ImGui::Text("structural strain, %s", tools_.strain_auto ? "auto scale (99th percentile)" : "fixed scale");
    // The bar: the shader's colour map (render::strain_colour_srgb) in 16 segments.
    const float bar_w = 240.0f, bar_h = 16.0f;
    const ImVec2 p = ImGui::GetCursorScreenPos();
    ImDrawList* draw = ImGui::GetWindowDrawList();
    constexpr int segments = 16;
    for (int i = 0; i < segments; ++i) {
        const Eigen::Vector3f a = render::strain_colour_srgb(float(i) / segments);
        const Eigen::Vector3f b = render::strain_colour_srgb(float(i + 1) / segments);
        const ImU32 ca = ImGui::ColorConvertFloat4ToU32(ImVec4(a.x(), a.y(), a.z(), 1.0f));
        const ImU32 cb = ImGui::ColorConvertFloat4ToU32(ImVec4(b.x(), b.y(), b.z(), 1.0f));
        const float x0 = p.x + bar_w * float(i) / segments, x1 = p.x + bar_w * float(i + 1) / segments;
        draw->AddRectFilledMultiColor(ImVec2(x0, p.y), ImVec2(x1, p.y + bar_h), ca, cb, cb, ca);
    }
    draw->AddRect(p, ImVec2(p.x + bar_w, p.y + bar_h), IM_COL32(20, 20, 20, 255));
    ImGui::Dummy(ImVec2(bar_w, bar_h));
    // Tick labels at 0, 1/2 and 1 of the scale.
    char mid[32], top[32];
    std::snprintf(mid, sizeof mid, "%.3g %%", double(scale_pct) * 0.5);
    std::snprintf(top, sizeof top, "%.3g %%", double(scale_pct));
    ImGui::TextUnformatted("0 %");
    ImGui::SameLine(bar_w * 0.5f - ImGui::CalcTextSize(mid).x * 0.5f + ImGui::GetStyle().WindowPadding.x);
    ImGui::TextUnformatted(mid);
    ImGui::SameLine(bar_w - ImGui::CalcTextSize(top).x + ImGui::GetStyle().WindowPadding.x);
    ImGui::TextUnformatted(top);
    ImGui::TextDisabled("largest now %.3g %%", 100.0 * double(tools_.strain_frame_max));
    ImGui::End();
}

// ---- File panel ----------------------------------------------------------------------------------------

void Viewer::save_scene_file(const std::string& path, bool with_state) {
    try {
        const SceneSpec spec = session_->current_spec();
        if (with_state) {
            const SceneState state = capture_state(session_->sim());
            save_scene(path, spec, &state);
        } else {
            save_scene(path, spec);
        }
        session_->post(MessageLevel::info, "saved the scene" + std::string(with_state ? " and its state" : "") +
                                               " to " + path);
        std::fprintf(stderr, "drape view: saved the scene to %s\n", path.c_str());
    } catch (const std::exception& e) { // InvalidInput (would not load back) or runtime_error (cannot write)
        tools_.write_failed = true;
        session_->post(MessageLevel::error, std::string("scene not saved: ") + e.what());
        std::fprintf(stderr, "drape view: scene not saved: %s\n", e.what());
    }
}

void Viewer::export_obj(const std::string& path) {
    try {
        write_obj_file(path, session_->sim(), session_->publisher(), tools_.obj_scratch, frame_index_);
        session_->post(MessageLevel::info, "exported this frame to " + path + " (" +
                                               std::to_string(session_->sim().cloth().particle_count) +
                                               " vertices)");
        std::fprintf(stderr, "drape view: exported %s\n", path.c_str());
    } catch (const std::exception& e) {
        tools_.write_failed = true;
        session_->post(MessageLevel::error, std::string("OBJ export failed: ") + e.what());
        std::fprintf(stderr, "drape view: OBJ export failed: %s\n", e.what());
    }
}

void Viewer::start_recording(const std::string& target) {
    if (tools_.recorder) return;
    int fw = 1, fh = 1;
    glfwGetFramebufferSize(window_, &fw, &fh);
    try {
        tools_.recorder = std::make_unique<FrameRecorder>(target, fw, fh);
        const FrameRecorder& r = *tools_.recorder;
        session_->post(MessageLevel::info, "recording " + std::string(r.video() ? "video " : "PNG frames ") +
                                               "to " + target + " (" + std::to_string(r.width()) + " x " +
                                               std::to_string(r.height()) + "); V stops");
    } catch (const std::exception& e) {
        tools_.write_failed = true;
        session_->post(MessageLevel::error, e.what());
        std::fprintf(stderr, "drape view: %s\n", e.what());
    }
}

void Viewer::stop_recording() {
    if (!tools_.recorder) return;
    const std::string error = tools_.recorder->finish();
    const std::size_t frames = tools_.recorder->frames_written();
    const std::string target = tools_.recorder->target();
    tools_.recorder.reset();
    if (!error.empty()) {
        tools_.write_failed = true;
        session_->post(MessageLevel::error, "recording failed: " + error);
        std::fprintf(stderr, "drape view: recording failed: %s\n", error.c_str());
    } else {
        session_->post(MessageLevel::info, "recorded " + std::to_string(frames) + " frames to " + target);
        std::fprintf(stderr, "drape view: recorded %zu frames to %s\n", frames, target.c_str());
    }
}

void Viewer::record_frame() {
    if (!options_.record.empty() && frame_index_ == 0 && !tools_.recorder && !tools_.write_failed)
        start_recording(options_.record); // --record: from the first frame
    if (!tools_.recorder) return;
    FrameRecorder& r = *tools_.recorder;
    int fw = 1, fh = 1;
    glfwGetFramebufferSize(window_, &fw, &fh);
    if (fw < r.width() || fh < r.height() || (!r.video() && (fw != r.width() || fh != r.height()))) {
        session_->post(MessageLevel::warning, "the window was resized: recording stopped");
        stop_recording();
        return;
    }
    std::vector<unsigned char>* frame = r.acquire();
    if (!frame) { // the writer failed
        stop_recording();
        return;
    }
    render::read_back_rgb(r.width(), r.height(), *frame);
    r.submit(frame);
}

void Viewer::ui_file_panel() {
    ImGui::SetNextItemOpen(options_.panels_open, ImGuiCond_Once);
    if (!ImGui::CollapsingHeader("File")) return;
    ToolsState& t = tools_;
    ImGui::PushItemWidth(220.0f);
    ImGui::InputText("##scene path", t.scene_path, sizeof t.scene_path);
    ImGui::SameLine();
    if (ImGui::Button("Save scene")) save_scene_file(t.scene_path, t.save_state);
    ImGui::Checkbox("with the cloth's current state", &t.save_state);
    ImGui::SameLine();
    ImGui::TextDisabled("(?)");
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("The scene file holds the current fabric, physics and size. With the state it also\n"
                          "holds every position, velocity and pin: opened again, the run continues from here.");
    ImGui::InputText("##obj path", t.obj_path, sizeof t.obj_path);
    ImGui::SameLine();
    if (ImGui::Button("Export OBJ")) export_obj(t.obj_path);
    ImGui::InputText("##record path", t.record_path, sizeof t.record_path);
    ImGui::SameLine();
    if (t.recorder) {
        if (ImGui::Button("Stop (V)")) stop_recording();
        ImGui::TextColored(ImVec4(1.0f, 0.35f, 0.3f, 1.0f), "REC %zu frames -> %s", t.recorder->frames_written(),
                           t.recorder->target().c_str());
    } else {
        if (ImGui::Button("Record (V)")) start_recording(t.record_path);
        ImGui::TextDisabled(on_path("ffmpeg") ? "a folder: PNG frames; x.mp4: video (ffmpeg)"
                                              : "a folder: PNG frames (.mp4 needs ffmpeg)");
    }
    ImGui::PopItemWidth();
}

bool Viewer::tools_key(int key) {
    switch (key) {
    case GLFW_KEY_C:
        shading_.strain_colours = !shading_.strain_colours;
        return true;
    case GLFW_KEY_V:
        if (tools_.recorder)
            stop_recording();
        else
            start_recording(tools_.record_path);
        return true;
    default:
        return false;
    }
}

int Viewer::finish_tools() {
    stop_recording();
    if (!options_.save_obj.empty()) export_obj(options_.save_obj);
    if (!options_.save_scene.empty()) save_scene_file(options_.save_scene, true);
    // Automation (--frames) exits write_failed; an interactive user has already seen the message.
    return tools_.write_failed && options_.frames > 0 ? exit_code::write_failed : exit_code::ok;
}

} // namespace drape::app
