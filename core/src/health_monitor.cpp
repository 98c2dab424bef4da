// Health monitor (the bounds and their derivation are in health_monitor.hpp and docs/user_guide.md).
#include "drape/health_monitor.hpp"

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "drape/simulation.hpp"
#include "drape/stability.hpp"
#include "for_each_index.hpp"

namespace drape {

namespace {

constexpr std::size_t strain_chunk = 16384; ///< springs per parallel chunk of the strain pass (fixed)
constexpr double floor_speed = 1.0;         ///< m/s: a cloth moving this fast everywhere is not an explosion

double wind_acceleration(const SimulationParams& p) {
    return p.wind.enabled ? std::sqrt(2.0) * p.wind.strength : 0.0; // |strength (sin, 0, |sin|)| <= sqrt 2 strength
}

double aero_speed(const SimulationParams& p) {
    if (!p.aero.enabled) return 0.0;
    const auto& w = p.aero.velocity;
    return std::sqrt(double(w[0]) * w[0] + double(w[1]) * w[1] + double(w[2]) * w[2]);
}

} // namespace

void HealthMonitor::init(const Cloth& cloth, const SimulationParams& params) {
    const std::size_t blocks = cloth.block_count(), n = cloth.particle_count;
    for (auto* v : {&block_ke_, &block_mass_, &block_cx_, &block_cy_, &block_cz_}) v->assign(blocks, 0.0);
    block_speed_.assign(blocks, 0.0f);
    chunk_strain_.assign((cloth.edges.size() + strain_chunk - 1) / strain_chunk, 0.0f);
    chunk_elastic_.assign(chunk_strain_.size(), 0.0);
    block_box_.assign(7 * blocks, 0.0f);
    for (auto* v : {&snap_x_, &snap_y_, &snap_z_, &snap_u_, &snap_v_, &snap_w_}) v->assign(n, 0.0f);
    // The softest structural spring (its kind's material times Edge::scale) and the shortest: the strain bound's
    // most permissive combination.
    const double k_material = cloth.material[static_cast<std::size_t>(SpringKind::structural)].stiffness;
    k_struct_ = 0.0;
    rest_min_ = 0.0;
    for (const Edge& e : cloth.edges)
        if (e.kind == SpringKind::structural) {
            rest_min_ = rest_min_ == 0.0 ? e.rest : std::min(rest_min_, double(e.rest));
            const double k = k_material * e.scale;
            k_struct_ = k_struct_ == 0.0 ? k : std::min(k_struct_, k);
        }
    if (k_struct_ == 0.0) k_struct_ = k_material;
    dt_bound_ = stability_bound(cloth, params).dt_max;
}

template <bool Parallel>
HealthMonitor::Reduced HealthMonitor::reduce(const Cloth& cloth, const SimulationParams& params, const StateBuffer& s) {
    const std::size_t n = cloth.particle_count;
    const bool verlet = params.integrator == Integrator::verlet;
    const float inv_dt = 1.0f / params.dt;
    for_each_index<Parallel>(cloth.block_count(), [&](std::size_t b) {
        const std::size_t begin = b * block_particles, end = std::min(begin + block_particles, n);
        // Float per particle (vectorisable), double per block (the sums of 1,024 terms keep ~1e-7).
        float ke = 0.0f, mass = 0.0f, cx = 0.0f, cy = 0.0f, cz = 0.0f, speed2 = 0.0f;
        for (std::size_t i = begin; i < end; ++i) {
            const float w = cloth.inv_mass[i];
            const float m = w > 0.0f ? 1.0f / w : 0.0f; // pinned: no mass that moves
            const float vx = verlet ? s.u[i] * inv_dt : s.u[i];
            const float vy = verlet ? s.v[i] * inv_dt : s.v[i];
            const float vz = verlet ? s.w[i] * inv_dt : s.w[i];
            const float v2 = w > 0.0f ? vx * vx + vy * vy + vz * vz : 0.0f;
            speed2 = std::max(speed2, v2);
            if (!(v2 == v2)) speed2 = v2; // NaN propagates
            ke += 0.5f * m * v2;
            mass += m;
            cx += m * s.x[i];
            cy += m * s.y[i];
            cz += m * s.z[i];
        }
        block_ke_[b] = ke;
        block_mass_[b] = mass;
        block_cx_[b] = cx;
        block_cy_[b] = cy;
        block_cz_[b] = cz;
        block_speed_[b] = std::sqrt(speed2);
    });
    const std::size_t springs = cloth.edges.size();
    for_each_index<Parallel>(chunk_strain_.size(), [&](std::size_t ch) {
        float worst = 0.0f;
        for (std::size_t k = ch * strain_chunk, end = std::min(springs, (ch + 1) * strain_chunk); k < end; ++k) {
            const Edge& e = cloth.edges[k];
            if (e.kind != SpringKind::structural) continue;
            const float dx = s.x[e.b] - s.x[e.a], dy = s.y[e.b] - s.y[e.a], dz = s.z[e.b] - s.z[e.a];
            const float strain = (std::sqrt(dx * dx + dy * dy + dz * dz) - e.rest) / e.rest;
            if (!(strain <= worst)) worst = strain;
        }
        chunk_strain_[ch] = worst;
    });
    Reduced r; // combined in block order: bitwise the same for any thread count
    for (std::size_t b = 0; b < block_ke_.size(); ++b) {
        r.ke += block_ke_[b];
        r.mass += block_mass_[b];
        r.cx += block_cx_[b];
        r.cy += block_cy_[b];
        r.cz += block_cz_[b];
        if (!(block_speed_[b] <= r.max_speed)) r.max_speed = block_speed_[b];
    }
    for (float v : chunk_strain_)
        if (!(v <= r.max_strain)) r.max_strain = v;
    if (r.mass > 0.0) {
        r.cx /= r.mass;
        r.cy /= r.mass;
        r.cz /= r.mass;
    }
    return r;
}

void HealthMonitor::save(const StateBuffer& s, std::size_t n, std::size_t step) {
    std::copy_n(s.x.data(), n, snap_x_.data());
    std::copy_n(s.y.data(), n, snap_y_.data());
    std::copy_n(s.z.data(), n, snap_z_.data());
    std::copy_n(s.u.data(), n, snap_u_.data());
    std::copy_n(s.v.data(), n, snap_v_.data());
    std::copy_n(s.w.data(), n, snap_w_.data());
    snap_step_ = step;
}

std::size_t HealthMonitor::restore(StateBuffer& s, std::size_t n) const {
    std::copy_n(snap_x_.data(), n, s.x.data());
    std::copy_n(snap_y_.data(), n, s.y.data());
    std::copy_n(snap_z_.data(), n, s.z.data());
    std::copy_n(snap_u_.data(), n, s.u.data());
    std::copy_n(snap_v_.data(), n, s.v.data());
    std::copy_n(snap_w_.data(), n, s.w.data());
    return snap_step_;
}

template <bool Parallel>
void HealthMonitor::rebaseline(const Cloth& cloth, const SimulationParams& params, const StateBuffer& s,
                               std::size_t step) {
    const Reduced r = reduce<Parallel>(cloth, params, s);
    // Elastic energy of every spring (seams included) and the cloth's extent: once per baseline, per fixed chunk /
    // block, combined in order.
    const std::size_t springs = cloth.edges.size(), n = cloth.particle_count;
    for_each_index<Parallel>(chunk_elastic_.size(), [&](std::size_t ch) {
        double e = 0.0;
        for (std::size_t k = ch * strain_chunk, end = std::min(springs, (ch + 1) * strain_chunk); k < end; ++k) {
            const Edge& edge = cloth.edges[k];
            const float dx = s.x[edge.b] - s.x[edge.a], dy = s.y[edge.b] - s.y[edge.a], dz = s.z[edge.b] - s.z[edge.a];
            const double stretch = std::sqrt(double(dx) * dx + double(dy) * dy + double(dz) * dz) - edge.rest;
            e += 0.5 * cloth.material[static_cast<std::size_t>(edge.kind)].stiffness * edge.scale * stretch * stretch;
        }
        chunk_elastic_[ch] = e;
    });
    for_each_index<Parallel>(cloth.block_count(), [&](std::size_t b) {
        const std::size_t begin = b * block_particles, end = std::min(begin + block_particles, n);
        float* box = &block_box_[7 * b]; // lo x y z, hi x y z, max inverse mass
        for (int k = 0; k < 3; ++k) {
            box[k] = std::numeric_limits<float>::max();
            box[3 + k] = std::numeric_limits<float>::lowest();
        }
        box[6] = 0.0f;
        for (std::size_t i = begin; i < end; ++i) {
            const float p[3] = {s.x[i], s.y[i], s.z[i]};
            for (int k = 0; k < 3; ++k) {
                box[k] = std::min(box[k], p[k]);
                box[3 + k] = std::max(box[3 + k], p[k]);
            }
            box[6] = std::max(box[6], cloth.inv_mass[i]);
        }
    });
    double elastic = 0.0;
    for (double e : chunk_elastic_) elastic += e;
    // The bending energy (serial, once per baseline; no allocation).
    if (!cloth.bending.empty())
        elastic += bending_energy(cloth.bending.elements, {s.x.data(), n}, {s.y.data(), n}, {s.z.data(), n});
    float lo[3] = {s.x[0], s.y[0], s.z[0]}, hi[3] = {s.x[0], s.y[0], s.z[0]};
    float max_inv_mass = 0.0f;
    for (std::size_t b = 0; b < cloth.block_count(); ++b) {
        const float* box = &block_box_[7 * b];
        for (int k = 0; k < 3; ++k) {
            lo[k] = std::min(lo[k], box[k]);
            hi[k] = std::max(hi[k], box[3 + k]);
        }
        max_inv_mass = std::max(max_inv_mass, box[6]);
    }
    ke_b_ = r.ke;
    elastic_b_ = elastic;
    mass_b_ = r.mass;
    cx_b_ = r.cx;
    cy_b_ = r.cy;
    cz_b_ = r.cz;
    speed_b_ = r.max_speed;
    strain_b_ = r.max_strain;
    // The stored elastic energy (a grab that jumped, seams that start stretched) may all end up in the lightest
    // particle.
    speed_elastic_ = static_cast<float>(std::sqrt(2.0 * elastic * double(max_inv_mass)));
    diagonal_b_ = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                            (hi[2] - lo[2]) * (hi[2] - lo[2]));
    wind_work_ = 0.0;
    ke_last_ = r.ke;
    step_last_ = step;
    figures_ = HealthFigures{};
    figures_.substep = step;
    figures_.kinetic_energy = r.ke;
    figures_.max_strain = r.max_strain;
    figures_.max_speed = r.max_speed;
    save(s, cloth.particle_count, step);
}

