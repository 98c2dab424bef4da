// The viewer's model (see view_session.hpp for the stability rules).
#include "view_session.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>
#include <utility>

#include "drape/errors.hpp"
#include "drape/memory_estimate.hpp"
#include "drape/stability.hpp"
#include "materials.hpp"

namespace drape::app {

namespace {

std::string fmt(double v, int precision = 3) {
    std::ostringstream s;
    s.precision(precision);
    s << v;
    return s.str();
}

std::string fixed(double v, int digits) {
    std::ostringstream s;
    s.setf(std::ios::fixed);
    s.precision(digits);
    s << v;
    return s.str();
}

float spec_total_mass(const SceneSpec& s) {
    return s.cloth == ClothType::grid ? s.grid.total_mass : s.tshirt.total_mass;
}

/// Outline, mask and mesh cloths: each particle's mass is the areal density x a third of its triangles' area (as
/// build_scene gives it, CLI and viewer alike), not a total mass spread evenly. The springs model's density field
/// (kg/m^2); null for a grid or the T-shirt.
float* areal_density(SceneSpec& s) {
    switch (s.cloth) {
    case ClothType::outline:
        return &s.outline.density;
    case ClothType::mask:
        return &s.masks.density;
    case ClothType::mesh:
        return &s.mesh.density;
    default:
        return nullptr;
    }
}
bool density_masses(const SceneSpec& s) {
    return areal_density(const_cast<SceneSpec&>(s)) != nullptr;
}

/// Automatic substeps: 1/60 s per frame, capped at view_auto_budget particle-substeps (at least 10).
int auto_substeps_for(std::size_t particles, double dt) {
    const int cap = std::clamp(static_cast<int>(view_auto_budget / double(std::max<std::size_t>(particles, 1))), 10,
                               view_max_substeps);
    const int want = static_cast<int>(std::ceil(view_frame_seconds / dt - 1e-9));
    return std::clamp(want, 1, cap);
}

/// The spec a snapshot builds: the scene at the snapshot's resolution.
/// An outline keeps its own spacing until the resolution is changed (its cells per metre are round(1 / spacing));
/// a mesh or a mask cloth has no resolution control (size 0).
SceneSpec sized_spec(SceneSpec spec, std::uint32_t size) {
    if (spec.cloth == ClothType::grid)
        spec.grid.n = size;
    else if (spec.cloth == ClothType::tshirt)
        spec.tshirt.cells_per_metre = static_cast<float>(size);
    else if (spec.cloth == ClothType::outline && size != 0 && scene_resolution(spec) != size)
        spec.outline.spacing = 1.0f / static_cast<float>(size);
    return spec;
}

/// Typical distance between neighbouring particles, m: the grid's, the T-shirt's or outline's spacing, the smallest
/// mask cell, a mesh's mean edge length.
float view_spacing(const SceneSpec& spec, const Cloth& cloth) {
    switch (spec.cloth) {
    case ClothType::grid:
        return spec.grid.size / float(std::max<std::uint32_t>(spec.grid.n, 2) - 1);
    case ClothType::tshirt:
        return 1.0f / spec.tshirt.cells_per_metre;
    case ClothType::outline:
        return spec.outline.spacing;
    case ClothType::mask: {
        float h = INFINITY;
        for (const MaskPanelSpec& p : spec.masks.panels)
            h = std::min(h, p.cell_size);
        return h;
    }
    case ClothType::mesh:
        break;
    }
    double sum = 0.0;
    std::size_t n = 0;
    for (const Edge& e : cloth.edges)
        if (e.kind == SpringKind::structural) sum += e.rest, ++n;
    return n ? static_cast<float>(sum / double(n)) : 0.01f;
}

double seconds_since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

} // namespace

int implicit_auto_steps(double dt) {
    const double want = std::round(view_frame_seconds / std::max(dt, 1e-9));
    return static_cast<int>(std::clamp(want, 1.0, double(view_implicit_max_auto_steps)));
}

std::uint32_t budget_iterations(double sim_ms, double budget_ms, std::uint32_t current, std::uint32_t ran,
                                std::uint32_t cap) {
    cap = std::max<std::uint32_t>(cap, 1);
    const std::uint32_t floor = std::min(view_min_iterations, cap);
    current = std::clamp(current, floor, cap);
    if (!(sim_ms > 0.0) || !(budget_ms > 0.0)) return current;
    // The cost of a frame is about proportional to the iterations its steps ran (a tolerance may stop them early).
    const double base = double(std::clamp<std::uint32_t>(ran == 0 ? current : ran, 1, current));
    if (sim_ms > budget_ms) {
        const double fit = std::floor(base * budget_ms / sim_ms);
        const std::uint32_t lower = current > floor ? current - 1 : floor;
        return std::clamp(static_cast<std::uint32_t>(std::min(fit, double(lower))), floor, cap);
    }
    if (sim_ms < 0.75 * budget_ms && current < cap) {
        const double fit = std::floor(base * 0.9 * budget_ms / sim_ms);
        const double step = std::max(1.0, std::floor(0.25 * double(current)));
        const double up = std::min(fit, double(current) + step);
        return std::clamp(static_cast<std::uint32_t>(std::max(up, double(current) + 1.0)), floor, cap);
    }
    return current;
}

std::string grouped(std::size_t n) {
    const std::string digits = std::to_string(n);
    std::string out;
    for (std::size_t i = 0; i < digits.size(); ++i) {
        if (i > 0 && (digits.size() - i) % 3 == 0) out.push_back(',');
        out.push_back(digits[i]);
    }
    return out;
}

int ViewSession::hardware_threads() {
    return std::max(1, Workers::hardware());
}

bool same_figures(const Fabric& a, const Fabric& b) noexcept {
    return a.density == b.density && a.stretch_u == b.stretch_u && a.stretch_v == b.stretch_v && a.shear == b.shear &&
           a.bend_u == b.bend_u && a.bend_v == b.bend_v && a.damping == b.damping;
}

namespace {
/// The viewer's own size for the built-in hang (view_default_hang_size). A scene file keeps its own grid, whatever
/// its "scene" name: a file naming itself "hang" with n = 100 opened at 64 x 64 before.
std::optional<std::uint32_t> view_default_size(const std::string& name_or_path, const SceneSpec& spec) {
    if (name_or_path == "hang" && spec.cloth == ClothType::grid) return view_default_hang_size;
    return std::nullopt;
}
} // namespace

ViewSession::ViewSession(const std::string& scene, std::optional<std::uint32_t> size, int threads,
                         std::optional<int> substeps, const std::optional<std::string>& material,
                         const SolverFlags& solver, std::optional<double> dt) {
    SceneSpec spec;
    try {
        spec = load_scene(scene);
    } catch (const InvalidInput& e) {
        throw InvalidInput(std::string("--scene: ") + e.what());
    }
    if (material) apply_material_flag(spec, *material);
    apply_solver_flags(spec, solver);
    if (dt) spec.dt = static_cast<float>(*dt);
    try {
        workers_ = std::make_unique<Workers>(threads);
    } catch (const InvalidInput& e) {
        throw InvalidInput(std::string("--") + e.what());
    }
    if (substeps) {
        auto_substeps_ = false;
        substeps_ = std::clamp(*substeps, 1, view_max_substeps);
    }
    if (!size) size = view_default_size(scene, spec);
    Snapshot target = settings_for(std::move(spec), size);
    // The first build runs here (there is no old cloth to show meanwhile); memory is checked first.
    check_scene_memory(sized_spec(target.spec, target.size),
                       size ? "--size " + std::to_string(*size) : "--scene " + scene);
    Request r;
    r.target = std::move(target);
    r.new_scene = true;
    r.history = History::none;
    install(build(r.target, nullptr, false), r);
    message_ = {};
    single_level_warned_ = thickness_warned_ = inside_warned_ = false;
    warn_about_settings(true); // the one message a start may show
    // An explicit --dt the cloth cannot take is refused (build() would quietly lower it).
    if (dt && params_.solver == Solver::explicit_euler && *dt > dt_bound_)
        throw InvalidInput("--dt: value " + fmt(*dt) + " s is above this cloth's explicit stability bound " +
                           fmt(dt_bound_) + " s (lower it, or use --solver implicit)");
}

ViewSession::~ViewSession() {
    if (step_thread_.joinable()) step_thread_.join();
    if (job_ && job_->thread.joinable()) job_->thread.join();
}

void ViewSession::post(MessageLevel level, std::string text) {
    message_ = {std::move(text), level, std::chrono::steady_clock::now()};
}

ViewSession::Snapshot ViewSession::settings_for(SceneSpec spec, std::optional<std::uint32_t> size) {
    Snapshot t = snapshot();
    if (spec.cloth == ClothType::grid) {
        if (size) {
            if (*size < view_min_size || *size > view_max_size)
                throw InvalidInput("--size: value " + std::to_string(*size) +
                                   " is outside the allowed range [" + std::to_string(view_min_size) + ", " +
                                   std::to_string(view_max_size) + "]");
            spec.grid.n = *size;
        }
        t.size = spec.grid.n;
        t.total_mass = spec.grid.total_mass;
    } else {
        // T-shirt and outline: cells per metre; refused for a mesh or a mask cloth (as `drape run --size`).
        if (size) {
            if (spec.cloth != ClothType::mesh && spec.cloth != ClothType::mask &&
                (*size < view_min_cells || *size > view_max_cells))
                throw InvalidInput("--size: value " + std::to_string(*size) + " is outside the allowed range [" +
                                   std::to_string(view_min_cells) + ", " + std::to_string(view_max_cells) +
                                   "] (cells per metre of the " +
                                   (spec.cloth == ClothType::outline ? "outline" : "T-shirt") + ")");
            set_scene_resolution(spec, *size, "--size");
        }
        t.size = scene_resolution(spec).value_or(0);
        // Density-mass cloths: the mean node mass is set exactly in build(), from the masses build_scene gives.
        t.total_mass = density_masses(spec) ? 0.0f : spec.tshirt.total_mass;
    }
    t.fabric.stiffness = {spec.stiffness, spec.stiffness * spec.shear_ratio, spec.stiffness * spec.bend_ratio,
                          spec.seam_stiffness};
    t.fabric.damping_ratio = spec.damping_ratio;
    t.fabric.model = spec.model;
    t.fabric.fabric = spec.fabric;
    // Node mass: the scene's total over its particles (set exactly in build(), once the count is known; a
    // density-mass cloth's there, from its masses).
    t.fabric.node_mass_g = density_masses(spec)
                               ? view_min_node_mass_g
                               : 1000.0f * t.total_mass / float(std::max<std::size_t>(1, scene_particle_count(spec)));
    t.params = spec.physics;
    // The scene's dt is the implicit step or the explicit substep, whichever solver it runs; the other one's is
    // automatic.
    const bool implicit = spec.physics.solver == Solver::implicit;
    t.implicit_dt = implicit && spec.dt ? double(*spec.dt) : view_implicit_dt;
    t.explicit_dt = 0.0;
    t.params.dt = implicit ? static_cast<float>(t.implicit_dt) : spec.dt ? *spec.dt : 0.0f;
    t.auto_dt = implicit || !spec.dt.has_value();
    t.max_iterations = spec.physics.implicit.iterations;
    t.spec = std::move(spec);
    t.topology = ++topology_counter_;
    return t;
}

std::array<SpringMaterial, spring_kind_count> ViewSession::materials(const FabricSettings& f) {
    std::array<SpringMaterial, spring_kind_count> out{};
    if (f.model == MaterialModel::fabric) { // as the builder derived them (the seam stiffness is the user's)
        for (std::size_t k = 0; k < spring_kind_count; ++k)
            out[k] = {f.stiffness[k], f.derived_damping[k]};
        return out;
    }
    // Damping as a fraction of the critical damping of one spring between two particles: kd = r * 2 sqrt(k m
    // / 2), the same rule the scenes use, so the damping means the same at any resolution and node mass.
    const float m = f.node_mass_g * 1e-3f;
    for (std::size_t k = 0; k < spring_kind_count; ++k)
        out[k] = {f.stiffness[k], f.damping_ratio * 2.0f * std::sqrt(f.stiffness[k] * m * 0.5f)};
    return out;
}

double ViewSession::bound_for(const FabricSettings& f, float air_drag, const AeroWind& aero) const {
    SimulationParams p;
    p.air_drag = air_drag;
    p.aero = aero; // the aerodynamic wind's drag and turning stiffness bound dt too (stability.hpp)
    if (grid_scene()) {
        // The Gershgorin bound is a maximum over particles; in a uniform grid every interior particle of an 8
        // x 8 grid already has all twelve springs, so a small probe cloth with the same node mass, spacing and
        // materials gives the bound of the full cloth without copying it.
        HangParams probe = spec_.grid;
        probe.n = std::min<std::uint32_t>(size_, 8);
        probe.size = spec_.grid.size * float(probe.n - 1) / float(std::max<std::uint32_t>(size_, 2) - 1);
        probe.total_mass = f.node_mass_g * 1e-3f * float(probe.n * probe.n);
        probe.pins = GridPins::none;
        // A fabric: the builder derives the probe's every term (springs, bending, damping) as for the cloth.
        probe.model = f.model;
        probe.fabric = f.fabric;
        SceneBuild s = build_hang_scene(probe);
        if (f.model == MaterialModel::springs) apply_materials(s.cloth, materials(f));
        return stability_bound(s.cloth, p).dt_max;
    }
    // Other cloths: the bound over a copy of the topology with every particle movable (pinned ones too: they
    // may be unpinned later) at the new node mass.
    const Cloth& c = sim_->cloth();
    Cloth probe;
    probe.particle_count = c.particle_count;
    probe.padded_count = c.padded_count;
    probe.inv_mass.reset(c.padded_count);
    const float inv = 1.0f / (f.node_mass_g * 1e-3f);
    // A fabric's or a density-mass cloth's own masses (the springs model's scaled to the new mean node mass).
    const bool own_masses =
        (f.model == MaterialModel::fabric || density_masses(spec_)) && c.free_inv_mass.size() == c.particle_count;
    const float scale = f.model == MaterialModel::springs ? fabric_.node_mass_g / f.node_mass_g : 1.0f;
    for (std::size_t i = 0; i < c.particle_count; ++i)
        probe.inv_mass[i] = own_masses ? c.free_inv_mass[i] * scale : inv;
    probe.edges = c.edges;
    probe.triangles = c.triangles;
    probe.material = materials(f);
    return stability_bound(probe, p).dt_max;
}

int ViewSession::auto_substep_count(double dt) const {
    if (params_.solver == Solver::implicit) return implicit_auto_steps(dt);
    return auto_substeps_for(particle_count(), dt);
}

ViewSession::Built ViewSession::build(Snapshot t, const KeepState* keep_state, bool keep_frame_time) {
    SceneSpec spec = sized_spec(t.spec, t.size);
    const std::size_t count = scene_particle_count(spec);
    const bool fabric = t.fabric.model == MaterialModel::fabric;
    spec.model = t.fabric.model;
    spec.fabric = t.fabric.fabric;
    const bool own_masses = fabric || density_masses(spec); // per-particle masses from build_scene
    if (!fabric) {
        spec.seam_stiffness = t.fabric.stiffness[static_cast<std::size_t>(SpringKind::seam)];
        if (spec.cloth == ClothType::grid)
            spec.grid.total_mass = t.fabric.node_mass_g * 1e-3f * float(count);
        else if (spec.cloth == ClothType::tshirt)
            spec.tshirt.total_mass = std::clamp(t.fabric.node_mass_g * 1e-3f * float(count), 0.001f, 10.0f);
        spec.stiffness = t.fabric.stiffness[0];
        spec.damping_ratio = t.fabric.damping_ratio;
    }
    BuiltScene scene = build_scene(spec);
    Cloth& cloth = scene.cloth;
    if (fabric) {
        // The builder derived every per-element value from the fabric and the mesh: shown, not imposed.
        const DerivedMaterial d = derive_material(cloth);
        // The seams too (the fabric's stiffness across one cell); a cloth without seams keeps the spring model's
        // seam value for a switch back to it.
        const float seam = t.fabric.stiffness[static_cast<std::size_t>(SpringKind::seam)];
        t.fabric.node_mass_g = static_cast<float>(d.node_mass_g_mean);
        t.fabric.stiffness = d.stiffness;
        if (cloth.seams.empty()) t.fabric.stiffness[static_cast<std::size_t>(SpringKind::seam)] = seam;
        t.fabric.derived_damping = d.damping;
    } else if (own_masses) {
        // Density x area, as build_scene gave them (the CLI's masses): the node mass shown is their mean, and the
        // damping uses it (as build_scene's cook does).
        double total = 0.0;
        for (std::size_t i = 0; i < cloth.particle_count; ++i)
            total += 1.0 / double(cloth.free_inv_mass[i]);
        t.total_mass = static_cast<float>(total);
        t.fabric.node_mass_g = static_cast<float>(1000.0 * total / double(cloth.particle_count));
        apply_materials(cloth, materials(t.fabric));
    } else {
        // The exact node mass now that the count is known (the T-shirt's estimate may differ).
        t.fabric.node_mass_g = 1000.0f * spec_total_mass(spec) / float(cloth.particle_count);
        apply_materials(cloth, materials(t.fabric));
    }
    // Pins authored by the scene become user pins: they get their mass back and are pinned after
    // construction, so every pin the user sees can be unpinned (the core restores an unpinned particle's
    // authored mass).
    std::vector<std::uint32_t> authored;
    const float inv = 1.0f / (t.fabric.node_mass_g * 1e-3f);
    const bool free_masses = own_masses && cloth.free_inv_mass.size() == cloth.particle_count;
    for (std::size_t i = 0; i < cloth.particle_count; ++i)
        if (cloth.inv_mass[i] == 0.0f) {
            authored.push_back(static_cast<std::uint32_t>(i));
            cloth.inv_mass[i] = free_masses ? cloth.free_inv_mass[i] : inv;
        }
    t.has_seams = false;
    for (const Edge& e : cloth.edges)
        t.has_seams = t.has_seams || e.kind == SpringKind::seam;

    // Geometry the viewer frames and draws around.
    std::array<float, 3> lo{INFINITY, INFINITY, INFINITY}, hi{-INFINITY, -INFINITY, -INFINITY};
    const InitialState& s0 = scene.initial;
    for (std::size_t i = 0; i < cloth.particle_count; ++i) {
        const float p[3] = {s0.x[i], s0.y[i], s0.z[i]};
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], p[a]);
            hi[a] = std::max(hi[a], p[a]);
        }
    }
    t.cloth_size = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-3f});
    t.spacing = view_spacing(spec, cloth);
    if (!authored.empty() && hi[1] - lo[1] < 0.1f * t.cloth_size) {
        // A flat cloth held by some of its particles will hang below them: frame the pins' span, a cloth size
        // deep, with a little room for the swing.
        std::array<float, 3> plo{INFINITY, INFINITY, INFINITY}, phi{-INFINITY, -INFINITY, -INFINITY};
        for (std::uint32_t i : authored) {
            const float p[3] = {s0.x[i], s0.y[i], s0.z[i]};
            for (int a = 0; a < 3; ++a) {
                plo[a] = std::min(plo[a], p[a]);
                phi[a] = std::max(phi[a], p[a]);
            }
        }
        const float swing = 0.25f * t.cloth_size;
        lo = {plo[0] - swing, phi[1] - t.cloth_size, plo[2] - swing};
        hi = {phi[0] + swing, phi[1], phi[2] + swing};
    }
    if (t.params.aero.enabled) {
        // A pinned cloth in a steady wind flies downwind, about its own size.
        const auto& v = t.params.aero.velocity;
        const float speed = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (speed > 0.0f && !authored.empty())
            for (int k = 0; k < 3; ++k) {
                const float d = t.cloth_size * v[k] / speed;
                if (d > 0.0f)
                    hi[k] += d;
                else
                    lo[k] += d;
            }
    }
    t.ground.reset();
    for (const Collider& c : scene.params.colliders) {
        if (c.kind == ColliderKind::plane) {
            if (c.axis[1] > 0.99f) t.ground = c.centre[1];
            continue;
        }
        float r = 0.0f;
        std::array<float, 3> a = c.centre, b = c.centre;
        if (c.kind == ColliderKind::sphere) r = c.size[0];
        if (c.kind == ColliderKind::ellipsoid) r = std::max({c.size[0], c.size[1], c.size[2]});
        if (c.kind == ColliderKind::capsule) {
            r = c.size[0];
            b = c.axis;
        }
        if (c.kind == ColliderKind::disc) {
            r = c.size[0];
            b[1] -= c.size[1];
        }
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min({lo[k], a[k] - r, b[k] - r});
            hi[k] = std::max({hi[k], a[k] + r, b[k] + r});
        }
    }
    t.frame_lo = lo;
    t.frame_hi = hi;

    // Run parameters: the user's (kept across rebuilds), the scene's colliders.
    t.params.colliders = scene.params.colliders;
    t.dt_bound = stability_bound(cloth, t.params).dt_max;
    const bool implicit = t.params.solver == Solver::implicit;
    if (implicit) // any step: the implicit solver has no stability bound
        t.params.dt = static_cast<float>(t.implicit_dt);
    else if (t.auto_dt || !(t.params.dt > 0.0f) || t.params.dt > t.dt_bound)
        t.params.dt = static_cast<float>(0.9 * t.dt_bound);
    // The new simulation is complete before it replaces the old one: if anything throws, the old one stays.
    const bool keep = keep_state && keep_state->state.x.size() == cloth.particle_count;
    const std::size_t particles = cloth.particle_count;
    Built out;
    out.sim = std::make_unique<Simulation>(std::move(scene.cloth), keep ? keep_state->state : scene.initial, t.params);
    for (std::uint32_t i : keep ? keep_state->pins : authored)
        out.sim->set_pinned(i, true);
    out.publisher = std::make_unique<Publisher>(out.sim->cloth());
    if (t.auto_substeps)
        t.substeps = implicit ? implicit_auto_steps(t.params.dt) : auto_substeps_for(particles, t.params.dt);
    else if (!keep_frame_time)
        t.frame_time = double(t.substeps) * double(t.params.dt);
    out.snap = std::move(t);
    return out;
}

