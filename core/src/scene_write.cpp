// Scene files out: SceneSpec (+ state) -> JSON text in the format parse_scene reads, and the atomic file write.
#include "drape/scene_write.hpp"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "drape/errors.hpp"

namespace drape {

namespace {

/// A float as the shortest decimal that reads back (as a double, then rounded to float: parse_scene's path) to the
/// same bits; max_digits10 (9) digits if the shortest form ever failed that.
std::string num(float f) {
    if (f == 0.0f) return std::signbit(f) ? "-0.0" : "0"; // "-0" would read back as the integer 0
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, f);
    std::string s(buf, r.ptr);
    if (static_cast<float>(std::strtod(s.c_str(), nullptr)) != f) {
        std::snprintf(buf, sizeof buf, "%.9g", double(f));
        s = buf;
    }
    return s;
}
/// A double (outline vertices) the same way, max_digits10 = 17.
std::string num(double d) {
    if (d == 0.0) return std::signbit(d) ? "-0.0" : "0";
    char buf[64];
    const auto r = std::to_chars(buf, buf + sizeof buf, d);
    std::string s(buf, r.ptr);
    if (std::strtod(s.c_str(), nullptr) != d) {
        std::snprintf(buf, sizeof buf, "%.17g", d);
        s = buf;
    }
    return s;
}
std::string num(std::uint32_t u) { return std::to_string(u); }
std::string str(const std::string& s) { return nlohmann::json(s).dump(); }
std::string boolean(bool b) { return b ? "true" : "false"; }
std::string vec(const std::array<float, 3>& v) {
    std::string out = "[";
    out += num(v[0]);
    out += ", ";
    out += num(v[1]);
    out += ", ";
    out += num(v[2]);
    out += "]";
    return out;
}

/// "key": value pairs of one object on one line.
class Fields {
  public:
    Fields& add(const std::string& key, const std::string& value) {
        text_ += (text_.empty() ? "" : ", ") + str(key) + ": " + value;
        return *this;
    }
    std::string object() const { return "{ " + text_ + " }"; }

