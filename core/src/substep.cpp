// One substep: the pipeline that runs the stages over fixed particle blocks.
//   stage 0a aero_forces (aero_forces.cpp, per triangle, gathered per particle) when aerodynamic wind is on;
//   stage 0b seam_forces (seam_forces.cpp, colour groups) when the cloth has seams;
//   stages 1-3 (external forces, spring forces, integrate + pins): fused or staged, below;
//   stage 5 strain_limit (strain_limit.cpp) and stage 6 collide (collide.cpp) on the freshly written buffer,
//   interleaved (sweep, collide, sweep, collide, ...) when both run.
//
// Fused (default): for each SIMD batch of a block, load the particle's own state once, sum its springs
// (stage 2), add external accelerations (stage 1), integrate and apply pins (stage 3), store into the other state
// buffer. One pass over memory: ~54 bytes of streaming state per particle (6 floats read, 6 written, inverse mass,
// grid mask); neighbour rows come from L1/L2.
// Staged: the same per-batch functions, each stage a separate pass through scratch arrays. Same operations in the
// same order, so both forms agree bit for bit (tested); the staged form lets bench/ time each stage alone.
//
// Blocks are `block_particles` wide whatever the thread count; each particle reads only buffer A and writes only
// its own entries of buffer B, so the result is independent of how oneTBB schedules blocks.
#include <cmath>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "drape/simulation.hpp"
#include "external_forces.hpp"
#include "integrate.hpp"
#include "spring_forces.hpp"

namespace drape {

namespace kernels {
namespace {

template <Integrator I, class Springs, bool Wind, bool Extra>
void fused_block(const StepContext& c, std::size_t begin, std::size_t end, std::size_t block) {
    fmask ok(true);
    for (std::size_t p = begin; p < end; p += simd::width) {
        const SelfBatch s = load_self(c, p);
        Vec3b f = Springs::template accumulate<I>(c, p, s);
        add_extra_forces<Extra>(c, p, f);
        const Vec3b a = external_acceleration<I, Wind>(c, s, movable_lanes(c, p));
        ok = ok & integrate_batch<I>(c, p, s, f, a);
    }
    c.block_ok[block] = xsimd::all(ok) ? 1 : 0;
}

using FusedFn = void (*)(const StepContext&, std::size_t, std::size_t, std::size_t);

template <Integrator I, class Springs, bool Extra> FusedFn pick_fused(bool wind) {
    return wind ? fused_block<I, Springs, true, Extra> : fused_block<I, Springs, false, Extra>;
}

template <Integrator I, bool Extra> FusedFn pick_fused(KernelPath path, bool wind, bool bending, bool mirror) {
    if (path == KernelPath::grid)
        return bending ? pick_fused<I, GridFabric, Extra>(wind) : pick_fused<I, GridSprings, Extra>(wind);
    if (mirror)
        return bending ? pick_fused<I, CsrFabricT<true>, Extra>(wind) : pick_fused<I, CsrSpringsT<true>, Extra>(wind);
    return bending ? pick_fused<I, CsrFabric, Extra>(wind) : pick_fused<I, CsrSprings, Extra>(wind);
}

template <Integrator I> FusedFn pick_fused(KernelPath path, bool wind, bool seams, bool bending, bool mirror) {
    return seams ? pick_fused<I, true>(path, wind, bending, mirror) : pick_fused<I, false>(path, wind, bending, mirror);
}

} // namespace
} // namespace kernels

namespace {

/// Runs body(block, begin, end) over every block, in parallel or serially.
template <bool Parallel, class Body> void for_each_block(const Cloth& cloth, Body&& body) {
    const std::size_t blocks = cloth.block_count();
    auto run = [&](std::size_t b) {
        const std::size_t begin = b * block_particles;
        const std::size_t end = std::min(begin + block_particles, cloth.padded_count);
        body(b, begin, end);
    };
    if constexpr (Parallel) {
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1),
                          [&](const tbb::blocked_range<std::size_t>& r) {
                              for (std::size_t b = r.begin(); b != r.end(); ++b) run(b);
                          });
    } else {
        for (std::size_t b = 0; b < blocks; ++b) run(b);
    }
}

} // namespace

