// The viewer's Dear ImGui panels: Run mode, Fabric, Physics, Lighting, Camera (seed 000's five), the stats
// overlay, the status line and the F1 key help. Every slider is clamped to the range of SPEC.md / the issue
// (typed values too: ImGuiSliderFlags_AlwaysClamp); changes go through ViewSession, which refuses or
// compensates unstable ones.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>

#include "view_app.hpp"

namespace drape::app {

namespace {

constexpr ImGuiSliderFlags clamp_flags = ImGuiSliderFlags_AlwaysClamp;
constexpr ImGuiSliderFlags log_flags = ImGuiSliderFlags_AlwaysClamp | ImGuiSliderFlags_Logarithmic;

void help_marker(const char* text) {
    ImGui::SameLine();
    ImGui::TextDisabled("(?)");
    if (ImGui::IsItemHovered()) {
        ImGui::BeginTooltip();
        ImGui::PushTextWrapPos(ImGui::GetFontSize() * 30.0f);
        ImGui::TextUnformatted(text);
        ImGui::PopTextWrapPos();
        ImGui::EndTooltip();
    }
}

bool colour_edit(const char* label, Eigen::Vector3f& c) {
    float v[3] = {c.x(), c.y(), c.z()};
    if (!ImGui::ColorEdit3(label, v, ImGuiColorEditFlags_Float | ImGuiColorEditFlags_NoInputs)) return false;
    for (int i = 0; i < 3; ++i)
        v[i] = std::clamp(v[i], 0.0f, 1.0f);
    c = {v[0], v[1], v[2]};
    return true;
}

/// Thousands separators for counts.
std::string grouped(std::size_t n) {
    const std::string digits = std::to_string(n);
    std::string out;
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) out.push_back(',');
        out.push_back(digits[i]);
    }
    return out;
}

} // namespace

void Viewer::build_ui() {
    if (show_ui_) {
        ui_panels();
        ui_overlay();
    }
    ui_tool_overlays();
    ui_messages();
    if (show_help_) ui_help();
}

