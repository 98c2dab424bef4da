// Analytic references for the textile tests (bench/textile, tests/test_textile.cpp): the heavy elastica, Peirce's
// cantilever relation and small-deflection beam theory. Plain double precision, no drape types.
//
// Heavy elastica: an inextensible strip of bending rigidity B (N*m per unit width) and weight q = w g (N/m^2, per
// unit width and length), clamped horizontally at s = 0, free at s = l. With phi(s) the angle below the horizontal,
// moment balance of the part beyond s gives
//   B phi'' = -q (l - s) cos(phi),   phi(0) = 0,   phi'(l) = 0 (no moment at the free end).
// With the bending length c = (B / q)^(1/3) this is phi'' = -(l - s) cos(phi) / c^3: the shape depends on l / c only.
// solve_elastica shoots on phi'(0) (bisection, classical RK4 in double).
#pragma once

#include <vector>

namespace drape::textile {

struct ElasticaShape {
    double length = 0.0;         ///< l, m
    double bending_length = 0.0; ///< c, m
    double kappa0 = 0.0;         ///< phi'(0), 1/m: curvature at the clamp
    std::vector<double> s, x, y, phi; ///< arc length, position (x along the ledge, y up; clamp at 0) and angle
    double tip_x() const { return x.back(); }
    double tip_y() const { return y.back(); }
    /// Angle below the horizontal of the chord from the clamp to the tip, rad (the Peirce / ASTM D1388 angle).
    double chord_angle() const;
    /// Position at arc length s (linear interpolation between the integration steps, which are fine).
    void at(double s_query, double& x_out, double& y_out) const;
};

/// The clamped heavy elastica of length l and bending length c (both > 0), `steps` RK4 steps.
ElasticaShape solve_elastica(double length, double bending_length, int steps = 4000);

/// Bending length c = (B / (w g))^(1/3), m: B in N*m, w in kg/m^2.
double bending_length(double rigidity, double areal_density, double gravity = 9.81);

/// Peirce's relation (Peirce 1930; ASTM D1388): bending length from the overhang l and the chord angle theta (rad):
///   c = l (cos(theta / 2) / (8 tan theta))^(1/3).   (An approximation of the elastica; see peirce_error.)
double peirce_bending_length(double length, double theta);

/// The exact bending length for overhang l and chord angle theta (0 < theta < pi/2): the c whose elastica has that
/// chord angle (bisection on l / c).
double elastica_bending_length(double length, double theta);

/// Small-deflection (Euler-Bernoulli) cantilever under a uniform load q: tip deflection q l^4 / (8 B).
double small_deflection_tip(double q, double length, double rigidity);

} // namespace drape::textile