kernels::StepContext Simulation::make_context(std::size_t step_index) {
    const StateBuffer& a = buffers_[current_];
    StateBuffer& b = buffers_[1 - current_];
    const Cloth& cl = cloth_;
    kernels::StepContext c{};
    c.x = a.x.data();
    c.y = a.y.data();
    c.z = a.z.data();
    c.u = a.u.data();
    c.v = a.v.data();
    c.w = a.w.data();
    c.out_x = b.x.data();
    c.out_y = b.y.data();
    c.out_z = b.z.data();
    c.out_u = b.u.data();
    c.out_v = b.v.data();
    c.out_w = b.w.data();
    c.inv_mass = cl.inv_mass.data();

    c.dt = params_.dt;
    c.dt2 = params_.dt * params_.dt;
    c.inv_dt = 1.0f / params_.dt;
    const std::array<float, 3> g = gravity_now();
    c.gx = g[0];
    c.gy = g[1];
    c.gz = g[2];
    c.drag = params_.air_drag;
    // Time at the start of this substep, from the step count (no drift from summing dt).
    const double t = static_cast<double>(step_index) * static_cast<double>(params_.dt);
    c.wind_strength = params_.wind.strength;
    // The field depends on the world z (sin(z + 10 t)): the frame's origin z joins the phase, in double.
    c.wind_phase = static_cast<float>(std::fmod(10.0 * t + cl.origin[2], 2.0 * M_PI));
    c.wind_x = params_.wind.strength * static_cast<float>(std::sin(10.0 * t));

    if (cl.grid) {
        const GridStencil& g = *cl.grid;
        c.grid_mask = g.mask.data();
        for (std::size_t s = 0; s < GridStencil::slot_count; ++s) {
            const SpringMaterial& m = cl.material[static_cast<std::size_t>(g.kind[s])];
            c.grid_offset[s] = g.offset[s];
            // Edge::scale of the slot (1 in the springs model: the same bits as the material's own figures).
            const float k = m.stiffness * g.scale[s], kd = m.damping * g.scale[s];
            c.grid_k[s] = k;
            c.grid_krest[s] = k * g.rest[s];
            c.grid_kd[s] = params_.integrator == Integrator::verlet ? kd * c.inv_dt : kd;
        }
    }
    const BendingSet& bend = cl.bending;
    // GridFabric also for a fabric grid without bending (its boundary halves); its bending weights are then 0.
    c.bending = !bend.empty() || (kernel_ == KernelPath::grid && cl.grid && cl.grid->half_edges);
    c.mirror = !cl.mirror.empty();
    c.bend_beta = params_.integrator == Integrator::verlet ? bend.damping * c.inv_dt : bend.damping;
    c.bend_slice_begin = bend.slice_begin.data();
    c.bend_slice_slots = bend.slice_slots.data();
    c.bend_neighbour = bend.sell_neighbour.data();
    c.bend_coefficient = bend.sell_coefficient.data();
    if (bend.grid) {
        c.grid_bend_u = bend.grid->u;
        c.grid_bend_v = bend.grid->v;
        c.grid_twist = bend.grid->twist;
    }
    c.slice_begin = cl.graph.slice_begin.data();
    c.slice_slots = cl.graph.slice_slots.data();
    c.sell_neighbour = cl.graph.sell_neighbour.data();
    c.sell_rest = cl.graph.sell_rest.data();
    c.sell_stiffness = cl.graph.sell_stiffness.data();
    c.sell_damping = cl.graph.sell_damping.data();

    c.extra_fx = extra_fx_.data();
    c.extra_fy = extra_fy_.data();
    c.extra_fz = extra_fz_.data();
    c.fx = fx_.data();
    c.fy = fy_.data();
    c.fz = fz_.data();
    c.ax = ax_.data();
    c.ay = ay_.data();
    c.az = az_.data();
    c.block_ok = block_ok_.data();
    return c;
}