void Viewer::ui_panels() {
    const ImGuiIO& io = ImGui::GetIO();
    ImGui::SetNextWindowPos(ImVec2(8.0f, 8.0f), ImGuiCond_Always);
    // Fixed width, height fitted to the open sections (a smaller translucent window is cheaper for software
    // GL).
    ImGui::SetNextWindowSizeConstraints(ImVec2(340.0f, 0.0f), ImVec2(340.0f, io.DisplaySize.y - 16.0f));
    ImGui::SetNextWindowBgAlpha(0.86f);
    ImGui::Begin("drape", nullptr,
                 ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                     ImGuiWindowFlags_AlwaysAutoResize);
    ImGui::PushItemWidth(170.0f);
    ViewSession& s = *session_;
    const ImGuiCond open_cond = ImGuiCond_Once;

    // ---- Run mode
    // -----------------------------------------------------------------------------------------------
    ImGui::SetNextItemOpen(true, open_cond);
    if (ImGui::CollapsingHeader("Run mode")) {
        if (ImGui::Button(s.running() ? "Pause" : "Run", ImVec2(70, 0))) s.set_running(!s.running());
        ImGui::SameLine();
        if (ImGui::Button("Step", ImVec2(70, 0))) s.step_once();
        ImGui::SameLine();
        if (ImGui::Button("Reset", ImVec2(70, 0))) s.reset();
        static const std::vector<std::string> names = builtin_scene_names();
        const std::string& current = s.scene().name;
        if (ImGui::BeginCombo("scene", current.c_str())) {
            for (const std::string& n : names)
                if (ImGui::Selectable(n.c_str(), n == current)) s.set_scene(n);
            ImGui::EndCombo();
        }
        help_marker(s.scene().description.c_str());
        const bool grid = s.grid_scene();
        ImGui::SliderInt(grid ? "grid size N" : "cells per metre", &ui_size_,
                         static_cast<int>(grid ? view_min_size : view_min_cells),
                         static_cast<int>(grid ? view_max_size : view_max_cells), "%d", log_flags);
        if (ImGui::IsItemDeactivatedAfterEdit()) s.set_size(static_cast<std::uint32_t>(ui_size_));
        if (!ImGui::IsItemActive() && ui_size_ != static_cast<int>(s.size()))
            ui_size_ = static_cast<int>(s.size());
        help_marker(
            "Applied when the slider is released: the cloth is rebuilt in its starting state with the same "
            "total mass and materials.");
        ImGui::Text("%s particles, %s springs", grouped(s.sim().cloth().particle_count).c_str(),
                    grouped(s.sim().cloth().spring_count()).c_str());
        ImGui::Text("simulated %.3f s  (%s substeps)", s.sim().time(), grouped(s.sim().steps_done()).c_str());
    }

    // ---- Fabric
    // -------------------------------------------------------------------------------------------------
    ImGui::SetNextItemOpen(true, open_cond);
    if (ImGui::CollapsingHeader("Fabric")) {
        ImGui::SliderFloat("node mass", &ui_node_mass_, view_min_node_mass_g, view_max_node_mass_g, "%.4f g",
                           log_flags);
        if (ImGui::IsItemDeactivatedAfterEdit()) s.set_node_mass(ui_node_mass_);
        if (!ImGui::IsItemActive()) ui_node_mass_ = s.fabric().node_mass_g;
        help_marker("Mass of one particle, 0.001-1 g (seed 000). Applied on release; the motion continues.");
        static const char* kinds[] = {"structural k", "shear k", "bend k", "seam k"};
        for (std::size_t k = 0; k < spring_kind_count; ++k) {
            if (static_cast<SpringKind>(k) == SpringKind::seam && !s.has_seams()) continue;
            float v = s.fabric().stiffness[k];
            if (ImGui::SliderFloat(kinds[k], &v, view_min_stiffness, view_max_stiffness, "%.0f N/m",
                                   log_flags))
                s.set_stiffness(static_cast<SpringKind>(k), v);
        }
        float damping = s.fabric().damping_ratio;
        if (ImGui::SliderFloat("damping", &damping, 0.0f, 1.0f, "%.3f", clamp_flags))
            s.set_damping_ratio(damping);
        help_marker("Spring damping as a fraction of the critical damping of one spring.");
        colour_edit("colour", shading_.front_colour);
        ImGui::SameLine();
        ImGui::Checkbox("back colour", &shading_.back_colour_enabled);
        if (shading_.back_colour_enabled) {
            ImGui::SameLine();
            colour_edit("##back", shading_.back_colour);
        }
        ImGui::SliderFloat("diffuse", &shading_.diffuse, 0.0f, 1.0f, "%.2f", clamp_flags);
        ImGui::SliderFloat("specular", &shading_.specular, 0.0f, 1.0f, "%.2f", clamp_flags);
        ImGui::SliderFloat("shininess", &shading_.shininess, 1.0f, 512.0f, "%.0f", log_flags);
        ImGui::Checkbox("checker pattern", &shading_.checker);
        ui_strain_controls();
    }

    // ---- Physics
    // ------------------------------------------------------------------------------------------------
    ImGui::SetNextItemOpen(options_.panels_open, open_cond);
    if (ImGui::CollapsingHeader("Physics")) {
        const SimulationParams& p = s.params();
        float g[3] = {p.gravity[0], p.gravity[1], p.gravity[2]};
        if (ImGui::SliderFloat3("gravity", g, -50.0f, 50.0f, "%.2f", clamp_flags))
            s.set_gravity({g[0], g[1], g[2]});
        help_marker("m/s^2. Earth: (0, -9.81, 0).");
        bool wind = p.wind.enabled;
        float wind_strength = p.wind.strength;
        bool changed = ImGui::Checkbox("wind", &wind);
        ImGui::SameLine();
        ImGui::PushItemWidth(112.0f);
        changed |= ImGui::SliderFloat("##wind", &wind_strength, 0.0f, 100.0f, "%.1f m/s^2", log_flags);
        ImGui::PopItemWidth();
        if (changed) s.set_wind(wind, wind_strength);
        help_marker("Seed 000's analytic field: strength x (sin 10t, 0, |sin(z + 10t)|).");
        float drag = p.air_drag;
        if (ImGui::SliderFloat("air drag", &drag, 0.0f, 100.0f, "%.3f 1/s", log_flags)) s.set_air_drag(drag);
        int integrator = p.integrator == Integrator::verlet ? 1 : 0;
        const char* integrators[] = {"symplectic Euler", "Verlet"};
        if (ImGui::Combo("integrator", &integrator, integrators, 2))
            s.set_integrator(integrator == 1 ? Integrator::verlet : Integrator::symplectic_euler);
        bool limit_on = p.strain_limit.ratio > 0.0f;
        float limit_ratio = limit_on ? p.strain_limit.ratio : 0.1f;
        int limit_every = static_cast<int>(p.strain_limit.every);
        bool limit_changed = ImGui::Checkbox("strain limit", &limit_on);
        ImGui::SameLine();
        ImGui::PushItemWidth(112.0f);
        limit_changed |= ImGui::SliderFloat("##limit", &limit_ratio, 0.01f, 1.0f, "%.2f stretch", log_flags);
        ImGui::PopItemWidth();
        help_marker(
            "Provot 1995: springs stretched beyond (1 + ratio) x rest length are pulled back after the "
            "substep (4 passes over the colour groups).");
        if (limit_on)
            limit_changed |= ImGui::SliderInt("limit every", &limit_every, 1, 1000, "%d substeps", log_flags);
        if (limit_changed)
            s.set_strain_limit({limit_on ? limit_ratio : 0.0f, p.strain_limit.passes,
                                static_cast<std::uint32_t>(std::max(limit_every, 1))});
        float dt = p.dt;
        const float bound = static_cast<float>(s.dt_bound());
        if (ImGui::SliderFloat("dt", &dt, 1e-3f * bound, bound, "%.3e s", log_flags)) s.set_dt(dt);
        help_marker(
            "One substep. The slider ends at the explicit stability bound: an unstable dt cannot be chosen.");
        bool auto_dt = s.auto_dt();
        if (ImGui::Checkbox("auto dt (0.9 x bound)", &auto_dt)) s.set_auto_dt(auto_dt);
        ImGui::TextDisabled("stability bound %.3e s", double(bound));
        int substeps = s.substeps();
        if (ImGui::SliderInt("substeps/frame", &substeps, 1, view_max_substeps, "%d", log_flags))
            s.set_substeps(substeps);
        bool auto_sub = s.auto_substeps();
        if (ImGui::Checkbox("auto substeps", &auto_sub)) s.set_auto_substeps(auto_sub);
        help_marker("Automatic: enough substeps for 1/60 s of simulated time per frame, at most ~1e6 "
                    "particle-substeps per frame (and at least 10).");
        int threads = s.threads();
        if (ImGui::SliderInt("threads", &threads, 1, ViewSession::hardware_threads(), "%d", clamp_flags))
            s.set_threads(threads);
        ImGui::TextDisabled("%.2f ms simulated per frame", 1e3 * double(s.substeps()) * double(p.dt));
    }

    // ---- Lighting
    // -----------------------------------------------------------------------------------------------
    ImGui::SetNextItemOpen(options_.panels_open, open_cond);
    if (ImGui::CollapsingHeader("Lighting")) {
        float lp[3] = {shading_.light_position.x(), shading_.light_position.y(), shading_.light_position.z()};
        if (ImGui::SliderFloat3("light", lp, -10.0f, 10.0f, "%.2f", clamp_flags))
            shading_.light_position = {lp[0], lp[1], lp[2]};
        help_marker("Point light position, m.");
        ImGui::SliderFloat("intensity", &shading_.light_intensity, 0.0f, 4.0f, "%.2f", clamp_flags);
        ImGui::SliderFloat("ambient", &shading_.ambient, 0.0f, 1.0f, "%.2f", clamp_flags);
        ImGui::Checkbox("ground grid (G)", &show_ground_);
    }

    // ---- Camera
    // -------------------------------------------------------------------------------------------------
    ImGui::SetNextItemOpen(options_.panels_open, open_cond);
    if (ImGui::CollapsingHeader("Camera")) {
        if (ImGui::Button("Reset view (R)")) reset_camera();
        ImGui::SliderFloat("field of view", &camera_.fov_y_deg, 20.0f, 90.0f, "%.0f deg", clamp_flags);
        ImGui::Checkbox("pins and hover markers", &show_pins_);
        ImGui::Checkbox("draw every triangle", &full_mesh_);
        help_marker(
            "Off: grids finer than 256 x 256 are drawn through every k-th row and column (the simulation and "
            "the normals still use every particle). On: all triangles, slower in software GL.");
        if (renderer_->lod_stride() > 1)
            ImGui::TextDisabled("drawing every %u-th row: %s of %s triangles", renderer_->lod_stride(),
                                grouped(renderer_->triangle_count()).c_str(),
                                grouped(session_->sim().cloth().triangles.size() / 3).c_str());
        ImGui::TextDisabled("distance %.2f m, yaw %.0f deg, pitch %.0f deg", double(camera_.distance),
                            double(camera_.yaw) * 57.2958, double(camera_.pitch) * 57.2958);
    }
    ui_file_panel();
    ImGui::Separator();
    ImGui::TextDisabled("F1: keys and mouse   Tab: hide panels");
    ImGui::PopItemWidth();
    ImGui::End();
}

