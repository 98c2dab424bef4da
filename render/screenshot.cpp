#include "screenshot.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <glad/gl.h>
#include <stb_image_write.h>

#include "drape/errors.hpp"

namespace drape::render {

void read_back_rgb(int width, int height, std::vector<unsigned char>& out_rgb) {
    if (width <= 0 || height <= 0) throw std::runtime_error("screenshot: empty framebuffer");
    const std::size_t row = static_cast<std::size_t>(width) * 3;
    out_rgb.resize(row * static_cast<std::size_t>(height));
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, out_rgb.data());
    // OpenGL's first row is the bottom one; PNG's is the top one.
    for (int y = 0; y < height / 2; ++y)
        std::swap_ranges(out_rgb.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y) * row),
                         out_rgb.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(y + 1) * row),
                         out_rgb.begin() +
                             static_cast<std::ptrdiff_t>(static_cast<std::size_t>(height - 1 - y) * row));
}

void write_png_rgb(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb) {
    errno = 0;
    if (!stbi_write_png(path.c_str(), width, height, 3, rgb.data(), width * 3))
        throw WriteError("cannot write the PNG " + path +
                         (errno ? std::string(" (") + std::strerror(errno) + ")" : std::string()));
}

void save_screenshot_png(const std::string& path, int width, int height) {
    std::vector<unsigned char> pixels;
    read_back_rgb(width, height, pixels);
    errno = 0;
    if (!stbi_write_png(path.c_str(), width, height, 3, pixels.data(), width * 3))
        throw WriteError("cannot write the screenshot " + path +
                         (errno ? std::string(" (") + std::strerror(errno) + ")" : std::string()));
}

} // namespace drape::render