template <bool Parallel> void Simulation::explicit_substep() {
    const Integrator integ = params_.integrator;
    const bool wind = params_.wind.enabled;
    const bool seams = !cloth_.seams.empty(), aero = params_.aero.enabled, extra = extra_forces();
    const kernels::StepContext c = make_context(steps_done_);
    const bool bending = c.bending;
    if (aero) aero_forces_stage<Parallel>();
    if (seams) seam_forces_stage<Parallel>();
    if (params_.fused) {
        const kernels::FusedFn fn = integ == Integrator::symplectic_euler
                                        ? kernels::pick_fused<Integrator::symplectic_euler>(kernel_, wind, extra, bending, c.mirror)
                                        : kernels::pick_fused<Integrator::verlet>(kernel_, wind, extra, bending, c.mirror);
        for_each_block<Parallel>(cloth_, [&](std::size_t b, std::size_t begin, std::size_t end) {
            fn(c, begin, end, b);
        });
    } else {
        for_each_block<Parallel>(cloth_, [&](std::size_t, std::size_t begin, std::size_t end) {
            kernels::spring_forces_range(c, integ, kernel_, extra, begin, end);
        });
        for_each_block<Parallel>(cloth_, [&](std::size_t, std::size_t begin, std::size_t end) {
            kernels::external_forces_range(c, integ, wind, begin, end);
        });
        for_each_block<Parallel>(cloth_, [&](std::size_t b, std::size_t begin, std::size_t end) {
            kernels::integrate_range(c, integ, begin, end, b);
        });
    }
}

template <bool Parallel> void Simulation::step_impl(std::size_t count) {
    if (grabbed_ != SIZE_MAX && grab_target_ != grab_applied_) {
        // The user moved the grab: its speed enters the monitor's speed bound, and the work it did its energy
        // balance (restarted below, after the grabbed particle has moved).
        const float dx = grab_target_[0] - grab_applied_[0], dy = grab_target_[1] - grab_applied_[1],
                    dz = grab_target_[2] - grab_applied_[2];
        if (count > 0) monitor_.note_user_speed(std::sqrt(dx * dx + dy * dy + dz * dz) / (float(count) * params_.dt));
        grab_applied_ = grab_target_;
        rebaseline_ = true;
    }
    apply_user_constraints();
    if (rebaseline_) { // pins, grabs or constants changed
        update_limit_levels();
        monitor_.rebaseline<Parallel>(cloth_, params_, cur(), steps_done_);
        rebaseline_ = false;
        strain_retry_failed_ = false; // a limit that could not hold may hold with the new pins or constants
    }
    const bool implicit = params_.solver == Solver::implicit;
    // An implicit step is a whole frame's worth of substeps: the monitor looks after every few.
    const std::size_t check_every = implicit ? 8 : HealthMonitor::check_every;
    // Contact sub-steps (docs/self_collision.md): an implicit step in which cloth touches cloth (the self-collision
    // stage pushed) is dropped and solved again from its start as `substeps` shorter steps.
    const bool sub = implicit && params_.self_collision.thickness > 0.0f && params_.self_collision.substeps > 1;
    // The strain retry (strain_retry_substeps) is off while self-collision is on: with it, the one step of the shirt
    // it split while settling (its limit, pressed on the body, cannot hold: no retry after that) sent the push of
    // its front into its back (tests/test_self_collision.cpp) along another path, which crossed the back at 11
    // triangle pairs; splitting the contact sub-steps as well left 1 (docs/implicit.md, "Steps the strain limit cannot
    // hold").
    const bool retry = implicit && !(params_.self_collision.thickness > 0.0f);
    for (std::size_t n = 0; n < count; ++n) {
        if (sewing_) update_sewing();
        step_time_ = double(steps_done_) * double(params_.dt);
        if (step_pipeline<Parallel>(implicit, sub)) {
            implicit_substeps<Parallel>(params_.self_collision.substeps, true, 0);
            ++sc_substepped_;
        } else if (retry && limit_over_ && !strain_retry_failed_) { // the limit could not hold it: shorter steps
            implicit_substeps<Parallel>(strain_retry_substeps, false, 0);
            ++strain_substepped_;
            strain_retry_failed_ = limit_over_;
        } else {
            if (!limit_over_) strain_retry_failed_ = false;
            current_ = 1 - current_;
        }
        ++steps_done_;
        // Also after steps 1, 2, 4, ... below check_every: a start that flings the cloth (placed inside a collider,
        // seams far off their rest) shows in the first steps, before the bounds grow with the distance it moves. An
        // adversarial sweep's cloth inside a sphere, pushed out at 28 m/s by the implicit solver, stopped when run for
        // 1-4 steps and ran "healthy" for 7 or more (the first check was at step 8).
        if (steps_done_ % check_every == 0 || (steps_done_ < check_every && (steps_done_ & (steps_done_ - 1)) == 0))
            check_health<Parallel>();
    }
}

