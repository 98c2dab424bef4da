// The viewer's model: the simulation, its output stage, the settings the panels edit and the rules that keep
// every change stable. No OpenGL here.
//
// Stability: the explicit step is stable only below a bound that falls as stiffness, damping or air drag rise
// and as node mass falls (drape/stability.hpp). Every change that moves the bound goes through
// apply_physics(): the substep dt follows the bound (0.9 x, unless the user fixed dt below it), and when dt
// must shrink the substeps per frame grow so that a frame still covers the same simulated time ("compensated
// with more substeps"). If that would need more than view_max_substeps, the change is refused. Either way the
// panel shows a message; the core's own checks (set_material / set_params throw InvalidInput) are the last
// line of defence and are caught here.
//
// Rebuilds (grid size, node mass, scene, reset) never block the caller: the new cloth, simulation and output stage
// are built on a background thread from a copy of the settings while the old cloth keeps running (a node-mass
// rebuild, which continues the motion, holds it still), and replace it in poll() (called by advance()) once
// complete. A newer request supersedes an older one: a running build's result is discarded and only the newest
// waiting request is built next. A build that fails (bad input, no memory) leaves the old cloth and settings with a
// message. Requests above view_confirm_particles particles or half the memory available wait for confirm_build();
// requests that cannot fit are refused with the figures.
//
// Undo: every applied change of a setting (fabric, physics, size, scene) pushes the settings as they were (a
// Snapshot) onto a bounded history (view_undo_depth); undo() restores them (rebuilding when the cloth's topology or
// node mass differ), redo() goes forward again. Successive changes of the same control within one edit (end_edit()
// not called between them: a slider dragged) are one entry.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "drape/publish.hpp"
#include "drape/scene.hpp"
#include "drape/simulation.hpp"
#include "drape/workers.hpp"
#include "materials.hpp"

