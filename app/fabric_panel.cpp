// The Fabric panel's material part for the fabric model: a preset list, the fabric's figures in file units
// (g/m^2, N/m, micro-N*m, s; a committed change rebuilds the cloth in the background, continuing its motion) and
// what the engine derived from them (node mass, spring stiffness per kind), read-only.
#include <string>

#include <imgui.h>
#include <imgui_internal.h>

#include "drape/fabric.hpp"
#include "materials.hpp"
#include "view_app.hpp"

namespace drape::app {

namespace {

/// A number field that shows `current` and, once an edit is committed (Enter, Tab or a click elsewhere), returns
/// true with the typed value in `out` (a rebuild per keystroke would be wasted work).
bool commit_float(const char* label, float current, const char* format, float& out) {
    // By value: a pointer into ImGui's state storage dangles once another key is inserted (view_ui.cpp edit_float).
    ImGuiStorage* storage = ImGui::GetStateStorage();
    const ImGuiID id = ImGui::GetID(label), key = id ^ 0x2545f491u;
    float buffer = ImGui::GetActiveID() == id ? storage->GetFloat(key, current) : current; // between edits: the session's
    ImGui::InputFloat(label, &buffer, 0.0f, 0.0f, format);
    storage->SetFloat(key, buffer);
    out = buffer;
    return ImGui::IsItemDeactivatedAfterEdit() && buffer != current;
}

} // namespace

void Viewer::ui_fabric_material() {
    ViewSession& s = *session_;
    const FabricSettings& f = s.fabric();
    if (ImGui::BeginCombo("preset", f.fabric.name.c_str())) {
        for (const FabricPreset& p : fabric_presets()) {
            if (ImGui::Selectable(p.fabric.name.c_str(), p.fabric.name == f.fabric.name))
                s.set_fabric_preset(p.fabric.name);
            if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s\n%s", p.description.c_str(), p.source.c_str());
        }
        ImGui::EndCombo();
    }
    struct Field {
        const char* label;
        float Fabric::*member;
        double scale; // SI -> file units
        const char* format;
    };
    static const Field fields[] = {
        {"density g/m^2", &Fabric::density, fabric_gsm_per_kg_m2, "%.1f"},
        {"stretch u N/m", &Fabric::stretch_u, 1.0, "%.0f"},
        {"stretch v N/m", &Fabric::stretch_v, 1.0, "%.0f"},
        {"shear N/m", &Fabric::shear, 1.0, "%.2f"},
        {"bend u uN*m", &Fabric::bend_u, fabric_uNm_per_Nm, "%.4g"},
        {"bend v uN*m", &Fabric::bend_v, fabric_uNm_per_Nm, "%.4g"},
        {"damping s", &Fabric::damping, 1.0, "%.3g"},
    };
    for (const Field& fl : fields) {
        float typed = 0.0f;
        if (commit_float(fl.label, static_cast<float>(double(f.fabric.*fl.member) * fl.scale), fl.format, typed)) {
            Fabric next = f.fabric;
            next.*fl.member = static_cast<float>(double(typed) / fl.scale);
            s.set_fabric(next); // checked there: an out-of-range figure is refused naming its range
        }
    }
    ImGui::SameLine();
    ImGui::TextDisabled("(?)");
    if (ImGui::IsItemHovered())
        ImGui::SetTooltip("The fabric in physical units (docs/fabric.md): areal density, tensile stiffness per unit\n"
                          "width along u (warp) and v (weft), shear stiffness, bending rigidity per unit width,\n"
                          "Rayleigh damping. A committed value rebuilds the cloth in the background; the motion\n"
                          "continues. The same fabric behaves the same at every resolution.");
    // What the engine derived from the fabric and the mesh: the seeds' per-node mass and per-spring stiffness.
    const DerivedMaterial d = derive_material(s.sim().cloth());
    ImGui::TextDisabled("derived: node mass %.4g g", double(f.node_mass_g));
    for (std::size_t k = 0; k < 2; ++k) // structural, shear: per spring (boundary springs hold half)
        ImGui::TextDisabled("  %s k %.4g - %.4g N/m", spring_kind_name(static_cast<SpringKind>(k)),
                            double(d.spring_min[k]), double(d.spring_max[k]));
}

} // namespace drape::app
