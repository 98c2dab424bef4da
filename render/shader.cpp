#include "shader.hpp"

#include <stdexcept>
#include <string>
#include <vector>

namespace drape::render {

namespace {

std::string info_log(GLuint object, bool program) {
    GLint length = 0;
    if (program)
        glGetProgramiv(object, GL_INFO_LOG_LENGTH, &length);
    else
        glGetShaderiv(object, GL_INFO_LOG_LENGTH, &length);
    std::vector<char> log(static_cast<std::size_t>(std::max(length, 1)));
    if (program)
        glGetProgramInfoLog(object, length, nullptr, log.data());
    else
        glGetShaderInfoLog(object, length, nullptr, log.data());
    return std::string(log.data());
}

GLuint compile(GLenum type, const char* source, const char* name) {
    const GLuint s = glCreateShader(type);
    glShaderSource(s, 1, &source, nullptr);
    glCompileShader(s);
    GLint ok = 0;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        const std::string log = info_log(s, false);
        glDeleteShader(s);
        throw std::runtime_error(std::string("cannot compile the ") + name +
                                 (type == GL_VERTEX_SHADER ? " vertex" : " fragment") + " shader: " + log);
    }
    return s;
}

} // namespace

GLuint link_program(const char* vertex_source, const char* fragment_source, const char* name) {
    const GLuint vs = compile(GL_VERTEX_SHADER, vertex_source, name);
    GLuint fs = 0;
    try {
        fs = compile(GL_FRAGMENT_SHADER, fragment_source, name);
    } catch (...) {
        glDeleteShader(vs);
        throw;
    }
    const GLuint p = glCreateProgram();
    glAttachShader(p, vs);
    glAttachShader(p, fs);
    glLinkProgram(p);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        const std::string log = info_log(p, true);
        glDeleteProgram(p);
        throw std::runtime_error(std::string("cannot link the ") + name + " program: " + log);
    }
    return p;
}

} // namespace drape::render
