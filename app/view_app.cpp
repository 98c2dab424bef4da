// The viewer's window, input and frame loop (see view_app.hpp).
#include "view_app.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <span>
#include <thread>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <Eigen/LU>
#include <glad/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <imgui.h>
#include <imgui_impl_glfw.h>
#include <imgui_impl_opengl3.h>
#include <nlohmann/json.hpp>

#include "drape/errors.hpp"
#include "gl_context.hpp"
#include "screenshot.hpp"

namespace drape::app {

namespace {

using clock_type = std::chrono::steady_clock;

double ms_since(clock_type::time_point t) {
    return std::chrono::duration<double, std::milli>(clock_type::now() - t).count();
}

Viewer* viewer_of(GLFWwindow* w) {
    return static_cast<Viewer*>(glfwGetWindowUserPointer(w));
}

// With --demo-grab the script owns the mouse: real pointer events (Xvfb's pointer sits somewhere) are
// ignored.
bool scripted_mouse = false;

void mouse_button_cb(GLFWwindow* w, int button, int action, int mods) {
    if (!scripted_mouse) viewer_of(w)->on_mouse_button(button, action, mods);
}
void cursor_cb(GLFWwindow* w, double x, double y) {
    if (!scripted_mouse) viewer_of(w)->on_cursor_event(x, y);
}
void scroll_cb(GLFWwindow* w, double, double dy) {
    viewer_of(w)->on_scroll(dy);
}
void key_cb(GLFWwindow* w, int key, int, int action, int mods) {
    viewer_of(w)->on_key(key, action, mods);
}
void drop_cb(GLFWwindow* w, int count, const char** paths) {
    viewer_of(w)->on_drop(count, paths);
}

bool ui_wants_mouse() {
    return ImGui::GetCurrentContext() && ImGui::GetIO().WantCaptureMouse;
}
/// A panel field has the keyboard (typing, or a control being edited): keys are ImGui's alone.
bool ui_wants_keyboard() {
    if (!ImGui::GetCurrentContext()) return false;
    const ImGuiIO& io = ImGui::GetIO();
    return io.WantCaptureKeyboard || io.WantTextInput || ImGui::IsAnyItemActive();
}

double median(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

} // namespace

Viewer::Viewer(const ViewOptions& options) : options_(options) {
    // The scene first: a bad --scene or --size is reported before any window opens.
    session_ = std::make_unique<ViewSession>(options.scene, options.size, options.threads, options.substeps,
                                             options.material,
                                             SolverFlags{.solver = options.solver,
                                                         .iterations = options.iterations,
                                                         .tolerance = options.tolerance,
                                                         .integrator = {}, // the viewer has no --integrator
                                                         .strain_limit = options.strain_limit,
                                                         .fas = false, // nor --fas
                                                         .single_level = options.single_level},
                                             options.dt);
    show_ui_ = options.ui;
#if defined(__GLIBC__)
    // llvmpipe builds each frame's binned triangle data on the heap (about 20 MB at N = 200, 79,202 triangles)
    // and frees it once the frame is drawn. glibc hands a freed heap top above 128 KB back to the kernel, so
    // every frame page-faulted those pages in again: 713,182 page faults in 120 frames, 16 % of the main
    // thread's samples, and 10-12 ms of the frame in most runs (docs/viewer.md, "Drawing cost"). Keep up to
    // 256 MiB of freed heap instead: 41,610 page faults in the same run.
    mallopt(M_TRIM_THRESHOLD, 256 << 20);
#endif
    scripted_mouse = options.demo_grab;
    // The demo script acts at given frames through the session: every frame owns it there.
    interpolate_ = options.overlap && options.interpolate && !options.demo_grab;
    full_mesh_ = options.full_mesh;
    pixel_lighting_ = options.pixel_lighting;
    shading_.strain_colours = options.strain_colours;
    show_help_ = options.key_help;
    window_ = render::open_window(options.width, options.height, "drape - cloth viewer", true);
    glfwSwapInterval(options.vsync ? 1 : 0);
    gl_renderer_ = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    gl_version_ = render::gl_version_string();

    glfwSetWindowUserPointer(window_, this);
    // Installed before ImGui's, which chains to them.
    glfwSetMouseButtonCallback(window_, mouse_button_cb);
    glfwSetCursorPosCallback(window_, cursor_cb);
    glfwSetScrollCallback(window_, scroll_cb);
    glfwSetKeyCallback(window_, key_cb);
    glfwSetDropCallback(window_, drop_cb);

    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr; // no imgui.ini in the user's directory
    ImGui::StyleColorsDark();
    ImGuiStyle& style = ImGui::GetStyle();
    style.WindowRounding = 4.0f;
    style.FrameRounding = 3.0f;
    style.WindowBorderSize = 0.0f;
    ImGui_ImplGlfw_InitForOpenGL(window_, true);
    ImGui_ImplOpenGL3_Init("#version 450 core");
    imgui_ready_ = true;

    if (options.start_paused) session_->set_running(false);
    sync_gpu();
    glfwGetCursorPos(window_, &cursor_x_, &cursor_y_);
    window_start_ = clock_type::now();
}

Viewer::~Viewer() {
    // GPU objects first, while the context lives.
    renderer_.reset();
    stage_.reset();
    colliders_.reset();
    if (imgui_ready_) {
        ImGui_ImplOpenGL3_Shutdown();
        ImGui_ImplGlfw_Shutdown();
        ImGui::DestroyContext();
    }
    render::close_window(window_);
}

float Viewer::aspect() const {
    int w = 1, h = 1;
    glfwGetFramebufferSize(window_, &w, &h);
    return h > 0 ? float(w) / float(h) : 1.0f;
}

float Viewer::panel_width() const {
    return show_ui_ ? 348.0f : 0.0f;
}

Eigen::Matrix4f Viewer::view_projection() const {
    // The scene is centred in the part of the window right of the panel column: the projection is shifted in
    // x by that column's width (in NDC units) and its aspect is that of the free area. Picking unprojects
    // through the same matrix, so it stays exact.
    int w = 1, h = 1;
    glfwGetWindowSize(window_, &w, &h);
    const float panel = std::min(panel_width(), 0.5f * float(w));
    const float free_aspect = float(std::max(w - static_cast<int>(panel), 1)) / float(std::max(h, 1));
    Eigen::Matrix4f shift = Eigen::Matrix4f::Identity();
    shift(0, 3) = panel / float(std::max(w, 1));
    // Keep the horizontal scale of the free area: x_ndc spans the free width, i.e. (w - panel) / w of the
    // window.
    shift(0, 0) = float(std::max(w - static_cast<int>(panel), 1)) / float(std::max(w, 1));
    return shift * camera_.projection(free_aspect) * camera_.view();
}

void Viewer::reset_camera() {
    // Frame the scene's box: the cloth where it starts and the colliders; a cloth pinned along one edge is
    // framed where it will hang (ViewSession::frame_lo). Seen from the front, right and a little above.
    camera_.yaw = 0.62f;
    camera_.pitch = 0.30f;
    camera_.fov_y_deg = 40.0f;
    const SimulationParams& p = session_->sim().params();
    if (p.aero.enabled && std::hypot(p.aero.velocity[0], p.aero.velocity[2]) > 0.0f) {
        // A flag flies downwind from its pole, in the vertical plane along the wind: look at that plane from
        // the side, a little from downwind and above.
        const float wind_yaw = std::atan2(p.aero.velocity[0], p.aero.velocity[2]);
        camera_.yaw = wind_yaw + 1.3f;
        camera_.pitch = 0.2f;
    }
    if (options_.camera_yaw_deg) {
        camera_.yaw = *options_.camera_yaw_deg * 3.14159265f / 180.0f;
        camera_.pitch = 0.15f;
    }
    int w = 1, h = 1;
    glfwGetWindowSize(window_, &w, &h);
    const float free_aspect = float(std::max(w - static_cast<int>(panel_width()), 1)) / float(std::max(h, 1));
    const auto lo = session_->frame_lo(), hi = session_->frame_hi();
    camera_.frame(Eigen::Vector3f(lo[0], lo[1], lo[2]), Eigen::Vector3f(hi[0], hi[1], hi[2]), free_aspect);
    camera_.distance *= 0.85f; // the bounding sphere is loose around a sheet
}

void Viewer::sync_gpu() {
    if (session_->generation() != gpu_generation_ || full_mesh_ != gpu_full_mesh_) {
        // A new cloth: new ring, index buffer and markers. Wait for the GPU to let go of the old buffers
        // first.
        glFinish();
        renderer_.reset();
        const Simulation& sim = session_->sim();
        const std::uint32_t columns = sim.cloth().grid ? sim.cloth().grid->columns : 0;
        const std::uint32_t rows = sim.cloth().grid ? sim.cloth().grid->rows : 0;
        const std::size_t n = sim.cloth().particle_count;
        const StateBuffer& state = sim.state();
        renderer_ = std::make_unique<render::ClothRenderer>(
            sim.cloth().triangles, n, session_->publisher().plane_floats(), columns, rows, full_mesh_,
            std::span<const float>(state.x.data(), n), std::span<const float>(state.y.data(), n),
            std::span<const float>(state.z.data(), n));
        gpu_full_mesh_ = full_mesh_;
        gpu_generation_ = session_->generation();
        gpu_markers_ = 0;
        hover_ = shown_hover_ = shown_grab_ = no_particle;
        if (drag_ == Drag::grab) drag_ = Drag::none;
        ui_size_ = static_cast<int>(session_->size());
        ui_node_mass_ = session_->fabric().node_mass_g;
    }
    if (session_->scene_generation() != gpu_scene_) {
        // A new scene: ground at its plane (or below what is framed), colliders, camera.
        const auto lo = session_->frame_lo(), hi = session_->frame_hi();
        const float extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2], 0.1f});
        const float ground = session_->ground_height().value_or(lo[1] - 0.2f * extent);
        const float spacing = std::pow(10.0f, std::round(std::log10(0.1f * extent)));
        stage_ = std::make_unique<render::Stage>(ground, 0.5f * (lo[0] + hi[0]), 0.5f * (lo[2] + hi[2]),
                                                 2.5f * extent, spacing);
        colliders_ = std::make_unique<render::ColliderRenderer>(session_->sim().params().colliders);
        gpu_scene_ = session_->scene_generation();
        reset_camera();
        // The point light: on the side the default view looks from and above, at about the scene's size (for
        // hang: in front, to the right and above).
        shading_.light_position = {0.5f * (lo[0] + hi[0]) + 1.5f * extent * std::sin(camera_.yaw),
                                   0.5f * (lo[1] + hi[1]) + 1.0f * extent,
                                   0.5f * (lo[2] + hi[2]) + 1.5f * extent * std::cos(camera_.yaw)};
    }
    const std::size_t grabbed = session_->sim().grabbed();
    // Automated runs (--frames) show no hover marker: Xvfb's pointer sits wherever it is.
    const bool markers = session_->show_markers();
    const std::size_t hover = markers && options_.frames == 0 ? hover_ : no_particle;
    if (session_->markers_version() != gpu_markers_ || grabbed != shown_grab_ || hover != shown_hover_) {
        static const std::vector<std::uint32_t> none;
        renderer_->set_markers(markers ? session_->pinned() : none, markers ? grabbed : no_particle, hover);
        gpu_markers_ = session_->markers_version();
        shown_grab_ = grabbed;
        shown_hover_ = hover;
    }
}

