// Plain scalar reference of one substep, in double precision, written straight from the formulas (SPEC.md) over
// the cold edge list - deliberately a different structure from the SIMD kernels (no CSR, no stencil, no fusion).
// The optimised kernels are tested against it.
#pragma once

#include <vector>

#include "drape/simulation.hpp"

namespace drape::reference {

struct State {
    std::vector<double> x, y, z;    ///< positions, m
    std::vector<double> vx, vy, vz; ///< velocities, m/s
};

struct Forces {
    std::vector<double> fx, fy, fz; ///< spring + damping force, N
    std::vector<double> scale;      ///< per particle: sum of |term| over its springs (cancellation scale), N
};

/// Spring forces F_i = sum_j [k (1 - l0/l) d + kd ((v_j - v_i).d) d / l^2], d = x_j - x_i (k, kd: the kind's
/// material times Edge::scale), plus the bending forces -Q (x + beta v) from the cold element list: per element
/// q_e = sum_k c_k (x_k + beta v_k), F_k -= w_e c_k q_e (bending.hpp).
Forces spring_forces(const Cloth& cloth, const State& s);

/// External acceleration of movable particles: g - kr v + wind(t); zero for pinned.
void external_acceleration(const Cloth& cloth, const SimulationParams& p, const State& s, double t,
                           std::vector<double>& ax, std::vector<double>& ay, std::vector<double>& az);

/// One symplectic-Euler substep (velocities in State are the true velocities).
State step_euler(const Cloth& cloth, const SimulationParams& p, const State& s, double t);

/// State read from a Simulation (velocities via Simulation::velocity).
State read_state(const Simulation& sim);

} // namespace drape::reference
