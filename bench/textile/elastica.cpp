// Analytic references: the heavy elastica by shooting, Peirce's relation, small-deflection beam theory.
#include "elastica.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace drape::textile {

namespace {

// State (phi, phi', x, y) along s; y up, the strip bends down.
using State = std::array<double, 4>;

State rhs(double s, const State& q, double l, double c3) {
    return {q[1], -(l - s) * std::cos(q[0]) / c3, std::cos(q[0]), -std::sin(q[0])};
}

/// Integrates from the clamp with phi'(0) = kappa0; fills `out` when given. Returns phi'(l), or (without `out`) the
/// first negative phi' met on the way.
double shoot(double l, double c, double kappa0, int steps, ElasticaShape* out) {
    const double c3 = c * c * c, h = l / steps;
    State q{0.0, kappa0, 0.0, 0.0};
    if (out) {
        out->s.assign(1, 0.0);
        out->x.assign(1, 0.0);
        out->y.assign(1, 0.0);
        out->phi.assign(1, 0.0);
    }
    for (int k = 0; k < steps; ++k) {
        const double s = k * h;
        auto add = [](const State& a, const State& b, double f) {
            return State{a[0] + f * b[0], a[1] + f * b[1], a[2] + f * b[2], a[3] + f * b[3]};
        };
        const State k1 = rhs(s, q, l, c3);
        const State k2 = rhs(s + 0.5 * h, add(q, k1, 0.5 * h), l, c3);
        const State k3 = rhs(s + 0.5 * h, add(q, k2, 0.5 * h), l, c3);
        const State k4 = rhs(s + h, add(q, k3, h), l, c3);
        for (int i = 0; i < 4; ++i) q[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        if (!out && q[1] < 0.0) return q[1];
        if (out) {
            out->s.push_back((k + 1) * h);
            out->phi.push_back(q[0]);
            out->x.push_back(q[2]);
            out->y.push_back(q[3]);
        }
    }
    return q[1];
}

} // namespace

double ElasticaShape::chord_angle() const { return std::atan2(-tip_y(), tip_x()); }

void ElasticaShape::at(double sq, double& xo, double& yo) const {
    sq = std::clamp(sq, 0.0, length);
    const auto it = std::upper_bound(s.begin(), s.end(), sq);
    const std::size_t k = std::min<std::size_t>(std::max<std::ptrdiff_t>(it - s.begin(), 1), s.size() - 1);
    const double t = (sq - s[k - 1]) / (s[k] - s[k - 1]);
    xo = x[k - 1] + t * (x[k] - x[k - 1]);
    yo = y[k - 1] + t * (y[k] - y[k - 1]);
}

ElasticaShape solve_elastica(double l, double c, int steps) {
    if (!(l > 0.0 && c > 0.0 && steps >= 10)) throw std::invalid_argument("solve_elastica: l, c > 0, steps >= 10");
    // The physical shape bends down monotonically: phi' > 0 on [0, l) and phi'(l) = 0. Raising kappa0 raises phi
    // everywhere, which lowers cos(phi) (phi in [0, pi]) and so raises phi' everywhere: "phi' stays >= 0 up to l" is
    // monotone in kappa0. It fails at kappa0 = 0 and holds at kappa0 = l^2 / (2 c^3) (the load integral is at most
    // that since cos <= 1). Bisection on it converges to the physical root; a plain root search on phi'(l) can land
    // on shapes that curl up and over (l / c > ~3.5 has several).
    double lo = 0.0, hi = l * l / (2.0 * c * c * c);
    for (int it = 0; it < 200 && hi - lo > 1e-15 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        (shoot(l, c, mid, steps, nullptr) < 0.0 ? lo : hi) = mid;
    }
    ElasticaShape out;
    out.length = l;
    out.bending_length = c;
    out.kappa0 = 0.5 * (lo + hi);
    shoot(l, c, out.kappa0, steps, &out);
    return out;
}

double bending_length(double rigidity, double areal_density, double gravity) {
    return std::cbrt(rigidity / (areal_density * gravity));
}

double peirce_bending_length(double l, double theta) {
    return l * std::cbrt(std::cos(0.5 * theta) / (8.0 * std::tan(theta)));
}

double elastica_bending_length(double l, double theta) {
    if (!(theta > 0.0 && theta < 1.5707963267948966)) throw std::invalid_argument("elastica_bending_length: theta");
    // The chord angle rises with l / c from 0 towards pi/2.
    double lo = 1e-3, hi = 20.0; // l / c (the chord angle is within 0.1 deg of 90 deg beyond)
    for (int it = 0; it < 100 && hi / lo > 1.0 + 1e-12; ++it) {
        const double mid = std::sqrt(lo * hi);
        (solve_elastica(l, l / mid, 2000).chord_angle() < theta ? lo : hi) = mid;
    }
    return l / std::sqrt(lo * hi);
}

double small_deflection_tip(double q, double length, double rigidity) {
    return q * std::pow(length, 4) / (8.0 * rigidity);
}

} // namespace drape::textile