void ViewSession::install(Built built, const Request& r) {
    publisher_ = std::move(built.publisher);
    sim_ = std::move(built.sim);
    restore(built.snap);
    if (r.new_scene) single_level_warned_ = thickness_warned_ = inside_warned_ = false;
    warn_about_settings(r.new_scene);
    ++generation_;
    if (r.new_scene) ++scene_generation_;
    if (r.clears_error) {
        error_.clear();
        error_code_ = 0;
    }
    refresh_pins();
    switch (r.history) {
    case History::record:
        record(r.before, "");
        break;
    case History::undo:
        if (!undo_.empty()) undo_.pop_back();
        redo_.push_back(r.before);
        break;
    case History::redo:
        if (!redo_.empty()) redo_.pop_back();
        undo_.push_back({r.before, ""});
        if (undo_.size() > view_undo_depth) undo_.pop_front();
        break;
    case History::none:
        break;
    }
    edit_open_ = false;
}

void ViewSession::refresh_pins() {
    pinned_.clear();
    const std::size_t n = sim_->cloth().particle_count, grabbed = sim_->grabbed();
    for (std::size_t i = 0; i < n; ++i)
        if (i != grabbed && sim_->is_pinned(i)) pinned_.push_back(static_cast<std::uint32_t>(i));
    ++markers_version_;
}

