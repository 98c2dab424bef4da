// Health monitor: tells "finite" from "healthy". Every `check_every` substeps the simulation reduces its state to
// three figures - kinetic energy, the largest structural stretch, the largest particle speed - and compares them
// with bounds derived from the scene. A figure above its bound is an explosion: Simulation::step throws BlowUpError
// (errors.hpp) naming the substep, the quantity, its value and bound and the likely cause, after putting the state
// back to the last check that passed.
//
// Bounds (docs/user_guide.md, "Health monitor"). Energy balance from the baseline b (construction, or the last user
// action: grab, pin, parameter or material change) to now, for springs (conservative, internal), spring damping and
// air drag (dissipative), pins and static colliders (no work):
//   KE + E_el = KE_b + E_el_b + W_gravity + W_wind + W_aero - dissipated,  so  KE <= KE_b + E_el_b + W_g + W_w + W_a.
//   W_gravity = M g . (c - c_b)             exactly (c: centre of mass of the movable particles, M their mass);
//   W_wind   <= sum over checks of a_max sqrt(2 M KE) dt_check   (power of an acceleration field of magnitude
//               <= a_max = sqrt(2) strength: sum m |a| |v| <= a_max sqrt(2 M KE), Cauchy-Schwarz);
//   W_aero   ~ 2 M |wind|^2 (a cloth flapping at up to twice the wind speed; aero drag is dissipative in the wind's
//               frame, the pins are what feed a flag's flutter, so this is an allowance, not an identity);
//   plus a floor 1/2 M (1 m/s)^2. energy bound = energy_factor x that sum. An explicit integrator's energy error
//   and a stiff cloth's modified energy stay far inside the factor (measured on every built-in scene). The implicit
//   solver (backward Euler) only dissipates, so its kinetic energy's factor is energy_factor_implicit = 2 (without
//   self-collision): under the factor 10 a sphere drape at 1/120 s gained 0.733 J, five times what gravity could
//   give it, and was reported healthy (docs/implicit.md, "Smaller steps on the drape scene"). The strain bound
//   below keeps energy_factor (an under-iterated implicit step stretches without gaining energy), and so does the
//   energy with self-collision on (its push-apart of a crowded start is energy the sum does not count).
// Strain (the largest (l - l0)/l0 of a structural spring): a single spring cannot hold more than all the energy,
//   1/2 k (s l0)^2 <= energy bound, so s_energy = sqrt(2 energy_bound / k) / l0_min; the bound is
//   max(1.0, s_energy) - and with a strain limit of ratio r on, max(1.0, min(s_energy, 10 r)): 100 % stretch while
//   the fabric is limited to a few percent is an explosion.
// Speed: a particle falls from the cloth's own extent plus the distance its centre of mass moved, under gravity plus
//   the wind field, or takes all the elastic energy stored at the baseline (a grab that jumped, seams that start
//   stretched) into the lightest particle: v_ref = v_b + sqrt(2 E_el_b / m_min) + sqrt(2 (|g| + a_max)
//   (diagonal_b + |c - c_b|)) + 2 |aero wind| + the grab's speed + 1 m/s; speed bound = speed_factor x v_ref.
// E_el is every spring's 1/2 k (l - l0)^2 (k = material x Edge::scale) plus the bending energy (bending.hpp), computed
//   at each baseline.
// Cost: one pass over the particles (fixed blocks, partial sums combined in block order: the figures are bitwise
// identical for any thread count) and one over the structural springs, every check_every substeps, plus a copy of
// the state (the restore point). No allocation after construction.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <algorithm>

#include "drape/cloth.hpp"

