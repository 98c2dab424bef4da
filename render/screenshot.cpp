#include "screenshot.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <vector>

#include <glad/gl.h>
#include <stb_image_write.h>

#include "drape/errors.hpp"

namespace drape::render {

void save_screenshot_png(const std::string& path, int width, int height) {
    if (width <= 0 || height <= 0) throw std::runtime_error("screenshot: empty framebuffer");
    const std::size_t row = static_cast<std::size_t>(width) * 3;
    std::vector<unsigned char> pixels(row * static_cast<std::size_t>(height));
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, pixels.data());
    // OpenGL's first row is the bottom one; PNG's is the top one.
    std::vector<unsigned char> tmp(row);
    for (int y = 0; y < height / 2; ++y) {
        unsigned char* a = pixels.data() + static_cast<std::size_t>(y) * row;
        unsigned char* b = pixels.data() + static_cast<std::size_t>(height - 1 - y) * row;
        std::memcpy(tmp.data(), a, row);
        std::memcpy(a, b, row);
        std::memcpy(b, tmp.data(), row);
    }
    errno = 0;
    if (!stbi_write_png(path.c_str(), width, height, 3, pixels.data(), static_cast<int>(row)))
        throw WriteError("cannot write the screenshot " + path +
                         (errno ? std::string(" (") + std::strerror(errno) + ")" : std::string()));
}

} // namespace drape::render