template <bool Parallel> bool Simulation::step_pipeline(bool implicit, bool attempt) {
    if (implicit)
        implicit_step<Parallel>();
    else
        explicit_substep<Parallel>();
    check_blocks(steps_done_);
    // Strain limiting and collisions: when limiting is due, each sweep is followed by a collide (both honoured: a point
    // a collider moved is limited again, and collide runs last); otherwise collide alone.
    StateBuffer& out = buffers_[1 - current_];
    const bool collide = !params_.colliders.empty();
    if (!strain_limit_stage<Parallel>(out, collide) && collide) collide_stage<Parallel>(out);
    if (!(params_.self_collision.thickness > 0.0f)) return false;
    self_collide_stage<Parallel>(out, false, attempt);
    if (attempt && sc_pushed_) return true; // dropped: solved again in sub-steps
    // Implicit: the contacts the pass pushed apart become planes the step is solved again with, then the pass checks
    // the result (implicit_contact_resolve).
    if (implicit && sc_pushed_) {
        implicit_contact_resolve<Parallel>();
        check_blocks(steps_done_);
        if (!strain_limit_stage<Parallel>(out, collide) && collide) collide_stage<Parallel>(out);
        self_collide_stage<Parallel>(out, true);
    }
    return false;
}

template <bool Parallel>
void Simulation::implicit_substeps(std::uint32_t substeps, bool self_contact, std::uint32_t depth) {
    // params_.dt is the sub-step's length while they run (every stage reads it), and params_.implicit.multilevel is
    // chosen per sub-step (below); both are the step's again after, also when a sub-step throws.
    struct Restore {
        float& dt;
        float frame;
        bool& multilevel;
        bool frame_multilevel;
        ~Restore() { dt = frame, multilevel = frame_multilevel; }
    } restore{params_.dt, params_.dt, params_.implicit.multilevel, params_.implicit.multilevel};
    // No sub-step below the implicit solver's shortest step (its motion would be lost to rounding).
    const std::uint32_t k = std::max<std::uint32_t>(
        1, std::min<std::uint32_t>(substeps, static_cast<std::uint32_t>(restore.frame / implicit_min_dt)));
    const double start = step_time_;
    params_.dt = restore.frame / float(k);
    // The sub-steps run at the frame's sweeps, and single level while the cloth is crowded against itself: when the
    // stage's last run found contacts at more than crowded_contact_share of the particles. The coarse levels cannot
    // represent a cloth lying in pleats on itself and fling it: once friction no longer held it (2026-12-02), the
    // implicit crumpled pile with multilevel sub-steps at half the frame's sweeps (as until then) ended 1 s at 5.5 J,
    // 14.6 m/s, strain 0.70 (at friction 0 before the fix the same: 0.71 J, 6.5 m/s, 0.57), and at the frame's sweeps
    // at 0.83 J, 7.0 m/s. Single level always made a hang that touches itself here and there sag and flap (N = 100,
    // 2 s: strain 0.71, 162 s wall, against 0.066 and 6.9 s), where the single-level solve does not converge. Measured
    // contacts per step: the N = 100 hang 0-10 of 10,000 particles; the pile 30-1,676 of 4,096 (docs/self_collision.md,
    // "Contact sub-steps").
    for (std::uint32_t j = 0; j < k; ++j) {
        step_time_ = start + double(j) * double(params_.dt);
        // The first sub-step asks the last sub-stepped step's end (the frame-long attempt only probed for one contact);
        // with none before it, it counts as crowded (the pile's impact, its first contact, flung by a multilevel first
        // sub-step: 12 intersecting pairs, strain 0.66).
        const bool crowded =
            !self_contact ? false
            : j == 0      ? sc_substepped_ == 0 ||
                         double(sc_substep_contacts_) > crowded_contact_share * double(cloth_.particle_count)
                   : double(sc_contacts_) > crowded_contact_share * double(cloth_.particle_count);
        params_.implicit.multilevel = restore.frame_multilevel && !crowded;
        step_pipeline<Parallel>(true, false);
        if (!self_contact && limit_over_ && depth + 1 < strain_retry_depth && k > 1)
            implicit_substeps<Parallel>(strain_retry_substeps, false, depth + 1); // this sub-step, split again
        else
            current_ = 1 - current_;
    }
    if (self_contact) sc_substep_contacts_ = sc_contacts_;
}