bool ViewSession::step_due() {
    // A new cloth is shown first as built: the frame that swaps it in (new GPU buffers) does not also simulate it.
    if (poll()) return false;
    if (!running_ && !step_pending_) return false;
    // A node-mass rebuild continues the motion from when it was asked for: the old cloth holds still meanwhile.
    if (job_ && job_->request.keep) return false;
    step_pending_ = false;
    return true;
}

void ViewSession::run_step() {
    const auto start = std::chrono::steady_clock::now();
    try {
        workers_->run([&] { sim_->step(static_cast<std::size_t>(substeps_)); });
    } catch (...) {
        step_error_ = std::current_exception();
    }
    step_ms_ = 1e3 * seconds_since(start);
    step_done_.store(true, std::memory_order_release);
}

std::size_t ViewSession::advance() {
    if (!step_due()) return 0;
    step_before_ = sim_->steps_done();
    step_open_ = true;
    run_step();
    return finish_step();
}

bool ViewSession::start_step() {
    if (step_open_ || !step_due()) return false;
    step_before_ = sim_->steps_done();
    step_open_ = true;
    step_done_.store(false, std::memory_order_relaxed);
    step_thread_ = std::thread([this] { run_step(); });
    return true;
}

std::size_t ViewSession::finish_step() {
    if (!step_open_) return 0;
    if (step_thread_.joinable()) step_thread_.join();
    step_open_ = false;
    if (std::exception_ptr error = std::exchange(step_error_, nullptr)) {
        try {
            std::rethrow_exception(error);
        } catch (const SimulationError& e) {
            running_ = false;
            error_ = e.what();
            error_code_ = dynamic_cast<const BlowUpError*>(&e) ? exit_code::blow_up : exit_code::non_finite;
            post(MessageLevel::error, std::string(error_code_ == exit_code::blow_up ? "the cloth exploded: "
                                                                                     : "simulation stopped: ") +
                                          error_ + " - Reset, or Undo the last change");
        }
    } else if (params_.solver == Solver::implicit) {
        note_frame_sim_ms(step_ms_);
    }
    return sim_->steps_done() - step_before_;
}

