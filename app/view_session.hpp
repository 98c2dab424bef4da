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
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "drape/publish.hpp"
#include "drape/scene.hpp"
#include "drape/simulation.hpp"

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
/// Node mass range of the Fabric panel, grams (SPEC: 0.001-1 g).
inline constexpr float view_min_node_mass_g = 0.001f;
inline constexpr float view_max_node_mass_g = 1.0f;
inline constexpr float view_min_stiffness = 100.0f;
inline constexpr float view_max_stiffness = 25000.0f;

/// What the Fabric panel edits (physics part; colours live in render::Shading).
struct FabricSettings {
    float node_mass_g = 0.0f; ///< g per particle
    /// N/m per spring kind: structural, shear, bend, seam (seams only on sewn garments)
    std::array<float, spring_kind_count> stiffness{1000.0f, 500.0f, 100.0f, 1000.0f};
    float damping_ratio = 0.05f; ///< spring damping as a fraction of critical damping of one spring (0..1)
};

enum class MessageLevel { info, warning, error };

struct Message {
    std::string text;
    MessageLevel level = MessageLevel::info;
    std::chrono::steady_clock::time_point when{};
};

class ViewSession {
  public:
    /// Loads a built-in scene by name or a scene file (.json) and builds it. size: particles per side of a
    /// grid scene or cells per metre of the T-shirt (empty: the scene's own; "hang": view_default_hang_size).
    /// threads 0 = all hardware threads; substeps empty = automatic. Throws InvalidInput naming the flag.
    ViewSession(const std::string& scene, std::optional<std::uint32_t> size, int threads,
                std::optional<int> substeps);
    /// Shorthand for scene "hang" of size x size particles (tests).
    ViewSession(std::uint32_t size, int threads, std::optional<int> substeps)
        : ViewSession("hang", size, threads, substeps) {}

    Simulation& sim() noexcept { return *sim_; }
    const Simulation& sim() const noexcept { return *sim_; }
    Publisher& publisher() noexcept { return *publisher_; }
    /// Increases whenever the cloth is rebuilt (new topology or size): GPU buffers must be recreated.
    std::uint64_t generation() const noexcept { return generation_; }
    /// Increases whenever pins or the grab change: the markers must be re-sent.
    std::uint64_t markers_version() const noexcept { return markers_version_; }

    /// One frame of simulation: substeps() substeps when running (or once after step_once()). Catches
    /// SimulationError: pauses and keeps the last finite state. Returns the substeps run.
    std::size_t advance();

    // Run mode.
    bool running() const noexcept { return running_; }
    void set_running(bool on);
    void step_once();
    /// Back to the initial flat cloth with the current settings (pins: the two corners again).
    void reset();
    /// Switches to another built-in scene (or file): its own settings, flat start.
    void set_scene(const std::string& name_or_path);
    const SceneSpec& scene() const noexcept { return spec_; }
    /// The scene as the panels have it now (size, total mass, materials, physics, fixed dt), without a
    /// state: what File > Save scene writes (with capture_state(sim()) as its state).
    SceneSpec current_spec() const;
    bool grid_scene() const noexcept { return spec_.cloth == ClothType::grid; }
    /// Increases when the scene changes (the camera reframes, the ground moves).
    std::uint64_t scene_generation() const noexcept { return scene_generation_; }
    /// Rebuilds at a new resolution: particles per side of a grid, cells per metre of the T-shirt. The
    /// scene's total mass is kept (so the node mass changes); materials are kept.
    void set_size(std::uint32_t n);
    std::uint32_t size() const noexcept { return size_; }
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
    void set_node_mass(float grams);

    // Physics.
    const SimulationParams& params() const noexcept { return sim_->params(); }
    void set_gravity(const std::array<float, 3>& g);
    void set_wind(bool enabled, float strength);
    void set_air_drag(float drag);
    void set_integrator(Integrator integrator);
    /// Provot strain limiting (ratio 0 = off); ranges as in drape/simulation.hpp.
    void set_strain_limit(const StrainLimit& limit);
    /// Fixes dt (s) within (0, bound]; the panel cannot offer more than the bound.
    void set_dt(double dt);
    void set_auto_dt(bool on);
    bool auto_dt() const noexcept { return auto_dt_; }
    double dt_bound() const noexcept { return dt_bound_; }
    int substeps() const noexcept { return substeps_; }
    bool auto_substeps() const noexcept { return auto_substeps_; }
    void set_substeps(int s);
    void set_auto_substeps(bool on);
    int threads() const noexcept { return threads_; }
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
    /// Non-empty after the simulation stopped on a non-finite value (until reset()).
    const std::string& error() const noexcept { return error_; }

  private:
    struct Candidate {
        FabricSettings fabric;
        float air_drag;
    };
    std::array<SpringMaterial, spring_kind_count> materials(const FabricSettings& f) const;
    double bound_for(const FabricSettings& f, float air_drag) const;
    int auto_substep_count(double dt) const;
    /// Manual substeps: enough substeps of dt to cover frame_time_ (may exceed view_max_substeps: callers
    /// refuse).
    int manual_substep_count(double dt) const;
    /// Applies a change of fabric or drag with the stability rules above; returns false if refused.
    bool apply_physics(const Candidate& next, const std::string& what);
    void rebuild(bool keep_state);
    struct Snapshot {
        std::uint32_t size;
        SceneSpec spec;
        float total_mass;
        FabricSettings fabric;
        bool has_seams;
        float cloth_size;
        std::array<float, 3> frame_lo, frame_hi;
        std::optional<float> ground;
        SimulationParams params;
        bool auto_dt;
        double dt_bound;
        int substeps;
        float spacing;
        double frame_time;
    };
    Snapshot snapshot() const;
    void restore(const Snapshot& before);
    /// Runs a change that rebuilds; on InvalidInput or bad_alloc restores the settings (the old simulation
    /// was never replaced) and posts a message. Returns whether it applied.
    bool guarded(const std::string& what, const std::function<void()>& change);
    /// Applies run parameters to the simulation and keeps them; a refused change (unstable, out of range) posts a
    /// message and changes nothing. Returns whether it was applied.
    bool commit_params(const SimulationParams& p);
    void refresh_pins();
    void load_spec(SceneSpec spec, std::optional<std::uint32_t> size);
    std::size_t particle_count() const noexcept { return sim_ ? sim_->cloth().particle_count : 1; }

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
    std::unique_ptr<tbb::global_control> thread_limit_;
    int threads_ = 1;
    int substeps_ = 10;
    bool auto_substeps_ = true;
    double frame_time_ = 0.0;      ///< s simulated per frame the user chose (manual substeps)
    bool keep_frame_time_ = false; ///< rebuild keeps frame_time_ (physics changes) instead of re-anchoring it
    bool auto_dt_ = true;
    double dt_bound_ = 0.0;
    float spacing_ = 0.0f;
    bool running_ = true;
    bool step_pending_ = false;
    SimulationParams params_; ///< run parameters kept across rebuilds
    std::vector<std::uint32_t> pinned_;
    std::uint64_t generation_ = 0;
    std::uint64_t markers_version_ = 0;
    Message message_;
    std::string error_;
};

} // namespace drape::app