template <bool Parallel>
std::string HealthMonitor::check(const Cloth& cloth, const SimulationParams& params, const StateBuffer& s,
                                 std::size_t step) {
    const Reduced r = reduce<Parallel>(cloth, params, s);
    const double M = mass_b_;
    const double g = std::sqrt(double(params.gravity[0]) * params.gravity[0] +
                               double(params.gravity[1]) * params.gravity[1] +
                               double(params.gravity[2]) * params.gravity[2]);
    const double a_wind = wind_acceleration(params), w_aero = aero_speed(params);
    const double elapsed = double(step - step_last_) * params.dt;
    wind_work_ += a_wind * std::sqrt(2.0 * M * std::max(ke_last_, std::isfinite(r.ke) ? r.ke : 0.0)) * elapsed;
    ke_last_ = r.ke;
    step_last_ = step;
    const double dcx = r.cx - cx_b_, dcy = r.cy - cy_b_, dcz = r.cz - cz_b_;
    const double gravity_work = M * (params.gravity[0] * dcx + params.gravity[1] * dcy + params.gravity[2] * dcz);
    const double available = ke_b_ + elastic_b_ + std::max(0.0, gravity_work) + wind_work_ +
                             2.0 * M * w_aero * w_aero + 0.5 * M * floor_speed * floor_speed;
    // The implicit solver's tighter factor bounds the kinetic energy only: an under-iterated implicit step stretches
    // without gaining energy (a flag at 0.1 s and 2 sweeps, strain 4.9: warned as unconverged, not a blow-up), and
    // a self-collision stage pushing apart a start closer than its thickness supplies energy this sum does not count
    // (a folded pile at 1/240 s: 0.34 J against 0.147 J available after one step), so both keep energy_factor.
    const bool tight = params.solver == Solver::implicit && params.self_collision.thickness <= 0.0f;
    const double energy_bound = (tight ? energy_factor_implicit : energy_factor) * available;
    double strain_bound = k_struct_ > 0.0 && rest_min_ > 0.0
                              ? std::sqrt(2.0 * energy_factor * available / k_struct_) / rest_min_
                              : 1e30;
    // A strain limit caps it (a limited cloth stretched 10 times the limit has failed), unless the user has dragged
    // the cloth: a drag out of its reach stretches it whatever the limit does (the energy bound above, which takes in
    // the drag's work at each move, still holds; released, the limit pulls it back: docs/implicit.md).
    if (params.strain_limit.ratio > 0.0f && user_speed_ == 0.0f)
        strain_bound = std::min(strain_bound, 10.0 * params.strain_limit.ratio);
    strain_bound = std::max(1.0, strain_bound);
    // However much energy gravity supplies (it grows as a failing cloth stretches downwards: an adversarial sweep's
    // 4 m ribbon reached strain 1,328 under a bound of 4,687), no cloth stretches to 51 times its length unless the
    // user dragged it (since the simulation was built), it started so, or a strain limit allows it.
    bool ceiling = false;
    const double most = std::max({strain_ceiling, 2.0 * strain_b_, 10.0 * double(params.strain_limit.ratio)});
    if (user_speed_ == 0.0f && strain_bound > most) {
        strain_bound = most;
        ceiling = true;
    }
    const double moved = std::sqrt(dcx * dcx + dcy * dcy + dcz * dcz);
    const double v_ref = speed_b_ + speed_elastic_ + std::sqrt(2.0 * (g + a_wind) * (diagonal_b_ + moved)) + 2.0 * w_aero +
                         user_speed_ + floor_speed;
    const double speed_bound = speed_factor * v_ref;

    figures_.substep = step;
    figures_.checked = true;
    figures_.kinetic_energy = r.ke;
    figures_.energy_bound = energy_bound;
    figures_.max_strain = r.max_strain;
    figures_.strain_bound = static_cast<float>(strain_bound);
    figures_.max_speed = r.max_speed;
    figures_.speed_bound = static_cast<float>(speed_bound);

    const char* quantity = nullptr;
    const char* supply = nullptr; // what the bound is, when not the energy balance
    double value = 0.0, bound = 0.0;
    const char* unit = "";
    if (!(r.ke <= energy_bound)) {
        quantity = "kinetic energy";
        value = r.ke;
        bound = energy_bound;
        unit = " J";
    } else if (!(r.max_strain <= strain_bound)) {
        quantity = "max structural strain";
        value = r.max_strain;
        bound = strain_bound;
        supply = ceiling ? "the most a cloth stretches: 50 = 5,000 %, or twice its start" : supply;
    } else if (!(r.max_speed <= speed_bound)) {
        quantity = "max particle speed";
        value = r.max_speed;
        bound = speed_bound;
        unit = " m/s";
    }
    if (!quantity) {
        figures_.healthy = true;
        save(s, cloth.particle_count, step);
        return {};
    }
    figures_.healthy = false;
    std::ostringstream msg;
    msg.precision(4);
    msg << "blow-up at substep " << step << " (t = " << double(step) * params.dt << " s): " << quantity << " "
        << value << unit << " exceeds the healthy bound " << bound << unit << " (";
    if (supply)
        msg << supply;
    else
        msg << "what gravity" << (params.wind.enabled || params.aero.enabled ? ", wind" : "")
            << " and the start state can supply";
    msg << "; health_monitor.hpp); likely cause: ";
    // Self-collision thicker than about half the spacing pushes neighbouring layers (or panels sewn close) apart at
    // once, whatever else the scene does (an adversarial sweep: every scene blew up at 0.05 m and was told to lower dt).
    const double spacing = cloth_spacing(cloth);
    const bool implicit = params.solver == Solver::implicit;
    if (params.self_collision.thickness > 0.0f && params.self_collision.thickness > 0.5 * spacing)
        msg << "self-collision's thickness (" << params.self_collision.thickness
            << " m) against the cloth's spacing (mean structural spring " << spacing
            << " m): layers or panels closer than the thickness are pushed apart at once; lower "
               "physics.self_collision.thickness (--self-collision)";
    else if (params.strain_limit.ratio > 0.0f && params.strain_limit.every > 1 && !implicit)
        // A limit applied every K substeps moves particles by K substeps' worth of stretch at once, and the springs
        // answer with that displacement as velocity (found: --strain-limit 0.01 --strain-every 100 on the hang).
        msg << "the strain limit (" << params.strain_limit.ratio << ") applied only every " << params.strain_limit.every
            << " substeps, its corrections too large for the springs: lower physics.strain_limit.every "
               "(--strain-every, 1 = every substep) or raise the ratio";
    else if (implicit && !params.colliders.empty() && params.dt < implicit_contact_dt_min && started_inside_ == 0 &&
             user_speed_ == 0.0f && strain_b_ <= stretched_baseline_strain)
        // Measured on the drape scene (docs/implicit.md, "Smaller steps on the drape scene"): at 1/240 s the cloth
        // gains energy in contact with 30, 100 or 300 sweeps, with or without its strain limit, so "raise the
        // iterations or lower dt" and "the strain limit" sent the user the wrong way. Not where a cause known for
        // certain (a start inside a collider, a grab, a stretched start: the branches below) is there.
        msg << "an implicit step of " << params.dt
            << " s against colliders: below about 1/120 s the implicit solver can gain energy in contact "
               "(docs/implicit.md, \"Smaller steps on the drape scene\"); use a longer step (the default is a "
               "frame, 1/30 s) or the explicit solver (--solver explicit)";
    else if (params.strain_limit.ratio > 0.0f)
        msg << "the strain limit (" << params.strain_limit.ratio
            << ") fighting the springs: raise the ratio or the passes, or lower the stiffness";
    else if (started_inside_ > 0)
        msg << "the cloth started inside colliders (" << started_inside_ << " particles): move the cloth or the colliders";
    else if (user_speed_ > 0.0f)
        msg << "a fast grab (up to " << user_speed_ << " m/s): move the grabbed particle more slowly";
    else if (strain_b_ > stretched_baseline_strain)
        // A start stretched by half or more snaps back and crumples: a spring compressed far below its rest length
        // is stiffer across itself than the stability bound assumes (an adversarial sweep: a start stretched 1.5
        // times blew up at once and was blamed on a state "changed from outside").
        msg << "the state it started from (or was last reset to by a grab, pin or parameter change) already stretched "
               "a structural spring by "
            << 100.0 * strain_b_ << " % (strain " << strain_b_
            << "): released, the springs snap back and crumple faster than the steps resolve; start from a less "
               "stretched state (state.positions), or bound it with a strain limit (--strain-limit, "
               "physics.strain_limit.ratio)"
            << (implicit ? "" : " or the implicit solver (--solver implicit)");
    else if (implicit && params.implicit.chebyshev_rho > 0.95f)
        msg << "Chebyshev acceleration amplifying the sweeps (physics.implicit.chebyshev_rho = "
            << std::setprecision(7) << params.implicit.chebyshev_rho << std::setprecision(4) << "): lower it (default 0.9; 0 turns it off)";
    else if (implicit)
        msg << "the implicit sweeps not converging at this step (dt = " << params.dt << " s, "
            << params.implicit.iterations << " iterations): raise the iterations or lower dt";
    else if (dt_bound_ > 0.0 && params.dt > 0.9 * dt_bound_ * (1.0 + 1e-5)) // the default dt is 0.9 x, rounded
        msg << "dt too close to the stability bound (dt = " << params.dt << " s, bound " << dt_bound_
            << " s): use a smaller dt (the default is 0.9 x the bound)";
    else if (params.aero.enabled)
        msg << "an aerodynamic load far above what the springs hold: lower the aero density, drag coefficient or "
               "wind speed, or raise the stiffness";
    else
        msg << "a force the scene cannot supply (the state was changed from outside the simulation): lower dt or "
               "the stiffness";
    msg << "; the state is back at substep " << snap_step_;
    return msg.str();
}

template void HealthMonitor::rebaseline<true>(const Cloth&, const SimulationParams&, const StateBuffer&, std::size_t);
template void HealthMonitor::rebaseline<false>(const Cloth&, const SimulationParams&, const StateBuffer&, std::size_t);
template std::string HealthMonitor::check<true>(const Cloth&, const SimulationParams&, const StateBuffer&, std::size_t);
template std::string HealthMonitor::check<false>(const Cloth&, const SimulationParams&, const StateBuffer&,
                                                 std::size_t);

} // namespace drape
