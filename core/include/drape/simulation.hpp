// The simulation: hot state plus the substep pipeline over it.
//
// One substep (DESIGN.md), each stage a function over spans of the SoA arrays, in core/src/<stage>.cpp:
//   1. external_forces  gravity, air drag, analytic wind field
//   2. spring_forces    Hooke springs and spring damping, CSR gather (or the regular-grid stencil); in the fabric
//                       model also the bending forces -Q (x + beta v) (bending.hpp)
//   3. integrate        symplectic Euler or position Verlet; pins (inverse mass 0) never move
// Stages 1-3 are fused into one pass over memory (core/src/substep.cpp); the staged form runs each stage as its own
// pass and serves as the reference and for per-stage benchmarks. State is double-buffered: a substep reads buffer
// A and writes buffer B, so every particle sees its neighbours' state of the same instant whatever the order of
// blocks and threads - results are bitwise identical for any thread count.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "drape/cloth.hpp"
#include "drape/colliders.hpp"
#include "drape/colouring.hpp"
#include "drape/errors.hpp"
#include "drape/health_monitor.hpp"
#include "drape/implicit.hpp"

namespace drape {

namespace kernels {
struct StepContext;
}
struct ImplicitSolver;

enum class Integrator : std::uint8_t {
    symplectic_euler, ///< v' = v + a dt, x' = x + v' dt (001 eqs 9-10)
    verlet,           ///< x' = 2x - x_prev + a dt^2 (000 eq 1.12, without the listing's spurious 1/2)
};
const char* integrator_name(Integrator integrator) noexcept;

/// Which spring kernel runs: the regular-grid stencil (contiguous loads) or the general sliced CSR (gathers).
enum class KernelPath : std::uint8_t { automatic, grid, csr };
const char* kernel_path_name(KernelPath path) noexcept;

/// Seed 000's analytic wind (listing 3.3) as an acceleration field, m/s^2:
///   a = strength * (sin(10 t), 0, |sin(z + 10 t)|).
/// The seed's y component is illegible in the source; drape uses 0 (horizontal wind).
struct WindField {
    bool enabled = false;
    float strength = 2.0f; ///< m/s^2, 0..100
};

/// A spring counts as held by the strain limit up to (1 + strain_limit_tolerance ratio) l0: the limit's sweeps stop
/// there (strain_limit.cpp), and the viewer and `drape run` do not call a strain within it the sweeps' error.
inline constexpr float strain_limit_tolerance = 1.05f;
/// At least `passes` sweeps run; more, up to strain_limit_max_passes, while a sweep still finds a spring longer than
/// (1 + strain_limit_tolerance ratio) l0, so a limit that can hold does (within the 10 % that `drape run` calls
/// honoured).
inline constexpr std::uint32_t strain_limit_max_passes = 100;
/// The implicit solver's form of the limit moves only the end of a spring farther from the fixed particles, for this
/// many sweeps of a step; later sweeps (the step's limit not yet held) move both ends by inverse mass. Where the
/// levels from two clips meet (the middle of the wool hang's bottom edge) each side is pulled towards its own clip
/// and the one-sided corrections cannot shorten the spring between them: at N = 100 that spring stayed at 0.111 with
/// the limit at 0.095 through 100 sweeps; with the switch at 30 or 60 sweeps the whole run kept within 0.098 at
/// N = 100, 0.099 at N = 200, 316 and 1000 (docs/implicit.md, "Compression next to the clips").
inline constexpr std::uint32_t strain_limit_one_sided_passes = 50;
/// An implicit step after whose strain limiting a spring is still longer than (1 + strain_limit_tolerance ratio) l0
/// (its sweeps left a stretch the limit's strain_limit_max_passes could not take out) is dropped and solved again from its start as this
/// many sub-steps of dt / strain_retry_substeps; a sub-step that again ends over the limit is split the same way, down
/// to strain_retry_depth levels (dt / 27 at the default: 1/810 s for a 1/30 s step), never below implicit_min_dt. The
/// wool dropped on the sphere at N >= 92 (10 mm cells and finer) with frame-long steps stretched its cap's rim past the
/// limit in the steps after it landed (0.12, 0.23, 0.42, 0.67 at N = 128: the health monitor stopped the run at
/// 0.53 s); one level of 3 held N = 100 but not 128, two levels N = 128 and 200 but not 256 (docs/implicit.md, "Steps
/// the strain limit cannot hold"). When a step's sub-steps still end over the limit, later steps are not solved again
/// until one ends within it (a limit no step can hold would otherwise cost every step up to 40 solves). Only while
/// self-collision is off (core/src/substep.cpp, step_impl: with it on, the shirt's push crossed itself).
inline constexpr std::uint32_t strain_retry_substeps = 3;
inline constexpr std::uint32_t strain_retry_depth = 3;
/// Provot strain limiting (seed 001 section 2; Provot 1995): after each substep, every structural, shear and seam
/// spring longer than (1 + ratio) l0 has its ends moved toward each other by inverse mass, colour group by colour
/// group, `passes` times or more (above). Groups are ordered outward from the cloth's authored pins (core/src/strain_limit.cpp), so one pass carries
/// the correction from the pins to the free edge.
struct StrainLimit {
    float ratio = 0.0f;         ///< critical stretch, 0 = off, 0..10 (0.1 = 10%)
    std::uint32_t passes = 4;   ///< least sweeps over all groups each time it runs, 1..100
    std::uint32_t every = 1;    ///< runs after every `every`-th substep, 1..1000 (1 = Provot: after each step)
};

/// Aerodynamic wind per triangle (seed 004 section 2.1.2): with v_rel = (mean velocity of the triangle's three
/// particles) - wind velocity, n the unit normal and A the area,
///   F = -1/2 rho C_d A |v_rel| (v_rel . n) n,
/// shared equally by the three particles (each particle gets the mean of its triangles' shares, gathered, not
/// scattered). Quadratic in speed like any drag; proportional to density, drag coefficient, area and the normal
/// component of the relative velocity, as the seed states (its formula (4) is lost from the source text).
struct AeroWind {
    bool enabled = false;
    float density = 1.2f;                        ///< rho, kg/m^3, 0..100
    float drag_coefficient = 1.0f;               ///< C_d, 0..10
    std::array<float, 3> velocity{0.0f, 0.0f, 5.0f}; ///< wind velocity, m/s, |each| <= 100
};

/// Self-collision (cloth against cloth, docs/self_collision.md; core/src/self_collide.cpp): every particle is kept at
/// least `thickness` from every triangle not containing it, and every edge from every edge sharing no vertex with
/// it, on the side it was on at the start of the step; approaching normal velocity is removed and Coulomb friction
/// applied. Runs after the collide stage, both solvers.
struct SelfCollision {
    float thickness = 0.0f; ///< m, 0 = off, else [0.0005, 0.05]
    float friction = 0.3f;  ///< Coulomb coefficient, [0, 2]
    /// Implicit solver only: a step in which cloth touches cloth (the stage pushed) is solved again from its start as
    /// this many sub-steps of dt / substeps (docs/self_collision.md, "Contact sub-steps"). [1, 16]; 1 = never.
    std::uint32_t substeps = 4;
};
inline constexpr std::uint32_t self_collision_max_substeps = 16;
/// A contact sub-step runs single level (no multilevel guess) when the self-collision stage's last run found contacts
/// at more than this share of the particles: a cloth crowded against itself (a crumpled pile), which the coarse levels
/// cannot represent (core/src/substep.cpp, implicit_substeps).
inline constexpr double crowded_contact_share = 0.005;
inline constexpr float self_collision_min_thickness = 0.0005f;
inline constexpr float self_collision_max_thickness = 0.05f;

struct SimulationParams {
    /// s: one explicit substep, which must be below the explicit stability bound (stability.hpp), or one implicit
    /// step (any length up to 0.1 s, typically a frame).
    float dt = 0.0f;
    Solver solver = Solver::explicit_euler;
    Integrator integrator = Integrator::symplectic_euler; ///< explicit solver only (implicit: symplectic_euler)
    ImplicitParams implicit;                              ///< implicit solver only
    std::array<float, 3> gravity{0.0f, -9.81f, 0.0f}; ///< m/s^2
    float air_drag = 0.2f;                            ///< 1/s: F = -m kr v (001 eq 4), 0..100
    WindField wind;
    AeroWind aero;
    KernelPath kernel = KernelPath::automatic;
    bool fused = true; ///< false runs each stage as its own pass (reference / per-stage profiling)
    StrainLimit strain_limit;
    /// Sewing, m/s (0..10; 0 = off): seams (SpringKind::seam) that start longer than their rest length are pulled
    /// shut at this speed instead of all at once (and seams that start shorter are let out to it). A seam's rest
    /// length starts at its length in the initial state and moves by sewing_speed x dt each step to its own rest
    /// length (Edge::rest); seam forces, strain limiting, the
    /// implicit solver and the health figures all use that current rest length. While a seam is still closing the
    /// cloth feels no gravity: the garment is sewn where it was placed (around a body), then dropped onto it. On by
    /// default (0.5 m/s, the T-shirt's), so every seam that starts open is sewn: snapped shut, even a seam 5 mm open
    /// on a canvas bag flung its particles at 182 m/s in the first substep. Off (0), every seam must start closed
    /// (within unsewn_gap_ratio of the cloth's spacing; Simulation refuses the cloth otherwise).
    float sewing_speed = 0.5f;
    /// Without sewing, a seam may start at most this many times the cloth's spacing (cloth_spacing: its mean
    /// structural spring) longer than its rest length: it snaps shut in the first substep (strain limiting or the seam
    /// spring close it at once), so its particles move at about gap / dt. On the canvas bag (2 cm spacing, explicit
    /// dt 3.3e-5 s) a gap of 0.1 / 0.2 / 5 mm flung them at 3.7 / 7.3 / 182 m/s; at this bound, 0.02 mm, 0.7 m/s.
    static constexpr float unsewn_gap_ratio = 0.001f;
    /// A saved state's seam_rest (sewing in progress) lies within this many times the cloth's spacing of its seam's
    /// length: the cloth lags its schedule by a few millimetres; shorter would snap the seam shut, longer push the
    /// panels apart (a saved seam_rest of 100 m was taken before this check).
    static constexpr float saved_seam_rest_ratio = 1.5f;
    /// Analytic colliders, positions relative to Cloth::origin; applied in order after strain limiting.
    std::vector<Collider> colliders;
    SelfCollision self_collision; ///< off by default (thickness 0)
};

/// The Chebyshev rho the cloth's own implicit sweeps run with: chebyshev_rho_for, none with colliders (vbd.cpp).
inline float chebyshev_rho_used(const SimulationParams& p) {
    return p.colliders.empty() ? chebyshev_rho_for(p.implicit) : 0.0f;
}

/// Hot state: one buffer of the double-buffered SoA arrays. u, v, w hold velocities (symplectic Euler) or the
/// previous positions (Verlet).
struct StateBuffer {
    AlignedArray<float> x, y, z, u, v, w;
};

/// Health figures computed on request (not per substep). The health monitor's own figures and bounds, from its last
/// check (every HealthMonitor::check_every substeps), are in `monitor`.
struct Health {
    float max_structural_strain = 0.0f; ///< max |l - l0| / l0 over structural springs
    double kinetic_energy = 0.0;        ///< J
    bool finite = true;
    float max_speed = 0.0f;             ///< m/s, the fastest particle
    /// Largest stretch (l - l0) / l0 over the springs strain limiting acts on (structural, seam; shear with the explicit
    /// solver only), leaving out springs between two fixed particles (nothing can move them); 0 without them.
    float max_limited_stretch = 0.0f;
    HealthFigures monitor;              ///< the monitor's last check: figures, bounds, healthy
};

/// Self-collision's patches (core/src/self_collide_patches.cpp), cooked once: compact connected pieces of the cloth's
/// triangles, each with the particles and edges it owns and the patches it touches (all CSR: entries of patch p lie
/// in [start[p], start[p + 1])). Patches past the last one with triangles hold particles in no triangle.
struct SelfCollisionPatches {
    std::vector<std::uint32_t> tri_start, tris;     ///< triangles
    std::vector<std::uint32_t> point_start, points; ///< particles (each in exactly one patch)
    std::vector<std::uint32_t> edge_start, edges;   ///< edges, as indices into the stage's edge list (each in one)
    std::vector<std::uint32_t> adj_start, adj;      ///< patches sharing a particle with it, ascending, not itself
    std::vector<std::uint8_t> on_border;            ///< 1: a triangle of it has an edge no other triangle has
    std::size_t count() const noexcept { return point_start.empty() ? 0 : point_start.size() - 1; }
};

/// Per-stage names in step order; the same strings label bench counters and profiler zones.
enum class Stage : std::uint8_t { aero_forces, seam_forces, external_forces, spring_forces, integrate, strain_limit, collide, self_collide, count };
const char* stage_name(Stage stage) noexcept;

class Simulation {
  public:
    /// Validates every parameter and the time step against the stability bound; throws InvalidInput naming the
    /// parameter and the allowed range. Allocates all state and scratch here, never in step().
    Simulation(Cloth cloth, const InitialState& initial, const SimulationParams& params);
    ~Simulation();
    Simulation(Simulation&&) noexcept;
    Simulation& operator=(Simulation&&) noexcept;

