// The exact reference for one implicit (backward-Euler) step: the step's objective G, its gradient, and a projected
// Newton solver (Eigen sparse LDLT) that minimises G to a tolerance. The fast implicit solver minimises the same G;
// tests and benchmarks compare it with this one. docs/implicit.md "The exact reference (Eigen Newton)".
//
// G (docs/implicit.md, the objective of one step of length h from x^n, v^n) over the movable particles' positions x:
//   G(x) = sum_i m_i/(2 h^2) |x_i - y_i|^2 + sum_i m_i kr/(2 h) |x_i - x_i^n|^2            y_i = x_i^n + h v_i^n + h^2 a_i
//        + sum_s k_s/2 (|x_b - x_a| - l_s)^2 + sum_s kd_s/(2 h) (((x_b - x_a) - (x_b^n - x_a^n)) . n_s)^2
//        + 1/2 sum_e w_e |q_e(x)|^2 + beta/(2 h) sum_e w_e |q_e(x) - q_e(x^n)|^2 - sum_i f_i . x_i
// springs s = Cloth::edges (seams included), k_s = material stiffness x Edge::scale, kd_s = material damping x scale,
// n_s = unit(x_b^n - x_a^n) frozen at the step start (the term is dropped when that length is 0); bending elements e =
// Cloth::bending.elements, beta = Cloth::bending.damping. A particle with inv_mass == 0 is fixed at x^n.
// After the step v^{n+1} = (x - x^n) / h.
//
// Positions here are double, 3 per particle interleaved (x0 y0 z0 x1 ...), in the cloth's frame (Cloth::origin).
// The entries of fixed particles are ignored (x^n is used); the gradient's entries there are 0.
// Everything is evaluated in double, single-threaded: a reference, not a fast path.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace drape {

struct Cloth;

/// One backward-Euler step's data. The per-particle spans have Cloth::particle_count entries; fx, fy, fz may all be
/// empty (no constant external force).
struct ImplicitProblem {
    const Cloth* cloth = nullptr;     ///< masses (inv_mass, 0 = fixed), edges + material, bending elements + damping
    double h = 0.0;                   ///< step, s (> 0, finite)
    double air_drag = 0.0;            ///< kr, 1/s (>= 0): implicit force -m kr v^{n+1}
    std::span<const float> x0, y0, z0; ///< x^n, m
    std::span<const float> vx, vy, vz; ///< v^n, m/s
    std::span<const float> ax, ay, az; ///< external acceleration per particle (gravity + wind at x^n), m/s^2
    std::span<const float> fx, fy, fz; ///< constant external force per particle, N (all empty = none)
};

/// Checks the problem: a cloth, h finite and > 0, air_drag finite and >= 0, every span of particle_count entries
/// (f: all three empty or all of that size), every entry finite. Throws InvalidInput naming the field and the range.
/// Every function below calls it.
void validate_implicit_problem(const ImplicitProblem& problem);

/// The inertial prediction y = x^n + h v^n + h^2 a (fixed particles: x^n), 3 per particle interleaved, m.
std::vector<double> inertial_prediction(const ImplicitProblem& problem);

/// G(x), J. x: 3 * particle_count entries (fixed particles' entries ignored). Throws InvalidInput on a wrong size or
/// a non-finite x.
double implicit_objective(const ImplicitProblem& problem, std::span<const double> x);

/// grad G(x) into g (3 * particle_count entries), N; 0 at fixed particles.
void implicit_gradient(const ImplicitProblem& problem, std::span<const double> x, std::span<double> g);

/// Euclidean norm of a gradient over the movable particles, N.
double movable_norm(const ImplicitProblem& problem, std::span<const double> g);

/// One projected Newton solve (see newton_reference).
struct NewtonResult {
    std::vector<double> x;        ///< the minimiser found, 3 per particle interleaved, m (fixed particles: x^n)
    int iterations = 0;           ///< Newton steps taken
    double objective = 0.0;       ///< G(x), J
    double gradient_norm = 0.0;   ///< |grad G(x)| over the movable particles, N
    bool converged = false;       ///< gradient_norm <= tolerance
    int projected_iterations = 0; ///< iterations that used the projected Hessian (the exact one was not positive definite)
    int cg_fallbacks = 0;         ///< iterations whose LDLT factorisation failed and used conjugate gradients instead
    std::vector<double> objective_history; ///< G at the start and after every iteration (iterations + 1 entries)
    std::vector<double> gradient_history;  ///< |grad G| likewise
};

/// Minimises G by Newton's method with a positive-definite Hessian: at each iterate the exact Hessian when it is
/// positive definite (every pivot of its sparse LDL^T factorisation, Eigen SimplicialLDLT, is > 0), which gives
/// quadratic convergence near the minimiser; otherwise the projected one (every spring's block made positive
/// semi-definite: a compressed spring keeps only its axial stiffness, k max(0, 1 - l/L) on the transverse part; all
/// other terms are convex already), positive definite with the inertia term m/h^2. The direction solves H p = -g
/// (ConjugateGradient if the factorisation fails); a backtracking line search halves the step until G satisfies
/// Armijo's condition G(x + a p) <= G(x) + 1e-4 a g.p (below G's rounding, ~1e3 eps x the sum of its terms'
/// magnitudes, a step is accepted when it reduces |grad G| instead). Starts from `start` (3 per particle) or, when
/// empty, from the inertial prediction y. Stops when |grad G| over the movable particles <= tolerance (N), after
/// max_iterations, or when the line search finds no decrease (the result says whether it converged).
/// Throws InvalidInput on a bad problem, a start of the wrong size or not finite, a tolerance not finite or < 0, or
/// max_iterations < 0.
NewtonResult newton_reference(const ImplicitProblem& problem, std::span<const double> start, double tolerance,
                              int max_iterations);

} // namespace drape
