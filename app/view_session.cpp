// The viewer's model (see view_session.hpp for the stability rules).
#include "view_session.hpp"

#include <algorithm>
#include <cmath>
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

constexpr float default_total_mass = 0.1f; // kg, scene "hang" (BENCH.md)

} // namespace

int ViewSession::hardware_threads() { return std::max(1, tbb::info::default_concurrency()); }

ViewSession::ViewSession(std::uint32_t size, int threads, std::optional<int> substeps) : size_(size) {
    if (size < view_min_size || size > view_max_size)
        throw InvalidInput("--size " + std::to_string(size) + " is outside the allowed range [" +
                           std::to_string(view_min_size) + ", " + std::to_string(view_max_size) + "]");
    set_threads(threads > 0 ? threads : hardware_threads());
    if (substeps) {
        auto_substeps_ = false;
        substeps_ = std::clamp(*substeps, 1, view_max_substeps);
    }
    fabric_.node_mass_g = 1000.0f * default_total_mass / float(std::size_t{size} * size);
    rebuild(false);
    message_ = {};
}

void ViewSession::post(MessageLevel level, std::string text) {
    message_ = {std::move(text), level, std::chrono::steady_clock::now()};
}

std::array<SpringMaterial, spring_kind_count> ViewSession::materials(const FabricSettings& f) const {
    // Damping as a fraction of the critical damping of one spring between two particles: kd = r * 2 sqrt(k m / 2),
    // the same rule scene "hang" uses, so the damping means the same at any resolution and node mass.
    const float m = f.node_mass_g * 1e-3f;
    std::array<SpringMaterial, spring_kind_count> out{}; // other kinds (seams) unused by "hang": zero
    for (std::size_t k = 0; k < grid_spring_kinds; ++k)
        out[k] = {f.stiffness[k], f.damping_ratio * 2.0f * std::sqrt(f.stiffness[k] * m * 0.5f)};
    return out;
}

double ViewSession::bound_for(const FabricSettings& f, float air_drag) const {
    // The Gershgorin bound is a maximum over particles; in a uniform grid every interior particle of an 8 x 8 grid
    // already has all twelve springs, so a small probe cloth with the same node mass and materials gives the bound
    // of the full cloth without copying it.
    HangParams probe = hang_;
    probe.n = std::min<std::uint32_t>(size_, 8);
    probe.total_mass = f.node_mass_g * 1e-3f * float(probe.n * probe.n);
    probe.pins = drape::GridPins::none;
    SceneBuild s = build_hang_scene(probe);
    apply_materials(s.cloth, materials(f));
    return stability_bound(s.cloth, air_drag).dt_max;
}

int ViewSession::auto_substep_count(double dt) const {
    const double particles = double(std::size_t{size_} * size_);
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
    hang_.n = size_;
    hang_.total_mass = fabric_.node_mass_g * 1e-3f * float(std::size_t{size_} * size_);
    hang_.stiffness = fabric_.stiffness[0];
    hang_.damping_ratio = fabric_.damping_ratio;
    // Corners are pinned by the viewer after construction, not by the scene: pins the user made are then all
    // alike and any of them can be unpinned (an authored pin has no mass to restore).
    hang_.pins = drape::GridPins::none;
    SceneBuild scene = build_hang_scene(hang_);
    apply_materials(scene.cloth, materials(fabric_));
    spacing_ = hang_.size / float(size_ - 1);

    dt_bound_ = stability_bound(scene.cloth, params_.air_drag).dt_max;
    if (auto_dt_ || !(params_.dt > 0.0f) || params_.dt > dt_bound_) params_.dt = static_cast<float>(0.9 * dt_bound_);
    if (auto_substeps_) substeps_ = auto_substep_count(params_.dt);

    sim_.reset();
    publisher_.reset();
    sim_ = std::make_unique<Simulation>(std::move(scene.cloth), keep_state && !state.x.empty() ? state : scene.initial,
                                        params_);
    if (keep_state && !pins.empty()) {
        for (std::uint32_t i : pins) sim_->set_pinned(i, true);
    } else {
        sim_->set_pinned(grid_index(size_, 0, 0), true);
        sim_->set_pinned(grid_index(size_, size_ - 1, 0), true);
    }
    publisher_ = std::make_unique<Publisher>(sim_->cloth());
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
    error_.clear();
    rebuild(false);
    post(MessageLevel::info, "reset: flat cloth, corners pinned");
}

void ViewSession::set_size(std::uint32_t n) {
    n = std::clamp(n, view_min_size, view_max_size);
    if (n == size_) return;
    const auto start = std::chrono::steady_clock::now();
    size_ = n;
    fabric_.node_mass_g = 1000.0f * default_total_mass / float(std::size_t{n} * n);
    error_.clear();
    rebuild(false);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    post(MessageLevel::info, "rebuilt at " + std::to_string(n) + " x " + std::to_string(n) + " = " +
                                 std::to_string(std::size_t{n} * n) + " particles in " + fmt(ms, 3) +
                                 " ms; node mass " + fmt(fabric_.node_mass_g, 3) + " g (0.1 kg in total)");
}