    /// Advances `count` steps of params().dt: explicit substeps, or implicit steps (params().solver). Parallel over fixed particle blocks with oneTBB (the thread
    /// count is the caller's: call it inside drape::Workers::run, workers.hpp). Throws SimulationError naming
    /// the step and the particle if any value becomes non-finite; the state is then left at the last finite
    /// step. Every HealthMonitor::check_every substeps (counted from 0, whatever `count` is) the health monitor
    /// checks the state; an explosion throws BlowUpError (a SimulationError) and leaves the state at the last
    /// check that passed.
    void step(std::size_t count = 1);

    /// Same as step() but runs every stage serially on the calling thread (the "serial twin" of the parallel path).
    void step_serial(std::size_t count = 1);
    /// The health monitor's check of the state as it is now (step() checks only every few steps, so a run's last
    /// steps may not have been checked): throws BlowUpError, the state back at the last check that passed, as step().
    void check_health_now();

    const Cloth& cloth() const noexcept { return cloth_; }
    const SimulationParams& params() const noexcept { return params_; }
    KernelPath kernel() const noexcept { return kernel_; }
    std::size_t steps_done() const noexcept { return steps_done_; }
    double time() const noexcept { return static_cast<double>(steps_done_) * params_.dt; }
    /// Seams' current rest lengths (SeamSet order) while any is still being sewn; empty once all are closed.
    std::span<const float> seams_being_sewn() const noexcept {
        return sewing_ ? std::span<const float>(seam_rest_) : std::span<const float>();
    }

