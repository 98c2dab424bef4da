// The cooked cloth: immutable topology and material data, built once from an edge list ("cook once, never
// allocate in a step"). Three tiers of data in drape:
//   cold   - what the user authored (scene parameters, grid size, masks): see scene_hang.hpp;
//   cooked - this file: particle count and padding, inverse masses, springs (edge list, CSR, SIMD-sliced CSR,
//            optional regular-grid stencil), triangles for drawing;
//   hot    - per-step state (positions, velocities / previous positions): see simulation.hpp.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "drape/aligned_array.hpp"
#include "drape/bending.hpp"
#include "drape/colouring.hpp"
#include "drape/simd.hpp"
#include "drape/spring_graph.hpp"

namespace drape {

/// Particles per parallel block. A multiple of the SIMD width, fixed, so block boundaries never depend on the
/// thread count (determinism) and a block's state (1024 x 6 floats x 2 buffers = 48 KiB) stays in L2.
inline constexpr std::size_t block_particles = 1024;
static_assert(block_particles % simd::width == 0);

/// Spring material per kind: Hooke stiffness and damping along the spring.
struct SpringMaterial {
    float stiffness = 0.0f; ///< k, N/m
    float damping = 0.0f;   ///< kd, N*s/m: F = kd ((v_j - v_i) . d) d, d the unit spring direction
};

/// Regular-grid fast path: every particle's neighbours sit at fixed index offsets, so the kernel uses unaligned
/// contiguous loads instead of gathers. Slot order is ascending offset, the same order as a sorted CSR row, so the
/// grid kernel sums the same terms in the same order as the general kernel.
struct GridStencil {
    static constexpr std::size_t slot_count = 12;
    std::uint32_t columns = 0; ///< particles per grid row (index = row * columns + column)
    std::uint32_t rows = 0;
    std::array<std::int32_t, slot_count> offset{};  ///< neighbour index - own index
    std::array<SpringKind, slot_count> kind{};      ///< material of the spring in this slot
    std::array<float, slot_count> rest{};           ///< rest length, m
    std::array<float, slot_count> scale{1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1}; ///< Edge::scale of the slot's springs
    /// Per particle:
    ///   bit s (0..11)        slot s's spring exists (in the fabric model the four bend slots +-2, +-2N carry none);
    ///   bit half_bit + s     slot s's spring has half the slot's stiffness (Edge::scale = scale[s] / 2: a membrane
    ///                        edge on the cloth's boundary, fabric model);
    ///   bits bend_u_bit + 0..2  the second difference along the row centred at the particle's left neighbour, at the
    ///                        particle, at its right neighbour exists (fabric model); bend_v_bit + 0..2 likewise
    ///                        along the column (up, self, down);
    ///   bit edge_row_bit     the particle's row is the first or last (its row elements have half weight);
    ///   bit edge_column_bit  its column is the first or last (its column elements have half weight).
    /// A twist element (cell cross difference) exists exactly where the cell's diagonal (shear-slot) spring does.
    AlignedArray<std::uint32_t> mask;
    /// Some mask word has a half bit (the fabric model): the grid kernel must be GridFabric, which reads them, even
    /// when the cloth has no bending.
    bool half_edges = false;
    static constexpr std::uint32_t half_bit = 12, bend_u_bit = 24, bend_v_bit = 27, edge_row_bit = 30,
                                   edge_column_bit = 31;
};

/// Seam springs (SpringKind::seam, e.g. sewing two panels): the irregular part of a garment. They are not in the CSR;
/// the seam_forces stage evaluates each once and writes both ends, colour group by colour group (no two springs of
/// a group share a particle), groups in a fixed order: parallel, without atomics, thread-count independent.
struct SeamSet {
    ColourGroups groups;                 ///< edge_index: indices into Cloth::edges
    std::vector<std::uint32_t> a, b;     ///< spring ends, in group order
    std::vector<float> rest;             ///< m, in group order
    std::vector<SpringKind> kind;        ///< material of each (seam), in group order
    std::vector<float> scale;            ///< Edge::scale of each, in group order
    std::vector<std::uint32_t> particles; ///< every particle touched by a seam, ascending
    bool empty() const noexcept { return a.empty(); }
};

/// Per particle (particle_count entries): the lowest index of the particles joined to it through seams (a seam pulls
/// its ends together: they are one point of the garment), itself where no seam touches it. Union-find.
std::vector<std::uint32_t> sewn_representatives(const SeamSet& seams, std::size_t particle_count);

struct CoarseCloth; // level_transfer.hpp

/// Everything about a cloth that does not change while it is simulated.
struct Cloth {
    std::size_t particle_count = 0; ///< real particles
    std::size_t padded_count = 0;   ///< particle_count rounded up to whole SIMD batches
    std::size_t halo = 0;           ///< zeroed elements on each side of every hot array (grid-kernel reads)
    AlignedArray<float> inv_mass;   ///< 1/kg; 0 = pinned (and for padding)
    /// 1/kg each particle has when it is not pinned, authored pins included (so the user can unpin them);
    /// empty = inv_mass.
    std::vector<float> free_inv_mass;
    std::array<SpringMaterial, spring_kind_count> material{};
    std::vector<Edge> edges;         ///< every spring once (cold list; health and colouring read it)
    SpringGraph graph;               ///< CSR and SIMD-sliced CSR over the edges, seams excepted
    SeamSet seams;                   ///< seam springs, coloured
    std::optional<GridStencil> grid; ///< present when the cloth is a full or masked regular grid
    BendingSet bending;              ///< bending elements and their Q (bending.hpp); empty in the springs model
    std::vector<std::uint32_t> triangles; ///< 3 indices per triangle, counter-clockwise seen from +normal
    /// Each particle's mirror twin when the cloth is its own mirror image and made mirror-exact
    /// (make_mirror_exact, mirror_symmetry.hpp); empty otherwise.
    std::vector<std::uint32_t> mirror;
    std::vector<std::uint32_t> mirror_triangle; ///< with `mirror`: each triangle's mirror image (mirror_triangle_map)
    /// With `mirror`: the triangles' corners in mirror order (make_mirror_exact), for the collide stage's triangle pass.
    std::vector<std::uint32_t> mirror_corners;
    /// The simulation frame: every position of this cloth (InitialState, the Simulation's state, its
    /// colliders and grab targets) is relative to this point, m, world coordinates in double. Scenes put it
    /// at the cloth's centre, so float32 positions keep their precision wherever the cloth is (a 1 cm cloth
    /// at 1000 m behaves as at the origin); world position = origin + stored position, added back (in double)
    /// only where absolute positions are shown (OBJ export, the run's JSON).
    std::array<double, 3> origin{0.0, 0.0, 0.0};
    /// For a cloth of the fabric model that can be rebuilt at a coarser spacing (a square grid, an outline): its
    /// level-th coarser copy (level 1, 2, ...: about 2^level times the spacing), with the maps between it and the
    /// cloth (level_transfer.hpp; the implicit solver's coarse levels); nullopt past the coarsest. Empty when the cloth
    /// cannot be rebuilt so (the springs model, whose constants are per spring; masks and OBJ meshes).
    std::function<std::optional<CoarseCloth>(std::uint32_t level)> coarsen;