PublishStats ViewSession::publish(std::span<float> out) {
    return workers_->run([&] { return publisher_->publish(sim_->x(), sim_->y(), sim_->z(), out); });
}

void ViewSession::set_running(bool on) {
    if (on && !error_.empty()) {
        post(MessageLevel::warning, "the simulation stopped on an error; Reset or Undo first");
        return;
    }
    running_ = on;
}

void ViewSession::step_once() {
    if (!error_.empty()) return;
    running_ = false;
    step_pending_ = true;
}

void ViewSession::set_show_markers(bool on) {
    if (on == show_markers_) return;
    show_markers_ = on;
    ++markers_version_;
}

void ViewSession::reset() {
    Request r;
    r.what = "reset";
    r.target = snapshot();
    r.history = History::none;
    r.done = "reset: the scene's starting state and pins, current settings";
    request(std::move(r));
}

ViewSession::Snapshot ViewSession::snapshot() const {
    return {size_,   spec_,   total_mass_, fabric_,   has_seams_, cloth_size_, frame_lo_,      frame_hi_,
            ground_, params_, auto_dt_,    dt_bound_, substeps_,  spacing_,    frame_time_, auto_substeps_,
            topology_, implicit_dt_, explicit_dt_, max_iterations_, budget_on_, budget_ms_};
}

void ViewSession::restore(const Snapshot& b) {
    size_ = b.size;
    spec_ = b.spec;
    total_mass_ = b.total_mass;
    fabric_ = b.fabric;
    has_seams_ = b.has_seams;
    cloth_size_ = b.cloth_size;
    frame_lo_ = b.frame_lo;
    frame_hi_ = b.frame_hi;
    ground_ = b.ground;
    params_ = b.params;
    auto_dt_ = b.auto_dt;
    dt_bound_ = b.dt_bound;
    substeps_ = b.substeps;
    frame_time_ = b.frame_time;
    spacing_ = b.spacing;
    auto_substeps_ = b.auto_substeps;
    topology_ = b.topology;
    implicit_dt_ = b.implicit_dt;
    explicit_dt_ = b.explicit_dt;
    max_iterations_ = b.max_iterations;
    budget_on_ = b.budget_on;
    budget_ms_ = b.budget_ms;
    budget_sum_ms_ = 0.0;
    budget_frames_ = 0;
}

bool ViewSession::busy(const std::string& what) {
    if (!building()) return false;
    post(MessageLevel::warning, "not now: " + what + " waits until the cloth being built is ready (or cancel it)");
    return true;
}

void ViewSession::record(const Snapshot& before, const std::string& key) {
    // One entry per edit: a slider dragged through many values is undone at once.
    if (!(edit_open_ && !key.empty() && !undo_.empty() && undo_.back().key == key)) {
        undo_.push_back({before, key});
        if (undo_.size() > view_undo_depth) undo_.pop_front();
    }
    redo_.clear();
    edit_open_ = true;
}

bool ViewSession::commit_params(const SimulationParams& p, const std::string& key) {
    if (busy(key)) return false;
    // set_params leaves the simulation as it was when it refuses, so no snapshot is needed.
    const Snapshot before = snapshot();
    if (!try_set_params(p)) return false;
    record(before, key);
    return true;
}

bool ViewSession::try_set_params(const SimulationParams& p) {
    try {
        sim_->set_params(p);
    } catch (const InvalidInput& e) {
        post(MessageLevel::warning, std::string("refused: ") + e.what());
        return false;
    }
    params_ = p;
    warn_about_settings(false);
    return true;
}

void ViewSession::warn_about_settings(bool new_cloth) {
    // Each warning is posted once when it starts to apply; two starting together share the message line.
    std::string text;
    auto check = [&](const std::string& w, bool& warned) {
        if (!w.empty() && !warned) text += (text.empty() ? "" : "; and ") + w;
        warned = !w.empty();
    };
    check(sim_ ? single_level_implicit_warning(*sim_) : std::string(), single_level_warned_);
    check(sim_ ? self_collision_thickness_warning(*sim_) : std::string(), thickness_warned_);
    // Only for a cloth just built: mid-run, particles held in the crevices between overlapping colliders are not
    // a cloth placed inside one.
    if (new_cloth) check(sim_ ? started_inside_warning(*sim_) : std::string(), inside_warned_);
    if (!text.empty()) post(MessageLevel::warning, text);
}

void ViewSession::note_published_strain(float max_structural_strain) {
    // Not over a stopped simulation's error (the frame that posts it publishes too).
    if (!sim_ || step_open_ || !error_.empty()) return;
    const bool applies = implicit_unconverged(*sim_, max_structural_strain);
    if (applies && !unconverged_warned_) {
        const bool budget_limited = budget_on_ && sim_->params().implicit.iterations < max_iterations_;
        post(MessageLevel::warning, unconverged_implicit_warning(*sim_, max_structural_strain, true, budget_limited));
    }
    unconverged_warned_ = applies;
    // Past 100 % strain for another reason (drape run's end-of-run warning): once each time it starts to apply; not
    // while the user drags a particle, whose pull they see (an adversarial sweep: a cloth started 10 times its size
    // ran at strain 32 in the viewer with nothing said).
    const std::string over = sim_->grabbed() == SIZE_MAX ? overstretched_warning(*sim_, max_structural_strain, true)
                                                         : std::string();
    if (!over.empty() && !overstretched_warned_) post(MessageLevel::warning, over);
    overstretched_warned_ = !over.empty();
}

void ViewSession::note_real_time_factor(double factor) {
    // params_ (the session's copy), not the simulation's: a step may be running on its own thread.
    // Substeps set by hand: the slow motion is the user's choice.
    if (!running_ || !auto_substeps_ || params_.solver == Solver::implicit || !(factor > 0.0) ||
        factor >= slow_explicit_factor)
        return;
    const std::pair<std::uint64_t, std::size_t> cloth{scene_generation_, sim_ ? sim_->cloth().particle_count : 0};
    if (slow_hinted_for_ == cloth) return;
    // A warning or error still fresh on the message line is not replaced by a hint.
    if (message_.level != MessageLevel::info &&
        std::chrono::steady_clock::now() - message_.when < std::chrono::seconds(10))
        return;
    slow_hinted_for_ = cloth;
    char text[400];
    std::snprintf(text, sizeof text,
                  "the explicit solver runs this cloth at %.2gx real time (below %.1fx): its substep (%.3g s) must "
                  "stay below the stability bound, which shrinks as the cloth gets finer; the implicit solver "
                  "(Physics panel: solver) takes frame-long steps and runs large cloths many times faster, though it "
                  "damps the swing more (docs/implicit.md)",
                  factor, slow_explicit_factor, double(params_.dt));
    post(MessageLevel::info, text);
}

std::shared_ptr<const ViewSession::KeepState> ViewSession::capture_state() {
    auto k = std::make_shared<KeepState>();
    sim_->release_grab();
    const std::size_t n = sim_->cloth().particle_count;
    k->state.x.assign(sim_->x().begin(), sim_->x().end());
    k->state.y.assign(sim_->y().begin(), sim_->y().end());
    k->state.z.assign(sim_->z().begin(), sim_->z().end());
    k->state.vx.resize(n);
    k->state.vy.resize(n);
    k->state.vz.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
        const auto v = sim_->velocity(i);
        k->state.vx[i] = v[0];
        k->state.vy[i] = v[1];
        k->state.vz[i] = v[2];
        if (sim_->is_pinned(i)) k->pins.push_back(static_cast<std::uint32_t>(i));
    }
    refresh_pins();
    return k;
}

