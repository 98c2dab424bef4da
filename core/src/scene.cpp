// Scene files: reading them into a SceneSpec (every field typed and range-checked, unknown fields refused, messages
// naming the file and the JSON path; the JSON reader is scene_json.cpp), loading built-in scenes and files, and a
// scene's resolution. Cooking a SceneSpec into a cloth plus simulation parameters is scene_build.cpp.
#include "drape/scene.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <filesystem>
#include <optional>
#include <cstdio>
#include <cstring>
#include <memory>
#include <set>

#include "drape/bending.hpp"
#include "drape/errors.hpp"

#include "mask_frame.hpp"
#include "scene_json.hpp"

namespace drape {

// Generated at build time from scenes/*.json (cmake/embed_scenes.cmake).
extern const char* const builtin_scene_json[];
extern const char* const builtin_scene_json_names[];
extern const std::size_t builtin_scene_json_count;

namespace {

/// Fabric model, mesh cloth: a warning when the OBJ is not flat (the hinge bending assumes a flat rest shape).
void warn_curved_mesh(SceneSpec& s) {
    if (s.model != MaterialModel::fabric || s.cloth != ClothType::mesh || !s.mesh.mesh) return;
    const TriangleMesh& m = *s.mesh.mesh;
    const std::vector<float> x(m.x.begin(), m.x.end()), y(m.y.begin(), m.y.end()), z(m.z.begin(), m.z.end());
    const double angle = hinge_rest_angle_max(x, y, z, m.triangles) * 180.0 / 3.14159265358979323846;
    if (angle > 1.0)
        s.warnings.push_back(s.source + ": cloth.file: the mesh is not flat (neighbouring triangles meet at up to " +
                             format_number(angle) +
                             " degrees); the fabric model's bending (Bergou et al. 2006) takes the flat sheet as "
                             "its rest shape, so curved parts of the mesh are pulled towards flat");
}

ColliderSurface read_surface(ObjectReader& r) {
    ColliderSurface s;
    s.thickness = static_cast<float>(r.number("thickness", 0.0, 1.0, " m", s.thickness));
    s.friction = static_cast<float>(r.number("friction", 0.0, 1.0, "", s.friction));
    return s;
}

Collider read_collider(ObjectReader& r) {
    const std::string type = r.text("type", {"ground", "plane", "sphere", "disc", "capsule", "ellipsoid"}, "");
    if (type.empty()) r.fail(r.at("type"), "is required (\"ground\", \"plane\", \"sphere\", \"disc\", \"capsule\", \"ellipsoid\")");
    const ColliderSurface surface = read_surface(r);
    Collider c;
    try {
        if (type == "ground") {
            c = make_ground(static_cast<float>(r.number("height", -1000.0, 1000.0, " m", 0.0)), surface);
        } else if (type == "plane") {
            c = make_plane(r.vec3("point", 1000.0, " m", {0, 0, 0}), r.vec3("normal", 1.0, "", {0, 1, 0}), surface);
        } else if (type == "sphere") {
            c = make_sphere(r.vec3("centre", 1000.0, " m", {0, 0, 0}),
                            static_cast<float>(r.number("radius", 1e-4, 1000.0, " m", 0.3)), surface);
        } else if (type == "disc") {
            c = make_disc(r.vec3("top_centre", 1000.0, " m", {0, 0, 0}),
                          static_cast<float>(r.number("radius", 1e-4, 1000.0, " m", 0.15)),
                          static_cast<float>(r.number("height", 1e-4, 1000.0, " m", 0.02)), surface);
        } else if (type == "capsule") {
            c = make_capsule(r.vec3("a", 1000.0, " m", {-0.3f, 0, 0}), r.vec3("b", 1000.0, " m", {0.3f, 0, 0}),
                             static_cast<float>(r.number("radius", 1e-4, 1000.0, " m", 0.1)), surface);
        } else {
            c = make_ellipsoid(r.vec3("centre", 1000.0, " m", {0, 0, 0}), r.vec3("semi_axes", 1000.0, " m", {0.3f, 0.2f, 0.2f}),
                               surface);
        }
    } catch (const FieldError&) {
        throw;
    } catch (const InvalidInput& e) {
        r.fail(r.at("type") + " \"" + type + "\":", e.what());
    }
    r.finish();
    return c;
}


/// cloth.type = "mesh": the fields, then the OBJ file (read here, so a broken file is an input error at load).
void read_mesh_cloth(ObjectReader& cloth, const std::string& base_dir, SceneSpec& s) {
    MeshClothSpec& m = s.mesh;
    const std::string file = cloth.text("file", {}, "");
    if (file.empty()) cloth.fail(cloth.at("file"), "is required: the OBJ file, relative to the scene file's directory");
    m.density = static_cast<float>(cloth.number("density", 1e-3, 10.0, " kg/m^2", m.density));
    m.scale = static_cast<float>(cloth.number("scale", 1e-4, 1e4, "", m.scale));
    m.centre = cloth.vec3("centre", 1000.0, " m", m.centre);
    const std::filesystem::path resolved =
        (base_dir.empty() ? std::filesystem::path(file) : std::filesystem::path(base_dir) / file).lexically_normal();
    try {
        m.mesh = std::make_shared<const TriangleMesh>(load_obj_mesh(resolved.string()));
    } catch (const InvalidInput& e) {
        cloth.fail(cloth.at("file") + " \"" + file + "\":", e.what());
    }
    m.file = std::filesystem::absolute(resolved).lexically_normal().string();
    const std::size_t vertices = m.mesh->obj_vertices();
    if (cloth.has_array("pins")) {
        const json* list = cloth.array("pins", vertices);
        m.pins = MeshPins::list;
        for (std::size_t k = 0; k < list->size(); ++k) {
            const json& v = (*list)[k];
            const std::string where = cloth.at("pins") + "[" + std::to_string(k) + "]";
            if (!v.is_number_unsigned() || v.get<std::uint64_t>() >= vertices)
                cloth.fail(where, "must be an OBJ vertex index in [0, " + std::to_string(vertices - 1) +
                                      "] (0-based, file order)");
            const auto i = v.get<std::uint32_t>();
            if (m.mesh->particle_of_vertex[i] < 0)
                cloth.fail(where, "= " + std::to_string(i) + " is a vertex in no triangle (dropped from the cloth)");
            m.pin_vertices.push_back(i);
        }
    } else {
        const std::string pins = cloth.text("pins", {"none", "top"}, "none");
        m.pins = pins == "top" ? MeshPins::top : MeshPins::none;
    }
    const std::string note = m.mesh->cleaning_note();
    if (!note.empty()) s.warnings.push_back(cloth.source() + ": cloth.file \"" + file + "\": " + note);
}

/// "[row, column]" of a mask cell, for messages.
std::string cell_text(std::int64_t row, std::int64_t column) {
    std::string out(1, '['); // (built up: GCC 12 warns falsely on "[" + std::to_string(...), -Wrestrict)
    out += std::to_string(row);
    out += ", ";
    out += std::to_string(column);
    out += ']';
    return out;
}

/// A [row, column] pair from the file: whole numbers below the mask's size.
std::array<std::uint32_t, 2> read_cell(const ObjectReader& r, const json& v, const std::string& where,
                                       const MaskPanel& mask) {
    const std::size_t rows = mask.rows.size(), columns = mask.rows[0].size();
    const std::string range =
        "rows [0, " + std::to_string(rows - 1) + "], columns [0, " + std::to_string(columns - 1) + "]";
    for (const std::string& w : {where, where + "[0]", where + "[1]"})
        r.check_finite(w, range);
    if (!v.is_array() || v.size() != 2 || !v[0].is_number_unsigned() || !v[1].is_number_unsigned())
        r.fail(where, "must be a cell [row, column] (whole numbers; " + range + ")");
    const std::uint64_t row = v[0].get<std::uint64_t>(), column = v[1].get<std::uint64_t>();
    if (row >= rows || column >= columns)
        r.fail(where,
               "= [" + std::to_string(row) + ", " + std::to_string(column) + "] is outside the mask (" + range + ")");
    return {static_cast<std::uint32_t>(row), static_cast<std::uint32_t>(column)};
}

/// An in-plane axis of a mask panel: 3 numbers, length 1e-6..1e6 (normalised when built).
std::array<float, 3> read_axis(ObjectReader& p, const std::string& key, std::array<float, 3> fallback) {
    const std::array<float, 3> a = p.vec3(key, 1e6, "", fallback);
    const double len = std::sqrt(double(a[0]) * a[0] + double(a[1]) * a[1] + double(a[2]) * a[2]);
    if (!(len >= 1e-6 * (1.0 - 1e-6))) // the bound itself passes (1e-6 read into a float is 9.99999997e-7)
        p.fail(p.at(key), "has length " + format_number(len) + "; an axis needs a length of at least 1e-6");
    return a;
}

/// One panel of a mask cloth (cloth.panels[k]).
MaskPanelSpec read_mask_panel(ObjectReader& p) {
    MaskPanelSpec out;
    out.name = p.text("name", {}, "");
    if (out.name.empty()) p.fail(p.at("name"), "is required: a name that seams use to refer to the panel");
    if (out.name.size() > 64) p.fail(p.at("name"), "is longer than 64 characters");
    const json* rows = p.array("rows", mask_max_side);
    if (!rows || rows->empty())
        p.fail(p.at("rows"), "must list 1 to " + std::to_string(mask_max_side) +
                                 " rows of '0' and '1' characters ('1' = a particle)");
    std::size_t ones = 0;
    for (std::size_t r = 0; r < rows->size(); ++r) {
        const std::string where = p.at("rows") + "[" + std::to_string(r) + "]";
        const json& v = (*rows)[r];
        p.check_finite(where, "");
        if (!v.is_string()) p.fail(where, "must be a string of '0' and '1' characters");
        const std::string& row = v.get_ref<const std::string&>();
        if (row.empty() || row.size() > mask_max_side)
            p.fail(where,
                   "has " + std::to_string(row.size()) + " characters; allowed 1 to " + std::to_string(mask_max_side));
        if (r > 0 && row.size() != out.mask.rows[0].size())
            p.fail(where, "has " + std::to_string(row.size()) + " characters but " + p.at("rows") + "[0] has " +
                              std::to_string(out.mask.rows[0].size()) +
                              " (a mask is rectangular: rows of equal length)");
        for (std::size_t c = 0; c < row.size(); ++c) {
            if (row[c] == '1') {
                ++ones;
            } else if (row[c] != '0') {
                const auto uc = static_cast<unsigned char>(row[c]);
                char what[32];
                if (uc >= 32 && uc < 127)
                    std::snprintf(what, sizeof what, "'%c'", row[c]);
                else
                    std::snprintf(what, sizeof what, "byte 0x%02x", unsigned(uc));
                p.fail(where, "column " + std::to_string(c) + " holds " + what + "; only '0' and '1' are allowed");
            }
        }
        out.mask.rows.push_back(row);
    }
    if (ones == 0) p.fail(p.at("rows"), "holds no '1': a panel needs at least one particle");
    out.cell_size = static_cast<float>(p.number("cell_size", 1e-3, 1.0, " m", out.cell_size));
    out.origin = p.vec3_double("origin", 1000.0, " m", out.origin);
    out.axis_u = read_axis(p, "axis_u", out.axis_u);
    out.axis_v = read_axis(p, "axis_v", out.axis_v);
    const auto& u = out.axis_u;
    const auto& v = out.axis_v;
    const double cosine = (double(u[0]) * v[0] + double(u[1]) * v[1] + double(u[2]) * v[2]) /
                          (std::sqrt(double(u[0]) * u[0] + double(u[1]) * u[1] + double(u[2]) * u[2]) *
                           std::sqrt(double(v[0]) * v[0] + double(v[1]) * v[1] + double(v[2]) * v[2]));
    if (!(std::fabs(cosine) <= 1e-5))
        p.fail(p.at("axis_v"), "is not perpendicular to " + p.at("axis_u") + " (cosine of the angle " +
                                   format_number(cosine) + "; allowed within 1e-5 of 0)");
    if (p.has_array("pins")) {
        const json* list = p.array("pins", ones);
        out.pins = MaskPins::list;
        for (std::size_t k = 0; k < list->size(); ++k) {
            const std::string where = p.at("pins") + "[" + std::to_string(k) + "]";
            const auto cell = read_cell(p, (*list)[k], where, out.mask);
            if (out.mask.rows[cell[0]][cell[1]] != '1')
                p.fail(where, "= " + cell_text(cell[0], cell[1]) + " is a '0' cell (no particle to pin)");
            out.pin_cells.push_back(cell);
        }
    } else {
        out.pins = p.text("pins", {"none", "top_row"}, "none") == "top_row" ? MaskPins::top_row : MaskPins::none;
    }
    p.finish();
    return out;
}

/// One side of a seam (cloth.seams[k].a or .b): the panel by name and the path along its boundary.
MaskEdgeSpec read_mask_edge(ObjectReader& e, const std::vector<MaskPanelSpec>& panels) {
    MaskEdgeSpec out;
    std::string names; // the first 8, for messages
    for (std::size_t k = 0; k < panels.size() && k < 8; ++k)
        names += (k ? ", \"" : "\"") + printable(panels[k].name, 64) + "\"";
    if (panels.size() > 8) names += ", ... (" + std::to_string(panels.size()) + " panels)";
    const std::string name = e.text("panel", {}, "");
    if (name.empty()) e.fail(e.at("panel"), "is required: the name of a panel (" + names + ")");
    const auto it = std::find_if(panels.begin(), panels.end(), [&](const MaskPanelSpec& p) { return p.name == name; });
    if (it == panels.end())
        e.fail(e.at("panel"), "= \"" + printable(name, 60) + "\" is not a panel of this cloth (" + names + ")");
    out.panel = static_cast<std::uint32_t>(it - panels.begin());
    const MaskPanel& mask = it->mask;
    const std::string shown = printable(name, 64); // the name as messages show it (no control characters)
    const json* path = e.array("path", 4096);
    if (!path || path->empty())
        e.fail(e.at("path"),
               "must list 1 to 4096 cells [row, column]: the edge's first cell, its corners, its last cell");
    for (std::size_t k = 0; k < path->size(); ++k) {
        const std::string where = e.at("path") + "[" + std::to_string(k) + "]";
        out.path.push_back(read_cell(e, (*path)[k], where, mask));
        if (k == 0) continue;
        const std::int64_t dr = std::int64_t(out.path[k][0]) - out.path[k - 1][0];
        const std::int64_t dc = std::int64_t(out.path[k][1]) - out.path[k - 1][1];
        if (dr == 0 && dc == 0) e.fail(where, "repeats the cell before it");
        if (dr != 0 && dc != 0 && std::llabs(dr) != std::llabs(dc))
            e.fail(where, "is not on the same row, column or 45-degree diagonal as " + e.at("path") + "[" +
                              std::to_string(k - 1) + "] (each leg of an edge is straight)");
    }
    std::set<std::pair<std::uint32_t, std::uint32_t>> seen;
    for (const auto& [r, c] : mask_edge_cells(out)) {
        if (mask.rows[r][c] != '1')
            e.fail(e.at("path"), "passes cell " + cell_text(r, c) + " of panel \"" + shown +
                                     "\", a '0' (an edge runs along particles)");
        if (!mask_cell_on_boundary(mask, r, c))
            e.fail(e.at("path"), "passes cell " + cell_text(r, c) + ", inside panel \"" + shown +
                                     "\": an edge runs along the panel's boundary");
        if (!seen.insert({r, c}).second) e.fail(e.at("path"), "passes cell " + cell_text(r, c) + " twice");
    }
    e.finish();
    return out;
}

/// cloth.type = "mask": panels, seams, density.
void read_mask_cloth(ObjectReader& cloth, SceneSpec& s) {
    MaskClothSpec& m = s.masks;
    m.density = static_cast<float>(cloth.number("density", 1e-3, 10.0, " kg/m^2", m.density));
    const json* panels = cloth.array("panels", 256);
    if (!panels || panels->empty()) cloth.fail(cloth.at("panels"), "must list 1 to 256 panels");
    std::size_t particles = 0;
    for (std::size_t k = 0; k < panels->size(); ++k) {
        ObjectReader p((*panels)[k], cloth.at("panels") + "[" + std::to_string(k) + "]", cloth.source(),
                       cloth.non_finite());
        MaskPanelSpec panel = read_mask_panel(p);
        for (const MaskPanelSpec& other : m.panels)
            if (other.name == panel.name)
                p.fail(p.at("name"),
                       "= \"" + printable(panel.name, 60) + "\" names an earlier panel too (names are unique)");
        for (const std::string& row : panel.mask.rows)
            particles += std::size_t(std::count(row.begin(), row.end(), '1'));
        if (particles > (std::size_t{1} << 24))
            p.fail(p.at("rows"),
                   "brings the cloth to " + std::to_string(particles) + " particles; at most 16,777,216 are allowed");
        m.panels.push_back(std::move(panel));
    }
    if (const json* seams = cloth.array("seams", 4096)) {
        for (std::size_t k = 0; k < seams->size(); ++k) {
            const std::string where = cloth.at("seams") + "[" + std::to_string(k) + "]";
            ObjectReader sr((*seams)[k], where, cloth.source(), cloth.non_finite());
            MaskSeamSpec seam;
            ObjectReader a = sr.object("a");
            if (!sr.has("a")) sr.fail(sr.at("a"), "is required: {\"panel\": name, \"path\": [[row, column], ...]}");
            seam.a = read_mask_edge(a, m.panels);
            ObjectReader b = sr.object("b");
            if (!sr.has("b")) sr.fail(sr.at("b"), "is required: {\"panel\": name, \"path\": [[row, column], ...]}");
            seam.b = read_mask_edge(b, m.panels);
            seam.rest_ratio = static_cast<float>(sr.number("rest_ratio", 0.01, 2.0, "", seam.rest_ratio));
            sr.finish();
            const std::size_t na = mask_edge_cells(seam.a).size(), nb = mask_edge_cells(seam.b).size();
            if (na != nb)
                sr.fail(sr.at("b") + ".path",
                        "has " + std::to_string(nb) + " cells but " + sr.at("a") + ".path has " + std::to_string(na) +
                            "; a seam joins two edges cell to cell, so they must have equal lengths");
            m.seams.push_back(std::move(seam));
        }
    }
}

/// The "material" object: the seeds' spring fields ("model": "springs", the default when none is given) or a fabric
/// ("model": "fabric"): a preset in "fabric" with any fields overriding it, or every figure of a custom fabric, in
/// file units (g/m^2, N/m, micro-N*m, s). A material with fields of both models is refused naming one of each.
void read_material(ObjectReader& mat, SceneSpec& s) {
    static const char* const spring_keys[] = {"stiffness", "shear_ratio", "bend_ratio", "damping_ratio"};
    static const char* const fabric_keys[] = {"fabric",  "density_gsm", "stretch_u", "stretch_v",
                                              "shear",   "bend_u_uNm",  "bend_v_uNm", "damping"};
    const char* spring_key = nullptr;
    const char* fabric_key = nullptr;
    for (const char* k : spring_keys)
        if (!spring_key && mat.has(k)) spring_key = k;
    for (const char* k : fabric_keys)
        if (!fabric_key && mat.has(k)) fabric_key = k;
    if (spring_key && fabric_key)
        mat.fail(mat.at(fabric_key), "is a fabric field but " + mat.at(spring_key) +
                                         " is a spring-model field; a material is one or the other "
                                         "(docs/scene_format.md \"material\")");
    const std::string model = mat.text("model", {"fabric", "springs"}, fabric_key ? "fabric" : "springs");
    if (model == "springs" && fabric_key)
        mat.fail(mat.at(fabric_key), "is a fabric field but " + mat.at("model") + " is \"springs\"");
    if (model == "fabric" && spring_key)
        mat.fail(mat.at(spring_key), "is a spring-model field but " + mat.at("model") + " is \"fabric\"");
    s.seam_stiffness = static_cast<float>(mat.number("seam_stiffness", 100.0, 25000.0, " N/m", s.seam_stiffness));
    if (model == "springs") {
        s.model = MaterialModel::springs;
        s.stiffness = static_cast<float>(mat.number("stiffness", 100.0, 25000.0, " N/m", s.stiffness));
        s.shear_ratio = static_cast<float>(mat.number("shear_ratio", 0.0, 1.0, "", s.shear_ratio));
        s.bend_ratio = static_cast<float>(mat.number("bend_ratio", 0.0, 1.0, "", s.bend_ratio));
        s.damping_ratio = static_cast<float>(mat.number("damping_ratio", 0.0, 1.0, "", s.damping_ratio));
        return;
    }
    s.model = MaterialModel::fabric;
    const std::string base = mat.text("fabric", {}, "");
    Fabric f;
    if (!base.empty()) {
        const std::optional<Fabric> preset = find_fabric(base);
        if (!preset) mat.fail(mat.at("fabric"), "= \"" + printable(base, 60) + "\" is not a fabric preset (presets: " +
                                                    fabric_preset_names() + ")");
        f = *preset;
    } else {
        f.damping = 0.0f;
        for (const char* k : {"density_gsm", "stretch_u", "stretch_v", "shear", "bend_u_uNm", "bend_v_uNm"})
            if (!mat.has(k))
                mat.fail(mat.at(k), std::string("is required for a custom fabric (or name a preset in ") +
                                        mat.at("fabric") + ": " + fabric_preset_names() + ")");
    }
    const Fabric before = f;
    const auto field = [&](const char* key, const FabricRange& r, double scale, float& value) {
        const std::string unit = std::string(" ") + r.unit;
        value = static_cast<float>(mat.number(key, r.lo, r.hi, unit.c_str(), double(value) * scale) / scale);
    };
    field("density_gsm", fabric_range_density_gsm, fabric_gsm_per_kg_m2, f.density);
    field("stretch_u", fabric_range_stretch, 1.0, f.stretch_u);
    field("stretch_v", fabric_range_stretch, 1.0, f.stretch_v);
    field("shear", fabric_range_shear, 1.0, f.shear);
    field("bend_u_uNm", fabric_range_bend_uNm, fabric_uNm_per_Nm, f.bend_u);
    field("bend_v_uNm", fabric_range_bend_uNm, fabric_uNm_per_Nm, f.bend_v);
    field("damping", fabric_range_damping, 1.0, f.damping);
    const bool same = f.density == before.density && f.stretch_u == before.stretch_u &&
                      f.stretch_v == before.stretch_v && f.shear == before.shear && f.bend_u == before.bend_u &&
                      f.bend_v == before.bend_v && f.damping == before.damping;
    f.name = !base.empty() && same ? base : "custom";
    try {
        validate_fabric(f, mat.source() + ": material");
    } catch (const InvalidInput& e) {
        throw FieldError(e.what());
    }
    s.fabric = f;
}

inline constexpr double state_limit = 1e6; ///< |position| (m) and |velocity| (m/s) in a saved state

/// The "state" section: positions and velocities ([x, y, z] per particle) and the pinned particles. Counts are
/// checked against the cloth in build_scene (the cloth is not built yet).
SceneState read_state(ObjectReader& st) {
    SceneState out;
    const std::size_t max_particles = std::size_t{1} << 24;
    auto triples = [&](const char* key, std::vector<float>& x, std::vector<float>& y, std::vector<float>& z,
                       const char* unit) {
        const json* list = st.array(key, max_particles);
        if (!list) st.fail(st.at(key), "is required: one [x, y, z] per particle");
        x.resize(list->size());
        y.resize(list->size());
        z.resize(list->size());
        for (std::size_t i = 0; i < list->size(); ++i) {
            const json& v = (*list)[i];
            if (!v.is_array() || v.size() != 3)
                st.fail(st.at(key) + "[" + std::to_string(i) + "]", "must be [x, y, z], three numbers");
            float* dst[3] = {&x[i], &y[i], &z[i]};
            for (int k = 0; k < 3; ++k) {
                // NaN or 1e400 written in the file: named with the range (the safety net below has none).
                st.check_finite(st.at(key) + "[" + std::to_string(i) + "][" + std::to_string(k) + "]",
                                "[-1e+06, 1e+06]" + std::string(unit));
                const double d = v[k].is_number() ? v[k].get<double>() : std::nan("");
                if (!(std::fabs(d) <= state_limit))
                    st.fail(st.at(key) + "[" + std::to_string(i) + "][" + std::to_string(k) + "]",
                            "must be a finite number in [-1e+06, 1e+06]" + std::string(unit));
                *dst[k] = static_cast<float>(d);
            }
        }
    };
    out.origin = st.vec3_double("origin", 1000.0, " m", {0.0, 0.0, 0.0});
    triples("positions", out.x, out.y, out.z, " m");
    triples("velocities", out.vx, out.vy, out.vz, " m/s");
    if (out.vx.size() != out.x.size())
        st.fail(st.at("velocities"), "has " + std::to_string(out.vx.size()) + " entries; state.positions has " +
                                         std::to_string(out.x.size()));
    const json* pinned = st.array("pinned", max_particles);
    if (!pinned) st.fail(st.at("pinned"), "is required: the pinned particles' indices ([] for none)");
    for (std::size_t k = 0; k < pinned->size(); ++k) {
        const json& v = (*pinned)[k];
        if (!v.is_number_unsigned() || v.get<std::uint64_t>() >= out.x.size())
            st.fail(st.at("pinned") + "[" + std::to_string(k) + "]",
                    "must be a particle index in [0, " + std::to_string(out.x.size()) + ")");
        out.pinned.push_back(v.get<std::uint32_t>());
    }
    if (st.has("self_collision_snapshot")) {
        triples("self_collision_snapshot", out.snapshot_x, out.snapshot_y, out.snapshot_z, " m");
        if (out.snapshot_x.size() != out.x.size())
            st.fail(st.at("self_collision_snapshot"), "has " + std::to_string(out.snapshot_x.size()) +
                                                          " entries; state.positions has " + std::to_string(out.x.size()));
    }
    if (const json* planes = st.array("self_collision_planes", max_particles)) {
        if (out.snapshot_x.empty())
            st.fail(st.at("self_collision_planes"), "needs self_collision_snapshot (the planes belong to its run)");
        SelfCollisionPlanes& pl = out.sc_planes;
        for (std::size_t k = 0; k < planes->size(); ++k) {
            const json& v = (*planes)[k];
            const std::string at = st.at("self_collision_planes") + "[" + std::to_string(k) + "]";
            if (!v.is_array() || v.size() != 6 || !v[0].is_number_unsigned() || v[0].get<std::uint64_t>() >= out.x.size() ||
                (k > 0 && v[0].get<std::uint64_t>() <= pl.index.back()) || !v[1].is_number_unsigned() ||
                v[1].get<std::uint64_t>() >= out.x.size())
                st.fail(at, "must be [particle, partner, nx, ny, nz, c]: particle indices in [0, " +
                                std::to_string(out.x.size()) + ") (the first ascending), then four numbers");
            double d[4];
            for (int j = 0; j < 4; ++j) d[j] = v[j + 2].is_number() ? v[j + 2].get<double>() : std::nan("");
            const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            if (!(std::fabs(len - 1.0) <= 1e-3))
                st.fail(at, "must have a unit normal nx, ny, nz (its length is " + std::to_string(len) + ")");
            const std::uint32_t i = v[0].get<std::uint32_t>();
            // The plane goes through where the run left the particle: the snapshot, up to rounding.
            const double on = d[0] * out.snapshot_x[i] + d[1] * out.snapshot_y[i] + d[2] * out.snapshot_z[i];
            if (!(std::fabs(d[3] - on) <= 1e-3))
                st.fail(at, "must have an offset c within 1 mm of n . self_collision_snapshot[" + std::to_string(i) +
                                "] (" + std::to_string(on) + " m)");
            pl.index.push_back(i);
            pl.partner.push_back(v[1].get<std::uint32_t>());
            pl.nx.push_back(static_cast<float>(d[0]));
            pl.ny.push_back(static_cast<float>(d[1]));
            pl.nz.push_back(static_cast<float>(d[2]));
            pl.c.push_back(static_cast<float>(d[3]));
        }
    }
    if (const json* sewn = st.array("seam_rest", max_particles))
        for (std::size_t k = 0; k < sewn->size(); ++k) {
            const json& v = (*sewn)[k];
            const double d = v.is_number() ? v.get<double>() : std::nan("");
            if (!(d > 0.0 && d <= 100.0))
                st.fail(st.at("seam_rest") + "[" + std::to_string(k) + "]",
                        "must be a seam's rest length in (0, 100] m (a seam being sewn)");
            out.seam_rest.push_back(static_cast<float>(d));
        }
    st.finish();
    return out;
}
} // namespace

std::vector<std::array<std::uint32_t, 2>> mask_edge_cells(const MaskEdgeSpec& edge) {
    std::vector<std::array<std::uint32_t, 2>> out;
    if (edge.path.empty()) return out;
    out.push_back(edge.path[0]);
    for (std::size_t k = 1; k < edge.path.size(); ++k) {
        std::int64_t r = edge.path[k - 1][0], c = edge.path[k - 1][1];
        const std::int64_t tr = edge.path[k][0], tc = edge.path[k][1];
        const std::int64_t sr = (tr > r) - (tr < r), sc = (tc > c) - (tc < c);
        while (r != tr || c != tc) {
            r += sr;
            c += sc;
            out.push_back({static_cast<std::uint32_t>(r), static_cast<std::uint32_t>(c)});
        }
    }
    return out;
}

bool mask_cell_on_boundary(const MaskPanel& mask, std::int64_t row, std::int64_t column) {
    const auto present = [&](std::int64_t r, std::int64_t c) {
        return r >= 0 && c >= 0 && r < std::int64_t(mask.rows.size()) && c < std::int64_t(mask.rows[0].size()) &&
               mask.rows[std::size_t(r)][std::size_t(c)] == '1';
    };
    if (!present(row, column)) return false;
    // add_mask_panel's triangles: a cell with four particles is covered by two triangles, one with three by the
    // triangle of those three. The quarter of a cell at (row, column) is covered when the cell has all four corners,
    // or three with the missing one opposite (row, column): exactly when both corners beside it are present. The
    // particle is inside the mesh when all four quarters around it are covered; otherwise a triangle edge through it
    // belongs to one triangle, or it is in none.
    for (const std::int64_t dr : {-1, 1})
        for (const std::int64_t dc : {-1, 1})
            if (!present(row + dr, column) || !present(row, column + dc)) return true;
    return false;
}

std::vector<std::string> builtin_scene_names() {
    std::vector<std::string> out;
    for (std::size_t k = 0; k < builtin_scene_json_count; ++k) out.emplace_back(builtin_scene_json_names[k]);
    return out;
}

// A function-try-block: whatever nlohmann throws (a type or range error the reader did not foresee) becomes
// InvalidInput naming the file; nothing else escapes but InvalidInput and std::bad_alloc.
SceneSpec parse_scene(const std::string& text, const std::string& source, const std::string& base_dir) try {
    if (text.size() > scene_file_max_bytes) throw InvalidInput(source + ": file is larger than 16 MiB");
    NonFiniteNumbers non_finite;
    const json doc = parse_json(text, source, non_finite);
    ObjectReader root(doc, "", source, &non_finite);
    SceneSpec s;
    s.source = source;
    s.name = root.text("scene", {}, "unnamed");
    s.description = root.text("description", {}, "");

    // cloth
    ObjectReader cloth = root.object("cloth");
    const std::string type = cloth.text("type", {"grid", "tshirt", "outline", "mesh", "mask"}, "grid");
    s.cloth = type == "tshirt"    ? ClothType::tshirt
              : type == "outline" ? ClothType::outline
              : type == "mesh"    ? ClothType::mesh
              : type == "mask"    ? ClothType::mask
                                  : ClothType::grid;
    if (s.cloth == ClothType::mesh) {
        read_mesh_cloth(cloth, base_dir, s);
    } else if (s.cloth == ClothType::mask) {
        read_mask_cloth(cloth, s);
    } else if (s.cloth == ClothType::outline) {
        OutlineClothSpec& o = s.outline;
        const json* pts = cloth.array("outline", 4096);
        if (!pts || pts->size() < 3) cloth.fail(cloth.at("outline"), "must list 3 to 4096 [u, v] vertices (m)");
        for (std::size_t k = 0; k < pts->size(); ++k) {
            const json& v = (*pts)[k];
            const std::string where = cloth.at("outline") + "[" + std::to_string(k) + "]";
            for (const std::string& w : {where, where + "[0]", where + "[1]"}) cloth.check_finite(w, "[-100, 100] m");
            if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number())
                cloth.fail(where, "must be [u, v], two numbers in metres");
            const double u = v[0].get<double>(), w = v[1].get<double>();
            if (!(std::fabs(u) <= 100.0 && std::fabs(w) <= 100.0))
                cloth.fail(where, "is outside the allowed range [-100, 100] m");
            o.outline.outline.push_back({u, w});
        }
        o.spacing = static_cast<float>(cloth.number("spacing", 1e-3, 1.0, " m", o.spacing));
        o.density = static_cast<float>(cloth.number("density", 1e-3, 10.0, " kg/m^2", o.density));
        o.plane = cloth.text("plane", {"horizontal", "vertical"}, "horizontal") == "vertical" ? GridPlane::vertical
                                                                                             : GridPlane::horizontal;
        o.centre = cloth.vec3("centre", 1000.0, " m", o.centre);
        o.pin_top = cloth.text("pins", {"none", "top_edge"}, "none") == "top_edge";
        ObjectReader copy = cloth.object("copy");
        o.copy = cloth.has("copy");
        o.gap = static_cast<float>(copy.number("gap", 1e-3, 2.0, " m", o.gap));
        o.seam_rest_ratio = static_cast<float>(copy.number("seam_rest_ratio", 0.01, 2.0, "", o.seam_rest_ratio));
        if (const json* sew = copy.array("sew", 4096)) {
            for (std::size_t k = 0; k < sew->size(); ++k) {
                const json& v = (*sew)[k];
                const std::string where = copy.at("sew") + "[" + std::to_string(k) + "]";
                for (const std::string& w : {where, where + "[0]", where + "[1]"})
                    copy.check_finite(w, "[0, " + std::to_string(pts->size() - 1) + "] (vertex indices)");
                if (!v.is_array() || v.size() != 2 || !v[0].is_number_unsigned() || !v[1].is_number_unsigned() ||
                    v[0].get<std::uint64_t>() >= pts->size() || v[1].get<std::uint64_t>() >= pts->size())
                    cloth.fail(where, "must be [from vertex, to vertex], indices in [0, " +
                                          std::to_string(pts->size() - 1) + "]");
                if (v[0].get<std::uint64_t>() == v[1].get<std::uint64_t>()) // was read as the whole loop
                    cloth.fail(where, "= [" + std::to_string(v[0].get<std::uint64_t>()) + ", " +
                                          std::to_string(v[1].get<std::uint64_t>()) +
                                          "]: from and to must be different vertices (a seam runs along the outline "
                                          "from one to the other; for the whole outline give two ranges, e.g. [0, 2] "
                                          "and [2, 0])");
                o.sew.push_back({v[0].get<std::uint32_t>(), v[1].get<std::uint32_t>()});
            }
            // Each outline edge sewn once: a stretch given twice (or two overlapping ones) sewed its particles again,
            // where the second seam joined nothing new.
            const std::size_t corners = pts->size();
            std::vector<std::size_t> sewn_by(corners, SIZE_MAX);
            for (std::size_t k = 0; k < o.sew.size(); ++k)
                for (std::size_t e = o.sew[k][0]; e != o.sew[k][1]; e = (e + 1) % corners) {
                    if (sewn_by[e] != SIZE_MAX)
                        cloth.fail(copy.at("sew") + "[" + std::to_string(k) + "]",
                                   "= [" + std::to_string(o.sew[k][0]) + ", " + std::to_string(o.sew[k][1]) +
                                       "] sews outline edge " + std::to_string(e) + " (vertices " + std::to_string(e) +
                                       "-" + std::to_string((e + 1) % corners) + ") that " + copy.at("sew") + "[" +
                                       std::to_string(sewn_by[e]) + "] sews already (each stretch is sewn once)");
                    sewn_by[e] = k;
                }
        }
        copy.finish();
        try {
            check_outline(o.outline);
        } catch (const InvalidInput& e) {
            cloth.fail(cloth.at("outline") + ":", e.what());
        }
        const double points = outline_panel_point_estimate(o.outline, o.spacing);
        const std::size_t max_points = OutlinePanelParams{}.max_points;
        if (points > double(max_points))
            cloth.fail(cloth.at("spacing"), "= " + format_number(o.spacing) + " m gives this outline up to " +
                                                (points < 1e15 ? std::to_string(static_cast<long long>(points)) : format_number(points)) + " points per panel; at most " +
                                                std::to_string(max_points) + " are allowed (raise the spacing)");
    } else if (s.cloth == ClothType::grid) {
        HangParams& g = s.grid;
        g.n = cloth.integer("n", hang_min_n, hang_max_n, 100);
        g.size = static_cast<float>(cloth.number("size", 0.01, 100.0, " m", 1.0));
        g.total_mass = static_cast<float>(cloth.number("mass", 1e-6, 1000.0, " kg", 0.1));
        const std::string plane = cloth.text("plane", {"horizontal", "vertical"}, "horizontal");
        g.plane = plane == "vertical" ? GridPlane::vertical : GridPlane::horizontal;
        g.centre = cloth.vec3("centre", 1000.0, " m", {0, 0, 0});
        const std::string pins = cloth.text("pins", {"corners", "top_edge", "left_edge", "none"}, "corners");
        g.pins = pins == "top_edge"    ? GridPins::top_edge
                 : pins == "left_edge" ? GridPins::left_edge
                 : pins == "none"      ? GridPins::none
                                       : GridPins::corners;
        g.pin_radius = static_cast<float>(cloth.number("pin_radius", 0.0, hang_max_pin_radius, " m", 0.0));
    } else {
        TShirtParams& t = s.tshirt;
        t.cells_per_metre = static_cast<float>(cloth.number("cells_per_metre", 10.0, 1000.0, " 1/m", t.cells_per_metre));
        t.total_mass = static_cast<float>(cloth.number("mass", 0.001, 10.0, " kg", t.total_mass));
        t.shoulder_y = static_cast<float>(cloth.number("shoulder_y", -10.0, 10.0, " m", t.shoulder_y));
        t.gap = static_cast<float>(cloth.number("gap", 0.001, 2.0, " m", t.gap));
        t.seam_rest_ratio = static_cast<float>(cloth.number("seam_rest_ratio", 0.01, 2.0, "", t.seam_rest_ratio));
        t.mirror_exact = cloth.boolean("mirror_exact", t.mirror_exact);
    }
    cloth.finish();

