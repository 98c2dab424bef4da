// Materials as users see them: the fabric presets in file units (`drape materials`), and a built cloth's derived
// per-element values (node mass, spring stiffness per kind) that the run's JSON and the viewer's Fabric panel show.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "drape/cloth.hpp"
#include "drape/scene.hpp"
#include "drape/simulation.hpp"
#include "drape/stability.hpp"

namespace drape::app {

/// What the engine derived from the material and the mesh (the seeds' units: grams per particle, N/m per spring).
struct DerivedMaterial {
    double node_mass_g_mean = 0.0, node_mass_g_min = 0.0, node_mass_g_max = 0.0; ///< free particles' masses, g
    /// N/m per spring kind (structural, shear, bend, seam): the kind's material (Cloth::material)
    std::array<float, spring_kind_count> stiffness{};
    std::array<float, spring_kind_count> damping{}; ///< N*s/m per spring kind: the kind's material
    /// N/m, the smallest and largest stiffness of one spring of each kind (the material times the spring's own
    /// factor where the model gives each spring its share, e.g. half on a boundary edge); 0 for a kind with none
    std::array<float, spring_kind_count> spring_min{}, spring_max{};
};
DerivedMaterial derive_material(const Cloth& cloth);

/// A fabric's figures in file units: { "name", "density_gsm", "stretch_u", "stretch_v", "shear", "bend_u_uNm",
/// "bend_v_uNm", "damping" }.
nlohmann::ordered_json fabric_json(const Fabric& fabric);

/// The run's "material" object: the model, the fabric (fabric model) or the spring fields (springs), and "derived".
nlohmann::ordered_json material_report(const SceneSpec& spec, const Cloth& cloth);

/// `drape materials`: the presets with their figures in file units, a table or (json) one JSON array. Returns 0.
int materials_command(bool json);

/// Applies `drape run --material NAME` to a scene: a preset switches it to the fabric model with that fabric;
/// "springs" to the seeds' spring model with the scene's spring fields. Throws InvalidInput listing the valid names.
void apply_material_flag(SceneSpec& spec, const std::string& name);

/// The solver flags of `drape run` and `drape view` (unset: the scene's).
struct SolverFlags {
    std::optional<std::string> solver;       ///< --solver explicit|implicit
    std::optional<std::uint32_t> iterations; ///< --iterations K, 1..1000
    std::optional<float> tolerance;          ///< --tolerance T, 0..1
    std::optional<std::string> integrator;   ///< --integrator euler|verlet
    std::optional<float> strain_limit;       ///< --strain-limit R, 0..10 (0 = off): the largest stretch
    bool fas = false;                        ///< --fas: the multilevel guess's coarse correction (ImplicitParams::fas)
    bool single_level = false;               ///< --single-level: no multilevel guess (ImplicitParams::multilevel off)
    bool fas_at_rest = false;                ///< --fas-at-rest: ImplicitParams::fas_at_rest on
};
/// Applies them to a scene: --solver implicit switches a Verlet scene to the Euler integrator (the implicit solver
/// keeps velocities); throws InvalidInput (exit code 2) naming the flag for --integrator verlet with the implicit
/// solver, and for --iterations, --tolerance, --fas, --single-level or --fas-at-rest when the solver (the flag's or
/// the scene's) is explicit.
void apply_solver_flags(SceneSpec& spec, const SolverFlags& flags);

/// A warning for the implicit solver on a cloth it solves on one grid only (no multilevel guess: OBJ meshes, mask
/// garments, the springs model, non-square grids; 256 particles or more) that hangs from pins: such a cloth does not
/// come to rest at ordinary sweep counts (docs/implicit.md). A cloth without pins (resting on colliders, as the
/// T-shirt on its body) is not warned. Empty when it does not apply. `drape run` and the viewer show it.
std::string single_level_implicit_warning(const Simulation& sim);
/// A warning (or empty) after implicit steps that end with the cloth strained (stretched or compressed) past
/// unconverged_strain while the last step's sweeps were far from converged (relative residual above
/// unconverged_residual): the motion is then the sweeps' error, not the fabric's (a flag at 2 sweeps per 0.1 s step
/// ended 720 % stretched and "healthy"). What to change is said in the words of the interface: `drape run`'s flags, or
/// (`viewer`) the Physics panel's controls; `budget_limited`: the viewer's iteration budget ran fewer sweeps than its
/// iterations allow. A tolerance above unconverged_residual is named first, the iterations only below their maximum;
/// the strain limit only when it is off. No warning for a strain within 5 % of the scene's strain limit (the limit
/// holds it: what the scene allows, not the sweeps' error).
std::string unconverged_implicit_warning(const Simulation& sim, float max_structural_strain, bool viewer,
                                         bool budget_limited = false);
/// Whether that warning applies (the implicit solver, the strain and the last step's residual past their bounds),
/// without composing it: `drape run --json`'s implicit.unconverged, and the viewer's per-frame check.
bool implicit_unconverged(const Simulation& sim, float max_structural_strain) noexcept;
inline constexpr double unconverged_residual = 0.1;
inline constexpr float unconverged_strain = 0.3f;
/// A warning (or empty) for a run that ends with its structural springs stretched or compressed past
/// overstretched_strain (100 %) and no implicit-convergence warning to explain it: far past what a woven or knitted
/// fabric survives, and within the health monitor's bounds, which allow what gravity, the start and seams can supply
/// (an adversarial sweep: a soft, heavy custom fabric at strain 12.8, a start state stretched 10 times at 31.6, both
/// exit 0 and "healthy", silently). Says what usually causes it and that a strain limit bounds it.
/// With `viewer`, in the viewer's words (the strain now, the Physics panel's strain limit).
std::string overstretched_warning(const Simulation& sim, float max_structural_strain, bool viewer = false);
inline constexpr float overstretched_strain = 1.0f;
/// A warning when movable particles of the simulation's present state are inside a collider, deeper than half its
/// thickness (the explicit collide stage holds them at rest there), else empty.
std::string started_inside_warning(const Simulation& sim);
/// A warning for an explicit run of more than long_explicit_run_work particle-substeps (about a minute at the
/// ~5e8 particle-substeps a second of 2 cores, docs/performance.md): how many substeps, what sets the stability bound
/// (the damping, or the stiffest spring on the lightest particle) and that the implicit solver takes steps of up to
/// 0.1 s. Empty below it. (A sweep found silk with damping 0.1 s asking 39 million substeps of 2.5e-8 s for 1 s of a
/// 32 x 32 cloth, silently.)
std::string long_explicit_run_warning(const StabilityBound& bound, double dt, std::uint64_t substeps,
                                      std::size_t particles);
/// What sets the explicit stability bound, in words for a message: the damping (with the rate and what the stiffness
/// alone would allow) or the stiffest spring on the lightest particle.
std::string explicit_bound_cause(const StabilityBound& bound);
bool damping_sets_explicit_bound(const StabilityBound& bound);
inline constexpr double long_explicit_run_work = 3e10;
/// A warning (or empty) when self-collision's thickness is above half the cloth's mean spring length: every particle
/// then lies within the thickness of its neighbours' triangles, which makes the stage slow (the 64 x 64 pile at 0.05 m:
/// ~1 s a substep, 935,447 contacts) and can push the cloth apart (the health monitor names it if so).
std::string self_collision_thickness_warning(const Simulation& sim);

} // namespace drape::app
