// One implicit step (backward Euler by vertex block descent; implicit.hpp, docs/implicit.md), from buffer A
// (x^n, v^n) into buffer B:
//   0. aero_forces at x^n (when on), as constant forces of the step;
//   1. per particle: the inertial prediction y = x^n + h v^n + h^2 (g + wind + f_aero / m) and the initial guess
//      (VBD paper section 3.6, "adaptive"): x^n + h v^n + h^2 (s g + the rest), s = the part of gravity the particle
//      was last seen accelerating with, clamped to [0, 1] (a resting particle starts at rest, a falling one falls);
//   2. on a grid or outline cloth of the fabric model, the multilevel guess: the same step solved on coarser copies
//      of the same fabric, coarsest first, each level's displacement mapped onto the next finer one as its guess;
//   3. the sweeps (vbd::Solver::run): colours in order, each vertex one local Newton step, Chebyshev acceleration;
//   4. v^{n+1} = (x - x^n) / h.
// The step then goes through the same strain-limit and collide passes as an explicit substep (substep.cpp).
// Determinism: a vertex reads only vertices of other colours and writes only itself; residuals are summed per fixed
// chunk and the chunks in order; interpolation is per node; so every thread count gives the same bits. No allocation:
// the scratch is cooked with the solver (cook_implicit).
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "drape/simulation.hpp"
#include "for_each_index.hpp"
#include "implicit_solver.hpp"