    // material: a preset's name, or an object (fabric fields, or the seeds' spring fields)
    if (root.has_string("material")) {
        const std::string preset = root.text("material", {}, "");
        const std::optional<Fabric> f = find_fabric(preset);
        if (!f) root.fail("material", "= \"" + printable(preset, 60) + "\" is not a fabric preset (presets: " +
                                          fabric_preset_names() + "; or an object, docs/scene_format.md)");
        s.model = MaterialModel::fabric;
        s.fabric = *f;
    } else {
        ObjectReader mat = root.object("material");
        read_material(mat, s);
        mat.finish();
    }
    if (s.model == MaterialModel::fabric && s.cloth == ClothType::mask && !mask_weave_aligned(s.masks))
        s.warnings.push_back(source + ": cloth.panels: the panels' axis_u differ, so the fabric's weave has no single "
                                      "direction in the cloth; the membrane uses the direction-free rule (unaligned, "
                                      "docs/fabric.md) along the first panel's axis_u");
    // With a fabric the mass comes from its areal density: a cloth's own mass or density would be a second answer.
    if (s.model == MaterialModel::fabric) {
        const char* key = s.cloth == ClothType::grid || s.cloth == ClothType::tshirt ? "mass" : "density";
        if (cloth.has(key))
            cloth.fail(cloth.at(key), std::string("is a spring-model field: with a fabric material the mass comes from "
                                                  "the fabric's areal density (material.density_gsm); remove ") +
                                          cloth.at(key) + " or use \"model\": \"springs\"");
    } else if (s.cloth == ClothType::grid) {
        // Node mass in seed 000's range 0.001 - 1 g.
        const HangParams& g = s.grid;
        const double node_mass = double(g.total_mass) / (double(g.n) * g.n);
        if (!(node_mass >= 1e-6 * 0.999 && node_mass <= 1e-3 * 1.001)) {
            if (cloth.has("mass"))
                cloth.fail(cloth.at("mass"), "gives a node mass of " + format_number(node_mass * 1000.0) +
                                                 " g; allowed range [0.001, 1] g per particle (seed 000)");
            // Not in the file: say where the mass came from (it read "cloth.mass gives ..." of a field not there).
            cloth.fail(cloth.at("n"), "gives the default cloth mass of " + format_number(double(g.total_mass)) +
                                          " kg a node mass of " + format_number(node_mass * 1000.0) +
                                          " g; allowed range [0.001, 1] g per particle (seed 000): set " +
                                          cloth.at("mass") + " (kg) or a fabric material");
        }
    }