namespace drape::app {

inline constexpr int view_max_substeps = 1000;
inline constexpr std::uint32_t view_min_size = 2;
inline constexpr std::uint32_t view_max_size = 2048;
/// Resolution range of the T-shirt scene, cells per metre (as `drape run --size`).
inline constexpr std::uint32_t view_min_cells = 10;
inline constexpr std::uint32_t view_max_cells = 1000;
/// Particles per side of scene "hang" in the viewer when --size is not given: real time on two cores.
inline constexpr std::uint32_t view_default_hang_size = 64;
/// Simulated seconds one frame aims to cover when substeps are automatic (real time at 60 FPS).
inline constexpr double view_frame_seconds = 1.0 / 60.0;
/// Cost cap of automatic substeps: particle-substeps per frame (about 4 ms at 2.4e8 particle-substeps/s).
inline constexpr double view_auto_budget = 1.0e6;
/// Implicit solver: the step when neither the scene nor --dt gives one, a frame at 60 FPS (one step per frame, the
/// explicit viewer's pace), and the range of the dt slider (s).
inline constexpr double view_implicit_dt = view_frame_seconds;
inline constexpr double view_implicit_min_dt = 1e-3;
inline constexpr double view_implicit_max_dt = 0.1;
/// Implicit solver, automatic steps per frame: round(view_frame_seconds / dt) within [1, this].
inline constexpr int view_implicit_max_auto_steps = 8;
/// Iteration budget (implicit solver): the fewest iterations per step it lowers to, the default simulation time per
/// frame it keeps to (ms; about half a frame at 30 FPS) and the frames it averages before each adjustment.
/// (10, not fewer: at 4 sweeps per step a 316 x 316 wool hang reached 284 % strain and a crumpled, noisy surface;
/// a slower frame is better than a picture of a broken cloth.)
inline constexpr std::uint32_t view_min_iterations = 10;
inline constexpr double view_default_sim_budget_ms = 16.0;
inline constexpr int view_budget_frames = 4;
/// Node mass range of the Fabric panel, grams (SPEC: 0.001-1 g).
inline constexpr float view_min_node_mass_g = 0.001f;
inline constexpr float view_max_node_mass_g = 1.0f;
inline constexpr float view_min_stiffness = 100.0f;
inline constexpr float view_max_stiffness = 25000.0f;
/// Rebuilds above this many particles (or half the available memory) ask for confirmation first.
inline constexpr std::size_t view_confirm_particles = 1u << 20;
/// Entries of the undo history.
inline constexpr std::size_t view_undo_depth = 64;

/// What the Fabric panel edits (physics part; colours live in render::Shading).
/// Springs model: node mass, per-kind stiffness and damping ratio are the user's. Fabric model: `fabric` is the
/// user's (physical units, docs/fabric.md); node_mass_g, stiffness and derived_damping are what the builder derived
/// from it and the mesh (shown read-only), except the seam stiffness, which stays the user's.
struct FabricSettings {
    float node_mass_g = 0.0f; ///< g per particle (fabric model: the mean over the free particles)
    /// N/m per spring kind: structural, shear, bend, seam (seams only on sewn garments)
    std::array<float, spring_kind_count> stiffness{1000.0f, 500.0f, 100.0f, 1000.0f};
    float damping_ratio = 0.05f; ///< spring damping as a fraction of critical damping of one spring (0..1)
    MaterialModel model = MaterialModel::springs;
    Fabric fabric;
    std::array<float, spring_kind_count> derived_damping{}; ///< fabric model: N*s/m per kind, as built
};
/// Whether two fabrics have the same figures (the name aside).
bool same_figures(const Fabric& a, const Fabric& b) noexcept;

enum class MessageLevel { info, warning, error };

struct Message {
    std::string text;
    MessageLevel level = MessageLevel::info;
    std::chrono::steady_clock::time_point when{};
};

/// A rebuild in progress on the background thread (for the progress indicator).
struct BuildStatus {
    std::string what;          ///< e.g. "resolution 1000"
    std::size_t particles = 0; ///< of the cloth being built
    std::size_t bytes = 0;     ///< memory it needs (drape::scene_memory_bytes)
    double seconds = 0.0;      ///< since it started
    bool queued = false;       ///< a newer request waits to be built after this one (whose result is discarded)
};

/// A large rebuild waiting for the user's go-ahead.
struct Confirmation {
    std::string what;
    std::size_t particles = 0;
    std::size_t bytes = 0;     ///< needed
    std::size_t available = 0; ///< bytes available now (SIZE_MAX: unknown)
};

/// Thousands separators for counts: 1,000,000.
std::string grouped(std::size_t n);

/// Implicit solver, automatic steps per frame: enough steps of dt for view_frame_seconds, rounded, within
/// [1, view_implicit_max_auto_steps] (1 for any dt from 1/90 s up: one step per frame).
int implicit_auto_steps(double dt);

/// The iteration budget that keeps the frame rate with the implicit solver: from the simulation time of the last
/// frames (ms, averaged) and the iterations a step ran, the iterations per step to run next, within
/// [min(view_min_iterations, cap), cap] (cap: the user's iterations). Over the budget: lowered in proportion at once;
/// under 3/4 of it: raised by at most a quarter (at least 1) per adjustment; in between: kept (no oscillation).
std::uint32_t budget_iterations(double sim_ms, double budget_ms, std::uint32_t current, std::uint32_t ran,
                                std::uint32_t cap);

class ViewSession {
  public:
    /// Loads a built-in scene by name or a scene file (.json) and builds it. size: particles per side of a
    /// grid scene or cells per metre of the T-shirt (empty: the scene's own; "hang": view_default_hang_size).
    /// threads 0 = all hardware threads; substeps empty = automatic. Throws InvalidInput naming the flag.
    /// material: a fabric preset or "springs" replacing the scene's material (`drape view --material`).
    /// solver: `drape view --solver/--iterations/--tolerance` (unset: the scene's); dt: `--dt`, the implicit step
    /// or the explicit substep (an explicit one above the stability bound is refused).
    ViewSession(const std::string& scene, std::optional<std::uint32_t> size, int threads,
                std::optional<int> substeps, const std::optional<std::string>& material = std::nullopt,
                const SolverFlags& solver = {}, std::optional<double> dt = std::nullopt);
    /// Shorthand for scene "hang" of size x size particles with the seeds' spring model (tests).
    ViewSession(std::uint32_t size, int threads, std::optional<int> substeps)
        : ViewSession("hang", size, threads, substeps, std::string("springs")) {}
    /// Waits for a build in progress (its result is discarded).
    ~ViewSession();
    ViewSession(const ViewSession&) = delete;
    ViewSession& operator=(const ViewSession&) = delete;

