// Shared test fixtures: hang scenes with a randomly perturbed state.
#pragma once

#include <random>

#include "drape/scene_hang.hpp"
#include "drape/simulation.hpp"
#include "drape/stability.hpp"

namespace drape::testing {

/// True in a build with AddressSanitizer (the CI's second run, 10-30 times slower than Release). The longest
/// simulations run shorter there (fewer steps or particles, never fewer checks): the Release run checks their figures
/// in full, and the ASan run looks for memory errors, which every code path shows in its first steps.
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

inline SimulationParams default_params(const Cloth& cloth, Integrator integrator = Integrator::symplectic_euler,
                                       KernelPath kernel = KernelPath::automatic) {
    SimulationParams p;
    p.dt = static_cast<float>(default_dt(cloth, p.air_drag));
    p.integrator = integrator;
    p.kernel = kernel;
    return p;
}

} // namespace drape::testing