namespace drape {

const char* solver_name(Solver solver) noexcept { return solver == Solver::implicit ? "implicit" : "explicit"; }

Simulation::~Simulation() = default;
Simulation::Simulation(Simulation&&) noexcept = default;
Simulation& Simulation::operator=(Simulation&&) noexcept = default;

const VbdGraph& Simulation::vbd_graph() const noexcept {
    static const VbdGraph empty;
    return implicit_ ? implicit_->fine.graph() : empty;
}

std::uint32_t Simulation::implicit_levels() const noexcept {
    if (!implicit_) return 0;
    return params_.implicit.multilevel ? static_cast<std::uint32_t>(1 + implicit_->coarse.size()) : 1;
}

namespace {

/// The most sweeps a coarse level runs per step (or twice the fine sweeps where that is more: a step asked to
/// converge fully gets a converged guess). Each level runs twice the sweeps of the next finer one, up to this:
/// more sweeps on a 5 x 5 .. 40 x 40 copy of the cloth solve that copy's own problem better, and its shape (its clips
/// spread over a quarter of the cloth) is not the fine cloth's. Measured (drape_implicit convergence, one step of the
/// wool hang, error after 30 fine sweeps): at N = 316 a cap of 1000 gave 6.25e-3, 240 gave 3.47e-3, 120 gave 2.06e-3
/// and 60 gave 3.09e-3; at N = 100, 1.21e-2 / 1.25e-2 / 1.67e-2 / 2.96e-2 (docs/implicit.md, "Coarse sweeps").
constexpr std::uint32_t coarse_iterations_max = 240;

/// What a sweep of a small coarse level costs beyond its particles, in particles: its colours' SIMD batches are
/// mostly empty and each sweep has fixed passes. Measured (2-core AMD EPYC with AVX-512, one thread, the N = 100 wool
/// hang at 10 sweeps, 60 steps, two runs): 37-41 ns per particle and sweep on the 50 x 50 and 25 x 25 levels, 74-76
/// ns on the 13 x 13 and 145-154 ns on the 7 x 7: some 5-6 us per sweep on top of ~38 ns per particle. Costed
/// without it, the 13 x 13 and 7 x 7 levels ran 80 and 160 sweeps (now 62 and 79) and took a quarter of the step
/// (docs/implicit.md, "Small coarse levels costed by their sweeps"). Checked again after the grid layout stopped
/// padding sub-grid rows (2026-11-28): without it the program ran 1.03x the time (farm-bench, within noise) and the
/// strain at 2 s rose from 0.0950 to 0.1001, over the 0.10 bound.
constexpr double sweep_floor_particles = 150.0;

/// Whether the coarse levels run half their sweeps (the first the cloth's k instead of 2k): on a cloth that touches nothing (no
/// collider, no self-collision) in a step of fewer than coarse_iterations_max / 2 sweeps. That level's sweeps cost
/// half the cloth's at 2k and a quarter at k: the wool hang at 10 sweeps with the strain limit at 0.095 ran 1.06x
/// (N = 100), 1.14x (N = 316) and 1.06-1.07x (N = 1000) faster (paired whole-process wall 0.91 and 0.94 at N = 100 and
/// 316), its structural strain within 0.10 over the whole run. Contact keeps 2k (the crumpled pile's contact
/// sub-steps at k: 22 intersecting pairs and 0.78 strain), and so does a step asked to converge (the one-step
/// reference at 300 sweeps: 0.56 mm from Newton's minimum at k, 0.08 mm at 2k); a quarter of every level's sweeps fed
/// energy into a grabbed cloth (docs/implicit.md, "First coarse level at the cloth's sweeps on a free cloth").
bool free_first_level(const SimulationParams& p) noexcept {
    return p.colliders.empty() && p.self_collision.thickness == 0.0f && 2 * p.implicit.iterations < coarse_iterations_max;
}

/// A coarse level's sweeps per step: the cloth's k times its sweep factor, at most coarse_iterations_max (or 2k);
/// every level of a free cloth half that (free_first_level; until 2026-11-30 only the first: at 10 sweeps the levels
/// of N = 316 ran 10, 40, 80, 160, 237, 240, now 10, 20, 40, 80, 119, 142). The coarse levels cost as much as the
/// cloth's own sweeps (stage timers, N = 316: 16.3 of a 32.3 ms step, the serial 40 x 40 .. 5 x 5 levels 6.7 ms of
/// it), and their second half bought little: one step's energy error after 10 sweeps 6.89e-3 -> 7.44e-3 (N = 316)
/// and 2.14e-2 -> 2.56e-2 (N = 100), the strain over a 2 s hang without the limit 0.637 -> 0.641 and 0.314 -> 0.320,
/// real time with the limit 0.97-1.01x -> 1.12-1.20x (N = 316) and 7.8-8.6x -> 9.7-10.0x (N = 100)
/// (docs/implicit.md, "Half the coarse sweeps on a free cloth"). The plan (implicit_level_plan) and the step
/// (multilevel_guess) both ask here.
std::uint32_t coarse_sweeps(const SimulationParams& p, double sweep_factor) noexcept {
    const std::uint32_t k = p.implicit.iterations;
    const double factor = free_first_level(p) ? 0.5 * sweep_factor : sweep_factor;
    return std::min<std::uint32_t>(std::max(coarse_iterations_max, 2 * k),
                                   static_cast<std::uint32_t>(std::lround(k * factor)));
}

/// A coarser copy is kept only if it has at most this share of the next finer one's particles (a cloth whose
/// rebuild hardly thins it, such as an outline already at its outline's own sampling, stops there) and at least
/// coarsest_particles.
constexpr double coarse_share_max = 0.7;
constexpr std::size_t coarsest_particles = 16;

/// out[a][k] = the transfer of src[a] (less base[a], when base is given) onto target node k (LevelTransfer), for K
/// arrays at once (each node's sources and weights read once), per node in parallel.
template <bool Parallel, std::size_t K>
void transfer(const LevelTransfer& t, const std::array<const float*, K>& src, const std::array<const float*, K>* base,
              const std::array<float*, K>& out) {
    const std::size_t count = t.size();
    for_each_index<Parallel>((count + block_particles - 1) / block_particles, [&](std::size_t blk) {
        for (std::size_t k = blk * block_particles, end = std::min(count, (blk + 1) * block_particles); k < end; ++k) {
            const auto& i = t.index[k];
            const auto& w = t.weight[k];
            for (std::size_t a = 0; a < K; ++a) {
                float v = 0.0f, b = 0.0f;
                for (std::size_t c = 0; c < LevelTransfer::width; ++c) v += w[c] * src[a][i[c]];
                if (base)
                    for (std::size_t c = 0; c < LevelTransfer::width; ++c) b += w[c] * (*base)[a][i[c]];
                out[a][k] = v - b;
            }
        }
    });
}

/// The transpose of transfer (no base): out (out_count source nodes) = the sum over the target nodes of each one's
/// value times the weight its transfer gives each source node. Serial, in node order.
void transfer_transpose(const LevelTransfer& t, const float* src, float* out, std::size_t out_count) {
    std::fill(out, out + out_count, 0.0f);
    for (std::size_t k = 0; k < t.size(); ++k)
        for (std::size_t c = 0; c < LevelTransfer::width; ++c) out[t.index[k][c]] += src[k] * t.weight[k][c];
}

/// The initial guess of a cloth at rest takes no gravity: once its rms speed has stayed below guess_rest_speed x g h
/// for guess_rest_steps steps, until it exceeds it. Before (the vertex block descent paper's adaptive guess at every
/// step: the share of gravity each particle's last acceleration had, clamped to [0, 1]) a cloth at rest read part of the
/// sweeps' unconverged remainder as acceleration, took that share of gravity into its next guess, kept part of it after
/// the sweeps and read more the next step: the cotton drape at rest on the disc (the explicit solver's equilibrium,
/// N = 34) gained kinetic energy e-fold every ~0.3 s on one level at 30 sweeps (3e-7 J at 0.5 s, 9e-5 J at 2.9 s) and
/// its drape coefficient fell from 0.29 to 0.11 (docs/implicit.md, "The guess at rest"). The bounds are FAS at rest's
/// (fas_rest_on, fas_rest_steps).
constexpr double guess_rest_speed = fas_rest_on;
constexpr std::uint32_t guess_rest_steps = fas_rest_steps;

} // namespace

std::vector<ImplicitLevelPlan> Simulation::implicit_level_plan() const {
    if (!implicit_) return {};
    const std::uint32_t k = params_.implicit.iterations;
    std::vector<ImplicitLevelPlan> plan{{cloth_.particle_count, k}};
    if (params_.implicit.multilevel)
        for (std::size_t l = 0; l < implicit_->coarse.size(); ++l) {
            const CoarseLevel& L = implicit_->coarse[l];
            plan.push_back({L.cloth.particle_count, coarse_sweeps(params_, L.sweep_factor)});
        }
    return plan;
}

void Simulation::cook_implicit() {
    if (implicit_) return;
    auto solver = std::make_unique<ImplicitSolver>();
    // A mirror-symmetric cloth (as it is now: the T-shirt at its start) is coloured in mirror pairs (vbd::mirror_twins).
    const StateBuffer& now = cur();
    const std::size_t n = cloth_.particle_count;
    // The pieces of cloth (particles joined by springs, seams included): a union-find, each particle's root stored.
    solver->piece.resize(cloth_.particle_count);
    std::uint32_t* root = solver->piece.data();
    std::iota(root, root + cloth_.particle_count, 0u);
    auto find = [&](std::uint32_t i) {
        while (root[i] != i) i = root[i] = root[root[i]];
        return i;
    };
    for (const Edge& e : cloth_.edges) {
        const std::uint32_t ra = find(e.a), rb = find(e.b);
        if (ra != rb) root[std::max(ra, rb)] = std::min(ra, rb);
    }
    for (std::uint32_t i = 0; i < cloth_.particle_count; ++i) root[i] = find(i);
    solver->piece_held.assign(cloth_.particle_count, 0);
    // A mirror-exact cloth (Cloth::mirror) brings its own map, and vbd::cook makes its sweeps mirror-exact
    // (VbdGraph::mirror_exact); another mesh's twins are found from its positions.
    const std::vector<std::uint32_t> fine_twins =
        !cloth_.mirror.empty() || cloth_.grid
            ? std::vector<std::uint32_t>{}
            : vbd::mirror_twins({now.x.data(), n}, {now.y.data(), n}, {now.z.data(), n});
    solver->fine.cook(cloth_, fine_twins);
    if (!edge_rest_.empty()) solver->fine.set_spring_rest(edge_rest_); // seams being sewn (sewing.cpp)
    // Coarse levels: a cloth that can rebuild its fabric at a coarser spacing (Cloth::coarsen: grids, outlines).
    if (cloth_.coarsen) {
        std::size_t finer_count = cloth_.particle_count;
        std::vector<std::uint32_t> finer_twins; // the next finer copy's mirror twins
        for (std::uint32_t k = 1;; ++k) {
            std::optional<CoarseCloth> copy = cloth_.coarsen(k);
            if (!copy) break;
            const std::size_t count = copy->cloth.particle_count;
            if (count < coarsest_particles || double(count) > coarse_share_max * double(finer_count) ||
                copy->from_fine.size() != count || copy->to_finer.size() != finer_count)
                break;
            CoarseLevel level;
            // Twice the sweeps of the next finer level where its sweep costs at most a third of that one's (a grid's
            // quarter: twice the sweeps cost half as much), else the square root of the ratio (an outline's levels
            // thin less: its outline's own points stay), so that no level costs more than the next finer one. From
            // the second coarse level on, a sweep is costed as sweep_floor_particles more particles than the level
            // has; the first keeps twice the cloth's sweeps whatever its size (it carries the cloth's smooth error),
            // halved on a free cloth at real-time sweep counts (free_first_level; the later levels' factors stay).
            const double overhead = solver->coarse.empty() ? 0.0 : sweep_floor_particles;
            const double ratio = (double(finer_count) + overhead) / (double(count) + overhead);
            level.sweep_factor =
                std::min(256.0, (solver->coarse.empty() ? 1.0 : solver->coarse.back().sweep_factor) *
                                    (ratio >= 3.0 ? 2.0 : std::sqrt(ratio)));
            finer_count = count;
            level.cloth = std::move(copy->cloth);
            level.from_fine = std::move(copy->from_fine);
            level.to_finer = std::move(copy->to_finer);
            // A mirror-symmetric copy (an outline cut symmetric, as built) is coloured in mirror pairs as the cloth is,
            // and its maps treat mirror images alike.
            std::vector<std::uint32_t> twins = level.cloth.grid || copy->x.size() != count
                                                   ? std::vector<std::uint32_t>{}
                                                   : vbd::mirror_twins(copy->x, copy->y, copy->z);
            if (!twins.empty() && !fine_twins.empty()) {
                level.from_fine.symmetrise(twins, fine_twins);
                level.to_finer.symmetrise(solver->coarse.empty() ? fine_twins : finer_twins, twins);
            }
            level.solver.cook(level.cloth, twins);
            finer_twins = std::move(twins);
            for (std::vector<float>* a : {&level.x0, &level.y0, &level.z0, &level.vx, &level.vy, &level.vz, &level.gx,
                                          &level.gy, &level.gz, &level.x, &level.y, &level.z, &level.inv_mass,
                                          &level.rx, &level.ry, &level.rz, &level.tx, &level.ty, &level.tz})
                a->assign(count, 0.0f);
            for (const Edge& e : level.cloth.edges) level.rest0.push_back(e.rest);
            level.rest = level.rest0;
            level.free_inv_mass = level.cloth.free_inv_mass.size() == count
                                      ? level.cloth.free_inv_mass
                                      : std::vector<float>(level.cloth.inv_mass.begin(),
                                                           level.cloth.inv_mass.begin() + std::ptrdiff_t(count));
            level.nearest = level.from_fine.nearest();
            level.up = level.to_finer.nearest();
            level.held.assign(count, 0);
            solver->coarse.push_back(std::move(level));
        }
        if (!solver->coarse.empty()) {
            solver->touching.assign(cloth_.particle_count, 0);
            for (std::vector<float>* a : {&solver->corr_x, &solver->corr_y, &solver->corr_z, &solver->res_x,
                                          &solver->res_y, &solver->res_z})
                a->assign(cloth_.particle_count, 0.0f);
        }
    }
    solver->block_dot.assign(cloth_.block_count(), 0.0); // FAS's dot products and the guess's rest test
    implicit_ = std::move(solver);
}

const char* fas_at_rest_excluded_by(const SimulationParams& p) noexcept {
    return !p.colliders.empty()                ? "colliders"
           : p.self_collision.thickness > 0.0f ? "self-collision"
           : p.wind.enabled                    ? "wind"
           : p.aero.enabled                    ? "aerodynamic wind"
                                               : nullptr;
}

/// Block sums added in block order: the same bits at any worker count.
template <bool Parallel> double Simulation::rms_speed() {
    ImplicitSolver& is = *implicit_;
    const StateBuffer& a = buffers_[current_];
    const std::size_t n = cloth_.particle_count;
    for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
        double m = 0.0;
        for (std::size_t i = blk * block_particles, end = std::min(n, (blk + 1) * block_particles); i < end; ++i)
            if (cloth_.inv_mass[i] != 0.0f)
                m += double(a.u[i]) * a.u[i] + double(a.v[i]) * a.v[i] + double(a.w[i]) * a.w[i];
        is.block_dot[blk] = m;
    });
    double sum = 0.0;
    for (double m : is.block_dot) sum += m;
    return std::sqrt(sum / double(std::max<std::size_t>(1, n)));
}