    // physics
    ObjectReader ph = root.object("physics");
    SimulationParams& p = s.physics;
    p.gravity = ph.vec3("gravity", 100.0, " m/s^2", p.gravity);
    p.air_drag = static_cast<float>(ph.number("drag", 0.0, 100.0, " 1/s", p.air_drag));
    p.sewing_speed = static_cast<float>(
        ph.number("sewing_speed", 0.0, 10.0, " m/s (0 = off: every seam must then start closed)", p.sewing_speed));
    p.integrator = ph.text("integrator", {"euler", "verlet"}, "euler") == "verlet" ? Integrator::verlet
                                                                                 : Integrator::symplectic_euler;
    p.solver = ph.text("solver", {"explicit", "implicit"}, "explicit") == "implicit" ? Solver::implicit
                                                                                    : Solver::explicit_euler;
    if (p.solver == Solver::implicit && p.integrator == Integrator::verlet)
        ph.fail(ph.at("integrator"), "= \"verlet\" is a choice of the explicit solver only; " + ph.at("solver") +
                                         " = \"implicit\" keeps velocities: use \"euler\" (or leave it out)");
    if (ph.has("dt")) s.dt = static_cast<float>(ph.number("dt", 1e-9, 0.1, " s", 0.0));
    ObjectReader im = ph.object("implicit");
    p.implicit.iterations = im.integer("iterations", 1, implicit_max_iterations, p.implicit.iterations);
    p.implicit.tolerance = static_cast<float>(
        im.number("tolerance", 0.0, 1.0, " (0 = run every iteration)", double(p.implicit.tolerance)));
    const double rho = im.number("chebyshev_rho", 0.0, 1.0, " (1 excluded; 0 = no acceleration)", double(p.implicit.chebyshev_rho));
    if (!(rho < 1.0))
        im.fail(im.at("chebyshev_rho"), "= 1 is outside the allowed range [0, 1) (0 = no acceleration)");
    p.implicit.chebyshev_rho = static_cast<float>(rho);
    p.implicit.fas = im.boolean("fas", p.implicit.fas);
    p.implicit.fas_at_rest = im.boolean("fas_at_rest", p.implicit.fas_at_rest);
    p.implicit.multilevel = im.boolean("multilevel", p.implicit.multilevel);
    p.implicit.method = im.text("method", {"gauss_seidel", "jacobi"}, "gauss_seidel") == "jacobi"
                            ? ImplicitMethod::jacobi
                            : ImplicitMethod::gauss_seidel;
    im.finish();
    ObjectReader wind = ph.object("wind");
    p.wind.enabled = wind.boolean("enabled", false);
    p.wind.strength = static_cast<float>(wind.number("strength", 0.0, 100.0, " m/s^2", p.wind.strength));
    wind.finish();
    ObjectReader aero = ph.object("aero");
    p.aero.enabled = aero.boolean("enabled", false);
    p.aero.density = static_cast<float>(aero.number("density", 0.0, 100.0, " kg/m^3", p.aero.density));
    p.aero.drag_coefficient = static_cast<float>(aero.number("drag_coefficient", 0.0, 10.0, "", p.aero.drag_coefficient));
    p.aero.velocity = aero.vec3("velocity", 100.0, " m/s", p.aero.velocity);
    aero.finish();
    ObjectReader sl = ph.object("strain_limit");
    p.strain_limit.ratio = static_cast<float>(sl.number("ratio", 0.0, 10.0, "", 0.0));
    p.strain_limit.passes = sl.integer("passes", 1, 100, 4);
    p.strain_limit.every = sl.integer("every", 1, 1000, 1);
    sl.finish();
    ObjectReader sc = ph.object("self_collision");
    const double thickness = sc.number("thickness", 0.0, double(self_collision_max_thickness), " m (0 = off)", 0.0);
    if (thickness != 0.0 && thickness < double(self_collision_min_thickness))
        sc.fail(sc.at("thickness"), "= " + format_number(thickness) +
                                        " m is outside the allowed range 0 (off) or [0.0005, 0.05] m");
    p.self_collision.thickness = static_cast<float>(thickness);
    p.self_collision.friction =
        static_cast<float>(sc.number("friction", 0.0, 2.0, "", double(p.self_collision.friction)));
    p.self_collision.substeps = sc.integer("substeps", 1, self_collision_max_substeps, p.self_collision.substeps);
    sc.finish();
    ph.finish();

