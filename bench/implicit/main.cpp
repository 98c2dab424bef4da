// drape_implicit: the implicit solver's figures for issue 8 (docs/implicit.md "Figures"). Each subcommand prints
// markdown tables (or, with --json, one JSON object); bench/implicit/figures.sh runs them all.
//   drape_implicit realtime     real-time factor at quality on the hang scene, implicit beside explicit
//                               (N = 100, 316, 1000; strain at the end of 2 s; settled shape at 10 s against a
//                               reference equilibrium)
//   drape_implicit convergence  relative energy error of one implicit step against iterations and wall time,
//                               Gauss-Seidel VBD with and without Chebyshev, Jacobi (N = 100, 316); writes a CSV
//   drape_implicit throughput   vertex-iterations/s beside explicit particle-substeps/s; 1 -> T thread scaling
//                               (N = 316, 1000)
//   drape_implicit rest         whether the hang comes to rest (air drag --ref-drag, --duration default 8 s):
//                               the largest motion in a step once a second, multilevel and single level (N = 32, 100)
// Options: --n N[,N..] (repeatable) grid sizes; --threads T (default 2); --json; --dt S implicit step (default
// 1/30); --iterations K (default 30); --rho R Chebyshev (default 0.9, 0 = off); --strain-limit R implicit runs'
// strain limit (default off); --single-level the implicit solver without its multilevel guess; --fas the multilevel guess with
// the full approximation scheme's coarse correction (ImplicitParams::fas); --duration S timed run (default 2); --settle-time S (default 10; 0 = no settled shape, no reference); --explicit-budget S
// wall seconds an explicit run may take before it is timed over a short interval only (default 60);
// --explicit-short S that interval (default 0.05); --explicit-settle-budget S wall seconds the explicit settle run
// may take (default 300; over it the explicit settled shape is not measured); --newton-max-n N static Eigen reference up to N (default 64: its sparse LDLT takes ~2.5 s per
// iteration at N = 100 and the static problem 100s of iterations); --newton-step-max-n N convergence's G* by Newton
// up to N (default 100);
// --newton-iterations K at most K Newton iterations per reference equilibrium (default 100);
// --ref-iterations K of the long-run reference (default 100), --ref-steps S its most steps of 0.1 s (default
// 60), --ref-drag D its air drag (default 5/s: the swing dies out; the equilibrium does not depend on drag);
// --settle-drag D (realtime) the air drag of both runs from the timed run's end to --settle-time (default: the
// scene's 0.2/s, under which the wool hang still swings at 10 s), so the settled shape is where each solver, as
// configured, comes to rest; --explicit-reference (realtime) the reference equilibrium by explicit Euler at the
// scene's dt and --ref-drag from the implicit settled shape, until 0.1 s moves nothing by 10 um or --ref-seconds S
// (default 20) pass, instead of the long implicit run; --fas-at-rest (realtime, rest) the implicit runs with
// ImplicitParams::fas_at_rest; --kmax K (convergence, default 300); --csv FILE or
// --out DIR (convergence's CSV; default ./convergence.csv); --json-out FILE also writes the JSON object there.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>

#include "commands.hpp"
#include "drape/workers.hpp"

using namespace drape;
using namespace drape::implicit_bench;

namespace {

[[noreturn]] void bad(const std::string& msg) {
    std::fprintf(stderr, "drape_implicit: %s\n", msg.c_str());
    std::exit(2);
}

double number(const char* flag, const char* text, double lo, double hi) {
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (end == text || *end != '\0' || !(v >= lo && v <= hi))
        bad(std::string(flag) + " must be a number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got '" +
            text + "'");
    return v;
}

} // namespace

