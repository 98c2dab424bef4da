// The viewer's Dear ImGui panels: Run mode, Fabric, Physics, Lighting, Camera (seed 000's five), the stats
// overlay, the status line and the F1 key help. Every slider is clamped to the range of SPEC.md / the issue
// (typed values too: ImGuiSliderFlags_AlwaysClamp); changes go through ViewSession, which refuses or
// compensates unstable ones. A value typed into a slider (Ctrl+click) applies only when committed (Enter, Tab or a
// click elsewhere), never keystroke by keystroke; a refused value shows the current one again. While a cloth is
// being built in the background, the settings panels are read-only and a progress window shows the build.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <imgui.h>
#include <imgui_internal.h>

#include "drape/errors.hpp"
#include "drape/memory_estimate.hpp"
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

/// A slider that applies while dragged but, when a value is typed into it (Ctrl+click), only once the edit is
/// committed: the keystrokes on the way (2, 25, 250, 2500 for 25000) never apply. Between edits it shows
/// `current` (the session's value), so a refused value reverts. Returns true with `out` when a value is to apply.
bool edit_float(const char* label, float current, float lo, float hi, const char* format, ImGuiSliderFlags flags,
                float& out) {
    // The edit buffer lives in ImGui's state storage, read and written by value: a pointer into the storage
    // dangles as soon as another key is inserted (ASan: heap-use-after-free with the Physics panel open).
    ImGuiStorage* storage = ImGui::GetStateStorage();
    const ImGuiID id = ImGui::GetID(label), key = id ^ 0x5bd1e995u;
    float buffer = ImGui::GetActiveID() == id ? storage->GetFloat(key, current) : current;
    const bool changed = ImGui::SliderFloat(label, &buffer, lo, hi, format, flags);
    const bool typing = ImGui::TempInputIsActive(id);
    storage->SetFloat(key, buffer);
    out = buffer;
    if (changed && !typing) return true;                          // dragged: live
    return ImGui::IsItemDeactivatedAfterEdit() && buffer != current; // typed: on commit
}

/// The same for three-component sliders (gravity, wind velocity).
bool edit_float3(const char* label, const std::array<float, 3>& current, float lo, float hi, const char* format,
                 ImGuiSliderFlags flags, std::array<float, 3>& out) {
    ImGuiStorage* storage = ImGui::GetStateStorage(); // by value, as in edit_float
    const ImGuiID id = ImGui::GetID(label), active_key = id ^ 0x27d4eb2du;
    const bool was_active = storage->GetBool(active_key, false);
    float v[3];
    for (unsigned i = 0; i < 3; ++i) v[i] = was_active ? storage->GetFloat(id ^ (0x5bd1e995u + i), current[i]) : current[i];
    const bool changed = ImGui::SliderFloat3(label, v, lo, hi, format, flags);
    storage->SetBool(active_key, ImGui::IsItemActive());
    const bool typing = ImGui::TempInputIsActive(ImGui::GetActiveID());
    for (unsigned i = 0; i < 3; ++i) {
        storage->SetFloat(id ^ (0x5bd1e995u + i), v[i]);
        out[i] = v[i];
    }
    if (changed && !typing) return true;
    return ImGui::IsItemDeactivatedAfterEdit() && out != current;
}

/// The same for integer sliders.
bool edit_int(const char* label, int current, int lo, int hi, const char* format, ImGuiSliderFlags flags, int& out) {
    ImGuiStorage* storage = ImGui::GetStateStorage(); // by value, as in edit_float
    const ImGuiID id = ImGui::GetID(label), key = id ^ 0x5bd1e995u;
    int buffer = ImGui::GetActiveID() == id ? storage->GetInt(key, current) : current;
    const bool changed = ImGui::SliderInt(label, &buffer, lo, hi, format, flags);
    const bool typing = ImGui::TempInputIsActive(id);
    storage->SetInt(key, buffer);
    out = buffer;
    if (changed && !typing) return true;
    return ImGui::IsItemDeactivatedAfterEdit() && buffer != current;
}


} // namespace

