// Stage "self_collide": cloth against cloth (docs/self_collision.md). Runs after the collide stage, on the state just
// written, for both solvers, when SimulationParams::self_collision.thickness h > 0.
//
// Proximity, as Bridson, Fedkiw and Anderson (2002) "Robust treatment of collisions, contact and friction for cloth
// animation" section 7.1 (repulsions) do it, without their continuous collision pass:
//   - point-triangle: a particle closer than h to a triangle that does not contain it;
//   - edge-edge: two edges sharing no vertex, closer than h.
// Pairs of 1-ring neighbours (the point shares a triangle with a vertex of the triangle; an endpoint of one edge
// shares a triangle with an endpoint of the other) are skipped when h exceeds half the shortest edge at rest: on such a
// fine flat cloth they lie within h of each other at rest. On a coarser cloth they count (a sharp crease needs them).
// Which side: the normal is oriented by the side the pair was on at the start of the step (the positions of buffer A),
// so a particle that crossed a triangle during the step is put back, not pushed through.
// Response: the pair is pushed apart to distance h along that normal, with inverse-mass weights (the point and the
// triangle's barycentric weights, or the edges' segment parameters: vertex i moves by alpha_i w_i (h - d) / W with
// W = sum alpha_i^2 w_i, so the gap opens exactly to h and a pinned vertex does not move); the relative normal velocity,
// if approaching, is removed and Coulomb friction takes mu |v_n| off the relative tangential velocity, distributed
// with the same weights. Each particle takes the mean of what its contacts ask (Jacobi, as the triangle pass does).
// A pair held at the thickness already (within 1%) and not approaching is left alone; a second and third round run
// only after a push of more than h / 2.
//
// Broad phase (docs/self_collision.md, "Broad phase"): the triangles are cut once into compact connected patches of
// 8 to 32 triangles (self_collide_patches.cpp; the size follows h over the edge length); each particle and edge belongs
// to one. Every round gives each patch a box (its triangles' boxes grown by h) and a cone of normals (unit axis,
// half-angle), after Volino and Magnenat-Thalmann 1994 ("Efficient self-collision detection on smoothly discretized
// surface animations using geometrical shape regularity"): cloth whose normals lie in a narrow cone is a graph over a
// plane and cannot come within h of itself if it is bent little enough for its triangles' altitudes (the test is in
// self_collide_round, "Flat pieces"). A patch that lies flat with all the patches it touches, away from the cloth's
// border, is calm: its own pairs, and those with a calm patch it touches or that touches the same calm patch, are
// skipped. The other patch pairs whose boxes overlap are found through a spatial hash of the patches (cells as large
// as the largest patch box, so at most 8 cells a patch; a pair is taken in the cell holding the low corner of the
// boxes' intersection) and searched primitive by primitive: the points of each inside the other's box against the
// triangles of the other, the edges of each inside the other's box against each other, each pair once.
// set_self_collision_reference tests every pair instead, for the tests.
//
// Parallel and deterministic: the buckets are filled with atomic cursors (their order varies from run to run), but
// every contact is computed from the pair alone, and what it asks of each particle is added into per-particle 64-bit
// fixed-point accumulators (2^-32 m, 2^-32 m/s): integer addition is exact and associative, so the sums, and the
// result, are the same bits for every thread count and order. No allocation: everything is cooked in
// cook_self_collision.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>

#include "closest_points.hpp"
#include "self_collide_hash.hpp"
#include "self_collide_patches.hpp"
#include "drape/mirror_symmetry.hpp"
#include "drape/simulation.hpp"