/// ImplicitParams::fas_at_rest: whether this step's coarse levels solve with FAS because the cloth is at rest.
template <bool Parallel> bool Simulation::fas_at_rest() {
    ImplicitSolver& is = *implicit_;
    const std::array<float, 3> g = gravity_now();
    const double gh = std::sqrt(double(g[0]) * g[0] + double(g[1]) * g[1] + double(g[2]) * g[2]) * params_.dt;
    if (!params_.implicit.fas_at_rest || fas_at_rest_excluded_by(params_) != nullptr || grabbed_ != SIZE_MAX ||
        !(gh > 0.0)) {
        is.slow_steps = 0;
        return is.at_rest = false;
    }
    // The root mean square speed (implicit_step took it this step), not the fastest particle: at N = 316 a few next to
    // the clips kept 0.18 m/s at rest (the plain guess's drift against the strain limit), which held FAS off for good.
    const double v = is.rms_speed / gh;
    const double on = double(fas_rest_on) * is.rest_scale;
    if (!is.at_rest) {
        is.slow_steps = v < on ? is.slow_steps + 1 : 0;
        is.at_rest = is.slow_steps >= fas_rest_steps;
        is.rest_steps = is.at_rest ? 1 : 0;
        return is.at_rest;
    }
    is.rest_steps = std::min(is.rest_steps + 1, fas_rest_grace_steps + 1);
    if (v >= fas_rest_off) { // moved on: a push, a pin released
        is.at_rest = false;
    } else if (is.rest_steps > fas_rest_grace_steps && v >= on) {
        // Not at rest after all (a cloth still swinging slowly, which FAS kept moving): off, and at rest next time
        // only below half the speed.
        is.at_rest = false;
        is.rest_scale = std::max(0.5f * is.rest_scale, fas_rest_scale_min);
    }
    if (!is.at_rest) is.slow_steps = 0;
    return is.at_rest;
}

