// The viewer's model (see view_session.hpp for the stability rules).
#include "view_session.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include <tbb/info.h>

#include "drape/errors.hpp"
#include "drape/stability.hpp"

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

} // namespace

int ViewSession::hardware_threads() {
    return std::max(1, tbb::info::default_concurrency());
}

ViewSession::ViewSession(const std::string& scene, std::optional<std::uint32_t> size, int threads,
                         std::optional<int> substeps) {
    SceneSpec spec;
    try {
        spec = load_scene(scene);
    } catch (const InvalidInput& e) {
        throw InvalidInput(std::string("--scene: ") + e.what());
    }
    set_threads(threads > 0 ? threads : hardware_threads());
    if (substeps) {
        auto_substeps_ = false;
        substeps_ = std::clamp(*substeps, 1, view_max_substeps);
    }
    if (!size && spec.cloth == ClothType::grid && spec.name == "hang") size = view_default_hang_size;
    load_spec(std::move(spec), size);
    message_ = {};
}

void ViewSession::post(MessageLevel level, std::string text) {
    message_ = {std::move(text), level, std::chrono::steady_clock::now()};
}

void ViewSession::load_spec(SceneSpec spec, std::optional<std::uint32_t> size) {
    if (spec.cloth == ClothType::grid) {
        if (size) {
            if (*size < view_min_size || *size > view_max_size)
                throw InvalidInput("--size: value " + std::to_string(*size) +
                                   " is outside the allowed range [" + std::to_string(view_min_size) + ", " +
                                   std::to_string(view_max_size) + "]");
            spec.grid.n = *size;
        }
        size_ = spec.grid.n;
        total_mass_ = spec.grid.total_mass;
    } else {
        if (size) {
            if (*size < view_min_cells || *size > view_max_cells)
                throw InvalidInput("--size: value " + std::to_string(*size) +
                                   " is outside the allowed range [" + std::to_string(view_min_cells) + ", " +
                                   std::to_string(view_max_cells) + "] (cells per metre of the T-shirt)");
            spec.tshirt.cells_per_metre = static_cast<float>(*size);
        }
        size_ = static_cast<std::uint32_t>(spec.tshirt.cells_per_metre);
        total_mass_ = spec.tshirt.total_mass;
    }
    fabric_.stiffness = {spec.stiffness, spec.stiffness * spec.shear_ratio, spec.stiffness * spec.bend_ratio,
                         spec.seam_stiffness};
    fabric_.damping_ratio = spec.damping_ratio;
    // Node mass: the scene's total over its particles (set exactly in rebuild, once the count is known).
    fabric_.node_mass_g = 1000.0f * total_mass_ / float(std::max<std::size_t>(1, scene_particle_count(spec)));
    params_ = spec.physics;
    params_.dt = spec.dt ? *spec.dt : 0.0f;
    auto_dt_ = !spec.dt.has_value();
    spec_ = std::move(spec);
    rebuild(false);
    error_.clear();
    ++scene_generation_;
}

std::array<SpringMaterial, spring_kind_count> ViewSession::materials(const FabricSettings& f) const {
    // Damping as a fraction of the critical damping of one spring between two particles: kd = r * 2 sqrt(k m
    // / 2), the same rule the scenes use, so the damping means the same at any resolution and node mass.
    const float m = f.node_mass_g * 1e-3f;
    std::array<SpringMaterial, spring_kind_count> out{};
    for (std::size_t k = 0; k < spring_kind_count; ++k)
        out[k] = {f.stiffness[k], f.damping_ratio * 2.0f * std::sqrt(f.stiffness[k] * m * 0.5f)};
    return out;
}

double ViewSession::bound_for(const FabricSettings& f, float air_drag) const {
    if (grid_scene()) {
        // The Gershgorin bound is a maximum over particles; in a uniform grid every interior particle of an 8
        // x 8 grid already has all twelve springs, so a small probe cloth with the same node mass and
        // materials gives the bound of the full cloth without copying it.
        HangParams probe = spec_.grid;
        probe.n = std::min<std::uint32_t>(size_, 8);
        probe.total_mass = f.node_mass_g * 1e-3f * float(probe.n * probe.n);
        probe.pins = GridPins::none;
        SceneBuild s = build_hang_scene(probe);
        apply_materials(s.cloth, materials(f));
        return stability_bound(s.cloth, air_drag).dt_max;
    }
    // Other cloths: the bound over a copy of the topology with every particle movable (pinned ones too: they
    // may be unpinned later) at the new node mass.
    const Cloth& c = sim_->cloth();
    Cloth probe;
    probe.particle_count = c.particle_count;
    probe.padded_count = c.padded_count;
    probe.inv_mass.reset(c.padded_count);
    const float inv = 1.0f / (f.node_mass_g * 1e-3f);
    for (std::size_t i = 0; i < c.particle_count; ++i)
        probe.inv_mass[i] = inv;
    probe.edges = c.edges;
    probe.material = materials(f);
    return stability_bound(probe, air_drag).dt_max;
}