    std::size_t block_count() const noexcept { return (padded_count + block_particles - 1) / block_particles; }
    std::size_t spring_count() const noexcept { return edges.size(); }
};

/// Self-collision's contact planes of its last run (explicit solver, Simulation::self_collision_planes): per particle
/// pushed, its index, the unit normal along its push and the offset n . x (m, relative to Cloth::origin) it is held on.
struct SelfCollisionPlanes {
    std::vector<std::uint32_t> index, partner; ///< the particle; its contacts' partner, whose move carries the plane
    std::vector<float> nx, ny, nz, c;
};

/// Initial per-particle state (cold, plain vectors of particle_count entries).
struct InitialState {
    std::vector<float> x, y, z;    ///< positions relative to Cloth::origin, m
    std::vector<float> vx, vy, vz; ///< velocities, m/s
    /// Seams still being sewn (SimulationParams::sewing_speed): each seam's current rest length, in SeamSet order,
    /// m; empty = the seams start from their lengths in x, y, z (a saved state carries it, so sewing resumes).
    std::vector<float> seam_rest;
    /// Self-collision's snapshot of its last run (positions after its pushes, relative to Cloth::origin): a saved
    /// state carries it so a resumed run continues as it would have; empty = none (the stage runs in the first step).
    std::vector<float> snapshot_x, snapshot_y, snapshot_z;
    /// And its contact planes (explicit solver; only with a snapshot); empty = none.
    SelfCollisionPlanes sc_planes;
};

/// Rounds n up to whole SIMD batches.
constexpr std::size_t pad_to_width(std::size_t n) noexcept {
    return (n + simd::width - 1) / simd::width * simd::width;
}

/// Cooks a cloth from inverse masses (1/kg, 0 = pinned) and an edge list: sorts and checks the
/// edges, builds CSR and the SIMD-sliced CSR, fills the per-entry material. Throws InvalidInput on a bad edge
/// (index out of range, self loop, duplicate, non-positive rest length) or a bad material.
Cloth cook_cloth(std::span<const float> inv_mass, std::vector<Edge> edges,
                 const std::array<SpringMaterial, spring_kind_count>& material, std::size_t halo = 0);

/// Re-fills every per-entry stiffness and damping from `material` (after the user changes a material).
void apply_materials(Cloth& cloth, const std::array<SpringMaterial, spring_kind_count>& material);

/// Rest lengths of a grid cloth's structural springs when they are exactly the grid's east and south neighbours
/// (every neighbour pair has its spring, no other structural spring), each direction with one rest length: the
/// case the SIMD strain figures (publish, strain colours) handle with contiguous loads. Empty otherwise.
struct GridStructuralRest {
    float east = 0.0f, south = 0.0f; ///< m
};
std::optional<GridStructuralRest> uniform_grid_structural(const Cloth& cloth);

/// The cloth's spacing: the mean rest length of its structural springs (of all its springs if it has none; 0 without
/// springs), m. Sizes self-collision's patches, and is what its thickness is judged against.
double cloth_spacing(const Cloth& cloth);

} // namespace drape
