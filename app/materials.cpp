// `drape materials`, `--material`, and the derived per-element values of a built cloth.
#include "materials.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>

#include "drape/errors.hpp"

namespace drape::app {

namespace {

/// A spring's own stiffness factor (Edge::scale, where the build has one: the fabric model's per-spring share of the
/// membrane), else 1.
template <class E> float spring_factor(const E& e) {
    if constexpr (requires { e.scale; })
        return static_cast<float>(e.scale);
    else
        return 1.0f;
}

} // namespace

DerivedMaterial derive_material(const Cloth& cloth) {
    DerivedMaterial d;
    const std::size_t n = cloth.particle_count;
    double sum = 0.0, lo = std::numeric_limits<double>::max(), hi = 0.0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const float inv = cloth.free_inv_mass.empty() ? cloth.inv_mass[i] : cloth.free_inv_mass[i];
        if (!(inv > 0.0f)) continue;
        const double g = 1000.0 / double(inv);
        sum += g;
        lo = std::min(lo, g);
        hi = std::max(hi, g);
        ++count;
    }
    if (count) {
        d.node_mass_g_mean = sum / double(count);
        d.node_mass_g_min = lo;
        d.node_mass_g_max = hi;
    }
    for (std::size_t k = 0; k < spring_kind_count; ++k) {
        d.stiffness[k] = cloth.material[k].stiffness;
        d.damping[k] = cloth.material[k].damping;
        d.spring_min[k] = std::numeric_limits<float>::max();
    }
    for (const Edge& e : cloth.edges) {
        const auto k = static_cast<std::size_t>(e.kind);
        const float ks = d.stiffness[k] * spring_factor(e);
        d.spring_min[k] = std::min(d.spring_min[k], ks);
        d.spring_max[k] = std::max(d.spring_max[k], ks);
    }
    for (std::size_t k = 0; k < spring_kind_count; ++k)
        if (d.spring_min[k] > d.spring_max[k]) d.spring_min[k] = 0.0f; // no spring of this kind
    return d;
}

nlohmann::ordered_json fabric_json(const Fabric& f) {
    nlohmann::ordered_json j;
    j["name"] = f.name;
    j["density_gsm"] = double(f.density) * fabric_gsm_per_kg_m2;
    j["stretch_u"] = f.stretch_u;
    j["stretch_v"] = f.stretch_v;
    j["shear"] = f.shear;
    j["bend_u_uNm"] = double(f.bend_u) * fabric_uNm_per_Nm;
    j["bend_v_uNm"] = double(f.bend_v) * fabric_uNm_per_Nm;
    j["damping"] = f.damping;
    return j;
}

nlohmann::ordered_json material_report(const SceneSpec& spec, const Cloth& cloth) {
    nlohmann::ordered_json j;
    j["model"] = material_model_name(spec.model);
    if (spec.model == MaterialModel::fabric) {
        j["fabric"] = fabric_json(spec.fabric);
    } else {
        j["stiffness"] = spec.stiffness;
        j["shear_ratio"] = spec.shear_ratio;
        j["bend_ratio"] = spec.bend_ratio;
        j["damping_ratio"] = spec.damping_ratio;
    }
    const DerivedMaterial d = derive_material(cloth);
    nlohmann::ordered_json k, kd, lo, hi;
    for (std::size_t s = 0; s < spring_kind_count; ++s) {
        const char* name = spring_kind_name(static_cast<SpringKind>(s));
        k[name] = d.stiffness[s];
        kd[name] = d.damping[s];
        lo[name] = d.spring_min[s];
        hi[name] = d.spring_max[s];
    }
    j["derived"] = {{"node_mass_g", d.node_mass_g_mean},
                    {"node_mass_g_min", d.node_mass_g_min},
                    {"node_mass_g_max", d.node_mass_g_max},
                    {"spring_k", k},
                    {"spring_damping", kd},
                    {"spring_k_min", lo},
                    {"spring_k_max", hi}};
    return j;
}

