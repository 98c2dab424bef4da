// Wavefront OBJ frames of a simulation (positions, area-weighted normals, triangles): what Blender and other tools
// import. One file per frame.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "drape/publish.hpp"
#include "drape/simulation.hpp"

namespace drape::app {

/// Writes the simulation's current state as one OBJ file at `path` (positions, area-weighted normals from
/// `publisher`, triangles); `scratch` receives the publisher's planes (resized to fit). Throws InvalidInput
/// naming the path when it cannot be written.
void write_obj_file(const std::string& path, const Simulation& sim, Publisher& publisher,
                    std::vector<float>& scratch, std::size_t frame_index = 0);

class ObjExporter {
  public:
    /// Creates `directory` if needed; throws WriteError if it cannot be created or read. Frames already in it
    /// (frame_<digits>.obj) are refused with InvalidInput, or removed first with `overwrite` (WriteError if one
    /// cannot be); other files are never touched.
    ObjExporter(const Cloth& cloth, std::string directory, bool overwrite = false);
    /// Writes <directory>/frame_<index, 5 digits>.obj for the current state; returns its path.
    std::string write(const Simulation& sim, std::size_t index);

  private:
    std::string directory_;
    std::unique_ptr<Publisher> publisher_;
    std::vector<float> planes_; ///< scratch for the publisher's output (sized once)
};

} // namespace drape::app