Ray Viewer::cursor_ray(double x, double y) const {
    int w = 1, h = 1;
    glfwGetWindowSize(window_, &w, &h);
    const Eigen::Vector2f ndc = window_to_ndc(x, y, w, h);
    return ray_from_ndc(view_projection().inverse(), ndc.x(), ndc.y());
}

PickHit Viewer::pick_at(double x, double y) const {
    const Simulation& sim = session_->sim();
    // Each particle is a sphere of 0.6 grid spacings: neighbouring spheres overlap, so the whole cloth is
    // pickable.
    return pick_particle(cursor_ray(x, y), sim.x(), sim.y(), sim.z(), 0.6f * session_->spacing());
}

void Viewer::start_grab(const PickHit& hit, double x, double y) {
    const Simulation& sim = session_->sim();
    const std::size_t i = hit.index;
    const Eigen::Vector3f p(sim.x()[i], sim.y()[i], sim.z()[i]);
    grab_depth_ = view_depth(p, camera_.eye(), camera_.forward());
    session_->grab(i, {p.x(), p.y(), p.z()});
    drag_ = Drag::grab;
    cursor_x_ = x;
    cursor_y_ = y;
}

void Viewer::on_mouse_button(int button, int action, int mods) {
    // Queued: whether a press belongs to a panel is decided after ImGui::NewFrame() (handle_input_events).
    if (action == GLFW_PRESS || action == GLFW_RELEASE) pending_mouse_.push_back({button, action, mods});
}