    // colliders
    if (const json* list = root.array("colliders", 64)) {
        for (std::size_t k = 0; k < list->size(); ++k) {
            ObjectReader r((*list)[k], "colliders[" + std::to_string(k) + "]", source, &non_finite);
            p.colliders.push_back(read_collider(r));
        }
    }
    s.body = root.boolean("body", false);
    if (root.has("state")) {
        ObjectReader st = root.object("state");
        s.state = read_state(st);
    }

    root.finish();
    // Every field was read or refused above, so a non-finite number has been reported; this is a safety net.
    if (!non_finite.empty())
        throw InvalidInput(source + ": " + printable(non_finite.begin()->first, 160) + " = " + shorten(non_finite.begin()->second) +
                           " is not a finite number");

    const std::size_t particles = scene_particle_count(s);
    if (particles > (std::size_t{1} << 24))
        throw InvalidInput(source + ": the cloth would have " + std::to_string(particles) +
                           " particles; at most 16,777,216 are allowed");
    warn_curved_mesh(s);
    return s;
} catch (const json::exception& e) {
    throw InvalidInput(source + ": " + e.what());
}

SceneSpec load_scene(const std::string& name_or_path) {
    const bool is_file = name_or_path.size() > 5 && name_or_path.substr(name_or_path.size() - 5) == ".json";
    if (!is_file) {
        for (std::size_t k = 0; k < builtin_scene_json_count; ++k)
            if (name_or_path == builtin_scene_json_names[k])
                return parse_scene(builtin_scene_json[k], "built-in scene '" + name_or_path + "'");
        std::string names;
        for (const std::string& n : builtin_scene_names()) names += (names.empty() ? "" : ", ") + n;
        throw InvalidInput("unknown scene '" + name_or_path + "' (built-in scenes: " + names + "; or a path to a .json file)");
    }
    // What the path is, before opening it: opening a FIFO would block until a writer comes, a directory "opens".
    const std::string& path = name_or_path;
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        const int err = errno;
        if (err == ENOENT) throw InvalidInput(path + ": the scene file does not exist");
        if (err == ENOTDIR) throw InvalidInput(path + ": the scene file does not exist (a part of the path is not a directory)");
        if (err == EACCES) throw InvalidInput(path + ": the scene file cannot be read (permission denied)");
        throw InvalidInput(path + ": the scene file cannot be read (" + std::strerror(err) + ")");
    }
    auto kind = [](mode_t mode) -> const char* {
        if (S_ISFIFO(mode)) return "a FIFO";
        if (S_ISSOCK(mode)) return "a socket";
        if (S_ISCHR(mode)) return "a character device";
        if (S_ISBLK(mode)) return "a block device";
        return "not a plain file";
    };
    if (S_ISDIR(st.st_mode)) throw InvalidInput(path + ": is a directory, not a scene file");
    if (!S_ISREG(st.st_mode)) throw InvalidInput(path + ": is not a regular file (" + kind(st.st_mode) + ")");
    const auto too_big = [&](std::uintmax_t bytes) {
        // In bytes too: a file just over the limit read "16.0 MiB; ... limited to 16 MiB".
        char text[96];
        std::snprintf(text, sizeof text, "%ju bytes (%.2f MiB)", std::uintmax_t(bytes), double(bytes) / (1024.0 * 1024.0));
        return InvalidInput(path + ": the file is " + text + "; scene files are limited to 16 MiB (" +
                            std::to_string(scene_file_max_bytes) + " bytes)");
    };
    if (std::uintmax_t(st.st_size) > std::uintmax_t(scene_file_max_bytes)) throw too_big(std::uintmax_t(st.st_size));

    // Opened without blocking and checked again on the descriptor: the path may have been replaced since the stat.
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        const int err = errno;
        throw InvalidInput(path + ": the scene file cannot be read (" +
                           (err == EACCES ? std::string("permission denied") : std::string(std::strerror(err))) + ")");
    }
    std::string text;
    std::string failure;
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        failure = "is not a regular file";
    } else {
        char buf[65536];
        for (;;) {
            const ssize_t got = ::read(fd, buf, sizeof buf);
            if (got < 0 && errno == EINTR) continue;
            if (got < 0) {
                failure = std::string("the scene file cannot be read (") + std::strerror(errno) + ")";
                break;
            }
            if (got == 0) break;
            text.append(buf, static_cast<std::size_t>(got));
            if (text.size() > scene_file_max_bytes) break;
        }
    }
    ::close(fd);
    if (!failure.empty()) throw InvalidInput(path + ": " + failure);
    if (text.size() > scene_file_max_bytes) throw too_big(text.size());
    return parse_scene(text, name_or_path, std::filesystem::path(name_or_path).parent_path().string());
}