    Simulation& sim() noexcept { return *sim_; }
    const Simulation& sim() const noexcept { return *sim_; }
    Publisher& publisher() noexcept { return *publisher_; }
    /// Increases whenever the cloth is rebuilt (new topology or size): GPU buffers must be recreated.
    std::uint64_t generation() const noexcept { return generation_; }
    /// Increases whenever pins or the grab change: the markers must be re-sent.
    std::uint64_t markers_version() const noexcept { return markers_version_; }

    /// One frame: poll(), then substeps() substeps when running (or once after step_once()), inside the workers.
    /// Catches SimulationError (BlowUpError too): pauses, keeps the last finite state and sets error(). Returns the
    /// substeps run.
    std::size_t advance();
    /// advance() in two halves, so that the viewer draws the last frame while the next one simulates: start_step()
    /// polls and decides on the caller's thread, then runs the step on a thread of its own and returns whether it
    /// started one; finish_step() waits for it and does what advance() does after the step (errors, the iteration
    /// budget), returning the substeps run (0 when none was started). Between the two nothing else may touch the
    /// simulation, and of the session only note_real_time_factor and step_ready (which read the session's own fields); the viewer only
    /// draws what it published before. The same bits as advance().
    bool start_step();
    std::size_t finish_step();
    /// Whether finish_step() would return at once: no step open, or the open one has ended. Safe while it runs (the
    /// viewer keeps drawing until it has ended: FrameInterpolator).
    bool step_ready() const noexcept { return !step_open_ || step_done_.load(std::memory_order_acquire); }
    /// Wall milliseconds of the last step (advance() or start_step()), measured on its own thread.
    double last_step_ms() const noexcept { return step_ms_; }
    /// Writes the current positions and normals into `out` (Publisher::publish) inside the workers.
    PublishStats publish(std::span<float> out);
    /// Runs f inside the session's workers (other per-frame output stages: strain colours).
    template <class F> decltype(auto) in_workers(F&& f) { return workers_->run(std::forward<F>(f)); }

    // Background rebuilds.
    /// Installs a finished build (the new cloth replaces the old one here, on the caller's thread) and starts the
    /// next waiting request. Never waits. Returns true when a new cloth was installed.
    bool poll();
    /// Whether a build runs or waits (the settings panels are read-only meanwhile).
    bool building() const noexcept { return job_ != nullptr || queued_ != nullptr; }
    std::optional<BuildStatus> build_status() const;
    /// Discards the build in progress and any waiting request; the current cloth stays.
    void cancel_build();
    /// Blocks until no build runs or waits (tests, automation); installs the results as poll() does.
    void wait();
    const std::optional<Confirmation>& confirmation() const noexcept { return confirm_; }
    /// Starts (yes) or drops the request waiting for confirmation.
    void confirm_build(bool yes);
    /// Called on the build thread before each build with the spec being built (tests: hold a build, or fail it
    /// by throwing InvalidInput or std::bad_alloc).
    void set_build_hook(std::function<void(const SceneSpec&)> hook) { build_hook_ = std::move(hook); }

    // Undo.
    void undo();
    void redo();
    bool can_undo() const noexcept { return !undo_.empty() || building(); }
    bool can_redo() const noexcept { return !redo_.empty(); }
    std::size_t undo_depth() const noexcept { return undo_.size(); }
    /// Closes the current edit: the next change starts a new undo entry even on the same control (the viewer calls
    /// it whenever no control is active).
    void end_edit() noexcept { edit_open_ = false; }

