#include "gl_context.hpp"

#include <stdexcept>

#include <glad/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

namespace drape::render {

namespace {
std::string last_glfw_error;
void on_glfw_error(int code, const char* text) {
    last_glfw_error = std::to_string(code) + ": " + text;
}
} // namespace

GLFWwindow* open_window(int width, int height, const std::string& title, bool visible) {
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit())
        throw DisplayError("cannot initialise GLFW (no display? run under xvfb-run -a): " + last_glfw_error);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
    GLFWwindow* window = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (!window) {
        glfwTerminate();
        throw std::runtime_error("cannot create an OpenGL 4.5 core window: " + last_glfw_error);
    }
    glfwMakeContextCurrent(window);
    if (!gladLoadGL(glfwGetProcAddress)) {
        glfwDestroyWindow(window);
        glfwTerminate();
        throw std::runtime_error("cannot load OpenGL 4.5 functions through glad");
    }
    return window;
}

std::string gl_version_string() {
    const auto* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    return v ? v : "unknown";
}

void close_window(GLFWwindow* window) {
    if (window) glfwDestroyWindow(window);
    glfwTerminate();
}

} // namespace drape::render
