// Cloth from an arbitrary triangle mesh (scene files: cloth.type = "mesh"). An OBJ file is read with tinyobjloader
// (polygons triangulated by it) and cleaned for a cloth:
//   - vertex coordinates must be finite numbers (checked per line, before tinyobjloader parses them);
//   - face indices must name existing vertices (1-based, or negative = relative, as OBJ defines them);
//   - vertices at exactly the same position are welded into one particle (OBJ exporters split vertices at UV seams;
//     a cloth must not tear there);
//   - degenerate triangles (a repeated vertex after welding, or zero area: |cross| <= 1e-12 x the squared bounding-box
//     diagonal) and repeated triangles (the same three vertices again) are dropped and counted;
//   - vertices in no kept triangle (lines, points, unused vertices) are dropped: a particle needs mass;
//   - no triangle left, more than 16,777,216 vertices, or a file over 1 GiB: refused.
// Springs (seed 001's rule, the model the engine has today): a structural spring on every mesh edge, rest length from
// the mesh; a bend "cross" spring joining the two opposite vertices of each pair of triangles sharing an edge. An
// edge of three or more triangles (non-manifold) keeps its structural spring but gets no bend spring. No shear
// springs: a triangle has no diagonal to shear along (the structural springs of a triangle already resist shear).
// Masses: areal density x triangle area, lumped one third to each of its vertices.
// (Springs material model. With a fabric, scenes cook the mesh with triangle_fabric.hpp instead: membrane springs from
// the fabric, hinge bending, the fabric's density.)
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "drape/garment_assembly.hpp"

namespace drape {

inline constexpr std::size_t mesh_max_vertices = std::size_t{1} << 24; ///< 16,777,216
inline constexpr std::size_t mesh_max_file_bytes = std::size_t{1} << 30; ///< 1 GiB

/// A triangle mesh read from an OBJ file and cleaned for a cloth (see the file comment). Positions as in the file.
struct TriangleMesh {
    std::vector<double> x, y, z;          ///< per particle (welded, used vertices only), file units
    std::vector<std::uint32_t> triangles; ///< 3 particle indices per triangle, winding as in the file
    /// Per OBJ vertex (0-based, file order): its particle, or -1 when it is in no kept triangle.
    std::vector<std::int64_t> particle_of_vertex;
    std::size_t obj_faces = 0;  ///< triangles tinyobjloader made of the file's faces
    std::size_t welded = 0;     ///< vertices merged into an earlier vertex at the same position
    std::size_t unused = 0;     ///< vertices dropped (in no kept triangle), welded ones not counted
    std::size_t degenerate = 0; ///< triangles dropped: a repeated vertex or zero area
    std::size_t repeated = 0;   ///< triangles dropped: the same three vertices as an earlier triangle

    std::size_t obj_vertices() const noexcept { return particle_of_vertex.size(); }
    std::size_t particle_count() const noexcept { return x.size(); }
    std::size_t triangle_count() const noexcept { return triangles.size() / 3; }
    /// Sum of the triangle areas, file units squared.
    double area() const noexcept;
    /// A one-line note of what cleaning dropped or merged ("" when nothing): the caller shows it as a warning.
    std::string cleaning_note() const;
};

/// Parses OBJ text. `source` names it in messages. Throws InvalidInput "source: line N: what" (or without the line
/// when tinyobjloader gives none): a malformed or non-finite coordinate, a face index out of range, no triangle, too
/// many vertices (more than `max_vertices`, 16,777,216 unless a test asks for fewer), any tinyobjloader error or
/// warning (material warnings excepted: materials are ignored).
TriangleMesh parse_obj_mesh(const std::string& text, const std::string& source,
                            std::size_t max_vertices = mesh_max_vertices);

/// Reads an OBJ file (a regular file of at most 1 GiB) and parses it. Throws InvalidInput naming the path.
TriangleMesh load_obj_mesh(const std::string& path);

/// Where a mesh goes: scaled by `scale` about its bounding-box centre, which then goes to `centre` (m).
struct MeshPlacement {
    double scale = 1.0;
    std::array<float, 3> centre{0.0f, 0.0f, 0.0f};
    double areal_density = 0.15; ///< kg/m^2 (of the scaled mesh)
};

/// Appends the mesh to an assembly: one particle per mesh particle (in order, from the assembly's current count),
/// lumped masses, the triangles, the springs (add_triangle_springs). Throws InvalidInput if a triangle's area becomes
/// zero in float after placement, or two vertices coincide.
void add_mesh_panel(GarmentAssembly& io_assembly, const TriangleMesh& mesh, const MeshPlacement& placement);

/// Mesh particles whose y is within max(1e-6, 1e-3 x the bounding-box diagonal) of the highest y, ascending (pins
/// "top"), in the file's units (the tolerance scales with the mesh, so the set does not depend on the placement).
std::vector<std::uint32_t> mesh_top_particles(const TriangleMesh& mesh);

} // namespace drape