  private:
    std::string text_;
};

std::string collider_json(const Collider& c, std::size_t index) {
    Fields f;
    switch (c.kind) {
    case ColliderKind::plane:
        if (c.axis == Vec3f{0.0f, 1.0f, 0.0f} && c.centre[0] == 0.0f && c.centre[2] == 0.0f)
            f.add("type", str("ground")).add("height", num(c.centre[1]));
        else
            f.add("type", str("plane")).add("point", vec(c.centre)).add("normal", vec(c.axis));
        break;
    case ColliderKind::sphere:
        f.add("type", str("sphere")).add("centre", vec(c.centre)).add("radius", num(c.size[0]));
        break;
    case ColliderKind::disc:
        f.add("type", str("disc")).add("top_centre", vec(c.centre)).add("radius", num(c.size[0]))
            .add("height", num(c.size[1]));
        break;
    case ColliderKind::capsule:
        f.add("type", str("capsule")).add("a", vec(c.centre)).add("b", vec(c.axis)).add("radius", num(c.size[0]));
        break;
    case ColliderKind::ellipsoid:
        if (c.rotation != std::array<float, 9>{1, 0, 0, 0, 1, 0, 0, 0, 1})
            throw InvalidInput("colliders[" + std::to_string(index) +
                               "]: a rotated ellipsoid cannot be written (scene files have no collider rotation)");
        f.add("type", str("ellipsoid")).add("centre", vec(c.centre)).add("semi_axes", vec(c.size));
        break;
    }
    f.add("thickness", num(c.thickness)).add("friction", num(c.friction));
    return f.object();
}

std::string cloth_json(const SceneSpec& s, const std::filesystem::path& relative_to) {
    Fields f;
    switch (s.cloth) {
    case ClothType::grid: {
        const HangParams& g = s.grid;
        const char* pins = g.pins == GridPins::corners    ? "corners"
                           : g.pins == GridPins::top_edge ? "top_edge"
                           : g.pins == GridPins::left_edge ? "left_edge"
                                                           : "none";
        f.add("type", str("grid")).add("n", num(g.n)).add("size", num(g.size));
        if (s.model == MaterialModel::springs) f.add("mass", num(g.total_mass));
        f.add("plane", str(g.plane == GridPlane::vertical ? "vertical" : "horizontal"))
            .add("centre", vec(g.centre)).add("pins", str(pins)).add("pin_radius", num(g.pin_radius));
        break;
    }
    case ClothType::tshirt: {
        const TShirtParams& t = s.tshirt;
        f.add("type", str("tshirt")).add("cells_per_metre", num(t.cells_per_metre));
        if (s.model == MaterialModel::springs) f.add("mass", num(t.total_mass));
        f.add("shoulder_y", num(t.shoulder_y)).add("gap", num(t.gap)).add("seam_rest_ratio", num(t.seam_rest_ratio));
        f.add("mirror_exact", boolean(t.mirror_exact));
        break;
    }
    case ClothType::outline: {
        const OutlineClothSpec& o = s.outline;
        std::string pts;
        for (const auto& v : o.outline.outline) pts += (pts.empty() ? "" : ", ") + ("[" + num(v[0]) + ", " + num(v[1]) + "]");
        f.add("type", str("outline")).add("outline", "[" + pts + "]").add("spacing", num(o.spacing));
        if (s.model == MaterialModel::springs) f.add("density", num(o.density));
        f.add("plane", str(o.plane == GridPlane::vertical ? "vertical" : "horizontal"))
            .add("centre", vec(o.centre)).add("pins", str(o.pin_top ? "top_edge" : "none"));
        if (o.copy) {
            std::string sew;
            for (const auto& [a, b] : o.sew) sew += (sew.empty() ? "" : ", ") + ("[" + num(a) + ", " + num(b) + "]");
            Fields c;
            c.add("gap", num(o.gap)).add("seam_rest_ratio", num(o.seam_rest_ratio)).add("sew", "[" + sew + "]");
            f.add("copy", c.object());
        }
        break;
    }
    case ClothType::mask: {
        const MaskClothSpec& m = s.masks;
        const auto cell = [](const std::array<std::uint32_t, 2>& c) {
            std::string out(1, '['); // (built up: GCC 12 warns falsely on "[" + std::string, -Wrestrict)
            out += num(c[0]);
            out += ", ";
            out += num(c[1]);
            out += ']';
            return out;
        };
        std::string panels;
        for (const MaskPanelSpec& p : m.panels) {
            std::string rows, pins;
            for (const std::string& r : p.mask.rows)
                rows += (rows.empty() ? "\n        " : ",\n        ") + str(r);
            if (p.pins == MaskPins::list) {
                for (const auto& c : p.pin_cells)
                    pins += (pins.empty() ? "" : ", ") + cell(c);
                pins = "[" + pins + "]";
            } else {
                pins = str(p.pins == MaskPins::top_row ? "top_row" : "none");
            }
            Fields pf;
            pf.add("name", str(p.name))
                .add("cell_size", num(p.cell_size))
                .add("origin", "[" + num(p.origin[0]) + ", " + num(p.origin[1]) + ", " + num(p.origin[2]) + "]")
                .add("axis_u", vec(p.axis_u))
                .add("axis_v", vec(p.axis_v))
                .add("pins", pins)
                .add("rows", "[" + rows + "]");
            panels += (panels.empty() ? "\n      " : ",\n      ") + pf.object();
        }
        std::string seams;
        for (const MaskSeamSpec& seam : m.seams) {
            const auto edge = [&](const MaskEdgeSpec& e) {
                std::string path;
                for (const auto& c : e.path)
                    path += (path.empty() ? "" : ", ") + cell(c);
                Fields ef;
                ef.add("panel", str(m.panels.at(e.panel).name)).add("path", "[" + path + "]");
                return ef.object();
            };
            Fields sf;
            sf.add("a", edge(seam.a)).add("b", edge(seam.b)).add("rest_ratio", num(seam.rest_ratio));
            seams += (seams.empty() ? "\n      " : ",\n      ") + sf.object();
        }
        f.add("type", str("mask"));
        if (s.model == MaterialModel::springs) f.add("density", num(m.density));
        f.add("panels", "[" + panels + "\n    ]").add("seams", "[" + seams + (seams.empty() ? "]" : "\n    ]"));
        break;
    }
    case ClothType::mesh: {
        const MeshClothSpec& m = s.mesh;
        std::filesystem::path file = std::filesystem::absolute(m.file).lexically_normal();
        if (!relative_to.empty()) {
            const std::filesystem::path rel = file.lexically_relative(std::filesystem::absolute(relative_to).lexically_normal());
            if (!rel.empty()) file = rel;
        }
        std::string pins;
        if (m.pins == MeshPins::list) {
            for (std::uint32_t v : m.pin_vertices) pins += (pins.empty() ? "" : ", ") + num(v);
            pins = "[" + pins + "]";
        } else {
            pins = str(m.pins == MeshPins::top ? "top" : "none");
        }
        f.add("type", str("mesh")).add("file", str(file.generic_string()));
        if (s.model == MaterialModel::springs) f.add("density", num(m.density));
        f.add("scale", num(m.scale)).add("centre", vec(m.centre)).add("pins", pins);
        break;
    }
    }
    return f.object();
}

/// A fabric figure in file units (SI x scale): the shortest float text when reading it back (as parse_scene does:
/// double / scale, rounded to float) gives the same bits, else the exact double (a float times 1000 or 1e6 is exact
/// in a double, and the division gives the float back).
std::string scaled(float si, double scale) {
    const std::string pretty = num(static_cast<float>(double(si) * scale));
    if (static_cast<float>(std::strtod(pretty.c_str(), nullptr) / scale) == si) return pretty;
    return num(double(si) * scale);
}

/// The material: the fabric's every figure in file units, naming its preset when it is one unchanged; or the
/// springs.
std::string material_json(const SceneSpec& s) {
    Fields mat;
    if (s.model == MaterialModel::fabric) {
        const Fabric& f = s.fabric;
        mat.add("model", str("fabric"));
        if (find_fabric(f.name)) mat.add("fabric", str(f.name));
        mat.add("density_gsm", scaled(f.density, fabric_gsm_per_kg_m2)).add("stretch_u", num(f.stretch_u))
            .add("stretch_v", num(f.stretch_v)).add("shear", num(f.shear))
            .add("bend_u_uNm", scaled(f.bend_u, fabric_uNm_per_Nm))
            .add("bend_v_uNm", scaled(f.bend_v, fabric_uNm_per_Nm)).add("damping", num(f.damping));
    } else {
        mat.add("model", str("springs")).add("stiffness", num(s.stiffness)).add("shear_ratio", num(s.shear_ratio))
            .add("bend_ratio", num(s.bend_ratio)).add("damping_ratio", num(s.damping_ratio));
    }
    mat.add("seam_stiffness", num(s.seam_stiffness));
    return mat.object();
}

std::string state_json(const SceneState& st) {
    const std::size_t n = st.x.size();
    for (const std::vector<float>* v : {&st.y, &st.z, &st.vx, &st.vy, &st.vz})
        if (v->size() != n)
            throw InvalidInput("scene state: " + std::to_string(n) + " x positions but an array of " +
                               std::to_string(v->size()) + " entries");
    for (const std::vector<float>* v : {&st.snapshot_x, &st.snapshot_y, &st.snapshot_z})
        if (!v->empty() && v->size() != n)
            throw InvalidInput("scene state: " + std::to_string(n) + " x positions but an array of " +
                               std::to_string(v->size()) + " entries");
    char origin[128];
    std::snprintf(origin, sizeof origin, "[%.17g, %.17g, %.17g]", st.origin[0], st.origin[1], st.origin[2]);
    std::string out = "{\n    \"origin\": " + std::string(origin) + ",\n    \"positions\": [";
    out.reserve(n * 80 + 64);
    for (std::size_t i = 0; i < n; ++i)
        out += std::string(i ? "," : "") + "\n      [" + num(st.x[i]) + ", " + num(st.y[i]) + ", " + num(st.z[i]) + "]";
    out += "\n    ],\n    \"velocities\": [";
    for (std::size_t i = 0; i < n; ++i)
        out += std::string(i ? "," : "") + "\n      [" + num(st.vx[i]) + ", " + num(st.vy[i]) + ", " + num(st.vz[i]) + "]";
    out += "\n    ],\n    \"pinned\": [";
    for (std::size_t k = 0; k < st.pinned.size(); ++k) out += (k ? ", " : "") + num(st.pinned[k]);
    out += "]";
    if (!st.seam_rest.empty()) {
        out += ",\n    \"seam_rest\": [";
        for (std::size_t k = 0; k < st.seam_rest.size(); ++k) out += (k ? ", " : "") + num(st.seam_rest[k]);
        out += "]";
    }
    if (!st.snapshot_x.empty()) {
        out += ",\n    \"self_collision_snapshot\": [";
        for (std::size_t i = 0; i < st.snapshot_x.size(); ++i)
            out += std::string(i ? "," : "") + "\n      [" + num(st.snapshot_x[i]) + ", " + num(st.snapshot_y[i]) + ", " +
                   num(st.snapshot_z[i]) + "]";
        out += "\n    ]";
    }
    const SelfCollisionPlanes& pl = st.sc_planes;
    if (!pl.index.empty()) {
        out += ",\n    \"self_collision_planes\": [";
        for (std::size_t k = 0; k < pl.index.size(); ++k)
            out += std::string(k ? "," : "") + "\n      [" + std::to_string(pl.index[k]) + ", " +
                   std::to_string(pl.partner[k]) + ", " + num(pl.nx[k]) + ", " +
                   num(pl.ny[k]) + ", " + num(pl.nz[k]) + ", " + num(pl.c[k]) + "]";
        out += "\n    ]";
    }
    out += "\n  }";
    return out;
}

std::string to_json(const SceneSpec& s, const SceneState* state, const std::filesystem::path& relative_to) {
    std::string out = "{\n";
    out += "  \"scene\": " + str(s.name) + ",\n";
    out += "  \"description\": " + str(s.description) + ",\n";
    out += "  \"cloth\": " + cloth_json(s, relative_to) + ",\n";
    out += "  \"material\": " + material_json(s) + ",\n";
    const SimulationParams& p = s.physics;
    Fields ph, wind, aero, sl;
    wind.add("enabled", boolean(p.wind.enabled)).add("strength", num(p.wind.strength));
    aero.add("enabled", boolean(p.aero.enabled)).add("density", num(p.aero.density))
        .add("drag_coefficient", num(p.aero.drag_coefficient)).add("velocity", vec(p.aero.velocity));
    sl.add("ratio", num(p.strain_limit.ratio)).add("passes", num(p.strain_limit.passes))
        .add("every", num(p.strain_limit.every));
    ph.add("gravity", vec(p.gravity)).add("drag", num(p.air_drag))
        .add("integrator", str(p.integrator == Integrator::verlet ? "verlet" : "euler"))
        .add("solver", str(solver_name(p.solver)));
    if (s.dt) ph.add("dt", num(*s.dt));
    if (p.sewing_speed != SimulationParams{}.sewing_speed) ph.add("sewing_speed", num(p.sewing_speed)); // 0: off
    Fields im;
    im.add("iterations", num(p.implicit.iterations)).add("tolerance", num(p.implicit.tolerance))
        .add("chebyshev_rho", num(p.implicit.chebyshev_rho))
        .add("method", str(p.implicit.method == ImplicitMethod::jacobi ? "jacobi" : "gauss_seidel"));
    if (p.implicit.fas) im.add("fas", boolean(true));
    if (p.implicit.fas_at_rest) im.add("fas_at_rest", boolean(true));
    if (!p.implicit.multilevel) im.add("multilevel", boolean(false));
    ph.add("implicit", im.object());
    ph.add("wind", wind.object()).add("aero", aero.object()).add("strain_limit", sl.object());
    if (p.self_collision.thickness > 0.0f) { // off: left out, as scenes written before it
        Fields sc;
        sc.add("thickness", num(p.self_collision.thickness)).add("friction", num(p.self_collision.friction));
        if (p.self_collision.substeps != SelfCollision{}.substeps) sc.add("substeps", num(p.self_collision.substeps));
        ph.add("self_collision", sc.object());
    }
    out += "  \"physics\": " + ph.object() + ",\n";
    out += "  \"colliders\": [";
    for (std::size_t k = 0; k < p.colliders.size(); ++k)
        out += std::string(k ? "," : "") + "\n    " + collider_json(p.colliders[k], k);
    out += p.colliders.empty() ? "],\n" : "\n  ],\n";
    out += "  \"body\": " + boolean(s.body);
    if (state) out += ",\n  \"state\": " + state_json(*state);
    out += "\n}\n";
    return out;
}

} // namespace