void Viewer::build_ui() {
    if (show_ui_) {
        ui_panels();
        ui_overlay();
    }
    ui_tool_overlays();
    ui_messages();
    ui_build_progress();
    ui_confirmation();
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
    const ImGuiCond open_cond = ImGuiCond_Once;
    ImGui::SetNextItemOpen(true, open_cond);
    if (ImGui::CollapsingHeader("Run mode")) ui_run_mode();
    ImGui::SetNextItemOpen(true, open_cond);
    if (ImGui::CollapsingHeader("Fabric")) ui_fabric();
    ImGui::SetNextItemOpen(options_.panels_open, open_cond);
    if (ImGui::CollapsingHeader("Physics")) ui_physics();
    ImGui::SetNextItemOpen(options_.panels_open, open_cond);
    if (ImGui::CollapsingHeader("Lighting")) ui_lighting();
    ImGui::SetNextItemOpen(options_.panels_open, open_cond);
    if (ImGui::CollapsingHeader("Camera")) ui_camera();
    ui_file_panel();
    ImGui::Separator();
    ImGui::TextDisabled("F1: keys and mouse   Tab: hide panels");
    ImGui::PopItemWidth();
    ImGui::End();
}

void Viewer::ui_run_mode() {
    ViewSession& s = *session_;
    if (ImGui::Button(s.running() ? "Pause" : "Run", ImVec2(70, 0))) s.set_running(!s.running());
    ImGui::SameLine();
    if (ImGui::Button("Step", ImVec2(70, 0))) s.step_once();
    ImGui::SameLine();
    if (ImGui::Button("Reset", ImVec2(70, 0))) s.reset();
    ImGui::BeginDisabled(!s.can_undo());
    if (ImGui::Button("Undo", ImVec2(70, 0))) s.undo();
    ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::BeginDisabled(!s.can_redo() || s.building());
    if (ImGui::Button("Redo", ImVec2(70, 0))) s.redo();
    ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::TextDisabled("Ctrl+Z / Ctrl+Y");
    static const std::vector<std::string> names = builtin_scene_names();
    const std::string& current = s.scene().name;
    if (ImGui::BeginCombo("scene", current.c_str())) {
        for (const std::string& n : names)
            if (ImGui::Selectable(n.c_str(), n == current)) s.set_scene(n);
        ImGui::EndCombo();
    }
    help_marker(s.scene().description.c_str());
    ui_scene_file();
    const bool grid = s.grid_scene();
    if (s.resizable()) {
        ImGui::SliderInt(grid ? "grid size N" : "cells per metre", &ui_size_,
                         static_cast<int>(grid ? view_min_size : view_min_cells),
                         static_cast<int>(grid ? view_max_size : view_max_cells), "%d", log_flags);
        if (ImGui::IsItemDeactivatedAfterEdit()) s.set_size(static_cast<std::uint32_t>(ui_size_));
        if (!ImGui::IsItemActive() && ui_size_ != static_cast<int>(s.size())) ui_size_ = static_cast<int>(s.size());
        help_marker(s.scene().cloth == ClothType::outline
                        ? "The outline's spacing is 1 / (cells per metre). Applied when the slider is released: the "
                          "cloth is rebuilt in the background, in its starting state with the same areal density "
                          "and materials; the old one runs until the new one is ready."
                        : "Applied when the slider is released: the cloth is rebuilt in the background, in its "
                          "starting state with the same total mass and materials; the old one runs until the new "
                          "one is ready.");
        if (!grid) ImGui::TextDisabled("  spacing %.4g mm", 1000.0 * double(s.spacing()));
    } else {
        // A mesh's resolution is its OBJ's, a mask cloth's its masks' cells: no slider, the figure instead.
        ImGui::Text("%s %.4g mm", s.scene().cloth == ClothType::mask ? "mask cell" : "mean edge",
                    1000.0 * double(s.spacing()));
        help_marker(s.scene().cloth == ClothType::mask
                        ? "A mask cloth's resolution is its masks' cells (cloth.panels[k].cell_size, the smallest "
                          "shown): edit the scene file to change it."
                        : "A mesh's resolution is that of its OBJ file.");
    }
    ImGui::Text("%s particles, %s springs", grouped(s.sim().cloth().particle_count).c_str(),
                grouped(s.sim().cloth().spring_count()).c_str());
    ImGui::Text("simulated %.3f s  (%s %s)", s.sim().time(), grouped(s.sim().steps_done()).c_str(),
                s.solver() == Solver::implicit ? "steps" : "substeps");
}