namespace drape {
namespace {

using geom::V3;

constexpr double fixed_scale = 4294967296.0; // 2^32
constexpr int self_collide_rounds = 3;        // most rounds per step (a second one only after a deep push)
constexpr int self_collide_substeps = 32;     // most parts a run cuts the motion since its last run into
constexpr double settled = 0.01;              // a pair within 1% of the thickness, not approaching: no contact
constexpr std::size_t sc_block = 256;         // particles / primitives per parallel task
constexpr float flat_cone = 1.0471976f;       // 60 degrees: the widest cone of normals a flat piece may have

inline V3 cross(V3 a, V3 b) noexcept { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

inline std::size_t pow2_at_least(std::size_t v) noexcept {
    std::size_t p = 1;
    while (p < v) p <<= 1;
    return p;
}

template <bool Parallel, class F> void for_blocks(std::size_t count, F&& body) {
    const std::size_t blocks = (count + sc_block - 1) / sc_block;
    auto run = [&](std::size_t b) { body(b * sc_block, std::min(count, (b + 1) * sc_block)); };
    if constexpr (Parallel)
        tbb::parallel_for(std::size_t{0}, blocks, run);
    else
        for (std::size_t b = 0; b < blocks; ++b) run(b);
}

} // namespace

void Simulation::cook_self_collision() {
    if (cloth_.triangles.empty()) return;
    const std::size_t n = cloth_.particle_count, tris = cloth_.triangles.size() / 3;
    if (sc_acc_.empty()) {
        cook_vertex_triangles();
        std::vector<std::uint64_t> keys;
        keys.reserve(3 * tris);
        for (std::size_t t = 0; t < tris; ++t)
            for (int k = 0; k < 3; ++k) {
                std::uint32_t a = cloth_.triangles[3 * t + k], b = cloth_.triangles[3 * t + (k + 1) % 3];
                if (a > b) std::swap(a, b);
                keys.push_back(std::uint64_t(a) << 32 | b);
            }
        std::sort(keys.begin(), keys.end());
        keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
        // Particles joined by seams are one point of the garment, not a contact.
        sc_sewn_ = sewn_representatives(cloth_.seams, n);
        // Per particle: the points of the garment its triangles hold (sewn representatives, ascending).
        sc_ring_start_.assign(n + 1, 0);
        sc_ring_.clear();
        std::vector<std::uint32_t> ring;
        for (std::size_t u = 0; u < n; ++u) {
            ring.clear();
            for (std::uint32_t k = vertex_tri_offsets_[u]; k < vertex_tri_offsets_[u + 1]; ++k)
                for (int c = 0; c < 3; ++c) ring.push_back(sc_sewn_[cloth_.triangles[3 * vertex_tris_[k] + c]]);
            std::sort(ring.begin(), ring.end());
            ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
            sc_ring_.insert(sc_ring_.end(), ring.begin(), ring.end());
            sc_ring_start_[u + 1] = std::uint32_t(sc_ring_.size());
        }
        // The points that hold several particles: a contact moves such a point as one (its mass the sum of theirs),
        // so that self-collision never pulls a seam open (docs/self_collision.md, "Seams").
        sc_group_start_.assign(1, 0);
        sc_group_.clear();
        {
            std::vector<std::uint32_t> size(n, 0);
            for (std::size_t i = 0; i < n; ++i) ++size[sc_sewn_[i]];
            std::vector<std::uint32_t> slot(n, UINT32_MAX);
            for (std::uint32_t r = 0; r < n; ++r)
                if (size[r] > 1) {
                    slot[r] = std::uint32_t(sc_group_start_.size() - 1);
                    sc_group_start_.push_back(sc_group_start_.back() + size[r]);
                }
            sc_group_.resize(sc_group_start_.back());
            std::vector<std::uint32_t> fill(sc_group_start_.begin(), sc_group_start_.end() - 1);
            for (std::uint32_t i = 0; i < n; ++i) // ascending: each point's particles in index order
                if (slot[sc_sewn_[i]] != UINT32_MAX) sc_group_[fill[slot[sc_sewn_[i]]]++] = i;
        }
        sc_contact_w_.assign(sc_group_.empty() ? 0 : n, 0.0f);
        sc_edges_.resize(2 * keys.size());
        for (std::size_t e = 0; e < keys.size(); ++e) {
            sc_edges_[2 * e] = std::uint32_t(keys[e] >> 32);
            sc_edges_[2 * e + 1] = std::uint32_t(keys[e] & 0xffffffffu);
        }
        const std::size_t edges = keys.size();
        // A mirror-exact cloth (mirror_symmetry.hpp): each edge's mirror image (its triangles are mirror images,
        // make_mirror_exact checked), and an edge after its mirror image given the twins of that one's ends in the
        // same order.
        sc_edge_twin_.clear();
        if (!cloth_.mirror.empty()) {
            const std::vector<std::uint32_t>& twin = cloth_.mirror;
            std::vector<Edge> as_edges(edges);
            for (std::size_t e = 0; e < edges; ++e) as_edges[e].a = sc_edges_[2 * e], as_edges[e].b = sc_edges_[2 * e + 1];
            sc_edge_twin_ = mirror_edge_map(as_edges, twin);
            for (std::size_t e = 0; e < edges; ++e) {
                const std::uint32_t m = sc_edge_twin_[e];
                if (m >= e) continue;
                sc_edges_[2 * e] = twin[sc_edges_[2 * m]];
                sc_edges_[2 * e + 1] = twin[sc_edges_[2 * m + 1]];
            }
        }
        // The mean rest length of the structural springs (of all springs if there are none) sizes the patches. The
        // shortest rest length of the springs along triangle edges (structural and shear) decides whether 1-ring
        // neighbours are exempt; without such springs, the shortest triangle edge now.
        float shortest = std::numeric_limits<float>::max();
        for (const Edge& e : cloth_.edges)
            if (e.kind == SpringKind::structural || e.kind == SpringKind::shear) shortest = std::min(shortest, e.rest);
        sc_mean_edge_ = float(cloth_spacing(cloth_));
        if (shortest == std::numeric_limits<float>::max()) {
            const StateBuffer& s = buffers_[current_];
            for (std::size_t e = 0; e < keys.size(); ++e) {
                const std::uint32_t a = std::uint32_t(keys[e] >> 32), b = std::uint32_t(keys[e] & 0xffffffffu);
                const float dx = s.x[a] - s.x[b], dy = s.y[a] - s.y[b], dz = s.z[a] - s.z[b];
                shortest = std::min(shortest, std::sqrt(dx * dx + dy * dy + dz * dz));
            }
        }
        sc_shortest_rest_ = shortest;
        sc_tri_box_.assign(6 * tris, 0.0f);
        sc_edge_box_.assign(6 * edges, 0.0f);
        sc_acc_.assign(6 * n, 0);
        sc_hits_.assign(n, 0);
        for (std::vector<float>* a : {&sc_snap_x_, &sc_snap_y_, &sc_snap_z_, &sc_end_x_, &sc_end_y_, &sc_end_z_,
                                      &sc_side_x_, &sc_side_y_, &sc_side_z_, &sc_push_x_, &sc_push_y_,
                                      &sc_push_z_, &sc_plane_c_})
            a->assign(n, 0.0f);
        sc_partner_.assign(n, UINT32_MAX);
        sc_block_moved_.assign((n + sc_block - 1) / sc_block, 0.0f);
        sc_snap_step_ = SIZE_MAX;
    }
    // The patches, sized for the thickness: cooked again when a new thickness wants another size.
    const std::uint32_t target = self_collision_patch_target(params_.self_collision.thickness, sc_mean_edge_);
    if (target == sc_patch_target_) return;
    sc_patch_target_ = target;
    sc_patches_ = cook_self_collision_patches(cloth_.triangles, n, sc_edges_, vertex_tri_offsets_, vertex_tris_, target);
    const std::size_t patches = sc_patches_.count(), buckets = pow2_at_least(2 * patches);
    sc_cell_count_.assign(buckets, 0);
    sc_cell_start_.assign(buckets + 1, 0);
    sc_cell_items_.assign(8 * patches, 0);
    sc_patch_box_.assign(6 * patches, 0.0f);
    sc_patch_cone_.assign(5 * patches, 0.0f);
    sc_patch_calm_.assign(patches, 0);
    sc_patch_sweep_.assign(6 * patches, 0.0f);
    sc_patch_motion_.assign(4 * patches, 0.0f);
    sc_patch_relative_.assign(patches, 0.0f);
}

template <bool Parallel>
float Simulation::self_collide_relative_motion(const StateBuffer& out, const float* xa, const float* ya,
                                               const float* za) {
    const SelfCollisionPatches& pa = sc_patches_;
    const std::size_t patches = pa.count();
    if (patches == 0) return 0.0f;
    const float h = params_.self_collision.thickness;
    const std::uint32_t* tri = cloth_.triangles.data();
    const std::uint32_t* edge = sc_edges_.data();
    float* sweep = sc_patch_sweep_.data();
    float* motion = sc_patch_motion_.data();
    // Per patch, over every particle a primitive of it holds (its triangles' corners, its points, its edges' ends):
    // the swept box, and the box of the displacements, whose centre c and half-diagonal r bound each displacement d
    // by |d - c| <= r.
    for_blocks<Parallel>(patches, [&](std::size_t begin, std::size_t end) {
        for (std::size_t p = begin; p < end; ++p) {
            float lo[3], hi[3], dlo[3], dhi[3];
            for (int c = 0; c < 3; ++c) {
                lo[c] = dlo[c] = std::numeric_limits<float>::max();
                hi[c] = dhi[c] = std::numeric_limits<float>::lowest();
            }
            auto take = [&](std::uint32_t i) {
                const float a[3] = {xa[i], ya[i], za[i]}, b[3] = {out.x[i], out.y[i], out.z[i]};
                for (int c = 0; c < 3; ++c) {
                    lo[c] = std::min({lo[c], a[c], b[c]});
                    hi[c] = std::max({hi[c], a[c], b[c]});
                    dlo[c] = std::min(dlo[c], b[c] - a[c]);
                    dhi[c] = std::max(dhi[c], b[c] - a[c]);
                }
            };
            for (std::uint32_t s = pa.tri_start[p]; s < pa.tri_start[p + 1]; ++s)
                for (int k = 0; k < 3; ++k) take(tri[3 * pa.tris[s] + k]);
            for (std::uint32_t s = pa.point_start[p]; s < pa.point_start[p + 1]; ++s) take(pa.points[s]);
            for (std::uint32_t s = pa.edge_start[p]; s < pa.edge_start[p + 1]; ++s)
                take(edge[2 * pa.edges[s]]), take(edge[2 * pa.edges[s] + 1]);
            float* sw = sweep + 6 * p;
            float* m = motion + 4 * p;
            if (!(dlo[0] <= dhi[0])) { // nothing in it: a box that meets none
                for (int c = 0; c < 3; ++c) sw[c] = std::numeric_limits<float>::max(), sw[3 + c] = std::numeric_limits<float>::lowest(), m[c] = 0.0f;
                m[3] = 0.0f;
                continue;
            }
            float r2 = 0.0f;
            for (int c = 0; c < 3; ++c) {
                sw[c] = lo[c] - 0.5f * h;
                sw[3 + c] = hi[c] + 0.5f * h;
                m[c] = 0.5f * (dlo[c] + dhi[c]);
                r2 += (dhi[c] - dlo[c]) * (dhi[c] - dlo[c]);
            }
            m[3] = 0.5f * std::sqrt(r2);
        }
    });
    // Two particles of patches p and q: |d_i - d_j| <= |c_p - c_q| + r_p + r_q. Only patches whose swept boxes meet can
    // come within h of each other during the motion.
    auto pair = [&](std::size_t p, std::size_t q) {
        const float *a = motion + 4 * p, *b = motion + 4 * q;
        const float dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
        return std::sqrt(dx * dx + dy * dy + dz * dz) + a[3] + b[3];
    };
    float* relative = sc_patch_relative_.data();
    if (sc_reference_) { // every pair of patches (the tests compare the hash with it)
        for (std::size_t p = 0; p < patches; ++p) {
            float r = 2.0f * motion[4 * p + 3];
            const float* bp = sweep + 6 * p;
            for (std::size_t q = p + 1; q < patches; ++q) {
                const float* bq = sweep + 6 * q;
                if (!boxes_meet(bp, bq)) continue;
                r = std::max(r, pair(p, q));
            }
            relative[p] = r;
        }
    } else {
        const PatchHash hash(sweep, patches, sc_cell_count_, sc_cell_start_, sc_cell_items_);
        for_blocks<Parallel>(patches, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p) {
                float r = 2.0f * motion[4 * p + 3];
                hash.overlapping(std::uint32_t(p), [&](std::uint32_t q) { r = std::max(r, pair(p, q)); });
                relative[p] = r;
            }
        });
    }
    return *std::max_element(relative, relative + patches);
}