    // Markers (pins, grab, hover) on or off: a change bumps markers_version() so the view updates at once.
    bool show_markers() const noexcept { return show_markers_; }
    void set_show_markers(bool on);

    // Run mode.
    bool running() const noexcept { return running_; }
    void set_running(bool on);
    void step_once();
    /// Back to the initial flat cloth with the current settings (pins: the two corners again).
    void reset();
    /// Switches to another built-in scene (or file): its own settings, flat start (in the background).
    void set_scene(const std::string& name_or_path);
    const SceneSpec& scene() const noexcept { return spec_; }
    /// The scene as the panels have it now (size, total mass, materials, physics, fixed dt), without a
    /// state: what File > Save scene writes (with capture_state(sim()) as its state).
    SceneSpec current_spec() const;
    bool grid_scene() const noexcept { return spec_.cloth == ClothType::grid; }
    /// Increases when the scene changes (the camera reframes, the ground moves).
    std::uint64_t scene_generation() const noexcept { return scene_generation_; }
    /// Rebuilds at a new resolution: particles per side of a grid, cells per metre of the T-shirt or an outline.
    /// The scene's total mass is kept (so the node mass changes; an outline keeps its areal density, so its mass
    /// follows its area); materials are kept.
    /// Outline: cells per metre too (spacing 1 / n). Refused (a message) for a mesh or a mask cloth.
    void set_size(std::uint32_t n);
    /// Particles per side (grid) or cells per metre (T-shirt, outline: round(1 / spacing)); 0 for a mesh or mask.
    std::uint32_t size() const noexcept { return size_; }
    /// Whether the scene has a resolution control (grid, T-shirt, outline; not a mesh or a mask cloth).
    bool resizable() const noexcept { return scene_resolution(spec_).has_value(); }
    /// Whether the cloth has seam springs (the seam stiffness slider).
    bool has_seams() const noexcept { return has_seams_; }
    /// Axis-aligned box around the cloth at the start and the colliders (planes excluded), m; a cloth pinned
    /// along one edge is extended downwards by its size (where it will hang).
    std::array<float, 3> frame_lo() const noexcept { return frame_lo_; }
    std::array<float, 3> frame_hi() const noexcept { return frame_hi_; }
    /// Height of the ground plane when the scene has one (else empty).
    std::optional<float> ground_height() const noexcept { return ground_; }

    // Fabric.
    const FabricSettings& fabric() const noexcept { return fabric_; }
    void set_stiffness(SpringKind kind, float k);
    void set_damping_ratio(float ratio);
    /// Rebuilds the cloth with the new node mass, continuing from the current positions, velocities and pins.
    /// Springs model only (a fabric's node mass follows its areal density).
    void set_node_mass(float grams);
    /// Switches the material model, rebuilding the cloth and continuing its motion: springs takes the scene's
    /// spring fields; fabric the scene's fabric (cotton_shirting when the scene has none).
    void set_material_model(MaterialModel model);
    /// The fabric (fabric model; switches to it), checked by validate_fabric: rebuilds in the background and
    /// continues the motion. A refused fabric posts the field and its range and changes nothing.
    void set_fabric(const Fabric& fabric);
    /// A preset by name (fabric_presets()).
    void set_fabric_preset(const std::string& name);