int materials_command(bool json) {
    if (json) {
        nlohmann::ordered_json list = nlohmann::ordered_json::array();
        for (const FabricPreset& p : fabric_presets()) {
            nlohmann::ordered_json j = fabric_json(p.fabric);
            j["description"] = p.description;
            j["source"] = p.source;
            list.push_back(j);
        }
        std::cout << list.dump() << std::endl;
        return exit_code::ok;
    }
    std::printf("%-16s %8s %9s %9s %8s %9s %9s %9s  %s\n", "preset", "g/m^2", "u N/m", "v N/m", "shear", "bend_u",
                "bend_v", "damping", "description");
    std::printf("%-16s %8s %9s %9s %8s %9s %9s %9s\n", "", "", "stretch", "stretch", "N/m", "uN*m", "uN*m", "s");
    for (const FabricPreset& p : fabric_presets()) {
        const Fabric& f = p.fabric;
        std::printf("%-16s %8.0f %9.0f %9.0f %8.1f %9.3g %9.3g %9.2g  %s\n", f.name.c_str(),
                    double(f.density) * fabric_gsm_per_kg_m2, double(f.stretch_u), double(f.stretch_v),
                    double(f.shear), double(f.bend_u) * fabric_uNm_per_Nm, double(f.bend_v) * fabric_uNm_per_Nm,
                    double(f.damping), p.description.c_str());
    }
    std::printf("Sources: docs/fabric.md \"Presets\" (or drape materials --json). Use one with --material NAME or "
                "\"material\": \"NAME\" in a scene file.\n");
    return exit_code::ok;
}

void apply_material_flag(SceneSpec& spec, const std::string& name) {
    if (name == "springs") {
        spec.model = MaterialModel::springs;
        return;
    }
    const std::optional<Fabric> f = find_fabric(name);
    if (!f)
        throw InvalidInput("--material: '" + name + "' is not a material (fabric presets: " + fabric_preset_names() +
                           "; or springs, the seeds' spring model; drape materials lists the presets)");
    spec.model = MaterialModel::fabric;
    spec.fabric = *f;
}

void apply_solver_flags(SceneSpec& spec, const SolverFlags& f) {
    if (f.solver) {
        if (*f.solver != "explicit" && *f.solver != "implicit")
            throw InvalidInput("--solver: '" + *f.solver + "' is not a solver (explicit or implicit)");
        spec.physics.solver = *f.solver == "implicit" ? Solver::implicit : Solver::explicit_euler;
    }
    const bool implicit = spec.physics.solver == Solver::implicit;
    const std::string whose = f.solver ? " (--solver)" : " (the scene's physics.solver)";
    if (f.integrator) {
        if (*f.integrator == "verlet" && implicit)
            throw InvalidInput("--integrator: verlet is a choice of the explicit solver only, but the solver is "
                               "implicit" + whose + "; the implicit solver keeps velocities (use euler)");
        spec.physics.integrator = *f.integrator == "verlet" ? Integrator::verlet : Integrator::symplectic_euler;
    } else if (implicit) {
        spec.physics.integrator = Integrator::symplectic_euler; // a Verlet scene run with --solver implicit
    }
    for (const auto& [given, flag] : {std::pair{f.iterations.has_value(), "--iterations"},
                                      {f.tolerance.has_value(), "--tolerance"},
                                      {f.fas, "--fas"},
                                      {f.single_level, "--single-level"},
                                      {f.fas_at_rest, "--fas-at-rest"}})
        if (given && !implicit)
            throw InvalidInput(std::string(flag) + ": a flag of the implicit solver, but the solver is explicit" + whose +
                               "; add --solver implicit");
    for (const auto& [given, flag] : {std::pair{f.fas, "--fas"}, {f.fas_at_rest, "--fas-at-rest"}})
        if (given && (f.single_level || !spec.physics.implicit.multilevel))
            throw InvalidInput(std::string(flag) + ": the coarse correction of the multilevel guess, but the multilevel "
                               "guess is off" + (f.single_level ? " (--single-level)" : " (the scene's "
                               "physics.implicit.multilevel)") + "; drop one of them");
    if (f.fas_at_rest && (f.fas || spec.physics.implicit.fas))
        throw InvalidInput(std::string("--fas-at-rest: FAS when the cloth is at rest, but ") +
                           (f.fas ? "--fas" : "the scene's physics.implicit.fas") +
                           " already runs it on every step; drop one of them");
    if (f.iterations) spec.physics.implicit.iterations = *f.iterations;
    if (f.tolerance) spec.physics.implicit.tolerance = *f.tolerance;
    if (f.fas) spec.physics.implicit.fas = true;
    if (f.single_level) spec.physics.implicit.multilevel = false;
    if (f.fas_at_rest) spec.physics.implicit.fas_at_rest = true;
    if (f.strain_limit) spec.physics.strain_limit.ratio = *f.strain_limit;
}

std::string self_collision_thickness_warning(const Simulation& sim) {
    const float h = sim.params().self_collision.thickness;
    const Cloth& c = sim.cloth();
    if (!(h > 0.0f)) return {};
    const double mean = cloth_spacing(c);
    if (!(mean > 0.0) || !(double(h) > 0.5 * mean)) return {};
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "self-collision's thickness (%.3g m) is above half the cloth's spacing (mean structural spring "
                  "%.3g m): every particle lies within it of its neighbours' triangles, so the stage is slow and may "
                  "push the cloth apart; a thickness of a few millimetres, below half the spacing, is the intended use",
                  double(h), mean);
    return buf;
}