void Viewer::ui_overlay() {
    const ImGuiIO& io = ImGui::GetIO();
    ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x - 8.0f, 8.0f), ImGuiCond_Always, ImVec2(1.0f, 0.0f));
    ImGui::SetNextWindowBgAlpha(0.62f);
    ImGui::Begin("stats", nullptr,
                 ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoNav |
                     ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoMove |
                     ImGuiWindowFlags_NoInputs);
    const ViewSession& s = *session_;
    const Simulation& sim = s.sim();
    ImGui::Text("%.1f FPS   (%.2f ms / frame)", shown_fps_, shown_.frame);
    ImGui::Text("sim %.2f ms | publish %.2f ms | draw %.2f ms", shown_.sim, shown_.publish, shown_.draw);
    ImGui::Text("substeps/frame %d   dt %.3g s", s.substeps(), double(sim.params().dt));
    ImGui::Text("particles %s   springs %s", grouped(sim.cloth().particle_count).c_str(),
                grouped(sim.cloth().spring_count()).c_str());
    ImGui::Text("threads %d   max strain %.2f %%", s.threads(),
                100.0 * double(last_publish_.max_structural_strain));
    const double realtime =
        shown_.frame > 0.0 ? double(s.substeps()) * sim.params().dt / (shown_.frame * 1e-3) : 0.0;
    if (s.running())
        ImGui::TextColored(ImVec4(0.55f, 0.9f, 0.55f, 1.0f), "running   %.2fx real time", realtime);
    else
        ImGui::TextColored(ImVec4(1.0f, 0.8f, 0.3f, 1.0f), "paused (Space runs, N steps)");
    ImGui::TextDisabled("F1 help");
    ImGui::End();
}