/// Step 2 above: fills buffer B's positions (holding the fine initial guess) with the multilevel guess; returns whether
/// its coarse levels solved with FAS.
template <bool Parallel> bool Simulation::multilevel_guess() {
    ImplicitSolver& is = *implicit_;
    const StateBuffer& a = buffers_[current_];
    StateBuffer& b = buffers_[1 - current_];
    const float h = params_.dt, h2 = h * h;
    const std::array<float, 3> g = gravity_now();
    const float gx = g[0], gy = g[1], gz = g[2];
    const double t = step_time_;
    const bool wind = params_.wind.enabled;
    const float wind_x = params_.wind.strength * static_cast<float>(std::sin(10.0 * t));
    const float wind_phase = static_cast<float>(std::fmod(10.0 * t + cloth_.origin[2], 2.0 * M_PI));
    const bool fas = params_.implicit.fas || fas_at_rest<Parallel>();
    // The nodes that stand for a fixed particle, level by level (serial: a few reads per particle, and the flags are
    // set in particle order). Before, a node was fixed only when its nearest particle was: a single particle held in
    // the middle of a 32 x 32 hang (a grab, a pin) was on no coarse level whose node did not fall on it, so the coarse
    // levels let the cloth around it fall and 10 sweeps could not pull it back: its springs reached 150 % strain in
    // 15 steps and blew up, where exact backward Euler (Newton) keeps 2.6 % (docs/implicit.md, "A held particle in the
    // middle").
    for (CoarseLevel& L : is.coarse) std::fill(L.held.begin(), L.held.end(), std::uint8_t{0});
    for (std::size_t i = 0; i < cloth_.particle_count; ++i) {
        if (cloth_.inv_mass[i] != 0.0f) continue;
        std::uint32_t k = static_cast<std::uint32_t>(i);
        for (CoarseLevel& L : is.coarse) {
            k = L.up[k];
            L.held[k] = node_fixed;
        }
    }
    // Against colliders the coarse levels leave the cloth where it touches them to its own sweeps (truncation, as in
    // monotone multigrid for obstacle problems): a node whose interpolation reaches a particle that touched a collider
    // in the last step or is within h |v| + |g| h^2 of one (the step may take it there; a cloth at rest on a disc: the
    // 2 mm drum skin of its top), or reaches such a node on the next finer level, is held at the cloth's guess. A
    // coarse copy cannot be at rest where the cloth is (its nodes cut the rim's corner), and its correction there
    // moved a drape at rest on the disc by itself (N = 34: DC 0.29 -> 0.53 in 3 s). Held only while the cloth is slow,
    // the frictionless rim test stretched to 0.16; held always, the wool on the sphere (cap and skirt within reach)
    // keeps only the cloth's sweeps there and stretches more on the way (0.092 at 2 s against 0.014; 0.019 at 8 s
    // against 0.007) (docs/implicit.md, "Coarse levels in contact").
    const bool contact = !params_.colliders.empty();
    if (contact) {
        const float *cnx = is.fine.contact_nx(), *cny = is.fine.contact_ny(), *cnz = is.fine.contact_nz();
        const float gh2 = std::sqrt(gx * gx + gy * gy + gz * gz) * h2;
        const std::size_t n = cloth_.particle_count;
        std::uint8_t* touching = is.touching.data();
        for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
            for (std::size_t i = blk * block_particles, end = std::min(n, (blk + 1) * block_particles); i < end; ++i) {
                bool t = cnx[i] != 0.0f || cny[i] != 0.0f || cnz[i] != 0.0f;
                const float reach = h * std::sqrt(a.u[i] * a.u[i] + a.v[i] * a.v[i] + a.w[i] * a.w[i]) + gh2;
                for (std::size_t c = 0; !t && c < params_.colliders.size(); ++c)
                    t = is_inside(params_.colliders[c], {a.x[i], a.y[i], a.z[i]}, -reach);
                touching[i] = t ? 1 : 0;
            }
        });
        for (std::size_t l = 0; l < is.coarse.size(); ++l) {
            CoarseLevel& L = is.coarse[l];
            const LevelTransfer& t = L.to_finer;
            for (std::size_t k = 0; k < t.size(); ++k) {
                if (l == 0 ? !touching[k] : is.coarse[l - 1].held[k] != node_touching) continue;
                for (std::size_t c = 0; c < LevelTransfer::width; ++c)
                    if (t.weight[k][c] != 0.0f && L.held[t.index[k][c]] == node_free)
                        L.held[t.index[k][c]] = node_touching;
            }
        }
    }
    // FAS at rest comes in over fas_rest_ramp_steps: its correction tau scaled from 1 / ramp to 1, so the cloth
    // moves from the plain guess's rest to its own gradually instead of in one step (which turned the 6 mm into
    // a velocity that light air drag took seconds to remove).
    const float ramp = params_.implicit.fas ? 1.0f
                                            : std::min(1.0f, float(is.rest_steps) / float(fas_rest_ramp_steps));
    if (fas) {
        // The cloth's force residual at x^n (grad E - M a_ext: zero at rest), restricted level by level.
        float* rx = is.res_x.data();
        float* ry = is.res_y.data();
        float* rz = is.res_z.data();
        is.fine.gradient<Parallel>({a.x.data(), a.y.data(), a.z.data(), a.x.data(), a.y.data(), a.z.data(),
                                    cloth_.inv_mass.data()},
                                   h, params_.air_drag, rx, ry, rz);
        const std::size_t n = cloth_.particle_count;
        for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
            for (std::size_t i = blk * block_particles, end = std::min(n, (blk + 1) * block_particles); i < end; ++i) {
                if (cloth_.inv_mass[i] == 0.0f) continue;
                const float mh = 1.0f / (cloth_.inv_mass[i] * h);
                rx[i] += mh * a.u[i];
                ry[i] += mh * a.v[i];
                rz[i] += mh * a.w[i];
            }
        });
        for (std::size_t l = 0; l < is.coarse.size(); ++l) {
            CoarseLevel& L = is.coarse[l];
            const std::size_t count = L.cloth.particle_count;
            const float* sx = l == 0 ? rx : is.coarse[l - 1].rx.data();
            const float* sy = l == 0 ? ry : is.coarse[l - 1].ry.data();
            const float* sz = l == 0 ? rz : is.coarse[l - 1].rz.data();
            transfer_transpose(L.to_finer, sx, L.rx.data(), count);
            transfer_transpose(L.to_finer, sy, L.ry.data(), count);
            transfer_transpose(L.to_finer, sz, L.rz.data(), count);
        }
    }
    for (std::size_t l = is.coarse.size(); l-- > 0;) {
        CoarseLevel& L = is.coarse[l];
        const std::size_t count = L.cloth.particle_count;
        const LevelTransfer& from_fine = L.from_fine;
        transfer<Parallel, 9>(from_fine,
                              {a.x.data(), a.y.data(), a.z.data(), a.u.data(), a.v.data(), a.w.data(), b.x.data(),
                               b.y.data(), b.z.data()},
                              nullptr,
                              {L.x0.data(), L.y0.data(), L.z0.data(), L.vx.data(), L.vy.data(), L.vz.data(),
                               L.gx.data(), L.gy.data(), L.gz.data()});
        if (l + 1 < is.coarse.size()) { // the next coarser level's correction of the guess
            const CoarseLevel& C = is.coarse[l + 1];
            const std::array<const float*, 3> base{C.gx.data(), C.gy.data(), C.gz.data()};
            transfer<Parallel, 3>(C.to_finer, {C.x.data(), C.y.data(), C.z.data()}, &base,
                                  {L.x.data(), L.y.data(), L.z.data()});
        } else {
            std::fill(L.x.begin(), L.x.end(), 0.0f);
            std::fill(L.y.begin(), L.y.end(), 0.0f);
            std::fill(L.z.begin(), L.z.end(), 0.0f);
        }
        float* px = L.solver.pred_x();
        float* py = L.solver.pred_y();
        float* pz = L.solver.pred_z();
        for_each_index<Parallel>((count + block_particles - 1) / block_particles, [&](std::size_t blk) {
            for (std::size_t k = blk * block_particles, end = std::min(count, (blk + 1) * block_particles); k < end; ++k) {
                const bool fixed = L.held[k] != node_free || cloth_.inv_mass[L.nearest[k]] == 0.0f ||
                                   L.free_inv_mass[k] == 0.0f;
                L.inv_mass[k] = fixed ? 0.0f : L.free_inv_mass[k];
                if (L.held[k] == node_touching) { // at the cloth's guess: no correction
                    px[k] = L.x[k] = L.gx[k];
                    py[k] = L.y[k] = L.gy[k];
                    pz[k] = L.z[k] = L.gz[k];
                    continue;
                }
                if (fixed) {
                    px[k] = L.x[k] = L.gx[k] = L.x0[k];
                    py[k] = L.y[k] = L.gy[k] = L.y0[k];
                    pz[k] = L.z[k] = L.gz[k] = L.z0[k];
                    continue;
                }
                float ex = 0.0f, ez = 0.0f;
                if (wind) {
                    ex = wind_x;
                    ez = params_.wind.strength * std::fabs(std::sin(L.z0[k] + wind_phase));
                }
                px[k] = L.x0[k] + h * L.vx[k] + h2 * (gx + ex);
                py[k] = L.y0[k] + h * L.vy[k] + h2 * gy;
                pz[k] = L.z0[k] + h * L.vz[k] + h2 * (gz + ez);
                L.x[k] += L.gx[k]; // the guess plus the coarser correction
                L.y[k] += L.gy[k];
                L.z[k] += L.gz[k];
            }
        });
        if (fas || contact) {
            // Springs compressed at x^n are slack (no buckling saddles; in contact, a coarse spring across a fold
            // pushed the cloth apart with the full stretch stiffness: docs/implicit.md, "The energy source"), then,
            // under FAS, the level's own residual at x^n.
            const std::vector<Edge>& edges = L.cloth.edges;
            for (std::size_t e = 0; e < edges.size(); ++e) {
                const std::uint32_t i = edges[e].a, j = edges[e].b;
                const float dx = L.x0[j] - L.x0[i], dy = L.y0[j] - L.y0[i], dz = L.z0[j] - L.z0[i];
                L.rest[e] = std::min(L.rest0[e], std::sqrt(dx * dx + dy * dy + dz * dz));
            }
            L.solver.set_spring_rest(L.rest);
            L.slack = true;
        }
        if (fas) {
            L.solver.gradient<false>({L.x0.data(), L.y0.data(), L.z0.data(), L.x0.data(), L.y0.data(), L.z0.data(),
                                      L.inv_mass.data()},
                                     h, params_.air_drag, L.tx.data(), L.ty.data(), L.tz.data());
            // G - tau . x with tau = (the level's residual: its gradient at x^n plus M v^n / h) - (the cloth's,
            // restricted), folded into the prediction as y + h^2 M^-1 tau.
            for (std::size_t k = 0; k < count; ++k) {
                const float w = L.inv_mass[k];
                if (w == 0.0f) continue;
                px[k] += ramp * (h2 * w * (L.tx[k] - L.rx[k]) + h * L.vx[k]);
                py[k] += ramp * (h2 * w * (L.ty[k] - L.ry[k]) + h * L.vy[k]);
                pz[k] += ramp * (h2 * w * (L.tz[k] - L.rz[k]) + h * L.vz[k]);
            }
        } else if (L.slack && !contact) { // FAS switched off: the natural rest lengths again
            L.rest = L.rest0;
            L.solver.set_spring_rest(L.rest);
            L.slack = false;
        }
        // The level's sweeps: the cloth's times L.sweep_factor (cook_implicit), at most coarse_iterations_max; the
        // first level of a free cloth half that (free_first_level).
        ImplicitParams level_params = params_.implicit;
        level_params.iterations = coarse_sweeps(params_, L.sweep_factor);
        vbd::LevelState st{L.x0.data(), L.y0.data(), L.z0.data(), L.x.data(), L.y.data(), L.z.data(),
                           L.inv_mass.data(), params_.colliders};
        st.coulomb_guess = l + 1 == is.coarse.size(); // the coarsest level starts from the inertial guess
        st.contact_steps = params_.self_collision.thickness == 0.0f;
        L.solver.run<Parallel>(st, level_params, h, params_.air_drag);
    }
    // The cloth's guess plus the finest coarse level's correction.
    const CoarseLevel& C = is.coarse.front();
    float* cx = is.corr_x.data();
    float* cy = is.corr_y.data();
    float* cz = is.corr_z.data();
    const std::array<const float*, 3> base{C.gx.data(), C.gy.data(), C.gz.data()};
    transfer<Parallel, 3>(C.to_finer, {C.x.data(), C.y.data(), C.z.data()}, &base, {cx, cy, cz});
    const std::size_t n = cloth_.particle_count;
    auto add = [&](float scale) {
        for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
            for (std::size_t i = blk * block_particles, end = std::min(n, (blk + 1) * block_particles); i < end; ++i) {
                if (cloth_.inv_mass[i] == 0.0f) continue;
                b.x[i] += scale * cx[i];
                b.y[i] += scale * cy[i];
                b.z[i] += scale * cz[i];
            }
        });
    };
    if (!fas && !contact) {
        add(1.0f);
        return false;
    }
    // The slope of the cloth's G along the correction c at the guess and at guess + c; secant step in [0, 1] (under
    // FAS, and against colliders: there the coarse copy's correction is not the cloth's and may raise its G).
    auto slope = [&]() {
        is.fine.gradient<Parallel>({a.x.data(), a.y.data(), a.z.data(), b.x.data(), b.y.data(), b.z.data(),
                                    cloth_.inv_mass.data()},
                                   h, params_.air_drag, is.res_x.data(), is.res_y.data(), is.res_z.data());
        for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
            double d = 0.0;
            for (std::size_t i = blk * block_particles, end = std::min(n, (blk + 1) * block_particles); i < end; ++i)
                d += double(is.res_x[i]) * cx[i] + double(is.res_y[i]) * cy[i] + double(is.res_z[i]) * cz[i];
            is.block_dot[blk] = d;
        });
        double d = 0.0;
        for (double v : is.block_dot) d += v;
        return d;
    };
    const double d0 = slope();
    add(1.0f);
    if (d0 >= 0.0) { // not a descent direction
        add(-1.0f);
        return fas;
    }
    const double d1 = slope();
    if (d1 > 0.0) add(static_cast<float>(d0 / (d0 - d1)) - 1.0f);
    return fas;
}

