// The viewer's model: the simulation, its output stage, the settings the panels edit and the rules that keep every
// change stable. No OpenGL here.
//
// Stability: the explicit step is stable only below a bound that falls as stiffness, damping or air drag rise and
// as node mass falls (drape/stability.hpp). Every change that moves the bound goes through apply_physics(): the
// substep dt follows the bound (0.9 x, unless the user fixed dt below it), and when dt must shrink the substeps per
// frame grow so that a frame still covers the same simulated time ("compensated with more substeps"). If that would
// need more than view_max_substeps, the change is refused. Either way the panel shows a message; the core's own
// checks (set_material / set_params throw InvalidInput) are the last line of defence and are caught here.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "drape/publish.hpp"
#include "drape/scene_hang.hpp"
#include "drape/simulation.hpp"

namespace drape::app {

inline constexpr int view_max_substeps = 1000;
inline constexpr std::uint32_t view_min_size = 2;
inline constexpr std::uint32_t view_max_size = 2048;
/// Simulated seconds one frame aims to cover when substeps are automatic (real time at 60 FPS).
inline constexpr double view_frame_seconds = 1.0 / 60.0;
/// Cost cap of automatic substeps: particle-substeps per frame (about 4 ms at 2.4e8 particle-substeps/s).
inline constexpr double view_auto_budget = 1.0e6;
/// Node mass range of the Fabric panel, grams (SPEC: 0.001-1 g).
inline constexpr float view_min_node_mass_g = 0.001f;
inline constexpr float view_max_node_mass_g = 1.0f;
inline constexpr float view_min_stiffness = 100.0f;
inline constexpr float view_max_stiffness = 25000.0f;

/// Spring kinds of a grid cloth the Fabric panel edits: structural, shear, bend.
inline constexpr std::size_t grid_spring_kinds = 3;

/// What the Fabric panel edits (physics part; colours live in render::Shading).
struct FabricSettings {
    float node_mass_g = 0.0f;                                       ///< g per particle
    /// N/m: structural, shear, bend (the grid's three kinds; scene "hang" has no seam springs)
    std::array<float, grid_spring_kinds> stiffness{1000.0f, 500.0f, 100.0f};
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
    /// Builds scene "hang" of size x size particles. threads 0 = all hardware threads; substeps empty = automatic.
    ViewSession(std::uint32_t size, int threads, std::optional<int> substeps);

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
    /// Rebuilds at a new grid size (node mass back to the scene default 0.1 kg / N^2; materials kept).
    void set_size(std::uint32_t n);
    std::uint32_t size() const noexcept { return size_; }

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

    /// Grid spacing, m (pick radius and markers scale with it).
    float spacing() const noexcept { return spacing_; }
    float cloth_size() const noexcept { return hang_.size; }

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
    /// Applies a change of fabric or drag with the stability rules above; returns false if refused.
    bool apply_physics(const Candidate& next, const std::string& what);
    void rebuild(bool keep_state);
    void refresh_pins();

    std::uint32_t size_ = 64;
    HangParams hang_;
    FabricSettings fabric_;
    std::unique_ptr<Simulation> sim_;
    std::unique_ptr<Publisher> publisher_;
    std::unique_ptr<tbb::global_control> thread_limit_;
    int threads_ = 1;
    int substeps_ = 10;
    bool auto_substeps_ = true;
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