void Viewer::ui_scene_file() {
    ImGui::PushItemWidth(230.0f);
    const bool enter = ImGui::InputTextWithHint("##scene file", "scene file (.json) or drop one here",
                                                scene_path_.data(), scene_path_.size(),
                                                ImGuiInputTextFlags_EnterReturnsTrue);
    ImGui::PopItemWidth();
    ImGui::SameLine();
    const bool open = ImGui::Button("Open");
    if ((enter || open) && scene_path_[0] != '\0') session_->set_scene(scene_path_.data());
    help_marker("Opens any scene file (docs/scene_format.md): typed here (Enter or Open) or dropped on the window. "
                "It is built in the background; a file with an error is refused with its message and the current "
                "scene stays.");
}

void Viewer::ui_fabric() {
    ViewSession& s = *session_;
    ImGui::BeginDisabled(s.building());
    int model = s.fabric().model == MaterialModel::fabric ? 0 : 1;
    if (ImGui::Combo("model", &model, "fabric\0springs\0"))
        s.set_material_model(model == 0 ? MaterialModel::fabric : MaterialModel::springs);
    help_marker("fabric: a material in physical units (presets from published measurements, docs/fabric.md); the "
                "engine derives the node mass and springs from it and the mesh. springs: the seeds' model, node mass "
                "and per-spring stiffness set directly.");
    if (s.fabric().model == MaterialModel::fabric) {
        ui_fabric_material();
        if (s.has_seams()) // derived from the fabric like the membrane springs (docs/fabric.md "Triangle meshes")
            ImGui::TextDisabled("  seam k %.4g N/m", double(s.fabric().stiffness[3]));
    } else {
        ui_spring_material();
    }
    ImGui::EndDisabled();
    ui_fabric_looks();
}

void Viewer::ui_spring_material() {
    ViewSession& s = *session_;
    ImGui::SliderFloat("node mass", &ui_node_mass_, view_min_node_mass_g, view_max_node_mass_g, "%.4f g", log_flags);
    if (ImGui::IsItemDeactivatedAfterEdit()) s.set_node_mass(ui_node_mass_);
    if (!ImGui::IsItemActive()) ui_node_mass_ = s.fabric().node_mass_g;
    help_marker("Mass of one particle, 0.001-1 g (seed 000). Applied on release (rebuilt in the background); the "
                "motion continues.");
    static const char* kinds[] = {"structural k", "shear k", "bend k", "seam k"};
    for (std::size_t k = 0; k < spring_kind_count; ++k) {
        if (static_cast<SpringKind>(k) == SpringKind::seam && !s.has_seams()) continue;
        float v = 0.0f;
        if (edit_float(kinds[k], s.fabric().stiffness[k], view_min_stiffness, view_max_stiffness, "%.0f N/m",
                       log_flags, v))
            s.set_stiffness(static_cast<SpringKind>(k), v);
    }
    float damping = 0.0f;
    if (edit_float("damping", s.fabric().damping_ratio, 0.0f, 1.0f, "%.3f", clamp_flags, damping))
        s.set_damping_ratio(damping);
    help_marker("Spring damping as a fraction of the critical damping of one spring.");
}