    // Physics.
    const SimulationParams& params() const noexcept { return sim_->params(); }
    void set_gravity(const std::array<float, 3>& g);
    void set_wind(bool enabled, float strength);
    /// Aerodynamic wind (core ranges: density 0..100 kg/m^3, C_d 0..10, each velocity component within +-100 m/s
    /// and |v| <= 100 m/s), applied with the stability rules of apply_physics.
    void set_aero(const AeroWind& aero);
    void set_air_drag(float drag);
    void set_integrator(Integrator integrator);
    /// Explicit or implicit. Implicit: the integrator becomes symplectic Euler, dt the implicit step (kept apart from
    /// the explicit dt: switching back restores it), steps per frame automatic (one per frame) or the manual pace.
    void set_solver(Solver solver);
    Solver solver() const noexcept { return params_.solver; }
    /// The implicit step (s), also while the explicit solver runs (used when switching).
    double implicit_dt() const noexcept { return implicit_dt_; }
    /// The user's iterations per step (the most; the budget may run fewer), 1..1000.
    std::uint32_t max_iterations() const noexcept { return max_iterations_; }
    void set_max_iterations(std::uint32_t iterations);
    /// The iterations per step running now (the budget's choice, or max_iterations() without it).
    std::uint32_t iterations() const noexcept { return sim_->params().implicit.iterations; }
    void set_chebyshev_rho(float rho);
    /// The implicit solver's multilevel guess on or off (ImplicitParams::multilevel; undoable).
    void set_multilevel(bool on);
    /// ImplicitParams::fas_at_rest (undoable).
    void set_fas_at_rest(bool on);
    /// The iteration budget (implicit solver): on, the iterations follow budget_iterations() every
    /// view_budget_frames frames so that the simulation takes about sim_budget_ms() per frame.
    bool iteration_budget() const noexcept { return budget_on_; }
    void set_iteration_budget(bool on);
    double sim_budget_ms() const noexcept { return budget_ms_; }
    void set_sim_budget_ms(double ms);
    /// Feeds the budget one frame's simulation time (advance() does, with the measured time; tests call it with
    /// chosen times).
    void note_frame_sim_ms(double ms);
    /// Provot strain limiting (ratio 0 = off); ranges as in drape/simulation.hpp.
    void set_strain_limit(const StrainLimit& limit);
    /// Self-collision thickness, m (0 = off, else self_collision_min_thickness to _max_thickness; the friction stays).
    void set_self_collision(float thickness);
    /// Fixes dt (s) within (0, bound]; the panel cannot offer more than the bound.
    void set_dt(double dt);
    void set_auto_dt(bool on);
    bool auto_dt() const noexcept { return auto_dt_; }
    double dt_bound() const noexcept { return dt_bound_; }
    int substeps() const noexcept { return substeps_; }
    bool auto_substeps() const noexcept { return auto_substeps_; }
    void set_substeps(int s);
    void set_auto_substeps(bool on);
    /// Workers that run the steps and the output stage (a drape::Workers arena of exactly that many).
    int threads() const noexcept { return workers_ ? workers_->workers() : 1; }
    static int hardware_threads();
    void set_threads(int t);

    // Pins and grab (particle indices).
    void grab(std::size_t i, const std::array<float, 3>& target);
    void move_grab(const std::array<float, 3>& target);
    void release_grab();
    /// Pins the grabbed particle where it is and lets go of it (the mouse is free for another).
    void pin_grabbed();
    /// Pins an unpinned particle, unpins a pinned one.
    void toggle_pin(std::size_t i);
    /// Pinned particles other than the grabbed one (for markers).
    const std::vector<std::uint32_t>& pinned() const noexcept { return pinned_; }

    /// Typical distance between neighbouring particles, m (the pick radius scales with it).
    float spacing() const noexcept { return spacing_; }
    /// Size of the cloth, m (the larger side of its starting box).
    float cloth_size() const noexcept { return cloth_size_; }

    const Message& message() const noexcept { return message_; }
    void post(MessageLevel level, std::string text);
    /// After a publish (the step joined, none running): posts unconverged_implicit_warning (materials.hpp) for the
    /// published strain once each time it starts to apply, and likewise overstretched_warning (not during a grab).
    void note_published_strain(float max_structural_strain);
    /// The overlay's real-time factor (simulated seconds per wall second over ~0.5 s), safe while a step runs. Below
    /// slow_explicit_factor with the explicit solver, posts once per cloth that the implicit solver steps a frame at a
    /// time (a 100 x 100 hang ran at 0.27x real time in the viewer with the explicit solver).
    void note_real_time_factor(double factor);
    static constexpr double slow_explicit_factor = 0.5;
    /// Non-empty after the simulation stopped on a non-finite value or an explosion (until reset()).
    const std::string& error() const noexcept { return error_; }
    /// exit_code::blow_up (BlowUpError), exit_code::non_finite (another SimulationError) or exit_code::ok.
    int error_code() const noexcept { return error_code_; }

