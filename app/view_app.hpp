// The viewer: a GLFW window with an OpenGL 4.5 core context, the frame loop, mouse and keyboard, and the Dear
// ImGui panels (view_ui.cpp). A frame that owns the session:
//
//   poll input -> end the step started last frame (finish_step) -> ImGui frame -> queued buttons and keys (routed
//   with this frame's capture flags) -> panels (changes apply now; rebuilds start on a background thread) -> install
//   a finished build -> wait for the next ring region's fence -> output stage writes positions + normals (oneTBB +
//   SIMD) -> start the next step on its own thread (--no-overlap: simulate here, before the output stage)
//   -> draw background, ground, cloth, markers, panels -> fence the region -> swap
//
// A step longer than a frame does not hold the frames (ViewOptions::interpolate): while it runs and no input waits
// for the session, a frame draws the blend of the last two published states (FrameInterpolator) with the panels as
// last built, paced to --blend-fps; if the step ends during such a frame, the frame takes it and starts the next
// before its swap. The input callbacks move the camera at once and queue what touches the session.
//
// Timings of the three parts (sim, publish, draw; the fence wait counts as draw) feed the overlay and
// --stats-json.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "camera.hpp"
#include "cloth_renderer.hpp"
#include "collider_renderer.hpp"
#include "frame_interpolation.hpp"
#include "drape/picking.hpp"
#include "stage.hpp"
#include "view_command.hpp"
#include "view_session.hpp"
#include "view_tools.hpp"

struct GLFWwindow;

namespace drape::app {

/// Per-frame timings, ms.
struct FrameTimes {
    double sim = 0.0;      ///< the step's own wall time (overlapped: the step that ran while the last frame drew)
    double sim_wait = 0.0; ///< overlapped: how long this frame waited for that step to end
    double publish = 0.0;
    double draw = 0.0;  ///< draw calls + panels + swap + fence wait
    double wait = 0.0;  ///< fence wait alone (part of draw)
    double swap = 0.0;  ///< glfwSwapBuffers alone (part of draw; llvmpipe rasterises and presents here)
    double frame = 0.0; ///< swap to swap
    double sim_advanced = 0.0; ///< simulated seconds of the steps that ended in this frame (the real-time factor)
    bool interpolated = false; ///< drawn while a step ran (FrameInterpolator): no panels, no input
    bool took_step = false;    ///< a step ended and was taken in this frame (sim, sim_wait are its)
};

class Viewer {
  public:
    /// Opens the window (throws render::DisplayError without a display) and builds the scene.
    explicit Viewer(const ViewOptions& options);
    ~Viewer();
    Viewer(const Viewer&) = delete;
    Viewer& operator=(const Viewer&) = delete;

    /// Runs until the window closes or options.frames frames are drawn; returns the exit code.
    int run();

    // GLFW callbacks (forwarded from static trampolines; also driven by the demo script).
    void on_mouse_button(int button, int action, int mods);
    void on_cursor_event(double x, double y); ///< GLFW's cursor callback: applied now, or queued behind a button
    void on_cursor(double x, double y);
    void on_scroll(double dy);
    void on_key(int key, int action, int mods);
    /// Files dropped on the window: the first .json is opened as the scene.
    void on_drop(int count, const char** paths);

  private:
    void frame_input(double wall_dt);
    /// The frame's simulation and publish (the session is this thread's: no step runs after its first lines until
    /// the step it starts); returns whether the state is drawn.
    bool session_frame(FrameTimes& t, bool last_frame);
    /// Ends the running step (finish_step) and books it in t; whether it simulated anything.
    bool take_step(FrameTimes& t);
    /// In a frame drawn beside the step: when the step has ended, takes it, publishes it as the interpolator's newest
    /// state and starts the next one (the panels and input wait for the next frame that owns the session).
    void hand_over_step(FrameTimes& t);
    /// Whether this frame may be drawn while the step runs (FrameInterpolator): interpolation on, a step running,
    /// and nothing queued that touches the session.
    bool may_draw_beside_step(bool last_frame) const;
    /// Applies what the input callbacks queued while a step ran: a grab's cursor, dropped files.
    void apply_deferred_input();
    /// Mouse buttons and keys queued by the callbacks, handled after ImGui::NewFrame(), when ImGui's capture flags
    /// describe the cursor and the focus of this frame (at callback time they are the previous frame's).
    void handle_input_events();
    void scene_press(int button, int mods);
    void scene_release(int button);
    void handle_key(int key, int mods);
    void build_ui();
    void ui_panels();
    void ui_run_mode();
    void ui_scene_file();
    void ui_fabric();
    void ui_fabric_material(); ///< fabric_panel.cpp: the fabric model's preset, figures and derived values
    void ui_spring_material(); ///< the seeds' spring model: node mass, stiffness per kind, damping ratio
    void ui_fabric_looks();    ///< colours, shading, strain colours
    void ui_physics();
    void ui_aero();
    void ui_solver();
    void ui_lighting();
    void ui_camera();
    void ui_overlay();
    void ui_help();
    void ui_messages();
    void ui_error_banner();
    void ui_build_progress();
    void ui_confirmation();
    void sync_gpu();
    void draw_scene();
    void reset_camera();
    void run_demo_script();
    void print_stats_json() const;
    Ray cursor_ray(double x, double y) const;
    PickHit pick_at(double x, double y) const;
    Eigen::Matrix4f view_projection() const;
    float aspect() const;
    /// Width of the panel column, in window units (0 when the panels are hidden).
    float panel_width() const;
    void update_hover();
    void start_grab(const PickHit& hit, double x, double y);
    void save_screenshot(const std::string& path);
    // Tools (view_tools.cpp): strain colours, File panel, recording.
    void publish_strain(std::span<float> region);
    void ui_strain_controls();
    void ui_tool_overlays();
    void ui_file_panel();
    void export_obj(const std::string& path);
    void save_scene_file(const std::string& path, bool with_state);
    void start_recording(const std::string& target);
    void stop_recording();
    void record_frame();
    bool tools_key(int key);
    int finish_tools();

