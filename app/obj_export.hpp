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

class ObjExporter {
  public:
    /// Creates `directory` if needed; throws InvalidInput if it cannot be created or written.
    ObjExporter(const Cloth& cloth, std::string directory);
    /// Writes <directory>/frame_<index, 5 digits>.obj for the current state; returns its path.
    std::string write(const Simulation& sim, std::size_t index);

  private:
    std::string directory_;
    std::unique_ptr<Publisher> publisher_;
    std::vector<float> planes_; ///< scratch for the publisher's output (sized once)
    std::vector<std::uint32_t> triangles_;
};

} // namespace drape::app