bool ViewSession::apply_physics(const Candidate& next, const std::string& what) {
    const double bound = bound_for(next.fabric, next.air_drag);
    const double old_dt = sim_->params().dt;
    double new_dt = old_dt;
    if (auto_dt_ || old_dt > bound) new_dt = 0.9 * bound;
    int new_substeps = substeps_;
    if (auto_substeps_) {
        new_substeps = auto_substep_count(new_dt);
    } else if (new_dt < old_dt) {
        // Keep the simulated time per frame: substeps x dt.
        new_substeps = static_cast<int>(std::ceil(double(substeps_) * old_dt / new_dt - 1e-6));
        if (new_substeps > view_max_substeps) {
            post(MessageLevel::warning,
                 "refused: " + what + " needs dt <= " + fmt(bound) + " s, i.e. " + std::to_string(new_substeps) +
                     " substeps per frame to keep the pace (max " + std::to_string(view_max_substeps) +
                     "); lower the substeps or choose automatic substeps");
            return false;
        }
    }
    const std::array<SpringMaterial, spring_kind_count> old_materials = sim_->cloth().material;
    const std::array<SpringMaterial, spring_kind_count> new_materials = materials(next.fabric);
    SimulationParams p = sim_->params();
    const SimulationParams old_params = p;
    try {
        // Order keeps every intermediate state stable: first the smaller dt (old materials, old drag), then the
        // new materials / drag, then the new dt.
        p.dt = static_cast<float>(std::min(old_dt, new_dt));
        sim_->set_params(p);
        for (std::size_t k = 0; k < grid_spring_kinds; ++k)
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
            for (std::size_t k = 0; k < grid_spring_kinds; ++k)
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
            note += ", substeps per frame " + std::to_string(old_substeps) + " -> " + std::to_string(new_substeps) +
                    (auto_substeps_ ? " (automatic)" : " to keep the simulated time per frame");
        post(MessageLevel::warning, note);
    } else {
        if (new_dt != old_dt) note += "; dt " + fmt(new_dt) + " s (bound " + fmt(bound) + " s)";
        post(MessageLevel::info, note);
    }
    return true;
}

void ViewSession::set_stiffness(SpringKind kind, float k) {
    k = std::clamp(k, view_min_stiffness, view_max_stiffness);
    Candidate c{fabric_, sim_->params().air_drag};
    c.fabric.stiffness[static_cast<std::size_t>(kind)] = k;
    static const char* names[] = {"structural", "shear", "bend"};
    apply_physics(c, std::string(names[static_cast<std::size_t>(kind)]) + " stiffness " + fmt(k, 4) + " N/m");
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
    if (!auto_substeps_ && new_dt < old_dt) {
        new_substeps = static_cast<int>(std::ceil(double(substeps_) * old_dt / new_dt - 1e-6));
        if (new_substeps > view_max_substeps) {
            post(MessageLevel::warning, "refused: node mass " + fmt(grams) + " g needs dt <= " + fmt(bound) + " s, i.e. " +
                                            std::to_string(new_substeps) + " substeps per frame (max " +
                                            std::to_string(view_max_substeps) + ")");
            return;
        }
    }
    const auto start = std::chrono::steady_clock::now();
    fabric_.node_mass_g = grams;
    params_ = sim_->params();
    params_.dt = static_cast<float>(new_dt);
    if (!auto_substeps_) substeps_ = new_substeps;
    const bool was_error = !error_.empty();
    rebuild(!was_error);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    post(new_dt < old_dt ? MessageLevel::warning : MessageLevel::info,
         "node mass " + fmt(grams) + " g (cloth rebuilt in " + fmt(ms) + " ms, motion kept); dt " + fmt(params_.dt) +
             " s (bound " + fmt(dt_bound_) + " s), " + std::to_string(substeps_) + " substeps per frame");
}

void ViewSession::set_gravity(const std::array<float, 3>& g) {
    SimulationParams p = sim_->params();
    for (int i = 0; i < 3; ++i) p.gravity[i] = std::clamp(g[i], -50.0f, 50.0f);
    sim_->set_params(p);
    params_ = p;
}

void ViewSession::set_wind(bool enabled, float strength) {
    SimulationParams p = sim_->params();
    p.wind.enabled = enabled;
    p.wind.strength = std::clamp(strength, 0.0f, 100.0f);
    sim_->set_params(p);
    params_ = p;
}

void ViewSession::set_integrator(Integrator integrator) {
    SimulationParams p = sim_->params();
    p.integrator = integrator;
    sim_->set_params(p);
    params_ = p;
    post(MessageLevel::info, std::string("integrator: ") + integrator_name(integrator));
}

void ViewSession::set_strain_limit(const StrainLimit& limit) {
    SimulationParams p = sim_->params();
    p.strain_limit.ratio = std::clamp(limit.ratio, 0.0f, 10.0f);
    p.strain_limit.passes = std::clamp<std::uint32_t>(limit.passes, 1, 100);
    p.strain_limit.every = std::clamp<std::uint32_t>(limit.every, 1, 1000);
    try {
        sim_->set_params(p);
    } catch (const InvalidInput& e) {
        post(MessageLevel::warning, std::string("refused: ") + e.what());
        return;
    }
    params_ = p;
}

void ViewSession::set_dt(double dt) {
    // The top of the slider is the bound itself: keep the float dt just below it (rounding to float, and the probe
    // bound against the core's own, may differ in the last bits).
    const double top = dt_bound_ * (1.0 - 1e-6);
    dt = std::clamp(dt, 1e-3 * dt_bound_, top);
    SimulationParams p = sim_->params();
    p.dt = static_cast<float>(dt);
    if (double(p.dt) > top) p.dt = std::nextafter(p.dt, 0.0f);
    try {
        sim_->set_params(p);
    } catch (const InvalidInput& e) {
        post(MessageLevel::warning, std::string("refused: ") + e.what());
        return;
    }
    params_ = p;
    auto_dt_ = false;
    if (auto_substeps_) substeps_ = auto_substep_count(dt);
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
}

void ViewSession::set_auto_substeps(bool on) {
    auto_substeps_ = on;
    if (on) substeps_ = auto_substep_count(sim_->params().dt);
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

} // namespace drape::app
