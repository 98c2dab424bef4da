// `drape run`: the headless batch/benchmark run. A stable contract: later versions add flags, never break these.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace drape::app {

/// Flags of `drape run`. Unset optionals keep the scene's own value.
struct RunOptions {
    std::string scene = "hang"; ///< built-in name or path to a .json scene file
    std::optional<std::uint32_t> size; ///< grid cloths: particles per side; tshirt, outline: cells per metre
    int threads = 0;                   ///< 0 = all hardware threads
    std::optional<std::uint64_t> steps;
    std::optional<double> sim_seconds;
    std::optional<double> dt;
    std::optional<std::string> integrator;
    std::optional<std::string> solver;       ///< explicit | implicit
    std::optional<std::uint32_t> iterations; ///< implicit solver: sweeps per step
    std::optional<float> tolerance;          ///< implicit solver: relative residual to stop a step early
    bool fas = false;                        ///< implicit solver: the multilevel guess's coarse correction
    bool single_level = false;               ///< implicit solver: no multilevel guess
    bool fas_at_rest = false;                ///< implicit solver: FAS once the cloth is at rest
    /// A fabric preset (switches the scene to the fabric model) or "springs" (the seeds' spring model).
    std::optional<std::string> material;
    std::optional<float> stiffness;
    std::optional<float> damping;
    std::optional<float> drag;
    bool wind = false;
    bool aero = false;
    std::optional<float> wind_strength;
    std::string kernel = "auto";
    bool staged = false;
    std::optional<float> strain_limit;
    std::optional<std::uint32_t> strain_passes;
    std::optional<std::uint32_t> strain_every;
    std::optional<float> self_collision; ///< thickness, m (0 = off)
    std::optional<std::uint32_t> self_collision_substeps; ///< implicit sub-steps of a step in contact (1 = none)
    std::optional<std::string> export_obj; ///< directory for OBJ frames
    std::uint32_t export_every = 100;      ///< substeps between exported frames
    bool export_overwrite = false;         ///< remove the frame_*.obj files already in export_obj first
    bool json = false;
};

/// Runs the scene; prints figures (human-readable or one JSON object). Returns the process exit code:
/// 0 success, 2 bad input, 3 simulation became non-finite.
int run_command(const RunOptions& options);

} // namespace drape::app