  private:
    struct Candidate {
        FabricSettings fabric;
        float air_drag;
        AeroWind aero;
    };
    static std::array<SpringMaterial, spring_kind_count> materials(const FabricSettings& f);
    double bound_for(const FabricSettings& f, float air_drag, const AeroWind& aero) const;
    /// After a refused change: the old run parameters and materials back, through stable intermediate states.
    void restore_run_state(const SimulationParams& old_params,
                           const std::array<SpringMaterial, spring_kind_count>& old_materials);
    int auto_substep_count(double dt) const;
    /// Manual substeps: enough substeps of dt to cover frame_time_ (may exceed view_max_substeps: callers
    /// refuse).
    int manual_substep_count(double dt) const;
    /// Applies a change of fabric, drag or aero with the stability rules above; returns false if refused.
    bool apply_physics(const Candidate& next, const std::string& what, const std::string& key);
    struct Snapshot { // every member initialised: a Request copies a Snapshot that settings_for() filled in part
        std::uint32_t size = 0;
        SceneSpec spec;
        float total_mass = 0.0f;
        FabricSettings fabric;
        bool has_seams = false;
        float cloth_size = 0.0f;
        std::array<float, 3> frame_lo{}, frame_hi{};
        std::optional<float> ground;
        SimulationParams params;
        bool auto_dt = true;
        double dt_bound = 0.0;
        int substeps = 10;
        float spacing = 0.0f;
        double frame_time = 0.0;
        bool auto_substeps = true;
        std::uint64_t topology = 0; ///< changes with the scene or the resolution (a rebuild from the start)
        double implicit_dt = view_implicit_dt; ///< the implicit step
        double explicit_dt = 0.0;              ///< the explicit dt the user fixed, while the implicit solver runs
        std::uint32_t max_iterations = 30;
        bool budget_on = true;
        double budget_ms = view_default_sim_budget_ms;
    };
    Snapshot snapshot() const;
    void restore(const Snapshot& before);
    /// Applies run parameters to the simulation and keeps them; a refused change (unstable, out of range) posts a
    /// message and changes nothing. Returns whether it was applied; records an undo entry under `key`.
    bool commit_params(const SimulationParams& p, const std::string& key);
    /// Sets the simulation's run parameters and keeps them (params_); a refusal is posted. No undo entry.
    bool try_set_params(const SimulationParams& p);
    /// Posts single_level_implicit_warning, self_collision_thickness_warning and started_inside_warning
    /// (materials.hpp) once each time each starts to apply (a new cloth, the implicit solver chosen for one, a
    /// thickness set); the last only for a new scene (`new_cloth`).
    void warn_about_settings(bool new_cloth);
    bool single_level_warned_ = false;
    bool thickness_warned_ = false;
    bool inside_warned_ = false;
    bool unconverged_warned_ = false;
    bool overstretched_warned_ = false;
    /// The cloth the slow-explicit hint was for: the scene (scene_generation_) and its particle count, so a reset,
    /// an undo or a node-mass rebuild of the same cloth does not repeat it.
    std::pair<std::uint64_t, std::size_t> slow_hinted_for_{UINT64_MAX, 0};
    void refresh_pins();
    /// The settings of a scene as loaded, at `size` (throws InvalidInput for a size out of range).
    Snapshot settings_for(SceneSpec spec, std::optional<std::uint32_t> size);

