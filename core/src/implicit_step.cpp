// One implicit step (backward Euler by vertex block descent; implicit.hpp, docs/implicit.md), from buffer A
// (x^n, v^n) into buffer B:
//   0. aero_forces at x^n (when on), as constant forces of the step;
//   1. per particle: the inertial prediction y = x^n + h v^n + h^2 (g + wind + f_aero / m) and the initial guess
//      (VBD paper section 3.6, "adaptive"): x^n + h v^n + h^2 (s g + the rest), s = the part of gravity the particle
//      was last seen accelerating with, clamped to [0, 1] (a resting particle starts at rest, a falling one falls);
//   2. `iterations` sweeps: colours in order, the vertices of a colour in fixed chunks in parallel, each vertex one
//      local Newton step (vbd.hpp) in place (Gauss-Seidel), or every vertex from the previous sweep (Jacobi);
//      after each sweep Chebyshev's extrapolation (VBD section 3.7; Wang 2015) when chebyshev_rho > 0; an early stop
//      once the sweep residual falls below tolerance x the first sweep's;
//   3. v^{n+1} = (x - x^n) / h.
// The step then goes through the same strain-limit and collide passes as an explicit substep (substep.cpp).
// Determinism: a vertex reads only vertices of other colours and writes only itself; residuals are summed per fixed
// chunk and the chunks in order; so every thread count gives the same bits. No allocation: the scratch is cooked
// with the solver (cook_implicit).
#include <algorithm>
#include <cmath>

#include "drape/simulation.hpp"
#include "for_each_index.hpp"
#include "vbd.hpp"