template <bool Parallel> void Simulation::self_collide_stage(StateBuffer& out, bool again, bool tentative) {
    if (sc_acc_.empty()) cook_self_collision(); // not expected: construction and set_params cook
    sc_pushed_ = false;
    if (sc_acc_.empty()) return;                // no triangles
    const std::size_t n = cloth_.particle_count;
    const float h = params_.self_collision.thickness;
    // steps_done_ has not been advanced for this step yet: the snapshot is of this trajectory when it was taken at or
    // before the end of the previous step (the health monitor's restore moves steps_done_ back before it).
    const bool snapshot = sc_snap_step_ != SIZE_MAX && (again || sc_snap_step_ <= steps_done_);
    // Where the motion this run covers starts (and each pair's side comes from): the snapshot, or (none yet) the
    // start of this step.
    const StateBuffer& start = buffers_[current_];
    const float* xa = snapshot ? sc_snap_x_.data() : start.x.data();
    const float* ya = snapshot ? sc_snap_y_.data() : start.y.data();
    const float* za = snapshot ? sc_snap_z_.data() : start.z.data();
    // The largest move of any particle since then (per block, then the largest of those: exact in any order).
    float* moved = sc_block_moved_.data();
    for_blocks<Parallel>(n, [&](std::size_t begin, std::size_t end) {
        float m = 0.0f;
        for (std::size_t i = begin; i < end; ++i) {
            const float dx = out.x[i] - xa[i], dy = out.y[i] - ya[i], dz = out.z[i] - za[i];
            m = std::max(m, dx * dx + dy * dy + dz * dz);
        }
        moved[begin / sc_block] = m;
    });
    const float most2 = *std::max_element(sc_block_moved_.begin(), sc_block_moved_.end());
    // Below a quarter of the thickness since the snapshot no two particles can have crossed a gap of half of it, and
    // every pair closer than that was pushed to the thickness at the snapshot: nothing to do.
    if (snapshot && most2 <= 0.0625f * h * h) {
        if (params_.solver != Solver::implicit && sc_plane_step_ == sc_snap_step_) self_collide_hold<Parallel>(out);
        return;
    }
    const float most = std::sqrt(most2);
    // The implicit contact re-solve's planes come from the pushes of a step's first run: only then are they summed.
    // The explicit solver's runs sum them too: their planes hold the pushed particles in the steps that skip the stage
    // (self_collide_hold).
    const bool explicit_solver = params_.solver != Solver::implicit;
    const bool track = explicit_solver || !again;
    sc_track_pushes_ = track;
    // Inverse masses of the contacts, once a run (pins and the grab change them between steps): a point of the
    // garment that holds several particles sewn together moves as one, with the sum of their masses (fixed if one of
    // them is).
    if (!sc_group_.empty()) {
        const float* w = cloth_.inv_mass.data();
        std::copy_n(w, n, sc_contact_w_.data());
        for (std::size_t g = 0; g + 1 < sc_group_start_.size(); ++g) {
            double mass = 0.0;
            bool fixed = false;
            for (std::uint32_t k = sc_group_start_[g]; k < sc_group_start_[g + 1]; ++k) {
                const float wi = w[sc_group_[k]];
                fixed = fixed || wi == 0.0f;
                if (!fixed) mass += 1.0 / double(wi);
            }
            const float wg = fixed ? 0.0f : float(1.0 / mass);
            for (std::uint32_t k = sc_group_start_[g]; k < sc_group_start_[g + 1]; ++k) sc_contact_w_[sc_group_[k]] = wg;
        }
    }
    if (track) for_blocks<Parallel>(n, [&](std::size_t begin, std::size_t end) {
        std::fill(sc_push_x_.data() + begin, sc_push_x_.data() + end, 0.0f);
        std::fill(sc_push_y_.data() + begin, sc_push_y_.data() + end, 0.0f);
        std::fill(sc_push_z_.data() + begin, sc_push_z_.data() + end, 0.0f);
        if (explicit_solver) std::fill(sc_partner_.data() + begin, sc_partner_.data() + end, UINT32_MAX);
    });
    // Sub-steps: the motion from there to here, cut into K equal parts, so that no pair closes by more than h within
    // one and a pair that crosses is still within h of the other side at its end, with its side from the part's start
    // (a large implicit step moves the cloth several thicknesses). Two bounds, the smaller taken: no particle moves
    // more than h / 2 in a part (so no pair closes by more than h), or no particle moves more than h / 2 relative to
    // any particle that can come near it (the particles of patches whose swept boxes meet; self_collide_relative_motion).
    // The second is the smaller where cloth moves fast but as a whole (the N = 100 hang: ~19 parts a run by its fastest
    // particle), the first where layers meet head on (a crumpled pile). Relative motion up to h per part, the first
    // rule's worst case, let the pile cross itself twice in seven runs where the first rule alone let it once
    // (docs/self_collision.md, "Parts"). K = 1 unless a particle moved more than h / 2; at most self_collide_substeps
    // (then a part may move more).
    int parts = 1;
    if (most > 0.5f * h) {
        const float reach = std::min(most, self_collide_relative_motion<Parallel>(out, xa, ya, za));
        if (reach > 0.5f * h) parts = int(std::min(float(self_collide_substeps), std::ceil(reach / (0.5f * h))));
    }
    if (parts > 1) { // the motion's end kept; the parts start where the motion does
        std::copy_n(out.x.data(), n, sc_end_x_.data());
        std::copy_n(out.y.data(), n, sc_end_y_.data());
        std::copy_n(out.z.data(), n, sc_end_z_.data());
        std::copy_n(xa, n, out.x.data());
        std::copy_n(ya, n, out.y.data());
        std::copy_n(za, n, out.z.data());
    }
    std::size_t total = 0;
    for (int part = 1; part <= parts; ++part) {
        const float *x0 = xa, *y0 = ya, *z0 = za;
        if (parts > 1) {
            // Each particle keeps what earlier parts pushed it by: x = (the motion's point at part k) + (x - its point
            // at part k - 1); the last part's point is the step's end itself, so with no push the step ends unchanged.
            const float s0 = float(part - 1) / float(parts), s1 = float(part) / float(parts);
            const float *ex = sc_end_x_.data(), *ey = sc_end_y_.data(), *ez = sc_end_z_.data();
            float *sx = sc_side_x_.data(), *sy = sc_side_y_.data(), *sz = sc_side_z_.data();
            for_blocks<Parallel>(n, [&](std::size_t begin, std::size_t end) {
                auto along = [&](const float* a, const float* e, std::size_t i, float t, bool last) {
                    return last ? e[i] : a[i] + t * (e[i] - a[i]);
                };
                for (std::size_t i = begin; i < end; ++i) {
                    sx[i] = out.x[i], sy[i] = out.y[i], sz[i] = out.z[i];
                    out.x[i] = along(xa, ex, i, s1, part == parts) + (out.x[i] - along(xa, ex, i, s0, false));
                    out.y[i] = along(ya, ey, i, s1, part == parts) + (out.y[i] - along(ya, ey, i, s0, false));
                    out.z[i] = along(za, ez, i, s1, part == parts) + (out.z[i] - along(za, ez, i, s0, false));
                }
            });
            x0 = sx, y0 = sy, z0 = sz;
        }
        for (int round = 0; round < self_collide_rounds; ++round) {
            bool deep = false;
            const std::size_t found = self_collide_round<Parallel>(out, x0, y0, z0, deep, tentative);
            if (round == 0) sc_contacts_ = found;
            total += found;
            if (!deep) break; // another round only when a pair was pushed by more than half the thickness
        }
        if (tentative && total > 0) break; // the step is solved again: whether it pushed is all that is wanted
    }
    sc_parts_ = std::size_t(parts);
    if (!again) ++sc_runs_;
    // A tentative run that would have pushed (it stops at the first contact, pushing nothing): its step is solved
    // again from its start in sub-steps. Its result is dropped, so nothing more is done for it (no planes, no collide
    // pass), and the snapshot stays the last one before the step.
    if (tentative && total > 0) {
        sc_pushed_ = true;
        return;
    }
    // Each pushed particle's contact plane: the unit normal along its total push in this run (normalised in place),
    // through where the run left it. The implicit solver's contact re-solve solves with them (after a step's first
    // run); the explicit solver's steps that skip the stage hold on them (self_collide_hold).
    auto place_planes = [&] {
        for_blocks<Parallel>(n, [&](std::size_t begin, std::size_t end) {
            for (std::size_t i = begin; i < end; ++i) {
                const float px = sc_push_x_[i], py = sc_push_y_[i], pz = sc_push_z_[i];
                const float l2 = px * px + py * py + pz * pz;
                if (!(l2 > 1e-4f * h * h)) { // pushed by less than h / 100 (or in opposite ways): no plane
                    sc_push_x_[i] = sc_push_y_[i] = sc_push_z_[i] = sc_plane_c_[i] = 0.0f;
                    continue;
                }
                const float inv = 1.0f / std::sqrt(l2);
                const float nx = px * inv, ny = py * inv, nz = pz * inv;
                sc_push_x_[i] = nx, sc_push_y_[i] = ny, sc_push_z_[i] = nz;
                sc_plane_c_[i] = nx * out.x[i] + ny * out.y[i] + nz * out.z[i];
            }
        });
    };
    sc_pushed_ = total > 0 && track && !explicit_solver;
    if (sc_pushed_) place_planes();
    // A push may have moved a particle into a collider: the collide stage's particle pass has the last word (before the
    // explicit planes are placed, so that a particle a collider holds is not held inside it).
    if (total > 0 && !params_.colliders.empty()) collide_stage<Parallel>(out, true, 0);
    sc_plane_step_ = total > 0 && explicit_solver ? steps_done_ + 1 : SIZE_MAX;
    if (sc_plane_step_ != SIZE_MAX) place_planes();
    std::copy_n(out.x.data(), n, sc_snap_x_.data());
    std::copy_n(out.y.data(), n, sc_snap_y_.data());
    std::copy_n(out.z.data(), n, sc_snap_z_.data());
    sc_snap_step_ = steps_done_ + 1;
}

