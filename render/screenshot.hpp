// Saves the current framebuffer (the back buffer, before the swap) as a PNG with stb_image_write.
#pragma once

#include <string>

namespace drape::render {

/// Reads width x height RGB pixels of the back buffer and writes them to `path` (rows flipped so the PNG is
/// upright). Throws drape::WriteError naming the path when it cannot be written.
void save_screenshot_png(const std::string& path, int width, int height);

} // namespace drape::render