std::string started_inside_warning(const Simulation& sim) {
    // Deeper than half the collider's margin (and 10 um): a cloth resting on a collider (a saved state, a viewer
    // rebuild) sits at the margin, within rounding.
    std::size_t inside = 0;
    const std::size_t n = sim.cloth().particle_count;
    for (std::size_t i = 0; i < n; ++i) {
        if (sim.is_pinned(i)) continue;
        for (const Collider& c : sim.params().colliders)
            if (is_inside(c, {sim.x()[i], sim.y()[i], sim.z()[i]}, 0.5f * c.thickness + 1e-5f)) {
                ++inside;
                break;
            }
    }
    if (inside == 0) return {};
    return std::to_string(inside) + " of the cloth's " + std::to_string(sim.cloth().particle_count) +
           " particles start inside a collider (deeper than half its thickness): the explicit solver holds each where it is "
           "until the cloth's motion carries it out, the implicit solver pushes them out or stops; move the cloth or "
           "the colliders";
}

std::string single_level_implicit_warning(const Simulation& sim) {
    if (sim.params().solver != Solver::implicit || sim.implicit_levels() != 1 || sim.cloth().particle_count < 256)
        return {};
    // Only a cloth hanging from pins: one resting on colliders (a garment on its body, a cloth on a disc) comes to
    // rest on one grid, its contacts holding it everywhere. At 3 s the implicit T-shirt's kinetic energy was 3.5e-6 J
    // against the explicit solver's 2.75e-5 J, the tank top's 7.6e-6 against 2.73e-5 J, each faster than explicit
    // (docs/implicit.md, "Coming to rest on one grid").
    bool hanging = false;
    for (std::size_t i = 0; i < sim.cloth().particle_count && !hanging; ++i)
        hanging = sim.is_pinned(i);
    if (!hanging) return {};
    const std::string one_grid = "solved on one grid does not come to rest at ordinary sweep counts (a 32 x 32 hang "
                                 "jumped 5-27 cm per step at 30 sweeps, docs/implicit.md)";
    if (!sim.params().implicit.multilevel)
        return "the implicit solver's multilevel guess is switched off (--single-level, physics.implicit.multilevel): "
               "a hanging cloth " + one_grid;
    return "the implicit solver has no multilevel guess for this cloth (only square grids and outline cloths of the "
           "fabric model have one): a cloth " + one_grid + "; prefer the explicit solver here";
}

bool implicit_unconverged(const Simulation& sim, float max_structural_strain) noexcept {
    // A strain the scene's strain limit holds (within strain_limit_tolerance of it) is what the scene allows,
    // not the sweeps' error: the implicit T-shirt (limit 0.3) rests at 0.300 on its body, and the viewer told it to
    // "switch the strain limit on".
    const float limit = sim.params().strain_limit.ratio;
    const bool held = limit > 0.0f && max_structural_strain <= strain_limit_tolerance * limit;
    return sim.params().solver == Solver::implicit && max_structural_strain > unconverged_strain && !held &&
           sim.implicit_stats().relative_residual > unconverged_residual;
}

std::string overstretched_warning(const Simulation& sim, float max_structural_strain, bool viewer) {
    if (!(max_structural_strain > overstretched_strain) || implicit_unconverged(sim, max_structural_strain)) return {};
    const float limit = sim.params().strain_limit.ratio;
    const char* fix = limit > 0.0f ? (viewer ? "the Physics panel's strain limit did not hold it"
                                             : "the strain limit on (physics.strain_limit.ratio) did not hold it")
                      : viewer     ? "the Physics panel's strain limit bounds it"
                                   : "a strain limit (--strain-limit, physics.strain_limit.ratio, allowed [0, 10]) "
                                     "bounds it";
    char text[700];
    std::snprintf(text, sizeof text,
                  "the cloth %s a structural spring strained by %.0f %% (strain %.3g), far past what a woven or "
                  "knitted fabric survives (a few tens of %%): a stretch stiffness (N/m) too low for the fabric's "
                  "weight and size, pins or seams holding panels apart, colliders squeezing it, or a start state "
                  "stretched so; %s",
                  viewer ? "has" : "ends with", 100.0 * double(max_structural_strain), double(max_structural_strain),
                  fix);
    return text;
}