    ViewOptions options_;
    GLFWwindow* window_ = nullptr;
    bool imgui_ready_ = false;
    std::unique_ptr<ViewSession> session_;
    std::unique_ptr<render::ClothRenderer> renderer_;
    std::unique_ptr<render::Stage> stage_;
    std::unique_ptr<render::ColliderRenderer> colliders_;
    std::uint64_t gpu_generation_ = 0;
    std::uint64_t gpu_scene_ = 0;
    std::uint64_t gpu_markers_ = 0;
    render::OrbitCamera camera_;
    render::Shading shading_;
    std::string gl_renderer_;
    std::string gl_version_;

    // Input state.
    enum class Drag { none, orbit, pan, grab };
    Drag drag_ = Drag::none;
    struct InputEvent {
        int code, action, mods; ///< button or key; action cursor_moved_to: a cursor move to (x, y)
        double x = 0.0, y = 0.0;
    };
    static constexpr int cursor_moved_to = -1;
    /// Mouse buttons, and the cursor moves that follow a queued button, in the order they came; keys.
    std::vector<InputEvent> pending_mouse_, pending_keys_;
    int buttons_down_ = 0;      ///< bit per mouse button held
    bool ui_owns_press_ = false; ///< the buttons held went down over a panel: ImGui's until all are released
    double cursor_x_ = 0.0, cursor_y_ = 0.0;
    bool cursor_moved_ = false;
    float grab_depth_ = 0.0f;
    std::size_t hover_ = no_particle;
    std::size_t shown_hover_ = no_particle;
    std::size_t shown_grab_ = no_particle;

    // UI state.
    bool show_ui_ = true;
    bool show_help_ = false;
    bool show_ground_ = true;
    bool full_mesh_ = false;
    bool step_running_ = false; ///< a step runs on its own thread while this frame is drawn (ViewOptions::overlap)
    FrameInterpolator interpolator_;  ///< the states drawn while a step runs longer than a frame
    std::uint64_t interpolator_generation_ = 0;
    bool interpolate_ = false;        ///< ViewOptions::interpolate, with the overlap and without --demo-grab
    bool grab_move_deferred_ = false; ///< the cursor moved a grab while a step ran: moved once it has ended
    std::vector<std::string> dropped_; ///< .json files dropped while a step ran
    std::uint64_t interpolated_frames_ = 0; ///< frames drawn while a step ran
    double blend_draw_ms_ = 0.0; ///< running mean: from the end of the pacing wait to the swap, in those frames
    double step_ms_mean_ = 0.0;  ///< running mean of the steps' wall time
    std::chrono::steady_clock::time_point step_started_; ///< of the running step
    void start_step(); ///< session_->start_step(), noting when
    void note_session_error(); ///< a simulation error: the exit code, and once on stderr
    bool pixel_lighting_ = false; ///< light every pixel, whatever the triangles' size on screen
    bool gpu_full_mesh_ = false;
    int ui_size_ = 64;
    float ui_node_mass_ = 0.0f;
    std::array<char, 1024> scene_path_{};

    // Stats.
    std::uint64_t frame_index_ = 0;
    FrameTimes last_;
    FrameTimes shown_; ///< averaged over ~0.5 s for the overlay
    double shown_fps_ = 0.0;
    double shown_real_time_ = 0.0; ///< simulated seconds per wall second over the overlay's window
    bool window_steady_ = true;    ///< every frame of the window simulated (the slow-explicit hint's condition)
    bool built_this_frame_ = false;
    FrameTimes window_sum_;
    int window_frames_ = 0;
    int window_took_ = 0; ///< of them took a step
    std::chrono::steady_clock::time_point window_start_;
    std::vector<FrameTimes> samples_;
    std::size_t last_substeps_ = 0;
    PublishStats last_publish_;
    bool had_error_ = false;
    int failure_code_ = 0;
    bool write_failed_ = false;  ///< a screenshot could not be written
    std::uint64_t building_frames_ = 0; ///< frames drawn while a cloth was built in the background
    double building_ms_ = 0.0;          ///< their total
    double building_max_ms_ = 0.0;      ///< the longest of them
    double install_frame_ms_ = 0.0;     ///< the frame that swapped the last one in       ///< exit code of the last simulation failure (exit_code::non_finite / blow_up)
    std::string reported_error_; ///< the failure last printed on stderr
    std::string pending_screenshot_;
    ToolsState tools_;
};

} // namespace drape::app
