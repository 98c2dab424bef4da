// Stage 6: collisions with analytic colliders (core/src/colliders.cpp has the geometry). Runs on the state just
// written by integration and strain limiting. Two passes:
//   1. particles, per fixed particle block, so no particle is left inside a collider at the end of a substep (a point
//      stuck between overlapping colliders whose projections disagree is held at its position from the start of the
//      substep, at rest: collide_range);
//   2. triangles (triangle_contact.hpp): a triangle whose inside reaches into a collider although its vertices are
//      out (a coarse cloth over a sphere, a sleeve across an arm) is pushed out at its deepest point. Per triangle,
//      in parallel, the contact is found and what it asks of the triangle's vertices written to the triangle's own
//      record; then per particle, in parallel, the records of its triangles in contact are averaged in the fixed
//      order of the particle's triangle list. No write is shared, so the result does not depend on the thread count.
//      Up to two rounds (a push can leave a neighbouring triangle in contact); one per sweep when strain limiting
//      interleaves its sweeps with the stage.
// Verlet stores the displacement d = x - x_prev, not v: velocities d / dt are made explicit in scratch, collided, and
// d rewritten only where the collision changed something (others keep their exact bits).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <limits>

#include "drape/simulation.hpp"
#include "drape/triangle_contact.hpp"
#include "triangle_contact_search.hpp"

