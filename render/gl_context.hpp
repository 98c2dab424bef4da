// Window and OpenGL 4.5 core context through GLFW and the glad loader generated at configure time.
// The viewer (app/) builds on this; core never includes it.
#pragma once

#include <string>

struct GLFWwindow;

namespace drape::render {

/// Opens a GLFW window with an OpenGL 4.5 core context and loads the GL functions. Throws std::runtime_error with
/// a message naming what failed (no display, no 4.5 context).
GLFWwindow* open_window(int width, int height, const std::string& title, bool visible = true);

/// "4.5 (Core Profile) Mesa ..." of the current context.
std::string gl_version_string();

void close_window(GLFWwindow* window);

} // namespace drape::render