void ViewSession::request(Request r, bool confirmed) {
    r.before = snapshot();
    const SceneSpec spec = sized_spec(r.target.spec, r.target.size);
    r.particles = scene_particle_count(spec);
    r.bytes = scene_memory_bytes(spec);
    if (!confirmed) {
        const std::size_t available = available_memory_bytes();
        if (r.bytes > available) {
            post(MessageLevel::warning, "refused: " + r.what + " needs " + format_bytes(r.bytes) + " for " +
                                            grouped(r.particles) + " particles; only " + format_bytes(available) +
                                            " is available");
            return;
        }
        if (r.particles > view_confirm_particles || (available != SIZE_MAX && r.bytes > available / 2)) {
            confirm_ = Confirmation{r.what, r.particles, r.bytes, available};
            confirm_request_ = std::make_unique<Request>(std::move(r));
            post(MessageLevel::warning, "confirm: " + confirm_->what + " builds " + grouped(confirm_->particles) +
                                            " particles and needs " + format_bytes(confirm_->bytes));
            return;
        }
    }
    confirm_.reset();
    confirm_request_.reset();
    if (job_) {
        // Newest wins: the running build finishes but is discarded; this waits in its place.
        job_->discard = true;
        queued_ = std::make_unique<Request>(std::move(r));
        post(MessageLevel::info, "building " + grouped(queued_->particles) + " particles for " + queued_->what +
                                     " after the build in progress (which will be discarded)");
        return;
    }
    start(std::move(r));
}

void ViewSession::confirm_build(bool yes) {
    if (!confirm_request_) return;
    std::unique_ptr<Request> r = std::move(confirm_request_);
    confirm_.reset();
    if (!yes) {
        post(MessageLevel::info, "cancelled: " + r->what);
        return;
    }
    request(std::move(*r), true);
}

void ViewSession::start(Request r) {
    r.start = std::chrono::steady_clock::now();
    job_ = std::make_unique<Job>();
    job_->request = std::move(r);
    Job* job = job_.get();
    std::function<void(const SceneSpec&)> hook = build_hook_;
    post(MessageLevel::info, "building " + grouped(job->request.particles) + " particles (" + job->request.what +
                                 ", needs " + format_bytes(job->request.bytes) + ")...");
    job->thread = std::thread([job, hook] {
        try {
            if (hook) hook(sized_spec(job->request.target.spec, job->request.target.size));
            job->result = build(job->request.target, job->request.keep.get(), job->request.keep_frame_time);
        } catch (const InvalidInput& e) {
            job->error = e.what();
        } catch (const std::bad_alloc&) {
            job->error = "out of memory";
        } catch (const std::exception& e) {
            job->error = e.what();
        }
        job->done.store(true, std::memory_order_release);
    });
}

bool ViewSession::poll() {
    if (!job_ || !job_->done.load(std::memory_order_acquire)) return false;
    if (job_->thread.joinable()) job_->thread.join();
    std::unique_ptr<Job> job = std::move(job_);
    bool installed = false;
    if (!job->discard) {
        const Request& r = job->request;
        if (!job->error.empty()) {
            // Transactional: the old cloth and settings were never touched.
            post(MessageLevel::warning, "refused: " + r.what + ": " + job->error);
        } else {
            install(std::move(*job->result), r);
            installed = true;
            const double s = seconds_since(r.start);
            if (!r.done.empty())
                post(MessageLevel::info, r.done + " (" + grouped(sim_->cloth().particle_count) + " particles, built in " +
                                             fmt(s, 3) + " s)");
            else
                post(MessageLevel::info, r.what + ": " + grouped(sim_->cloth().particle_count) +
                                             " particles built in " + fmt(s, 3) + " s; node mass " +
                                             fmt(fabric_.node_mass_g, 3) + " g, dt " + fmt(params_.dt) + " s, " +
                                             std::to_string(substeps_) + " substeps per frame");
        }
    }
    job.reset(); // frees a discarded cloth
    if (queued_) {
        std::unique_ptr<Request> next = std::move(queued_);
        start(std::move(*next));
    }
    return installed;
}

std::optional<BuildStatus> ViewSession::build_status() const {
    if (!job_) return std::nullopt;
    const Request& r = job_->discard && queued_ ? *queued_ : job_->request;
    return BuildStatus{r.what, r.particles, r.bytes, seconds_since(job_->request.start), queued_ != nullptr};
}

void ViewSession::cancel_build() {
    if (!building()) return;
    if (job_) job_->discard = true;
    queued_.reset();
    post(MessageLevel::info, "build cancelled; the current cloth stays");
}

void ViewSession::wait() {
    while (job_) {
        if (job_->thread.joinable()) job_->thread.join();
        poll();
    }
}

void ViewSession::set_scene(const std::string& name_or_path) {
    SceneSpec spec;
    try {
        spec = load_scene(name_or_path);
    } catch (const InvalidInput& e) {
        post(MessageLevel::warning, std::string("refused: ") + e.what());
        return;
    } catch (const std::exception& e) {
        // Whatever the loader lets through (a bug there) must not take the window down: refused, scene kept.
        post(MessageLevel::warning, "refused: " + name_or_path + ": " + e.what());
        return;
    }
    const std::optional<std::uint32_t> size = view_default_size(name_or_path, spec);
    Request r;
    r.what = "scene " + name_or_path;
    try {
        r.target = settings_for(std::move(spec), size);
    } catch (const InvalidInput& e) {
        post(MessageLevel::warning, "refused: " + r.what + ": " + e.what());
        return;
    }
    r.new_scene = true;
    r.done = "scene " + r.target.spec.name + ": " + r.target.spec.description;
    request(std::move(r));
}

void ViewSession::set_size(std::uint32_t n) {
    if (!resizable()) {
        post(MessageLevel::warning, std::string("refused: a ") + (spec_.cloth == ClothType::mesh
                                                                      ? "mesh's resolution is its OBJ file's"
                                                                      : "mask cloth's resolution is its masks' cells"));
        return;
    }
    if (grid_scene())
        n = std::clamp(n, view_min_size, view_max_size);
    else
        n = std::clamp(n, view_min_cells, view_max_cells);
    if (n == size_) return;
    Request r;
    r.what = "resolution " + std::to_string(n);
    r.target = snapshot();
    r.target.size = n;
    r.target.topology = ++topology_counter_;
    r.target.fabric.node_mass_g =
        1000.0f * total_mass_ / float(std::max<std::size_t>(1, scene_particle_count(sized_spec(spec_, n))));
    request(std::move(r));
}

void ViewSession::restore_run_state(const SimulationParams& old_params,
                                    const std::array<SpringMaterial, spring_kind_count>& old_materials) {
    // The smaller dt first, so that every intermediate state is stable.
    try {
        SimulationParams safe = sim_->params();
        safe.dt = std::min(safe.dt, old_params.dt);
        if (safe.solver == Solver::implicit) safe.dt = std::max(safe.dt, implicit_min_dt);
        sim_->set_params(safe);
        for (std::size_t k = 0; k < spring_kind_count; ++k)
            sim_->set_material(static_cast<SpringKind>(k), old_materials[k]);
        sim_->set_params(old_params);
    } catch (const InvalidInput&) {
        // Cannot happen (the old state was stable); the smaller dt then stays, which is stable too.
    }
}

bool ViewSession::apply_physics(const Candidate& next, const std::string& what, const std::string& key) {
    if (busy(what)) return false;
    const Snapshot before = snapshot();
    const double bound = bound_for(next.fabric, next.air_drag, next.aero);
    const double old_dt = sim_->params().dt;
    const bool implicit = params_.solver == Solver::implicit;
    double new_dt = old_dt;
    if (!implicit && (auto_dt_ || old_dt > bound)) new_dt = 0.9 * bound; // the implicit step stays
    int new_substeps = substeps_;
    if (implicit) {
        // Steps per frame unchanged.
    } else if (auto_substeps_) {
        new_substeps = auto_substep_count(new_dt);
    } else {
        // Keep the simulated time per frame the user chose (substeps x dt when they last set either), in both
        // directions, so the result does not depend on the path (typing 20000 passes through 2, 20, 200,
        // ...).
        new_substeps = manual_substep_count(new_dt);
        if (new_substeps > view_max_substeps) {
            post(MessageLevel::warning, "refused: " + what + " needs dt <= " + fmt(bound) + " s, i.e. " +
                                            std::to_string(new_substeps) +
                                            " substeps per frame to keep the pace (max " +
                                            std::to_string(view_max_substeps) +
                                            "); lower the substeps or choose automatic substeps");
            return false;
        }
    }
    const std::array<SpringMaterial, spring_kind_count> old_materials = sim_->cloth().material;
    const std::array<SpringMaterial, spring_kind_count> new_materials = materials(next.fabric);
    SimulationParams p = sim_->params();
    const SimulationParams old_params = p;
    try {
        // Order keeps every intermediate state stable: first the smaller dt (old materials, old drag), then
        // the new materials / drag, then the new dt.
        p.dt = static_cast<float>(std::min(old_dt, new_dt));
        sim_->set_params(p);
        for (std::size_t k = 0; k < spring_kind_count; ++k)
            if (new_materials[k].stiffness != old_materials[k].stiffness ||
                new_materials[k].damping != old_materials[k].damping)
                sim_->set_material(static_cast<SpringKind>(k), new_materials[k]);
        p.air_drag = next.air_drag;
        p.aero = next.aero;
        sim_->set_params(p);
        p.dt = static_cast<float>(new_dt);
        sim_->set_params(p);
    } catch (const InvalidInput& e) {
        // The probe bound and the core's disagree in the last bits: restore everything and say so.
        restore_run_state(old_params, old_materials);
        post(MessageLevel::warning, "refused: " + what + ": " + e.what());
        return false;
    }
    fabric_ = next.fabric;
    params_ = sim_->params();
    dt_bound_ = bound;
    record(before, key);
    const int old_substeps = substeps_;
    substeps_ = new_substeps;
    std::string note = what + " applied";
    if (new_dt < old_dt) {
        note += "; dt lowered to " + fmt(new_dt) + " s (bound " + fmt(bound) + " s)";
        if (new_substeps != old_substeps)
            note += ", substeps per frame " + std::to_string(old_substeps) + " -> " +
                    std::to_string(new_substeps) +
                    (auto_substeps_ ? " (automatic)" : " to keep the simulated time per frame");
        post(MessageLevel::warning, note);
    } else {
        if (new_dt != old_dt) note += "; dt " + fmt(new_dt) + " s (bound " + fmt(bound) + " s)";
        if (new_substeps != old_substeps)
            note += ", substeps per frame " + std::to_string(old_substeps) + " -> " +
                    std::to_string(new_substeps);
        post(MessageLevel::info, note);
    }
    return true;
}