namespace drape {

template <bool Parallel> void Simulation::collide_stage(StateBuffer& out, bool particles, int triangle_rounds) {
    const std::vector<Collider>& colliders = params_.colliders;
    if (colliders.empty()) return;
    const std::size_t n = cloth_.particle_count;
    const bool verlet = params_.integrator == Integrator::verlet;
    const float dt = params_.dt, inv_dt = 1.0f / params_.dt;
    // Positions at the start of the substep: where a point stuck between overlapping colliders is held.
    // The implicit solver keeps points out during its sweeps, from the side each came from (vbd::contact_project):
    // what is left is rounding, projected without holding.
    const StateBuffer& start = buffers_[current_];
    const bool hold = params_.solver == Solver::explicit_euler;
    const float *hx = hold ? start.x.data() : nullptr, *hy = hold ? start.y.data() : nullptr,
                *hz = hold ? start.z.data() : nullptr;
    const std::size_t blocks = (n + block_particles - 1) / block_particles;
    auto for_blocks = [&](auto&& block) {
        if constexpr (Parallel)
            tbb::parallel_for(std::size_t{0}, blocks, block);
        else
            for (std::size_t b = 0; b < blocks; ++b) block(b);
    };
    if (!verlet) {
        auto particle_pass = [&](std::size_t b) {
            const std::size_t begin = b * block_particles, end = std::min(begin + block_particles, n);
            collide_range(colliders, out.x.data(), out.y.data(), out.z.data(), out.u.data(), out.v.data(),
                          out.w.data(), cloth_.inv_mass.data(), begin, end, hx, hy, hz);
        };
        if (particles) for_blocks(particle_pass);
        if (triangle_rounds > 0 &&
            collide_triangles<Parallel>(out.x.data(), out.y.data(), out.z.data(), out.u.data(), out.v.data(),
                                        out.w.data(), triangle_rounds) > 0 &&
            particles)
            for_blocks(particle_pass); // a triangle pushed out of one collider may have pushed a vertex into another
        return;
    }
    // Scratch: ax..az hold velocities, fx..fz the positions before the collision.
    float *vx = ax_.data(), *vy = ay_.data(), *vz = az_.data();
    float *px = fx_.data(), *py = fy_.data(), *pz = fz_.data();
    auto particle_pass = [&](std::size_t b) {
        const std::size_t begin = b * block_particles, end = std::min(begin + block_particles, n);
        collide_range(colliders, out.x.data(), out.y.data(), out.z.data(), vx, vy, vz, cloth_.inv_mass.data(), begin,
                      end, hx, hy, hz);
    };
    for_blocks([&](std::size_t b) {
        const std::size_t begin = b * block_particles, end = std::min(begin + block_particles, n);
        for (std::size_t i = begin; i < end; ++i) {
            vx[i] = out.u[i] * inv_dt;
            vy[i] = out.v[i] * inv_dt;
            vz[i] = out.w[i] * inv_dt;
            px[i] = out.x[i];
            py[i] = out.y[i];
            pz[i] = out.z[i];
        }
    });
    if (particles) for_blocks(particle_pass);
    if (triangle_rounds > 0 &&
        collide_triangles<Parallel>(out.x.data(), out.y.data(), out.z.data(), vx, vy, vz, triangle_rounds) > 0 &&
        particles)
        for_blocks(particle_pass);
    for_blocks([&](std::size_t b) {
        const std::size_t begin = b * block_particles, end = std::min(begin + block_particles, n);
        for (std::size_t i = begin; i < end; ++i) {
            if (out.x[i] == px[i] && out.y[i] == py[i] && out.z[i] == pz[i]) continue;
            out.u[i] = vx[i] * dt;
            out.v[i] = vy[i] * dt;
            out.w[i] = vz[i] * dt;
        }
    });
}

void Simulation::cook_triangle_contact() {
    if (cloth_.triangles.empty()) return;
    const std::size_t tris = cloth_.triangles.size() / 3, n = cloth_.particle_count;
    if (tri_in_contact_.empty()) {
        cook_vertex_triangles();
        tri_response_.assign(tris, TriangleResponse{});
        tri_in_contact_.assign(tris, 0);
        clearance_.assign(n, 0.0f);
    }
    cook_triangle_terms();
    if (core_measure_.size() != n * params_.colliders.size())
        core_measure_.assign(n * params_.colliders.size(), 0.0f);
}

template <bool Parallel>
std::size_t Simulation::collide_triangles(float* x, float* y, float* z, float* vx, float* vy, float* vz,
                                          int rounds) {
    const std::vector<Collider>& colliders = params_.colliders;
    const std::size_t tris = tri_in_contact_.size(), n = cloth_.particle_count;
    if (tris == 0 || colliders.empty()) return 0;
    // A mirror-exact cloth's triangles in mirror corner order (make_mirror_exact): a triangle and its twin take the
    // same steps.
    const std::uint32_t* tri = cloth_.mirror_corners.empty() ? cloth_.triangles.data() : cloth_.mirror_corners.data();
    const float* w = cloth_.inv_mass.data();
    constexpr std::size_t tri_block = 256;
    const std::size_t tri_blocks = (tris + tri_block - 1) / tri_block;
    const std::size_t blocks = (n + block_particles - 1) / block_particles;
    bool any_solid = false; // a plane's triangle contacts are its vertices'
    for (const Collider& col : colliders) any_solid = any_solid || col.kind != ColliderKind::plane;
    if (!any_solid) return 0;
    if (core_measure_.size() != n * colliders.size()) cook_triangle_contact(); // not expected: set_params cooks
    float* clear = clearance_.data();
    float* measure = core_measure_.data();
    std::size_t applied = 0; // contacts applied, over the rounds
    for (int round = 0; round < rounds; ++round) {
        std::atomic<std::size_t> contacts{0};
        // Per particle: a lower bound of its distance to the nearest collider (planes aside).
        auto bound = [&](std::size_t blk) {
            const std::size_t begin = blk * block_particles, end = std::min(begin + block_particles, n);
            detail::triangle_contact_bounds(colliders, n, x, y, z, clear, measure, begin, end);
        };
        // Per triangle: its deepest contact over the colliders, and what it asks of its vertices.
        auto find = [&](std::size_t blk) {
            std::size_t local = 0;
            const std::size_t end = std::min(tris, (blk + 1) * tri_block);
            for (std::size_t t = blk * tri_block; t < end; ++t) {
                tri_in_contact_[t] = 0;
                const std::uint32_t i[3] = {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]};
                if (w[i[0]] == 0.0f && w[i[1]] == 0.0f && w[i[2]] == 0.0f) continue;
                TriangleContact best;
                float mu = 0.0f;
                if (!detail::deepest_triangle_contact(colliders, n, i, x, y, z, clear, measure, best, mu))
                    continue;
                const float* b = best.barycentric.data();
                const float sum = b[0] * b[0] * w[i[0]] + b[1] * b[1] * w[i[1]] + b[2] * b[2] * w[i[2]];
                if (!(sum > 0.0f)) continue;
                TriangleResponse& r = tri_response_[t];
                const Vec3f& nrm = best.normal;
                r.b[0] = b[0], r.b[1] = b[1], r.b[2] = b[2];
                r.k = 1.0f / sum;
                for (int c = 0; c < 3; ++c) r.dq[c] = best.depth * nrm[c];
                // The contact point's velocity: its inward normal part removed, Coulomb friction on the rest.
                float v[3];
                for (int c = 0; c < 3; ++c) {
                    const float* vel = c == 0 ? vx : (c == 1 ? vy : vz);
                    v[c] = b[0] * vel[i[0]] + b[1] * vel[i[1]] + b[2] * vel[i[2]];
                }
                const float vn = v[0] * nrm[0] + v[1] * nrm[1] + v[2] * nrm[2];
                r.dv[0] = r.dv[1] = r.dv[2] = 0.0f;
                if (vn < 0.0f) {
                    const float t3[3] = {v[0] - vn * nrm[0], v[1] - vn * nrm[1], v[2] - vn * nrm[2]};
                    const float vt = std::sqrt(t3[0] * t3[0] + t3[1] * t3[1] + t3[2] * t3[2]);
                    const float cut = vt > 0.0f ? std::min(mu * -vn, vt) / vt : 0.0f;
                    for (int c = 0; c < 3; ++c) r.dv[c] = -vn * nrm[c] - cut * t3[c];
                }
                tri_in_contact_[t] = 1;
                ++local;
            }
            if (local) contacts.fetch_add(local, std::memory_order_relaxed);
        };
        // Per particle: the mean of what its triangles in contact ask, in the order of its triangle list.
        auto apply = [&](std::size_t blk) {
            const std::size_t begin = blk * block_particles, end = std::min(begin + block_particles, n);
            for (std::size_t i = begin; i < end; ++i) {
                if (w[i] == 0.0f) continue;
                float d[6] = {0.0f, 0.0f, 0.0f, 0.0f, 0.0f, 0.0f};
                int count = 0;
                for (std::uint32_t k = vertex_tri_offsets_[i]; k < vertex_tri_offsets_[i + 1]; ++k) {
                    const std::uint32_t t = vertex_tris_[k];
                    if (!tri_in_contact_[t]) continue;
                    const TriangleResponse& r = tri_response_[t];
                    const int corner = tri[3 * t] == i ? 0 : (tri[3 * t + 1] == i ? 1 : 2);
                    const float s = r.k * r.b[corner] * w[i];
                    for (int c = 0; c < 3; ++c) {
                        d[c] += s * r.dq[c];
                        d[3 + c] += s * r.dv[c];
                    }
                    ++count;
                }
                if (count == 0) continue;
                const float inv = 1.0f / float(count);
                x[i] += d[0] * inv;
                y[i] += d[1] * inv;
                z[i] += d[2] * inv;
                vx[i] += d[3] * inv;
                vy[i] += d[4] * inv;
                vz[i] += d[5] * inv;
            }
        };
        if constexpr (Parallel) {
            tbb::parallel_for(std::size_t{0}, blocks, bound);
            tbb::parallel_for(std::size_t{0}, tri_blocks, find);
            if (contacts.load() == 0) break;
            tbb::parallel_for(std::size_t{0}, blocks, apply);
        } else {
            for (std::size_t b = 0; b < blocks; ++b) bound(b);
            for (std::size_t b = 0; b < tri_blocks; ++b) find(b);
            if (contacts.load() == 0) break;
            for (std::size_t b = 0; b < blocks; ++b) apply(b);
        }
        applied += contacts.load();
    }
    return applied;
}

template void Simulation::collide_stage<true>(StateBuffer&, bool, int);
template void Simulation::collide_stage<false>(StateBuffer&, bool, int);
template std::size_t Simulation::collide_triangles<true>(float*, float*, float*, float*, float*, float*, int);
template std::size_t Simulation::collide_triangles<false>(float*, float*, float*, float*, float*, float*, int);

} // namespace drape