/// The health monitor's check (health_monitor.hpp): on an explosion, back to the last check that passed and throw.
template <bool Parallel> void Simulation::check_health() {
    std::string problem = monitor_.check<Parallel>(cloth_, params_, cur(), steps_done_);
    if (problem.empty()) return;
    steps_done_ = monitor_.restore(cur(), cloth_.particle_count);
    throw BlowUpError(problem);
}

void Simulation::step(std::size_t count) { step_impl<true>(count); }
void Simulation::check_health_now() { check_health<true>(); }
void Simulation::step_serial(std::size_t count) { step_impl<false>(count); }

void Simulation::run_stage(Stage stage) {
    if (stage == Stage::aero_forces) return params_.aero.enabled ? aero_forces_stage<true>() : void();
    if (stage == Stage::seam_forces) return cloth_.seams.empty() ? void() : seam_forces_stage<true>();
    if (stage == Stage::strain_limit) return void(strain_limit_stage<true>(cur(), false));
    if (stage == Stage::collide) return collide_stage<true>(cur());
    if (stage == Stage::self_collide)
        return params_.self_collision.thickness > 0.0f ? self_collide_stage<true>(cur()) : void();
    const kernels::StepContext c = make_context(steps_done_);
    const Integrator integ = params_.integrator;
    for_each_block<true>(cloth_, [&](std::size_t b, std::size_t begin, std::size_t end) {
        switch (stage) {
        case Stage::external_forces: kernels::external_forces_range(c, integ, params_.wind.enabled, begin, end); break;
        case Stage::spring_forces:
            kernels::spring_forces_range(c, integ, kernel_, extra_forces(), begin, end);
            break;
        case Stage::integrate: kernels::integrate_range(c, integ, begin, end, b); break;
        default: break;
        }
    });
}

/// After a substep: if a block wrote a non-finite value, find the first such particle and stop with an error.
/// The failed substep's output buffer is discarded, so the state stays at the last finite step.
void Simulation::check_blocks(std::size_t step_index) {
    for (std::size_t b = 0; b < block_ok_.size(); ++b) {
        if (block_ok_[b]) continue;
        const StateBuffer& out = buffers_[1 - current_];
        const std::size_t begin = b * block_particles;
        const std::size_t end = std::min(begin + block_particles, cloth_.particle_count);
        for (std::size_t i = begin; i < end; ++i) {
            const float vals[6] = {out.x[i], out.y[i], out.z[i], out.u[i], out.v[i], out.w[i]};
            for (float v : vals)
                if (!std::isfinite(v))
                    throw SimulationError("non-finite state at substep " + std::to_string(step_index + 1) +
                                          " (t = " + std::to_string(step_time_ + double(params_.dt)) +
                                          " s), particle " + std::to_string(i) +
                                          ": the step is unstable; lower dt or stiffness");
        }
        throw SimulationError("non-finite state at substep " + std::to_string(step_index + 1) + " in block " +
                              std::to_string(b));
    }
}

} // namespace drape