    // Background builds.
    enum class History : std::uint8_t { record, undo, redo, none };
    struct KeepState {
        InitialState state;
        std::vector<std::uint32_t> pins;
    };
    struct Request {
        std::string what;
        Snapshot target;                 ///< settings to build
        std::shared_ptr<const KeepState> keep; ///< continue this motion (node mass), else the scene's start
        bool keep_frame_time = false;
        bool new_scene = false;
        bool clears_error = true;
        History history = History::record;
        Snapshot before;                 ///< settings when requested (the undo entry)
        std::string done;                ///< message once installed ("" = the default)
        std::chrono::steady_clock::time_point start;
        std::size_t particles = 0, bytes = 0;
    };
    struct Built {
        Snapshot snap;
        std::unique_ptr<Simulation> sim;
        std::unique_ptr<Publisher> publisher;
    };
    struct Job {
        Request request;
        std::thread thread;
        std::atomic<bool> done{false};
        bool discard = false;
        std::optional<Built> result;
        std::string error;
    };
    /// Builds the cloth, simulation and output stage for `target` (no member is read or written: runs on the
    /// background thread).
    static Built build(Snapshot target, const KeepState* keep, bool keep_frame_time);
    void install(Built built, const Request& request);
    /// Checks memory, asks for confirmation when large, supersedes what waits, starts when idle.
    void request(Request r, bool confirmed = false);
    void start(Request r);
    /// Refuses a settings change while a build runs or waits (posts why). Returns true when busy.
    bool busy(const std::string& what);
    void record(const Snapshot& before, const std::string& key);
    /// Makes `target` the current settings (undo / redo), rebuilding when needed.
    void apply_settings(const Snapshot& target, History history);
    std::shared_ptr<const KeepState> capture_state();
    /// Sets dt (clamped below the bound) and the substeps that follow; false (with a message) when refused.
    bool apply_dt(double dt);
    std::size_t particle_count() const noexcept { return sim_ ? sim_->cloth().particle_count : 1; }
    /// Sets the running iterations per step (no undo entry: the budget's, or the cap's).
    void set_running_iterations(std::uint32_t iterations);

    std::uint32_t size_ = 64;
    SceneSpec spec_;
    float total_mass_ = 0.1f; ///< kg, the scene's; kept across resolution changes
    FabricSettings fabric_;
    bool has_seams_ = false;
    float cloth_size_ = 1.0f;
    std::array<float, 3> frame_lo_{}, frame_hi_{};
    std::optional<float> ground_;
    std::uint64_t scene_generation_ = 0;
    std::unique_ptr<Simulation> sim_;
    std::unique_ptr<Publisher> publisher_;
    std::unique_ptr<Workers> workers_;
    int substeps_ = 10;
    bool auto_substeps_ = true;
    double frame_time_ = 0.0;      ///< s simulated per frame the user chose (manual substeps)
    bool auto_dt_ = true;
    double dt_bound_ = 0.0;
    float spacing_ = 0.0f;
    bool running_ = true;
    bool step_pending_ = false;
    // The step start_step() began: its thread, the steps done before it, its wall time and its exception.
    std::thread step_thread_;
    bool step_open_ = false;
    std::atomic<bool> step_done_{false}; ///< set by the step's thread as its last act
    std::size_t step_before_ = 0;
    double step_ms_ = 0.0;
    std::exception_ptr step_error_;
    bool step_due();
    void run_step();
    SimulationParams params_; ///< run parameters kept across rebuilds
    double implicit_dt_ = view_implicit_dt;
    double explicit_dt_ = 0.0;
    std::uint32_t max_iterations_ = 30;
    bool budget_on_ = true;
    double budget_ms_ = view_default_sim_budget_ms;
    double budget_sum_ms_ = 0.0; ///< simulation time of the frames since the last adjustment
    int budget_frames_ = 0;
    std::vector<std::uint32_t> pinned_;
    std::uint64_t generation_ = 0;
    std::uint64_t markers_version_ = 0;
    Message message_;
    std::string error_;
    int error_code_ = 0;
    bool show_markers_ = true;
    std::uint64_t topology_ = 0;
    std::uint64_t topology_counter_ = 0;
    // Builds.
    std::unique_ptr<Job> job_;
    std::unique_ptr<Request> queued_;
    std::optional<Confirmation> confirm_;
    std::unique_ptr<Request> confirm_request_;
    std::function<void(const SceneSpec&)> build_hook_;
    // Undo.
    struct Entry {
        Snapshot settings;
        std::string key;
    };
    std::deque<Entry> undo_;
    std::vector<Snapshot> redo_;
    bool edit_open_ = false;
};

} // namespace drape::app