void ViewSession::set_stiffness(SpringKind kind, float k) {
    if (fabric_.model == MaterialModel::fabric) {
        post(MessageLevel::warning, std::string("refused: the fabric model derives the ") + spring_kind_name(kind) +
                                        " springs from the fabric; edit its figures, or switch the model to springs");
        return;
    }
    k = std::clamp(k, view_min_stiffness, view_max_stiffness);
    Candidate c{fabric_, sim_->params().air_drag, sim_->params().aero};
    c.fabric.stiffness[static_cast<std::size_t>(kind)] = k;
    static const char* names[] = {"structural", "shear", "bend", "seam"};
    apply_physics(c, std::string(names[static_cast<std::size_t>(kind)]) + " stiffness " + fixed(k, 0) + " N/m",
                  std::string("stiffness ") + names[static_cast<std::size_t>(kind)]);
}

void ViewSession::set_damping_ratio(float ratio) {
    if (fabric_.model == MaterialModel::fabric) {
        post(MessageLevel::warning, "refused: the fabric model's damping is the fabric's (s, Rayleigh beta); edit it "
                                    "there, or switch the model to springs");
        return;
    }
    ratio = std::clamp(ratio, 0.0f, 1.0f);
    Candidate c{fabric_, sim_->params().air_drag, sim_->params().aero};
    c.fabric.damping_ratio = ratio;
    apply_physics(c, "damping " + fmt(ratio, 3) + " of critical", "damping");
}

void ViewSession::set_air_drag(float drag) {
    drag = std::clamp(drag, 0.0f, 100.0f);
    apply_physics({fabric_, drag, sim_->params().aero}, "air drag " + fmt(drag, 3) + " 1/s", "air drag");
}

void ViewSession::set_aero(const AeroWind& aero) {
    AeroWind a = aero;
    a.density = std::clamp(a.density, 0.0f, 100.0f);
    a.drag_coefficient = std::clamp(a.drag_coefficient, 0.0f, 10.0f);
    float speed2 = 0.0f;
    for (float& v : a.velocity) {
        v = std::clamp(v, -100.0f, 100.0f);
        speed2 += v * v;
    }
    if (speed2 > 100.0f * 100.0f) {
        // Keep the direction, shorten to 100 m/s.
        const float scale = 100.0f / std::sqrt(speed2) * (1.0f - 1e-6f);
        for (float& v : a.velocity)
            v *= scale;
    }
    apply_physics({fabric_, sim_->params().air_drag, a},
                  std::string("aero wind ") + (a.enabled ? "on" : "off") + ": density " + fmt(a.density) +
                      " kg/m^3, C_d " + fmt(a.drag_coefficient) + ", velocity (" + fmt(a.velocity[0]) + ", " +
                      fmt(a.velocity[1]) + ", " + fmt(a.velocity[2]) + ") m/s",
                  "aero");
}

void ViewSession::set_node_mass(float grams) {
    if (fabric_.model == MaterialModel::fabric) {
        post(MessageLevel::warning, "refused: a fabric's node mass follows its areal density (g/m^2) and the mesh; "
                                    "edit the density, or switch the model to springs");
        return;
    }
    grams = std::clamp(grams, view_min_node_mass_g, view_max_node_mass_g);
    FabricSettings next = fabric_;
    next.node_mass_g = grams;
    const double bound = bound_for(next, params_.air_drag, params_.aero);
    const double old_dt = sim_->params().dt;
    const bool implicit = params_.solver == Solver::implicit;
    double new_dt = !implicit && (auto_dt_ || old_dt > bound) ? 0.9 * bound : old_dt;
    int new_substeps = substeps_;
    if (!auto_substeps_ && !implicit) {
        new_substeps = manual_substep_count(new_dt);
        if (new_substeps > view_max_substeps) {
            post(MessageLevel::warning, "refused: node mass " + fmt(grams) + " g needs dt <= " + fmt(bound) +
                                            " s, i.e. " + std::to_string(new_substeps) +
                                            " substeps per frame (max " + std::to_string(view_max_substeps) +
                                            ")");
            return;
        }
    }
    Request r;
    r.what = "node mass " + fmt(grams) + " g";
    r.target = snapshot();
    r.target.fabric.node_mass_g = grams;
    if (float* density = areal_density(r.target.spec)) {
        // Masses are density x area: the node mass scales the areal density (the mean node mass becomes `grams`).
        const float scaled = *density * (grams / fabric_.node_mass_g);
        if (!(scaled >= 1e-3f && scaled <= 10.0f)) {
            post(MessageLevel::warning, "refused: node mass " + fmt(grams) + " g needs an areal density of " +
                                            fmt(scaled) + " kg/m^2; allowed range [0.001, 10] kg/m^2");
            return;
        }
        *density = scaled;
    }
    r.target.params = sim_->params();
    r.target.params.dt = static_cast<float>(new_dt);
    if (!auto_substeps_) r.target.substeps = new_substeps;
    r.keep_frame_time = true; // the node mass keeps the pace, like the other physics changes
    // The motion continues from here (after an error: from the scene's start).
    if (error_.empty()) r.keep = capture_state();
    request(std::move(r));
}

void ViewSession::set_material_model(MaterialModel model) {
    if (model == fabric_.model || busy("material model")) return;
    Request r;
    r.what = std::string("material model ") + material_model_name(model);
    r.target = snapshot();
    FabricSettings& f = r.target.fabric;
    f.model = model;
    if (model == MaterialModel::fabric) {
        f.fabric = spec_.model == MaterialModel::fabric ? spec_.fabric : *find_fabric("cotton_shirting");
    } else { // the scene's spring fields, at the scene's total mass
        const SceneSpec& sp = spec_;
        f.stiffness = {sp.stiffness, sp.stiffness * sp.shear_ratio, sp.stiffness * sp.bend_ratio, sp.seam_stiffness};
        f.damping_ratio = sp.damping_ratio;
        f.node_mass_g =
            1000.0f * total_mass_ / float(std::max<std::size_t>(1, scene_particle_count(sized_spec(spec_, size_))));
    }
    r.target.params = sim_->params();
    r.keep_frame_time = true;
    if (error_.empty()) r.keep = capture_state();
    request(std::move(r));
}

void ViewSession::set_fabric(const Fabric& fabric) {
    if (busy("fabric")) return;
    Fabric f = fabric;
    if (const std::optional<Fabric> preset = find_fabric(f.name); !preset || !same_figures(*preset, f)) f.name = "custom";
    try {
        validate_fabric(f, "Fabric panel: fabric");
    } catch (const InvalidInput& e) {
        post(MessageLevel::warning, std::string("refused: ") + e.what());
        return;
    }
    if (fabric_.model == MaterialModel::fabric && same_figures(f, fabric_.fabric)) return;
    Request r;
    r.what = "fabric " + f.name;
    r.target = snapshot();
    r.target.fabric.model = MaterialModel::fabric;
    r.target.fabric.fabric = f;
    r.target.params = sim_->params();
    r.keep_frame_time = true; // the motion continues with the new fabric, like a node-mass change
    if (error_.empty()) r.keep = capture_state();
    request(std::move(r));
}