std::size_t scene_particle_count(const SceneSpec& s) {
    if (s.cloth == ClothType::grid) return std::size_t{s.grid.n} * s.grid.n;
    if (s.cloth == ClothType::mask) { // exact: the '1' cells
        std::size_t n = 0;
        for (const MaskPanelSpec& p : s.masks.panels)
            for (const std::string& row : p.mask.rows)
                n += static_cast<std::size_t>(std::count(row.begin(), row.end(), '1'));
        return n;
    }
    if (s.cloth == ClothType::mesh) return s.mesh.mesh ? s.mesh.mesh->particle_count() : 0;
    if (s.cloth == ClothType::outline) { // bounding box / spacing^2, per panel (an upper bound)
        double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
        for (const auto& v : s.outline.outline.outline)
            for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
        const double h = s.outline.spacing;
        const double per_panel = ((hi[0] - lo[0]) / h + 2) * ((hi[1] - lo[1]) / h + 2);
        return static_cast<std::size_t>(std::min(per_panel * (s.outline.copy ? 2 : 1), 1e12));
    }
    const double r = s.tshirt.cells_per_metre;
    return static_cast<std::size_t>(0.8 * r * r) + 64; // the mask's area is ~0.39 m^2 per panel (panels.hpp)
}

std::optional<std::uint32_t> scene_resolution(const SceneSpec& s) {
    switch (s.cloth) {
    case ClothType::grid:
        return s.grid.n;
    case ClothType::tshirt:
        return static_cast<std::uint32_t>(std::lround(s.tshirt.cells_per_metre));
    case ClothType::outline:
        return static_cast<std::uint32_t>(std::max(1L, std::lround(1.0 / double(s.outline.spacing))));
    case ClothType::mesh:
    case ClothType::mask:
        return std::nullopt;
    }
    return std::nullopt;
}