void Viewer::on_cursor_event(double x, double y) {
    // A move after a queued button waits behind it: a press, a drag and a release that all arrive in one poll (a
    // frame that waited for a long step) still orbit, pan or grab, from where the press was.
    if (pending_mouse_.empty())
        on_cursor(x, y);
    else
        pending_mouse_.push_back({0, cursor_moved_to, 0, x, y});
}

void Viewer::handle_input_events() {
    for (const InputEvent& e : pending_mouse_) {
        if (e.action == cursor_moved_to) {
            on_cursor(e.x, e.y);
            continue;
        }
        const int bit = 1 << std::clamp(e.code, 0, 15);
        if (e.action == GLFW_PRESS) {
            // The first button down decides who owns the drag until every button is up: a slider dragged past
            // the panel's edge stays the slider's, an orbit dragged over a panel stays the camera's.
            if (buttons_down_ == 0) ui_owns_press_ = ui_wants_mouse();
            buttons_down_ |= bit;
            if (!ui_owns_press_) scene_press(e.code, e.mods);
        } else {
            const bool was_down = (buttons_down_ & bit) != 0;
            buttons_down_ &= ~bit;
            if (was_down && !ui_owns_press_) scene_release(e.code);
            if (buttons_down_ == 0) ui_owns_press_ = false;
        }
    }
    pending_mouse_.clear();
    for (const InputEvent& e : pending_keys_) {
        if (e.code == GLFW_KEY_F1 && e.action == GLFW_PRESS) {
            show_help_ = !show_help_;
            continue;
        }
        if (e.code == GLFW_KEY_F12 && e.action == GLFW_PRESS) {
            handle_key(e.code, e.mods); // a screenshot, also of a dialog
            continue;
        }
        if (e.code == GLFW_KEY_Q && (e.mods & GLFW_MOD_CONTROL)) {
            glfwSetWindowShouldClose(window_, GLFW_TRUE); // Ctrl+Q quits from anywhere, a field too
            continue;
        }
        // A field being edited has the keyboard: Backspace there deletes a digit, never resets the cloth.
        if (ui_wants_keyboard()) continue;
        if (e.action == GLFW_REPEAT && e.code != GLFW_KEY_N) continue;
        handle_key(e.code, e.mods);
    }
    pending_keys_.clear();
}

void Viewer::scene_press(int button, int mods) {
    const double x = cursor_x_, y = cursor_y_;
    if (button == GLFW_MOUSE_BUTTON_LEFT && !(mods & GLFW_MOD_SHIFT)) {
        const PickHit hit = pick_at(x, y);
        if (hit.hit() && (mods & GLFW_MOD_CONTROL)) {
            session_->toggle_pin(hit.index); // Ctrl+click: pin / unpin
            return;
        }
        if (hit.hit()) {
            start_grab(hit, x, y);
            return;
        }
        drag_ = Drag::orbit;
    } else if (button == GLFW_MOUSE_BUTTON_LEFT || button == GLFW_MOUSE_BUTTON_RIGHT ||
               button == GLFW_MOUSE_BUTTON_MIDDLE) {
        drag_ = Drag::pan;
    }
}

void Viewer::scene_release(int button) {
    if (drag_ == Drag::grab && button == GLFW_MOUSE_BUTTON_LEFT) session_->release_grab();
    drag_ = Drag::none;
}