std::string scene_to_json(const SceneSpec& spec, const SceneState* state) { return to_json(spec, state, {}); }

void save_scene(const std::string& path, const SceneSpec& spec, const SceneState* state) {
    // Through a symbolic link (a chain of them, a dangling one): the file it points to is written (renaming over the
    // link replaced the link with a file and left its target as it was). Relative paths in the file stay relative
    // to the name the user gave, as load_scene reads them; messages keep that name.
    const std::filesystem::path given(path);
    std::filesystem::path target = given;
    std::error_code ec;
    for (int hops = 0; hops < 40 && std::filesystem::is_symlink(target, ec); ++hops) {
        const std::filesystem::path to = std::filesystem::read_symlink(target, ec);
        if (ec) break;
        target = to.is_absolute() ? to : target.parent_path() / to;
    }
    if (std::filesystem::is_symlink(target, ec))
        throw std::runtime_error(path + ": cannot write the scene file (a loop of symbolic links)");
    const std::filesystem::path dir = given.parent_path();
    const std::string text = to_json(spec, state, dir.empty() ? std::filesystem::path(".") : dir);
    if (text.size() > scene_file_max_bytes) { // load_scene's limit: said here as what it is, not as a load error
        char msg[300];
        std::snprintf(msg, sizeof msg,
                      ": not written: the scene%s would be %.1f MiB, over the %zu MiB a scene file may hold; "
                      "nothing was changed on disk%s",
                      state ? " with its state" : "", double(text.size()) / double(1 << 20), scene_file_max_bytes >> 20,
                      state ? " (save it without the state, or a cloth of fewer particles)" : "");
        throw InvalidInput(path + msg);
    }
    try {
        (void)parse_scene(text, path, dir.string());
    } catch (const InvalidInput& e) {
        throw InvalidInput(path + ": not written, the scene would not load back: " + e.what());
    }
    // Temp file beside the target (same file system, so rename is atomic), then rename over it.
    std::string tmp = target.string() + ".tmp-XXXXXX";
    const int fd = ::mkstemp(tmp.data());
    if (fd < 0) throw std::runtime_error(path + ": cannot write the scene file (" + std::strerror(errno) + ")");
    std::size_t done = 0;
    while (done < text.size()) {
        const ssize_t w = ::write(fd, text.data() + done, text.size() - done);
        if (w < 0 && errno == EINTR) continue;
        if (w <= 0) {
            const std::string why = std::strerror(errno);
            ::close(fd);
            ::unlink(tmp.c_str());
            throw std::runtime_error(path + ": cannot write the scene file (" + why + ")");
        }
        done += static_cast<std::size_t>(w);
    }
    if (::fsync(fd) != 0 || ::close(fd) != 0) {
        const std::string why = std::strerror(errno);
        ::unlink(tmp.c_str());
        throw std::runtime_error(path + ": cannot write the scene file (" + why + ")");
    }
    ::chmod(tmp.c_str(), 0644);
    if (std::rename(tmp.c_str(), target.c_str()) != 0) {
        const std::string why = std::strerror(errno);
        ::unlink(tmp.c_str());
        throw std::runtime_error(path + ": cannot write the scene file (" + why + ")");
    }
}

SceneState capture_state(const Simulation& sim) {
    SceneState s;
    s.origin = sim.origin();
    const std::size_t n = sim.cloth().particle_count;
    s.x.assign(sim.x().begin(), sim.x().end());
    s.y.assign(sim.y().begin(), sim.y().end());
    s.z.assign(sim.z().begin(), sim.z().end());
    s.vx.resize(n);
    s.vy.resize(n);
    s.vz.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const std::array<float, 3> v = sim.velocity(i);
        s.vx[i] = v[0];
        s.vy[i] = v[1];
        s.vz[i] = v[2];
        if (sim.is_pinned(i) && i != sim.grabbed()) s.pinned.push_back(static_cast<std::uint32_t>(i));
    }
    const std::span<const float> sewn = sim.seams_being_sewn();
    s.seam_rest.assign(sewn.begin(), sewn.end());
    const std::array<std::span<const float>, 3> snap = sim.self_collision_snapshot();
    s.snapshot_x.assign(snap[0].begin(), snap[0].end());
    s.snapshot_y.assign(snap[1].begin(), snap[1].end());
    s.snapshot_z.assign(snap[2].begin(), snap[2].end());
    s.sc_planes = sim.self_collision_planes();
    return s;
}

} // namespace drape
