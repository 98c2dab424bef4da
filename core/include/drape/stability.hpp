// Explicit time-step bound.
//
// For a damped oscillator x'' = -w^2 x - g x', symplectic Euler (and position Verlet, the same scheme) is stable
// iff  w^2 dt^2 + 2 g dt < 4  (Jury criterion on the 2x2 step matrix: trace 2 - w^2 dt^2 - g dt, det 1 - g dt).
// For the whole cloth, Gershgorin's theorem bounds the largest eigenvalue of M^-1 K by
//   w^2_max <= max_i 2 * sum_j k_ij / m_i, and likewise g_max <= kr + max_i 2 * sum_j kd_ij / m_i,
// which holds for any deformation (a spring's Hessian never exceeds k along or across it when stretched).
// dt_max solves w^2 dt^2 + 2 g dt = 4 with those bounds: conservative, and close to SPEC's ~sqrt(m/k).
#pragma once

#include <string>

#include "drape/cloth.hpp"

namespace drape {

struct SimulationParams;

struct StabilityBound {
    double dt_max = 0.0;        ///< s, largest stable substep
    double omega2_max = 0.0;    ///< 1/s^2, Gershgorin bound of the stiffness spectrum
    double gamma_max = 0.0;     ///< 1/s, Gershgorin bound of the damping spectrum (incl. air drag)
    double min_mass = 0.0;      ///< kg, lightest movable particle
    double max_stiffness = 0.0; ///< N/m, stiffest spring
};

StabilityBound stability_bound(const Cloth& cloth, float air_drag);

/// The default substep for a cloth: 90% of the bound.
double default_dt(const Cloth& cloth, float air_drag);

/// Throws InvalidInput when dt exceeds the bound (compared in float, dt's precision); the message names `what`
/// (e.g. "dt", "--dt", "scene.json: physics.dt") and states the bound and the substeps needed.
void check_stability(const Cloth& cloth, const SimulationParams& params, const std::string& what = "dt");

/// A time step as float precision holds it: the fewest significant digits (6 to 9) that read back as the same
/// float, so that a printed bound pasted back as dt is that float.
std::string format_dt(double dt);

} // namespace drape