void Viewer::on_cursor(double x, double y) {
    const double dx = x - cursor_x_, dy = y - cursor_y_;
    cursor_x_ = x;
    cursor_y_ = y;
    cursor_moved_ = true;
    int w = 1, h = 1;
    glfwGetWindowSize(window_, &w, &h);
    switch (drag_) {
    case Drag::orbit:
        camera_.orbit(float(-dx) * 0.006f, float(dy) * 0.006f);
        break;
    case Drag::pan:
        camera_.pan(float(-dx) / float(std::max(h, 1)), float(dy) / float(std::max(h, 1)));
        break;
    case Drag::grab:
        if (step_running_) {
            grab_move_deferred_ = true; // the step owns the simulation: moved once it has ended
        } else if (session_->sim().grabbed() == SIZE_MAX) {
            drag_ = Drag::none; // pinned with P: the mouse is free again
        } else {
            const Eigen::Vector3f t =
                point_at_depth(cursor_ray(x, y), camera_.eye(), camera_.forward(), grab_depth_);
            session_->move_grab({t.x(), t.y(), t.z()});
        }
        break;
    case Drag::none:
        break;
    }
}

void Viewer::on_scroll(double dy) {
    if (ui_wants_mouse()) return;
    camera_.zoom(std::pow(0.88f, float(dy)));
}

void Viewer::on_key(int key, int action, int mods) {
    // Queued like the mouse buttons: ImGui's keyboard flags are known after NewFrame.
    if (action == GLFW_PRESS || action == GLFW_REPEAT) pending_keys_.push_back({key, action, mods});
}

void Viewer::on_drop(int count, const char** paths) {
    // Opened by the next frame that owns the session (apply_deferred_input): a step may be running now.
    for (int i = 0; i < count; ++i) dropped_.emplace_back(paths[i]);
}

void Viewer::handle_key(int key, int mods) {
    switch (key) {
    case GLFW_KEY_SPACE:
        session_->set_running(!session_->running());
        break;
    case GLFW_KEY_N:
        session_->step_once();
        break;
    case GLFW_KEY_BACKSPACE:
        if (mods == 0) session_->reset();
        break;
    case GLFW_KEY_Z:
        if ((mods & GLFW_MOD_CONTROL) && (mods & GLFW_MOD_SHIFT))
            session_->redo();
        else if (mods & GLFW_MOD_CONTROL)
            session_->undo();
        break;
    case GLFW_KEY_Y:
        if (mods & GLFW_MOD_CONTROL) session_->redo();
        break;
    case GLFW_KEY_R:
    case GLFW_KEY_HOME:
        reset_camera();
        break;
    case GLFW_KEY_P:
        if (session_->sim().grabbed() != SIZE_MAX) {
            session_->pin_grabbed();
            drag_ = Drag::none;
        } else {
            const PickHit hit = pick_at(cursor_x_, cursor_y_);
            if (hit.hit()) session_->toggle_pin(hit.index);
        }
        break;
    case GLFW_KEY_TAB:
        show_ui_ = !show_ui_;
        break;
    case GLFW_KEY_G:
        show_ground_ = !show_ground_;
        break;
    case GLFW_KEY_ESCAPE:
        if (show_help_)
            show_help_ = false;
        else if (drag_ == Drag::grab) {
            session_->release_grab();
            drag_ = Drag::none;
        }
        break;
    case GLFW_KEY_F12: {
        char name[64];
        std::snprintf(name, sizeof name, "drape_%lld.png", static_cast<long long>(std::time(nullptr)));
        pending_screenshot_ = name;
        break;
    }
    case GLFW_KEY_Q:
        if (mods & GLFW_MOD_CONTROL) glfwSetWindowShouldClose(window_, GLFW_TRUE);
        break;
    default:
        tools_key(key);
        break;
    }
}

void Viewer::frame_input(double wall_dt) {
    // Held keys: orbit with the arrows, zoom with W/S, pan with A/D (sideways) and Q/E (down/up).
    if (ui_wants_keyboard()) return;
    const float step = static_cast<float>(std::min(wall_dt, 0.1));
    auto down = [&](int key) { return glfwGetKey(window_, key) == GLFW_PRESS; };
    if (glfwGetKey(window_, GLFW_KEY_LEFT_CONTROL) == GLFW_PRESS) return;
    const float orbit = 1.6f * step, pan = 0.5f * step, zoom = std::pow(0.35f, step);
    if (down(GLFW_KEY_LEFT)) camera_.orbit(orbit, 0.0f);
    if (down(GLFW_KEY_RIGHT)) camera_.orbit(-orbit, 0.0f);
    if (down(GLFW_KEY_UP)) camera_.orbit(0.0f, orbit);
    if (down(GLFW_KEY_DOWN)) camera_.orbit(0.0f, -orbit);
    if (down(GLFW_KEY_W)) camera_.zoom(zoom);
    if (down(GLFW_KEY_S)) camera_.zoom(1.0f / zoom);
    if (down(GLFW_KEY_A)) camera_.pan(-pan, 0.0f);
    if (down(GLFW_KEY_D)) camera_.pan(pan, 0.0f);
    if (down(GLFW_KEY_Q)) camera_.pan(0.0f, -pan);
    if (down(GLFW_KEY_E)) camera_.pan(0.0f, pan);
}

void Viewer::update_hover() {
    // Hover marker: what a click would grab. Picking scans every particle, so it runs only when the cursor
    // moved.
    if (!cursor_moved_ || drag_ != Drag::none) return;
    cursor_moved_ = false;
    if (ui_wants_mouse()) {
        hover_ = no_particle;
        return;
    }
    hover_ = pick_at(cursor_x_, cursor_y_).index;
}