int main(int argc, char** argv) {
    if (argc < 2 || std::strcmp(argv[1], "--help") == 0) {
        std::fprintf(stderr, "usage: drape_implicit realtime|convergence|throughput|rest [--n N,..] [--threads T] [--json] "
                             "[--dt S] [--iterations K] [--rho R] [--strain-limit R] [--single-level] [--fas] [--duration S] [--settle-time S] "
                             "[--explicit-budget S] [--explicit-settle-budget S] [--explicit-short S] [--newton-max-n N] [--newton-step-max-n N] [--newton-iterations K] [--ref-iterations K] [--ref-steps S] [--ref-drag D] [--ref-seconds S] [--settle-drag D] [--explicit-reference] [--fas-at-rest] "
                             "[--kmax K] [--csv FILE | --out DIR] [--json-out FILE] [--scene S] [--explicit-rest] (rest)\n");
        return 2;
    }
    const std::string cmd = argv[1];
    Options opt;
    for (int a = 2; a < argc; ++a) {
        const std::string s = argv[a];
        auto value = [&]() -> const char* {
            if (a + 1 >= argc) bad(s + " needs a value");
            return argv[++a];
        };
        if (s == "--json") opt.json = true;
        else if (s == "--threads") opt.threads = static_cast<int>(number("--threads", value(), 1, 256));
        else if (s == "--n") {
            std::string list = value();
            std::size_t pos = 0;
            while (pos <= list.size()) {
                const std::size_t comma = std::min(list.find(',', pos), list.size());
                const std::string item = list.substr(pos, comma - pos);
                opt.sizes.push_back(static_cast<std::uint32_t>(number("--n", item.c_str(), 2, 4096)));
                pos = comma + 1;
            }
        }
        else if (s == "--dt") opt.dt = static_cast<float>(number("--dt", value(), 1e-4, 0.1));
        else if (s == "--iterations") opt.iterations = static_cast<std::uint32_t>(number("--iterations", value(), 1, 1000));
        else if (s == "--rho") {
            opt.rho = static_cast<float>(number("--rho", value(), 0, 0.999));
        }
        else if (s == "--strain-limit") opt.strain_limit = static_cast<float>(number("--strain-limit", value(), 0, 10));
        else if (s == "--duration") opt.duration = number("--duration", value(), 0.001, 600);
        else if (s == "--settle-time") opt.settle_time = number("--settle-time", value(), 0, 600);
        else if (s == "--explicit-budget") opt.explicit_budget = number("--explicit-budget", value(), 0, 1e5);
        else if (s == "--explicit-settle-budget")
            opt.explicit_settle_budget = number("--explicit-settle-budget", value(), 0, 1e5);
        else if (s == "--explicit-short") opt.explicit_short = number("--explicit-short", value(), 1e-4, 600);
        else if (s == "--newton-max-n") opt.newton_max_n = static_cast<std::uint32_t>(number("--newton-max-n", value(), 0, 4096));
        else if (s == "--newton-step-max-n")
            opt.newton_step_max_n = static_cast<std::uint32_t>(number("--newton-step-max-n", value(), 0, 4096));
        else if (s == "--newton-iterations")
            opt.newton_iterations = static_cast<int>(number("--newton-iterations", value(), 1, 100000));
        else if (s == "--ref-steps") opt.ref_steps = static_cast<int>(number("--ref-steps", value(), 1, 10000));
        else if (s == "--ref-drag") opt.ref_drag = number("--ref-drag", value(), 0, 100);
        else if (s == "--ref-seconds") opt.ref_seconds = number("--ref-seconds", value(), 0.1, 600);
        else if (s == "--settle-drag") opt.settle_drag = number("--settle-drag", value(), 0, 100);
        else if (s == "--explicit-reference") opt.explicit_reference = true;
        else if (s == "--fas-at-rest") opt.fas_at_rest = true;
        else if (s == "--ref-iterations")
            opt.ref_iterations = static_cast<std::uint32_t>(number("--ref-iterations", value(), 1, 1000));
        else if (s == "--kmax") opt.kmax = static_cast<std::uint32_t>(number("--kmax", value(), 1, 1000));
        else if (s == "--scene") opt.scene = value();
        else if (s == "--explicit-rest") opt.explicit_rest = true;
        else if (s == "--single-level") opt.multilevel = false;
        else if (s == "--fas") opt.fas = true;
        else if (s == "--csv") opt.csv = value();
        else if (s == "--json-out") opt.json_out = value();
        else if (s == "--out") opt.out_dir = value();
        else bad("unknown option " + s);
    }
    try {
        if (cmd == "throughput") return cmd_throughput(opt);
        if (cmd != "realtime" && cmd != "convergence" && cmd != "rest")
            bad("unknown command " + cmd + " (realtime, convergence, throughput, rest)");
        Workers workers(opt.threads);
        return workers.run([&]() -> int {
            return cmd == "realtime" ? cmd_realtime(opt) : cmd == "rest" ? cmd_rest(opt) : cmd_convergence(opt);
        });
    } catch (const std::exception& e) {
        std::fprintf(stderr, "drape_implicit: %s\n", e.what());
        return 1;
    }
}
