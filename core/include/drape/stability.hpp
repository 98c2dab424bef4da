// Explicit time-step bound.
//
// For a damped oscillator x'' = -w^2 x - g x', symplectic Euler (and position Verlet, the same scheme) is stable
// iff  w^2 dt^2 + 2 g dt < 4  (Jury criterion on the 2x2 step matrix: trace 2 - w^2 dt^2 - g dt, det 1 - g dt).
// For the whole cloth, Gershgorin's theorem bounds the largest eigenvalue of M^-1 K by
//   w^2_max <= max_i 2 * sum_j k_ij / m_i, and likewise g_max <= kr + max_i 2 * sum_j kd_ij / m_i,
// which holds for any deformation (a spring's Hessian never exceeds k along or across it when stretched).
// dt_max solves w^2 dt^2 + 2 g dt = 4 with those bounds: conservative, and close to SPEC's ~sqrt(m/k).
// k_ij is each spring's own stiffness (its kind's material times Edge::scale). The bending energy (bending.hpp) adds
// Q (x) I3 to K, so row i gains sum_j |Q_ij| / m_i in w^2, and its Rayleigh damping beta Q adds beta sum_j |Q_ij| / m_i
// to g (a spring's Rayleigh damping kd = beta k is already in sum kd).
//
// The aerodynamic wind (AeroWind, seed 004) is a drag quadratic in the relative speed. Linearised about v_rel, the
// Jacobian of F_t = -1/2 rho C_d A_t |v_rel| (v_rel . n) n with respect to v_rel has norm <= rho C_d A_t |v_rel|
// (d/dv of |v|(v.n) is (v.n) v/|v| + |v| n, norm <= 2 |v|); a triangle's v_rel is the mean of its three particles'
// velocities and each particle takes a third of F_t, so the Gershgorin row sum for particle i is
//   g_aero_i = rho C_d (sum over its triangles of A_t / 3) |v_rel|max / m_i,
// added to its damping rate. |v_rel|max = |wind velocity| + aero_speed_margin (the cloth's own speed: aero drag
// never pushes it faster than the wind, and 10 m/s is a free fall from 5 m). Triangle areas come from the rest
// lengths of their edges' springs (Heron). Without it, density 100, C_d 10 and a 100 m/s wind went non-finite at
// substep 4 at the "stable" default dt.
// The force also turns with the triangle: F_t = -1/2 rho C_d |v_rel| (v_rel . N) N / |N| with N = A n = 1/2 e1 x e2,
// whose derivative with respect to a corner's position has norm <= 3 |dN/dx| <= 3/2 L_t (L_t the triangle's longest
// edge), times 1/2 rho C_d |v_rel|^2. Summed over the corners and shared by three, the row sum for particle i is
//   w2_aero_i = 3/4 rho C_d |v_rel|max^2 (sum over its triangles of L_t) / m_i,
// added to its w^2 (an aerodynamic "stiffness"; it dominates for heavy cloth in a strong wind: a 2.5 kg, 0.5 m
// cloth at 100 m/s, rho C_d = 1000, went non-finite at substep 25 with the drag term alone).
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
    double aero_gamma_max = 0.0; ///< 1/s, largest linearised aerodynamic drag rate (0 without aero)
};

/// Margin added to the wind speed for the cloth's own speed in the aero term, m/s.
inline constexpr double aero_speed_margin = 10.0;

struct AeroWind;

/// The bound from springs, spring damping and air drag (no aerodynamic wind).
StabilityBound stability_bound(const Cloth& cloth, float air_drag);
/// The bound for these run parameters: air drag and, when params.aero.enabled, the aerodynamic wind.
StabilityBound stability_bound(const Cloth& cloth, const SimulationParams& params);
/// aero: nullptr = no aerodynamic wind.
StabilityBound stability_bound(const Cloth& cloth, float air_drag, const AeroWind* aero);

/// The default substep for a cloth: 90% of the bound (the air_drag form ignores the aerodynamic wind).
double default_dt(const Cloth& cloth, float air_drag);
double default_dt(const Cloth& cloth, const SimulationParams& params);

/// Throws InvalidInput when dt exceeds the bound (compared in float, dt's precision); the message names `what`
/// (e.g. "dt", "--dt", "scene.json: physics.dt") and states the bound and the substeps needed.
void check_stability(const Cloth& cloth, const SimulationParams& params, const std::string& what = "dt");

/// A time step as float precision holds it: the fewest significant digits (6 to 9) that read back as the same
/// float, so that a printed bound pasted back as dt is that float.
std::string format_dt(double dt);

} // namespace drape