template <bool Parallel> void Simulation::implicit_step() {
    const std::size_t n = cloth_.particle_count;
    ImplicitSolver& is = *implicit_;
    const StateBuffer& a = buffers_[current_];
    StateBuffer& b = buffers_[1 - current_];
    const float h = params_.dt, h2 = h * h, inv_h = 1.0f / h;
    const float* inv_mass = cloth_.inv_mass.data();

    if (params_.aero.enabled) aero_forces_stage<Parallel>();
    const bool aero = params_.aero.enabled;

    // 1. Prediction and initial guess. Buffer B still holds the state one step back: its velocity is v^{n-1}.
    const std::array<float, 3> g = gravity_now();
    const float gx = g[0], gy = g[1], gz = g[2];
    const float g2 = gx * gx + gy * gy + gz * gz;
    const double t = step_time_;
    const bool wind = params_.wind.enabled;
    const float wind_x = params_.wind.strength * static_cast<float>(std::sin(10.0 * t));
    const float wind_phase = static_cast<float>(std::fmod(10.0 * t + cloth_.origin[2], 2.0 * M_PI));
    // The acceleration a particle was last seen with is (v^n - v^{n-1}) / h only when the previous step was one of
    // these. Without one (the first step, a new dt or solver) gravity is taken whole: taken from the state's zero
    // history (s = 0), a free-falling stiff mesh fell at 1 % of g for good, the sweeps' few vertex-sized moves
    // being all the acceleration the next step saw (a 4 x 4 wool mask: 0.036 m/s after 0.3 s, free fall 2.94).
    // A piece's particles fall together only if none of them is fixed (pins and grabs change, so this is asked on
    // each such step; the pieces themselves were found when the solver was cooked).
    const bool fresh = implicit_fresh_;
    implicit_fresh_ = false;
    if (fresh) {
        const std::uint32_t* root = is.piece.data();
        std::fill(is.piece_held.begin(), is.piece_held.end(), std::uint8_t(0));
        for (std::uint32_t i = 0; i < n; ++i)
            if (inv_mass[i] == 0.0f) is.piece_held[root[i]] = 1;
        // A piece resting on a collider is held too: its gravity guess would go into it (a T-shirt on its body, a
        // cloth on a disc, a saved state resumed).
        if (!params_.colliders.empty())
            for (std::uint32_t i = 0; i < n; ++i) {
                if (is.piece_held[root[i]] || inv_mass[i] == 0.0f) continue;
                const Vec3f p{a.x[i] + h2 * gx, a.y[i] + h2 * gy, a.z[i] + h2 * gz};
                for (const Collider& c : params_.colliders)
                    if (is_inside(c, p)) {
                        is.piece_held[root[i]] = 1;
                        break;
                    }
            }
    }
    // At rest (guess_rest_speed); the speed is kept for FAS at rest (multilevel_guess).
    is.rms_speed = rms_speed<Parallel>();
    if (g2 > 0.0f) {
        const double v = is.rms_speed / (std::sqrt(double(g2)) * h);
        is.guess_slow_steps = v < guess_rest_speed && !fresh ? is.guess_slow_steps + 1 : 0;
    }
    // Not under FAS (the option, or FAS at rest acting since the last step): its coarse levels hold the rest already,
    // and the two switching together at the same bound moved the wool hang by 0.68 mm a step at 8 s (FAS at rest
    // alone: 0.015 mm; the test Implicit.FasComesToRestOnTheExplicitEquilibrium).
    const bool guess_at_rest = is.guess_slow_steps >= guess_rest_steps && !params_.implicit.fas && !is.at_rest;
    float* pred_x = is.fine.pred_x();
    float* pred_y = is.fine.pred_y();
    float* pred_z = is.fine.pred_z();
    const float kr = params_.air_drag, drag_share = 1.0f / (1.0f + h * kr);
    // The last step's contact normals (implicit_velocities reads them too; zero where none, or before any step).
    const float *cnx = is.fine.contact_nx(), *cny = is.fine.contact_ny(), *cnz = is.fine.contact_nz();
    const bool contact_history = !params_.colliders.empty();
    for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
        const std::size_t begin = blk * block_particles, end = std::min(begin + block_particles, n);
        for (std::size_t i = begin; i < end; ++i) {
            const float x = a.x[i], y = a.y[i], z = a.z[i];
            if (inv_mass[i] == 0.0f) {
                pred_x[i] = b.x[i] = x;
                pred_y[i] = b.y[i] = y;
                pred_z[i] = b.z[i] = z;
                continue;
            }
            float ex = 0.0f, ey = 0.0f, ez = 0.0f; // accelerations other than gravity
            if (wind) {
                ex += wind_x;
                ez += params_.wind.strength * std::fabs(std::sin(z + wind_phase));
            }
            const float vx = a.u[i], vy = a.v[i], vz = a.w[i];
            if (aero) {
                // The aerodynamic force, taken at x^n, is a drag: over a step it may at most stop the particle's
                // motion relative to the wind, never reverse it (an explicit drag of a light particle over a frame
                // would: measured, the flag scene's energy grew to 1e15 J in 8 steps).
                float fx = extra_fx_[i] * inv_mass[i], fy = extra_fy_[i] * inv_mass[i], fz = extra_fz_[i] * inv_mass[i];
                const float rx = vx - params_.aero.velocity[0], ry = vy - params_.aero.velocity[1],
                            rz = vz - params_.aero.velocity[2];
                const float change = h * std::sqrt(fx * fx + fy * fy + fz * fz);
                const float relative = std::sqrt(rx * rx + ry * ry + rz * rz);
                if (change > relative) {
                    const float scale = relative / change;
                    fx *= scale;
                    fy *= scale;
                    fz *= scale;
                }
                ex += fx;
                ey += fy;
                ez += fz;
            }
            pred_x[i] = x + h * vx + h2 * (gx + ex);
            pred_y[i] = y + h * vy + h2 * (gy + ey);
            pred_z[i] = z + h * vz + h2 * (gz + ez);
            // No step of this solver before (its first, or after new parameters): all of gravity for a piece of
            // cloth that nothing holds; one hanging from a fixed particle reads its history as before.
            float s = 0.0f;
            const bool held_before = contact_history && (cnx[i] != 0.0f || cny[i] != 0.0f || cnz[i] != 0.0f);
            if (fresh && !is.piece_held[is.piece[i]]) {
                s = 1.0f;
            } else if (g2 > 0.0f && !guess_at_rest) {
                // The acceleration of the last step less the air drag's (implicit: v^n (1 + h kr) = v^{n-1} + h a),
                // so a cloth falling at its terminal velocity still reads as falling freely.
                const float ax = (vx - b.u[i]) * inv_h + kr * vx, ay = (vy - b.v[i]) * inv_h + kr * vy,
                            az = (vz - b.w[i]) * inv_h + kr * vz;
                s = std::clamp((ax * gx + ay * gy + az * gz) / g2, 0.0f, 1.0f);
            }
            // Divided by 1 + h kr: the air drag's part of G (m kr / (2 h) |x - x^n|^2) applied to the guess, which
            // is then G's minimiser for a cloth moving as a whole. The sweeps move a stiff cloth as a whole by a
            // vertex-sized amount each, so without it a falling mesh hardly felt the drag (a 2 x 2 cloth of 25,000
            // N/m springs, drag 1/s, reached 54 m/s in 10 s; terminal velocity g / kr = 9.81 m/s).
            // A particle that a collider held in the last step (its contact normal n, gravity into it): the share s
            // of gravity's part into the surface, and all of its part along it, which the contact does not take (from
            // the share alone, the sweeps, slow to move a stiff cloth as a whole, left a cloth on a 20-degree
            // frictionless plane at 1/140 of its g sin 20 acceleration). A collider taken away makes the step fresh:
            // s = 1, all of gravity.
            float tx = s * gx, ty = s * gy, tz = s * gz;
            if (held_before) {
                const float nx = cnx[i], ny = cny[i], nz = cnz[i], gn = gx * nx + gy * ny + gz * nz;
                if (gn < 0.0f) {
                    const float into = (1.0f - s) * gn;
                    tx = gx - into * nx;
                    ty = gy - into * ny;
                    tz = gz - into * nz;
                }
            }
            b.x[i] = x + (h * vx + h2 * (tx + ex)) * drag_share;
            b.y[i] = y + (h * vy + h2 * (ty + ey)) * drag_share;
            b.z[i] = z + (h * vz + h2 * (tz + ez)) * drag_share;
        }
    });

    // 2. The multilevel guess.
    const bool multilevel = params_.implicit.multilevel && !is.coarse.empty();
    const bool fas = multilevel && multilevel_guess<Parallel>();

    // 3. Sweeps.
    vbd::LevelState st{a.x.data(), a.y.data(), a.z.data(), b.x.data(), b.y.data(), b.z.data(), inv_mass,
                       params_.colliders};
    st.coulomb_guess = !multilevel; // else the coarse levels' friction is in the guess
    st.contact_steps = multilevel && params_.self_collision.thickness == 0.0f;
    // Triangles near a solid collider at the step's start (x^n, clear of the colliders; the guess may be
    // inside them): their contact enters the sweeps (implicit_triangle_contact.cpp), on every cloth: with the
    // constrained steps off too (self-collision, single-level cloths) the terms are the triangles' only contact
    // inside the step (without them the implicit T-shirt's hem pushed into the hips put 26 triangles in the body;
    // docs/collisions.md, "Triangle contact inside the solve").
    vbd::TriangleTerms terms;
    if (implicit_triangle_terms<Parallel>(a.x.data(), a.y.data(), a.z.data())) {
        terms = {cloth_.mirror_corners.empty() ? cloth_.triangles.data() : cloth_.mirror_corners.data(),
                 vertex_tri_offsets_.data(),
                 vertex_tris_.data(),     tt_vertex_on_.data(),
                 tt_on_.data(),           tt_term_.data(),
                 tt_colliders_,           tt_reach_};
        if (!tt_warm_.empty()) { // the Jacobi sweeps ignore them (Solver::run)
            terms.warm = tt_warm_.data();
            terms.plane = tt_plane_.data();
        }
        st.triangle_terms = &terms;
    }
    implicit_stats_ = is.fine.run<Parallel>(st, params_.implicit, h, params_.air_drag);
    implicit_stats_.levels = multilevel ? static_cast<std::uint32_t>(1 + is.coarse.size()) : 1;
    implicit_stats_.fas = fas;

    implicit_velocities<Parallel>();
}

