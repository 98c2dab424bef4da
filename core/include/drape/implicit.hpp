// The implicit (backward Euler) solver's parameters, its cooked per-vertex data and its per-step figures.
//
// One implicit step of length h minimises the variational form of backward Euler over the movable particles,
//   G(x) = sum_i m_i/(2 h^2) |x_i - y_i|^2 + sum_i m_i kr/(2 h) |x_i - x_i^n|^2 + E(x) + D(x) - f_ext . x,
// y = x^n + h v^n + h^2 a_ext the inertial prediction, E every elastic energy of the cloth (springs of every kind,
// seams included; bending, bending.hpp) and D the Rayleigh damping written as a potential of the step (spring
// damping along the direction at the start of the step, bending damping beta/(2h) |x - x^n|_Q^2). Every term is
// written out with its gradient and Hessian in docs/implicit.md; the exact reference (implicit_reference.hpp) and the
// fast solver minimise the same G.
//
// The fast solver is vertex block descent (Chen, Liu, Yang and Yuksel 2024, "Vertex Block Descent", ACM TOG 43(4)):
// Gauss-Seidel over vertices, each vertex taking one Newton step of G restricted to its own three coordinates (a 3x3
// solve with the projected, positive-definite local Hessian), vertices of one colour (no energy term couples two of
// them) in parallel, colours in a fixed order; then optional Chebyshev acceleration (Wang 2015) of the sweeps.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace drape {

/// Which solver advances the cloth.
enum class Solver : std::uint8_t {
    explicit_euler, ///< the seeds' explicit substeps (SimulationParams::integrator), dt below the stability bound
    implicit,       ///< backward Euler by vertex block descent, any dt from implicit_min_dt up to 0.1 s
};
const char* solver_name(Solver solver) noexcept; ///< "explicit" / "implicit"

/// The implicit step when a scene or flag gives none: one frame at 30 FPS, s.
inline constexpr float implicit_default_dt = 1.0f / 30.0f;
/// The implicit solver's shortest step, s: below it a step's motion under gravity (h^2 g, 1e-7 m at 1e-4 s) is lost to
/// the float rounding of positions a metre from the origin, and the cloth never moves (found at 1e-9 s).
inline constexpr float implicit_min_dt = 1e-4f;
/// The most sweeps a step may be asked for (ImplicitParams::iterations: scene files, --iterations, the viewer).
inline constexpr std::uint32_t implicit_max_iterations = 1000;

/// Iteration method of the implicit solver.
enum class ImplicitMethod : std::uint8_t {
    gauss_seidel, ///< vertex block descent: colours in order, each vertex sees its neighbours' newest positions
    jacobi,       ///< every vertex from the previous sweep's positions (the parallel-everything variant; slower)
};

/// The fewest sweeps per step with which Chebyshev acceleration runs. Its extrapolation of the last sweeps is left
/// uncorrected when few follow: on the N = 100 wool hang (h = 1/30 s, no strain limit, 2 s; max structural strain over
/// the run) 2 and 3 sweeps with rho 0.9 blew up (the health monitor stopped the run), 4, 5 and 6 sweeps reached 2.21,
/// 0.78 and 0.79 against 0.86, 0.68 and 0.61 plain; from 7 sweeps on it helps (7: 0.53 against 0.56, 8: 0.36 against
/// 0.51, 10: 0.29 against 0.45). docs/implicit.md, "Few sweeps without Chebyshev".
inline constexpr std::uint32_t chebyshev_min_iterations = 7;

/// Below this many sweeps per step Chebyshev's rho is at most chebyshev_few_rho. With rho 0.9 and 7-14 sweeps the
/// extrapolation of the last sweeps left the resting wool hang in a cycle its air drag could not damp: the bottom
/// edge flapping by 25-260 mm a step at N = 16-100 (7, 10, 12 sweeps; 13 at N = 32: 75 mm) where from 15 sweeps, or
/// with rho 0.85 at any count, a particle moves at most 1-6 mm a step at rest (the multilevel guess's own drift).
/// docs/implicit.md, "Chebyshev at few sweeps".
inline constexpr std::uint32_t chebyshev_full_iterations = 15;
inline constexpr float chebyshev_few_rho = 0.85f;

struct ImplicitParams {
    std::uint32_t iterations = 30;  ///< sweeps per step (the most, with a tolerance), 1..1000
    /// Stop early once the sweep residual is below tolerance x the first sweep's (0 = always run `iterations`), 0..1.
    float tolerance = 0.0f;
    /// Chebyshev acceleration's estimate of the sweep's spectral radius, [0, 1); 0 = off. A level whose step runs
    /// fewer than chebyshev_min_iterations sweeps runs them plain, fewer than chebyshev_full_iterations with at most
    /// chebyshev_few_rho (chebyshev_rho_for).
    float chebyshev_rho = 0.9f;
    ImplicitMethod method = ImplicitMethod::gauss_seidel;
    /// On a grid or outline cloth of the fabric model: start each step from the same step solved on coarser copies of
    /// the same fabric (coarsest first, each level's displacement mapped onto the next as its initial guess).
    bool multilevel = true;
    /// With the multilevel guess: each coarse level solves its step with the cloth's own force residual at x^n
    /// (a full approximation scheme, docs/implicit.md "Coarse correction"), so a cloth at rest stays at rest and comes
    /// to rest at the cloth's own equilibrium rather than the coarse grids'. Off: each level solves its own step.
    bool fas = false;
    /// With the multilevel guess and `fas` off: a cloth whose rms particle speed has been below fas_rest_on g h for
    /// fas_rest_steps steps in a row solves its coarse levels with FAS until it is above fas_rest_off g h, or above
    /// the bound that started it after fas_rest_grace_steps (then that bound halves), so it
    /// comes to rest at its own equilibrium instead of the coarse grids' (the plain guess hung the N = 100 wool hang
    /// 11.8 mm from the explicit equilibrium on average, FAS at rest 0.18 mm). Never with colliders, self-collision,
    /// wind, aerodynamic wind or a grab, where FAS misbehaves. Off by default: with 10 sweeps at N >= 200 FAS does not
    /// settle (8-22 mm a step, where the plain guess drifts by 1 mm; docs/implicit.md, "FAS at rest"); there it now
    /// tries twice and stays off.
    bool fas_at_rest = false;
};