void ViewSession::set_fabric_preset(const std::string& name) {
    const std::optional<Fabric> f = find_fabric(name);
    if (!f) {
        post(MessageLevel::warning, "refused: no fabric preset '" + name + "' (presets: " + fabric_preset_names() + ")");
        return;
    }
    set_fabric(*f);
}

void ViewSession::set_gravity(const std::array<float, 3>& g) {
    SimulationParams p = sim_->params();
    for (int i = 0; i < 3; ++i)
        p.gravity[i] = std::clamp(g[i], -50.0f, 50.0f);
    commit_params(p, "gravity");
}

void ViewSession::set_wind(bool enabled, float strength) {
    SimulationParams p = sim_->params();
    p.wind.enabled = enabled;
    p.wind.strength = std::clamp(strength, 0.0f, 100.0f);
    commit_params(p, "wind");
}

void ViewSession::set_integrator(Integrator integrator) {
    SimulationParams p = sim_->params();
    p.integrator = integrator;
    if (!commit_params(p, "integrator")) return;
    post(MessageLevel::info, std::string("integrator: ") + integrator_name(integrator));
}

void ViewSession::set_solver(Solver solver) {
    if (solver == params_.solver || busy("solver")) return;
    const Snapshot before = snapshot();
    SimulationParams p = sim_->params();
    const double saved_explicit_dt = explicit_dt_;
    if (solver == Solver::implicit) {
        if (!auto_dt_) explicit_dt_ = p.dt;
        p.solver = Solver::implicit;
        p.integrator = Integrator::symplectic_euler; // the implicit solver keeps velocities
        p.dt = static_cast<float>(implicit_dt_);
    } else {
        p.solver = Solver::explicit_euler;
        const double top = dt_bound_ * (1.0 - 1e-6);
        p.dt = static_cast<float>(auto_dt_ || !(explicit_dt_ > 0.0) ? 0.9 * dt_bound_ : std::min(explicit_dt_, top));
    }
    p.implicit.iterations = max_iterations_;
    // The pace: automatic steps, or the simulated time per frame the user chose.
    const int steps = auto_substeps_ ? (solver == Solver::implicit ? implicit_auto_steps(p.dt)
                                                                   : auto_substeps_for(particle_count(), p.dt))
                                     : manual_substep_count(p.dt);
    if (steps > view_max_substeps) {
        post(MessageLevel::warning, "refused: the explicit solver needs " + std::to_string(steps) +
                                        " substeps per frame to keep the pace (max " +
                                        std::to_string(view_max_substeps) + "); choose automatic substeps first");
        return;
    }
    if (!try_set_params(p)) {
        explicit_dt_ = saved_explicit_dt;
        return;
    }
    substeps_ = steps;
    budget_sum_ms_ = 0.0;
    budget_frames_ = 0;
    record(before, "solver");
    if (solver == Solver::implicit)
        post(MessageLevel::info, "solver implicit: " + std::to_string(substeps_) + " step(s) of " + fmt(p.dt) +
                                     " s per frame, up to " + std::to_string(max_iterations_) + " iterations each" +
                                     (budget_on_ ? " (fewer when a frame's simulation takes over " + fmt(budget_ms_) +
                                                       " ms)"
                                                 : ""));
    else
        post(MessageLevel::info, "solver explicit: dt " + fmt(p.dt) + " s (bound " + fmt(dt_bound_) + " s), " +
                                     std::to_string(substeps_) + " substeps per frame");
}

void ViewSession::set_running_iterations(std::uint32_t iterations) {
    SimulationParams p = sim_->params();
    if (p.implicit.iterations == iterations) return;
    p.implicit.iterations = iterations;
    try {
        sim_->set_params(p);
    } catch (const InvalidInput& e) { // cannot happen (1..1000)
        post(MessageLevel::warning, std::string("refused: ") + e.what());
        return;
    }
    params_ = p;
}

void ViewSession::set_max_iterations(std::uint32_t iterations) {
    iterations = std::clamp<std::uint32_t>(iterations, 1, 1000);
    if (iterations == max_iterations_) return;
    SimulationParams p = sim_->params();
    p.implicit.iterations = iterations; // the budget starts from the new cap
    if (!commit_params(p, "iterations")) return; // its undo entry holds the old cap
    max_iterations_ = iterations;
    budget_sum_ms_ = 0.0;
    budget_frames_ = 0;
}

void ViewSession::set_chebyshev_rho(float rho) {
    SimulationParams p = sim_->params();
    p.implicit.chebyshev_rho = std::clamp(rho, 0.0f, 0.99f);
    commit_params(p, "chebyshev rho");
}

void ViewSession::set_multilevel(bool on) {
    SimulationParams p = sim_->params();
    if (p.implicit.multilevel == on) return;
    p.implicit.multilevel = on;
    commit_params(p, "multilevel guess");
    single_level_warned_ = false;
    warn_about_settings(false);
}

void ViewSession::set_fas_at_rest(bool on) {
    SimulationParams p = sim_->params();
    if (p.implicit.fas_at_rest == on) return;
    p.implicit.fas_at_rest = on;
    commit_params(p, "FAS at rest");
}

void ViewSession::set_iteration_budget(bool on) {
    if (on == budget_on_ || busy("iteration budget")) return;
    const Snapshot before = snapshot();
    budget_on_ = on;
    budget_sum_ms_ = 0.0;
    budget_frames_ = 0;
    if (!on) set_running_iterations(max_iterations_);
    record(before, "iteration budget");
}

void ViewSession::set_sim_budget_ms(double ms) {
    if (busy("iteration budget")) return;
    const Snapshot before = snapshot();
    budget_ms_ = std::clamp(ms, 1.0, 1000.0);
    budget_sum_ms_ = 0.0;
    budget_frames_ = 0;
    record(before, "budget ms");
}

void ViewSession::note_frame_sim_ms(double ms) {
    if (params_.solver != Solver::implicit || !budget_on_ || !(ms >= 0.0)) return;
    budget_sum_ms_ += ms;
    if (++budget_frames_ < view_budget_frames) return;
    const double mean = budget_sum_ms_ / budget_frames_;
    budget_sum_ms_ = 0.0;
    budget_frames_ = 0;
    const std::uint32_t current = sim_->params().implicit.iterations;
    set_running_iterations(
        budget_iterations(mean, budget_ms_, current, sim_->implicit_stats().iterations, max_iterations_));
}

void ViewSession::set_strain_limit(const StrainLimit& limit) {
    SimulationParams p = sim_->params();
    p.strain_limit.ratio = std::clamp(limit.ratio, 0.0f, 10.0f);
    p.strain_limit.passes = std::clamp<std::uint32_t>(limit.passes, 1, 100);
    p.strain_limit.every = std::clamp<std::uint32_t>(limit.every, 1, 1000);
    commit_params(p, "strain limit");
}

void ViewSession::set_self_collision(float thickness) {
    SimulationParams p = sim_->params();
    p.self_collision.thickness =
        thickness > 0.0f ? std::clamp(thickness, self_collision_min_thickness, self_collision_max_thickness) : 0.0f;
    commit_params(p, "self-collision");
}

bool ViewSession::apply_dt(double dt) {
    if (params_.solver == Solver::implicit) { // any step in the slider's range
        SimulationParams p = sim_->params();
        p.dt = static_cast<float>(std::clamp(dt, view_implicit_min_dt, view_implicit_max_dt));
        if (!try_set_params(p)) return false;
        implicit_dt_ = p.dt;
        if (auto_substeps_)
            substeps_ = auto_substep_count(p.dt);
        else
            frame_time_ = double(substeps_) * double(p.dt);
        return true;
    }
    // The top of the slider is the bound itself: keep the float dt just below it (rounding to float, and the
    // probe bound against the core's own, may differ in the last bits).
    const double top = dt_bound_ * (1.0 - 1e-6);
    dt = std::clamp(dt, 1e-3 * dt_bound_, top);
    SimulationParams p = sim_->params();
    p.dt = static_cast<float>(dt);
    if (double(p.dt) > top) p.dt = std::nextafter(p.dt, 0.0f);
    if (!try_set_params(p)) return false;
    if (auto_substeps_)
        substeps_ = auto_substep_count(dt);
    else
        frame_time_ = double(substeps_) * double(p.dt);
    return true;
}