/// Step 4: v^{n+1} = (x - x^n) / h (friction acted inside the sweeps: vbd.cpp); a collider contact of the last sweep
/// keeps no inward normal velocity (an inelastic contact). Finite check per block.
template <bool Parallel> void Simulation::implicit_velocities() {
    const std::size_t n = cloth_.particle_count;
    const ImplicitSolver& is = *implicit_;
    const StateBuffer& a = buffers_[current_];
    StateBuffer& b = buffers_[1 - current_];
    const float inv_h = 1.0f / params_.dt;
    const bool contact = !params_.colliders.empty();
    const float *cnx = is.fine.contact_nx(), *cny = is.fine.contact_ny(), *cnz = is.fine.contact_nz();
    for_each_index<Parallel>(cloth_.block_count(), [&](std::size_t blk) {
        const std::size_t begin = blk * block_particles, end = std::min(begin + block_particles, n);
        bool ok = true;
        for (std::size_t i = begin; i < end; ++i) {
            float vx = (b.x[i] - a.x[i]) * inv_h, vy = (b.y[i] - a.y[i]) * inv_h, vz = (b.z[i] - a.z[i]) * inv_h;
            if (contact && (cnx[i] != 0.0f || cny[i] != 0.0f || cnz[i] != 0.0f)) {
                const float vn = vx * cnx[i] + vy * cny[i] + vz * cnz[i];
                if (vn < 0.0f) {
                    vx -= vn * cnx[i];
                    vy -= vn * cny[i];
                    vz -= vn * cnz[i];
                }
            }
            b.u[i] = vx;
            b.v[i] = vy;
            b.w[i] = vz;
            ok = ok && std::isfinite(b.x[i] + b.y[i] + b.z[i] + b.u[i] + b.v[i] + b.w[i]);
        }
        block_ok_[blk] = ok ? 1 : 0;
    });
}