    /// Self-collision's snapshot of its last run (x, y, z relative to the origin) while it is on and has one; empty
    /// spans otherwise (InitialState::snapshot_x).
    std::array<std::span<const float>, 3> self_collision_snapshot() const noexcept {
        if (params_.self_collision.thickness <= 0.0f || sc_snap_step_ == SIZE_MAX || sc_snap_step_ > steps_done_)
            return {};
        return {std::span<const float>(sc_snap_x_), std::span<const float>(sc_snap_y_), std::span<const float>(sc_snap_z_)};
    }
    /// The contact planes the explicit solver holds the particles of the snapshot's run on (InitialState::sc_planes);
    /// empty when there is no snapshot or that run pushed nothing.
    SelfCollisionPlanes self_collision_planes() const;

    /// The frame's origin (world coordinates, m): positions, colliders and grab targets are relative to it
    /// (Cloth::origin).
    const std::array<double, 3>& origin() const noexcept { return cloth_.origin; }
    /// Current positions relative to origin(), m (particle_count entries each).
    std::span<const float> x() const noexcept { return {cur().x.data(), cloth_.particle_count}; }
    std::span<const float> y() const noexcept { return {cur().y.data(), cloth_.particle_count}; }
    std::span<const float> z() const noexcept { return {cur().z.data(), cloth_.particle_count}; }
    /// Velocity of particle i, m/s (for Verlet: (x - x_prev) / dt).
    std::array<float, 3> velocity(std::size_t i) const noexcept;
    /// Names of the stages a substep runs, e.g. {"external_forces", "spring_forces", "integrate"}.
    std::vector<std::string> stage_names() const;

