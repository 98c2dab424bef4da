// Window and OpenGL 4.5 core context through GLFW and the glad loader generated at configure time.
// The viewer (app/) builds on this; core never includes it.
#pragma once

#include <stdexcept>
#include <string>

struct GLFWwindow;

namespace drape::render {

/// No display to open a window on (no X server / $DISPLAY). The viewer maps it to exit code 2 with an
/// xvfb-run hint.
class DisplayError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// Opens a GLFW window with an OpenGL 4.5 core context and loads the GL functions. Throws DisplayError when
/// GLFW cannot initialise (no display) and std::runtime_error naming what failed otherwise (no 4.5 context).
GLFWwindow* open_window(int width, int height, const std::string& title, bool visible = true);

/// "4.5 (Core Profile) Mesa ..." of the current context.
std::string gl_version_string();

void close_window(GLFWwindow* window);

} // namespace drape::render