void ViewSession::set_dt(double dt) {
    if (busy("dt")) return;
    const Snapshot before = snapshot();
    if (!apply_dt(dt)) return;
    if (params_.solver == Solver::explicit_euler) auto_dt_ = false; // the implicit step is always the user's
    record(before, "dt");
}

void ViewSession::set_auto_dt(bool on) {
    if (busy("auto dt")) return;
    const Snapshot before = snapshot();
    // With the implicit solver the flag waits for the switch back to explicit.
    if (on && params_.solver == Solver::explicit_euler && !apply_dt(0.9 * dt_bound_)) return;
    auto_dt_ = on;
    record(before, "auto dt");
}

void ViewSession::set_substeps(int s) {
    if (busy("substeps")) return;
    const Snapshot before = snapshot();
    substeps_ = std::clamp(s, 1, view_max_substeps);
    auto_substeps_ = false;
    frame_time_ = double(substeps_) * double(sim_->params().dt);
    record(before, "substeps");
}

void ViewSession::set_auto_substeps(bool on) {
    if (busy("auto substeps")) return;
    const Snapshot before = snapshot();
    auto_substeps_ = on;
    if (on)
        substeps_ = auto_substep_count(sim_->params().dt);
    else
        frame_time_ = double(substeps_) * double(sim_->params().dt);
    record(before, "auto substeps");
}

int ViewSession::manual_substep_count(double dt) const {
    const double want = std::ceil(frame_time_ / dt - 1e-6);
    return want > 1e6 ? 1000000 : std::max(1, static_cast<int>(want));
}

void ViewSession::set_threads(int t) {
    t = std::clamp(t, min_workers, max_workers);
    if (workers_ && workers_->workers() == t) return;
    workers_.reset(); // one arena (and its global_control) at a time
    workers_ = std::make_unique<Workers>(t);
}

void ViewSession::undo() {
    if (building()) {
        // The change being built never applied: undoing it is cancelling it.
        cancel_build();
        return;
    }
    confirm_build(false);
    if (undo_.empty()) {
        post(MessageLevel::info, "nothing to undo");
        return;
    }
    apply_settings(undo_.back().settings, History::undo);
}

void ViewSession::redo() {
    if (busy("redo")) return;
    if (redo_.empty()) {
        post(MessageLevel::info, "nothing to redo");
        return;
    }
    apply_settings(redo_.back(), History::redo);
}

void ViewSession::apply_settings(const Snapshot& target, History history) {
    const Snapshot before = snapshot();
    const char* verb = history == History::undo ? "undo" : "redo";
    const bool same_cloth = target.topology == topology_ && target.fabric.node_mass_g == fabric_.node_mass_g &&
                            target.fabric.model == fabric_.model &&
                            (fabric_.model == MaterialModel::springs ||
                             same_figures(target.fabric.fabric, fabric_.fabric));
    if (!same_cloth || !error_.empty()) {
        // Another scene, resolution or node mass (or a stopped simulation): rebuild with those settings, keeping
        // the motion when only the node mass differs.
        Request r;
        r.what = verb;
        r.target = target;
        r.history = history;
        r.new_scene = target.spec.name != spec_.name;
        r.keep_frame_time = true;
        if (target.topology == topology_ && error_.empty()) r.keep = capture_state();
        r.done = std::string(verb) + ": settings restored";
        request(std::move(r));
        return;
    }
    // Same cloth: materials and run parameters in place, in an order that keeps every intermediate state stable
    // (the smaller dt first, the target dt last).
    const std::array<SpringMaterial, spring_kind_count> old_materials = sim_->cloth().material;
    const std::array<SpringMaterial, spring_kind_count> new_materials = materials(target.fabric);
    const SimulationParams old_params = sim_->params();
    try {
        // (The implicit solver takes no step below implicit_min_dt, and needs no smaller one to stay stable.)
        const float smaller = std::min(old_params.dt, target.params.dt);
        auto intermediate = [&](SimulationParams s) {
            s.dt = s.solver == Solver::implicit ? std::max(smaller, implicit_min_dt) : smaller;
            return s;
        };
        sim_->set_params(intermediate(old_params));
        for (std::size_t k = 0; k < spring_kind_count; ++k)
            sim_->set_material(static_cast<SpringKind>(k), new_materials[k]);
        sim_->set_params(intermediate(target.params));
        sim_->set_params(target.params);
    } catch (const InvalidInput& e) {
        restore_run_state(old_params, old_materials);
        post(MessageLevel::warning, std::string("refused: ") + verb + ": " + e.what());
        return;
    }
    restore(target);
    if (history == History::undo) {
        undo_.pop_back();
        redo_.push_back(before);
    } else {
        redo_.pop_back();
        undo_.push_back({before, ""});
        if (undo_.size() > view_undo_depth) undo_.pop_front();
    }
    edit_open_ = false;
    post(MessageLevel::info, std::string(verb) + ": settings restored (" + std::to_string(undo_.size()) +
                                 " more to undo, " + std::to_string(redo_.size()) + " to redo)");
}

void ViewSession::grab(std::size_t i, const std::array<float, 3>& target) {
    sim_->grab(i, target);
    refresh_pins();
}

void ViewSession::move_grab(const std::array<float, 3>& target) {
    for (float v : target)
        if (!std::isfinite(v)) return;
    sim_->move_grab(target);
}

void ViewSession::release_grab() {
    if (sim_->grabbed() == SIZE_MAX) return;
    sim_->release_grab();
    refresh_pins();
}

void ViewSession::pin_grabbed() {
    const std::size_t g = sim_->grabbed();
    if (g == SIZE_MAX) return;
    sim_->set_pinned(g, true); // takes effect on release: stays where the grab holds it
    sim_->release_grab();
    refresh_pins();
    post(MessageLevel::info, "pinned particle " + std::to_string(g) + " where it was dragged");
}

void ViewSession::toggle_pin(std::size_t i) {
    if (i >= sim_->cloth().particle_count) return;
    if (i == sim_->grabbed()) {
        pin_grabbed();
        return;
    }
    const bool pin = !sim_->is_pinned(i);
    sim_->set_pinned(i, pin);
    refresh_pins();
    post(MessageLevel::info, std::string(pin ? "pinned" : "unpinned") + " particle " + std::to_string(i));
}

SceneSpec ViewSession::current_spec() const {
    // The same mapping from the panels' settings to a spec as rebuild() uses, plus the physics panel.
    SceneSpec spec = spec_;
    spec.state.reset();
    spec.warnings.clear();
    if (spec.cloth == ClothType::grid) {
        spec.grid.n = size_;
        if (sim_) spec.grid.total_mass = fabric_.node_mass_g * 1e-3f * float(sim_->cloth().particle_count);
    } else if (spec.cloth == ClothType::tshirt) {
        spec.tshirt.cells_per_metre = static_cast<float>(size_);
        if (sim_)
            spec.tshirt.total_mass =
                std::clamp(fabric_.node_mass_g * 1e-3f * float(sim_->cloth().particle_count), 0.001f, 10.0f);
    } else {
        spec = sized_spec(spec, size_); // an outline's spacing; a density-mass cloth's density is spec_'s already
    }
    const std::array<float, spring_kind_count>& k = fabric_.stiffness;
    spec.model = fabric_.model;
    spec.seam_stiffness = k[static_cast<std::size_t>(SpringKind::seam)];
    if (fabric_.model == MaterialModel::fabric) {
        spec.fabric = fabric_.fabric; // the spring fields stay the scene's (not written for a fabric)
    } else {
        spec.stiffness = k[0];
        if (k[0] > 0.0f) {
            spec.shear_ratio = k[static_cast<std::size_t>(SpringKind::shear)] / k[0];
            spec.bend_ratio = k[static_cast<std::size_t>(SpringKind::bend)] / k[0];
        }
        spec.damping_ratio = fabric_.damping_ratio;
    }
    const std::vector<Collider> colliders = spec_.physics.colliders; // the scene's own (a body is spec.body)
    spec.physics = params_;
    spec.physics.colliders = colliders;
    spec.physics.implicit.iterations = max_iterations_; // the user's, not the budget's of the moment
    // The implicit step is always written (the viewer's default differs from a scene file's, 1/30 s).
    spec.dt = params_.solver == Solver::implicit ? std::optional<float>(static_cast<float>(implicit_dt_))
              : auto_dt_                        ? std::nullopt
                                                : std::optional<float>(params_.dt);
    return spec;
}

} // namespace drape::app