void Viewer::ui_messages() {
    const ImGuiIO& io = ImGui::GetIO();
    const ViewSession& s = *session_;
    if (!s.error().empty()) {
        ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x * 0.5f, 60.0f), ImGuiCond_Always, ImVec2(0.5f, 0.0f));
        ImGui::SetNextWindowBgAlpha(0.92f);
        ImGui::Begin("simulation stopped", nullptr,
                     ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse);
        ImGui::PushTextWrapPos(520.0f);
        ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.4f, 1.0f), "%s", s.error().c_str());
        ImGui::PopTextWrapPos();
        ImGui::Text("The last finite state is shown.");
        if (ImGui::Button("Reset (Backspace)")) session_->reset();
        ImGui::End();
        return;
    }
    const Message& m = s.message();
    const double age = std::chrono::duration<double>(std::chrono::steady_clock::now() - m.when).count();
    if (m.text.empty() || age > 8.0) return;
    ImGui::SetNextWindowPos(
        ImVec2(io.DisplaySize.x * 0.5f + (show_ui_ ? 170.0f : 0.0f), io.DisplaySize.y - 12.0f),
        ImGuiCond_Always, ImVec2(0.5f, 1.0f));
    ImGui::SetNextWindowBgAlpha(0.75f);
    ImGui::Begin("status", nullptr,
                 ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize |
                     ImGuiWindowFlags_NoInputs | ImGuiWindowFlags_NoFocusOnAppearing |
                     ImGuiWindowFlags_NoNav);
    const ImVec4 colour = m.level == MessageLevel::error     ? ImVec4(1.0f, 0.45f, 0.4f, 1.0f)
                          : m.level == MessageLevel::warning ? ImVec4(1.0f, 0.8f, 0.3f, 1.0f)
                                                             : ImVec4(0.85f, 0.9f, 1.0f, 1.0f);
    ImGui::PushTextWrapPos(std::min(900.0f, io.DisplaySize.x - 380.0f));
    ImGui::TextColored(colour, "%s", m.text.c_str());
    ImGui::PopTextWrapPos();
    ImGui::End();
}

