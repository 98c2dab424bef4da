// Stage 6: collisions with analytic colliders (core/src/colliders.cpp has the geometry). Runs on the state just
// written by integration and strain limiting, per fixed particle block, so no particle is left inside a collider at
// the end of a substep (a point stuck between overlapping colliders whose projections disagree is held at its
// position from the start of the substep, at rest: collide_range). Verlet stores the displacement d = x - x_prev,
// not v: the block's velocities d / dt are made explicit in scratch, collided, and d rewritten only where the
// collision changed something (others keep their exact bits).
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "drape/simulation.hpp"

namespace drape {

template <bool Parallel> void Simulation::collide_stage(StateBuffer& out) {
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
    auto block = [&](std::size_t b) {
        const std::size_t begin = b * block_particles, end = std::min(begin + block_particles, n);
        if (!verlet) {
            collide_range(colliders, out.x.data(), out.y.data(), out.z.data(), out.u.data(), out.v.data(),
                          out.w.data(), cloth_.inv_mass.data(), begin, end, hx, hy, hz);
            return;
        }
        // Scratch: ax..az hold velocities, fx..fz the positions before the collision.
        float *vx = ax_.data(), *vy = ay_.data(), *vz = az_.data();
        float *px = fx_.data(), *py = fy_.data(), *pz = fz_.data();
        for (std::size_t i = begin; i < end; ++i) {
            vx[i] = out.u[i] * inv_dt;
            vy[i] = out.v[i] * inv_dt;
            vz[i] = out.w[i] * inv_dt;
            px[i] = out.x[i];
            py[i] = out.y[i];
            pz[i] = out.z[i];
        }
        collide_range(colliders, out.x.data(), out.y.data(), out.z.data(), vx, vy, vz, cloth_.inv_mass.data(), begin,
                      end, hx, hy, hz);
        for (std::size_t i = begin; i < end; ++i) {
            if (out.x[i] == px[i] && out.y[i] == py[i] && out.z[i] == pz[i]) continue;
            out.u[i] = vx[i] * dt;
            out.v[i] = vy[i] * dt;
            out.w[i] = vz[i] * dt;
        }
    };
    const std::size_t blocks = (n + block_particles - 1) / block_particles;
    if constexpr (Parallel)
        tbb::parallel_for(std::size_t{0}, blocks, block);
    else
        for (std::size_t b = 0; b < blocks; ++b) block(b);
}

template void Simulation::collide_stage<true>(StateBuffer&);
template void Simulation::collide_stage<false>(StateBuffer&);

} // namespace drape