template <bool Parallel>
std::size_t Simulation::self_collide_round(StateBuffer& out, const float* x0, const float* y0, const float* z0,
                                           bool& deep, bool probe) {
    const std::size_t n = cloth_.particle_count;
    const float h = params_.self_collision.thickness;
    const double hd = h, mu = params_.self_collision.friction;
    const bool verlet = params_.integrator == Integrator::verlet;
    const bool partners = sc_track_pushes_ && params_.solver != Solver::implicit; // for self_collide_hold
    const float dt = params_.dt, inv_dt = 1.0f / params_.dt;
    const std::uint32_t* tri = cloth_.triangles.data();
    // The contacts read a triangle's corners in mirror order on a mirror-exact cloth (Cloth::mirror_corners), so that a
    // pair and its mirror image take the same steps.
    const std::uint32_t* corners = cloth_.mirror_corners.empty() ? tri : cloth_.mirror_corners.data();
    const std::uint32_t* edge = sc_edges_.data();
    const std::uint32_t* edge_twin = sc_edge_twin_.empty() ? nullptr : sc_edge_twin_.data();
    const std::uint32_t* twin = cloth_.mirror.empty() ? nullptr : cloth_.mirror.data();
    // Inverse masses of the contacts (sc_contact_w_ where particles are sewn together, filled by the run).
    const float* w = sc_group_.empty() ? cloth_.inv_mass.data() : sc_contact_w_.data();
    float *x = out.x.data(), *y = out.y.data(), *z = out.z.data();
    const SelfCollisionPatches& pa = sc_patches_;
    const std::size_t patches = pa.count();

    // 1-ring neighbours (a point and a triangle one edge apart, two edges across one triangle) lie about 0.7 of an
    // edge apart on a flat cloth: within h of each other at rest once h > half the shortest edge at rest. Only then
    // are they exempt; on a coarser cloth they are contacts like any other (a sharp crease needs them). The rest
    // length decides, not the edges now: one edge crushed in a fold must not switch off the 1-ring contacts of the
    // whole cloth (it did: a T-shirt's front and back crossed at the seams while an edge elsewhere was 1 mm long).
    const bool ring_exempt = h > 0.5f * sc_shortest_rest_;

    // Per patch: the boxes of its triangles (grown by h) and edges (grown by h / 2), in patch order; its own box;
    // its cone of normals.
    auto box_of = [&](const std::uint32_t* v, int count, float grow, float* b) {
        b[0] = b[3] = x[v[0]], b[1] = b[4] = y[v[0]], b[2] = b[5] = z[v[0]];
        for (int k = 1; k < count; ++k) {
            const float p[3] = {x[v[k]], y[v[k]], z[v[k]]};
            for (int c = 0; c < 3; ++c) b[c] = std::min(b[c], p[c]), b[3 + c] = std::max(b[3 + c], p[c]);
        }
        for (int c = 0; c < 3; ++c) b[c] -= grow, b[3 + c] += grow;
    };
    // A triangle's unit normal; its smallest altitude (twice its area over its longest edge) in `altitude`.
    auto unit_normal = [&](std::uint32_t t, float nrm[3], float& altitude) {
        const std::uint32_t* v = tri + 3 * t;
        const float ax = x[v[1]] - x[v[0]], ay = y[v[1]] - y[v[0]], az = z[v[1]] - z[v[0]];
        const float bx = x[v[2]] - x[v[0]], by = y[v[2]] - y[v[0]], bz = z[v[2]] - z[v[0]];
        const float cx = bx - ax, cy = by - ay, cz = bz - az;
        nrm[0] = ay * bz - az * by, nrm[1] = az * bx - ax * bz, nrm[2] = ax * by - ay * bx;
        const float l = std::sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        const float longest2 = std::max({ax * ax + ay * ay + az * az, bx * bx + by * by + bz * bz, cx * cx + cy * cy + cz * cz});
        altitude = longest2 > 0.0f ? l / std::sqrt(longest2) : 0.0f;
        if (!(l > 0.0f)) return false;
        for (int c = 0; c < 3; ++c) nrm[c] /= l;
        return true;
    };
    float* tri_box = sc_tri_box_.data();
    float* edge_box = sc_edge_box_.data();
    float* patch_box = sc_patch_box_.data();
    float* cone = sc_patch_cone_.data();
    constexpr float not_flat = 4.0f; // a half-angle above pi
    for_blocks<Parallel>(patches, [&](std::size_t begin, std::size_t end) {
        for (std::size_t p = begin; p < end; ++p) {
            float* pb = patch_box + 6 * p;
            for (int c = 0; c < 3; ++c)
                pb[c] = std::numeric_limits<float>::max(), pb[3 + c] = std::numeric_limits<float>::lowest();
            float sum[3] = {0.0f, 0.0f, 0.0f}, lowest = std::numeric_limits<float>::max();
            bool degenerate = pa.tri_start[p] == pa.tri_start[p + 1];
            for (std::uint32_t s = pa.tri_start[p]; s < pa.tri_start[p + 1]; ++s) {
                float* b = tri_box + 6 * s;
                box_of(tri + 3 * pa.tris[s], 3, h, b);
                for (int c = 0; c < 3; ++c) pb[c] = std::min(pb[c], b[c]), pb[3 + c] = std::max(pb[3 + c], b[3 + c]);
                float nrm[3], altitude;
                if (unit_normal(pa.tris[s], nrm, altitude)) {
                    for (int c = 0; c < 3; ++c) sum[c] += nrm[c];
                } else {
                    degenerate = true;
                }
                lowest = std::min(lowest, altitude);
            }
            for (std::uint32_t s = pa.point_start[p]; s < pa.point_start[p + 1]; ++s) {
                const std::uint32_t i = pa.points[s];
                const float q[3] = {x[i], y[i], z[i]};
                for (int c = 0; c < 3; ++c) pb[c] = std::min(pb[c], q[c] - h), pb[3 + c] = std::max(pb[3 + c], q[c] + h);
            }
            for (std::uint32_t s = pa.edge_start[p]; s < pa.edge_start[p + 1]; ++s)
                box_of(edge + 2 * pa.edges[s], 2, 0.5f * h, edge_box + 6 * s);
            float* cp = cone + 5 * p;
            const float sl = std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
            if (degenerate || !(sl > 0.0f)) {
                cp[0] = cp[1] = cp[2] = 0.0f, cp[3] = not_flat, cp[4] = 0.0f;
                continue;
            }
            for (int c = 0; c < 3; ++c) cp[c] = sum[c] / sl;
            float least = 1.0f;
            for (std::uint32_t s = pa.tri_start[p]; s < pa.tri_start[p + 1]; ++s) {
                float nrm[3], altitude;
                unit_normal(pa.tris[s], nrm, altitude);
                least = std::min(least, nrm[0] * cp[0] + nrm[1] * cp[1] + nrm[2] * cp[2]);
            }
            cp[3] = std::acos(std::clamp(least, -1.0f, 1.0f));
            cp[4] = lowest;
        }
    });
    // Flat pieces. On a piece of cloth whose normals all lie within an angle A of one axis (A < 90 degrees) the cloth
    // is a graph over the plane normal to the axis: a path on it is at most 1 / cos A times longer than its shadow, so
    // two of its primitives are at least cos A times the shortest path between them on the cloth apart. Primitives
    // that are not a contact's exemptions (same point; 1-ring neighbours when ring_exempt) are, on the cloth, at least
    // one triangle altitude apart (two when 1-ring neighbours are exempt). A patch is calm when it and every patch it
    // touches form such a piece, none of them at the cloth's border (where a garment's panel can fold within its own
    // plane: the underside of a sleeve against the side of the body), with A <= flat_cone and cos A times that
    // distance, with the smallest altitude of the piece, above h. Then no pair of the patch, nor of it and a patch it
    // touches, is closer than h; a pair of calm patches both touching a third calm patch neither.
    const float rings = ring_exempt ? 2.0f : 1.0f;
    auto angle_between = [&](std::uint32_t p, std::uint32_t q) {
        const float *a = cone + 5 * p, *b = cone + 5 * q;
        return std::acos(std::clamp(a[0] * b[0] + a[1] * b[1] + a[2] * b[2], -1.0f, 1.0f));
    };
    std::uint8_t* calm = sc_patch_calm_.data();
    for_blocks<Parallel>(patches, [&](std::size_t begin, std::size_t end) {
        for (std::size_t pi = begin; pi < end; ++pi) {
            const std::uint32_t p = std::uint32_t(pi);
            bool ok = !pa.on_border[p] && cone[5 * p + 3] <= flat_cone;
            float angle = cone[5 * p + 3], lowest = cone[5 * p + 4];
            for (std::uint32_t k = pa.adj_start[p]; ok && k < pa.adj_start[p + 1]; ++k) {
                const std::uint32_t r = pa.adj[k];
                ok = !pa.on_border[r] && cone[5 * r + 3] <= flat_cone;
                angle = std::max(angle, angle_between(p, r) + cone[5 * r + 3]);
                lowest = std::min(lowest, cone[5 * r + 4]);
            }
            calm[p] = ok && angle <= flat_cone && std::cos(angle) * rings * lowest > h;
        }
    });
    auto touching = [&](std::uint32_t p, std::uint32_t q) {
        return std::binary_search(pa.adj.begin() + pa.adj_start[p], pa.adj.begin() + pa.adj_start[p + 1], q);
    };
    auto on_flat_piece = [&](std::uint32_t p, std::uint32_t q) {
        if (!calm[p] || !calm[q]) return false;
        if (touching(p, q)) return true;
        for (std::uint32_t k = pa.adj_start[p]; k < pa.adj_start[p + 1]; ++k)
            if (calm[pa.adj[k]] && touching(pa.adj[k], q)) return true;
        return false;
    };

    // The same point of the garment (the same particle, or particles sewn together), or 1-ring neighbours across
    // that: a triangle of u holds v or a particle sewn to v (or the other way round).
    const std::uint32_t* sewn = sc_sewn_.data();
    auto ring = [&](std::uint32_t u, std::uint32_t v) {
        return std::binary_search(sc_ring_.begin() + sc_ring_start_[u], sc_ring_.begin() + sc_ring_start_[u + 1], sewn[v]);
    };
    auto near = [&](std::uint32_t u, std::uint32_t v) {
        if (sewn[u] == sewn[v]) return true;
        if (!ring_exempt) return false;
        return ring(u, v) || ring(v, u);
    };
    auto pos = [&](std::uint32_t i) { return V3{x[i], y[i], z[i]}; };
    auto pos0 = [&](std::uint32_t i) { return V3{x0[i], y0[i], z0[i]}; };
    auto vel = [&](std::uint32_t i) {
        return verlet ? V3{out.u[i] * inv_dt, out.v[i] * inv_dt, out.w[i] * inv_dt} : V3{out.u[i], out.v[i], out.w[i]};
    };
    std::int64_t* acc = sc_acc_.data();
    std::uint32_t* hits = sc_hits_.data();
    // Adds what one contact asks of its (up to 4) particles: particle v[k] moves by coef[k] (push n) and its velocity
    // changes by coef[k] dv.
    // `weight` scales it (1/2: one of the two halves of a pair taken both ways, counted once: `hit`).
    auto deposit = [&](const std::uint32_t* v, const double* coef, int count, V3 push, V3 dv, double weight, bool hit) {
        for (int k = 0; k < count; ++k) {
            if (coef[k] == 0.0) continue;
            const double c = weight * coef[k] * fixed_scale;
            const double d[6] = {c * push.x, c * push.y, c * push.z, c * dv.x, c * dv.y, c * dv.z};
            for (int f = 0; f < 6; ++f)
                std::atomic_ref<std::int64_t>(acc[6 * std::size_t(v[k]) + f])
                    .fetch_add(std::llround(d[f]), std::memory_order_relaxed);
            if (hit) std::atomic_ref<std::uint32_t>(hits[v[k]]).fetch_add(1, std::memory_order_relaxed);
        }
    };
    // A partner particle's rank for sc_partner_ (the lowest rank wins): its index, but on a mirror-exact cloth for a
    // particle after its twin the index of the candidate's twin, so that twins choose twin partners.
    auto partner_rank = [&](std::uint32_t i, std::uint32_t candidate) {
        return twin && twin[i] < i ? twin[candidate] : candidate;
    };
    std::atomic<bool> deep_any{false};
    // A probe only asks whether any pair is a contact: the first one stops the search, and nothing is pushed.
    std::atomic<bool> stop{false};
    // The response of a pair with weights alpha (signed: + on the first side, - on the second) along unit n, gap d.
    auto respond = [&](const std::uint32_t* v, const double* alpha, int count, V3 nrm, double d, double weight = 1.0,
                       bool hit = true) {
        double wsum = 0.0, coef[4];
        V3 vrel{0.0, 0.0, 0.0};
        for (int k = 0; k < count; ++k) {
            wsum += alpha[k] * alpha[k] * w[v[k]];
            coef[k] = alpha[k] * w[v[k]];
            vrel = vrel + alpha[k] * vel(v[k]);
        }
        if (!(wsum > 0.0)) return false;
        for (int k = 0; k < count; ++k) coef[k] /= wsum;
        const double vn = geom::dot(vrel, nrm);
        if (hd - d < settled * hd && vn >= 0.0) return false; // held at the thickness already, not approaching
        if (probe) {
            stop.store(true, std::memory_order_relaxed);
            return true;
        }
        if (hd - d > 0.5 * hd) deep_any.store(true, std::memory_order_relaxed);
        const V3 push = (hd - d) * nrm;
        V3 dv{0.0, 0.0, 0.0};
        if (vn < 0.0) {
            const V3 vt = vrel - vn * nrm;
            const double vtl = geom::norm(vt);
            const double cut = vtl > 0.0 ? std::min(mu * -vn, vtl) / vtl : 0.0;
            dv = -vn * nrm - cut * vt;
        }
        deposit(v, coef, count, push, dv, weight, hit);
        if (partners) // each pushed vertex: the other side's vertex of largest weight (the first of equals)
            for (int k = 0; k < count; ++k) {
                if (coef[k] == 0.0) continue;
                int best = -1;
                for (int j = 0; j < count; ++j)
                    if ((alpha[j] > 0.0) != (alpha[k] > 0.0) && (best < 0 || std::abs(alpha[j]) > std::abs(alpha[best])))
                        best = j;
                if (best < 0) continue;
                std::atomic_ref<std::uint32_t> slot(sc_partner_[v[k]]); // the lowest rank: the same in any order
                std::uint32_t cur = slot.load(std::memory_order_relaxed);
                while ((cur == UINT32_MAX || partner_rank(v[k], v[best]) < partner_rank(v[k], cur)) &&
                       !slot.compare_exchange_weak(cur, v[best], std::memory_order_relaxed)) {
                }
            }
        return true;
    };

    const double h2 = hd * hd;
    // Point p against the triangle in patch slot s (box tri_box + 6 s): 1 when it was a contact.
    auto point_triangle = [&](std::uint32_t p, std::uint32_t s) -> std::size_t {
        const float* b = tri_box + 6 * std::size_t(s);
        const float px = x[p], py = y[p], pz = z[p];
        if (px < b[0] || px > b[3] || py < b[1] || py > b[4] || pz < b[2] || pz > b[5]) return 0;
        const std::uint32_t* tv = corners + 3 * pa.tris[s];
        if (tv[0] == p || tv[1] == p || tv[2] == p) return 0;
        if (w[p] == 0.0f && w[tv[0]] == 0.0f && w[tv[1]] == 0.0f && w[tv[2]] == 0.0f) return 0;
        {
            // Farther than h from the triangle's plane (with 1% to spare for float rounding): no contact. Cheaper
            // than the 1-ring lookups and the closest point, and most candidates in a fold end here.
            const float ax = x[tv[1]] - x[tv[0]], ay = y[tv[1]] - y[tv[0]], az = z[tv[1]] - z[tv[0]];
            const float bx = x[tv[2]] - x[tv[0]], by = y[tv[2]] - y[tv[0]], bz = z[tv[2]] - z[tv[0]];
            const float nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
            const float d = (px - x[tv[0]]) * nx + (py - y[tv[0]]) * ny + (pz - z[tv[0]]) * nz;
            if (d * d > 1.0201f * h * h * (nx * nx + ny * ny + nz * nz)) return 0;
        }
        if (near(p, tv[0]) || near(p, tv[1]) || near(p, tv[2])) return 0;
        const V3 P = pos(p), A = pos(tv[0]), B = pos(tv[1]), C = pos(tv[2]);
        const std::array<double, 3> bc = geom::closest_on_triangle(P, A, B, C);
        const V3 q = bc[0] * A + bc[1] * B + bc[2] * C;
        const V3 diff = P - q;
        if (geom::dot(diff, diff) >= h2) return 0;
        V3 nrm = cross(B - A, C - A);
        const double nl = geom::norm(nrm);
        if (!(nl > 0.0)) return 0;
        nrm = (1.0 / nl) * nrm;
        // The side at the start of the step (the plane of the triangle then).
        const V3 A0 = pos0(tv[0]);
        const double side = geom::dot(pos0(p) - A0, cross(pos0(tv[1]) - A0, pos0(tv[2]) - A0));
        const double sg = side > 0.0 ? 1.0 : (side < 0.0 ? -1.0 : (geom::dot(diff, nrm) >= 0.0 ? 1.0 : -1.0));
        nrm = sg * nrm;
        const std::uint32_t v[4] = {p, tv[0], tv[1], tv[2]};
        const double alpha[4] = {1.0, -bc[0], -bc[1], -bc[2]};
        return respond(v, alpha, 4, nrm, geom::dot(diff, nrm)) ? 1 : 0;
    };
    // The edges in patch slots a and b: 1 when they were a contact. Taken in the order of their indices, so that the
    // rounding of the response does not depend on how the cloth was cut into patches; on a mirror-exact cloth in the
    // order of the lower index of each edge and its mirror image, so that a pair and its mirror image are taken alike,
    // and an edge against its own mirror image both ways round, each half the response (the pair is its own mirror
    // image: either order alone would treat the halves differently).
    auto edge_rank = [&](std::uint32_t e) -> std::uint64_t {
        if (!edge_twin) return e;
        return std::uint64_t(std::min(e, edge_twin[e])) << 1 | (e > edge_twin[e] ? 1u : 0u);
    };
    auto edge_edge_ordered = [&](std::uint32_t a, std::uint32_t b, double weight, bool hit) -> std::size_t {
        const std::uint32_t *ev = edge + 2 * pa.edges[a], *fv = edge + 2 * pa.edges[b];
        if (fv[0] == ev[0] || fv[0] == ev[1] || fv[1] == ev[0] || fv[1] == ev[1]) return 0;
        if (w[ev[0]] == 0.0f && w[ev[1]] == 0.0f && w[fv[0]] == 0.0f && w[fv[1]] == 0.0f) return 0;
        {
            // The segments' bounding spheres (centre, half length) farther apart than h (1% to spare): no contact.
            const float ex = x[ev[1]] - x[ev[0]], ey = y[ev[1]] - y[ev[0]], ez = z[ev[1]] - z[ev[0]];
            const float fx = x[fv[1]] - x[fv[0]], fy = y[fv[1]] - y[fv[0]], fz = z[fv[1]] - z[fv[0]];
            const float cx = 0.5f * (x[ev[0]] + x[ev[1]] - x[fv[0]] - x[fv[1]]);
            const float cy = 0.5f * (y[ev[0]] + y[ev[1]] - y[fv[0]] - y[fv[1]]);
            const float cz = 0.5f * (z[ev[0]] + z[ev[1]] - z[fv[0]] - z[fv[1]]);
            const float reach = 0.5f * (std::sqrt(ex * ex + ey * ey + ez * ez) + std::sqrt(fx * fx + fy * fy + fz * fz)) +
                                1.01f * h;
            if (cx * cx + cy * cy + cz * cz > reach * reach) return 0;
        }
        if (near(ev[0], fv[0]) || near(ev[0], fv[1]) || near(ev[1], fv[0]) || near(ev[1], fv[1])) return 0;
        const V3 P1 = pos(ev[0]), Q1 = pos(ev[1]), P2 = pos(fv[0]), Q2 = pos(fv[1]);
        double s = 0.0, t = 0.0;
        geom::closest_segments(P1, Q1, P2, Q2, s, t);
        const V3 diff = (P1 + s * (Q1 - P1)) - (P2 + t * (Q2 - P2));
        const double dist2 = geom::dot(diff, diff);
        if (dist2 >= h2) return 0;
        // Orientation: the same closest points at the start of the step.
        const V3 a0 = pos0(ev[0]), b0 = pos0(ev[1]), c0 = pos0(fv[0]), d0 = pos0(fv[1]);
        const V3 diff0 = (a0 + s * (b0 - a0)) - (c0 + t * (d0 - c0));
        const double dist = std::sqrt(dist2), dist0 = geom::norm(diff0);
        V3 nrm;
        constexpr double tiny = 1e-12;
        if (dist > tiny) {
            nrm = (1.0 / dist) * diff;
            if (geom::dot(nrm, diff0) < 0.0) nrm = -1.0 * nrm; // crossed during the step
        } else if (dist0 > tiny) {
            nrm = (1.0 / dist0) * diff0;
        } else {
            return 0; // touching now and then: no side to restore
        }
        const std::uint32_t v[4] = {ev[0], ev[1], fv[0], fv[1]};
        const double alpha[4] = {1.0 - s, s, -(1.0 - t), -t};
        return respond(v, alpha, 4, nrm, geom::dot(diff, nrm), weight, hit) ? 1 : 0;
    };
    auto edge_edge = [&](std::uint32_t a, std::uint32_t b) -> std::size_t {
        if (edge_rank(pa.edges[a]) > edge_rank(pa.edges[b])) std::swap(a, b);
        const float *be = edge_box + 6 * std::size_t(a), *bf = edge_box + 6 * std::size_t(b);
        if (!boxes_meet(be, bf)) return 0;
        if (edge_twin && edge_twin[pa.edges[a]] == pa.edges[b]) {
            const std::size_t first = edge_edge_ordered(a, b, 0.5, true);
            return first | edge_edge_ordered(b, a, 0.5, first == 0);
        }
        return edge_edge_ordered(a, b, 1.0, true);
    };
    // Every pair of patches p <= q: the points of each against the triangles of the other, the edges against the
    // edges (p == q: each pair of its own once). Of two different patches only the points and edges inside the other
    // patch's box can be near it: those are gathered first.
    auto inside = [](const float* b, float px, float py, float pz) {
        return px >= b[0] && px <= b[3] && py >= b[1] && py <= b[4] && pz >= b[2] && pz <= b[5];
    };
    auto patch_pair = [&](std::uint32_t p, std::uint32_t q) -> std::size_t {
        std::size_t found = 0;
        if (p == q) {
            for (std::uint32_t i = pa.point_start[p]; i < pa.point_start[p + 1]; ++i)
                for (std::uint32_t s = pa.tri_start[p]; s < pa.tri_start[p + 1]; ++s) found += point_triangle(pa.points[i], s);
            for (std::uint32_t e = pa.edge_start[p]; e < pa.edge_start[p + 1]; ++e)
                for (std::uint32_t f = e + 1; f < pa.edge_start[p + 1]; ++f) found += edge_edge(e, f);
            return found;
        }
        // The candidates of one side gathered into short arrays (coordinates or box bounds), so that the test of a
        // primitive of the other side against all of them is a loop the compiler vectorises; the narrow phase runs
        // for the hits. (The same for a patch's own pairs measured no faster: kept plain.)
        constexpr std::size_t cap = 3 * self_collision_patch_max;
        alignas(64) float c[6][cap];
        alignas(64) std::uint8_t hit[cap];
        std::uint32_t id[cap];
        for (int side = 0; side < 2; ++side) {
            const std::uint32_t a = side == 0 ? p : q, b = side == 0 ? q : p;
            const float* bb = patch_box + 6 * b;
            std::size_t m = 0;
            for (std::uint32_t i = pa.point_start[a]; i < pa.point_start[a + 1]; ++i) {
                const std::uint32_t v = pa.points[i];
                if (!inside(bb, x[v], y[v], z[v])) continue;
                c[0][m] = x[v], c[1][m] = y[v], c[2][m] = z[v], id[m++] = v;
            }
            if (m == 0) continue;
            for (std::uint32_t s = pa.tri_start[b]; s < pa.tri_start[b + 1]; ++s) {
                const float* tb = tri_box + 6 * std::size_t(s);
                if (!boxes_meet(tb, patch_box + 6 * a)) continue;
                for (std::size_t i = 0; i < m; ++i)
                    hit[i] = (c[0][i] >= tb[0]) & (c[0][i] <= tb[3]) & (c[1][i] >= tb[1]) & (c[1][i] <= tb[4]) &
                             (c[2][i] >= tb[2]) & (c[2][i] <= tb[5]);
                for (std::size_t i = 0; i < m; ++i)
                    if (hit[i]) found += point_triangle(id[i], s);
            }
        }
        std::size_t m = 0;
        for (std::uint32_t e = pa.edge_start[p]; e < pa.edge_start[p + 1]; ++e) {
            const float* eb = edge_box + 6 * std::size_t(e);
            if (!boxes_meet(eb, patch_box + 6 * q)) continue;
            for (int k = 0; k < 6; ++k) c[k][m] = eb[k];
            id[m++] = e;
        }
        if (m == 0) return found;
        for (std::uint32_t f = pa.edge_start[q]; f < pa.edge_start[q + 1]; ++f) {
            const float* fb = edge_box + 6 * std::size_t(f);
            if (!boxes_meet(fb, patch_box + 6 * p)) continue;
            for (std::size_t i = 0; i < m; ++i)
                hit[i] = (c[3][i] >= fb[0]) & (fb[3] >= c[0][i]) & (c[4][i] >= fb[1]) & (fb[4] >= c[1][i]) &
                         (c[5][i] >= fb[2]) & (fb[5] >= c[2][i]);
            for (std::size_t i = 0; i < m; ++i)
                if (hit[i]) found += edge_edge(id[i], f);
        }
        return found;
    };

    std::atomic<std::size_t> contacts{0};
    if (sc_reference_) {
        // The reference: every pair of the cloth, through the same narrow phase (slots cover every particle,
        // triangle and edge once).
        std::size_t found = 0;
        for (std::uint32_t i = 0; i < pa.points.size(); ++i)
            for (std::uint32_t s = 0; s < pa.tris.size(); ++s) found += point_triangle(pa.points[i], s);
        for (std::uint32_t e = 0; e < pa.edges.size(); ++e)
            for (std::uint32_t f = e + 1; f < pa.edges.size(); ++f) found += edge_edge(e, f);
        contacts.store(found);
    } else {
        // Spatial hash of the patch boxes (self_collide_hash.hpp).
        const PatchHash hash(patch_box, patches, sc_cell_count_, sc_cell_start_, sc_cell_items_);
        for_blocks<Parallel>(patches, [&](std::size_t begin, std::size_t end) {
            std::size_t local = 0;
            for (std::size_t pi = begin; pi < end; ++pi) {
                if (probe && stop.load(std::memory_order_relaxed)) break;
                const std::uint32_t p = std::uint32_t(pi);
                if (!calm[p]) local += patch_pair(p, p);
                hash.overlapping(p, [&](std::uint32_t q) {
                    if (!on_flat_piece(p, q)) local += patch_pair(p, q);
                });
            }
            if (local) contacts.fetch_add(local, std::memory_order_relaxed);
        });
    }
    const std::size_t found = contacts.load();
    deep = deep_any.load();
    if (found == 0) return 0;
    if (probe) return 1; // nothing was deposited
    // A point holding several particles: every one of them takes what the point's contacts asked (integer sums: the
    // same in any order).
    if (!sc_group_.empty()) for_blocks<Parallel>(sc_group_start_.size() - 1, [&](std::size_t begin, std::size_t end) {
        for (std::size_t g = begin; g < end; ++g) {
            std::int64_t sum[6] = {0, 0, 0, 0, 0, 0};
            std::uint32_t count = 0;
            for (std::uint32_t k = sc_group_start_[g]; k < sc_group_start_[g + 1]; ++k) {
                const std::uint32_t i = sc_group_[k];
                for (int f = 0; f < 6; ++f) sum[f] += acc[6 * std::size_t(i) + f];
                count += hits[i];
            }
            for (std::uint32_t k = sc_group_start_[g]; k < sc_group_start_[g + 1]; ++k) {
                const std::uint32_t i = sc_group_[k];
                for (int f = 0; f < 6; ++f) acc[6 * std::size_t(i) + f] = sum[f];
                hits[i] = count;
            }
        }
    });
    // Per particle: the mean of what its contacts asked; the accumulators are cleared for the next round.
    for_blocks<Parallel>(n, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            if (hits[i] == 0) continue;
            const double inv = 1.0 / (fixed_scale * double(hits[i]));
            std::int64_t* a = acc + 6 * i;
            const float px = float(double(a[0]) * inv), py = float(double(a[1]) * inv), pz = float(double(a[2]) * inv);
            x[i] += px;
            y[i] += py;
            z[i] += pz;
            if (sc_track_pushes_) {
                sc_push_x_[i] += px;
                sc_push_y_[i] += py;
                sc_push_z_[i] += pz;
            }
            const float dvx = float(double(a[3]) * inv), dvy = float(double(a[4]) * inv), dvz = float(double(a[5]) * inv);
            if (verlet) {
                out.u[i] += dvx * dt;
                out.v[i] += dvy * dt;
                out.w[i] += dvz * dt;
            } else {
                out.u[i] += dvx;
                out.v[i] += dvy;
                out.w[i] += dvz;
            }
            for (int f = 0; f < 6; ++f) a[f] = 0;
            hits[i] = 0;
        }
    });
    return found;
}