void Viewer::ui_help() {
    const ImGuiIO& io = ImGui::GetIO();
    ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x * 0.5f, io.DisplaySize.y * 0.5f), ImGuiCond_Always,
                            ImVec2(0.5f, 0.5f));
    ImGui::SetNextWindowBgAlpha(0.93f);
    ImGui::Begin("Keys and mouse (F1 closes)", &show_help_,
                 ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse);
    struct Row {
        const char* key;
        const char* what;
    };
    static const Row rows[] = {
        {"left drag on the cloth", "grab the particle under the cursor; it follows at its depth"},
        {"P (while dragging)", "pin the grabbed particle where it is; the mouse is free again"},
        {"P / Ctrl + left click", "pin or unpin the particle under the cursor"},
        {"left drag elsewhere", "orbit the camera"},
        {"right / middle / Shift+left drag", "pan"},
        {"wheel", "zoom"},
        {"arrows", "orbit"},
        {"W / S", "zoom in / out"},
        {"A / D, Q / E", "pan left / right, down / up"},
        {"R or Home", "reset the view"},
        {"Space", "run / pause"},
        {"N", "one frame of substeps (pauses)"},
        {"Backspace", "reset the cloth"},
        {"G", "ground grid on / off"},
        {"Tab", "panels on / off"},
        {"C", "strain colours on / off"},
        {"V", "record on / off (File panel: PNG frames or .mp4)"},
        {"F12", "screenshot drape_<time>.png"},
        {"Esc", "close this help / let go of the particle"},
        {"Ctrl+Q", "quit"},
    };
    if (ImGui::BeginTable("keys", 2, ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit)) {
        for (const Row& r : rows) {
            ImGui::TableNextRow();
            ImGui::TableSetColumnIndex(0);
            ImGui::TextColored(ImVec4(1.0f, 0.82f, 0.4f, 1.0f), "%s", r.key);
            ImGui::TableSetColumnIndex(1);
            ImGui::TextUnformatted(r.what);
        }
        ImGui::EndTable();
    }
    ImGui::Separator();
    ImGui::TextDisabled("Markers: amber = pinned, cyan = grabbed, white = under the cursor.");
    ImGui::End();
}

} // namespace drape::app
