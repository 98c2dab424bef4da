// drape_implicit's shared pieces (bench/implicit): the hang scene at a grid size, the implicit step's objective G
// evaluated in double from a simulation's state (docs/implicit.md; the same G the solver and the Eigen reference
// minimise), reference equilibria, and table/JSON output.
#pragma once

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "drape/scene.hpp"
#include "drape/simulation.hpp"

namespace drape::implicit_bench {

struct Options {
    int threads = 2;
    bool json = false;
    std::vector<std::uint32_t> sizes;      ///< --n (repeatable or comma list)
    std::string scene = "hang";            ///< --scene (rest): a built-in scene or a scene file; --n its resolution
    float dt = 1.0f / 30.0f;               ///< --dt implicit step, s
    std::uint32_t iterations = 30;         ///< --iterations per implicit step
    float rho = 0.9f;                      ///< --rho Chebyshev spectral radius estimate (0 = off)
    float strain_limit = 0.0f;             ///< --strain-limit ratio for the implicit run (0 = off)
    bool multilevel = true;                ///< --single-level turns the implicit solver's multilevel guess off
    bool explicit_rest = false;            ///< --explicit-rest: rest also runs the explicit solver (the equilibrium)
    bool fas = false;                      ///< --fas: the multilevel guess's coarse correction (ImplicitParams::fas)
    bool fas_at_rest = false;              ///< --fas-at-rest (ImplicitParams::fas_at_rest)
    std::optional<double> duration;        ///< --duration s: realtime's timed run (default 2), rest's run (default 8)
    double settle_time = 10.0;             ///< --settle-time s, the settled shape
    double settle_drag = 0.0;              ///< --settle-drag 1/s: air drag from the timed run's end on (0: the scene's)
    bool explicit_reference = false;       ///< --explicit-reference: the equilibrium by explicit Euler (realtime)
    double ref_seconds = 20.0;             ///< --ref-seconds: the explicit reference's most simulated seconds
    double explicit_budget = 60.0;         ///< --explicit-budget s of wall time an explicit run may take
    double explicit_settle_budget = 300.0; ///< --explicit-settle-budget s of wall time for the explicit settle run
    double explicit_short = 0.05;          ///< --explicit-short s simulated when the full run is over budget
    std::uint32_t newton_max_n = 64;       ///< --newton-max-n: the static Eigen reference up to this N, a long run above
    std::uint32_t newton_step_max_n = 100; ///< --newton-step-max-n: convergence's G* by Newton up to this N
    int newton_iterations = 100;           ///< --newton-iterations: at most this many Newton iterations per reference
    std::uint32_t ref_iterations = 100;    ///< --ref-iterations of the long implicit reference run
    int ref_steps = 60;                    ///< --ref-steps: at most this many 0.1 s steps of it
    double ref_drag = 5.0;                 ///< --ref-drag: its air drag, 1/s (the equilibrium does not depend on it)
    std::uint32_t kmax = 300;              ///< --kmax (convergence) most iterations plotted
    std::string json_out;                  ///< --json-out FILE: the JSON object also written there
    std::string csv;                       ///< --csv (convergence) file
    std::string out_dir;                   ///< --out DIR: CSV files go there
};

/// The built-in hang scene (scenes/hang.json: wool, 2 cm clips) at n x n particles; dt = the explicit default.
BuiltScene hang_scene(std::uint32_t n);
/// A built-in scene or scene file at resolution n (set_scene_resolution: grid particles per side, outline and T-shirt
/// cells per metre).
BuiltScene scene_at(const std::string& scene, std::uint32_t n);

/// A new simulation of sim's cloth starting from its current positions and velocities, with params (Simulation is
/// move-only; the implicit solver's memory of the previous step - its adaptive initial guess - starts afresh).
Simulation restart(const Simulation& sim, const SimulationParams& params);

/// Parameters of the implicit solver for a built scene.
SimulationParams implicit_params(const SimulationParams& base, float dt, std::uint32_t iterations, float rho,
                                 ImplicitMethod method, float strain_limit, bool multilevel = true,
                                 bool fas = false);

/// One implicit step's data from a simulation's current state (x^n, v^n, a = gravity), evaluated in double.
struct StepProblem {
    const Cloth* cloth = nullptr;
    double h = 0.0, kr = 0.0;
    std::vector<double> xn, vn, a; ///< 3 per particle interleaved
};
StepProblem step_problem(const Simulation& sim, double h);
/// G(x) (implicit_objective.md), J; x 3 per particle interleaved (fixed particles must be at x^n).
double objective(const StepProblem& p, const std::vector<double>& x);
/// The inertial prediction y (fixed particles at x^n).
std::vector<double> prediction(const StepProblem& p);
/// Positions of a simulation, 3 per particle interleaved, double.
std::vector<double> positions(const Simulation& sim);

/// Whether the Eigen Newton reference (implicit_reference.hpp) was compiled in.
bool have_newton_reference();
/// Newton's minimiser of G (tolerance N over the movable particles); empty when the reference is absent.
struct NewtonOut {
    std::vector<double> x;
    double objective = 0.0, gradient_norm = 0.0;
    int iterations = 0;
    bool converged = false;
};
/// G(x) by the reference's own implicit_objective (NaN when absent): a cross-check of objective().
double reference_objective(const StepProblem& p, const std::vector<double>& x);
NewtonOut newton_minimise(const StepProblem& p, const std::vector<double>& start, double tolerance, int max_iterations);

/// A static equilibrium near `start` (a settled shape of sim's cloth).
struct Equilibrium {
    std::vector<double> x;
    std::string method;     ///< how it was found, for the output
    double residual = 0.0;  ///< Newton: |grad E - m g| (N); long run: the last step's max motion (m)
};
Equilibrium reference_equilibrium(const Simulation& settled, const Options& opt, std::uint32_t n);
/// The equilibrium by explicit Euler: `explicit_params` (the scene's, at its default dt) with the air drag raised to
/// opt.ref_drag, from the settled shape at rest, until 0.1 s moves no particle more than 10 um (or opt.ref_seconds).
Equilibrium explicit_equilibrium(const Simulation& settled, const SimulationParams& explicit_params, const Options& opt);

/// Max over particles of |a_i - b_i|, m.
double max_distance(const std::vector<double>& a, const std::vector<double>& b);
/// Root mean square over particles of |a_i - b_i|, m.
double rms_distance(const std::vector<double>& a, const std::vector<double>& b);
/// |mean over particles of (a_i - b_i)|, m: how far the shape as a whole is displaced.
double mean_offset(const std::vector<double>& a, const std::vector<double>& b);

inline double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Machine load (the first figure of /proc/loadavg), -1 when unreadable.
double load_average();

// Tables: every command collects rows of (column, text) and prints a markdown table or a JSON array.
struct Cell {
    std::string text;
    bool number = false;
};
struct Table {
    std::vector<std::string> columns;
    std::vector<std::vector<Cell>> rows;
    std::string title;
    void add(std::vector<Cell> row) { rows.push_back(std::move(row)); }
};
/// What a command prints: tables and notes, as markdown (notes as lines after the tables) or as one JSON object
/// {"command", "threads", "load", "tables": [{"title", "rows": [{column: value}]}], "notes": [...]}.
struct Report {
    std::string command;
    int threads = 0;
    std::vector<Table> tables;
    std::vector<std::string> notes;
    /// Prints markdown (or JSON with `json`) on stdout; also writes the JSON to json_file when not empty.
    void print(bool json, const std::string& json_file = "") const;
    void write_json(std::FILE* f) const;
};
Cell num(double v, const char* fmt = "%.4g");
Cell txt(const std::string& s);

} // namespace drape::implicit_bench
