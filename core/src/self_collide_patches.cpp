// Self-collision's patches (docs/self_collision.md, "Broad phase"): the cloth's triangles cut once, at cooking, into
// compact connected pieces of about `target` triangles, each with the particles and edges it owns and the patches it
// touches. The stage bounds each patch with a box and a cone of normals every round; a patch whose normals lie within
// a narrow cone cannot touch itself, nor can two touching patches whose normals together do (Volino and
// Magnenat-Thalmann 1994), so only the rest are searched pair by pair.
#include "self_collide_patches.hpp"

#include <algorithm>

namespace drape {

SelfCollisionPatches cook_self_collision_patches(std::span<const std::uint32_t> triangles, std::size_t particles,
                                                 std::span<const std::uint32_t> edges,
                                                 std::span<const std::uint32_t> vertex_tri_offsets,
                                                 std::span<const std::uint32_t> vertex_tris, std::uint32_t target) {
    const std::size_t tris = triangles.size() / 3, edge_count = edges.size() / 2;
    constexpr std::uint32_t none = ~0u;
    std::vector<std::uint32_t> patch_of(tris, none);
    SelfCollisionPatches out;
    out.tri_start.push_back(0);
    // Grow each patch breadth-first from the lowest triangle not yet taken, through triangles sharing a particle,
    // until it holds `target` triangles (or nothing connected is left).
    std::vector<std::uint32_t> queue;
    queue.reserve(tris);
    std::uint32_t patches = 0;
    for (std::uint32_t seed = 0; seed < tris; ++seed) {
        if (patch_of[seed] != none) continue;
        const std::size_t first = out.tris.size();
        queue.clear();
        queue.push_back(seed);
        patch_of[seed] = patches;
        for (std::size_t head = 0; head < queue.size() && out.tris.size() - first < target; ++head) {
            const std::uint32_t t = queue[head];
            out.tris.push_back(t);
            for (int k = 0; k < 3; ++k) {
                const std::uint32_t v = triangles[3 * t + k];
                for (std::uint32_t j = vertex_tri_offsets[v]; j < vertex_tri_offsets[v + 1]; ++j) {
                    const std::uint32_t u = vertex_tris[j];
                    if (patch_of[u] != none) continue;
                    patch_of[u] = patches;
                    queue.push_back(u);
                }
            }
        }
        // Queued but not taken: free again for a later patch.
        for (std::size_t j = out.tris.size() - first; j < queue.size(); ++j) patch_of[queue[j]] = none;
        out.tri_start.push_back(std::uint32_t(out.tris.size()));
        ++patches;
    }
    // Particles: owned by the patch of their lowest triangle; particles in no triangle go to patches of their own
    // (no triangles, never flat), `target` at a time.
    std::vector<std::vector<std::uint32_t>> owned(patches);
    std::vector<std::uint32_t> loose;
    for (std::uint32_t v = 0; v < particles; ++v) {
        if (vertex_tri_offsets[v] == vertex_tri_offsets[v + 1]) loose.push_back(v);
        else owned[patch_of[vertex_tris[vertex_tri_offsets[v]]]].push_back(v);
    }
    for (std::size_t j = 0; j < loose.size(); j += target) {
        owned.emplace_back(loose.begin() + std::ptrdiff_t(j),
                           loose.begin() + std::ptrdiff_t(std::min(loose.size(), j + std::size_t(target))));
        out.tri_start.push_back(out.tri_start.back());
    }
    out.point_start.push_back(0);
    for (const auto& o : owned) {
        out.points.insert(out.points.end(), o.begin(), o.end());
        out.point_start.push_back(std::uint32_t(out.points.size()));
    }
    // Edges: owned by the patch of the lowest triangle holding both ends. An edge that only one triangle holds is on
    // the cloth's border, and so is that triangle's patch (as are the patches of particles in no triangle).
    std::vector<std::vector<std::uint32_t>> edges_of(owned.size());
    out.on_border.assign(owned.size(), 0);
    for (std::size_t p = patches; p < owned.size(); ++p) out.on_border[p] = 1;
    for (std::uint32_t e = 0; e < edge_count; ++e) {
        const std::uint32_t a = edges[2 * e], b = edges[2 * e + 1];
        std::uint32_t first = none, holding = 0;
        for (std::uint32_t j = vertex_tri_offsets[a]; j < vertex_tri_offsets[a + 1]; ++j) {
            const std::uint32_t t = vertex_tris[j];
            if (triangles[3 * t] == b || triangles[3 * t + 1] == b || triangles[3 * t + 2] == b) {
                if (first == none) first = t;
                ++holding;
            }
        }
        if (first == none) continue;
        edges_of[patch_of[first]].push_back(e);
        if (holding == 1) out.on_border[patch_of[first]] = 1;
    }
    out.edge_start.push_back(0);
    for (const auto& o : edges_of) {
        out.edges.insert(out.edges.end(), o.begin(), o.end());
        out.edge_start.push_back(std::uint32_t(out.edges.size()));
    }
    // Touching patches: two patches with triangles at one particle.
    std::vector<std::uint64_t> pairs;
    std::vector<std::uint32_t> at;
    for (std::uint32_t v = 0; v < particles; ++v) {
        at.clear();
        for (std::uint32_t j = vertex_tri_offsets[v]; j < vertex_tri_offsets[v + 1]; ++j) at.push_back(patch_of[vertex_tris[j]]);
        std::sort(at.begin(), at.end());
        at.erase(std::unique(at.begin(), at.end()), at.end());
        for (std::uint32_t p : at)
            for (std::uint32_t q : at)
                if (p != q) pairs.push_back(std::uint64_t(p) << 32 | q);
    }
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    out.adj_start.assign(owned.size() + 1, 0);
    for (std::uint64_t pq : pairs) ++out.adj_start[(pq >> 32) + 1];
    for (std::size_t p = 0; p < owned.size(); ++p) out.adj_start[p + 1] += out.adj_start[p];
    out.adj.resize(pairs.size());
    for (std::size_t j = 0; j < pairs.size(); ++j) out.adj[j] = std::uint32_t(pairs[j] & 0xffffffffu);
    return out;
}

} // namespace drape