/// x g h: a cloth of a smaller rms speed is at rest. The plain guess's own drift at rest is 0.03-0.11 g h (wool hang,
/// N = 32-316, 10 sweeps); a hang still swinging under the scene's light air drag 0.24-0.68 g h, and 0.5 let FAS start
/// there and feed the swing (docs/implicit.md, "FAS at rest under light air drag").
inline constexpr float fas_rest_on = 0.15f;
inline constexpr float fas_rest_off = 2.0f;         ///< x g h: a larger rms speed ends FAS at rest
inline constexpr std::uint32_t fas_rest_steps = 10; ///< steps at rest before FAS starts
/// FAS at rest's first steps move the cloth from the plain guess's rest to its own (a jump of 0.3 g h for one step at
/// N = 100); after these steps a cloth whose rms speed is again above the bound that started FAS is not at rest: FAS
/// stops, and the bound to start it again halves (down to fas_rest_on x fas_rest_scale_min).
inline constexpr std::uint32_t fas_rest_grace_steps = 30;
/// FAS at rest's correction comes in linearly over this many steps (ImplicitSolver::rest_steps).
inline constexpr std::uint32_t fas_rest_ramp_steps = 30;
inline constexpr float fas_rest_scale_min = 1.0f / 16.0f;
// FAS at rest is judged (fas_rest_grace_steps) only once its correction is in whole.
static_assert(fas_rest_grace_steps >= fas_rest_ramp_steps);

/// The Chebyshev rho a level runs its `iterations` sweeps with (0: plain sweeps): the asked rho, none below
/// chebyshev_min_iterations, at most chebyshev_few_rho below chebyshev_full_iterations.
inline float chebyshev_rho_for(const ImplicitParams& ip) {
    if (ip.chebyshev_rho <= 0.0f || ip.iterations < chebyshev_min_iterations) return 0.0f;
    if (ip.iterations < chebyshev_full_iterations && ip.chebyshev_rho > chebyshev_few_rho) return chebyshev_few_rho;
    return ip.chebyshev_rho;
}

/// Figures of the last implicit step.
struct ImplicitStats {
    std::uint32_t iterations = 0;  ///< sweeps run
    /// Sweep residual of the last sweep over the first: sqrt(sum_i |g_i|^2) with g_i the gradient of G at vertex i
    /// when the sweep visits it (Gauss-Seidel: with its neighbours' newest positions); 0 when nothing moves.
    double relative_residual = 0.0;
    double first_residual = 0.0;   ///< N, the first sweep's sqrt(sum |g_i|^2)
    double last_residual = 0.0;    ///< N
    std::uint32_t levels = 1;      ///< grids solved this step (1 + coarse levels)
    bool fas = false;              ///< its coarse levels solved with FAS (ImplicitParams::fas or fas_at_rest)
};

/// One level the implicit solver solves per step (Simulation::implicit_level_plan): the cloth itself or a coarse copy
/// of its multilevel guess.
struct ImplicitLevelPlan {
    std::size_t particles = 0;
    std::uint32_t sweeps = 0; ///< per step, at most (a coarse level stops early at its tolerance)
};

/// Cooked for vertex block descent (built once per cloth): every energy term a vertex takes part in, and the vertex
/// colouring.
struct VbdGraph {
    std::size_t particle_count = 0;
    // Springs at each vertex (every Cloth::edges entry, seams and the springs model's bend springs included), CSR
    // sorted by neighbour: the neighbour, k = material stiffness x Edge::scale (N/m), kd (N*s/m), rest length (m).
    std::vector<std::uint32_t> spring_offsets, spring_neighbour, spring_edge;
    std::vector<float> spring_k, spring_kd, spring_rest;
    // Bending: Q's rows (off-diagonal Q_ij and the diagonal Q_ii), N/m, in float; beta in s.
    std::vector<std::uint32_t> bend_offsets, bend_neighbour;
    std::vector<float> bend_q, bend_diag;
    float bend_beta = 0.0f;
    // Colours: vertices of colour c are colour_vertex[colour_offsets[c] .. colour_offsets[c + 1]), ascending; no
    // spring and no bending element joins two vertices of one colour. Greedy in index order.
    // Mirror-exact (a cloth with Cloth::mirror, docs/garments.md "Mirror-exact sums"): every row in mirror order
    // (mirror_row_order), the sums rounded term by term (vbd::accumulate), and a particle coupled to its own twin
    // across the mirror plane shares its colour: such pairs open their colour, the lower index first, and are
    // solved together from the same positions (`paired`: per colour_vertex entry, 1 at the first of a pair).
    bool mirror_exact = false;
    std::vector<std::uint32_t> colour_offsets, colour_vertex;
    std::vector<std::uint8_t> paired;

    std::size_t colour_count() const noexcept { return colour_offsets.empty() ? 0 : colour_offsets.size() - 1; }
};

} // namespace drape