/// The contact re-solve (docs/self_collision.md, "Inside the implicit solve"). Self-collision pushed particles of the
/// step's result apart; on their own those pushes strain the cloth around each contact, which the next step's sweeps
/// then pull back into the contact (the fight measured on the crumpled pile: strain 1.0). Here the step's objective is
/// minimised again from the pushed positions, each pushed particle held on its side of its contact plane (active-set
/// style: the contacts the pass found become constraints), so the cloth around a contact follows it.
template <bool Parallel> void Simulation::implicit_contact_resolve() {
    ImplicitSolver& is = *implicit_;
    const StateBuffer& a = buffers_[current_];
    StateBuffer& b = buffers_[1 - current_];
    vbd::LevelState st{a.x.data(), a.y.data(), a.z.data(), b.x.data(), b.y.data(), b.z.data(),
                       cloth_.inv_mass.data(), params_.colliders};
    st.plane_nx = sc_push_x_.data(); // normalised into the planes' normals at the end of the stage's first run
    st.plane_ny = sc_push_y_.data();
    st.plane_nz = sc_push_z_.data();
    st.plane_c = sc_plane_c_.data();
    is.fine.run<Parallel>(st, params_.implicit, params_.dt, params_.air_drag);
    implicit_velocities<Parallel>();
    ++sc_resolves_;
}

template void Simulation::implicit_step<true>();
template void Simulation::implicit_step<false>();
template void Simulation::implicit_contact_resolve<true>();
template void Simulation::implicit_contact_resolve<false>();

} // namespace drape
