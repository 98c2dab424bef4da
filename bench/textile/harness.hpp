// Textile test harness (bench/textile, tests/test_textile.cpp): builds a grid cloth with the fabric model through
// build_hang_scene, holds it as a standard test does (a clamp, a load, a disc), settles it with air drag, and
// measures what the test measures. Shared by the drape_textile bench program and the cheap ctest versions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "drape/fabric.hpp"
#include "drape/simulation.hpp"

namespace drape::textile {

/// A fabric preset by name (find_fabric); throws std::invalid_argument naming an unknown one.
Fabric textile_fabric(const std::string& name);

/// Velocity of particle i, m/s, whatever the integrator stores (the one place that reads integrator state).
std::array<float, 3> particle_velocity(const Simulation& sim, std::size_t i);

/// How a run was settled: simulated time, substeps, wall time, final speed.
struct SettleStats {
    double sim_time = 0.0;    ///< s
    std::size_t steps = 0;
    double wall = 0.0;        ///< s
    double dt = 0.0;          ///< s
    float max_speed = 0.0f;   ///< m/s at the end
    bool settled = false;     ///< max speed fell below the tolerance before the time limit
};

/// Steps until, at `checks_needed` checks in a row (every `check_every` s of simulated time), the fastest particle is
/// slower than `speed_tol` (m/s) or the measured figure `probe` (when given) moved less than `probe_tol` since the
/// previous check; or until `max_time` s. (Float32 state keeps light particles jittering at ~1 mm/s around a stiff
/// equilibrium, so a test that measures one figure settles on that figure.)
SettleStats settle(Simulation& sim, double max_time, double speed_tol, double check_every = 0.01,
                   int checks_needed = 3, const std::function<double(const Simulation&)>& probe = {},
                   double probe_tol = 0.0);

// --- Peirce cantilever (ASTM D1388) ------------------------------------------------------------------------------
struct CantileverCase {
    Fabric fabric;
    /// Wanted overhang, m: the strip gets the whole number of cells m that brings l = (m + 1/2) h nearest to it.
    double overhang = 0.04;
    double spacing = 0.01;  ///< h, m
    bool along_v = false;   ///< false: the strip runs along u (warp, bend_u); true: along v (weft, bend_v)
    /// Columns (rows) held. A held segment fixes the slope; the clamp line is the midpoint of the last held segment
    /// (a segment's direction is the slope at its midpoint to second order), so the overhang is l = (m + 1/2) h for
    /// m free cells. (Taking the last held row as the clamp makes the strip effectively h/2 longer: a first-order
    /// error, reported as c_last_row.)
    int clamp_rows = 2;
    double drag = -1.0;     ///< air drag, 1/s; < 0: critical for the strip's first mode, 2 w1
    double max_time = 20.0; ///< s
};
struct CantileverResult {
    std::uint32_t n = 0;           ///< grid side (particles)
    std::size_t particles = 0;
    double overhang = 0.0;         ///< l, m, from the clamp line to the tip
    double c_input = 0.0;          ///< (B / (w g))^(1/3), m
    double theta = 0.0;            ///< chord angle clamp -> tip, rad
    double c_peirce = 0.0;         ///< from theta by Peirce's relation, m
    double c_elastica = 0.0;       ///< from theta by the exact elastica, m
    double c_last_row = 0.0;       ///< the same with the clamp at the last held row (l = m h), m
    double theta_reference = 0.0;  ///< the elastica's chord angle for c_input, rad
    double shape_error = 0.0;      ///< max distance of a node (column mean) from the elastica at its arc length / l
    double tip_x = 0.0, tip_y = 0.0, ref_tip_x = 0.0, ref_tip_y = 0.0; ///< m, from the clamp
    SettleStats settle;
};
CantileverResult run_cantilever(const CantileverCase& c);

// --- Uniaxial tension -------------------------------------------------------------------------------------------
struct TensionCase {
    Fabric fabric;
    double length = 0.1;   ///< m, the square strip's side
    double spacing = 0.01; ///< m
    bool along_v = false;
    double strain = 0.01;  ///< target strain from the end load T = strain * stretch (N/m)
    double max_time = 5.0;
};
struct TensionResult {
    std::uint32_t n = 0;
    double tension = 0.0;          ///< end load per unit width, N/m
    double expected_strain = 0.0;  ///< end load plus the strip's own weight along the load, over the stiffness
    double measured_strain = 0.0;  ///< mean displacement of the loaded row / length
    double lateral_strain = 0.0;   ///< change of the loaded row's width / width (Poisson contraction)
    SettleStats settle;
};
TensionResult run_tension(const TensionCase& c);

} // namespace drape::textile
