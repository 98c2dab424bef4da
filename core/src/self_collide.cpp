// Stage "self_collide": cloth against cloth (docs/self_collision.md). Runs after the collide stage, on the state just
// written, for both solvers, when SimulationParams::self_collision.thickness h > 0.
//
// Proximity, as Bridson, Fedkiw and Anderson (2002) "Robust treatment of collisions, contact and friction for cloth
// animation" section 7.1 (repulsions) do it, without their continuous collision pass:
//   - point-triangle: a particle closer than h to a triangle that does not contain it;
//   - edge-edge: two edges sharing no vertex, closer than h.
// Pairs of 1-ring neighbours (the point shares a triangle with a vertex of the triangle; an endpoint of one edge
// shares a triangle with an endpoint of the other) are skipped when h exceeds half the shortest edge: on such a fine
// flat cloth they lie within h of each other at rest. On a coarser cloth they count (a sharp crease needs them).
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
// Broad phase: a spatial hash of cubic cells of size c = 1.01 (longest edge now + 2 h), rebuilt each round. Every
// triangle (its box grown by h) and every edge (grown by h / 2) is entered in the buckets of the cells its box
// overlaps: at most 2 per axis since the box is shorter than c, so at most 8 entries per primitive and every array is
// sized when cooked. A particle looks in its own cell's bucket; an edge looks in the buckets of its cells and takes a
// pair only in the cell holding the low corner of the two boxes' intersection (each pair once).
//
// Parallel and deterministic: the buckets are filled with atomic cursors (their order varies from run to run), but
// every contact is computed from the pair alone, and what it asks of each particle is added into per-particle 64-bit
// fixed-point accumulators (2^-32 m, 2^-32 m/s): integer addition is exact and associative, so the sums, and the
// result, are the same bits for every thread count and order. No allocation: everything is cooked in
// cook_self_collision.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "closest_points.hpp"
#include "drape/simulation.hpp"