    Health health() const;
    /// Colour groups used by strain limiting, in processing order (empty until strain limiting is first enabled).
    const ColourGroups& strain_limit_groups() const noexcept { return limit_groups_; }
    /// Whether group g is an overflow group (run serially; its springs may share particles).
    bool strain_limit_group_serial(std::size_t g) const noexcept { return limit_serial_[g] != 0; }
    /// 64-bit FNV-1a hash of the position bits (x, y, z of particle 0, then particle 1, ...).
    std::uint64_t checksum() const noexcept;

    /// Changes one spring kind's material; throws InvalidInput if it would make params().dt unstable.
    void set_material(SpringKind kind, SpringMaterial material);
    /// Sets the time step and other run parameters; throws InvalidInput when out of range or unstable.
    void set_params(const SimulationParams& params);

    // Constraints from the user (stage 7 of DESIGN.md; applied at the start of each step() call).
    /// Pins (inverse mass 0, velocity 0) or unpins (its mass restored; authored pins too, when the cloth knows their
    /// mass: Cloth::free_inv_mass) particle i. Throws InvalidInput if i is out of range.
    /// (User actions - pins, grabs, set_params, set_material - restart the health monitor's energy balance.)
    void set_pinned(std::size_t i, bool pinned);
    bool is_pinned(std::size_t i) const noexcept { return cloth_.inv_mass[i] == 0.0f; }
    /// Grabs particle i: it becomes kinematic and is moved to `target` (m, relative to origin()) at the start
    /// of every step() call until release_grab(). Grabbing another particle releases the previous one. A
    /// grabbed particle that was pinned stays pinned when released.
    void grab(std::size_t i, std::array<float, 3> target);
    void move_grab(std::array<float, 3> target) noexcept { grab_target_ = target; }
    void release_grab() noexcept;
    /// The grabbed particle, or SIZE_MAX.
    std::size_t grabbed() const noexcept { return grabbed_; }

    /// Figures of the last implicit step (iterations, residual); zeros before the first.
    const ImplicitStats& implicit_stats() const noexcept { return implicit_stats_; }
    /// Levels the implicit solver solves per step: 1 + the coarse levels of its multilevel guess (only square grid and
    /// outline cloths of the fabric model have them); 0 while the implicit solver is not cooked.
    std::uint32_t implicit_levels() const noexcept;
    /// Per level the implicit solver solves (implicit_levels() of them: the cloth first, then the coarse levels finer
    /// first), its particles and the sweeps it runs per step at most; empty while the implicit solver is not cooked.
    std::vector<ImplicitLevelPlan> implicit_level_plan() const;
    /// Self-collision contacts applied in the first round of the stage's last run: point-triangle and edge-edge pairs closer
    /// than the thickness, less those already held at it (within 1%) and not approaching; 0 when self-collision is off.
    std::size_t self_contacts() const noexcept { return sc_contacts_; }
    /// Steps (and contact sub-steps) in which the self-collision stage ran since construction (it skips a step in which no particle has moved
    /// a quarter of the thickness since its last run).
    std::size_t self_collision_runs() const noexcept { return sc_runs_; }
    /// Parts the stage's last run cut the motion since its previous run into (1 unless a particle moved more than half
    /// the thickness: then each part moves none more than that, up to 32 parts; docs/self_collision.md).
    std::size_t self_collision_parts() const noexcept { return sc_parts_; }
    /// Implicit steps solved again as SelfCollision::substeps sub-steps because cloth touched cloth in them
    /// (docs/self_collision.md, "Contact sub-steps").
    std::size_t self_collision_substepped() const noexcept { return sc_substepped_; }
    /// Implicit steps in which self-collision pushed particles apart and the step was solved again with them held on
    /// their contact planes, since construction (docs/self_collision.md, "Inside the implicit solve").
    std::size_t self_collision_resolves() const noexcept { return sc_resolves_; }
    /// Implicit steps solved again as strain_retry_substeps sub-steps because their strain limiting could not hold the
    /// limit, since construction.
    std::size_t strain_substepped() const noexcept { return strain_substepped_; }
    /// For tests: when on, the self-collision stage tests every pair of the cloth (point-triangle and edge-edge, no
    /// patches, no culling): the reference its broad phase is checked against. O(n^2): small cloths only.
    void set_self_collision_reference(bool on) noexcept { sc_reference_ = on; }
    /// The implicit solver's cooked data of the cloth itself (empty until the implicit solver is first chosen).
    const VbdGraph& vbd_graph() const noexcept;