int ViewSession::auto_substep_count(double dt) const {
    const double particles = double(particle_count());
    const int cap = std::clamp(static_cast<int>(view_auto_budget / particles), 10, view_max_substeps);
    const int want = static_cast<int>(std::ceil(view_frame_seconds / dt - 1e-9));
    return std::clamp(want, 1, cap);
}

void ViewSession::rebuild(bool keep_state) {
    // Capture what continues across the rebuild.
    InitialState state;
    std::vector<std::uint32_t> pins;
    if (keep_state && sim_) {
        sim_->release_grab();
        const std::size_t n = sim_->cloth().particle_count;
        state.x.assign(sim_->x().begin(), sim_->x().end());
        state.y.assign(sim_->y().begin(), sim_->y().end());
        state.z.assign(sim_->z().begin(), sim_->z().end());
        state.vx.resize(n);
        state.vy.resize(n);
        state.vz.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const auto v = sim_->velocity(i);
            state.vx[i] = v[0];
            state.vy[i] = v[1];
            state.vz[i] = v[2];
            if (sim_->is_pinned(i)) pins.push_back(static_cast<std::uint32_t>(i));
        }
    }
    SceneSpec spec = spec_;
    if (spec.cloth == ClothType::grid)
        spec.grid.n = size_;
    else
        spec.tshirt.cells_per_metre = static_cast<float>(size_);
    const std::size_t count = scene_particle_count(spec);
    if (spec.cloth == ClothType::grid)
        spec.grid.total_mass = fabric_.node_mass_g * 1e-3f * float(count);
    else
        spec.tshirt.total_mass = std::clamp(fabric_.node_mass_g * 1e-3f * float(count), 0.001f, 10.0f);
    spec.stiffness = fabric_.stiffness[0];
    spec.damping_ratio = fabric_.damping_ratio;
    BuiltScene scene = build_scene(spec);
    Cloth& cloth = scene.cloth;
    // The exact node mass now that the count is known (the T-shirt's estimate may differ).
    fabric_.node_mass_g = 1000.0f * spec_total_mass(spec) / float(cloth.particle_count);
    apply_materials(cloth, materials(fabric_));
    // Pins authored by the scene become user pins: they get the node mass back and are pinned after
    // construction, so every pin the user sees can be unpinned (the core restores an unpinned particle's
    // authored mass).
    std::vector<std::uint32_t> authored;
    const float inv = 1.0f / (fabric_.node_mass_g * 1e-3f);
    for (std::size_t i = 0; i < cloth.particle_count; ++i)
        if (cloth.inv_mass[i] == 0.0f) {
            authored.push_back(static_cast<std::uint32_t>(i));
            cloth.inv_mass[i] = inv;
        }
    has_seams_ = false;
    for (const Edge& e : cloth.edges)
        has_seams_ = has_seams_ || e.kind == SpringKind::seam;

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
    cloth_size_ = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 1e-3f});
    spacing_ = spec.cloth == ClothType::grid ? spec.grid.size / float(std::max<std::uint32_t>(size_, 2) - 1)
                                             : 1.0f / float(size_);
    if (!authored.empty() && hi[1] - lo[1] < 0.1f * cloth_size_) {
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
        const float swing = 0.25f * cloth_size_;
        lo = {plo[0] - swing, phi[1] - cloth_size_, plo[2] - swing};
        hi = {phi[0] + swing, phi[1], phi[2] + swing};
    }
    if (params_.aero.enabled) {
        // A pinned cloth in a steady wind flies downwind, about its own size.
        const auto& v = params_.aero.velocity;
        const float speed = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (speed > 0.0f && !authored.empty())
            for (int k = 0; k < 3; ++k) {
                const float d = cloth_size_ * v[k] / speed;
                if (d > 0.0f)
                    hi[k] += d;
                else
                    lo[k] += d;
            }
    }
    ground_.reset();
    for (const Collider& c : scene.params.colliders) {
        if (c.kind == ColliderKind::plane) {
            if (c.axis[1] > 0.99f) ground_ = c.centre[1];
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
    frame_lo_ = lo;
    frame_hi_ = hi;

    // Run parameters: the user's (kept across rebuilds), the scene's colliders.
    params_.colliders = scene.params.colliders;
    dt_bound_ = stability_bound(cloth, params_.air_drag).dt_max;
    if (auto_dt_ || !(params_.dt > 0.0f) || params_.dt > dt_bound_)
        params_.dt = static_cast<float>(0.9 * dt_bound_);
    // The new simulation is complete before it replaces the old one: if anything throws, the old one stays.
    const bool keep = keep_state && !state.x.empty() && state.x.size() == cloth.particle_count;
    auto sim = std::make_unique<Simulation>(std::move(scene.cloth), keep ? state : scene.initial, params_);
    for (std::uint32_t i : keep ? pins : authored)
        sim->set_pinned(i, true);
    auto publisher = std::make_unique<Publisher>(sim->cloth());
    publisher_ = std::move(publisher);
    sim_ = std::move(sim);
    if (auto_substeps_)
        substeps_ = auto_substep_count(params_.dt);
    else if (!keep_frame_time_)
        frame_time_ = double(substeps_) * double(params_.dt);
    ++generation_;
    refresh_pins();
}

void ViewSession::refresh_pins() {
    pinned_.clear();
    const std::size_t n = sim_->cloth().particle_count, grabbed = sim_->grabbed();
    for (std::size_t i = 0; i < n; ++i)
        if (i != grabbed && sim_->is_pinned(i)) pinned_.push_back(static_cast<std::uint32_t>(i));
    ++markers_version_;
}

std::size_t ViewSession::advance() {
    if (!running_ && !step_pending_) return 0;
    step_pending_ = false;
    const std::size_t before = sim_->steps_done();
    try {
        sim_->step(static_cast<std::size_t>(substeps_));
    } catch (const SimulationError& e) {
        running_ = false;
        error_ = e.what();
        post(MessageLevel::error, "simulation stopped: " + error_ + " - press Backspace or Reset to restart");
    }
    return sim_->steps_done() - before;
}

void ViewSession::set_running(bool on) {
    if (on && !error_.empty()) {
        post(MessageLevel::warning, "the simulation stopped on a non-finite value; Reset first");
        return;
    }
    running_ = on;
}

void ViewSession::step_once() {
    if (!error_.empty()) return;
    running_ = false;
    step_pending_ = true;
}

void ViewSession::reset() {
    if (!guarded("reset", [&] { rebuild(false); })) return;
    error_.clear();
    post(MessageLevel::info, "reset: the scene's starting state and pins, current settings");
}

ViewSession::Snapshot ViewSession::snapshot() const {
    return {size_,   spec_,   total_mass_, fabric_,   has_seams_, cloth_size_, frame_lo_,  frame_hi_,
            ground_, params_, auto_dt_,    dt_bound_, substeps_,  spacing_,    frame_time_};
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
    keep_frame_time_ = false;
    spacing_ = b.spacing;
}

bool ViewSession::commit_params(const SimulationParams& p) {
    // set_params leaves the simulation as it was when it refuses, so no snapshot is needed (unlike guarded()).
    try {
        sim_->set_params(p);
    } catch (const InvalidInput& e) {
        post(MessageLevel::warning, std::string("refused: ") + e.what());
        return false;
    }
    params_ = p;
    return true;
}

bool ViewSession::guarded(const std::string& what, const std::function<void()>& change) {
    // Rebuilds are transactional: on bad input or no memory the old cloth and settings stay, with a message.
    const Snapshot before = snapshot();
    try {
        change();
        return true;
    } catch (const InvalidInput& e) {
        restore(before);
        post(MessageLevel::warning, "refused: " + what + ": " + e.what());
    } catch (const std::bad_alloc&) {
        restore(before);
        post(MessageLevel::warning, "refused: " + what + ": out of memory");
    }
    return false;
}

void ViewSession::set_scene(const std::string& name_or_path) {
    const auto start = std::chrono::steady_clock::now();
    SceneSpec spec;
    try {
        spec = load_scene(name_or_path);
    } catch (const InvalidInput& e) {
        post(MessageLevel::warning, std::string("refused: ") + e.what());
        return;
    }
    std::optional<std::uint32_t> size;
    if (spec.cloth == ClothType::grid && spec.name == "hang") size = view_default_hang_size;
    if (!guarded("scene " + name_or_path, [&] { load_spec(std::move(spec), size); })) return;
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    post(MessageLevel::info, "scene " + spec_.name + ": " + std::to_string(sim_->cloth().particle_count) +
                                 " particles, built in " + fmt(ms, 3) + " ms. " + spec_.description);
}

void ViewSession::set_size(std::uint32_t n) {
    if (grid_scene())
        n = std::clamp(n, view_min_size, view_max_size);
    else
        n = std::clamp(n, view_min_cells, view_max_cells);
    if (n == size_) return;
    const auto start = std::chrono::steady_clock::now();
    SceneSpec probe = spec_;
    if (grid_scene())
        probe.grid.n = n;
    else
        probe.tshirt.cells_per_metre = static_cast<float>(n);
    const std::string what = "resolution " + std::to_string(n);
    if (!guarded(what, [&] {
            size_ = n;
            fabric_.node_mass_g =
                1000.0f * total_mass_ / float(std::max<std::size_t>(1, scene_particle_count(probe)));
            rebuild(false);
        }))
        return;
    error_.clear();
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    post(MessageLevel::info, "rebuilt: " + std::to_string(sim_->cloth().particle_count) + " particles in " +
                                 fmt(ms, 3) + " ms; node mass " + fmt(fabric_.node_mass_g, 3) + " g (" +
                                 fmt(total_mass_, 3) + " kg in total)");
}

bool ViewSession::apply_physics(const Candidate& next, const std::string& what) {
    const double bound = bound_for(next.fabric, next.air_drag);
    const double old_dt = sim_->params().dt;
    double new_dt = old_dt;
    if (auto_dt_ || old_dt > bound) new_dt = 0.9 * bound;
    int new_substeps = substeps_;
    if (auto_substeps_) {
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
        sim_->set_params(p);
        p.dt = static_cast<float>(new_dt);
        sim_->set_params(p);
    } catch (const InvalidInput& e) {
        // The probe bound and the core's disagree in the last bits: restore everything and say so.
        try {
            SimulationParams safe = sim_->params();
            safe.dt = std::min(safe.dt, old_params.dt);
            sim_->set_params(safe);
            for (std::size_t k = 0; k < spring_kind_count; ++k)
                sim_->set_material(static_cast<SpringKind>(k), old_materials[k]);
            sim_->set_params(old_params);
        } catch (const InvalidInput&) {
            // Cannot happen (the old state was stable); the smaller dt then stays, which is stable too.
        }
        post(MessageLevel::warning, "refused: " + what + ": " + e.what());
        return false;
    }
    fabric_ = next.fabric;
    params_ = sim_->params();
    dt_bound_ = bound;
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
    k = std::clamp(k, view_min_stiffness, view_max_stiffness);
    Candidate c{fabric_, sim_->params().air_drag};
    c.fabric.stiffness[static_cast<std::size_t>(kind)] = k;
    static const char* names[] = {"structural", "shear", "bend", "seam"};
    apply_physics(c,
                  std::string(names[static_cast<std::size_t>(kind)]) + " stiffness " + fixed(k, 0) + " N/m");
}

void ViewSession::set_damping_ratio(float ratio) {
    ratio = std::clamp(ratio, 0.0f, 1.0f);
    Candidate c{fabric_, sim_->params().air_drag};
    c.fabric.damping_ratio = ratio;
    apply_physics(c, "damping " + fmt(ratio, 3) + " of critical");
}

void ViewSession::set_air_drag(float drag) {
    drag = std::clamp(drag, 0.0f, 100.0f);
    apply_physics({fabric_, drag}, "air drag " + fmt(drag, 3) + " 1/s");
}

void ViewSession::set_node_mass(float grams) {
    grams = std::clamp(grams, view_min_node_mass_g, view_max_node_mass_g);
    const double bound = bound_for({grams, fabric_.stiffness, fabric_.damping_ratio}, params_.air_drag);
    const double old_dt = sim_->params().dt;
    double new_dt = (auto_dt_ || old_dt > bound) ? 0.9 * bound : old_dt;
    int new_substeps = substeps_;
    if (!auto_substeps_) {
        new_substeps = manual_substep_count(new_dt);
        if (new_substeps > view_max_substeps) {
            post(MessageLevel::warning, "refused: node mass " + fmt(grams) + " g needs dt <= " + fmt(bound) +
                                            " s, i.e. " + std::to_string(new_substeps) +
                                            " substeps per frame (max " + std::to_string(view_max_substeps) +
                                            ")");
            return;
        }
    }
    const auto start = std::chrono::steady_clock::now();
    const bool was_error = !error_.empty();
    if (!guarded("node mass " + fmt(grams) + " g", [&] {
            fabric_.node_mass_g = grams;
            params_ = sim_->params();
            params_.dt = static_cast<float>(new_dt);
            if (!auto_substeps_) substeps_ = new_substeps;
            keep_frame_time_ = true; // the node mass keeps the pace, like the other physics changes
            rebuild(!was_error);
            keep_frame_time_ = false;
        }))
        return;
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    post(new_dt < old_dt ? MessageLevel::warning : MessageLevel::info,
         "node mass " + fmt(grams) + " g (cloth rebuilt in " + fmt(ms) + " ms, motion kept); dt " +
             fmt(params_.dt) + " s (bound " + fmt(dt_bound_) + " s), " + std::to_string(substeps_) +
             " substeps per frame");
}

void ViewSession::set_gravity(const std::array<float, 3>& g) {
    SimulationParams p = sim_->params();
    for (int i = 0; i < 3; ++i)
        p.gravity[i] = std::clamp(g[i], -50.0f, 50.0f);
    commit_params(p);
}

void ViewSession::set_wind(bool enabled, float strength) {
    SimulationParams p = sim_->params();
    p.wind.enabled = enabled;
    p.wind.strength = std::clamp(strength, 0.0f, 100.0f);
    commit_params(p);
}

void ViewSession::set_integrator(Integrator integrator) {
    SimulationParams p = sim_->params();
    p.integrator = integrator;
    if (!commit_params(p)) return;
    post(MessageLevel::info, std::string("integrator: ") + integrator_name(integrator));
}

void ViewSession::set_strain_limit(const StrainLimit& limit) {
    SimulationParams p = sim_->params();
    p.strain_limit.ratio = std::clamp(limit.ratio, 0.0f, 10.0f);
    p.strain_limit.passes = std::clamp<std::uint32_t>(limit.passes, 1, 100);
    p.strain_limit.every = std::clamp<std::uint32_t>(limit.every, 1, 1000);
    commit_params(p);
}

void ViewSession::set_dt(double dt) {
    // The top of the slider is the bound itself: keep the float dt just below it (rounding to float, and the
    // probe bound against the core's own, may differ in the last bits).
    const double top = dt_bound_ * (1.0 - 1e-6);
    dt = std::clamp(dt, 1e-3 * dt_bound_, top);
    SimulationParams p = sim_->params();
    p.dt = static_cast<float>(dt);
    if (double(p.dt) > top) p.dt = std::nextafter(p.dt, 0.0f);
    if (!commit_params(p)) return;
    auto_dt_ = false;
    if (auto_substeps_)
        substeps_ = auto_substep_count(dt);
    else
        frame_time_ = double(substeps_) * double(p.dt);
}

void ViewSession::set_auto_dt(bool on) {
    auto_dt_ = on;
    if (on) {
        set_dt(0.9 * dt_bound_);
        auto_dt_ = true;
    }
}

void ViewSession::set_substeps(int s) {
    substeps_ = std::clamp(s, 1, view_max_substeps);
    auto_substeps_ = false;
    frame_time_ = double(substeps_) * double(sim_->params().dt);
}

void ViewSession::set_auto_substeps(bool on) {
    auto_substeps_ = on;
    if (on)
        substeps_ = auto_substep_count(sim_->params().dt);
    else
        frame_time_ = double(substeps_) * double(sim_->params().dt);
}

int ViewSession::manual_substep_count(double dt) const {
    const double want = std::ceil(frame_time_ / dt - 1e-6);
    return want > 1e6 ? 1000000 : std::max(1, static_cast<int>(want));
}

void ViewSession::set_threads(int t) {
    t = std::clamp(t, 1, 256);
    thread_limit_.reset();
    thread_limit_ = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                          static_cast<std::size_t>(t));
    threads_ = t;
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
    }
    const std::array<float, spring_kind_count>& k = fabric_.stiffness;
    spec.stiffness = k[0];
    if (k[0] > 0.0f) {
        spec.shear_ratio = k[static_cast<std::size_t>(SpringKind::shear)] / k[0];
        spec.bend_ratio = k[static_cast<std::size_t>(SpringKind::bend)] / k[0];
    }
    spec.seam_stiffness = k[static_cast<std::size_t>(SpringKind::seam)];
    spec.damping_ratio = fabric_.damping_ratio;
    const std::vector<Collider> colliders = spec_.physics.colliders; // the scene's own (a body is spec.body)
    spec.physics = params_;
    spec.physics.colliders = colliders;
    spec.dt = auto_dt_ ? std::nullopt : std::optional<float>(params_.dt);
    return spec;
}

} // namespace drape::app
