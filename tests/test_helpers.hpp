// Shared test fixtures: hang scenes with a randomly perturbed state.
#pragma once

#include <cmath>
#include <random>

#include "drape/scene_hang.hpp"
#include "drape/simulation.hpp"
#include "drape/stability.hpp"

namespace drape::testing {

/// True in a build with AddressSanitizer (the CI's second run, 10-30 times slower than Release). The longest
/// simulations run shorter there (fewer steps or particles; the worker-count determinism tests at 1, 3 and 8 workers
/// instead of 1, 2, 3, 5 and 8), with the same assertions: the Release run checks their figures in full, and the ASan
/// run looks for memory errors, which every code path shows in its first steps.
inline constexpr bool sanitized =
#if defined(__SANITIZE_ADDRESS__)
    true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
    true;
#else
    false;
#endif
#else
    false;
#endif

/// Hang scene of n x n with positions perturbed by up to `jitter` grid spacings and random velocities up to `speed`
/// m/s (so springs are stretched, compressed and moving: every term of the force matters).
inline SceneBuild perturbed_hang(std::uint32_t n, float jitter, float speed, unsigned seed, HangParams hp = {}) {
    hp.n = n;
    SceneBuild scene = build_hang_scene(hp);
    std::mt19937 rng(seed);
    const float h = hp.size / float(n - 1);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    InitialState& s = scene.initial;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
        s.x[i] += jitter * h * u(rng);
        s.y[i] += jitter * h * u(rng);
        s.z[i] += jitter * h * u(rng);
        s.vx[i] = speed * u(rng);
        s.vy[i] = speed * u(rng);
        s.vz[i] = speed * u(rng);
    }
    return scene;
}

/// An n x n grid cloth of side `size`, folded in half over itself just above the ground (y = 4 mm): the columns
/// i < n/2 flat, the rest folded back one spacing above them, shifted by 0.3 spacing in x and z and waved by up to
/// 0.3 spacing; at rest. Positions in grid_index order. The folded pile of test_self_collision.cpp, test_implicit.cpp
/// and test_scene_write.cpp.
inline void fold_over_itself(std::uint32_t n, float size, std::vector<float>& x, std::vector<float>& y,
                             std::vector<float>& z) {
    const float s = size / float(n - 1), yb = 0.004f;
    x.assign(std::size_t(n) * n, 0.0f);
    y.assign(x.size(), 0.0f);
    z.assign(x.size(), 0.0f);
    for (std::uint32_t j = 0; j < n; ++j)
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::uint32_t k = grid_index(n, i, j);
            if (i < n / 2) {
                x[k] = float(i) * s, y[k] = yb, z[k] = float(j) * s;
            } else {
                const float wave = 0.3f * s * std::sin(0.7f * float(j)) * std::sin(0.9f * float(i - n / 2));
                x[k] = float(n - 1 - i) * s + 0.3f * s, y[k] = yb + s + wave, z[k] = float(j) * s + 0.3f * s;
            }
        }
}
inline void fold_over_itself(std::uint32_t n, float size, InitialState& s) {
    fold_over_itself(n, size, s.x, s.y, s.z);
    s.vx.assign(s.x.size(), 0.0f);
    s.vy.assign(s.x.size(), 0.0f);
    s.vz.assign(s.x.size(), 0.0f);
}

inline SimulationParams default_params(const Cloth& cloth, Integrator integrator = Integrator::symplectic_euler,
                                       KernelPath kernel = KernelPath::automatic) {
    SimulationParams p;
    p.dt = static_cast<float>(default_dt(cloth, p.air_drag));
    p.integrator = integrator;
    p.kernel = kernel;
    return p;
}

} // namespace drape::testing