void Viewer::ui_fabric_looks() {
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

void Viewer::ui_physics() {
    ViewSession& s = *session_;
    ImGui::BeginDisabled(s.building());
    const SimulationParams& p = s.params();
    std::array<float, 3> g{};
    if (edit_float3("gravity", p.gravity, -50.0f, 50.0f, "%.2f", clamp_flags, g)) s.set_gravity(g);
    help_marker("m/s^2. Earth: (0, -9.81, 0).");
    bool wind = p.wind.enabled;
    float wind_strength = p.wind.strength;
    bool changed = ImGui::Checkbox("wind", &wind);
    ImGui::SameLine();
    ImGui::PushItemWidth(112.0f);
    changed |= edit_float("##wind", p.wind.strength, 0.0f, 100.0f, "%.1f m/s^2", log_flags, wind_strength);
    ImGui::PopItemWidth();
    if (changed) s.set_wind(wind, wind_strength);
    help_marker("Seed 000's analytic field: strength x (sin 10t, 0, |sin(z + 10t)|).");
    ui_aero();
    ui_solver();
    float drag = 0.0f;
    if (edit_float("air drag", p.air_drag, 0.0f, 100.0f, "%.3f 1/s", log_flags, drag)) s.set_air_drag(drag);
    const bool implicit = p.solver == Solver::implicit;
    ImGui::BeginDisabled(implicit);
    int integrator = p.integrator == Integrator::verlet ? 1 : 0;
    const char* integrators[] = {"symplectic Euler", "Verlet"};
    if (ImGui::Combo("integrator", &integrator, integrators, 2))
        s.set_integrator(integrator == 1 ? Integrator::verlet : Integrator::symplectic_euler);
    ImGui::EndDisabled();
    if (implicit) help_marker("The explicit solver's choice; the implicit solver keeps velocities (Euler).");
    bool limit_on = p.strain_limit.ratio > 0.0f;
    float limit_ratio = limit_on ? p.strain_limit.ratio : 0.1f;
    int limit_every = static_cast<int>(p.strain_limit.every);
    bool limit_changed = ImGui::Checkbox("strain limit", &limit_on);
    ImGui::SameLine();
    ImGui::PushItemWidth(112.0f);
    limit_changed |= edit_float("##limit", limit_ratio, 0.01f, 1.0f, "%.2f stretch", log_flags, limit_ratio);
    ImGui::PopItemWidth();
    help_marker("Provot 1995: springs stretched beyond (1 + ratio) x rest length are pulled back after the "
                "substep (4 passes over the colour groups).");
    if (limit_on)
        limit_changed |= edit_int("limit every", limit_every, 1, 1000, "%d substeps", log_flags, limit_every);
    if (limit_changed)
        s.set_strain_limit({limit_on ? limit_ratio : 0.0f, p.strain_limit.passes,
                            static_cast<std::uint32_t>(std::max(limit_every, 1))});
    bool self_on = p.self_collision.thickness > 0.0f;
    float self_mm = self_on ? 1e3f * p.self_collision.thickness : 4.0f;
    bool self_changed = ImGui::Checkbox("self-collision", &self_on);
    ImGui::SameLine();
    ImGui::PushItemWidth(112.0f);
    self_changed |= edit_float("##self", self_mm, 1e3f * self_collision_min_thickness,
                               1e3f * self_collision_max_thickness, "%.1f mm", log_flags, self_mm);
    ImGui::PopItemWidth();
    help_marker("Cloth against cloth (docs/self_collision.md): points and edges closer than this thickness are pushed "
                "apart, once something moved a quarter of it. Costly (tens of times an explicit substep). With the "
                "implicit solver a step in which cloth touched cloth is solved again as 4 sub-steps (sub-stepped); a "
                "sub-step that pushed is solved again with the contacts held (re-solves).");
    if (self_changed) s.set_self_collision(self_on ? 1e-3f * self_mm : 0.0f);
    if (self_on)
        ImGui::TextDisabled("%s contacts at its last run, %s runs%s%s%s%s", grouped(s.sim().self_contacts()).c_str(),
                            grouped(s.sim().self_collision_runs()).c_str(), implicit ? ", sub-stepped " : "",
                            implicit ? grouped(s.sim().self_collision_substepped()).c_str() : "",
                            implicit ? ", re-solves " : "",
                            implicit ? grouped(s.sim().self_collision_resolves()).c_str() : "");
    float dt = 0.0f;
    const float bound = static_cast<float>(s.dt_bound());
    if (implicit) {
        if (edit_float("dt (step)", p.dt, float(view_implicit_min_dt), float(view_implicit_max_dt), "%.4f s",
                       log_flags, dt))
            s.set_dt(dt);
        help_marker("One implicit step: any length is stable (1/60 s: one step per frame at 60 FPS is real time; "
                    "1/30 s at 30 FPS). With self-collision off, a step whose strain limit cannot hold the stretch "
                    "is solved again as shorter sub-steps, each split again while it still ends over the limit "
                    "(split for the limit).");
        if (p.self_collision.thickness > 0.0f)
            ImGui::TextDisabled("%.0f x the explicit bound %.3e s (no split for the limit with self-collision)",
                                double(p.dt) / double(bound), double(bound));
        else
            ImGui::TextDisabled("%.0f x the explicit bound %.3e s, %s split for the limit",
                                double(p.dt) / double(bound), double(bound),
                                grouped(s.sim().strain_substepped()).c_str());
    } else {
        if (edit_float("dt", p.dt, 1e-3f * bound, bound, "%.3e s", log_flags, dt)) s.set_dt(dt);
        help_marker("One substep. The slider ends at the explicit stability bound: an unstable dt cannot be chosen.");
        bool auto_dt = s.auto_dt();
        if (ImGui::Checkbox("auto dt (0.9 x bound)", &auto_dt)) s.set_auto_dt(auto_dt);
        ImGui::TextDisabled("stability bound %.3e s", double(bound));
    }
    int substeps = 0;
    if (edit_int(implicit ? "steps/frame" : "substeps/frame", s.substeps(), 1, view_max_substeps, "%d", log_flags,
                 substeps))
        s.set_substeps(substeps);
    bool auto_sub = s.auto_substeps();
    if (ImGui::Checkbox(implicit ? "auto steps" : "auto substeps", &auto_sub)) s.set_auto_substeps(auto_sub);
    if (implicit)
        help_marker("Automatic: 1/60 s of simulated time per frame in whole steps (one step per frame for any dt "
                    "from 1/90 s up), at most 8.");
    else
        help_marker("Automatic: enough substeps for 1/60 s of simulated time per frame, at most ~1e6 "
                    "particle-substeps per frame (and at least 10).");
    ImGui::EndDisabled();
    // Workers: a task arena of exactly this many (also above the core count).
    int threads = 0;
    if (edit_int("threads", s.threads(), 1, std::max(8, ViewSession::hardware_threads()), "%d", clamp_flags,
                 threads))
        s.set_threads(threads);
    help_marker("Worker threads that run the substeps and the output stage (a oneTBB arena of exactly this many; "
                "more than the cores is allowed). Results are the same for every count.");
    ImGui::TextDisabled("%.2f ms simulated per frame", 1e3 * double(s.substeps()) * double(p.dt));
}

void Viewer::ui_solver() {
    ViewSession& s = *session_;
    const SimulationParams& p = s.params();
    int solver = p.solver == Solver::implicit ? 1 : 0;
    if (ImGui::Combo("solver", &solver, "explicit\0implicit\0"))
        s.set_solver(solver == 1 ? Solver::implicit : Solver::explicit_euler);
    help_marker("explicit: the seeds' substeps, each below the stability bound (cost grows like N^3 per simulated "
                "second). implicit: backward Euler by vertex block descent (docs/implicit.md), one step per frame "
                "whatever the resolution or stiffness; switching to it sets the integrator to symplectic Euler.");
    if (p.solver != Solver::implicit) return;
    ImGui::Indent();
    int iterations = 0;
    if (edit_int("iterations", static_cast<int>(s.max_iterations()), 1, 1000, "%d", log_flags, iterations))
        s.set_max_iterations(static_cast<std::uint32_t>(iterations));
    help_marker("Sweeps of vertex block descent per step, the most: more converge further (stiffer, less sag), "
                "fewer run faster.");
    float rho = 0.0f;
    if (edit_float("Chebyshev rho", p.implicit.chebyshev_rho, 0.0f, 0.99f, "%.2f", clamp_flags, rho))
        s.set_chebyshev_rho(rho);
    help_marker("Chebyshev acceleration of the sweeps (Wang 2015): the estimate of the sweep's spectral radius; 0 = "
                "off.");
    bool multilevel = p.implicit.multilevel;
    if (ImGui::Checkbox("multilevel guess", &multilevel)) s.set_multilevel(multilevel);
    help_marker("Grid and outline cloths of the fabric model: each step starts from the same step solved on coarser "
                "copies of the cloth, so a "
                "hanging cloth falls and settles in a few sweeps. Against colliders the coarse grids leave the cloth "
                "where it touches them to its own sweeps, so keep it on for cloth lying on a collider too.");
    bool at_rest = p.implicit.fas_at_rest;
    if (ImGui::Checkbox("FAS at rest", &at_rest)) s.set_fas_at_rest(at_rest);
    help_marker("With the multilevel guess: once the cloth's rms speed has stayed below 0.15 g dt for 10 steps, the "
                "coarse levels answer the cloth's own force residual (full approximation scheme, brought in over 30 "
                "steps) until it exceeds 2 g dt or is not at rest 30 steps later, so a cloth at rest settles at its "
                "own equilibrium, not the coarse grids' (which hang it a few millimetres too high). Never with "
                "colliders, self-collision, wind or a grab. Above 150 x 150 it needs more than 10 iterations; "
                "with fewer it gives up after two tries.");
    bool budget = s.iteration_budget();
    if (ImGui::Checkbox("iteration budget", &budget)) s.set_iteration_budget(budget);
    ImGui::SameLine();
    ImGui::PushItemWidth(90.0f);
    float budget_ms = 0.0f;
    if (edit_float("##budget", float(s.sim_budget_ms()), 1.0f, 100.0f, "%.0f ms", log_flags, budget_ms))
        s.set_sim_budget_ms(budget_ms);
    ImGui::PopItemWidth();
    help_marker("Keeps the frame rate: when a frame's simulation takes longer than this, the iterations per step "
                "are lowered (down to 4), and raised again (up to the slider's) when there is room.");
    const ImplicitStats& st = s.sim().implicit_stats();
    ImGui::Text("running %u of %u iterations%s", s.iterations(), s.max_iterations(),
                s.iteration_budget() && s.iterations() < s.max_iterations() ? " (budget)" : "");
    ImGui::TextDisabled("last step: %u iterations, residual %.2e", st.iterations, st.relative_residual);
    ImGui::Unindent();
}

void Viewer::ui_aero() {
    ViewSession& s = *session_;
    AeroWind a = s.params().aero;
    bool changed = ImGui::Checkbox("aero wind", &a.enabled);
    help_marker("Aerodynamic wind per triangle (seed 004): F = -1/2 rho C_d A |v_rel| (v_rel . n) n, v_rel the "
                "triangle's velocity less the wind's. Density 0-100 kg/m^3, C_d 0-10, |v| <= 100 m/s. dt follows "
                "the stability bound like any other physics change.");
    if (!a.enabled) return;
    ImGui::Indent();
    const AeroWind& cur = s.params().aero;
    changed |= edit_float("air density", cur.density, 0.0f, 100.0f, "%.2f kg/m^3", log_flags, a.density);
    changed |= edit_float("drag coeff. C_d", cur.drag_coefficient, 0.0f, 10.0f, "%.2f", clamp_flags,
                          a.drag_coefficient);
    changed |= edit_float3("wind velocity", cur.velocity, -100.0f, 100.0f, "%.1f", clamp_flags, a.velocity);
    ImGui::TextDisabled("m/s; speed %.1f m/s", double(std::hypot(cur.velocity[0], cur.velocity[1], cur.velocity[2])));
    ImGui::Unindent();
    if (changed) s.set_aero(a);
}

void Viewer::ui_lighting() {
    float lp[3] = {shading_.light_position.x(), shading_.light_position.y(), shading_.light_position.z()};
    if (ImGui::SliderFloat3("light", lp, -10.0f, 10.0f, "%.2f", clamp_flags))
        shading_.light_position = {lp[0], lp[1], lp[2]};
    help_marker("Point light position, m.");
    ImGui::SliderFloat("intensity", &shading_.light_intensity, 0.0f, 4.0f, "%.2f", clamp_flags);
    ImGui::SliderFloat("ambient", &shading_.ambient, 0.0f, 1.0f, "%.2f", clamp_flags);
    ImGui::Checkbox("ground grid (G)", &show_ground_);
}

void Viewer::ui_camera() {
    if (ImGui::Button("Reset view (R)")) reset_camera();
    ImGui::SliderFloat("field of view", &camera_.fov_y_deg, 20.0f, 90.0f, "%.0f deg", clamp_flags);
    bool markers = session_->show_markers();
    if (ImGui::Checkbox("pins and hover markers", &markers)) session_->set_show_markers(markers);
    ImGui::Checkbox("draw every triangle", &full_mesh_);
    help_marker("Off: grids finer than 256 x 256 are drawn through every k-th row and column (the simulation and "
                "the normals still use every particle). On: all triangles, slower in software GL.");
    if (renderer_->lod_stride() > 1)
        ImGui::TextDisabled("drawing every %u-th row: %s of %s triangles", renderer_->lod_stride(),
                            grouped(renderer_->triangle_count()).c_str(),
                            grouped(session_->sim().cloth().triangles.size() / 3).c_str());
    ImGui::Checkbox("light every pixel", &pixel_lighting_);
    help_marker("Off: a cloth whose drawn triangles are under 4 pixels across on screen is lit at its vertices "
                "(the same colours, interpolated; much cheaper in software GL). On: lit per pixel at any size.");
    ImGui::TextDisabled("triangles %.1f px across: lit per %s", double(renderer_->drawn_edge_px()),
                        renderer_->lit_per_vertex() ? "vertex" : "pixel");
    if (options_.overlap && !options_.demo_grab) { // (--demo-grab acts through the session every frame)
        ImGui::Checkbox("draw between long steps", &interpolate_);
        help_marker("On: while a step takes longer than a frame, the frames in between draw the blend of the last two "
                    "states (one step behind the simulation), paced to the rate below; in software GL each drawn frame "
                    "takes CPU from the simulation. Off: every frame waits for its step (--no-interpolate).");
        if (interpolate_)
            ImGui::SliderInt("frames/s between steps", &options_.blend_fps, 10, 240, "%d", clamp_flags);
    }
    ImGui::TextDisabled("distance %.2f m, yaw %.0f deg, pitch %.0f deg", double(camera_.distance),
                        double(camera_.yaw) * 57.2958, double(camera_.pitch) * 57.2958);
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
    // (With the overlap, the default, sim runs beside the draw: the frame takes about the larger of the two.)
    ImGui::Text("sim %.2f ms | publish %.2f ms | draw %.2f ms", shown_.sim, shown_.publish, shown_.draw);
    const bool implicit = sim.params().solver == Solver::implicit;
    ImGui::Text("%s/frame %d   dt %.3g s", implicit ? "implicit steps" : "substeps", s.substeps(),
                double(sim.params().dt));
    if (interpolator_.frames_per_step() > 1.05)
        ImGui::Text("a step spans %.1f frames (drawn blended)", interpolator_.frames_per_step());
    if (implicit)
        ImGui::Text("iterations %u%s   residual %.2e", sim.implicit_stats().iterations,
                    s.iteration_budget() && s.iterations() < s.max_iterations() ? " (budget)" : "",
                    sim.implicit_stats().relative_residual);
    ImGui::Text("particles %s   springs %s", grouped(sim.cloth().particle_count).c_str(),
                grouped(sim.cloth().spring_count()).c_str());
    ImGui::Text("threads %d   max strain %.2f %%", s.threads(),
                100.0 * double(last_publish_.max_structural_strain));
    if (s.running())
        ImGui::TextColored(ImVec4(0.55f, 0.9f, 0.55f, 1.0f), "running   %.2fx real time", shown_real_time_);
    else
        ImGui::TextColored(ImVec4(1.0f, 0.8f, 0.3f, 1.0f), "paused (Space runs, N steps)");
    ImGui::TextDisabled("F1 help");
    ImGui::End();
}

void Viewer::ui_error_banner() {
    // The simulation stopped: a non-finite value or an explosion (the health monitor's BlowUpError). The cloth is
    // not drawn; this banner says what happened and offers the way back.
    const ImGuiIO& io = ImGui::GetIO();
    ViewSession& s = *session_;
    const bool blow_up = s.error_code() == exit_code::blow_up;
    ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x * 0.5f + (show_ui_ ? 170.0f : 0.0f), io.DisplaySize.y * 0.35f),
                            ImGuiCond_Always, ImVec2(0.5f, 0.5f));
    ImGui::SetNextWindowBgAlpha(0.95f);
    ImGui::PushStyleColor(ImGuiCol_WindowBg, ImVec4(0.28f, 0.06f, 0.06f, 0.95f));
    ImGui::Begin(blow_up ? "The cloth exploded - simulation paused" : "Simulation stopped: non-finite value",
                 nullptr, ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoMove);
    ImGui::PushTextWrapPos(560.0f);
    ImGui::TextColored(ImVec4(1.0f, 0.75f, 0.7f, 1.0f), "%s", s.error().c_str());
    ImGui::Spacing();
    ImGui::TextUnformatted(blow_up ? "The cloth is hidden instead of drawing the explosion. Reset restarts the scene "
                                     "with the current settings; Undo restores the settings before the last change "
                                     "and restarts."
                                   : "The cloth is hidden. Reset restarts the scene with the current settings; Undo "
                                     "restores the settings before the last change and restarts.");
    ImGui::PopTextWrapPos();
    if (ImGui::Button("Reset (Backspace)")) s.reset();
    ImGui::SameLine();
    ImGui::BeginDisabled(!s.can_undo());
    if (ImGui::Button("Undo last change (Ctrl+Z)")) s.undo();
    ImGui::EndDisabled();
    ImGui::End();
    ImGui::PopStyleColor();
}