void set_scene_resolution(SceneSpec& s, std::uint32_t size, const std::string& flag) {
    const auto out_of_range = [&](std::uint32_t lo, std::uint32_t hi, const std::string& what) {
        return InvalidInput(flag + ": value " + std::to_string(size) + " is outside the allowed range [" +
                            std::to_string(lo) + ", " + std::to_string(hi) + "] (" + what + ")");
    };
    switch (s.cloth) {
    case ClothType::grid:
        if (size < hang_min_n || size > hang_max_n) throw out_of_range(hang_min_n, hang_max_n, "particles per side");
        s.grid.n = size;
        return;
    case ClothType::tshirt:
        if (size < 10 || size > 1000) throw out_of_range(10, 1000, "cells per metre of the T-shirt");
        s.tshirt.cells_per_metre = static_cast<float>(size);
        return;
    case ClothType::outline: {
        if (size < 10 || size > 1000)
            throw out_of_range(10, 1000, "cells per metre of the outline: spacing 1 / size m");
        const float spacing = 1.0f / static_cast<float>(size);
        const double points = outline_panel_point_estimate(s.outline.outline, spacing);
        const std::size_t max_points = OutlinePanelParams{}.max_points;
        if (points > double(max_points))
            throw InvalidInput(flag + " " + std::to_string(size) + ": a spacing of " + format_number(spacing) +
                               " m gives this outline up to " + format_number(std::floor(points)) +
                               " points per panel; at most " + std::to_string(max_points) + " are allowed");
        s.outline.spacing = spacing;
        return;
    }
    case ClothType::mesh:
        throw InvalidInput(flag + ": the scene's cloth is a mesh; its resolution is that of its OBJ file");
    case ClothType::mask:
        throw InvalidInput(flag + ": the scene's cloth is made of masks; its resolution is their cells "
                                  "(cloth.panels[k].rows and cell_size)");
    }
}

} // namespace drape
