// Scene files: strict JSON reading (every field typed and range-checked, unknown fields refused, messages naming the
// file and the JSON path) and cooking a SceneSpec into a cloth plus simulation parameters.
#include "drape/scene.hpp"

#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "drape/errors.hpp"
#include "drape/stability.hpp"

namespace drape {

// Generated at build time from scenes/*.json (cmake/embed_scenes.cmake).
extern const char* const builtin_scene_json[];
extern const char* const builtin_scene_json_names[];
extern const std::size_t builtin_scene_json_count;

namespace {

using json = nlohmann::json;

std::string format_number(double v) {
    std::ostringstream out;
    out << v;
    return out.str();
}

/// Reads one JSON object: typed, range-checked fields; remembers which keys were read so that finish() can refuse
/// unknown ones.
class ObjectReader {
  public:
    ObjectReader(const json& j, std::string path, const std::string& source) : j_(j), path_(std::move(path)), source_(source) {
        if (!j_.is_object()) fail(path_.empty() ? "the document" : path_, "must be a JSON object");
    }

    [[noreturn]] void fail(const std::string& where, const std::string& what) const {
        throw InvalidInput(source_ + ": " + where + " " + what);
    }
    std::string at(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
    bool has(const std::string& key) const { return j_.contains(key); }

    double number(const std::string& key, double lo, double hi, const char* unit, double fallback) {
        seen_.insert(key);
        if (!j_.contains(key)) return fallback;
        const json& v = j_[key];
        if (!v.is_number()) fail(at(key), "must be a number in [" + format_number(lo) + ", " + format_number(hi) + "]" + unit);
        const double d = v.get<double>();
        if (!(d >= lo && d <= hi))
            fail(at(key), "= " + format_number(d) + " is outside the allowed range [" + format_number(lo) + ", " +
                              format_number(hi) + "]" + unit);
        return d;
    }
    std::uint32_t integer(const std::string& key, std::uint32_t lo, std::uint32_t hi, std::uint32_t fallback) {
        seen_.insert(key);
        if (!j_.contains(key)) return fallback;
        const json& v = j_[key];
        if (!v.is_number_integer() && !(v.is_number() && std::floor(v.get<double>()) == v.get<double>()))
            fail(at(key), "must be a whole number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
        const double d = v.get<double>();
        if (!(d >= lo && d <= hi))
            fail(at(key), "= " + format_number(d) + " is outside the allowed range [" + std::to_string(lo) + ", " +
                              std::to_string(hi) + "]");
        return static_cast<std::uint32_t>(d);
    }
    bool boolean(const std::string& key, bool fallback) {
        seen_.insert(key);
        if (!j_.contains(key)) return fallback;
        if (!j_[key].is_boolean()) fail(at(key), "must be true or false");
        return j_[key].get<bool>();
    }
    std::string text(const std::string& key, const std::vector<std::string>& allowed, const std::string& fallback) {
        seen_.insert(key);
        if (!j_.contains(key)) return fallback;
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + ("\"" + a + "\"");
        if (!j_[key].is_string()) fail(at(key), allowed.empty() ? "must be a string" : "must be one of " + list);
        const std::string s = j_[key].get<std::string>();
        if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), s) == allowed.end())
            fail(at(key), "= \"" + s + "\" is not one of " + list);
        if (s.size() > 4096) fail(at(key), "is longer than 4096 characters");
        return s;
    }
    std::array<float, 3> vec3(const std::string& key, double limit, const char* unit, std::array<float, 3> fallback) {
        seen_.insert(key);
        if (!j_.contains(key)) return fallback;
        const json& v = j_[key];
        if (!v.is_array() || v.size() != 3)
            fail(at(key), std::string("must be an array of 3 numbers in [-") + format_number(limit) + ", " +
                              format_number(limit) + "]" + unit);
        std::array<float, 3> out{};
        for (int k = 0; k < 3; ++k) {
            if (!v[k].is_number()) fail(at(key) + "[" + std::to_string(k) + "]", "must be a number");
            const double d = v[k].get<double>();
            if (!(std::fabs(d) <= limit))
                fail(at(key) + "[" + std::to_string(k) + "]", "= " + format_number(d) + " is outside the allowed range [-" +
                                                                  format_number(limit) + ", " + format_number(limit) +
                                                                  "]" + unit);
            out[k] = static_cast<float>(d);
        }
        return out;
    }
    /// A nested object (absent = empty object).
    ObjectReader object(const std::string& key) {
        seen_.insert(key);
        static const json empty = json::object();
        return ObjectReader(j_.contains(key) ? j_[key] : empty, at(key), source_);
    }
    const json* array(const std::string& key, std::size_t max_items) {
        seen_.insert(key);
        if (!j_.contains(key)) return nullptr;
        if (!j_[key].is_array()) fail(at(key), "must be an array");
        if (j_[key].size() > max_items) fail(at(key), "has " + std::to_string(j_[key].size()) + " entries (at most " +
                                                          std::to_string(max_items) + ")");
        return &j_[key];
    }
    void finish() const {
        for (auto it = j_.begin(); it != j_.end(); ++it)
            if (!seen_.count(it.key())) fail(at(it.key()), "is not a known field");
    }
    const std::string& source() const { return source_; }