void Viewer::run_demo_script() {
    // --demo-grab: half-way through --frames, press on the free corner (N-1, N-1) through the real picking
    // path, drag it up and a little to the right over 60 frames, and hold it there until the end.
    if (!options_.demo_grab || options_.frames == 0 || !session_->grid_scene()) return;
    const std::uint64_t grab_frame = options_.frames / 2, drag_frames = 60;
    const std::uint64_t f = frame_index_;
    if (f < grab_frame) return;
    int w = 1, h = 1;
    glfwGetWindowSize(window_, &w, &h);
    static double start_x = 0.0, start_y = 0.0;
    if (f == grab_frame) {
        const Simulation& sim = session_->sim();
        const std::size_t n = session_->size();
        const auto last = static_cast<std::uint32_t>(n - 1);
        const std::size_t corner = grid_index(static_cast<std::uint32_t>(n), last, last);
        const Eigen::Vector4f clip =
            view_projection() * Eigen::Vector4f(sim.x()[corner], sim.y()[corner], sim.z()[corner], 1.0f);
        start_x = (clip.x() / clip.w() + 1.0) * 0.5 * w;
        start_y = (1.0 - clip.y() / clip.w()) * 0.5 * h;
        on_cursor(start_x, start_y);
        drag_ = Drag::none;
        const PickHit hit = pick_at(start_x, start_y);
        if (hit.hit()) start_grab(hit, start_x, start_y);
        std::fprintf(stderr, "demo-grab: corner %zu at pixel (%.0f, %.0f) -> picked %zu\n", corner, start_x,
                     start_y, hit.index);
        return;
    }
    const double t = std::min(1.0, double(f - grab_frame) / double(drag_frames));
    const double s = t * t * (3.0 - 2.0 * t); // smooth start and stop
    on_cursor(start_x + s * 0.06 * w, start_y - s * 0.22 * h);
}

void Viewer::draw_scene() {
    int fw = 1, fh = 1;
    glfwGetFramebufferSize(window_, &fw, &fh);
    glViewport(0, 0, fw, fh);
    const Eigen::Matrix4f vp = view_projection();
    stage_->draw_background();
    glEnable(GL_DEPTH_TEST);
    colliders_->draw(vp, camera_.eye(), shading_.light_position);
    // Pixels per metre at the camera's target: the screen scale that decides per-vertex or per-pixel lighting.
    const float ppm = float(fh) / camera_.visible_height();
    renderer_->draw_cloth(vp, camera_.eye(), shading_, ppm, pixel_lighting_);
    if (show_ground_) stage_->draw_ground(vp, camera_.eye());
    int ww = 1, wh = 1;
    glfwGetWindowSize(window_, &ww, &wh);
    renderer_->draw_markers(vp, float(fw) / float(std::max(ww, 1)));
    renderer_->end_frame(); // fence: the GPU is done with this region once these draws complete
}

void Viewer::save_screenshot(const std::string& path) {
    int fw = 1, fh = 1;
    glfwGetFramebufferSize(window_, &fw, &fh);
    try {
        render::save_screenshot_png(path, fw, fh);
    } catch (const std::runtime_error& e) {
        // Not fatal in the window (a message); the exit code says so (exit_code::write_failed).
        std::fprintf(stderr, "drape view: %s\n", e.what());
        session_->post(MessageLevel::error, e.what());
        write_failed_ = true;
        return;
    }
    std::fprintf(stderr, "drape view: saved %s (%d x %d)\n", path.c_str(), fw, fh);
}

void Viewer::note_session_error() {
    if (session_->error().empty()) return;
    had_error_ = true;
    failure_code_ = session_->error_code();
    if (session_->error() != reported_error_) {
        // Said on stderr too (automation reads it; the window shows a banner).
        reported_error_ = session_->error();
        std::fprintf(stderr, "drape view: %s: %s\n",
                     failure_code_ == exit_code::blow_up ? "the cloth exploded" : "simulation stopped",
                     reported_error_.c_str());
    }
}

bool Viewer::may_draw_beside_step(bool last_frame) const {
    if (!(interpolate_ && step_running_ && !last_frame && !session_->step_ready() && pending_mouse_.empty() &&
          pending_keys_.empty() && !grab_move_deferred_ && dropped_.empty() &&
          session_->generation() == interpolator_generation_))
        return false;
    // A step due to end within half a blended frame's drawing is waited for: drawing a frame beside it would leave
    // the simulation idle from its end until that frame hands it over (at N = 200, steps about as long as a frame,
    // 0.71x real time against 1.0x waiting).
    const double remaining = step_ms_mean_ - ms_since(step_started_);
    return remaining > 0.5 * blend_draw_ms_;
}

void Viewer::apply_deferred_input() {
    if (std::exchange(grab_move_deferred_, false) && drag_ == Drag::grab) on_cursor(cursor_x_, cursor_y_);
    if (!dropped_.empty()) {
        const std::vector<std::string> paths = std::exchange(dropped_, {});
        for (const std::string& path : paths)
            if (path.size() >= 5 && path.compare(path.size() - 5, 5, ".json") == 0) {
                std::snprintf(scene_path_.data(), scene_path_.size(), "%s", path.c_str());
                session_->set_scene(path);
                return;
            }
        session_->post(MessageLevel::warning, "dropped files: none ends in .json (scene files are JSON)");
    }
}

void Viewer::start_step() {
    step_running_ = session_->start_step();
    if (step_running_) step_started_ = clock_type::now();
}