std::string unconverged_implicit_warning(const Simulation& sim, float max_structural_strain, bool viewer,
                                         bool budget_limited) {
    if (!implicit_unconverged(sim, max_structural_strain)) return {};
    const ImplicitStats& st = sim.implicit_stats();
    const SimulationParams& p = sim.params();
    auto fmt = [](const char* f, auto... v) {
        char b[400];
        std::snprintf(b, sizeof b, f, v...);
        return std::string(b);
    };
    std::vector<std::string> fixes;
    if (p.implicit.tolerance > unconverged_residual)
        fixes.push_back(fmt(viewer ? "lower the tolerance (now %g) below %g" : "lower --tolerance (now %g) below %g "
                                                                              "(allowed [0, 1])",
                            double(p.implicit.tolerance), unconverged_residual));
    if (budget_limited)
        fixes.push_back("give the Physics panel's iteration budget more ms or switch it off (it ran " +
                        std::to_string(st.iterations) + " sweeps)");
    if (p.implicit.iterations < implicit_max_iterations)
        fixes.push_back(fmt(viewer ? "raise the Physics panel's iterations (now %u, allowed [1, %u])"
                                   : "raise --iterations (now %u, allowed [1, %u])",
                            p.implicit.iterations, implicit_max_iterations));
    fixes.push_back(fmt(viewer ? "shorten dt (now %.4g s)" : "shorten --dt (now %.4g s, allowed [%g, 0.1] s)",
                        double(p.dt), double(implicit_min_dt)));
    if (!(p.strain_limit.ratio > 0.0f)) // on already and not holding: the sweeps are what to change
        fixes.push_back(viewer ? "switch the strain limit on (0.1 = 10 %)" : "set --strain-limit (0.1 = 10 %)");
    std::string fix;
    for (std::size_t k = 0; k < fixes.size(); ++k)
        fix += (k == 0 ? "" : k + 1 == fixes.size() ? " or " : ", ") + fixes[k];
    return fmt("the cloth is strained by %.0f %% (max structural strain %.3g, above %.0f %%) and the implicit steps "
               "are far from converged (relative residual %.3g after %u sweeps, above %g): this strain is the sweeps' "
               "error, not the fabric's; ",
               100.0 * double(max_structural_strain), double(max_structural_strain), 100.0 * double(unconverged_strain),
               st.relative_residual, st.iterations, unconverged_residual) +
           fix;
}

// At the bound w^2 dt^2 + 2 g dt = 4 (stability.cpp): the damping's share of it, 2 g dt / 4, says which sets it.
bool damping_sets_explicit_bound(const StabilityBound& bound) { return 0.5 * bound.gamma_max * bound.dt_max > 0.5; }

std::string explicit_bound_cause(const StabilityBound& bound) {
    char cause[400];
    if (damping_sets_explicit_bound(bound))
        std::snprintf(cause, sizeof cause,
                      "the damping sets that bound (damping rates up to %.3g 1/s; the stiffness alone would allow %.3g "
                      "s): a smaller material.damping (the fabric model's Rayleigh beta, s) or damping_ratio (the "
                      "springs model) allows longer substeps",
                      bound.gamma_max, bound.omega2_max > 0.0 ? 2.0 / std::sqrt(bound.omega2_max) : 0.1);
    else
        std::snprintf(cause, sizeof cause,
                      "the stiffest spring (%.4g N/m) on the lightest particle (%.3g g) sets that bound, and it "
                      "shrinks as the cloth gets finer",
                      bound.max_stiffness, 1e3 * bound.min_mass);
    return cause;
}

std::string long_explicit_run_warning(const StabilityBound& bound, double dt, std::uint64_t substeps,
                                      std::size_t particles) {
    const double work = double(substeps) * double(particles);
    if (!(work > long_explicit_run_work)) return {};
    const std::string cause = explicit_bound_cause(bound);
    const double minutes = work / 5e8 / 60.0;
    char duration[64];
    if (minutes < 90.0)
        std::snprintf(duration, sizeof duration, "%.0f minute%s", std::max(1.0, std::round(minutes)),
                      minutes < 1.5 ? "" : "s");
    else
        std::snprintf(duration, sizeof duration, "%.3g hours", minutes / 60.0);
    char text[900];
    std::snprintf(text, sizeof text,
                  "this run takes %.4g substeps of %.3g s (under the explicit stability bound, %.3g s) for %zu "
                  "particles: %.3g particle-substeps, about %s at 5e8 a second (2 cores); %s. The implicit solver "
                  "(--solver implicit) takes steps of up to 0.1 s at any stiffness and damping",
                  double(substeps), dt, bound.dt_max, particles, work, duration, cause.c_str());
    return text;
}

} // namespace drape::app

