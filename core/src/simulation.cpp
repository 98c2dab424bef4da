// Simulation set-up, parameters and state queries. The per-substep pipeline is in substep.cpp.
#include "drape/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>

#include "drape/stability.hpp"
#include "implicit_solver.hpp"
#include "vbd.hpp"

namespace drape {

const char* integrator_name(Integrator integrator) noexcept {
    return integrator == Integrator::verlet ? "verlet" : "euler";
}

const char* kernel_path_name(KernelPath path) noexcept {
    switch (path) {
    case KernelPath::automatic: return "auto";
    case KernelPath::grid: return "grid";
    case KernelPath::csr: return "csr";
    }
    return "unknown";
}

const char* stage_name(Stage stage) noexcept {
    switch (stage) {
    case Stage::aero_forces: return "aero_forces";
    case Stage::seam_forces: return "seam_forces";
    case Stage::external_forces: return "external_forces";
    case Stage::spring_forces: return "spring_forces";
    case Stage::integrate: return "integrate";
    case Stage::strain_limit: return "strain_limit";
    case Stage::collide: return "collide";
    case Stage::self_collide: return "self_collide";
    case Stage::count: break;
    }
    return "unknown";
}

namespace {

void check(bool ok, const std::string& name, double value, const char* range) {
    if (!ok) throw InvalidInput(name + " = " + std::to_string(value) + " is outside the allowed range " + range);
}

} // namespace

void validate_params(const SimulationParams& p) {
    check(std::isfinite(p.dt) && p.dt > 0.0f && p.dt <= 0.1f, "dt", p.dt, "(0, 0.1] s");
    for (int k = 0; k < 3; ++k)
        check(std::isfinite(p.gravity[k]) && std::fabs(p.gravity[k]) <= 100.0f, "gravity[" + std::to_string(k) + "]",
              p.gravity[k], "[-100, 100] m/s^2");
    check(std::isfinite(p.air_drag) && p.air_drag >= 0.0f && p.air_drag <= 100.0f, "air drag", p.air_drag,
          "[0, 100] 1/s");
    check(std::isfinite(p.wind.strength) && p.wind.strength >= 0.0f && p.wind.strength <= 100.0f, "wind strength",
          p.wind.strength, "[0, 100] m/s^2");
    check(std::isfinite(p.strain_limit.ratio) && p.strain_limit.ratio >= 0.0f && p.strain_limit.ratio <= 10.0f,
          "strain limit ratio", p.strain_limit.ratio, "[0, 10] (0 = off)");
    check(p.strain_limit.passes >= 1 && p.strain_limit.passes <= 100, "strain limit passes", p.strain_limit.passes,
          "[1, 100]");
    check(std::isfinite(p.aero.density) && p.aero.density >= 0.0f && p.aero.density <= 100.0f, "aero density",
          p.aero.density, "[0, 100] kg/m^3");
    check(std::isfinite(p.aero.drag_coefficient) && p.aero.drag_coefficient >= 0.0f && p.aero.drag_coefficient <= 10.0f,
          "aero drag coefficient", p.aero.drag_coefficient, "[0, 10]");
    for (int k = 0; k < 3; ++k)
        check(std::isfinite(p.aero.velocity[k]) && std::fabs(p.aero.velocity[k]) <= 100.0f,
              "aero velocity[" + std::to_string(k) + "]", p.aero.velocity[k], "[-100, 100] m/s");
    check(std::isfinite(p.sewing_speed) && p.sewing_speed >= 0.0f && p.sewing_speed <= 10.0f, "sewing speed",
          p.sewing_speed, "[0, 10] m/s (0 = off: every seam must then start closed)");
    check(p.strain_limit.every >= 1 && p.strain_limit.every <= 1000, "strain limit interval", p.strain_limit.every,
          "[1, 1000] substeps");
    if (p.solver == Solver::implicit) {
        if (p.integrator != Integrator::symplectic_euler)
            throw InvalidInput("integrator 'verlet' is a choice of the explicit solver only; the implicit solver keeps "
                               "velocities (use integrator 'euler' with solver 'implicit')");
        if (!(p.dt >= implicit_min_dt)) {
            char dt[32];
            std::snprintf(dt, sizeof dt, "%.4g", double(p.dt));
            throw InvalidInput("dt = " + std::string(dt) + " s is below the implicit solver's shortest step, 1e-4 s "
                               "(its motion under gravity would be lost to the rounding of positions); use the explicit "
                               "solver for steps that short");
        }
        check(p.implicit.iterations >= 1 && p.implicit.iterations <= 1000, "implicit iterations", p.implicit.iterations,
              "[1, 1000]");
        check(std::isfinite(p.implicit.tolerance) && p.implicit.tolerance >= 0.0f && p.implicit.tolerance <= 1.0f,
              "implicit tolerance", p.implicit.tolerance, "[0, 1] (0 = run every iteration)");
        check(std::isfinite(p.implicit.chebyshev_rho) && p.implicit.chebyshev_rho >= 0.0f &&
                  p.implicit.chebyshev_rho < 1.0f,
              "implicit chebyshev rho", p.implicit.chebyshev_rho, "[0, 1) (0 = no acceleration)");
    }
    {
        const SelfCollision& sc = p.self_collision;
        if (!(std::isfinite(sc.thickness) && (sc.thickness == 0.0f || (sc.thickness >= self_collision_min_thickness &&
                                                                        sc.thickness <= self_collision_max_thickness))))
            throw InvalidInput("self_collision.thickness = " + std::to_string(sc.thickness) +
                               " is outside the allowed range 0 (off) or [0.0005, 0.05] m");
        check(std::isfinite(sc.friction) && sc.friction >= 0.0f && sc.friction <= 2.0f, "self_collision.friction",
              sc.friction, "[0, 2]");
        if (sc.substeps < 1 || sc.substeps > self_collision_max_substeps)
            throw InvalidInput("self_collision.substeps = " + std::to_string(sc.substeps) +
                               " is outside the allowed range [1, " + std::to_string(self_collision_max_substeps) +
                               "] (1 = none)");
    }
    if (p.colliders.size() > 64)
        throw InvalidInput("colliders: " + std::to_string(p.colliders.size()) + " given, at most 64 allowed");
    for (std::size_t k = 0; k < p.colliders.size(); ++k) {
        try {
            check_collider(p.colliders[k]);
        } catch (const InvalidInput& e) {
            throw InvalidInput("colliders[" + std::to_string(k) + "]: " + e.what());
        }
    }
}

// A start stretched beyond what the health monitor lets a running cloth reach (HealthMonitor::strain_ceiling) cannot
// come from a healthy run, and the monitor's bounds, which include what the start holds, would then pass anything:
// a saved state with one corner of a 10 cm cloth at 1e6 m (in range) ran at 1.6e9 m/s, "healthy". Refused.
void Simulation::refuse_overstretched_start(const InitialState& initial) const {
    double worst = 0.0;
    const Edge* worst_edge = nullptr;
    for (const Edge& e : cloth_.edges) {
        if (e.kind != SpringKind::structural || !(e.rest > 0.0f)) continue;
        const double dx = double(initial.x[e.b]) - initial.x[e.a], dy = double(initial.y[e.b]) - initial.y[e.a],
                     dz = double(initial.z[e.b]) - initial.z[e.a];
        const double strain = std::sqrt(dx * dx + dy * dy + dz * dz) / double(e.rest) - 1.0;
        if (strain > worst) {
            worst = strain;
            worst_edge = &e;
        }
    }
    if (worst_edge == nullptr || !(worst > HealthMonitor::strain_ceiling)) return;
    char text[400];
    std::snprintf(text, sizeof text,
                  "the initial state stretches the structural spring between particles %u and %u to %.4g times its rest "
                  "length of %.3g m (strain %.4g); a cloth may start stretched at most %g (%g %%): check the state's "
                  "positions (a scene file's state.positions)",
                  unsigned(worst_edge->a), unsigned(worst_edge->b), worst + 1.0, double(worst_edge->rest), worst,
                  HealthMonitor::strain_ceiling, 100.0 * HealthMonitor::strain_ceiling);
    throw InvalidInput(text);
}

Simulation::Simulation(Cloth cloth, const InitialState& initial, const SimulationParams& params)
    : cloth_(std::move(cloth)) {
    const std::size_t n = cloth_.particle_count;
    const std::vector<float>* fields[6] = {&initial.x, &initial.y, &initial.z, &initial.vx, &initial.vy, &initial.vz};
    const char* names[6] = {"x", "y", "z", "vx", "vy", "vz"};
    for (int f = 0; f < 6; ++f) {
        if (fields[f]->size() != n)
            throw InvalidInput(std::string("initial state field ") + names[f] + " has " +
                               std::to_string(fields[f]->size()) + " entries, expected " + std::to_string(n));
        for (std::size_t i = 0; i < n; ++i)
            if (!std::isfinite((*fields[f])[i]))
                throw InvalidInput(std::string("initial state field ") + names[f] + " of particle " +
                                   std::to_string(i) + " is not finite");
    }
    refuse_overstretched_start(initial);
    kernel_ = resolve_params(params);
    params_ = params;

    const std::size_t padded = cloth_.padded_count, halo = cloth_.halo;
    for (StateBuffer& b : buffers_)
        for (AlignedArray<float>* a : {&b.x, &b.y, &b.z, &b.u, &b.v, &b.w}) a->reset(padded, halo);
    for (AlignedArray<float>* a : {&fx_, &fy_, &fz_, &ax_, &ay_, &az_}) a->reset(padded);
    block_ok_.assign(cloth_.block_count(), 1);
    for (AlignedArray<float>* a : {&extra_fx_, &extra_fy_, &extra_fz_}) a->reset(padded);
    inv_mass_authored_.assign(cloth_.inv_mass.begin(), cloth_.inv_mass.end());
    inv_mass_free_ = cloth_.free_inv_mass.size() == n ? cloth_.free_inv_mass : inv_mass_authored_;
    cook_sewing(initial);
    if (params_.strain_limit.ratio > 0.0f) cook_strain_limit();
    if (params_.aero.enabled) cook_aero();
    if (!params_.colliders.empty()) cook_triangle_contact();
    if (params_.self_collision.thickness > 0.0f) cook_self_collision();
    if (!sc_snap_x_.empty() && initial.snapshot_x.size() == n && initial.snapshot_y.size() == n &&
        initial.snapshot_z.size() == n) { // a saved run's snapshot: the stage continues as it would have
        sc_snap_x_ = initial.snapshot_x;
        sc_snap_y_ = initial.snapshot_y;
        sc_snap_z_ = initial.snapshot_z;
        sc_snap_step_ = 0;
        const SelfCollisionPlanes& pl = initial.sc_planes;
        const std::size_t m = pl.index.size();
        if (pl.partner.size() != m || pl.nx.size() != m || pl.ny.size() != m || pl.nz.size() != m || pl.c.size() != m)
            throw InvalidInput("initial.sc_planes: " + std::to_string(m) + " indices but normals and offsets of other lengths");
        for (std::size_t k = 0; k < m; ++k)
            if (pl.index[k] >= n || pl.partner[k] >= n)
                throw InvalidInput("initial.sc_planes: particle " + std::to_string(pl.index[k]) + " or partner " +
                                   std::to_string(pl.partner[k]) + " is not in [0, " + std::to_string(n) + ")");
        if (!pl.index.empty() && params_.solver != Solver::implicit) {
            for (std::size_t k = 0; k < pl.index.size(); ++k) {
                const std::uint32_t i = pl.index[k];
                sc_push_x_[i] = pl.nx[k];
                sc_push_y_[i] = pl.ny[k];
                sc_push_z_[i] = pl.nz[k];
                sc_plane_c_[i] = pl.c[k];
                sc_partner_[i] = pl.partner[k];
            }
            sc_plane_step_ = 0;
        }
    }

    StateBuffer& s = buffers_[0];
    std::memcpy(s.x.data(), initial.x.data(), n * sizeof(float));
    std::memcpy(s.y.data(), initial.y.data(), n * sizeof(float));
    std::memcpy(s.z.data(), initial.z.data(), n * sizeof(float));
    for (std::size_t i = 0; i < n; ++i) {
        const bool pinned = cloth_.inv_mass[i] == 0.0f;
        store_velocity(s, i, pinned ? std::array<float, 3>{} : std::array{initial.vx[i], initial.vy[i], initial.vz[i]},
                       params_.integrator, params_.dt);
    }
    if (params_.solver == Solver::implicit) cook_implicit(); // after the state: its colouring reads the positions
    monitor_.init(cloth_, params_);
    std::size_t inside = 0;
    for (std::size_t i = 0; i < n; ++i) {
        bool in = false;
        for (const Collider& c : params_.colliders) in = in || is_inside(c, {s.x[i], s.y[i], s.z[i]});
        inside += in && cloth_.inv_mass[i] != 0.0f;
    }
    monitor_.set_started_inside(inside);
    monitor_.rebaseline<true>(cloth_, params_, s, 0);
}

void Simulation::store_velocity(StateBuffer& s, std::size_t i, std::array<float, 3> vel, Integrator integrator,
                                float dt) noexcept {
    if (integrator == Integrator::symplectic_euler) {
        s.u[i] = vel[0];
        s.v[i] = vel[1];
        s.w[i] = vel[2];
    } else { // the displacement over one step that gives this velocity
        s.u[i] = vel[0] * dt;
        s.v[i] = vel[1] * dt;
        s.w[i] = vel[2] * dt;
    }
}

KernelPath Simulation::resolve_params(const SimulationParams& params) const {
    validate_params(params);
    KernelPath kernel = params.kernel;
    // The grid kernel evaluates bending only in the grid fabric's closed form (GridBending).
    const bool grid_bending = cloth_.bending.empty() || cloth_.bending.grid.has_value();
    if (kernel == KernelPath::automatic) kernel = cloth_.grid && grid_bending ? KernelPath::grid : KernelPath::csr;
    if (kernel == KernelPath::grid && !cloth_.grid)
        throw InvalidInput("kernel 'grid' needs a regular-grid cloth; this cloth has no grid stencil (use csr)");
    if (kernel == KernelPath::grid && !grid_bending)
        throw InvalidInput("kernel 'grid' evaluates only the grid fabric's own bending stencil; this cloth's bending "
                           "elements are general (use csr)");
    if (params.solver == Solver::explicit_euler) check_stability(cloth_, params); // implicit: any dt
    return kernel;
}

void Simulation::set_params(const SimulationParams& params) {
    const KernelPath kernel = resolve_params(params);
    if (sewing_ && !(params.sewing_speed > 0.0f)) // seams still open would snap shut
        refuse_seams_off_schedule(x().data(), y().data(), z().data(), {});
    // The last step's velocities stop being this solver's history only when the solver, dt or integrator changes (the
    // viewer sets parameters on any edit: a wind or friction change must not re-guess a resting cloth).
    // A collider taken away or moved may leave a cloth that rested on it held by nothing (as a pin let go,
    // set_pinned): a table lowered by 1 m in the viewer let its cloth fall at 44 % of g. Its friction or margin alone
    // does not count.
    const auto same_solid = [](const Collider& a, const Collider& b) {
        return a.kind == b.kind && a.centre == b.centre && a.axis == b.axis && a.size == b.size &&
               a.rotation == b.rotation;
    };
    bool colliders_moved = params.colliders.size() != params_.colliders.size();
    for (std::size_t k = 0; k < params.colliders.size() && !colliders_moved; ++k)
        colliders_moved = !same_solid(params.colliders[k], params_.colliders[k]);
    if (params.solver != params_.solver || params.dt != params_.dt || params.integrator != params_.integrator ||
        colliders_moved)
        implicit_fresh_ = true;
    // A new integrator or dt changes what u, v, w mean (velocity, or displacement per step): convert them.
    if (params.integrator != params_.integrator || params.dt != params_.dt) {
        for (std::size_t i = 0; i < cloth_.particle_count; ++i)
            store_velocity(cur(), i, velocity(i), params.integrator, params.dt);
    }
    params_ = params;
    kernel_ = kernel;
    if (params_.strain_limit.ratio > 0.0f) cook_strain_limit();
    if (params_.aero.enabled) cook_aero();
    if (!params_.colliders.empty()) cook_triangle_contact();
    if (params_.self_collision.thickness > 0.0f) cook_self_collision();
    else sc_snap_step_ = SIZE_MAX; // off: the next time it is on, sides come from the start of that step again
    sc_plane_step_ = SIZE_MAX; // the explicit planes belong to the parameters of their run
    if (params_.solver == Solver::implicit) cook_implicit();
    monitor_.init(cloth_, params_);
    rebaseline_ = true;
}

void Simulation::set_material(SpringKind kind, SpringMaterial material) {
    const std::array<SpringMaterial, spring_kind_count> previous = cloth_.material;
    std::array<SpringMaterial, spring_kind_count> next = previous;
    next[static_cast<std::size_t>(kind)] = material;
    apply_materials(cloth_, next);
    try {
        if (params_.solver == Solver::explicit_euler) check_stability(cloth_, params_);
    } catch (...) {
        apply_materials(cloth_, previous);
        throw;
    }
    if (implicit_) {
        implicit_->fine.refresh_materials(cloth_);
        // Coarse levels keep the fabric's own constants (a user's spring material applies to the cloth itself).
    }
    monitor_.init(cloth_, params_);
    rebaseline_ = true;
}

void Simulation::set_pinned(std::size_t i, bool pinned) {
    if (i >= cloth_.particle_count)
        throw InvalidInput("particle " + std::to_string(i) + " is outside [0, " +
                           std::to_string(cloth_.particle_count - 1) + "]");
    if (i == grabbed_) {
        grabbed_was_pinned_ = pinned; // takes effect on release
        return;
    }
    if (!pinned && inv_mass_free_[i] == 0.0f) return; // a particle with no known mass stays pinned
    rebaseline_ = true;
    // A particle let go may leave its piece of cloth held by nothing: the implicit solver's next guess must not read
    // the history of a cloth at rest (implicit_step.cpp's first-step rule).
    if (!pinned && cloth_.inv_mass[i] == 0.0f) implicit_fresh_ = true;
    cloth_.inv_mass[i] = pinned ? 0.0f : inv_mass_free_[i];
    if (pinned) store_velocity(cur(), i, {}, params_.integrator, params_.dt);
}

void Simulation::grab(std::size_t i, std::array<float, 3> target) {
    if (i >= cloth_.particle_count)
        throw InvalidInput("particle " + std::to_string(i) + " is outside [0, " +
                           std::to_string(cloth_.particle_count - 1) + "]");
    for (float t : target)
        if (!std::isfinite(t)) throw InvalidInput("grab target is not finite");
    release_grab();
    grabbed_was_pinned_ = is_pinned(i);
    set_pinned(i, true);
    grabbed_ = i;
    grab_target_ = target;
    // Where the particle is: a target away from it is the user's move (the next step notes its speed for the monitor).
    const StateBuffer& s = cur();
    grab_applied_ = {s.x[i], s.y[i], s.z[i]};
    rebaseline_ = true;
}

void Simulation::release_grab() noexcept {
    if (grabbed_ == SIZE_MAX) return;
    const std::size_t i = grabbed_;
    grabbed_ = SIZE_MAX;
    if (!grabbed_was_pinned_) {
        cloth_.inv_mass[i] = inv_mass_free_[i];
        implicit_fresh_ = true; // as when a pin is let go (set_pinned)
    }
    rebaseline_ = true;
}

void Simulation::apply_user_constraints() noexcept {
    if (grabbed_ == SIZE_MAX) return;
    StateBuffer& s = cur();
    const std::size_t i = grabbed_;
    float p[3] = {grab_target_[0], grab_target_[1], grab_target_[2]};
    if (!params_.colliders.empty()) {
        // The hand does not drag the cloth into or through a collider (the body under a garment): the path from where
        // the grabbed particle is to the target is walked in steps of at most 2 mm (256 at most); at the first point
        // inside a collider the particle stops where that path enters it and slides on the tangent plane there
        // (vbd::contact_project, as the implicit sweeps keep points out), so a target inside or beyond the body
        // leaves the particle on the near side of it.
        const float p0[3] = {s.x[i], s.y[i], s.z[i]};
        const float dx = p[0] - p0[0], dy = p[1] - p0[1], dz = p[2] - p0[2];
        const float length = std::sqrt(dx * dx + dy * dy + dz * dz);
        const int samples = std::clamp(static_cast<int>(std::ceil(length / 0.002f)), 1, 256);
        for (int k = 1; k <= samples; ++k) {
            const float t = float(k) / float(samples);
            float q[3] = {p0[0] + t * dx, p0[1] + t * dy, p0[2] + t * dz};
            bool inside = false;
            for (const Collider& c : params_.colliders) inside = inside || is_inside(c, {q[0], q[1], q[2]});
            if (!inside) continue;
            float normal[3];
            vbd::contact_project(params_.colliders, p0, q, normal);
            p[0] = q[0], p[1] = q[1], p[2] = q[2];
            break;
        }
    }
    s.x[i] = p[0];
    s.y[i] = p[1];
    s.z[i] = p[2];
    store_velocity(s, i, {}, params_.integrator, params_.dt);
}

std::array<float, 3> Simulation::velocity(std::size_t i) const noexcept {
    const StateBuffer& s = cur();
    if (params_.integrator == Integrator::symplectic_euler) return {s.u[i], s.v[i], s.w[i]};
    const float inv_dt = 1.0f / params_.dt;
    return {s.u[i] * inv_dt, s.v[i] * inv_dt, s.w[i] * inv_dt};
}

std::vector<std::string> Simulation::stage_names() const {
    if (params_.solver == Solver::implicit) { // implicit_step.cpp
        std::vector<std::string> out{"predict", "vbd_sweeps", "velocity"};
        if (params_.implicit.multilevel && implicit_ && !implicit_->coarse.empty()) out.insert(out.begin() + 1, "multilevel");
        if (!params_.colliders.empty()) out.insert(out.end() - 1, "contact");
        if (params_.aero.enabled) out.insert(out.begin(), "aero_forces");
        if (params_.strain_limit.ratio > 0.0f) out.push_back("strain_limit");
        if (!params_.colliders.empty()) out.push_back("collide");
        if (params_.self_collision.thickness > 0.0f) out.push_back("self_collide");
        return out;
    }
    std::vector<std::string> out{"external_forces", "spring_forces", "spring_damping", "integrate", "pins"};
    if (params_.wind.enabled) out.insert(out.begin() + 1, "wind");
    if (!cloth_.seams.empty()) out.insert(out.begin() + 2, "seam_forces");
    if (params_.aero.enabled) out.insert(out.begin() + 1, "aero_forces");
    if (params_.strain_limit.ratio > 0.0f) out.push_back("strain_limit");
    if (!params_.colliders.empty()) out.push_back("collide");
    if (params_.self_collision.thickness > 0.0f) out.push_back("self_collide");
    return out;
}

std::uint64_t Simulation::checksum() const noexcept {
    std::uint64_t h = 0xcbf29ce484222325ull; // FNV-1a 64
    const StateBuffer& s = cur();
    for (std::size_t i = 0; i < cloth_.particle_count; ++i) {
        for (float f : {s.x[i], s.y[i], s.z[i]}) {
            std::uint32_t bits;
            std::memcpy(&bits, &f, sizeof bits);
            for (int byte = 0; byte < 4; ++byte) {
                h ^= (bits >> (8 * byte)) & 0xffu;
                h *= 0x100000001b3ull;
            }
        }
    }
    return h;
}

SelfCollisionPlanes Simulation::self_collision_planes() const {
    SelfCollisionPlanes out;
    if (self_collision_snapshot()[0].empty() || sc_plane_step_ != sc_snap_step_ || params_.solver == Solver::implicit)
        return out;
    for (std::size_t i = 0; i < cloth_.particle_count; ++i) {
        if (sc_push_x_[i] == 0.0f && sc_push_y_[i] == 0.0f && sc_push_z_[i] == 0.0f) continue;
        out.index.push_back(static_cast<std::uint32_t>(i));
        out.partner.push_back(sc_partner_[i]);
        out.nx.push_back(sc_push_x_[i]);
        out.ny.push_back(sc_push_y_[i]);
        out.nz.push_back(sc_push_z_[i]);
        out.c.push_back(sc_plane_c_[i]);
    }
    return out;
}

} // namespace drape