bool Viewer::take_step(FrameTimes& t) {
    const auto w0 = clock_type::now();
    last_substeps_ = session_->finish_step();
    t.sim_wait += ms_since(w0);
    t.sim = session_->last_step_ms();
    t.took_step = true;
    step_ms_mean_ = step_ms_mean_ > 0.0 ? step_ms_mean_ + 0.25 * (t.sim - step_ms_mean_) : t.sim;
    step_running_ = false;
    note_session_error();
    if (last_substeps_ == 0) return false;
    t.sim_advanced += double(last_substeps_) * double(session_->sim().params().dt);
    return true;
}

void Viewer::hand_over_step(FrameTimes& t) {
    if (!interpolate_ || !step_running_ || !session_->step_ready() || !take_step(t) || !session_->error().empty())
        return;
    const auto t0 = clock_type::now();
    const std::span<float> state = interpolator_.arrival();
    last_publish_ = session_->publish(state);
    if (last_publish_.finite) {
        publish_strain(state);
        session_->note_published_strain(last_publish_.max_structural_strain);
        start_step();
    } // else the next frame owns the session (no step runs) and says so
    t.publish += ms_since(t0);
}

bool Viewer::session_frame(FrameTimes& t, bool last_frame) {
    // The step started while the last frame was drawn ends before input, panels or picking touch the session.
    bool stepped = step_running_ && take_step(t);
    apply_deferred_input();
    run_demo_script();

    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    // ImGui 1.86 reads the keys' state, not their events: a key pressed and released within one poll (fast
    // typing, xdotool) would never be seen down, and a lost Enter leaves a field in text-edit mode. Such keys
    // are held down for this frame.
    ImGuiIO& io = ImGui::GetIO();
    std::vector<int> held;
    for (const InputEvent& e : pending_keys_)
        if (e.code >= 0 && e.code < static_cast<int>(IM_ARRAYSIZE(io.KeysDown)) && !io.KeysDown[e.code]) {
            io.KeysDown[e.code] = true;
            held.push_back(e.code);
        }
    ImGui::NewFrame();
    handle_input_events();
    frame_input(last_.frame > 0.0 ? last_.frame * 1e-3 : 1.0 / 60.0);
    build_ui(); // panel changes apply to the session right here, within this frame
    if (!ImGui::IsAnyItemActive()) session_->end_edit(); // the next change is a new undo entry
    for (int key : held)
        io.KeysDown[key] = glfwGetKey(window_, key) == GLFW_PRESS;

    // 1. Simulate: here (the last frame, or --no-overlap: the frame shows this step), or on a thread of its own
    // once this frame's state is published (below), while the frame is drawn.
    const bool overlap = options_.overlap && !last_frame;
    auto t0 = clock_type::now();
    built_this_frame_ = session_->building();
    if (!overlap) {
        last_substeps_ = session_->advance();
        t.sim = ms_since(t0);
        t.took_step = true;
        stepped = stepped || last_substeps_ > 0;
        note_session_error();
    }
    if (!overlap && last_substeps_ > 0)
        t.sim_advanced += double(last_substeps_) * double(session_->sim().params().dt);
    sync_gpu();
    update_hover();
    sync_gpu();

    // 2. Publish: positions + normals straight into the mapped region; with interpolation into the newest of its
    // two states, and the region gets their blend (alpha 1 while steps end every frame).
    std::span<float> region = renderer_->begin_frame(&t.wait);
    t0 = clock_type::now();
    if (interpolate_) {
        if (interpolator_.floats() != region.size() || interpolator_generation_ != session_->generation()) {
            interpolator_.resize(region.size()); // a new cloth: nothing to blend from
            interpolator_generation_ = session_->generation();
            stepped = false;
        }
        const std::span<float> state = stepped ? interpolator_.arrival() : interpolator_.snap();
        last_publish_ = session_->publish(state);
        if (last_publish_.finite) publish_strain(state);
        interpolator_.write(region);
    } else {
        last_publish_ = session_->publish(region);
        if (last_publish_.finite) publish_strain(region);
    }
    if (last_publish_.finite) session_->note_published_strain(last_publish_.max_structural_strain);
    t.publish = ms_since(t0);
    if (!last_publish_.finite) {
        // Cannot happen after a finite step (the core checks); never draw garbage if it does.
        session_->set_running(false);
        session_->post(MessageLevel::error, "non-finite vertex data; drawing paused - press Backspace to reset");
        if (!had_error_) std::fprintf(stderr, "drape view: non-finite vertex data; drawing paused\n");
        had_error_ = true;
        failure_code_ = exit_code::non_finite;
    }
    if (overlap && last_publish_.finite) start_step();
    return last_publish_.finite && session_->error().empty();
}