    /// Direct access for tests and benchmarks (current buffer and the cooked data).
    const StateBuffer& state() const noexcept { return cur(); }

    /// Staged-pipeline scratch after run_stage(): spring force (N) and external acceleration (m/s^2) per particle.
    struct StageOutput {
        std::span<const float> fx, fy, fz, ax, ay, az;
    };
    StageOutput stage_output() const noexcept {
        const std::size_t n = cloth_.particle_count;
        return {{fx_.data(), n}, {fy_.data(), n}, {fz_.data(), n}, {ax_.data(), n}, {ay_.data(), n}, {az_.data(), n}};
    }

    /// Runs one named stage alone over every block (per-stage benchmarks). The stages read/write scratch arrays;
    /// the state is not advanced.
    void run_stage(Stage stage);

  private:
    template <bool Parallel> void step_impl(std::size_t count);
    /// One explicit substep from buffer A into buffer B (substep.cpp).
    template <bool Parallel> void explicit_substep();
    /// One implicit step from buffer A into buffer B (implicit_step.cpp).
    template <bool Parallel> void implicit_step();
    /// Cooks the implicit solver's graph and scratch (when first chosen).
    void cook_implicit();
    template <bool Parallel> bool multilevel_guess();
    template <bool Parallel> bool fas_at_rest();
    /// The root mean square speed of the current state over all particles (fixed ones count as still), m/s.
    template <bool Parallel> double rms_speed();
    /// The implicit step's contact re-solve: the step's sweeps again from where self-collision left the cloth, each
    /// pushed particle held on its side of its contact plane, then the velocities (implicit_step.cpp).
    template <bool Parallel> void implicit_contact_resolve();
    /// v = (x - x^n) / h into buffer B, without the inward normal velocity of a collider contact; finite check.
    template <bool Parallel> void implicit_velocities();
    std::unique_ptr<ImplicitSolver> implicit_; ///< cooked when the implicit solver is first chosen (implicit_solver.hpp)
    ImplicitStats implicit_stats_;
    kernels::StepContext make_context(std::size_t step_index);
    KernelPath resolve_params(const SimulationParams& params) const;
    void check_blocks(std::size_t step_index);
    StateBuffer& cur() noexcept { return buffers_[current_]; }
    const StateBuffer& cur() const noexcept { return buffers_[current_]; }

