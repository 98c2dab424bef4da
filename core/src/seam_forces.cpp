// Stage 0: seam forces. Seam springs (sewing between panels) are irregular, so they are not CSR rows: each is
// evaluated once, with the same Hooke + damping law as spring_forces.hpp,
//   F_a = c d,  F_b = -c d,  c = k (1 - l0 / l) + kd ((v_b - v_a) . d) / l^2,  d = x_b - x_a,
// and written to both ends, colour group by colour group (no two springs of a group share a particle, so the writes
// of a group never collide), groups in a fixed order. The per-particle result is added to the spring forces by the
// fused pass. Same result for any thread count.
#include <cmath>

#include <tbb/parallel_for.h>

#include "drape/simulation.hpp"

namespace drape {

namespace {
constexpr std::size_t seam_chunk = 2048; ///< springs per parallel chunk of a group (fixed)
}

template <bool Parallel> void Simulation::seam_forces_stage() {
    const SeamSet& s = cloth_.seams;
    const StateBuffer& st = cur();
    float* __restrict fx = extra_fx_.data();
    float* __restrict fy = extra_fy_.data();
    float* __restrict fz = extra_fz_.data();
    if (!params_.aero.enabled) // else aero_forces has just written every particle's entry: add on top
        for (std::uint32_t i : s.particles) fx[i] = fy[i] = fz[i] = 0.0f;
    const bool verlet = params_.integrator == Integrator::verlet;
    const float inv_dt = 1.0f / params_.dt;
    auto range = [&](std::size_t begin, std::size_t end) {
        for (std::size_t k = begin; k < end; ++k) {
            const std::uint32_t a = s.a[k], b = s.b[k];
            const SpringMaterial& m = cloth_.material[static_cast<std::size_t>(s.kind[k])];
            const float dx = st.x[b] - st.x[a], dy = st.y[b] - st.y[a], dz = st.z[b] - st.z[a];
            const float l2 = std::max(dx * dx + dy * dy + dz * dz, 1e-24f);
            const float inv = 1.0f / std::sqrt(l2);
            float dvx = st.u[b] - st.u[a], dvy = st.v[b] - st.v[a], dvz = st.w[b] - st.w[a];
            if (verlet) { // u, v, w hold the displacement over the last step
                dvx *= inv_dt;
                dvy *= inv_dt;
                dvz *= inv_dt;
            }
            const float k_s = m.stiffness * s.scale[k], kd_s = m.damping * s.scale[k];
            const float c = k_s * (1.0f - seam_rest_[k] * inv) + kd_s * (dvx * dx + dvy * dy + dvz * dz) * inv * inv;
            fx[a] += c * dx;
            fy[a] += c * dy;
            fz[a] += c * dz;
            fx[b] -= c * dx;
            fy[b] -= c * dy;
            fz[b] -= c * dz;
        }
    };
    for (std::size_t g = 0; g < s.groups.group_count(); ++g) {
        const std::size_t begin = s.groups.group_offsets[g], end = s.groups.group_offsets[g + 1];
        const std::size_t chunks = (end - begin + seam_chunk - 1) / seam_chunk;
        if (Parallel && !s.groups.is_overflow(g) && chunks > 1)
            tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t ch) {
                range(begin + ch * seam_chunk, std::min(end, begin + (ch + 1) * seam_chunk));
            });
        else
            range(begin, end);
    }
}

template void Simulation::seam_forces_stage<true>();
template void Simulation::seam_forces_stage<false>();

} // namespace drape