namespace drape {

struct SimulationParams;
struct StateBuffer;

/// The monitor's last figures and bounds (for the CLI's JSON and the viewer).
struct HealthFigures {
    std::size_t substep = 0;         ///< substep of the last check (0 = at construction / the last baseline)
    bool checked = false;            ///< a check ran since the last baseline (else the bounds below are 0)
    double kinetic_energy = 0.0;     ///< J
    double energy_bound = 0.0;       ///< J
    float max_strain = 0.0f;         ///< largest (l - l0)/l0 over structural springs
    float strain_bound = 0.0f;
    float max_speed = 0.0f;          ///< m/s
    float speed_bound = 0.0f;        ///< m/s
    bool healthy = true;
};

class HealthMonitor {
  public:
    static constexpr std::size_t check_every = 128; ///< substeps between checks (a check costs ~2.6 substeps)
    static constexpr double energy_factor = 10.0;
    /// The factor for the implicit solver. Measured at each scene's default step, 4 s, kinetic energy against this
    /// bound: hang 0.0086 / 1.77 J, drape 0.00054 / 0.051, sphere 0.00007 / 1.14, tshirt 0.00014 / 158, flag 0.40 /
    /// 24.3, tank top 0.00004 / 134, banner 0.0078 / 1.33 (docs/implicit.md).
    static constexpr double energy_factor_implicit = 2.0;
    /// Below this step an implicit blow-up against colliders is blamed on the step (measured: the drape scene at
    /// 1/240 s and a sphere drape at 1/120 s gain energy in contact; 1/160 s ran the drape; docs/implicit.md).
    static constexpr float implicit_contact_dt_min = 1.0f / 120.0f;
    static constexpr double speed_factor = 10.0;
    /// The largest structural strain a healthy cloth reaches without a grab (or twice its start's, or 10 x a strain
    /// limit's ratio, if more). Well above what soft heavy fabrics reach (a 3 m hang of 2000 g/m^2 at 10 N/m: ~12 as it
    /// swings) or a short edge of an OBJ mesh in series with long ones.
    static constexpr double strain_ceiling = 50.0;
    /// A baseline strained past this is named as a blow-up's likely cause (springs far from rest snap back).
    static constexpr double stretched_baseline_strain = 0.3;

    /// Sizes the scratch (the only allocation) and records the scene's constants.
    void init(const Cloth& cloth, const SimulationParams& params);
    /// Starts the energy balance afresh from `s` (also the restore point), at substep `step`.
    template <bool Parallel>
    void rebaseline(const Cloth& cloth, const SimulationParams& params, const StateBuffer& s, std::size_t step);
    /// Measures `s` at substep `step` against the bounds. Returns "" when healthy (and makes `s` the restore
    /// point), else the message for BlowUpError.
    template <bool Parallel>
    std::string check(const Cloth& cloth, const SimulationParams& params, const StateBuffer& s, std::size_t step);
    /// Copies the restore point into `s`; returns its substep.
    std::size_t restore(StateBuffer& s, std::size_t n) const;
    const HealthFigures& figures() const noexcept { return figures_; }
    /// The particles inside a collider at construction (a likely cause of a blow-up).
    std::size_t started_inside() const noexcept { return started_inside_; }
    void set_started_inside(std::size_t count) noexcept { started_inside_ = count; }
    /// The largest speed of the grab target seen, m/s (the user's allowance in the speed bound).
    void note_user_speed(float speed) noexcept { user_speed_ = std::max(user_speed_, speed); }

  private:
    struct Reduced {
        double ke = 0.0, mass = 0.0, cx = 0.0, cy = 0.0, cz = 0.0;
        float max_speed = 0.0f, max_strain = 0.0f;
    };
    template <bool Parallel>
    Reduced reduce(const Cloth& cloth, const SimulationParams& params, const StateBuffer& s);
    void save(const StateBuffer& s, std::size_t n, std::size_t step);

    std::vector<double> block_ke_, block_mass_, block_cx_, block_cy_, block_cz_;
    std::vector<float> block_speed_, chunk_strain_;
    std::vector<double> chunk_elastic_; ///< rebaseline: elastic energy per spring chunk
    std::vector<float> block_box_;      ///< rebaseline: per block, bounding box (6) and largest inverse mass
    std::vector<float> snap_x_, snap_y_, snap_z_, snap_u_, snap_v_, snap_w_; ///< the restore point
    std::size_t snap_step_ = 0;
    // Baseline.
    double ke_b_ = 0.0, elastic_b_ = 0.0, mass_b_ = 0.0, cx_b_ = 0.0, cy_b_ = 0.0, cz_b_ = 0.0;
    float speed_b_ = 0.0f, diagonal_b_ = 0.0f, speed_elastic_ = 0.0f;
    double strain_b_ = 0.0; ///< max structural strain at the baseline
    double wind_work_ = 0.0, ke_last_ = 0.0;
    std::size_t step_last_ = 0;
    // Scene constants.
    double k_struct_ = 0.0, rest_min_ = 0.0, dt_bound_ = 0.0;
    float user_speed_ = 0.0f;
    std::size_t started_inside_ = 0;
    HealthFigures figures_;
};

} // namespace drape