  private:
    const json& j_;
    std::string path_;
    const std::string& source_;
    std::set<std::string> seen_;
};

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
    } catch (const InvalidInput& e) {
        r.fail(r.at("type") + " \"" + type + "\":", e.what());
    }
    r.finish();
    return c;
}

} // namespace

std::vector<std::string> builtin_scene_names() {
    std::vector<std::string> out;
    for (std::size_t k = 0; k < builtin_scene_json_count; ++k) out.emplace_back(builtin_scene_json_names[k]);
    return out;
}

SceneSpec parse_scene(const std::string& text, const std::string& source) {
    if (text.size() > (std::size_t{16} << 20)) throw InvalidInput(source + ": file is larger than 16 MiB");
    json doc;
    try {
        doc = json::parse(text);
    } catch (const json::parse_error& e) {
        throw InvalidInput(source + ": malformed JSON: " + e.what());
    }
    ObjectReader root(doc, "", source);
    SceneSpec s;
    s.name = root.text("scene", {}, "unnamed");
    s.description = root.text("description", {}, "");

    // cloth
    ObjectReader cloth = root.object("cloth");
    const std::string type = cloth.text("type", {"grid", "tshirt", "outline"}, "grid");
    s.cloth = type == "tshirt" ? ClothType::tshirt : type == "outline" ? ClothType::outline : ClothType::grid;
    if (s.cloth == ClothType::outline) {
        OutlineClothSpec& o = s.outline;
        const json* pts = cloth.array("outline", 4096);
        if (!pts || pts->size() < 3) cloth.fail(cloth.at("outline"), "must list 3 to 4096 [u, v] vertices (m)");
        for (std::size_t k = 0; k < pts->size(); ++k) {
            const json& v = (*pts)[k];
            const std::string where = cloth.at("outline") + "[" + std::to_string(k) + "]";
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
                if (!v.is_array() || v.size() != 2 || !v[0].is_number_unsigned() || !v[1].is_number_unsigned() ||
                    v[0].get<std::uint64_t>() >= pts->size() || v[1].get<std::uint64_t>() >= pts->size())
                    cloth.fail(where, "must be [from vertex, to vertex], indices in [0, " +
                                          std::to_string(pts->size() - 1) + "]");
                o.sew.push_back({v[0].get<std::uint32_t>(), v[1].get<std::uint32_t>()});
            }
        }
        copy.finish();
        try {
            check_outline(o.outline);
        } catch (const InvalidInput& e) {
            cloth.fail(cloth.at("outline") + ":", e.what());
        }
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
        // Node mass in seed 000's range 0.001 - 1 g.
        const double node_mass = double(g.total_mass) / (double(g.n) * g.n);
        if (!(node_mass >= 1e-6 * 0.999 && node_mass <= 1e-3 * 1.001))
            cloth.fail(cloth.at("mass"), "gives a node mass of " + format_number(node_mass * 1000.0) +
                                             " g; allowed range [0.001, 1] g per particle (seed 000)");
    } else {
        TShirtParams& t = s.tshirt;
        t.cells_per_metre = static_cast<float>(cloth.number("cells_per_metre", 10.0, 1000.0, " 1/m", t.cells_per_metre));
        t.total_mass = static_cast<float>(cloth.number("mass", 0.001, 10.0, " kg", t.total_mass));
        t.shoulder_y = static_cast<float>(cloth.number("shoulder_y", -10.0, 10.0, " m", t.shoulder_y));
        t.gap = static_cast<float>(cloth.number("gap", 0.001, 2.0, " m", t.gap));
        t.seam_rest_ratio = static_cast<float>(cloth.number("seam_rest_ratio", 0.01, 2.0, "", t.seam_rest_ratio));
    }
    cloth.finish();

    // material
    ObjectReader mat = root.object("material");
    s.stiffness = static_cast<float>(mat.number("stiffness", 100.0, 25000.0, " N/m", s.stiffness));
    s.shear_ratio = static_cast<float>(mat.number("shear_ratio", 0.0, 1.0, "", s.shear_ratio));
    s.bend_ratio = static_cast<float>(mat.number("bend_ratio", 0.0, 1.0, "", s.bend_ratio));
    s.damping_ratio = static_cast<float>(mat.number("damping_ratio", 0.0, 1.0, "", s.damping_ratio));
    s.seam_stiffness = static_cast<float>(mat.number("seam_stiffness", 100.0, 25000.0, " N/m", s.seam_stiffness));
    mat.finish();

    // physics
    ObjectReader ph = root.object("physics");
    SimulationParams& p = s.physics;
    p.gravity = ph.vec3("gravity", 100.0, " m/s^2", p.gravity);
    p.air_drag = static_cast<float>(ph.number("drag", 0.0, 100.0, " 1/s", p.air_drag));
    p.integrator = ph.text("integrator", {"euler", "verlet"}, "euler") == "verlet" ? Integrator::verlet
                                                                                 : Integrator::symplectic_euler;
    if (ph.has("dt")) s.dt = static_cast<float>(ph.number("dt", 1e-9, 0.1, " s", 0.0));
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
    ph.finish();

    // colliders
    if (const json* list = root.array("colliders", 64)) {
        for (std::size_t k = 0; k < list->size(); ++k) {
            ObjectReader r((*list)[k], "colliders[" + std::to_string(k) + "]", source);
            p.colliders.push_back(read_collider(r));
        }
    }
    s.body = root.boolean("body", false);

    root.finish();

    const std::size_t particles = scene_particle_count(s);
    if (particles > (std::size_t{1} << 24))
        throw InvalidInput(source + ": the cloth would have " + std::to_string(particles) +
                           " particles; at most 16,777,216 are allowed");
    return s;
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
    std::ifstream in(name_or_path, std::ios::binary);
    if (!in) throw InvalidInput(name_or_path + ": cannot open the scene file");
    in.seekg(0, std::ios::end);
    const auto size = in.tellg();
    if (size < 0) throw InvalidInput(name_or_path + ": cannot read the scene file");
    if (size > (std::streamoff{16} << 20)) throw InvalidInput(name_or_path + ": file is larger than 16 MiB");
    in.seekg(0);
    std::string text(static_cast<std::size_t>(size), '\0');
    in.read(text.data(), size);
    return parse_scene(text, name_or_path);
}