int Viewer::run() {
    auto last_swap = clock_type::now();
    const std::string final_screenshot = options_.screenshot;
    while (!glfwWindowShouldClose(window_)) {
        FrameTimes t;
        // Input first: the callbacks move the camera at once and queue what touches the session (buttons, keys, a
        // grab's cursor, dropped files) for a frame that owns it.
        glfwPollEvents();
        const bool last_frame = options_.frames > 0 && frame_index_ + 1 >= options_.frames;
        bool drawn = true;
        auto frame_start = clock_type::now();
        if (may_draw_beside_step(last_frame)) {
            // Paced to --blend-fps: a frame drawn sooner takes the cores from the step (llvmpipe draws on them too).
            // The wait ends early when the step ends, so the next one starts at once.
            // The swaps are paced: the frame starts its drawing that long before it is due (a running mean).
            const double lead_ms = std::max(0.0, 1000.0 / double(options_.blend_fps) - blend_draw_ms_);
            const auto due = last_swap + std::chrono::duration_cast<clock_type::duration>(
                                             std::chrono::duration<double, std::milli>(lead_ms));
            while (clock_type::now() < due && !session_->step_ready())
                std::this_thread::sleep_for(std::chrono::microseconds(500));
        }
        if (may_draw_beside_step(last_frame)) {
            frame_start = clock_type::now();
            // The step runs on (longer than a frame): draw the blend of the last two states it produced, with the
            // panels as the last frame built them. Nothing here touches the session's simulation.
            t.interpolated = true;
            ++interpolated_frames_;
            frame_input(last_.frame > 0.0 ? last_.frame * 1e-3 : 1.0 / 60.0);
            std::span<float> region = renderer_->begin_frame(&t.wait);
            const auto t0 = clock_type::now();
            interpolator_.write(region);
            t.publish = ms_since(t0);
            drawn = last_publish_.finite && session_->error().empty();
        } else {
            built_this_frame_ = false;
            drawn = session_frame(t, last_frame);
        }

        // 3. Draw. A simulation stopped on an error is not drawn (an explosion would fill the window): the
        // banner says what happened.
        const auto t0 = clock_type::now();
        if (drawn) {
            draw_scene();
        } else {
            renderer_->end_frame();
            stage_->draw_background();
        }
        if (!t.interpolated) ImGui::Render();
        if (ImDrawData* ui = ImGui::GetDrawData()) ImGui_ImplOpenGL3_RenderDrawData(ui);
        // A step that ended while this frame was drawn: take it and start the next before the swap (where llvmpipe
        // rasterises for a good part of the frame), so the simulation does not wait for the frame.
        if (t.interpolated) hand_over_step(t);
        if (!pending_screenshot_.empty()) {
            save_screenshot(pending_screenshot_);
            pending_screenshot_.clear();
        }
        if (last_frame && !final_screenshot.empty()) save_screenshot(final_screenshot);
        record_frame();
        const auto swap_start = clock_type::now();
        glfwSwapBuffers(window_);
        const auto now = clock_type::now();
        t.swap = std::chrono::duration<double, std::milli>(now - swap_start).count();
        t.draw = std::chrono::duration<double, std::milli>(now - t0).count() + t.wait;
        t.frame = std::chrono::duration<double, std::milli>(now - last_swap).count();
        if (t.interpolated) blend_draw_ms_ += 0.25 * (ms_since(frame_start) - blend_draw_ms_);
        last_swap = now;
        last_ = t;
        if (samples_.size() < 1'000'000) samples_.push_back(t);
        if (!t.interpolated && session_->building()) {
            // Responsiveness while a cloth is built in the background.
            ++building_frames_;
            building_ms_ += t.frame;
            building_max_ms_ = std::max(building_max_ms_, t.frame);
        } else if (built_this_frame_) {
            install_frame_ms_ = t.frame; // the frame that swapped the new cloth in (and simulated it once)
        }

        // Overlay figures: averages over ~0.5 s.
        window_sum_.sim += t.sim;
        window_sum_.sim_wait += t.sim_wait;
        window_sum_.publish += t.publish;
        window_sum_.draw += t.draw;
        window_sum_.wait += t.wait;
        window_sum_.swap += t.swap;
        window_sum_.frame += t.frame;
        window_sum_.sim_advanced += t.sim_advanced;
        // Every frame of the window simulating (stepped or drawn beside a step): a real-time factor worth a hint.
        window_steady_ = window_steady_ && (t.interpolated || t.sim_advanced > 0.0);
        ++window_frames_;
        window_took_ += t.took_step ? 1 : 0;
        const double window_ms = ms_since(window_start_);
        if (window_ms >= 500.0 || frame_index_ < 2) {
            const double n = window_frames_;
            // The step's time and the wait for it: over the frames that took a step (not those drawn beside one).
            const double stepped = std::max(1, window_took_);
            shown_.sim = window_sum_.sim / stepped;
            shown_.sim_wait = window_sum_.sim_wait / stepped;
            shown_.publish = window_sum_.publish / n;
            shown_.draw = window_sum_.draw / n;
            shown_.wait = window_sum_.wait / n;
            shown_.swap = window_sum_.swap / n;
            shown_.frame = window_sum_.frame / n;
            shown_fps_ = 1000.0 * n / std::max(window_ms, 1e-3);
            // Simulated seconds per wall second: what the steps that ended in the window advanced over its frames.
            shown_real_time_ = window_sum_.frame > 0.0 ? window_sum_.sim_advanced / (window_sum_.frame * 1e-3) : 0.0;
            if (frame_index_ >= 2 && window_steady_) session_->note_real_time_factor(shown_real_time_);
            window_sum_ = {};
            window_frames_ = 0;
            window_took_ = 0;
            window_steady_ = true;
            window_start_ = clock_type::now();
        }
        ++frame_index_;
        if (last_frame) break;
    }
    if (step_running_) { // the window was closed while a step ran
        last_substeps_ = session_->finish_step();
        step_running_ = false;
        note_session_error();
    }
    if (options_.frames == 0 && !final_screenshot.empty()) {
        // Interactive run with --screenshot: the last frame drawn is still in the front buffer; redraw it
        // once.
        glfwPollEvents();
        ImGui_ImplOpenGL3_NewFrame();
        ImGui_ImplGlfw_NewFrame();
        ImGui::NewFrame();
        build_ui();
        std::span<float> region = renderer_->begin_frame();
        session_->publish(region);
        publish_strain(region);
        draw_scene();
        ImGui::Render();
        ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
        save_screenshot(final_screenshot);
    }
    const int tools_rc = finish_tools();
    if (options_.stats_json) print_stats_json();
    if (had_error_) return failure_code_ ? failure_code_ : exit_code::non_finite;
    return write_failed_ ? exit_code::write_failed : tools_rc;
}