namespace drape {
namespace {

using geom::V3;

constexpr double fixed_scale = 4294967296.0; // 2^32
constexpr int self_collide_rounds = 3;        // most rounds per step (a second one only after a deep push)
constexpr double settled = 0.01;              // a pair within 1% of the thickness, not approaching: no contact
constexpr std::size_t sc_block = 256;         // particles / primitives per parallel task

inline V3 cross(V3 a, V3 b) noexcept { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

inline std::uint32_t bucket_of(std::int64_t i, std::int64_t j, std::int64_t k, std::uint32_t mask) noexcept {
    std::uint64_t h = std::uint64_t(i) * 0x9E3779B185EBCA87ull ^ std::uint64_t(j) * 0xC2B2AE3D27D4EB4Full ^
                      std::uint64_t(k) * 0x165667B19E3779F9ull;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 32;
    return std::uint32_t(h) & mask;
}

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
    if (!sc_acc_.empty() || cloth_.triangles.empty()) return;
    cook_vertex_triangles();
    const std::size_t n = cloth_.particle_count, tris = cloth_.triangles.size() / 3;
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
    sc_edges_.resize(2 * keys.size());
    for (std::size_t e = 0; e < keys.size(); ++e) {
        sc_edges_[2 * e] = std::uint32_t(keys[e] >> 32);
        sc_edges_[2 * e + 1] = std::uint32_t(keys[e] & 0xffffffffu);
    }
    const std::size_t edges = keys.size();
    const std::size_t tri_buckets = pow2_at_least(2 * tris), edge_buckets = pow2_at_least(2 * edges);
    sc_tri_count_.assign(tri_buckets, 0);
    sc_tri_start_.assign(tri_buckets + 1, 0);
    sc_tri_items_.assign(8 * tris, 0);
    sc_edge_count_.assign(edge_buckets, 0);
    sc_edge_start_.assign(edge_buckets + 1, 0);
    sc_edge_items_.assign(8 * edges, 0);
    sc_tri_box_.assign(6 * tris, 0.0f);
    sc_edge_box_.assign(6 * edges, 0.0f);
    sc_acc_.assign(6 * n, 0);
    sc_hits_.assign(n, 0);
    sc_block_extremes_.assign(2 * ((edges + sc_block - 1) / sc_block), 0.0f);
    for (std::vector<float>* a : {&sc_snap_x_, &sc_snap_y_, &sc_snap_z_}) a->assign(n, 0.0f);
    sc_block_moved_.assign((n + sc_block - 1) / sc_block, 0.0f);
    sc_snap_step_ = SIZE_MAX;
}

template <bool Parallel> void Simulation::self_collide_stage(StateBuffer& out) {
    if (sc_acc_.empty()) cook_self_collision(); // not expected: construction and set_params cook
    if (sc_acc_.empty()) return;                // no triangles
    const std::size_t n = cloth_.particle_count;
    const float h = params_.self_collision.thickness;
    // steps_done_ has not been advanced for this step yet: the snapshot is of this trajectory when it was taken at or
    // before the end of the previous step (the health monitor's restore moves steps_done_ back before it).
    const bool snapshot = sc_snap_step_ != SIZE_MAX && sc_snap_step_ <= steps_done_;
    if (snapshot) {
        // The largest move of any particle since the snapshot (per block, then the largest of those: exact in any
        // order). Below a quarter of the thickness no two particles can have crossed a gap of half of it, and every
        // pair closer than that was pushed to the thickness at the snapshot: nothing to do.
        const float *x = out.x.data(), *y = out.y.data(), *z = out.z.data();
        const float *sx = sc_snap_x_.data(), *sy = sc_snap_y_.data(), *sz = sc_snap_z_.data();
        float* moved = sc_block_moved_.data();
        for_blocks<Parallel>(n, [&](std::size_t begin, std::size_t end) {
            float m = 0.0f;
            for (std::size_t i = begin; i < end; ++i) {
                const float dx = x[i] - sx[i], dy = y[i] - sy[i], dz = z[i] - sz[i];
                m = std::max(m, dx * dx + dy * dy + dz * dz);
            }
            moved[begin / sc_block] = m;
        });
        const float most = *std::max_element(sc_block_moved_.begin(), sc_block_moved_.end());
        if (most <= 0.0625f * h * h) return;
    }
    // Each pair's side: from the snapshot, or (none yet) from the start of this step.
    const StateBuffer& start = buffers_[current_];
    const float* x0 = snapshot ? sc_snap_x_.data() : start.x.data();
    const float* y0 = snapshot ? sc_snap_y_.data() : start.y.data();
    const float* z0 = snapshot ? sc_snap_z_.data() : start.z.data();
    std::size_t total = 0;
    for (int round = 0; round < self_collide_rounds; ++round) {
        bool deep = false;
        const std::size_t found = self_collide_round<Parallel>(out, x0, y0, z0, deep);
        if (round == 0) sc_contacts_ = found;
        total += found;
        if (!deep) break; // another round only when a pair was pushed by more than half the thickness
    }
    // A push may have moved a particle into a collider: the collide stage's particle pass has the last word.
    if (total > 0 && !params_.colliders.empty()) collide_stage<Parallel>(out, true, 0);
    std::copy_n(out.x.data(), n, sc_snap_x_.data());
    std::copy_n(out.y.data(), n, sc_snap_y_.data());
    std::copy_n(out.z.data(), n, sc_snap_z_.data());
    sc_snap_step_ = steps_done_ + 1;
    ++sc_runs_;
}

template <bool Parallel>
std::size_t Simulation::self_collide_round(StateBuffer& out, const float* x0, const float* y0, const float* z0,
                                           bool& deep) {
    const std::size_t n = cloth_.particle_count, tris = cloth_.triangles.size() / 3, edges = sc_edges_.size() / 2;
    const float h = params_.self_collision.thickness;
    const double hd = h, mu = params_.self_collision.friction;
    const bool verlet = params_.integrator == Integrator::verlet;
    const float dt = params_.dt, inv_dt = 1.0f / params_.dt;
    const std::uint32_t* tri = cloth_.triangles.data();
    const std::uint32_t* edge = sc_edges_.data();
    const float* w = cloth_.inv_mass.data();
    float *x = out.x.data(), *y = out.y.data(), *z = out.z.data();

    // Cell size: the longest edge now; the shortest decides whether 1-ring neighbours are exempt (per-block extremes,
    // then the extremes of those: exact whatever the order).
    for_blocks<Parallel>(edges, [&](std::size_t begin, std::size_t end) {
        float hi = 0.0f, lo = std::numeric_limits<float>::max();
        for (std::size_t e = begin; e < end; ++e) {
            const std::uint32_t a = edge[2 * e], b = edge[2 * e + 1];
            const float dx = x[a] - x[b], dy = y[a] - y[b], dz = z[a] - z[b];
            const float l2 = dx * dx + dy * dy + dz * dz;
            hi = std::max(hi, l2);
            lo = std::min(lo, l2);
        }
        sc_block_extremes_[2 * (begin / sc_block)] = hi;
        sc_block_extremes_[2 * (begin / sc_block) + 1] = lo;
    });
    float longest2 = 0.0f, shortest2 = std::numeric_limits<float>::max();
    for (std::size_t k = 0; k < sc_block_extremes_.size(); k += 2) {
        longest2 = std::max(longest2, sc_block_extremes_[k]);
        shortest2 = std::min(shortest2, sc_block_extremes_[k + 1]);
    }
    // 1-ring neighbours (a point and a triangle one edge apart, two edges across one triangle) lie about 0.7 of an
    // edge apart on a flat cloth: within h of each other at rest once h > half the shortest edge. Only then are they
    // exempt; on a coarser cloth they are contacts like any other (a sharp crease needs them).
    const bool ring_exempt = h > 0.5f * std::sqrt(shortest2);
    const float cell = 1.01f * (std::sqrt(longest2) + 2.0f * h);
    const float inv_cell = 1.0f / cell;
    auto cell_of = [&](float v) { return std::int64_t(std::floor(v * inv_cell)); };

    // Boxes of every triangle (grown by h) and edge (grown by h / 2), computed once per round.
    auto box_of = [&](const std::uint32_t* v, int count, float grow, float* b) {
        b[0] = b[3] = x[v[0]], b[1] = b[4] = y[v[0]], b[2] = b[5] = z[v[0]];
        for (int k = 1; k < count; ++k) {
            const float p[3] = {x[v[k]], y[v[k]], z[v[k]]};
            for (int c = 0; c < 3; ++c) b[c] = std::min(b[c], p[c]), b[3 + c] = std::max(b[3 + c], p[c]);
        }
        for (int c = 0; c < 3; ++c) b[c] -= grow, b[3 + c] += grow;
    };
    float* tri_box = sc_tri_box_.data();
    float* edge_box = sc_edge_box_.data();
    for_blocks<Parallel>(tris, [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t < end; ++t) box_of(tri + 3 * t, 3, h, tri_box + 6 * t);
    });
    for_blocks<Parallel>(edges, [&](std::size_t begin, std::size_t end) {
        for (std::size_t e = begin; e < end; ++e) box_of(edge + 2 * e, 2, 0.5f * h, edge_box + 6 * e);
    });
    // The cells a box overlaps (at most 2 per axis: the box is shorter than a cell), as lo and count per axis.
    auto span_of = [&](const float* b, std::int64_t lo[3], int cnt[3]) {
        for (int c = 0; c < 3; ++c) {
            lo[c] = cell_of(b[c]);
            cnt[c] = cell_of(b[3 + c]) > lo[c] ? 2 : 1;
        }
    };
    // Counting sort of primitives into buckets (a primitive enters a bucket once even if two cells share it).
    auto build = [&](std::vector<std::uint32_t>& count, std::vector<std::uint32_t>& first,
                     std::vector<std::uint32_t>& items, const float* boxes, std::size_t prims) {
        const std::uint32_t mask = std::uint32_t(count.size() - 1);
        std::fill(count.begin(), count.end(), 0u);
        auto each_bucket = [&](std::size_t p, auto&& f) {
            std::int64_t lo[3];
            int cnt[3];
            span_of(boxes + 6 * p, lo, cnt);
            std::uint32_t seen[8];
            int nseen = 0;
            for (int i = 0; i < cnt[0]; ++i)
                for (int j = 0; j < cnt[1]; ++j)
                    for (int k = 0; k < cnt[2]; ++k) {
                        const std::uint32_t bk = bucket_of(lo[0] + i, lo[1] + j, lo[2] + k, mask);
                        if (std::find(seen, seen + nseen, bk) != seen + nseen) continue;
                        seen[nseen++] = bk;
                        f(bk);
                    }
        };
        for_blocks<Parallel>(prims, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p)
                each_bucket(p, [&](std::uint32_t bk) {
                    std::atomic_ref<std::uint32_t>(count[bk]).fetch_add(1, std::memory_order_relaxed);
                });
        });
        first[0] = 0;
        for (std::size_t k = 0; k < count.size(); ++k) {
            first[k + 1] = first[k] + count[k];
            count[k] = first[k]; // now the bucket's fill cursor
        }
        for_blocks<Parallel>(prims, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p)
                each_bucket(p, [&](std::uint32_t bk) {
                    const std::uint32_t at =
                        std::atomic_ref<std::uint32_t>(count[bk]).fetch_add(1, std::memory_order_relaxed);
                    items[at] = std::uint32_t(p);
                });
        });
    };
    build(sc_tri_count_, sc_tri_start_, sc_tri_items_, tri_box, tris);
    build(sc_edge_count_, sc_edge_start_, sc_edge_items_, edge_box, edges);

    // The same point of the garment (the same particle, or particles sewn together), or 1-ring neighbours across
    // that: a triangle of u holds v or a particle sewn to v (or the other way round).
    const std::uint32_t* sewn = sc_sewn_.data();
    auto ring = [&](std::uint32_t u, std::uint32_t v) {
        for (std::uint32_t k = vertex_tri_offsets_[u]; k < vertex_tri_offsets_[u + 1]; ++k) {
            const std::uint32_t* t = tri + 3 * vertex_tris_[k];
            if (sewn[t[0]] == sewn[v] || sewn[t[1]] == sewn[v] || sewn[t[2]] == sewn[v]) return true;
        }
        return false;
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
    auto deposit = [&](const std::uint32_t* v, const double* coef, int count, V3 push, V3 dv) {
        for (int k = 0; k < count; ++k) {
            if (coef[k] == 0.0) continue;
            const double c = coef[k] * fixed_scale;
            const double d[6] = {c * push.x, c * push.y, c * push.z, c * dv.x, c * dv.y, c * dv.z};
            for (int f = 0; f < 6; ++f)
                std::atomic_ref<std::int64_t>(acc[6 * std::size_t(v[k]) + f])
                    .fetch_add(std::llround(d[f]), std::memory_order_relaxed);
            std::atomic_ref<std::uint32_t>(hits[v[k]]).fetch_add(1, std::memory_order_relaxed);
        }
    };
    std::atomic<bool> deep_any{false};
    // The response of a pair with weights alpha (signed: + on the first side, - on the second) along unit n, gap d.
    auto respond = [&](const std::uint32_t* v, const double* alpha, int count, V3 nrm, double d) {
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
        if (hd - d > 0.5 * hd) deep_any.store(true, std::memory_order_relaxed);
        const V3 push = (hd - d) * nrm;
        V3 dv{0.0, 0.0, 0.0};
        if (vn < 0.0) {
            const V3 vt = vrel - vn * nrm;
            const double vtl = geom::norm(vt);
            const double cut = vtl > 0.0 ? std::min(mu * -vn, vtl) / vtl : 0.0;
            dv = -vn * nrm - cut * vt;
        }
        deposit(v, coef, count, push, dv);
        return true;
    };

    std::atomic<std::size_t> contacts{0};
    const double h2 = hd * hd;
    // Point-triangle: each particle against the triangles in its cell's bucket.
    const std::uint32_t tri_mask = std::uint32_t(sc_tri_count_.size() - 1);
    for_blocks<Parallel>(n, [&](std::size_t begin, std::size_t end) {
        std::size_t local = 0;
        for (std::size_t pi = begin; pi < end; ++pi) {
            const std::uint32_t p = std::uint32_t(pi);
            const float px = x[p], py = y[p], pz = z[p];
            const std::uint32_t bk = bucket_of(cell_of(px), cell_of(py), cell_of(pz), tri_mask);
            for (std::uint32_t k = sc_tri_start_[bk]; k < sc_tri_start_[bk + 1]; ++k) {
                const std::uint32_t t = sc_tri_items_[k];
                const std::uint32_t* tv = tri + 3 * t;
                if (tv[0] == p || tv[1] == p || tv[2] == p) continue;
                if (w[p] == 0.0f && w[tv[0]] == 0.0f && w[tv[1]] == 0.0f && w[tv[2]] == 0.0f) continue;
                const float* b = tri_box + 6 * t;
                if (px < b[0] || px > b[3] || py < b[1] || py > b[4] || pz < b[2] || pz > b[5]) continue;
                const V3 P = pos(p), A = pos(tv[0]), B = pos(tv[1]), C = pos(tv[2]);
                const std::array<double, 3> bc = geom::closest_on_triangle(P, A, B, C);
                const V3 q = bc[0] * A + bc[1] * B + bc[2] * C;
                const V3 diff = P - q;
                if (geom::dot(diff, diff) >= h2) continue;
                if (near(p, tv[0]) || near(p, tv[1]) || near(p, tv[2])) continue;
                V3 nrm = cross(B - A, C - A);
                const double nl = geom::norm(nrm);
                if (!(nl > 0.0)) continue;
                nrm = (1.0 / nl) * nrm;
                // The side at the start of the step (the plane of the triangle then).
                const V3 A0 = pos0(tv[0]);
                const double side = geom::dot(pos0(p) - A0, cross(pos0(tv[1]) - A0, pos0(tv[2]) - A0));
                const double s = side > 0.0 ? 1.0 : (side < 0.0 ? -1.0 : (geom::dot(diff, nrm) >= 0.0 ? 1.0 : -1.0));
                nrm = s * nrm;
                const std::uint32_t v[4] = {p, tv[0], tv[1], tv[2]};
                const double alpha[4] = {1.0, -bc[0], -bc[1], -bc[2]};
                if (respond(v, alpha, 4, nrm, geom::dot(diff, nrm))) ++local;
            }
        }
        if (local) contacts.fetch_add(local, std::memory_order_relaxed);
    });
    // Edge-edge: each edge against the higher-numbered edges in the buckets of its cells.
    const std::uint32_t edge_mask = std::uint32_t(sc_edge_count_.size() - 1);
    for_blocks<Parallel>(edges, [&](std::size_t begin, std::size_t end) {
        std::size_t local = 0;
        for (std::size_t e = begin; e < end; ++e) {
            const std::uint32_t* ev = edge + 2 * e;
            const float* be = edge_box + 6 * e;
            std::int64_t lo[3];
            int cnt[3];
            span_of(be, lo, cnt);
            for (int i = 0; i < cnt[0]; ++i)
                for (int j = 0; j < cnt[1]; ++j)
                    for (int kk = 0; kk < cnt[2]; ++kk) {
                        const std::int64_t cellc[3] = {lo[0] + i, lo[1] + j, lo[2] + kk};
                        const std::uint32_t bk = bucket_of(cellc[0], cellc[1], cellc[2], edge_mask);
                        for (std::uint32_t k = sc_edge_start_[bk]; k < sc_edge_start_[bk + 1]; ++k) {
                            const std::uint32_t f = sc_edge_items_[k];
                            if (f <= e) continue;
                            const float* bf = edge_box + 6 * f;
                            if (be[3] < bf[0] || bf[3] < be[0] || be[4] < bf[1] || bf[4] < be[1] || be[5] < bf[2] ||
                                bf[5] < be[2])
                                continue;
                            if (cell_of(std::max(be[0], bf[0])) != cellc[0] || cell_of(std::max(be[1], bf[1])) != cellc[1] ||
                                cell_of(std::max(be[2], bf[2])) != cellc[2])
                                continue;
                            const std::uint32_t* fv = edge + 2 * f;
                            if (fv[0] == ev[0] || fv[0] == ev[1] || fv[1] == ev[0] || fv[1] == ev[1]) continue;
                            if (w[ev[0]] == 0.0f && w[ev[1]] == 0.0f && w[fv[0]] == 0.0f && w[fv[1]] == 0.0f) continue;
                            const V3 P1 = pos(ev[0]), Q1 = pos(ev[1]), P2 = pos(fv[0]), Q2 = pos(fv[1]);
                            double s = 0.0, t = 0.0;
                            geom::closest_segments(P1, Q1, P2, Q2, s, t);
                            const V3 diff = (P1 + s * (Q1 - P1)) - (P2 + t * (Q2 - P2));
                            const double dist2 = geom::dot(diff, diff);
                            if (dist2 >= h2) continue;
                            if (near(ev[0], fv[0]) || near(ev[0], fv[1]) || near(ev[1], fv[0]) || near(ev[1], fv[1]))
                                continue;
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
                                continue; // touching now and then: no side to restore
                            }
                            const std::uint32_t v[4] = {ev[0], ev[1], fv[0], fv[1]};
                            const double alpha[4] = {1.0 - s, s, -(1.0 - t), -t};
                            if (respond(v, alpha, 4, nrm, geom::dot(diff, nrm))) ++local;
                        }
                    }
        }
        if (local) contacts.fetch_add(local, std::memory_order_relaxed);
    });
    const std::size_t found = contacts.load();
    deep = deep_any.load();
    if (found == 0) return 0;
    // Per particle: the mean of what its contacts asked; the accumulators are cleared for the next round.
    for_blocks<Parallel>(n, [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            if (hits[i] == 0) continue;
            const double inv = 1.0 / (fixed_scale * double(hits[i]));
            std::int64_t* a = acc + 6 * i;
            x[i] += float(double(a[0]) * inv);
            y[i] += float(double(a[1]) * inv);
            z[i] += float(double(a[2]) * inv);
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

template void Simulation::self_collide_stage<true>(StateBuffer&);
template void Simulation::self_collide_stage<false>(StateBuffer&);

} // namespace drape
