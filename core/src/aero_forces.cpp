// Stage 0a: aerodynamic wind per triangle (seed 004 section 2.1.2; the law is documented at AeroWind in
// simulation.hpp). Two passes, no scatter:
//   1. per triangle (parallel over fixed chunks): the force on the triangle, F = -1/2 rho C_d A |v_rel| (v_rel . n) n,
//      v_rel = mean velocity of its particles - wind; stored per triangle;
//   2. per particle (parallel over fixed blocks): the particle's share, the sum over its triangles of F / 3 in a
//      fixed order, written into the extra-force array the fused pass adds to the spring forces.
// Thread-count independent: every value is computed by one fixed sequence of operations.
#include <cmath>

#include <tbb/parallel_for.h>

#include "drape/mirror_symmetry.hpp"
#include "drape/simulation.hpp"

namespace drape {

namespace {
constexpr std::size_t aero_chunk = 4096; ///< triangles per parallel chunk
}

void Simulation::cook_vertex_triangles() {
    if (!vertex_tri_offsets_.empty()) return;
    const std::size_t n = cloth_.particle_count, tris = cloth_.triangles.size() / 3;
    vertex_tri_offsets_.assign(n + 1, 0);
    for (std::uint32_t v : cloth_.triangles) ++vertex_tri_offsets_[v + 1];
    for (std::size_t i = 0; i < n; ++i) vertex_tri_offsets_[i + 1] += vertex_tri_offsets_[i];
    vertex_tris_.resize(cloth_.triangles.size());
    std::vector<std::uint32_t> fill(vertex_tri_offsets_.begin(), vertex_tri_offsets_.end() - 1);
    for (std::uint32_t t = 0; t < tris; ++t)
        for (int k = 0; k < 3; ++k) vertex_tris_[fill[cloth_.triangles[3 * t + k]]++] = t;
    // A mirror-exact cloth (mirror_symmetry.hpp): each particle's triangles in mirror order, so that a particle and its
    // twin sum their triangles' terms alike.
    if (cloth_.mirror.empty() || cloth_.mirror_triangle.empty()) return;
    vertex_tris_ = gather(vertex_tris_,
                          mirror_row_sources(vertex_tri_offsets_, vertex_tris_, cloth_.mirror, cloth_.mirror_triangle));
}

void Simulation::cook_aero() {
    if (!tri_fx_.empty()) return;
    cook_vertex_triangles();
    const std::size_t tris = cloth_.triangles.size() / 3;
    tri_fx_.assign(tris, 0.0f);
    tri_fy_.assign(tris, 0.0f);
    tri_fz_.assign(tris, 0.0f);
}

template <bool Parallel> void Simulation::aero_forces_stage() {
    const AeroWind& aero = params_.aero;
    const StateBuffer& s = cur();
    const std::uint32_t* tri = cloth_.triangles.data();
    const std::size_t tris = cloth_.triangles.size() / 3;
    const bool verlet = params_.integrator == Integrator::verlet;
    const float inv_dt = 1.0f / params_.dt;
    const float half_rho_cd = 0.5f * aero.density * aero.drag_coefficient;
    auto velocity = [&](std::uint32_t i, float out[3]) {
        if (verlet) {
            out[0] = s.u[i] * inv_dt;
            out[1] = s.v[i] * inv_dt;
            out[2] = s.w[i] * inv_dt;
        } else {
            out[0] = s.u[i];
            out[1] = s.v[i];
            out[2] = s.w[i];
        }
    };
    auto triangles = [&](std::size_t begin, std::size_t end) {
        for (std::size_t t = begin; t < end; ++t) {
            const std::uint32_t a = tri[3 * t], b = tri[3 * t + 1], c = tri[3 * t + 2];
            const float e1[3] = {s.x[b] - s.x[a], s.y[b] - s.y[a], s.z[b] - s.z[a]};
            const float e2[3] = {s.x[c] - s.x[a], s.y[c] - s.y[a], s.z[c] - s.z[a]};
            // cross = 2 A n
            const float cx = e1[1] * e2[2] - e1[2] * e2[1], cy = e1[2] * e2[0] - e1[0] * e2[2],
                        cz = e1[0] * e2[1] - e1[1] * e2[0];
            const float twice_area = std::sqrt(cx * cx + cy * cy + cz * cz);
            float va[3], vb[3], vc[3];
            velocity(a, va);
            velocity(b, vb);
            velocity(c, vc);
            const float third = 1.0f / 3.0f;
            const float rx = (va[0] + vb[0] + vc[0]) * third - aero.velocity[0];
            const float ry = (va[1] + vb[1] + vc[1]) * third - aero.velocity[1];
            const float rz = (va[2] + vb[2] + vc[2]) * third - aero.velocity[2];
            const float speed = std::sqrt(rx * rx + ry * ry + rz * rz);
            float fx = 0.0f, fy = 0.0f, fz = 0.0f;
            if (twice_area > 0.0f) {
                const float inv = 1.0f / twice_area;
                const float nx = cx * inv, ny = cy * inv, nz = cz * inv;
                const float vn = rx * nx + ry * ny + rz * nz;
                // -1/2 rho Cd A |v| vn n, with A = twice_area / 2; one third per particle.
                const float k = -half_rho_cd * 0.5f * twice_area * speed * vn * third;
                fx = k * nx;
                fy = k * ny;
                fz = k * nz;
            }
            tri_fx_[t] = fx;
            tri_fy_[t] = fy;
            tri_fz_[t] = fz;
        }
    };
    auto particles = [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            float fx = 0.0f, fy = 0.0f, fz = 0.0f;
            for (std::uint32_t k = vertex_tri_offsets_[i]; k < vertex_tri_offsets_[i + 1]; ++k) {
                const std::uint32_t t = vertex_tris_[k];
                fx += tri_fx_[t];
                fy += tri_fy_[t];
                fz += tri_fz_[t];
            }
            extra_fx_[i] = fx;
            extra_fy_[i] = fy;
            extra_fz_[i] = fz;
        }
    };
    const std::size_t n = cloth_.particle_count;
    if constexpr (Parallel) {
        tbb::parallel_for(std::size_t{0}, (tris + aero_chunk - 1) / aero_chunk, [&](std::size_t ch) {
            triangles(ch * aero_chunk, std::min(tris, (ch + 1) * aero_chunk));
        });
        tbb::parallel_for(std::size_t{0}, cloth_.block_count(), [&](std::size_t b) {
            particles(b * block_particles, std::min(n, (b + 1) * block_particles));
        });
    } else {
        triangles(0, tris);
        particles(0, n);
    }
}

template void Simulation::aero_forces_stage<true>();
template void Simulation::aero_forces_stage<false>();

} // namespace drape