// Explicit steps that skip the stage: a particle the last run pushed stays on the far side of its plane (the unit
// normal along its push, through where that run and the collide pass left it, carried along the normal by its
// partner's move since), and loses the velocity into it relative to the partner's, with Coulomb friction
// (self_collision.friction) on the rest like a contact of the run. A plane fixed in space braked layers that move
// together: the top of a falling fold lost its fall at every skipping step. Without this, a particle pressed
// into a contact (a folded cloth's edge, a layer's weight) met it only when the stage next ran, a quarter of the
// thickness of motion later: in between it accelerated into it and was then pushed back, and a resting fold's corners
// chattered at 1-5 m/s (N = 100, 1.5 s after the fold), which in turn kept the stage running every 4 to 14 steps.
template <bool Parallel> void Simulation::self_collide_hold(StateBuffer& out) {
    const float mu = params_.self_collision.friction;
    const float* w = cloth_.inv_mass.data(); // a particle pinned (or grabbed) since the run stays where it is held
    const std::size_t n = cloth_.particle_count;
    const std::uint32_t* twin = cloth_.mirror.empty() ? nullptr : cloth_.mirror.data();
    // First every plane where its partner has carried it (the partner's move since the snapshot, along the normal) and
    // the partner's velocity, read before any particle is moved (so the result does not depend on the order).
    float* c = sc_side_x_.data();
    float *pu = sc_end_x_.data(), *pv = sc_end_y_.data(), *pw = sc_end_z_.data();
    for_blocks<Parallel>(n, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const float nx = sc_push_x_[i], ny = sc_push_y_[i], nz = sc_push_z_[i];
            if (nx == 0.0f && ny == 0.0f && nz == 0.0f) continue;
            const std::uint32_t q = sc_partner_[i];
            if (q == UINT32_MAX) {
                c[i] = sc_plane_c_[i], pu[i] = pv[i] = pw[i] = 0.0f;
                continue;
            }
            // A particle on the mirror line of a mirror-exact cloth: its partner and the partner's twin, averaged (the
            // partner alone would pull it to one side).
            const std::uint32_t r = twin && twin[i] == i ? twin[q] : q;
            const auto mean = [](float a, float b) { return 0.5f * (a + b); };
            c[i] = sc_plane_c_[i] + nx * mean(out.x[q] - sc_snap_x_[q], out.x[r] - sc_snap_x_[r]) +
                   ny * mean(out.y[q] - sc_snap_y_[q], out.y[r] - sc_snap_y_[r]) +
                   nz * mean(out.z[q] - sc_snap_z_[q], out.z[r] - sc_snap_z_[r]);
            pu[i] = mean(out.u[q], out.u[r]), pv[i] = mean(out.v[q], out.v[r]), pw[i] = mean(out.w[q], out.w[r]);
        }
    });
    float* held = sc_block_moved_.data(); // per block: 1 when it put a particle back (the move test is done with it)
    // Then each particle behind its plane back onto it, without the velocity into it relative to the partner's, and
    // Coulomb friction on the relative tangential velocity. With Verlet u, v, w hold displacements (x - x_prev): the
    // same rule applies to them.
    for_blocks<Parallel>(n, [&](std::size_t begin, std::size_t end) {
        held[begin / sc_block] = 0.0f;
        for (std::size_t i = begin; i < end; ++i) {
            const float nx = sc_push_x_[i], ny = sc_push_y_[i], nz = sc_push_z_[i];
            if ((nx == 0.0f && ny == 0.0f && nz == 0.0f) || w[i] == 0.0f) continue;
            const float gap = c[i] - (nx * out.x[i] + ny * out.y[i] + nz * out.z[i]);
            if (!(gap > 0.0f)) continue;
            held[begin / sc_block] = 1.0f;
            out.x[i] += gap * nx;
            out.y[i] += gap * ny;
            out.z[i] += gap * nz;
            const float ru = out.u[i] - pu[i], rv = out.v[i] - pv[i], rw = out.w[i] - pw[i];
            const float vn = ru * nx + rv * ny + rw * nz;
            if (!(vn < 0.0f)) continue;
            const float tx = ru - vn * nx, ty = rv - vn * ny, tz = rw - vn * nz;
            const float vt = std::sqrt(tx * tx + ty * ty + tz * tz);
            const float keep = vt > 0.0f ? std::max(0.0f, 1.0f - mu * -vn / vt) : 0.0f;
            out.u[i] = pu[i] + keep * tx;
            out.v[i] = pv[i] + keep * ty;
            out.w[i] = pw[i] + keep * tz;
        }
    });
    // A plane tilted from a collider's surface can hold a particle sliding along it a little inside its margin: the
    // collide stage's particle pass has the last word, as after a run.
    if (!params_.colliders.empty() && *std::max_element(sc_block_moved_.begin(), sc_block_moved_.end()) > 0.0f)
        collide_stage<Parallel>(out, true, 0);
}

template void Simulation::self_collide_hold<true>(StateBuffer&);
template void Simulation::self_collide_hold<false>(StateBuffer&);
template float Simulation::self_collide_relative_motion<true>(const StateBuffer&, const float*, const float*,
                                                               const float*);
template float Simulation::self_collide_relative_motion<false>(const StateBuffer&, const float*, const float*,
                                                                const float*);
template void Simulation::self_collide_stage<true>(StateBuffer&, bool, bool);
template void Simulation::self_collide_stage<false>(StateBuffer&, bool, bool);

} // namespace drape