std::size_t scene_particle_count(const SceneSpec& s) {
    if (s.cloth == ClothType::grid) return std::size_t{s.grid.n} * s.grid.n;
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

BuiltScene build_scene(const SceneSpec& s) {
    BuiltScene out;
    if (s.cloth == ClothType::grid) {
        HangParams g = s.grid;
        g.stiffness = s.stiffness;
        g.shear_ratio = s.shear_ratio;
        g.bend_ratio = s.bend_ratio;
        g.damping_ratio = s.damping_ratio;
        SceneBuild b = build_hang_scene(g);
        out.cloth = std::move(b.cloth);
        out.initial = std::move(b.initial);
    } else if (s.cloth == ClothType::outline) {
        const OutlineClothSpec& o = s.outline;
        double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
        for (const auto& v : o.outline.outline)
            for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
        const float cu = float(0.5 * (lo[0] + hi[0])), cv = float(0.5 * (lo[1] + hi[1]));
        // Panel frame: u along +x; v along +z (horizontal) or -y (vertical); the normal u x v is -y or -z.
        PanelFrame frame;
        frame.axis_v = o.plane == GridPlane::horizontal ? std::array{0.0f, 0.0f, 1.0f} : std::array{0.0f, -1.0f, 0.0f};
        const std::array<float, 3> normal = o.plane == GridPlane::horizontal ? std::array{0.0f, -1.0f, 0.0f}
                                                                           : std::array{0.0f, 0.0f, -1.0f};
        const float half_gap = o.copy ? 0.5f * o.gap : 0.0f;
        for (int k = 0; k < 3; ++k)
            frame.origin[k] = o.centre[k] - cu * frame.axis_u[k] - cv * frame.axis_v[k] - half_gap * normal[k];
        OutlinePanelParams op;
        op.spacing = o.spacing;
        op.areal_density = o.density;
        GarmentAssembly a;
        const OutlinePanelBuild front = add_outline_panel(a, o.outline, op, frame);
        if (o.copy) {
            PanelFrame back = frame;
            for (int k = 0; k < 3; ++k) back.origin[k] += 2.0f * half_gap * normal[k];
            const OutlinePanelBuild rear = add_outline_panel(a, o.outline, op, back);
            for (const auto& [from, to] : o.sew) {
                const OutlineStretch stretch{from, to, false};
                sew_by_arc_length(a, outline_stretch_particles(front, stretch), outline_stretch_particles(rear, stretch),
                                  o.seam_rest_ratio * o.spacing);
            }
        }
        std::vector<float> inv_mass = a.inverse_masses();
        const std::vector<float> free_inv_mass = inv_mass;
        if (o.pin_top) { // the particles along the top (vertical) or the far edge (horizontal: largest z)
            const bool vertical = o.plane == GridPlane::vertical;
            float top = -1e30f;
            for (std::size_t i = 0; i < a.particle_count(); ++i) top = std::max(top, vertical ? a.y[i] : a.z[i]);
            for (std::size_t i = 0; i < a.particle_count(); ++i)
                if ((vertical ? a.y[i] : a.z[i]) >= top - 0.25f * o.spacing) inv_mass[i] = 0.0f;
        }
        // Material: stiffness per kind as for the other cloths; the damping ratio uses the mean particle mass.
        double total = 0.0;
        for (float m : a.mass) total += m;
        const float mean_mass = float(total / double(std::max<std::size_t>(1, a.particle_count())));
        std::array<SpringMaterial, spring_kind_count> material{};
        const float ks[4] = {s.stiffness, s.stiffness * s.shear_ratio, s.stiffness * s.bend_ratio, s.seam_stiffness};
        for (int kind = 0; kind < 4; ++kind)
            material[kind] = {ks[kind], s.damping_ratio * 2.0f * std::sqrt(ks[kind] * mean_mass * 0.5f)};
        out.cloth = cook_cloth(inv_mass, a.edges, material);
        out.cloth.triangles = a.triangles;
        out.cloth.free_inv_mass = free_inv_mass;
        out.initial = a.initial_state();
    } else {
        const TShirtBuild t = build_tshirt(s.tshirt);
        const GarmentAssembly& a = t.assembly;
        const float mass = s.tshirt.total_mass / static_cast<float>(a.particle_count());
        std::array<SpringMaterial, spring_kind_count> material{};
        const float ks[4] = {s.stiffness, s.stiffness * s.shear_ratio, s.stiffness * s.bend_ratio, s.seam_stiffness};
        for (int kind = 0; kind < 4; ++kind)
            material[kind] = {ks[kind], s.damping_ratio * 2.0f * std::sqrt(ks[kind] * mass * 0.5f)};
        out.cloth = cook_cloth(a.inverse_masses(), a.edges, material);
        out.cloth.triangles = a.triangles;
        out.initial = a.initial_state();
    }
    out.params = s.physics;
    if (s.body) {
        const std::vector<Collider> body = default_body();
        out.params.colliders.insert(out.params.colliders.end(), body.begin(), body.end());
    }
    out.params.dt = s.dt ? *s.dt : static_cast<float>(default_dt(out.cloth, out.params));
    return out;
}

} // namespace drape
