// GLSL program helpers: compile and link with the driver's log in the error message.
#pragma once

#include <utility>

#include <glad/gl.h>

namespace drape::render {

/// Compiles and links a vertex + fragment program. Throws std::runtime_error with the info log on failure.
GLuint link_program(const char* vertex_source, const char* fragment_source, const char* name);

/// Owns one GL program name.
class Program {
  public:
    Program() = default;
    Program(const char* vertex_source, const char* fragment_source, const char* name)
        : id_(link_program(vertex_source, fragment_source, name)) {}
    Program(const Program&) = delete;
    Program& operator=(const Program&) = delete;
    Program(Program&& other) noexcept : id_(other.id_) { other.id_ = 0; }
    Program& operator=(Program&& other) noexcept {
        std::swap(id_, other.id_);
        return *this;
    }
    ~Program() {
        if (id_) glDeleteProgram(id_);
    }
    GLuint id() const noexcept { return id_; }
    GLint uniform(const char* name) const { return glGetUniformLocation(id_, name); }

  private:
    GLuint id_ = 0;
};

} // namespace drape::render