void Viewer::ui_build_progress() {
    const std::optional<BuildStatus> b = session_->build_status();
    if (!b) return;
    const ImGuiIO& io = ImGui::GetIO();
    // Centred in the free area, below the stats overlay.
    ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x * 0.5f + (show_ui_ ? 170.0f : 0.0f), 170.0f), ImGuiCond_Always,
                            ImVec2(0.5f, 0.0f));
    ImGui::SetNextWindowBgAlpha(0.9f);
    ImGui::Begin("building", nullptr,
                 ImGuiWindowFlags_NoDecoration | ImGuiWindowFlags_AlwaysAutoResize | ImGuiWindowFlags_NoMove |
                     ImGuiWindowFlags_NoFocusOnAppearing | ImGuiWindowFlags_NoNav);
    ImGui::Text("building %s particles (%s, needs %s)...", grouped(b->particles).c_str(), b->what.c_str(),
                format_bytes(b->bytes).c_str());
    // No progress figure comes from the build: an animated bar with the time so far.
    const float phase = static_cast<float>(std::fmod(b->seconds, 1.2) / 1.2);
    ImGui::ProgressBar(phase, ImVec2(360.0f, 0.0f), "");
    ImGui::SameLine();
    ImGui::Text("%.1f s", b->seconds);
    ImGui::TextDisabled(b->queued ? "a newer request waits: this result will be discarded"
                                  : "the current cloth stays until the new one is ready");
    if (ImGui::Button("Cancel")) session_->cancel_build();
    ImGui::End();
}

