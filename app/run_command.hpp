// `drape run`: the headless batch/benchmark run. A stable contract: later versions add flags, never break these.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace drape::app {

struct RunOptions {
    std::string scene = "hang";
    std::uint32_t size = 100;
    int threads = 0; ///< 0 = all hardware threads
    std::optional<std::uint64_t> steps;
    std::optional<double> sim_seconds;
    std::optional<double> dt;
    std::string integrator = "euler";
    float stiffness = 1000.0f;
    float damping = 0.05f;
    float drag = 0.2f;
    bool wind = false;
    float wind_strength = 2.0f;
    std::string kernel = "auto";
    bool staged = false;
    float strain_limit = 0.0f;
    std::uint32_t strain_passes = 4;
    std::uint32_t strain_every = 1;
    bool json = false;
};

/// Runs the scene; prints figures (human-readable or one JSON object). Returns the process exit code:
/// 0 success, 2 bad input, 3 simulation became non-finite.
int run_command(const RunOptions& options);

} // namespace drape::app
