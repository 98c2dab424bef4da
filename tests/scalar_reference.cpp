#include "scalar_reference.hpp"

#include <cmath>

namespace drape::reference {

Forces spring_forces(const Cloth& cloth, const State& s) {
    const std::size_t n = cloth.particle_count;
    Forces f{std::vector<double>(n, 0.0), std::vector<double>(n, 0.0), std::vector<double>(n, 0.0),
             std::vector<double>(n, 0.0)};
    for (const Edge& e : cloth.edges) {
        const SpringMaterial& mat = cloth.material[static_cast<std::size_t>(e.kind)];
        const struct {
            double stiffness, damping;
        } m{double(mat.stiffness) * e.scale, double(mat.damping) * e.scale};
        const double dx = s.x[e.b] - s.x[e.a], dy = s.y[e.b] - s.y[e.a], dz = s.z[e.b] - s.z[e.a];
        const double l2 = dx * dx + dy * dy + dz * dz;
        const double l = std::sqrt(l2);
        const double dvx = s.vx[e.b] - s.vx[e.a], dvy = s.vy[e.b] - s.vy[e.a], dvz = s.vz[e.b] - s.vz[e.a];
        const double hooke = m.stiffness * (1.0 - e.rest / l);
        const double damp = m.damping * (dvx * dx + dvy * dy + dvz * dz) / l2;
        const double c = hooke + damp; // force on a is c d, on b is -c d
        f.fx[e.a] += c * dx;
        f.fy[e.a] += c * dy;
        f.fz[e.a] += c * dz;
        f.fx[e.b] -= c * dx;
        f.fy[e.b] -= c * dy;
        f.fz[e.b] -= c * dz;
        const double mag = (std::fabs(hooke) + std::fabs(damp)) * l;
        f.scale[e.a] += mag;
        f.scale[e.b] += mag;
    }
    const double beta = cloth.bending.damping;
    for (const BendElement& el : cloth.bending.elements) {
        double q[3] = {0.0, 0.0, 0.0}, spread = 0.0;
        for (std::size_t k = 0; k < 4; ++k) {
            const std::uint32_t i = el.v[k];
            q[0] += el.c[k] * (s.x[i] + beta * s.vx[i]);
            q[1] += el.c[k] * (s.y[i] + beta * s.vy[i]);
            q[2] += el.c[k] * (s.z[i] + beta * s.vz[i]);
        }
        for (std::size_t k = 0; k < 4; ++k) {
            const std::uint32_t i = el.v[k];
            const double wc = double(el.weight) * el.c[k];
            f.fx[i] -= wc * q[0];
            f.fy[i] -= wc * q[1];
            f.fz[i] -= wc * q[2];
            // Cancellation scale: the kernels sum w c_k c_m (x_m - x_k + beta (v_m - v_k)) over m.
            spread = 0.0;
            for (std::size_t m = 0; m < 4; ++m) {
                const std::uint32_t j = el.v[m];
                const double dx = s.x[j] - s.x[i] + beta * (s.vx[j] - s.vx[i]),
                             dy = s.y[j] - s.y[i] + beta * (s.vy[j] - s.vy[i]),
                             dz = s.z[j] - s.z[i] + beta * (s.vz[j] - s.vz[i]);
                spread += std::fabs(el.c[m]) * std::sqrt(dx * dx + dy * dy + dz * dz);
            }
            f.scale[i] += std::fabs(wc) * spread;
        }
    }
    return f;
}

void external_acceleration(const Cloth& cloth, const SimulationParams& p, const State& s, double t,
                           std::vector<double>& ax, std::vector<double>& ay, std::vector<double>& az) {
    const std::size_t n = cloth.particle_count;
    ax.assign(n, 0.0);
    ay.assign(n, 0.0);
    az.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i) {
        if (cloth.inv_mass[i] == 0.0f) continue;
        ax[i] = p.gravity[0] - p.air_drag * s.vx[i];
        ay[i] = p.gravity[1] - p.air_drag * s.vy[i];
        az[i] = p.gravity[2] - p.air_drag * s.vz[i];
        if (p.wind.enabled) {
            ax[i] += p.wind.strength * std::sin(10.0 * t);
            az[i] += p.wind.strength * std::fabs(std::sin(s.z[i] + 10.0 * t));
        }
    }
}

State step_euler(const Cloth& cloth, const SimulationParams& p, const State& s, double t) {
    const Forces f = spring_forces(cloth, s);
    std::vector<double> ax, ay, az;
    external_acceleration(cloth, p, s, t, ax, ay, az);
    State out = s;
    const double dt = p.dt;
    for (std::size_t i = 0; i < cloth.particle_count; ++i) {
        const double inv_m = cloth.inv_mass[i];
        if (inv_m == 0.0) {
            out.vx[i] = out.vy[i] = out.vz[i] = 0.0;
            continue;
        }
        out.vx[i] = s.vx[i] + dt * (inv_m * f.fx[i] + ax[i]);
        out.vy[i] = s.vy[i] + dt * (inv_m * f.fy[i] + ay[i]);
        out.vz[i] = s.vz[i] + dt * (inv_m * f.fz[i] + az[i]);
        out.x[i] = s.x[i] + dt * out.vx[i];
        out.y[i] = s.y[i] + dt * out.vy[i];
        out.z[i] = s.z[i] + dt * out.vz[i];
    }
    return out;
}

State read_state(const Simulation& sim) {
    const std::size_t n = sim.cloth().particle_count;
    State s;
    s.x.assign(sim.x().begin(), sim.x().end());
    s.y.assign(sim.y().begin(), sim.y().end());
    s.z.assign(sim.z().begin(), sim.z().end());
    s.vx.resize(n);
    s.vy.resize(n);
    s.vz.resize(n);
    const StateBuffer& b = sim.state();
    const double inv_dt = 1.0 / double(sim.params().dt);
    for (std::size_t i = 0; i < n; ++i) {
        if (sim.params().integrator == Integrator::verlet) { // exact velocity implied by the stored x and x_prev
            s.vx[i] = (double(b.x[i]) - double(b.u[i])) * inv_dt;
            s.vy[i] = (double(b.y[i]) - double(b.v[i])) * inv_dt;
            s.vz[i] = (double(b.z[i]) - double(b.w[i])) * inv_dt;
        } else {
            s.vx[i] = b.u[i];
            s.vy[i] = b.v[i];
            s.vz[i] = b.w[i];
        }
    }
    return s;
}

} // namespace drape::reference