namespace drape {

const char* solver_name(Solver solver) noexcept { return solver == Solver::implicit ? "implicit" : "explicit"; }

namespace {
constexpr std::size_t vbd_chunk = 256; ///< vertices per parallel chunk of a colour (fixed: determinism)
}

void Simulation::cook_implicit() {
    if (vbd_.particle_count == cloth_.particle_count && !vbd_.colour_offsets.empty()) return;
    vbd_ = vbd::cook(cloth_);
    const std::size_t n = cloth_.particle_count;
    for (std::vector<float>* a : {&pred_x_, &pred_y_, &pred_z_, &cheb1_x_, &cheb1_y_, &cheb1_z_, &cheb2_x_, &cheb2_y_,
                                  &cheb2_z_, &jac_x_, &jac_y_, &jac_z_})
        a->assign(n, 0.0f);
    colour_chunk_base_.assign(vbd_.colour_count() + 1, 0);
    for (std::size_t c = 0; c < vbd_.colour_count(); ++c) {
        const std::size_t size = vbd_.colour_offsets[c + 1] - vbd_.colour_offsets[c];
        colour_chunk_base_[c + 1] = colour_chunk_base_[c] + static_cast<std::uint32_t>((size + vbd_chunk - 1) / vbd_chunk);
    }
    const std::size_t jacobi_chunks = (n + vbd_chunk - 1) / vbd_chunk;
    chunk_residual_.assign(std::max<std::size_t>(colour_chunk_base_.back(), jacobi_chunks), 0.0);
}

template <bool Parallel> void Simulation::implicit_step() {
    const std::size_t n = cloth_.particle_count;
    const StateBuffer& a = buffers_[current_];
    StateBuffer& b = buffers_[1 - current_];
    const float h = params_.dt, h2 = h * h, inv_h = 1.0f / h;
    const ImplicitParams& ip = params_.implicit;
    const float* inv_mass = cloth_.inv_mass.data();

    if (params_.aero.enabled) aero_forces_stage<Parallel>();
    const bool aero = params_.aero.enabled;

    // 1. Prediction and initial guess. Buffer B still holds the state one step back: its velocity is v^{n-1}.
    const float gx = params_.gravity[0], gy = params_.gravity[1], gz = params_.gravity[2];
    const float g2 = gx * gx + gy * gy + gz * gz;
    const double t = static_cast<double>(steps_done_) * static_cast<double>(h);
    const bool wind = params_.wind.enabled;
    const float wind_x = params_.wind.strength * static_cast<float>(std::sin(10.0 * t));
    const float wind_phase = static_cast<float>(std::fmod(10.0 * t + cloth_.origin[2], 2.0 * M_PI));
    for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
        const std::size_t begin = blk * block_particles, end = std::min(begin + block_particles, n);
        for (std::size_t i = begin; i < end; ++i) {
            const float x = a.x[i], y = a.y[i], z = a.z[i];
            if (inv_mass[i] == 0.0f) {
                pred_x_[i] = b.x[i] = x;
                pred_y_[i] = b.y[i] = y;
                pred_z_[i] = b.z[i] = z;
                continue;
            }
            float ex = 0.0f, ey = 0.0f, ez = 0.0f; // accelerations other than gravity
            if (wind) {
                ex += wind_x;
                ez += params_.wind.strength * std::fabs(std::sin(z + wind_phase));
            }
            if (aero) {
                ex += extra_fx_[i] * inv_mass[i];
                ey += extra_fy_[i] * inv_mass[i];
                ez += extra_fz_[i] * inv_mass[i];
            }
            const float vx = a.u[i], vy = a.v[i], vz = a.w[i];
            pred_x_[i] = x + h * vx + h2 * (gx + ex);
            pred_y_[i] = y + h * vy + h2 * (gy + ey);
            pred_z_[i] = z + h * vz + h2 * (gz + ez);
            float s = 0.0f;
            if (g2 > 0.0f) {
                const float ax = (vx - b.u[i]) * inv_h, ay = (vy - b.v[i]) * inv_h, az = (vz - b.w[i]) * inv_h;
                s = std::clamp((ax * gx + ay * gy + az * gz) / g2, 0.0f, 1.0f);
            }
            b.x[i] = x + h * vx + h2 * (s * gx + ex);
            b.y[i] = y + h * vy + h2 * (s * gy + ey);
            b.z[i] = z + h * vz + h2 * (s * gz + ez);
        }
    });

    // 2. Sweeps.
    vbd::SweepArgs args{a.x.data(),     a.y.data(),   a.z.data(),   pred_x_.data(), pred_y_.data(),
                        pred_z_.data(), b.x.data(),   b.y.data(),   b.z.data(),     inv_mass,
                        &vbd_,          inv_h * inv_h, params_.air_drag * inv_h, inv_h};
    const bool jacobi = ip.method == ImplicitMethod::jacobi;
    const bool chebyshev = ip.chebyshev_rho > 0.0f;
    const float rho2 = ip.chebyshev_rho * ip.chebyshev_rho;
    float omega = 1.0f;
    if (chebyshev) {
        std::copy_n(b.x.data(), n, cheb1_x_.data());
        std::copy_n(b.y.data(), n, cheb1_y_.data());
        std::copy_n(b.z.data(), n, cheb1_z_.data());
    }
    implicit_stats_ = ImplicitStats{};
    for (std::uint32_t it = 0; it < ip.iterations; ++it) {
        std::size_t chunks_used = 0;
        if (!jacobi) {
            for (std::size_t c = 0; c < vbd_.colour_count(); ++c) {
                const std::uint32_t first = vbd_.colour_offsets[c], last = vbd_.colour_offsets[c + 1];
                const std::uint32_t base = colour_chunk_base_[c];
                const std::size_t chunks = colour_chunk_base_[c + 1] - base;
                for_each_index<Parallel>(chunks, [&](std::size_t ch) {
                    double r = 0.0;
                    const std::uint32_t lo = first + static_cast<std::uint32_t>(ch * vbd_chunk);
                    const std::uint32_t hi = std::min<std::uint32_t>(last, lo + static_cast<std::uint32_t>(vbd_chunk));
                    for (std::uint32_t k = lo; k < hi; ++k) {
                        const std::uint32_t i = vbd_.colour_vertex[k];
                        if (inv_mass[i] == 0.0f) continue;
                        float out[3];
                        r += vbd::solve_vertex(args, i, out);
                        b.x[i] = out[0];
                        b.y[i] = out[1];
                        b.z[i] = out[2];
                    }
                    chunk_residual_[base + ch] = r;
                });
            }
            chunks_used = colour_chunk_base_.back();
        } else {
            const std::size_t chunks = (n + vbd_chunk - 1) / vbd_chunk;
            for_each_index<Parallel>(chunks, [&](std::size_t ch) {
                double r = 0.0;
                for (std::size_t i = ch * vbd_chunk, hi = std::min(n, (ch + 1) * vbd_chunk); i < hi; ++i) {
                    if (inv_mass[i] == 0.0f) {
                        jac_x_[i] = b.x[i];
                        jac_y_[i] = b.y[i];
                        jac_z_[i] = b.z[i];
                        continue;
                    }
                    float out[3];
                    r += vbd::solve_vertex(args, static_cast<std::uint32_t>(i), out);
                    jac_x_[i] = out[0];
                    jac_y_[i] = out[1];
                    jac_z_[i] = out[2];
                }
                chunk_residual_[ch] = r;
            });
            std::copy_n(jac_x_.data(), n, b.x.data());
            std::copy_n(jac_y_.data(), n, b.y.data());
            std::copy_n(jac_z_.data(), n, b.z.data());
            chunks_used = chunks;
        }
        double r2 = 0.0; // in chunk order: the same bits for any thread count
        for (std::size_t ch = 0; ch < chunks_used; ++ch) r2 += chunk_residual_[ch];
        const double r = std::sqrt(r2);
        if (it == 0) implicit_stats_.first_residual = r;
        implicit_stats_.last_residual = r;
        implicit_stats_.iterations = it + 1;

        if (chebyshev) {
            // x^(k) = omega (xbar^(k) - x^(k-2)) + x^(k-2); omega_1 = 1, omega_2 = 2 / (2 - rho^2),
            // omega_k = 4 / (4 - rho^2 omega_{k-1}).
            omega = it == 0 ? 1.0f : it == 1 ? 2.0f / (2.0f - rho2) : 4.0f / (4.0f - rho2 * omega);
            const float w = omega;
            for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
                const std::size_t begin = blk * block_particles, end = std::min(begin + block_particles, n);
                for (std::size_t i = begin; i < end; ++i) {
                    float px = b.x[i], py = b.y[i], pz = b.z[i];
                    if (it > 0 && inv_mass[i] != 0.0f) {
                        px = w * (px - cheb2_x_[i]) + cheb2_x_[i];
                        py = w * (py - cheb2_y_[i]) + cheb2_y_[i];
                        pz = w * (pz - cheb2_z_[i]) + cheb2_z_[i];
                        b.x[i] = px;
                        b.y[i] = py;
                        b.z[i] = pz;
                    }
                    cheb2_x_[i] = cheb1_x_[i];
                    cheb2_y_[i] = cheb1_y_[i];
                    cheb2_z_[i] = cheb1_z_[i];
                    cheb1_x_[i] = px;
                    cheb1_y_[i] = py;
                    cheb1_z_[i] = pz;
                }
            });
        }
        if (ip.tolerance > 0.0f && r <= double(ip.tolerance) * implicit_stats_.first_residual) break;
    }
    implicit_stats_.relative_residual =
        implicit_stats_.first_residual > 0.0 ? implicit_stats_.last_residual / implicit_stats_.first_residual : 0.0;

    // 3. Velocities; finite check per block.
    for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
        const std::size_t begin = blk * block_particles, end = std::min(begin + block_particles, n);
        bool ok = true;
        for (std::size_t i = begin; i < end; ++i) {
            b.u[i] = (b.x[i] - a.x[i]) * inv_h;
            b.v[i] = (b.y[i] - a.y[i]) * inv_h;
            b.w[i] = (b.z[i] - a.z[i]) * inv_h;
            ok = ok && std::isfinite(b.x[i] + b.y[i] + b.z[i] + b.u[i] + b.v[i] + b.w[i]);
        }
        block_ok_[blk] = ok ? 1 : 0;
    });
}

template void Simulation::implicit_step<true>();
template void Simulation::implicit_step<false>();

} // namespace drape