    Cloth cloth_;
    SimulationParams params_;
    KernelPath kernel_ = KernelPath::csr;
    std::array<StateBuffer, 2> buffers_;
    int current_ = 0;
    std::size_t steps_done_ = 0;
    /// No implicit step since construction, a new solver, dt or integrator, a particle let go or a collider taken away
    /// (implicit_step.cpp's first-step guess).
    bool implicit_fresh_ = true;
    // Scratch for the staged pipeline: spring force (N) and external acceleration (m/s^2), sized at construction.
    AlignedArray<float> fx_, fy_, fz_, ax_, ay_, az_;
    std::vector<std::uint8_t> block_ok_; ///< per block: 1 when every value the block wrote is finite
    std::vector<float> inv_mass_authored_; ///< inverse masses as cooked (0 = an authored pin)
    std::vector<float> inv_mass_free_;     ///< inverse masses when unpinned (Cloth::free_inv_mass)
    // Strain limiting (cooked when first enabled): colour groups over structural, shear and seam springs, with the
    // spring ends and rest lengths copied in group order for linear sweeps.
    ColourGroups limit_groups_;
    std::vector<std::uint8_t> limit_serial_; ///< per group: 1 = overflow group, run serially
    /// Per group, where its shear springs begin (each group holds its other springs first): the frame form, which
    /// limits no shear spring, runs only the part before.
    std::vector<std::uint32_t> limit_shear_begin_;
    /// Which sweeps may skip a group (strain_limit_sweep.hpp): per particle the groups holding one of its springs
    /// (CSR), per group the sequence number of the last correction that moved one of its particles, and the running
    /// sequence number (one per group visited).
    std::vector<std::uint32_t> limit_particle_group_offsets_, limit_particle_groups_;
    std::vector<std::uint64_t> limit_group_moved_;
    /// The implicit solver's form: the positions before the stage, whose moves decide the velocities a limit that
    /// could not hold keeps (strain_limit_stage).
    std::vector<float> limit_px_, limit_py_, limit_pz_;
    std::uint64_t limit_seq_ = 0;
    std::vector<std::uint32_t> limit_a_, limit_b_;
    /// The strain limit's form for frame-long steps (the implicit solver, a grab held or not; strain_limit.cpp) and the springs
    /// it acts on: structural and seam springs always, shear springs only in the explicit solver's form. The limit
    /// and the health figures (max_limited_stretch) both ask here.
    bool strain_limit_frame_form() const noexcept { return params_.solver == Solver::implicit; }
    bool strain_limited(SpringKind kind) const noexcept {
        return kind != SpringKind::bend && (kind != SpringKind::shear || !strain_limit_frame_form());
    }
    /// Per limited spring, flags for the implicit solver's limit (core/src/strain_limit.cpp): which end is nearer the
    /// fixed particles (it moves only the far end), and whether it is a shear spring (not limited there).
    std::vector<std::uint8_t> limit_inner_;
    /// A mirror-exact cloth (Cloth::mirror): per limited spring strain_limit::pair_first / pair_second for the two
    /// springs meeting at a particle on the mirror line, solved together; empty on other cloths.
    std::vector<std::uint8_t> limit_pair_;
    /// The limited springs' adjacency, and breadth-first levels and queue (cooked once; update_limit_levels).
    std::vector<std::uint32_t> limit_adj_offsets_, limit_adj_, limit_level_, limit_queue_;
    std::vector<float> limit_rest_;
    void cook_strain_limit();
    /// limit_level_: springs away from the nearest particle with inverse mass 0 in `inv_mass`. No allocation.
    void limit_levels(const float* inv_mass) noexcept;
    /// Refreshes limit_inner_'s ends from the particles fixed now (after a pin, a grab or its release). No allocation.
    void update_limit_levels() noexcept;
    // Sewing (SimulationParams::sewing_speed, sewing.cpp): per seam, in SeamSet order, its current rest length; per
    // edge, the current rest length (Edge::rest except seams being sewn). Empty without seams. update_sewing() runs
    // before each substep or implicit step while a seam is still longer than its rest.
    std::vector<float> seam_rest_, edge_rest_;
    std::vector<std::uint32_t> limit_seam_slot_, limit_seam_edge_; ///< seams in limit_rest_: slot, edge index
    bool sewing_ = false;
    /// Gravity as the step feels it: none while seams are being sewn (the garment is sewn in place, then dropped).
    std::array<float, 3> gravity_now() const noexcept {
        return sewing_ ? std::array<float, 3>{0.0f, 0.0f, 0.0f} : params_.gravity;
    }
    void cook_sewing(const InitialState& initial);
    void refuse_seams_held_apart(const InitialState& initial) const;
    void refuse_seams_off_schedule(const float* x, const float* y, const float* z,
                                   std::span<const float> saved_rest) const;
    void refuse_overstretched_start(const InitialState& initial) const;
    void update_sewing();
    /// Runs strain limiting on `out` when it is due this substep (returns false when not); with `with_collide`, the
    /// collide stage runs after every sweep (limit and collide interleaved, collide last).
    template <bool Parallel> bool strain_limit_stage(StateBuffer& out, bool with_collide);
    /// The collide stage on `out`: its particle pass (unless `particles` is false), then `triangle_rounds` rounds of
    /// its triangle pass (strain limiting interleaves the stage with its sweeps, with one round each).
    template <bool Parallel> void collide_stage(StateBuffer& out, bool particles = true, int triangle_rounds = 2);
    /// The triangle pass of the collide stage (collide.cpp, triangle_contact.hpp): triangles whose inside reaches
    /// into a collider are pushed out at their deepest point, in up to `rounds` rounds (stopping at a round with no
    /// contact); returns the number of contacts it applied (over the rounds).
    template <bool Parallel>
    std::size_t collide_triangles(float* x, float* y, float* z, float* vx, float* vy, float* vz, int rounds);
    /// Per triangle, what its contact asks of its vertices: vertex i of the triangle moves by k b_i w_i dq and its
    /// velocity changes by k b_i w_i dv (w = inverse mass, k = 1 / sum b_j^2 w_j), so the contact point moves by dq.
    struct TriangleResponse {
        float b[3], k, dq[3], dv[3];
    };
    std::vector<TriangleResponse> tri_response_;
    std::vector<std::uint8_t> tri_in_contact_;
    std::vector<float> clearance_; ///< per particle: a lower bound of its distance to the nearest non-plane collider
    std::vector<float> core_measure_; ///< per collider, per particle: core_measure (triangle_contact.hpp)
    void cook_triangle_contact();
    void cook_vertex_triangles();
    /// The implicit solver's triangle contact terms for this step (implicit_triangle_contact.cpp;
    /// vbd::TriangleTerms): found at positions x, y, z (the step's start, x^n); false when no triangle has one.
    template <bool Parallel> bool implicit_triangle_terms(const float* x, const float* y, const float* z);
    void cook_triangle_terms();
    std::vector<std::uint8_t> tt_on_;        ///< per triangle: it has a term
    std::vector<std::uint8_t> tt_vertex_on_; ///< per particle: one of its triangles has a term
    std::vector<float> tt_term_;         ///< per triangle: vbd::triangle_term_floats floats
    std::vector<Collider> tt_colliders_; ///< the colliders grown by the terms' search reach
    float tt_reach_ = 0.0f;              ///< that reach, m
    /// Per triangle: its last projection's ellipsoid parameter (ellipsoid_closest_point's warm start; 0 at each
    /// step's start); empty when a colour holds two corners of one triangle (two threads would share it).
    std::vector<float> tt_warm_;
    /// Per triangle: its kept tangent plane (vbd::TriangleTerms::plane; none at each step's start); empty with tt_warm_.
    std::vector<float> tt_plane_;
    bool tt_warm_checked_ = false;
    // Self-collision (self_collide.cpp; cooked when first enabled): the cloth's unique edges, its patches, per round
    // the boxes of every triangle and edge (in patch order), each patch's box and cone of normals and a spatial hash
    // of the patches (counting sort into buckets: sizes fixed at cooking, at most 8 cells per patch), and per particle
    // fixed-point accumulators of the pushes (integer sums are exact, so the result does not depend on the order in
    // which threads add).
    /// `again`: this step's second run (after the implicit contact re-solve): the motion it covers starts at the first
    /// run's end (its snapshot), where the pairs were pushed apart.
    /// `tentative`: the step is dropped if this run pushes (an implicit step about to be solved again in contact
    /// sub-steps), so it only probes: it stops at its first contact, pushing nothing (sc_pushed_ set), and keeps the
    /// previous snapshot: the sub-steps' first run covers the motion from there (a grab's jump included).
    /// `probe` (self_collide_round): stop at the first contact and push nothing; returns 1 if there was one.
    template <bool Parallel> void self_collide_stage(StateBuffer& out, bool again = false, bool tentative = false);
    template <bool Parallel>
    std::size_t self_collide_round(StateBuffer& out, const float* x0, const float* y0, const float* z0, bool& deep,
                                   bool probe);
    /// The largest displacement, over the motion from (xa, ya, za) to `out`, of one particle relative to another
    /// of a patch whose swept box meets its own patch's (self_collide.cpp): the run's parts keep it, or every
    /// particle's own motion (whichever needs fewer parts), under h / 2 a part.
    template <bool Parallel>
    float self_collide_relative_motion(const StateBuffer& out, const float* xa, const float* ya, const float* za);
    void cook_self_collision();
    /// 2 per edge, a < b; on a mirror-exact cloth an edge after its mirror image holds the twins of that one's ends,
    /// in the same order (so that the two take the same steps).
    std::vector<std::uint32_t> sc_edges_;
    /// A mirror-exact cloth (Cloth::mirror): each edge of sc_edges_'s mirror image; empty otherwise.
    std::vector<std::uint32_t> sc_edge_twin_;
    std::vector<std::uint32_t> sc_sewn_; ///< per particle: the lowest particle sewn to it through seams (itself if none)
    std::vector<std::uint32_t> sc_ring_start_, sc_ring_; ///< per particle: sc_sewn_ of its triangles' particles (CSR)
    /// The points of the garment that hold more than one particle (sewn together): their particles, ascending (CSR).
    std::vector<std::uint32_t> sc_group_start_, sc_group_;
    /// Per particle, for the contacts of a round: its inverse mass, or for a particle of such a point the inverse of
    /// the point's mass (0 when a particle of it is fixed). Filled per run; unused without sewn points.
    std::vector<float> sc_contact_w_;
    SelfCollisionPatches sc_patches_;
    std::uint32_t sc_patch_target_ = 0; ///< triangles per patch the patches were cooked for (0: none yet)
    float sc_mean_edge_ = 0.0f;         ///< m: mean rest length of the structural springs (sizes the patches)
    std::vector<std::uint32_t> sc_cell_count_, sc_cell_start_, sc_cell_items_; ///< bucket counts, starts, patches
    std::vector<float> sc_tri_box_, sc_edge_box_; ///< per triangle / edge in patch order: its grown box (lo, hi xyz)
    std::vector<float> sc_patch_box_;   ///< per patch: the box of its triangles' grown boxes and its particles +- h
    std::vector<float> sc_patch_cone_;  ///< per patch: unit axis (3), half-angle (rad; > pi: none), least altitude (m)
    std::vector<std::uint8_t> sc_patch_calm_; ///< per patch: it and the patches it touches lie flat (self_collide.cpp)
    // Per patch, over a run's motion: the box swept by its particles (grown by h / 2); the centre of its particles'
    // displacements (3) and their largest distance from it (1); the largest relative displacement with a patch whose
    // swept box meets it.
    std::vector<float> sc_patch_sweep_, sc_patch_motion_, sc_patch_relative_;
    bool sc_reference_ = false;         ///< set_self_collision_reference
    std::vector<std::int64_t> sc_acc_;  ///< per particle: dx, dy, dz, dvx, dvy, dvz (fixed point)
    std::vector<std::uint32_t> sc_hits_; ///< per particle: contacts that pushed it
    float sc_shortest_rest_ = 0.0f; ///< shortest rest length along a triangle edge (1-ring exemption), m
    std::size_t sc_contacts_ = 0;        ///< contacts applied in the last run's first round (self_contacts)
    std::size_t sc_substep_contacts_ = 0; ///< sc_contacts_ after the last contact sub-step (implicit_substeps)
    // The snapshot of the last run (positions after its pushes, and the step it ended): the stage runs again only once
    // some particle has moved more than a quarter of the thickness from it, and takes each pair's side from it.
    std::vector<float> sc_snap_x_, sc_snap_y_, sc_snap_z_;
    std::vector<float> sc_block_moved_; ///< per block of particles: the largest squared move from the snapshot
    // A run that cuts the motion into parts (a particle moved more than h / 2): the motion's end, and the positions at
    // the start of the part (each pair's side).
    std::vector<float> sc_end_x_, sc_end_y_, sc_end_z_, sc_side_x_, sc_side_y_, sc_side_z_;
    std::size_t sc_parts_ = 0; ///< parts of the last run (self_collision_parts)
    // Per particle: the sum of the pushes of a run (an implicit step's first, every explicit one), then (at its end,
    // normalised in place) the unit normal of its contact plane, with the offset n . x where the run left it: for the
    // implicit contact re-solve (implicit_step.cpp) or the explicit steps that skip the stage. Normal 0 0 0: none.
    std::vector<float> sc_push_x_, sc_push_y_, sc_push_z_, sc_plane_c_;
    bool sc_track_pushes_ = false; ///< this run sums its pushes (an implicit step's first run, every explicit run)
    bool sc_pushed_ = false; ///< the last run was an implicit step's first and pushed some particle (planes set)
    /// Explicit solver: the planes (sc_push_*, sc_plane_c_) of the run that took the snapshot of step sc_plane_step_
    /// hold the particles it pushed in the steps that skip the stage (SIZE_MAX: none).
    std::size_t sc_plane_step_ = SIZE_MAX;
    /// Explicit solver, per particle pushed by the run: a partner of its contacts (of the pair's other side, the
    /// vertex with the largest weight; over several contacts the lowest index), whose move since the snapshot moves the
    /// plane with it. UINT32_MAX: none.
    std::vector<std::uint32_t> sc_partner_;
    template <bool Parallel> void self_collide_hold(StateBuffer& out);
    std::size_t sc_snap_step_ = SIZE_MAX; ///< steps_done_ after the step the snapshot was taken in (SIZE_MAX: none)
    std::size_t sc_runs_ = 0;             ///< steps in which the stage ran (self_collision_runs)
    std::size_t sc_resolves_ = 0;         ///< implicit contact re-solves (self_collision_resolves)
    std::size_t sc_substepped_ = 0;       ///< implicit steps solved in sub-steps (self_collision_substepped)
    /// Simulated time at the start of the step or sub-step being solved (the wind's phase), s.
    double step_time_ = 0.0;
    /// One step or sub-step of params_.dt: the solver, strain limiting and colliders, self-collision (with the
    /// implicit contact re-solve when it pushed). Leaves the result in the other buffer. `attempt` (implicit, contact
    /// sub-steps on): returns true, at once, when the stage pushed: the step is to be solved again in sub-steps.
    template <bool Parallel> bool step_pipeline(bool implicit, bool attempt);
    /// The current step again, from its start, as `k` implicit sub-steps (at most one per implicit_min_dt);
    /// `self_contact`: the contact sub-steps of self-collision (multilevel or not by how crowded the contact is);
    /// otherwise the strain retry's, `depth` levels down: a sub-step over the limit is split again (strain_retry_depth).
    template <bool Parallel> void implicit_substeps(std::uint32_t k, bool self_contact, std::uint32_t depth);
    /// The last strain limiting's last sweep still found a spring over (1 + strain_limit_tolerance ratio) l0.
    bool limit_over_ = false;
    std::size_t strain_substepped_ = 0; ///< implicit steps solved again in sub-steps (strain_substepped)
    /// The last step's sub-steps still ended over the limit: no more retries until a step ends within it (a limit no
    /// step can hold would otherwise cost every step its sub-steps).
    bool strain_retry_failed_ = false;
    template <bool Parallel> void seam_forces_stage();
    template <bool Parallel> void aero_forces_stage();
    void cook_aero();
    /// Force per particle from aero_forces and seam_forces, N (allocated when either runs).
    AlignedArray<float> extra_fx_, extra_fy_, extra_fz_;
    // Aerodynamic wind (cooked when first enabled): per-triangle forces and, per particle, its triangles (CSR, cooked
    // for the wind or for triangle contact: cook_vertex_triangles).
    std::vector<float> tri_fx_, tri_fy_, tri_fz_;
    std::vector<std::uint32_t> vertex_tri_offsets_, vertex_tris_;
    bool extra_forces() const noexcept { return !cloth_.seams.empty() || params_.aero.enabled; }
    std::size_t grabbed_ = SIZE_MAX;
    bool grabbed_was_pinned_ = false;
    std::array<float, 3> grab_target_{};
    std::array<float, 3> grab_applied_{}; ///< the target the last step() call applied
    HealthMonitor monitor_;
    bool rebaseline_ = false; ///< a user action since the last step(): restart the monitor's energy balance
    template <bool Parallel> void check_health();
    void apply_user_constraints() noexcept;
    /// Writes velocity `vel` (m/s) of particle i into s in the integrator's form: u, v, w = vel (symplectic Euler) or
    /// the previous position x - vel dt (Verlet).
    static void store_velocity(StateBuffer& s, std::size_t i, std::array<float, 3> vel, Integrator integrator,
                               float dt) noexcept;
};

/// Validates run parameters (ranges, not stability); throws InvalidInput.
void validate_params(const SimulationParams& params);
/// Why ImplicitParams::fas_at_rest can never act with these parameters (its measured faults: "colliders",
/// "self-collision", "wind", "aerodynamic wind"), or nullptr. (A grab also stops it, for as long as it is held.)
const char* fas_at_rest_excluded_by(const SimulationParams& params) noexcept;

} // namespace drape