void Viewer::print_stats_json() const {
    // Median over the frames after the first few (shader compilation, first touches of the buffers).
    const std::size_t skip = std::min<std::size_t>(10, samples_.size() / 5);
    std::vector<double> frame, sim, sim_wait, publish, draw, wait, swap;
    double frames_ms = 0.0, simulated = 0.0;
    for (std::size_t i = skip; i < samples_.size(); ++i) {
        frame.push_back(samples_[i].frame);
        frames_ms += samples_[i].frame;
        simulated += samples_[i].sim_advanced;
        if (samples_[i].took_step) { // frames drawn beside a running step that did not end in them: no step
            sim.push_back(samples_[i].sim);
            sim_wait.push_back(samples_[i].sim_wait);
        }
        publish.push_back(samples_[i].publish);
        draw.push_back(samples_[i].draw);
        wait.push_back(samples_[i].wait);
        swap.push_back(samples_[i].swap);
    }
    const double frame_ms = median(frame);
    const Simulation& s = session_->sim();
    nlohmann::ordered_json j;
    j["fps"] = frame_ms > 0.0 ? 1000.0 / frame_ms : 0.0;
    // sim: the step's own time; with the overlap (the default) it runs while the previous frame draws, and sim_wait
    // is what the frame waited for it.
    j["frame_ms"] = {{"sim", median(sim)},           {"sim_wait", median(sim_wait)}, {"publish", median(publish)},
                     {"draw", median(draw)},         {"fence_wait", median(wait)},   {"swap", median(swap)},
                     {"total", frame_ms}};
    j["overlap"] = options_.overlap;
    j["interpolate"] = interpolate_;
    // Frames drawn while a step ran (blending the last two states), and the running mean of frames per step.
    j["interpolated_frames"] = interpolated_frames_;
    j["frames_per_step"] = interpolator_.frames_per_step();
    j["particles"] = s.cloth().particle_count;
    j["springs"] = s.cloth().spring_count();
    j["substeps_per_frame"] = session_->substeps();
    j["threads"] = session_->threads();
    j["scene"] = options_.scene;
    if (session_->resizable()) j["n"] = session_->size(); // grid N or cells per metre; a mesh or mask cloth has none
    j["frames"] = samples_.size();
    j["frames_measured"] = frame.size();
    j["dt"] = s.params().dt;
    j["sim_seconds"] = s.time();
    // Simulated seconds per wall second: what the steps that ended in the measured frames advanced, over their wall
    // time (the overlay's figure, over the whole run).
    j["real_time_factor"] = frames_ms > 0.0 ? simulated / (frames_ms * 1e-3) : 0.0;
    j["solver"] = solver_name(s.params().solver);
    if (s.params().solver == Solver::implicit)
        j["implicit"] = {{"iterations", s.params().implicit.iterations}, // running now (the budget's)
                         {"max_iterations", session_->max_iterations()},
                         {"last_step_iterations", s.implicit_stats().iterations},
                         {"relative_residual", s.implicit_stats().relative_residual},
                         {"chebyshev_rho", s.params().implicit.chebyshev_rho},
                         {"chebyshev_rho_used", chebyshev_rho_used(s.params())},
                         {"tolerance", s.params().implicit.tolerance},
                         {"budget", session_->iteration_budget()},
                         {"budget_ms", session_->sim_budget_ms()},
                         {"fas_at_rest", s.params().implicit.fas_at_rest},
                         {"fas_last_step", s.implicit_stats().fas}};
    j["max_strain"] = last_publish_.max_structural_strain;
    j["strain_limit"] = s.params().strain_limit.ratio; // 0 = off
    // The state kept and drawn: a stopped run keeps its last finite state (finite stays true); healthy says whether
    // the simulation stopped, and error (below, only then) why; the exit code too: 3 non-finite, 4 exploded.
    j["finite"] = last_publish_.finite;
    j["healthy"] = last_publish_.finite && session_->error().empty();
    j["camera"] = {{"yaw", camera_.yaw}, {"pitch", camera_.pitch}, {"distance", camera_.distance}};
    j["stiffness"] = session_->fabric().stiffness;
    j["markers"] = session_->show_markers();
    j["undo_depth"] = session_->undo_depth();
    j["generation"] = session_->generation(); // 1 + the rebuilds installed (resets included)
    j["building"] = {{"frames", building_frames_},
                     {"seconds", building_ms_ * 1e-3},
                     {"max_frame_ms", building_max_ms_},
                     {"install_frame_ms", install_frame_ms_}};
    j["sim_steps"] = s.steps_done();
    j["publish_path"] = session_->publisher().grid_path() ? "grid-simd" : "general";
    j["strain_colours"] = shading_.strain_colours;
    j["triangles_drawn"] = renderer_->triangle_count();
    j["triangles"] = s.cloth().triangles.size() / 3;
    j["lod_stride"] = renderer_->lod_stride();
    j["lighting"] = renderer_->lit_per_vertex() ? "vertex" : "pixel";
    j["drawn_edge_px"] = renderer_->drawn_edge_px();
    j["vsync"] = options_.vsync;
    int fw = 0, fh = 0;
    glfwGetFramebufferSize(window_, &fw, &fh);
    j["framebuffer"] = {fw, fh};
    j["gl_renderer"] = gl_renderer_;
    j["gl_version"] = gl_version_;
    if (!session_->error().empty()) j["error"] = session_->error();
    std::cout << j.dump() << std::endl;
}

} // namespace drape::app