void Viewer::ui_confirmation() {
    const std::optional<Confirmation>& c = session_->confirmation();
    if (!c) return;
    if (!ImGui::IsPopupOpen("Large cloth")) ImGui::OpenPopup("Large cloth");
    const ImGuiIO& io = ImGui::GetIO();
    ImGui::SetNextWindowPos(ImVec2(io.DisplaySize.x * 0.5f, io.DisplaySize.y * 0.4f), ImGuiCond_Always,
                            ImVec2(0.5f, 0.5f));
    if (ImGui::BeginPopupModal("Large cloth", nullptr, ImGuiWindowFlags_AlwaysAutoResize)) {
        ImGui::Text("%s builds %s particles and needs about %s of memory.", c->what.c_str(),
                    grouped(c->particles).c_str(), format_bytes(c->bytes).c_str());
        if (c->available != SIZE_MAX)
            ImGui::Text("Available now: %s. The build runs in the background; the window stays responsive, but "
                        "each frame will be slow.",
                        format_bytes(c->available).c_str());
        bool close = false;
        if (ImGui::Button("Build it")) {
            session_->confirm_build(true);
            close = true;
        }
        ImGui::SameLine();
        if (ImGui::Button("Cancel") || ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape))) {
            session_->confirm_build(false);
            close = true;
        }
        if (close) ImGui::CloseCurrentPopup();
        ImGui::EndPopup();
    }
}

void Viewer::ui_messages() {
    const ImGuiIO& io = ImGui::GetIO();
    const ViewSession& s = *session_;
    if (!s.error().empty()) {
        ui_error_banner();
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
        {"Backspace", "reset the cloth (not while a field is being edited)"},
        {"Ctrl+Z", "undo the last parameter change (or cancel a build in progress)"},
        {"Ctrl+Shift+Z / Ctrl+Y", "redo"},
        {"drop a .json file", "open it as the scene"},
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
