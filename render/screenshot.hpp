// Saves the current framebuffer (the back buffer, before the swap) as a PNG with stb_image_write; the two
// halves (read back, write PNG) also serve the viewer's recorder (app/frame_recorder.hpp).
#pragma once

#include <string>
#include <vector>

namespace drape::render {

/// Reads width x height RGB pixels of the back buffer into out_rgb (resized once to width * height * 3; rows
/// top first, as PNG and ffmpeg's rawvideo expect).
void read_back_rgb(int width, int height, std::vector<unsigned char>& out_rgb);

/// Writes width x height RGB pixels (rows top first) to `path` as PNG. Throws std::runtime_error naming the
/// path when it cannot be written. No OpenGL: safe on any thread.
void write_png_rgb(const std::string& path, int width, int height, const std::vector<unsigned char>& rgb);

/// Reads width x height RGB pixels of the back buffer and writes them to `path` (rows flipped so the PNG is
/// upright). Throws drape::WriteError naming the path when it cannot be written.
void save_screenshot_png(const std::string& path, int width, int height);

} // namespace drape::render
